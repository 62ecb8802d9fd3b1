//! The allocation feature graph's node features and their incremental update.
//!
//! For robot i and task j (paper §III A):
//! - robot feature `ν_i ∈ R^M`: one-hot of i's task, zero while unassigned;
//! - task feature `μ_i[j] = u_i(j, n_j^{-i} + 1)`: the utility i would get in j given
//!   the others' current assignment (eq. 2), in the welfare unit of the state's
//!   [`Units`]; a task that is full for i gets [`Units::full_task_feature`] and is
//!   masked as an action.
//!
//! When one robot moves into task j, `n_j^{-i}` changes for every robot except the
//! mover, so exactly column j of μ changes (and the column of the task it left, if
//! any): O(N) per move, never a rebuild.

use afg_game::{Assignment, Instance, Preference, RobotId, TaskId};

use crate::Units;

/// Writes column `task` of the task features μ (row-major `[N, M]`, see the module
/// docs) for `assignment`, in `units`. O(N): the value part F_j(m+1)/(m+1) takes only
/// two values, m = n_j for robots outside j and m = n_j - 1 for its members.
///
/// [`AllocationState`] keeps μ up to date with this; a caller that keeps only an
/// [`Assignment`] can rebuild μ whenever it needs it.
///
/// # Panics
/// If `mu` is shorter than N·M or `task` is out of range.
///
/// # Examples
/// ```
/// use afg_game::GeneratorConfig;
/// use afg_graph::{AllocationState, Units, write_task_column};
/// let inst = GeneratorConfig::paper(8, 3, 1).generate()?;
/// let state = AllocationState::new(&inst, afg_graph::Units::Bounded);
/// let mut mu = vec![0.0; 8 * 3];
/// for j in inst.task_ids() {
///     write_task_column(&inst, state.assignment(), Units::default(), j, &mut mu);
/// }
/// assert_eq!(mu, state.mu_matrix());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_task_column(
    instance: &Instance,
    assignment: &Assignment,
    units: Units,
    task: TaskId,
    mu: &mut [f32],
) {
    let m = instance.num_tasks();
    let scale = units.welfare_unit(instance);
    let full = units.full_task_feature();
    let n_j = assignment.size(task);
    let cap = instance.capacity(task);
    let value_cap = units.value_cap(instance, task);
    let share = |others: usize| {
        (instance.coalition_value(task, others + 1) / (others + 1) as f64).min(value_cap)
    };
    let (outside, inside) = (share(n_j), if n_j > 0 { share(n_j - 1) } else { 0.0 });
    for i in instance.robot_ids() {
        let member = assignment.task_of(i) == Some(task);
        let others = n_j - usize::from(member);
        mu[i.index() * m + task.index()] = if others >= cap {
            full
        } else {
            let value = if member { inside } else { outside };
            ((value - instance.cost(i, task)) / scale) as f32
        };
    }
}

/// The welfare gain of `robot` joining `task` (its balanced score: the change in total
/// welfare when an unassigned robot joins), divided by `scale` (a
/// [`Units::welfare_unit`]); 0 where the task is full for it. AFGNet's optional gain residual adds this to its Q values.
///
/// # Examples
/// ```
/// use afg_game::{Assignment, GeneratorConfig, RobotId, TaskId};
/// use afg_graph::join_gain;
/// let inst = GeneratorConfig::paper(4, 2, 1).generate()?;
/// let mut a = Assignment::unassigned(4, 2);
/// let gain = join_gain(&inst, &a, RobotId(0), TaskId(1), 1.0);
/// let before = inst.welfare(&a);
/// a.set(RobotId(0), Some(TaskId(1)));
/// assert!((f64::from(gain) - (inst.welfare(&a) - before)).abs() < 1e-4);
/// # Ok::<(), afg_game::GameError>(())
/// ```
pub fn join_gain(
    instance: &Instance,
    assignment: &Assignment,
    robot: RobotId,
    task: TaskId,
    scale: f64,
) -> f32 {
    if assignment.has_room(instance, robot, task) {
        (instance.score(assignment, robot, task, Preference::Balanced) / scale) as f32
    } else {
        0.0
    }
}

/// What an [`AllocationState`] holds besides its instance ([`AllocationState::into_parts`]).
#[derive(Clone, Debug, PartialEq)]
pub struct StateParts {
    assignment: Assignment,
    mu: Vec<f32>,
    units: Units,
}

impl StateParts {
    /// The assignment.
    pub fn assignment(&self) -> &Assignment {
        &self.assignment
    }

    /// The units of the features.
    pub fn units(&self) -> Units {
        self.units
    }
}

/// An assignment in progress with its μ features kept up to date.
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, RobotId, TaskId};
/// use afg_graph::AllocationState;
/// let inst = GeneratorConfig::paper(10, 3, 1).generate()?;
/// let mut s = AllocationState::new(&inst, afg_graph::Units::Bounded);
/// s.assign(RobotId(0), TaskId(2));
/// assert_eq!(s.nu(RobotId(0)), vec![0.0, 0.0, 1.0]);
/// assert_eq!(s, AllocationState::from_assignment(&inst, s.assignment().clone(), afg_graph::Units::Bounded));
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct AllocationState<'a> {
    instance: &'a Instance,
    assignment: Assignment,
    /// `mu[i * M + j]`, in feature units.
    mu: Vec<f32>,
    units: Units,
    scale: f64,
}

