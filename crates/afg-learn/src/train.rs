//! DQN and Double DQN training on the sequential allocation MDP, on the CPU.
//!
//! - **Experience.** `parallel_envs` episodes run side by side on fresh seeded training
//!   instances (never the test datasets); one batched forward pass picks ε-greedy
//!   actions for all of them. Finished episodes enter the replay buffer as compact
//!   records (instance seed + actions); a transition is an (episode, step) pair whose
//!   states and reward are rebuilt when it is sampled.
//! - **Learning.** One gradient step per acting step: Adam on the Huber (or squared)
//!   error between `Q(s_t, a_t)` and the DQN or Double DQN target, the target network
//!   synced every `target_sync` steps.
//! - **Determinism.** Everything random comes from one ChaCha8 generator seeded by
//!   `seed`; a checkpoint stores its state, the replay records, the running episodes,
//!   both networks and Adam's moments, so a resumed run ends with the same weights as
//!   an uninterrupted one.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};

use afg_baseline::{Allocator, Optimum};
use afg_game::{Assignment, GeneratorConfig, Instance, RobotId, TaskId};
use afg_graph::{AllocationState, GraphBatch, GraphKind, RobotGraph};
use burn::module::AutodiffModule;
use burn::optim::adaptor::OptimizerAdaptor;
use burn::optim::{Adam, AdamConfig, GradientsParams, Optimizer};
use burn::record::{FullPrecisionSettings, NamedMpkFileRecorder, Recorder};
use burn::tensor::{Int, Tensor, TensorData};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::{
    GraphTensors, InferBackend, LearnError, NetworkConfig, QNetwork, TrainBackend,
    double_dqn_target, dqn_target, greedy_rollouts, load_network, masked_argmax, n_step_reward,
    save_network,
};

/// The bootstrap rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algo {
    /// `r + max_a Q_target(s', a)`.
    Dqn,
    /// `r + Q_target(s', argmax_a Q_online(s', a))`.
    Ddqn,
}

impl Algo {
    /// `dqn` or `ddqn`.
    pub fn name(self) -> &'static str {
        match self {
            Algo::Dqn => "dqn",
            Algo::Ddqn => "ddqn",
        }
    }
}

/// Every setting of a training run. Stored in the run directory; `--resume` refuses a
/// directory whose settings differ from the ones asked for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// Robots per training instance N (M and the network come from `network`).
    pub robots: usize,
    /// DQN or Double DQN.
    pub algo: Algo,
    /// The network and its initialisation seed.
    pub network: NetworkConfig,
    /// Gradient steps.
    pub steps: u64,
    /// Transitions per gradient step.
    pub batch: usize,
    /// Adam learning rate (at step 0; see `lr_decay`).
    pub lr: f64,
    /// Anneal the learning rate linearly from `lr` to `lr / 10` over the run
    /// ([`TrainConfig::learning_rate`]), so that the final weights settle instead of
    /// swinging between validations. Files written before it existed load as `false`.
    #[serde(default)]
    pub lr_decay: bool,
    /// Gradient steps between target-network syncs.
    pub target_sync: u64,
    /// ε at the start of training.
    pub eps_start: f64,
    /// ε after the decay.
    pub eps_end: f64,
    /// Fraction of `steps` over which ε decays linearly.
    pub eps_fraction: f64,
    /// Episodes run side by side; each acting step adds this many transitions.
    pub parallel_envs: usize,
    /// Replay capacity in transitions (oldest episodes are dropped).
    pub replay_capacity: usize,
    /// Transitions collected before the first gradient step.
    pub warmup: usize,
    /// Steps of reward summed before bootstrapping (1: the paper's one-step target;
    /// with γ = 1 an n-step target is `r_t + … + r_{t+n-1} + Q(s_{t+n}, ·)`).
    #[serde(default = "one")]
    pub n_step: usize,
    /// Huber loss (δ = 1) instead of the squared error.
    pub huber: bool,
    /// Rewards in the network's welfare unit ([`afg_graph::Units::welfare_unit`], the
    /// task features' unit) instead of raw welfare.
    pub reward_scaling: bool,
    /// Potential-based reward shaping (Ng, Harada and Russell, 1999) with the potential
    /// Φ(s) = W(greedy completion of s) − W(s), the welfare that one-pass greedy would
    /// still add from s. The shaped reward of steps t..t+n is then
    /// `W(greedy completion of s_{t+n}) − W(greedy completion of s_t)`, and the network
    /// learns `Q(s, a) − Φ(s)`: what the policy gains over finishing greedily, O(action
    /// gaps) instead of O(N). Φ does not depend on the action, so the optimal policy and
    /// the greedy policy of a learned Q are unchanged. Not in the paper; files written
    /// before it existed load as `false`.
    #[serde(default)]
    pub greedy_shaping: bool,
    /// Gradient norm clipping.
    pub grad_clip: Option<f32>,
    /// Size of the fixed validation set (seeded, disjoint from datasets and training).
    pub validation_instances: usize,
    /// Gradient steps between validations.
    pub validate_every: u64,
    /// Seed of everything random in the run.
    pub seed: u64,
}

