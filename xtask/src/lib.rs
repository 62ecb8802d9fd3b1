//! The maintainer's jobs behind `cargo xtask`: the paper's reproduction and our
//! measurements: the learned models of the paper's
//! tables ([`ModelSpec`]), the numbers the paper reports ([`paper`]), the tables
//! themselves ([`tables`], with the price model's ablation in [`price_ablation`] and
//! the comparison of two renderings in [`table_diff`]), the benchmarks ([`bench`](mod@bench),
//! [`scale`]), the regret study ([`regret_study`]), the removal study
//! ([`realloc_study`]), the mission study ([`mission_study`]) and GRAPE's published
//! runs beside ours ([`grape_fig7`]).
//!
//! Each module holds one job whole: its computation and the `cargo xtask` command
//! that runs it (`src/main.rs` only parses the command line and dispatches). Nothing
//! else depends on this crate: the `afg` command line and the Python package call
//! `afg-eval`, so neither compiles the tables, the paper's numbers or the benchmarks.

pub mod bench;
pub mod bench_opt;
pub mod bench_schedule;
pub mod bench_staffing;
pub mod bench_teams;
pub mod crash;
pub mod datasets;
pub mod grape_fig7;
pub mod mission_study;
mod model;
pub mod paper;
pub mod price_ablation;
pub mod realloc_study;
pub mod regret_study;
pub mod run_manifests;
pub mod scale;
pub mod study_families;
pub mod table_diff;
pub mod tables;
pub mod train_all;

pub use model::{Head, ModelSpec, PriceSpec, PriceTraining};

/// The global allocator of the `cargo xtask` binary, for benchmark headers (see the
/// `mimalloc` feature in Cargo.toml).
pub const ALLOCATOR_NAME: &str = if cfg!(feature = "mimalloc") {
    "mimalloc"
} else {
    "system"
};

/// The repository root (xtask lives one level below it).
pub fn repo_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask has a parent")
        .to_path_buf()
}
