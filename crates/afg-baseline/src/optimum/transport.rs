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
//! with the prices as potentials.
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
//! log₈(N) levels (a geometric sum: O(N M) in all), plus O(M² log M) for one
//! Dijkstra over the M + 1 nodes per routed unit, of which warm prices leave a few per
//! task and level. Memory O(N M) for the costs; nothing of size N × N.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use afg_game::{Instance, Point, TaskId};
use rayon::prelude::*;

use super::movers::Movers;

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
    let warm = coarse_prices(inst, FACTOR);
    Level::new(inst, 1).solve(warm.as_deref())
}

/// Solves `inst` exactly from `prices` (one per column: the tasks', then the void's
/// where the instance allows it; any common offset), without subsample levels.
pub(super) fn solve_from(inst: &Instance, prices: &[f64]) -> Solution {
    Level::new(inst, 1).solve(Some(prices))
}

/// The prices of the subsample of every `stride`-th robot, solved from the prices of
/// its own subsample; `None` below [`BASE_ROBOTS`].
fn coarse_prices(inst: &Instance, stride: usize) -> Option<Vec<f64>> {
    if inst.num_robots().div_ceil(stride) < BASE_ROBOTS {
        return None;
    }
    let warm = coarse_prices(inst, stride * FACTOR);
    Some(Level::new(inst, stride).solve(warm.as_deref()).prices)
}

/// The problem on every `stride`-th robot, each standing for `stride` robots: task j's
/// k-th member is worth `(F_j(k s) − F_j((k − 1) s)) / s` and its capacity is
/// `⌈cap_j / s⌉` (at most the robots there are). Its columns are the tasks, then the
/// void where the instance allows it (cost 0, every member worth 0, room for all).
struct Level<'a> {
    inst: &'a Instance,
    stride: usize,
    n: usize,
    /// Columns: M tasks, plus one for the void.
    m: usize,
    /// Row-major `n × m` travel costs `β d(i, j)`; 0 in the void's column.
    costs: Vec<f64>,
    capacity: Vec<usize>,
}

impl<'a> Level<'a> {
    fn new(inst: &'a Instance, stride: usize) -> Self {
        let n = inst.num_robots().div_ceil(stride);
        let mut capacity: Vec<usize> = inst
            .task_ids()
            .map(|j| inst.capacity(j).div_ceil(stride).min(n))
            .collect();
        if inst.allows_void() {
            capacity.push(n);
        }
        let m = capacity.len();
        Level {
            inst,
            stride,
            n,
            m,
            costs: cost_matrix(inst, stride),
            capacity,
        }
    }

    /// The value of task j's k-th member (k ≥ 1) at this level.
    fn marginal(&self, j: usize, k: usize) -> f64 {
        if j == self.inst.num_tasks() {
            return 0.0; // the void
        }
        let task = TaskId(j as u32);
        if self.stride == 1 {
            return self.inst.marginal_value(task, k);
        }
        let s = self.stride;
        let value = |k: usize| self.inst.coalition_value(task, k * s);
        (value(k) - value(k - 1)) / s as f64
    }

