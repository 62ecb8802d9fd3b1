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
//! otherwise the task with the most envelope value at stake is branched on, both ways
//! (with skills, first a task the Lagrangian relaxation below holds a share of).
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
//! met and the skills held. Every threshold is read as the task's smallest earning
//! team ([`Instance::smallest_team`]: more than k where its skills need more robots),
//! which tightens the envelope of a task that needs few robots but many skills. (The
//! dives a rounding or a staffing takes, [`TeamOptimum::dive`] and
//! [`TeamOptimum::staff`], read the thresholds as they are.) Once a skill game has
//! taken 2 000 nodes, the staffing neighbourhood (ours) looks for a better best found
//! among the staffings one task away from the best found's, each finished by the
//! search itself (a skill dive and a small search below it).
//!
//! **Pairs ruled out.** The root's relaxation, priced, bounds every assignment less the
//! reduced costs of where it puts its robots; a robot-task pair whose reduced cost
//! alone brings that bound to the best found is kept out of every node, more of them
//! with each better assignment found (reduced-cost fixing).

use std::collections::BinaryHeap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use afg_game::{Assignment, Instance, TaskId};

use super::Optimum;
use crate::{AllocError, AllocStats, Allocation, Allocator, timed};

mod deadline;
mod node;
mod start;
use deadline::Deadline;
use node::{AFTER_NODES, Decision, Node, Search};

use super::transport::NEVER;

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
#[derive(Clone, Debug, Default)]
pub struct TeamOptimum {
    /// Stop within this long with the best found and its gap (`None`: until proven):
    /// the search starts no step that its longest step so far says would end later,
    /// and the root's relaxation stops at 3/4 of it where it is not solved by then
    /// (its prices then give the bound, and the teams they half staff the answer).
    pub time_limit: Option<Duration>,
    /// Stop as soon as the certified gap ([`TeamSolution::gap`]) is at most this
    /// (`Some(0.001)`: within 0.1 % of the bound; `None`: until proven).
    pub gap: Option<f64>,
    /// Stop, with the best found, once this is set (from another thread: a Ctrl-C
    /// handler, a user's cancel button). Checked between the search's steps, and
    /// inside the root's relaxation.
    pub stop: Option<Arc<AtomicBool>>,
    /// Told the search's state after the dive and after every node (at most every
    /// millisecond or so: rate-limit what it prints).
    pub progress: Option<fn(&TeamProgress)>,
    /// A start: an assignment of the instance (from a heuristic, a learned model, an
    /// earlier solve) that the search takes as its best found before its root, so that
    /// its welfare prunes from the first node, as a MIP solver's start does. The
    /// answer is never worse than it. `None`: the search finds its own.
    pub start: Option<Assignment>,
}

/// Where [`TeamOptimum`]'s search stands, as [`TeamOptimum::progress`] is told.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TeamProgress {
    /// Seconds since the solve began.
    pub seconds: f64,
    /// The best welfare found so far.
    pub welfare: f64,
    /// The highest bound of the nodes still open (proven: no assignment is worth more).
    pub bound: f64,
    /// Nodes whose relaxation was solved.
    pub nodes: u64,
    /// Nodes still open.
    pub open: usize,
}

impl TeamProgress {
    /// The certified relative gap of the best found ([`crate::certified_gap`]).
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::TeamProgress;
    /// let p = TeamProgress { seconds: 1.0, welfare: 100.0, bound: 101.0, nodes: 7, open: 3 };
    /// assert!((p.gap() - 0.01).abs() < 1e-12);
    /// ```
    pub fn gap(&self) -> f64 {
        crate::certified_gap(self.bound, self.welfare)
    }
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
        crate::certified_gap(self.bound, self.welfare)
    }
}

impl TeamOptimum {
    /// `opt` stopped within `seconds` (see [`TeamOptimum::time_limit`]); a limit beyond
    /// what a clock can hold is no limit.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] where `seconds` is not finite and positive.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::TeamOptimum;
    /// assert!(TeamOptimum::with_time_limit(0.5)?.time_limit.is_some());
    /// assert!(TeamOptimum::with_time_limit(1e30).is_ok());
    /// for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
    ///     assert!(TeamOptimum::with_time_limit(bad).is_err());
    /// }
    /// # Ok::<(), afg_baseline::AllocError>(())
    /// ```
    pub fn with_time_limit(seconds: f64) -> Result<Self, AllocError> {
        TeamOptimum::default().stopping(Some(seconds), None)
    }

