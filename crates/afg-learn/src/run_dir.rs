//! A training run's directory, the one owner of its files:
//!
//! | file | written by | content |
//! |---|---|---|
//! | `config.json` | [`RunDir::create`] | the format version and the [`TrainConfig`] |
//! | `log.jsonl` | [`RunDir::append`] | one [`LogEvent`] per line |
//! | `checkpoint/` | [`Trainer::save_checkpoint`](crate::Trainer::save_checkpoint) | the resumable state |
//! | `model.json`, `model.mpk` | [`save_network`](crate::weights::save_network) at [`RunDir::weights`] | the final weights |
//! | `manifest.json` | [`RunDir::write_manifest`] | a [`RunManifest`](crate::run::RunManifest): the kind of model, how to rerun it, what it cost |
//! | `.lock` | [`RunDir::lock`] | held while a trainer writes into the directory |
//!
//! Files of an older format are refused with a word on [`migrate_run`](crate::run::migrate_run).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use afg_baseline::Method;
use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::train::config::TrainConfig;
use crate::train::validation::Validation;

/// One line of `log.jsonl`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "lowercase")]
pub enum LogEvent {
    /// The run started.
    Start {
        /// The format of the run's files ([`crate::run::RUN_FORMAT_VERSION`]).
        version: u32,
        /// Its settings.
        config: Box<TrainConfig>,
        /// The git revision it was started from, if known.
        git_revision: Option<String>,
        /// Mean welfare of the classical methods on the validation set.
        baselines: BTreeMap<Method, f64>,
    },
    /// Mean loss over the last ten gradient steps.
    Step {
        /// Gradient steps done.
        step: u64,
        /// Mean loss of the steps since the previous line.
        #[serde(with = "crate::log_float")]
        loss: f32,
        /// ε used for acting.
        #[serde(with = "crate::log_float")]
        epsilon: f64,
        /// Seconds of training so far, across resumes.
        #[serde(with = "crate::log_float")]
        elapsed_s: f64,
    },
    /// The greedy policy on the validation set.
    Validation(ValidationLine),
    /// The run finished.
    End {
        /// Gradient steps done.
        step: u64,
        /// Seconds of training in all.
        #[serde(with = "crate::log_float")]
        elapsed_s: f64,
    },
}

/// A validation as logged.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ValidationLine {
    /// Gradient steps done.
    pub step: u64,
    /// Mean welfare.
    #[serde(with = "crate::log_float")]
    pub welfare: f64,
    /// Mean of welfare / OPT, in percent.
    #[serde(with = "crate::log_float")]
    pub percent_of_opt: f64,
    /// See [`Validation::largest_task_share`] (absent in logs written before it existed).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        with = "crate::log_float::option"
    )]
    pub largest_task_share: Option<f64>,
    /// See [`Validation::collapsed`] (absent in older logs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collapsed: Option<bool>,
    /// Seconds of training so far, across resumes.
    #[serde(with = "crate::log_float")]
    pub elapsed_s: f64,
}

impl ValidationLine {
    /// The log line of `result` at `step`.
    pub fn new(step: u64, result: &Validation, elapsed_s: f64) -> Self {
        ValidationLine {
            step,
            welfare: result.welfare,
            percent_of_opt: result.percent_of_opt,
            largest_task_share: Some(result.largest_task_share),
            collapsed: Some(result.collapsed()),
            elapsed_s,
        }
    }
}

impl LogEvent {
    /// The gradient step of the event (`None` for the start).
    pub fn step(&self) -> Option<u64> {
        match self {
            LogEvent::Start { .. } => None,
            LogEvent::Step { step, .. } | LogEvent::End { step, .. } => Some(*step),
            LogEvent::Validation(v) => Some(v.step),
        }
    }

    /// Seconds of training when the event was logged (`None` for the start).
    pub fn elapsed_s(&self) -> Option<f64> {
        match self {
            LogEvent::Start { .. } => None,
            LogEvent::Step { elapsed_s, .. } | LogEvent::End { elapsed_s, .. } => Some(*elapsed_s),
            LogEvent::Validation(v) => Some(v.elapsed_s),
        }
    }
}

