//! Evaluation of allocators: the fixed test datasets ([`dataset`]), one way to score an
//! allocation against the exact optimum ([`Score`], [`evaluate`]), the learned models
//! of the paper's tables ([`ModelSpec`]), the numbers the paper reports ([`paper`]) and
//! the tables themselves ([`tables`], with the price model's ablation in
//! [`price_ablation`]).
//!
//! Every command that prints "% of OPT" computes it here.

pub mod bench;
pub mod dataset;
mod error;
pub mod figures;
pub mod markdown;
mod model;
pub mod paper;
pub mod price_ablation;
pub mod realloc;
pub mod regret;
pub mod runs;
pub mod scale;
mod score;
pub mod solve;
pub mod tables;

pub use afg_baseline::percent_of_opt;
pub use error::EvalError;
pub use model::{Head, ModelSpec, PriceSpec, PriceTraining};
pub use score::{Score, Summary, evaluate, optima, optimum_welfare};