impl TrainConfig {
    /// Defaults for `robots` and a step budget: batch 256, Adam 1e-3 (the paper's 1e-4
    /// learns too slowly for a CPU budget; docs/training.md), ε 1.0 → 0.05 over
    /// 10 % of the steps, 16 parallel episodes, Huber loss, reward scaling, greedy
    /// reward shaping ([`TrainConfig::greedy_shaping`]), gradient
    /// clipping at norm 10, and a target sync every `clamp(steps / 20, 10, 1000)` steps
    /// (the paper's c = 1000 assumes 2.5 M steps; a CPU budget needs more syncs).
    pub fn new(robots: usize, algo: Algo, network: NetworkConfig, steps: u64, seed: u64) -> Self {
        TrainConfig {
            robots,
            algo,
            network,
            steps,
            batch: 256,
            lr: 1e-3,
            lr_decay: true,
            target_sync: (steps / 20).clamp(10, 1000),
            eps_start: 1.0,
            eps_end: 0.05,
            eps_fraction: 0.1,
            parallel_envs: 16,
            n_step: 1,
            replay_capacity: 50_000,
            warmup: 2_048,
            huber: true,
            reward_scaling: true,
            greedy_shaping: true,
            grad_clip: Some(10.0),
            validation_instances: 32,
            validate_every: (steps / 40).max(1),
            seed,
        }
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] naming the first bad setting.
    pub fn check(&self) -> Result<(), LearnError> {
        let bad = |what: &str| Err(LearnError::InvalidConfig(what.to_owned()));
        if self.robots < 2 {
            return bad("robots must be at least 2");
        }
        if self.network.tasks() == 0 || self.network.tasks() > 255 {
            return bad("the network's task count must be 1..=255");
        }
        if self.steps == 0 || self.batch == 0 || self.target_sync == 0 || self.validate_every == 0 {
            return bad("steps, batch, target_sync and validate_every must be positive");
        }
        if !(self.lr.is_finite() && self.lr > 0.0) {
            return bad("lr must be positive");
        }
        let unit = |x: f64| (0.0..=1.0).contains(&x);
        if !(unit(self.eps_start) && unit(self.eps_end) && unit(self.eps_fraction)) {
            return bad("eps_start, eps_end and eps_fraction must lie in [0, 1]");
        }
        if self.parallel_envs == 0 || self.validation_instances == 0 || self.n_step == 0 {
            return bad("parallel_envs, validation_instances and n_step must be positive");
        }
        if self.replay_capacity < self.robots || self.warmup > self.replay_capacity {
            return bad("replay_capacity must hold an episode and the warmup");
        }
        if matches!(&self.network, NetworkConfig::AfgNet(c) if c.gain_residual == Some(true))
            && (!self.reward_scaling || self.greedy_shaping)
        {
            return bad(
                "the gain residual is in the features' unit and adds the unshaped reward: it needs reward scaling and no shaping",
            );
        }
        Ok(())
    }

    /// The learning rate of gradient step `step` (0-based): `lr` constant, or annealed
    /// linearly to `lr / 10` at the last step when `lr_decay` is set.
    ///
    /// # Examples
    /// ```
    /// use afg_learn::{Algo, NetworkConfig, TrainConfig};
    ///
    /// let mut c = TrainConfig::new(20, Algo::Ddqn, NetworkConfig::afgnet(5, 0), 101, 0);
    /// c.lr = 1e-3;
    /// assert_eq!(c.learning_rate(0), 1e-3);
    /// assert!((c.learning_rate(50) - 5.5e-4).abs() < 1e-12);
    /// assert!((c.learning_rate(100) - 1e-4).abs() < 1e-12);
    /// c.lr_decay = false;
    /// assert_eq!(c.learning_rate(100), 1e-3);
    /// ```
    pub fn learning_rate(&self, step: u64) -> f64 {
        if !self.lr_decay || self.steps <= 1 {
            return self.lr;
        }
        let progress = (step as f64 / (self.steps - 1) as f64).min(1.0);
        self.lr * (1.0 - 0.9 * progress)
    }

