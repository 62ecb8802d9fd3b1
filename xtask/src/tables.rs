//! `cargo xtask reproduce-tables`: Tables I and II, Fig. 1 and an assignment map, from
//! the committed datasets and weights.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use afg_baseline::{Allocator, Method, Optimum};
use afg_eval::tables::{
    Row, Scale, classical_rows, headline, price_headed_rows, price_model_rows, table1_markdown,
    table2_markdown,
};
use afg_eval::{ModelSpec, Variant, dataset, evaluate, optima};
use afg_game::Instance;
use afg_learn::LearnedPolicy;
use anyhow::{Context, Result, bail};
use clap::Args;
use serde::Serialize;

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

/// What Table I's rows are, under it.
const TABLE1_NOTE: &str = "The learned rows keep the paper's networks and algorithms; where their training departs from the paper (units of the inputs and rewards, reward shaping, loss, learning rate, target sync) is in each model's command under \"The committed models\" in docs/RESULTS.md, and explained in docs/training.md. The rows marked (ours) are not the paper's method: \"AFGNet, exact Q* regression\" is the paper's network trained by regression on the exact Q* of the sequential MDP instead of TD targets (docs/training.md); \"AFGNet + price head\" (docs/price.md) is the paper's AFGNet with a price head added, Q(s, a) = π_a(s) − β d(t, a) + c_a(s), which is Nearest before training, trained on the exact Q*, by Double DQN, or by Double DQN with demonstrations from the optimum, and run without any repair (its one-shot row evaluates the network once for all robots); the price model (docs/price.md) is a per-task price network without the graph embedding, trained on the same Q*, run without any repair. \"Blind round robin\" gives each robot the task with the fewest robots so far and never looks at a task: no policy that cannot see the tasks, such as the paper's S2V, does better on average (docs/training.md).\n\n";

const BEGIN: &str = "<!-- reproduce-tables:begin -->";
const END: &str = "<!-- reproduce-tables:end -->";

#[derive(Serialize)]
struct Results {
    quick: bool,
    table1: Vec<Scale>,
    table2: Vec<Scale>,
    price_ablation: Vec<crate::price::AblationRow>,
    price_ablation_instances: usize,
    missing_models: Vec<String>,
}

