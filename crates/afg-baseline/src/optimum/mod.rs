//! The exact welfare maximum (OPT) as a min-cost flow with M task nodes, with prices
//! that prove it.
//!
//! Maximising `sum_j F_j(n_j) - beta sum_i d(i, g_i)` over complete assignments is
//! a min-cost flow: robot i sends one unit to task j at cost `c_ij = beta d(i, j)`,
//! and task j sends its n-th unit to the sink at cost `-(F_j(n) - F_j(n - 1))`.
//! Concavity of F_j (eps ≥ φ) makes those slot costs increase with n, so a task's
//! slots are filled in order and one "next slot" per task is all the graph needs.
//! Between tasks, the residual edge j → k costs `min_{r in j} (c_rk - c_rj)`, read
//! from one lazy-deletion heap per ordered task pair.
//!
//! Two solvers share that graph:
//! - [`transport`]: the whole instance from prices — every robot at its cheapest task
//!   under warm prices (from a subsample of the robots, solved the same way), then the
//!   few units that are out of balance routed along shortest paths over the M + 1
//!   nodes. Behind [`Optimum::allocate`] and [`Optimum::with_prices`], and, with its
//!   state kept between events, [`IncrementalOptimum`].
//! - [`augmenting`]: robot by robot, each along a shortest augmenting path. It can keep
//!   some robots fixed: [`Optimum::complete`] and [`Optimum::action_values`] (the exact
//!   Q\* oracle of the sequential MDP: with γ = 1 and the welfare difference as reward,
//!   `Q*(s_t, a) = OPT(robots before t fixed, robot t on a) − W(s_t)`), and the
//!   reference the first is tested against.
//!
//! [`verify_optimal`] checks an assignment against prices in O(N M) without trusting
//! either solver: the duality gap it computes bounds how far the assignment is from
//! the optimum.
//!
//! # Complexity
//! [`Optimum::allocate`]: O(N M) to read the costs and place the robots, plus
//! O(M² + L M log N) per routed unit, of which warm prices leave few.
//! [`Optimum::complete`]: O(N M² log N). Both O(N M) memory; no N × N structure.

mod augmenting;
mod certificate;
mod incremental;
mod memory;
mod movers;
mod teams;
mod transport;

use afg_game::{Assignment, Instance, RobotId, TaskId};

pub use certificate::{Certificate, verify_optimal};
pub use incremental::IncrementalOptimum;
pub(crate) use memory::check_memory;
pub use memory::{BYTES_PER_PAIR, available_memory, exact_memory};
pub use teams::{TeamOptimum, TeamProgress, TeamRelaxation, TeamSolution};

use crate::{AllocError, AllocStats, Allocation, Allocator, timed};
use transport::assignment_of;

/// The exact optimum. Deterministic.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Optimum};
/// use afg_game::GeneratorConfig;
/// let inst = GeneratorConfig::paper(100, 5, 1).generate()?;
/// let opt = Optimum.allocate(&inst)?;
/// assert!(opt.assignment.is_complete());
/// assert!(inst.is_stable(&opt.assignment, afg_game::Preference::Balanced)); // paper Lemma 1
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, Default)]
pub struct Optimum;

