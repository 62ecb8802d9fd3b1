//! The sequential allocation MDP (paper §III): robots act once each in index order, an
//! action is a task with room, the reward is the change in welfare, γ = 1.

use afg_baseline::{Greedy, Optimum};
use afg_game::{Assignment, Instance, Preference, RobotId, TaskId};
use afg_graph::{AllocationState, StateParts, Units};
use serde::{Deserialize, Serialize};

use crate::LearnError;

/// One episode over one instance. The return (sum of rewards) equals the final welfare.
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, TaskId};
/// use afg_learn::env::Env;
/// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
/// let mut env = Env::reset(&inst, afg_graph::Units::Bounded);
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
    /// A fresh episode: nobody assigned, robot 0 to act; features in `units` (rewards
    /// stay raw welfare).
    pub fn reset(instance: &'a Instance, units: Units) -> Self {
        Env {
            state: AllocationState::new(instance, units),
            next: 0,
        }
    }

    /// The episode after its first t steps: `assignment` gives robots `0..t` their
    /// tasks and leaves the others unassigned (for a caller that keeps the assignment
    /// between steps, such as the Python environment). O(N M) to rebuild the features.
    ///
    /// # Errors
    /// [`LearnError::InvalidAction`] if the assigned robots are not a prefix `0..t`, and
    /// the errors of [`Instance::check`] if the assignment does not fit the instance.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, GeneratorConfig, RobotId, TaskId};
    /// use afg_graph::Units;
    /// use afg_learn::env::Env;
    /// let inst = GeneratorConfig::paper(4, 2, 1).generate()?;
    /// let mut env = Env::reset(&inst, Units::Bounded);
    /// env.step(TaskId(1))?;
    /// let again = Env::resume_at(&inst, env.state().assignment().clone(), Units::Bounded)?;
    /// assert_eq!((again.actor(), again.state()), (Some(RobotId(1)), env.state()));
    /// let mut gap = Assignment::unassigned(4, 2);
    /// gap.set(RobotId(2), Some(TaskId(0)));
    /// assert!(Env::resume_at(&inst, gap, Units::Bounded).is_err());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn resume_at(
        instance: &'a Instance,
        assignment: Assignment,
        units: Units,
    ) -> Result<Self, LearnError> {
        let next = acted(instance, &assignment)?;
        Ok(Env {
            state: AllocationState::from_assignment(instance, assignment, units),
            next,
        })
    }

    /// The episode of [`Env::into_parts`] again, without rebuilding its features: O(N).
    ///
    /// # Errors
    /// As [`Env::resume_at`].
    ///
    /// # Panics
    /// As [`AllocationState::from_parts`].
    ///
    /// # Examples
    /// ```
    /// use afg_game::{GeneratorConfig, TaskId};
    /// use afg_graph::Units;
    /// use afg_learn::env::Env;
    /// let inst = GeneratorConfig::paper(4, 2, 1).generate()?;
    /// let mut env = Env::reset(&inst, Units::Bounded);
    /// env.step(TaskId(1))?;
    /// let again = Env::from_parts(&inst, env.clone().into_parts())?;
    /// assert_eq!((again.actor(), again.state()), (env.actor(), env.state()));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn from_parts(instance: &'a Instance, parts: StateParts) -> Result<Self, LearnError> {
        let next = acted(instance, parts.assignment())?;
        Self::from_parts_after(instance, parts, next)
    }

    /// [`Env::from_parts`] after `acted` robots have acted. Where the instance allows
    /// the void task, robots that stayed out look like robots yet to act, so a caller
    /// that keeps the state between steps keeps this count too.
    ///
    /// # Errors
    /// [`LearnError::InvalidAction`] if `acted` is above N, a robot from `acted` on has
    /// a task, or (in the paper's game) one before it has none.
    ///
    /// # Panics
    /// As [`AllocationState::from_parts`].
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, RobotId, Task, TaskId};
    /// use afg_graph::Units;
    /// use afg_learn::env::Env;
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(9.0, 0.0), Point::new(1.0, 0.0)];
    /// let inst = Instance::with_void(robots, vec![task], 1.0)?;
    /// let mut env = Env::reset(&inst, Units::Bounded);
    /// assert_eq!(env.stay_out()?, (0.0, false));
    /// let again = Env::from_parts_after(&inst, env.into_parts(), 1)?;
    /// assert_eq!(again.actor(), Some(RobotId(1)));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn from_parts_after(
        instance: &'a Instance,
        parts: StateParts,
        acted: usize,
    ) -> Result<Self, LearnError> {
        let tasks = parts.assignment().tasks();
        let bad = |why: String| Err(LearnError::InvalidAction(why));
        if acted > tasks.len() {
            return bad(format!(
                "{acted} robots cannot have acted out of {}",
                tasks.len()
            ));
        }
        if let Some(i) = (acted..tasks.len()).find(|&i| tasks[i].is_some()) {
            return bad(format!(
                "robots act in index order, but robot {i} has a task after {acted} have acted"
            ));
        }
        if !instance.allows_void()
            && let Some(i) = (0..acted).find(|&i| tasks[i].is_none())
        {
            return bad(format!(
                "robot {i} has acted but has no task, and the instance is the paper's game"
            ));
        }
        Ok(Env {
            state: AllocationState::from_parts(instance, parts),
            next: acted,
        })
    }

    /// The assignment and features so far, to keep between calls
    /// ([`Env::from_parts`]).
    pub fn into_parts(self) -> StateParts {
        self.state.into_parts()
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

    /// The acting robot stays out (the void task, where the instance allows it): the
    /// reward is 0, the welfare being unchanged. Returns it and whether the episode is
    /// over.
    ///
    /// # Errors
    /// [`LearnError::InvalidAction`] after the last robot, or in the paper's game.
    pub fn stay_out(&mut self) -> Result<(f64, bool), LearnError> {
        if !self.state.instance().allows_void() {
            return Err(LearnError::InvalidAction(
                "no robot may stay out of the paper's game: the instance does not allow the void task".into(),
            ));
        }
        self.actor()
            .ok_or_else(|| LearnError::InvalidAction("the episode is over".into()))?;
        self.next += 1;
        Ok((0.0, self.actor().is_none()))
    }

    /// Whether the acting robot may stay out ([`Env::stay_out`]).
    pub fn may_stay_out(&self) -> bool {
        self.state.instance().allows_void() && self.actor().is_some()
    }

    /// [`Env::step`] with the reward shaped by `shaping`: the welfare change plus the
    /// change of the shaping potential ([`Shaping::potential`]), so that a whole
    /// episode's shaped return is its welfare minus the potential of the empty state.
    /// [`Shaping::None`] gives [`Env::step`]'s reward.
    ///
    /// # Errors
    /// As [`Env::step`].
    ///
    /// # Examples
    /// ```
    /// use afg_game::{GeneratorConfig, TaskId};
    /// use afg_learn::env::{Env, Shaping};
    /// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
    /// let mut env = Env::reset(&inst, afg_graph::Units::Bounded);
    /// let start = Shaping::Greedy.potential(&inst, env.state().assignment());
    /// let mut shaped = 0.0;
    /// while env.actor().is_some() {
    ///     shaped += env.step_shaped(TaskId(1), Shaping::Greedy).unwrap().0;
    /// }
    /// let welfare = inst.welfare(env.state().assignment());
    /// assert!((shaped - (welfare - start)).abs() < 1e-9);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn step_shaped(
        &mut self,
        task: TaskId,
        shaping: Shaping,
    ) -> Result<(f64, bool), LearnError> {
        let inst = self.state.instance();
        let before = shaping.potential(inst, self.state.assignment());
        let (reward, done) = self.step(task)?;
        let after = shaping.potential(self.state.instance(), self.state.assignment());
        Ok((reward + after - before, done))
    }
}

