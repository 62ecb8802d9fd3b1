//! `afg mission`: missions over time — `gen` draws one, `run` plays one allocator in
//! the loop, `compare` plays several on the same missions (docs/missions.md).

use std::path::{Path, PathBuf};

use afg_eval::figures::{mission_html, mission_svg};
use afg_eval::mission::{CompareRow, compare, planner, swarm_table, table, teams_table};
use afg_game::fs::{write_atomic, write_atomic_making_dirs};
use afg_game::{Named, Preference};
use afg_mission::{
    Latency, Mission, MissionKnobs, MissionMethod, MissionPlan, Planner, Preset, Recording,
    SwarmKnobs,
};

use crate::swarm::RadioArgs;
use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};

mod output;
use output::{note, print_metrics, still};

/// `afg mission`'s commands.
#[derive(Subcommand)]
pub enum MissionCommand {
    /// Draw a mission: robots and K tasks arriving over it by a preset, with every knob.
    Gen(GenArgs),
    /// Run one allocator in the loop and print the mission's metrics.
    Run(RunArgs),
    /// Run several allocators on the same missions: one table (and curves with --svg).
    Compare(CompareArgs),
}

/// `afg mission gen`: the preset, its knobs and the output file.
#[derive(Args)]
pub struct GenArgs {
    /// How tasks arrive: static (all at 0), waves, poisson, attrition (waves, and robots fail).
    #[arg(long, value_parser = crate::choice::<Preset>())]
    preset: Preset,
    /// Robots N.
    #[arg(long)]
    robots: usize,
    /// Tasks K over the whole mission.
    #[arg(long)]
    tasks: usize,
    /// Seed of the ChaCha8 generator.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Workloads are uniform in [LO, HI] (one robot does 1 unit per time unit).
    #[arg(long, value_delimiter = ',', num_args = 1, value_names = ["LO,HI"], default_value = DEFAULT_WORKLOAD.as_str())]
    workload: Vec<f64>,
    /// Every robot's speed (arena units per time unit).
    #[arg(long, default_value_t = MissionKnobs::default().speed)]
    speed: f64,
    /// The arena's side: positions uniform in [0, arena]², β scaled by 1/arena.
    #[arg(long, default_value_t = MissionKnobs::default().arena)]
    arena: f64,
    /// The mission ends at this time at the latest.
    #[arg(long, default_value_t = MissionKnobs::default().horizon)]
    horizon: f64,
    /// Waves of tasks (waves, attrition).
    #[arg(long, default_value_t = MissionKnobs::default().waves)]
    waves: usize,
    /// Time between waves.
    #[arg(long, default_value_t = MissionKnobs::default().interval)]
    interval: f64,
    /// Task arrivals per time unit (poisson; default K / 20).
    #[arg(long)]
    rate: Option<f64>,
    /// Share of the robots that fail (attrition), at times uniform over the whole
    /// horizon: a run that ends earlier (every task done) sees only the failures before
    /// its end, so set --horizon near the mission's span to see them all.
    #[arg(long, default_value_t = MissionKnobs::default().fail_share)]
    fail_share: f64,
    /// Task capacities as `afg gen --capacity-slack` draws them (s ≥ 1).
    #[arg(long)]
    capacity_slack: Option<f64>,
    /// Robots may idle (the void task) when no task is worth their trip.
    #[arg(long)]
    allow_void: bool,
    #[command(flatten)]
    teams: crate::generate::TeamArgs,
    /// The mission file to write (JSON).
    #[arg(long)]
    out: PathBuf,
}

/// The allocator in the loop and the run's options, shared by `run` and `compare`:
/// mapped one to one onto a [`MissionPlan`] (defaults from [`MissionPlan::default`]).
#[derive(Args)]
pub struct LoopArgs {
    /// Warm start: the optimum re-solved from its previous prices (opt), or survivors
    /// keeping their task and best-response dynamics settling the rest (others).
    #[arg(long)]
    warm: bool,
    /// Also decide every T time units, not only at events.
    #[arg(long, value_name = "T")]
    replan: Option<f64>,
    /// Each decision takes D time units of mission time.
    #[arg(long, value_name = "D", conflicts_with = "latency_factor")]
    latency: Option<f64>,
    /// Each decision takes the allocator's measured compute time times F (mission time
    /// units per second): not reproducible run to run.
    #[arg(long, value_name = "F")]
    latency_factor: Option<f64>,
    /// Commitment: robots at work stay until their task is done.
    #[arg(long)]
    commit: bool,
    /// Hysteresis: a travelling robot switches task only for a gain above THETA
    /// (balanced score, in the game's welfare units).
    #[arg(long, value_name = "THETA")]
    hysteresis: Option<f64>,
    /// The exact optimum's time limit per decision, seconds (opt without --warm): each
    /// decision takes the best found, its certified gap in the trace and the metrics'
    /// largest gap.
    #[arg(long, value_name = "SECS", allow_negative_numbers = true)]
    time_limit: Option<f64>,
    /// Seed of the random method, and of GRAPE's draws and the radio's (grape).
    #[arg(long, default_value_t = MissionPlan::default().seed)]
    seed: u64,
    #[command(flatten)]
    swarm: SwarmArgs,
}

