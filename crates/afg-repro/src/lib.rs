//! The paper's reproduction and our measurements: the learned models of the paper's
//! tables ([`ModelSpec`]), the numbers the paper reports ([`paper`]), the tables
//! themselves ([`tables`], with the price model's ablation in [`price_ablation`] and
//! the comparison of two renderings in [`markdown`]), the benchmarks ([`bench`](mod@bench),
//! [`scale`]), the regret study ([`regret`]), the removal study
//! ([`realloc_study`]), the mission study ([`mission_study`]) and GRAPE's published
//! runs beside ours ([`grape_fig7`]).
//!
//! Only the maintainer's `cargo xtask` depends on this crate: the `afg` command line
//! and the Python package call `afg-eval`, so neither compiles the tables, the paper's
//! numbers or the benchmarks.

pub mod bench;
pub mod grape_fig7;
pub mod markdown;
pub mod mission_study;
mod model;
pub mod paper;
pub mod price_ablation;
pub mod realloc_study;
pub mod regret;
pub mod scale;
pub mod tables;

pub use model::{Head, ModelSpec, PriceSpec, PriceTraining};
