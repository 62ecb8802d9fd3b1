//! Training the staffing model: label generated team games with the staffing of the
//! best assignment found (proven optimal where the time limit allows), then fit the
//! network so that the knapsack over its worths picks that staffing (Adam on the
//! structured hinge loss, [`StaffingTrainer::epoch`]).
//!
//! The labelling (one exact solve per game) is the long part; it is kept in the run
//! directory ([`LABELS_FILE_NAME`], one game per line, written as it goes), so a run
//! stopped while labelling continues where it stopped. The fitting that follows is
//! seeded and takes seconds to minutes: a rerun repeats it and ends with the same
//! weights.

use std::path::Path;
use std::time::Duration;

use afg_game::{Family, GameSize, Instance, SkillDraw};
use burn::optim::adaptor::OptimizerAdaptor;
use burn::optim::{Adam, AdamConfig, GradientsParams, Optimizer};
use burn::tensor::{Tensor, TensorData};
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::features::{MARGIN, SIZE, STAFF_FEATURES, staffing_input_width, staffing_inputs};
use super::labels::{GameDraw, LABELS_FILE_NAME, LabelledGame, label, lines_of, read_labels};
use super::{StaffingModel, knapsack, staff_by_values, values_of};
use crate::price::{PriceNet, PriceNetConfig, TaskMlp};
use crate::train::training_instance_seed;
use crate::{LearnError, TrainBackend};

/// Every setting of a staffing training run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaffingTrainConfig {
    /// The sizes of the training games; each game's thresholds are uniform in
    /// [N/M, 2N/M] (scarce: they add up to about 1.5 N).
    pub sizes: Vec<GameSize>,
    /// The games' skills (`None`: thresholds only). A model trained with skills reads
    /// the skill features too and plays skill games; one trained without refuses them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skills: Option<SkillDraw>,
    /// Draw the games from these named families instead (each size's training and
    /// validation games per family; empty: the scarce game above). The model reads the
    /// skill features where any of them draws skills.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub families: Vec<Family>,
    /// Training games per size (per family and size, with families).
    pub games: usize,
    /// Validation games per size (other seeds).
    pub validation_games: usize,
    /// The exact solver's time limit per game, seconds (a game it does not prove is
    /// labelled with the best it found).
    pub label_time_limit: f64,
    /// The network and its initialisation seed.
    pub network: PriceNetConfig,
    /// Passes over every labelled game.
    pub epochs: usize,
    /// Games per Adam step.
    pub batch: usize,
    /// Adam learning rate at the start; it falls linearly to a tenth over the run.
    pub lr: f64,
    /// The structured loss's margin per task, in units of its worth's slope k_j / share.
    pub margin: f64,
    /// Seed of everything random in the run.
    pub seed: u64,
}

impl StaffingTrainConfig {
    /// The defaults (docs/teams.md): games of 100 robots and 10 tasks, 300 and 20, 600
    /// and 30, 600 of each; width 64; 60 epochs of 16 games per step, lr 1e-3.
    pub fn new(seed: u64) -> Self {
        StaffingTrainConfig {
            sizes: [(100, 10), (300, 20), (600, 30)]
                .map(|(robots, tasks)| GameSize { robots, tasks })
                .to_vec(),
            skills: None,
            families: Vec::new(),
            games: 600,
            validation_games: 20,
            label_time_limit: 10.0,
            network: PriceNetConfig { hidden: 64, seed },
            epochs: 60,
            batch: 16,
            lr: 1e-3,
            margin: 0.1,
            seed,
        }
    }

