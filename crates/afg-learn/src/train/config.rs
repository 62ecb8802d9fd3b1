//! Every setting of a training run, and the seeded instances it trains and validates on.

use afg_baseline::Allocator;
use afg_game::{GeneratorConfig, Instance};
use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::env::Shaping;
use crate::qnetwork::NetworkConfig;

/// What the network's Q values are fitted to: a bootstrap rule, or the exact `Q*`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algo {
    /// `r + max_a Q_target(s', a)`.
    Dqn,
    /// `r + Q_target(s', argmax_a Q_online(s', a))`.
    Ddqn,
    /// Every allowed action's value regressed on the exact `Q*(s, a)` of the sequential
    /// MDP ([`crate::regret::q_star`]), on the states the ε-greedy policy of the network visits
    /// (as in DAgger), in the run's reward convention: divided by the welfare unit with
    /// `reward_scaling`, minus the shaping potential of `shaping` (the exact
    /// value that the TD targets estimate). Supervised, not reinforcement learning, and
    /// not in the paper (ours).
    QStar,
}

impl afg_game::Named for Algo {
    const ALL: &'static [Self] = &[Algo::Dqn, Algo::Ddqn, Algo::QStar];
    const WHAT: &'static str = "algorithm";

    fn name(self) -> &'static str {
        Algo::name(self)
    }
}

impl Algo {
    /// `dqn`, `ddqn` or `qstar`.
    pub fn name(self) -> &'static str {
        match self {
            Algo::Dqn => "dqn",
            Algo::Ddqn => "ddqn",
            Algo::QStar => "qstar",
        }
    }
}

/// The family of defaults a configuration starts from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// This project's settings ([`TrainConfig::new`]).
    #[default]
    Ours,
    /// The paper's settings where ours differ ([`TrainConfig::paper`]).
    Paper,
}

/// Every setting of a training run. Stored in the run directory; `--resume` refuses a
/// directory whose settings differ from the ones asked for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainConfig {
    /// The defaults this configuration started from (recorded so that a run's command
    /// line can be rebuilt).
    pub preset: Preset,
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
    /// swinging between validations.
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
    pub n_step: usize,
    /// Huber loss (δ = 1) instead of the squared error.
    pub huber: bool,
    /// Rewards in the network's welfare unit ([`afg_graph::Units::welfare_unit`], the
    /// task features' unit) instead of raw welfare.
    pub reward_scaling: bool,
    /// Potential-based reward shaping (Ng, Harada and Russell, 1999; [`Shaping`]): with
    /// [`Shaping::Greedy`] the potential is Φ(s) = W(greedy completion of s) − W(s), the
    /// welfare that one-pass greedy would still add from s, and the shaped reward of
    /// steps t..t+n is `W(greedy completion of s_{t+n}) − W(greedy completion of s_t)`:
    /// the network learns `Q(s, a) − Φ(s)`, what the policy gains over finishing
    /// greedily, O(action gaps) instead of O(N). Φ does not depend on the action, so
    /// the optimal policy and the greedy policy of a learned Q are unchanged. Not in the
    /// paper.
    pub shaping: Shaping,
    /// Gradient norm clipping.
    pub grad_clip: Option<f32>,
    /// Size of the fixed validation set (seeded, disjoint from datasets and training).
    pub validation_instances: usize,
    /// Gradient steps between validations.
    pub validate_every: u64,
    /// Seed of everything random in the run.
    pub seed: u64,
    /// Start from the weights of another run (its directory, relative to where the
    /// trainer runs) instead of fresh ones: a warm start, e.g. from a model trained at
    /// another N. The network configuration must be the same. Not in the paper.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub init_from: Option<std::path::PathBuf>,
    /// Learning from demonstrations as in Deep Q-learning from Demonstrations (Hester
    /// et al., 2018): expert episodes in every batch and a large-margin loss on the
    /// expert's action. Ours, not in the paper; DQN and Double DQN only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub demonstrations: Option<Demonstrations>,
    /// Weight of the one-shot price loss (ours, not in the paper; 0, the default, turns
    /// it off; needs a price head). Each gradient step then also draws a quarter batch
    /// of empty states of the replay's instances, each with a random acting robot i,
    /// and adds `price_loss · mean_j (ĉ_j − π̂*_j)²`, where `ĉ_j = Q(s_0, j) + β d(i, j)`
    /// (the price plus the correction, what the one-shot mode compares), `π*` are the
    /// instance's exact task prices ([`afg_baseline::Optimum::with_prices`]) in the
    /// network's welfare unit, and a hat centres a row over the tasks (prices are
    /// defined up to a constant). The one-shot mode, every robot at once on
    /// `argmax_j Q(s_0, j)`, is then supervised on what it should reproduce.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub price_loss: f64,
}

