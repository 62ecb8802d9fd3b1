//! The learned models of the tables, by identity rather than by directory string.

use std::path::Path;

use afg_learn::{nets::Net, run::RunDir, train::Algo};

/// What a model adds to the paper's method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Nothing: the paper's network, trained by `algo` (the paper's algorithm unless it
    /// is [`Algo::QStar`]; training departures are in its command).
    Paper,
    /// Ours: AFGNet with the action's immediate reward added to its Q values.
    GainResidual,
    /// The paper's network and algorithm, trained starting from the weights of the same
    /// kind of model trained at N = `from` (a warm start; not in the paper, named in the
    /// row).
    WarmStart {
        /// The N of the model whose weights the run starts from.
        from: usize,
    },
    /// Ours: AFGNet with a price head (`--price-head`):
    /// `Q(s, a) = π_a(s) − β d(t, a) + c_a(s)`, Nearest before training.
    PriceHead,
    /// Ours: [`Variant::PriceHead`] trained with demonstrations from the exact optimum
    /// and a large-margin loss (`--demos`, as in Deep Q-learning from Demonstrations).
    PriceHeadDemos,
    /// Ours: [`Variant::PriceHead`] whose one-shot scores are also fitted to the exact
    /// task prices (`--price-loss`, [`afg_learn::train::TrainConfig::price_loss`]).
    PriceHeadPriceLoss,
    /// Ours: the paper's network and algorithm with the reward shaped by the optimal
    /// completion (`--shaping optimal`, [`afg_learn::env::Shaping::Optimal`]): the optimal
    /// policy is unchanged, but the rewards carry the exact optimum's values.
    OptimalShaping,
    /// Ours: [`Variant::OptimalShaping`] trained starting from the weights of the same
    /// kind of model trained at N = `from`.
    OptimalShapingWarmStart {
        /// The N of the model whose weights the run starts from.
        from: usize,
    },
}

/// One trained model: network, algorithm, variant and the N it was trained at.
///
/// # Examples
/// ```
/// use afg_eval::{ModelSpec, Variant};
/// use afg_learn::{nets::Net, train::Algo};
/// let m = ModelSpec::new(Net::AfgNet, Algo::Ddqn, Variant::Paper, 60);
/// assert_eq!(m.dir_name(), "afgnet_ddqn_n60");
/// assert_eq!(m.label(), "AFGNet_DDQN");
/// let ours = ModelSpec { variant: Variant::GainResidual, ..m };
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
/// assert_eq!(warm.dir_name(), "s2v_ddqn_warm_n60");
/// assert_eq!(warm.label(), "S2V_DDQN, warm start from the N = 20 model");
/// assert!(!warm.is_ours());
/// let shaped_warm = ModelSpec::WARM_STARTS[1];
/// assert_eq!(shaped_warm.dir_name(), "afgnet_ddqn_optshape_warm_n100");
/// assert_eq!(
///     shaped_warm.label(),
///     "AFGNet_DDQN, optimal-completion shaping, warm start from the N = 60 model (ours)"
/// );
/// let [exact, prices, td, demos] = ModelSpec::PRICE_HEADED;
/// assert_eq!(exact.dir_name(), "afgnet_qstar_price_n60");
/// assert_eq!(prices.dir_name(), "afgnet_qstar_price_oneshot_n60");
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
    /// The variant.
    pub variant: Variant,
    /// Robots per training instance.
    pub trained_at: usize,
}

impl ModelSpec {
    /// The training scale of the model the paper transfers to other N ("Pretrain_60").
    pub const PRETRAINED_AT: usize = 60;

    /// The learned rows of Table I at one scale, in table order: the paper's three
    /// models, then ours.
    pub const TABLE1_KINDS: [(Net, Algo, Variant); 5] = [
        (Net::S2v, Algo::Ddqn, Variant::Paper),
        (Net::AfgNet, Algo::Dqn, Variant::Paper),
        (Net::AfgNet, Algo::Ddqn, Variant::Paper),
        (Net::AfgNet, Algo::Ddqn, Variant::GainResidual),
        (Net::AfgNet, Algo::QStar, Variant::Paper),
    ];

