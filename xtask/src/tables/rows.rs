//! The rows of the tables: every classical method, and the committed models of ours
//! that do not belong to one scale of Table I.

use std::path::Path;

use afg_baseline::{Allocator, Method};
use afg_game::Instance;
use afg_learn::{policy::LearnedPolicy, train::Algo};
use serde::Serialize;

use afg_eval::{EvalError, Summary, evaluate};

use crate::{ModelSpec, PriceSpec};

/// How a learned Q-network is run: one network pass per `block` robots, with or
/// without balanced repair afterwards.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    /// Robots placed per network pass (1: an exact rollout; N: one pass for all).
    pub block: usize,
    /// Balanced repair after the network.
    pub repair: bool,
}

impl Run {
    /// As trained: one robot per pass, no repair.
    pub const AS_TRAINED: Run = Run {
        block: 1,
        repair: false,
    };
}

/// What a row measures; its label is made from this alone ([`RowId::label`]).
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use xtask::{ModelSpec, tables::{RowId, Run}};
/// assert_eq!(RowId::Method(Method::Opt).label(), "OPT");
/// let ddqn = ModelSpec::afgnet_ddqn(60);
/// let own = RowId::Model { spec: ddqn, robots: 60, run: Run::AS_TRAINED };
/// assert_eq!(own.label(), "AFGNet_DDQN");
/// assert!(own.is_paper_row());
/// let fast = RowId::Model { spec: ddqn, robots: 500, run: Run { block: 5, repair: true } };
/// assert_eq!(fast.label(), "AFGNet_DDQN, network every 5 robots, + repair, trained at N = 60");
/// let one_shot = RowId::Model { spec: ModelSpec::TRANSFERRED[1], robots: 20, run: Run { block: 20, repair: false } };
/// assert_eq!(one_shot.label(), "AFGNet, exact Q* regression, one-shot (one pass), trained at N = 60 (ours)");
/// assert!(!fast.is_paper_row() && !one_shot.is_paper_row());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowId {
    /// A classical method.
    Method(Method),
    /// A learned Q-network evaluated at `robots` robots, run as `run` says.
    Model {
        /// The model.
        spec: ModelSpec,
        /// Robots per evaluated instance.
        robots: usize,
        /// How it is run.
        run: Run,
    },
    /// The price model (ours).
    PriceModel(PriceSpec),
}

impl RowId {
    /// The row's label, e.g. `AFGNet_DDQN, network every 5 robots, + repair, trained at N = 60`.
    pub fn label(&self) -> String {
        match self {
            RowId::Method(m) => m.label().to_owned(),
            RowId::PriceModel(p) => p.label(),
            RowId::Model { spec, robots, run } => {
                let mut detail = match run.block {
                    1 => String::new(),
                    b if b >= *robots => ", one-shot (one pass)".to_owned(),
                    b => format!(", network every {b} robots"),
                };
                if run.repair {
                    detail += ", + repair";
                }
                if *robots != spec.trained_at {
                    detail += &format!(", trained at N = {}", spec.trained_at);
                }
                spec.label_with(&detail)
            }
        }
    }

    /// Whether the row is one of the paper's models at the scale it was trained at, run
    /// as trained: the paper's number stands beside it.
    pub fn is_paper_row(&self) -> bool {
        matches!(self, RowId::Model { spec, robots, run }
            if spec.is_paper_method() && *robots == spec.trained_at && *run == Run::AS_TRAINED)
    }
}

/// One row of a table: what it measures, and the measurement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// What the row measures.
    #[serde(skip)]
    pub id: RowId,
    /// The measurement, under [`RowId::label`].
    #[serde(flatten)]
    pub summary: Summary,
}

impl Row {
    /// `allocator`, which is what `id` names, measured on `insts` whose optima are `opt`.
    ///
    /// # Errors
    /// The allocator's errors; see [`evaluate`].
    pub fn measure(
        id: RowId,
        allocator: &dyn Allocator,
        insts: &[Instance],
        opt: &[f64],
    ) -> Result<Row, EvalError> {
        Ok(Row {
            id,
            summary: evaluate(&id.label(), allocator, insts, opt)?,
        })
    }
}

/// The committed Q-network `spec` under `root`, run as `run` says, measured on `insts`
/// (N robots each); `None` when its weights are not committed.
pub(super) fn committed_model_row(
    root: &Path,
    spec: ModelSpec,
    run: Run,
    insts: &[Instance],
    opt: &[f64],
) -> Result<Option<Row>, EvalError> {
    let dir = spec.run_dir(root);
    if !dir.has_weights() {
        return Ok(None);
    }
    let policy = LearnedPolicy::load(&dir.weights())?
        .with_block(run.block)?
        .with_repair(run.repair);
    let robots = insts.first().map_or(0, Instance::num_robots);
    let id = RowId::Model { spec, robots, run };
    Row::measure(id, &policy, insts, opt).map(Some)
}

