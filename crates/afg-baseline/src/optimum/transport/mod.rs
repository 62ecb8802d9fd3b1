//! The optimum of a whole instance as a transportation problem with M concave sinks,
//! solved from prices: successive shortest paths over the M task nodes and the sink,
//! warm-started from the prices of a subsample of the robots (multi-scale).
//!
//! With task prices π (and the sink's potential μ, which this solver keeps at the
//! common offset of π), every robot at a minimum of `c_ij − π_j` and every task's count
//! between the slots its price buys (`F_j(n_j + 1) − F_j(n_j) ≤ π_j − μ ≤ F_j(n_j) −
//! F_j(n_j − 1)`) is optimal — LP duality for the min-cost flow, the check that
//! [`verify_optimal`](super::verify_optimal) makes. The solver starts from prices,
//! puts every robot at its minimum, and gives each task the count its price buys.
//! What is left are node imbalances (a task with more robots than its count buys, or
//! fewer), each one unit routed along a shortest path of the residual graph over the
//! M + 1 nodes — robots shifting between tasks, counts moving up or down — Dijkstra
//! with the prices as potentials, searched from whichever side of the imbalance has
//! fewer nodes. The state ([`Flow`]) can be kept and changed by events
//! ([`IncrementalOptimum`](super::IncrementalOptimum)): columns opened and closed,
//! robots added and removed.
//!
//! How many units must be routed depends on how good the starting prices are. They come
//! from the same problem on every 8th robot (with the value functions scaled so that
//! one robot of the subsample stands for 8), solved the same way from its own
//! subsample, down to a few hundred robots solved from zero prices. The subsample's
//! prices are near the full problem's, so only a few units per task move at each level,
//! and almost all the work is reading the N × M costs once.
//!
//! # Complexity
//! O(N M) to read the costs and place every robot at its minimum, at each of the
//! log₈(N) levels (a geometric sum: O(N M) in all), plus O(M²) for one Dijkstra over
//! the M + 1 nodes (dense: a scan of the labels per node settled) per routed unit, of
//! which warm prices leave a few per task and level. Memory O(N M) for the costs;
//! nothing of size N × N.

use std::cmp::{Ordering, Reverse};

use afg_game::{Assignment, Instance, Point, RobotId, TaskId};
use rayon::prelude::*;

use super::movers::{Movers, NOWHERE};

mod columns;
mod levels;
mod search;
mod stopped;
use crate::simple::task_positions;
pub(in crate::optimum) use columns::{Column, Slots};
use levels::{Level, cheapest, coarse_prices, cost_row, sink};
use stopped::interrupted;
pub(in crate::optimum) use stopped::{Interrupted, NEVER, Stop, reduced_costs};

/// Each coarser level keeps every `FACTOR`-th robot of the level above.
const FACTOR: usize = 8;
/// Levels with fewer robots than this start from zero prices.
const BASE_ROBOTS: usize = 256;
/// Cost matrices with at least this many entries are filled on all cores.
const PARALLEL_ENTRIES: usize = 1 << 16;
/// [`Flow::route_until`] asks whether to stop once every this many units.
const STOP_EVERY: u64 = 8;

/// An optimal assignment (column per robot: a task index, or M for the void), its
/// prices (one per column, offset so that the sink's potential is 0: each price lies
/// between its column's last and next marginal value), and the units routed at the
/// finest level.
pub(super) struct Solution {
    pub task_of: Vec<u32>,
    pub prices: Vec<f64>,
    pub routed: u64,
}

/// Solves `inst` exactly.
/// The assignment of a solver's columns (M: the void).
pub(super) fn assignment_of(instance: &Instance, task_of: &[u32]) -> Assignment {
    let m = instance.num_tasks();
    let tasks = task_of
        .iter()
        .map(|&j| (j as usize) < m)
        .zip(task_of)
        .map(|(task, &j)| task.then_some(TaskId(j)))
        .collect();
    Assignment::from_tasks(instance, tasks).expect("the solver respects capacities")
}

