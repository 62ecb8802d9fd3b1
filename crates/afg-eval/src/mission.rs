//! Allocators in missions, as the front ends name them: a [`Planner`] (a built-in
//! method or a trained model, from scratch or warm-started) and the table of
//! [`compare`] (several planners on the same missions).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

use afg_baseline::{Allocator, Method, SwarmMethod};
use afg_game::Preference;
use afg_graph::GraphKind;
use afg_learn::run::{ModelOptions, load_model};
use afg_mission::{Decentralised, Metrics, Mission, MissionRun, Replan, RunOptions, simulate_with};
use serde::Serialize;

use crate::EvalError;
use crate::report::duration;

/// The methods a mission comparison runs unless told otherwise.
pub const DEFAULT_METHODS: &str = "opt,da,da-balanced,greedy,nearest";

/// A method in a mission, as the front ends name it: a built-in allocator deciding
/// centrally, or `grape` / `auction`: GRAPE or the auction run by the robots
/// themselves over the radio.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_eval::mission::MissionMethod;
/// assert_eq!("grape".parse::<MissionMethod>()?, MissionMethod::Grape);
/// assert_eq!("auction".parse::<MissionMethod>()?, MissionMethod::Auction);
/// assert_eq!("greedy".parse::<MissionMethod>()?, MissionMethod::Central(Method::Greedy));
/// assert!("gpare".parse::<MissionMethod>().unwrap_err().contains("grape"));
/// # Ok::<(), String>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MissionMethod {
    /// A built-in allocator deciding for every robot at each decision.
    Central(Method),
    /// GRAPE run by the robots over the radio, each on its own view.
    Grape,
    /// The consensus-based auction run by the robots over the radio.
    Auction,
}

impl MissionMethod {
    /// The decentralised method this names — GRAPE with `preference`, or the auction
    /// with bid increment `epsilon` — or `None` for a central allocator.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{Method, SwarmMethod};
    /// use afg_eval::mission::MissionMethod;
    /// use afg_game::Preference;
    /// let auction = MissionMethod::Auction.swarm(Preference::Selfish, 1e-3);
    /// assert!(matches!(auction, Some(SwarmMethod::Auction { epsilon }) if epsilon == 1e-3));
    /// assert!(MissionMethod::Central(Method::Opt).swarm(Preference::Selfish, 1e-3).is_none());
    /// ```
    pub fn swarm(self, preference: Preference, epsilon: f64) -> Option<SwarmMethod> {
        match self {
            MissionMethod::Central(_) => None,
            MissionMethod::Grape => Some(SwarmMethod::Grape { preference }),
            MissionMethod::Auction => Some(SwarmMethod::Auction { epsilon }),
        }
    }
}

impl std::str::FromStr for MissionMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "grape" => Ok(MissionMethod::Grape),
            "auction" => Ok(MissionMethod::Auction),
            _ => s.parse().map(MissionMethod::Central).map_err(|e: String| {
                format!("{e}, or grape or auction (decentralised, over the radio)")
            }),
        }
    }
}

impl std::fmt::Display for MissionMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MissionMethod::Central(method) => method.fmt(f),
            MissionMethod::Grape => f.write_str("grape"),
            MissionMethod::Auction => f.write_str("auction"),
        }
    }
}

/// An allocator in the loop and how it replans.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_eval::mission::Planner;
/// use afg_mission::{MissionConfig, Preset, RunOptions};
/// let mission = MissionConfig::new(Preset::Waves, 30, 6, 1).generate()?;
/// let opt = Planner::method(Method::Opt, 0, true);
/// assert_eq!(opt.name(), "opt (incremental)");
/// let run = opt.run(&mission, RunOptions::default())?;
/// assert!(run.metrics.tasks_done > 0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Planner {
    name: String,
    rule: Rule,
}

/// Who decides: an allocator for everyone, or each robot over the radio.
enum Rule {
    Central {
        allocator: Box<dyn Allocator>,
        method: Option<Method>,
        warm: bool,
    },
    Swarm(Decentralised),
}

impl Planner {
    /// A built-in method (seeded where it draws); `warm`: warm-started decisions
    /// ([`Planner::replan`]).
    pub fn method(method: Method, seed: u64, warm: bool) -> Self {
        Planner {
            name: method.to_string(),
            rule: Rule::Central {
                allocator: method.allocator(seed),
                method: Some(method),
                warm,
            },
        }
    }

    /// A decentralised method run by the robots inside the mission, named with its
    /// radio: `grape (swarm, r 0.12, loss 30 %)`.
    pub fn swarm(config: Decentralised) -> Self {
        let mut name = match config.method {
            SwarmMethod::Grape { .. } => "grape (swarm".to_string(),
            SwarmMethod::Auction { .. } => "auction (swarm".to_string(),
        };
        match config.network.graph {
            GraphKind::Radius { radius } => write!(name, ", r {radius:.3}"),
            GraphKind::Knn { k } => write!(name, ", {k}-NN"),
            GraphKind::Complete => write!(name, ", all linked"),
        }
        .expect("writing to a string");
        if config.network.loss > 0.0 {
            let _ = write!(name, ", loss {:.0} %", 100.0 * config.network.loss);
        }
        if let Some(range) = config.sensing {
            let _ = write!(name, ", sensing {range}");
        }
        name.push(')');
        Planner {
            name,
            rule: Rule::Swarm(config),
        }
    }

