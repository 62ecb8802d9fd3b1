//! The exact optimum of the team-threshold game, by branch and bound over which tasks
//! are staffed, with the transport solver at every node.
//!
//! A task with threshold k earns `F(n)` from n ≥ k members and nothing below. The
//! relaxation at a node replaces each undecided task's value by its concave envelope
//! (its first k members worth `F(k) / k` each, then F's marginals): a concave game
//! again, solved exactly by the transport solver, whose welfare bounds every assignment
//! below the node. A node decides some tasks: **staffed** (n ≥ k, forced by a bonus on
//! the first k members that is taken off again) or **unstaffed** (worth nothing, room
//! for k − 1). Where the relaxed optimum leaves no undecided task between 0 and k
//! members it is a real assignment worth exactly its bound, and the node is closed;
//! otherwise the task with the most envelope value at stake is branched on, both ways.
//! Every node's assignment is a feasible one whose true welfare may improve the best
//! found; a dive from the root (rounding each fractional task to the nearer side) finds
//! a good one before the search, which takes the open node of highest bound first. A
//! time limit stops it with the best assignment, the highest open bound and the gap.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::time::{Duration, Instant};

use afg_game::{Assignment, Instance, TaskId};

use super::assignment_of;
use super::transport::{self, Column, Slots, Solution};
use crate::{AllocError, AllocStats, Allocation, Allocator, timed};

/// The exact optimum of a game with team thresholds (or the paper's game), with a
/// proven upper bound: branch and bound over which tasks are staffed (see the module
/// docs). Without a time limit the answer is proven optimal; with one, it is the best
/// found and its certified gap.
///
/// # Examples
/// ```
/// use afg_baseline::TeamOptimum;
/// use afg_game::GeneratorConfig;
/// let mut cfg = GeneratorConfig::paper(30, 5, 1);
/// cfg.min_team = Some(afg_game::CountRange { min: 6, max: 12 });
/// let inst = cfg.generate()?;
/// let best = TeamOptimum::default().solve(&inst)?;
/// assert!(best.proven && best.gap() == 0.0);
/// assert!((inst.welfare(&best.assignment) - best.welfare).abs() < 1e-9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct TeamOptimum {
    /// Stop after this long with the best found and its gap (`None`: until proven).
    pub time_limit: Option<Duration>,
}

/// What [`TeamOptimum::solve`] found.
#[derive(Clone, Debug)]
pub struct TeamSolution {
    /// The best assignment found.
    pub assignment: Assignment,
    /// Its welfare.
    pub welfare: f64,
    /// A proven upper bound on every assignment's welfare (the welfare itself when
    /// proven optimal).
    pub bound: f64,
    /// Whether the search finished, proving the assignment optimal.
    pub proven: bool,
    /// Nodes whose relaxation was solved.
    pub nodes: u64,
}

impl TeamSolution {
    /// The certified relative gap `(bound − welfare) / |welfare|` (0 when proven; where
    /// the welfare is 0, the absolute gap).
    pub fn gap(&self) -> f64 {
        if self.proven {
            return 0.0;
        }
        (self.bound - self.welfare).max(0.0) / self.welfare.abs().max(1e-12)
    }
}

/// What a node decides of one task.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Decision {
    /// Not decided: its value replaced by its envelope.
    Open,
    /// Staffed: at least k members.
    Staffed,
    /// Unstaffed: worth nothing, at most k − 1 members.
    Unstaffed,
}

/// A node: its decisions, its relaxation's bound, and where that relaxation put each
/// task's members (the branching is read from it).
#[derive(Clone)]
struct Node {
    decisions: Vec<Decision>,
    bound: f64,
    prices: Vec<f64>,
    sizes: Vec<usize>,
}

impl PartialEq for Node {
    fn eq(&self, other: &Self) -> bool {
        self.bound.total_cmp(&other.bound) == Ordering::Equal
    }
}
impl Eq for Node {}
impl PartialOrd for Node {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Node {
    fn cmp(&self, other: &Self) -> Ordering {
        self.bound.total_cmp(&other.bound)
    }
}

/// The search's fixed data: the instance, the bonus that forces a staffed task's
/// first members, and the best assignment found so far.
struct Search<'a> {
    instance: &'a Instance,
    bonus: f64,
    best: Assignment,
    best_welfare: f64,
    nodes: u64,
}

