//! `cargo xtask reproduce-tables`: Tables I and II, Fig. 1 and an assignment map, from
//! the committed datasets and weights.

use std::path::{Path, PathBuf};

use afg_eval::dataset;
use afg_eval::figures::runs_curves_svg;
use afg_game::fs::write_atomic_making_dirs;
use afg_repro::ModelSpec;
use afg_repro::tables::{
    BEGIN, END, RunInfo, Tables, assignment_map_svg, block, compute, markdown, results_document,
    with_block,
};
use anyhow::{Context, Result, bail};
use clap::Args;

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

pub fn run(args: TablesArgs) -> Result<()> {
    if args.check {
        return check_readme(&crate::repo_root());
    }
    if args.verify {
        let root = crate::repo_root();
        check_readme(&root)?;
        let committed = results_block(&root.join("docs/RESULTS.md"))?;
        let fresh = markdown(&compute_tables(&root, false)?);
        let differences = afg_repro::markdown::table_differences(&committed, &fresh);
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