/// Every classical method ([`Method::ALL`]) on `insts`, whose optima are `opt`; the
/// decentralised DA (the slowest: a message-passing simulation of the dynamics that
/// [`Method::Da`] runs centrally) on the first `simulated` instances only, and not at
/// all above N = 1000.
///
/// # Errors
/// The allocators' errors.
///
/// # Examples
/// ```
/// use afg_eval::optima;
/// use xtask::tables::classical_rows;
/// use afg_game::GeneratorConfig;
/// let insts: Vec<_> = (0..3).map(|s| GeneratorConfig::paper(20, 5, s).generate()).collect::<Result<_, _>>()?;
/// let rows = classical_rows(&insts, &optima(&insts)?, 2)?;
/// let count = |label: &str| rows.iter().find(|r| r.summary.method == label).unwrap().summary.instances;
/// assert_eq!((count("OPT"), count("GRAPE DA, decentralised")), (3, 2));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn classical_rows(
    insts: &[Instance],
    opt: &[f64],
    simulated: usize,
) -> Result<Vec<Row>, EvalError> {
    let n = insts.first().map_or(0, Instance::num_robots);
    let mut rows = Vec::new();
    for method in Method::ALL {
        let k = match method {
            Method::DaDecentralised if n > 1000 => continue,
            Method::DaDecentralised => simulated.min(insts.len()),
            _ => insts.len(),
        };
        let allocator = method.allocator(0);
        rows.push(Row::measure(
            RowId::Method(method),
            allocator.as_ref(),
            &insts[..k],
            &opt[..k],
        )?);
    }
    Ok(rows)
}

/// The committed AFGNet models with a price head (ours, [`ModelSpec::PRICE_HEADED`])
/// under `root` on `insts` (N robots each), without repair: exact rollouts up to
/// N = 100 and one network pass per N/10 robots beyond (ten passes); the Q* model also
/// in one pass for all robots (one-shot). Models not committed give no rows.
///
/// # Errors
/// A model that cannot be loaded, and the policies' errors.
pub fn price_headed_rows(
    root: &Path,
    insts: &[Instance],
    opt: &[f64],
) -> Result<Vec<Row>, EvalError> {
    let n = insts.first().map_or(0, Instance::num_robots);
    let mut rows = Vec::new();
    for spec in ModelSpec::PRICE_HEADED {
        let block = if n >= 500 { n / 10 } else { 1 };
        let mut runs = vec![block];
        if spec.algo == Algo::QStar {
            runs.push(n);
        }
        for block in runs {
            let run = Run {
                block,
                repair: false,
            };
            rows.extend(committed_model_row(root, spec, run, insts, opt)?);
        }
    }
    Ok(rows)
}

/// The committed price model's rows (ours, [`PriceSpec::committed`]) under `root` on
/// `insts`: both modes, and from N = 500 on the sequential mode with prices once per
/// N/100 robots too; none while the model is not committed.
///
/// # Errors
/// A model that cannot be loaded, and the policy's errors.
pub fn price_model_rows(
    root: &Path,
    insts: &[Instance],
    opt: &[f64],
) -> Result<Vec<Row>, EvalError> {
    let n = insts.first().map_or(0, Instance::num_robots);
    let [sequential, one_shot] = PriceSpec::committed();
    let blocked = (n >= 500).then(|| sequential.with_block(n / 100));
    let mut rows = Vec::new();
    for spec in [Some(sequential), blocked, Some(one_shot)]
        .into_iter()
        .flatten()
    {
        if spec.model_path(root).exists() {
            let policy = spec.load(root)?;
            rows.push(Row::measure(RowId::PriceModel(spec), &policy, insts, opt)?);
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_price_headed_rows_name_their_mode_and_scale() {
        let root = &crate::repo_root();
        let labels = |n: usize| -> Vec<String> {
            let insts = afg_eval::dataset::load(root, n).unwrap();
            let insts = &insts[..1];
            let opt = afg_eval::optima(insts).unwrap();
            price_headed_rows(root, insts, &opt)
                .unwrap()
                .into_iter()
                .map(|r| {
                    assert!(r.summary.percent_of_opt > 90.0, "{}", r.summary.method);
                    r.summary.method
                })
                .collect()
        };
        // The four committed models, the two Q* ones also in one pass.
        let at_60 = labels(60);
        assert_eq!(at_60.len(), 6, "{at_60:?}");
        assert!(at_60.iter().all(|l| !l.contains("trained at")));
        assert_eq!(at_60.iter().filter(|l| l.contains("one-shot")).count(), 2);
        let at_500 = labels(500);
        assert!(at_500.iter().all(|l| l.contains("trained at N = 60")));
        // The price model: both modes, and prices once per N/100 robots from N = 500.
        let insts = afg_eval::dataset::load(root, 500).unwrap();
        let opt = afg_eval::optima(&insts[..1]).unwrap();
        let price = price_model_rows(root, &insts[..1], &opt).unwrap();
        assert_eq!(price.len(), 3);
        assert!(price[1].summary.method.contains("prices every 5 robots"));
        assert_eq!(
            at_500
                .iter()
                .filter(|l| l.contains("network every 50 robots"))
                .count(),
            4
        );
    }
}