/// The demonstrations of a run ([`TrainConfig::demonstrations`]): episodes in which
/// every robot takes its task in the exact optimum (the optimum's choice maximises
/// `Q*` at every state along it), on instances seeded apart from the training,
/// validation and test instances, fixed for the whole run.
///
/// Each batch draws `share` of its transitions from them; on those the loss adds
/// `weight · (max_a [Q(s, a) + margin · 1(a ≠ a_E)] − Q(s, a_E))` (the maximum over
/// the tasks with room), which is zero only when the expert's action `a_E` leads every
/// other by `margin`. The TD loss applies to every transition.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Demonstrations {
    /// Expert episodes.
    pub episodes: usize,
    /// Share of each batch drawn from them, in (0, 1).
    pub share: f64,
    /// The margin, in the network's welfare unit.
    pub margin: f64,
    /// Weight of the large-margin loss.
    pub weight: f64,
}

impl Demonstrations {
    /// Seed of demonstration episode `episode` of a run seeded `run_seed`, apart from
    /// the training instances (2^62 + …), validation (2^63 + i) and datasets (< 2^40).
    pub fn instance_seed(run_seed: u64, episode: u64) -> u64 {
        (1 << 62) + (1 << 61) + (run_seed << 32) + episode
    }

    /// Transitions of a batch of `batch` drawn from the demonstrations.
    pub fn per_batch(&self, batch: usize) -> usize {
        ((batch as f64 * self.share).round() as usize).clamp(1, batch)
    }
}

impl TrainConfig {
    /// Defaults for `robots` and a step budget: batch 256, Adam 1e-3 (the paper's 1e-4
    /// learns too slowly for a CPU budget; docs/training.md), ε 1.0 → 0.05 over
    /// 10 % of the steps, 16 parallel episodes, Huber loss, reward scaling, greedy
    /// reward shaping ([`TrainConfig::shaping`]), gradient
    /// clipping at norm 10, and a target sync every `clamp(steps / 20, 10, 1000)` steps
    /// (the paper's c = 1000 assumes 2.5 M steps; a CPU budget needs more syncs).
    pub fn new(robots: usize, algo: Algo, network: NetworkConfig, steps: u64, seed: u64) -> Self {
        TrainConfig {
            preset: Preset::Ours,
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
            shaping: Shaping::Greedy,
            grad_clip: Some(10.0),
            validation_instances: 32,
            validate_every: (steps / 40).max(1),
            seed,
            init_from: None,
            demonstrations: None,
            price_loss: 0.0,
        }
    }

    /// The paper's settings where [`TrainConfig::new`] differs: squared loss, raw
    /// rewards, no reward shaping, no gradient clipping, a target sync every 1 000
    /// steps and a constant learning rate of 1e-4 (paper §IV).
    ///
    /// # Examples
    /// ```
    /// use afg_learn::{nets::NetworkConfig, train::{Algo, Preset, TrainConfig}};
    ///
    /// let c = TrainConfig::paper(20, Algo::Ddqn, NetworkConfig::afgnet(5, 0), 100, 0);
    /// assert_eq!((c.preset, c.lr, c.target_sync, c.huber), (Preset::Paper, 1e-4, 1000, false));
    /// ```
    pub fn paper(robots: usize, algo: Algo, network: NetworkConfig, steps: u64, seed: u64) -> Self {
        TrainConfig {
            preset: Preset::Paper,
            shaping: Shaping::None,
            huber: false,
            reward_scaling: false,
            grad_clip: None,
            target_sync: 1000,
            lr: 1e-4,
            lr_decay: false,
            ..Self::new(robots, algo, network, steps, seed)
        }
    }

    /// The configuration `preset` gives.
    pub fn from_preset(
        preset: Preset,
        robots: usize,
        algo: Algo,
        network: NetworkConfig,
        steps: u64,
        seed: u64,
    ) -> Self {
        match preset {
            Preset::Ours => Self::new(robots, algo, network, steps, seed),
            Preset::Paper => Self::paper(robots, algo, network, steps, seed),
        }
    }

