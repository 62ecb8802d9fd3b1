//! Evaluation of allocators, as the `afg` command line and the Python package call it:
//! the fixed test datasets ([`dataset`]), one way to score an allocation against the
//! exact optimum ([`Score`], [`evaluate`]), one allocator on a set of instances
//! ([`solve`]), any assignment judged against the game ([`scorecard`]), warm-start
//! reallocation ([`realloc`]), the decentralised swarm's grid
//! of runs ([`swarm`]), training runs' curves and summaries ([`runs`]), figures
//! ([`figures`]), and what every command prints around its work: durations, progress
//! bars and the one-line error with its exit code ([`report`]).
//!
//! Every command that prints "% of OPT" computes it here. The paper's tables, its
//! numbers and the benchmarks live in the maintainer's `xtask`.

pub mod dataset;
mod error;
pub mod figures;
pub mod frame_image;
pub mod mission;
pub mod realloc;
pub mod report;
pub mod runs;
pub mod schedule_figure;
mod score;
pub mod scorecard;
pub mod solve;
pub mod swarm;

pub use afg_baseline::percent_of_opt;
pub use error::EvalError;
pub use score::{Score, Summary, evaluate, optima, optimum_welfare};