    /// The exact solver a user's `time_limit` and `gap` ask for (see
    /// [`TeamOptimum::stopping`]), `None` where neither is given: what
    /// [`Method::allocator_with`](crate::Method::allocator_with) takes.
    ///
    /// # Errors
    /// As [`TeamOptimum::stopping`].
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::TeamOptimum;
    /// assert!(TeamOptimum::limits(None, None)?.is_none());
    /// assert_eq!(TeamOptimum::limits(None, Some(0.01))?.unwrap().gap, Some(0.01));
    /// assert!(TeamOptimum::limits(Some(f64::NAN), None).is_err());
    /// # Ok::<(), afg_baseline::AllocError>(())
    /// ```
    pub fn limits(time_limit: Option<f64>, gap: Option<f64>) -> Result<Option<Self>, AllocError> {
        if time_limit.is_none() && gap.is_none() {
            return Ok(None);
        }
        TeamOptimum::default().stopping(time_limit, gap).map(Some)
    }

    /// This solver with a time limit in seconds (see [`TeamOptimum::time_limit`]) and
    /// a gap target (see [`TeamOptimum::gap`]), each `None` for none: the one place
    /// both are checked.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] where the time limit is not finite and positive
    /// or the gap is not finite and non-negative.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::TeamOptimum;
    /// let exact = TeamOptimum::default().stopping(None, Some(0.001))?;
    /// assert_eq!((exact.time_limit, exact.gap), (None, Some(0.001)));
    /// assert!(TeamOptimum::default().stopping(None, Some(-0.1)).is_err());
    /// assert!(TeamOptimum::default().stopping(Some(0.0), None).is_err());
    /// # Ok::<(), afg_baseline::AllocError>(())
    /// ```
    pub fn stopping(self, time_limit: Option<f64>, gap: Option<f64>) -> Result<Self, AllocError> {
        if let Some(seconds) = time_limit
            && !(seconds.is_finite() && seconds > 0.0)
        {
            return Err(AllocError::InvalidParameter(format!(
                "the time limit must be a finite and positive number of seconds (got {seconds})"
            )));
        }
        if let Some(gap) = gap
            && !(gap.is_finite() && gap >= 0.0)
        {
            return Err(AllocError::InvalidParameter(format!(
                "the gap must be a finite, non-negative fraction, e.g. 0.001 for 0.1 % (got {gap})"
            )));
        }
        Ok(TeamOptimum {
            time_limit: time_limit
                .map(|seconds| Duration::try_from_secs_f64(seconds).unwrap_or(Duration::MAX)),
            gap,
            ..self
        })
    }
}

