//! Preferences (balanced, paper Def. 2; selfish, GRAPE), best responses, stability (Def. 3)
//! and the NS_rate of Tables I and II.
//!
//! Both rules score a robot's place in a task from the others already there,
//! `m = n_j^{-i}`, so the same score serves the task it is in and the tasks it
//! could move to:
//! - balanced: `F_j(m + 1) - F_j(m) - beta d(i, j)`, its marginal contribution to
//!   welfare; a move between two tasks changes welfare by exactly the difference of
//!   the two scores;
//! - selfish: `u_i(j, m + 1) = F_j(m + 1) / (m + 1) - beta d(i, j)`, its own utility.
//!
//! An unassigned robot scores −∞ where it is, so it prefers any task with room. In
//! GRAPE's game ([`Instance::allows_void`]) a robot in no coalition is in the **void
//! task** and scores 0 there (both preferences: it adds nothing and gets nothing), and
//! leaving for the void is a move like any other ([`Instance::best_move`]): a robot
//! whose place scores below 0 prefers to stay out.
//! A robot strictly prefers a task when its score there exceeds its current score
//! by more than [`TOLERANCE`] × max(1, |either score|): differences below that are
//! floating-point noise, not preferences.

use serde::{Deserialize, Serialize};

use crate::{Assignment, Instance, RobotId, TaskId};

/// Relative tolerance of a strict preference (see the module docs).
pub const TOLERANCE: f64 = 1e-9;

/// Which preference relation robots follow.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Preference {
    /// Utilitarian (paper Def. 2): a robot prefers a task when moving there raises welfare.
    Balanced,
    /// Selfish (GRAPE): a robot prefers a task when its own utility there is higher.
    Selfish,
}

impl crate::Named for Preference {
    const ALL: &'static [Self] = &[Preference::Balanced, Preference::Selfish];
    const WHAT: &'static str = "preference";

    fn name(self) -> &'static str {
        match self {
            Preference::Balanced => "balanced",
            Preference::Selfish => "selfish",
        }
    }
}

/// Whether score `a` is strictly better than `b` beyond the tolerance.
///
/// # Examples
/// ```
/// use afg_game::strictly_better;
/// assert!(strictly_better(1.0, f64::NEG_INFINITY));
/// assert!(!strictly_better(1.0 + 1e-12, 1.0));
/// assert!(strictly_better(1.1, 1.0));
/// ```
#[inline]
pub fn strictly_better(a: f64, b: f64) -> bool {
    if b == f64::NEG_INFINITY {
        return a > b;
    }
    a - b > TOLERANCE * a.abs().max(b.abs()).max(1.0)
}

impl Instance {
    /// Score of `robot` in `task` under `pref`, counting the others there (see module docs).
    #[inline]
    pub fn score(
        &self,
        assignment: &Assignment,
        robot: RobotId,
        task: TaskId,
        pref: Preference,
    ) -> f64 {
        self.score_among(robot, task, assignment.others_in(robot, task), pref, None)
    }

    /// Score of `robot` in `task` with `others` other robots there; in a game with
    /// skill rules, `held` has what each coalition holds (the robot counted in its own).
    #[inline]
    fn score_among(
        &self,
        robot: RobotId,
        task: TaskId,
        others: usize,
        pref: Preference,
        held: Option<Held<'_>>,
    ) -> f64 {
        let value = match held {
            None => match pref {
                Preference::Balanced => self.marginal_value(task, others + 1),
                Preference::Selfish => self.coalition_value(task, others + 1) / (others + 1) as f64,
            },
            Some(held) => {
                let (with, without) = held.rows(self, robot, task);
                let worth = |n: usize, row: &[u64]| {
                    if self.skills_met(task, row) {
                        self.coalition_value(task, n)
                    } else {
                        0.0
                    }
                };
                match pref {
                    Preference::Balanced => worth(others + 1, &with) - worth(others, &without),
                    Preference::Selfish => worth(others + 1, &with) / (others + 1) as f64,
                }
            }
        };
        value - self.cost(robot, task)
    }

