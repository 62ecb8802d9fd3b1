//! A second bound for games with skills: the Lagrangian relaxation of "a task earns
//! only with the skills it requires".
//!
//! The envelope relaxation counts a team's value without its skills, which is loose
//! where skills are scarce. For any prices λ_js ≥ 0 (one per task and skill), every
//! real assignment satisfies `Σ_{i ∈ team j} skill_is − requires_js · earns_j ≥ 0`, so
//! adding λ times that to the welfare bounds it from above. The added terms split by
//! robot (robot i at task j gains `Σ_s λ_js skill_is`, a change of its cost) and by task
//! (an earning task pays `Λ_j = Σ_s λ_js requires_js`): task j's value becomes
//! `max(0, F_j(n) − Λ_j)` from its threshold on, whose concave envelope is again a
//! column of the transport solver (`Slots::penalised`). Every λ gives a valid bound;
//! the root chooses λ by subgradient steps (the shortfall of each skill at each task
//! in the relaxed optimum), every other node takes a few more from its parent's λ,
//! and every node keeps the lower of its two bounds.

use afg_game::Assignment;

use super::super::super::transport::{self, Column, NEVER, assignment_of, skill_rebates};
use super::{Decision, Node, Pair, Search};

/// Subgradient steps at the root at most.
const ROUNDS: usize = 80;
/// Subgradient steps at every other node, from its parent's skill prices.
const NODE_ROUNDS: usize = 4;
/// Where pricing the skills lowers the root's bound by more than this share (skills
/// that bind), every other node takes [`BINDING_NODE_ROUNDS`] steps instead: on eight
/// seeds of `sparse-skills` and of `mixed` at 100 × 20 that proved them 3.4× and 2.2×
/// sooner in geometric mean (one `sparse-skills` game from unproven at 10 s to 0.64 s),
/// where on `skills` (pricing lowers its root by 0.1 % at most) 16 steps everywhere
/// took 1.5× as long.
const BINDING: f64 = 0.002;
/// Subgradient steps at every other node where the skills bind ([`BINDING`]).
const BINDING_NODE_ROUNDS: usize = 16;
/// How far below the best found Polyak's step aims, as a share of the bound: a step
/// towards the best found alone shrinks as the best found nears the bound and stalls
/// the prices (on 12 seeds of each skill family at 100 × 20, aiming 10 % lower proved
/// them 1.5× to 5× sooner in geometric mean than aiming at the best found). 20 %
/// since the skill dive gives the root a better first incumbent (whose steps 10 %
/// below it were too short: `mixed` seed 7 at 100 × 20 took 322 ms, 10× as long).
const TARGET_BELOW: f64 = 0.2;
/// Steps without a lower bound before the step size halves.
const PATIENCE: usize = 5;
/// Games with more robot-task pairs than this keep the envelope bound alone: a
/// Lagrangian solve cannot start from a subsample's prices, so it reads every cost at
/// every step.
pub(in super::super) const MAX_PAIRS: usize = 1 << 21;

/// A Lagrangian relaxation's optimum: its bound, its assignment, its prices, and how
/// much of each task's team it holds (y_j: 1 where it earns, a share of the team its
/// envelope spreads the value over where it is open, 0 where it may not earn).
pub(super) struct Relaxed {
    pub(super) bound: f64,
    assignment: Assignment,
    pub(super) prices: Vec<f64>,
    pub(super) earns: Vec<f64>,
    /// The relaxation's columns (its tasks' at λ, then the void's).
    pub(super) columns: Vec<Column>,
    /// λ as the relaxation priced it (zero at tasks that may not earn).
    pub(super) lambda: Vec<f64>,
}

