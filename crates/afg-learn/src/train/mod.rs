//! DQN and Double DQN training on the sequential allocation MDP, on the CPU.
//!
//! - **Experience.** `parallel_envs` episodes run side by side on fresh seeded training
//!   instances (never the test datasets); one batched forward pass picks ε-greedy
//!   actions for all of them. Finished episodes enter the replay buffer as compact
//!   records (instance seed + actions); a transition is an (episode, step) pair whose
//!   states and reward are rebuilt when it is sampled.
//! - **Learning.** One gradient step per acting step: Adam on the Huber (or squared)
//!   error between `Q(s_t, a_t)` and the DQN or Double DQN target, the target network
//!   synced every `target_sync` steps; or, with [`Algo::QStar`], between `Q(s_t, ·)`
//!   and the exact `Q*(s_t, ·)` of every task with room (one optimal completion per
//!   task, [`crate::regret::q_star`]).
//! - **Determinism.** Everything random comes from one ChaCha8 generator seeded by
//!   `seed`; a checkpoint stores its state, the replay records, the running episodes,
//!   both networks and Adam's moments, so a resumed run ends with the same weights as
//!   an uninterrupted one.

mod batch;
mod checkpoint;
pub(crate) mod config;
mod demos;
mod replay;
mod session;
pub(crate) mod validation;

use std::collections::VecDeque;

use afg_game::{Instance, RobotId};
use afg_graph::{AllocationState, GraphKind};
use burn::module::AutodiffModule;
use burn::optim::adaptor::OptimizerAdaptor;
use burn::optim::{Adam, AdamConfig, GradientsParams, Optimizer};
use burn::tensor::{Int, Tensor, TensorData};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub use crate::run_dir::checkpoint_dir;
pub(crate) use crate::run_dir::checkpoint_dirs;
pub use crate::targets::{double_dqn_target, dqn_target, masked_argmax};
pub(crate) use config::validation_set;
pub use config::{
    Algo, Demonstrations, Preset, TrainConfig, training_instance_seed, validation_instances,
};
use demos::{demonstrations, large_margins};
use replay::{Episode, EpisodeRecord};
pub use session::Session;
pub use validation::Validation;

use crate::qnetwork::QNetwork;
use crate::rollout::greedy_rollouts;
use crate::tensors::GraphTensors;
use crate::{InferBackend, LearnError, TrainBackend};

/// What one call of [`Trainer::step`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// Gradient steps done, this one included.
    pub step: u64,
    /// Loss of this step (finite: a non-finite loss is an error).
    pub loss: f32,
    /// ε used for acting.
    pub epsilon: f64,
    /// The validation after this step, when one was due (every `validate_every` steps
    /// and at the last step).
    pub validation: Option<Validation>,
}

type Optim = OptimizerAdaptor<Adam, QNetwork<TrainBackend>, TrainBackend>;

