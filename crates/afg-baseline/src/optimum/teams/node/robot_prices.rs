//! A third bound at a node (ours): the robots' one-task rule priced, and every task's
//! best team on its own.
//!
//! Given a price u_i on each robot, every task j picks the team S worth most to it
//! alone: F_j(|S|) where S earns (its threshold met, every skill it requires held by
//! its members together), nothing where it does not, less Σ_{i∈S} (c_ij + u_i). Then
//! Σ_i u_i + Σ_j best_j(u) bounds every assignment below the node: each robot is in
//! one team, so its price is paid once and returned once. This is the Lagrangian
//! bound of the model over whole teams (one column per team, as column generation
//! solves it), and where skills bind it is far tighter than the transport relaxation
//! with the skills priced, which lets a robot bring a fraction of its skills to each
//! of two teams: on `sparse-skills` seed 7 (100 × 20) 48 steps take the root's from
//! 188.67 to 188.15 (the optimum is 187.39; HiGHS's root bound after its cuts 188.13).
//!
//! A task's best team is a covering knapsack (module `team`). The prices start at the
//! node's Lagrangian relaxation's robot potentials (where this bound is at most that
//! one's) or at its parent's, and move by subgradient steps: a robot in no team is
//! priced lower, one in several higher. Where every robot is in exactly one team the
//! teams are an assignment worth the bound, offered to the best found. A node pays a
//! programme per task per step, so only nodes of searches that run long, whose
//! Lagrangian bound is near the best found, are priced ([`Gate`]).

use afg_game::{Assignment, RobotId};

use super::super::super::transport::skill_rebates;
use super::lagrange::Relaxed;
use super::{Decision, Node, Pair, Search};

mod team;
use team::{Programme, Role, TaskAt, best_team};

/// Subgradient steps at a node.
const ROUNDS: usize = 8;
/// Each step aims this many times the node's gap below the best found (Polyak's rule
/// with a target there).
const TARGET_BELOW: f64 = 1.5;
/// A search prices robots once it has solved this many nodes (shorter ones are over
/// before it would pay)...
const AFTER_NODES: u64 = 200;
/// ...at nodes whose Lagrangian bound is within this share of the best found (it
/// closes about a third of a percent, not more)...
const WITHIN: f64 = 0.002;
/// ...where no task's programme fills more cells (states × counts × candidates).
const MAX_WORK: usize = 1 << 20;
/// Steps without a lower bound before the step size halves.
const PATIENCE: usize = 3;

/// The best robot prices a node's steps reached, their bound, and the step size the
/// steps ended at.
#[derive(Clone, Debug)]
pub(super) struct RobotPrices {
    pub(super) bound: f64,
    pub(super) prices: Vec<f64>,
    pub(super) step: f64,
}

/// Which nodes are robot-priced: once the search has solved `after_nodes` nodes, those
/// whose Lagrangian bound is within `within` (a share) of the best found, where no
/// task's programme fills more than `max_work` cells.
#[derive(Clone, Copy, Debug)]
pub(super) struct Gate {
    pub(super) after_nodes: u64,
    pub(super) within: f64,
    pub(super) max_work: usize,
}

impl Default for Gate {
    fn default() -> Self {
        Gate {
            after_nodes: AFTER_NODES,
            within: WITHIN,
            max_work: MAX_WORK,
        }
    }
}

