//! The price-structured allocator (ours, not in the paper).
//!
//! The welfare problem is a min-cost flow, so LP duality gives per-task prices π such
//! that every robot of an optimal assignment takes `argmin_j [β d(i, j) − π_j]`;
//! Nearest is that rule with π = 0. The model learns π as a function of the state:
//! `Q(s, a) = π_a(s) − β d(t, a)`, where `π_a(s)` is one MLP shared by all tasks
//! ([`TaskMlp`]) reading per-task summaries of the state ([`PriceState`]): the task's
//! members, reward and the demand of the robots still to act. The output layer starts
//! at zero, so the untrained model is exactly Nearest. It is trained by regression on
//! the exact `Q*` of the sequential MDP ([`crate::regret::q_star`]), on states its own rollouts
//! visit (DAgger, Ross et al. 2011; [`PriceTrainer`]).
//!
//! Two ways to allocate ([`PriceMode`]):
//! - *sequential*, in the paper's MDP: robots in index order, each taking the best
//!   `Q(s, a)` with the prices of the current state. O(N · M · h²).
//! - *one-shot*: the prices of the empty state, once; then every robot takes
//!   `argmin_j [β d(i, j) − π_j]` among the tasks with room. O(N · M) plus one network
//!   pass per task.
//!
//! Every input is per task, so the same weights serve any M.
//!
//! Where the instance allows the void task (GRAPE's game), staying out is one more
//! action worth 0 beside every `π_a − β d(t, a)`: a robot stays out when each task's is
//! below 0. The committed models were trained on the paper's game only (ours, not
//! retrained for the void).

mod config;
pub(crate) mod net;
mod train;

use std::path::Path;

use afg_baseline::{AllocError, AllocStats, Allocation, Allocator};
use afg_game::{Instance, RobotId, TaskId};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use afg_graph::{PriceState, TASK_FEATURES};
pub use config::PriceTrainConfig;
use net::PriceScratch;
pub use net::{PRICE_INPUTS, PriceNet, PriceNetConfig, TaskMlp};
pub use train::{PriceRound, PriceTrainer};

use crate::LearnError;
use crate::model_file::{check_model_file, read_model_file, write_model_file};
use crate::targets::masked_argmax;

/// How a [`PricePolicy`] allocates (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PriceMode {
    /// Prices of the current state at every step.
    Sequential,
    /// Prices of the empty state for every robot.
    OneShot,
}

impl PriceMode {
    /// `sequential` or `one-shot`.
    pub fn name(self) -> &'static str {
        match self {
            PriceMode::Sequential => "sequential",
            PriceMode::OneShot => "one-shot",
        }
    }
}

/// A trained price model and the settings it was trained with, as saved in a file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriceModel {
    format: String,
    version: u32,
    /// The settings of the training run.
    pub training: PriceTrainConfig,
    /// The weights.
    pub mlp: TaskMlp,
}

const PRICE_FORMAT: &str = "afg-price-model";
const PRICE_VERSION: u32 = 1;

impl PriceModel {
    /// The model's file name in a run directory.
    pub const FILE_NAME: &str = "price.json";

    /// A model with these weights, trained with `training`.
    pub fn new(training: PriceTrainConfig, mlp: TaskMlp) -> Self {
        PriceModel {
            format: PRICE_FORMAT.into(),
            version: PRICE_VERSION,
            training,
            mlp,
        }
    }

    /// Writes the model as JSON (temporary file, then rename).
    ///
    /// # Errors
    /// [`LearnError::Weights`] if the file cannot be written.
    pub fn save(&self, path: &Path) -> Result<(), LearnError> {
        write_model_file(self, path)
    }

    /// Reads a model written by [`PriceModel::save`].
    ///
    /// # Errors
    /// [`LearnError::Weights`] for an unreadable or malformed file, another format or
    /// version, or weights whose shapes or values do not fit the recorded network.
    pub fn load(path: &Path) -> Result<Self, LearnError> {
        let model: PriceModel = read_model_file(path, "a price model")?;
        let hidden = model.training.network.hidden;
        check_model_file(
            path,
            (&model.format, model.version),
            (PRICE_FORMAT, PRICE_VERSION),
            model.mlp.has_shape(hidden).then_some(()).ok_or_else(|| {
                format!(
                    "the weights are not those of a price network of width {hidden} (or not finite)"
                )
            }),
        )?;
        Ok(model)
    }
}

