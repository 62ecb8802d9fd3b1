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

use afg_game::{Instance, Point, ValueFunction};
use rayon::prelude::*;

use super::movers::{Movers, NOWHERE};

/// Each coarser level keeps every `FACTOR`-th robot of the level above.
const FACTOR: usize = 8;
/// Levels with fewer robots than this start from zero prices.
const BASE_ROBOTS: usize = 256;
/// Cost matrices with at least this many entries are filled on all cores.
const PARALLEL_ENTRIES: usize = 1 << 16;

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
pub(super) fn solve(inst: &Instance) -> Solution {
    solved(inst, 0).into_solution()
}

/// The solved residual state of `inst` (from its subsample's prices), to keep, with
/// `spare` closed columns to open later.
pub(super) fn solved(inst: &Instance, spare: usize) -> Flow {
    let mut warm = coarse_prices(inst, FACTOR);
    if let Some(prices) = &mut warm {
        prices.resize(prices.len() + spare, 0.0);
    }
    Flow::solved(Level::new(inst, 1, spare), warm.as_deref())
}

/// Solves `inst` exactly from `prices` (one per column: the tasks', then the void's
/// where the instance allows it; any common offset), without subsample levels.
pub(super) fn solve_from(inst: &Instance, prices: &[f64]) -> Solution {
    Flow::solved(Level::new(inst, 1, 0), Some(prices)).into_solution()
}

/// The prices of the subsample of every `stride`-th robot, solved from the prices of
/// its own subsample; `None` below [`BASE_ROBOTS`].
fn coarse_prices(inst: &Instance, stride: usize) -> Option<Vec<f64>> {
    if inst.num_robots().div_ceil(stride) < BASE_ROBOTS {
        return None;
    }
    let warm = coarse_prices(inst, stride * FACTOR);
    Some(
        Flow::solved(Level::new(inst, stride, 0), warm.as_deref())
            .into_solution()
            .prices,
    )
}

/// What a column of the problem is.
#[derive(Clone, Copy)]
pub(super) enum Column {
    /// A task: its value function and its capacity (in robots of the instance).
    Task {
        value: ValueFunction,
        capacity: usize,
    },
    /// The void task: cost 0, every member worth 0, room for all.
    Void,
    /// No task (one that was removed): no room.
    Closed,
}

/// The problem on every `stride`-th robot, each standing for `stride` robots: task j's
/// k-th member is worth `(F_j(k s) − F_j((k − 1) s)) / s` and its capacity is
/// `⌈cap_j / s⌉` (at most the robots there are). Its columns are the tasks, then the
/// void where the instance allows it.
#[derive(Clone)]
struct Level {
    stride: usize,
    /// The robots placed (the rows whose robot is still there): units the sink takes.
    n: usize,
    columns: Vec<Column>,
    /// Row-major travel costs `β d(i, j)`, one row of `columns.len()` per robot; 0 in
    /// the void's column.
    costs: Vec<f64>,
}

impl Level {
    /// The level of every `stride`-th robot, with `spare` closed columns last.
    fn new(inst: &Instance, stride: usize, spare: usize) -> Self {
        let mut columns: Vec<Column> = inst
            .task_ids()
            .map(|j| Column::Task {
                value: inst.value_function(j),
                capacity: inst.capacity(j),
            })
            .collect();
        if inst.allows_void() {
            columns.push(Column::Void);
        }
        columns.resize(columns.len() + spare, Column::Closed);
        Level {
            stride,
            n: inst.num_robots().div_ceil(stride),
            costs: cost_matrix(inst, stride, columns.len()),
            columns,
        }
    }

    /// The number of columns.
    fn m(&self) -> usize {
        self.columns.len()
    }

    /// The travel costs of the robot in `row`.
    pub fn row(&self, row: usize) -> &[f64] {
        let m = self.m();
        &self.costs[row * m..][..m]
    }

    /// The robots column j may hold at this level.
    fn capacity(&self, j: usize) -> usize {
        match self.columns[j] {
            Column::Task { capacity, .. } => capacity.div_ceil(self.stride).min(self.n),
            Column::Void => self.n,
            Column::Closed => 0,
        }
    }

    /// The value of column j's k-th member (k ≥ 1) at this level.
    fn marginal(&self, j: usize, k: usize) -> f64 {
        let Column::Task { value, .. } = self.columns[j] else {
            return 0.0;
        };
        if self.stride == 1 {
            return value.marginal(k);
        }
        let s = self.stride;
        (value.value(k * s) - value.value((k - 1) * s)) / s as f64
    }

