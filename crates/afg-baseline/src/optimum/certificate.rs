//! A proof of optimality that does not trust the solver: weak LP duality.
//!
//! For any task prices π (and any offset μ), every complete assignment's welfare is at
//! most
//! `D = Σ_i max_j (π_j − μ − c_ij) + Σ_j max_{0 ≤ n ≤ min(cap_j, N)} (F_j(n) − n (π_j − μ))`,
//! because `W(a) = Σ_i (π_a(i) − μ − c_i,a(i)) + Σ_j (F_j(n_j) − n_j (π_j − μ))` term
//! by term. The gap `D − W(a)` is a sum of non-negative terms — how far each robot is
//! from its cheapest task at these prices, and how far each task's count is from the
//! count its price buys — so it is computed without cancellation, and it bounds how
//! much welfare any other assignment could add. It is zero exactly when every robot
//! is at a minimum of `c_ij − π_j` and every task's count is consistent with its
//! marginal values (complementary slackness).
//!
//! Where the instance allows the void task, it is one more place with cost 0 and price
//! 0 (so μ = 0: the prices have no free offset), every member worth 0, and room for all:
//! a robot's term is `max(max_j (π_j − c_ij), 0)`, the void adds no task term, and an
//! assignment that leaves robots out is complete.

use afg_game::{Assignment, Instance, TaskId};

use crate::AllocError;

/// Relative duality gap below which an assignment counts as proven optimal: rounding
/// in sums of N terms, not a modelling slack.
const TOLERANCE: f64 = 1e-9;

/// What [`verify_optimal`] proved: the assignment's welfare and an upper bound on the
/// welfare of every complete assignment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Certificate {
    /// The welfare of the assignment checked.
    pub welfare: f64,
    /// No complete assignment has more welfare (the LP dual at the prices).
    pub upper_bound: f64,
}

impl Certificate {
    /// `upper_bound − welfare`: at most this much welfare is missing. Non-negative.
    pub fn gap(&self) -> f64 {
        self.upper_bound - self.welfare
    }
}

/// Checks in O(N M) that `prices` prove `assignment` optimal for `instance`, and
/// returns the bound they give. Prices may carry any common offset (the best one is
/// used; none where the instance allows the void task, whose price is 0), so [`Optimum::with_prices`](super::Optimum::with_prices) or any other
/// solver's duals are accepted.
///
/// # Errors
/// [`AllocError::InvalidParameter`] if the assignment does not fit the instance, is
/// incomplete (in the paper's game) or above a capacity, or if `prices` are not M finite numbers;
/// [`AllocError::NotOptimal`] if the duality gap is above 1e-9 of the welfare's scale
/// (the task values plus the travel costs).
///
/// # Examples
/// ```
/// use afg_baseline::{Optimum, verify_optimal};
/// use afg_game::{GeneratorConfig, RobotId};
/// let inst = GeneratorConfig::paper(200, 5, 7).generate()?;
/// let (opt, prices) = Optimum.with_prices(&inst);
/// let proof = verify_optimal(&inst, &opt, &prices)?;
/// assert!(proof.gap() <= 1e-9 * proof.upper_bound.abs().max(1.0));
/// // Any other assignment is rejected, with its shortfall bounded by the gap.
/// let mut worse = opt.clone();
/// let (j, k) = (opt.task_of(RobotId(0)), opt.task_of(RobotId(1)));
/// if j != k {
///     worse.set(RobotId(0), k);
///     worse.set(RobotId(1), j);
///     assert!(verify_optimal(&inst, &worse, &prices).is_err());
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn verify_optimal(
    instance: &Instance,
    assignment: &Assignment,
    prices: &[f64],
) -> Result<Certificate, AllocError> {
    check_inputs(instance, assignment, prices)?;
    let n = instance.num_robots();
    // The void's reduced cost, 0, where it is a place; above every task's otherwise.
    let outside = if instance.allows_void() {
        0.0
    } else {
        f64::INFINITY
    };
    let mut robot_gap = 0.0;
    let mut costs = 0.0;
    for i in instance.robot_ids() {
        let reduced = |j: TaskId| instance.cost(i, j) - prices[j.index()];
        let cheapest = instance.task_ids().map(reduced).fold(outside, f64::min);
        let own = assignment.task_of(i);
        robot_gap += own.map_or(outside, reduced) - cheapest;
        costs += own.map_or(0.0, |j| instance.cost(i, j));
    }
    let offset = offset(instance, assignment, prices);
    let mut task_gap = 0.0;
    let mut values = 0.0;
    for j in instance.task_ids() {
        let (price, held) = (prices[j.index()] - offset, assignment.size(j));
        let room = instance.capacity(j).min(n);
        values += instance.coalition_value(j, held);
        // Slots the price buys that the task lacks, then members it keeps beyond them.
        let mut k = held;
        while k < room && instance.marginal_value(j, k + 1) > price {
            task_gap += instance.marginal_value(j, k + 1) - price;
            k += 1;
        }
        let mut k = held;
        while k > 0 && instance.marginal_value(j, k) < price {
            task_gap += price - instance.marginal_value(j, k);
            k -= 1;
        }
    }
    let welfare = values - costs;
    let certificate = Certificate {
        welfare,
        upper_bound: welfare + robot_gap + task_gap,
    };
    let tolerance = TOLERANCE * (values + costs).max(1.0);
    if certificate.gap() > tolerance {
        return Err(AllocError::NotOptimal {
            welfare,
            upper_bound: certificate.upper_bound,
        });
    }
    Ok(certificate)
}

