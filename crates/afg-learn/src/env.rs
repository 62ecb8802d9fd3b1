//! The sequential allocation MDP (paper §III): robots act once each in index order, an
//! action is a task with room, the reward is the change in welfare, γ = 1.

use afg_baseline::Greedy;
use afg_game::{Assignment, Instance, Preference, RobotId, TaskId};
use afg_graph::{AllocationState, Units};

use crate::LearnError;

/// One episode over one instance. The return (sum of rewards) equals the final welfare.
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, TaskId};
/// use afg_learn::Env;
/// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
/// let mut env = Env::reset(&inst);
/// let mut ret = 0.0;
/// while env.actor().is_some() {
///     let (reward, _done) = env.step(TaskId(0)).unwrap();
///     ret += reward;
/// }
/// assert!((ret - inst.welfare(env.state().assignment())).abs() < 1e-9);
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Env<'a> {
    state: AllocationState<'a>,
    next: usize,
}

impl<'a> Env<'a> {
    /// A fresh episode: nobody assigned, robot 0 to act; features in the default
    /// [`Units`].
    pub fn reset(instance: &'a Instance) -> Self {
        Self::reset_in(instance, Units::default())
    }

    /// A fresh episode with features in `units` (rewards stay raw welfare).
    pub fn reset_in(instance: &'a Instance, units: Units) -> Self {
        Env {
            state: AllocationState::with_units(
                instance,
                afg_game::Assignment::unassigned(instance.num_robots(), instance.num_tasks()),
                units,
            ),
            next: 0,
        }
    }

    /// The robot to act now, `None` once every robot has acted.
    pub fn actor(&self) -> Option<RobotId> {
        (self.next < self.state.instance().num_robots()).then_some(RobotId(self.next as u32))
    }

    /// Step index t (robots that have acted).
    pub fn step_index(&self) -> usize {
        self.next
    }

    /// The graph state (features, assignment).
    pub fn state(&self) -> &AllocationState<'a> {
        &self.state
    }

    /// Tasks the acting robot may take; all `false` once done.
    pub fn action_mask(&self) -> Vec<bool> {
        match self.actor() {
            Some(i) => self.state.action_mask(i),
            None => vec![false; self.state.instance().num_tasks()],
        }
    }

    /// The acting robot takes `task`. Returns the reward `W(s_{t+1}) - W(s_t)` and
    /// whether the episode is over.
    ///
    /// # Errors
    /// [`LearnError::InvalidAction`] after the last robot, for a task out of range or
    /// one without room.
    pub fn step(&mut self, task: TaskId) -> Result<(f64, bool), LearnError> {
        let inst = self.state.instance();
        let robot = self
            .actor()
            .ok_or_else(|| LearnError::InvalidAction("the episode is over".into()))?;
        if task.index() >= inst.num_tasks() || !self.state.is_available(robot, task) {
            return Err(LearnError::InvalidAction(format!(
                "robot {robot} cannot take task {task}"
            )));
        }
        // The balanced score of an unassigned robot is exactly its welfare contribution.
        let reward = inst.score(self.state.assignment(), robot, task, Preference::Balanced);
        self.state.assign(robot, task);
        self.next += 1;
        Ok((reward, self.actor().is_none()))
    }
}

/// `W(greedy completion of assignment)`: the welfare once one-pass greedy has placed
/// every unassigned robot. The shaping potential of [`n_step_reward`] is this minus
/// `W(assignment)`. O(N M).
pub fn greedy_completion_welfare(instance: &Instance, assignment: &Assignment) -> f64 {
    instance.welfare(&Greedy.complete(instance, assignment))
}

/// The summed reward (γ = 1, raw welfare) of robots `first, first + 1, …` taking
/// `actions` from `assignment`, which is advanced past them.
///
/// Unshaped, this is the welfare change. With `greedy_shaping` it is the change of
/// `W(greedy completion)`, i.e. the reward plus `Φ(s') − Φ(s)` with the potential
/// `Φ(s) = W(greedy completion of s) − W(s)` (Ng, Harada and Russell, 1999): Φ depends
/// on the state only, so the optimal policy is unchanged, while the values to learn
/// become what an action gains over finishing greedily.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Greedy};
/// use afg_game::{Assignment, GeneratorConfig, TaskId};
/// use afg_learn::n_step_reward;
/// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
/// let actions = [TaskId(0), TaskId(1), TaskId(1), TaskId(0), TaskId(0), TaskId(1)];
/// let mut a = Assignment::unassigned(6, 2);
/// let raw = n_step_reward(&inst, &mut a, 0, &actions, false);
/// assert!((raw - inst.welfare(&a)).abs() < 1e-9);
/// // Shaped, a whole episode returns the final welfare minus greedy's.
/// let mut b = Assignment::unassigned(6, 2);
/// let shaped = n_step_reward(&inst, &mut b, 0, &actions, true);
/// let greedy = inst.welfare(&Greedy.allocate(&inst)?.assignment);
/// assert!((shaped - (inst.welfare(&a) - greedy)).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn n_step_reward(
    instance: &Instance,
    assignment: &mut Assignment,
    first: usize,
    actions: &[TaskId],
    greedy_shaping: bool,
) -> f64 {
    let mut reward = if greedy_shaping {
        -greedy_completion_welfare(instance, assignment)
    } else {
        0.0
    };
    for (k, &task) in actions.iter().enumerate() {
        let robot = RobotId((first + k) as u32);
        if !greedy_shaping {
            reward += instance.score(assignment, robot, task, Preference::Balanced);
        }
        assignment.set(robot, Some(task));
    }
    if greedy_shaping {
        reward += greedy_completion_welfare(instance, assignment);
    }
    reward
}
