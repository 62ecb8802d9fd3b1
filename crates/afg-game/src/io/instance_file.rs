//! The serialised shape of an instance: its robots and tasks as files write them, with
//! the team games' fields written only when used.

use serde::{Deserialize, Serialize};

use super::{FORMAT_VERSION, INSTANCE_FORMAT, check_header};
use crate::{GameError, GeneratorConfig, Instance, Point, Task};

/// The serialised shape of an [`Instance`]; deserialising validates it.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct InstanceFile {
    format: String,
    version: u32,
    beta: f64,
    robots: Vec<RobotEntry>,
    tasks: Vec<TaskEntry>,
    /// GRAPE's game: robots may join the void task. Absent (false) in the paper's game,
    /// so files of the paper's game read and write as before.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    allow_void: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    generator: Option<GeneratorConfig>,
}

/// A robot as files write it: its position and, in a game with skills, its skills.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotEntry {
    x: f64,
    y: f64,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    skills: Vec<Count>,
}

/// A whole number as a file holds it, kept as JSON until the instance is built so
/// that a wrong one (negative, fractional, a string) is named — robot or task, field,
/// value — instead of the parser's column.
#[derive(Clone, Serialize, Deserialize)]
#[serde(transparent)]
struct Count(serde_json::Value);

impl Count {
    /// The count, checked: a JSON integer of at least `min` that fits in `u32`.
    fn read(
        &self,
        of: (&'static str, usize),
        field: &'static str,
        min: u32,
    ) -> Result<u32, GameError> {
        self.0
            .as_u64()
            .and_then(|n| u32::try_from(n).ok())
            .filter(|&n| n >= min)
            .ok_or_else(|| GameError::InvalidCount {
                what: of.0,
                index: of.1,
                field,
                min,
                value: self.0.to_string(),
            })
    }

    fn of(n: impl Into<u64>) -> Count {
        Count(serde_json::Value::from(n.into()))
    }
}

/// A task as files write it: a [`Task`] and its team rules, written only when used.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskEntry {
    position: Point,
    reward: f64,
    eps: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    capacity: Option<Count>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min_team: Option<Count>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    requires: Vec<Count>,
}

impl TryFrom<InstanceFile> for Instance {
    type Error = GameError;
    fn try_from(f: InstanceFile) -> Result<Self, GameError> {
        check_header(&f.format, f.version, INSTANCE_FORMAT)?;
        let robots = f.robots.iter().map(|r| Point::new(r.x, r.y)).collect();
        let tasks = (f.tasks.iter().enumerate())
            .map(|(j, t)| {
                let capacity = t
                    .capacity
                    .as_ref()
                    .map(|c| c.read(("task", j), "capacity", 0));
                Ok(Task {
                    position: t.position,
                    reward: t.reward,
                    eps: t.eps,
                    capacity: capacity.transpose()?.map(|c| c as usize),
                })
            })
            .collect::<Result<_, GameError>>()?;
        let inst = if f.allow_void {
            Instance::with_void(robots, tasks, f.beta)?
        } else {
            Instance::new(robots, tasks, f.beta)?
        };
        let inst = if f
            .tasks
            .iter()
            .any(|t| t.min_team.is_some() || !t.requires.is_empty())
            || f.robots.iter().any(|r| !r.skills.is_empty())
        {
            let amounts = |of: (&'static str, usize), field, list: &[Count]| {
                list.iter()
                    .map(|c| c.read(of, field, 0))
                    .collect::<Result<Vec<u32>, _>>()
            };
            let min_team = (f.tasks.iter().enumerate())
                .map(|(j, t)| match &t.min_team {
                    Some(k) => Ok(k.read(("task", j), "min_team", 1)? as usize),
                    None => Ok(1),
                })
                .collect::<Result<_, GameError>>()?;
            let skills = (f.robots.iter().enumerate())
                .map(|(i, r)| amounts(("robot", i), "skills", &r.skills))
                .collect::<Result<Vec<_>, _>>()?;
            let requires = (f.tasks.iter().enumerate())
                .map(|(j, t)| amounts(("task", j), "requires", &t.requires))
                .collect::<Result<Vec<_>, _>>()?;
            inst.with_teams(min_team, &skills, &requires)?
        } else {
            inst
        };
        Ok(match f.generator {
            Some(g) => inst.with_generator(g),
            None => inst,
        })
    }
}

impl From<Instance> for InstanceFile {
    fn from(inst: Instance) -> Self {
        InstanceFile {
            format: INSTANCE_FORMAT.to_owned(),
            version: FORMAT_VERSION,
            beta: inst.beta(),
            robots: inst
                .robot_ids()
                .map(|i| {
                    let p = inst.robots()[i.index()];
                    RobotEntry {
                        x: p.x,
                        y: p.y,
                        skills: inst.skills(i).iter().map(|&s| Count::of(s)).collect(),
                    }
                })
                .collect(),
            tasks: inst
                .task_ids()
                .map(|j| {
                    let t = inst.task(j);
                    TaskEntry {
                        position: t.position,
                        reward: t.reward,
                        eps: t.eps,
                        capacity: t.capacity.map(|c| Count::of(c as u64)),
                        min_team: Some(inst.min_team(j))
                            .filter(|&k| k != 1)
                            .map(|k| Count::of(k as u64)),
                        requires: inst.requires(j).iter().map(|&r| Count::of(r)).collect(),
                    }
                })
                .collect(),
            allow_void: inst.allows_void(),
            generator: inst.generator().cloned(),
        }
    }
}
