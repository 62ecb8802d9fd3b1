//! Checkpoints: both networks, Adam's moments, the generator, the replay records and
//! the running episodes, so that a resumed run ends with the same weights as an
//! uninterrupted one.

use std::path::Path;

use burn::optim::Optimizer;
use burn::record::{FullPrecisionSettings, NamedMpkFileRecorder, Recorder};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::replay::EpisodeRecord;
use super::{TrainConfig, Trainer, optimizer};
use crate::run_dir::{checkpoint_dir, previous_checkpoint_dir};
use crate::weights::write_record;
use crate::weights::{load_network, save_network};
use crate::{InferBackend, LearnError, TrainBackend};

/// The mutable state of a run, as written to `state.json` in a checkpoint.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TrainerState {
    format: String,
    version: u32,
    config: TrainConfig,
    step: u64,
    next_episode: u64,
    rng: ChaCha8Rng,
    replay: Vec<EpisodeRecord>,
    running: Vec<EpisodeRecord>,
}

impl TrainerState {
    /// Whether the episodes can be those of this run: every replayed episode complete,
    /// every running one at most N long, every action a task of the instance.
    fn check(&self) -> Result<(), String> {
        let (n, m) = (self.config.robots, self.config.network.tasks());
        let episodes = self.replay.iter().map(|e| (e, true));
        for (e, complete) in episodes.chain(self.running.iter().map(|e| (e, false))) {
            let len = e.actions.len();
            if len > n || (complete && len != n) {
                return Err(format!(
                    "an episode of seed {} has {len} actions, but the run has {n} robots",
                    e.seed
                ));
            }
            if let Some(&a) = e.actions.iter().find(|&&a| usize::from(a) >= m) {
                return Err(format!(
                    "an episode of seed {} takes task {a}, but the run has {m} tasks",
                    e.seed
                ));
            }
        }
        Ok(())
    }
}

const STATE_FORMAT: &str = "afg-train-state";
/// Format 2: the configuration inside states every field ([`crate::run::migrate_run`]).
const STATE_VERSION: u32 = crate::format::RUN_FORMAT_VERSION;

impl Trainer {
    /// Writes a checkpoint into `dir/checkpoint` atomically: everything goes to
    /// `dir/checkpoint.new` first, which then replaces the old checkpoint.
    ///
    /// # Errors
    /// [`LearnError::Weights`] or [`LearnError::Io`] if a file cannot be written.
    pub fn save_checkpoint(&self, dir: &Path) -> Result<(), LearnError> {
        let fresh = dir.join("checkpoint.new");
        let io = |path: &Path| {
            let path = path.display().to_string();
            move |source| LearnError::Io { path, source }
        };
        if fresh.exists() {
            std::fs::remove_dir_all(&fresh).map_err(io(&fresh))?;
        }
        std::fs::create_dir_all(&fresh).map_err(io(&fresh))?;
        save_network(
            self.online.clone(),
            &self.config.network,
            &fresh.join("online"),
        )?;
        save_network(
            self.target.clone(),
            &self.config.network,
            &fresh.join("target"),
        )?;
        write_record::<TrainBackend, _>(self.optim.to_record(), &fresh.join("optim.mpk"))?;
        let state = TrainerState {
            format: STATE_FORMAT.into(),
            version: STATE_VERSION,
            config: self.config.clone(),
            step: self.step,
            next_episode: self.next_episode,
            rng: self.rng.clone(),
            replay: self.replay.iter().map(|e| e.record.clone()).collect(),
            running: self.running.iter().map(|e| e.record.clone()).collect(),
        };
        let json = serde_json::to_string(&state).expect("state serialises");
        afg_game::fs::write_atomic(&fresh.join("state.json"), json.as_bytes())?;
        // The previous checkpoint is kept as checkpoint.old until the next save, so
        // that a crash at any moment leaves one complete checkpoint to resume from.
        let current = checkpoint_dir(dir);
        let old = previous_checkpoint_dir(dir);
        if current.exists() {
            if old.exists() {
                std::fs::remove_dir_all(&old).map_err(io(&old))?;
            }
            std::fs::rename(&current, &old).map_err(io(&current))?;
        }
        std::fs::rename(&fresh, &current).map_err(io(&fresh))?;
        afg_game::fs::sync_dir(dir).map_err(io(dir))?;
        Ok(())
    }

    /// Whether `dir` holds a checkpoint (the current or the previous one).
    pub fn has_checkpoint(dir: &Path) -> bool {
        checkpoint_dir(dir).exists() || previous_checkpoint_dir(dir).exists()
    }

    /// Restores a run from `dir/checkpoint`, or, if that is missing or unusable (a
    /// crash while it was replaced), from the previous one, `dir/checkpoint.old`.
    ///
    /// # Errors
    /// As [`Trainer::resume_from`], for the current checkpoint when both fail.
    pub fn resume(dir: &Path) -> Result<Self, LearnError> {
        match Self::resume_from(&checkpoint_dir(dir)) {
            Ok(trainer) => Ok(trainer),
            Err(e) => Self::resume_from(&previous_checkpoint_dir(dir)).map_err(|_| e),
        }
    }

    /// Restores a run from the checkpoint directory `ckpt`.
    ///
    /// # Errors
    /// [`LearnError::Checkpoint`] for a missing, truncated, foreign or inconsistent
    /// checkpoint, and [`LearnError::Weights`] for unusable network or optimiser files.
    pub fn resume_from(ckpt: &Path) -> Result<Self, LearnError> {
        let state_path = ckpt.join("state.json");
        let bad = |reason: String| LearnError::Checkpoint {
            path: state_path.display().to_string(),
            reason,
        };
        let text = std::fs::read_to_string(&state_path).map_err(|e| bad(e.to_string()))?;
        if crate::format::is_older(&text) {
            return Err(bad(crate::format::older_format_hint()));
        }
        let state: TrainerState =
            serde_json::from_str(&text).map_err(|e| bad(format!("corrupt or truncated: {e}")))?;
        if state.format != STATE_FORMAT || state.version != STATE_VERSION {
            return Err(bad(format!(
                "format {} version {}, expected {STATE_FORMAT} {STATE_VERSION}",
                state.format, state.version
            )));
        }
        state.config.check()?;
        state.check().map_err(bad)?;
        let device = Default::default();
        let (online_config, online) = load_network::<TrainBackend>(&ckpt.join("online"), &device)?;
        let (target_config, target) = load_network::<InferBackend>(&ckpt.join("target"), &device)?;
        if online_config != state.config.network || target_config != state.config.network {
            return Err(bad(
                "the saved networks do not match the run's configuration".into(),
            ));
        }
        let optim_path = ckpt.join("optim.mpk");
        let record = NamedMpkFileRecorder::<FullPrecisionSettings>::new()
            .load(optim_path.clone(), &device)
            .map_err(|e| LearnError::Weights {
                path: optim_path.display().to_string(),
                reason: format!("corrupt or truncated: {e}"),
            })?;
        // Burn panics on a record of another optimiser shape; report that as an error.
        let optim = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            optimizer(&state.config).load_record(record)
        }))
        .map_err(|_| LearnError::Weights {
            path: optim_path.display().to_string(),
            reason: "the optimiser state does not fit the run's networks".into(),
        })?;
        Self::assemble(
            state.config,
            online,
            target,
            Some(optim),
            state.rng,
            state.replay,
            state.running,
            state.next_episode,
            state.step,
        )
    }
}