/// The knobs of `grape` and `auction`, run by the robots over the radio
/// (docs/missions.md); refused with a central method.
#[derive(Args)]
#[command(next_help_heading = "Decentralised over the radio (--method grape or auction)")]
pub struct SwarmArgs {
    /// Rounds per mission time unit.
    #[arg(long, default_value_t = SwarmKnobs::default().rounds_per_time)]
    rounds_per_time: f64,
    /// Long-run share of messages lost.
    #[arg(long, default_value_t = SwarmKnobs::default().radio.loss)]
    loss: f64,
    /// Robots see tasks within this distance and hear of the others from their
    /// neighbours [default: every robot hears of every task at once].
    #[arg(long)]
    sensing: Option<f64>,
    /// GRAPE's preference: selfish (GRAPE's own) or balanced.
    #[arg(long, value_parser = crate::choice::<Preference>(), default_value = SwarmKnobs::default().preference.name())]
    preference: Preference,
    /// The auction's least price increment ε: 0.001, or 0.01 where a mission's tasks
    /// need teams or skills (docs/teams.md) [default: by the mission].
    #[arg(long)]
    epsilon: Option<f64>,
    #[command(flatten)]
    radio: RadioArgs,
}

impl LoopArgs {
    /// The plan of `method` with these options, for `missions` (the auction's default
    /// ε depends on them).
    fn plan(&self, method: MissionMethod, missions: &[Mission]) -> Result<MissionPlan> {
        let latency = Latency::from_knobs(self.latency, self.latency_factor)?;
        let knobs = &self.swarm;
        Ok(MissionPlan {
            method,
            warm: self.warm,
            seed: self.seed,
            swarm: SwarmKnobs {
                preference: knobs.preference,
                epsilon: (knobs.epsilon).unwrap_or_else(|| {
                    SwarmKnobs::default_epsilon(method, missions.iter().any(Mission::needs_teams))
                }),
                radio: knobs.radio.knobs(knobs.loss),
                rounds_per_time: knobs.rounds_per_time,
                sensing: knobs.sensing,
            },
            replan_every: self.replan,
            latency,
            commit: self.commit,
            hysteresis: self.hysteresis,
            time_limit: self.time_limit,
        })
    }
}

/// `afg mission run`: one mission, one allocator.
#[derive(Args)]
pub struct RunArgs {
    /// The mission file (`afg mission gen --out`).
    #[arg(long)]
    mission: PathBuf,
    /// The allocator (ignored with --model), or grape / auction: GRAPE or the auction
    /// run by the robots themselves over the radio.
    #[arg(long, default_value_t = MissionPlan::default().method)]
    method: MissionMethod,
    /// A trained model's run directory instead of a built-in method.
    #[arg(long)]
    model: Option<PathBuf>,
    /// Print the metrics as JSON.
    #[arg(long)]
    json: bool,
    /// Write every event and decision as JSON Lines.
    #[arg(long)]
    trace: Option<PathBuf>,
    /// Write an animation of the run: a self-contained HTML page (opens in a browser,
    /// no server), robots coloured by task moving, tasks sized by the work left.
    #[arg(long)]
    animate: Option<PathBuf>,
    /// Write one moment of the run as a PNG image (the animation's drawing without its
    /// text): at --still-at, or else where the most robots wait for their team.
    #[arg(long)]
    still: Option<PathBuf>,
    /// The mission time of --still (the recorded moment nearest to it).
    #[arg(long, requires = "still")]
    still_at: Option<f64>,
    #[command(flatten)]
    looping: LoopArgs,
}

