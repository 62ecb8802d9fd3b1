//! Learned allocators: the AFGNet and S2V Q networks in Burn, the sequential
//! allocation environment, and a greedy policy that implements
//! [`afg_baseline::Allocator`].
//!
//! Model code is generic over the Burn [`Backend`](burn::tensor::backend::Backend):
//! [`TrainBackend`] (autodiff over ndarray) trains, [`InferBackend`] (ndarray)
//! evaluates, and a user with a GPU back end can swap one in.
//!
//! | module | what it holds |
//! |---|---|
//! | [`nets`] | AFGNet and S2V (Burn), `NetworkConfig`, `QNetwork`, batches as tensors, weight files |
//! | [`env`](mod@env) | the sequential allocation MDP (`Env`) and reward shaping |
//! | [`train`] | DQN / Double DQN: `TrainConfig`, `TrainSettings`, `Trainer`, `Session`, the targets |
//! | [`run`] | a training run's directory: `RunDir`, its log, manifest and lock; `migrate_run` for older formats |
//! | [`policy`] | a trained network as an allocator (`LearnedPolicy`), rollouts, regret against Q* |
//! | [`fast`] | the trained network exported to faer for fast exact rollouts (`FastPolicy`) |
//! | [`price`] | the price model (ours): `PriceNet`, `PriceTrainer`, `PricePolicy` |

mod afgnet;
mod dense;
pub mod env;
mod error;
pub mod fast;
mod layers;
mod log_float;
mod manifest;
mod migrate;
mod network;
pub mod policy;
pub mod price;
mod regret;
mod rollout;
mod run_dir;
mod s2v;
mod targets;
mod tensors;
pub mod train;
mod weights;

/// The Q networks (AFGNet, S2V) generic over the Burn back end, their batches as
/// tensors, their configurations and weight files.
pub mod nets {
    pub use crate::afgnet::{AfgLayer, AfgNet, AfgNetConfig};
    pub use crate::layers::{Activation, QHead, linear_of_concat};
    pub use crate::network::{NETWORK_LIMITS, Net, NetworkConfig, NetworkLimits, QNetwork};
    pub use crate::s2v::{S2v, S2vConfig};
    pub use crate::tensors::{DENSE_MAX_NODES, DenseAdjacency, GraphTensors};
    pub use crate::weights::{load_network, parameter_values, save_network};
}

/// A training run's directory: its files, typed log, manifest and lock.
pub mod run {
    pub use crate::manifest::{ModelKind, RunManifest, RunRecord};
    pub use crate::migrate::{RUN_FORMAT_VERSION, migrate_run};
    pub use crate::run_dir::{LogEvent, RunDir, RunLock, ValidationLine};
}

pub use error::LearnError;

// Every module reaches the others' items from the crate root.
pub(crate) use afgnet::AfgNetConfig;
pub(crate) use env::{Env, Shaping, n_step_reward};
pub(crate) use fast::{FastPolicy, FastRollout};
pub(crate) use layers::Activation;
pub(crate) use network::{Net, NetworkConfig, QNetwork};
pub(crate) use price::PRICE_INPUTS;
pub(crate) use regret::q_star;
pub(crate) use rollout::greedy_rollouts;
pub(crate) use run_dir::{LogEvent, RunDir, RunLock, ValidationLine};
pub(crate) use targets::{double_dqn_target, dqn_target, masked_argmax};
pub(crate) use tensors::GraphTensors;
pub(crate) use train::{
    Algo, Demonstrations, Preset, TrainConfig, Validation, checkpoint_dir, training_instance_seed,
};
pub(crate) use weights::{load_network, save_network};

/// The CPU inference back end.
pub type InferBackend = burn::backend::NdArray<f32>;
/// The CPU training back end.
pub type TrainBackend = burn::backend::Autodiff<InferBackend>;
