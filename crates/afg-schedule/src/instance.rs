//! A scheduling instance: depots, robots, tasks that need teams, and the rules of time.
//!
//! One instance is one JSON object, one per line in a file. The layout is DCMRTA's test
//! set as committed in `datasets/dcmrta-20a50t/` (its provenance fields included), and
//! the same layout with skills: a top-level `skills` count, robots' `skills` (whole
//! amounts, one per skill) and `species`, tasks' `requires` (the amounts a team must hold
//! together). Unknown fields are refused.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::ScheduleError;

/// How the simulator treats a robot that sets off for a task whose team is already complete.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Rules {
    /// DCMRTA's simulator: the robot goes there anyway and is released at the task's finish.
    #[default]
    Dcmrta,
    /// HeteroMRTA's simulator: the robot skips the task and goes on to its next one.
    Heteromrta,
}

/// How distances are measured. Only straight lines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Metric {
    /// Straight lines in the plane.
    #[default]
    Euclidean,
}

/// A robot: where it starts, its depot, and what it can do.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Robot {
    /// Start position, x.
    pub x: f64,
    /// Start position, y.
    pub y: f64,
    /// The depot it returns to (an index into `depots`).
    pub depot: usize,
    /// The whole amount it holds of each skill (games with skills only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skills: Option<Vec<u32>>,
    /// Its species (robots of one species hold the same skills), for the record.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub species: Option<usize>,
}

/// A task: where it is, how long it runs, and the team it needs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    /// Position, x.
    pub x: f64,
    /// Position, y.
    pub y: f64,
    /// The number of robots it needs present together (1 when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_team: Option<u32>,
    /// The amount of each skill its team must hold together (games with skills only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub requires: Option<Vec<u32>>,
    /// How long it runs once its team is complete.
    pub duration: f64,
}

impl Task {
    /// The fewest robots that can make up its team: `min_team`, and at least one.
    pub fn team_floor(&self) -> usize {
        self.min_team.unwrap_or(1).max(1) as usize
    }
}

/// A scheduling instance, validated when read or built (see [`ScheduleInstance::validate`]).
///
/// # Examples
/// ```
/// use afg_schedule::ScheduleInstance;
/// let line = r#"{"speed":0.2,"max_wait":10,"depots":[[0,0]],
///   "robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],
///   "tasks":[{"x":1,"y":0,"min_team":2,"duration":1.5}]}"#;
/// let inst = ScheduleInstance::from_json(line)?;
/// assert_eq!((inst.num_robots(), inst.num_tasks()), (2, 1));
/// assert_eq!(inst.travel_time(inst.depot_place(0), inst.task_place(0)), 5.0);
/// # Ok::<(), afg_schedule::ScheduleError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleInstance {
    /// Where the instance came from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The licence it came under.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub licence: Option<String>,
    /// The name of the set it belongs to.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub set: Option<String>,
    /// What happens to a robot that sets off for a task already staffed.
    #[serde(default)]
    pub rules: Rules,
    /// Its place in its set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub index: Option<usize>,
    /// The robots' speed (distance per unit of time).
    pub speed: f64,
    /// How distances are measured.
    #[serde(default)]
    pub metric: Metric,
    /// The longest a robot may wait at a task whose team is incomplete before it gives up.
    pub max_wait: f64,
    /// DCMRTA's set: the stricter `max_wait` its learned policies were tested under.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_wait_rl_test: Option<f64>,
    /// DCMRTA's set: the `max_wait` stored in its pickled environments.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_wait_pickled: Option<f64>,
    /// DCMRTA's set: the time its simulator stops at.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon: Option<f64>,
    /// Whether every robot drives back to its depot at the end (the makespan counts it).
    #[serde(default = "yes")]
    pub return_to_depot: bool,
    /// The number of skills (games with skills only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skills: Option<usize>,
    /// Depot positions.
    pub depots: Vec<[f64; 2]>,
    /// The robots.
    pub robots: Vec<Robot>,
    /// The tasks.
    pub tasks: Vec<Task>,
}

fn yes() -> bool {
    true
}

/// The straight-line distance between two points: the one formula of every distance in
/// this crate (the evaluator, the decoder's table, the bound).
pub(crate) fn straight(u: [f64; 2], v: [f64; 2]) -> f64 {
    ((u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2)).sqrt()
}

/// A place a robot can be: a task or a depot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    /// Task j.
    Task(usize),
    /// Depot d.
    Depot(usize),
    /// Where robot i starts.
    Start(usize),
}

impl ScheduleInstance {
    /// Parses one instance from JSON and validates it.
    pub fn from_json(text: &str) -> Result<Self, ScheduleError> {
        let inst: Self = serde_json::from_str(text).map_err(|e| ScheduleError::Parse {
            line: e.line(),
            message: e.to_string(),
        })?;
        inst.validate()?;
        Ok(inst)
    }

