//! Training the price model by regression on the exact Q\*, on the states its own
//! rollouts visit (DAgger).
//!
//! Each round rolls out `episodes_per_round` fresh instances. At every step the exact
//! `Q*(s_t, a)` of every task is computed ([`crate::regret::q_star`], one min-cost flow for all tasks), and the
//! acting robot follows the expert (the best Q\*) with probability `expert_decay^round`,
//! otherwise the current model (with a random task instead in a share `explore` of the
//! steps). Every visited state is kept (up to `buffer_states`, oldest dropped), and
//! `steps_per_round` Adam steps fit the model's action values to Q\* on random batches:
//! the loss is the squared error of the *centred* values (each minus its mean over the
//! tasks with room), since the policy only compares actions of one state.

use afg_baseline::Optimum;
use afg_game::{GeneratorConfig, Instance};
use burn::optim::adaptor::OptimizerAdaptor;
use burn::optim::{Adam, AdamConfig, GradientsParams, Optimizer};
use burn::tensor::{Tensor, TensorData};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::config::PriceTrainConfig;
use super::net::{PRICE_INPUTS, PriceNet, PriceScratch, TaskMlp};
use super::{PriceMode, PriceModel, PricePolicy};
use crate::regret::q_star;
use crate::targets::masked_argmax;
use crate::train::training_instance_seed;
use crate::train::validation_set;
use crate::{LearnError, TrainBackend};
use afg_graph::{PriceState, TASK_FEATURES, task_inputs};

/// What one round did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PriceRound {
    /// Rounds done (1 after the first).
    pub round: usize,
    /// States in the buffer.
    pub states: usize,
    /// Probability that the expert acted in this round's rollouts.
    pub expert_share: f64,
    /// Mean training loss of the round's steps (β units squared).
    #[serde(with = "crate::log_float")]
    pub loss: f64,
    /// Validation welfare of the sequential policy, % of OPT (mean over instances;
    /// logs written before 2026-12-02 hold the ratio of the sums).
    #[serde(with = "crate::log_float")]
    pub sequential: f64,
    /// The same for the one-shot policy.
    #[serde(with = "crate::log_float")]
    pub one_shot: f64,
}

/// Visited states: per state, the features, the acting robot's costs, the centred-free
/// Q\* targets and which tasks had room.
struct Buffer {
    features: Vec<f32>,
    costs: Vec<f32>,
    targets: Vec<f32>,
    room: Vec<f32>,
    tasks: usize,
    capacity: usize,
    len: usize,
    next: usize,
}

impl Buffer {
    fn new(tasks: usize, capacity: usize) -> Self {
        Buffer {
            features: Vec::new(),
            costs: Vec::new(),
            targets: Vec::new(),
            room: Vec::new(),
            tasks,
            capacity,
            len: 0,
            next: 0,
        }
    }

    fn push(&mut self, features: &[f32], costs: &[f32], targets: &[f32], room: &[f32]) {
        let (m, k) = (self.tasks, TASK_FEATURES);
        if self.len < self.capacity {
            self.features.extend_from_slice(features);
            self.costs.extend_from_slice(costs);
            self.targets.extend_from_slice(targets);
            self.room.extend_from_slice(room);
            self.len += 1;
        } else {
            let i = self.next;
            self.features[i * m * k..(i + 1) * m * k].copy_from_slice(features);
            self.costs[i * m..(i + 1) * m].copy_from_slice(costs);
            self.targets[i * m..(i + 1) * m].copy_from_slice(targets);
            self.room[i * m..(i + 1) * m].copy_from_slice(room);
        }
        self.next = (self.next + 1) % self.capacity;
    }
}

/// Empty states of the training instances with their exact prices (one per instance).
struct Initial {
    features: Vec<f32>,
    prices: Vec<f32>,
    len: usize,
}

type Optim = OptimizerAdaptor<Adam, PriceNet<TrainBackend>, TrainBackend>;