pub fn run(args: TablesArgs) -> Result<()> {
    if args.check {
        return check_readme(&crate::repo_root());
    }
    if args.verify {
        let root = crate::repo_root();
        check_readme(&root)?;
        let committed = results_block(&root.join("docs/RESULTS.md"))?;
        let fresh = markdown_tables(&compute(&root, false)?);
        let differences = afg_eval::markdown::table_differences(&committed, &fresh);
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
    let results = compute(&root, args.quick)?;
    let minutes = start.elapsed().as_secs_f64() / 60.0;
    let tables = markdown_tables(&results);
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

/// Evaluates every method on the committed datasets, with the weights under `root/models`.
fn compute(root: &Path, quick: bool) -> Result<Results> {
    let (t1_instances, t2_instances, t2_learned) = if quick { (3, 2, 1) } else { (100, 100, 20) };
    let mut missing = Vec::new();
    let bar = crate::progress(5, "reproduce-tables (datasets)");
    let mut table1 = Vec::new();
    for n in dataset::TABLE1_SIZES {
        let insts: Vec<Instance> = crate::datasets::load(n)?
            .into_iter()
            .take(t1_instances)
            .collect();
        let opt = optima(&insts)?;
        let mut rows = Vec::new();
        for spec in ModelSpec::table1(n) {
            let run = spec.run_dir(root);
            if !run.has_weights() {
                // Our variants are optional; the paper's three models are expected.
                if !spec.is_ours() {
                    missing.push(format!("models/{}", spec.dir_name()));
                }
                continue;
            }
            let policy = LearnedPolicy::load(&run.weights())
                .with_context(|| format!("loading {}", run.path().display()))?;
            rows.push(Row::of_model(
                spec,
                evaluate(&spec.label(), &policy, &insts, &opt)?,
            ));
        }
        // The N = 60 models at the other scales (the paper's "Pretrain_60" at N = 20, 100).
        for pretrained in ModelSpec::TRANSFERRED {
            let run = pretrained.run_dir(root);
            if n != ModelSpec::PRETRAINED_AT && run.has_weights() {
                let policy = LearnedPolicy::load(&run.weights())?;
                let label = format!(
                    "{} trained at N = {}",
                    pretrained.label(),
                    ModelSpec::PRETRAINED_AT
                );
                rows.push(Row::new(evaluate(&label, &policy, &insts, &opt)?));
            }
        }
        // Models trained further at this N from a smaller one (warm starts).
        for warm in ModelSpec::WARM_STARTS
            .into_iter()
            .filter(|w| w.trained_at == n)
        {
            let run = warm.run_dir(root);
            if run.has_weights() {
                let policy = LearnedPolicy::load(&run.weights())?;
                rows.push(Row::new(evaluate(&warm.label(), &policy, &insts, &opt)?));
            }
        }
        rows.extend(price_headed_rows(root, &insts, &opt)?);
        rows.extend(price_model_rows(root, &insts, &opt)?);
        rows.extend(classical_rows(&insts, &opt, insts.len())?);
        bar.inc(1);
        table1.push(Scale { robots: n, rows });
    }
    let mut table2 = Vec::new();
    for n in dataset::TABLE2_SIZES {
        let insts: Vec<Instance> = crate::datasets::load(n)?
            .into_iter()
            .take(t2_instances)
            .collect();
        let opt = optima(&insts)?;
        let few = t2_learned.min(insts.len());
        let mut rows = Vec::new();
        rows.extend(classical_rows(&insts, &opt, few)?);
        rows.extend(price_headed_rows(root, &insts, &opt)?);
        rows.extend(price_model_rows(root, &insts, &opt)?);
        // The paper's model and ours with the gain residual at every training N, then
        // ours trained at N = 60 only.
        let specs = [Variant::Paper, Variant::GainResidual]
            .into_iter()
            .flat_map(|variant| {
                dataset::TABLE1_SIZES.map(|trained| ModelSpec {
                    variant,
                    ..ModelSpec::afgnet_ddqn(trained)
                })
            })
            .chain(ModelSpec::TRANSFERRED.into_iter().filter(|s| s.is_ours()));
        for spec in specs {
            let run = spec.run_dir(root);
            if !run.has_weights() {
                continue;
            }
            let policy = LearnedPolicy::load(&run.weights())?;
            let label = format!("{} trained at N = {}", spec.label(), spec.trained_at);
            rows.push(Row::new(evaluate(
                &label,
                &policy,
                &insts[..few],
                &opt[..few],
            )?));
            if spec == ModelSpec::afgnet_ddqn(spec.trained_at) {
                // The fast variant: one pass per N/100 robots, then balanced repair.
                let policy = policy.with_block(n / 100)?.with_repair(true);
                let label = format!("{label}, block {}, + repair", policy.block());
                rows.push(Row::new(evaluate(&label, &policy, &insts, &opt)?));
            }
        }
        bar.inc(1);
        table2.push(Scale { robots: n, rows });
    }
    bar.finish_and_clear();
    missing.sort();
    missing.dedup();
    Ok(Results {
        quick,
        table1,
        table2,
        price_ablation: crate::price::ablation(root, t1_instances)?,
        price_ablation_instances: t1_instances,
        missing_models: missing,
    })
}

fn markdown_tables(res: &Results) -> String {
    let mut s = table1_markdown(&res.table1);
    s.push_str(TABLE1_NOTE);
    s.push_str(&table2_markdown(&res.table2));
    if !res.price_ablation.is_empty() {
        s += &crate::price::ablation_markdown(&res.price_ablation, res.price_ablation_instances);
    }
    if !res.missing_models.is_empty() {
        let _ = writeln!(
            s,
            "Not trained yet (rows omitted): {}.",
            res.missing_models.join(", ")
        );
    }
    s
}

fn write_outputs(
    root: &Path,
    res: &Results,
    tables: &str,
    quick: bool,
    minutes: f64,
) -> Result<()> {
    let docs = root.join("docs");
    std::fs::create_dir_all(docs.join("figures"))?;
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
            crate::curves::plot_curves(
                &dirs,
                &docs.join("figures").join(format!("fig1_n{n}.svg")),
                &format!("Fig. 1 — N = {n}: validation welfare (dashed: classical methods)"),
            )?;
        }
    }
    assignment_map(root, &docs.join("figures").join("assignment_n100.svg"))?;
    let mut md = String::new();
    let _ = writeln!(md, "# Results\n");
    let _ = writeln!(
        md,
        "Made by `cargo xtask reproduce-tables{}` on {} ({}-core CPU), committed datasets `datasets/` and committed weights `models/`. Defaults: eps = max(2, N/M), no capacities, beta = 1, M = 5 (see decisions.md). Instances run in parallel, one per core; each time / instance is one instance's wall time on one core (`RAYON_NUM_THREADS=1` runs them one after another). The whole run took {minutes:.1} min.\n",
        if quick { " --quick" } else { "" },
        std::env::consts::ARCH,
        rayon::current_num_threads()
    );
    md.push_str(BEGIN);
    md.push('\n');
    md.push_str(tables);
    md.push_str(END);
    md.push('\n');
    let _ = writeln!(md, "\n{}", headline(&res.table1));
    md.push_str(&models_table(root)?);
    afg_game::io::write_atomic(&docs.join("RESULTS.md"), md.as_bytes())?;
    let readme = root.join("README.md");
    if readme.exists() {
        let text = std::fs::read_to_string(&readme)?;
        if let (Some(b), Some(e)) = (text.find(BEGIN), text.find(END)) {
            let new = format!(
                "{}{BEGIN}\n{tables}{END}{}",
                &text[..b],
                &text[e + END.len()..]
            );
            afg_game::io::write_atomic(&readme, new.as_bytes())?;
        }
    }
    Ok(())
}