impl PriceTrainer {
    /// Trains to the end with run directory `dir` (created if needed, then locked as a
    /// [`RunDir`](crate::run_dir::RunDir) is, so that a second trainer is refused): after each
    /// round the log ([`RunDir::LOG`](crate::run_dir::RunDir::LOG), one [`PriceRound`] per line) is rewritten
    /// atomically and `on_round` called; at the end the run's manifest
    /// ([`RunManifest`](crate::manifest::RunManifest), with `command`) and then the model
    /// ([`PriceModel::FILE_NAME`]) are written. A run
    /// killed before its end leaves no model; the same call starts it again from round
    /// 0 and, being seeded, ends with the same weights.
    ///
    /// # Errors
    /// [`LearnError::RunInUse`] while another trainer holds the directory, a failed
    /// round, or a file that cannot be written.
    pub fn run_in(
        self,
        dir: &Path,
        command: String,
        on_round: impl FnMut(&PriceRound),
    ) -> Result<crate::manifest::RunManifest, LearnError> {
        crate::rounds::run_rounds(self, dir, command, |_| Ok(()), on_round)
    }
}

impl crate::rounds::RoundTrainer for PriceTrainer {
    type Round = PriceRound;

    fn is_finished(&self) -> bool {
        PriceTrainer::is_finished(self)
    }

    fn next_round(&mut self) -> Result<PriceRound, LearnError> {
        self.round()
    }

    fn record(&self, last: Option<PriceRound>) -> (crate::manifest::RunRecord, u64) {
        let training = self.config();
        let record = crate::manifest::RunRecord::PriceModel {
            rounds: training.rounds,
            last_round: last,
        };
        (record, training.seed)
    }

    fn save_model(&self, dir: &Path) -> Result<(), LearnError> {
        self.model().save(&dir.join(PriceModel::FILE_NAME))
    }
}

/// The price model as an [`Allocator`].
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Nearest};
/// use afg_game::GeneratorConfig;
/// use afg_learn::price::{TaskMlp, PriceMode, PriceNetConfig, PricePolicy};
/// // An untrained model has every price at 0: it is Nearest.
/// let net = PriceNetConfig { hidden: 16, seed: 0 }.init::<afg_learn::InferBackend>(&Default::default());
/// let policy = PricePolicy::new(TaskMlp::from_burn(&net), PriceMode::Sequential);
/// let inst = GeneratorConfig::paper(50, 5, 2).generate()?;
/// assert_eq!(
///     policy.allocate(&inst)?.assignment,
///     Nearest.allocate(&inst)?.assignment
/// );
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct PricePolicy {
    mlp: TaskMlp,
    mode: PriceMode,
    block: usize,
}

impl PricePolicy {
    /// A policy with these weights.
    pub fn new(mlp: TaskMlp, mode: PriceMode) -> Self {
        PricePolicy {
            mlp,
            mode,
            block: 1,
        }
    }

    /// Sequential mode: recompute the prices once per `block` robots instead of at every
    /// step (1, the default, is the exact sequential rollout). ⌈N / block⌉ network
    /// evaluations replace N; the features are still kept up to date at every step.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] for a block of 0.
    pub fn with_block(mut self, block: usize) -> Result<Self, LearnError> {
        if block == 0 {
            return Err(LearnError::InvalidConfig(
                "the block must be at least 1".into(),
            ));
        }
        self.block = block;
        Ok(self)
    }

    /// Robots per price evaluation in the sequential mode.
    pub fn block(&self) -> usize {
        self.block
    }

    /// The policy of a saved model.
    ///
    /// # Errors
    /// See [`PriceModel::load`].
    pub fn load(path: &Path, mode: PriceMode) -> Result<Self, LearnError> {
        Ok(PricePolicy::new(PriceModel::load(path)?.mlp, mode))
    }

