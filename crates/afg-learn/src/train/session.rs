//! A training run driven in its run directory: the log, the checkpoints and the final
//! weights written as the trainer goes ([`Session`]).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

use afg_baseline::Method;

use super::{StepReport, TrainConfig, Trainer, Validation, validation_instances};
use crate::LearnError;
use crate::run_dir::{LogEvent, RunDir, RunLock, ValidationLine};
use crate::weights::save_network;

/// A [`Trainer`] attached to its [`RunDir`], which it holds locked: [`Session::run`]
/// logs the mean loss every ten steps and every validation to `log.jsonl`, writes a
/// checkpoint at a fixed wall-time interval and at the end, then the final weights.
pub struct Session {
    run: RunDir,
    _lock: RunLock,
    trainer: Trainer,
    /// Seconds of training before this session (after a resume).
    elapsed_before: f64,
}

impl Session {
    /// Starts a new run in `dir` (which must not hold one): writes `config.json` and the
    /// log's start event, with the mean welfare of the classical methods on the
    /// validation set and `git_revision`.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] for invalid settings; a directory that holds a run or is
    /// in use; an unwritable directory.
    pub fn start(
        dir: &Path,
        config: TrainConfig,
        git_revision: Option<String>,
    ) -> Result<Session, LearnError> {
        config.check()?;
        let (run, lock) = RunDir::create(dir, &config)?;
        let trainer = Trainer::new(config.clone())?;
        run.append(&LogEvent::Start {
            version: crate::format::RUN_FORMAT_VERSION,
            baselines: baselines(&config)?,
            config: Box::new(config),
            git_revision,
        })?;
        Ok(Session {
            run,
            _lock: lock,
            trainer,
            elapsed_before: 0.0,
        })
    }

    /// Continues the run in `dir` from its last good checkpoint (see
    /// [`Trainer::resume`]); log lines written after it are dropped. A run stopped
    /// before its first checkpoint starts again from step 0 with its own settings
    /// (the same seed gives the same run).
    ///
    /// # Errors
    /// A directory in use or holding no run, or checkpoints that are all unusable.
    pub fn resume(dir: &Path) -> Result<Session, LearnError> {
        let run = RunDir::new(dir);
        let lock = run.lock()?;
        let trainer = if Trainer::has_checkpoint(dir) {
            Trainer::resume(dir)?
        } else {
            Trainer::new(run.config()?)?
        };
        let elapsed_before = run.truncate_log(trainer.steps_done())?;
        Ok(Session {
            run,
            _lock: lock,
            trainer,
            elapsed_before,
        })
    }

    /// The trainer.
    pub fn trainer(&self) -> &Trainer {
        &self.trainer
    }

    /// The run directory.
    pub fn run_dir(&self) -> &RunDir {
        &self.run
    }

    /// Trains to the end of the budget, calling `observe` after every step, with a
    /// checkpoint every `checkpoint_every` of wall time; then the final checkpoint,
    /// weights and end event. Returns the final validation.
    ///
    /// # Errors
    /// A failed step (a non-finite loss among them: the last checkpoint stays as it
    /// was) or an unwritable file.
    pub fn run(
        &mut self,
        checkpoint_every: Duration,
        mut observe: impl FnMut(&StepReport),
    ) -> Result<Validation, LearnError> {
        let started = Instant::now();
        // Seconds of training so far, across resumes (time lost after a run's last
        // checkpoint is not counted).
        let elapsed_before = self.elapsed_before;
        let elapsed = || elapsed_before + started.elapsed().as_secs_f64();
        let mut last_checkpoint = Instant::now();
        let mut window = Vec::new();
        while !self.trainer.is_finished() {
            let report = self.trainer.step()?;
            window.push(report.loss);
            if report.step.is_multiple_of(10) {
                let mean = window.iter().sum::<f32>() / window.len() as f32;
                window.clear();
                self.run.append(&LogEvent::Step {
                    step: report.step,
                    loss: mean,
                    epsilon: report.epsilon,
                    elapsed_s: elapsed(),
                })?;
            }
            if let Some(result) = &report.validation {
                let line = ValidationLine::new(report.step, result, elapsed());
                self.run.append(&LogEvent::Validation(line))?;
            }
            observe(&report);
            if last_checkpoint.elapsed() >= checkpoint_every {
                self.trainer.save_checkpoint(self.run.path())?;
                last_checkpoint = Instant::now();
            }
        }
        self.trainer.save_checkpoint(self.run.path())?;
        let config = self.trainer.config();
        save_network(self.trainer.network(), &config.network, &self.run.weights())?;
        self.run.append(&LogEvent::End {
            step: self.trainer.steps_done(),
            elapsed_s: elapsed(),
        })?;
        self.trainer.validate()
    }
}

/// Mean welfare of the classical methods on the validation set of `config`.
fn baselines(config: &TrainConfig) -> Result<BTreeMap<Method, f64>, LearnError> {
    let insts = validation_instances(
        config.robots,
        config.network.tasks(),
        config.validation_instances,
    )?;
    let mut out = BTreeMap::new();
    for m in Method::CENTRALISED {
        let alloc = m.allocator(0);
        let mut total = 0.0;
        for inst in &insts {
            total += inst.welfare(&alloc.allocate(inst)?.assignment);
        }
        out.insert(m, total / insts.len() as f64);
    }
    Ok(out)
}
