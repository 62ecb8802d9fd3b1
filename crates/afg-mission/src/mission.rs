//! A mission: robots with speeds and failures, tasks that appear with a workload, the
//! game's β, and a horizon; its JSON format (`afg-mission`, versioned, unknown fields
//! refused) and its checks.

use afg_game::{GOLDEN_RATIO, Point, Task};
use serde::{Deserialize, Serialize};

use crate::{MissionConfig, MissionError};

/// The format name of a mission file.
pub const MISSION_FORMAT: &str = "afg-mission";
/// The format version this build reads and writes.
pub const MISSION_VERSION: u32 = 1;

/// A robot: where it starts, how fast it moves, and the skills it carries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Start position.
    pub position: Point,
    /// Arena units per time unit (default 1).
    #[serde(default = "one")]
    pub speed: f64,
    /// How much of each skill it holds (empty: no skills in this mission).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skills: Vec<u32>,
}

fn one() -> f64 {
    1.0
}

/// A task: the game's task (as in an instance), when it appears, how much work it
/// takes, and the team it needs: work advances only while the robots present number
/// at least `min_team` and hold the skills it `requires`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpec {
    /// Location.
    pub position: Point,
    /// `r_j`: the value of a coalition of one robot per time unit, F_j(1).
    pub reward: f64,
    /// `eps_j` of F_j (at least φ).
    pub eps: f64,
    /// Largest coalition; `None`: unbounded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capacity: Option<usize>,
    /// Its workload `W_j`: one robot does one unit per time unit.
    pub workload: f64,
    /// When it appears (time units from the start).
    #[serde(default)]
    pub appears: f64,
    /// The fewest robots that do its work (default 1).
    #[serde(default = "one_robot", skip_serializing_if = "is_one")]
    pub min_team: usize,
    /// How much of each skill its robots must hold together (empty: none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub requires: Vec<u32>,
}

fn one_robot() -> usize {
    1
}

fn is_one(n: &usize) -> bool {
    *n == 1
}

impl TaskSpec {
    /// The task of the game.
    pub fn task(&self) -> Task {
        Task {
            position: self.position,
            reward: self.reward,
            eps: self.eps,
            capacity: self.capacity,
        }
    }
}

/// A robot failure: from `time` the robot is gone, for good or until `returns`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Failure {
    /// The robot's index.
    pub robot: usize,
    /// When it fails.
    pub time: f64,
    /// When it is back (where it failed, with no task); `None`: gone for good.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub returns: Option<f64>,
}

/// A mission: everything a run ([`Planner::run`](crate::Planner::run)) needs besides
/// the allocator.
///
/// # Examples
/// ```
/// use afg_mission::{Mission, MissionConfig, Preset};
/// let mission = MissionConfig::new(Preset::Waves, 20, 8, 1).generate()?;
/// let again = Mission::from_json(&mission.to_json())?;
/// assert_eq!(again, mission);
/// assert!(Mission::from_json(&mission.to_json().replace("\"horizon\"", "\"horizont\"")).is_err());
/// # Ok::<(), afg_mission::MissionError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mission {
    format: String,
    version: u32,
    /// The distance penalty β of the game at every decision.
    pub beta: f64,
    /// Whether robots may idle (the void task of GRAPE's game) when no task is worth
    /// their trip; otherwise every living robot is given an open task.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub allow_void: bool,
    /// The mission ends at this time at the latest.
    pub horizon: f64,
    /// The robots.
    pub robots: Vec<RobotSpec>,
    /// The tasks.
    pub tasks: Vec<TaskSpec>,
    /// Robot failures.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub failures: Vec<Failure>,
    /// The generator settings that made it, if generated.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generator: Option<MissionConfig>,
}

impl Mission {
    /// The tasks (by index) that no team of the mission's robots can ever staff: a
    /// threshold above the number of robots, or an amount of a skill beyond what all
    /// the robots hold together. They earn nothing, whoever decides.
    ///
    /// # Examples
    /// ```
    /// use afg_mission::{MissionConfig, Preset};
    /// let mut config = MissionConfig::new(Preset::Static, 6, 3, 1);
    /// config.min_team = Some(afg_game::CountRange { min: 7, max: 7 });
    /// assert_eq!(config.generate()?.unstaffable_tasks(), vec![0, 1, 2]);
    /// # Ok::<(), afg_mission::MissionError>(())
    /// ```
    pub fn unstaffable_tasks(&self) -> Vec<usize> {
        let mut held = vec![0u64; self.num_skills()];
        for robot in &self.robots {
            for (h, &s) in held.iter_mut().zip(&robot.skills) {
                *h += u64::from(s);
            }
        }
        (self.tasks.iter().enumerate())
            .filter(|(_, t)| {
                t.min_team > self.robots.len()
                    || (t.requires.iter().zip(&held)).any(|(&need, &have)| u64::from(need) > have)
            })
            .map(|(j, _)| j)
            .collect()
    }

    /// Whether any task needs a team (a threshold above 1) or a skill.
    pub fn needs_teams(&self) -> bool {
        (self.tasks.iter()).any(|t| t.min_team > 1 || t.requires.iter().any(|&r| r > 0))
    }

    /// A checked mission.
    ///
    /// # Errors
    /// [`MissionError::Invalid`] naming the first thing wrong (see [`Mission::check`]).
    pub fn new(
        beta: f64,
        allow_void: bool,
        horizon: f64,
        robots: Vec<RobotSpec>,
        tasks: Vec<TaskSpec>,
        failures: Vec<Failure>,
    ) -> Result<Self, MissionError> {
        let mission = Mission {
            format: MISSION_FORMAT.into(),
            version: MISSION_VERSION,
            beta,
            allow_void,
            horizon,
            robots,
            tasks,
            failures,
            generator: None,
        };
        mission.check()?;
        Ok(mission)
    }

