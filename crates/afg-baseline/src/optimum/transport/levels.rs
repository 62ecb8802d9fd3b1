//! The coarse-to-fine levels: every `FACTOR`-th robot of the level above, each level's
//! cost matrix, and the prices a coarser level hands down.

use super::*;

/// The prices of the subsample of every `stride`-th robot, solved from the prices of
/// its own subsample (or as far as they got where `stop` said so); `None` below
/// [`BASE_ROBOTS`].
pub(super) fn coarse_prices(
    inst: &Instance,
    columns: &[Column],
    stride: usize,
    stop: Stop,
) -> Option<Vec<f64>> {
    if inst.num_robots().div_ceil(stride) < BASE_ROBOTS {
        return None;
    }
    let warm = coarse_prices(inst, columns, stride * FACTOR, stop);
    Some(Flow::solved(Level::new(inst, columns, stride, 0), warm.as_deref(), stop).prices())
}

/// The problem on every `stride`-th robot, each standing for `stride` robots: task j's
/// k-th member is worth `(F_j(k s) − F_j((k − 1) s)) / s` and its capacity is
/// `⌈cap_j / s⌉` (at most the robots there are). Its columns are the tasks, then the
/// void where the instance allows it.
#[derive(Clone)]
pub(super) struct Level {
    pub(super) stride: usize,
    /// The robots placed (the rows whose robot is still there): units the sink takes.
    pub(super) n: usize,
    pub(super) columns: Vec<Column>,
    /// Row-major travel costs `β d(i, j)`, one row of `columns.len()` per robot; 0 in
    /// the void's column.
    pub(super) costs: Vec<f64>,
}

impl Level {
    /// The level of every `stride`-th robot of `inst` with `columns` (its tasks', then
    /// the void's), and `spare` closed columns last.
    pub(super) fn new(inst: &Instance, columns: &[Column], stride: usize, spare: usize) -> Self {
        let mut columns = columns.to_vec();
        columns.resize(columns.len() + spare, Column::Closed);
        Level {
            stride,
            n: inst.num_robots().div_ceil(stride),
            costs: cost_matrix(inst, stride, columns.len()),
            columns,
        }
    }

    /// The finest level of `inst` with `columns`, each `(robot, column, delta)` of
    /// `adjust` added to that robot's cost there and its skills' worth at
    /// `skill_prices` taken off (see [`solve_columns`]).
    pub(super) fn priced(
        inst: &Instance,
        columns: &[Column],
        adjust: &[(usize, usize, f64)],
        skill_prices: &[f64],
    ) -> Self {
        let mut level = Level::new(inst, columns, 1, 0);
        let m = level.m();
        for &(robot, column, delta) in adjust {
            level.costs[robot * m + column] += delta;
        }
        if !skill_prices.is_empty() {
            for i in inst.robot_ids() {
                let row = &mut level.costs[i.index() * m..][..inst.num_tasks()];
                for (cost, rebate) in row.iter_mut().zip(skill_rebates(inst, i, skill_prices)) {
                    *cost -= rebate;
                }
            }
        }
        level
    }

    /// The finest level of `inst` with `columns`, its costs left out: its counts and
    /// marginal values only.
    pub(super) fn without_costs(inst: &Instance, columns: &[Column]) -> Self {
        Level {
            stride: 1,
            n: inst.num_robots(),
            columns: columns.to_vec(),
            costs: Vec::new(),
        }
    }

    /// The number of columns.
    pub(super) fn m(&self) -> usize {
        self.columns.len()
    }

    /// The travel costs of the robot in `row`.
    pub fn row(&self, row: usize) -> &[f64] {
        let m = self.m();
        &self.costs[row * m..][..m]
    }

    /// The robots column j may hold at this level.
    pub(super) fn capacity(&self, j: usize) -> usize {
        match self.columns[j] {
            Column::Task { capacity, .. } => capacity.div_ceil(self.stride).min(self.n),
            Column::Void => self.n,
            Column::Closed => 0,
        }
    }

    /// The value of column j's k-th member (k ≥ 1) at this level.
    pub(super) fn marginal(&self, j: usize, k: usize) -> f64 {
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
    pub(super) fn count_at(&self, j: usize, price: f64) -> usize {
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
    pub(super) fn balancing_offset(&self, prices: &[f64], near: Option<f64>) -> f64 {
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
pub(super) fn cost_matrix(inst: &Instance, stride: usize, width: usize) -> Vec<f64> {
    let (n, beta) = (inst.num_robots().div_ceil(stride), inst.beta());
    let tasks = task_positions(inst);
    let robots = inst.robots();
    let mut costs = vec![0.0; n * width];
    let fill = |(t, row): (usize, &mut [f64])| cost_row(robots[t * stride], &tasks, beta, row);
    if n * width >= PARALLEL_ENTRIES {
        costs.par_chunks_mut(width).enumerate().for_each(fill);
    } else {
        costs.chunks_mut(width).enumerate().for_each(fill);
    }
    costs
}

/// The travel costs of a robot at `robot` to `tasks` into the first entries of `row`
/// (the same arithmetic as `Instance::cost`).
pub(super) fn cost_row(robot: Point, tasks: &[Point], beta: f64, row: &mut [f64]) {
    for (c, &task) in row.iter_mut().zip(tasks) {
        *c = beta * robot.distance(task);
    }
}

/// The cheapest open column of `row` under `prices` (the lowest such index).
pub(super) fn cheapest(row: &[f64], prices: &[f64], columns: &[Column]) -> u32 {
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
pub(super) fn sink(m: usize) -> usize {
    m
}
