//! The mission study (`cargo xtask mission-study`): allocators in the loop of missions
//! of each preset, from scratch and warm-started, without and with decision latency;
//! one Markdown table per preset and latency.

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
/// use afg_repro::mission_study::{CentralStudy, study};
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
    Ok(compare(missions, planners, Default::default(), on_run)?
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
/// use afg_repro::mission_study::{SwarmStudy, swarm_study};
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