    /// A model.
    pub const fn new(net: Net, algo: Algo, variant: Variant, trained_at: usize) -> Self {
        ModelSpec {
            net,
            algo,
            variant,
            trained_at,
        }
    }

    /// The learned rows of Table I trained at `robots`.
    pub fn table1(robots: usize) -> Vec<ModelSpec> {
        Self::TABLE1_KINDS
            .iter()
            .map(|&(net, algo, variant)| Self::new(net, algo, variant, robots))
            .collect()
    }

    /// The paper's AFGNet DDQN trained at `robots` (its headline model).
    pub const fn afgnet_ddqn(robots: usize) -> Self {
        Self::new(Net::AfgNet, Algo::Ddqn, Variant::Paper, robots)
    }

    /// The models trained at [`ModelSpec::PRETRAINED_AT`] that the tables also run at
    /// every other N: the paper's AFGNet DDQN, AFGNet trained on the exact Q* (ours)
    /// and AFGNet DDQN with the optimal completion as shaping potential (ours).
    pub const TRANSFERRED: [ModelSpec; 3] = [
        Self::afgnet_ddqn(Self::PRETRAINED_AT),
        Self::new(
            Net::AfgNet,
            Algo::QStar,
            Variant::Paper,
            Self::PRETRAINED_AT,
        ),
        Self::new(
            Net::AfgNet,
            Algo::Ddqn,
            Variant::OptimalShaping,
            Self::PRETRAINED_AT,
        ),
    ];

    /// The warm starts the tables show beside the paper's rows: AFGNet DDQN at N = 100
    /// from the N = 60 model (the paper's, and ours with optimal-completion shaping),
    /// S2V DDQN at N = 60 and 100 from the N = 20 model.
    pub const WARM_STARTS: [ModelSpec; 4] = [
        Self::new(
            Net::AfgNet,
            Algo::Ddqn,
            Variant::WarmStart { from: 60 },
            100,
        ),
        Self::new(
            Net::AfgNet,
            Algo::Ddqn,
            Variant::OptimalShapingWarmStart { from: 60 },
            100,
        ),
        Self::new(Net::S2v, Algo::Ddqn, Variant::WarmStart { from: 20 }, 60),
        Self::new(Net::S2v, Algo::Ddqn, Variant::WarmStart { from: 20 }, 100),
    ];

    /// AFGNet with a price head, trained at [`ModelSpec::PRETRAINED_AT`] and run at
    /// every N (ours): on the exact Q*, on the exact Q* and the exact prices, by Double
    /// DQN, and by Double DQN with demonstrations.
    pub const PRICE_HEADED: [ModelSpec; 4] = [
        Self::new(
            Net::AfgNet,
            Algo::QStar,
            Variant::PriceHead,
            Self::PRETRAINED_AT,
        ),
        Self::new(
            Net::AfgNet,
            Algo::QStar,
            Variant::PriceHeadPriceLoss,
            Self::PRETRAINED_AT,
        ),
        Self::new(
            Net::AfgNet,
            Algo::Ddqn,
            Variant::PriceHead,
            Self::PRETRAINED_AT,
        ),
        Self::new(
            Net::AfgNet,
            Algo::Ddqn,
            Variant::PriceHeadDemos,
            Self::PRETRAINED_AT,
        ),
    ];

