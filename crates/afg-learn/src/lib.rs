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
//! | [`train`] | DQN / Double DQN: `TrainConfig`, `Trainer`, `Session`, the targets |
//! | [`run`] | a training run's directory: `RunDir`, its log, manifest and lock; `migrate_run` for older formats |
//! | [`policy`] | a trained network as an allocator (`LearnedPolicy`), rollouts, regret against Q* |
//! | [`fast`] | the trained network exported to faer for fast exact rollouts (`FastPolicy`) |
//! | [`price`] | the price model (ours): `PriceNet`, `PriceTrainer`, `PricePolicy` |
//! | [`staffing`] | the staffing model for team games (ours): `StaffingTrainer`, `StaffingPolicy`, `knapsack` |

mod afgnet;
mod dense;
pub mod env;
mod error;
pub mod fast;
mod format;
mod layers;
mod load;
mod log_float;
mod manifest;
mod migrate;
mod model_file;
pub mod policy;
pub mod price;
mod qnetwork;
mod regret;
mod rollout;
mod rounds;
mod run_dir;
mod s2v;
pub mod staffing;
mod targets;
mod tensors;
pub mod train;
mod weights;

/// The Q networks (AFGNet, S2V) generic over the Burn back end, their batches as
/// tensors, their configurations and weight files.
pub mod nets {
    pub use crate::afgnet::{AfgLayer, AfgNet, AfgNetConfig};
    pub use crate::layers::{Activation, QHead, linear_of_concat};
    pub use crate::qnetwork::{NETWORK_LIMITS, Net, NetworkConfig, NetworkLimits, QNetwork};
    pub use crate::s2v::{S2v, S2vConfig};
    pub use crate::tensors::{DENSE_MAX_NODES, DenseAdjacency, GraphTensors};
    pub use crate::weights::{load_network, parameter_values, save_network};
}

/// A training run's directory: its files, typed log, manifest and lock, and its trained
/// model loaded as an allocator.
pub mod run {
    pub use crate::format::RUN_FORMAT_VERSION;
    pub use crate::load::{ModelOptions, OptionConflict, load_model, load_q_network};
    pub use crate::manifest::{ModelKind, RunManifest, RunRecord};
    pub use crate::migrate::migrate_run;
    pub use crate::run_dir::{LogEvent, RunDir, RunLock, ValidationLine};
}

pub use error::LearnError;

/// Why the trained models refuse the team games (`afg_baseline::check_game`).
pub(crate) const TRAINED_CONCAVE: &str =
    "it was trained on the paper's concave game, where every member adds value";

/// The CPU inference back end.
pub type InferBackend = burn::backend::NdArray<f32>;
/// The CPU training back end.
pub type TrainBackend = burn::backend::Autodiff<InferBackend>;