    fn validate(&self) -> Result<(), LearnError> {
        let bad = |what: &str| Err(LearnError::InvalidConfig(what.to_string()));
        if self.sizes.is_empty() || self.sizes.iter().any(|s| s.robots == 0 || s.tasks == 0) {
            return bad("give at least one size, with N and M at least 1");
        }
        if self.games == 0 || self.validation_games == 0 || self.epochs == 0 || self.batch == 0 {
            return bad("games, validation games, epochs and batch must be at least 1");
        }
        if self.network.hidden == 0 {
            return bad("the width must be at least 1");
        }
        if !(self.lr.is_finite() && self.lr > 0.0) {
            return bad("the learning rate must be positive and finite");
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return bad("the margin must be finite and not negative");
        }
        if !(self.label_time_limit.is_finite() && self.label_time_limit > 0.0) {
            return bad("the label time limit must be positive and finite");
        }
        if let Some(d) = self.skills
            && (d.count == 0 || !(0.0..=1.0).contains(&d.share) || d.requires.min > d.requires.max)
        {
            return bad("skills need S ≥ 1, a share in [0, 1] and requirements LO ≤ HI");
        }
        if self.skills.is_some() && !self.families.is_empty() {
            return bad("named families draw their own skills: give skills or families, not both");
        }
        Ok(())
    }

    /// The width of the network's input (it reads the skill features where the games
    /// have skills).
    pub fn input_width(&self) -> usize {
        staffing_input_width(self.reads_skills())
    }

    /// Whether the games have skills, so that the model reads the skill features.
    pub fn reads_skills(&self) -> bool {
        self.skills.is_some() || self.families.iter().any(|f| f.draws_skills())
    }

    /// How many training games the run labels: per size (and family).
    pub fn training_game_count(&self) -> usize {
        self.games * self.sizes.len() * self.families.len().max(1)
    }

    /// The games of a run: per size, per family (or the scarce game), `count` seeds
    /// from `seed_of(size's index, k)`; a family's games at a size are the same in every
    /// run that names it.
    fn draws(&self, count: usize, seed_of: impl Fn(usize, u64) -> u64) -> Vec<GameDraw> {
        let families: Vec<Option<Family>> = if self.families.is_empty() {
            vec![None]
        } else {
            self.families.iter().copied().map(Some).collect()
        };
        let mut draws = Vec::new();
        for (at, &size) in self.sizes.iter().enumerate() {
            for &family in &families {
                draws.extend((0..count as u64).map(|k| GameDraw {
                    family,
                    seed: seed_of(at, k),
                    size,
                }));
            }
        }
        draws
    }
}

/// What one epoch did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaffingEpoch {
    /// Epochs done.
    pub epoch: usize,
    /// Mean cross-entropy of its steps.
    pub loss: f64,
    /// Share of the validation games' tasks that the knapsack staffs as the label
    /// does, %.
    pub agree: f64,
    /// Mean welfare of the validation games' placements, % of their optimum.
    pub percent_of_opt: f64,
}

type Optim = OptimizerAdaptor<Adam, PriceNet<TrainBackend>, TrainBackend>;

/// A staffing training run (see the module docs).
///
/// # Examples
/// ```
/// use afg_learn::staffing::{StaffingTrainConfig, StaffingTrainer};
/// let mut config = StaffingTrainConfig::new(0);
/// config.sizes.truncate(1);
/// (config.games, config.validation_games, config.epochs) = (4, 2, 2);
/// let mut trainer = StaffingTrainer::new(config)?;
/// trainer.label(None, |_| ())?;
/// let first = trainer.epoch()?;
/// assert_eq!(first.epoch, 1);
/// # Ok::<(), afg_learn::LearnError>(())
/// ```
pub struct StaffingTrainer {
    config: StaffingTrainConfig,
    net: PriceNet<TrainBackend>,
    optim: Optim,
    rng: ChaCha8Rng,
    epoch: usize,
    training: Vec<LabelledGame>,
    validation: Vec<(Instance, LabelledGame)>,
}