    /// One line of JSON, fields in the order of the published files.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("an instance is always serialisable")
    }

    /// Number of robots.
    pub fn num_robots(&self) -> usize {
        self.robots.len()
    }

    /// Number of tasks.
    pub fn num_tasks(&self) -> usize {
        self.tasks.len()
    }

    /// The number of skills (0 in games without skills).
    pub fn num_skills(&self) -> usize {
        self.skills.unwrap_or(0)
    }

    /// Robot i's amount of skill s (0 in games without skills).
    pub fn robot_skill(&self, robot: usize, skill: usize) -> u32 {
        self.robots[robot].skills.as_ref().map_or(0, |v| v[skill])
    }

    /// Task j's requirement of skill s (0 where it requires nothing).
    pub fn task_requires(&self, task: usize, skill: usize) -> u32 {
        self.tasks[task].requires.as_ref().map_or(0, |v| v[skill])
    }

    /// Where task j is.
    pub fn task_place(&self, task: usize) -> Place {
        Place::Task(task)
    }

    /// Where robot i's depot is.
    pub fn depot_place(&self, robot: usize) -> Place {
        Place::Depot(self.robots[robot].depot)
    }

    /// The coordinates of a place.
    pub fn point(&self, place: Place) -> [f64; 2] {
        match place {
            Place::Task(j) => [self.tasks[j].x, self.tasks[j].y],
            Place::Depot(d) => self.depots[d],
            Place::Start(i) => [self.robots[i].x, self.robots[i].y],
        }
    }

    /// The straight-line distance between two places.
    pub fn distance(&self, a: Place, b: Place) -> f64 {
        straight(self.point(a), self.point(b))
    }

    /// The time a robot takes from one place to another.
    pub fn travel_time(&self, a: Place, b: Place) -> f64 {
        self.distance(a, b) / self.speed
    }

    /// Checks every number and count, and that some team can staff every task.
    pub fn validate(&self) -> Result<(), ScheduleError> {
        positive("speed", self.speed)?;
        positive("max_wait", self.max_wait)?;
        if self.depots.is_empty() || self.robots.is_empty() || self.tasks.is_empty() {
            return Err(ScheduleError::Invalid(format!(
                "an instance needs depots, robots and tasks (it has {}, {} and {})",
                self.depots.len(),
                self.robots.len(),
                self.tasks.len()
            )));
        }
        for (d, p) in self.depots.iter().enumerate() {
            finite(&format!("depot {d}'s coordinates"), p[0])?;
            finite(&format!("depot {d}'s coordinates"), p[1])?;
        }
        let skills = self.num_skills();
        for (i, r) in self.robots.iter().enumerate() {
            finite(&format!("robot {i}'s x"), r.x)?;
            finite(&format!("robot {i}'s y"), r.y)?;
            if r.depot >= self.depots.len() {
                return Err(ScheduleError::Invalid(format!(
                    "robot {i}'s depot is {}, but there are {} depots",
                    r.depot,
                    self.depots.len()
                )));
            }
            check_len(&format!("robot {i}'s skills"), r.skills.as_ref(), skills)?;
        }
        for (j, t) in self.tasks.iter().enumerate() {
            finite(&format!("task {j}'s x"), t.x)?;
            finite(&format!("task {j}'s y"), t.y)?;
            finite(&format!("task {j}'s duration"), t.duration)?;
            if t.duration < 0.0 {
                return Err(out_of_range(
                    format!("task {j}'s duration"),
                    t.duration,
                    "at least 0",
                ));
            }
            if t.min_team == Some(0) {
                return Err(out_of_range(
                    format!("task {j}'s min_team"),
                    0.0,
                    "at least 1",
                ));
            }
            check_len(&format!("task {j}'s requires"), t.requires.as_ref(), skills)?;
            if t.min_team.is_none() && t.requires.is_none() {
                return Err(ScheduleError::Invalid(format!(
                    "task {j} names neither min_team nor requires: say what its team needs"
                )));
            }
        }
        self.check_staffable()
    }

    fn check_staffable(&self) -> Result<(), ScheduleError> {
        for (j, t) in self.tasks.iter().enumerate() {
            if t.team_floor() > self.num_robots() {
                return Err(ScheduleError::Unstaffable {
                    task: j,
                    why: format!(
                        "it needs {} robots and there are {}",
                        t.team_floor(),
                        self.num_robots()
                    ),
                });
            }
            for s in 0..self.num_skills() {
                let held: u64 = (0..self.num_robots())
                    .map(|i| u64::from(self.robot_skill(i, s)))
                    .sum();
                let needed = self.task_requires(j, s);
                if u64::from(needed) > held {
                    return Err(ScheduleError::Unstaffable {
                        task: j,
                        why: format!(
                            "it requires {needed} of skill {s} and all the robots together hold {held}"
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}

fn out_of_range(what: String, value: f64, expected: &'static str) -> ScheduleError {
    ScheduleError::OutOfRange {
        what,
        value,
        expected,
    }
}

fn finite(what: &str, value: f64) -> Result<(), ScheduleError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(out_of_range(what.to_string(), value, "a finite number"))
    }
}

fn positive(what: &str, value: f64) -> Result<(), ScheduleError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(out_of_range(
            what.to_string(),
            value,
            "a finite number above 0",
        ))
    }
}

fn check_len(what: &str, values: Option<&Vec<u32>>, skills: usize) -> Result<(), ScheduleError> {
    match values {
        Some(v) if v.len() != skills => Err(ScheduleError::Invalid(format!(
            "{what} has {} amounts, but the instance has {skills} skills (its top-level `skills`)",
            v.len()
        ))),
        _ => Ok(()),
    }
}

/// Reads a JSON Lines file of instances (blank lines skipped), each validated.
pub fn read_instances(path: &Path) -> Result<Vec<ScheduleInstance>, ScheduleError> {
    let text = std::fs::read_to_string(path).map_err(|source| ScheduleError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse_lines(&text, ScheduleInstance::from_json)
}

/// Parses every non-blank line with `parse`, naming the line of the first failure.
pub(crate) fn parse_lines<T>(
    text: &str,
    parse: impl Fn(&str) -> Result<T, ScheduleError>,
) -> Result<Vec<T>, ScheduleError> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(n, l)| {
            parse(l).map_err(|e| match e {
                ScheduleError::Parse { message, .. } => ScheduleError::Parse {
                    line: n + 1,
                    message,
                },
                other => ScheduleError::Parse {
                    line: n + 1,
                    message: other.to_string(),
                },
            })
        })
        .collect()
}