/// The number t of robots that have acted in `assignment`, a state of the MDP: robots
/// `0..t` assigned, the others not.
fn acted(instance: &Instance, assignment: &Assignment) -> Result<usize, LearnError> {
    instance.check(assignment)?;
    let next = assignment
        .tasks()
        .iter()
        .take_while(|t| t.is_some())
        .count();
    if assignment.tasks()[next..].iter().any(Option::is_some) {
        return Err(LearnError::InvalidAction(format!(
            "robots act in index order, but robot {next} is unassigned while a later one has a task"
        )));
    }
    Ok(next)
}

/// The potential of potential-based reward shaping (Ng, Harada and Russell, 1999):
/// `Φ(s) = W(completion of s) − W(s)`, the welfare that a fixed completion rule would
/// still add from state `s`. The shaped reward of a transition `s → s'` is the change
/// of `W(completion)`; Φ depends on the state only, so the optimal policy is unchanged,
/// while the values to learn become what an action gains over finishing by the rule.
/// Not in the paper (ours).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Shaping {
    /// The paper's reward, the welfare change (Φ = 0).
    #[default]
    None,
    /// Φ from one-pass greedy ([`afg_baseline::Greedy::complete`]), O(N M) per state.
    Greedy,
    /// Φ from the optimal completion ([`afg_baseline::Optimum::complete`]), one min-cost
    /// flow per state. Then Φ(s) = V*(s), so the shaped reward of one step is exactly
    /// the advantage `Q*(s, a) − V*(s)` ≤ 0 and the shaped optimal values are 0 along
    /// optimal play: the TD targets carry the oracle's values.
    Optimal,
}

