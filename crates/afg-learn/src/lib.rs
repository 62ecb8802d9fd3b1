//! Learned allocators: the AFGNet and S2V Q networks in Burn, the sequential
//! allocation environment, and a greedy policy that implements
//! [`afg_baseline::Allocator`].
//!
//! Model code is generic over the Burn [`Backend`](burn::tensor::backend::Backend):
//! [`TrainBackend`] (autodiff over ndarray) trains, [`InferBackend`] (ndarray)
//! evaluates, and a user with a GPU back end can swap one in.

mod afgnet;
mod dense;
mod env;
mod error;
mod fast;
mod layers;
mod log_float;
mod network;
mod policy;
mod price;
mod regret;
mod rollout;
mod run_dir;
mod s2v;
mod targets;
mod tensors;
mod train;
mod weights;

pub use afgnet::{AfgLayer, AfgNet, AfgNetConfig, PriceHead};
pub use env::{Env, Shaping, n_step_reward};
pub use error::LearnError;
pub use fast::{FastPolicy, FastRollout, FastRolloutOutcome};
pub use layers::{Activation, QHead, linear_of_concat};
pub use network::{NETWORK_LIMITS, Net, NetworkConfig, NetworkLimits, QNetwork};
pub use policy::{LearnedPolicy, LearnedRun};
pub use price::{
    PRICE_INPUTS, PriceMlp, PriceMode, PriceModel, PriceNet, PriceNetConfig, PricePolicy,
    PriceRound, PriceRunSummary, PriceTrainConfig, PriceTrainer,
};
pub use regret::{RegretStep, q_star, regret_trace};
pub use rollout::greedy_rollouts;
pub use run_dir::{LogEvent, RunDir, RunLock, RunManifest, ValidationLine};
pub use s2v::{S2v, S2vConfig};
pub use targets::{double_dqn_target, dqn_target, masked_argmax};
pub use tensors::{DENSE_MAX_NODES, DenseAdjacency, GraphTensors};
pub use train::{
    Algo, Demonstrations, Preset, Session, StepReport, TrainConfig, TrainSettings, Trainer,
    Validation, checkpoint_dir, training_instance_seed, validation_instances,
};
pub use weights::{load_network, parameter_values, save_network};

/// The CPU inference back end.
pub type InferBackend = burn::backend::NdArray<f32>;
/// The CPU training back end.
pub type TrainBackend = burn::backend::Autodiff<InferBackend>;
