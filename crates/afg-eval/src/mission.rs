//! Allocators in missions, as the front ends name them: the [`Planner`] of a
//! [`MissionPlan`] (a built-in method or a trained model, from scratch or
//! warm-started, or a swarm over the radio) and the table of [`compare`] (several
//! planners on the same missions).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

use afg_learn::run::{ModelOptions, load_model};
use afg_mission::{Metrics, Mission, MissionPlan, MissionRun, Planner, Recording};
use serde::Serialize;

use crate::EvalError;
use crate::report::duration;

/// The methods a mission comparison runs unless told otherwise.
pub const DEFAULT_METHODS: &str = "opt,da,da-balanced,greedy,nearest";

/// The planner of `plan`, or, given a trained model's run directory (a Q network or a
/// price model), of that model deciding under `plan`.
///
/// # Errors
/// The plan's checks ([`MissionPlan::planner`]) and the model's loading errors.
///
/// # Examples
/// ```
/// use afg_eval::mission::planner;
/// use afg_mission::{MissionMethod, MissionPlan};
/// let plan = MissionPlan { method: "greedy".parse::<MissionMethod>()?, warm: true, ..MissionPlan::default() };
/// assert_eq!(planner(&plan, None)?.name(), "greedy (warm)");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn planner(plan: &MissionPlan, model: Option<&Path>) -> Result<Planner, EvalError> {
    Ok(match model {
        Some(dir) => plan.planner_with(load_model(dir, ModelOptions::default())?)?,
        None => plan.planner()?,
    })
}

/// One planner's metrics on each mission.
#[derive(Clone, Debug, Serialize)]
pub struct CompareRow {
    /// The planner's name.
    pub method: String,
    /// Each mission's metrics.
    pub missions: Vec<Metrics>,
}

/// What [`compare`] ran: each planner's row and runs, in order, and the planners that
/// refused a mission (their name and why) — a comparison goes on without them.
#[derive(Debug)]
pub struct Comparison {
    /// Each planner that played every mission: its row and its runs.
    pub rows: Vec<(CompareRow, Vec<MissionRun>)>,
    /// Each planner that refused a mission (a method that does not play its rules):
    /// its name and the refusal.
    pub refused: Vec<(String, String)>,
}

/// The refusal of a game's rules by a method (not a failure) that `error` is, if it is
/// one.
fn refusal(error: &afg_mission::MissionError) -> Option<&afg_baseline::AllocError> {
    use afg_baseline::AllocError::TeamsNotSupported;
    use afg_mission::MissionError::{Alloc, Decision};
    match error {
        Alloc(refused @ TeamsNotSupported { .. })
        | Decision {
            source: refused @ TeamsNotSupported { .. },
            ..
        } => Some(refused),
        _ => None,
    }
}

/// Runs every planner on every mission (in order); a planner that refuses a mission
/// is left out of the rows and named in [`Comparison::refused`].
///
/// # Errors
/// The simulator's errors other than refusals.
pub fn compare(
    missions: &[Mission],
    planners: &[Planner],
    recording: Recording,
    mut on_run: impl FnMut(),
) -> Result<Comparison, EvalError> {
    let mut compared = Comparison {
        rows: Vec::new(),
        refused: Vec::new(),
    };
    'planners: for p in planners {
        let mut runs = Vec::with_capacity(missions.len());
        for m in missions {
            let run = p.run(m, recording, |_| {});
            on_run();
            match run {
                Ok(run) => runs.push(run),
                Err(e) => {
                    let Some(why) = refusal(&e).map(ToString::to_string) else {
                        return Err(e.into());
                    };
                    compared.refused.push((p.name().to_string(), why));
                    continue 'planners;
                }
            }
        }
        let row = CompareRow {
            method: p.name().to_string(),
            missions: runs.iter().map(|r| r.metrics.clone()).collect(),
        };
        compared.rows.push((row, runs));
    }
    Ok(compared)
}

/// The Markdown table of [`compare`]'s rows: means over the missions.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_eval::mission::{compare, table};
/// use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset};
/// let missions = vec![MissionConfig::new(Preset::Poisson, 20, 5, 1).generate()?];
/// let greedy = MissionPlan { method: MissionMethod::Central(Method::Greedy), ..MissionPlan::default() };
/// let warm_opt = MissionPlan { warm: true, ..MissionPlan::default() };
/// let planners = [greedy.planner()?, warm_opt.planner()?];
/// let rows: Vec<_> = compare(&missions, &planners, Default::default(), || {})?
///     .rows.into_iter().map(|(row, _)| row).collect();
/// let text = table(&rows);
/// assert!(text.contains("| greedy |") && text.contains("| opt (warm) |"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn table(rows: &[CompareRow]) -> String {
    let mut out = String::from(
        "| method | tasks done | reward done, % of all | latency mean | p95 | max | makespan | distance | reassignments | decisions | compute / decision | compute max |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for row in rows {
        let k = row.missions.len().max(1) as f64;
        let mean = |f: &dyn Fn(&Metrics) -> f64| row.missions.iter().map(f).sum::<f64>() / k;
        let opt_mean = |f: &dyn Fn(&Metrics) -> Option<f64>| {
            let values: Vec<f64> = row.missions.iter().filter_map(f).collect();
            if values.len() == row.missions.len() && !values.is_empty() {
                format!("{:.2}", values.iter().sum::<f64>() / values.len() as f64)
            } else {
                "—".into()
            }
        };
        let compute_max = row
            .missions
            .iter()
            .map(|m| m.compute_max_s)
            .fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "| {} | {:.2} / {:.0} | {:.2} % | {} | {} | {} | {} | {:.2} | {:.1} | {:.1} | {} | {} |",
            row.method,
            mean(&|m| m.tasks_done as f64),
            mean(&|m| m.tasks as f64),
            100.0 * mean(&|m| m.reward_done / m.reward_total),
            opt_mean(&|m| m.latency_mean),
            opt_mean(&|m| m.latency_p95),
            opt_mean(&|m| m.latency_max),
            opt_mean(&|m| m.makespan),
            mean(&|m| m.distance),
            mean(&|m| m.reassignments as f64),
            mean(&|m| m.decisions as f64),
            duration(Duration::from_secs_f64(mean(&|m| m.compute_mean_s))),
            duration(Duration::from_secs_f64(compute_max)),
        );
    }
    out
}

