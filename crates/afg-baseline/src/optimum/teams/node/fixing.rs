//! Reduced-cost fixing: robot-task pairs that no assignment better than the best found
//! can use, kept out of every node.
//!
//! The root's relaxation (at the skill prices the root chose) has a dual: one price
//! per column. Any assignment's welfare is at most that dual's bound less, for every
//! robot, how much less its column gains it than its best column does (its reduced
//! cost there; [`transport::reduced_costs`]). Where robot i's reduced cost at task j
//! alone takes the bound to the best welfare found, no better assignment puts i at
//! j: the pair is kept out of every node's relaxation, which tightens them all. Each
//! better assignment found keeps out more.
//!
//! **Below a node** (ours). Where skills are priced, every node's Lagrangian relaxation
//! has a dual of its own, as tight as the node's bound: the pairs it rules out are
//! kept out of that node and every node below it ([`Search::keep_out_below`]), which
//! shortens the chains of "this robot may not bring the skill" branches.
//!
//! **Tasks ruled out.** The same dual bounds an assignment in which task j earns by
//! the reduced costs of the team it needs there: at least its threshold of robots, and
//! for every skill it requires, robots holding that much of it. Where even the cheapest
//! such team ([`cheapest_team_closes`]) takes the bound to the best found, no better
//! assignment lets j earn: it is decided unstaffed in every node. Each better
//! assignment found asks again of every task still open, so the exact cheapest team (a
//! dynamic programme over the units still lacking) is asked for only where a lower
//! bound on it does not already settle the question and a greedy team does not
//! already show that it cannot.

use afg_game::{RobotId, TaskId};

use super::super::super::transport::{self, Costs};
use super::cover::cheapest_team_closes;
use super::lagrange::Relaxed;
use super::{Decision, Node, Pair, Search};

/// The root's dual bound and every robot's reduced cost at every column (row-major).
pub(super) struct RootDual {
    bound: f64,
    reduced: Vec<f64>,
}