impl StaffingTrainer {
    /// A fresh run (nothing labelled yet).
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] for a setting out of range.
    pub fn new(config: StaffingTrainConfig) -> Result<Self, LearnError> {
        config.validate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(config.network.seed);
        Ok(StaffingTrainer {
            net: PriceNet::seeded(
                &mut rng,
                config.input_width(),
                config.network.hidden,
                &Default::default(),
            ),
            optim: AdamConfig::new().init(),
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            epoch: 0,
            training: Vec::new(),
            validation: Vec::new(),
            config,
        })
    }

    /// The settings.
    pub fn config(&self) -> &StaffingTrainConfig {
        &self.config
    }

    /// The training games to label, every size's (and family's) in turn.
    fn training_games(&self) -> Vec<GameDraw> {
        let (seed, games) = (self.config.seed, self.config.games as u64);
        self.config.draws(self.config.games, |at, k| {
            training_instance_seed(seed, at as u64 * games + k)
        })
    }

    /// Labels every training and validation game, in parallel over the cores. With
    /// `cache` (a labels file), the games already there are read back rather than
    /// solved again, and each new one is appended as it is labelled; `on_game` is
    /// called once per training game.
    ///
    /// # Errors
    /// A cache file that is not this run's (another size or seed at a line), a failed
    /// write, or a generator error.
    pub fn label(
        &mut self,
        cache: Option<&Path>,
        on_game: impl Fn(&LabelledGame) + Sync,
    ) -> Result<(), LearnError> {
        let limit = Duration::from_secs_f64(self.config.label_time_limit);
        let skills = self.config.skills;
        let games = self.training_games();
        let solve = |draw: GameDraw| -> Result<(Instance, LabelledGame), LearnError> {
            let inst = draw.game(skills)?;
            let labelled = label(&inst, draw, limit)?;
            Ok((inst, labelled))
        };
        // The games already labelled, in whatever order a stopped run finished them.
        let cached: Vec<LabelledGame> = match cache {
            Some(path) if path.exists() => read_labels(path)?,
            _ => Vec::new(),
        };
        if let Some(game) = cached.iter().find(|g| !games.contains(&g.draw)) {
            return Err(LearnError::InvalidConfig(format!(
                "{} holds another run's games (seed {} of {}x{}{}, which this run does not draw); remove it or choose another directory",
                cache.map_or_else(String::new, |p| p.display().to_string()),
                game.draw.seed,
                game.draw.size.robots,
                game.draw.size.tasks,
                game.draw
                    .family
                    .map_or_else(String::new, |f| format!(" of {f}")),
            )));
        }
        cached.iter().for_each(&on_game);
        let todo: Vec<GameDraw> = (games.iter().copied())
            .filter(|&draw| !cached.iter().any(|g| g.draw == draw))
            .collect();
        let file = std::sync::Mutex::new(cache.map(|path| (path.to_path_buf(), lines_of(&cached))));
        let fresh: Vec<LabelledGame> = todo
            .par_iter()
            .map(|&draw| {
                let (_, game) = solve(draw)?;
                if let Some((path, text)) = file.lock().expect("no panics while held").as_mut() {
                    text.push_str(&serde_json::to_string(&game).expect("a game serialises"));
                    text.push('\n');
                    afg_game::fs::write_atomic(path, text.as_bytes())?;
                }
                on_game(&game);
                Ok(game)
            })
            .collect::<Result<_, LearnError>>()?;
        // Every game in run order; the cache (written in the order games finished) is
        // rewritten so.
        let mut labelled: Vec<Option<LabelledGame>> =
            cached.into_iter().chain(fresh).map(Some).collect();
        let done: Vec<LabelledGame> = (games.iter())
            .map(|&draw| {
                let at = labelled
                    .iter()
                    .position(|g| g.as_ref().is_some_and(|g| g.draw == draw));
                at.and_then(|at| labelled[at].take())
                    .expect("every game labelled")
            })
            .collect();
        if let Some(path) = cache {
            afg_game::fs::write_atomic(path, lines_of(&done).as_bytes())?;
        }
        self.training = done;
        let validation = (self.config).draws(self.config.validation_games, |_, i| (1 << 63) + i);
        self.validation = validation
            .par_iter()
            .map(|&draw| solve(draw))
            .collect::<Result<_, LearnError>>()?;
        Ok(())
    }

    /// Whether every epoch has run.
    pub fn is_finished(&self) -> bool {
        self.epoch >= self.config.epochs
    }

    /// The current weights as a saveable model.
    pub fn model(&self) -> StaffingModel {
        StaffingModel::new(self.config.clone(), TaskMlp::from_burn(&self.net))
    }

    /// One pass over every labelled game in a seeded random order, `batch` games per
    /// Adam step, then validation.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] before [`StaffingTrainer::label`];
    /// [`LearnError::NonFiniteLoss`] / [`LearnError::NonFiniteWeights`] if training
    /// diverges.
    pub fn epoch(&mut self) -> Result<StaffingEpoch, LearnError> {
        if self.training.is_empty() {
            return Err(LearnError::InvalidConfig("label the games first".into()));
        }
        let mut games: Vec<usize> = (0..self.training.len()).collect();
        games.shuffle(&mut self.rng);
        let per_epoch = games.len().div_ceil(self.config.batch);
        let total = (self.config.epochs * per_epoch).max(1);
        let (mut loss, mut steps) = (0.0, 0);
        for batch in games.chunks(self.config.batch) {
            let done = self.epoch * per_epoch + steps;
            let lr = self.config.lr * (1.0 - 0.9 * (done as f64 / total as f64).min(1.0));
            loss += self.step(batch, lr, done as u64)?;
            steps += 1;
        }
        self.epoch += 1;
        let mlp = TaskMlp::from_burn(&self.net);
        let reads_skills = self.config.reads_skills();
        let (mut agree, mut tasks, mut percent) = (0usize, 0usize, 0.0);
        for (inst, game) in &self.validation {
            let values = values_of(&mlp, &game.features, reads_skills);
            let chosen = knapsack(&game.thresholds, &values, game.draw.size.robots);
            agree += chosen
                .iter()
                .zip(&game.labels)
                .filter(|&(&c, &y)| c == (y > 0.5))
                .count();
            tasks += chosen.len();
            let (_, welfare) = staff_by_values(inst, &values)
                .map_err(|e| LearnError::InvalidConfig(e.to_string()))?;
            percent += 100.0 * welfare / game.welfare;
        }
        Ok(StaffingEpoch {
            epoch: self.epoch,
            loss: loss / steps.max(1) as f64,
            agree: 100.0 * agree as f64 / tasks.max(1) as f64,
            percent_of_opt: percent / self.validation.len().max(1) as f64,
        })
    }

    /// One Adam step on the games `batch`: the structured hinge loss of the knapsack's
    /// choice. With worths `w_j = (k_j / share)(m_j + z_j)` and the label's staffing
    /// y*, the loss-augmented knapsack picks ŷ maximising `Σ_j (w_j y_j + δ_j [y_j ≠
    /// y*_j])` (δ_j = margin · k_j / share), and the loss is `Σ_j w_j (ŷ_j − y*_j) +
    /// Σ_j δ_j [ŷ_j ≠ y*_j] ≥ 0` (y* fits), 0 only when the label wins by its margin;
    /// its gradient moves the worths of the tasks chosen wrongly. Returns the mean loss
    /// per game.
    fn step(&mut self, batch: &[usize], lr: f64, step: u64) -> Result<f64, LearnError> {
        let device = Default::default();
        let width = self.config.input_width();
        let mut x = Vec::new();
        for &g in batch {
            x.extend(staffing_inputs(
                &self.training[g].features,
                self.config.reads_skills(),
            ));
        }
        let rows = x.len() / width;
        let x = Tensor::<TrainBackend, 2>::from_data(TensorData::new(x, [rows, width]), &device);
        let z = self.net.forward(x);
        let corrections = crate::dense::to_vec(z.clone());
        // Per row: the worth's slope k_j / share times (ŷ_j − y*_j), and the constant
        // part of the loss.
        let (mut slope, mut constant) = (Vec::with_capacity(rows), 0.0);
        let mut at = 0;
        for &g in batch {
            let game = &self.training[g];
            let m = game.labels.len();
            let z = &corrections[at..at + m];
            at += m;
            let (worth, delta): (Vec<f64>, Vec<f64>) = game
                .features
                .chunks_exact(STAFF_FEATURES)
                .zip(z)
                .map(|(f, &z)| {
                    let size = f64::from(f[SIZE]);
                    (size * f64::from(f[MARGIN] + z), self.config.margin * size)
                })
                .unzip();
            let augmented: Vec<f64> = (0..m)
                .map(|j| {
                    worth[j]
                        + if game.labels[j] > 0.5 {
                            -delta[j]
                        } else {
                            delta[j]
                        }
                })
                .collect();
            let chosen = knapsack(&game.thresholds, &augmented, game.draw.size.robots);
            for j in 0..m {
                let diff = f64::from(u8::from(chosen[j])) - f64::from(game.labels[j]);
                let size = f64::from(game.features[j * STAFF_FEATURES + SIZE]);
                slope.push((size * diff) as f32);
                constant += size * f64::from(game.features[j * STAFF_FEATURES + MARGIN]) * diff
                    + delta[j] * diff.abs();
            }
        }
        let slope = Tensor::<TrainBackend, 1>::from_data(TensorData::new(slope, [rows]), &device);
        let games = batch.len() as f64;
        let loss = (z * slope).sum() / games;
        let value = f64::from(loss.clone().into_scalar()) + constant / games;
        if !value.is_finite() {
            return Err(LearnError::NonFiniteLoss {
                step,
                loss: value as f32,
            });
        }
        let grads = GradientsParams::from_grads(loss.backward(), &self.net);
        let updated = self.optim.step(lr, self.net.clone(), grads);
        if !crate::weights::weights_are_finite(&updated) {
            return Err(LearnError::NonFiniteWeights { step });
        }
        self.net = updated;
        Ok(value)
    }

    /// Trains to the end with run directory `dir` (created if needed and locked as a
    /// [`RunDir`](crate::run_dir::RunDir) is): labels the games (resuming from
    /// [`LABELS_FILE_NAME`]), then after each epoch rewrites the log
    /// ([`RunDir::LOG`](crate::run_dir::RunDir::LOG)) and calls `on_epoch`; at the end writes the manifest and
    /// then the model ([`StaffingModel::FILE_NAME`]).
    ///
    /// # Errors
    /// [`LearnError::RunInUse`] while another trainer holds the directory, a failed
    /// epoch, or a file that cannot be written.
    pub fn run_in(
        self,
        dir: &Path,
        command: String,
        on_game: impl Fn(&LabelledGame) + Sync,
        on_epoch: impl FnMut(&StaffingEpoch),
    ) -> Result<crate::manifest::RunManifest, LearnError> {
        let labels = dir.join(LABELS_FILE_NAME);
        let prepare = |trainer: &mut Self| trainer.label(Some(&labels), on_game);
        crate::rounds::run_rounds(self, dir, command, prepare, on_epoch)
    }
}

impl crate::rounds::RoundTrainer for StaffingTrainer {
    type Round = StaffingEpoch;

    fn is_finished(&self) -> bool {
        StaffingTrainer::is_finished(self)
    }

    fn next_round(&mut self) -> Result<StaffingEpoch, LearnError> {
        self.epoch()
    }

    fn record(&self, last: Option<StaffingEpoch>) -> (crate::manifest::RunRecord, u64) {
        let record = crate::manifest::RunRecord::StaffingModel {
            epochs: self.config.epochs,
            last_epoch: last,
        };
        (record, self.config.seed)
    }

    fn save_model(&self, dir: &Path) -> Result<(), LearnError> {
        self.model().save(&dir.join(StaffingModel::FILE_NAME))
    }
}
