//! A solve stopped before its optimum: what [`Stop`] asks, and the answer and bound
//! a stopped root still gives from the prices it reached.

use super::*;

/// Asked between the routed units of a solve: whether to stop it there.
pub(in crate::optimum) type Stop<'a> = &'a dyn Fn() -> bool;

/// A [`Stop`] that never stops.
pub(in crate::optimum) const NEVER: Stop<'static> = &|| false;

/// A solve that [`Stop`] ended before its optimum: where every robot stood then (a
/// column each, capacities not yet met), and the Lagrangian bound of the prices it
/// had reached.
pub(in crate::optimum) struct Interrupted {
    pub task_of: Vec<u32>,
    pub bound: f64,
}

/// Where a root's solve was stopped at `prices` (one per column; its costs the
/// instance's own, no `adjust` nor skill prices): each robot at its cheapest column,
/// and a proven upper bound on the welfare of every assignment of `columns` from those
/// prices, whatever they are — relaxing the coupling of robots and counts,
/// `Σ_i max_j (π_j − c_ij) + Σ_j max_n (F_j(n) − n π_j)`, each robot placed and each
/// column's count chosen apart (Lagrangian duality; equal to the optimum's welfare at
/// its prices). One pass over the costs, on all cores, no cost matrix kept.
pub(super) fn interrupted(inst: &Instance, columns: &[Column], prices: &[f64]) -> Interrupted {
    let level = Level::without_costs(inst, columns);
    let (tasks, beta) = (task_positions(inst), inst.beta());
    let place = |row: &mut Vec<f64>, &robot: &Point| {
        row.resize(columns.len(), 0.0);
        cost_row(robot, &tasks, beta, row);
        let j = cheapest(row, prices, columns);
        (j, prices[j as usize] - row[j as usize])
    };
    let (task_of, gains): (Vec<u32>, Vec<f64>) =
        if inst.num_robots() * columns.len() >= PARALLEL_ENTRIES {
            inst.robots().par_iter().map_init(Vec::new, place).unzip()
        } else {
            let mut row = Vec::new();
            inst.robots().iter().map(|r| place(&mut row, r)).unzip()
        };
    Interrupted {
        bound: gains.iter().sum::<f64>() + counts_at(&level, prices),
        task_of,
    }
}

/// `Σ_j max_n (value_j(n) − n π_j)`: what every open column's best count is worth at
/// its price, the columns' half of a dual bound.
fn counts_at(level: &Level, prices: &[f64]) -> f64 {
    (0..level.m())
        .filter(|&j| !matches!(level.columns[j], Column::Closed))
        .map(|j| {
            (1..=level.count_at(j, prices[j]))
                .map(|k| level.marginal(j, k) - prices[j])
                .sum::<f64>()
        })
        .sum()
}

/// The dual bound of `prices` (one per column) on the problem [`solve_columns`](super::solve_columns) solves
/// with these `columns` and `costs` — `Σ_i max_j (π_j − c_ij) + Σ_j
/// max_n (value_j(n) − n π_j)`, every robot and every column's count chosen apart, an
/// upper bound on every assignment's welfare there whatever the prices — and every
/// robot's reduced cost at every column (row-major, a row of `columns.len()` per
/// robot): how far below its best column's gain that one's is. An assignment that
/// puts robot i in column j is worth at most the bound less that reduced cost.
pub(in crate::optimum) fn reduced_costs(
    inst: &Instance,
    columns: &[Column],
    prices: &[f64],
    costs: Costs,
) -> (f64, Vec<f64>) {
    let level = Level::priced(inst, columns, costs);
    let open = |j: &usize| !matches!(columns[*j], Column::Closed);
    let mut reduced = vec![f64::INFINITY; level.costs.len()];
    let mut bound = 0.0;
    for (row, costs) in reduced
        .chunks_exact_mut(level.m())
        .zip(level.costs.chunks_exact(level.m()))
    {
        let gain = |j: usize| prices[j] - costs[j];
        let best = (0..level.m())
            .filter(open)
            .map(gain)
            .fold(f64::NEG_INFINITY, f64::max);
        bound += best;
        for j in (0..level.m()).filter(open) {
            row[j] = best - gain(j);
        }
    }
    (bound + counts_at(&level, prices), reduced)
}

#[cfg(test)]
mod tests {
    use afg_game::Family;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// The welfare of `task_of` (a column each) under `columns`' values.
    fn welfare(inst: &Instance, columns: &[Column], task_of: &[u32]) -> f64 {
        let mut sizes = vec![0; columns.len()];
        let mut travel = 0.0;
        for (i, &j) in inst.robot_ids().zip(task_of) {
            sizes[j as usize] += 1;
            if (j as usize) < inst.num_tasks() {
                travel += inst.cost(i, TaskId(j));
            }
        }
        let values = (columns.iter().zip(&sizes)).map(|(c, &n)| match c {
            Column::Task { value, .. } => value.value(n),
            _ => 0.0,
        });
        values.sum::<f64>() - travel
    }

    #[test]
    fn the_bound_of_the_optimal_prices_is_the_optimum_and_any_prices_bound_it() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for (case, family) in Family::ALL.iter().cycle().take(30).enumerate() {
            let inst = family
                .config(50, 7, case as u64)
                .unwrap()
                .generate()
                .unwrap();
            let columns = task_columns(&inst);
            let Ok(best) = solve_columns(&inst, &columns, None, Costs::default(), NEVER) else {
                unreachable!("never stopped")
            };
            let optimum = welfare(&inst, &columns, &best.task_of);
            let tol = 1e-9 * optimum.abs().max(1.0);
            // Strong duality at the optimal prices, where every robot is at its
            // cheapest column.
            let at_optimum = interrupted(&inst, &columns, &best.prices);
            assert!(
                (at_optimum.bound - optimum).abs() < tol,
                "{family}: {} vs {optimum}",
                at_optimum.bound
            );
            // Weak duality at any prices, strictly above where they are far off.
            let mut above = 0;
            for _ in 0..20 {
                let off: Vec<f64> = (best.prices.iter())
                    .map(|p| p + rng.random_range(-1.0..1.0) * p.abs().max(1.0))
                    .collect();
                let bound = interrupted(&inst, &columns, &off).bound;
                assert!(bound >= optimum - tol, "{family}: {bound} < {optimum}");
                above += usize::from(bound > optimum + tol);
            }
            assert!(above >= 15, "{family}: {above} of 20");
        }
    }
}