    /// The run directory's name under `models/`, e.g. `afgnet_ddqn_n60`.
    pub fn dir_name(&self) -> String {
        let net = self.net.name();
        let variant = match self.variant {
            Variant::Paper => "",
            Variant::GainResidual => "_gain",
            Variant::WarmStart { .. } => "_warm",
            Variant::PriceHead => "_price",
            Variant::PriceHeadDemos => "_price_demos",
            Variant::PriceHeadPriceLoss => "_price_oneshot",
            Variant::OptimalShaping => "_optshape",
            Variant::OptimalShapingWarmStart { .. } => "_optshape_warm",
        };
        format!("{net}_{}{variant}_n{}", self.algo.name(), self.trained_at)
    }

    /// The run directory under the repository `root`.
    pub fn run_dir(&self, root: &Path) -> RunDir {
        RunDir::new(root.join("models").join(self.dir_name()))
    }

    /// The row label, in the paper's naming (e.g. `AFGNet_DDQN`); ours end in "(ours)".
    pub fn label(&self) -> String {
        self.label_with("")
    }

    /// The row label with `detail` (how the model is run, e.g. ", one-shot") after the
    /// model's name and before "(ours)".
    pub fn label_with(&self, detail: &str) -> String {
        let net = match self.net {
            Net::AfgNet => "AFGNet",
            Net::S2v => "S2V",
        };
        let algo = match self.algo {
            Algo::Dqn => "DQN",
            Algo::Ddqn => "DDQN",
            Algo::QStar => "",
        };
        let name = match (self.algo, self.variant) {
            (Algo::QStar, Variant::PriceHead) => format!("{net} + price head, exact Q* regression"),
            (Algo::QStar, Variant::PriceHeadPriceLoss) => {
                format!("{net} + price head, exact Q* and price regression")
            }
            (Algo::QStar, _) => format!("{net}, exact Q* regression"),
            (_, Variant::PriceHead) => format!("{net}_{algo} + price head"),
            (_, Variant::PriceHeadDemos) => format!("{net}_{algo} + price head + demonstrations"),
            (_, Variant::PriceHeadPriceLoss) => {
                format!("{net}_{algo} + price head + price regression")
            }
            (_, Variant::Paper) => format!("{net}_{algo}"),
            (_, Variant::GainResidual) => format!("{net}_{algo} + gain residual"),
            (_, Variant::OptimalShaping) => format!("{net}_{algo}, optimal-completion shaping"),
            (_, Variant::WarmStart { from }) => {
                format!("{net}_{algo}, warm start from the N = {from} model")
            }
            (_, Variant::OptimalShapingWarmStart { from }) => format!(
                "{net}_{algo}, optimal-completion shaping, warm start from the N = {from} model"
            ),
        };
        let ours = if self.is_ours() { " (ours)" } else { "" };
        format!("{name}{detail}{ours}")
    }

    /// Whether the model is ours (not the paper's network and algorithm); the tables
    /// treat ours as optional. A warm start keeps the paper's network and algorithm.
    pub fn is_ours(&self) -> bool {
        matches!(
            self.variant,
            Variant::GainResidual
                | Variant::PriceHead
                | Variant::PriceHeadDemos
                | Variant::PriceHeadPriceLoss
                | Variant::OptimalShaping
                | Variant::OptimalShapingWarmStart { .. }
        ) || self.algo == Algo::QStar
    }
}

/// The price-structured model (ours, [`afg_learn::price::PricePolicy`]) trained at one N, in
/// one of its two modes, with prices recomputed every `block` robots in the sequential
/// mode.
///
/// # Examples
/// ```
/// use afg_eval::PriceSpec;
/// use afg_learn::price::PriceMode;
/// let s = PriceSpec::new(60, PriceMode::OneShot);
/// assert_eq!(s.dir_name(), "price_n60");
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
        }
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

    /// The run directory's name under `models/` (every mode shares one model).
    pub fn dir_name(&self) -> String {
        format!("price_n{}", self.trained_at)
    }

    /// The model file under the repository `root`.
    pub fn model_path(&self, root: &Path) -> std::path::PathBuf {
        root.join("models")
            .join(self.dir_name())
            .join(afg_learn::price::PriceModel::FILE_NAME)
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