    /// The number of column j's slots worth more than `price`: the count that price buys.
    fn count_at(&self, j: usize, price: f64) -> usize {
        let (mut lo, mut hi) = (0, self.capacity(j));
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if self.marginal(j, mid) > price {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo
    }

    /// A sink potential μ at which `prices` buy N slots in all (or, where ties make that
    /// impossible, the least above), by bisection from a bracket grown around `near`
    /// (or from where no price buys a slot): the flow starts with the sink balanced.
    fn balancing_offset(&self, prices: &[f64], near: Option<f64>) -> f64 {
        let bought = |mu: f64| {
            (0..self.m())
                .map(|j| self.count_at(j, prices[j] - mu))
                .sum::<usize>()
        };
        // At `none` every price is at least its task's first marginal value: none buys.
        let none = (0..self.m())
            .map(|j| prices[j] - self.marginal(j, 1))
            .fold(f64::INFINITY, f64::min);
        let start = near.map_or(none, |mu| mu.max(none));
        let mut step = near.map_or(1.0, |mu| 1e-9 * mu.abs().max(1.0));
        let (mut lo, mut hi) = (start, start);
        // Grow the bracket (lo, hi] until bought(lo) < N ≤ bought(hi).
        while bought(hi) < self.n {
            lo = hi;
            hi = start + step;
            step *= 2.0;
        }
        if lo == hi {
            step = 1e-9 * hi.abs().max(1.0);
            lo = hi - step;
            while lo > none && bought(lo) >= self.n {
                hi = lo;
                step *= 2.0;
                lo = (start - step).max(none);
            }
        }
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            match bought(mid).cmp(&self.n) {
                Ordering::Equal => return mid,
                Ordering::Greater => hi = mid,
                Ordering::Less => lo = mid,
            }
        }
        hi
    }
}

/// The row-major cost matrix of every `stride`-th robot, `width` columns (the void's,
/// if any, stays 0), on all cores when large.
fn cost_matrix(inst: &Instance, stride: usize, width: usize) -> Vec<f64> {
    let (n, beta) = (inst.num_robots().div_ceil(stride), inst.beta());
    let tasks: Vec<Point> = inst.tasks().iter().map(|t| t.position).collect();
    let robots = inst.robots();
    let mut costs = vec![0.0; n * width];
    // The same arithmetic as `Instance::cost`, with the task positions contiguous.
    let fill = |(t, row): (usize, &mut [f64])| {
        let robot = robots[t * stride];
        for (c, &task) in row.iter_mut().zip(&tasks) {
            *c = beta * robot.distance(task);
        }
    };
    if n * width >= PARALLEL_ENTRIES {
        costs.par_chunks_mut(width).enumerate().for_each(fill);
    } else {
        costs.chunks_mut(width).enumerate().for_each(fill);
    }
    costs
}

/// The cheapest open column of `row` under `prices` (the lowest such index).
fn cheapest(row: &[f64], prices: &[f64], columns: &[Column]) -> u32 {
    let mut best = None;
    for j in 0..row.len() {
        if matches!(columns[j], Column::Closed) {
            continue;
        }
        if best.is_none_or(|b: usize| row[j] - prices[j] < row[b] - prices[b]) {
            best = Some(j);
        }
    }
    best.expect("a problem has an open column") as u32
}