impl TeamOptimum {
    /// Solves `instance`: any team game, or the paper's.
    ///
    /// # Errors
    /// [`AllocError::TooLarge`] where the solve would need more memory than this
    /// machine has available ([`crate::exact_memory`]).
    pub fn solve(&self, instance: &Instance) -> Result<TeamSolution, AllocError> {
        super::check_memory(instance)?;
        let deadline = Deadline::new(self.time_limit);
        let stopped = || {
            self.stop
                .as_ref()
                .is_some_and(|s| s.load(Ordering::Relaxed))
        };
        let out_of_time = || deadline.near() || stopped();
        let mut search = Search::exact(instance);
        if let Some(start) = &self.start {
            start::check(instance, start)?;
            search.offer(start);
        }
        let root = search.root(&|| deadline.root_over() || stopped());
        let mut root = match root {
            Ok(root) => root,
            Err(bound) => {
                let (assignment, welfare, nodes) = search.into_best();
                return Ok(TeamSolution {
                    assignment,
                    welfare,
                    bound: bound.max(welfare),
                    proven: false,
                    nodes,
                });
            }
        };
        let m = instance.num_tasks();
        // The dive rounds without skills: a skill dive brings its last node what it lacks.
        if let Some(leaf) = search.dive(&root, &out_of_time, &mut |node, fractional| {
            Self::half_rounding(instance, &node.relaxation(m), fractional)
        }) {
            search.skill_dive(leaf, &out_of_time);
        }
        search.price_root(&mut root, &out_of_time);
        // With skills, the staffing neighbourhood once the search runs long.
        let mut staffing_after = instance.has_skill_rules().then(|| root.clone());
        let mut open = BinaryHeap::from([root]);
        let bound =
            |open: &BinaryHeap<Node>, best: f64| open.peek().map_or(best, |n| n.bound.max(best));
        while let Some(node) = open.peek() {
            if search.closes(node.bound) {
                open.clear();
                break;
            }
            let (welfare, bound) = (search.best_welfare(), bound(&open, search.best_welfare()));
            if let Some(report) = self.progress {
                report(&TeamProgress {
                    seconds: deadline.start.elapsed().as_secs_f64(),
                    welfare,
                    bound,
                    nodes: search.nodes(),
                    open: open.len(),
                });
            }
            if out_of_time()
                || self
                    .gap
                    .is_some_and(|gap| crate::certified_gap(bound, welfare) <= gap)
            {
                break;
            }
            if let Some(root) = staffing_after.take_if(|_| search.nodes() >= AFTER_NODES) {
                search.flip_staffing(&root, &out_of_time);
            }
            let node = open.pop().expect("peeked");
            open.extend(search.expand(&node));
        }
        let (best, best_welfare, nodes) = search.into_best();
        Ok(TeamSolution {
            proven: open.is_empty(),
            bound: bound(&open, best_welfare),
            welfare: best_welfare,
            assignment: best,
            nodes,
        })
    }
}

/// The root of [`TeamOptimum`]'s search: every task's value replaced by its concave
/// envelope (module docs), solved exactly. What a rounding — hand-written or learned —
/// reads to decide which tasks to staff.
#[derive(Clone, Debug)]
pub struct TeamRelaxation {
    /// Each task's coalition size in the relaxed optimum (between 0 and its threshold:
    /// a fraction of a team).
    pub sizes: Vec<usize>,
    /// Each task's price in the relaxed optimum: a robot joins the task where the price
    /// less its cost is highest (the transport solver's dual, one per task).
    pub prices: Vec<f64>,
    /// The relaxation's welfare: an upper bound on every assignment's.
    pub bound: f64,
}