    /// How it allocates.
    pub fn mode(&self) -> PriceMode {
        self.mode
    }

    /// The task robot `t` takes in `state` with prices `prices`: the best
    /// `π_a − β d(t, a)` among tasks with room. `None` when none has room or, where
    /// the instance allows the void task, when that best is below the void's 0.
    pub(super) fn choose(
        state: &PriceState<'_>,
        robot: RobotId,
        prices: &[f32],
        q: &mut [f32],
        mask: &mut [bool],
    ) -> Option<TaskId> {
        let inst = state.instance();
        for j in inst.task_ids() {
            q[j.index()] = prices[j.index()] - state.cost(robot, j) as f32;
            mask[j.index()] = state.assignment().has_room(inst, robot, j);
        }
        let best = masked_argmax(q, mask)?;
        let out = inst.allows_void() && q[best] < 0.0;
        (!out).then_some(TaskId(best as u32))
    }

    /// The greedy rollout of this policy.
    pub fn rollout<'a>(&self, instance: &'a Instance) -> Result<PriceState<'a>, AllocError> {
        let m = instance.num_tasks();
        let mut state = PriceState::new(instance);
        let mut features = vec![0.0; m * TASK_FEATURES];
        let (mut prices, mut q, mut mask) = (vec![0.0; m], vec![0.0; m], vec![false; m]);
        let mut scratch = PriceScratch::default();
        state.features(&mut features);
        self.mlp.prices_with(&features, &mut prices, &mut scratch);
        let uncapped = instance
            .task_ids()
            .all(|j| instance.capacity(j) == usize::MAX);
        if self.mode == PriceMode::OneShot && uncapped {
            // Fixed prices and no capacities: robots do not interact, so every robot's
            // choice is made on all cores, then placed in order.
            let tasks: Vec<Option<TaskId>> = (0..instance.num_robots() as u32)
                .into_par_iter()
                .map_init(
                    || (vec![0.0; m], vec![false; m]),
                    |(q, mask), robot| Self::choose(&state, RobotId(robot), &prices, q, mask),
                )
                .collect();
            for (robot, task) in instance.robot_ids().zip(tasks) {
                Self::place(&mut state, robot, task)?;
            }
            return Ok(state);
        }
        for robot in instance.robot_ids() {
            let refresh = robot.index() > 0 && robot.index() % self.block == 0;
            if self.mode == PriceMode::Sequential && refresh {
                state.features(&mut features);
                self.mlp.prices_with(&features, &mut prices, &mut scratch);
            }
            let task = Self::choose(&state, robot, &prices, &mut q, &mut mask);
            Self::place(&mut state, robot, task)?;
        }
        Ok(state)
    }

    /// Puts `robot` where [`PricePolicy::choose`] sent it: in `task`, or, with `None`,
    /// in the void where the instance allows it.
    fn place(
        state: &mut PriceState<'_>,
        robot: RobotId,
        task: Option<TaskId>,
    ) -> Result<(), AllocError> {
        match task {
            Some(task) => state.assign(robot, task),
            None if state.instance().allows_void() => state.leave_out(robot),
            None => {
                return Err(AllocError::InvalidParameter(format!(
                    "no task has room for robot {robot}"
                )));
            }
        }
        Ok(())
    }
}

