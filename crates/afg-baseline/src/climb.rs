//! Hill climbing on the welfare (ours): robot moves, pairwise swaps and whole teams.
//!
//! A finish for any allocator of a team game: each robot moves to the task (or the void
//! where the game has one) where it gains most, and pairs of robots at different tasks
//! swap, each change taken where it raises the welfare. A change touches two coalitions, so each is
//! priced from their sizes and held skills in O(S). Where no single change gains, whole
//! teams change: an earning coalition is dissolved (its members go where they gain most)
//! or a task that earns nothing is staffed (robots join it until it earns), each
//! followed by single moves and kept only where the welfare rises; then the single
//! changes start again.

use afg_game::{Assignment, Instance, RobotId, TaskId};

/// What a change must gain to be taken (beyond rounding).
const MIN_GAIN: f64 = 1e-9;

/// The coalitions of an assignment as the climb reads them.
struct Coalitions<'a> {
    instance: &'a Instance,
    sizes: Vec<usize>,
    /// Row-major M × S skill totals.
    held: Vec<u64>,
    num_skills: usize,
    /// One coalition's skills after a change, reused from change to change.
    scratch: Vec<u64>,
}

impl Coalitions<'_> {
    /// What task j earns with `size` members holding `held`.
    fn value(&self, j: TaskId, size: usize, held: &[u64]) -> f64 {
        if self.instance.earns(j, size, held) {
            self.instance.coalition_value(j, size)
        } else {
            0.0
        }
    }

    fn held(&self, j: TaskId) -> &[u64] {
        &self.held[j.index() * self.num_skills..][..self.num_skills]
    }

    /// What task j earns now.
    fn value_now(&self, j: TaskId) -> f64 {
        self.value(j, self.sizes[j.index()], self.held(j))
    }

    /// Task j's value now, and with robot `out` leaving and robot `into` joining.
    fn change(&mut self, j: TaskId, out: Option<RobotId>, into: Option<RobotId>) -> f64 {
        let s = self.num_skills;
        let mut held = std::mem::take(&mut self.scratch);
        held.clear();
        held.extend_from_slice(&self.held[j.index() * s..][..s]);
        let mut size = self.sizes[j.index()];
        if let Some(i) = into {
            size += 1;
            for (h, &q) in held.iter_mut().zip(self.instance.skills(i)) {
                *h += u64::from(q);
            }
        }
        if let Some(i) = out {
            size -= 1;
            for (h, &q) in held.iter_mut().zip(self.instance.skills(i)) {
                *h -= u64::from(q);
            }
        }
        let gained = self.value(j, size, &held) - self.value_now(j);
        self.scratch = held;
        gained
    }

    fn cost(&self, i: RobotId, at: Option<TaskId>) -> f64 {
        at.map_or(0.0, |j| self.instance.cost(i, j))
    }

    /// The welfare gained by moving robot i from `from` to `to`.
    fn move_gain(&mut self, i: RobotId, from: Option<TaskId>, to: Option<TaskId>) -> f64 {
        let left = from.map_or(0.0, |a| self.change(a, Some(i), None));
        let joined = to.map_or(0.0, |b| self.change(b, None, Some(i)));
        left + joined - self.cost(i, to) + self.cost(i, from)
    }

    /// The welfare gained by swapping robots i (at `a`) and k (at `b`).
    fn swap_gain(
        &mut self,
        (i, a): (RobotId, Option<TaskId>),
        (k, b): (RobotId, Option<TaskId>),
    ) -> f64 {
        let at_a = a.map_or(0.0, |a| self.change(a, Some(i), Some(k)));
        let at_b = b.map_or(0.0, |b| self.change(b, Some(k), Some(i)));
        at_a + at_b - self.cost(i, b) - self.cost(k, a) + self.cost(i, a) + self.cost(k, b)
    }

    /// Robot i leaves coalition j (`joins` false) or joins it.
    fn shift(&mut self, i: RobotId, j: Option<TaskId>, joins: bool) {
        let Some(j) = j else {
            return; // the void holds no coalition
        };
        let s = self.num_skills;
        let size = &mut self.sizes[j.index()];
        *size = if joins { *size + 1 } else { *size - 1 };
        for (h, &q) in self.held[j.index() * s..][..s]
            .iter_mut()
            .zip(self.instance.skills(i))
        {
            *h = if joins {
                *h + u64::from(q)
            } else {
                *h - u64::from(q)
            };
        }
    }

    /// Moves robot i to `to`, in the coalitions and in `assignment`.
    fn relocate(&mut self, assignment: &mut Assignment, i: RobotId, to: Option<TaskId>) {
        self.shift(i, assignment.task_of(i), false);
        self.shift(i, to, true);
        assignment.set(i, to);
    }

    /// Where robot i, now at `from`, gains most by moving, never to `from` or `barred`
    /// (or to a task without room); `None` where it cannot move.
    fn best_move(
        &mut self,
        assignment: &Assignment,
        places: &[Option<TaskId>],
        i: RobotId,
        barred: Option<TaskId>,
    ) -> Option<(f64, Option<TaskId>)> {
        let from = assignment.task_of(i);
        let mut best: Option<(f64, Option<TaskId>)> = None;
        for &to in places {
            if to == from
                || barred.is_some_and(|j| to == Some(j))
                || to.is_some_and(|b| !assignment.has_room(self.instance, i, b))
            {
                continue;
            }
            let gain = self.move_gain(i, from, to);
            if best.is_none_or(|(g, _)| gain > g) {
                best = Some((gain, to));
            }
        }
        best
    }

    /// One pass of single moves over every robot, each taken where it gains (never to
    /// `barred`): the number taken and the welfare they gained.
    fn move_pass(
        &mut self,
        assignment: &mut Assignment,
        places: &[Option<TaskId>],
        barred: Option<TaskId>,
    ) -> (u64, f64) {
        let (mut taken, mut gained) = (0, 0.0);
        for i in self.instance.robot_ids() {
            if let Some((gain, to)) = self.best_move(assignment, places, i, barred)
                && gain > MIN_GAIN
            {
                self.relocate(assignment, i, to);
                taken += 1;
                gained += gain;
            }
        }
        (taken, gained)
    }

    /// How much robot i would lessen task j's shortfall (members below its threshold,
    /// plus every skill's amount below its requirement) by joining it.
    fn lessens(&self, j: TaskId, i: RobotId) -> u64 {
        let below = u64::from(self.sizes[j.index()] < self.instance.min_team(j));
        let short = self
            .instance
            .requires(j)
            .iter()
            .zip(self.held(j))
            .zip(self.instance.skills(i))
            .map(|((&need, &have), &q)| u64::from(need).saturating_sub(have).min(u64::from(q)))
            .sum::<u64>();
        below + short
    }

    /// Staffs task j, which earns nothing now: robots join it one at a time, each the one
    /// that lessens its shortfall at the least welfare lost per unit, until it earns.
    /// The welfare gained (mostly lost), or `None` where no robot can lessen it.
    fn staff(&mut self, assignment: &mut Assignment, j: TaskId) -> Option<f64> {
        let mut gain = 0.0;
        while self.value_now(j) == 0.0 {
            let mut best: Option<(f64, f64, RobotId)> = None;
            for i in self.instance.robot_ids() {
                let from = assignment.task_of(i);
                let lessens = self.lessens(j, i);
                if from == Some(j) || lessens == 0 || !assignment.has_room(self.instance, i, j) {
                    continue;
                }
                let g = self.move_gain(i, from, Some(j));
                let per_unit = g / lessens as f64;
                if best.is_none_or(|(b, _, _)| per_unit > b) {
                    best = Some((per_unit, g, i));
                }
            }
            let (_, g, i) = best?;
            gain += g;
            self.relocate(assignment, i, Some(j));
        }
        Some(gain)
    }

    /// Dissolves the coalition at task j: each member in turn goes where it gains most
    /// (never back to j). The welfare gained, or `None` where a member has nowhere to go.
    fn dissolve(
        &mut self,
        assignment: &mut Assignment,
        places: &[Option<TaskId>],
        j: TaskId,
    ) -> Option<f64> {
        let members: Vec<RobotId> = self
            .instance
            .robot_ids()
            .filter(|&i| assignment.task_of(i) == Some(j))
            .collect();
        let mut gain = 0.0;
        for i in members {
            let (g, to) = self.best_move(assignment, places, i, Some(j))?;
            gain += g;
            self.relocate(assignment, i, to);
        }
        Some(gain)
    }

    /// Changes task j's team whole — dissolves it where it earns, staffs it where it
    /// does not — then climbs by single moves (never back to a dissolved task). Kept
    /// where the welfare rises; undone otherwise.
    fn change_team(
        &mut self,
        assignment: &mut Assignment,
        places: &[Option<TaskId>],
        j: TaskId,
    ) -> bool {
        let kept = (assignment.clone(), self.sizes.clone(), self.held.clone());
        let earns = self.value_now(j) > 0.0;
        let changed = if earns {
            self.dissolve(assignment, places, j)
        } else {
            self.staff(assignment, j)
        };
        if let Some(mut gain) = changed {
            let barred = earns.then_some(j);
            loop {
                let (taken, gained) = self.move_pass(assignment, places, barred);
                gain += gained;
                if taken == 0 {
                    break;
                }
            }
            if gain > MIN_GAIN {
                return true;
            }
        }
        (*assignment, self.sizes, self.held) = kept;
        false
    }
}

