//! The paper's Tables I and II as data, and their Markdown: what
//! `cargo xtask reproduce-tables` prints and writes. [`compute`] evaluates every row
//! on the committed datasets and weights; [`markdown`] renders them.

mod document;
mod markdown;
mod rows;

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

pub use document::{BEGIN, END, RunInfo, assignment_map_svg, block, results_document, with_block};
pub use markdown::{headline, models_table, table1_markdown, table2_markdown};
use rows::committed_model_row;
pub use rows::{Row, RowId, Run, classical_rows, price_headed_rows, price_model_rows};

use crate::price_ablation::{PriceAblationRow, price_ablation, price_ablation_markdown};
use afg_eval::{EvalError, dataset};

use crate::{Head, ModelSpec};

/// The rows of one N.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scale {
    /// Robots per instance.
    pub robots: usize,
    /// The rows, in table order.
    pub rows: Vec<Row>,
}

/// Every table: what [`compute`] measures and [`markdown`] renders.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tables {
    /// A few instances per table only (a check of the pipeline, not results).
    pub quick: bool,
    /// Table I, one entry per N of [`dataset::TABLE1_SIZES`].
    pub table1: Vec<Scale>,
    /// Table II, one entry per N of [`dataset::TABLE2_SIZES`].
    pub table2: Vec<Scale>,
    /// The price model's ablation (ours).
    pub price_ablation: Vec<PriceAblationRow>,
    /// Instances per scale of the ablation.
    pub price_ablation_instances: usize,
    /// The paper's models expected under `models/` but not committed (rows omitted).
    pub missing_models: Vec<String>,
}

/// Evaluates every method on the committed datasets under `root`, with the weights
/// under `root/models`: Table I on the first 100 instances of each test set, Table II
/// on 100 (the slowest rows on 20), or 3, 2 and 1 with `quick`. `on_scale` is called
/// after each test set (for a progress bar; five calls in all).
///
/// # Errors
/// A missing dataset, a model that cannot be loaded, or an allocator's error.
pub fn compute(root: &Path, quick: bool, mut on_scale: impl FnMut()) -> Result<Tables, EvalError> {
    let (t1_instances, t2_instances, t2_learned) = if quick { (3, 2, 1) } else { (100, 100, 20) };
    let mut missing = Vec::new();
    let mut table1 = Vec::new();
    for n in dataset::TABLE1_SIZES {
        table1.push(table1_scale(root, n, t1_instances, &mut missing)?);
        on_scale();
    }
    let mut table2 = Vec::new();
    for n in dataset::TABLE2_SIZES {
        table2.push(table2_scale(root, n, t2_instances, t2_learned)?);
        on_scale();
    }
    missing.sort();
    missing.dedup();
    Ok(Tables {
        quick,
        table1,
        table2,
        price_ablation: price_ablation(root, t1_instances)?,
        price_ablation_instances: t1_instances,
        missing_models: missing,
    })
}

/// Table I at `n` robots on its first `instances` test instances; the paper's models
/// that are not there are added to `missing`.
fn table1_scale(
    root: &Path,
    n: usize,
    instances: usize,
    missing: &mut Vec<String>,
) -> Result<Scale, EvalError> {
    let (insts, opt) = dataset::first_with_optima(root, n, instances)?;
    let mut rows = Vec::new();
    // Our variants are optional; the paper's three models are expected.
    for spec in ModelSpec::table1(n) {
        if !spec.run_dir(root).has_weights() && !spec.is_ours() {
            missing.push(spec.models_path().display().to_string());
        }
    }
    // Table I's models, the N = 60 models at the other scales (the paper's
    // "Pretrain_60" at N = 20, 100) and at N = 60 those that are not one of Table I's
    // kinds, then the models trained further at this N from a smaller one.
    let transferred = ModelSpec::TRANSFERRED
        .into_iter()
        .filter(|t| !ModelSpec::table1(n).contains(t));
    let warm = ModelSpec::WARM_STARTS
        .into_iter()
        .filter(|w| w.trained_at == n);
    for spec in ModelSpec::table1(n)
        .into_iter()
        .chain(transferred)
        .chain(warm)
    {
        rows.extend(committed_model_row(
            root,
            spec,
            Run::AS_TRAINED,
            &insts,
            &opt,
        )?);
    }
    rows.extend(price_headed_rows(root, &insts, &opt)?);
    rows.extend(price_model_rows(root, &insts, &opt)?);
    rows.extend(classical_rows(&insts, &opt, insts.len())?);
    Ok(Scale { robots: n, rows })
}