    /// Score of `robot` where it is now; for a robot in no coalition, 0 (the void task)
    /// where the instance allows the void, −∞ otherwise.
    #[inline]
    pub fn current_score(&self, assignment: &Assignment, robot: RobotId, pref: Preference) -> f64 {
        match assignment.task_of(robot) {
            Some(task) => self.score(assignment, robot, task, pref),
            None => self.outside_score(),
        }
    }

    /// The score of being in no coalition: the void task's 0 where the instance allows
    /// it, else −∞ (a robot yet to be placed).
    #[inline]
    fn outside_score(&self) -> f64 {
        if self.allows_void() {
            0.0
        } else {
            f64::NEG_INFINITY
        }
    }

    /// Where `robot` would move, if it strictly prefers another place to its own:
    /// `Some(Some(task))` for a task, `Some(None)` for the void task (only where the
    /// instance allows it: when its place scores below 0 and no task with room scores 0
    /// or more), `None` to stay. In the paper's game this is
    /// [`Instance::best_response`].
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, Instance, Point, Preference, RobotId, Task, TaskId};
    /// let far = Task { position: Point::new(5.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(0.0, 0.0)];
    /// let mut a = Assignment::unassigned(1, 1);
    /// a.set(RobotId(0), Some(TaskId(0)));
    /// // The task is worth 1 and 5 away: in GRAPE's game the robot would rather stay out.
    /// let grape = Instance::with_void(robots.clone(), vec![far], 1.0)?;
    /// assert_eq!(grape.best_move(&a, RobotId(0), Preference::Selfish), Some(None));
    /// let paper = Instance::new(robots, vec![far], 1.0)?;
    /// assert_eq!(paper.best_move(&a, RobotId(0), Preference::Selfish), None);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn best_move(
        &self,
        assignment: &Assignment,
        robot: RobotId,
        pref: Preference,
    ) -> Option<Option<TaskId>> {
        if self.has_skill_rules() {
            let totals = self.skills_held(assignment);
            let current = assignment.task_of(robot);
            let held = Some(Held {
                totals: &totals,
                current,
            });
            return self.best_move_held(robot, current, assignment.sizes(), pref, &|_| true, held);
        }
        self.best_move_given(robot, assignment.task_of(robot), assignment.sizes(), pref)
    }

    /// [`Instance::best_move`] from the task `robot` is in (`current`) and the
    /// coalition sizes, as [`Instance::best_response_given`].
    ///
    /// # Panics
    /// If `sizes` has fewer than M entries.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Preference, RobotId, Task, TaskId};
    /// let far = Task { position: Point::new(5.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let grape = Instance::with_void(vec![Point::new(0.0, 0.0)], vec![far], 1.0)?;
    /// let out = grape.best_move_given(RobotId(0), Some(TaskId(0)), &[1], Preference::Selfish);
    /// assert_eq!(out, Some(None));
    /// // Already out, it stays out.
    /// assert_eq!(grape.best_move_given(RobotId(0), None, &[0], Preference::Selfish), None);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn best_move_given(
        &self,
        robot: RobotId,
        current: Option<TaskId>,
        sizes: &[usize],
        pref: Preference,
    ) -> Option<Option<TaskId>> {
        self.best_move_among(robot, current, sizes, pref, |_| true)
    }

    /// [`Instance::best_move_given`] for a robot that can only move to the tasks
    /// `known` accepts (a robot in a mission that has not heard of every task): the
    /// others are not candidates. Its own task counts as it is.
    ///
    /// # Panics
    /// If `sizes` has fewer than M entries.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Preference, RobotId, Task, TaskId};
    /// let at = |x| Task { position: Point::new(x, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let inst = Instance::new(vec![Point::new(0.9, 0.0)], vec![at(0.0), at(1.0)], 1.0)?;
    /// let all = inst.best_move_among(RobotId(0), None, &[0, 0], Preference::Selfish, |_| true);
    /// assert_eq!(all, Some(Some(TaskId(1))));
    /// // Not knowing of task 1, it goes to task 0.
    /// let known = |t: TaskId| t == TaskId(0);
    /// let some = inst.best_move_among(RobotId(0), None, &[0, 0], Preference::Selfish, known);
    /// assert_eq!(some, Some(Some(TaskId(0))));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn best_move_among(
        &self,
        robot: RobotId,
        current: Option<TaskId>,
        sizes: &[usize],
        pref: Preference,
        known: impl Fn(TaskId) -> bool,
    ) -> Option<Option<TaskId>> {
        self.best_move_held(robot, current, sizes, pref, &known, None)
    }

    /// [`Instance::best_move_among`], judged with the skills each coalition holds where
    /// `held` has them.
    fn best_move_held(
        &self,
        robot: RobotId,
        current: Option<TaskId>,
        sizes: &[usize],
        pref: Preference,
        known: &dyn Fn(TaskId) -> bool,
        held: Option<Held<'_>>,
    ) -> Option<Option<TaskId>> {
        let others = |task: TaskId| sizes[task.index()] - usize::from(current == Some(task));
        if let Some(task) = self.best_response_held(robot, current, sizes, pref, known, held) {
            // The task beats where the robot is; the void beats it only when it scores < 0.
            let s = self.score_among(robot, task, others(task), pref, held);
            let void_better = self.allows_void() && current.is_some() && s < 0.0;
            return Some(if void_better { None } else { Some(task) });
        }
        let here = current.map_or(self.outside_score(), |c| {
            self.score_among(robot, c, others(c), pref, held)
        });
        (self.allows_void() && current.is_some() && strictly_better(0.0, here)).then_some(None)
    }

    /// The task `robot` most prefers to move to, if it strictly prefers any over where it is.
    /// Ties go to the lowest task index; full tasks are not candidates.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, Instance, Point, Preference, RobotId, Task, TaskId};
    /// let at = |x| Task { position: Point::new(x, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let inst = Instance::new(vec![Point::new(0.9, 0.0)], vec![at(0.0), at(1.0)], 1.0)?;
    /// let mut a = Assignment::unassigned(1, 2);
    /// assert_eq!(inst.best_response(&a, RobotId(0), Preference::Selfish), Some(TaskId(1)));
    /// a.set(RobotId(0), Some(TaskId(1)));
    /// assert_eq!(inst.best_response(&a, RobotId(0), Preference::Selfish), None);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn best_response(
        &self,
        assignment: &Assignment,
        robot: RobotId,
        pref: Preference,
    ) -> Option<TaskId> {
        self.best_response_given(robot, assignment.task_of(robot), assignment.sizes(), pref)
    }

    /// [`Instance::best_response`] from all that it reads of an assignment: the task
    /// `robot` is in (`current`) and the coalition sizes (one per task, `robot`
    /// counted in its own), for a caller that keeps the partition in another form.
    ///
    /// # Panics
    /// If `sizes` has fewer than M entries.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Preference, RobotId, Task, TaskId};
    /// let at = |x| Task { position: Point::new(x, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(0.9, 0.0), Point::new(1.0, 0.0)];
    /// let inst = Instance::new(robots, vec![at(0.0), at(1.0)], 1.0)?;
    /// // Alone at task 1 it stays (0.9 there against 0.1 at task 0); unassigned it goes there.
    /// let stay = inst.best_response_given(RobotId(0), Some(TaskId(1)), &[0, 1], Preference::Selfish);
    /// assert_eq!(stay, None);
    /// let go = inst.best_response_given(RobotId(0), None, &[0, 1], Preference::Selfish);
    /// assert_eq!(go, Some(TaskId(1)));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn best_response_given(
        &self,
        robot: RobotId,
        current: Option<TaskId>,
        sizes: &[usize],
        pref: Preference,
    ) -> Option<TaskId> {
        self.best_response_held(robot, current, sizes, pref, &|_| true, None)
    }

    /// [`Instance::best_response_given`] among the tasks `known` accepts, judged with
    /// the skills each coalition holds where `held` has them.
    fn best_response_held(
        &self,
        robot: RobotId,
        current: Option<TaskId>,
        sizes: &[usize],
        pref: Preference,
        known: &dyn Fn(TaskId) -> bool,
        held: Option<Held<'_>>,
    ) -> Option<TaskId> {
        let others = |task: TaskId| sizes[task.index()] - usize::from(current == Some(task));
        let mut best: Option<(TaskId, f64)> = None;
        for task in self.task_ids() {
            if Some(task) == current || others(task) >= self.capacity(task) || !known(task) {
                continue;
            }
            let s = self.score_among(robot, task, others(task), pref, held);
            if best.is_none_or(|(_, b)| s > b) {
                best = Some((task, s));
            }
        }
        let (task, s) = best?;
        let here = current.map_or(self.outside_score(), |c| {
            self.score_among(robot, c, others(c), pref, held)
        });
        strictly_better(s, here).then_some(task)
    }

    /// Whether `robot` has no strictly preferred move (Def. 3 for one robot). In a game
    /// with skill rules a move is judged by what the two coalitions hold with and
    /// without the robot.
    pub fn is_satisfied(&self, assignment: &Assignment, robot: RobotId, pref: Preference) -> bool {
        let totals = self.skills_held(assignment);
        self.satisfied(assignment, robot, pref, &totals)
    }

    /// [`Instance::is_satisfied`] with the coalitions' skills (`totals`) already summed.
    fn satisfied(
        &self,
        assignment: &Assignment,
        robot: RobotId,
        pref: Preference,
        totals: &[u64],
    ) -> bool {
        let current = assignment.task_of(robot);
        let held = self.has_skill_rules().then_some(Held { totals, current });
        self.best_move_held(robot, current, assignment.sizes(), pref, &|_| true, held)
            .is_none()
    }

    /// Whether no robot strictly prefers another task (Def. 3), or the void where the
    /// instance allows it. In the paper's game unassigned robots always prefer a task,
    /// so only a complete assignment can be stable. A team game may have no stable
    /// assignment at all.
    pub fn is_stable(&self, assignment: &Assignment, pref: Preference) -> bool {
        let totals = self.skills_held(assignment);
        self.robot_ids()
            .all(|i| self.satisfied(assignment, i, pref, &totals))
    }

    /// NS_rate: the fraction of robots that are satisfied (no strictly preferred move)
    /// under `pref`. The paper reports it without a definition; this is ours.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, Instance, Point, Preference, Task, TaskId};
    /// let at = |x| Task { position: Point::new(x, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(0.0, 0.0), Point::new(1.0, 0.0)];
    /// let inst = Instance::new(robots, vec![at(0.0), at(1.0)], 1.0)?;
    /// // Both robots on the far task: robot 0 would rather move.
    /// let a = Assignment::from_tasks(&inst, vec![Some(TaskId(1)), Some(TaskId(1))])?;
    /// assert_eq!(inst.ns_rate(&a, Preference::Balanced), 0.5);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn ns_rate(&self, assignment: &Assignment, pref: Preference) -> f64 {
        let totals = self.skills_held(assignment);
        let satisfied = self
            .robot_ids()
            .filter(|&i| self.satisfied(assignment, i, pref, &totals))
            .count();
        satisfied as f64 / self.num_robots() as f64
    }
}

/// What every coalition holds of every skill (row-major M × S, each robot counted in
/// its own task), and the task of the robot whose moves are judged.
#[derive(Clone, Copy)]
struct Held<'a> {
    totals: &'a [u64],
    current: Option<TaskId>,
}

impl Held<'_> {
    /// What `task`'s coalition holds with `robot` in it, and without.
    fn rows(self, instance: &Instance, robot: RobotId, task: TaskId) -> (Vec<u64>, Vec<u64>) {
        let s = instance.num_skills();
        let row = &self.totals[task.index() * s..][..s];
        let own = instance.skills(robot).iter().map(|&q| u64::from(q));
        if self.current == Some(task) {
            let without = row.iter().zip(own).map(|(h, q)| h - q).collect();
            (row.to_vec(), without)
        } else {
            let with = row.iter().zip(own).map(|(h, q)| h + q).collect();
            (with, row.to_vec())
        }
    }
}
