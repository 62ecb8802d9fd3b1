//! A local search on the team solver's incumbents: a robot moved to another task (or
//! the void, where the game allows it), then two robots swapped, while a move raises
//! the welfare. It reads thresholds and skills, which the relaxations do not: the
//! relaxed optima the search offers often miss a team's last skill by one robot.

use afg_game::{Assignment, Instance, RobotId, TaskId};

/// Games with more robot–task pairs than this keep their incumbents as found: a sweep
/// of moves reads every pair.
const MAX_PAIRS: usize = 200_000;
/// Games with more robots than this try no swaps (a sweep of swaps reads every pair of
/// robots).
const MAX_SWAP_ROBOTS: usize = 400;
/// Sweeps at most (each one improves, so this is only a guard).
const MAX_SWEEPS: usize = 50;

/// Where the search stands: each task's size and skills held.
struct State<'a> {
    inst: &'a Instance,
    assignment: Assignment,
    held: Vec<u64>,
    s: usize,
}

impl State<'_> {
    /// What task `j` earns with `n` members holding `held` (its row of skills).
    fn value(&self, j: TaskId, n: usize, held: &[u64]) -> f64 {
        if self.inst.skills_met(j, held) {
            self.inst.coalition_value(j, n)
        } else {
            0.0
        }
    }

    fn row(&self, j: TaskId) -> &[u64] {
        &self.held[j.index() * self.s..][..self.s]
    }

    /// Task j's row after one robot with skills `out` leaves and one with `into`
    /// joins (either may be absent).
    fn changed(&self, j: TaskId, out: Option<&[u32]>, into: Option<&[u32]>) -> Vec<u64> {
        let mut row = self.row(j).to_vec();
        for (k, h) in row.iter_mut().enumerate() {
            *h = *h - out.map_or(0, |q| u64::from(q[k])) + into.map_or(0, |q| u64::from(q[k]));
        }
        row
    }

    /// The welfare change of robot i leaving its place for `to` (`None`: the void).
    fn move_gain(&self, i: RobotId, to: Option<TaskId>) -> f64 {
        let inst = self.inst;
        let from = self.assignment.task_of(i);
        let q = inst.skills(i);
        let mut gain = 0.0;
        if let Some(a) = from {
            let n = self.assignment.size(a);
            gain += self.value(a, n - 1, &self.changed(a, Some(q), None))
                - self.value(a, n, self.row(a));
            gain += inst.cost(i, a);
        }
        if let Some(b) = to {
            let n = self.assignment.size(b);
            gain += self.value(b, n + 1, &self.changed(b, None, Some(q)))
                - self.value(b, n, self.row(b));
            gain -= inst.cost(i, b);
        }
        gain
    }

    /// The welfare change of robots x and y trading places (both at tasks).
    fn swap_gain(&self, x: RobotId, y: RobotId) -> f64 {
        let inst = self.inst;
        let (Some(a), Some(b)) = (self.assignment.task_of(x), self.assignment.task_of(y)) else {
            return 0.0;
        };
        let (qx, qy) = (inst.skills(x), inst.skills(y));
        let (na, nb) = (self.assignment.size(a), self.assignment.size(b));
        self.value(a, na, &self.changed(a, Some(qx), Some(qy))) - self.value(a, na, self.row(a))
            + self.value(b, nb, &self.changed(b, Some(qy), Some(qx)))
            - self.value(b, nb, self.row(b))
            + inst.cost(x, a)
            + inst.cost(y, b)
            - inst.cost(x, b)
            - inst.cost(y, a)
    }

    fn place(&mut self, i: RobotId, to: Option<TaskId>) {
        let q = self.inst.skills(i).to_vec();
        if let Some(a) = self.assignment.task_of(i) {
            for (h, &k) in self.held[a.index() * self.s..][..self.s].iter_mut().zip(&q) {
                *h -= u64::from(k);
            }
        }
        if let Some(b) = to {
            for (h, &k) in self.held[b.index() * self.s..][..self.s].iter_mut().zip(&q) {
                *h += u64::from(k);
            }
        }
        self.assignment.set(i, to);
    }
}