/// A training run in memory.
pub struct Trainer {
    config: TrainConfig,
    online: QNetwork<TrainBackend>,
    target: QNetwork<InferBackend>,
    optim: Optim,
    rng: ChaCha8Rng,
    replay: VecDeque<Episode>,
    /// The expert episodes of [`TrainConfig::demonstrations`] (rebuilt from the
    /// configuration, never stored in checkpoints).
    demos: Vec<Episode>,
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
    /// [`LearnError::InvalidConfig`] for bad settings; [`LearnError::Weights`] if
    /// `init_from` names weights that cannot be read or belong to another network.
    pub fn new(config: TrainConfig) -> Result<Self, LearnError> {
        config.check()?;
        let device = Default::default();
        let online = match &config.init_from {
            None => config.network.init::<TrainBackend>(&device),
            Some(dir) => {
                let stem = crate::run_dir::RunDir::new(dir).weights();
                let (network, weights) =
                    crate::weights::load_network::<TrainBackend>(&stem, &device)?;
                if !network.same_shape(&config.network) {
                    return Err(LearnError::Weights {
                        path: stem.display().to_string(),
                        reason: format!(
                            "a warm start needs the same network: the run asks for {:?}, the weights are {:?}",
                            config.network, network
                        ),
                    });
                }
                weights
            }
        };
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
        let (validation, validation_opt) = validation_set(
            config.robots,
            config.network.tasks(),
            config.validation_instances,
        )?;
        let replay = replay
            .into_iter()
            .map(|r| Episode::new(&config, r))
            .collect::<Result<_, _>>()?;
        let running = running
            .into_iter()
            .map(|r| Episode::new(&config, r))
            .collect::<Result<_, _>>()?;
        let optim = optim.unwrap_or_else(|| optimizer(&config));
        let demos = demonstrations(&config)?;
        Ok(Trainer {
            config,
            online,
            target,
            optim,
            rng,
            replay,
            demos,
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
    pub fn steps_done(&self) -> u64 {
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
        let mut batch = self.online.empty_batch(m);
        for ep in &self.running {
            let t = ep.record.actions.len();
            let state =
                AllocationState::from_assignment(&ep.instance, ep.assignment_after(t), units);
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

    /// One gradient step on a sampled batch; returns the loss. A non-finite loss, or an
    /// update that would make a weight non-finite, is an error and leaves the weights
    /// untouched.
    fn learn(&mut self) -> Result<f32, LearnError> {
        let device = Default::default();
        let loss = match self.config.algo {
            Algo::Dqn | Algo::Ddqn => {
                let (now, actions, targets, experts) =
                    self.td_batch(self.config.algo == Algo::Ddqn);
                let b = actions.len();
                let expert_actions = actions[b - experts..].to_vec();
                let g = GraphTensors::<TrainBackend>::new(&now, &device);
                let action_index = Tensor::<TrainBackend, 2, Int>::from_data(
                    TensorData::new(actions, [b, 1]),
                    &device,
                );
                let q = self.online.forward(&g);
                let q_sa = q.clone().gather(1, action_index);
                let y =
                    Tensor::<TrainBackend, 2>::from_data(TensorData::new(targets, [b, 1]), &device);
                let td = self.elementwise_loss(q_sa.clone() - y).mean();
                match &self.config.demonstrations {
                    Some(d) if experts > 0 => {
                        let m = self.config.network.tasks();
                        let mask = &now.mask[(b - experts) * m..];
                        let margins = large_margins(mask, &expert_actions, m, d.margin);
                        let margins = Tensor::<TrainBackend, 2>::from_data(
                            TensorData::new(margins, [experts, m]),
                            &device,
                        );
                        let best = (q.slice([b - experts..b, 0..m]) + margins).max_dim(1);
                        let expert = q_sa.slice([b - experts..b, 0..1]);
                        td + (best - expert).mean() * d.weight
                    }
                    _ => td,
                }
            }
            Algo::QStar => {
                let (now, labels, allowed) = self.q_star_batch()?;
                let shape = [now.num_graphs(), self.config.network.tasks()];
                let count = allowed.iter().sum::<f32>();
                let g = GraphTensors::<TrainBackend>::new(&now, &device);
                let y =
                    Tensor::<TrainBackend, 2>::from_data(TensorData::new(labels, shape), &device);
                let w =
                    Tensor::<TrainBackend, 2>::from_data(TensorData::new(allowed, shape), &device);
                // Full tasks have label 0 and weight 0: they add nothing.
                let diff = (self.online.forward(&g) - y) * w;
                self.elementwise_loss(diff).sum() / count
            }
        };
        let loss = if self.config.price_loss > 0.0 {
            loss + self.price_loss() * self.config.price_loss
        } else {
            loss
        };
        let loss_value: f32 = loss.clone().into_scalar();
        if !loss_value.is_finite() {
            return Err(LearnError::NonFiniteLoss {
                step: self.step + 1,
                loss: loss_value,
            });
        }
        let grads = GradientsParams::from_grads(loss.backward(), &self.online);
        let lr = self.config.learning_rate(self.step);
        let updated = self.optim.step(lr, self.online.clone(), grads);
        // A finite loss can still have a gradient that overflows a weight.
        if !crate::weights::weights_are_finite(&updated) {
            return Err(LearnError::NonFiniteWeights {
                step: self.step + 1,
            });
        }
        self.online = updated;
        Ok(loss_value)
    }

    /// The one-shot price loss ([`TrainConfig::price_loss`], without its weight): the
    /// mean squared error of the centred `Q(s_0, j) + β d(i, j)` against the centred
    /// exact prices on [`Trainer::price_batch`].
    fn price_loss(&mut self) -> Tensor<TrainBackend, 1> {
        let device = Default::default();
        let (empty, prices) = self.price_batch();
        let shape = [empty.num_graphs(), self.config.network.tasks()];
        let g = GraphTensors::<TrainBackend>::new(&empty, &device);
        let scores = self.online.forward(&g) + g.cost.clone();
        let centred = scores.clone() - scores.mean_dim(1);
        let y = Tensor::<TrainBackend, 2>::from_data(TensorData::new(prices, shape), &device);
        (centred - y).powi_scalar(2).mean()
    }

    /// The Huber (δ = 1) or squared error of every entry of `diff`.
    fn elementwise_loss<const D: usize>(
        &self,
        diff: Tensor<TrainBackend, D>,
    ) -> Tensor<TrainBackend, D> {
        if self.config.huber {
            // huber(x) = q²/2 + (|x| - q) with q = min(|x|, 1).
            let abs = diff.abs();
            let quad = abs.clone().clamp_max(1.0);
            quad.clone().powi_scalar(2) * 0.5 + (abs - quad)
        } else {
            diff.powi_scalar(2)
        }
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
        let pairs = welfare
            .iter()
            .copied()
            .zip(self.validation_opt.iter().copied());
        let pct = afg_baseline::mean_percent_of_opt(pairs).unwrap_or(f64::NAN);
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

    /// Whether every configured gradient step is done.
    pub fn is_finished(&self) -> bool {
        self.step >= self.config.steps
    }

    /// Acts until the replay buffer allows a gradient step, takes it, and validates when
    /// a validation is due.
    ///
    /// # Errors
    /// [`LearnError::NonFiniteLoss`] when the loss is NaN or infinite (the weights are
    /// left as they were, so the last checkpoint stays the last good state),
    /// [`LearnError::InvalidConfig`] when the run is already finished, and graph errors
    /// (none for valid configurations).
    pub fn step(&mut self) -> Result<StepReport, LearnError> {
        if self.is_finished() {
            return Err(LearnError::InvalidConfig(format!(
                "the run is finished: all {} steps are done",
                self.config.steps
            )));
        }
        let epsilon = self.config.epsilon(self.step);
        loop {
            self.act(epsilon)?;
            if self.replay_len() >= self.config.warmup.max(1) {
                break;
            }
        }
        let loss = self.learn()?;
        self.step += 1;
        if self.step.is_multiple_of(self.config.target_sync) {
            self.target = self.online.valid();
        }
        let validation = (self.step.is_multiple_of(self.config.validate_every)
            || self.step == self.config.steps)
            .then(|| self.validate())
            .transpose()?;
        Ok(StepReport {
            step: self.step,
            loss,
            epsilon,
            validation,
        })
    }
}
