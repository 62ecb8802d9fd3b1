//! The one front door of a mission run: a [`MissionPlan`] says everything about who
//! decides and how, and [`Planner::run`] runs it. The command line (`afg mission
//! run|compare`), Python (`afg.run_mission`) and the maintainer's studies only map
//! their flags or keyword arguments onto a plan.

use std::fmt::Write as _;

use afg_baseline::{Allocator, Method, SwarmMethod};
use afg_game::Preference;
use afg_graph::GraphKind;

mod knobs;
pub use knobs::{RadioKnobs, SwarmKnobs};

use crate::sim::{
    Decentralised, Replan, RunOptions, check_frame_every, check_options, run_checked,
};
use crate::{Latency, Mission, MissionError, MissionRun};

/// A method in a mission, as the front ends name it: a built-in allocator deciding
/// centrally, or `grape` / `auction`: GRAPE or the auction run by the robots
/// themselves over the radio.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_mission::MissionMethod;
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

impl Default for MissionMethod {
    /// The exact optimum, deciding centrally.
    fn default() -> Self {
        MissionMethod::Central(Method::Opt)
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

/// Everything about who decides in a mission and how: the method, warm or not, the
/// seed, the swarm's knobs and the central decisions' options. [`MissionPlan::planner`]
/// checks it once and gives the [`Planner`] that runs it.
///
/// # Examples
/// ```
/// use afg_mission::{Latency, MissionConfig, MissionMethod, MissionPlan, Preset};
/// let mission = MissionConfig::new(Preset::Waves, 30, 6, 1).generate()?;
/// let plan = MissionPlan { warm: true, latency: Latency::Fixed { delay: 0.5 }, ..MissionPlan::default() };
/// let planner = plan.planner()?;
/// assert_eq!(planner.name(), "opt (warm)");
/// let run = planner.run(&mission, Default::default(), |_| {})?;
/// assert!(run.metrics.decisions >= 1);
/// // A radio knob is for the robots' own methods: refused with a central one.
/// let mut radio = MissionPlan::default();
/// radio.swarm.radio.loss = 0.3;
/// let refused = radio.planner().err().expect("a radio knob with a central method");
/// assert!(refused.to_string().contains("loss is for grape"));
/// // With GRAPE, it runs.
/// radio.method = MissionMethod::Grape;
/// assert!(radio.planner()?.name().starts_with("grape (swarm"));
/// # Ok::<(), afg_mission::MissionError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MissionPlan {
    /// Who decides (ignored by [`MissionPlan::planner_with`], whose allocator decides).
    pub method: MissionMethod,
    /// Warm start: the optimum re-solved from its previous prices (opt), or survivors
    /// keeping their task and best-response dynamics settling the rest (others).
    pub warm: bool,
    /// Seeds the random method, and GRAPE's, the auction's and the radio's draws.
    pub seed: u64,
    /// The knobs of `grape` and `auction`.
    pub swarm: SwarmKnobs,
    /// Also decide every this many time units, not only at events (central only).
    pub replan_every: Option<f64>,
    /// How long a central decision takes.
    pub latency: Latency,
    /// Commitment: robots at work stay until their task is done (central only).
    pub commit: bool,
    /// Hysteresis: a travelling robot switches task only for a gain above this
    /// (central only).
    pub hysteresis: Option<f64>,
    /// The exact optimum's time limit per decision, seconds (`opt` from scratch only):
    /// each decision takes the best found and records its certified gap.
    pub time_limit: Option<f64>,
}

impl Default for MissionPlan {
    /// The exact optimum from scratch at every event, seed 0, no latency.
    fn default() -> Self {
        MissionPlan {
            method: MissionMethod::default(),
            warm: false,
            seed: 0,
            swarm: SwarmKnobs::default(),
            replan_every: None,
            latency: Latency::None,
            commit: false,
            hysteresis: None,
            time_limit: None,
        }
    }
}

/// What a run keeps besides its metrics and timeline.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Recording {
    /// Keep every event and decision ([`MissionRun::trace`]).
    pub trace: bool,
    /// Snapshot the whole state every this many time units ([`MissionRun::frames`]).
    pub frame_every: Option<f64>,
}