/// `config.json` as written: the format version, then the configuration.
pub(crate) fn config_json(config: &TrainConfig) -> String {
    let json = serde_json::to_string_pretty(config).expect("a configuration serialises");
    // `{` and the fields of the configuration, with the version first.
    format!(
        "{{\n  \"version\": {},{}",
        crate::format::RUN_FORMAT_VERSION,
        &json[1..]
    )
}

/// The lines of a log as written with their events, and the number of a torn last line.
type LogLines = (Vec<(String, LogEvent)>, Option<usize>);

/// A training run's directory (see the module docs for its files).
///
/// # Examples
/// ```
/// use afg_learn::{nets::NetworkConfig, run::{LogEvent, RunDir}, train::{Algo, TrainConfig}};
///
/// let path = std::env::temp_dir().join(format!("afg-doc-run-{}", std::process::id()));
/// # let _ = std::fs::remove_dir_all(&path);
/// let config = TrainConfig::new(20, Algo::Ddqn, NetworkConfig::afgnet(5, 0), 100, 0);
/// let (run, _lock) = RunDir::create(&path, &config)?; // a second trainer is now refused
/// assert!(run.lock().is_err());
/// run.append(&LogEvent::End { step: 100, elapsed_s: 1.5 })?;
/// assert_eq!(run.config()?, config);
/// assert_eq!(run.log()?[0].step(), Some(100));
/// // A second run into the same directory is refused.
/// assert!(RunDir::create(&path, &config).is_err());
/// # drop(_lock);
/// # std::fs::remove_dir_all(&path)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RunDir {
    path: PathBuf,
}

/// Exclusive use of a run directory, released when dropped (or when the process ends).
#[derive(Debug)]
pub struct RunLock {
    file: File,
}

impl Drop for RunLock {
    fn drop(&mut self) {
        // The lock file stays: deleting it would let a second process lock a new file
        // of the same name while a third still holds the old one.
        let _ = self.file.unlock();
    }
}

impl RunDir {
    /// The files of the final weights, relative to the directory.
    pub const WEIGHT_FILES: [&'static str; 2] = ["model.json", "model.mpk"];

    /// The run directory at `path` (nothing is read or written).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        RunDir { path: path.into() }
    }

    /// A new run directory holding `config`, locked for the caller: the directory is
    /// made, then locked, then checked to hold no run, then `config.json` written.
    ///
    /// # Errors
    /// [`LearnError::RunFile`] if `path` already holds a run, [`LearnError::RunInUse`]
    /// if another process holds it, [`LearnError::Io`] if it cannot be written.
    pub fn create(
        path: impl Into<PathBuf>,
        config: &TrainConfig,
    ) -> Result<(Self, RunLock), LearnError> {
        let run = RunDir::new(path);
        std::fs::create_dir_all(&run.path).map_err(|source| LearnError::Io {
            path: run.path.display().to_string(),
            source,
        })?;
        let lock = run.lock()?;
        let config_path = run.path.join("config.json");
        if config_path.exists() {
            return Err(LearnError::RunFile {
                path: run.path.display().to_string(),
                reason: "already holds a training run; resume it or choose another directory"
                    .into(),
            });
        }
        afg_game::fs::write_atomic(&config_path, config_json(config).as_bytes())?;
        Ok((run, lock))
    }

    /// The training log of every kind of run: one JSON line per event or epoch.
    pub const LOG: &'static str = "log.jsonl";