/// The index of the sink node among the potentials and imbalances.
fn sink(m: usize) -> usize {
    m
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
    /// the sink's potential set so that the counts they buy add up to N.
    fn solved(level: Level, warm: Option<&[f64]>) -> Flow {
        let prices = warm.map_or_else(|| vec![0.0; level.m()], <[f64]>::to_vec);
        let sink = level.balancing_offset(&prices, None);
        let mut flow = Flow::new(level, prices, sink);
        flow.route();
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
        self.routed = 0;
        loop {
            let surplus = self.excess.iter().filter(|&&e| e > 0).count();
            let short = self.excess.iter().filter(|&&e| e < 0).count();
            if surplus == 0 {
                break;
            }
            let backward = surplus > short;
            let end = self.search(backward);
            self.augment(end, backward);
            self.routed += 1;
        }
        self.routed
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

    /// Dijkstra with reduced costs between a node with excess and the nearest node on
    /// the other side of the imbalance: forward, from the node with most excess along
    /// the edges to the nearest node short of units; or `backward`, from the node most
    /// short of units against the edges (the labels are then distances to it) to the
    /// nearest node with excess. Updates the potentials (keeping every reduced cost
    /// non-negative and the path's zero) and returns the node where the search ended;
    /// `via` leads from it back to the start (forward) or on to the start (backward).
    fn search(&mut self, backward: bool) -> usize {
        let m = self.level.m();
        let t = sink(m);
        // One start, the node with the largest imbalance (searching from all of them
        // would settle every one at distance 0 first).
        let start = if backward {
            (0..=m).min_by_key(|&u| (self.excess[u], u))
        } else {
            (0..=m).max_by_key(|&u| (self.excess[u], Reverse(u)))
        };
        self.start_search(start.expect("a problem has nodes"));
        let end = loop {
            let u = self.settle_nearest();
            let found = if backward {
                self.excess[u] > 0
            } else {
                self.excess[u] < 0
            };
            if found {
                break u;
            }
            match (backward, u == t) {
                (false, true) => self.relax_from_sink(),
                (false, false) => self.relax_from_task(u),
                (true, true) => self.relax_into_sink(),
                (true, false) => self.relax_into_task(u),
            }
        };
        let (reach, sign) = (self.dist[end], if backward { -1.0 } else { 1.0 });
        for (p, &d) in self.potential.iter_mut().zip(&self.dist) {
            *p += sign * d.min(reach);
        }
        end
    }

    /// Every label infinite and unsettled but `start`'s, at 0.
    fn start_search(&mut self, start: usize) {
        self.dist.fill(f64::INFINITY);
        self.done.fill(false);
        self.dist[start] = 0.0;
        self.via[start] = SOURCE;
    }

    /// Settles and returns the nearest unsettled node, the lowest index among equals.
    /// The graph is dense (an edge between every two tasks), so a scan of the M + 1
    /// labels finds it rather than a heap.
    fn settle_nearest(&mut self) -> usize {
        let mut u = None;
        let mut nearest = f64::INFINITY;
        for (v, (&d, &done)) in self.dist.iter().zip(&self.done).enumerate() {
            if !done && d < nearest {
                (u, nearest) = (Some(v), d);
            }
        }
        let u = u.expect("the other side of the imbalance is reachable");
        self.done[u] = true;
        u
    }

    fn relax(&mut self, to: usize, from: usize, reduced: f64) {
        // Rounding can leave a tight edge a hair below zero.
        let d = self.dist[from] + reduced.max(0.0);
        if d < self.dist[to] {
            self.dist[to] = d;
            self.via[to] = from as u32;
        }
    }

    fn relax_from_task(&mut self, j: usize) {
        let m = self.level.m();
        let (here, from) = (self.dist[j], self.potential[j]);
        // A missing edge has an infinite key and never improves a distance; a settled
        // node is nearer than `here` and is not improved either.
        let keys = self.movers.keys(j);
        let (dist, via) = (&mut self.dist[..m], &mut self.via[..m]);
        for (k, (&key, &price)) in keys.iter().zip(&self.potential[..m]).enumerate() {
            let d = here + (key + from - price).max(0.0);
            if d < dist[k] {
                dist[k] = d;
                via[k] = j as u32;
            }
        }
        let t = sink(m);
        if !self.done[t] && self.bought[j] < self.level.capacity(j) {
            let cost = -self.level.marginal(j, self.bought[j] + 1);
            self.relax(t, j, cost + self.potential[j] - self.potential[t]);
        }
    }

    fn relax_from_sink(&mut self) {
        let m = self.level.m();
        for j in 0..m {
            if !self.done[j] && self.bought[j] > 0 {
                let cost = self.level.marginal(j, self.bought[j]);
                self.relax(
                    j,
                    sink(m),
                    cost + self.potential[sink(m)] - self.potential[j],
                );
            }
        }
    }

    /// The edges into task `v`: shifts from every task, and its count going down (from
    /// the sink).
    fn relax_into_task(&mut self, v: usize) {
        let m = self.level.m();
        let (here, to) = (self.dist[v], self.potential[v]);
        for u in 0..m {
            let d = here + (self.movers.keys(u)[v] + self.potential[u] - to).max(0.0);
            if d < self.dist[u] {
                self.dist[u] = d;
                self.via[u] = v as u32;
            }
        }
        let t = sink(m);
        if !self.done[t] && self.bought[v] > 0 {
            let cost = self.level.marginal(v, self.bought[v]);
            self.relax(t, v, cost + self.potential[t] - to);
        }
    }

    /// The edges into the sink: every task's count going up.
    fn relax_into_sink(&mut self) {
        let m = self.level.m();
        for u in 0..m {
            if !self.done[u] && self.bought[u] < self.level.capacity(u) {
                let cost = -self.level.marginal(u, self.bought[u] + 1);
                self.relax(
                    u,
                    sink(m),
                    cost + self.potential[u] - self.potential[sink(m)],
                );
            }
        }
    }

    /// One unit along the edge from node `from` to node `to`.
    fn step(&mut self, from: usize, to: usize) {
        let t = sink(self.level.m());
        if to == t {
            self.bought[from] += 1;
        } else if from == t {
            self.bought[to] -= 1;
        } else {
            let robot = self.movers.robot(from, to);
            self.place(robot as usize, from, to);
        }
    }

    /// Sends one unit along the last search's path, which `via` walks from `end` to the
    /// start: against the unit's way after a forward search (`end` is where it goes),
    /// along it after a backward one (`end` is where it comes from). The path's pairs of
    /// tasks are distinct, so each shift moves the mover the search saw, or one at the
    /// same key.
    fn augment(&mut self, end: usize, backward: bool) {
        let mut at = end;
        while self.via[at] != SOURCE {
            let next = self.via[at] as usize;
            if backward {
                self.step(at, next);
            } else {
                self.step(next, at);
            }
            at = next;
        }
        let (source, target) = if backward { (end, at) } else { (at, end) };
        self.excess[source] -= 1;
        self.excess[target] += 1;
    }
}
