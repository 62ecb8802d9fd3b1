//! The search's roundings: the dive that finds the first incumbent, the skill dive
//! that brings a staffing's missing skills, and the assignment built from where a
//! stopped root left the robots.

use afg_game::{Assignment, RobotId, TaskId};

use super::{Branch, Decision, Node, Search};
use crate::Greedy;

impl Search<'_> {
    /// A real assignment near where a stopped solve left the robots (`task_of`, a
    /// column each): the tasks it left at least half staffed, fullest first, each
    /// take the nearest robots still free up to their threshold where those are
    /// worth their travel; the others are placed by [`Greedy::complete`] (which joins
    /// them to staffed teams, or completes a team one short). O(N M).
    pub(super) fn completed(&self, task_of: &[u32]) -> Assignment {
        let inst = self.instance;
        let m = inst.num_tasks();
        let mut sizes = vec![0usize; m];
        for &j in task_of.iter().filter(|&&j| (j as usize) < m) {
            sizes[j as usize] += 1;
        }
        let fill = |j: TaskId| sizes[j.index()] as f64 / self.threshold(j) as f64;
        let mut tasks: Vec<TaskId> = inst.task_ids().filter(|&j| fill(j) >= 0.5).collect();
        tasks.sort_by(|&a, &b| fill(b).total_cmp(&fill(a)));
        let mut staffed = Assignment::unassigned(inst.num_robots(), m);
        let mut free: Vec<RobotId> = inst.robot_ids().collect();
        for j in tasks {
            let k = self.threshold(j);
            if k > free.len() || k > inst.capacity(j) {
                continue;
            }
            let mut nearest: Vec<(f64, usize)> = (free.iter().enumerate())
                .map(|(at, &i)| (inst.cost(i, j), at))
                .collect();
            nearest.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            let travel: f64 = nearest[..k].iter().map(|&(cost, _)| cost).sum();
            if inst.coalition_value(j, k) > travel {
                let mut taken: Vec<usize> = nearest[..k].iter().map(|&(_, at)| at).collect();
                taken.sort_unstable_by(|a, b| b.cmp(a));
                for at in taken {
                    staffed.set(free.swap_remove(at), Some(j));
                }
            }
        }
        Greedy.complete(inst, &staffed)
    }

    /// Brings the skills that the earning tasks of `node` lack, robot by robot: each
    /// step fixes the robot that the skill branching names (the cheapest one free to
    /// bring a missing skill to the earning task with the most value at stake) at that
    /// task, or keeps it out where that leaves no assignment, or, where neither does
    /// (the robots that hold the skill are fixed at other tasks), gives the task up
    /// (unstaffed, its robots free again), and re-solves, until no earning task lacks a
    /// skill or no robot can bring one, or `out_of_time`. Every assignment met is offered
    /// to the best found. Nothing happens in a game without skills. Returns the node
    /// where no earning task lacks a skill that a robot can bring (`None`: stopped
    /// before, out of time or out of children).
    pub(in crate::optimum::teams) fn skill_dive(
        &mut self,
        node: Node,
        out_of_time: &dyn Fn() -> bool,
    ) -> Option<Node> {
        let mut current = node;
        loop {
            if out_of_time() {
                return None;
            }
            let Some(branch @ Branch::Pair(_, task)) = self.skill_branch(&current) else {
                return Some(current);
            };
            let [(join, with), (keep_out, without)] = self.children(&current, branch);
            let give_up = || {
                let mut decisions = current.decisions.clone();
                decisions[task.index()] = Decision::Unstaffed;
                let mut pairs = current.pairs.clone();
                pairs.retain(|&(_, j, _)| j != task);
                (decisions, pairs)
            };
            let next = self
                .node(join, with, Some(&current))
                .or_else(|| self.node(keep_out, without, Some(&current)))
                .or_else(|| {
                    let (decisions, pairs) = give_up();
                    self.node(decisions, pairs, Some(&current))
                });
            current = next?;
        }
    }

    /// Rounds the relaxation down to an assignment with no task between 0 and its
    /// threshold, a good first incumbent: `round` decides every such task of a node at
    /// once (staffed or not; all unstaffed where its choice asks for too many robots),
    /// and the node is re-solved until none is left or `out_of_time`. Returns the node
    /// where it ended with no task left to decide (`None`: stopped before).
    pub(in crate::optimum::teams) fn dive(
        &mut self,
        root: &Node,
        out_of_time: &dyn Fn() -> bool,
        round: &mut dyn FnMut(&Node, &[TaskId]) -> Vec<bool>,
    ) -> Option<Node> {
        let mut current = root.clone();
        while !out_of_time() {
            let sizes = &current.sizes;
            let fractional: Vec<TaskId> = self
                .instance
                .task_ids()
                .filter(|&j| current.decisions[j.index()] == Decision::Open)
                .filter(|&j| sizes[j.index()] > 0 && sizes[j.index()] < self.threshold(j))
                .collect();
            if fractional.is_empty() {
                return Some(current);
            }
            let staff = round(&current, &fractional);
            let rounded = |keep: bool| {
                let mut decisions = current.decisions.clone();
                for (&j, &staff) in fractional.iter().zip(&staff) {
                    decisions[j.index()] = if keep && staff {
                        Decision::Staffed
                    } else {
                        Decision::Unstaffed
                    };
                }
                decisions
            };
            let pairs = current.pairs.clone();
            let next = self
                .node(rounded(true), pairs.clone(), Some(&current))
                .or_else(|| self.node(rounded(false), pairs, Some(&current)));
            match next {
                Some(next) => current = next,
                None => return None,
            }
        }
        None
    }
}