impl Search<'_> {
    /// Solves the Lagrangian relaxation of a node (its decisions and fixed robots) at
    /// `lambda` (task-major, one per task and skill), from `warm` prices; `None` where
    /// it cannot keep the fixed robots.
    pub(super) fn relax(
        &self,
        decisions: &[Decision],
        pairs: &[Pair],
        lambda: &[f64],
        warm: &[f64],
    ) -> Option<Relaxed> {
        let inst = self.instance;
        let s = inst.num_skills();
        // A task that may not earn gains nothing from its price: it is left at zero.
        let mut lambda = lambda.to_vec();
        let mut flats = vec![0usize; inst.num_tasks()];
        let mut columns: Vec<Column> = inst
            .task_ids()
            .map(|j| {
                let prices = &mut lambda[j.index() * s..][..s];
                if decisions[j.index()] == Decision::Unstaffed {
                    prices.fill(0.0);
                }
                let penalty: f64 = prices
                    .iter()
                    .zip(inst.requires(j))
                    .map(|(&l, &r)| l * f64::from(r))
                    .sum();
                let (column, flat) = self.task_column(j, decisions[j.index()], penalty);
                flats[j.index()] = flat;
                column
            })
            .collect();
        if inst.allows_void() {
            columns.push(Column::Void);
        }
        let adjust = self.adjust(pairs);
        let Ok(solution) = transport::solve_columns(
            inst,
            &columns,
            Some(warm),
            self.costs(&adjust, &lambda),
            NEVER,
        ) else {
            unreachable!("never stopped")
        };
        let assignment = assignment_of(inst, &solution.task_of);
        if !self.keeps(&assignment, pairs) {
            return None;
        }
        let mut bound = 0.0;
        for i in inst.robot_ids() {
            if let Some(j) = assignment.task_of(i) {
                // Without skills λ is empty, and so are the rebates.
                let rebate = skill_rebates(inst, i, &lambda).nth(j.index());
                bound += rebate.unwrap_or(0.0) - inst.cost(i, j);
            }
        }
        let earns = inst
            .task_ids()
            .map(|j| {
                let Column::Task { value, .. } = columns[j.index()] else {
                    unreachable!("tasks come first")
                };
                let n = assignment.size(j);
                bound += value.value(n);
                match decisions[j.index()] {
                    Decision::Staffed => {
                        bound -= self.bonus * self.threshold(j) as f64;
                        1.0
                    }
                    Decision::Open if flats[j.index()] > 0 => {
                        (n as f64 / flats[j.index()] as f64).min(1.0)
                    }
                    _ => 0.0,
                }
            })
            .collect();
        Some(Relaxed {
            bound,
            assignment,
            prices: solution.prices,
            earns,
            columns,
            lambda,
        })
    }

    /// A node's Lagrangian dual: a few subgradient steps from its parent's skill prices
    /// (or the root's), the flow solved from the parent's, every relaxed optimum offered
    /// to the best found; `Some(None)` where the root priced no skills, `None` where no
    /// assignment keeps the node's fixed robots.
    pub(super) fn skill_bound(
        &mut self,
        decisions: &[Decision],
        pairs: &[Pair],
        parent: &Node,
    ) -> Option<Option<Dual>> {
        if self.skill_prices.is_empty() {
            return Some(None);
        }
        let lambda = if parent.skill_prices.is_empty() {
            self.skill_prices.clone()
        } else {
            parent.skill_prices.clone()
        };
        let steps = Steps {
            rounds: self.node_rounds,
            size: self.skill_step,
        };
        let best = self.subgradient(decisions, pairs, lambda, &parent.prices, steps, &|| false)?;
        Some(Some(best))
    }

    /// Chooses the skill prices from the root by subgradient steps, keeps those of the
    /// lowest bound for every node, and returns that bound.
    pub(in super::super) fn price_skills(
        &mut self,
        root: &Node,
        out_of_time: &dyn Fn() -> bool,
    ) -> f64 {
        if self.closes(root.bound) {
            return root.bound; // the dive's answer is proven already
        }
        let lambda = vec![0.0; self.instance.num_tasks() * self.instance.num_skills()];
        let steps = Steps {
            rounds: ROUNDS,
            size: 2.0,
        };
        match self.subgradient(
            &root.decisions,
            &root.pairs,
            lambda,
            &root.prices,
            steps,
            out_of_time,
        ) {
            Some(best) => {
                let bound = best.relaxed.bound;
                self.skill_prices = best.lambda;
                self.skill_step = best.step_size;
                let lowered = (root.bound - bound) / bound.abs().max(f64::MIN_POSITIVE);
                self.node_rounds = if lowered > BINDING {
                    BINDING_NODE_ROUNDS
                } else {
                    NODE_ROUNDS
                };
                bound
            }
            None => root.bound,
        }
    }

    /// Up to `steps.rounds` subgradient steps on a node's Lagrangian dual from `lambda`:
    /// Polyak's step towards [`TARGET_BELOW`] under the best welfare found, its size halved after [`PATIENCE`]
    /// steps without a lower bound. Every relaxed optimum is offered to the best found;
    /// returns the lowest bound, its prices and the step size reached (`None`: the node
    /// is infeasible).
    fn subgradient(
        &mut self,
        decisions: &[Decision],
        pairs: &[Pair],
        mut lambda: Vec<f64>,
        warm: &[f64],
        steps: Steps,
        out_of_time: &dyn Fn() -> bool,
    ) -> Option<Dual> {
        let inst = self.instance;
        let s = inst.num_skills();
        let mut best: Option<Dual> = None;
        let mut prices = warm.to_vec();
        let (mut step_size, mut stalled) = (steps.size, 0);
        for _ in 0..steps.rounds {
            if out_of_time() || best.as_ref().is_some_and(|b| self.closes(b.relaxed.bound)) {
                break;
            }
            let relaxed = self.relax(decisions, pairs, &lambda, &prices)?;
            self.offer(&relaxed.assignment);
            // The subgradient: each required skill held at each task, less what the
            // task's share of earning asks for.
            let held = inst.skills_held(&relaxed.assignment);
            let mut gradient = vec![0.0; lambda.len()];
            for j in inst.task_ids() {
                let at = j.index() * s;
                for (t, &need) in inst.requires(j).iter().enumerate() {
                    if need > 0 {
                        gradient[at + t] =
                            held[at + t] as f64 - f64::from(need) * relaxed.earns[j.index()];
                    }
                }
            }
            let bound = relaxed.bound;
            prices.clone_from(&relaxed.prices);
            if best
                .as_ref()
                .is_none_or(|b| bound < b.relaxed.bound - 1e-12 * b.relaxed.bound.abs().max(1.0))
            {
                best = Some(Dual {
                    lambda: lambda.clone(),
                    step_size,
                    relaxed,
                });
                stalled = 0;
            } else {
                stalled += 1;
                if stalled == PATIENCE {
                    step_size /= 2.0;
                    stalled = 0;
                }
            }
            let norm: f64 = gradient.iter().map(|g| g * g).sum();
            if norm == 0.0 {
                break; // λ is optimal: the relaxation meets every skill it prices
            }
            let target = self.best_welfare - TARGET_BELOW * bound.abs();
            let step = step_size * (bound - target) / norm;
            for (l, g) in lambda.iter_mut().zip(&gradient) {
                *l = (*l - step * g).max(0.0);
            }
        }
        best
    }
}