/// `afg mission compare`: several allocators on the same missions.
#[derive(Args)]
pub struct CompareArgs {
    /// Mission files.
    #[arg(long, num_args = 1.., required = true)]
    mission: Vec<PathBuf>,
    /// The allocators, comma-separated (grape, auction: run by the robots over the radio).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = afg_eval::mission::DEFAULT_METHODS
    )]
    methods: Vec<MissionMethod>,
    /// Trained models' run directories, run beside the methods.
    #[arg(long, num_args = 1..)]
    model: Vec<PathBuf>,
    /// Print JSON (each method's metrics per mission) instead of the table.
    #[arg(long)]
    json: bool,
    /// Draw the first mission's tasks open, tasks done and reward against time.
    #[arg(long)]
    svg: Option<PathBuf>,
    #[command(flatten)]
    looping: LoopArgs,
}

/// Runs `afg mission …`.
///
/// # Errors
/// A bad knob or file, or an allocator that fails.
pub fn run(command: MissionCommand) -> Result<()> {
    match command {
        MissionCommand::Gen(args) => generate(&args),
        MissionCommand::Run(args) => run_one(&args),
        MissionCommand::Compare(args) => run_compare(&args),
    }
}

/// `LO,HI` of the default workloads, for `--workload`.
static DEFAULT_WORKLOAD: std::sync::LazyLock<String> = std::sync::LazyLock::new(|| {
    let (lo, hi) = MissionKnobs::default().workload;
    format!("{lo},{hi}")
});

fn generate(args: &GenArgs) -> Result<()> {
    let &[lo, hi] = args.workload.as_slice() else {
        bail!("--workload takes two numbers, LO,HI");
    };
    let knobs = MissionKnobs {
        workload: (lo, hi),
        speed: args.speed,
        arena: args.arena,
        horizon: args.horizon,
        waves: args.waves,
        interval: args.interval,
        rate: args.rate,
        fail_share: args.fail_share,
        capacity_slack: args.capacity_slack,
        allow_void: args.allow_void,
        min_team: args.teams.min_team()?,
        skills: args.teams.skills,
        skill_share: args.teams.skill_share,
        requires: args.teams.requires()?,
    };
    let config = knobs.config(args.preset, args.robots, args.tasks, args.seed);
    let mission = config.generate()?;
    crate::warn_unstaffable_tasks("mission", &[mission.unstaffable_tasks()]);
    write_atomic(&args.out, (mission.to_json() + "\n").as_bytes())?;
    println!(
        "wrote {} ({} robots, {} tasks, {} failures, horizon {})",
        args.out.display(),
        mission.robots.len(),
        mission.tasks.len(),
        mission.failures.len(),
        mission.horizon
    );
    Ok(())
}

fn read_mission(path: &Path) -> Result<Mission> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Mission::from_json(&text).with_context(|| path.display().to_string())
}

fn run_one(args: &RunArgs) -> Result<()> {
    let inputs: Vec<&Path> = std::iter::once(args.mission.as_path())
        .chain(args.model.as_deref())
        .collect();
    let outputs = [
        ("trace", args.trace.as_deref()),
        ("animate", args.animate.as_deref()),
        ("still", args.still.as_deref()),
    ];
    crate::refuse_overwriting_inputs(&outputs, &inputs)?;
    let mission = read_mission(&args.mission)?;
    let plan = (args.looping).plan(args.method, std::slice::from_ref(&mission))?;
    note(std::slice::from_ref(&plan), std::slice::from_ref(&mission));
    let planner = planner(&plan, args.model.as_deref())?;
    let mut recording = Recording {
        trace: args.trace.is_some(),
        frame_every: None,
    };
    if let Some(t) = args.still_at
        && !(t.is_finite() && t >= 0.0)
    {
        anyhow::bail!("--still-at must be a finite time ≥ 0, not {t}");
    }
    if args.animate.is_some() || args.still.is_some() {
        // Frames enough for a smooth page, few enough to keep it a few megabytes.
        let frames = (2_000_000 / mission.robots.len().max(1)).clamp(20, 400);
        recording.frame_every = Some(mission.horizon / frames as f64);
    }
    // The bar counts mission time (in thousandths of the horizon, the run's latest end)
    // and fills when the run ends, early or not.
    let horizon = mission.horizon;
    let bar = afg_eval::report::progress(1000, "mission time");
    let run = planner.run(&mission, recording, |t| {
        bar.set_message(format!("mission time {t:.2} of at most {horizon}"));
        bar.set_position((1000.0 * t / horizon) as u64);
    })?;
    bar.set_message(format!("mission ended at {:.2}", run.metrics.end));
    bar.set_position(1000);
    bar.finish_and_clear();
    if let Some(path) = &args.animate {
        let title = format!("{} on {}", planner.name(), args.mission.display());
        write_atomic_making_dirs(path, mission_html(&mission, &run, &title)?.as_bytes())?;
    }
    if let Some(path) = &args.still {
        write_atomic_making_dirs(path, &still(&mission, &run, args.still_at)?)?;
    }
    if let Some(path) = &args.trace {
        write_atomic_making_dirs(path, run.trace_jsonl().as_bytes())?;
    }
    if args.json {
        println!("{}", serde_json::to_string(&run.metrics)?);
    } else {
        print_metrics(planner.name(), &args.mission, &run);
        if args.looping.latency_factor.is_some() {
            println!(
                "  (measured latency: mission times depend on this machine, not reproducible run to run)"
            );
        }
    }
    Ok(())
}

