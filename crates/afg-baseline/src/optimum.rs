//! The exact welfare maximum (OPT) as a min-cost flow with M task nodes.
//!
//! Maximising `sum_j F_j(n_j) - beta sum_i d(i, g_i)` over complete assignments is
//! a min-cost flow: robot i sends one unit to task j at cost `c_ij = beta d(i, j)`,
//! and task j sends its n-th unit to the sink at cost `-(F_j(n) - F_j(n - 1))`.
//! Concavity of F_j (eps ≥ φ) makes those slot costs increase with n, so a task's
//! slots are filled in order and one "next slot" per task is all the graph needs.
//!
//! Robots are added one at a time, each along a shortest augmenting path (the
//! Hungarian / successive-shortest-path scheme): the new robot joins some task j0,
//! a chain of robots shifts j0 → j1 → … → jt, and task jt takes one more member.
//! Between tasks, the residual edge j → k costs `min_{r in j} (c_rk - c_rj)`, read
//! from one lazy-deletion heap per ordered task pair; Johnson potentials keep the
//! reduced costs non-negative so Dijkstra over the M task nodes applies.
//!
//! [`Optimum::complete`] solves the same problem with some robots fixed in place: a
//! fixed robot never enters a heap (so no path shifts it), and the slot costs of its
//! task start after the fixed members (F_j(n + f_j) − F_j(f_j) is concave whenever
//! F_j is). This is the exact Q\* oracle of the sequential MDP: with γ = 1 and the
//! welfare difference as reward, `Q*(s_t, a) = OPT(robots before t fixed, robot t on
//! a) − W(s_t)`.
//!
//! # Complexity
//! Per robot O(M² + L M log N) for a path of L shifts; O(N M² log N) in all and
//! O(N M) memory. No N × N structure anywhere.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use afg_game::{Assignment, Instance, RobotId, TaskId};

use crate::{AllocError, AllocStats, Allocation, Allocator, timed};

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
        Ok(optimum(instance, partial.clone()).0)
    }

    /// The optimum with its task prices π: every robot's optimal task minimises
    /// `β d(i, j) − π_j` over all tasks (LP duality for the min-cost flow; the prices are
    /// the Johnson potentials of the task nodes after the last augmentation). Prices are
    /// defined up to a common constant; these have no particular offset.
    ///
    /// Why: a robot in task j may move to k through the residual edge of cost
    /// `c_ik − c_ij`, whose reduced cost `c_ik − c_ij + π_j − π_k` is non-negative at
    /// the optimum. Robots whose minimum is unique therefore sit exactly where argmin
    /// sends them; ties are settled by the counts.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::Optimum;
    /// use afg_game::{GeneratorConfig, RobotId};
    /// let inst = GeneratorConfig::paper(60, 5, 1).generate()?;
    /// let (opt, prices) = Optimum.with_prices(&inst);
    /// for i in inst.robot_ids() {
    ///     let own = opt.task_of(i).unwrap();
    ///     let value = |j: afg_game::TaskId| inst.cost(i, j) - prices[j.index()];
    ///     assert!(inst.task_ids().all(|k| value(own) <= value(k) + 1e-9));
    /// }
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_prices(&self, instance: &Instance) -> (Assignment, Vec<f64>) {
        let empty = Assignment::unassigned(instance.num_robots(), instance.num_tasks());
        let (assignment, _, prices) = optimum(instance, empty);
        (assignment, prices)
    }
}

impl Allocator for Optimum {
    fn name(&self) -> String {
        "opt".into()
    }

    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        let empty = Assignment::unassigned(instance.num_robots(), instance.num_tasks());
        let ((assignment, shifts, _), wall_time) = timed(|| optimum(instance, empty));
        Ok(Allocation {
            assignment,
            stats: AllocStats {
                iterations: shifts,
                wall_time,
                ..AllocStats::default()
            },
        })
    }
}

/// A robot in task j, keyed by the cost of moving it to task k: `c_rk - c_rj`.
#[derive(Clone, Copy)]
struct Entry {
    key: f64,
    robot: u32,
    /// The robot's move counter when pushed; a mismatch marks the entry stale.
    stamp: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    /// Reversed, so that `BinaryHeap` pops the cheapest; ties by lower robot index.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .key
            .total_cmp(&self.key)
            .then(other.robot.cmp(&self.robot))
    }
}

