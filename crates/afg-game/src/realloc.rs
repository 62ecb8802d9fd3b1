//! Warm starts: an assignment of an earlier instance carried over to the instance as
//! it is after robots or tasks left or joined.

use crate::io::AssignmentFile;
use crate::{Assignment, GameError, Instance, RobotId, TaskId};

/// An assignment of an earlier instance, with the robots and tasks that have left
/// since, to be carried over to the instance as it is now.
///
/// The new instance keeps the surviving robots in their old order, followed by any
/// robots that joined, and likewise the surviving tasks followed by new ones. Carried
/// over, survivors keep their task (with its new index); robots that joined, or whose
/// task left, are unassigned.
///
/// # Examples
/// ```
/// use afg_game::realloc::PreviousAssignment;
/// use afg_game::{GeneratorConfig, RobotId, TaskId};
/// // Three robots on tasks 1, 0, 1; robot 1 left and two robots joined.
/// let old = r#"{"format":"afg-assignment","version":1,"tasks":[1,0,1],"left_robots":[1]}"#;
/// let now = GeneratorConfig::paper(4, 2, 7).generate()?;
/// let start = PreviousAssignment::from_json(old)?.carry_over(&now)?;
/// assert_eq!(start.tasks(), &[Some(TaskId(1)), Some(TaskId(1)), None, None]);
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct PreviousAssignment {
    /// The old assignment, indexed by the old robot ids.
    pub tasks: Vec<Option<TaskId>>,
    /// Old robot ids that left.
    pub left_robots: Vec<RobotId>,
    /// Old task ids that left.
    pub left_tasks: Vec<TaskId>,
}

impl PreviousAssignment {
    /// Parses an assignment document (`left_robots` and `left_tasks` optional).
    ///
    /// # Errors
    /// [`GameError::Json`], [`GameError::WrongFormat`], [`GameError::UnsupportedVersion`].
    pub fn from_json(text: &str) -> Result<Self, GameError> {
        let file = AssignmentFile::parse(text, None)?;
        Ok(PreviousAssignment {
            tasks: file.tasks,
            left_robots: file.left_robots,
            left_tasks: file.left_tasks,
        })
    }

    /// Robots of the old assignment that are still there.
    pub fn survivors(&self) -> usize {
        self.tasks.len() - self.left_robots.len()
    }

    /// The starting assignment on `instance` (see the type's docs).
    ///
    /// # Errors
    /// [`GameError::Reallocation`] if a task index is beyond the tasks the old
    /// instance can have had, a left robot is out of range, a robot or task is named
    /// twice, or the instance has fewer robots or tasks than survived; the errors of
    /// [`Assignment::from_tasks`] if the survivors overfill a task.
    pub fn carry_over(&self, instance: &Instance) -> Result<Assignment, GameError> {
        let bad = |what: String| Err(GameError::Reallocation(what));
        // The old instance had the surviving tasks (at most the new M) and the left ones.
        let most_tasks = instance.num_tasks() + self.left_tasks.len();
        let old_tasks = self
            .tasks
            .iter()
            .flatten()
            .chain(&self.left_tasks)
            .map(|j| j.index() + 1)
            .max()
            .unwrap_or(0);
        if old_tasks > most_tasks {
            return bad(format!(
                "task {} is out of range: the instance has {} tasks and {} left, so the \
                 old one had at most {most_tasks}",
                old_tasks - 1,
                instance.num_tasks(),
                self.left_tasks.len()
            ));
        }
        let mut robot_gone = vec![false; self.tasks.len()];
        for &r in &self.left_robots {
            match robot_gone.get_mut(r.index()) {
                Some(g) if !*g => *g = true,
                Some(_) => return bad(format!("robot {r} is named twice in left_robots")),
                None => {
                    return bad(format!(
                        "left robot {r} is out of range (the assignment has {} robots)",
                        self.tasks.len()
                    ));
                }
            }
        }
        // New index of each old task, None if it left.
        let mut task_map: Vec<Option<u32>> = vec![Some(0); old_tasks];
        for &j in &self.left_tasks {
            if task_map[j.index()].is_none() {
                return bad(format!("task {j} is named twice in left_tasks"));
            }
            task_map[j.index()] = None;
        }
        let mut next = 0;
        for slot in task_map.iter_mut().flatten() {
            *slot = next;
            next += 1;
        }
        if (next as usize) > instance.num_tasks() || self.survivors() > instance.num_robots() {
            return bad(format!(
                "{} robots and {next} tasks survived, but the instance has only {} and {}",
                self.survivors(),
                instance.num_robots(),
                instance.num_tasks()
            ));
        }
        let mut tasks: Vec<Option<TaskId>> = self
            .tasks
            .iter()
            .zip(&robot_gone)
            .filter(|(_, gone)| !**gone)
            .map(|(t, _)| t.and_then(|j| task_map[j.index()]).map(TaskId))
            .collect();
        tasks.resize(instance.num_robots(), None);
        Assignment::from_tasks(instance, tasks)
    }
}
