//! The flags of `afg train` ([`TrainSettings`]): a preset and the values that differ
//! from it, turned into afg-learn's [`TrainConfig`] and back.

use std::path::PathBuf;

use afg_game::GeneratorConfig;
use afg_graph::Units;
use serde::Serialize;

use afg_learn::LearnError;
use afg_learn::env::Shaping;
use afg_learn::nets::{AfgNetConfig, Net, NetworkConfig};
use afg_learn::train::{Algo, Demonstrations, Preset, TrainConfig};

use crate::{choice, set_given};

/// A training run as a user asks for it: the scale, the network and the algorithm, and
/// only the settings that differ from the preset's defaults (`None` / `false`: the
/// default). These are the flags of `afg train` and `cargo xtask train` (each field's
/// name in kebab case).
///
/// # Examples
/// ```
/// use afg_cli::settings::TrainSettings;
/// use afg_learn::{nets::Net, train::{Algo, Preset}};
///
/// let asked = TrainSettings { scale: Some(60), lr: Some(3e-4), ..TrainSettings::default() };
/// let config = asked.to_config()?;
/// assert_eq!((config.robots, config.lr, config.steps), (60, 3e-4, 2_500));
/// assert_eq!((config.algo, config.preset), (Algo::Ddqn, Preset::Ours));
/// // The inverse names the scale, network, algorithm, budget and seed, and the rest
/// // only where it differs from the defaults.
/// let back = TrainSettings::from_config(&config);
/// assert_eq!(back.net, Some(Net::AfgNet));
/// assert_eq!(back.to_config()?, config);
/// assert!(TrainSettings::default().to_config().is_err()); // no scale
/// # Ok::<(), afg_learn::LearnError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, clap::Args)]
pub struct TrainSettings {
    /// Robots per training instance N (defaults exist for 20, 60 and 100).
    #[arg(long)]
    pub scale: Option<usize>,
    /// What the Q values are fitted to: dqn (the paper's bootstrap rule), ddqn (Double
    /// DQN, the paper's; the default) or qstar (regression on the exact Q* of every
    /// action; ours, not reinforcement learning).
    #[arg(long, value_parser = choice::<Algo>())]
    pub algo: Option<Algo>,
    /// Network: afgnet (the paper's; the default) or s2v (Structure2Vec, the paper's
    /// comparison).
    #[arg(long, value_parser = choice::<Net>())]
    pub net: Option<Net>,
    /// Gradient steps (default: the per-scale budget of about an hour on one core).
    #[arg(long)]
    pub steps: Option<u64>,
    /// Seed of everything random in the run (initial weights, instances, exploration).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Tasks per training instance M (the network is built for this M) [default: 5,
    /// the paper's].
    #[arg(long)]
    pub tasks: Option<usize>,
    /// Transitions per gradient step.
    #[arg(long)]
    pub batch: Option<usize>,
    /// Adam learning rate (default 1e-3; the paper's is 1e-4).
    #[arg(long)]
    pub lr: Option<f64>,
    /// Keep the learning rate constant (by default it anneals linearly to a tenth of
    /// --lr over the run).
    #[arg(long)]
    pub constant_lr: bool,
    /// n-step returns (1 = the paper's one-step target).
    #[arg(long)]
    pub n_step: Option<usize>,
    /// Gradient steps between target-network syncs (default: the run's budget / 20,
    /// clamped to 10..=1000).
    #[arg(long)]
    pub target_sync: Option<u64>,
    /// Episodes run side by side (each acting step adds this many transitions).
    #[arg(long)]
    pub parallel_envs: Option<usize>,
    /// Instances in the fixed validation set (default 32); fewer make each validation
    /// cheaper at large N.
    #[arg(long)]
    pub validation_instances: Option<usize>,
    /// Gradient steps between validations (default: the run's budget / 40).
    #[arg(long)]
    pub validate_every: Option<u64>,
    /// Turn off the reward shaping. By default rewards are shaped with the potential
    /// "welfare a greedy completion would still add", so the network learns how much
    /// better than finishing greedily each action is (not in the paper; the optimal
    /// policy is unchanged; docs/training.md).
    #[arg(long)]
    pub no_shaping: bool,
    /// The reward shaping: none (the paper's reward, the welfare change), greedy (the
    /// potential is the welfare a greedy completion would still add; the default) or
    /// optimal (the welfare the optimal completion would still add, one min-cost flow
    /// per state, so the TD targets carry the exact advantages; ours). `--no-shaping` is
    /// `--shaping none`.
    #[arg(long, value_parser = choice::<Shaping>(), conflicts_with = "no_shaping")]
    pub shaping: Option<Shaping>,
    /// Units of the network's inputs and rewards: mean-reward (welfare / the mean task
    /// reward, raw edge weights: the first models' units), scale-free (welfare / β, edge
    /// weights / their mean: the same at every N) or bounded (scale-free, with the value
    /// part of the task features capped at 4 r_j/eps_j so that nearly empty tasks look
    /// alike at every N; the default).
    #[arg(long, value_parser = choice::<Units>())]
    pub units: Option<Units>,
    /// AFGNet only: add each action's immediate reward (the actor's join gain) to the
    /// Q values, so the network learns only the value of what follows (not in the
    /// paper; implies no shaping).
    #[arg(long)]
    pub gain_residual: bool,
    /// AFGNet only: the price structure Q(s, a) = π_a(s) − β d(t, a) + c_a(s), with a
    /// price head shared by all tasks that reads each task's summaries and the pooled
    /// embedding; the untrained network is Nearest (ours, not in the paper;
    /// docs/price.md).
    #[arg(long)]
    pub price_head: bool,
    /// With --price-head: weight of the one-shot price loss (ours, not in the paper):
    /// every step also fits the Q values of empty states, plus the actor's distance
    /// cost, to the instance's exact task prices (centred), so that the one-shot mode
    /// (every robot at once on the empty state's Q values) reproduces the optimum.
    #[arg(long, value_name = "WEIGHT", requires = "price_head")]
    pub price_loss: Option<f64>,
    /// Learn from demonstrations as in Deep Q-learning from Demonstrations (ours, not
    /// in the paper): this many expert episodes (each robot on its task in the exact
    /// optimum), a share of every batch drawn from them, and a large-margin loss on the
    /// expert's action. DQN and Double DQN only.
    #[arg(long, value_name = "EPISODES")]
    pub demos: Option<usize>,
    /// With --demos: share of each batch drawn from the demonstrations [default: 0.25].
    #[arg(long, requires = "demos")]
    pub demo_share: Option<f64>,
    /// With --demos: the margin by which the expert's action should lead, in the
    /// network's welfare unit (distance units with the default units) [default: 0.05].
    #[arg(long, requires = "demos")]
    pub demo_margin: Option<f64>,
    /// With --demos: weight of the large-margin loss [default: 1].
    #[arg(long, requires = "demos")]
    pub demo_weight: Option<f64>,
    /// The paper's settings where ours differ: squared loss, raw rewards, no clipping,
    /// target sync every 1000 steps, constant learning rate 1e-4 (an explicit --lr still
    /// wins).
    #[arg(long)]
    pub paper: bool,
    /// ε at the start (default 1.0, decaying to 0.05 over the first tenth of the run).
    #[arg(long)]
    pub eps_start: Option<f64>,
    /// Warm start: begin from the final weights of this run directory (same network and
    /// units) instead of fresh ones, e.g. a model trained at N = 60 for a run at N = 100.
    /// Not in the paper. Usually with a small --eps-start.
    #[arg(long)]
    pub init_from: Option<PathBuf>,
}

