//! The learned models of the tables, by identity rather than by directory string.

use std::path::{Path, PathBuf};

use afg_learn::{nets::Net, run::RunDir, train::Algo};

/// The output head a model adds to the paper's network.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Head {
    /// The paper's Q head.
    #[default]
    Plain,
    /// Ours: the action's immediate reward added to the Q values.
    GainResidual,
    /// Ours: a price head, `Q(s, a) = π_a(s) − β d(t, a) + c_a(s)`, Nearest before
    /// training.
    Price,
}

/// One trained model, as data: network, algorithm, head, how it was trained, and the N
/// it was trained at. Directory names and row labels are made from these fields.
///
/// # Examples
/// ```
/// use xtask::{Head, ModelSpec};
/// use afg_learn::{nets::Net, train::Algo};
/// let m = ModelSpec::new(Net::AfgNet, Algo::Ddqn, 60);
/// assert_eq!(m.dir_name(), "afgnet_ddqn_n60");
/// assert_eq!(m.models_path(), std::path::Path::new("models/paper/afgnet_ddqn_n60"));
/// assert_eq!(m.label(), "AFGNet_DDQN");
/// let ours = m.with_head(Head::GainResidual);
/// assert!(ours.is_ours() && ours.label().ends_with("(ours)"));
/// assert_eq!(ModelSpec::table1(20).len(), 5);
/// let exact = ModelSpec::TRANSFERRED[1];
/// assert_eq!(exact.dir_name(), "afgnet_qstar_n60");
/// assert_eq!(exact.label(), "AFGNet, exact Q* regression (ours)");
/// assert!(exact.is_ours());
/// let shaped = ModelSpec::TRANSFERRED[2];
/// assert_eq!(shaped.dir_name(), "afgnet_ddqn_optshape_n60");
/// assert_eq!(shaped.label(), "AFGNet_DDQN, optimal-completion shaping (ours)");
/// let warm = ModelSpec::WARM_STARTS[2];
/// assert_eq!(warm.dir_name(), "s2v_ddqn_warm20_n60");
/// assert_eq!(warm.label(), "S2V_DDQN, warm start from the N = 20 model");
/// assert!(!warm.is_ours() && !warm.is_paper_method());
/// let shaped_warm = ModelSpec::WARM_STARTS[1];
/// assert_eq!(shaped_warm.dir_name(), "afgnet_ddqn_optshape_warm60_n100");
/// assert_eq!(
///     shaped_warm.models_path(),
///     std::path::Path::new("models/ours/afgnet_ddqn_optshape_warm60_n100")
/// );
/// assert_eq!(
///     shaped_warm.label(),
///     "AFGNet_DDQN, optimal-completion shaping, warm start from the N = 60 model (ours)"
/// );
/// let [exact, prices, td, demos] = ModelSpec::PRICE_HEADED;
/// assert_eq!(exact.dir_name(), "afgnet_qstar_price_n60");
/// assert_eq!(prices.dir_name(), "afgnet_qstar_price_priceloss_n60");
/// assert_eq!(
///     prices.label(),
///     "AFGNet + price head, exact Q* and price regression (ours)"
/// );
/// assert_eq!(exact.label(), "AFGNet + price head, exact Q* regression (ours)");
/// assert_eq!(td.dir_name(), "afgnet_ddqn_price_n60");
/// assert_eq!(demos.dir_name(), "afgnet_ddqn_price_demos_n60");
/// assert_eq!(demos.label(), "AFGNet_DDQN + price head + demonstrations (ours)");
/// assert!(td.is_ours() && demos.is_ours());
/// assert_eq!(
///     exact.label_with(", one-shot"),
///     "AFGNet + price head, exact Q* regression, one-shot (ours)"
/// );
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ModelSpec {
    /// The network.
    pub net: Net,
    /// The bootstrap rule (or exact Q* regression).
    pub algo: Algo,
    /// The output head.
    pub head: Head,
    /// Ours: the reward shaped by the optimal completion (`--shaping optimal`,
    /// [`afg_learn::env::Shaping::Optimal`]): the optimal policy is unchanged, but the
    /// rewards carry the exact optimum's values.
    pub optimal_shaping: bool,
    /// Ours: demonstrations from the exact optimum with a large-margin loss
    /// (`--demos`, as in Deep Q-learning from Demonstrations).
    pub demonstrations: bool,
    /// Ours: the one-shot scores also fitted to the exact task prices (`--price-loss`,
    /// [`afg_learn::train::TrainConfig::price_loss`]).
    pub price_loss: bool,
    /// The N of the same kind of model whose weights the run starts from (a warm
    /// start; not in the paper, named in the row).
    pub warm_start_from: Option<usize>,
    /// Robots per training instance.
    pub trained_at: usize,
}

