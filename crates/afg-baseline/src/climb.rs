//! Hill climbing on the welfare (ours): single robot moves and pairwise swaps.
//!
//! A finish for any allocator of a team game: robots move to another task (or to the
//! void where the game has one) and pairs of robots at different tasks swap, each change
//! taken as soon as it raises the welfare, until none does. A change touches two
//! coalitions, so each is priced from their sizes and held skills in O(S).

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
}

impl Coalitions<'_> {
    /// What task j earns with `size` members holding `held`.
    fn value(&self, j: TaskId, size: usize, held: &[u64]) -> f64 {
        if size >= self.instance.min_team(j) && self.instance.skills_met(j, held) {
            self.instance.coalition_value(j, size)
        } else {
            0.0
        }
    }

    fn held(&self, j: TaskId) -> &[u64] {
        &self.held[j.index() * self.num_skills..][..self.num_skills]
    }

    /// Task j's value now, and with robot `out` leaving and robot `into` joining.
    fn change(&self, j: TaskId, out: Option<RobotId>, into: Option<RobotId>) -> f64 {
        let mut held = self.held(j).to_vec();
        let mut size = self.sizes[j.index()];
        if let Some(i) = out {
            size -= 1;
            for (h, &q) in held.iter_mut().zip(self.instance.skills(i)) {
                *h -= u64::from(q);
            }
        }
        if let Some(i) = into {
            size += 1;
            for (h, &q) in held.iter_mut().zip(self.instance.skills(i)) {
                *h += u64::from(q);
            }
        }
        self.value(j, size, &held) - self.value(j, self.sizes[j.index()], self.held(j))
    }

    fn cost(&self, i: RobotId, at: Option<TaskId>) -> f64 {
        at.map_or(0.0, |j| self.instance.cost(i, j))
    }

    /// The welfare gained by moving robot i from `from` to `to`.
    fn move_gain(&self, i: RobotId, from: Option<TaskId>, to: Option<TaskId>) -> f64 {
        let left = from.map_or(0.0, |a| self.change(a, Some(i), None));
        let joined = to.map_or(0.0, |b| self.change(b, None, Some(i)));
        left + joined - self.cost(i, to) + self.cost(i, from)
    }

    /// The welfare gained by swapping robots i (at `a`) and k (at `b`).
    fn swap_gain(
        &self,
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
}

/// Climbs from `assignment` by robot moves and pairwise swaps until no single one
/// raises the welfare; returns the number of changes made. The welfare never falls,
/// capacities are kept, and a robot goes to the void only in a game that has one.
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
    };
    let mut places: Vec<Option<TaskId>> = instance.task_ids().map(Some).collect();
    if instance.allows_void() {
        places.push(None);
    }
    let robots: Vec<RobotId> = instance.robot_ids().collect();
    let mut changes = 0;
    loop {
        let before = changes;
        for &i in &robots {
            let from = assignment.task_of(i);
            let to = places.iter().copied().find(|&to| {
                to != from
                    && to.is_none_or(|b| assignment.has_room(instance, i, b))
                    && state.move_gain(i, from, to) > MIN_GAIN
            });
            if let Some(to) = to {
                state.shift(i, from, false);
                state.shift(i, to, true);
                assignment.set(i, to);
                changes += 1;
            }
        }
        for (x, &i) in robots.iter().enumerate() {
            for &k in &robots[x + 1..] {
                let (a, b) = (assignment.task_of(i), assignment.task_of(k));
                if a != b && state.swap_gain((i, a), (k, b)) > MIN_GAIN {
                    state.shift(i, a, false);
                    state.shift(k, b, false);
                    state.shift(i, b, true);
                    state.shift(k, a, true);
                    assignment.set(i, b);
                    assignment.set(k, a);
                    changes += 1;
                }
            }
        }
        if changes == before {
            return changes;
        }
    }
}