/// How many subgradient steps, and the first one's size.
#[derive(Clone, Copy)]
struct Steps {
    rounds: usize,
    size: f64,
}

/// The best point of a subgradient search: its skill prices, the step size reached,
/// and the relaxation solved there.
pub(super) struct Dual {
    pub(super) lambda: Vec<f64>,
    step_size: f64,
    pub(super) relaxed: Relaxed,
}

#[cfg(test)]
pub(super) mod tests {
    use afg_game::{Assignment, GeneratorKnobs, Instance, TaskId};
    use proptest::prelude::*;

    use super::super::{Decision, Pair, Search};

    /// Every assignment of `inst` (with the void where allowed) that respects its
    /// capacities.
    pub(in super::super) fn every_assignment(inst: &Instance) -> impl Iterator<Item = Assignment> {
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let choices = m + usize::from(inst.allows_void());
        (0..choices.pow(n as u32)).filter_map(move |code| {
            let tasks = (0..n)
                .map(|i| {
                    let c = code / choices.pow(i as u32) % choices;
                    (c < m).then_some(TaskId(c as u32))
                })
                .collect();
            Assignment::from_tasks(inst, tasks).ok()
        })
    }

    /// Whether assignment `a` lies in the region of a node that decided `decisions`
    /// and fixed or kept out `pairs`.
    pub(in super::super) fn in_region(
        inst: &Instance,
        decisions: &[Decision],
        pairs: &[Pair],
        a: &Assignment,
    ) -> bool {
        let s = inst.num_skills();
        let held = inst.skills_held(a);
        let earns = |j: TaskId| inst.earns(j, a.size(j), &held[j.index() * s..][..s]);
        (pairs.iter()).all(|&(i, j, fixed)| (a.task_of(i) == Some(j)) == fixed)
            && inst.task_ids().all(|j| match decisions[j.index()] {
                Decision::Staffed => earns(j),
                Decision::Unstaffed => !earns(j),
                Decision::Open => true,
            })
    }