impl ModelSpec {
    /// The training scale of the model the paper transfers to other N ("Pretrain_60").
    pub const PRETRAINED_AT: usize = 60;

    /// The paper's `net` trained by `algo` at `trained_at` robots (the paper's method
    /// unless `algo` is [`Algo::QStar`]; training departures are in its command).
    pub const fn new(net: Net, algo: Algo, trained_at: usize) -> Self {
        ModelSpec {
            net,
            algo,
            head: Head::Plain,
            optimal_shaping: false,
            demonstrations: false,
            price_loss: false,
            warm_start_from: None,
            trained_at,
        }
    }

    /// The same with another output head.
    pub const fn with_head(self, head: Head) -> Self {
        ModelSpec { head, ..self }
    }

    /// The same with the reward shaped by the optimal completion.
    pub const fn with_optimal_shaping(self) -> Self {
        ModelSpec {
            optimal_shaping: true,
            ..self
        }
    }

    /// The same trained with demonstrations.
    pub const fn with_demonstrations(self) -> Self {
        ModelSpec {
            demonstrations: true,
            ..self
        }
    }

    /// The same with the price loss.
    pub const fn with_price_loss(self) -> Self {
        ModelSpec {
            price_loss: true,
            ..self
        }
    }

    /// The same started from the weights of the model trained at N = `from`.
    pub const fn warm_started_from(self, from: usize) -> Self {
        ModelSpec {
            warm_start_from: Some(from),
            ..self
        }
    }

    /// The learned rows of Table I trained at `robots`, in table order: the paper's
    /// three models, then ours.
    pub const fn table1(robots: usize) -> [ModelSpec; 5] {
        [
            Self::new(Net::S2v, Algo::Ddqn, robots),
            Self::new(Net::AfgNet, Algo::Dqn, robots),
            Self::afgnet_ddqn(robots),
            Self::afgnet_ddqn(robots).with_head(Head::GainResidual),
            Self::new(Net::AfgNet, Algo::QStar, robots),
        ]
    }

    /// The paper's AFGNet DDQN trained at `robots` (its headline model).
    pub const fn afgnet_ddqn(robots: usize) -> Self {
        Self::new(Net::AfgNet, Algo::Ddqn, robots)
    }

    /// The models trained at [`ModelSpec::PRETRAINED_AT`] that the tables also run at
    /// every other N: the paper's AFGNet DDQN, AFGNet trained on the exact Q* (ours)
    /// and AFGNet DDQN with the optimal completion as shaping potential (ours).
    pub const TRANSFERRED: [ModelSpec; 3] = [
        Self::afgnet_ddqn(Self::PRETRAINED_AT),
        Self::new(Net::AfgNet, Algo::QStar, Self::PRETRAINED_AT),
        Self::afgnet_ddqn(Self::PRETRAINED_AT).with_optimal_shaping(),
    ];

    /// The warm starts the tables show beside the paper's rows: AFGNet DDQN at N = 100
    /// from the N = 60 model (the paper's, and ours with optimal-completion shaping),
    /// S2V DDQN at N = 60 and 100 from the N = 20 model.
    pub const WARM_STARTS: [ModelSpec; 4] = [
        Self::afgnet_ddqn(100).warm_started_from(60),
        Self::afgnet_ddqn(100)
            .with_optimal_shaping()
            .warm_started_from(60),
        Self::new(Net::S2v, Algo::Ddqn, 60).warm_started_from(20),
        Self::new(Net::S2v, Algo::Ddqn, 100).warm_started_from(20),
    ];

    /// AFGNet with a price head, trained at [`ModelSpec::PRETRAINED_AT`] and run at
    /// every N (ours): on the exact Q*, on the exact Q* and the exact prices, by Double
    /// DQN, and by Double DQN with demonstrations.
    pub const PRICE_HEADED: [ModelSpec; 4] = {
        let exact = Self::new(Net::AfgNet, Algo::QStar, Self::PRETRAINED_AT).with_head(Head::Price);
        let td = Self::afgnet_ddqn(Self::PRETRAINED_AT).with_head(Head::Price);
        [exact, exact.with_price_loss(), td, td.with_demonstrations()]
    };

