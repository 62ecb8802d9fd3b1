//! The one training loop of the trainers that run in rounds to the end (the price
//! model's rounds, the staffing model's epochs): lock the run directory, run each
//! round and rewrite the log after it, then write the manifest and the model last.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::LearnError;
use crate::manifest::{RunManifest, RunRecord};
use crate::run_dir::RunDir;

/// A trainer that [`run_rounds`] drives.
pub(crate) trait RoundTrainer {
    /// What one round reports: a line of the log.
    type Round: Serialize;

    /// Whether every round is done.
    fn is_finished(&self) -> bool;

    /// Runs the next round.
    fn next_round(&mut self) -> Result<Self::Round, LearnError>;

    /// What the manifest records of a run whose last round was `last`, and its seed.
    fn record(&self, last: Option<Self::Round>) -> (RunRecord, u64);

    /// Writes the trained model into `dir`.
    fn save_model(&self, dir: &Path) -> Result<(), LearnError>;
}

/// Trains `trainer` to the end with run directory `dir` (created if needed, then
/// locked as a [`RunDir`] is, so that a second trainer is refused): `prepare` runs
/// first, under the lock; after each round the log ([`RunDir::LOG`], one round per
/// line) is rewritten atomically and `on_round` called; at the end the manifest (with
/// `command`) and then the model are written, so a directory that holds a model holds
/// a whole run. A run killed before its end leaves no model; being seeded, the same
/// call starts it again and ends with the same weights.
pub(crate) fn run_rounds<T: RoundTrainer>(
    mut trainer: T,
    dir: &Path,
    command: String,
    prepare: impl FnOnce(&mut T) -> Result<(), LearnError>,
    mut on_round: impl FnMut(&T::Round),
) -> Result<RunManifest, LearnError> {
    let start = Instant::now();
    std::fs::create_dir_all(dir).map_err(|source| LearnError::Io {
        path: dir.display().to_string(),
        source,
    })?;
    let run = RunDir::new(dir);
    let _lock = run.lock()?;
    prepare(&mut trainer)?;
    let mut log = String::new();
    let mut last = None;
    while !trainer.is_finished() {
        let round = trainer.next_round()?;
        log += &serde_json::to_string(&round).expect("a round always serialises");
        log.push('\n');
        afg_game::fs::write_atomic(&run.file(RunDir::LOG), log.as_bytes())?;
        on_round(&round);
        last = Some(round);
    }
    let (record, seed) = trainer.record(last);
    let manifest = RunManifest {
        wall_time_s: Some(start.elapsed().as_secs_f64()),
        ..RunManifest::new(command, seed, record)
    };
    run.write_manifest(&manifest)?;
    trainer.save_model(dir)?;
    Ok(manifest)
}
