//! The mission study (`cargo xtask mission-study`): allocators in the loop of missions
//! of each preset, from scratch and warm-started, without and with decision latency;
//! one Markdown table per preset and latency.
//!
//! `cargo xtask mission-study`: allocators in the loop of generated missions, as the
//! Markdown tables of docs/missions.md.

use afg_baseline::Method;
use afg_eval::EvalError;
use afg_eval::mission::{CompareRow, compare, swarm_table, table};
use afg_mission::{
    Latency, Mission, MissionConfig, MissionMethod, MissionPlan, Planner, Preset, RadioKnobs,
    SwarmKnobs,
};

/// The study's missions and allocators.
#[derive(Clone, Debug, PartialEq)]
pub struct CentralStudy {
    /// Robots N.
    pub robots: usize,
    /// Tasks K over each mission.
    pub tasks: usize,
    /// Missions per preset (seeds `0..count`).
    pub count: u64,
    /// The presets.
    pub presets: Vec<Preset>,
    /// The allocators, each from scratch and warm-started.
    pub methods: Vec<Method>,
    /// A fixed decision latency to run beside none (time units), if any.
    pub latency: Option<f64>,
}

/// Runs the study: a table per preset (and latency).
///
/// # Errors
/// [`EvalError::BadOptions`] for no missions; the generator's and simulator's errors.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_mission::Preset;
/// use xtask::mission_study::{CentralStudy, study};
/// let plan = CentralStudy {
///     robots: 20, tasks: 6, count: 1, presets: vec![Preset::Waves],
///     methods: vec![Method::Greedy], latency: None,
/// };
/// let text = study(&plan, || {})?;
/// assert!(text.contains("| greedy |") && text.contains("| greedy (warm) |"));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn study(plan: &CentralStudy, mut on_run: impl FnMut()) -> Result<String, EvalError> {
    if plan.count == 0 {
        return Err(EvalError::BadOptions(
            "the study needs at least one mission",
        ));
    }
    let latencies: Vec<Latency> = std::iter::once(Latency::None)
        .chain(plan.latency.map(|delay| Latency::Fixed { delay }))
        .collect();
    let mut out = String::new();
    for &preset in &plan.presets {
        let missions = missions(preset, plan.robots, plan.tasks, plan.count)?;
        for &latency in &latencies {
            let planners = [false, true]
                .into_iter()
                .flat_map(|warm| {
                    plan.methods.iter().map(move |&m| MissionPlan {
                        method: MissionMethod::Central(m),
                        warm,
                        latency,
                        ..MissionPlan::default()
                    })
                })
                .map(|p| p.planner())
                .collect::<Result<Vec<Planner>, _>>()?;
            let rows = rows(&missions, &planners, &mut on_run)?;
            let delay = match latency {
                Latency::Fixed { delay } => format!(", each decision {delay} time units late"),
                _ => String::new(),
            };
            out.push_str(&format!(
                "**{}**, N = {}, K = {}, {} mission(s){delay}\n\n{}\n",
                afg_game::Named::name(preset),
                plan.robots,
                plan.tasks,
                plan.count,
                table(&rows)
            ));
        }
    }
    Ok(out)
}

/// Missions of `preset` with seeds `0..count`.
fn missions(
    preset: Preset,
    robots: usize,
    tasks: usize,
    count: u64,
) -> Result<Vec<Mission>, EvalError> {
    Ok((0..count)
        .map(|seed| MissionConfig::new(preset, robots, tasks, seed).generate())
        .collect::<Result<Vec<_>, _>>()?)
}

/// Every planner's row on `missions`.
fn rows(
    missions: &[Mission],
    planners: &[Planner],
    on_run: impl FnMut(),
) -> Result<Vec<CompareRow>, EvalError> {
    let compared = compare(missions, planners, Default::default(), on_run)?;
    if let Some((method, why)) = compared.refused.first() {
        return Err(EvalError::Mission(afg_mission::MissionError::Invalid(
            format!("{method} refused a study mission: {why}"),
        )));
    }
    Ok(compared.rows.into_iter().map(|(row, _)| row).collect())
}

