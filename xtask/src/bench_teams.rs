//! `cargo xtask bench-teams`: the team-threshold game on scarce instances — afg's exact
//! solver (proven optimum, or best found, bound and gap under a time limit), OR-Tools
//! CP-SAT and HiGHS on the same files at their budgets, and every allocator that plays
//! the game, as a share of the best proven bound.

use std::path::{Path, PathBuf};

use std::time::Instant;

use afg_baseline::{AllocError, Allocator, Method, TeamOptimum};
use afg_game::fs::write_atomic;
use afg_game::io::dataset_to_jsonl;
use afg_game::{Family, GeneratorKnobs, Instance};
use anyhow::{Context, Result, bail, ensure};
use clap::Args;
use serde::Serialize;

use crate::bench::runs::{check_python, measure_rows, scratch_dir};
use crate::bench_opt::Case;

mod families;
mod peer;
pub(crate) use peer::{Peer, peer};

/// The options of `cargo xtask bench-teams`.
#[derive(Args)]
pub struct BenchTeamsArgs {
    /// Sizes as N x M; thresholds uniform in [N/M, 2N/M] (scarce: they add up to
    /// about 1.5 N, so not every task can be staffed).
    #[arg(long, value_delimiter = ',', default_values = ["100x10", "300x20", "1000x50"])]
    cases: Vec<Case>,
    /// Instances per size (seeds seed, seed + 1, …).
    #[arg(long, default_value_t = 3)]
    instances: usize,
    /// Seed of the first instance: `afg gen --robots N --tasks M --min-team N/M,2N/M --seed S`.
    #[arg(long, default_value_t = 54)]
    seed: u64,
    #[command(flatten)]
    skills: SkillFlags,
    /// Named families of team games instead of the scarce ones (`afg gen --family`),
    /// e.g. `--families scarce,clustered,heavy-tail` or `--families all`: a table per
    /// family and size of the time to proof beside HiGHS and CP-SAT, and every
    /// allocator's share, worst instance beside the mean.
    #[arg(long, value_delimiter = ',', value_parser = families::parse, conflicts_with = "skills")]
    families: Vec<Vec<Family>>,
    /// afg's time limit per instance, seconds.
    #[arg(long, default_value_t = 10.0)]
    time_limit: f64,
    /// A Python with ortools, highspy and numpy, for the CP-SAT and HiGHS columns (e.g.
    /// after `python3 -m venv .venv-bench && .venv-bench/bin/pip install ortools
    /// highspy numpy`, pass `.venv-bench/bin/python`). Without it they are left out.
    #[arg(long)]
    python: Option<PathBuf>,
    /// Run the peers on sizes up to this N only (their models have N · M variables).
    #[arg(long, default_value_t = 1000)]
    peers_up_to: usize,
    /// Run the allocators on sizes up to this N only (GRAPE DA decentralised grows as N²).
    #[arg(long, default_value_t = 10_000)]
    allocators_up_to: usize,
    /// The peers' time budgets, seconds.
    #[arg(long, value_delimiter = ',', default_values_t = [1.0, 60.0])]
    budgets: Vec<f64>,
    /// Threads of CP-SAT's and HiGHS' own parallel search (default: every core).
    #[arg(long)]
    threads: Option<usize>,
    /// Folder for the instance files (kept); default: a temporary folder.
    #[arg(long)]
    dir: Option<PathBuf>,
    /// Print JSON lines (one per instance) instead of the Markdown tables.
    #[arg(long)]
    json: bool,
}

/// The allocators that play the threshold game (the auction and the learned models
/// refuse it; see docs/teams.md).
pub(crate) const ALLOCATORS: [Method; 6] = [
    Method::Greedy,
    Method::Nearest,
    Method::Da,
    Method::DaDecentralised,
    Method::DaBalanced,
    Method::Random,
];

/// One instance's measurements.
#[derive(Serialize)]
struct Row {
    /// The named family it was drawn from (`None`: the scarce game of the flags).
    #[serde(skip_serializing_if = "Option::is_none")]
    family: Option<Family>,
    robots: usize,
    tasks: usize,
    seed: u64,
    afg: Exact,
    peers: Vec<Peer>,
    /// Each allocator's welfare and seconds; `None` where it found no stable partition
    /// or refused the game (skills); empty above `--allocators-up-to`.
    allocators: Vec<(String, Option<f64>, f64)>,
    /// The lowest proven bound of all exact solvers.
    best_bound: f64,
    /// The best welfare of all exact solvers.
    best_welfare: f64,
}