pub(super) fn solve(inst: &Instance) -> Solution {
    solved(inst, 0).into_solution()
}

/// The columns of `inst` as they are: each task's concave value function (its
/// threshold left out) and capacity, then the void where the instance allows it.
pub(super) fn task_columns(inst: &Instance) -> Vec<Column> {
    let mut columns: Vec<Column> = inst
        .task_ids()
        .map(|j| Column::Task {
            value: Slots::concave(inst.value_function(j)),
            capacity: inst.capacity(j),
        })
        .collect();
    if inst.allows_void() {
        columns.push(Column::Void);
    }
    columns
}

/// How a solve's costs differ from the instance's travel costs `β d(i, j)` (0 at the
/// void): those costs already computed, with changes of the caller's own (`travel`,
/// row-major, a row of the columns per robot; `None`: computed anew), each `(robot,
/// column, delta)` of `adjust` added to that robot's cost there, and each robot's cost
/// at task j lowered by `Σ_s skill_prices[j S + s] · skills[s]` where `skill_prices` is
/// not empty.
#[derive(Clone, Copy, Default)]
pub(in crate::optimum) struct Costs<'a> {
    pub travel: Option<&'a [f64]>,
    pub adjust: &'a [(usize, usize, f64)],
    pub skill_prices: &'a [f64],
}

impl Costs<'_> {
    /// Whether these are the instance's own travel costs.
    fn unchanged(&self) -> bool {
        self.travel.is_none() && self.adjust.is_empty() && self.skill_prices.is_empty()
    }
}

/// Solves the problem of `inst`'s robots at `costs` with other `columns` (one per task,
/// then the void's where the instance allows it) exactly, from `warm` prices (or from
/// its subsamples' where there are none: only at unchanged costs); or, where `stop`
/// says so first (a root's solve, at unchanged costs), where it stood.
pub(super) fn solve_columns(
    inst: &Instance,
    columns: &[Column],
    warm: Option<&[f64]>,
    costs: Costs,
    stop: Stop,
) -> Result<Solution, Interrupted> {
    let coarse;
    let warm = match warm {
        Some(prices) => Some(prices),
        None if costs.unchanged() => {
            coarse = coarse_prices(inst, columns, FACTOR, stop);
            coarse.as_deref()
        }
        None => None,
    };
    if let Some(prices) = warm
        && stop()
    {
        return Err(interrupted(inst, columns, prices));
    }
    let flow = Flow::solved(Level::priced(inst, columns, costs), warm, stop);
    if flow.balanced() {
        Ok(flow.into_solution())
    } else {
        Err(interrupted(inst, columns, &flow.prices()))
    }
}

/// Every robot's travel cost at every column of `inst` (its tasks', then the void's
/// where it allows it), row-major: [`Costs::travel`] as the instance has them.
pub(super) fn travel_costs(inst: &Instance) -> Vec<f64> {
    levels::cost_matrix(inst, 1, inst.num_tasks() + usize::from(inst.allows_void()))
}

/// What robot i's skills are worth at each task at `skill_prices` (one per task and
/// skill): `Σ_s skill_prices[j S + s] · skills_i[s]` for every task j.
pub(super) fn skill_rebates<'a>(
    inst: &'a Instance,
    i: RobotId,
    skill_prices: &'a [f64],
) -> impl Iterator<Item = f64> + 'a {
    let skills = inst.skills(i);
    skill_prices
        .chunks_exact(inst.num_skills().max(1))
        .map(move |prices| {
            prices
                .iter()
                .zip(skills)
                .map(|(&p, &q)| p * f64::from(q))
                .sum()
        })
}