/// Table II at `n` robots on its first `instances` test instances, the slowest learned
/// rows on the first `learned` of them.
fn table2_scale(
    root: &Path,
    n: usize,
    instances: usize,
    learned: usize,
) -> Result<Scale, EvalError> {
    let (insts, opt) = dataset::first_with_optima(root, n, instances)?;
    let few = learned.min(insts.len());
    let mut rows = Vec::new();
    rows.extend(classical_rows(&insts, &opt, few)?);
    rows.extend(price_headed_rows(root, &insts, &opt)?);
    rows.extend(price_model_rows(root, &insts, &opt)?);
    // The paper's model and ours with the gain residual at every training N, then
    // ours trained at N = 60 only.
    let specs = [Head::Plain, Head::GainResidual]
        .into_iter()
        .flat_map(|head| dataset::TABLE1_SIZES.map(|t| ModelSpec::afgnet_ddqn(t).with_head(head)))
        .chain(ModelSpec::TRANSFERRED.into_iter().filter(|s| s.is_ours()));
    for spec in specs {
        let exact = committed_model_row(root, spec, Run::AS_TRAINED, &insts[..few], &opt[..few])?;
        if exact.is_some() && spec == ModelSpec::afgnet_ddqn(spec.trained_at) {
            // The fast variant: one pass per N/100 robots, then balanced repair.
            let fast = Run {
                block: n / 100,
                repair: true,
            };
            rows.extend(exact);
            rows.extend(committed_model_row(root, spec, fast, &insts, &opt)?);
        } else {
            rows.extend(exact);
        }
    }
    Ok(Scale { robots: n, rows })
}

/// What Table I's rows are, under it.
const TABLE1_NOTE: &str = "The learned rows keep the paper's networks and algorithms; where their training departs from the paper (units of the inputs and rewards, reward shaping, loss, learning rate, target sync) is in each model's command under \"The committed models\" in docs/RESULTS.md, and explained in docs/training.md. The rows marked (ours) are not the paper's method: \"AFGNet, exact Q* regression\" is the paper's network trained by regression on the exact Q* of the sequential MDP instead of TD targets (docs/training.md); \"AFGNet_DDQN, optimal-completion shaping\" is the paper's network and Double DQN with the reward shaped by the potential W(optimal completion of s) − W(s) instead of the greedy one, so its rewards carry the exact optimum's values (docs/training.md, the eighth round); \"AFGNet + price head\" (docs/price.md) is the paper's AFGNet with a price head added, Q(s, a) = π_a(s) − β d(t, a) + c_a(s), which is Nearest before training, trained on the exact Q*, by Double DQN, or by Double DQN with demonstrations from the optimum, and run without any repair (its one-shot row evaluates the network once for all robots); the price model (docs/price.md) is a per-task price network without the graph embedding, trained on the same Q*, run without any repair. \"Blind round robin\" gives each robot the task with the fewest robots so far and never looks at a task: no policy that cannot see the tasks, such as the paper's S2V, does better on average (docs/training.md).\n\n";

/// Every table in Markdown: Table I with the note on its rows, Table II, the price
/// model's ablation, and the models that are missing.
pub fn markdown(tables: &Tables) -> String {
    let mut s = table1_markdown(&tables.table1);
    s.push_str(TABLE1_NOTE);
    s.push_str(&table2_markdown(&tables.table2));
    if !tables.price_ablation.is_empty() {
        s += &price_ablation_markdown(&tables.price_ablation, tables.price_ablation_instances);
    }
    if !tables.missing_models.is_empty() {
        let _ = writeln!(
            s,
            "Not trained yet (rows omitted): {}.",
            tables.missing_models.join(", ")
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use afg_baseline::Method;

    use super::*;

    /// The tables with timings removed.
    fn without_timings(t: &Tables) -> Tables {
        let mut t = t.clone();
        for scale in t.table1.iter_mut().chain(&mut t.table2) {
            for row in &mut scale.rows {
                row.summary.seconds_per_instance = 0.0;
            }
        }
        t
    }

    #[test]
    fn quick_tables_are_reproducible_and_opt_dominates() {
        let root = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
        let mut calls = 0;
        let a = compute(root, true, || calls += 1).unwrap();
        assert_eq!(calls, 5);
        let b = compute(root, true, || {}).unwrap();
        assert_eq!(without_timings(&a), without_timings(&b));
        for scale in a.table1.iter().chain(&a.table2) {
            let opt = &scale
                .rows
                .iter()
                .find(|r| r.id == RowId::Method(Method::Opt))
                .unwrap()
                .summary;
            let rows: Vec<_> = scale.rows.iter().map(|r| &r.summary).collect();
            assert!((opt.percent_of_opt - 100.0).abs() < 1e-9);
            for r in &rows {
                assert!(
                    r.welfare <= opt.welfare + 1e-9 * opt.welfare.abs()
                        || r.instances < opt.instances,
                    "{}",
                    r.method
                );
                assert!(r.percent_of_opt <= 100.0 + 1e-9, "{}", r.method);
            }
        }
        let tables = markdown(&a);
        assert!(
            tables.contains("Table I") && tables.contains("Table II") && tables.contains("22.61")
        );
    }
}
