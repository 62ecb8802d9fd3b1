//! The exact optimum of the team games, by branch and bound over which tasks are
//! staffed (and, with skills, which robots join them), with the transport solver at
//! every node.
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
//! found; a dive from the root (rounding every fractional task to the nearer side at
//! once, re-solved until none is left) finds a good one before the search, which takes the open node of highest bound first. A
//! time limit stops it with the best assignment, the highest open bound and the gap.
//!
//! **Skills.** The relaxation counts a team's value without its skills. Where a node's
//! relaxed optimum is a real assignment but some earning task lacks a skill, the node
//! branches on the cheapest robot holding that skill (not there, free to go there):
//! it joins the task, or it may not. A task left with too little of a skill among the
//! robots free to join it earns nothing. Staffed then means earning: the threshold
//! met and the skills held.

use std::cell::Cell;
use std::collections::BinaryHeap;
use std::time::{Duration, Instant};

use afg_game::{Assignment, Instance};

use crate::{AllocError, AllocStats, Allocation, Allocator, timed};

mod node;
use node::Search;

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
    /// Stop within this long with the best found and its gap (`None`: until proven):
    /// the search starts no step that its longest step so far says would end later
    /// (the root's relaxation is always solved, however long it takes).
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

impl TeamOptimum {
    /// Solves `instance`: any team game, or the paper's.
    ///
    /// # Errors
    /// None on a valid instance (the `Result` is the [`Allocator`]'s).
    pub fn solve(&self, instance: &Instance) -> Result<TeamSolution, AllocError> {
        let deadline = Deadline::new(self.time_limit);
        let out_of_time = || deadline.near();
        let mut search = Search::new(instance);
        let Some(mut root) = search.node(search.root_decisions(), Vec::new(), None) else {
            unreachable!("the root is feasible: the instance holds every robot")
        };
        search.dive(&root, &out_of_time);
        if instance.has_skill_rules()
            && instance.num_robots() * instance.num_tasks() <= node::MAX_PAIRS
        {
            root.bound = root.bound.min(search.price_skills(&root, &out_of_time));
        }
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
            let Some(branch) = search.branch(&node) else {
                continue; // closed: its assignment was offered to the best
            };
            for (decisions, pairs) in search.children(&node, branch) {
                if let Some(child) = search.node(decisions, pairs, Some(&node))
                    && !search.closes(child.bound)
                {
                    open.push(child);
                }
            }
        }
        let (best, best_welfare, nodes) = search.into_best();
        let bound = open
            .peek()
            .map_or(best_welfare, |n| n.bound.max(best_welfare));
        Ok(TeamSolution {
            proven: open.is_empty(),
            bound,
            welfare: best_welfare,
            assignment: best,
            nodes,
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

/// A time limit that the search checks between steps: it is near when the time spent
/// plus the longest step between two checks so far (the root's solve before the first
/// check aside: it always runs) reaches it.
struct Deadline {
    limit: Option<Duration>,
    start: Instant,
    last: Cell<Option<Instant>>,
    longest: Cell<Duration>,
}

impl Deadline {
    fn new(limit: Option<Duration>) -> Self {
        Deadline {
            limit,
            start: Instant::now(),
            last: Cell::new(None),
            longest: Cell::new(Duration::ZERO),
        }
    }

    /// Whether the next step would likely end past the limit.
    fn near(&self) -> bool {
        let now = Instant::now();
        if let Some(last) = self.last.replace(Some(now)) {
            self.longest.set(self.longest.get().max(now - last));
        }
        self.limit
            .is_some_and(|limit| now - self.start + self.longest.get() >= limit)
    }
}