impl TeamOptimum {
    /// Solves `instance` (thresholds and the paper's game; skill requirements are
    /// refused).
    ///
    /// # Errors
    /// [`AllocError::TeamsNotSupported`] for a game with skill requirements.
    pub fn solve(&self, instance: &Instance) -> Result<TeamSolution, AllocError> {
        if instance.has_skill_rules() {
            return Err(AllocError::TeamsNotSupported {
                method: "opt".into(),
                rules: "skill requirements",
                reason: "the exact solver decides which tasks are staffed by how many robots, not which",
            });
        }
        let start = Instant::now();
        let out_of_time = || {
            self.time_limit
                .is_some_and(|limit| start.elapsed() >= limit)
        };
        let mut decisions = vec![Decision::Open; instance.num_tasks()];
        for j in instance.unstaffable_tasks() {
            decisions[j.index()] = Decision::Unstaffed;
        }
        let mut search = Search::new(instance);
        let Some(root) = search.node(decisions, None) else {
            unreachable!("the root is feasible: the instance holds every robot")
        };
        search.dive(&root);
        let mut open = BinaryHeap::from([root]);
        while let Some(node) = open.peek() {
            if search.closes(node.bound) {
                open.clear();
                break;
            }
            if out_of_time() {
                break;
            }
            let node = open.pop().expect("peeked");
            let Some(task) = search.branching_task(&node) else {
                continue; // closed: its assignment was offered to the best
            };
            for decision in [Decision::Staffed, Decision::Unstaffed] {
                let mut decisions = node.decisions.clone();
                decisions[task] = decision;
                if let Some(child) = search.node(decisions, Some(&node))
                    && !search.closes(child.bound)
                {
                    open.push(child);
                }
            }
        }
        let bound = open
            .peek()
            .map_or(search.best_welfare, |n| n.bound.max(search.best_welfare));
        Ok(TeamSolution {
            proven: open.is_empty(),
            bound,
            welfare: search.best_welfare,
            assignment: search.best,
            nodes: search.nodes,
        })
    }
}

/// `opt` with a time limit: the best assignment found, its bound in
/// [`AllocStats::bound`] and the nodes solved in [`AllocStats::iterations`].
impl Allocator for TeamOptimum {
    fn name(&self) -> String {
        "opt".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        let (solution, wall_time) = timed(|| self.solve(instance));
        let solution = solution?;
        Ok(Allocation {
            stats: AllocStats {
                iterations: solution.nodes,
                wall_time,
                bound: Some(solution.bound),
                ..AllocStats::default()
            },
            assignment: solution.assignment,
        })
    }
}

impl<'a> Search<'a> {
    fn new(instance: &'a Instance) -> Self {
        let max_cost = instance
            .robot_ids()
            .flat_map(|i| instance.task_ids().map(move |j| instance.cost(i, j)))
            .fold(0.0, f64::max);
        let max_reward = instance
            .tasks()
            .iter()
            .map(|t| t.reward)
            .fold(0.0, f64::max);
        Search {
            instance,
            // More than any other member or move is worth: a staffed task's first k
            // members come before anything else.
            bonus: 2.0 * (max_cost + max_reward) + 1.0,
            best: Assignment::unassigned(instance.num_robots(), instance.num_tasks()),
            best_welfare: f64::NEG_INFINITY,
            nodes: 0,
        }
    }

    /// Whether a node of this bound cannot beat the best found (beyond rounding).
    fn closes(&self, bound: f64) -> bool {
        bound <= self.best_welfare + 1e-9 * self.best_welfare.abs().max(1.0)
    }