    /// The files any run directory holds at least one of.
    pub const RUN_FILES: [&'static str; 4] = ["config.json", Self::LOG, "model.json", "price.json"];

    /// Every run directory at or below `root` (a directory holding one of
    /// [`RunDir::RUN_FILES`]; a run's own subdirectories are not searched), sorted by
    /// path.
    ///
    /// # Examples
    /// ```
    /// use afg_learn::run::RunDir;
    /// let models = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models");
    /// let runs = RunDir::find_all(&models).unwrap();
    /// assert!(runs.iter().any(|r| r.path().ends_with("paper/afgnet_ddqn_n20")));
    /// ```
    ///
    /// # Errors
    /// [`LearnError::Io`] if a directory cannot be listed.
    pub fn find_all(root: &Path) -> Result<Vec<RunDir>, LearnError> {
        let run = RunDir::new(root);
        if Self::RUN_FILES.iter().any(|f| run.file(f).exists()) {
            return Ok(vec![run]);
        }
        let io = |source| LearnError::Io {
            path: root.display().to_string(),
            source,
        };
        let mut runs = Vec::new();
        for entry in std::fs::read_dir(root).map_err(io)? {
            let entry = entry.map_err(io)?;
            if entry.file_type().map_err(io)?.is_dir() {
                runs.extend(Self::find_all(&entry.path())?);
            }
        }
        runs.sort_by(|a, b| a.path.cmp(&b.path));
        Ok(runs)
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The directory's name (its last component), or its path.
    pub fn name(&self) -> String {
        self.path.file_name().map_or_else(
            || self.path.display().to_string(),
            |f| f.to_string_lossy().into_owned(),
        )
    }

    /// The stem of the final weights (`model`, for [`crate::weights::load_network`]).
    pub fn weights(&self) -> PathBuf {
        self.path.join("model")
    }

    /// Whether the run has finished and saved its weights.
    pub fn has_weights(&self) -> bool {
        Self::WEIGHT_FILES.iter().all(|f| self.file(f).exists())
    }

    /// Whether the run has a log.
    pub fn has_log(&self) -> bool {
        self.file(Self::LOG).exists()
    }

    /// Whether the run has a manifest.
    pub fn has_manifest(&self) -> bool {
        self.file("manifest.json").exists()
    }

    /// The checkpoint directory.
    pub fn checkpoint(&self) -> PathBuf {
        checkpoint_dir(&self.path)
    }

    pub(crate) fn file(&self, name: &str) -> PathBuf {
        self.path.join(name)
    }

    /// Reads the JSON file `name`, a file of the current format, as a `T`; `missing`
    /// says what a missing file means, `kind` what the file should be. A file of an
    /// older format is refused with a word on the migration.
    pub(crate) fn read_json<T: serde::de::DeserializeOwned>(
        &self,
        name: &str,
        missing: &str,
        kind: &str,
    ) -> Result<T, LearnError> {
        let path = self.file(name);
        let bad = |reason| LearnError::RunFile {
            path: path.display().to_string(),
            reason,
        };
        let text = std::fs::read_to_string(&path).map_err(|e| bad(format!("{missing} ({e})")))?;
        if crate::format::is_older(&text) {
            return Err(bad(crate::format::older_format_hint()));
        }
        serde_json::from_str(&text).map_err(|e| bad(format!("not {kind}: {e}")))
    }

    /// Takes exclusive use of the directory for this process.
    ///
    /// # Errors
    /// [`LearnError::RunInUse`] if another [`RunLock`] holds it, [`LearnError::Io`] if
    /// the lock file cannot be opened.
    pub fn lock(&self) -> Result<RunLock, LearnError> {
        let path = self.file(".lock");
        let io = |source| LearnError::Io {
            path: path.display().to_string(),
            source,
        };
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(io)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(LearnError::RunInUse {
                    path: self.path.display().to_string(),
                });
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io(e)),
        }
        file.set_len(0).map_err(io)?;
        writeln!(file, "{}", std::process::id()).map_err(io)?;
        Ok(RunLock { file })
    }

    /// The run's settings (`config.json`).
    ///
    /// # Errors
    /// [`LearnError::RunFile`] if the directory holds no run or the file is not a
    /// training configuration.
    pub fn config(&self) -> Result<TrainConfig, LearnError> {
        let mut config: serde_json::Value = self.read_json(
            "config.json",
            "no training run here",
            "a training configuration",
        )?;
        if let Some(fields) = config.as_object_mut() {
            fields.remove("version");
        }
        serde_json::from_value(config).map_err(|e| LearnError::RunFile {
            path: self.file("config.json").display().to_string(),
            reason: format!("not a training configuration: {e}"),
        })
    }