impl MissionPlan {
    /// Advice on running this plan on `mission` that is not an error: the auction at
    /// ε = 0.001 (the paper's game's default; the front ends give team missions 0.01,
    /// [`SwarmKnobs::default_epsilon`]) on a mission whose tasks need teams or skills
    /// fills the teams slowly (its robots beyond the teams bid in steps of ε).
    ///
    /// # Examples
    /// ```
    /// use afg_mission::{Mission, MissionConfig, MissionMethod, MissionPlan, Preset};
    /// let mut config = MissionConfig::new(Preset::Static, 8, 2, 1);
    /// config.min_team = Some(afg_game::CountRange { min: 2, max: 3 });
    /// let mission = config.generate()?;
    /// let mut plan = MissionPlan { method: MissionMethod::Auction, ..MissionPlan::default() };
    /// assert!(plan.advice(&mission).unwrap().contains("--epsilon 0.01"));
    /// plan.swarm.epsilon = 0.01;
    /// assert!(plan.advice(&mission).is_none());
    /// # Ok::<(), afg_mission::MissionError>(())
    /// ```
    pub fn advice(&self, mission: &Mission) -> Option<String> {
        let default = SwarmKnobs::default().epsilon;
        (self.method == MissionMethod::Auction
            && self.swarm.epsilon == default
            && mission.needs_teams())
        .then(|| {
            format!(
                "the auction on a mission whose tasks need teams or skills wants --epsilon 0.01 or more \
                 (epsilon=0.01 in Python, the default there; at {default} its robots fill the teams slowly: docs/teams.md)"
            )
        })
    }

    /// The planner of a built-in method (or GRAPE or the auction over the radio).
    ///
    /// # Errors
    /// [`MissionError::Invalid`] for a knob out of range, a radio knob with a central
    /// method, or a central option (replanning, latency, commitment, hysteresis) with
    /// a decentralised one.
    pub fn planner(&self) -> Result<Planner, MissionError> {
        let decider = match self.method {
            MissionMethod::Central(method) => {
                if self.time_limit.is_some() && self.warm {
                    return Err(MissionError::Invalid(
                        "a time limit is for the exact optimum solved from scratch (without --warm)"
                            .into(),
                    ));
                }
                let allocator = (method.exact(self.time_limit, None))
                    .and_then(|exact| method.allocator_with(self.seed, exact))
                    .map_err(|e| MissionError::Invalid(e.to_string()))?;
                return self.central(allocator, Some(method));
            }
            MissionMethod::Grape => SwarmMethod::Grape {
                preference: self.swarm.preference,
            },
            MissionMethod::Auction => SwarmMethod::Auction {
                epsilon: self.swarm.epsilon,
            },
        };
        self.check()?;
        if let Some(option) = self.central_options().first() {
            return Err(MissionError::Invalid(format!(
                "{option} is for central decisions; a decentralised method runs at its rounds per time unit"
            )));
        }
        let knobs = &self.swarm;
        Ok(Planner {
            name: swarm_name(decider, knobs),
            decider: Decider::Swarm(Decentralised {
                method: decider,
                network: knobs.radio.network(),
                rounds_per_time: knobs.rounds_per_time,
                sensing: knobs.sensing,
                seed: self.seed,
            }),
            options: self.options(),
        })
    }

    /// The planner of an allocator passed in (a trained model, say), deciding
    /// centrally under this plan; the plan's method is not used.
    ///
    /// # Errors
    /// As [`MissionPlan::planner`] for a central method.
    pub fn planner_with(&self, allocator: Box<dyn Allocator>) -> Result<Planner, MissionError> {
        if self.time_limit.is_some() {
            return Err(MissionError::Invalid(
                "a time limit is for the exact optimum (method opt), not a model".into(),
            ));
        }
        self.central(allocator, None)
    }

    fn central(
        &self,
        allocator: Box<dyn Allocator>,
        method: Option<Method>,
    ) -> Result<Planner, MissionError> {
        self.check()?;
        let changed = self.swarm.changed();
        if !changed.is_empty() {
            return Err(MissionError::Invalid(format!(
                "{} {} for grape and auction (the robots over the radio), not for a central method",
                changed.join(", "),
                if changed.len() == 1 { "is" } else { "are" }
            )));
        }
        let name = method.map_or_else(|| allocator.name(), |m| m.to_string());
        Ok(Planner {
            name: if self.warm {
                format!("{name} (warm)")
            } else {
                name
            },
            decider: Decider::Central {
                allocator,
                method,
                warm: self.warm,
            },
            options: self.options(),
        })
    }