/// The solved residual state of `inst` (from its subsample's prices), to keep, with
/// `spare` closed columns to open later.
pub(super) fn solved(inst: &Instance, spare: usize) -> Flow {
    let columns = task_columns(inst);
    let mut warm = coarse_prices(inst, &columns, FACTOR, NEVER);
    if let Some(prices) = &mut warm {
        prices.resize(prices.len() + spare, 0.0);
    }
    Flow::solved(Level::new(inst, &columns, 1, spare), warm.as_deref(), NEVER)
}

/// Solves `inst` exactly from `prices` (one per column: the tasks', then the void's
/// where the instance allows it; any common offset), without subsample levels.
pub(super) fn solve_from(inst: &Instance, prices: &[f64]) -> Solution {
    Flow::solved(
        Level::new(inst, &task_columns(inst), 1, 0),
        Some(prices),
        NEVER,
    )
    .into_solution()
}

/// The residual state of one level: where every robot is, the count each column sends
/// to the sink, what each node still has to send (positive) or receive (negative), and
/// the potentials (column prices, then the sink's).
#[derive(Clone)]
pub(super) struct Flow {
    level: Level,
    task_of: Vec<u32>,
    /// Units each column sends to the sink: its count, once balanced.
    bought: Vec<usize>,
    excess: Vec<i64>,
    potential: Vec<f64>,
    movers: Movers,
    dist: Vec<f64>,
    /// The node each node was reached from on the current shortest-path tree
    /// ([`SOURCE`] for the source): a shift of the cheapest mover between two tasks, a
    /// count up (into the sink) or down (from it).
    via: Vec<u32>,
    done: Vec<bool>,
    /// Units routed by the last [`Flow::route`].
    routed: u64,
}

/// Marks the source of a shortest-path tree.
const SOURCE: u32 = u32::MAX;

impl Flow {
    /// `level` solved from `warm` prices (sink potential 0), or from zero prices with
    /// the sink's potential set so that the counts they buy add up to N; where `stop`
    /// says so first, as far as it got (not [`Flow::balanced`]).
    fn solved(level: Level, warm: Option<&[f64]>, stop: Stop) -> Flow {
        let prices = warm.map_or_else(|| vec![0.0; level.m()], <[f64]>::to_vec);
        let sink = level.balancing_offset(&prices, None);
        let mut flow = Flow::new(level, prices, sink);
        flow.route_until(stop);
        flow
    }

    /// Every robot at a minimum of `c_ij − π_j` (the lowest such column), every column's
    /// count what `π_j − μ` buys.
    fn new(level: Level, prices: Vec<f64>, sink_potential: f64) -> Self {
        let m = level.m();
        let argmin = |row: &[f64]| cheapest(row, &prices, &level.columns);
        let task_of: Vec<u32> = if level.costs.len() >= PARALLEL_ENTRIES {
            level.costs.par_chunks(m).map(argmin).collect()
        } else {
            level.costs.chunks(m).map(argmin).collect()
        };
        let bought: Vec<usize> = (0..m)
            .map(|j| level.count_at(j, prices[j] - sink_potential))
            .collect();
        let mut excess = vec![0i64; m + 1];
        for &j in &task_of {
            excess[j as usize] += 1;
        }
        for (j, &b) in bought.iter().enumerate() {
            excess[j] -= b as i64;
            excess[sink(m)] += b as i64;
        }
        excess[sink(m)] -= level.n as i64;
        let mut potential = prices;
        potential.push(sink_potential);
        Flow {
            movers: Movers::new(
                &task_of,
                &level.costs,
                (level.columns.iter())
                    .map(|c| matches!(c, Column::Closed))
                    .collect(),
            ),
            level,
            task_of,
            bought,
            excess,
            potential,
            dist: vec![0.0; m + 1],
            via: vec![SOURCE; m + 1],
            done: vec![false; m + 1],
            routed: 0,
        }
    }

    /// The assignment and the prices measured from the sink's potential.
    pub fn into_solution(self) -> Solution {
        Solution {
            prices: self.prices(),
            routed: self.routed,
            task_of: self.task_of,
        }
    }

