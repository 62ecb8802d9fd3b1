//! A bound on how many tasks earn at once, priced into every node's relaxation.
//!
//! Every earning task holds at least its threshold of the N robots, so at most C tasks
//! earn at once: C, the most thresholds that fit in N, smallest first. For any price
//! μ ≥ 0, an assignment's welfare is at most its welfare plus μ (C − its earning
//! tasks): each earning task pays μ (its value less μ from its threshold on, whose
//! envelope is again a transport column, as the skills' prices are) and the bound gains
//! μ C. Where the envelope spreads the robots over more than C teams — every threshold
//! alike and N not a multiple of it, say — the price takes that fraction of a team
//! back. The root chooses μ by bisection on the subgradient C − Σ_j y_j (y_j, the share
//! of its team a task holds in the relaxed optimum), and every node after it is priced
//! at that μ where it closes a good share of the root's gap ([`KEEP_SHARE`]; a price
//! that closes little only makes every node's relaxation harder to close).

use super::super::super::transport::{self, NEVER};
use afg_game::TaskId;

use super::{Branch, Decision, MAX_PAIRS, Node, Search};

/// Bisection steps on the count price at the root.
const BISECTIONS: usize = 12;
/// The share of the root's gap (its bound less the best found) the price must close
/// for the nodes to be priced at it.
const KEEP_SHARE: f64 = 0.25;

/// The most tasks that can earn at once among N robots: `thresholds` within N,
/// smallest first, while they fit.
pub(super) fn count_cap(thresholds: &[usize], n: usize) -> usize {
    let mut thresholds: Vec<usize> = thresholds.iter().copied().filter(|&k| k <= n).collect();
    thresholds.sort_unstable();
    let mut left = n;
    thresholds
        .into_iter()
        .take_while(|&k| {
            let fits = k <= left;
            left -= k.min(left);
            fits
        })
        .count()
}