/// The radius at which N robots uniform in the unit square become connected (with
/// high probability): `sqrt(ln N / (π N))`.
///
/// # Examples
/// ```
/// let r = xtask::mission_study::connectivity_radius(100);
/// assert!((r - 0.1211).abs() < 1e-4);
/// ```
pub fn connectivity_radius(robots: usize) -> f64 {
    let n = robots.max(2) as f64;
    (n.ln() / (std::f64::consts::PI * n)).sqrt()
}

/// The decentralised study: GRAPE and the auction run by the robots over the radio,
/// beside the central optimum and GRAPE's centralised twin (both warm-started).
#[derive(Clone, Debug, PartialEq)]
pub struct SwarmStudy {
    /// Robots N.
    pub robots: usize,
    /// Tasks K over each mission.
    pub tasks: usize,
    /// Missions per preset (seeds `0..count`).
    pub count: u64,
    /// The presets.
    pub presets: Vec<Preset>,
    /// Communication radii, as multiples of [`connectivity_radius`].
    pub radius_factors: Vec<f64>,
    /// Shares of messages lost.
    pub losses: Vec<f64>,
    /// The decentralised methods ([`MissionMethod::Grape`], [`MissionMethod::Auction`]),
    /// with the default [`SwarmKnobs`] but the radius, loss and rounds per time unit.
    pub methods: Vec<MissionMethod>,
    /// Their rounds per time unit.
    pub rounds_per_time: f64,
}

/// Runs the decentralised study: per preset, the mission table and the radio's.
///
/// # Errors
/// [`EvalError::BadOptions`] for no missions; the generator's and simulator's errors.
///
/// # Examples
/// ```
/// use afg_mission::{MissionMethod, Preset};
/// use xtask::mission_study::{SwarmStudy, swarm_study};
/// let plan = SwarmStudy {
///     robots: 20, tasks: 4, count: 1, presets: vec![Preset::Waves],
///     radius_factors: vec![2.0], losses: vec![0.0, 0.3], rounds_per_time: 50.0,
///     methods: vec![MissionMethod::Grape],
/// };
/// let text = swarm_study(&plan, || {})?;
/// assert!(text.contains("| opt (warm) |") && text.contains("loss 30 %)"));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn swarm_study(plan: &SwarmStudy, mut on_run: impl FnMut()) -> Result<String, EvalError> {
    if plan.count == 0 {
        return Err(EvalError::BadOptions(
            "the study needs at least one mission",
        ));
    }
    let warm = |method| MissionPlan {
        method: MissionMethod::Central(method),
        warm: true,
        ..MissionPlan::default()
    };
    let mut planners = vec![warm(Method::Opt).planner()?, warm(Method::Da).planner()?];
    let threshold = connectivity_radius(plan.robots);
    for &method in &plan.methods {
        for (&factor, &loss) in
            (plan.radius_factors.iter()).flat_map(|f| plan.losses.iter().map(move |l| (f, l)))
        {
            let swarm = SwarmKnobs {
                radio: RadioKnobs {
                    radius: Some(factor * threshold),
                    loss,
                    ..RadioKnobs::default()
                },
                rounds_per_time: plan.rounds_per_time,
                ..SwarmKnobs::default()
            };
            let plan = MissionPlan {
                method,
                swarm,
                ..MissionPlan::default()
            };
            planners.push(plan.planner()?);
        }
    }
    let mut out = String::new();
    for &preset in &plan.presets {
        let missions = missions(preset, plan.robots, plan.tasks, plan.count)?;
        let rows = rows(&missions, &planners, &mut on_run)?;
        out.push_str(&format!(
            "**{}**, N = {}, K = {}, {} mission(s); over the radio at {} rounds per time unit, radius in multiples of the connectivity radius {threshold:.3}\n\n{}\n{}\n",
            afg_game::Named::name(preset),
            plan.robots,
            plan.tasks,
            plan.count,
            plan.rounds_per_time,
            table(&rows),
            swarm_table(&rows).unwrap_or_default(),
        ));
    }
    Ok(out)
}