    /// The run directory's name: `{network}_{algorithm}`, then one word per way it
    /// departs from the paper's training (`gain`, `price`, `priceloss`, `demos`,
    /// `optshape`, `warm{N}` for a warm start from the model trained at N), then
    /// `n{N trained at}`; e.g. `afgnet_ddqn_warm60_n100`.
    pub fn dir_name(&self) -> String {
        let mut name = format!("{}_{}", self.net.name(), self.algo.name());
        name += match self.head {
            Head::Plain => "",
            Head::GainResidual => "_gain",
            Head::Price => "_price",
        };
        for (on, part) in [
            (self.price_loss, "_priceloss"),
            (self.demonstrations, "_demos"),
            (self.optimal_shaping, "_optshape"),
        ] {
            if on {
                name += part;
            }
        }
        if let Some(from) = self.warm_start_from {
            name += &format!("_warm{from}");
        }
        format!("{name}_n{}", self.trained_at)
    }

    /// The run directory relative to the repository root: `models/paper/…` for the
    /// paper's method, `models/ours/…` for every other model the tables show.
    pub fn models_path(&self) -> PathBuf {
        let role = if self.is_paper_method() {
            "paper"
        } else {
            "ours"
        };
        ["models", role, &self.dir_name()].iter().collect()
    }

    /// The run directory under the repository `root`.
    pub fn run_dir(&self, root: &Path) -> RunDir {
        RunDir::new(root.join(self.models_path()))
    }

    /// The row label, in the paper's naming (e.g. `AFGNet_DDQN`); ours end in "(ours)".
    pub fn label(&self) -> String {
        self.label_with("")
    }

    /// The row label with `detail` (how the model is run, e.g. ", one-shot") after the
    /// model's name and before "(ours)".
    pub fn label_with(&self, detail: &str) -> String {
        let mut name = String::from(match self.net {
            Net::AfgNet => "AFGNet",
            Net::S2v => "S2V",
        });
        match self.algo {
            Algo::Dqn => name += "_DQN",
            Algo::Ddqn => name += "_DDQN",
            Algo::QStar => {}
        }
        name += match self.head {
            Head::Plain => "",
            Head::GainResidual => " + gain residual",
            Head::Price => " + price head",
        };
        if self.demonstrations {
            name += " + demonstrations";
        }
        match (self.algo, self.price_loss) {
            (Algo::QStar, false) => name += ", exact Q* regression",
            (Algo::QStar, true) => name += ", exact Q* and price regression",
            (_, true) => name += " + price regression",
            (_, false) => {}
        }
        if self.optimal_shaping {
            name += ", optimal-completion shaping";
        }
        if let Some(from) = self.warm_start_from {
            name += &format!(", warm start from the N = {from} model");
        }
        let ours = if self.is_ours() { " (ours)" } else { "" };
        format!("{name}{detail}{ours}")
    }

    /// Whether the model is ours (not the paper's network and algorithm); the tables
    /// treat ours as optional. A warm start keeps the paper's network and algorithm.
    pub fn is_ours(&self) -> bool {
        self.head != Head::Plain
            || self.optimal_shaping
            || self.demonstrations
            || self.price_loss
            || self.algo == Algo::QStar
    }

    /// Whether the model is one the paper reports: its network and algorithm, trained
    /// from scratch.
    pub fn is_paper_method(&self) -> bool {
        !self.is_ours() && self.warm_start_from.is_none()
    }
}

/// How a price model was trained: the steps of its ablation (ours).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PriceTraining {
    /// Q* regression on the expert's states only (no DAgger, no one-shot loss).
    ExpertStates,
    /// Q* regression with DAgger, no one-shot loss.
    Dagger,
    /// Q* regression with DAgger and the one-shot price loss: the committed model.
    #[default]
    DaggerPriceLoss,
}

impl PriceTraining {
    /// Every training, in the ablation's order.
    pub const ALL: [PriceTraining; 3] = [
        PriceTraining::ExpertStates,
        PriceTraining::Dagger,
        PriceTraining::DaggerPriceLoss,
    ];

