//! One allocator on a set of instances, instance by instance (`afg solve`): the
//! trained model of a run directory as an allocator, each instance's score and the
//! means.

use std::path::Path;

use afg_baseline::{AllocStats, Allocator};
use afg_game::{Assignment, Instance, Preference};
use afg_learn::{
    policy::LearnedPolicy,
    price::{PriceMode, PriceModel, PricePolicy},
    run::{ModelKind, RunDir},
};
use serde::Serialize;

use crate::{EvalError, Score, optimum_welfare};

/// How the model of a directory is run ([`load_model`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ModelOptions {
    /// Robots per network evaluation (Q networks and sequential price models; default
    /// 1, the exact greedy rollout).
    pub block: Option<usize>,
    /// Q networks: balanced best-response sweeps after the rollout.
    pub repair: bool,
    /// Price models: every robot uses the prices of the empty state.
    pub one_shot: bool,
    /// Q networks: roll out with the Burn network (the slow reference path).
    pub exact_burn: bool,
}

/// [`ModelOptions`] that do not go together, or not with the model found. The messages
/// name the options as [`ModelOptions`] does; a command line adds its flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OptionConflict {
    /// Repair or the exact Burn rollout asked of a price model.
    #[error("repair and the exact Burn rollout apply to Q networks, not price models")]
    QNetworkOptionOnPriceModel,
    /// A block size with the one-shot mode.
    #[error("a block size applies to the sequential mode, not the one-shot one")]
    BlockWithOneShot,
    /// The one-shot mode asked of a Q network.
    #[error("the one-shot mode applies to price models, not Q networks")]
    OneShotOnQNetwork,
    /// A block size other than 1 with the exact Burn rollout.
    #[error("the exact Burn rollout places one robot at a time (block 1)")]
    BlockWithExactBurn,
}

/// The trained model in run directory `dir` as an allocator, whatever its kind
/// ([`RunDir::kind`]: a Q network or a price model).
///
/// # Errors
/// [`EvalError::ModelOptions`] for options that do not apply to the model found, and
/// [`EvalError::Model`] if it cannot be loaded.
///
/// # Examples
/// ```
/// use afg_eval::solve::{ModelOptions, load_model};
/// let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/paper/afgnet_ddqn_n20");
/// let one_shot = ModelOptions { one_shot: true, ..ModelOptions::default() };
/// let err = load_model(&dir, one_shot).err().unwrap(); // a Q network has no one-shot mode
/// assert!(err.to_string().starts_with("the one-shot mode applies to price models"));
/// assert!(load_model(&dir, ModelOptions::default()).is_ok());
/// ```
pub fn load_model(dir: &Path, options: ModelOptions) -> Result<Box<dyn Allocator>, EvalError> {
    let bad = |conflict: OptionConflict| Err(conflict.into());
    let loading = |source| EvalError::Model {
        path: dir.display().to_string(),
        source,
    };
    if RunDir::new(dir).kind().map_err(loading)? == ModelKind::PriceModel {
        let price = dir.join(PriceModel::FILE_NAME);
        if options.repair || options.exact_burn {
            return bad(OptionConflict::QNetworkOptionOnPriceModel);
        }
        if options.one_shot && options.block.is_some() {
            return bad(OptionConflict::BlockWithOneShot);
        }
        let mode = if options.one_shot {
            PriceMode::OneShot
        } else {
            PriceMode::Sequential
        };
        let policy = PricePolicy::load(&price, mode)
            .and_then(|p| p.with_block(options.block.unwrap_or(1)))
            .map_err(loading)?;
        return Ok(Box::new(policy));
    }
    if options.one_shot {
        return bad(OptionConflict::OneShotOnQNetwork);
    }
    let policy = load_learned(dir)?.with_repair(options.repair);
    let policy = match (options.exact_burn, options.block) {
        (true, Some(b)) if b != 1 => {
            return bad(OptionConflict::BlockWithExactBurn);
        }
        (true, _) => policy.exact_burn(),
        (false, block) => policy.with_block(block.unwrap_or(1)).map_err(loading)?,
    };
    Ok(Box::new(policy))
}

/// The Q network of the training run in `dir` (its final weights).
///
/// # Errors
/// [`EvalError::Model`], naming the directory, if the weights cannot be loaded.
pub fn load_learned(dir: &Path) -> Result<LearnedPolicy, EvalError> {
    LearnedPolicy::load(&RunDir::new(dir).weights()).map_err(|source| EvalError::Model {
        path: dir.display().to_string(),
        source,
    })
}

/// One instance's result.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// The allocation against OPT.
    #[serde(flatten)]
    pub score: Score,
    /// What the allocator reported.
    pub stats: AllocStats,
}

impl Row {
    /// Runs `method` and OPT on `instance`: the row and the method's assignment.
    ///
    /// # Errors
    /// The allocators' errors, or [`EvalError::BeatsOptimum`].
    pub fn compute(
        instance: &Instance,
        method: &dyn Allocator,
    ) -> Result<(Row, Assignment), EvalError> {
        let out = method.allocate(instance)?;
        let opt = optimum_welfare(instance)?;
        let score = Score::of("the allocation", instance, &out.assignment, opt)?;
        let row = Row {
            score,
            stats: out.stats,
        };
        Ok((row, out.assignment))
    }

    /// The JSON line of `assignment` (format "afg-assignment") with a summary of this
    /// row: welfare, % of OPT, coalition sizes, stability and NS rates.
    pub fn assignment_line(
        &self,
        method: &str,
        instance: &Instance,
        assignment: &Assignment,
    ) -> String {
        assignment.to_json_with_summary(Some(serde_json::json!({
            "method": method,
            "welfare": self.score.welfare,
            "opt_welfare": self.score.opt_welfare,
            "percent_of_opt": self.score.percent_of_opt,
            "coalition_sizes": assignment.sizes(),
            "stable_balanced": instance.is_stable(assignment, Preference::Balanced),
            "ns_rate_balanced": self.score.ns_rate_balanced,
            "ns_rate_selfish": self.score.ns_rate_selfish,
        })))
    }
}