// The command.
use afg_game::Named as _;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Args;

/// The study's missions and allocators.
#[derive(Args)]
pub struct MissionStudyArgs {
    /// Robots N.
    #[arg(long, default_value_t = 100)]
    robots: usize,
    /// Tasks K over each mission.
    #[arg(long, default_value_t = 40)]
    tasks: usize,
    /// Missions per preset (seeds 0..count).
    #[arg(long, default_value_t = 5)]
    count: u64,
    /// The presets, comma-separated.
    #[arg(long, value_delimiter = ',', value_parser = |name: &str| Preset::from_name(name).map_err(|e| e.to_string()), default_value = "waves,poisson,attrition")]
    presets: Vec<Preset>,
    /// The allocators, comma-separated (each from scratch and warm-started).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = afg_eval::mission::DEFAULT_METHODS
    )]
    methods: Vec<Method>,
    /// Also run every mission with each decision this many time units late.
    #[arg(long)]
    latency: Option<f64>,
    /// The decentralised study instead: GRAPE and the auction run by the robots over
    /// the radio beside the central optimum and GRAPE's centralised twin (warm-started).
    #[arg(long, conflicts_with_all = ["methods", "latency"])]
    swarm: bool,
    /// Communication radii as multiples of the connectivity radius sqrt(ln N / (π N)) (--swarm).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    radius_factors: Vec<f64>,
    /// Shares of messages lost (--swarm).
    #[arg(long, value_delimiter = ',', default_value = "0,0.3")]
    losses: Vec<f64>,
    /// The decentralised methods (--swarm), comma-separated: grape, auction.
    #[arg(long, value_delimiter = ',', default_value = "grape,auction")]
    swarm_methods: Vec<String>,
    /// Rounds per time unit (--swarm).
    #[arg(long, default_value_t = SwarmKnobs::default().rounds_per_time)]
    rounds_per_time: f64,
    /// Instead of printing the tables, check that FILE shows them (every number but
    /// the compute times, which are the machine's) under the line `$ cargo xtask
    /// mission-study …` with these same arguments.
    #[arg(long, value_name = "FILE")]
    verify: Option<PathBuf>,
}

/// Runs the study and prints its tables.
pub fn run(args: MissionStudyArgs) -> Result<()> {
    if args.swarm {
        return run_swarm(args);
    }
    let plan = CentralStudy {
        robots: args.robots,
        tasks: args.tasks,
        count: args.count,
        presets: args.presets,
        methods: args.methods,
        latency: args.latency,
    };
    let runs = plan.presets.len() as u64
        * plan.count
        * 2
        * plan.methods.len() as u64
        * (1 + u64::from(plan.latency.is_some()));
    let bar = afg_eval::report::progress(runs, "missions");
    let text = study(&plan, || bar.inc(1))?;
    bar.finish_and_clear();
    show(&text, args.verify.as_deref())
}

/// The decentralised study.
fn run_swarm(args: MissionStudyArgs) -> Result<()> {
    let plan = SwarmStudy {
        robots: args.robots,
        tasks: args.tasks,
        count: args.count,
        presets: args.presets,
        radius_factors: args.radius_factors,
        losses: args.losses,
        methods: args
            .swarm_methods
            .iter()
            .map(|name| match name.parse() {
                Ok(m @ (MissionMethod::Grape | MissionMethod::Auction)) => Ok(m),
                _ => bail!("unknown decentralised method '{name}': grape or auction"),
            })
            .collect::<Result<_>>()?,
        rounds_per_time: args.rounds_per_time,
    };
    let runs = plan.presets.len() as u64
        * plan.count
        * (2 + (plan.methods.len() * plan.radius_factors.len() * plan.losses.len()) as u64);
    let bar = afg_eval::report::progress(runs, "missions");
    let text = swarm_study(&plan, || bar.inc(1))?;
    bar.finish_and_clear();
    show(&text, args.verify.as_deref())
}