    /// The number of task j's slots worth more than `price`: the count that price buys.
    fn count_at(&self, j: usize, price: f64) -> usize {
        let (mut lo, mut hi) = (0, self.capacity[j]);
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

    /// Solves this level from `warm` prices (sink potential 0), or from zero prices
    /// with the sink's potential set so that the counts they buy add up to N.
    fn solve(&self, warm: Option<&[f64]>) -> Solution {
        let prices = warm.map_or_else(|| vec![0.0; self.m], <[f64]>::to_vec);
        let sink = self.balancing_offset(&prices);
        let mut flow = Flow::new(self, prices, sink);
        let mut routed = 0;
        while let Some(target) = flow.shortest_path() {
            flow.augment(target);
            routed += 1;
        }
        let sink = flow.potential[self.m];
        Solution {
            prices: flow.potential[..self.m].iter().map(|p| p - sink).collect(),
            task_of: flow.task_of,
            routed,
        }
    }

    /// A sink potential μ at which `prices` buy N slots in all (or, where ties make that
    /// impossible, the least above), by bisection: the flow starts with the sink balanced.
    fn balancing_offset(&self, prices: &[f64]) -> f64 {
        let bought = |mu: f64| {
            (0..self.m)
                .map(|j| self.count_at(j, prices[j] - mu))
                .sum::<usize>()
        };
        // At `lo` every price is at least its task's first marginal value: none buys.
        let mut lo = (0..self.m)
            .map(|j| prices[j] - self.marginal(j, 1))
            .fold(f64::INFINITY, f64::min);
        let (mut hi, mut step) = (lo + 1.0, 1.0);
        while bought(hi) < self.n {
            step *= 2.0;
            hi = lo + step;
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

/// The row-major cost matrix of every `stride`-th robot (with the void's column of
/// zeros where the instance allows it), on all cores when large.
fn cost_matrix(inst: &Instance, stride: usize) -> Vec<f64> {
    let (n, beta) = (inst.num_robots().div_ceil(stride), inst.beta());
    let m = inst.num_tasks() + usize::from(inst.allows_void());
    let tasks: Vec<Point> = inst.tasks().iter().map(|t| t.position).collect();
    let robots = inst.robots();
    let mut costs = vec![0.0; n * m];
    // The same arithmetic as `Instance::cost`, with the task positions contiguous.
    let fill = |(t, row): (usize, &mut [f64])| {
        let robot = robots[t * stride];
        // The void's column, if any, stays 0.
        for (c, &task) in row.iter_mut().zip(&tasks) {
            *c = beta * robot.distance(task);
        }
    };
    if n * m >= PARALLEL_ENTRIES {
        costs.par_chunks_mut(m).enumerate().for_each(fill);
    } else {
        costs.chunks_mut(m).enumerate().for_each(fill);
    }
    costs
}

/// The index of the sink node among the potentials and imbalances.
fn sink(m: usize) -> usize {
    m
}

/// The residual state: where every robot is, the count each task sends to the sink,
/// what each node still has to send (positive) or receive (negative), and the
/// potentials (task prices, then the sink's).
struct Flow<'l, 'a> {
    level: &'l Level<'a>,
    task_of: Vec<u32>,
    /// Units each task sends to the sink: its count, once balanced.
    bought: Vec<usize>,
    excess: Vec<i64>,
    potential: Vec<f64>,
    movers: Movers,
    dist: Vec<f64>,
    pred: Vec<Pred>,
    done: Vec<bool>,
    queue: BinaryHeap<Reverse<Queued>>,
}

/// A node waiting in Dijkstra's queue at a tentative distance.
#[derive(Clone, Copy, PartialEq)]
struct Queued(f64, usize);

impl Eq for Queued {}
impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Queued {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0).then(self.1.cmp(&other.1))
    }
}

/// How a node was reached on the current shortest-path tree.
#[derive(Clone, Copy)]
enum Pred {
    /// A node with excess: where the path starts.
    Source,
    /// From task `from`, by moving `robot` from it to this task.
    Shift { from: usize, robot: u32 },
    /// The sink, from task `from`, whose count goes up by one.
    Up { from: usize },
    /// A task, from the sink: its count goes down by one.
    Down,
}

impl<'l, 'a> Flow<'l, 'a> {
    /// Every robot at a minimum of `c_ij − π_j` (the lowest such task), every task's
    /// count what `π_j − μ` buys.
    fn new(level: &'l Level<'a>, prices: Vec<f64>, sink_potential: f64) -> Self {
        let m = level.m;
        let argmin = |row: &[f64]| {
            let mut best = 0;
            for j in 1..m {
                if row[j] - prices[j] < row[best] - prices[best] {
                    best = j;
                }
            }
            best as u32
        };
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
            level,
            movers: Movers::new(m, &task_of, &level.costs),
            task_of,
            bought,
            excess,
            potential,
            dist: vec![0.0; m + 1],
            pred: vec![Pred::Source; m + 1],
            done: vec![false; m + 1],
            queue: BinaryHeap::new(),
        }
    }

    /// Dijkstra with reduced costs from the node with most excess to the nearest node
    /// short of units; updates the potentials (keeping every reduced cost
    /// non-negative and the path's zero) and returns that node. `None` when balanced.
    fn shortest_path(&mut self) -> Option<usize> {
        let m = self.level.m;
        let t = sink(m);
        // One source, the node with most excess (searching from all of them would settle
        // every one at distance 0 first).
        let source = (0..=m).max_by_key(|&u| (self.excess[u], Reverse(u)))?;
        if self.excess[source] <= 0 {
            return None;
        }
        self.dist.fill(f64::INFINITY);
        self.done.fill(false);
        self.dist[source] = 0.0;
        self.pred[source] = Pred::Source;
        self.queue.clear();
        self.queue.push(Reverse(Queued(0.0, source)));
        let target = loop {
            let Reverse(Queued(d, u)) = self
                .queue
                .pop()
                .expect("a node short of units is reachable");
            if self.done[u] || d > self.dist[u] {
                continue;
            }
            self.done[u] = true;
            if self.excess[u] < 0 {
                break u;
            }
            if u == t {
                self.relax_from_sink();
            } else {
                self.relax_from_task(u);
            }
        };
        let reach = self.dist[target];
        for (p, &d) in self.potential.iter_mut().zip(&self.dist) {
            *p += d.min(reach);
        }
        Some(target)
    }

    fn relax(&mut self, to: usize, through: f64, reduced: f64, pred: Pred) {
        // Rounding can leave a tight edge a hair below zero.
        let d = through + reduced.max(0.0);
        if d < self.dist[to] {
            self.dist[to] = d;
            self.pred[to] = pred;
            self.queue.push(Reverse(Queued(d, to)));
        }
    }

    fn relax_from_task(&mut self, j: usize) {
        let (m, level) = (self.level.m, self.level);
        let (here, from) = (self.dist[j], self.potential[j]);
        // A missing edge has an infinite key and never improves a distance.
        for (k, e) in self.movers.row(j).iter().enumerate() {
            if self.done[k] {
                continue;
            }
            let d = here + (e.key + from - self.potential[k]).max(0.0);
            if d < self.dist[k] {
                self.dist[k] = d;
                self.pred[k] = Pred::Shift {
                    from: j,
                    robot: e.robot,
                };
                self.queue.push(Reverse(Queued(d, k)));
            }
        }
        let t = sink(m);
        if !self.done[t] && self.bought[j] < level.capacity[j] {
            let cost = -level.marginal(j, self.bought[j] + 1);
            let reduced = cost + self.potential[j] - self.potential[t];
            self.relax(t, here, reduced, Pred::Up { from: j });
        }
    }

    fn relax_from_sink(&mut self) {
        let (m, level) = (self.level.m, self.level);
        let here = self.dist[sink(m)];
        for j in 0..m {
            if !self.done[j] && self.bought[j] > 0 {
                let cost = level.marginal(j, self.bought[j]);
                let reduced = cost + self.potential[sink(m)] - self.potential[j];
                self.relax(j, here, reduced, Pred::Down);
            }
        }
    }

    /// Sends one unit along the last shortest path into `target`.
    fn augment(&mut self, target: usize) {
        let m = self.level.m;
        let mut at = target;
        loop {
            match self.pred[at] {
                Pred::Source => break,
                Pred::Shift { from, robot } => {
                    self.task_of[robot as usize] = at as u32;
                    let costs = &self.level.costs;
                    self.movers.leave(robot, from, &self.task_of, costs);
                    let row = &self.level.costs[robot as usize * m..][..m];
                    self.movers.enter(robot, at, row);
                    at = from;
                }
                Pred::Up { from } => {
                    self.bought[from] += 1;
                    at = from;
                }
                Pred::Down => {
                    self.bought[at] -= 1;
                    at = sink(m);
                }
            }
        }
        self.excess[at] -= 1;
        self.excess[target] += 1;
    }
}