/// `assignment` improved by moves and swaps while one raises the welfare by more than
/// rounding (unchanged in a game too large for a sweep).
pub(super) fn improve(inst: &Instance, assignment: Assignment) -> Assignment {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    if n * m > MAX_PAIRS {
        return assignment;
    }
    let mut state = State {
        held: inst.skills_held(&assignment),
        s: inst.num_skills(),
        assignment,
        inst,
    };
    let places: Vec<Option<TaskId>> = inst
        .task_ids()
        .map(Some)
        .chain(inst.allows_void().then_some(None))
        .collect();
    let tol = 1e-9 * inst.welfare(&state.assignment).abs().max(1.0);
    for _ in 0..MAX_SWEEPS {
        let mut improved = false;
        for i in inst.robot_ids() {
            let here = state.assignment.task_of(i);
            let best = places
                .iter()
                .filter(|&&to| {
                    to != here && to.is_none_or(|b| state.assignment.has_room(inst, i, b))
                })
                .map(|&to| (to, state.move_gain(i, to)))
                .max_by(|x, y| x.1.total_cmp(&y.1));
            if let Some((to, gain)) = best
                && gain > tol
            {
                state.place(i, to);
                improved = true;
            }
        }
        if !improved && n <= MAX_SWAP_ROBOTS && inst.has_skill_rules() {
            for x in inst.robot_ids() {
                for y in inst.robot_ids().skip(x.index() + 1) {
                    if state.assignment.task_of(x) != state.assignment.task_of(y)
                        && state.swap_gain(x, y) > tol
                    {
                        let (a, b) = (state.assignment.task_of(x), state.assignment.task_of(y));
                        state.place(x, None);
                        state.place(y, a);
                        state.place(x, b);
                        improved = true;
                    }
                }
            }
        }
        if !improved {
            break;
        }
    }
    state.assignment
}

#[cfg(test)]
mod tests {
    use afg_game::{Assignment, Family, Instance, RobotId, TaskId};

    use super::improve;

    /// Every robot, in turn, at its nearest task with room: a poor start on the team
    /// games.
    fn nearest(inst: &Instance) -> Assignment {
        let mut a = Assignment::unassigned(inst.num_robots(), inst.num_tasks());
        for i in inst.robot_ids() {
            let to = inst
                .task_ids()
                .filter(|&j| a.has_room(inst, i, j))
                .min_by(|&x, &y| inst.cost(i, x).total_cmp(&inst.cost(i, y)));
            a.set(i, to);
        }
        a
    }

    /// Whether some single move (to a task with room, or the void where allowed)
    /// raises the welfare, judged by the whole welfare: what `improve` must leave none of.
    fn a_move_improves(inst: &Instance, a: &Assignment) -> Option<(RobotId, Option<TaskId>)> {
        let here = inst.welfare(a);
        let places: Vec<Option<TaskId>> = inst
            .task_ids()
            .map(Some)
            .chain(inst.allows_void().then_some(None))
            .collect();
        for i in inst.robot_ids() {
            for &to in &places {
                if to == a.task_of(i) || to.is_some_and(|b| !a.has_room(inst, i, b)) {
                    continue;
                }
                let mut moved = a.clone();
                moved.set(i, to);
                if inst.welfare(&moved) > here + 1e-9 * here.abs().max(1.0) {
                    return Some((i, to));
                }
            }
        }
        None
    }

    #[test]
    fn the_local_search_only_raises_the_welfare_and_leaves_no_improving_move() {
        let mut raised = 0;
        for family in Family::ALL {
            for seed in 0..4 {
                let inst = family.config(24, 4, seed).unwrap().generate().unwrap();
                let start = nearest(&inst);
                let better = improve(&inst, start.clone());
                inst.check(&better).unwrap();
                let (before, after) = (inst.welfare(&start), inst.welfare(&better));
                assert!(
                    after >= before - 1e-9,
                    "{family} {seed}: {after} < {before}"
                );
                assert_eq!(a_move_improves(&inst, &better), None, "{family} {seed}");
                raised += usize::from(after > before + 1e-9);
            }
        }
        assert!(raised >= 30, "{raised} of 40 raised");
    }
}