fn check_inputs(
    instance: &Instance,
    assignment: &Assignment,
    prices: &[f64],
) -> Result<(), AllocError> {
    instance.check(assignment)?;
    if let Some(i) = instance
        .robot_ids()
        .find(|&i| !instance.allows_void() && assignment.task_of(i).is_none())
    {
        return Err(AllocError::InvalidParameter(format!(
            "robot {i} is unassigned: only complete assignments can be optimal"
        )));
    }
    super::check_prices(instance, prices)?;
    Ok(())
}

/// The offset μ that zeroes every task's term when the counts are consistent with the
/// prices: the largest `π_j − (F_j(n_j) − F_j(n_j − 1))` over tasks with members.
/// Any offset gives a valid bound; this one is tight at an optimum. Where the instance
/// allows the void, its price 0 fixes the offset at 0.
fn offset(instance: &Instance, assignment: &Assignment, prices: &[f64]) -> f64 {
    if instance.allows_void() {
        return 0.0;
    }
    instance
        .task_ids()
        .filter(|&j| assignment.size(j) > 0)
        .map(|j| prices[j.index()] - instance.marginal_value(j, assignment.size(j)))
        .reduce(f64::max)
        .unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use afg_game::{Point, Task};

    /// Two robots at 0 and 10 on a line, tasks at 0 and 10 with reward 5 and eps 2:
    /// each robot at its own task is optimal (welfare 10); prices (5, 5) prove it.
    #[test]
    fn hand_computed_gap() {
        let task = |x: f64| Task {
            position: Point::new(x, 0.0),
            reward: 5.0,
            eps: 2.0,
            capacity: None,
        };
        let robots = vec![Point::new(0.0, 0.0), Point::new(10.0, 0.0)];
        let inst = Instance::new(robots, vec![task(0.0), task(10.0)], 1.0).unwrap();
        let tasks = |a: u32, b: u32| vec![Some(TaskId(a)), Some(TaskId(b))];
        let own = Assignment::from_tasks(&inst, tasks(0, 1)).unwrap();
        let proof = verify_optimal(&inst, &own, &[5.0, 5.0]).unwrap();
        assert_eq!(proof.welfare, 10.0);
        assert_eq!(proof.gap(), 0.0);
        // Both at task 0: F(2) = 5 log2(3), robot 1 travels 10. At prices (5, 5) the
        // offset is 5 − 5 (log2(3) − 1) and robot 1 is 10 above its cheapest task, task 1
        // buys one slot worth 5 − offset more than nothing: the bound is 10 again.
        let both = Assignment::from_tasks(&inst, tasks(0, 0)).unwrap();
        let err = verify_optimal(&inst, &both, &[5.0, 5.0]).unwrap_err();
        let AllocError::NotOptimal {
            welfare,
            upper_bound,
        } = err
        else {
            panic!("{err}")
        };
        assert!((welfare - (5.0 * 3f64.log2() - 10.0)).abs() < 1e-12);
        assert!((upper_bound - 10.0).abs() < 1e-12, "{upper_bound}");
    }
}
