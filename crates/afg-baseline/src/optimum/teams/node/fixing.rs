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

use super::super::super::transport;
use super::{Node, Search};

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
        let (bound, reduced) =
            transport::reduced_costs(inst, &relaxed.columns, &relaxed.prices, &adjust, &lambda);
        self.root_dual = Some(RootDual { bound, reduced });
        self.forbid();
    }

    /// Keeps out every pair the root's dual rules out for the best welfare found.
    pub(super) fn forbid(&mut self) {
        let Some(dual) = &self.root_dual else {
            return;
        };
        let (n, m) = (self.instance.num_robots(), self.instance.num_tasks());
        let width = dual.reduced.len() / n.max(1);
        if self.forbidden.is_empty() {
            self.forbidden = vec![false; n * m];
        }
        let best = self.best_welfare;
        let tolerance = 1e-9 * best.abs().max(1.0);
        for i in 0..n {
            for j in 0..m {
                if !self.forbidden[i * m + j]
                    && dual.bound - dual.reduced[i * width + j] <= best + tolerance
                {
                    self.forbidden[i * m + j] = true;
                    self.kept_out.push((i, j));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Search;
    use super::super::lagrange::tests::{every_assignment, skill_knobs};

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
            let mut search = Search::new(&inst);
            let root = search
                .node(search.root_decisions(), Vec::new(), None)
                .unwrap();
            search.price_skills(&root, &|| false);
            let assignments: Vec<_> = every_assignment(&inst).collect();
            let optimum = (assignments.iter())
                .map(|a| inst.welfare(a))
                .fold(f64::NEG_INFINITY, f64::max);
            search.best_welfare = optimum - 0.05 * optimum.abs();
            search.fix_pairs(&root);
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
            fixed += usize::from(!search.kept_out.is_empty());
        }
        assert!(2 * fixed >= games, "{fixed} of {games}");
    }
}
