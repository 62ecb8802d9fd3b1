//! `cargo xtask solve`: one allocator on an instance file or a committed dataset.

use std::path::PathBuf;

use afg_baseline::{Allocator, Method, Optimum};
use afg_eval::solve::{ModelOptions, Report, Row, load_model};
use afg_game::{Assignment, Instance};
use anyhow::{Context, Result};
use clap::Args;

#[derive(Args)]
#[command(group = clap::ArgGroup::new("source").required(true))]
#[command(group = clap::ArgGroup::new("allocator").required(true))]
pub struct SolveArgs {
    /// Allocator: opt, da (GRAPE, centralised), da-decentralised, da-balanced, greedy, nearest, random.
    #[arg(long, short, group = "allocator")]
    pub(crate) method: Option<Method>,
    /// A learned policy instead: a trained run directory (holding model.json and
    /// model.mpk), e.g. models/afgnet_ddqn_n20.
    #[arg(long, group = "allocator")]
    pub(crate) model: Option<PathBuf>,
    /// Learned policy (Q network or sequential price model): robots per network evaluation
    /// [default: 1, the exact greedy rollout].
    #[arg(long)]
    pub(crate) block: Option<usize>,
    /// Learned policy: balanced best-response sweeps after the rollout (Def. 3 stable result).
    #[arg(long)]
    pub(crate) repair: bool,
    /// Price model (a directory holding price.json): every robot uses the prices of the
    /// empty state instead of the current one.
    #[arg(long)]
    pub(crate) one_shot: bool,
    /// Learned policy: roll out with the Burn network (the slow reference path).
    #[arg(long)]
    pub(crate) exact_burn: bool,
    /// Your instances: one instance JSON file (format "afg-instance"), or a JSON Lines
    /// file with one instance per line; "-" reads standard input.
    #[arg(long, group = "source")]
    pub(crate) input: Option<PathBuf>,
    /// Write each instance's assignment to this file: one JSON line per instance, format
    /// "afg-assignment" (`tasks[i]` = robot i's task), with a `summary` of its welfare,
    /// % of OPT, coalition sizes and stability.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Draw the first instance's assignment (beside OPT's) as an SVG map.
    #[arg(long)]
    pub(crate) svg: Option<PathBuf>,
    /// Warm start after robots or tasks changed: a previous assignment file whose
    /// optional `left_robots` / `left_tasks` name what left (the instance keeps the
    /// survivors in order, then the newcomers). Survivors keep their task, the others
    /// join by best response, then best-response dynamics run to a stable assignment
    /// (method da-balanced or da only; one instance).
    #[arg(long)]
    pub(crate) from: Option<PathBuf>,
    /// A committed dataset by robot count: 20, 60, 100, 500 or 1000.
    #[arg(long, group = "source")]
    pub(crate) dataset: Option<usize>,
    /// Use only the first K instances of the dataset.
    #[arg(long)]
    pub(crate) limit: Option<usize>,
    /// Seed of the randomised methods (random, da-decentralised).
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// Print JSON (per instance and mean) instead of text.
    #[arg(long)]
    pub(crate) json: bool,
}

/// Reads `--input`: a file or standard input ("-"), one instance or JSON Lines.
fn read_instances(path: &std::path::Path) -> Result<Vec<Instance>> {
    let text = if path.as_os_str() == "-" {
        std::io::read_to_string(std::io::stdin()).context("reading standard input")?
    } else {
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?
    };
    let instances = afg_game::io::parse_instances(&text)
        .with_context(|| format!("reading {}", path.display()))?;
    if instances.is_empty() {
        anyhow::bail!("{} holds no instance", path.display());
    }
    Ok(instances)
}