impl Optimum {
    /// The best complete assignment that keeps every robot assigned in `partial` where
    /// it is (its optimal completion). With an empty `partial` this is the optimum.
    /// Where the instance allows the void task, the robots without a task in `partial`
    /// are the free ones, and some may stay out.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] if `partial` has another N or M than the
    /// instance, or puts more robots in a task than its capacity.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::{Allocator, Optimum};
    /// use afg_game::{Assignment, GeneratorConfig, RobotId, TaskId};
    /// let inst = GeneratorConfig::paper(30, 5, 1).generate()?;
    /// let mut partial = Assignment::unassigned(30, 5);
    /// partial.set(RobotId(0), Some(TaskId(3)));
    /// let done = Optimum.complete(&inst, &partial)?;
    /// assert_eq!(done.task_of(RobotId(0)), Some(TaskId(3)));
    /// // Fixing a robot can only cost welfare.
    /// let opt = Optimum.allocate(&inst)?.assignment;
    /// assert!(inst.welfare(&done) <= inst.welfare(&opt) + 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn complete(
        &self,
        instance: &Instance,
        partial: &Assignment,
    ) -> Result<Assignment, AllocError> {
        check_partial(instance, partial)?;
        Ok(augmenting::solved(instance, partial.clone(), None).assignment)
    }

    /// The optimum of the paper's concave game with its task prices π, which prove it
    /// ([`verify_optimal`]; a team game's thresholds and skills are not read: prices
    /// prove only a flow, and [`TeamOptimum`] solves those games): every
    /// robot's task minimises `β d(i, j) − π_j` over all tasks, and every task's price
    /// lies between the marginal values of its last member and of one more,
    /// `F_j(n_j + 1) − F_j(n_j) ≤ π_j ≤ F_j(n_j) − F_j(n_j − 1)` (LP duality for the
    /// min-cost flow). Robots whose minimum is unique sit exactly where argmin sends
    /// them; ties are settled by the counts.
    ///
    /// Where the instance allows the void task, it is one more place at cost 0 and
    /// price 0: robots whose every `β d(i, j) − π_j` is above 0 stay out. The prices
    /// then have no free offset.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Optimum;
    /// use afg_game::{GeneratorConfig, RobotId};
    /// let inst = GeneratorConfig::paper(60, 5, 1).generate()?;
    /// let (opt, prices) = Optimum.with_prices(&inst);
    /// assert!(afg_baseline::verify_optimal(&inst, &opt, &prices).is_ok());
    /// for i in inst.robot_ids() {
    ///     let own = opt.task_of(i).unwrap();
    ///     let value = |j: afg_game::TaskId| inst.cost(i, j) - prices[j.index()];
    ///     assert!(inst.task_ids().all(|k| value(own) <= value(k) + 1e-9));
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_prices(&self, instance: &Instance) -> (Assignment, Vec<f64>) {
        let solution = transport::solve(instance);
        (
            assignment_of(instance, &solution.task_of),
            task_prices(instance, solution.prices),
        )
    }

    /// [`Optimum::with_prices`] started from `prices` (one per task, any common offset;
    /// where the instance allows the void, measured from the void's 0) instead of from
    /// a subsample's: every robot starts at its cheapest task under
    /// them and only what is out of balance is routed. Good prices — a previous
    /// optimum's after robots left or joined, or a learned model's — leave little to
    /// route; zero prices start from the nearest-task assignment.
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] unless `prices` are M finite numbers.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Optimum;
    /// use afg_game::GeneratorConfig;
    /// let inst = GeneratorConfig::paper(500, 5, 3).generate()?;
    /// let (opt, prices) = Optimum.with_prices(&inst);
    /// let (cold, _) = Optimum.with_prices_from(&inst, &[0.0; 5])?;
    /// let (warm, _) = Optimum.with_prices_from(&inst, &prices)?;
    /// assert!((inst.welfare(&cold) - inst.welfare(&opt)).abs() < 1e-9);
    /// assert!((inst.welfare(&warm) - inst.welfare(&opt)).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_prices_from(
        &self,
        instance: &Instance,
        prices: &[f64],
    ) -> Result<(Assignment, Vec<f64>), AllocError> {
        check_prices(instance, prices)?;
        let mut columns = prices.to_vec();
        if instance.allows_void() {
            columns.push(0.0);
        }
        let solution = transport::solve_from(instance, &columns);
        Ok((
            assignment_of(instance, &solution.task_of),
            task_prices(instance, solution.prices),
        ))
    }

    /// A price to start [`Optimum::with_prices_from`] at for a task that has none yet
    /// (one that just appeared): the marginal value of its member at the mean coalition
    /// size N / M, what its price would be if it got an average share of the robots.
    ///
    /// # Panics
    /// If `task` is not a task of the instance.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Optimum;
    /// use afg_game::{GeneratorConfig, TaskId};
    /// let inst = GeneratorConfig::paper(100, 5, 1).generate()?;
    /// let p = Optimum::start_price(&inst, TaskId(2));
    /// assert_eq!(p, inst.marginal_value(TaskId(2), 20));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn start_price(instance: &Instance, task: TaskId) -> f64 {
        let mean = instance.num_robots() / instance.num_tasks();
        let size = mean.clamp(1, instance.capacity(task).max(1));
        instance.marginal_value(task, size)
    }

    /// For every task a, the best final welfare with the robots assigned in `partial`
    /// fixed and `actor` (unassigned there) on a; `None` where a has no room for it.
    /// Where the instance allows the void task, one more entry last: the actor staying
    /// out.
    /// The same numbers as one [`Optimum::complete`] per task, from one completion:
    /// the others are completed without the actor, then the actor on a is one more
    /// unit entering at task a, and (by the successive-shortest-path argument) the
    /// cheapest augmenting path from a turns the others' optimum into the optimum with
    /// the actor on a — one Dijkstra over the M task nodes per task.
    ///
    /// # Errors
    /// As [`Optimum::complete`], and [`AllocError::InvalidParameter`] if `actor` is not
    /// a robot of the instance or is assigned in `partial`.
    ///
    /// # Complexity
    /// One completion, O(N M² log N), then O(M³) heap reads (amortised); one
    /// completion per task would cost M times the first term.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Optimum;
    /// use afg_game::{Assignment, GeneratorConfig, RobotId, TaskId};
    /// let inst = GeneratorConfig::paper(30, 5, 1).generate()?;
    /// let mut partial = Assignment::unassigned(30, 5);
    /// partial.set(RobotId(0), Some(TaskId(3)));
    /// let values = Optimum.action_values(&inst, &partial, RobotId(1))?;
    /// for j in inst.task_ids() {
    ///     let mut forced = partial.clone();
    ///     forced.set(RobotId(1), Some(j));
    ///     let one = inst.welfare(&Optimum.complete(&inst, &forced)?);
    ///     assert!((values[j.index()].unwrap() - one).abs() < 1e-9);
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn action_values(
        &self,
        instance: &Instance,
        partial: &Assignment,
        actor: RobotId,
    ) -> Result<Vec<Option<f64>>, AllocError> {
        check_partial(instance, partial)?;
        if actor.index() >= instance.num_robots() || partial.task_of(actor).is_some() {
            return Err(AllocError::InvalidParameter(format!(
                "robot {actor} is not an unassigned robot of the instance"
            )));
        }
        let mut s = augmenting::solved(instance, partial.clone(), Some(actor.index()));
        let others = instance.welfare(&s.assignment);
        let m = instance.num_tasks();
        let void = instance.allows_void().then_some(m);
        Ok((0..m)
            .chain(void)
            .map(|a| {
                if a < m && !partial.has_room(instance, actor, TaskId(a as u32)) {
                    return None;
                }
                s.dist.fill(f64::INFINITY);
                s.dist[a] = s.cost(actor.index(), a);
                s.shortest_paths();
                Some(others - s.best_end().1)
            })
            .collect())
    }
}