/// Instance 0 of the N = 100 test set: OPT beside AFGNet_DDQN (or GRAPE DA while no
/// N = 100 model is committed). Robots coloured by task, tasks as squares sized by coalition.
fn assignment_map(root: &Path, out: &Path) -> Result<()> {
    let inst = crate::datasets::load(100)?.swap_remove(0);
    let opt = Optimum.allocate(&inst)?.assignment;
    let run = ModelSpec::afgnet_ddqn(100).run_dir(root);
    let (label, other) = if run.has_weights() {
        (
            ModelSpec::afgnet_ddqn(100).label(),
            LearnedPolicy::load(&run.weights())?
                .allocate(&inst)?
                .assignment,
        )
    } else {
        (
            format!("{} (no N = 100 model yet)", Method::Da.label()),
            Method::Da.allocator(0).allocate(&inst)?.assignment,
        )
    };
    crate::map::draw_assignments(&inst, &[(Method::Opt.label(), &opt), (&label, &other)], out)
}

/// The training budget of every committed model the tables use, from its manifest.
fn models_table(root: &Path) -> Result<String> {
    let mut md = String::from(
        "\n## The committed models\n\n\
         Each row's command retrains it (`manifest.json` beside the weights; \
         wall times are those of runs that shared the 2 cores with other work).\n\n\
         | model | N | steps | learning rate | wall time | final validation, % of OPT | command |\n\
         |---|---|---|---|---|---|---|\n",
    );
    let specs = ModelSpec::TABLE1_KINDS
        .into_iter()
        .flat_map(|(net, algo, variant)| {
            dataset::TABLE1_SIZES.map(|n| ModelSpec::new(net, algo, variant, n))
        })
        .chain(ModelSpec::WARM_STARTS)
        .chain(ModelSpec::PRICE_HEADED);
    for spec in specs {
        let n = spec.trained_at;
        let label = spec.label();
        let run = spec.run_dir(root);
        if !run.has_manifest() {
            continue;
        }
        let manifest = run.manifest()?;
        let config = run.config()?;
        let lr = if config.lr_decay {
            format!(
                "{:.1e} → {:.1e} (annealed)",
                config.lr,
                config.learning_rate(config.steps)
            )
        } else {
            format!("{:.1e} (constant)", config.lr)
        };
        let minutes = manifest.wall_time_s.unwrap_or(f64::NAN) / 60.0;
        let pct = manifest
            .final_validation
            .as_ref()
            .map_or(f64::NAN, |v| v.percent_of_opt);
        let _ = writeln!(
            md,
            "| {label} | {n} | {} | {lr} | {minutes:.0} min | {pct:.1} % | `{}` |",
            config.steps, manifest.command
        );
    }
    Ok(md)
}

/// The tables between the BEGIN and END markers of a file.
fn results_block(path: &Path) -> Result<String> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    match (text.find(BEGIN), text.find(END)) {
        (Some(b), Some(e)) if b < e => Ok(text[b + BEGIN.len()..e].trim_start().to_owned()),
        _ => bail!("{} has no {BEGIN} … {END} block", path.display()),
    }
}

fn check_readme(root: &Path) -> Result<()> {
    if results_block(&root.join("README.md"))? != results_block(&root.join("docs/RESULTS.md"))? {
        bail!("README.md's tables differ from docs/RESULTS.md; run `cargo xtask reproduce-tables`");
    }
    println!("README.md shows the tables of docs/RESULTS.md");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The results with timings removed.
    fn without_timings(r: &Results) -> serde_json::Value {
        let mut v = serde_json::to_value(r).unwrap();
        for table in ["table1", "table2"] {
            for entry in v[table].as_array_mut().unwrap() {
                for row in entry["rows"].as_array_mut().unwrap() {
                    row["seconds_per_instance"] = serde_json::Value::Null;
                }
            }
        }
        v
    }

    #[test]
    fn quick_tables_are_reproducible_and_opt_dominates() {
        let root = crate::repo_root();
        let a = compute(&root, true).unwrap();
        let b = compute(&root, true).unwrap();
        assert_eq!(without_timings(&a), without_timings(&b));
        for scale in a.table1.iter().chain(&a.table2) {
            let rows: Vec<_> = scale.rows.iter().map(|r| &r.summary).collect();
            let opt = rows
                .iter()
                .find(|r| r.method == Method::Opt.label())
                .unwrap();
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
        let tables = markdown_tables(&a);
        assert!(
            tables.contains("Table I") && tables.contains("Table II") && tables.contains("22.61")
        );
    }
}