impl afg_game::Named for Shaping {
    const ALL: &'static [Self] = &[Shaping::None, Shaping::Greedy, Shaping::Optimal];
    const WHAT: &'static str = "shaping";

    fn name(self) -> &'static str {
        match self {
            Shaping::None => "none",
            Shaping::Greedy => "greedy",
            Shaping::Optimal => "optimal",
        }
    }
}

impl Shaping {
    /// `W(completion of assignment)` by this rule; `W(assignment)` for
    /// [`Shaping::None`] (so that Φ = 0).
    ///
    /// # Panics
    /// If `assignment` does not fit `instance` (more robots than a capacity, other
    /// sizes), which the trainer's own states never do.
    pub fn completion_welfare(self, instance: &Instance, assignment: &Assignment) -> f64 {
        match self {
            Shaping::None => instance.welfare(assignment),
            Shaping::Greedy => instance.welfare(&Greedy.complete(instance, assignment)),
            Shaping::Optimal => instance.welfare(
                &Optimum
                    .complete(instance, assignment)
                    .expect("a state of the MDP fits its instance"),
            ),
        }
    }

    /// `Φ(assignment) = W(completion) − W(assignment)`, in raw welfare.
    pub fn potential(self, instance: &Instance, assignment: &Assignment) -> f64 {
        match self {
            Shaping::None => 0.0,
            _ => self.completion_welfare(instance, assignment) - instance.welfare(assignment),
        }
    }
}

/// The summed reward (γ = 1, raw welfare) of robots `first, first + 1, …` taking
/// `actions` from `assignment`, which is advanced past them, shaped by `shaping`: the
/// welfare change plus `Φ(s') − Φ(s)`, i.e. the change of `W(completion)`.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Greedy, Optimum};
/// use afg_game::{Assignment, GeneratorConfig, TaskId};
/// use afg_learn::env::{Shaping, n_step_reward};
/// let inst = GeneratorConfig::paper(6, 2, 1).generate()?;
/// let actions = [TaskId(0), TaskId(1), TaskId(1), TaskId(0), TaskId(0), TaskId(1)];
/// let mut a = Assignment::unassigned(6, 2);
/// let raw = n_step_reward(&inst, &mut a, 0, &actions, Shaping::None);
/// assert!((raw - inst.welfare(&a)).abs() < 1e-9);
/// // Shaped, a whole episode returns the final welfare minus the rule's.
/// let mut b = Assignment::unassigned(6, 2);
/// let shaped = n_step_reward(&inst, &mut b, 0, &actions, Shaping::Greedy);
/// let greedy = inst.welfare(&Greedy.allocate(&inst)?.assignment);
/// assert!((shaped - (inst.welfare(&a) - greedy)).abs() < 1e-9);
/// // With the optimal completion, an episode's shaped return is its regret, ≤ 0.
/// let mut c = Assignment::unassigned(6, 2);
/// let regret = -n_step_reward(&inst, &mut c, 0, &actions, Shaping::Optimal);
/// let opt = inst.welfare(&Optimum.allocate(&inst)?.assignment);
/// assert!((regret - (opt - inst.welfare(&a))).abs() < 1e-9 && regret >= -1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn n_step_reward(
    instance: &Instance,
    assignment: &mut Assignment,
    first: usize,
    actions: &[TaskId],
    shaping: Shaping,
) -> f64 {
    let shaped = shaping != Shaping::None;
    let mut reward = if shaped {
        -shaping.completion_welfare(instance, assignment)
    } else {
        0.0
    };
    for (k, &task) in actions.iter().enumerate() {
        let robot = RobotId((first + k) as u32);
        if !shaped {
            reward += instance.score(assignment, robot, task, Preference::Balanced);
        }
        assignment.set(robot, Some(task));
    }
    if shaped {
        reward += shaping.completion_welfare(instance, assignment);
    }
    reward
}