    /// What it is, as the ablation table says.
    pub fn describe(self) -> &'static str {
        match self {
            PriceTraining::ExpertStates => {
                "Q* regression on the expert's states only (no DAgger, no one-shot loss)"
            }
            PriceTraining::Dagger => "Q* regression with DAgger, no one-shot loss",
            PriceTraining::DaggerPriceLoss => {
                "Q* regression with DAgger + one-shot price loss (the committed model)"
            }
        }
    }
}

/// The price-structured model (ours, [`afg_learn::price::PricePolicy`]) trained at one N, in
/// one of its two modes, with prices recomputed every `block` robots in the sequential
/// mode.
///
/// # Examples
/// ```
/// use std::path::Path;
/// use xtask::{PriceSpec, PriceTraining};
/// use afg_learn::price::PriceMode;
/// let s = PriceSpec::new(60, PriceMode::OneShot);
/// assert_eq!(s.dir(Path::new("/repo")), Path::new("/repo/models/ours/price_n60"));
/// let ablation = s.with_training(PriceTraining::Dagger);
/// assert_eq!(ablation.dir(Path::new("r")), Path::new("r/models/ablations/price_dagger_n60"));
/// assert_eq!(s.label(), "Price model, one-shot, trained at N = 60 (ours)");
/// let b = PriceSpec::new(60, PriceMode::Sequential).with_block(10);
/// assert_eq!(b.label(), "Price model, sequential, prices every 10 robots, trained at N = 60 (ours)");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PriceSpec {
    /// Robots per training instance.
    pub trained_at: usize,
    /// Sequential or one-shot.
    pub mode: afg_learn::price::PriceMode,
    /// Robots per price evaluation in the sequential mode (1: every step).
    pub block: usize,
    /// How it was trained.
    pub training: PriceTraining,
}

impl PriceSpec {
    /// The N the committed price model is trained at.
    pub const TRAINED_AT: usize = 60;

    /// A model, prices at every step.
    pub const fn new(trained_at: usize, mode: afg_learn::price::PriceMode) -> Self {
        PriceSpec {
            trained_at,
            mode,
            block: 1,
            training: PriceTraining::DaggerPriceLoss,
        }
    }

    /// The same trained otherwise (one of the ablation's models).
    pub const fn with_training(self, training: PriceTraining) -> Self {
        PriceSpec { training, ..self }
    }

    /// The same in the sequential mode with prices once per `block` robots.
    pub const fn with_block(self, block: usize) -> Self {
        PriceSpec { block, ..self }
    }

    /// Both modes of the committed model, sequential first.
    pub fn committed() -> [PriceSpec; 2] {
        [
            Self::new(Self::TRAINED_AT, afg_learn::price::PriceMode::Sequential),
            Self::new(Self::TRAINED_AT, afg_learn::price::PriceMode::OneShot),
        ]
    }

    /// The run directory under the repository `root` (every mode shares one model).
    pub fn dir(&self, root: &Path) -> std::path::PathBuf {
        let n = self.trained_at;
        let models = root.join("models");
        match self.training {
            PriceTraining::DaggerPriceLoss => models.join(format!("ours/price_n{n}")),
            PriceTraining::Dagger => models.join(format!("ablations/price_dagger_n{n}")),
            PriceTraining::ExpertStates => models.join(format!("ablations/price_expert_n{n}")),
        }
    }

    /// The model file under the repository `root`.
    pub fn model_path(&self, root: &Path) -> std::path::PathBuf {
        self.dir(root).join(afg_learn::price::PriceModel::FILE_NAME)
    }

    /// The row label; ends in "(ours)".
    pub fn label(&self) -> String {
        let block = if self.block > 1 {
            format!(", prices every {} robots", self.block)
        } else {
            String::new()
        };
        format!(
            "Price model, {}{block}, trained at N = {} (ours)",
            self.mode.name(),
            self.trained_at
        )
    }

    /// The policy of the committed weights under `root`.
    ///
    /// # Errors
    /// See [`afg_learn::price::PriceModel::load`]; a block of 0.
    pub fn load(
        &self,
        root: &Path,
    ) -> Result<afg_learn::price::PricePolicy, afg_learn::LearnError> {
        afg_learn::price::PricePolicy::load(&self.model_path(root), self.mode)?
            .with_block(self.block)
    }
}