impl Search<'_> {
    /// The robot-priced bound of a node (`decisions`, `pairs`, its Lagrangian
    /// relaxation `relaxed`) where [`Search::robot_gate`] lets it in: `None` where it
    /// closes the node, `Some(None)` where the node is not priced. Its steps start
    /// from its parent's prices, or the relaxation's robot potentials.
    pub(super) fn price_robots(
        &mut self,
        decisions: &[Decision],
        pairs: &[Pair],
        relaxed: &Relaxed,
        parent: Option<&Node>,
    ) -> Option<Option<RobotPrices>> {
        let gate = self.robot_gate;
        let gap = relaxed.bound - self.best_welfare;
        if self.nodes < gate.after_nodes || gap > gate.within * self.best_welfare.abs() {
            return Some(None);
        }
        let inst = self.instance;
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let barred = self.barred(pairs);
        let mut candidates = vec![Vec::new(); m];
        for i in inst.robot_ids() {
            for j in inst.task_ids().filter(|&j| self.free(&barred, i, j)) {
                candidates[j.index()].push(i.index());
            }
        }
        let mut fixed = vec![Vec::new(); m];
        for &(i, j, _) in pairs.iter().filter(|p| p.2) {
            fixed[j.index()].push(i.index());
            candidates[j.index()].retain(|&r| r != i.index());
        }
        let tasks: Vec<TaskAt> = inst
            .task_ids()
            .map(|j| {
                let capacity = inst.capacity(j).min(n);
                let role = match decisions[j.index()] {
                    Decision::Staffed => Role::Earn,
                    Decision::Open => Role::Either { capacity },
                    Decision::Unstaffed => Role::Idle {
                        room: self.unstaffed_room(j).min(n),
                    },
                };
                TaskAt {
                    j,
                    needs: team::skill_needs(inst, j),
                    threshold: self.threshold(j),
                    capacity,
                    role,
                    candidates: &candidates[j.index()],
                    fixed: &fixed[j.index()],
                }
            })
            .collect();
        if !tasks.iter().all(|at| at.fits(gate.max_work)) {
            return Some(None);
        }
        let (start, step) = match parent.and_then(|p| p.robot_prices.as_ref()) {
            Some(p) => (p.prices.clone(), p.step),
            None => (self.robot_potentials(relaxed, &barred), 1.0),
        };
        let best = self.robot_steps(&tasks, start, step);
        (!self.closes(best.bound)).then_some(Some(best))
    }

    /// Robot i's potential in a node's Lagrangian relaxation: its best gain over the
    /// tasks it is free to join (`barred`: [`Search::barred`]) and the void where it is
    /// allowed, where the robot-priced bound is at most that relaxation's.
    fn robot_potentials(&self, relaxed: &Relaxed, barred: &[bool]) -> Vec<f64> {
        let inst = self.instance;
        let void = if inst.allows_void() {
            0.0
        } else {
            f64::NEG_INFINITY
        };
        inst.robot_ids()
            .map(|i| {
                (inst.task_ids().zip(skill_rebates(inst, i, &relaxed.lambda)))
                    .filter(|&(j, _)| self.free(barred, i, j))
                    .map(|(j, rebate)| rebate - inst.cost(i, j) + relaxed.prices[j.index()])
                    .fold(void, f64::max)
            })
            .collect()
    }

    /// [`ROUNDS`] subgradient steps on the robot prices from `start` at step size
    /// `step`, stopped once the bound closes the node: the best prices reached.
    fn robot_steps(&mut self, tasks: &[TaskAt], start: Vec<f64>, step: f64) -> RobotPrices {
        let inst = self.instance;
        let n = inst.num_robots();
        let void = inst.allows_void();
        let (mut dp, mut members) = (Programme::default(), Vec::new());
        let mut best = RobotPrices {
            bound: f64::INFINITY,
            prices: start.clone(),
            step,
        };
        let (mut u, mut step, mut stalled) = (start, step, 0);
        let (mut w, mut task_of, mut count) = (vec![0.0; n], vec![None; n], vec![0u32; n]);
        for _ in 0..ROUNDS {
            if self.closes(best.bound) {
                break;
            }
            let mut bound: f64 = u.iter().sum();
            count.fill(0);
            for at in tasks {
                for (i, w) in w.iter_mut().enumerate() {
                    *w = inst.cost(RobotId(i as u32), at.j) + u[i];
                }
                bound += best_team(inst, at, &w, &mut dp, &mut members);
                for &i in &members {
                    count[i] += 1;
                    task_of[i] = Some(at.j);
                }
            }
            if bound < best.bound {
                best = RobotPrices {
                    bound,
                    prices: u.clone(),
                    step,
                };
                stalled = 0;
            } else {
                stalled += 1;
                if stalled == PATIENCE {
                    step /= 2.0;
                    stalled = 0;
                }
            }
            // Where the void is allowed a robot may be in no team: its price stays ≥ 0.
            let gradient: Vec<f64> = (u.iter().zip(&count))
                .map(|(&ui, &c)| {
                    let g = 1.0 - f64::from(c);
                    if void && ui <= 0.0 && g > 0.0 { 0.0 } else { g }
                })
                .collect();
            let norm: f64 = gradient.iter().map(|g| g * g).sum();
            if norm == 0.0 {
                // Every robot in one team (or none, where allowed): an assignment.
                let tasks = (0..n)
                    .map(|i| task_of[i].filter(|_| count[i] == 1))
                    .collect();
                if let Ok(assignment) = Assignment::from_tasks(inst, tasks) {
                    self.offer(&assignment);
                }
                break;
            }
            let over = (bound - self.best_welfare).max(1e-9 * bound.abs().max(1.0));
            let t = step * (1.0 + TARGET_BELOW) * over / norm;
            for (ui, g) in u.iter_mut().zip(&gradient) {
                *ui -= t * g;
                if void {
                    *ui = ui.max(0.0);
                }
            }
            task_of.fill(None);
        }
        RobotPrices { step, ..best }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BinaryHeap;

    use afg_game::{Assignment, Family, GeneratorKnobs, Instance, Point, Task};

    use super::super::Search;
    use super::super::lagrange::tests::{brute_force, every_assignment, in_region, skill_knobs};
    use super::{Gate, RobotPrices};

    /// A search that robot-prices every node from its first.
    fn robot_priced(inst: &Instance) -> Search<'_> {
        let mut search = Search::exact(inst);
        search.robot_gate = Gate {
            after_nodes: 0,
            within: f64::INFINITY,
            max_work: usize::MAX,
        };
        search
    }

    /// At any robot prices the bound holds every assignment of the node's region (the
    /// root's and its children's, on small skill games whose best found is set below
    /// the optimum, half of them with the void): it closes only nodes with nothing better, and from the Lagrangian
    /// relaxation's robot potentials it is never above that relaxation's bound and
    /// lower in some.
    #[test]
    fn every_robot_price_bounds_the_node() {
        let (mut priced, mut lower) = (0, 0);
        for seed in 0..40 {
            // Every other game lets robots stay out (the void).
            let knobs = GeneratorKnobs {
                allow_void: seed % 2 == 1,
                ..skill_knobs(0.4, (0, 2))
            };
            let inst = knobs.config(6, 3, seed).unwrap().generate().unwrap();
            let assignments: Vec<Assignment> = every_assignment(&inst).collect();
            let optimum = brute_force(&inst);
            let tol = 1e-9 * optimum.abs().max(1.0);
            let mut search = robot_priced(&inst);
            let mut root = search
                .node(search.root_decisions(), Vec::new(), None)
                .unwrap();
            search.price_skills(&root, &|| false);
            let best = optimum - 0.05 * optimum.abs();
            search.best_welfare = best;
            let mut regions = vec![(root.decisions.clone(), root.pairs.clone())];
            if let Some(branch) = search.branch(&root) {
                regions.extend(search.children(&root, branch));
            }
            for (k, (decisions, pairs)) in regions.into_iter().enumerate() {
                let of_node = |a: &&Assignment| in_region(&inst, &decisions, &pairs, a);
                let region = (assignments.iter().filter(of_node))
                    .map(|a| inst.welfare(a))
                    .fold(f64::NEG_INFINITY, f64::max);
                let Some(Some(dual)) = search.skill_bound(&decisions, &pairs, &root) else {
                    continue;
                };
                for start in 0..3 {
                    // From the potentials, then from two made-up parents' prices.
                    root.robot_prices = (start > 0).then(|| RobotPrices {
                        bound: f64::INFINITY,
                        prices: (0..inst.num_robots())
                            .map(|i| ((seed as usize * 7 + i * 5 + start) % 11) as f64 * 0.3 - 1.0)
                            .collect(),
                        step: 1.0,
                    });
                    search.best_welfare = best;
                    match search.price_robots(&decisions, &pairs, &dual.relaxed, Some(&root)) {
                        // Closed: nothing better than the best found, which its steps
                        // may have raised.
                        None => assert!(
                            region <= search.best_welfare + tol,
                            "seed {seed} region {k}: closed"
                        ),
                        Some(None) => panic!("every node is priced"),
                        Some(Some(p)) => {
                            assert!(
                                p.bound >= region - tol,
                                "seed {seed} region {k}: {} < {region}",
                                p.bound
                            );
                            if start == 0 {
                                priced += 1;
                                assert!(p.bound <= dual.relaxed.bound + tol, "seed {seed}: above");
                                lower += usize::from(p.bound < dual.relaxed.bound - tol);
                            }
                        }
                    }
                }
            }
        }
        assert!(priced >= 20 && lower >= 5, "{lower} lower of {priced}");
    }

    /// Where robots may stay out, a robot's potential is never below 0 (staying out
    /// gains it nothing, and its price must not be negative for the bound to hold): two
    /// robots 3 away from the one task, which pays at most 1, start at exactly 0.
    #[test]
    fn a_robot_free_to_stay_out_starts_at_zero() {
        let task = Task {
            position: Point::new(3.0, 0.0),
            reward: 1.0,
            eps: 2.0,
            capacity: None,
        };
        let robots = vec![Point::new(0.0, 0.0); 2];
        let inst = Instance::with_void(robots, vec![task], 1.0)
            .unwrap()
            .with_teams(vec![1], &[vec![1], vec![0]], &[vec![1]])
            .unwrap();
        let mut search = robot_priced(&inst);
        let root = search
            .node(search.root_decisions(), Vec::new(), None)
            .unwrap();
        let lambda = vec![0.5; inst.num_skills()];
        let relaxed = (search.relax(&root.decisions, &root.pairs, &lambda, &root.prices)).unwrap();
        let barred = search.barred(&root.pairs);
        assert_eq!(search.robot_potentials(&relaxed, &barred), vec![0.0, 0.0]);
    }

    /// Where skills bind, the steps take the bound well below the skill-priced
    /// relaxation's: at the root of `sparse-skills` seed 7 (100 × 20; its optimum,
    /// 187.388, as the best found), from 188.67 to below 188.25 in six calls of
    /// [`super::ROUNDS`] steps, each from the last one's prices and step size (188.12
    /// after 300 steps).
    #[test]
    fn robot_prices_beat_skill_prices_where_skills_bind() {
        let inst = (Family::SparseSkills.config(100, 20, 7).unwrap())
            .generate()
            .unwrap();
        let mut search = robot_priced(&inst);
        let mut root = search
            .node(search.root_decisions(), Vec::new(), None)
            .unwrap();
        search.price_root(&mut root, &|| false);
        search.best_welfare = 187.388;
        let lambda = search.skill_prices.clone();
        let relaxed = (search.relax(&root.decisions, &root.pairs, &lambda, &root.prices)).unwrap();
        assert!(relaxed.bound > 188.6, "{}", relaxed.bound);
        // Each call steps on from the last one's prices (as a child from its parent's).
        let mut priced = None;
        for _ in 0..6 {
            root.robot_prices = priced;
            let Some(Some(p)) =
                search.price_robots(&root.decisions, &root.pairs, &relaxed, Some(&root))
            else {
                panic!("the root is priced and not closed")
            };
            priced = Some(p);
        }
        let priced = priced.unwrap();
        assert!(priced.bound < 188.25, "{}", priced.bound);
    }

    /// With every node robot-priced, the search still ends at the optimum: brute force
    /// on small skill games, half of them with the void.
    #[test]
    fn a_robot_priced_search_finds_the_optimum() {
        for seed in 0..60 {
            let knobs = GeneratorKnobs {
                allow_void: seed % 2 == 1,
                ..skill_knobs(0.4, (0, 2))
            };
            let inst = knobs.config(6, 3, seed).unwrap().generate().unwrap();
            let optimum = brute_force(&inst);
            let mut search = robot_priced(&inst);
            let mut root = search
                .node(search.root_decisions(), Vec::new(), None)
                .unwrap();
            search.price_root(&mut root, &|| false);
            let mut open = BinaryHeap::from([root]);
            while let Some(node) = open.pop() {
                if search.closes(node.bound) {
                    break;
                }
                open.extend(search.expand(&node));
            }
            let tol = 1e-9 * optimum.abs().max(1.0);
            assert!((search.best_welfare - optimum).abs() <= tol, "seed {seed}");
        }
    }
}