    /// Every column's price measured from the sink's potential.
    pub fn prices(&self) -> Vec<f64> {
        let m = self.level.m();
        let sink = self.potential[sink(m)];
        self.potential[..m].iter().map(|p| p - sink).collect()
    }

    /// The column of every row (`NOWHERE` for a robot no longer there).
    pub fn task_of(&self) -> &[u32] {
        &self.task_of
    }

    /// Builds every heap of movers now (see [`Movers::build_all`]).
    pub fn build_movers(&mut self) {
        self.movers.build_all(&self.task_of, &self.level.costs);
    }

    /// The units routed by the last [`Flow::route`].
    pub fn routed(&self) -> u64 {
        self.routed
    }

    /// The columns.
    pub fn columns(&self) -> &[Column] {
        &self.level.columns
    }

    /// Moves the sink's potential to where the column prices buy every robot there is
    /// (the same shift for every task's price, so no robot's cheapest column changes),
    /// and sets the counts those prices buy: after an event that takes robots from
    /// many columns or gives them to many, most of the imbalance goes without routing.
    pub fn rebalance(&mut self) {
        let m = self.level.m();
        let mu = (self.level).balancing_offset(&self.potential[..m], Some(self.potential[sink(m)]));
        self.potential[sink(m)] = mu;
        for j in 0..m {
            let bought = self.level.count_at(j, self.potential[j] - mu);
            let change = bought as i64 - self.bought[j] as i64;
            self.bought[j] = bought;
            self.excess[j] -= change;
            self.excess[sink(m)] += change;
        }
    }

    /// Routes every imbalance along shortest paths; returns the units routed.
    /// Each unit goes along a shortest path from a node with excess to one short of
    /// units, searched from the side with fewer such nodes (so that the search meets
    /// one of the many on the other side early).
    pub fn route(&mut self) -> u64 {
        self.route_until(NEVER);
        self.routed
    }

    /// [`Flow::route`], asking `stop` before every unit but the first few: whether
    /// it finished (every node balanced).
    fn route_until(&mut self, stop: Stop) -> bool {
        self.routed = 0;
        loop {
            let surplus = self.excess.iter().filter(|&&e| e > 0).count();
            let short = self.excess.iter().filter(|&&e| e < 0).count();
            if surplus == 0 {
                return true;
            }
            if self.routed % STOP_EVERY == STOP_EVERY - 1 && stop() {
                return false;
            }
            let backward = surplus > short;
            let end = self.search(backward);
            self.augment(end, backward);
            self.routed += 1;
        }
    }

    /// Whether every node is balanced: the flow is optimal at its prices.
    fn balanced(&self) -> bool {
        self.excess.iter().all(|&e| e == 0)
    }

    /// Moves the robot in `row` from column `from` to column `to`, ahead of routing.
    fn shift(&mut self, row: usize, from: usize, to: usize) {
        self.place(row, from, to);
        self.excess[from] -= 1;
        self.excess[to] += 1;
    }

    /// Puts the robot in `row` from column `from` into column `to`; the movers follow.
    fn place(&mut self, row: usize, from: usize, to: usize) {
        self.task_of[row] = to as u32;
        let costs = &self.level.costs;
        self.movers.leave(row as u32, from, &self.task_of, costs);
        self.movers.enter(row as u32, to, self.level.row(row));
    }

    /// The robot in `row` is gone: one unit less for the sink.
    pub fn remove_robot(&mut self, row: usize) {
        let j = self.task_of[row] as usize;
        self.task_of[row] = NOWHERE;
        let costs = &self.level.costs;
        self.movers.leave(row as u32, j, &self.task_of, costs);
        self.excess[j] -= 1;
        self.level.n -= 1;
        let m = self.level.m();
        self.excess[sink(m)] += 1;
    }