impl<'a> AllocationState<'a> {
    /// The empty assignment, with features in `units`.
    pub fn new(instance: &'a Instance, units: Units) -> Self {
        Self::from_assignment(
            instance,
            Assignment::unassigned(instance.num_robots(), instance.num_tasks()),
            units,
        )
    }

    /// Features of `assignment` in `units`, computed from scratch (the reference for
    /// the incremental update).
    pub fn from_assignment(instance: &'a Instance, assignment: Assignment, units: Units) -> Self {
        let mut s = AllocationState {
            instance,
            assignment,
            mu: vec![0.0; instance.num_robots() * instance.num_tasks()],
            units,
            scale: units.welfare_unit(instance),
        };
        for j in instance.task_ids() {
            s.refresh_column(j);
        }
        s
    }

    /// The assignment and its features, to keep between calls by a caller that cannot
    /// keep the borrow of the instance (the Python environment); they come back with
    /// [`AllocationState::from_parts`] without a rebuild.
    pub fn into_parts(self) -> StateParts {
        StateParts {
            assignment: self.assignment,
            mu: self.mu,
            units: self.units,
        }
    }

    /// The state of [`AllocationState::into_parts`] again, on the same instance.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{GeneratorConfig, RobotId, TaskId};
    /// use afg_graph::{AllocationState, Units};
    /// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
    /// let mut s = AllocationState::from_assignment(&inst, afg_game::Assignment::unassigned(6, 2), Units::Bounded);
    /// s.assign(RobotId(0), TaskId(1));
    /// let again = AllocationState::from_parts(&inst, s.clone().into_parts());
    /// assert_eq!(again, s);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    ///
    /// # Panics
    /// If the parts do not fit the instance (another N or M); with debug assertions,
    /// if the features are not those of the assignment.
    pub fn from_parts(instance: &'a Instance, parts: StateParts) -> Self {
        assert_eq!(
            parts.mu.len(),
            instance.num_robots() * instance.num_tasks(),
            "the parts belong to another instance"
        );
        let state = AllocationState {
            instance,
            assignment: parts.assignment,
            mu: parts.mu,
            units: parts.units,
            scale: parts.units.welfare_unit(instance),
        };
        debug_assert_eq!(
            state.mu,
            AllocationState::from_assignment(instance, state.assignment.clone(), state.units).mu
        );
        state
    }

    /// The instance.
    pub fn instance(&self) -> &'a Instance {
        self.instance
    }

    /// The units of the features.
    pub fn units(&self) -> Units {
        self.units
    }

    /// The welfare unit of the features ([`Units::welfare_unit`] of the instance).
    pub fn welfare_unit(&self) -> f64 {
        self.scale
    }

    /// The current assignment.
    pub fn assignment(&self) -> &Assignment {
        &self.assignment
    }

    /// Consumes the state, returning the assignment.
    pub fn into_assignment(self) -> Assignment {
        self.assignment
    }

    /// Moves `robot` into `task` and updates the features: O(N).
    ///
    /// # Panics
    /// If the task has no room for the robot; check [`AllocationState::is_available`].
    pub fn assign(&mut self, robot: RobotId, task: TaskId) {
        assert!(
            self.is_available(robot, task),
            "task {task} is full for robot {robot}"
        );
        let old = self.assignment.task_of(robot);
        self.assignment.set(robot, Some(task));
        if let Some(old) = old.filter(|&o| o != task) {
            self.refresh_column(old);
        }
        self.refresh_column(task);
    }

    /// Whether `robot` may take `task` (the task has room for it).
    #[inline]
    pub fn is_available(&self, robot: RobotId, task: TaskId) -> bool {
        self.assignment.has_room(self.instance, robot, task)
    }

    /// [`join_gain`] of `robot` for every task, in the features' unit.
    pub fn gains(&self, robot: RobotId) -> Vec<f32> {
        self.instance
            .task_ids()
            .map(|j| join_gain(self.instance, &self.assignment, robot, j, self.scale))
            .collect()
    }

    /// The action mask of `robot`: `true` where the task has room.
    pub fn action_mask(&self, robot: RobotId) -> Vec<bool> {
        self.instance
            .task_ids()
            .map(|j| self.is_available(robot, j))
            .collect()
    }

    /// Robot feature ν_i (one-hot of the task, zeros if unassigned).
    pub fn nu(&self, robot: RobotId) -> Vec<f32> {
        let mut v = vec![0.0; self.instance.num_tasks()];
        if let Some(j) = self.assignment.task_of(robot) {
            v[j.index()] = 1.0;
        }
        v
    }

    /// Task features μ_i of one robot, in feature units.
    pub fn mu(&self, robot: RobotId) -> &[f32] {
        let m = self.instance.num_tasks();
        &self.mu[robot.index() * m..(robot.index() + 1) * m]
    }

    /// All task features, row-major `[N, M]`.
    pub fn mu_matrix(&self) -> &[f32] {
        &self.mu
    }

    fn refresh_column(&mut self, task: TaskId) {
        write_task_column(
            self.instance,
            &self.assignment,
            self.units,
            task,
            &mut self.mu,
        );
    }
}
