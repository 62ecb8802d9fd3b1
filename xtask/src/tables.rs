//! `cargo xtask reproduce-tables`: Tables I and II, Fig. 1 and an assignment map, from
//! the committed datasets and weights.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use afg_baseline::{Allocator, Method, Optimum};
use afg_game::{Instance, Preference};
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
    /// Where to write RESULTS.md, figures/ and the README block (default: the repository).
    #[arg(long)]
    root: Option<PathBuf>,
}

/// The learned rows: (label, model directory under models/).
const TABLE1_MODELS: [(&str, &str); 4] = [
    ("S2V_DDQN", "s2v_ddqn"),
    ("AFGNet_DQN", "afgnet_dqn"),
    ("AFGNet_DDQN", "afgnet_ddqn"),
    // Ours, not in the paper: AFGNet_DDQN with the action's immediate reward added to Q.
    ("AFGNet_DDQN + gain residual (ours)", "afgnet_ddqn_gain"),
];

/// Paper Table I: N → (S2V_DDQN, AFGNet_DQN, AFGNet_DDQN, NS_rate of AFGNet_DDQN in %).
const PAPER_TABLE1: [(usize, [f64; 4]); 3] = [
    (20, [14.85, 19.31, 22.61, 81.8]),
    (60, [42.37, 48.00, 59.51, 80.8]),
    (100, [96.18, 96.99, 106.21, 78.0]),
];

/// Paper Table II: N → (DA utility, Pretrain_60 utility, DA NS %, P60 NS %, DA s, DRL s).
const PAPER_TABLE2: [(usize, [f64; 6]); 2] = [
    (500, [619.11, 620.23, 80.5, 79.5, 181.83, 2.66]),
    (1000, [1247.53, 1250.75, 80.0, 81.1, 714.88, 10.42]),
];

const BEGIN: &str = "<!-- reproduce-tables:begin -->";
const END: &str = "<!-- reproduce-tables:end -->";

/// One method on one dataset.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub method: String,
    pub instances: usize,
    pub welfare: f64,
    pub percent_of_opt: f64,
    pub ns_rate_balanced: f64,
    pub ns_rate_selfish: f64,
    pub seconds_per_instance: f64,
}

#[derive(Serialize)]
struct Results {
    quick: bool,
    table1: Vec<(usize, Vec<Row>)>,
    table2: Vec<(usize, Vec<Row>)>,
    missing_models: Vec<String>,
}

fn evaluate(label: &str, alloc: &dyn Allocator, insts: &[Instance], opt: &[f64]) -> Result<Row> {
    let (mut welfare, mut pct, mut nsb, mut nss, mut secs) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (inst, &o) in insts.iter().zip(opt) {
        let start = Instant::now();
        let a = alloc.allocate(inst)?.assignment;
        secs += start.elapsed().as_secs_f64();
        let w = inst.welfare(&a);
        if w > o + 1e-9 * o.abs().max(1.0) {
            bail!("{label} beats OPT ({w} > {o}): OPT is wrong");
        }
        welfare += w;
        pct += 100.0 * w / o;
        nsb += inst.ns_rate(&a, Preference::Balanced);
        nss += inst.ns_rate(&a, Preference::Selfish);
    }
    let k = insts.len() as f64;
    Ok(Row {
        method: label.to_owned(),
        instances: insts.len(),
        welfare: welfare / k,
        percent_of_opt: pct / k,
        ns_rate_balanced: 100.0 * nsb / k,
        ns_rate_selfish: 100.0 * nss / k,
        seconds_per_instance: secs / k,
    })
}

fn model_stem(root: &Path, dir: &str, n: usize) -> PathBuf {
    root.join("models")
        .join(format!("{dir}_n{n}"))
        .join("model")
}

fn classical(n: usize) -> Vec<(&'static str, Method)> {
    let mut v = vec![
        ("OPT", Method::Opt),
        ("GRAPE DA", Method::Da),
        ("GRAPE DA, decentralised", Method::DaDecentralised),
        ("balanced DA", Method::DaBalanced),
        ("Greedy", Method::Greedy),
        ("Nearest", Method::Nearest),
        ("Random", Method::Random),
    ];
    if n > 1000 {
        v.retain(|(_, m)| *m != Method::DaDecentralised);
    }
    v
}

pub fn run(args: TablesArgs) -> Result<()> {
    if args.check {
        return check_readme(&crate::repo_root());
    }
    let root = args.root.clone().unwrap_or_else(crate::repo_root);
    let results = compute(&root, args.quick)?;
    let tables = markdown_tables(&results);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&results)?);
    } else {
        println!("{tables}");
    }
    if !args.quick || args.root.is_some() {
        write_outputs(&root, &results, &tables, args.quick)?;
    }
    Ok(())
}

