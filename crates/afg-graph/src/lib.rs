//! The allocation feature graph of the paper (§III A): the robot communication graph
//! with distance-weighted edges ([`RobotGraph`]), the robot and task node features of
//! an assignment in progress with their incremental update ([`AllocationState`]), and
//! several graphs packed into flat arrays for batched tensor work ([`GraphBatch`]).
//! No ML dependency: the learning crate turns a [`GraphBatch`] into tensors.

mod batch;
mod neighbours;
mod price_features;
mod state;
mod units;

pub use batch::GraphBatch;
pub use neighbours::{GraphKind, RobotGraph};
pub use price_features::{PriceState, TASK_FEATURES, rows_with_mean, task_inputs};
pub use state::{AllocationState, StateParts, join_gain, write_task_column};
pub use units::{MIN_BETA_UNIT, Units, VALUE_CAP, feature_scale};

use thiserror::Error;

/// Errors of graph construction.
#[derive(Debug, Error)]
pub enum GraphError {
    /// A graph parameter is out of range.
    #[error("invalid graph parameter: {0}")]
    InvalidParameter(String),
    /// A robot has a NaN or infinite coordinate.
    #[error("robot {0} has a non-finite coordinate")]
    NonFinite(usize),
}