/// What afg's exact solver did.
#[derive(Serialize)]
struct Exact {
    welfare: f64,
    bound: f64,
    proven: bool,
    nodes: u64,
    seconds: f64,
    peak_rss_mib: Option<f64>,
}

/// Runs `cargo xtask bench-teams`.
pub fn run(args: BenchTeamsArgs) -> Result<()> {
    let dir = scratch_dir(args.dir.as_deref(), "bench-teams")?;
    if let Some(python) = &args.python {
        check_python(python, &["ortools", "highspy", "numpy"])?;
    }
    let seeds = args.seed..args.seed + args.instances as u64;
    let families: Vec<Option<Family>> = match args.families.concat() {
        named if named.is_empty() => vec![None],
        named => named.into_iter().map(Some).collect(),
    };
    let runs: Vec<(Option<Family>, Case, u64)> = families
        .iter()
        .flat_map(|&family| {
            let seeds = seeds.clone();
            args.cases
                .iter()
                .flat_map(move |&case| seeds.clone().map(move |seed| (family, case, seed)))
        })
        .collect();
    let describe = |(family, c, seed): &(Option<Family>, Case, u64)| {
        let family = family.map_or(String::new(), |f| format!("{f} "));
        format!("{family}N = {} M = {} seed {seed}", c.robots, c.tasks)
    };
    let rows = measure_rows(
        "bench-teams",
        &runs,
        args.json,
        describe,
        |&(family, case, seed)| measure(family, case, seed, &args, &dir),
    )?;
    if !args.json {
        if args.families.is_empty() {
            print!("{}", markdown(&rows, &args));
        } else {
            print!("{}", families::markdown(&rows, &args));
        }
    }
    Ok(())
}

/// `--skills`, `--skill-share` and `--requires`: the skills of the scarce games.
#[derive(Args)]
pub struct SkillFlags {
    /// Skill games: S binary skills (each robot holds each with probability
    /// --skill-share), as `afg gen --skills`.
    #[arg(long, value_name = "S")]
    skills: Option<usize>,
    /// With --skills: the probability that a robot holds a skill.
    #[arg(long, default_value_t = GeneratorKnobs::SKILL_SHARE)]
    skill_share: f64,
    /// With --skills: each task requires each skill in an amount uniform in LO..=HI.
    #[arg(long, value_delimiter = ',', num_args = 1, value_names = ["LO,HI"], default_values_t = [1, 2])]
    requires: Vec<usize>,
}

impl SkillFlags {
    /// The generator's skill knobs (`None`: no skills).
    pub fn knobs(&self) -> Result<Option<GeneratorKnobs>> {
        let Some(count) = self.skills else {
            return Ok(None);
        };
        let &[lo, hi] = self.requires.as_slice() else {
            bail!("--requires takes two numbers, LO,HI");
        };
        Ok(Some(GeneratorKnobs {
            skills: Some(count),
            skill_share: Some(self.skill_share),
            requires: Some((lo, hi)),
            ..GeneratorKnobs::default()
        }))
    }

    /// The game the scarce instances are, in words.
    pub fn game_text(&self) -> String {
        match self.skills {
            Some(count) => format!(
                "thresholds uniform in [N/M, 2N/M] and {count} skills (each robot holds each with probability {}, each task requires {}..={} of each)",
                self.skill_share, self.requires[0], self.requires[1]
            ),
            None => "thresholds uniform in [N/M, 2N/M]".to_owned(),
        }
    }
}

/// The scarce threshold instance of `case` and `seed`: thresholds uniform in
/// [N/M, 2N/M], and the skills of `skills` where given.
pub fn scarce(case: Case, seed: u64, skills: Option<&GeneratorKnobs>) -> Result<Instance> {
    let knobs = GeneratorKnobs {
        min_team: Some(case.scarce_thresholds()),
        ..skills.copied().unwrap_or_default()
    };
    Ok(knobs.config(case.robots, case.tasks, seed)?.generate()?)
}