pub fn run(args: SolveArgs) -> Result<()> {
    if args.model.is_none() && (args.block.is_some() || args.repair || args.exact_burn) {
        anyhow::bail!("--block, --repair and --exact-burn apply to a learned policy (--model DIR)");
    }
    let (source, mut instances) = match (&args.input, args.dataset) {
        (Some(p), _) => (p.display().to_string(), read_instances(p)?),
        (None, Some(n)) => (format!("datasets/n{n}.jsonl"), crate::datasets::load(n)?),
        (None, None) => unreachable!("clap requires a source"),
    };
    if let Some(k) = args.limit {
        instances.truncate(k);
    }
    if let Some(from) = &args.from {
        return crate::realloc::run(&args, from, &instances);
    }
    let (name, method): (String, Box<dyn Allocator>) = match (&args.method, &args.model) {
        (Some(m), _) => (m.to_string(), m.allocator(args.seed)),
        (None, Some(dir)) => {
            let options = ModelOptions {
                block: args.block,
                repair: args.repair,
                one_shot: args.one_shot,
                exact_burn: args.exact_burn,
            };
            (dir.display().to_string(), load_model(dir, options)?)
        }
        (None, None) => unreachable!("clap requires an allocator"),
    };
    let bar = crate::progress(instances.len() as u64, &format!("{name} on {source}"));
    let (rows, assignments): (Vec<Row>, Vec<Assignment>) = instances
        .iter()
        .map(|inst| {
            let row = Row::compute(inst, method.as_ref());
            bar.inc(1);
            row
        })
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    bar.finish_and_clear();
    write_outputs(&args, &name, &instances, &rows, &assignments)?;
    let report = Report::new(name, source, rows)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    let m = &report.mean;
    println!(
        "{} on {} ({} instance{})",
        report.method,
        report.source,
        report.instances,
        if report.instances == 1 { "" } else { "s" }
    );
    println!(
        "  welfare           {:>12.3}   (OPT {:.3})",
        m.welfare, m.opt_welfare
    );
    println!("  % of OPT          {:>12.2}", m.percent_of_opt);
    println!("  NS_rate balanced  {:>11.1} %", 100.0 * m.ns_rate_balanced);
    println!("  NS_rate selfish   {:>11.1} %", 100.0 * m.ns_rate_selfish);
    println!("  iterations        {:>12.1}", m.iterations);
    println!("  rounds            {:>12.1}", m.rounds);
    if m.messages > 0.0 {
        println!("  messages          {:>12.0}", m.messages);
    }
    println!("  time / instance   {:>10.3} ms", 1e3 * m.seconds);
    if report.instances > 1 {
        println!("  (means over instances; --json for each one)");
    }
    Ok(())
}