/// Prints `text`, or checks it against the block of `verify` under this command.
fn show(text: &str, verify: Option<&Path>) -> Result<()> {
    let Some(path) = verify else {
        print!("{text}");
        return Ok(());
    };
    // The command as the page shows it: these arguments without `--verify FILE`.
    let args: Vec<String> = std::env::args().skip(1).collect();
    let at = args
        .iter()
        .position(|a| a == "--verify")
        .unwrap_or(args.len());
    let shown: Vec<&str> = (args.iter().enumerate())
        .filter(|&(i, _)| i != at && i != at + 1)
        .map(|(_, a)| a.as_str())
        .collect();
    let command = format!("$ cargo xtask {}", shown.join(" "));
    let page = std::fs::read_to_string(path)?;
    verify_block(&page, &command, text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    println!("{}: the tables under `{command}` match", path.display());
    Ok(())
}

/// Checks that the code block of `page` opened by the line `command` holds `text`,
/// compute times (cells ending in a unit of time) aside.
fn verify_block(page: &str, command: &str, text: &str) -> Result<()> {
    let mut lines = page.lines().skip_while(|l| l.trim_end() != command);
    if lines.next().is_none() {
        bail!("no line `{command}`");
    }
    let shown: Vec<String> = lines
        .take_while(|l| !l.starts_with("```"))
        .map(untimed)
        .collect();
    let computed: Vec<String> = text.lines().map(untimed).collect();
    let shown = shown.join("\n");
    let computed = computed.join("\n");
    if shown.trim_end() != computed.trim_end() {
        let first = (shown.lines().zip(computed.lines()))
            .find(|(a, b)| a != b)
            .map_or_else(String::new, |(a, b)| {
                format!(": the page shows\n  {a}\nthe command gives\n  {b}")
            });
        bail!(
            "the tables under `{command}` differ from what it gives{first}\n(rerun it and paste its output)"
        );
    }
    Ok(())
}

/// A table row with its compute times (`12.3 µs`, `4.5 ms`, `1.2 s`) masked.
fn untimed(line: &str) -> String {
    if !line.starts_with('|') {
        return line.trim_end().to_string();
    }
    line.split('|')
        .map(|cell| {
            let timed = ["ns", "µs", "ms", "s"].iter().any(|unit| {
                cell.trim()
                    .strip_suffix(unit)
                    .is_some_and(|v| v.trim_end().parse::<f64>().is_ok() && v.ends_with(' '))
            });
            if timed { " … " } else { cell }
        })
        .collect::<Vec<_>>()
        .join("|")
}

#[cfg(test)]
mod tests {
    use super::{untimed, verify_block};

    const PAGE: &str =
        "text\n```\n$ cargo xtask mission-study --count 1\n| a | 1.50 | 3.2 µs |\n```\n";

    #[test]
    fn a_block_matches_but_its_compute_times_and_nothing_else() {
        assert_eq!(
            untimed("| a | 1.50 | 3.2 µs | 4 s |"),
            "| a | 1.50 | … | … |"
        );
        let command = "$ cargo xtask mission-study --count 1";
        verify_block(PAGE, command, "| a | 1.50 | 9.9 ms |\n").unwrap();
        let err = verify_block(PAGE, command, "| a | 1.51 | 3.2 µs |\n").unwrap_err();
        assert!(err.to_string().contains("| a | 1.50 |"), "{err}");
        assert!(verify_block(PAGE, "$ cargo xtask mission-study", "").is_err());
    }
}
