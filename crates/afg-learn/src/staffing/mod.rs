//! The staffing model (ours, not in the paper): a learned allocator for the team
//! threshold game.
//!
//! In the team game the hard part is which tasks to staff: once that is decided, the
//! best place for every robot is a transport problem that afg solves exactly
//! ([`TeamOptimum::staff`]). Which tasks is a knapsack: each staffed task takes its
//! threshold k_j of the N robots and is worth something, and the thresholds of the best
//! staffing often add up to N exactly. So the model predicts what staffing each task is
//! worth and a knapsack ([`knapsack`], exact, O(N · M)) picks the tasks of most worth
//! whose thresholds fit in N; the transport solver places the robots
//! ([`staff_by_values`]).
//!
//! A task's worth is `(k_j / share) · (m_j + z_j)`: `m_j`, what a member earns at the
//! threshold less the mean cost of the task's k_j nearest robots (in units of the mean
//! member value, feature 6 of [`staffing_features`]), and `z_j` the network's correction.
//! The network reads each task's verdict in the root relaxation of the exact solver
//! ([`TeamOptimum::relax`]: every task's value replaced by its concave envelope, one
//! transport solve) and a few scale-free facts about its threshold. With `z = 0` — the
//! untrained network, whose output layer starts at zero — it is the hand-written
//! knapsack over each task's nearest robots, which ignores that tasks compete for the
//! same robots; the correction learns that competition from the relaxation.
//!
//! The network is one MLP shared by every task (the price model's shape,
//! [`PriceNet`](crate::price::PriceNet): `inputs → h → h → 1`, ReLU), reading the
//! task's features and the mean of all tasks', so the same weights serve any N and M.
//! It is trained as a structured predictor ([`StaffingTrainer`]): on generated games
//! labelled with the staffing of their certified optimum, the structured hinge loss of
//! the knapsack's choice (Taskar et al. 2005; the knapsack is the inference). This is
//! neural diving (Nair et al. 2020) with an exact sub-solver on each side: the network
//! fixes the integer decisions through a knapsack, the flow does the rest. No repair
//! follows.
//!
//! **Skills.** A model trained on skill games (`StaffingTrainConfig::skills`) reads
//! three more features per task — whether its nearest robots hold what it requires,
//! how much further the holders are, how scarce the skills are over all tasks — and
//! is labelled with the tasks that *earn* in the optimum (team complete, skills held).
//! Its placement is [`TeamOptimum::staff`], which then also brings each staffed team
//! the skills it lacks (the exact solver's skill branching followed down one side), so
//! it is no longer exact there. A model trained without skills refuses skill games.

mod features;
mod labels;
mod train;

use std::path::Path;

use afg_baseline::{AllocError, AllocStats, Allocation, Allocator, TeamOptimum};
use afg_game::{Assignment, Instance};
use serde::{Deserialize, Serialize};

pub use features::{COUNT_FEATURES, STAFF_FEATURES, staffing_features, staffing_input_width};
pub use labels::{GameDraw, LABELS_FILE_NAME, LabelledGame, scarce_game};
pub use train::{StaffingEpoch, StaffingTrainConfig, StaffingTrainer};

use crate::LearnError;
use crate::model_file::{check_model_file, read_model_file, write_model_file};
use crate::price::TaskMlp;

/// A trained staffing model and the settings it was trained with, as saved in a file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaffingModel {
    format: String,
    version: u32,
    /// The settings of the training run.
    pub training: StaffingTrainConfig,
    /// The weights (an MLP of the price model's shape, [`staffing_input_width`] wide).
    pub mlp: TaskMlp,
}

const STAFFING_FORMAT: &str = "afg-staffing-model";
const STAFFING_VERSION: u32 = 1;

impl StaffingModel {
    /// The model's file name in a run directory.
    pub const FILE_NAME: &str = "staffing.json";

    /// A model with these weights, trained with `training`.
    pub fn new(training: StaffingTrainConfig, mlp: TaskMlp) -> Self {
        StaffingModel {
            format: STAFFING_FORMAT.into(),
            version: STAFFING_VERSION,
            training,
            mlp,
        }
    }

    /// Writes the model as JSON (temporary file, then rename).
    ///
    /// # Errors
    /// [`LearnError::Io`] if the file cannot be written.
    pub fn save(&self, path: &Path) -> Result<(), LearnError> {
        write_model_file(self, path)
    }

    /// Reads a model written by [`StaffingModel::save`].
    ///
    /// # Errors
    /// [`LearnError::Weights`] for an unreadable or malformed file, another format or
    /// version, or weights whose shapes or values do not fit the recorded network.
    pub fn load(path: &Path) -> Result<Self, LearnError> {
        let model: StaffingModel = read_model_file(path, "a staffing model")?;
        let hidden = model.training.network.hidden;
        let width = model.training.input_width();
        check_model_file(
            path,
            (&model.format, model.version),
            (STAFFING_FORMAT, STAFFING_VERSION),
            model.mlp.has_layers(width, hidden).then_some(()).ok_or_else(|| {
                format!("the weights are not those of a staffing network of width {hidden} (or not finite)")
            }),
        )?;
        Ok(model)
    }
}