/// `--out` and `--svg`; written before anything is printed, atomically.
fn write_outputs(
    args: &SolveArgs,
    name: &str,
    instances: &[Instance],
    rows: &[Row],
    assignments: &[Assignment],
) -> Result<()> {
    if let Some(out) = &args.out {
        let mut text = String::new();
        for ((inst, row), a) in instances.iter().zip(rows).zip(assignments) {
            text += &row.assignment_line(name, inst, a);
            text.push('\n');
        }
        afg_game::io::write_atomic(out, text.as_bytes())?;
    }
    if let Some(svg) = &args.svg {
        let opt = Optimum.allocate(&instances[0])?.assignment;
        crate::write_svg(
            svg,
            &afg_eval::figures::assignments_svg(
                &instances[0],
                &[("OPT", &opt), (name, &assignments[0])],
            )?,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    fn solve(args: &[&str]) -> anyhow::Result<()> {
        let mut argv = vec!["cargo xtask", "solve"];
        argv.extend_from_slice(args);
        match crate::Cli::try_parse_from(argv)?.command {
            crate::Command::Solve(a) => super::run(a),
            _ => unreachable!("only solve here"),
        }
    }

    fn temp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("afg-solve-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn json_lines_in_assignments_and_a_map_out() {
        let dir = temp("out");
        let a = afg_game::GeneratorConfig::paper(12, 3, 1)
            .generate()
            .unwrap();
        let b = afg_game::GeneratorConfig::paper(9, 3, 2)
            .generate()
            .unwrap();
        let input = dir.join("mine.jsonl");
        std::fs::write(
            &input,
            afg_game::io::dataset_to_jsonl(&[a.clone(), b.clone()]),
        )
        .unwrap();
        let (out, svg) = (dir.join("out.jsonl"), dir.join("map.svg"));
        let path = |p: &std::path::Path| p.to_str().unwrap().to_owned();
        solve(&[
            "--method",
            "da-balanced",
            "--input",
            &path(&input),
            "--out",
            &path(&out),
            "--svg",
            &path(&svg),
        ])
        .unwrap();
        let text = std::fs::read_to_string(&out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 2);
        for (line, inst) in lines.iter().zip([&a, &b]) {
            // Each line is an assignment of its instance, with its summary.
            let assignment = afg_game::Assignment::from_json(line, inst).unwrap();
            assert!(assignment.is_complete());
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            let sizes: Vec<usize> =
                serde_json::from_value(v["summary"]["coalition_sizes"].clone()).unwrap();
            assert_eq!(sizes, assignment.sizes());
            assert!(
                (v["summary"]["welfare"].as_f64().unwrap() - inst.welfare(&assignment)).abs()
                    < 1e-9
            );
            assert_eq!(v["summary"]["stable_balanced"], true);
        }
        assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
        // A single instance file (pretty-printed over many lines) is one instance.
        let single = dir.join("one.json");
        let pretty = serde_json::to_string_pretty(
            &serde_json::from_str::<serde_json::Value>(&a.to_json()).unwrap(),
        )
        .unwrap();
        std::fs::write(&single, pretty).unwrap();
        solve(&[
            "--method",
            "greedy",
            "--input",
            &path(&single),
            "--out",
            &path(&out),
        ])
        .unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap().lines().count(), 1);
    }

    #[test]
    fn a_bad_line_names_its_line_and_writes_nothing() {
        let dir = temp("bad");
        let a = afg_game::GeneratorConfig::paper(12, 3, 1)
            .generate()
            .unwrap();
        let input = dir.join("mine.jsonl");
        let bad = a.to_json().replace("\"eps\":4.0", "\"eps\":1.0");
        let text = format!("{}\n{}\n{}\n", a.to_json(), a.to_json(), bad);
        assert_ne!(bad, a.to_json(), "the test must break the third line");
        std::fs::write(&input, text).unwrap();
        let out = dir.join("out.jsonl");
        let err = solve(&[
            "--method",
            "opt",
            "--input",
            input.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .unwrap_err();
        assert!(format!("{err:#}").contains("line 3"), "{err:#}");
        assert!(!out.exists());
        std::fs::write(&input, "").unwrap();
        let err = solve(&["--method", "opt", "--input", input.to_str().unwrap()]).unwrap_err();
        assert!(format!("{err:#}").contains("no instance"), "{err:#}");
    }

    #[test]
    fn warm_start_from_a_previous_assignment() {
        let dir = temp("from");
        let inst = afg_game::GeneratorConfig::paper(40, 5, 3)
            .generate()
            .unwrap();
        let path = |p: &std::path::Path| p.to_str().unwrap().to_owned();
        let (input, first) = (dir.join("now.json"), dir.join("first.jsonl"));
        inst.write(&input).unwrap();
        solve(&[
            "--method",
            "opt",
            "--input",
            &path(&input),
            "--out",
            &path(&first),
        ])
        .unwrap();
        // The same robots again: nothing moves, nothing is placed.
        let again = dir.join("again.jsonl");
        solve(&[
            "--method",
            "da-balanced",
            "--input",
            &path(&input),
            "--from",
            &path(&first),
            "--out",
            &path(&again),
        ])
        .unwrap();
        let v: serde_json::Value =
            serde_json::from_str(std::fs::read_to_string(&again).unwrap().trim()).unwrap();
        assert_eq!(
            (
                v["summary"]["moved"].as_u64(),
                v["summary"]["placed"].as_u64()
            ),
            (Some(0), Some(0))
        );
        let err = solve(&[
            "--method",
            "opt",
            "--input",
            &path(&input),
            "--from",
            &path(&first),
        ])
        .unwrap_err();
        assert!(format!("{err:#}").contains("da-balanced"), "{err:#}");
    }

    #[test]
    fn learned_policies_solve_and_bad_options_are_refused() {
        let model = crate::repo_root().join("models/afgnet_ddqn_n20");
        let model = model.to_str().unwrap();
        solve(&[
            "--model",
            model,
            "--dataset",
            "20",
            "--limit",
            "2",
            "--json",
        ])
        .unwrap();
        solve(&[
            "--model",
            model,
            "--dataset",
            "100",
            "--limit",
            "1",
            "--block",
            "7",
            "--repair",
        ])
        .unwrap();
        let err = solve(&[
            "--model",
            model,
            "--dataset",
            "20",
            "--exact-burn",
            "--block",
            "3",
        ])
        .unwrap_err();
        assert!(format!("{err:#}").contains("block 1"), "{err:#}");
        let err = solve(&["--model", "/nonexistent", "--dataset", "20"]).unwrap_err();
        assert!(format!("{err:#}").contains("/nonexistent"), "{err:#}");
        // A method and a model at once, or --block without a model: usage errors.
        assert!(solve(&["--method", "opt", "--model", model, "--dataset", "20"]).is_err());
        assert!(solve(&["--method", "opt", "--block", "2", "--dataset", "20"]).is_err());
    }
}
