//! The sequential allocation MDP (SPEC §3): robots act once each in index order, an
//! action is a task with room, the reward is the change in welfare, γ = 1.

use afg_game::{Instance, Preference, RobotId, TaskId};
use afg_graph::AllocationState;

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
    /// A fresh episode: nobody assigned, robot 0 to act.
    pub fn reset(instance: &'a Instance) -> Self {
        Env {
            state: AllocationState::new(instance),
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