/// The staffing model as an [`Allocator`]: it plays the paper's game and team
/// thresholds and, where it was trained on skill games (it reads the skill features),
/// skills too; a model trained without skills refuses them (its features count robots,
/// not skills).
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, TeamOptimum};
/// use afg_game::GeneratorConfig;
/// use afg_learn::price::PriceNetConfig;
/// use afg_learn::staffing::StaffingPolicy;
/// let mut cfg = GeneratorConfig::paper(40, 5, 3);
/// cfg.min_team = Some(afg_game::CountRange { min: 8, max: 16 });
/// let inst = cfg.generate()?;
/// // Untrained, every correction is 0: the hand-written knapsack over each task's
/// // nearest robots.
/// let policy = StaffingPolicy::untrained(PriceNetConfig { hidden: 8, seed: 0 }, false);
/// let out = policy.allocate(&inst)?;
/// assert!(inst.welfare(&out.assignment) <= TeamOptimum::default().solve(&inst)?.welfare + 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct StaffingPolicy {
    mlp: TaskMlp,
    reads_skills: bool,
    repair: bool,
}

impl StaffingPolicy {
    /// A policy with these weights: a network reading the skill features
    /// ([`staffing_input_width`]`(true)` inputs) plays skill games, one reading only
    /// the robot counts does not.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] if they are not a staffing network's.
    pub fn new(mlp: TaskMlp) -> Result<Self, LearnError> {
        let reads = |skills| mlp.has_layers(staffing_input_width(skills), mlp.hidden());
        let reads_skills = match (reads(false), reads(true)) {
            (true, _) => false,
            (_, true) => true,
            _ => {
                return Err(LearnError::InvalidConfig(
                    "the weights are not those of a staffing network".into(),
                ));
            }
        };
        Ok(StaffingPolicy {
            mlp,
            reads_skills,
            repair: false,
        })
    }

    /// The untrained network of `config` (every correction 0), reading the skill
    /// features where `reads_skills`.
    pub fn untrained(config: crate::price::PriceNetConfig, reads_skills: bool) -> Self {
        let net = crate::price::PriceNet::<crate::InferBackend>::seeded(
            &mut <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(config.seed),
            staffing_input_width(reads_skills),
            config.hidden,
            &Default::default(),
        );
        StaffingPolicy {
            mlp: TaskMlp::from_burn(&net),
            reads_skills,
            repair: false,
        }
    }

    /// Whether a welfare climb ([`afg_baseline::climb`]: robot moves, pairwise swaps and
    /// whole teams dissolved or staffed, each taken while it raises the welfare) follows
    /// the placement (ours). With skills
    /// the placement brings each staffed team the skills it lacks one robot at a time,
    /// and the climb takes back what that costs.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Allocator;
    /// use afg_learn::price::PriceNetConfig;
    /// use afg_learn::staffing::StaffingPolicy;
    /// let inst = afg_game::Family::SparseSkills.config(60, 6, 2)?.generate()?;
    /// let policy = StaffingPolicy::untrained(PriceNetConfig { hidden: 8, seed: 0 }, true);
    /// let placed = policy.allocate(&inst)?.assignment;
    /// let climbed = policy.with_repair(true).allocate(&inst)?.assignment;
    /// assert!(inst.welfare(&climbed) >= inst.welfare(&placed));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_repair(mut self, repair: bool) -> Self {
        self.repair = repair;
        self
    }

    /// The policy of a saved model.
    ///
    /// # Errors
    /// See [`StaffingModel::load`].
    pub fn load(path: &Path) -> Result<Self, LearnError> {
        Self::new(StaffingModel::load(path)?.mlp)
    }

    /// What staffing each task of `instance` is worth, by the model (see the module
    /// docs).
    pub fn values(&self, instance: &Instance) -> Vec<f64> {
        let root = TeamOptimum::relax(instance);
        values_of(
            &self.mlp,
            &staffing_features(instance, &root),
            self.reads_skills,
        )
    }
}

/// Each task's worth `(k_j / share) · (m_j + z_j)` from its features
/// (`[M, STAFF_FEATURES]`) and the network's corrections, the network reading the
/// skill features where `reads_skills`.
pub(crate) fn values_of(mlp: &TaskMlp, features: &[f32], reads_skills: bool) -> Vec<f64> {
    let inputs = features::staffing_inputs(features, reads_skills);
    let mut corrections = vec![0.0; features.len() / STAFF_FEATURES];
    mlp.forward_rows(&inputs, &mut corrections);
    features
        .chunks_exact(STAFF_FEATURES)
        .zip(corrections)
        .map(|(f, z)| f64::from(f[features::SIZE]) * f64::from(f[features::MARGIN] + z))
        .collect()
}

