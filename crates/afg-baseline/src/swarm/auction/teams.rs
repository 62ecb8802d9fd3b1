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
//!
//! **Skills** (ours as well). A task requiring `r_js` of skill s gets a team of
//! `T_j = max(k_j, Σ_s r_js)` places whose first `r_j0` are skill-0 places, the next
//! `r_j1` skill-1 places and so on; only a robot holding skill s may bid for a skill-s
//! place (the others are general). A full team then holds every skill it requires. The
//! rule ranks tasks by `F_j(T_j) / T_j` and fits a task while its team fits in the
//! living robots and each of its skill places in that skill's holders (counted over
//! every robot, scaled to the living share; a robot holding two skills counts for
//! both, so a rare team may stay short). A robot reads every robot's skills from the
//! game, as it reads their positions: no message carries them.

use afg_game::{Instance, TaskId};

use super::table::Place;

/// The rule that picks the tasks to staff, and the team places' worth.
#[derive(Clone, Debug)]
pub(in crate::swarm) struct Staffing {
    /// The tasks in the order they are staffed: value per member, then index.
    order: Vec<usize>,
    /// Each task's team: `max(k_j, Σ_s r_js)` places (a task whose capacity is below it
    /// never earns).
    team: Vec<usize>,
    /// Each task's requirement of every skill (row-major M × S): its first places are
    /// skill places in that order.
    requires: Vec<usize>,
    /// Every skill's holders among all robots.
    holders: Vec<usize>,
    /// Every robot's skills, held or not (row-major N × S).
    held: Vec<bool>,
    /// What a team place is worth to any robot.
    bonus: f64,
}

impl Staffing {
    /// The rule for `instance` and an auction of increment `epsilon`, or `None` when
    /// no task needs a team or a skill (the concave game's places then).
    pub(in crate::swarm) fn of(instance: &Instance, epsilon: f64) -> Option<Staffing> {
        if !instance.has_skill_rules() && instance.task_ids().all(|j| instance.min_team(j) <= 1) {
            return None;
        }
        let s = instance.num_skills();
        let requires: Vec<usize> = (instance.task_ids())
            .flat_map(|j| instance.requires(j).iter().map(|&r| r as usize))
            .collect();
        let held: Vec<bool> = (instance.robot_ids())
            .flat_map(|i| instance.skills(i).iter().map(|&q| q > 0))
            .collect();
        let holders: Vec<usize> = (0..s)
            .map(|k| {
                held.iter()
                    .skip(k)
                    .step_by(s.max(1))
                    .filter(|&&h| h)
                    .count()
            })
            .collect();
        let team: Vec<usize> = (instance.task_ids())
            .map(|j| {
                let skills: usize = requires[j.index() * s..][..s].iter().sum();
                instance.min_team(j).max(skills)
            })
            .collect();
        let per_member = |j: usize| {
            let k = team[j];
            instance.value_function(TaskId(j as u32)).value(k) / k as f64
        };
        let possible = |j: usize| {
            team[j] <= instance.capacity(TaskId(j as u32))
                && (0..s).all(|k| requires[j * s + k] <= holders[k])
        };
        let mut order: Vec<usize> = (0..team.len()).filter(|&j| possible(j)).collect();
        order.sort_by(|&a, &b| per_member(b).total_cmp(&per_member(a)).then(a.cmp(&b)));
        // More than any later place (F's marginal after k) plus the widest difference
        // in cost, by 3ε: a robot within 2ε of its best choice takes a team place
        // before any other. No more than that: the robots beyond the teams raise the
        // team places' prices until they would rather stay out of them, by about
        // `bonus − later` in steps as small as ε.
        let later = (instance.task_ids())
            .map(|j| instance.value_function(j).marginal(team[j.index()] + 1))
            .fold(0.0, f64::max);
        let bonus = later + instance.beta() * span(instance) + 3.0 * epsilon;
        Some(Staffing {
            order,
            team,
            requires,
            holders,
            held,
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
                let k = self.team[j.index()];
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
        let s = self.holders.len();
        let n = self.held.len() / s.max(1);
        let mut staffed = vec![false; self.team.len()];
        let mut room = living;
        let mut skill_room: Vec<usize> = (self.holders.iter())
            .map(|&h| h * living / n.max(1))
            .collect();
        for &j in self.order.iter().filter(|&&j| known(j)) {
            let needs = &self.requires[j * s..][..s];
            if self.team[j] <= room && needs.iter().zip(&skill_room).all(|(r, left)| r <= left) {
                room -= self.team[j];
                for (left, r) in skill_room.iter_mut().zip(needs) {
                    *left -= r;
                }
                staffed[j] = true;
            }
        }
        staffed
    }

    /// Whether `place` is beyond its task's team (a place a robot may leave for a
    /// team place without breaking a team).
    pub(in crate::swarm) fn beyond_team(&self, (j, k): Place) -> bool {
        self.team
            .get(j as usize)
            .is_some_and(|&team| k as usize >= team)
    }

    /// Whether `robot` may bid for place k of task j: a skill place only where it
    /// holds that skill.
    pub(in crate::swarm) fn eligible(&self, robot: usize, j: usize, k: usize) -> bool {
        let s = self.holders.len();
        let mut first = 0;
        for (skill, &r) in self.requires[j * s..][..s].iter().enumerate() {
            if k < first + r {
                return self.held[robot * s + skill];
            }
            first += r;
        }
        true
    }

    /// The first place of task j from `from` on that `robot` may bid for.
    pub(in crate::swarm) fn first_eligible(&self, robot: usize, j: usize, from: usize) -> usize {
        (from..)
            .find(|&k| self.eligible(robot, j, k))
            .expect("every place past the skill places is general")
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