    /// The columns of a node's relaxation; `None` where no assignment meets its
    /// decisions (staffed thresholds above N, or too little room in all).
    fn columns(&self, decisions: &[Decision]) -> Option<Vec<Column>> {
        let inst = self.instance;
        let staffed: usize = inst
            .task_ids()
            .filter(|j| decisions[j.index()] == Decision::Staffed)
            .map(|j| inst.min_team(j))
            .sum();
        if staffed > inst.num_robots() {
            return None;
        }
        let mut room = 0usize;
        let mut columns: Vec<Column> = inst
            .task_ids()
            .map(|j| {
                let (value, k) = (inst.value_function(j), inst.min_team(j));
                let (value, capacity) = match decisions[j.index()] {
                    Decision::Open => (Slots::envelope(value, k, 0.0), inst.capacity(j)),
                    Decision::Staffed => (Slots::envelope(value, k, self.bonus), inst.capacity(j)),
                    Decision::Unstaffed => (Slots::worthless(value), inst.capacity(j).min(k - 1)),
                };
                room = room.saturating_add(capacity);
                Column::Task { value, capacity }
            })
            .collect();
        if inst.allows_void() {
            columns.push(Column::Void);
        } else if room < inst.num_robots() {
            return None;
        }
        Some(columns)
    }

    /// Solves a node's relaxation (warm from its parent's prices), offers its
    /// assignment to the best found, and returns it; `None` if infeasible.
    fn node(&mut self, decisions: Vec<Decision>, parent: Option<&Node>) -> Option<Node> {
        let inst = self.instance;
        let columns = self.columns(&decisions)?;
        let warm = parent.map(|p| {
            let mut prices = p.prices.clone();
            for (j, (&now, &before)) in decisions.iter().zip(&p.decisions).enumerate() {
                match (now, before) {
                    (Decision::Staffed, Decision::Open) => prices[j] += self.bonus,
                    (Decision::Unstaffed, Decision::Open) => prices[j] = 0.0,
                    _ => {}
                }
            }
            prices
        });
        let Solution {
            task_of, prices, ..
        } = transport::solve_columns(inst, &columns, warm.as_deref());
        self.nodes += 1;
        let assignment = assignment_of(inst, &task_of);
        let mut bound = -inst
            .robot_ids()
            .map(|i| assignment.task_of(i).map_or(0.0, |j| inst.cost(i, j)))
            .sum::<f64>();
        for j in inst.task_ids() {
            let Column::Task { value, .. } = columns[j.index()] else {
                unreachable!("tasks come first")
            };
            bound += value.value(assignment.size(j));
            if decisions[j.index()] == Decision::Staffed {
                bound -= self.bonus * inst.min_team(j) as f64;
            }
        }
        let welfare = inst.welfare(&assignment);
        if welfare > self.best_welfare {
            self.best_welfare = welfare;
            self.best = assignment.clone();
        }
        Some(Node {
            decisions,
            bound,
            prices,
            sizes: assignment.sizes().to_vec(),
        })
    }

    /// The open task whose relaxed coalition is between 0 and its threshold with the
    /// most envelope value at stake; `None` when there is none (the relaxation is a
    /// real assignment, worth its bound).
    fn branching_task(&self, node: &Node) -> Option<usize> {
        let inst = self.instance;
        inst.task_ids()
            .filter(|j| node.decisions[j.index()] == Decision::Open)
            .filter_map(|j| {
                let (n, k) = (node.sizes[j.index()], inst.min_team(j));
                (n > 0 && n < k).then(|| {
                    let at_stake = n as f64 * inst.value_function(j).value(k) / k as f64;
                    (j.index(), at_stake)
                })
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(j, _)| j)
    }

    /// Rounds the relaxation task by task (staffed where at least half the threshold is
    /// there, else unstaffed) down to a real assignment: a good first incumbent.
    fn dive(&mut self, root: &Node) {
        let mut current = root.clone();
        loop {
            let Some(task) = self.branching_task(&current) else {
                return;
            };
            let k = self.instance.min_team(TaskId(task as u32));
            let mut decisions = current.decisions.clone();
            decisions[task] = if 2 * current.sizes[task] >= k {
                Decision::Staffed
            } else {
                Decision::Unstaffed
            };
            let next = self.node(decisions.clone(), Some(&current)).or_else(|| {
                decisions[task] = Decision::Unstaffed;
                self.node(decisions, Some(&current))
            });
            match next {
                Some(next) => current = next,
                None => return,
            }
        }
    }
}