struct Solver<'a> {
    inst: &'a Instance,
    m: usize,
    /// `costs[i * m + j] = beta d(i, j)`.
    costs: Vec<f64>,
    assignment: Assignment,
    stamps: Vec<u32>,
    /// `heaps[j * m + k]`: robots of task j keyed by `c_rk - c_rj`.
    heaps: Vec<BinaryHeap<Entry>>,
}

impl Solver<'_> {
    fn cost(&self, robot: usize, task: usize) -> f64 {
        self.costs[robot * self.m + task]
    }

    /// Puts `robot` in `task`, invalidating its old heap entries and pushing new ones.
    fn place(&mut self, robot: usize, task: usize) {
        self.assignment
            .set(RobotId(robot as u32), Some(TaskId(task as u32)));
        self.stamps[robot] += 1;
        let stamp = self.stamps[robot];
        let here = self.cost(robot, task);
        for k in (0..self.m).filter(|&k| k != task) {
            let key = self.cost(robot, k) - here;
            self.heaps[task * self.m + k].push(Entry {
                key,
                robot: robot as u32,
                stamp,
            });
        }
    }

    /// The cheapest live robot to move from task j to task k, dropping stale entries.
    fn cheapest(&mut self, j: usize, k: usize) -> Option<Entry> {
        let heap = &mut self.heaps[j * self.m + k];
        while let Some(&top) = heap.peek() {
            let live = self.stamps[top.robot as usize] == top.stamp;
            if live {
                return Some(top);
            }
            heap.pop();
        }
        None
    }
}

/// Where a task node was reached from on the current shortest-path tree.
#[derive(Clone, Copy)]
enum Pred {
    /// Directly from the new robot.
    Source,
    /// From task `from`, by moving `robot` out of it.
    Shift { from: usize, robot: u32 },
}

/// The optimal completion of `partial` (robots assigned there stay), the number of
/// robot shifts the augmentations made and the final task potentials. `partial` must
/// respect capacities.
fn optimum(inst: &Instance, partial: Assignment) -> (Assignment, u64, Vec<f64>) {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    let costs = inst
        .robot_ids()
        .flat_map(|i| inst.task_ids().map(move |j| inst.cost(i, j)))
        .collect();
    let mut s = Solver {
        inst,
        m,
        costs,
        assignment: partial,
        stamps: vec![0; n],
        heaps: (0..m * m).map(|_| BinaryHeap::new()).collect(),
    };
    let mut potential = vec![0.0f64; m];
    let mut dist = vec![0.0f64; m];
    let mut pred = vec![Pred::Source; m];
    let mut done = vec![false; m];
    let mut shifts = 0u64;
    let free: Vec<usize> = (0..n)
        .filter(|&i| s.assignment.task_of(RobotId(i as u32)).is_none())
        .collect();
    for robot in free {
        // Dijkstra over task nodes with reduced costs; the source's own edges may be negative.
        for j in 0..m {
            dist[j] = s.cost(robot, j) - potential[j];
            pred[j] = Pred::Source;
            done[j] = false;
        }
        for _ in 0..m {
            let j = (0..m)
                .filter(|&j| !done[j])
                .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))
                .expect("an unsettled task remains");
            done[j] = true;
            for k in 0..m {
                if done[k] {
                    continue;
                }
                if let Some(e) = s.cheapest(j, k) {
                    let d = dist[j] + e.key + potential[j] - potential[k];
                    if d < dist[k] {
                        dist[k] = d;
                        pred[k] = Pred::Shift {
                            from: j,
                            robot: e.robot,
                        };
                    }
                }
            }
        }
        // The path ends where taking one more member is cheapest (real, not reduced, cost).
        let end = (0..m)
            .filter(|&j| s.assignment.size(TaskId(j as u32)) < s.inst.capacity(TaskId(j as u32)))
            .min_by(|&a, &b| {
                let total = |j: usize| {
                    dist[j] + potential[j]
                        - s.inst.marginal_value(
                            TaskId(j as u32),
                            s.assignment.size(TaskId(j as u32)) + 1,
                        )
                };
                total(a).total_cmp(&total(b))
            })
            .expect("capacities hold every robot (checked by Instance::new)");
        // Shift robots back along the path, then place the new robot.
        let mut at = end;
        while let Pred::Shift { from, robot: r } = pred[at] {
            s.place(r as usize, at);
            shifts += 1;
            at = from;
        }
        s.place(robot, at);
        for j in 0..m {
            potential[j] += dist[j];
        }
    }
    (s.assignment, shifts, potential)
}