impl Search<'_> {
    /// Prices the root's relaxation at the search's skill prices (none: the envelope's)
    /// and keeps out every pair the best found already rules out.
    pub(in super::super) fn fix_pairs(&mut self, root: &Node) {
        let inst = self.instance;
        let lambda = if self.skill_prices.is_empty() {
            vec![0.0; inst.num_tasks() * inst.num_skills()]
        } else {
            self.skill_prices.clone()
        };
        let Some(relaxed) = self.relax(&root.decisions, &root.pairs, &lambda, &root.prices) else {
            return;
        };
        let adjust = self.adjust(&root.pairs);
        let (bound, reduced) = transport::reduced_costs(
            inst,
            &relaxed.columns,
            &relaxed.prices,
            self.costs(&adjust, &lambda),
        );
        self.root_dual = Some(RootDual { bound, reduced });
        self.forbid();
    }

    /// Keeps out every pair, and rules out every task, that the root's dual rules out
    /// for the best welfare found.
    pub(super) fn forbid(&mut self) {
        let Some(dual) = self.root_dual.take() else {
            return; // the root was not priced (a game too large for it)
        };
        // The root is priced only where the travel table is kept (`MAX_PAIRS`).
        debug_assert!(
            !self.travel.is_empty(),
            "a priced root without a travel table"
        );
        let keep_out = self.keep_out_cost();
        let (n, m) = (self.instance.num_robots(), self.instance.num_tasks());
        let width = dual.reduced.len() / n.max(1);
        if self.forbidden.is_empty() {
            self.forbidden = vec![false; n * m];
        }
        for i in 0..n {
            for j in 0..m {
                if !self.forbidden[i * m + j]
                    && self.closes(dual.bound - dual.reduced[i * width + j])
                {
                    self.forbidden[i * m + j] = true;
                    self.travel[i * width + j] += keep_out;
                }
            }
        }
        if self.cannot_earn.is_empty() {
            self.cannot_earn = vec![false; m];
        }
        let mut reduced = Vec::with_capacity(n);
        for j in self.instance.task_ids() {
            if self.cannot_earn[j.index()] {
                continue;
            }
            reduced.clear();
            reduced.extend((0..n).map(|i| dual.reduced[i * width + j.index()]));
            let closes = |cost: f64| self.closes(dual.bound - cost);
            self.cannot_earn[j.index()] =
                cheapest_team_closes(self.instance, j, self.threshold(j), &reduced, closes);
        }
        self.root_dual = Some(dual);
    }

    /// What keeping a robot out of a task adds to its cost there (fixing it takes as
    /// much off): more than any assignment's welfare can make up.
    pub(super) fn keep_out_cost(&self) -> f64 {
        4.0 * self.bonus
    }

    /// The cost changes that fix robots at tasks or keep them out: `pairs`'.
    pub(super) fn adjust(&self, pairs: &[Pair]) -> Vec<(usize, usize, f64)> {
        let fix = self.keep_out_cost();
        pairs
            .iter()
            .map(|&(i, j, fixed)| (i.index(), j.index(), if fixed { -fix } else { fix }))
            .collect()
    }

    /// A relaxation's costs: the travel costs with the pairs the root's dual rules out
    /// kept out, `adjust` (see [`Search::adjust`]), and the skills' worth at
    /// `skill_prices`.
    pub(super) fn costs<'s>(
        &'s self,
        adjust: &'s [(usize, usize, f64)],
        skill_prices: &'s [f64],
    ) -> Costs<'s> {
        Costs {
            travel: (!self.travel.is_empty()).then_some(self.travel.as_slice()),
            adjust,
            skill_prices,
        }
    }

    /// Keeps out of a node, and so of every node below it, each pair that the node's
    /// Lagrangian relaxation (`relaxed`, its dual) rules out for the best found, as the
    /// root's dual does for every node: any assignment of the node is worth at most the
    /// relaxation's bound less its robots' reduced costs there (the bonuses of fixed robots and staffed
    /// tasks are the same for all of them). Robots fixed by the node, pairs already
    /// out, and tasks decided unstaffed are left as they are.
    pub(super) fn keep_out_below(
        &self,
        decisions: &[Decision],
        pairs: &mut Vec<Pair>,
        relaxed: &Relaxed,
    ) {
        let inst = self.instance;
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let adjust = self.adjust(pairs);
        let (_, reduced) = transport::reduced_costs(
            inst,
            &relaxed.columns,
            &relaxed.prices,
            self.costs(&adjust, &relaxed.lambda),
        );
        let width = reduced.len() / n.max(1);
        let mut listed = self.barred(pairs);
        for &(i, _, fixed) in pairs.iter() {
            if fixed {
                listed[i.index() * m..][..m].fill(true);
            }
        }
        for i in inst.robot_ids() {
            for j in inst.task_ids() {
                let out = decisions[j.index()] == Decision::Unstaffed
                    || listed[i.index() * m + j.index()]
                    || !self.allowed(i, j);
                if !out && self.closes(relaxed.bound - reduced[i.index() * width + j.index()]) {
                    pairs.push((i, j, false));
                }
            }
        }
    }

    /// Whether task j can still get every skill it requires from the robots free to
    /// join it: allowed there, and not `barred` (see [`Search::barred`]).
    pub(super) fn skills_reachable(&self, j: TaskId, barred: &[bool]) -> bool {
        let inst = self.instance;
        let mut held = vec![0u64; inst.num_skills()];
        for i in inst.robot_ids().filter(|&i| self.free(barred, i, j)) {
            for (h, &q) in held.iter_mut().zip(inst.skills(i)) {
                *h += u64::from(q);
            }
        }
        inst.skills_met(j, &held)
    }

    /// Whether robot i is free to join task j at a node: allowed there, and not
    /// `barred` (see [`Search::barred`]).
    pub(super) fn free(&self, barred: &[bool], i: RobotId, j: TaskId) -> bool {
        self.allowed(i, j) && !barred[i.index() * self.instance.num_tasks() + j.index()]
    }

    /// Where `pairs` bar robot i from task j (fixed elsewhere, or kept out of it):
    /// row-major N × M.
    pub(super) fn barred(&self, pairs: &[Pair]) -> Vec<bool> {
        let m = self.instance.num_tasks();
        let mut barred = vec![false; self.instance.num_robots() * m];
        for &(i, j, fixed) in pairs {
            let row = &mut barred[i.index() * m..][..m];
            for (k, bar) in row.iter_mut().enumerate() {
                *bar |= (k == j.index()) != fixed;
            }
        }
        barred
    }
}

#[cfg(test)]
mod tests {
    use afg_game::{Assignment, Instance};

    use super::super::Search;
    use super::super::lagrange::tests::{every_assignment, in_region, skill_knobs};

    /// Every assignment of `inst`, its optimum, and its search with the root priced and
    /// the pairs and tasks ruled out for a best found `below` the optimum (a share).
    fn ruled_out(inst: &Instance, below: f64) -> (Search<'_>, Vec<Assignment>, f64) {
        let mut search = Search::exact(inst);
        let root = search
            .node(search.root_decisions(), Vec::new(), None)
            .unwrap();
        search.price_skills(&root, &|| false);
        let assignments: Vec<_> = every_assignment(inst).collect();
        let optimum = (assignments.iter())
            .map(|a| inst.welfare(a))
            .fold(f64::NEG_INFINITY, f64::max);
        search.best_welfare = optimum - below * optimum.abs();
        search.fix_pairs(&root);
        (search, assignments, optimum)
    }

