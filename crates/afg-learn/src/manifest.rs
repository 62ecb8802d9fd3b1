//! `manifest.json`: how to rerun a finished run and what it cost, for every kind of
//! model, written and read through [`RunDir`].

use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::run_dir::{LogEvent, RunDir, ValidationLine};

/// How to rerun a finished run and what it cost (`manifest.json`), for every kind of
/// model: what the run trained ([`RunRecord`], tagged `kind`), the command, the seed,
/// the wall time and the weight files.
///
/// # Examples
/// ```
/// use afg_learn::run::{ModelKind, RunManifest, RunRecord};
/// let manifest = RunManifest::new(
///     "afg train-price --scale 60 --out m".into(),
///     0,
///     RunRecord::PriceModel { rounds: 40, last_round: None },
/// );
/// assert_eq!(manifest.kind(), ModelKind::PriceModel);
/// let json = serde_json::to_string(&manifest)?;
/// assert!(json.contains(r#""kind":"price-model""#) && json.contains(r#""version":2"#));
/// assert_eq!(serde_json::from_str::<RunManifest>(&json)?, manifest);
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunManifest {
    /// The format of the run's files ([`crate::run::RUN_FORMAT_VERSION`]).
    pub version: u32,
    /// What the run trained, and how it ended.
    #[serde(flatten)]
    pub record: RunRecord,
    /// The command line that reproduces the run.
    pub command: String,
    /// Seed of everything random in the run.
    pub seed: u64,
    /// Seconds of training, across resumes.
    pub wall_time_s: Option<f64>,
    /// The git revision the run started from.
    pub git_revision: Option<String>,
    /// The weight files, relative to the run directory.
    pub weights: Vec<String>,
}

/// The kinds of model a run directory can hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ModelKind {
    /// A Q network (AFGNet or S2V) trained by DQN, Double DQN or Q* regression:
    /// `config.json`, `log.jsonl` of events, `model.json` + `model.mpk`.
    QNetwork,
    /// The price model (ours): `price.json` (settings and weights), `log.jsonl` of rounds.
    PriceModel,
    /// The staffing model (ours): `staffing.json` (settings and weights), `log.jsonl` of
    /// epochs, `labels.jsonl` of labelled games.
    StaffingModel,
}

/// What a run trained and how it ended, by kind of model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum RunRecord {
    /// A Q network.
    QNetwork {
        /// Gradient steps.
        steps: u64,
        /// The last validation of the run.
        final_validation: Option<ValidationLine>,
    },
    /// The price model.
    PriceModel {
        /// DAgger rounds.
        rounds: usize,
        /// The last round.
        last_round: Option<crate::price::PriceRound>,
    },
    /// The staffing model.
    StaffingModel {
        /// Epochs.
        epochs: usize,
        /// The last epoch.
        last_epoch: Option<crate::staffing::StaffingEpoch>,
    },
}

impl RunManifest {
    /// The manifest of a run in the current format, its wall time, revision and
    /// weight files not yet known.
    pub fn new(command: String, seed: u64, record: RunRecord) -> Self {
        let weights = match record {
            RunRecord::QNetwork { .. } => RunDir::WEIGHT_FILES.to_vec(),
            RunRecord::PriceModel { .. } => vec![crate::price::PriceModel::FILE_NAME],
            RunRecord::StaffingModel { .. } => vec![crate::staffing::StaffingModel::FILE_NAME],
        };
        RunManifest {
            version: crate::format::RUN_FORMAT_VERSION,
            record,
            command,
            seed,
            wall_time_s: None,
            git_revision: None,
            weights: weights.into_iter().map(str::to_owned).collect(),
        }
    }

    /// The kind of model the run trained.
    pub fn kind(&self) -> ModelKind {
        match self.record {
            RunRecord::QNetwork { .. } => ModelKind::QNetwork,
            RunRecord::PriceModel { .. } => ModelKind::PriceModel,
            RunRecord::StaffingModel { .. } => ModelKind::StaffingModel,
        }
    }
}

impl RunDir {
    /// `manifest.json`.
    ///
    /// # Errors
    /// [`LearnError::RunFile`] if it is missing or not a manifest.
    pub fn manifest(&self) -> Result<RunManifest, LearnError> {
        self.read_json("manifest.json", "no manifest", "a run manifest")
    }

    /// The kind of model the directory holds: the one its manifest names, or a Q
    /// network for a run that has finished its weights but has no manifest yet.
    ///
    /// # Errors
    /// [`LearnError::RunFile`] if the directory holds neither, or its manifest cannot
    /// be read.
    pub fn kind(&self) -> Result<ModelKind, LearnError> {
        if self.has_manifest() {
            return Ok(self.manifest()?.kind());
        }
        if self.has_weights() {
            return Ok(ModelKind::QNetwork);
        }
        Err(LearnError::RunFile {
            path: self.path().display().to_string(),
            reason: "holds no finished run (no manifest.json, no model.json + model.mpk)".into(),
        })
    }

    /// The manifest of this finished run, from its config and log: `command`, seed,
    /// steps, wall time, the git revision the run started from and the last validation.
    ///
    /// # Errors
    /// [`LearnError::RunFile`] if the config or the log is missing or unreadable.
    pub fn manifest_from_log(&self, command: String) -> Result<RunManifest, LearnError> {
        let config = self.config()?;
        let events = self.log()?;
        let record = RunRecord::QNetwork {
            steps: config.steps,
            final_validation: events.iter().rev().find_map(|e| match e {
                LogEvent::Validation(v) => Some(v.clone()),
                _ => None,
            }),
        };
        Ok(RunManifest {
            wall_time_s: events.iter().rev().find_map(LogEvent::elapsed_s),
            git_revision: events.iter().find_map(|e| match e {
                LogEvent::Start { git_revision, .. } => git_revision.clone(),
                _ => None,
            }),
            ..RunManifest::new(command, config.seed, record)
        })
    }

    /// Writes `manifest.json` atomically.
    ///
    /// # Errors
    /// [`LearnError::Io`] if it cannot be written.
    pub fn write_manifest(&self, manifest: &RunManifest) -> Result<(), LearnError> {
        let json = serde_json::to_string_pretty(manifest).expect("a manifest serialises");
        afg_game::fs::write_atomic(&self.file("manifest.json"), json.as_bytes())?;
        Ok(())
    }
}
