//! The crate's error type.

use afg_baseline::AllocError;
use afg_game::GameError;
use afg_graph::GraphError;
use thiserror::Error;

/// Errors of the learning crate.
#[derive(Debug, Error)]
pub enum LearnError {
    /// Invalid instance or assignment.
    #[error(transparent)]
    Game(#[from] GameError),
    /// The robot graph could not be built.
    #[error(transparent)]
    Graph(#[from] GraphError),
    /// A classical allocator failed (they do not on valid instances).
    #[error(transparent)]
    Alloc(#[from] AllocError),
    /// An action that the environment does not allow.
    #[error("invalid action: {0}")]
    InvalidAction(String),
    /// Training settings that cannot work.
    #[error("invalid training configuration: {0}")]
    InvalidConfig(String),
    /// A training checkpoint that cannot be used.
    #[error("{path}: {reason}")]
    Checkpoint {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A weight file that cannot be used.
    #[error("{path}: {reason}")]
    Weights {
        /// The file.
        path: String,
        /// What is wrong, and what to do.
        reason: String,
    },
    /// Training produced a NaN or infinite loss; the weights were not updated.
    #[error(
        "step {step}: the loss is {loss}; training stopped (the last checkpoint is the last good state; try a lower learning rate)"
    )]
    NonFiniteLoss {
        /// The gradient step that failed.
        step: u64,
        /// The loss.
        loss: f32,
    },
    /// A gradient step would have made a weight NaN or infinite (with a finite loss);
    /// the weights were not updated.
    #[error(
        "step {step}: an update made a weight NaN or infinite; training stopped (the last checkpoint is the last good state; try a lower learning rate)"
    )]
    NonFiniteWeights {
        /// The gradient step that failed.
        step: u64,
    },
    /// Another trainer holds the run directory.
    #[error("{path} is in use by another training process")]
    RunInUse {
        /// The run directory.
        path: String,
    },
    /// A run directory's file that cannot be read as what it should be.
    #[error("{path}: {reason}")]
    RunFile {
        /// The file (with a line number for logs).
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// Model options that do not go together, or not with the model found.
    #[error(transparent)]
    ModelOptions(#[from] crate::load::OptionConflict),
    /// A trained model could not be loaded from its run directory.
    #[error("loading the model in {path}: {source}")]
    Model {
        /// The run directory.
        path: String,
        /// What is wrong.
        #[source]
        source: Box<LearnError>,
    },
}