fn run_compare(args: &CompareArgs) -> Result<()> {
    let inputs: Vec<&Path> = args
        .mission
        .iter()
        .chain(&args.model)
        .map(PathBuf::as_path)
        .collect();
    crate::refuse_overwriting_inputs(&[("svg", args.svg.as_deref())], &inputs)?;
    let missions = args
        .mission
        .iter()
        .map(|p| read_mission(p))
        .collect::<Result<Vec<_>>>()?;
    let plans = (args.methods.iter())
        .map(|&m| args.looping.plan(m, &missions))
        .collect::<Result<Vec<_>>>()?;
    note(&plans, &missions);
    let mut planners: Vec<Planner> = plans
        .iter()
        .map(|plan| Ok(planner(plan, None)?))
        .collect::<Result<_>>()?;
    let models = args
        .model
        .iter()
        .map(|dir| {
            Ok(planner(
                &args.looping.plan(MissionMethod::default(), &missions)?,
                Some(dir),
            )?)
        })
        .collect::<Result<Vec<_>>>()?;
    // Rows of the same name (two models of the same kind): theirs say which directory.
    let names: Vec<String> = (planners.iter().chain(&models))
        .map(|p| p.name().to_string())
        .collect();
    for (model, dir) in models.into_iter().zip(&args.model) {
        let name = model.name().to_string();
        let shared = names.iter().filter(|n| **n == name).count() > 1;
        planners.push(if shared {
            model.named(format!("{name} ({})", dir.display()))
        } else {
            model
        });
    }
    let bar = afg_eval::report::progress((missions.len() * planners.len()) as u64, "missions");
    let compared = compare(&missions, &planners, Recording::default(), || bar.inc(1))?;
    bar.finish_and_clear();
    // A method that does not play the missions' rules is named, and the others shown.
    for (method, why) in &compared.refused {
        eprintln!("note: {method} left out: {why}");
    }
    if compared.rows.is_empty() {
        bail!("every method refused the missions");
    }
    let results = compared.rows;
    if let Some(path) = &args.svg {
        let curves = results
            .iter()
            .map(|(row, runs)| (row.method.clone(), runs[0].clone()))
            .collect::<Vec<_>>();
        let title = format!("{} (first mission)", args.mission[0].display());
        write_atomic_making_dirs(path, mission_svg(&curves, &title)?.as_bytes())?;
    }
    let rows: Vec<_> = results.into_iter().map(|(row, _)| row).collect();
    print_compared(&rows, missions.len(), args)
}

/// `afg mission compare`'s rows: JSON, or the tables (the radio's and the teams' where
/// they apply).
fn print_compared(rows: &[CompareRow], missions: usize, args: &CompareArgs) -> Result<()> {
    if args.json {
        println!("{}", serde_json::to_string(rows)?);
        return Ok(());
    }
    let measured = if args.looping.latency_factor.is_some() {
        " (measured latency: not reproducible run to run)"
    } else {
        ""
    };
    println!("{missions} mission(s), means over them{measured}\n");
    print!("{}", table(rows));
    if let Some(swarms) = swarm_table(rows) {
        println!("\nOver the radio:\n\n{swarms}");
    }
    if let Some(teams) = teams_table(rows) {
        println!("\nTeams:\n\n{teams}");
    }
    Ok(())
}