    /// The root's dual bounds every assignment less its robots' reduced costs (so the
    /// pairs it keeps out are used by no assignment better than the best found), on
    /// small skill games whose best found is set a little below the optimum; and it
    /// keeps some out in most of them.
    #[test]
    fn the_pairs_kept_out_are_in_no_better_assignment() {
        let (mut games, mut fixed) = (0, 0);
        for seed in 0..40 {
            let inst = skill_knobs(0.5, (0, 2))
                .config(6, 3, seed)
                .unwrap()
                .generate()
                .unwrap();
            let (search, assignments, optimum) = ruled_out(&inst, 0.05);
            let dual = search.root_dual.as_ref().unwrap();
            let width = dual.reduced.len() / inst.num_robots();
            let tol = 1e-9 * optimum.abs().max(1.0);
            for a in &assignments {
                let reduced: f64 = (inst.robot_ids())
                    .map(|i| {
                        let column = a.task_of(i).map_or(inst.num_tasks(), |j| j.index());
                        dual.reduced[i.index() * width + column]
                    })
                    .sum();
                let welfare = inst.welfare(a);
                assert!(
                    welfare <= dual.bound - reduced + tol,
                    "seed {seed}: {welfare}"
                );
                if welfare > search.best_welfare + tol {
                    assert!(
                        search.keeps(a, &[]),
                        "seed {seed}: a better assignment kept out"
                    );
                }
            }
            games += 1;
            fixed += usize::from(search.forbidden.contains(&true));
        }
        assert!(2 * fixed >= games, "{fixed} of {games}");
    }

    /// A task the root's dual rules out earns in no assignment better than the best
    /// found, on small skill games whose best found is set a little below the optimum;
    /// and some are ruled out.
    #[test]
    fn the_tasks_ruled_out_earn_in_no_better_assignment() {
        let (mut tasks, mut ruled) = (0, 0);
        for seed in 0..60 {
            let inst = skill_knobs(0.4, (0, 2))
                .config(6, 3, seed)
                .unwrap()
                .generate()
                .unwrap();
            let (search, assignments, optimum) = ruled_out(&inst, 0.02);
            let tol = 1e-9 * optimum.abs().max(1.0);
            for a in assignments
                .iter()
                .filter(|a| inst.welfare(a) > search.best_welfare + tol)
            {
                let held = inst.skills_held(a);
                let s = inst.num_skills();
                for j in inst.task_ids().filter(|&j| search.cannot_earn[j.index()]) {
                    let earns = inst.earns(j, a.size(j), &held[j.index() * s..][..s]);
                    assert!(!earns, "seed {seed}: task {} earns", j.index());
                }
            }
            tasks += inst.num_tasks();
            ruled += search.cannot_earn.iter().filter(|&&c| c).count();
        }
        assert!(ruled * 10 >= tasks, "{ruled} of {tasks}");
    }

    /// A node's dual keeps out only pairs that no assignment of the node better than the
    /// best found uses (brute force over every assignment of small skill games, at the
    /// root and at its two children, the best found set a little below the optimum),
    /// and it keeps some out.
    #[test]
    fn the_pairs_a_node_keeps_out_are_in_none_of_its_better_assignments() {
        let mut kept = 0;
        for seed in 0..200 {
            let inst = (skill_knobs(0.4, (0, 2)).config(6, 3, seed).unwrap())
                .generate()
                .unwrap();
            let (mut search, assignments, optimum) = ruled_out(&inst, 0.03);
            let mut best = search.best_welfare;
            let root = search
                .node(search.root_decisions(), Vec::new(), None)
                .unwrap();
            let mut regions = vec![(root.decisions.clone(), root.pairs.clone())];
            if let Some(branch) = search.branch(&root) {
                regions.extend(search.children(&root, branch));
            }
            let tol = 1e-9 * optimum.abs().max(1.0);
            for (decisions, pairs) in regions {
                let Some(Some(dual)) = search.skill_bound(&decisions, &pairs, &root) else {
                    continue;
                };
                // The steps may have found better, and the root's dual has kept pairs
                // out for that since (`forbid`): what is checked is the best held.
                best = best.max(search.best_welfare);
                let mut after = pairs.clone();
                search.keep_out_below(&decisions, &mut after, &dual.relaxed);
                let out = &after[pairs.len()..];
                kept += out.len();
                let of_node = |a: &&Assignment| in_region(&inst, &decisions, &pairs, a);
                for a in assignments.iter().filter(of_node) {
                    if inst.welfare(a) > best + tol {
                        for &(i, j, _) in out {
                            assert_ne!(a.task_of(i), Some(j), "seed {seed}: a better one kept out");
                        }
                    }
                }
            }
        }
        assert!(kept >= 20, "{kept} pairs kept out");
    }
}
