//! Assignments of robots to tasks (the partition Π of the paper) and their welfare.

use crate::{GameError, Instance, RobotId, TaskId};

/// Which task each robot is in (`None`: not yet assigned), with coalition sizes kept in step.
///
/// A partial assignment is the state of a sequential rollout; allocators return
/// complete ones. Sizes are maintained incrementally, so moving a robot is O(1).
///
/// # Examples
/// ```
/// use afg_game::{Assignment, RobotId, TaskId};
/// let mut a = Assignment::unassigned(3, 2);
/// a.set(RobotId(0), Some(TaskId(1)));
/// a.set(RobotId(2), Some(TaskId(1)));
/// assert_eq!(a.size(TaskId(1)), 2);
/// assert!(!a.is_complete());
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assignment {
    tasks: Vec<Option<TaskId>>,
    sizes: Vec<usize>,
}

impl Assignment {
    /// N robots, M tasks, nobody assigned.
    pub fn unassigned(num_robots: usize, num_tasks: usize) -> Self {
        Assignment {
            tasks: vec![None; num_robots],
            sizes: vec![0; num_tasks],
        }
    }

    /// An assignment for `instance` from one entry per robot, validated.
    ///
    /// # Errors
    /// [`GameError::AssignmentLength`] if there is not one entry per robot,
    /// [`GameError::TaskOutOfRange`] for a task index ≥ M and
    /// [`GameError::CapacityExceeded`] if a coalition is larger than its task allows.
    pub fn from_tasks(instance: &Instance, tasks: Vec<Option<TaskId>>) -> Result<Self, GameError> {
        if tasks.len() != instance.num_robots() {
            return Err(GameError::AssignmentLength {
                expected: instance.num_robots(),
                got: tasks.len(),
            });
        }
        let mut sizes = vec![0; instance.num_tasks()];
        for (robot, task) in tasks.iter().enumerate() {
            if let Some(t) = task {
                let size = sizes.get_mut(t.index()).ok_or(GameError::TaskOutOfRange {
                    robot,
                    task: t.index(),
                    tasks: instance.num_tasks(),
                })?;
                *size += 1;
            }
        }
        for task in instance.task_ids() {
            let (size, capacity) = (sizes[task.index()], instance.capacity(task));
            if size > capacity {
                return Err(GameError::CapacityExceeded {
                    task: task.index(),
                    size,
                    capacity,
                });
            }
        }
        Ok(Assignment { tasks, sizes })
    }

    /// Number of robots N.
    pub fn num_robots(&self) -> usize {
        self.tasks.len()
    }

    /// The task of each robot, indexed by [`RobotId`].
    pub fn tasks(&self) -> &[Option<TaskId>] {
        &self.tasks
    }

    /// The task of one robot.
    #[inline]
    pub fn task_of(&self, robot: RobotId) -> Option<TaskId> {
        self.tasks[robot.index()]
    }

    /// Coalition size |Π_j|.
    #[inline]
    pub fn size(&self, task: TaskId) -> usize {
        self.sizes[task.index()]
    }

    /// All coalition sizes, indexed by [`TaskId`].
    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// Robots of task j other than `robot`: n_j^{-i}.
    #[inline]
    pub fn others_in(&self, robot: RobotId, task: TaskId) -> usize {
        self.sizes[task.index()] - usize::from(self.tasks[robot.index()] == Some(task))
    }

    /// Whether `robot` could be in `task` without exceeding its capacity.
    #[inline]
    pub fn has_room(&self, instance: &Instance, robot: RobotId, task: TaskId) -> bool {
        self.others_in(robot, task) < instance.capacity(task)
    }

    /// Whether every robot is assigned.
    pub fn is_complete(&self) -> bool {
        self.sizes.iter().sum::<usize>() == self.tasks.len()
    }

    /// Number of assigned robots.
    pub fn num_assigned(&self) -> usize {
        self.sizes.iter().sum()
    }

    /// Moves `robot` to `task` (or out of any task with `None`), updating sizes.
    /// Capacity is the caller's concern: check [`Assignment::has_room`] first.
    ///
    /// # Panics
    /// If the robot or task index is out of range.
    #[inline]
    pub fn set(&mut self, robot: RobotId, task: Option<TaskId>) {
        if let Some(old) = self.tasks[robot.index()] {
            self.sizes[old.index()] -= 1;
        }
        if let Some(new) = task {
            self.sizes[new.index()] += 1;
        }
        self.tasks[robot.index()] = task;
    }
}

impl Instance {
    /// Welfare (sum of robot utilities) of a full or partial assignment:
    /// `sum_j F_j(n_j) - beta * sum_{assigned i} d(i, g_i)`; unassigned robots add 0. A
    /// coalition below its task's threshold, or short of a skill its task requires,
    /// adds no value (its robots still pay their travel).
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, Instance, Point, Task, TaskId};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 2.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(1.0, 0.0), Point::new(0.0, 2.0)];
    /// let inst = Instance::new(robots, vec![task], 1.0)?;
    /// let a = Assignment::from_tasks(&inst, vec![Some(TaskId(0)), Some(TaskId(0))])?;
    /// // F(2) = 2 log2(3); distances 1 and 2.
    /// assert!((inst.welfare(&a) - (2.0 * 3f64.log2() - 3.0)).abs() < 1e-12);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    ///
    /// # Panics
    /// If the assignment was made for an instance of another size.
    pub fn welfare(&self, assignment: &Assignment) -> f64 {
        assert_eq!(
            assignment.num_robots(),
            self.num_robots(),
            "assignment of another instance"
        );
        let earning = self.earning_tasks(assignment);
        let value: f64 = self
            .task_ids()
            .filter(|j| earning[j.index()])
            .map(|j| self.coalition_value(j, assignment.size(j)))
            .sum();
        let cost: f64 = self
            .robot_ids()
            .filter_map(|i| assignment.task_of(i).map(|j| self.cost(i, j)))
            .sum();
        value - cost
    }

    /// Checks that `assignment` fits this instance: one entry per robot, tasks in range,
    /// capacities respected.
    ///
    /// # Errors
    /// As [`Assignment::from_tasks`].
    pub fn check(&self, assignment: &Assignment) -> Result<(), GameError> {
        Assignment::from_tasks(self, assignment.tasks.clone()).map(drop)
    }
}