/// A price-model training run (see the module docs).
///
/// # Examples
/// ```
/// use afg_learn::price::{PriceTrainConfig, PriceTrainer};
/// let mut config = PriceTrainConfig::new(12, 3, 0);
/// (config.rounds, config.episodes_per_round, config.steps_per_round) = (2, 2, 3);
/// config.validation_instances = 2;
/// let mut trainer = PriceTrainer::new(config)?;
/// let first = trainer.round()?;
/// assert_eq!((first.round, first.states, first.expert_share), (1, 24, 1.0));
/// trainer.round()?;
/// assert!(trainer.is_finished());
/// # Ok::<(), afg_learn::LearnError>(())
/// ```
pub struct PriceTrainer {
    config: PriceTrainConfig,
    net: PriceNet<TrainBackend>,
    optim: Optim,
    buffer: Buffer,
    initial: Initial,
    rng: ChaCha8Rng,
    round: usize,
    episodes: u64,
    validation: Vec<Instance>,
    /// The optimum's welfare of each validation instance.
    optima: Vec<f64>,
}

impl PriceTrainer {
    /// A fresh run.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] for a setting out of range.
    pub fn new(config: PriceTrainConfig) -> Result<Self, LearnError> {
        config.validate()?;
        let (validation, optima) =
            validation_set(config.robots, config.tasks, config.validation_instances)?;
        Ok(PriceTrainer {
            net: config.network.init(&Default::default()),
            optim: AdamConfig::new().init(),
            buffer: Buffer::new(config.tasks, config.buffer_states),
            initial: Initial {
                features: Vec::new(),
                prices: Vec::new(),
                len: 0,
            },
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            round: 0,
            episodes: 0,
            validation,
            optima,
            config,
        })
    }

    /// The settings.
    pub fn config(&self) -> &PriceTrainConfig {
        &self.config
    }

    /// Whether every round has run.
    pub fn is_finished(&self) -> bool {
        self.round >= self.config.rounds
    }

    /// The current weights as a saveable model.
    pub fn model(&self) -> PriceModel {
        PriceModel::new(self.config.clone(), TaskMlp::from_burn(&self.net))
    }

    /// One round: roll out, fit, validate.
    ///
    /// # Errors
    /// [`LearnError::NonFiniteLoss`] if the loss stops being finite, or
    /// [`LearnError::NonFiniteWeights`] if an update would make a weight NaN or
    /// infinite (the weights of the step are discarded either way); errors of the
    /// instance generator.
    pub fn round(&mut self) -> Result<PriceRound, LearnError> {
        let expert_share = self.config.expert_decay.powi(self.round as i32);
        let mlp = TaskMlp::from_burn(&self.net);
        for _ in 0..self.config.episodes_per_round {
            let seed = training_instance_seed(self.config.seed, self.episodes);
            self.episodes += 1;
            let inst =
                GeneratorConfig::paper(self.config.robots, self.config.tasks, seed).generate()?;
            self.collect(&inst, &mlp, expert_share)?;
        }
        let mut loss = 0.0;
        for _ in 0..self.config.steps_per_round {
            loss += self.step()?;
        }
        self.round += 1;
        let mlp = TaskMlp::from_burn(&self.net);
        let score = |mode| -> Result<f64, LearnError> {
            let policy = PricePolicy::new(mlp.clone(), mode);
            let mut welfare = Vec::with_capacity(self.validation.len());
            for inst in &self.validation {
                let state = policy
                    .rollout(inst)
                    .map_err(|e| LearnError::InvalidAction(e.to_string()))?;
                welfare.push(inst.welfare(state.assignment()));
            }
            let pairs = welfare.into_iter().zip(self.optima.iter().copied());
            Ok(afg_baseline::mean_percent_of_opt(pairs).unwrap_or(f64::NAN))
        };
        Ok(PriceRound {
            round: self.round,
            states: self.buffer.len,
            expert_share,
            loss: loss / self.config.steps_per_round.max(1) as f64,
            sequential: score(PriceMode::Sequential)?,
            one_shot: score(PriceMode::OneShot)?,
        })
    }