/// The tasks' prices among a solver's column prices (all measured from the sink's
/// potential). Where the instance allows the void, its price is that potential
/// whenever a robot stays out, and at or above it otherwise; counting the void at 0
/// proves the optimum either way: no robot gains by leaving.
fn task_prices(instance: &Instance, mut prices: Vec<f64>) -> Vec<f64> {
    prices.truncate(instance.num_tasks());
    prices
}

/// Checks that `prices` are one finite number per task.
fn check_prices(instance: &Instance, prices: &[f64]) -> Result<(), AllocError> {
    if prices.len() != instance.num_tasks() || prices.iter().any(|p| !p.is_finite()) {
        return Err(AllocError::InvalidParameter(format!(
            "need {} finite task prices, got {prices:?}",
            instance.num_tasks()
        )));
    }
    Ok(())
}

/// Checks that `partial` fits `instance` and respects its capacities.
fn check_partial(instance: &Instance, partial: &Assignment) -> Result<(), AllocError> {
    if partial.num_robots() != instance.num_robots()
        || partial.sizes().len() != instance.num_tasks()
    {
        return Err(AllocError::InvalidParameter(format!(
            "the partial assignment has {} robots and {} tasks, the instance {} and {}",
            partial.num_robots(),
            partial.sizes().len(),
            instance.num_robots(),
            instance.num_tasks()
        )));
    }
    if let Some(j) = instance
        .task_ids()
        .find(|&j| partial.size(j) > instance.capacity(j))
    {
        return Err(AllocError::InvalidParameter(format!(
            "the partial assignment puts {} robots in task {j}, above its capacity {}",
            partial.size(j),
            instance.capacity(j)
        )));
    }
    Ok(())
}

impl Allocator for Optimum {
    fn name(&self) -> String {
        "opt".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        if instance.has_teams() {
            return TeamOptimum::default().allocate(instance);
        }
        check_memory(instance)?;
        let (solution, wall_time) = timed(|| transport::solve(instance));
        Ok(Allocation {
            assignment: assignment_of(instance, &solution.task_of),
            stats: AllocStats {
                iterations: solution.routed,
                wall_time,
                ..AllocStats::default()
            },
        })
    }
}