/// The items of most total value whose weights fit in `capacity`: an exact 0/1
/// knapsack by dynamic programming over the capacity, O(items · capacity) time, one bit
/// per item and capacity kept for the answer. Items of value ≤ 0 are never taken.
///
/// # Examples
/// ```
/// use afg_learn::staffing::knapsack;
/// // Thresholds 10, 13, 13 and 15 robots; 26 robots fit the two thirteens (worth 5),
/// // not 10 + 15 (worth 4.5).
/// let take = knapsack(&[10, 13, 13, 15], &[2.0, 2.5, 2.5, 2.5], 26);
/// assert_eq!(take, [false, true, true, false]);
/// ```
///
/// # Panics
/// If `weights` and `values` differ in length.
pub fn knapsack(weights: &[usize], values: &[f64], capacity: usize) -> Vec<bool> {
    assert_eq!(weights.len(), values.len(), "one value per weight");
    let width = capacity + 1;
    let mut best = vec![0.0f64; width];
    let mut taken = vec![false; weights.len() * width];
    for (item, (&w, &v)) in weights.iter().zip(values).enumerate() {
        if v <= 0.0 || w > capacity {
            continue;
        }
        for c in (w..width).rev() {
            let with = best[c - w] + v;
            if with > best[c] {
                best[c] = with;
                taken[item * width + c] = true;
            }
        }
    }
    let mut take = vec![false; weights.len()];
    let mut c = capacity;
    for item in (0..weights.len()).rev() {
        if taken[item * width + c] {
            take[item] = true;
            c -= weights[item];
        }
    }
    take
}

/// The placement of the staffing of most worth: the tasks that a [`knapsack`] over
/// their thresholds (capacity N) picks by `values`, placed by [`TeamOptimum::staff`];
/// where that leaves robots with no place (every unstaffed task capped, no void), the
/// other tasks that still fit are added in the order of their values until it does not.
/// The assignment and its welfare.
///
/// # Errors
/// [`AllocError::InvalidParameter`] if no such staffing places every robot.
///
/// # Examples
/// ```
/// use afg_baseline::TeamOptimum;
/// use afg_game::GeneratorConfig;
/// use afg_learn::staffing::staff_by_values;
/// let mut cfg = GeneratorConfig::paper(40, 5, 3);
/// cfg.min_team = Some(afg_game::CountRange { min: 8, max: 16 });
/// let inst = cfg.generate()?;
/// let (placed, welfare) = staff_by_values(&inst, &[1.0, -1.0, 1.0, 1.0, -1.0])?;
/// assert_eq!(inst.welfare(&placed), welfare);
/// assert!(welfare <= TeamOptimum::relax(&inst).bound + 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Panics
/// If `values` does not hold one value per task.
pub fn staff_by_values(
    instance: &Instance,
    values: &[f64],
) -> Result<(Assignment, f64), AllocError> {
    let unstaffable = instance.unstaffable_tasks();
    let weights: Vec<usize> = instance
        .task_ids()
        .map(|j| {
            if unstaffable.contains(&j) {
                usize::MAX // never fits
            } else {
                instance.min_team(j)
            }
        })
        .collect();
    let mut staffed = knapsack(&weights, values, instance.num_robots());
    let mut left = instance.num_robots()
        - (0..weights.len())
            .filter(|&j| staffed[j])
            .map(|j| weights[j])
            .sum::<usize>();
    let mut rest: Vec<usize> = (0..weights.len()).filter(|&j| !staffed[j]).collect();
    rest.sort_by(|&a, &b| values[b].total_cmp(&values[a]).then(a.cmp(&b)));
    let mut rest = rest.into_iter();
    loop {
        if let Some(found) = TeamOptimum::staff(instance, &staffed) {
            return Ok(found);
        }
        let Some(j) = rest.by_ref().find(|&j| weights[j] <= left) else {
            return Err(AllocError::InvalidParameter(
                "no staffing places every robot (every task capped and no void)".into(),
            ));
        };
        staffed[j] = true;
        left -= weights[j];
    }
}

impl Allocator for StaffingPolicy {
    fn name(&self) -> String {
        "staffing".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        if !self.reads_skills && instance.has_skill_rules() {
            return Err(AllocError::TeamsNotSupported {
                method: self.name(),
                rules: "skill requirements",
                reason: "this model was trained without skills, and its features count robots, not \
                         the skills they hold (a model trained with `afg train-staffing --skills`, \
                         such as models/ours/staffing_skills, plays them)",
            });
        }
        let start = std::time::Instant::now();
        let (mut assignment, _) = staff_by_values(instance, &self.values(instance))?;
        let moves = if self.repair {
            afg_baseline::climb(instance, &mut assignment)
        } else {
            0
        };
        Ok(Allocation {
            assignment,
            stats: AllocStats {
                iterations: 2 + moves, // the relaxation, the placement, each change of the climb
                wall_time: start.elapsed(),
                ..AllocStats::default()
            },
        })
    }
}