    /// A robot with travel costs `costs` (one per column) joins at its cheapest column;
    /// returns its row.
    pub fn add_robot(&mut self, costs: &[f64]) -> usize {
        let m = self.level.m();
        let row = self.task_of.len();
        let j = cheapest(costs, &self.potential[..m], &self.level.columns) as usize;
        self.level.costs.extend_from_slice(costs);
        self.task_of.push(j as u32);
        self.movers.enter(row as u32, j, costs);
        self.excess[j] += 1;
        self.level.n += 1;
        self.excess[sink(m)] -= 1;
        row
    }

    /// Column `k` is closed: its robots move to their cheapest open column, and it
    /// buys nothing.
    pub fn close(&mut self, k: usize) {
        let m = self.level.m();
        self.level.columns[k] = Column::Closed;
        let members: Vec<usize> = (0..self.task_of.len())
            .filter(|&r| self.task_of[r] as usize == k)
            .collect();
        self.movers.close(k);
        for r in members {
            let to = cheapest(self.level.row(r), &self.potential[..m], &self.level.columns);
            self.shift(r, k, to as usize);
        }
        let b = std::mem::take(&mut self.bought[k]) as i64;
        self.excess[k] += b;
        self.excess[sink(m)] -= b;
    }

    /// Opens `column` with travel costs `costs` (one per row; anything for rows whose
    /// robot is gone) in a closed column, or a new one; returns its index. Its price is
    /// chosen where the robots that prefer it at that price fill the count the price
    /// buys, and those robots move in; no other robot prefers it. Route next.
    pub fn open(&mut self, column: Column, costs: &[f64]) -> usize {
        let k = match (self.level.columns.iter()).position(|c| matches!(c, Column::Closed)) {
            Some(k) => k,
            None => {
                self.widen();
                self.level.m() - 1
            }
        };
        let m = self.level.m();
        self.level.columns[k] = column;
        self.movers
            .open(k, &self.task_of, &mut self.level.costs, costs);
        // Robots enter k cheapest first — the least `c_rk − c_rj + π_j` among the
        // heads of the pairs (j, k), the price at which robot r would rather be in k —
        // while that price still buys more of k's slots than robots have entered. The
        // price stops at the next robot's, so no robot left outside prefers k.
        let mu = self.potential[sink(m)];
        let mut entered = 0;
        self.potential[k] = loop {
            let head = (0..m)
                .filter(|&j| j != k)
                .map(|j| (self.movers.keys(j)[k] + self.potential[j], j))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((price, j)) = head.filter(|(price, _)| price.is_finite()) else {
                // No robot can move: a price at which k buys nothing.
                break mu + self.level.marginal(k, 1);
            };
            let full = entered >= self.level.capacity(k)
                || self.level.marginal(k, entered + 1) <= price - mu;
            if full {
                break price;
            }
            self.shift(self.movers.robot(j, k) as usize, j, k);
            entered += 1;
        };
        let b = self.level.count_at(k, self.potential[k] - mu);
        self.bought[k] = b;
        self.excess[k] -= b as i64;
        self.excess[sink(m)] += b as i64;
        k
    }

    /// Adds a closed column last (ahead of the sink), and a few more for later.
    fn widen(&mut self) {
        let m = self.level.m();
        let wider = m + (m / 4).max(1);
        let rows = self.task_of.len();
        let mut costs = vec![0.0; rows * wider];
        for (new, old) in costs.chunks_mut(wider).zip(self.level.costs.chunks(m)) {
            new[..m].copy_from_slice(old);
        }
        self.level.costs = costs;
        self.level.columns.resize(wider, Column::Closed);
        self.movers.widen(wider);
        let added = wider - m;
        let at = sink(m);
        let sink_price = self.potential[at];
        self.potential
            .splice(at..at, std::iter::repeat_n(sink_price, added));
        self.excess.splice(at..at, std::iter::repeat_n(0, added));
        self.bought.resize(wider, 0);
        self.dist.resize(wider + 1, 0.0);
        self.via.resize(wider + 1, SOURCE);
        self.done.resize(wider + 1, false);
    }
}
