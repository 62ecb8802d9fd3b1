//! `afg solve`: one allocator on an instance file or a committed dataset.

use std::path::PathBuf;

use afg_baseline::{Allocator, Method};
use afg_eval::solve::{Against, Report, Row};
use afg_game::fs::write_atomic_making_dirs;
use afg_game::io::read_instances;
use afg_game::{Assignment, Instance};
use afg_learn::LearnError;
use afg_learn::run::{ModelOptions, OptionConflict, load_model};
use anyhow::{Context, Result};
use clap::Args;

mod exact;

/// `afg solve`: an allocator, a source of instances and what to write.
#[derive(Args)]
#[command(group = clap::ArgGroup::new("source").required(true))]
#[command(group = clap::ArgGroup::new("allocator").required(true))]
pub struct SolveArgs {
    /// Allocator: opt, da (GRAPE, centralised), da-decentralised, da-balanced, greedy, nearest, random.
    #[arg(long, short, group = "allocator")]
    pub(crate) method: Option<Method>,
    /// A learned policy instead: a trained run directory (holding model.json and
    /// model.mpk), e.g. models/paper/afgnet_ddqn_n20.
    #[arg(long, group = "allocator")]
    pub(crate) model: Option<PathBuf>,
    /// Learned policy (Q network or sequential price model): robots per network evaluation
    /// [default: 1, the exact greedy rollout].
    #[arg(long)]
    pub(crate) block: Option<usize>,
    /// Learned policy: balanced best-response sweeps after the rollout (Def. 3 stable result);
    /// with a staffing model, a welfare climb after its placement (robot moves, swaps, whole teams dissolved or staffed; ours).
    #[arg(long)]
    pub(crate) repair: bool,
    /// Price model (a run whose manifest names a price model): every robot uses the prices of the
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
    /// Use only the first K instances (K ≥ 1).
    #[arg(long, value_parser = crate::at_least_one)]
    pub(crate) limit: Option<usize>,
    /// The exact optimum (--method opt) stops after SECS seconds with the best
    /// assignment found, its proven bound and the gap (the team games are NP-hard;
    /// without a limit it runs until optimality is proven).
    #[arg(long, value_name = "SECS", allow_negative_numbers = true)]
    pub(crate) time_limit: Option<f64>,
    /// The exact optimum (--method opt) stops as soon as its certified gap (the bound
    /// over the best found, less 1) is at most FRACTION, e.g. 0.001 for 0.1 %. While
    /// it searches a team game, it prints the best found, the bound and the gap to
    /// stderr every second.
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true)]
    pub(crate) gap: Option<f64>,
    /// The exact optimum (--method opt) starts from these assignments: one
    /// "afg-assignment" line per instance, in order (another method's --out, an earlier
    /// solve's). Each is its search's best found before the root, so the search prunes
    /// from its first node, and the answer is never worse than it.
    #[arg(long, value_name = "FILE", conflicts_with = "from")]
    pub(crate) start: Option<PathBuf>,
    /// "% of OPT" on a team game solves the game exactly first, which can cost far more
    /// than the method: the exact solver stops after SECS seconds per instance, and the
    /// share is then of its certified bound (said beside it). The paper's game is
    /// always solved exactly (in polynomial time).
    #[arg(
        long,
        value_name = "SECS",
        default_value_t = 10.0,
        allow_negative_numbers = true
    )]
    pub(crate) reference_time_limit: f64,
    /// Measure nothing against the optimum: the welfare alone, in the method's own time.
    #[arg(long, conflicts_with = "reference_time_limit")]
    pub(crate) no_reference: bool,
    /// Seed of the randomised methods (random, da-decentralised).
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u64,
    /// Print JSON (per instance and mean) instead of text.
    #[arg(long)]
    pub(crate) json: bool,
}

/// The library's error, with the flags to change when options conflict.
fn with_flags(error: LearnError) -> anyhow::Error {
    let LearnError::ModelOptions(conflict) = error else {
        return error.into();
    };
    let fix = match conflict {
        OptionConflict::QNetworkOptionOnPriceModel => "drop --repair and --exact-burn",
        OptionConflict::BlockWithOneShot => "drop --one-shot or --block",
        OptionConflict::OneShotOnQNetwork => "drop --one-shot",
        OptionConflict::BlockWithExactBurn => "drop --block or --exact-burn",
        OptionConflict::OptionOnStaffingModel => "drop --block, --one-shot and --exact-burn",
    };
    anyhow::anyhow!("{conflict}: {fix}")
}