    /// A trained model's run directory (a Q network or a price model).
    ///
    /// # Errors
    /// The model's loading errors.
    pub fn model(dir: &Path, options: ModelOptions, warm: bool) -> Result<Self, EvalError> {
        let allocator = load_model(dir, options)?;
        Ok(Planner {
            name: allocator.name(),
            rule: Rule::Central {
                allocator,
                method: None,
                warm,
            },
        })
    }

    /// The planner's name in tables: the method's, with "(incremental)" for the
    /// warm-started optimum, "(warm)" for other warm starts and "(swarm)" for a
    /// decentralised method.
    pub fn name(&self) -> String {
        match self.rule {
            Rule::Central {
                warm: true,
                method: Some(Method::Opt),
                ..
            } => format!("{} (incremental)", self.name),
            Rule::Central { warm: true, .. } => format!("{} (warm)", self.name),
            _ => self.name.clone(),
        }
    }

    /// The replanning rule: from scratch; or, warm-started, the optimum re-solved from
    /// its previous prices, and for every other method its answer at the first
    /// decision and then survivors kept and best-response dynamics (GRAPE's selfish
    /// ones for `da`, balanced for the rest); a decentralised method runs as itself.
    pub fn replan(&self) -> Replan<'_> {
        let (first, warm, method) = match &self.rule {
            Rule::Swarm(config) => return Replan::Decentralised(config),
            Rule::Central {
                allocator,
                method,
                warm,
            } => (allocator.as_ref(), *warm, *method),
        };
        match (warm, method) {
            (false, _) => Replan::Scratch(first),
            (true, Some(Method::Opt)) => Replan::IncrementalOpt,
            (true, Some(Method::Da | Method::DaDecentralised)) => Replan::Warm {
                first,
                preference: Preference::Selfish,
            },
            (true, _) => Replan::Warm {
                first,
                preference: Preference::Balanced,
            },
        }
    }

    /// Runs `mission` with this planner.
    ///
    /// # Errors
    /// The simulator's errors.
    pub fn run(&self, mission: &Mission, options: RunOptions) -> Result<MissionRun, EvalError> {
        self.run_with(mission, options, |_| {})
    }

    /// [`Planner::run`], telling `on_time` the mission time after every event.
    ///
    /// # Errors
    /// The simulator's errors.
    pub fn run_with(
        &self,
        mission: &Mission,
        options: RunOptions,
        on_time: impl FnMut(f64),
    ) -> Result<MissionRun, EvalError> {
        Ok(simulate_with(mission, self.replan(), options, on_time)?)
    }
}

/// One planner's metrics on each mission.
#[derive(Clone, Debug, Serialize)]
pub struct CompareRow {
    /// The planner's name.
    pub method: String,
    /// Each mission's metrics.
    pub missions: Vec<Metrics>,
}

/// Runs every planner on every mission (in order).
///
/// # Errors
/// The simulator's errors.
pub fn compare(
    missions: &[Mission],
    planners: &[Planner],
    options: RunOptions,
    mut on_run: impl FnMut(),
) -> Result<Vec<(CompareRow, Vec<MissionRun>)>, EvalError> {
    planners
        .iter()
        .map(|p| {
            let runs = missions
                .iter()
                .map(|m| {
                    let run = p.run(m, options);
                    on_run();
                    run
                })
                .collect::<Result<Vec<_>, _>>()?;
            let row = CompareRow {
                method: p.name(),
                missions: runs.iter().map(|r| r.metrics.clone()).collect(),
            };
            Ok((row, runs))
        })
        .collect()
}

/// The Markdown table of [`compare`]'s rows: means over the missions.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_eval::mission::{Planner, compare, table};
/// use afg_mission::{MissionConfig, Preset, RunOptions};
/// let missions = vec![MissionConfig::new(Preset::Poisson, 20, 5, 1).generate()?];
/// let planners = [Planner::method(Method::Greedy, 0, false), Planner::method(Method::Opt, 0, true)];
/// let rows: Vec<_> = compare(&missions, &planners, RunOptions::default(), || {})?
///     .into_iter().map(|(row, _)| row).collect();
/// let text = table(&rows);
/// assert!(text.contains("| greedy |") && text.contains("| opt (incremental) |"));
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
/// use afg_baseline::{Method, Network, SwarmMethod};
/// use afg_eval::mission::{Planner, compare, swarm_table};
/// use afg_game::Preference;
/// use afg_mission::{Decentralised, MissionConfig, Preset, RunOptions};
/// let missions = vec![MissionConfig::new(Preset::Waves, 20, 4, 1).generate()?];
/// let grape = Decentralised::new(SwarmMethod::Grape { preference: Preference::Selfish }, Network::default());
/// let planners = [Planner::method(Method::Greedy, 0, false), Planner::swarm(grape)];
/// let rows: Vec<_> = compare(&missions, &planners, RunOptions::default(), || {})?
///     .into_iter().map(|(row, _)| row).collect();
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