fn measure(
    family: Option<Family>,
    case: Case,
    seed: u64,
    args: &BenchTeamsArgs,
    dir: &Path,
) -> Result<Row> {
    let inst = match family {
        Some(family) => family.config(case.robots, case.tasks, seed)?.generate()?,
        None => scarce(case, seed, args.skills.knobs()?.as_ref())?,
    };
    let name = family.map_or("teams".to_owned(), |f| f.to_string());
    let file = dir.join(format!(
        "{name}_n{}_m{}_seed{seed}.jsonl",
        case.robots, case.tasks
    ));
    write_atomic(
        &file,
        dataset_to_jsonl(std::slice::from_ref(&inst)).as_bytes(),
    )?;
    crate::bench::reset_peak_rss();
    let exact = TeamOptimum::with_time_limit(args.time_limit).context("--time-limit")?;
    let start = Instant::now();
    let one_core = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let exact = one_core.install(|| exact.solve(&inst))?;
    let afg = Exact {
        seconds: start.elapsed().as_secs_f64(),
        peak_rss_mib: crate::bench::peak_rss_mib(),
        welfare: exact.welfare,
        bound: exact.bound,
        proven: exact.proven,
        nodes: exact.nodes,
    };
    let mut peers = Vec::new();
    if let Some(python) = args
        .python
        .as_ref()
        .filter(|_| case.robots <= args.peers_up_to)
    {
        for solver in ["cpsat", "highs"] {
            for &budget in &args.budgets {
                peers.push(peer(python, solver, budget, args.threads, &file, &inst)?);
            }
        }
    }
    let allocators = play(family.is_some(), case, seed, args, &inst)?;
    let best_bound = peers
        .iter()
        .filter_map(|p| p.bound)
        .fold(afg.bound, f64::min);
    let best_welfare = peers
        .iter()
        .filter_map(|p| p.welfare)
        .fold(afg.welfare, f64::max);
    ensure!(
        best_welfare <= best_bound + 1e-6 * best_bound.abs().max(1.0),
        "N = {} M = {} seed {seed}: a solver's welfare {best_welfare} is above a proven bound {best_bound}",
        case.robots,
        case.tasks
    );
    Ok(Row {
        family,
        robots: case.robots,
        tasks: case.tasks,
        seed,
        afg,
        peers,
        allocators,
        best_bound,
        best_welfare,
    })
}

/// Each allocator's welfare (`None`: refused or unsettled) and seconds on `inst`, the
/// committed staffing models too where `staffing`; none above `--allocators-up-to`.
fn play(
    staffing: bool,
    case: Case,
    seed: u64,
    args: &BenchTeamsArgs,
    inst: &Instance,
) -> Result<Vec<(String, Option<f64>, f64)>> {
    let mut players: Vec<(String, Box<dyn Allocator>)> = ALLOCATORS
        .iter()
        .map(|&m| (m.label().to_owned(), m.allocator(seed)))
        .collect();
    if staffing {
        players.extend(families::staffing_models()?);
    }
    players
        .iter()
        .filter(|_| case.robots <= args.allocators_up_to)
        .map(|(label, allocator)| {
            let start = Instant::now();
            let welfare = match allocator.allocate(inst) {
                Ok(out) => Some(inst.welfare(&out.assignment)),
                Err(
                    AllocError::NotConverged { .. }
                    | AllocError::TeamsNotSupported { .. }
                    | AllocError::VoidNotSupported { .. },
                ) => None,
                Err(e) => return Err(e.into()),
            };
            Ok((label.clone(), welfare, start.elapsed().as_secs_f64()))
        })
        .collect()
}

/// The peers' columns of the tables, in the first row's order: each solver's name as
/// printed and its budget.
fn peer_columns(rows: &[Row]) -> Vec<(&'static str, f64)> {
    let name = |solver: &str| if solver == "cpsat" { "CP-SAT" } else { "HiGHS" };
    rows.first()
        .map(|r| {
            r.peers
                .iter()
                .map(|p| (name(&p.solver), p.budget))
                .collect()
        })
        .unwrap_or_default()
}

/// Means over a case's rows.
fn mean(rows: &[&Row], f: impl Fn(&Row) -> f64) -> f64 {
    rows.iter().map(|r| f(r)).sum::<f64>() / rows.len() as f64
}