impl TrainSettings {
    /// Whether nothing is set.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }

    /// The configuration these settings ask for: the preset's defaults for the scale
    /// and budget ([`TrainConfig::from_preset`], [`TrainConfig::default_steps`]), with
    /// every given setting applied, checked.
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] without a scale, without a budget where none is
    /// known for the scale, for settings of one network given to the other, or for
    /// settings that [`TrainConfig::check`] refuses.
    pub fn to_config(&self) -> Result<TrainConfig, LearnError> {
        let bad = |what: String| Err(LearnError::InvalidConfig(what));
        let Some(scale) = self.scale else {
            return bad("--scale is required for a new run".into());
        };
        let Some(steps) = self.steps.or(TrainConfig::default_steps(scale)) else {
            return bad(format!(
                "no default budget for --scale {scale} (known: 20, 60, 100); pass --steps"
            ));
        };
        let seed = self.seed.unwrap_or(0);
        let tasks = self.tasks.unwrap_or(GeneratorConfig::PAPER_TASKS);
        let network = match self.net.unwrap_or(Net::AfgNet) {
            Net::AfgNet => NetworkConfig::AfgNet(
                AfgNetConfig::new(tasks, Units::Bounded)
                    .with_seed(seed)
                    .with_gain_residual(self.gain_residual)
                    .with_price_head(self.price_head),
            ),
            Net::S2v if self.gain_residual || self.price_head => {
                return bad("--gain-residual and --price-head exist for AFGNet only".into());
            }
            Net::S2v => NetworkConfig::s2v(tasks, seed),
        }
        .with_units(self.units.unwrap_or(Units::Bounded));
        let preset = if self.paper {
            Preset::Paper
        } else {
            Preset::Ours
        };
        let algo = self.algo.unwrap_or(Algo::Ddqn);
        let mut c = TrainConfig::from_preset(preset, scale, algo, network, steps, seed);
        c.lr_decay &= !self.constant_lr;
        set_given!(c;
            batch = self.batch,
            lr = self.lr,
            n_step = self.n_step,
            target_sync = self.target_sync,
            parallel_envs = self.parallel_envs,
            validation_instances = self.validation_instances,
            validate_every = self.validate_every,
            eps_start = self.eps_start,
            price_loss = self.price_loss,
            shaping = self.shaping,
        );
        c.init_from.clone_from(&self.init_from);
        c.demonstrations = self.demos.map(|episodes| Demonstrations {
            episodes,
            share: self.demo_share.unwrap_or(0.25),
            margin: self.demo_margin.unwrap_or(0.05),
            weight: self.demo_weight.unwrap_or(1.0),
        });
        // The gain residual adds the unshaped reward to Q: it implies no shaping.
        if self.no_shaping || self.gain_residual {
            c.shaping = Shaping::None;
        }
        c.check()?;
        Ok(c)
    }

    /// The settings that give `config` back through [`TrainSettings::to_config`]: the
    /// scale, algorithm, network, budget and seed always, everything else only where it
    /// differs from the preset's defaults. Settings that have no flag (the ε decay, the
    /// replay size, …) keep their defaults.
    pub fn from_config(config: &TrainConfig) -> Self {
        let c = config;
        let default = TrainConfig::from_preset(
            c.preset,
            c.robots,
            c.algo,
            c.network.clone(),
            c.steps,
            c.seed,
        );
        let (gain_residual, price_head) = match &c.network {
            NetworkConfig::AfgNet(a) => (a.gain_residual, a.price_head),
            NetworkConfig::S2v(_) => (false, false),
        };
        // --gain-residual implies no shaping.
        let shaping =
            differs(c.shaping, default.shaping).filter(|s| !(gain_residual && *s == Shaping::None));
        TrainSettings {
            scale: Some(c.robots),
            algo: Some(c.algo),
            net: Some(c.network.net()),
            steps: Some(c.steps),
            seed: Some(c.seed),
            tasks: differs(c.network.tasks(), GeneratorConfig::PAPER_TASKS),
            batch: differs(c.batch, default.batch),
            lr: differs(c.lr, default.lr),
            constant_lr: default.lr_decay && !c.lr_decay,
            n_step: differs(c.n_step, default.n_step),
            target_sync: differs(c.target_sync, default.target_sync),
            parallel_envs: differs(c.parallel_envs, default.parallel_envs),
            validation_instances: differs(c.validation_instances, default.validation_instances),
            validate_every: differs(c.validate_every, default.validate_every),
            no_shaping: shaping == Some(Shaping::None),
            shaping: shaping.filter(|&s| s != Shaping::None),
            units: differs(c.network.units(), Units::Bounded),
            gain_residual,
            price_head,
            price_loss: differs(c.price_loss, default.price_loss),
            demos: c.demonstrations.map(|d| d.episodes),
            demo_share: c.demonstrations.map(|d| d.share),
            demo_margin: c.demonstrations.map(|d| d.margin),
            demo_weight: c.demonstrations.map(|d| d.weight),
            paper: c.preset == Preset::Paper,
            eps_start: differs(c.eps_start, default.eps_start),
            init_from: c.init_from.clone(),
        }
    }
}

/// `Some(value)` where it differs from the default.
fn differs<T: PartialEq>(value: T, default: T) -> Option<T> {
    (value != default).then_some(value)
}