    /// Parses and checks a mission file.
    ///
    /// # Errors
    /// [`MissionError::Json`] for malformed JSON, an unknown field or a missing one;
    /// [`MissionError::Format`] for another format or version; the errors of
    /// [`Mission::check`].
    pub fn from_json(text: &str) -> Result<Self, MissionError> {
        let text = text.trim_start_matches('\u{feff}');
        let mission: Mission = serde_json::from_str(text).map_err(|e| {
            match afg_game::io::non_finite_number(text, &e) {
                Some(message) => MissionError::Invalid(message),
                None => MissionError::Json(e),
            }
        })?;
        if mission.format != MISSION_FORMAT || mission.version != MISSION_VERSION {
            return Err(MissionError::Format {
                found: format!("{} version {}", mission.format, mission.version),
            });
        }
        mission.check()?;
        Ok(mission)
    }

    /// The mission as one line of JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a mission serialises")
    }

    /// Checks every field: a finite positive horizon and speeds, finite positions,
    /// valid tasks (reward, eps ≥ φ, capacity ≥ 1, min_team ≥ 1, a `requires` of as
    /// many skills as every robot lists), finite positive workloads, tasks
    /// appearing in `[0, horizon)`, failures of existing robots within the horizon
    /// (returning later), β finite and ≥ 0, at least one robot and one task.
    ///
    /// # Errors
    /// [`MissionError::Invalid`] naming the first thing wrong.
    pub fn check(&self) -> Result<(), MissionError> {
        let bad = |what: String| Err(MissionError::Invalid(what));
        if self.robots.is_empty() || self.tasks.is_empty() {
            return bad("a mission needs at least one robot and one task".into());
        }
        if !(self.horizon.is_finite() && self.horizon > 0.0) {
            return bad(format!(
                "horizon {} is not finite and positive",
                self.horizon
            ));
        }
        if !(self.beta.is_finite() && self.beta >= 0.0) {
            return bad(format!("beta {} is not finite and ≥ 0", self.beta));
        }
        for (i, r) in self.robots.iter().enumerate() {
            if !r.position.is_finite() {
                return bad(format!("robot {i} has a non-finite position"));
            }
            if !(r.speed.is_finite() && r.speed > 0.0) {
                return bad(format!(
                    "robot {i} has speed {}: it must be finite and > 0",
                    r.speed
                ));
            }
        }
        let skills = self.num_skills();
        if let Some(i) = self.robots.iter().position(|r| r.skills.len() != skills) {
            return bad(format!(
                "robot {i} holds {} skills, but robot 0 holds {skills}: every robot lists the same skills",
                self.robots[i].skills.len()
            ));
        }
        for (j, t) in self.tasks.iter().enumerate() {
            self.check_task(j, t, skills)?;
        }
        for f in &self.failures {
            if f.robot >= self.robots.len() {
                return bad(format!(
                    "a failure names robot {}, but the mission has {} robots",
                    f.robot,
                    self.robots.len()
                ));
            }
            if !(f.time.is_finite() && (0.0..self.horizon).contains(&f.time)) {
                return bad(format!(
                    "robot {} fails at {}, outside the mission",
                    f.robot, f.time
                ));
            }
            if let Some(back) = f.returns
                && !(back.is_finite() && back > f.time)
            {
                return bad(format!(
                    "robot {} returns at {back}, not after it fails",
                    f.robot
                ));
            }
        }
        Ok(())
    }

    /// Checks task j (`t`) of a mission whose robots list `skills` skills.
    fn check_task(&self, j: usize, t: &TaskSpec, skills: usize) -> Result<(), MissionError> {
        let bad = |what: String| Err(MissionError::Invalid(what));
        let task = t.task();
        if !task.position.is_finite() {
            return bad(format!("task {j} has a non-finite position"));
        }
        if !(task.reward.is_finite() && task.reward >= 0.0) {
            return bad(format!("task {j} has reward {}", task.reward));
        }
        if !(task.eps.is_finite() && task.eps >= GOLDEN_RATIO) {
            return bad(format!("task {j} has eps {}, below φ ≈ 1.618", task.eps));
        }
        if task.capacity == Some(0) {
            return bad(format!("task {j} has capacity 0"));
        }
        if !(t.workload.is_finite() && t.workload > 0.0) {
            return bad(format!(
                "task {j} has workload {}: it must be finite and > 0",
                t.workload
            ));
        }
        if t.min_team == 0 {
            return bad(format!("task {j} has min_team 0: it must be at least 1"));
        }
        if !t.requires.is_empty() && t.requires.len() != skills {
            return bad(format!(
                "task {j} requires {} skills, but the robots hold {skills}",
                t.requires.len()
            ));
        }
        if !(t.appears.is_finite() && (0.0..self.horizon).contains(&t.appears)) {
            return bad(format!(
                "task {j} appears at {}, outside the mission [0, {})",
                t.appears, self.horizon
            ));
        }
        Ok(())
    }

    /// The number of skills the robots carry (0: none).
    pub fn num_skills(&self) -> usize {
        self.robots.first().map_or(0, |r| r.skills.len())
    }

    /// Whether any task needs a team of more than one robot or skills.
    pub fn has_teams(&self) -> bool {
        self.tasks
            .iter()
            .any(|t| t.min_team > 1 || t.requires.iter().any(|&r| r > 0))
    }

    /// Records the generator settings.
    pub(crate) fn with_generator(mut self, generator: MissionConfig) -> Self {
        self.generator = Some(generator);
        self
    }
}