/// The Markdown table of what the decentralised rows of [`compare`] add (rounds,
/// traffic, response times; means over the missions), or `None` if no row is
/// decentralised.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_eval::mission::{compare, swarm_table};
/// use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset};
/// let missions = vec![MissionConfig::new(Preset::Waves, 20, 4, 1).generate()?];
/// let plan = |method| MissionPlan { method, ..MissionPlan::default() };
/// let planners = [plan(MissionMethod::Central(Method::Greedy)).planner()?, plan(MissionMethod::Grape).planner()?];
/// let rows: Vec<_> = compare(&missions, &planners, Default::default(), || {})?
///     .rows.into_iter().map(|(row, _)| row).collect();
/// let text = swarm_table(&rows).expect("one row is decentralised");
/// assert!(text.contains("| grape (swarm, 10-NN) |") && !text.contains("| greedy |"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn swarm_table(rows: &[CompareRow]) -> Option<String> {
    let mut out = String::from(
        "| method | rounds | messages / robot | kB on the air / robot | response mean | response max | events never settled |\n|---|---|---|---|---|---|---|\n",
    );
    let mut any = false;
    for row in rows {
        let swarms: Vec<&afg_mission::SwarmMetrics> = row
            .missions
            .iter()
            .filter_map(|m| m.swarm.as_ref())
            .collect();
        if swarms.is_empty() {
            continue;
        }
        any = true;
        let k = swarms.len() as f64;
        let mean = |f: &dyn Fn(&afg_mission::SwarmMetrics, f64) -> f64| {
            swarms
                .iter()
                .map(|s| f(s, s.robots.max(1) as f64))
                .sum::<f64>()
                / k
        };
        let settled: Vec<f64> = swarms.iter().filter_map(|s| s.response_mean).collect();
        let response = if settled.is_empty() {
            "—".to_string()
        } else {
            format!("{:.3}", settled.iter().sum::<f64>() / settled.len() as f64)
        };
        let max = (swarms.iter())
            .filter_map(|s| s.response_max)
            .reduce(f64::max)
            .map_or("—".into(), |v| format!("{v:.3}"));
        let _ = writeln!(
            out,
            "| {} | {:.0} | {:.0} | {:.1} | {response} | {max} | {:.1} |",
            row.method,
            mean(&|s, _| s.rounds as f64),
            mean(&|s, n| s.messages as f64 / n),
            mean(&|s, n| s.bytes as f64 / n / 1e3),
            mean(&|s, _| s.unsettled as f64),
        );
    }
    any.then_some(out)
}

/// The Markdown table of what missions with teams add (the robot-time spent waiting
/// for a team, and the exact solver's largest gap where it decided; means over the
/// missions), or `None` if no mission has teams.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_eval::mission::{compare, teams_table};
/// use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset};
/// let mut config = MissionConfig::new(Preset::Waves, 20, 4, 1);
/// config.min_team = Some(afg_game::CountRange { min: 2, max: 4 });
/// let missions = vec![config.generate()?];
/// let plan = |method| MissionPlan { method, ..MissionPlan::default() };
/// let planners = [plan(MissionMethod::Central(Method::Opt)).planner()?];
/// let rows: Vec<_> = compare(&missions, &planners, Default::default(), || {})?
///     .rows.into_iter().map(|(row, _)| row).collect();
/// assert!(teams_table(&rows).expect("a mission with teams").contains("| opt | "));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn teams_table(rows: &[CompareRow]) -> Option<String> {
    let mut out = String::from(
        "| method | robot-time waiting for a team | exact solver's largest gap |\n|---|---|---|\n",
    );
    let mut any = false;
    for row in rows {
        let waiting: Vec<f64> = (row.missions.iter())
            .filter_map(|m| m.waiting.as_ref().map(|w| w.total))
            .collect();
        if waiting.is_empty() {
            continue;
        }
        any = true;
        let gap = (row.missions.iter())
            .filter_map(|m| m.gap_max)
            .reduce(f64::max)
            .map_or("—".into(), |g| format!("{:.4} %", 100.0 * g));
        let _ = writeln!(
            out,
            "| {} | {:.3} | {gap} |",
            row.method,
            waiting.iter().sum::<f64>() / waiting.len() as f64
        );
    }
    any.then_some(out)
}