    /// Rolls out one instance, storing every state with its Q\* targets.
    fn collect(
        &mut self,
        inst: &Instance,
        mlp: &TaskMlp,
        expert_share: f64,
    ) -> Result<(), LearnError> {
        let m = inst.num_tasks();
        let mut state = PriceState::new(inst);
        let mut features = vec![0.0; m * TASK_FEATURES];
        let (mut prices, mut costs) = (vec![0.0f32; m], vec![0.0f32; m]);
        let (mut targets, mut room, mut q) = (vec![0.0f32; m], vec![0.0f32; m], vec![0.0f32; m]);
        let mut mask = vec![false; m];
        let mut scratch = PriceScratch::default();
        if self.config.one_shot_weight > 0.0 && self.initial.len < self.config.buffer_states {
            state.features(&mut features);
            let (_, prices) = Optimum.with_prices(inst);
            self.initial.features.extend_from_slice(&features);
            self.initial
                .prices
                .extend(prices.iter().map(|p| (p / state.unit()) as f32));
            self.initial.len += 1;
        }
        for robot in inst.robot_ids() {
            state.features(&mut features);
            let star = q_star(inst, state.assignment(), robot)?;
            for j in inst.task_ids() {
                costs[j.index()] = state.cost(robot, j) as f32;
                let value = star[j.index()];
                mask[j.index()] = value.is_some();
                room[j.index()] = f32::from(u8::from(value.is_some()));
                targets[j.index()] = value.map_or(0.0, |v| (v / state.unit()) as f32);
            }
            self.buffer.push(&features, &costs, &targets, &room);
            let draw: f64 = self.rng.random();
            let action = if draw < expert_share {
                masked_argmax(&targets, &mask)
            } else if self.rng.random::<f64>() < self.config.explore {
                let open: Vec<usize> = (0..m).filter(|&j| mask[j]).collect();
                (!open.is_empty()).then(|| open[self.rng.random_range(0..open.len())])
            } else {
                mlp.prices_with(&features, &mut prices, &mut scratch);
                PricePolicy::choose(&state, robot, &prices, &mut q, &mut mask).map(|j| j.index())
            };
            let action = action.ok_or_else(|| {
                LearnError::InvalidAction(format!("no task has room for robot {robot}"))
            })?;
            state.assign(robot, afg_game::TaskId(action as u32));
        }
        Ok(())
    }

    /// One Adam step on a random batch; returns its loss.
    fn step(&mut self) -> Result<f64, LearnError> {
        let (m, b) = (self.config.tasks, self.config.batch);
        let picks: Vec<usize> = (0..b)
            .map(|_| self.rng.random_range(0..self.buffer.len))
            .collect();
        let x = inputs_of(&self.buffer.features, &picks, m);
        let c = rows_of(&self.buffer.costs, &picks, m);
        let y = rows_of(&self.buffer.targets, &picks, m);
        let w = rows_of(&self.buffer.room, &picks, m);
        let q = self.net.forward(x).reshape([b, m]) - c;
        let open = w.clone().sum_dim(1);
        let centre = |v: Tensor<TrainBackend, 2>| {
            let mean = (v.clone() * w.clone()).sum_dim(1) / open.clone();
            v - mean
        };
        let error = (centre(q) - centre(y)) * w.clone();
        let mut loss = error.powf_scalar(2.0).sum() / w.sum();
        if self.config.one_shot_weight > 0.0 && self.initial.len > 0 {
            loss = loss + self.one_shot_loss() * self.config.one_shot_weight;
        }
        let value = f64::from(loss.clone().into_scalar());
        if !value.is_finite() {
            return Err(LearnError::NonFiniteLoss {
                step: (self.round * self.config.steps_per_round) as u64,
                loss: value as f32,
            });
        }
        let total = (self.config.rounds * self.config.steps_per_round).max(1) as f64;
        let done = (self.round * self.config.steps_per_round) as f64;
        let lr = self.config.lr * (1.0 - 0.9 * (done / total).min(1.0));
        let grads = GradientsParams::from_grads(loss.backward(), &self.net);
        let updated = self.optim.step(lr, self.net.clone(), grads);
        // A finite loss can still have a gradient that overflows a weight.
        if !crate::weights::weights_are_finite(&updated) {
            return Err(LearnError::NonFiniteWeights {
                step: (self.round * self.config.steps_per_round) as u64,
            });
        }
        self.net = updated;
        Ok(value)
    }

    /// Squared error of the centred prices of random empty states against their exact
    /// prices (a quarter batch of instances).
    fn one_shot_loss(&mut self) -> Tensor<TrainBackend, 1> {
        let (m, b) = (self.config.tasks, (self.config.batch / 4).max(1));
        let picks: Vec<usize> = (0..b)
            .map(|_| self.rng.random_range(0..self.initial.len))
            .collect();
        let x = inputs_of(&self.initial.features, &picks, m);
        let y = rows_of(&self.initial.prices, &picks, m);
        let p = self.net.forward(x).reshape([b, m]);
        let centre = |v: Tensor<TrainBackend, 2>| v.clone() - v.mean_dim(1);
        (centre(p) - centre(y)).powf_scalar(2.0).mean()
    }
}

