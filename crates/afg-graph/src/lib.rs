//! The allocation feature graph of the paper (§III A): the robot communication graph
//! with distance-weighted edges. Shared by the decentralised baseline (its message
//! graph) and the learned models (their neighbourhoods).

mod neighbours;

pub use neighbours::{GraphKind, RobotGraph};

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