/// Climbs from `assignment` by robot moves, pairwise swaps, dissolved and staffed teams
/// until none raises the welfare; returns the number of changes made (a team change
/// counts once). The welfare never falls, capacities are kept, and a robot goes to the
/// void only in a game that has one.
///
/// # Examples
/// ```
/// use afg_baseline::climb;
/// use afg_game::{Assignment, Instance, Point, Task, TaskId};
/// let task = |x| Task { position: Point::new(x, 0.0), reward: 10.0, eps: 2.0, capacity: None };
/// let robots = vec![Point::new(0.0, 0.0), Point::new(5.0, 0.0)];
/// let inst = Instance::new(robots, vec![task(5.0), task(0.0)], 1.0)?;
/// // each robot at the task farther from it: two moves bring both home
/// let mut a = Assignment::from_tasks(&inst, vec![Some(TaskId(0)), Some(TaskId(1))])?;
/// let before = inst.welfare(&a);
/// assert_eq!(climb(&inst, &mut a), 2);
/// assert_eq!(a.tasks(), [Some(TaskId(1)), Some(TaskId(0))]);
/// assert!((inst.welfare(&a) - (before + 10.0)).abs() < 1e-9);
/// # Ok::<(), afg_game::GameError>(())
/// ```
///
/// # Panics
/// If the assignment was made for an instance of another size.
pub fn climb(instance: &Instance, assignment: &mut Assignment) -> u64 {
    assert_eq!(
        assignment.num_robots(),
        instance.num_robots(),
        "assignment of another instance"
    );
    let mut state = Coalitions {
        instance,
        sizes: assignment.sizes().to_vec(),
        held: instance.skills_held(assignment),
        num_skills: instance.num_skills(),
        scratch: Vec::new(),
    };
    let mut places: Vec<Option<TaskId>> = instance.task_ids().map(Some).collect();
    if instance.allows_void() {
        places.push(None);
    }
    let robots: Vec<RobotId> = instance.robot_ids().collect();
    let mut changes = 0;
    loop {
        let before = changes;
        changes += state.move_pass(assignment, &places, None).0;
        for (x, &i) in robots.iter().enumerate() {
            for &k in &robots[x + 1..] {
                let (a, b) = (assignment.task_of(i), assignment.task_of(k));
                if a != b && state.swap_gain((i, a), (k, b)) > MIN_GAIN {
                    state.relocate(assignment, i, b);
                    state.relocate(assignment, k, a);
                    changes += 1;
                }
            }
        }
        if changes == before {
            for j in instance.task_ids() {
                changes += u64::from(state.change_team(assignment, &places, j));
            }
        }
        if changes == before {
            return changes;
        }
    }
}