/// The network inputs of states `picks` of a `[states, M, TASK_FEATURES]` array.
///
/// # Shapes
/// output: `[picks · M, PRICE_INPUTS]`
fn inputs_of(features: &[f32], picks: &[usize], m: usize) -> Tensor<TrainBackend, 2> {
    let k = m * TASK_FEATURES;
    let mut inputs = vec![0.0f32; picks.len() * m * PRICE_INPUTS];
    for (&i, out) in picks.iter().zip(inputs.chunks_exact_mut(m * PRICE_INPUTS)) {
        task_inputs(&features[i * k..(i + 1) * k], out);
    }
    let shape = [picks.len() * m, PRICE_INPUTS];
    Tensor::from_data(TensorData::new(inputs, shape), &Default::default())
}

/// Rows `picks` of a `[states, M]` array.
///
/// # Shapes
/// output: `[picks, M]`
fn rows_of(values: &[f32], picks: &[usize], m: usize) -> Tensor<TrainBackend, 2> {
    let rows: Vec<f32> = picks
        .iter()
        .flat_map(|&i| values[i * m..(i + 1) * m].iter().copied())
        .collect();
    Tensor::from_data(TensorData::new(rows, [picks.len(), m]), &Default::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> PriceTrainConfig {
        let mut config = PriceTrainConfig::new(12, 3, 4);
        (
            config.rounds,
            config.episodes_per_round,
            config.steps_per_round,
        ) = (3, 3, 20);
        config.validation_instances = 3;
        config
    }

    #[test]
    fn same_seed_same_weights() {
        let run = || {
            let mut t = PriceTrainer::new(tiny()).unwrap();
            while !t.is_finished() {
                t.round().unwrap();
            }
            t.model()
        };
        let (a, b) = (run(), run());
        assert_eq!(a, b);
        assert_ne!(
            a.mlp,
            PriceTrainer::new(tiny()).unwrap().model().mlp,
            "it learned nothing"
        );
    }

    #[test]
    fn bad_settings_are_refused() {
        for change in [
            |c: &mut PriceTrainConfig| c.robots = 0,
            |c: &mut PriceTrainConfig| c.lr = f64::NAN,
            |c: &mut PriceTrainConfig| c.explore = 1.5,
            |c: &mut PriceTrainConfig| c.batch = 0,
        ] {
            let mut config = tiny();
            change(&mut config);
            assert!(matches!(
                PriceTrainer::new(config),
                Err(LearnError::InvalidConfig(_))
            ));
        }
    }

    /// Fitting Q\* on the states of one instance lowers the loss: the gradient points
    /// the right way.
    #[test]
    fn the_loss_falls_on_a_fixed_set() {
        let mut config = tiny();
        config.lr = 3e-3;
        let mut t = PriceTrainer::new(config).unwrap();
        let inst = GeneratorConfig::paper(12, 3, 77).generate().unwrap();
        let mlp = TaskMlp::from_burn(&t.net);
        t.collect(&inst, &mlp, 1.0).unwrap();
        let first = t.step().unwrap();
        let mut last = first;
        for _ in 0..150 {
            last = t.step().unwrap();
        }
        assert!(last < 0.5 * first, "{first} → {last}");
    }

    /// An update that overflows a weight (a learning rate of 1e300 overflows f32 at
    /// once) is refused and leaves the weights as they were.
    #[test]
    fn an_update_that_overflows_a_weight_is_refused() {
        let mut config = tiny();
        config.lr = 1e300;
        let mut t = PriceTrainer::new(config).unwrap();
        let inst = GeneratorConfig::paper(12, 3, 77).generate().unwrap();
        let mlp = TaskMlp::from_burn(&t.net);
        t.collect(&inst, &mlp, 1.0).unwrap();
        let before = crate::weights::parameter_values(&t.net);
        let err = t.step().unwrap_err();
        assert!(matches!(err, LearnError::NonFiniteWeights { .. }), "{err}");
        assert_eq!(crate::weights::parameter_values(&t.net), before);
    }
}
