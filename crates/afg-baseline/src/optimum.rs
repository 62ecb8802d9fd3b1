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
        check_partial(instance, partial)?;
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

    /// For every task a, the best final welfare with the robots assigned in `partial`
    /// fixed and `actor` (unassigned there) on a; `None` where a has no room for it.
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
        let mut s = solved(instance, partial.clone(), Some(actor.index()));
        let others = instance.welfare(&s.assignment);
        Ok(instance
            .task_ids()
            .map(|a| {
                if !partial.has_room(instance, actor, a) {
                    return None;
                }
                s.dist.fill(f64::INFINITY);
                s.dist[a.index()] = s.cost(actor.index(), a.index());
                s.shortest_paths();
                Some(others - s.best_end().1)
            })
            .collect())
    }
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
    /// Johnson potentials of the task nodes: every residual edge's reduced cost
    /// `c + potential[from] − potential[to]` is non-negative.
    potential: Vec<f64>,
    /// Reduced distances of the last [`Solver::shortest_paths`].
    dist: Vec<f64>,
    pred: Vec<Pred>,
    done: Vec<bool>,
    /// Robot shifts made by the augmentations so far.
    shifts: u64,
}

impl<'a> Solver<'a> {
    /// A solver holding `partial` (robots assigned there are fixed: never in a heap).
    fn new(inst: &'a Instance, partial: Assignment) -> Self {
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let costs = inst
            .robot_ids()
            .flat_map(|i| inst.task_ids().map(move |j| inst.cost(i, j)))
            .collect();
        Solver {
            inst,
            m,
            costs,
            assignment: partial,
            stamps: vec![0; n],
            heaps: (0..m * m).map(|_| BinaryHeap::new()).collect(),
            potential: vec![0.0; m],
            dist: vec![0.0; m],
            pred: vec![Pred::Source; m],
            done: vec![false; m],
            shifts: 0,
        }
    }

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

    /// Dijkstra over the task nodes with reduced costs, from a new unit that enters
    /// task j at the real cost the caller wrote into `dist[j]` (infinite: not there);
    /// only these first edges may be negative. Fills `dist` and `pred`.
    fn shortest_paths(&mut self) {
        let m = self.m;
        for j in 0..m {
            self.dist[j] -= self.potential[j];
            self.pred[j] = Pred::Source;
            self.done[j] = false;
        }
        for _ in 0..m {
            let dist = &self.dist;
            let j = (0..m)
                .filter(|&j| !self.done[j])
                .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))
                .expect("an unsettled task remains");
            self.done[j] = true;
            if self.dist[j] == f64::INFINITY {
                break;
            }
            for k in 0..m {
                if self.done[k] {
                    continue;
                }
                if let Some(e) = self.cheapest(j, k) {
                    let d = self.dist[j] + e.key + self.potential[j] - self.potential[k];
                    if d < self.dist[k] {
                        self.dist[k] = d;
                        self.pred[k] = Pred::Shift {
                            from: j,
                            robot: e.robot,
                        };
                    }
                }
            }
        }
    }

    /// Where the paths of the last [`Solver::shortest_paths`] should end: the task with
    /// room where taking one more member is cheapest, and that real cost (the path's
    /// cost minus the member's marginal value), the change in `−welfare` of the
    /// augmentation.
    fn best_end(&self) -> (usize, f64) {
        let total = |j: usize| {
            let task = TaskId(j as u32);
            self.dist[j] + self.potential[j]
                - self
                    .inst
                    .marginal_value(task, self.assignment.size(task) + 1)
        };
        (0..self.m)
            .filter(|&j| {
                let task = TaskId(j as u32);
                self.assignment.size(task) < self.inst.capacity(task)
            })
            .map(|j| (j, total(j)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .expect("capacities hold every robot (checked by Instance::new)")
    }

    /// Adds `robot` along a shortest augmenting path and updates the potentials.
    fn augment(&mut self, robot: usize) {
        for j in 0..self.m {
            self.dist[j] = self.cost(robot, j);
        }
        self.shortest_paths();
        let (end, _) = self.best_end();
        // Shift robots back along the path, then place the new robot.
        let mut at = end;
        while let Pred::Shift { from, robot: r } = self.pred[at] {
            self.place(r as usize, at);
            self.shifts += 1;
            at = from;
        }
        self.place(robot, at);
        for j in 0..self.m {
            self.potential[j] += self.dist[j];
        }
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

/// A solver that has completed `partial` optimally, leaving `skip` (if any) out.
fn solved(inst: &Instance, partial: Assignment, skip: Option<usize>) -> Solver<'_> {
    let mut s = Solver::new(inst, partial);
    let free: Vec<usize> = (0..inst.num_robots())
        .filter(|&i| s.assignment.task_of(RobotId(i as u32)).is_none() && Some(i) != skip)
        .collect();
    for robot in free {
        s.augment(robot);
    }
    s
}

/// The optimal completion of `partial` (robots assigned there stay), the number of
/// robot shifts the augmentations made and the final task potentials. `partial` must
/// respect capacities.
fn optimum(inst: &Instance, partial: Assignment) -> (Assignment, u64, Vec<f64>) {
    let s = solved(inst, partial, None);
    (s.assignment, s.shifts, s.potential)
}
