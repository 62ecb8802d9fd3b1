//! The coarse-to-fine levels: every `FACTOR`-th robot of the level above, each level's
//! cost matrix, and the prices a coarser level hands down.

use std::collections::BinaryHeap;

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

    /// The finest level of `inst` with `columns` at `costs`.
    pub(super) fn priced(inst: &Instance, columns: &[Column], costs: Costs) -> Self {
        let mut level = match costs.travel {
            Some(travel) => Level {
                stride: 1,
                n: inst.num_robots(),
                columns: columns.to_vec(),
                costs: travel.to_vec(),
            },
            None => Level::new(inst, columns, 1, 0),
        };
        let m = level.m();
        for &(robot, column, delta) in costs.adjust {
            level.costs[robot * m + column] += delta;
        }
        let skill_prices = costs.skill_prices;
        if !skill_prices.is_empty() {
            // `skill_rebates`, summed over the skills the robot holds only (the others
            // add exact zeros): most robots hold few of them, many none.
            let s = inst.num_skills();
            let mut held = Vec::with_capacity(s);
            for i in inst.robot_ids() {
                held.clear();
                held.extend((inst.skills(i).iter().enumerate()).filter(|&(_, &q)| q > 0));
                if held.is_empty() {
                    continue;
                }
                let row = &mut level.costs[i.index() * m..][..inst.num_tasks()];
                for (cost, prices) in row.iter_mut().zip(skill_prices.chunks_exact(s)) {
                    *cost -= held
                        .iter()
                        .map(|&(t, &q)| prices[t] * f64::from(q))
                        .sum::<f64>();
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
    /// impossible, the least above): `near` where it does, else between the N-th
    /// cheapest slot and the next. Slot k of column j is bought once μ passes
    /// `π_j − marginal(j, k)`, which rises with k (the columns are concave), so the N
    /// cheapest slots come from merging the columns' rising lists: O(N log M) marginal
    /// values, not a bisection over every column's count.
    pub(super) fn balancing_offset(&self, prices: &[f64], near: Option<f64>) -> f64 {
        let opens_at = |j: usize, k: usize| Slot {
            mu: prices[j] - self.marginal(j, k),
            column: j,
            k,
        };
        let mut next: BinaryHeap<Reverse<Slot>> = (0..self.m())
            .filter(|&j| self.capacity(j) > 0)
            .map(|j| Reverse(opens_at(j, 1)))
            .collect();
        let mut last = f64::NEG_INFINITY;
        for _ in 0..self.n {
            let Some(Reverse(slot)) = next.pop() else {
                break; // fewer slots than robots: every one is bought
            };
            last = slot.mu;
            if slot.k < self.capacity(slot.column) {
                next.push(Reverse(opens_at(slot.column, slot.k + 1)));
            }
        }
        let after = next.peek().map_or(f64::INFINITY, |Reverse(slot)| slot.mu);
        match near {
            Some(mu) if last < mu && mu <= after => mu,
            _ if after.is_finite() && last < after => 0.5 * (last + after),
            _ => last + 1e-9 * last.abs().max(1.0),
        }
    }
}

/// A slot of a column and the sink potential from which its price buys it, ordered by
/// that potential (then column and rank, for a fixed order among ties).
#[derive(Clone, Copy, PartialEq)]
struct Slot {
    mu: f64,
    column: usize,
    k: usize,
}

impl Eq for Slot {}

impl PartialOrd for Slot {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Slot {
    fn cmp(&self, other: &Self) -> Ordering {
        (self.mu.total_cmp(&other.mu)).then((self.column, self.k).cmp(&(other.column, other.k)))
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
    let mut best: Option<(usize, f64)> = None;
    for (j, ((&cost, &price), column)) in row.iter().zip(prices).zip(columns).enumerate() {
        let reduced = cost - price;
        if best.is_none_or(|(_, least)| reduced < least) && !matches!(column, Column::Closed) {
            best = Some((j, reduced));
        }
    }
    best.expect("a problem has an open column").0 as u32
}

/// The index of the sink node among the potentials and imbalances.
pub(super) fn sink(m: usize) -> usize {
    m
}

#[cfg(test)]
mod tests {
    use afg_game::Family;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// Against every slot's potential, sorted: the sink potential buys exactly N slots
    /// where the N-th and the next differ (the least above where they tie), and keeps a
    /// `near` that does so — on every family, finest and coarser levels, a closed column.
    #[test]
    fn the_balancing_offset_buys_every_robot() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut exact = 0;
        for (case, family) in Family::ALL.iter().cycle().take(60).enumerate() {
            let inst = (family.config(30, 6, case as u64).unwrap())
                .generate()
                .unwrap();
            let level = Level::new(&inst, &task_columns(&inst), [1, 1, 4][case % 3], 1);
            let prices: Vec<f64> = (0..level.m())
                .map(|j| rng.random_range(-1.0..1.5) * level.marginal(j, 1).max(1.0))
                .collect();
            let mut opens: Vec<f64> = (0..level.m())
                .flat_map(|j| (1..=level.capacity(j)).map(move |k| (j, k)))
                .map(|(j, k)| prices[j] - level.marginal(j, k))
                .collect();
            opens.sort_by(f64::total_cmp);
            let bought = |mu: f64| {
                (0..level.m())
                    .map(|j| level.count_at(j, prices[j] - mu))
                    .sum::<usize>()
            };
            let (nth, after) = (opens[level.n - 1], opens.get(level.n).copied());
            let mu = level.balancing_offset(&prices, None);
            match after {
                Some(after) if after - nth > 1e-6 => {
                    exact += 1;
                    assert_eq!(bought(mu), level.n, "{family}");
                    let near = nth + rng.random_range(0.01..1.0) * (after - nth);
                    assert_eq!(level.balancing_offset(&prices, Some(near)), near);
                    let far = level.balancing_offset(&prices, Some(after + 1.0));
                    assert_eq!(bought(far), level.n, "{family}");
                }
                _ => {
                    assert!(bought(mu) >= level.n, "{family}");
                    assert!(
                        mu - nth < 1e-6 * nth.abs().max(1.0),
                        "{family}: {mu} vs {nth}"
                    );
                }
            }
        }
        assert!(exact >= 40, "{exact} of 60 without ties");
    }
}
