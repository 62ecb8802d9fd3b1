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
    /// A mission could not be read or run.
    #[error(transparent)]
    Mission(#[from] afg_mission::MissionError),
    /// A learned model could not be loaded.
    #[error(transparent)]
    Learn(#[from] LearnError),
    /// A committed dataset is missing or unreadable.
    #[error("{source} (regenerate it with `cargo xtask gen-datasets`)")]
    Dataset {
        /// The file.
        path: String,
        /// What is wrong.
        #[source]
        source: GameError,
    },
    /// Options that do not apply to the model or method at hand.
    #[error("{0}")]
    BadOptions(&'static str),
    /// A training run's log lacks what is needed.
    #[error("{path}: the log has {what}")]
    Log {
        /// The run directory.
        path: String,
        /// What is missing.
        what: &'static str,
    },
    /// A robot in no coalition, where the instance does not allow the void task.
    #[error(
        "robot {robot} has no task (-1), but the instance is the paper's game, where every robot joins a coalition (\"allow_void\": true allows the void task)"
    )]
    Unplaced {
        /// The robot.
        robot: usize,
    },
    /// A committed file that does not say what it must, or disagrees with the files
    /// beside it.
    #[error("{path}: {message}")]
    BadFile {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A figure could not be drawn.
    #[error("drawing a figure: {0}")]
    Figure(String),
    /// A measurement was asked for on no instance.
    #[error("no instances to evaluate on")]
    NoInstances,
    /// An instance could not be generated.
    #[error(transparent)]
    Game(#[from] GameError),
    /// A mean % of OPT over instances of which one has an optimum of welfare ≤ 0.
    #[error("% of OPT is undefined: an instance's optimal welfare is not positive")]
    PercentUndefined,
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
