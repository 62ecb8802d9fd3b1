//! The paper's Tables I and II as data, and their Markdown: what
//! `cargo xtask reproduce-tables` prints and writes. [`compute`] evaluates every row
//! on the committed datasets and weights; [`markdown`] renders them.
//!
//! `cargo xtask reproduce-tables`: Tables I and II, Fig. 1 and an assignment map, from
//! the committed datasets and weights.

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
        let root = &crate::repo_root();
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

// The command.
use std::path::PathBuf;

use afg_eval::figures::runs_curves_svg;
use afg_game::fs::write_atomic_making_dirs;
use anyhow::{Context, Result, bail};
use clap::Args;

/// The options of `cargo xtask reproduce-tables`.
#[derive(Args)]
pub struct TablesArgs {
    /// A few instances per table (about a minute), to check the pipeline end to end.
    #[arg(long)]
    quick: bool,
    /// Print the results as JSON on stdout as well.
    #[arg(long)]
    json: bool,
    /// Write nothing; check that README.md shows the tables of docs/RESULTS.md.
    #[arg(long)]
    check: bool,
    /// Write nothing; recompute every table and fail, naming the cell, where a number
    /// other than a timing differs from docs/RESULTS.md (beyond the last printed digit).
    #[arg(long, conflicts_with_all = ["check", "quick", "root"])]
    verify: bool,
    /// Where to write RESULTS.md, figures/ and the README block (default: the repository).
    #[arg(long)]
    root: Option<PathBuf>,
}

/// Runs `cargo xtask reproduce-tables` (or, with `--verify`, compares with docs/RESULTS.md).
pub fn run(args: TablesArgs) -> Result<()> {
    if args.check {
        return check_readme(&crate::repo_root());
    }
    if args.verify {
        let root = crate::repo_root();
        check_readme(&root)?;
        let committed = results_block(&root.join("docs/RESULTS.md"))?;
        let fresh = markdown(&compute_tables(&root, false)?);
        let differences = crate::table_diff::table_differences(&committed, &fresh);
        if !differences.is_empty() {
            for d in &differences {
                eprintln!("{d}");
            }
            bail!(
                "{} cell(s) of docs/RESULTS.md differ from a fresh run; run `cargo xtask reproduce-tables`",
                differences.len()
            );
        }
        println!("docs/RESULTS.md matches a fresh run (timings aside)");
        return Ok(());
    }
    let root = args.root.clone().unwrap_or_else(crate::repo_root);
    let start = std::time::Instant::now();
    let results = compute_tables(&root, args.quick)?;
    let minutes = start.elapsed().as_secs_f64() / 60.0;
    let tables = markdown(&results);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&results)?);
    } else {
        println!("{tables}");
    }
    if !args.quick || args.root.is_some() {
        write_outputs(&root, &results, &tables, args.quick, minutes)?;
    }
    Ok(())
}

/// Every table, with a progress bar over the five test sets.
fn compute_tables(root: &Path, quick: bool) -> Result<Tables> {
    let bar = afg_eval::report::progress(5, "reproduce-tables (datasets)");
    let tables = compute(root, quick, || bar.inc(1))?;
    bar.finish_and_clear();
    Ok(tables)
}

fn write_outputs(root: &Path, res: &Tables, tables: &str, quick: bool, minutes: f64) -> Result<()> {
    let figures = root.join("docs/figures");
    for n in dataset::TABLE1_SIZES {
        // The paper's three models at this scale (Fig. 1 has no curves of ours).
        let dirs: Vec<PathBuf> = ModelSpec::table1(n)
            .iter()
            .filter(|m| !m.is_ours())
            .map(|m| m.run_dir(root))
            .filter(|run| run.has_log())
            .map(|run| run.path().to_path_buf())
            .collect();
        if !dirs.is_empty() {
            let svg = runs_curves_svg(
                &dirs,
                &format!("Fig. 1 — N = {n}: validation welfare (dashed: classical methods)"),
            )?;
            write_atomic_making_dirs(&figures.join(format!("fig1_n{n}.svg")), svg.as_bytes())?;
        }
    }
    write_atomic_making_dirs(
        &figures.join("assignment_n100.svg"),
        assignment_map_svg(root)?.as_bytes(),
    )?;
    let threads = rayon::current_num_threads();
    let info = RunInfo {
        quick,
        minutes,
        threads,
    };
    let md = results_document(res, tables, info, root)?;
    afg_game::fs::write_atomic(&root.join("docs/RESULTS.md"), md.as_bytes())?;
    let readme = root.join("README.md");
    if readme.exists()
        && let Some(new) = with_block(&std::fs::read_to_string(&readme)?, tables)
    {
        afg_game::fs::write_atomic(&readme, new.as_bytes())?;
    }
    Ok(())
}

/// The tables between the markers of a file.
fn results_block(path: &Path) -> Result<String> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    block(&text).with_context(|| format!("{} has no {BEGIN} … {END} block", path.display()))
}

fn check_readme(root: &Path) -> Result<()> {
    if results_block(&root.join("README.md"))? != results_block(&root.join("docs/RESULTS.md"))? {
        bail!("README.md's tables differ from docs/RESULTS.md; run `cargo xtask reproduce-tables`");
    }
    println!("README.md shows the tables of docs/RESULTS.md");
    Ok(())
}