/// `--dataset N`: the committed `datasets/n{N}.jsonl`, read from the current directory
/// (the repository's root).
fn committed_dataset(n: usize) -> Result<Vec<Instance>> {
    let root = std::path::Path::new(".");
    if !afg_eval::dataset::path(root, n).exists() {
        anyhow::bail!(
            "--dataset {n} reads datasets/n{n}.jsonl under the current directory, which has \
             none: run afg from the repository's root (committed sizes: {:?}), or pass --input FILE",
            afg_eval::dataset::SIZES
        );
    }
    Ok(afg_eval::dataset::load(root, n)?)
}

/// Solves every instance and prints (or writes) the report.
///
/// # Errors
/// Options that do not go together, an unreadable input or model, or a failed write
/// (nothing is written then).
pub fn run(args: SolveArgs) -> Result<()> {
    if args.model.is_none()
        && (args.block.is_some() || args.repair || args.exact_burn || args.one_shot)
    {
        anyhow::bail!(
            "--block, --repair, --one-shot and --exact-burn apply to a learned policy (--model DIR)"
        );
    }
    let (source, mut instances) = match (&args.input, args.dataset) {
        (Some(p), _) => (p.display().to_string(), read_instances(p)?),
        (None, Some(n)) => (format!("datasets/n{n}.jsonl"), committed_dataset(n)?),
        (None, None) => unreachable!("clap requires a source"),
    };
    if let Some(k) = args.limit {
        instances.truncate(k);
    }
    if let Some(from) = &args.from {
        let out = crate::realloc::Outputs {
            out: args.out.as_deref(),
            svg: args.svg.as_deref(),
            json: args.json,
        };
        return crate::realloc::run(args.method, from, &instances, &out);
    }
    crate::warn_unstaffable(&instances);
    let (name, method) = allocator(&args)?;
    let started = exact::started(&args, &instances)?;
    let (against, measuring) = reference(&args, &instances)?;
    let bar = afg_eval::report::progress(
        instances.len() as u64,
        &format!("{name} on {source}{measuring}"),
    );
    let (rows, assignments): (Vec<Row>, Vec<Assignment>) = instances
        .iter()
        .enumerate()
        .map(|(k, inst)| {
            let method = started
                .as_ref()
                .map_or(method.as_ref(), |all| &all[k] as &dyn Allocator);
            let row = Row::compute(inst, method, against);
            bar.inc(1);
            row
        })
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .unzip();
    bar.finish_and_clear();
    // Everything that can fail is done before any file is written.
    let report = Report::new(name.clone(), source, rows)?;
    write_outputs(&args, &name, &instances, &report.rows, &assignments)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    print!("{report}");
    Ok(())
}

/// What the rows are measured against (`--reference-time-limit`, `--no-reference`),
/// and how the progress line says so.
/// The allocator `args` name and its label: a method (the exact one with the limits
/// and a progress line) or a trained model.
fn allocator(args: &SolveArgs) -> Result<(String, Box<dyn Allocator>)> {
    Ok(match (&args.method, &args.model) {
        (Some(m), _) => {
            let exact = exact::solver(args, *m)?;
            let allocator = m
                .allocator_with(args.seed, exact)
                .context("--time-limit / --gap")?;
            (m.to_string(), allocator)
        }
        _ if args.time_limit.is_some() || args.gap.is_some() => {
            anyhow::bail!(
                "--time-limit / --gap: a time limit or a gap is for the exact optimum (method opt) only"
            )
        }
        (None, Some(dir)) => {
            let options = ModelOptions {
                block: args.block,
                repair: args.repair,
                one_shot: args.one_shot,
                exact_burn: args.exact_burn,
            };
            (
                dir.display().to_string(),
                load_model(dir, options).map_err(with_flags)?,
            )
        }
        (None, None) => unreachable!("clap requires an allocator"),
    })
}