/// The rows of one allocator on a set of instances, and their means.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The allocator.
    pub method: String,
    /// Where the instances came from.
    pub source: String,
    /// Instances solved.
    pub instances: usize,
    /// Means over the rows.
    pub mean: Mean,
    /// One per instance.
    pub rows: Vec<Row>,
}

/// Means of a [`Report`]'s rows (NS rates as shares in 0..=1, as in [`Score`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Mean {
    /// Welfare.
    pub welfare: f64,
    /// OPT's welfare.
    pub opt_welfare: f64,
    /// Mean of the per-instance % of OPT; `None` if one of them is undefined.
    pub percent_of_opt: Option<f64>,
    /// Balanced NS rate.
    pub ns_rate_balanced: f64,
    /// Selfish NS rate.
    pub ns_rate_selfish: f64,
    /// [`AllocStats::iterations`].
    pub iterations: f64,
    /// [`AllocStats::rounds`].
    pub rounds: f64,
    /// [`AllocStats::messages`].
    pub messages: f64,
    /// Wall time per instance, seconds.
    pub seconds: f64,
}

impl Report {
    /// The report of `rows` (at least one).
    ///
    /// # Errors
    /// [`EvalError::NoInstances`] if `rows` is empty.
    pub fn new(method: String, source: String, rows: Vec<Row>) -> Result<Report, EvalError> {
        if rows.is_empty() {
            return Err(EvalError::NoInstances);
        }
        let k = rows.len() as f64;
        let mean = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() / k;
        let mean = Mean {
            welfare: mean(&|r| r.score.welfare),
            opt_welfare: mean(&|r| r.score.opt_welfare),
            percent_of_opt: rows
                .iter()
                .map(|r| r.score.percent_of_opt)
                .sum::<Option<f64>>()
                .map(|total| total / k),
            ns_rate_balanced: mean(&|r| r.score.ns_rate_balanced),
            ns_rate_selfish: mean(&|r| r.score.ns_rate_selfish),
            iterations: mean(&|r| r.stats.iterations as f64),
            rounds: mean(&|r| r.stats.rounds as f64),
            messages: mean(&|r| r.stats.messages as f64),
            seconds: mean(&|r| r.stats.wall_time.as_secs_f64()),
        };
        Ok(Report {
            method,
            source,
            instances: rows.len(),
            mean,
            rows,
        })
    }
}

/// A % of OPT as printed: two decimals, or why there is none.
pub fn percent_text(percent: Option<f64>) -> String {
    percent.map_or_else(
        || "undefined (OPT's welfare <= 0)".to_owned(),
        |p| format!("{p:.2}"),
    )
}

/// The report as `afg solve` prints it: the means, one per line.
impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (m, k) = (&self.mean, self.instances);
        let plural = if k == 1 { "" } else { "s" };
        writeln!(
            f,
            "{} on {} ({k} instance{plural})",
            self.method, self.source
        )?;
        writeln!(
            f,
            "  welfare           {:>12.3}   (OPT {:.3})",
            m.welfare, m.opt_welfare
        )?;
        writeln!(
            f,
            "  % of OPT          {:>12}",
            percent_text(m.percent_of_opt)
        )?;
        writeln!(
            f,
            "  NS_rate balanced  {:>11.1} %",
            100.0 * m.ns_rate_balanced
        )?;
        writeln!(
            f,
            "  NS_rate selfish   {:>11.1} %",
            100.0 * m.ns_rate_selfish
        )?;
        writeln!(f, "  iterations        {:>12.1}", m.iterations)?;
        writeln!(f, "  rounds            {:>12.1}", m.rounds)?;
        if m.messages > 0.0 {
            writeln!(f, "  messages          {:>12.0}", m.messages)?;
        }
        writeln!(f, "  time / instance   {:>10.3} ms", 1e3 * m.seconds)?;
        if k > 1 {
            writeln!(f, "  (means over instances; --json for each one)")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use afg_baseline::{Greedy, Optimum};
    use afg_game::GeneratorConfig;

    use super::*;

    #[test]
    fn the_means_are_those_of_the_rows() {
        let insts: Vec<Instance> = (0..3)
            .map(|s| GeneratorConfig::paper(15, 3, s).generate().unwrap())
            .collect();
        let rows: Vec<Row> = insts
            .iter()
            .map(|i| Row::compute(i, &Greedy).unwrap().0)
            .collect();
        let by_hand = rows.iter().map(|r| r.score.welfare).sum::<f64>() / 3.0;
        let report = Report::new("greedy".into(), "here".into(), rows).unwrap();
        assert_eq!(report.instances, 3);
        assert!((report.mean.welfare - by_hand).abs() < 1e-12);
        let text = report.to_string();
        assert!(text.starts_with("greedy on here (3 instances)\n"), "{text}");
        let welfare = format!("welfare           {:>12.3}", by_hand);
        assert!(
            text.contains(&welfare) && !text.contains("messages"),
            "{text}"
        );
        assert!(report.mean.percent_of_opt.unwrap() <= 100.0 + 1e-9);
        let (opt, _) = Row::compute(&insts[0], &Optimum).unwrap();
        assert_eq!(opt.score.percent_of_opt, Some(100.0));
        assert!(matches!(
            Report::new("x".into(), "y".into(), Vec::new()),
            Err(EvalError::NoInstances)
        ));
    }
}