/// `100 · welfare / bound` as printed.
fn percent(welfare: f64, bound: f64) -> f64 {
    100.0 * welfare / bound
}

fn markdown(rows: &[Row], args: &BenchTeamsArgs) -> String {
    let cases: Vec<Vec<&Row>> = args
        .cases
        .iter()
        .map(|c| {
            rows.iter()
                .filter(|r| (r.robots, r.tasks) == (c.robots, c.tasks))
                .collect()
        })
        .collect();
    let k = args.instances;
    let game = args.skills.game_text();
    let mut md = format!(
        "Game: {game}.\n\nExact solvers ({k} scarce instance{} per size; % of the best proven bound, mean; \
         proven: instances proven optimal; afg with a {}s limit on one core):\n\n| N | M | afg time | afg proven | afg % of bound | afg nodes | afg peak RSS |",
        if k == 1 { "" } else { "s" },
        args.time_limit
    );
    let peer_names = peer_columns(rows);
    for (name, budget) in &peer_names {
        md += &format!(" {name} {budget}s: proven | % of bound | time |");
    }
    md += "\n|---|---|---|---|---|---|---|";
    md += &"---|---|---|".repeat(peer_names.len());
    md.push('\n');
    for rows in cases.iter().filter(|r| !r.is_empty()) {
        let r0 = rows[0];
        let proven = rows.iter().filter(|r| r.afg.proven).count();
        md += &format!(
            "| {} | {} | {:.3} s | {proven}/{k} | {:.3} | {:.0} | {} |",
            r0.robots,
            r0.tasks,
            mean(rows, |r| r.afg.seconds),
            mean(rows, |r| percent(r.afg.welfare, r.best_bound)),
            mean(rows, |r| r.afg.nodes as f64),
            r0.afg
                .peak_rss_mib
                .map_or("—".into(), |m| format!("{m:.0} MiB")),
        );
        for (p, _) in peer_names.iter().enumerate() {
            if rows.iter().any(|r| r.peers.len() <= p) {
                md += " — | — | — |"; // above --peers-up-to
                continue;
            }
            let proven = rows
                .iter()
                .filter(|r| r.peers[p].status == "optimal")
                .count();
            let found = rows.iter().all(|r| r.peers[p].welfare.is_some());
            let share = if found {
                format!(
                    "{:.3}",
                    mean(rows, |r| percent(
                        r.peers[p].welfare.unwrap_or(0.0),
                        r.best_bound
                    ))
                )
            } else {
                "none found".into()
            };
            md += &format!(
                " {proven}/{k} | {share} | {:.2} s |",
                mean(rows, |r| r.peers[p].seconds)
            );
        }
        md.push('\n');
    }
    md + "\n" + &allocator_table(&cases, k)
}

/// The allocators' table: each one's welfare as a share of the best proven bound
/// (none where every size is above `--allocators-up-to`).
fn allocator_table(cases: &[Vec<&Row>], k: usize) -> String {
    if cases.iter().flatten().all(|r| r.allocators.is_empty()) {
        return String::new();
    }
    let mut md =
        "Allocators (% of the best proven bound, mean; time per instance):\n\n| N | M |".to_owned();
    let names: Vec<&str> = ALLOCATORS.iter().map(|m| m.label()).collect();
    for name in &names {
        md += &format!(" {name} |");
    }
    md += "\n|---|---|";
    md += &"---|".repeat(names.len());
    md.push('\n');
    for rows in cases
        .iter()
        .filter(|r| !r.is_empty() && !r[0].allocators.is_empty())
    {
        md += &format!("| {} | {} |", rows[0].robots, rows[0].tasks);
        for a in 0..names.len() {
            let settled = rows.iter().filter(|r| r.allocators[a].1.is_some()).count();
            let cell = if settled == rows.len() {
                format!(
                    "{:.1} % ({:.1} ms)",
                    mean(rows, |r| percent(
                        r.allocators[a].1.unwrap_or(0.0),
                        r.best_bound
                    )),
                    1e3 * mean(rows, |r| r.allocators[a].2)
                )
            } else {
                format!("refused or unsettled on {}/{k}", rows.len() - settled)
            };
            md += &format!(" {cell} |");
        }
        md.push('\n');
    }
    md
}