    /// The best welfare over every assignment.
    pub(in super::super) fn brute_force(inst: &Instance) -> f64 {
        every_assignment(inst)
            .map(|a| inst.welfare(&a))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Small games with thresholds 1–3 and two skills of `share`, tasks requiring
    /// `requires` of each.
    pub(in super::super) fn skill_knobs(share: f64, requires: (usize, usize)) -> GeneratorKnobs {
        GeneratorKnobs {
            min_team: Some((1, 3)),
            skills: Some(2),
            skill_share: Some(share),
            requires: Some(requires),
            ..GeneratorKnobs::default()
        }
    }

    /// Pricing the skills earns its keep: over small skill games whose root's envelope
    /// bound the best assignment found so far does not meet, the priced bound is strictly below the
    /// envelope's in most of them (a pricing that does nothing fails), and never below
    /// the optimum.
    #[test]
    fn pricing_skills_lowers_the_envelope_bound() {
        let knobs = skill_knobs(0.3, (1, 2));
        let (mut open, mut lowered) = (0, 0);
        for seed in 0..60 {
            let inst = knobs.config(6, 3, seed).unwrap().generate().unwrap();
            let optimum = brute_force(&inst);
            let mut search = Search::new(&inst);
            let root = search
                .node(search.root_decisions(), Vec::new(), None)
                .unwrap();
            if search.closes(root.bound) {
                continue;
            }
            open += 1;
            let priced = search.price_skills(&root, &|| false);
            let tol = 1e-9 * optimum.abs().max(1.0);
            assert!(priced >= optimum - tol, "seed {seed}: {priced} < {optimum}");
            lowered += usize::from(priced < root.bound - tol);
        }
        assert!(open >= 20, "{open} open roots");
        assert!(4 * lowered >= 3 * open, "{lowered} of {open}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Every skill price gives a bound on the optimum, and the root's search lowers
        /// the envelope's bound without crossing the optimum.
        #[test]
        fn every_skill_price_bounds_the_optimum(
            seed in 0u64..10_000,
            n in 2usize..=6,
            m in 1usize..=3,
            raw in proptest::collection::vec(0.0f64..3.0, 6),
        ) {
            let inst = skill_knobs(0.5, (0, 2)).config(n, m, seed).unwrap().generate().unwrap();
            let optimum = brute_force(&inst);
            let tol = 1e-9 * optimum.abs().max(1.0);
            let mut search = Search::new(&inst);
            let root = search.node(search.root_decisions(), Vec::new(), None).unwrap();
            let lambda = &raw[..m * 2];
            let relaxed = search.relax(&root.decisions, &[], lambda, &root.prices).unwrap();
            prop_assert!(relaxed.bound >= optimum - tol, "{} < {optimum}", relaxed.bound);
            let priced = search.price_skills(&root, &|| false);
            prop_assert!(priced >= optimum - tol, "{priced} < {optimum}");
            prop_assert!(priced <= root.bound + tol, "{priced} > {}", root.bound);
        }
    }
}