impl Allocator for PricePolicy {
    fn name(&self) -> String {
        format!("price-{}", self.mode.name())
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        afg_baseline::check_game(
            instance,
            self,
            afg_baseline::Plays::Concave(crate::TRAINED_CONCAVE),
        )?;
        let start = std::time::Instant::now();
        let state = self.rollout(instance)?;
        Ok(Allocation {
            assignment: state.assignment().clone(),
            stats: AllocStats {
                iterations: instance.num_robots() as u64,
                wall_time: start.elapsed(),
                ..AllocStats::default()
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Prices once per N robots are the one-shot prices; a block of 0 is refused; the
    /// blocked rollout stays complete.
    #[test]
    fn a_block_of_n_is_the_one_shot_mode() {
        // The committed model: its prices move with the state.
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/ours/price_n60/price.json");
        let mlp = PriceModel::load(&path).unwrap().mlp;
        let sequential = PricePolicy::new(mlp.clone(), PriceMode::Sequential);
        let one_shot = PricePolicy::new(mlp, PriceMode::OneShot);
        let mut moved = 0;
        for seed in 0..5 {
            let inst = afg_game::GeneratorConfig::paper(60, 5, seed)
                .generate()
                .unwrap();
            let once = one_shot.allocate(&inst).unwrap().assignment;
            let whole = sequential.clone().with_block(60).unwrap();
            assert_eq!(whole.allocate(&inst).unwrap().assignment, once);
            let blocked = sequential.clone().with_block(7).unwrap();
            assert!(blocked.allocate(&inst).unwrap().assignment.is_complete());
            moved += usize::from(sequential.allocate(&inst).unwrap().assignment != once);
        }
        assert!(
            moved > 0,
            "the prices must move for the test to mean anything"
        );
        assert!(matches!(
            sequential.with_block(0),
            Err(LearnError::InvalidConfig(_))
        ));
    }

    #[test]
    fn a_saved_model_loads_back_and_bad_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("afg-price-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let config = PriceTrainConfig::new(20, 5, 1);
        let net = config
            .network
            .init::<crate::InferBackend>(&Default::default());
        let model = PriceModel::new(config, TaskMlp::from_burn(&net));
        let path = dir.join("model.json");
        model.save(&path).unwrap();
        assert_eq!(PriceModel::load(&path).unwrap(), model);

        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, &text[..text.len() / 2]).unwrap();
        assert!(matches!(
            PriceModel::load(&path),
            Err(LearnError::Weights { .. })
        ));

        let mut other = model.clone();
        other.training.network.hidden += 1;
        other.save(&path).unwrap();
        let err = PriceModel::load(&path).unwrap_err().to_string();
        assert!(err.contains("width"), "{err}");

        std::fs::write(&path, text.replace("afg-price-model", "afg-weights")).unwrap();
        assert!(
            PriceModel::load(&path)
                .unwrap_err()
                .to_string()
                .contains("format")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_run_writes_its_log_model_and_summary() {
        let dir = std::env::temp_dir().join(format!("afg-price-run-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut config = PriceTrainConfig::new(12, 3, 4);
        (
            config.rounds,
            config.episodes_per_round,
            config.steps_per_round,
        ) = (2, 2, 5);
        config.validation_instances = 2;
        let mut rounds = Vec::new();
        let run = dir.join("run");
        // While another trainer holds the directory, a run into it is refused.
        std::fs::create_dir_all(&run).unwrap();
        let held = crate::run_dir::RunDir::new(&run).lock().unwrap();
        let refused =
            PriceTrainer::new(config.clone())
                .unwrap()
                .run_in(&run, "train it".into(), |_| ());
        assert!(
            matches!(refused, Err(LearnError::RunInUse { .. })),
            "{refused:?}"
        );
        drop(held);
        let manifest = PriceTrainer::new(config.clone())
            .unwrap()
            .run_in(&run, "train it".into(), |r| rounds.push(r.clone()))
            .unwrap();
        assert_eq!(
            crate::run_dir::RunDir::new(&run).manifest().unwrap(),
            manifest
        );
        let crate::manifest::RunRecord::PriceModel { last_round, .. } = &manifest.record else {
            unreachable!("a price run")
        };
        assert_eq!(
            (manifest.command.as_str(), last_round.as_ref()),
            ("train it", Some(&rounds[1]))
        );
        assert_eq!(
            crate::run_dir::RunDir::new(&run).kind().unwrap(),
            crate::manifest::ModelKind::PriceModel
        );
        let log = std::fs::read_to_string(run.join(crate::run_dir::RunDir::LOG)).unwrap();
        let logged: Vec<PriceRound> = log
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(logged, rounds);
        assert_eq!(
            PriceModel::load(&run.join(PriceModel::FILE_NAME))
                .unwrap()
                .training,
            config
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