    /// ε at gradient step `step`.
    pub fn epsilon(&self, step: u64) -> f64 {
        let horizon = self.eps_fraction * self.steps as f64;
        let progress = if horizon > 0.0 {
            (step as f64 / horizon).min(1.0)
        } else {
            1.0
        };
        self.eps_start + (self.eps_end - self.eps_start) * progress
    }

    fn instance(&self, seed: u64) -> Instance {
        GeneratorConfig::paper(self.robots, self.network.tasks(), seed)
            .generate()
            .expect("checked configuration generates valid instances")
    }
}

fn one() -> usize {
    1
}

/// Seed of training episode `episode` of a run seeded `run_seed`. Datasets use seeds
/// below 2^40 and validation sets 2^63 + i, so the three never meet.
pub fn training_instance_seed(run_seed: u64, episode: u64) -> u64 {
    (1 << 62) + (run_seed << 32) + episode
}

/// The fixed validation set: `count` instances with seeds 2^63 + i.
pub fn validation_instances(
    robots: usize,
    tasks: usize,
    count: usize,
) -> Result<Vec<Instance>, LearnError> {
    (0..count as u64)
        .map(|i| Ok(GeneratorConfig::paper(robots, tasks, (1 << 63) + i).generate()?))
        .collect()
}

/// What the trainer reports to its caller.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "event", rename_all = "lowercase")]
pub enum TrainEvent {
    /// After each gradient step.
    Step {
        /// Gradient steps done.
        step: u64,
        /// Loss of this step.
        loss: f32,
        /// ε used for acting.
        epsilon: f64,
    },
    /// After a validation.
    Validation {
        /// Gradient steps done.
        step: u64,
        /// The greedy policy on the validation set.
        #[serde(flatten)]
        result: Validation,
    },
}

/// The greedy policy of a network on the validation set.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    /// Mean welfare.
    pub welfare: f64,
    /// Mean of welfare / OPT, in percent.
    pub percent_of_opt: f64,
    /// Mean over instances of the share of robots on the most common task. Near 1 the
    /// policy has collapsed onto one task index; OPT's share is far lower (about 0.3 in
    /// the paper's distribution at M = 5).
    pub largest_task_share: f64,
}

impl Validation {
    /// Share of robots on one task above which a validation counts as collapsed.
    pub const COLLAPSE_SHARE: f64 = 0.6;

    /// Whether most robots went to one task ([`Validation::COLLAPSE_SHARE`]).
    pub fn collapsed(&self) -> bool {
        self.largest_task_share > Self::COLLAPSE_SHARE
    }
}

/// One episode as stored: the instance seed and the actions taken.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct EpisodeRecord {
    seed: u64,
    actions: Vec<u8>,
}

/// An episode with its instance and graph rebuilt (not stored in checkpoints).
struct Episode {
    record: EpisodeRecord,
    instance: Instance,
    graph: RobotGraph,
}

impl Episode {
    fn new(config: &TrainConfig, record: EpisodeRecord) -> Result<Self, LearnError> {
        let instance = config.instance(record.seed);
        let graph = RobotGraph::build(instance.robots(), GraphKind::default())?;
        Ok(Episode {
            record,
            instance,
            graph,
        })
    }

    /// The assignment after the first `t` actions.
    fn assignment_after(&self, t: usize) -> Assignment {
        let mut a = Assignment::unassigned(self.instance.num_robots(), self.instance.num_tasks());
        for (i, &task) in self.record.actions[..t].iter().enumerate() {
            a.set(RobotId(i as u32), Some(TaskId(u32::from(task))));
        }
        a
    }
}

/// The mutable state of a run, as written to `state.json` in a checkpoint.
#[derive(Serialize, Deserialize)]
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

const STATE_FORMAT: &str = "afg-train-state";
const STATE_VERSION: u32 = 1;

type Optim = OptimizerAdaptor<Adam, QNetwork<TrainBackend>, TrainBackend>;

