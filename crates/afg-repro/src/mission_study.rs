//! The mission study (`cargo xtask mission-study`): allocators in the loop of missions
//! of each preset, from scratch and warm-started, without and with decision latency;
//! one Markdown table per preset and latency.

use afg_baseline::{Method, Network, SwarmMethod};
use afg_eval::EvalError;
use afg_eval::mission::{CompareRow, Planner, compare, swarm_table, table};
use afg_graph::GraphKind;
use afg_mission::{Decentralised, Latency, Mission, MissionConfig, Preset, RunOptions};

/// The study's missions and allocators.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionPlan {
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
/// use afg_repro::mission_study::{MissionPlan, study};
/// let plan = MissionPlan {
///     robots: 20, tasks: 6, count: 1, presets: vec![Preset::Waves],
///     methods: vec![Method::Greedy], latency: None,
/// };
/// let text = study(&plan, || {})?;
/// assert!(text.contains("| greedy |") && text.contains("| greedy (warm) |"));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn study(plan: &MissionPlan, mut on_run: impl FnMut()) -> Result<String, EvalError> {
    if plan.count == 0 {
        return Err(EvalError::BadOptions(
            "the study needs at least one mission",
        ));
    }
    let planners: Vec<Planner> = [false, true]
        .into_iter()
        .flat_map(|warm| {
            plan.methods
                .iter()
                .map(move |&m| Planner::method(m, 0, warm))
        })
        .collect();
    let latencies: Vec<Latency> = std::iter::once(Latency::None)
        .chain(plan.latency.map(|delay| Latency::Fixed { delay }))
        .collect();
    let mut out = String::new();
    for &preset in &plan.presets {
        let missions = missions(preset, plan.robots, plan.tasks, plan.count)?;
        for &latency in &latencies {
            let options = RunOptions {
                latency,
                ..RunOptions::default()
            };
            let rows = rows(&missions, &planners, options, &mut on_run)?;
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
    options: RunOptions,
    on_run: impl FnMut(),
) -> Result<Vec<CompareRow>, EvalError> {
    Ok(compare(missions, planners, options, on_run)?
        .into_iter()
        .map(|(row, _)| row)
        .collect())
}

/// The radius at which N robots uniform in the unit square become connected (with
/// high probability): `sqrt(ln N / (π N))`.
///
/// # Examples
/// ```
/// let r = afg_repro::mission_study::connectivity_radius(100);
/// assert!((r - 0.1211).abs() < 1e-4);
/// ```
pub fn connectivity_radius(robots: usize) -> f64 {
    let n = robots.max(2) as f64;
    (n.ln() / (std::f64::consts::PI * n)).sqrt()
}

/// The decentralised study: GRAPE and the auction run by the robots over the radio,
/// beside the central optimum and GRAPE's centralised twin (both warm-started).
#[derive(Clone, Debug, PartialEq)]
pub struct SwarmPlan {
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
    /// The decentralised methods.
    pub methods: Vec<SwarmMethod>,
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
/// use afg_baseline::SwarmMethod;
/// use afg_game::Preference;
/// use afg_mission::Preset;
/// use afg_repro::mission_study::{SwarmPlan, swarm_study};
/// let plan = SwarmPlan {
///     robots: 20, tasks: 4, count: 1, presets: vec![Preset::Waves],
///     radius_factors: vec![2.0], losses: vec![0.0, 0.3], rounds_per_time: 50.0,
///     methods: vec![SwarmMethod::Grape { preference: Preference::Selfish }],
/// };
/// let text = swarm_study(&plan, || {})?;
/// assert!(text.contains("| opt (incremental) |") && text.contains("loss 30 %)"));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn swarm_study(plan: &SwarmPlan, mut on_run: impl FnMut()) -> Result<String, EvalError> {
    if plan.count == 0 {
        return Err(EvalError::BadOptions(
            "the study needs at least one mission",
        ));
    }
    let mut planners = vec![
        Planner::method(Method::Opt, 0, true),
        Planner::method(Method::Da, 0, true),
    ];
    let threshold = connectivity_radius(plan.robots);
    for &method in &plan.methods {
        for (&factor, &loss) in
            (plan.radius_factors.iter()).flat_map(|f| plan.losses.iter().map(move |l| (f, l)))
        {
            let network = Network {
                graph: GraphKind::Radius {
                    radius: factor * threshold,
                },
                loss,
                ..Network::default()
            };
            planners.push(Planner::swarm(Decentralised {
                rounds_per_time: plan.rounds_per_time,
                ..Decentralised::new(method, network)
            }));
        }
    }
    let mut out = String::new();
    for &preset in &plan.presets {
        let missions = missions(preset, plan.robots, plan.tasks, plan.count)?;
        let rows = rows(&missions, &planners, RunOptions::default(), &mut on_run)?;
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