impl Search<'_> {
    /// The root's relaxation priced at `price` per earning task: its bound and the
    /// teams it holds (Σ_j y_j); `None` where it cannot keep the root's fixed robots.
    fn priced_root(&mut self, root: &Node, price: f64) -> Option<(f64, f64)> {
        self.count_price = price;
        let mut decisions = root.decisions.clone();
        let columns = self.columns(&mut decisions, &root.pairs)?;
        let adjust = self.adjust(&root.pairs);
        let Ok(solution) = transport::solve_columns(
            self.instance,
            &columns,
            Some(&root.prices),
            self.costs(&adjust, &[]),
            NEVER,
        ) else {
            unreachable!("never stopped")
        };
        let node = self.node_of(
            decisions,
            root.pairs.clone(),
            Vec::new(),
            &columns,
            solution,
        )?;
        let teams = (self.instance.task_ids())
            .map(|j| match node.decisions[j.index()] {
                Decision::Staffed => 1.0,
                Decision::Unstaffed => 0.0,
                Decision::Open => match self.task_column(j, Decision::Open, price).1 {
                    0 => 0.0,
                    flat => (node.sizes[j.index()] as f64 / flat as f64).min(1.0),
                },
            })
            .sum();
        Some((node.bound, teams))
    }

    /// Prices the root after its dive, where a Lagrangian solve may read every pair
    /// ([`MAX_PAIRS`]; beyond, one root solve is already long): in a game with skills
    /// the skills, then the pairs its dual rules out, then the count of earning tasks,
    /// each lowering its bound. The count comes last:
    /// the assignments its solves find would move the target of the skills' steps.
    pub(in super::super) fn price_root(&mut self, root: &mut Node, out_of_time: &dyn Fn() -> bool) {
        let inst = self.instance;
        let small = inst.num_robots() * inst.num_tasks() <= MAX_PAIRS;
        if inst.has_skill_rules() && small {
            root.bound = root.bound.min(self.price_skills(root, out_of_time));
        }
        if small {
            self.fix_pairs(root);
            root.bound = root.bound.min(self.price_count(root, out_of_time));
        }
    }

    /// Chooses the price of an earning task at the root (bisection on the subgradient,
    /// at most [`BISECTIONS`] solves, until `out_of_time`), keeps the one of the lowest
    /// bound for every later node (0 where none lowers it), and returns that bound.
    pub(in super::super) fn price_count(
        &mut self,
        root: &Node,
        out_of_time: &dyn Fn() -> bool,
    ) -> f64 {
        let cap = self.count_cap as f64;
        let mut best = (root.bound, 0.0);
        let teams_at_zero = (root.sizes.iter().zip(&root.decisions))
            .filter(|&(&n, d)| n > 0 && *d != Decision::Unstaffed)
            .count();
        if self.closes(root.bound) || (teams_at_zero as f64) <= cap {
            return root.bound; // fewer teams than C are even touched: the price cannot bind
        }
        let (mut low, mut high) = (0.0, self.most_a_team_earns());
        for _ in 0..BISECTIONS {
            if out_of_time() {
                break;
            }
            let price = 0.5 * (low + high);
            let Some((bound, teams)) = self.priced_root(root, price) else {
                break;
            };
            if bound < best.0 {
                best = (bound, price);
            }
            if teams > cap {
                low = price;
            } else {
                high = price;
            }
        }
        // A price that closes little of the root's gap only slows every node down.
        let closed = (root.bound - best.0) / (root.bound - self.best_welfare);
        self.count_price = if closed >= KEEP_SHARE { best.1 } else { 0.0 };
        best.0
    }

    /// Where a node still branches once no task is between 0 and its threshold: with a
    /// price on earning, an open task's column meets its value less the price only at 0
    /// and from the size its envelope spreads over (which the price can raise above the
    /// threshold), so an open task between its threshold and that size is decided first;
    /// then, where fewer tasks earn than may (C), the open task worth most at its
    /// threshold (only with C earning is the relaxation's assignment worth its bound).
    /// `None` without a price, or with no open task left (the node's relaxation is then
    /// its own optimum, its decisions fixing how many earn).
    pub(super) fn count_branch(&self, node: &Node) -> Option<Branch> {
        if self.count_price <= 0.0 {
            return None;
        }
        let inst = self.instance;
        let open: Vec<TaskId> = (inst.task_ids())
            .filter(|j| node.decisions[j.index()] == Decision::Open)
            .collect();
        let between = open.iter().find(|&&j| {
            let n = node.sizes[j.index()];
            match self.task_column(j, Decision::Open, self.count_price).1 {
                0 => n >= self.threshold(j), // worth nothing in the relaxation, yet earning
                flat => n > 0 && n < flat,
            }
        });
        if let Some(j) = between {
            return Some(Branch::Task(j.index()));
        }
        let earning = (inst.task_ids())
            .filter(|j| node.decisions[j.index()] != Decision::Unstaffed)
            .filter(|j| node.sizes[j.index()] >= self.threshold(*j))
            .count();
        if earning >= self.count_cap {
            return None;
        }
        (open.into_iter())
            .map(|j| (j, inst.value_function(j).value(self.threshold(j))))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(j, _)| Branch::Task(j.index()))
    }

    /// The most any task's coalition is worth (a price above it leaves no task earning).
    fn most_a_team_earns(&self) -> f64 {
        let inst = self.instance;
        (inst.task_ids())
            .map(|j| {
                let value = inst.value_function(j);
                (1..=inst.capacity(j).min(inst.num_robots()))
                    .map(|n| value.value(n))
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use afg_game::{Family, Instance};

    use super::super::Search;
    use super::super::lagrange::tests::every_assignment;
    use crate::TeamOptimum;

    /// Small games where fewer teams fit than the envelope spreads the robots over:
    /// every threshold alike (`constant`, N not a multiple of it), `scarce` and
    /// `clustered`.
    fn games() -> impl Iterator<Item = (String, Instance)> {
        [Family::Constant, Family::Scarce, Family::Clustered]
            .into_iter()
            .flat_map(|family| {
                (0..16u64).map(move |seed| {
                    let (robots, tasks) = (5 + seed as usize % 4, 2 + seed as usize % 2);
                    let inst = family
                        .config(robots, tasks, seed)
                        .unwrap()
                        .generate()
                        .unwrap();
                    (format!("{family} seed {seed}"), inst)
                })
            })
    }

    fn optimum(inst: &Instance) -> f64 {
        every_assignment(inst)
            .map(|a| inst.welfare(&a))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// At every price the root's priced bound stays above the optimum (brute force),
    /// and the price the root chooses lowers the envelope's bound in most games where
    /// the envelope spreads its robots over more teams than fit.
    #[test]
    fn the_priced_count_bound_stays_above_the_optimum_and_lowers_the_envelope() {
        let (mut binding, mut lowered) = (0, 0);
        for (at, inst) in games() {
            let best = optimum(&inst);
            let tol = 1e-9 * best.abs().max(1.0);
            let mut search = Search::exact(&inst);
            let root = search.root(&|| false).ok().unwrap();
            let most = search.most_a_team_earns();
            for step in 0..=16 {
                let price = most * step as f64 / 8.0;
                if let Some((bound, _)) = search.priced_root(&root, price) {
                    assert!(
                        bound >= best - tol,
                        "{at} at price {price}: {bound} < {best}"
                    );
                }
            }
            search.count_price = 0.0;
            let teams = root.sizes.iter().filter(|&&n| n > 0).count();
            if teams > search.count_cap && root.bound > best + tol {
                binding += 1;
                let priced = search.price_count(&root, &|| false);
                assert!(priced >= best - tol, "{at}: {priced} < {best}");
                lowered += usize::from(priced < root.bound - tol);
            }
        }
        assert!(
            binding >= 8 && 2 * lowered > binding,
            "{lowered} of {binding}"
        );
    }

    /// With the count priced, the search still finds the optimum (brute force): a
    /// relaxation that is a real assignment closes its node only where it is worth its
    /// bound.
    #[test]
    fn the_search_priced_by_count_finds_the_optimum() {
        for (at, inst) in games() {
            let best = optimum(&inst);
            let found = TeamOptimum::default().solve(&inst).unwrap();
            assert!(found.proven, "{at}");
            assert!(
                (found.welfare - best).abs() <= 1e-9 * best.abs().max(1.0),
                "{at}: {} against {best}",
                found.welfare
            );
        }
    }
}