impl TeamOptimum {
    /// The root relaxation of `instance` (one transport solve).
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::TeamOptimum;
    /// use afg_game::GeneratorConfig;
    /// let mut cfg = GeneratorConfig::paper(30, 5, 1);
    /// cfg.min_team = Some(afg_game::CountRange { min: 6, max: 12 });
    /// let inst = cfg.generate()?;
    /// let root = TeamOptimum::relax(&inst);
    /// assert_eq!(root.sizes.iter().sum::<usize>(), 30);
    /// assert!(root.bound >= TeamOptimum::default().solve(&inst)?.welfare - 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn relax(instance: &Instance) -> TeamRelaxation {
        let mut search = Search::new(instance);
        let Ok(root) = search.root(NEVER) else {
            unreachable!("never stopped")
        };
        root.relaxation(instance.num_tasks())
    }

    /// `opt`'s rounding in its dive: each of the `fractional` tasks staffed where the
    /// relaxation `root` holds at least half its threshold.
    pub fn half_rounding(
        instance: &Instance,
        root: &TeamRelaxation,
        fractional: &[TaskId],
    ) -> Vec<bool> {
        fractional
            .iter()
            .map(|&j| 2 * root.sizes[j.index()] >= instance.min_team(j))
            .collect()
    }

    /// A dive from the root relaxation ([`TeamOptimum::relax`]) to an assignment, with
    /// the rounding `round`: at each step it is given the relaxation of the current
    /// decisions and the tasks still undecided that it leaves between 0 and their
    /// threshold, and says of each whether to staff it; the others stay open, the
    /// decisions are re-solved (warm) and the dive goes on until no task is left
    /// between. Where its choice asks for more robots than there are, all of them are
    /// left unstaffed. The best assignment met on the way and its welfare. `opt`'s own
    /// first answer is this dive with [`TeamOptimum::half_rounding`].
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::TeamOptimum;
    /// use afg_game::GeneratorConfig;
    /// let mut cfg = GeneratorConfig::paper(40, 5, 3);
    /// cfg.min_team = Some(afg_game::CountRange { min: 8, max: 16 });
    /// let inst = cfg.generate()?;
    /// let (dived, welfare) = TeamOptimum::dive(&inst, |root, fractional| {
    ///     TeamOptimum::half_rounding(&inst, root, fractional)
    /// });
    /// assert_eq!(inst.welfare(&dived), welfare);
    /// assert!(welfare <= TeamOptimum::default().solve(&inst)?.welfare + 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn dive(
        instance: &Instance,
        mut round: impl FnMut(&TeamRelaxation, &[TaskId]) -> Vec<bool>,
    ) -> (Assignment, f64) {
        let mut search = Search::new(instance);
        let Ok(root) = search.root(NEVER) else {
            unreachable!("never stopped")
        };
        let m = instance.num_tasks();
        search.dive(&root, NEVER, &mut |node, fractional| {
            round(&node.relaxation(m), fractional)
        });
        let (best, welfare, _) = search.into_best();
        (best, welfare)
    }

    /// The best assignment in which the tasks of `staffed` (one flag per task) hold
    /// their thresholds and the others earn nothing — one transport solve, exact for
    /// that choice in a game without skills — and its welfare; `None` where no
    /// assignment staffs them all (their thresholds add up to more than N, a task no
    /// team can staff, too little room for the rest).
    ///
    /// With skills, where a staffed task's team lacks a skill, a dive brings it: the
    /// cheapest robot free to bring the missing skill is fixed at the task (or kept out
    /// where that leaves no assignment), re-solved, until every staffed team holds its
    /// skills or no robot can bring one; the best assignment met is returned (a staffed
    /// task still short of a skill earns nothing). Not exact then: it is the exact
    /// solver's skill branching followed down one side.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::TeamOptimum;
    /// use afg_game::GeneratorConfig;
    /// let mut cfg = GeneratorConfig::paper(30, 5, 1);
    /// cfg.min_team = Some(afg_game::CountRange { min: 6, max: 12 });
    /// let inst = cfg.generate()?;
    /// let best = TeamOptimum::default().solve(&inst)?;
    /// let staffed: Vec<bool> =
    ///     inst.task_ids().map(|j| best.assignment.size(j) >= inst.min_team(j)).collect();
    /// let (_, welfare) = TeamOptimum::staff(&inst, &staffed).expect("the optimum's staffing");
    /// assert!((welfare - best.welfare).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Panics
    /// If `staffed` does not hold one flag per task.
    pub fn staff(instance: &Instance, staffed: &[bool]) -> Option<(Assignment, f64)> {
        assert_eq!(staffed.len(), instance.num_tasks(), "one flag per task");
        let mut search = Search::new(instance);
        let root = search.root_decisions();
        if root
            .iter()
            .zip(staffed)
            .any(|(&d, &staff)| staff && d == Decision::Unstaffed)
        {
            return None; // a task no team can staff
        }
        let decisions = staffed
            .iter()
            .map(|&staff| {
                if staff {
                    Decision::Staffed
                } else {
                    Decision::Unstaffed
                }
            })
            .collect();
        let node = search.node(decisions, Vec::new(), None)?;
        search.skill_dive(node, NEVER);
        let (best, welfare, _) = search.into_best();
        Some((best, welfare))
    }
}

/// `opt` with its limits: on a team game the best assignment found, its bound in
/// [`AllocStats::bound`] and the nodes solved in [`AllocStats::iterations`]; the
/// paper's game is [`Optimum`]'s (exact in polynomial time, no limit needed).
impl Allocator for TeamOptimum {
    fn name(&self) -> String {
        "opt".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        if !instance.has_teams() {
            // No search to start; the start is still checked (`solve` checks it itself).
            if let Some(start) = &self.start {
                start::check(instance, start)?;
            }
            return Optimum.allocate(instance);
        }
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