    /// Appends one event to `log.jsonl`.
    ///
    /// # Errors
    /// [`LearnError::Io`] if the log cannot be written.
    pub fn append(&self, event: &LogEvent) -> Result<(), LearnError> {
        let path = self.file(Self::LOG);
        let io = |source| LearnError::Io {
            path: path.display().to_string(),
            source,
        };
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .map_err(io)?;
        let mut line = serde_json::to_string(event).expect("an event serialises");
        line.push('\n');
        // One write, so that a crash can only cut the last line short.
        f.write_all(line.as_bytes()).map_err(io)
    }

    /// Every event of `log.jsonl`, in order. A last line cut short (a crash while it
    /// was written: no line end, not an event) is left out; [`RunDir::torn_log_line`]
    /// reports it.
    ///
    /// # Errors
    /// [`LearnError::RunFile`] naming the line that is not an event, or the missing log.
    pub fn log(&self) -> Result<Vec<LogEvent>, LearnError> {
        Ok(self.log_lines()?.0.into_iter().map(|(_, e)| e).collect())
    }

    /// The number of the log's last line if a crash cut it short (it is then ignored).
    ///
    /// # Errors
    /// As [`RunDir::log`].
    pub fn torn_log_line(&self) -> Result<Option<usize>, LearnError> {
        Ok(self.log_lines()?.1)
    }

    /// Every non-blank line of `log.jsonl` as written, with its event, and the number of
    /// a torn last line.
    fn log_lines(&self) -> Result<LogLines, LearnError> {
        let path = self.file(Self::LOG);
        let text = std::fs::read_to_string(&path).map_err(|e| LearnError::RunFile {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        let mut lines: Vec<(usize, &str)> = text
            .lines()
            .enumerate()
            .filter(|(_, line)| !line.trim().is_empty())
            .map(|(i, line)| (i + 1, line))
            .collect();
        let mut torn = None;
        if !text.ends_with('\n')
            && let Some(&(number, last)) = lines.last()
            && serde_json::from_str::<LogEvent>(last).is_err()
        {
            torn = Some(number);
            lines.pop();
        }
        let events = lines
            .into_iter()
            .map(|(number, line)| {
                let event = serde_json::from_str(line).map_err(|e| LearnError::RunFile {
                    path: format!("{}:{number}", path.display()),
                    reason: if line.contains(r#""event":"start""#) && crate::format::is_older(line)
                    {
                        crate::format::older_format_hint()
                    } else {
                        format!("not a log event: {e}")
                    },
                })?;
                Ok((line.to_owned(), event))
            })
            .collect::<Result<_, LearnError>>()?;
        Ok((events, torn))
    }

    /// Keeps the log's lines up to gradient step `step`, as they were written (a resumed
    /// run repeats what came after), and returns the last kept `elapsed_s`, from which
    /// the resumed run's clock goes on. A missing log is an empty one.
    ///
    /// # Errors
    /// As [`RunDir::log`], and [`LearnError::Io`] if the log cannot be rewritten.
    pub fn truncate_log(&self, step: u64) -> Result<f64, LearnError> {
        if !self.has_log() {
            return Ok(0.0);
        }
        let (mut kept, mut elapsed) = (String::new(), 0.0f64);
        for (line, event) in self.log_lines()?.0 {
            if event.step().is_some_and(|s| s > step) {
                continue;
            }
            elapsed = elapsed.max(event.elapsed_s().unwrap_or(0.0));
            kept.push_str(&line);
            kept.push('\n');
        }
        afg_game::fs::write_atomic(&self.file(Self::LOG), kept.as_bytes())?;
        Ok(elapsed)
    }
}

/// Where [`Trainer::save_checkpoint`](crate::train::Trainer::save_checkpoint) puts the checkpoint of a run directory.
pub fn checkpoint_dir(dir: &Path) -> PathBuf {
    dir.join("checkpoint")
}

/// Where [`Trainer::save_checkpoint`](crate::train::Trainer::save_checkpoint) keeps the previous checkpoint.
pub(crate) fn previous_checkpoint_dir(dir: &Path) -> PathBuf {
    dir.join("checkpoint.old")
}

/// The checkpoint directories a run in `dir` may hold: the current and the previous.
pub(crate) fn checkpoint_dirs(dir: &Path) -> [PathBuf; 2] {
    [checkpoint_dir(dir), previous_checkpoint_dir(dir)]
}