/// Evaluates every method on the committed datasets, with the weights under `root/models`.
fn compute(root: &Path, quick: bool) -> Result<Results> {
    let (t1_instances, t2_instances, t2_learned) = if quick { (3, 2, 1) } else { (100, 100, 20) };
    let mut missing = Vec::new();
    let bar = crate::progress(5, "reproduce-tables (datasets)");
    let mut table1 = Vec::new();
    for n in [20, 60, 100] {
        let insts: Vec<Instance> = crate::datasets::load(n)?
            .into_iter()
            .take(t1_instances)
            .collect();
        let opt = optima(&insts)?;
        let mut rows = Vec::new();
        for (label, dir) in TABLE1_MODELS {
            let stem = model_stem(root, dir, n);
            if !stem.with_extension("mpk").exists() {
                // Our variants are optional; the paper's three models are expected.
                if !label.ends_with("(ours)") {
                    missing.push(format!("models/{dir}_n{n}"));
                }
                continue;
            }
            let policy = LearnedPolicy::load(&stem)
                .with_context(|| format!("loading {}", stem.display()))?;
            rows.push(evaluate(label, &policy, &insts, &opt)?);
        }
        for (label, method) in classical(n) {
            rows.push(evaluate(label, method.allocator(0).as_ref(), &insts, &opt)?);
        }
        bar.inc(1);
        table1.push((n, rows));
    }
    let mut table2 = Vec::new();
    for n in [500, 1000] {
        let insts: Vec<Instance> = crate::datasets::load(n)?
            .into_iter()
            .take(t2_instances)
            .collect();
        let opt = optima(&insts)?;
        let mut rows = Vec::new();
        for (label, method) in classical(n) {
            rows.push(evaluate(label, method.allocator(0).as_ref(), &insts, &opt)?);
        }
        let few = t2_learned.min(insts.len());
        for (name, dir) in [
            ("AFGNet_DDQN", "afgnet_ddqn"),
            ("AFGNet_DDQN + gain residual (ours)", "afgnet_ddqn_gain"),
        ] {
            for trained in [20, 60, 100] {
                let stem = model_stem(root, dir, trained);
                if !stem.with_extension("mpk").exists() {
                    continue;
                }
                let mut policy = LearnedPolicy::load(&stem)?;
                let label = format!("{name} trained at N = {trained}");
                rows.push(evaluate(&label, &policy, &insts[..few], &opt[..few])?);
                if dir == "afgnet_ddqn" {
                    // The fast variant: one pass per N/100 robots, then balanced repair.
                    (policy.block, policy.repair) = (n / 100, true);
                    let label = format!("{label}, block {}, + repair", policy.block);
                    rows.push(evaluate(&label, &policy, &insts, &opt)?);
                }
            }
        }
        bar.inc(1);
        table2.push((n, rows));
    }
    bar.finish_and_clear();
    missing.sort();
    missing.dedup();
    Ok(Results {
        quick,
        table1,
        table2,
        missing_models: missing,
    })
}

fn optima(insts: &[Instance]) -> Result<Vec<f64>> {
    insts
        .iter()
        .map(|i| Ok(i.welfare(&Optimum.allocate(i)?.assignment)))
        .collect()
}

fn row_line(r: &Row, paper: &str) -> String {
    format!(
        "| {} | {:.2} | {:.2} % | {:.1} % | {:.1} % | {} |",
        r.method, r.welfare, r.percent_of_opt, r.ns_rate_balanced, r.ns_rate_selfish, paper
    )
}

/// The paper's numbers for N = `n` in one of its tables.
fn paper_row<const K: usize>(table: &[(usize, [f64; K])], n: usize) -> [f64; K] {
    table
        .iter()
        .find(|(m, _)| *m == n)
        .map(|(_, p)| *p)
        .expect("the paper reports every N we tabulate")
}