    /// The central options in range (the swarm's are checked when its robots start).
    fn check(&self) -> Result<(), MissionError> {
        check_options(&self.options())
    }

    /// The central options set, by their command-line names.
    fn central_options(&self) -> Vec<&'static str> {
        [
            (self.replan_every.is_some(), "replan"),
            (self.latency != Latency::None, "latency"),
            (self.commit, "commit"),
            (self.hysteresis.is_some(), "hysteresis"),
            (self.time_limit.is_some(), "time-limit"),
        ]
        .into_iter()
        .filter_map(|(set, name)| set.then_some(name))
        .collect()
    }

    fn options(&self) -> RunOptions {
        RunOptions {
            replan_every: self.replan_every,
            latency: self.latency,
            commit: self.commit,
            hysteresis: self.hysteresis,
            ..RunOptions::default()
        }
    }
}

/// A decentralised method's name in tables, with its radio (and the auction's ε where
/// it is not 0.001): `grape (swarm, r 0.120, loss 30 %)`.
fn swarm_name(method: SwarmMethod, knobs: &SwarmKnobs) -> String {
    let mut name = match method {
        SwarmMethod::Grape { .. } => "grape (swarm".to_string(),
        SwarmMethod::Auction { .. } => "auction (swarm".to_string(),
    };
    let _ = match knobs.radio.network().graph {
        GraphKind::Radius { radius } => write!(name, ", r {radius:.3}"),
        GraphKind::Knn { k } => write!(name, ", {k}-NN"),
        GraphKind::Complete => write!(name, ", all linked"),
    };
    if knobs.radio.loss > 0.0 {
        let _ = write!(name, ", loss {:.0} %", 100.0 * knobs.radio.loss);
    }
    if let Some(range) = knobs.sensing {
        let _ = write!(name, ", sensing {range}");
    }
    if matches!(method, SwarmMethod::Auction { .. })
        && knobs.epsilon != SwarmKnobs::default().epsilon
    {
        let _ = write!(name, ", ε {}", knobs.epsilon);
    }
    name.push(')');
    name
}

/// A checked [`MissionPlan`], ready to run missions: its allocator built, its name
/// for tables.
pub struct Planner {
    name: String,
    decider: Decider,
    options: RunOptions,
}

/// Who decides: an allocator for everyone, or each robot over the radio.
enum Decider {
    Central {
        allocator: Box<dyn Allocator>,
        method: Option<Method>,
        warm: bool,
    },
    Swarm(Decentralised),
}

impl Planner {
    /// The planner's name in tables: the method's (or the model's), with "(warm)" for
    /// warm starts and "(swarm, …)" with the radio for a decentralised method.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The planner under another name (two models of the same kind, say).
    pub fn named(self, name: String) -> Self {
        Planner { name, ..self }
    }

    /// The replanning rule: from scratch; or, warm-started, the optimum re-solved from
    /// its previous prices, and for every other method its answer at the first
    /// decision and then survivors kept and best-response dynamics (GRAPE's selfish
    /// ones for `da`, balanced for the rest); a decentralised method runs as itself.
    fn replan(&self) -> Replan<'_> {
        let (first, warm, method) = match &self.decider {
            Decider::Swarm(config) => return Replan::Decentralised(config),
            Decider::Central {
                allocator,
                method,
                warm,
            } => (allocator.as_ref(), *warm, *method),
        };
        match (warm, method) {
            (false, _) => Replan::Scratch(first),
            (true, Some(Method::Opt)) => Replan::WarmOpt,
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

    /// Runs `mission` under this plan, keeping what `recording` asks for and telling
    /// `on_time` the mission time after every event (a progress bar).
    ///
    /// # Errors
    /// [`MissionError::Invalid`] for a time between frames that is not finite and
    /// positive; the simulator's errors.
    pub fn run(
        &self,
        mission: &Mission,
        recording: Recording,
        on_time: impl FnMut(f64),
    ) -> Result<MissionRun, MissionError> {
        check_frame_every(recording.frame_every)?;
        let options = RunOptions {
            trace: recording.trace,
            frame_every: recording.frame_every,
            ..self.options
        };
        run_checked(mission, self.replan(), options, on_time)
    }
}
