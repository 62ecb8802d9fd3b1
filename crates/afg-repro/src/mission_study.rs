//! The mission study (`cargo xtask mission-study`): allocators in the loop of missions
//! of each preset, from scratch and warm-started, without and with decision latency;
//! one Markdown table per preset and latency.

use afg_baseline::Method;
use afg_eval::EvalError;
use afg_eval::mission::{Planner, compare, table};
use afg_mission::{Latency, MissionConfig, Preset, RunOptions};

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
        let missions = (0..plan.count)
            .map(|seed| MissionConfig::new(preset, plan.robots, plan.tasks, seed).generate())
            .collect::<Result<Vec<_>, _>>()?;
        for &latency in &latencies {
            let options = RunOptions {
                latency,
                ..RunOptions::default()
            };
            let rows: Vec<_> = compare(&missions, &planners, options, &mut on_run)?
                .into_iter()
                .map(|(row, _)| row)
                .collect();
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
