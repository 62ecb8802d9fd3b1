//! The auction on a game whose tasks need teams (ours): which tasks the robots
//! staff, and what a task's places are worth.
//!
//! A task with threshold k earns nothing below k members, so the concave game's
//! places (the k-th worth `F(k) − F(k−1)`) would be worth 0, 0, …, F(k): no robot
//! bids first for a place that pays only once the team is complete, and the prices
//! of such places say nothing. Instead the robots agree, without a message, on
//! which tasks to staff, and every such task's first k places are made equal and
//! large:
//!
//! - **The tasks staffed.** Every robot ranks the tasks it knows are open by their
//!   value per member `F_j(k_j) / k_j` (ties: the lower index) and takes them in that
//!   order while their thresholds fit in the robots its epoch counts as living
//!   (first fit: a task too large for what is left is passed over, a smaller one
//!   after it may still fit). Robots that know the same tasks and epoch choose the
//!   same set.
//! - **The places.** A staffed task's first k places are team places, each worth the
//!   same bonus, more than any later place plus any difference in cost: the staffed
//!   set's value is then fixed, so only distances decide who fills which team and
//!   the auction fills every team place before any other (the thresholds fit in the
//!   robots), at the least total cost within its ε. Its later places are worth F's
//!   marginal values, as in the concave game. A task not staffed has no places.
//!
//! So, converged, every staffed task has its team. The staffing is a fixed rule, not
//! an optimum: the exact solver may staff other tasks (docs/teams.md measures what
//! that costs).

use afg_game::{Instance, TaskId};

use super::table::Place;

/// The rule that picks the tasks to staff, and the team places' worth.
#[derive(Clone, Debug)]
pub(in crate::swarm) struct Staffing {
    /// The tasks in the order they are staffed: value per member, then index.
    order: Vec<usize>,
    /// Each task's threshold k (a task whose capacity is below it never earns).
    min_team: Vec<usize>,
    /// What a team place is worth to any robot.
    bonus: f64,
}

impl Staffing {
    /// The rule for `instance` and an auction of increment `epsilon`, or `None` when
    /// no task needs a team (the concave game's places then).
    pub(in crate::swarm) fn of(instance: &Instance, epsilon: f64) -> Option<Staffing> {
        if instance.task_ids().all(|j| instance.min_team(j) <= 1) {
            return None;
        }
        let min_team: Vec<usize> = instance.task_ids().map(|j| instance.min_team(j)).collect();
        let per_member = |j: usize| {
            let k = min_team[j];
            instance.value_function(TaskId(j as u32)).value(k) / k as f64
        };
        let mut order: Vec<usize> = (0..min_team.len())
            .filter(|&j| min_team[j] <= instance.capacity(TaskId(j as u32)))
            .collect();
        order.sort_by(|&a, &b| per_member(b).total_cmp(&per_member(a)).then(a.cmp(&b)));
        // More than any later place (F's marginal after k) plus the widest difference
        // in cost, by 3ε: a robot within 2ε of its best choice takes a team place
        // before any other. No more than that: the robots beyond the teams raise the
        // team places' prices until they would rather stay out of them, by about
        // `bonus − later` in steps as small as ε.
        let later = (instance.task_ids())
            .map(|j| {
                instance
                    .value_function(j)
                    .marginal(instance.min_team(j) + 1)
            })
            .fold(0.0, f64::max);
        let bonus = later + instance.beta() * span(instance) + 3.0 * epsilon;
        Some(Staffing {
            order,
            min_team,
            bonus,
        })
    }

    /// The worth of each staffed task's places, k from 0, as many as `places(j)`.
    pub(in crate::swarm) fn values(
        &self,
        instance: &Instance,
        places: impl Fn(TaskId) -> usize,
    ) -> Vec<Vec<f64>> {
        (instance.task_ids())
            .map(|j| {
                let value = instance.value_function(j);
                let k = self.min_team[j.index()];
                (1..=places(j))
                    .map(|n| {
                        if n <= k {
                            self.bonus
                        } else {
                            value.marginal(n)
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// The tasks staffed by a robot that knows the tasks `known` accepts are open
    /// and counts `living` robots.
    pub(in crate::swarm) fn staffed(
        &self,
        living: usize,
        known: impl Fn(usize) -> bool,
    ) -> Vec<bool> {
        let mut staffed = vec![false; self.min_team.len()];
        let mut room = living;
        for &j in self.order.iter().filter(|&&j| known(j)) {
            if self.min_team[j] <= room {
                room -= self.min_team[j];
                staffed[j] = true;
            }
        }
        staffed
    }

    /// Whether `place` is beyond its task's team (a place a robot may leave for a
    /// team place without breaking a team).
    pub(in crate::swarm) fn beyond_team(&self, (j, k): Place) -> bool {
        self.min_team
            .get(j as usize)
            .is_some_and(|&team| k as usize >= team)
    }
}

/// The diagonal of the box holding every robot and task of `instance`: no robot of a
/// mission leaves it (robots move towards tasks).
fn span(instance: &Instance) -> f64 {
    let points = (instance.robots().iter()).chain(instance.tasks().iter().map(|t| &t.position));
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for p in points {
        lo = (lo.0.min(p.x), lo.1.min(p.y));
        hi = (hi.0.max(p.x), hi.1.max(p.y));
    }
    (hi.0 - lo.0).hypot(hi.1 - lo.1)
}