fn reference(args: &SolveArgs, instances: &[Instance]) -> Result<(Against, String)> {
    if args.no_reference {
        return Ok((Against::Nothing, String::new()));
    }
    let seconds = args.reference_time_limit;
    let against = Against::optimum_within(seconds).context("--reference-time-limit")?;
    let saying = if instances.iter().any(Instance::has_teams) {
        format!(
            ", measured against the exact optimum (up to {seconds} s each: --reference-time-limit, --no-reference)"
        )
    } else {
        ", measured against the exact optimum".to_owned()
    };
    Ok((against, saying))
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
        afg_game::fs::write_atomic(out, text.as_bytes())?;
    }
    if let Some(svg) = &args.svg {
        let map =
            afg_eval::figures::beside_optimum_svg(&instances[0], "OPT", name, &assignments[0])?;
        write_atomic_making_dirs(svg, map.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// Runs `afg solve ARGS` (arguments separated by single spaces).
    fn solve(args: &str) -> anyhow::Result<()> {
        crate::afg(&format!("solve {args}"))
    }

    /// An empty temporary directory, as a string.
    fn temp(name: &str) -> String {
        let d = std::env::temp_dir().join(format!("afg-solve-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d.to_str().unwrap().to_owned()
    }

    fn instance(robots: usize, tasks: usize, seed: u64) -> afg_game::Instance {
        afg_game::GeneratorConfig::paper(robots, tasks, seed)
            .generate()
            .unwrap()
    }

    #[test]
    fn json_lines_in_assignments_and_a_map_out() {
        let dir = temp("out");
        let (a, b) = (instance(12, 3, 1), instance(9, 3, 2));
        let text = afg_game::io::dataset_to_jsonl(&[a.clone(), b.clone()]);
        std::fs::write(format!("{dir}/mine.jsonl"), text).unwrap();
        solve(&format!(
            "--method da-balanced --input {dir}/mine.jsonl --out {dir}/out.jsonl --svg {dir}/map.svg"
        ))
        .unwrap();
        let text = std::fs::read_to_string(format!("{dir}/out.jsonl")).unwrap();
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
            let welfare = v["summary"]["welfare"].as_f64().unwrap();
            assert!((welfare - inst.welfare(&assignment)).abs() < 1e-9);
            assert_eq!(v["summary"]["stable_balanced"], true);
        }
        let svg = std::fs::read_to_string(format!("{dir}/map.svg")).unwrap();
        assert!(svg.starts_with("<svg"));
        // A single instance file (pretty-printed over many lines) is one instance.
        let value: serde_json::Value = serde_json::from_str(&a.to_json()).unwrap();
        let pretty = serde_json::to_string_pretty(&value).unwrap();
        std::fs::write(format!("{dir}/one.json"), pretty).unwrap();
        solve(&format!(
            "--method greedy --input {dir}/one.json --out {dir}/out.jsonl"
        ))
        .unwrap();
        let text = std::fs::read_to_string(format!("{dir}/out.jsonl")).unwrap();
        assert_eq!(text.lines().count(), 1);
    }

    #[test]
    fn a_bad_line_names_its_line_and_writes_nothing() {
        let dir = temp("bad");
        let a = instance(12, 3, 1).to_json();
        let bad = a.replace("\"eps\":4.0", "\"eps\":1.0");
        assert_ne!(bad, a, "the test must break the third line");
        std::fs::write(format!("{dir}/mine.jsonl"), format!("{a}\n{a}\n{bad}\n")).unwrap();
        let err = solve(&format!(
            "--method opt --input {dir}/mine.jsonl --out {dir}/out.jsonl"
        ))
        .unwrap_err();
        assert!(format!("{err:#}").contains("line 3"), "{err:#}");
        assert!(!std::path::Path::new(&format!("{dir}/out.jsonl")).exists());
        std::fs::write(format!("{dir}/mine.jsonl"), "").unwrap();
        let err = solve(&format!("--method opt --input {dir}/mine.jsonl")).unwrap_err();
        assert!(format!("{err:#}").contains("no instance"), "{err:#}");
    }

    #[test]
    fn bad_options_fail_before_any_file_is_touched() {
        let dir = temp("limit");
        let out = format!("{dir}/keep.jsonl");
        std::fs::write(&out, "precious\n").unwrap();
        for flags in [
            format!("--method greedy --dataset 20 --limit 0 --out {out}"),
            format!("--method greedy --dataset 20 --limit 0 --svg {out}"),
            format!("--method opt --one-shot --dataset 20 --out {out}"),
        ] {
            assert!(solve(&flags).is_err(), "{flags}");
            assert_eq!(std::fs::read_to_string(&out).unwrap(), "precious\n");
        }
        let err = solve("--method greedy --dataset 20 --limit 0").unwrap_err();
        assert!(format!("{err:#}").contains("at least 1"), "{err:#}");
    }

    #[test]
    fn team_games_get_a_bound_and_a_gap_and_a_time_limit_only_with_opt() {
        let dir = temp("teams");
        let file = format!("{dir}/scarce.jsonl");
        crate::afg(&format!(
            "gen --robots 40 --tasks 5 --min-team 8,16 --count 2 --out {file}"
        ))
        .unwrap();
        let out = format!("{dir}/opt.jsonl");
        solve(&format!("--method opt --input {file} --out {out}")).unwrap();
        solve(&format!("--method opt --gap 0 --input {file}")).unwrap();
        let lines = std::fs::read_to_string(&out).unwrap();
        let instances = afg_game::io::read_dataset(std::path::Path::new(&file)).unwrap();
        for (line, inst) in lines.lines().zip(&instances) {
            let a = afg_game::Assignment::from_json(line, inst).unwrap();
            let best = afg_baseline::TeamOptimum::default().solve(inst).unwrap();
            assert!((inst.welfare(&a) - best.welfare).abs() < 1e-9);
        }
        for (flags, needle) in [
            ("--method greedy --time-limit 1", "for the exact optimum"),
            ("--method opt --time-limit -1", "finite and positive"),
            ("--method opt --time-limit 0", "finite and positive"),
            ("--method opt --time-limit nan", "finite and positive"),
            ("--method nearest --gap 0.01", "for the exact optimum"),
            ("--method opt --gap -0.01", "finite, non-negative"),
            ("--method opt --gap inf", "finite, non-negative"),
        ] {
            let err = solve(&format!("{flags} --input {file}")).unwrap_err();
            assert!(format!("{err:#}").contains(needle), "{flags}: {err:#}");
        }
        let skills = format!("{dir}/skills.jsonl");
        crate::afg(&format!(
            "gen --robots 20 --tasks 4 --skills 2 --out {skills}"
        ))
        .unwrap();
        let err = solve(&format!("--method da --input {skills}")).unwrap_err();
        assert!(
            format!("{err:#}").contains("da does not play games with skill requirements"),
            "{err:#}"
        );
    }

    /// `--dataset N` reads the committed file under the current directory; the tests
    /// run in the crate's directory, which has none.
    #[test]
    fn a_dataset_outside_the_repository_says_where_to_run() {
        let err = solve("--method greedy --dataset 20").unwrap_err();
        let message = format!("{err:#}");
        assert!(
            message.contains("datasets/n20.jsonl") && message.contains("repository's root"),
            "{message}"
        );
    }

    #[test]
    fn an_optimum_without_positive_welfare_has_no_percent() {
        let dir = temp("zero");
        let inst = instance(10, 3, 5);
        let tasks = inst
            .tasks()
            .iter()
            .map(|t| afg_game::Task { reward: 0.0, ..*t })
            .collect();
        let zero = afg_game::Instance::new(inst.robots().to_vec(), tasks, 1.0).unwrap();
        zero.write(std::path::Path::new(&format!("{dir}/zero.json")))
            .unwrap();
        solve(&format!(
            "--method greedy --input {dir}/zero.json --out {dir}/out.jsonl"
        ))
        .unwrap();
        let text = std::fs::read_to_string(format!("{dir}/out.jsonl")).unwrap();
        let v: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
        assert!(v["summary"]["percent_of_opt"].is_null(), "{v}");
        assert!(v["summary"]["welfare"].as_f64().unwrap() < 0.0);
    }

    #[test]
    fn warm_start_from_a_previous_assignment() {
        let dir = temp("from");
        instance(40, 5, 3)
            .write(std::path::Path::new(&format!("{dir}/now.json")))
            .unwrap();
        solve(&format!(
            "--method opt --input {dir}/now.json --out {dir}/first.jsonl"
        ))
        .unwrap();
        // The same robots again: nothing moves, nothing is placed.
        solve(&format!(
            "--method da-balanced --input {dir}/now.json --from {dir}/first.jsonl --out {dir}/again.jsonl"
        ))
        .unwrap();
        let text = std::fs::read_to_string(format!("{dir}/again.jsonl")).unwrap();
        let v: serde_json::Value = serde_json::from_str(text.trim()).unwrap();
        let summary = &v["summary"];
        let moved_placed = (summary["moved"].as_u64(), summary["placed"].as_u64());
        assert_eq!(moved_placed, (Some(0), Some(0)));
        let err = solve(&format!(
            "--method opt --input {dir}/now.json --from {dir}/first.jsonl"
        ))
        .unwrap_err();
        assert!(format!("{err:#}").contains("da-balanced"), "{err:#}");
    }

    #[test]
    fn learned_policies_solve_and_bad_options_are_refused() {
        let root = crate::repo_root();
        let model = root.join("models/paper/afgnet_ddqn_n20");
        let model = model.to_str().unwrap();
        let data = |n: usize| format!("--input {}/datasets/n{n}.jsonl", root.display());
        solve(&format!("--model {model} {} --limit 2 --json", data(20))).unwrap();
        solve(&format!(
            "--model {model} {} --limit 1 --block 7 --repair",
            data(100)
        ))
        .unwrap();
        let err = solve(&format!(
            "--model {model} {} --exact-burn --block 3",
            data(20)
        ))
        .unwrap_err();
        let message = format!("{err:#}");
        assert!(
            message.contains("block 1") && message.contains("drop --block"),
            "{message}"
        );
        let err = solve(&format!("--model /nonexistent {}", data(20))).unwrap_err();
        assert!(format!("{err:#}").contains("/nonexistent"), "{err:#}");
        // A method and a model at once, or --block without a model: usage errors.
        assert!(solve(&format!("--method opt --model {model} --dataset 20")).is_err());
        assert!(solve("--method opt --block 2 --dataset 20").is_err());
    }
}
