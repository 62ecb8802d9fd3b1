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
    skills: Vec<u32>,
}

/// A task as files write it: a [`Task`] and its team rules, written only when used.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskEntry {
    position: Point,
    reward: f64,
    eps: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    capacity: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min_team: Option<usize>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    requires: Vec<u32>,
}

impl TryFrom<InstanceFile> for Instance {
    type Error = GameError;
    fn try_from(f: InstanceFile) -> Result<Self, GameError> {
        check_header(&f.format, f.version, INSTANCE_FORMAT)?;
        let robots = f.robots.iter().map(|r| Point::new(r.x, r.y)).collect();
        let tasks = f
            .tasks
            .iter()
            .map(|t| Task {
                position: t.position,
                reward: t.reward,
                eps: t.eps,
                capacity: t.capacity,
            })
            .collect();
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
            let min_team = f.tasks.iter().map(|t| t.min_team.unwrap_or(1)).collect();
            let skills: Vec<Vec<u32>> = f.robots.into_iter().map(|r| r.skills).collect();
            let requires: Vec<Vec<u32>> = f.tasks.into_iter().map(|t| t.requires).collect();
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
                        skills: inst.skills(i).to_vec(),
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
                        capacity: t.capacity,
                        min_team: Some(inst.min_team(j)).filter(|&k| k != 1),
                        requires: inst.requires(j).to_vec(),
                    }
                })
                .collect(),
            allow_void: inst.allows_void(),
            generator: inst.generator().cloned(),
        }
    }
}