fn markdown_tables(res: &Results) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "### Table I — mean over the first {} instances of each test set\n",
        res.table1[0].1[0].instances
    );
    for (n, rows) in &res.table1 {
        let paper = paper_row(&PAPER_TABLE1, *n);
        let _ = writeln!(
            s,
            "**N = {n}** (paper: S2V_DDQN {}, AFGNet_DQN {}, AFGNet_DDQN {}, NS_rate {} %)\n",
            paper[0], paper[1], paper[2], paper[3]
        );
        let _ = writeln!(
            s,
            "| method | welfare | % of OPT | NS_rate balanced | NS_rate selfish | paper welfare |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|");
        for r in rows {
            let p = match r.method.as_str() {
                "S2V_DDQN" => format!("{}", paper[0]),
                "AFGNet_DQN" => format!("{}", paper[1]),
                "AFGNet_DDQN" => format!("{} (NS {} %)", paper[2], paper[3]),
                _ => "–".into(),
            };
            let _ = writeln!(s, "{}", row_line(r, &p));
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "The learned rows keep the paper's networks and algorithms; where their training departs from the paper (units of the inputs and rewards, reward shaping, loss, learning rate, target sync) is in each model's command under \"The committed models\" in docs/RESULTS.md, and explained in docs/training.md.\n"
    );
    let _ = writeln!(
        s,
        "### Table II — large swarms (classical methods on the first {} instances)\n",
        res.table2[0].1[0].instances
    );
    for (n, rows) in &res.table2 {
        let paper = paper_row(&PAPER_TABLE2, *n);
        let _ = writeln!(
            s,
            "**N = {n}** (paper: DA {} in {} s, NS {} %; Pretrain_60 {} in {} s, NS {} %)\n",
            paper[0], paper[4], paper[2], paper[1], paper[5], paper[3]
        );
        let _ = writeln!(
            s,
            "| method | instances | welfare | % of OPT | NS_rate balanced | NS_rate selfish | time / instance |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
        for r in rows {
            let _ = writeln!(
                s,
                "| {} | {} | {:.2} | {:.2} % | {:.1} % | {:.1} % | {} |",
                r.method,
                r.instances,
                r.welfare,
                r.percent_of_opt,
                r.ns_rate_balanced,
                r.ns_rate_selfish,
                crate::bench::fmt_time(std::time::Duration::from_secs_f64(r.seconds_per_instance))
            );
        }
        let _ = writeln!(s);
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

fn write_outputs(root: &Path, res: &Results, tables: &str, quick: bool) -> Result<()> {
    let docs = root.join("docs");
    std::fs::create_dir_all(docs.join("figures"))?;
    let runs: Vec<PathBuf> = ["afgnet_ddqn", "afgnet_dqn", "s2v_ddqn"]
        .iter()
        .flat_map(|d| [20, 60, 100].map(|n| root.join("models").join(format!("{d}_n{n}"))))
        .filter(|p| p.join("log.jsonl").exists())
        .collect();
    for n in [20, 60, 100] {
        let dirs: Vec<PathBuf> = runs
            .iter()
            .filter(|p| p.to_string_lossy().ends_with(&format!("_n{n}")))
            .cloned()
            .collect();
        if !dirs.is_empty() {
            crate::train::plot_curves(
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
        "Made by `cargo xtask reproduce-tables{}` on {} (2-core CPU), committed datasets `datasets/` and committed weights `models/`. Defaults: eps = max(2, N/M), no capacities, beta = 1, M = 5 (see decisions.md).\n",
        if quick { " --quick" } else { "" },
        std::env::consts::ARCH
    );
    md.push_str(BEGIN);
    md.push('\n');
    md.push_str(tables);
    md.push_str(END);
    md.push('\n');
    let _ = writeln!(md, "\n{}", headline(res));
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
    let stem = model_stem(root, "afgnet_ddqn", 100);
    let (label, other) = if stem.with_extension("mpk").exists() {
        (
            "AFGNet_DDQN",
            LearnedPolicy::load(&stem)?.allocate(&inst)?.assignment,
        )
    } else {
        (
            "GRAPE DA (no N = 100 model yet)",
            Method::Da.allocator(0).allocate(&inst)?.assignment,
        )
    };
    draw_assignments(&inst, &[("OPT", &opt), (label, &other)], out)
}

/// Draws assignments of one instance side by side as an SVG: robots coloured by task
/// (black if unassigned), tasks as squares sized by coalition, welfare in each title.
pub fn draw_assignments(
    inst: &Instance,
    panels: &[(&str, &afg_game::Assignment)],
    out: &Path,
) -> Result<()> {
    use plotters::prelude::*;
    let mut svg = String::new();
    {
        let width = 500 * panels.len().max(1) as u32;
        let root_area = SVGBackend::with_string(&mut svg, (width, 520)).into_drawing_area();
        root_area.fill(&WHITE)?;
        let areas = root_area.split_evenly((1, panels.len().max(1)));
        // The unit square, widened to hold every robot and task of other instances.
        let points = inst
            .robots()
            .iter()
            .chain(inst.tasks().iter().map(|t| &t.position));
        let (mut x, mut y) = ((0.0f64, 1.0f64), (0.0f64, 1.0f64));
        for p in points {
            x = (x.0.min(p.x), x.1.max(p.x));
            y = (y.0.min(p.y), y.1.max(p.y));
        }
        for (area, (name, a)) in areas.iter().zip(panels) {
            let title = format!("{name}: welfare {:.2}", inst.welfare(a));
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 18))
                .margin(10)
                .x_label_area_size(25)
                .y_label_area_size(35)
                .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
            chart.configure_mesh().disable_mesh().draw()?;
            for (i, p) in inst.robots().iter().enumerate() {
                let color =
                    a.tasks()[i].map_or(BLACK.to_rgba(), |j| Palette99::pick(j.index()).to_rgba());
                chart.draw_series(std::iter::once(Circle::new((p.x, p.y), 3, color.filled())))?;
            }
            for j in inst.task_ids() {
                let t = inst.task(j).position;
                let size = 4 + 2 * (a.size(j) as f64).sqrt() as i32;
                let color = Palette99::pick(j.index()).to_rgba();
                chart.draw_series(std::iter::once(Rectangle::new(
                    [
                        (t.x - 0.004 * size as f64, t.y - 0.004 * size as f64),
                        (t.x + 0.004 * size as f64, t.y + 0.004 * size as f64),
                    ],
                    color.stroke_width(3),
                )))?;
            }
        }
        root_area.present()?;
    }
    afg_game::io::write_atomic(out, svg.as_bytes())?;
    Ok(())
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
    for (label, dir) in TABLE1_MODELS {
        for n in [20, 60, 100] {
            let path = root.join("models").join(format!("{dir}_n{n}"));
            let Ok(text) = std::fs::read_to_string(path.join("manifest.json")) else {
                continue;
            };
            let manifest: serde_json::Value = serde_json::from_str(&text)
                .with_context(|| format!("reading {}/manifest.json", path.display()))?;
            let config = crate::train::read_config(&path)?;
            let lr = if config.lr_decay {
                format!(
                    "{:.1e} → {:.1e} (annealed)",
                    config.lr,
                    config.learning_rate(config.steps)
                )
            } else {
                format!("{:.1e} (constant)", config.lr)
            };
            let minutes = manifest["wall_time_s"].as_f64().unwrap_or(f64::NAN) / 60.0;
            let pct = manifest["final_validation"]["percent_of_opt"]
                .as_f64()
                .unwrap_or(f64::NAN);
            let _ = writeln!(
                md,
                "| {label} | {n} | {} | {lr} | {minutes:.0} min | {pct:.1} % | `{}` |",
                config.steps,
                manifest["command"].as_str().unwrap_or("?")
            );
        }
    }
    Ok(md)
}

/// The honest headline: AFGNet_DDQN against DA, greedy and OPT at each N, in numbers.
fn headline(res: &Results) -> String {
    let mut s = String::from("**Headline.** ");
    for (n, rows) in &res.table1 {
        let get = |m: &str| rows.iter().find(|r| r.method == m);
        let (Some(da), Some(greedy), Some(nearest)) =
            (get("GRAPE DA"), get("Greedy"), get("Nearest"))
        else {
            continue;
        };
        match get("AFGNet_DDQN") {
            Some(drl) => {
                let _ = write!(
                    s,
                    "At N = {n}, AFGNet_DDQN reaches {:.1} % of OPT, against {:.1} % for GRAPE DA, {:.1} % for one-pass greedy and {:.1} % for nearest-task. ",
                    drl.percent_of_opt,
                    da.percent_of_opt,
                    greedy.percent_of_opt,
                    nearest.percent_of_opt
                );
            }
            None => {
                let _ = write!(
                    s,
                    "At N = {n} no AFGNet_DDQN model is committed yet; GRAPE DA reaches {:.1} % of OPT, greedy {:.1} % and nearest {:.1} %. ",
                    da.percent_of_opt, greedy.percent_of_opt, nearest.percent_of_opt
                );
            }
        }
    }
    s
}

fn check_readme(root: &Path) -> Result<()> {
    let block = |path: &Path| -> Result<String> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let (b, e) = (text.find(BEGIN), text.find(END));
        match (b, e) {
            (Some(b), Some(e)) if b < e => Ok(text[b..e].to_owned()),
            _ => bail!("{} has no {BEGIN} … {END} block", path.display()),
        }
    };
    if block(&root.join("README.md"))? != block(&root.join("docs/RESULTS.md"))? {
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
                for row in entry[1].as_array_mut().unwrap() {
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
        for (_, rows) in a.table1.iter().chain(&a.table2) {
            let opt = rows.iter().find(|r| r.method == "OPT").unwrap();
            assert!((opt.percent_of_opt - 100.0).abs() < 1e-9);
            for r in rows {
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