/// A training run in memory.
pub struct Trainer {
    config: TrainConfig,
    online: QNetwork<TrainBackend>,
    target: QNetwork<InferBackend>,
    optim: Optim,
    rng: ChaCha8Rng,
    replay: VecDeque<Episode>,
    running: Vec<Episode>,
    next_episode: u64,
    step: u64,
    validation: Vec<Instance>,
    validation_opt: Vec<f64>,
}

fn optimizer(config: &TrainConfig) -> Optim {
    let clip = config
        .grad_clip
        .map(burn::grad_clipping::GradientClippingConfig::Norm);
    AdamConfig::new().with_grad_clipping(clip).init()
}

impl Trainer {
    /// A fresh run.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] for bad settings.
    pub fn new(config: TrainConfig) -> Result<Self, LearnError> {
        config.check()?;
        let device = Default::default();
        let online = config.network.init::<TrainBackend>(&device);
        let target = online.valid();
        let rng = ChaCha8Rng::seed_from_u64(config.seed);
        Self::assemble(
            config,
            online,
            target,
            None,
            rng,
            Vec::new(),
            Vec::new(),
            0,
            0,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn assemble(
        config: TrainConfig,
        online: QNetwork<TrainBackend>,
        target: QNetwork<InferBackend>,
        optim: Option<Optim>,
        rng: ChaCha8Rng,
        replay: Vec<EpisodeRecord>,
        running: Vec<EpisodeRecord>,
        next_episode: u64,
        step: u64,
    ) -> Result<Self, LearnError> {
        let validation = validation_instances(
            config.robots,
            config.network.tasks(),
            config.validation_instances,
        )?;
        let validation_opt = validation
            .iter()
            .map(|inst| {
                Ok(inst.welfare(
                    &Optimum
                        .allocate(inst)
                        .map_err(|e| LearnError::InvalidConfig(e.to_string()))?
                        .assignment,
                ))
            })
            .collect::<Result<_, LearnError>>()?;
        let replay = replay
            .into_iter()
            .map(|r| Episode::new(&config, r))
            .collect::<Result<_, _>>()?;
        let running = running
            .into_iter()
            .map(|r| Episode::new(&config, r))
            .collect::<Result<_, _>>()?;
        let optim = optim.unwrap_or_else(|| optimizer(&config));
        Ok(Trainer {
            config,
            online,
            target,
            optim,
            rng,
            replay,
            running,
            next_episode,
            step,
            validation,
            validation_opt,
        })
    }

    /// The run's settings.
    pub fn config(&self) -> &TrainConfig {
        &self.config
    }

    /// Gradient steps done.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// Transitions in the replay buffer (bounded by `replay_capacity`).
    pub fn replay_len(&self) -> usize {
        self.replay.len() * self.config.robots
    }

    /// The online network, for inference.
    pub fn network(&self) -> QNetwork<InferBackend> {
        self.online.valid()
    }

    fn reward_unit(&self, inst: &Instance) -> f64 {
        if self.config.reward_scaling {
            self.config.network.units().welfare_unit(inst)
        } else {
            1.0
        }
    }

    /// Advances every running episode by one ε-greedy action.
    fn act(&mut self, epsilon: f64) -> Result<(), LearnError> {
        let m = self.config.network.tasks();
        while self.running.len() < self.config.parallel_envs {
            let seed = training_instance_seed(self.config.seed, self.next_episode);
            self.next_episode += 1;
            self.running.push(Episode::new(
                &self.config,
                EpisodeRecord {
                    seed,
                    actions: Vec::new(),
                },
            )?);
        }
        let units = self.config.network.units();
        let mut batch = GraphBatch::new(m);
        for ep in &self.running {
            let t = ep.record.actions.len();
            let state = AllocationState::with_units(&ep.instance, ep.assignment_after(t), units);
            batch.push(&ep.graph, &state, RobotId(t as u32));
        }
        let device = Default::default();
        let q: Vec<f32> = self
            .online
            .valid()
            .forward(&GraphTensors::new(&batch, &device))
            .into_data()
            .to_vec()
            .expect("f32");
        let mut finished = Vec::new();
        for (e, ep) in self.running.iter_mut().enumerate() {
            let range = e * m..(e + 1) * m;
            let mask = &batch.mask[range.clone()];
            let action = if self.rng.random::<f64>() < epsilon {
                let open: Vec<usize> = (0..m).filter(|&j| mask[j]).collect();
                open[self.rng.random_range(0..open.len())]
            } else {
                masked_argmax(&q[range], mask).expect("a task has room")
            };
            ep.record.actions.push(action as u8);
            if ep.record.actions.len() == self.config.robots {
                finished.push(e);
            }
        }
        for &e in finished.iter().rev() {
            let ep = self.running.remove(e);
            self.replay.push_back(ep);
        }
        while self.replay_len() > self.config.replay_capacity {
            self.replay.pop_front();
        }
        Ok(())
    }

    /// One gradient step on a sampled batch; returns the loss.
    fn learn(&mut self) -> f32 {
        let (n, m, b) = (
            self.config.robots,
            self.config.network.tasks(),
            self.config.batch,
        );
        let total = self.replay_len();
        let units = self.config.network.units();
        let mut now = GraphBatch::new(m);
        let mut next = GraphBatch::new(m);
        let (mut actions, mut rewards, mut next_row) = (
            Vec::with_capacity(b),
            Vec::with_capacity(b),
            Vec::with_capacity(b),
        );
        for _ in 0..b {
            let k = self.rng.random_range(0..total);
            let (ep, t) = (&self.replay[k / n], k % n);
            let (robot, task) = (RobotId(t as u32), TaskId(u32::from(ep.record.actions[t])));
            let mut a = ep.assignment_after(t);
            now.push(
                &ep.graph,
                &AllocationState::with_units(&ep.instance, a.clone(), units),
                robot,
            );
            actions.push(i64::from(task.0));
            // n-step return: the rewards of steps t..end, then bootstrap from s_end.
            let end = (t + self.config.n_step).min(n);
            let taken: Vec<TaskId> = ep.record.actions[t..end]
                .iter()
                .map(|&j| TaskId(u32::from(j)))
                .collect();
            let reward = n_step_reward(&ep.instance, &mut a, t, &taken, self.config.greedy_shaping);
            rewards.push((reward / self.reward_unit(&ep.instance)) as f32);
            next_row.push((end < n).then(|| {
                next.push(
                    &ep.graph,
                    &AllocationState::with_units(&ep.instance, a, units),
                    RobotId(end as u32),
                );
                next.num_graphs() - 1
            }));
        }
        let device = Default::default();
        let (next_target, next_online) = if next.num_graphs() > 0 {
            let g = GraphTensors::<InferBackend>::new(&next, &device);
            let target: Vec<f32> = self.target.forward(&g).into_data().to_vec().expect("f32");
            let online: Vec<f32> = match self.config.algo {
                Algo::Ddqn => self
                    .online
                    .valid()
                    .forward(&g)
                    .into_data()
                    .to_vec()
                    .expect("f32"),
                Algo::Dqn => Vec::new(),
            };
            (target, online)
        } else {
            (Vec::new(), Vec::new())
        };
        let targets: Vec<f32> = (0..b)
            .map(|i| match next_row[i] {
                None => rewards[i],
                Some(row) => {
                    let range = row * m..(row + 1) * m;
                    let mask = &next.mask[range.clone()];
                    match self.config.algo {
                        Algo::Dqn => dqn_target(rewards[i], &next_target[range], mask, false),
                        Algo::Ddqn => double_dqn_target(
                            rewards[i],
                            &next_online[range.clone()],
                            &next_target[range],
                            mask,
                            false,
                        ),
                    }
                }
            })
            .collect();
        let g = GraphTensors::<TrainBackend>::new(&now, &device);
        let action_index =
            Tensor::<TrainBackend, 2, Int>::from_data(TensorData::new(actions, [b, 1]), &device);
        let q_sa = self.online.forward(&g).gather(1, action_index);
        let y = Tensor::<TrainBackend, 2>::from_data(TensorData::new(targets, [b, 1]), &device);
        let diff = q_sa - y;
        let loss = if self.config.huber {
            // huber(x) = q²/2 + (|x| - q) with q = min(|x|, 1).
            let abs = diff.abs();
            let quad = abs.clone().clamp_max(1.0);
            (quad.clone().powi_scalar(2) * 0.5 + (abs - quad)).mean()
        } else {
            diff.powi_scalar(2).mean()
        };
        let loss_value: f32 = loss.clone().into_scalar();
        let grads = GradientsParams::from_grads(loss.backward(), &self.online);
        let lr = self.config.learning_rate(self.step);
        self.online = self.optim.step(lr, self.online.clone(), grads);
        loss_value
    }

    /// The greedy policy of the current network on the validation set.
    ///
    /// # Errors
    /// Graph errors (none for valid configurations).
    pub fn validate(&self) -> Result<Validation, LearnError> {
        let device = Default::default();
        let assignments = greedy_rollouts(
            &self.online.valid(),
            self.config.network.tasks(),
            &self.validation,
            GraphKind::default(),
            &device,
        )?;
        let k = self.validation.len() as f64;
        let welfare: Vec<f64> = self
            .validation
            .iter()
            .zip(&assignments)
            .map(|(i, a)| i.welfare(a))
            .collect();
        let mean = welfare.iter().sum::<f64>() / k;
        let pct = welfare
            .iter()
            .zip(&self.validation_opt)
            .map(|(w, o)| 100.0 * w / o)
            .sum::<f64>()
            / k;
        let largest_task_share = assignments
            .iter()
            .map(|a| {
                let largest = a.sizes().iter().copied().max().unwrap_or(0);
                largest as f64 / a.num_robots().max(1) as f64
            })
            .sum::<f64>()
            / k;
        Ok(Validation {
            welfare: mean,
            percent_of_opt: pct,
            largest_task_share,
        })
    }

    /// Trains until `until` gradient steps (at most the configured total), reporting
    /// each step and validation to `on_event`. Validation runs every `validate_every`
    /// steps and at the last step.
    ///
    /// # Errors
    /// Graph errors (none for valid configurations).
    pub fn run_until(
        &mut self,
        until: u64,
        mut on_event: impl FnMut(&TrainEvent),
    ) -> Result<(), LearnError> {
        let until = until.min(self.config.steps);
        while self.step < until {
            let epsilon = self.config.epsilon(self.step);
            self.act(epsilon)?;
            if self.replay_len() < self.config.warmup.max(1) {
                continue;
            }
            let loss = self.learn();
            self.step += 1;
            if self.step.is_multiple_of(self.config.target_sync) {
                self.target = self.online.valid();
            }
            on_event(&TrainEvent::Step {
                step: self.step,
                loss,
                epsilon,
            });
            if self.step.is_multiple_of(self.config.validate_every)
                || self.step == self.config.steps
            {
                let result = self.validate()?;
                on_event(&TrainEvent::Validation {
                    step: self.step,
                    result,
                });
            }
        }
        Ok(())
    }

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
        let optim_path = fresh.join("optim.mpk");
        NamedMpkFileRecorder::<FullPrecisionSettings>::new()
            .record(self.optim.to_record(), optim_path.clone())
            .map_err(|e| LearnError::Weights {
                path: optim_path.display().to_string(),
                reason: e.to_string(),
            })?;
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
        afg_game::io::write_atomic(&fresh.join("state.json"), json.as_bytes())?;
        let current = dir.join("checkpoint");
        let old = dir.join("checkpoint.old");
        if current.exists() {
            if old.exists() {
                std::fs::remove_dir_all(&old).map_err(io(&old))?;
            }
            std::fs::rename(&current, &old).map_err(io(&current))?;
        }
        std::fs::rename(&fresh, &current).map_err(io(&fresh))?;
        if old.exists() {
            std::fs::remove_dir_all(&old).map_err(io(&old))?;
        }
        Ok(())
    }

    /// Restores a run from `dir/checkpoint`.
    ///
    /// # Errors
    /// [`LearnError::Checkpoint`] for a missing, truncated or foreign checkpoint, and
    /// [`LearnError::Weights`] for unusable network or optimiser files.
    pub fn resume(dir: &Path) -> Result<Self, LearnError> {
        let ckpt = checkpoint_dir(dir);
        let state_path = ckpt.join("state.json");
        let bad = |reason: String| LearnError::Checkpoint {
            path: state_path.display().to_string(),
            reason,
        };
        let text = std::fs::read_to_string(&state_path).map_err(|e| bad(e.to_string()))?;
        let state: TrainerState =
            serde_json::from_str(&text).map_err(|e| bad(format!("corrupt or truncated: {e}")))?;
        if state.format != STATE_FORMAT || state.version != STATE_VERSION {
            return Err(bad(format!(
                "format {} version {}, expected {STATE_FORMAT} {STATE_VERSION}",
                state.format, state.version
            )));
        }
        state.config.check()?;
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
        let optim = optimizer(&state.config).load_record(record);
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

/// Where [`Trainer::save_checkpoint`] puts the checkpoint of a run directory.
pub fn checkpoint_dir(dir: &Path) -> PathBuf {
    dir.join("checkpoint")
}
