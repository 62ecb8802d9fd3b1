//! The crate's error type.

use afg_baseline::AllocError;
use afg_game::GameError;
use afg_learn::LearnError;
use thiserror::Error;

/// Errors of evaluation.
#[derive(Debug, Error)]
pub enum EvalError {
    /// An allocator failed.
    #[error(transparent)]
    Alloc(#[from] AllocError),
    /// A learned model could not be loaded.
    #[error(transparent)]
    Learn(#[from] LearnError),
    /// A committed dataset is missing or unreadable.
    #[error("{path}: {source} (regenerate it with `cargo xtask gen-datasets`)")]
    Dataset {
        /// The file.
        path: String,
        /// What is wrong.
        #[source]
        source: GameError,
    },
    /// An instance could not be generated.
    #[error(transparent)]
    Game(#[from] GameError),
    /// An allocation scored above the exact optimum: the optimum is wrong.
    #[error("{method} beats OPT ({welfare} > {opt}): the optimum is wrong")]
    BeatsOptimum {
        /// The allocator.
        method: String,
        /// Its welfare.
        welfare: f64,
        /// The optimum's.
        opt: f64,
    },
}