    /// The default gradient-step budget at a scale: about an hour on one core of this
    /// project's 2-core reference machine for AFGNet DDQN (measured rates in
    /// `docs/training.md`); `None` where no budget has been measured.
    ///
    /// # Examples
    /// ```
    /// use afg_learn::train::TrainConfig;
    /// assert_eq!(TrainConfig::default_steps(60), Some(2_500));
    /// assert_eq!(TrainConfig::default_steps(33), None);
    /// ```
    pub fn default_steps(robots: usize) -> Option<u64> {
        match robots {
            20 => Some(20_000),
            60 => Some(2_500),
            100 => Some(1_500),
            _ => None,
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
        self.network.check().map_err(LearnError::InvalidConfig)?;
        if self.seed > MAX_RUN_SEED {
            return Err(LearnError::InvalidConfig(format!(
                "seed {} is above {MAX_RUN_SEED} (2^29 - 1): larger run seeds would draw \
                 training instances from the seeds of the demonstrations or the validation set",
                self.seed
            )));
        }
        if self.steps > MAX_STEPS {
            return bad("steps must be at most 2^31 (episode numbers must stay below 2^32)");
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
        self.check_sizes()?;
        self.check_heads()
    }

    /// Bounds on what a run may allocate, checked before anything is built.
    fn check_sizes(&self) -> Result<(), LearnError> {
        for (name, value, max) in [
            ("robots", self.robots, 100_000),
            ("batch", self.batch, 65_536),
            ("parallel_envs", self.parallel_envs, 4_096),
            ("replay_capacity", self.replay_capacity, 100_000_000),
            ("validation_instances", self.validation_instances, 10_000),
            ("n_step", self.n_step, self.robots),
            (
                "demonstration episodes",
                self.demonstrations.as_ref().map_or(0, |d| d.episodes),
                100_000,
            ),
        ] {
            if value > max {
                return Err(LearnError::InvalidConfig(format!(
                    "{name} is {value}; at most {max}"
                )));
            }
        }
        Ok(())
    }

    /// The settings that go together: gain residual, demonstrations, price head and loss.
    fn check_heads(&self) -> Result<(), LearnError> {
        let bad = |what: &str| Err(LearnError::InvalidConfig(what.to_owned()));
        if matches!(&self.network, NetworkConfig::AfgNet(c) if c.gain_residual)
            && (!self.reward_scaling || self.shaping != Shaping::None)
        {
            return bad(
                "the gain residual is in the features' unit and adds the unshaped reward: it needs reward scaling and no shaping",
            );
        }
        if let Some(d) = &self.demonstrations {
            if self.algo == Algo::QStar {
                return bad("demonstrations go with DQN or Double DQN, not Q* regression");
            }
            if d.episodes == 0
                || !(d.share > 0.0 && d.share < 1.0)
                || !(d.margin >= 0.0 && d.margin.is_finite())
                || !(d.weight >= 0.0 && d.weight.is_finite())
            {
                return bad(
                    "demonstrations need episodes > 0, a share in (0, 1), and a finite margin and weight ≥ 0",
                );
            }
        }
        let price_head = matches!(&self.network, NetworkConfig::AfgNet(c) if c.price_head);
        if !(self.price_loss.is_finite() && self.price_loss >= 0.0) {
            return bad("price_loss must be finite and at least 0");
        }
        if self.price_loss > 0.0 && !price_head {
            return bad("the price loss supervises a price head: it needs a price head");
        }
        if price_head
            && (!self.reward_scaling
                || matches!(&self.network, NetworkConfig::AfgNet(c) if c.gain_residual))
        {
            return bad(
                "the price head subtracts the actor's cost in the features' unit: it needs reward scaling, and no gain residual",
            );
        }
        Ok(())
    }

    /// The learning rate of gradient step `step` (0-based): `lr` constant, or annealed
    /// linearly to `lr / 10` at the last step when `lr_decay` is set.
    ///
    /// # Examples
    /// ```
    /// use afg_learn::{nets::NetworkConfig, train::{Algo, TrainConfig}};
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

    pub(super) fn instance(&self, seed: u64) -> Instance {
        GeneratorConfig::paper(self.robots, self.network.tasks(), seed)
            .generate()
            .expect("checked configuration generates valid instances")
    }
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// The largest run seed: training instances (2^62 + seed · 2^32 + episode) stay below
/// the demonstrations' seeds (2^62 + 2^61 + …) and those below the validation set's
/// (2^63 + i).
pub const MAX_RUN_SEED: u64 = (1 << 29) - 1;

/// The largest step budget, so that episode numbers stay below 2^32.
const MAX_STEPS: u64 = 1 << 31;

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

/// The fixed validation set ([`validation_instances`]) with the optimum's welfare of
/// each instance, what every validation compares with.
pub(crate) fn validation_set(
    robots: usize,
    tasks: usize,
    count: usize,
) -> Result<(Vec<Instance>, Vec<f64>), LearnError> {
    let instances = validation_instances(robots, tasks, count)?;
    let optima = instances
        .iter()
        .map(|inst| {
            let opt = afg_baseline::Optimum
                .allocate(inst)
                .map_err(|e| LearnError::InvalidConfig(e.to_string()))?;
            Ok(inst.welfare(&opt.assignment))
        })
        .collect::<Result<_, LearnError>>()?;
    Ok((instances, optima))
}
