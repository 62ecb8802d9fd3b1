//! Per-task summaries of an allocation in progress (the inputs of the price model and
//! of AFGNet's price head), kept up to date as robots join tasks.
//!
//! Everything is measured so that it means the same at every N (β units for welfare,
//! a task's `eps_j` for counts): the paper's distribution has `eps_j = N/M` and rewards
//! in `[N/M, 2N/M]`, so `n_j / eps_j` and `r_j / eps_j` are O(1) at any scale.

use crate::{Units, VALUE_CAP};
use afg_game::{Assignment, Instance, RobotId, TaskId};
use rayon::prelude::*;

/// Number of inputs per task ([`PriceState::features`]).
pub const TASK_FEATURES: usize = 9;

/// Temperatures (distance units) of the two soft demands.
const SOFT_TEMPERATURES: [f64; 2] = [0.05, 0.2];

/// Robot–task pairs from which a state's per-robot rows are computed on all cores.
const PARALLEL_PAIRS: usize = 1 << 16;

/// The state of a sequential allocation seen through per-task summaries: each task's
/// members and the demand of the robots not yet placed.
///
/// # Complexity
/// [`PriceState::new`] O(N·M) time and memory; [`PriceState::assign`] O(M);
/// [`PriceState::features`] O(M).
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, RobotId, TaskId};
/// use afg_graph::{PriceState, TASK_FEATURES};
/// let inst = GeneratorConfig::paper(60, 5, 1).generate()?;
/// let mut state = PriceState::new(&inst);
/// let mut before = vec![0.0; 5 * TASK_FEATURES];
/// state.features(&mut before);
/// state.assign(RobotId(0), TaskId(2));
/// let mut after = vec![0.0; 5 * TASK_FEATURES];
/// state.features(&mut after);
/// // Task 2's occupancy n_j / eps_j grew by 1 / eps_j = 1 / 12.
/// let occupancy = |f: &[f32]| f[2 * TASK_FEATURES + 1];
/// assert!((occupancy(&after) - occupancy(&before) - 1.0 / 12.0).abs() < 1e-6);
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug)]
pub struct PriceState<'a> {
    instance: &'a Instance,
    /// The welfare unit (β).
    unit: f64,
    assignment: Assignment,
    /// Per robot, its nearest task.
    nearest: Vec<u32>,
    /// Per robot and temperature, its soft-min weights over tasks: `[N, 2, M]`.
    soft: Vec<f32>,
    /// Robots not yet placed whose nearest task is j.
    demand_nearest: Vec<f64>,
    /// Soft demands of robots not yet placed: `[2, M]`.
    demand_soft: Vec<f64>,
    /// Per robot, whether it was placed or left out.
    decided: Vec<bool>,
    unassigned: usize,
    eps_total: f64,
}

impl<'a> PriceState<'a> {
    /// The state with no robot placed.
    pub fn new(instance: &'a Instance) -> Self {
        let (n, m) = (instance.num_robots(), instance.num_tasks());
        let unit = Units::ScaleFree.welfare_unit(instance);
        let mut nearest = vec![0u32; n];
        let mut soft = vec![0.0f32; n * 2 * m];
        // Each robot's nearest task and soft-min weights (on all cores when large), then
        // the demands summed in robot order, so the result is the same on any core count.
        let robot_row =
            |cost: &mut Vec<f64>, (i, (weights, near)): (usize, (&mut [f32], &mut u32))| {
                cost.clear();
                let robot = RobotId(i as u32);
                cost.extend(instance.task_ids().map(|j| instance.cost(robot, j) / unit));
                let (best, low) =
                    cost.iter()
                        .enumerate()
                        .fold(
                            (0, f64::INFINITY),
                            |(b, lo), (j, &c)| {
                                if c < lo { (j, c) } else { (b, lo) }
                            },
                        );
                *near = best as u32;
                for (weights, &tau) in weights.chunks_exact_mut(m).zip(&SOFT_TEMPERATURES) {
                    let mut total = 0.0;
                    for (w, &c) in weights.iter_mut().zip(cost.iter()) {
                        let e = (-(c - low) / tau).exp();
                        *w = e as f32;
                        total += e;
                    }
                    for w in weights.iter_mut() {
                        *w = (f64::from(*w) / total) as f32;
                    }
                }
            };
        let rows = soft
            .chunks_exact_mut(2 * m)
            .zip(nearest.iter_mut())
            .enumerate();
        if n * m >= PARALLEL_PAIRS {
            let rows = soft
                .par_chunks_exact_mut(2 * m)
                .zip(nearest.par_iter_mut())
                .enumerate();
            rows.for_each_init(Vec::new, robot_row);
        } else {
            let mut cost = Vec::with_capacity(m);
            rows.for_each(|row| robot_row(&mut cost, row));
        }
        let mut demand_nearest = vec![0.0; m];
        let mut demand_soft = vec![0.0; 2 * m];
        for (&near, weights) in nearest.iter().zip(soft.chunks_exact(2 * m)) {
            demand_nearest[near as usize] += 1.0;
            for (d, &w) in demand_soft.iter_mut().zip(weights) {
                *d += f64::from(w);
            }
        }
        PriceState {
            instance,
            unit,
            assignment: Assignment::unassigned(n, m),
            nearest,
            soft,
            demand_nearest,
            demand_soft,
            decided: vec![false; n],
            unassigned: n,
            eps_total: instance.tasks().iter().map(|t| t.eps).sum(),
        }
    }

    /// The state with the robots of `assignment` placed.
    ///
    /// # Panics
    /// If `assignment` is for another number of robots or tasks.
    pub fn from_assignment(instance: &'a Instance, assignment: &Assignment) -> Self {
        assert_eq!(
            (assignment.num_robots(), assignment.sizes().len()),
            (instance.num_robots(), instance.num_tasks()),
            "assignment of another instance"
        );
        let mut state = Self::new(instance);
        for i in instance.robot_ids() {
            if let Some(j) = assignment.task_of(i) {
                state.assign(i, j);
            }
        }
        state
    }

    /// The instance.
    pub fn instance(&self) -> &'a Instance {
        self.instance
    }

    /// The robots placed so far.
    pub fn assignment(&self) -> &Assignment {
        &self.assignment
    }

    /// `β d(robot, task)` in the features' welfare unit.
    pub fn cost(&self, robot: RobotId, task: TaskId) -> f64 {
        self.instance.cost(robot, task) / self.unit
    }

    /// The welfare unit (β, or 1 when β = 0): features, costs and prices are in it.
    pub fn unit(&self) -> f64 {
        self.unit
    }

    /// Places `robot` (not yet placed or left out) in `task`.
    ///
    /// # Panics
    /// If `robot` is already placed or left out.
    pub fn assign(&mut self, robot: RobotId, task: TaskId) {
        self.decide(robot);
        self.assignment.set(robot, Some(task));
    }

    /// Leaves `robot` (not yet placed or left out) in the void task, where the
    /// instance allows it: it no longer counts among the robots still to place.
    ///
    /// # Panics
    /// If `robot` is already placed or left out.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, RobotId, Task};
    /// use afg_graph::{PriceState, TASK_FEATURES};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(1.0, 0.0), Point::new(9.0, 0.0)];
    /// let inst = Instance::with_void(robots, vec![task], 1.0)?;
    /// let mut state = PriceState::new(&inst);
    /// state.leave_out(RobotId(1));
    /// let mut f = vec![0.0; TASK_FEATURES];
    /// state.features(&mut f);
    /// assert_eq!(f[3], 0.5); // one robot left to place, over Σ eps = 2
    /// assert_eq!(state.assignment().num_assigned(), 0);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn leave_out(&mut self, robot: RobotId) {
        self.decide(robot);
    }

    /// Takes `robot` out of the robots still to place and their demands.
    fn decide(&mut self, robot: RobotId) {
        assert!(
            !std::mem::replace(&mut self.decided[robot.index()], true),
            "robot {robot} is already placed or left out"
        );
        let m = self.instance.num_tasks();
        self.unassigned -= 1;
        self.demand_nearest[self.nearest[robot.index()] as usize] -= 1.0;
        let soft = &self.soft[robot.index() * 2 * m..(robot.index() + 1) * 2 * m];
        for (d, &w) in self.demand_soft.iter_mut().zip(soft) {
            *d -= f64::from(w);
        }
    }

    /// The inputs of every task, `[M, TASK_FEATURES]` row-major into `out`:
    ///
    /// 0. the next member's marginal value `F_j(n_j + 1) − F_j(n_j)`, capped at
    ///    [`VALUE_CAP`]` · r_j / eps_j` (an empty task's first member is worth r_j,
    ///    which grows with N);
    /// 1. occupancy `n_j / eps_j`;
    /// 2. `r_j / eps_j`;
    /// 3. robots not yet placed over `Σ_k eps_k`;
    /// 4. robots not yet placed whose nearest task is j, over `eps_j`;
    /// 5. their soft-min demand for j at temperature 0.05, over `eps_j`;
    /// 6. the same at temperature 0.2;
    /// 7. the marginal value (capped as in 0) at `n_j` plus the demand of 4: what j's
    ///    price would be if every robot left went to its nearest task;
    /// 8. the same with the demand of 6.
    ///
    /// # Panics
    /// If `out` is not `M · TASK_FEATURES` long.
    pub fn features(&self, out: &mut [f32]) {
        let m = self.instance.num_tasks();
        assert_eq!(out.len(), m * TASK_FEATURES);
        let supply = self.unassigned as f64 / self.eps_total;
        for (j, row) in out.chunks_exact_mut(TASK_FEATURES).enumerate() {
            let task = TaskId(j as u32);
            let t = self.instance.task(task);
            let n = self.assignment.size(task);
            let cap = VALUE_CAP * t.reward / t.eps;
            let marginal = |members: f64| {
                let k = members.round().max(0.0) as usize;
                self.instance.marginal_value(task, k + 1).min(cap) / self.unit
            };
            let near = self.demand_nearest[j];
            let soft_wide = self.demand_soft[m + j];
            row.copy_from_slice(&[
                marginal(n as f64) as f32,
                (n as f64 / t.eps) as f32,
                (t.reward / t.eps / self.unit) as f32,
                supply as f32,
                (near / t.eps) as f32,
                (self.demand_soft[j] / t.eps) as f32,
                (soft_wide / t.eps) as f32,
                marginal(n as f64 + near) as f32,
                marginal(n as f64 + soft_wide) as f32,
            ]);
        }
    }
}

/// The network input of each task: its own features, then the mean of every task's
/// features (what the others look like), `[M, 2 · TASK_FEATURES]` into `out`.
///
/// # Panics
/// If the lengths are not `M · TASK_FEATURES` and `2 M · TASK_FEATURES`.
pub fn task_inputs(features: &[f32], out: &mut [f32]) {
    rows_with_mean(features, TASK_FEATURES, out);
}

/// Each row of `width` features (`[M, width]`), then the mean of every row, side by
/// side into `out` (`[M, 2 · width]`): a task's input to a network shared by every
/// task ([`task_inputs`] for the price features; the staffing model's too).
///
/// # Examples
/// ```
/// let mut out = vec![0.0; 8];
/// afg_graph::rows_with_mean(&[1.0, 2.0, 3.0, 4.0], 2, &mut out);
/// assert_eq!(out, [1.0, 2.0, 2.0, 3.0, 3.0, 4.0, 2.0, 3.0]);
/// ```
///
/// # Panics
/// If `width` is 0 or the lengths are not `M · width` and `2 M · width`.
pub fn rows_with_mean(features: &[f32], width: usize, out: &mut [f32]) {
    assert!(width > 0 && features.len().is_multiple_of(width));
    assert_eq!(out.len(), 2 * features.len());
    let m = features.len() / width;
    let mut mean = vec![0.0f32; width];
    for row in features.chunks_exact(width) {
        for (s, &x) in mean.iter_mut().zip(row) {
            *s += x / m as f32;
        }
    }
    for (row, input) in features
        .chunks_exact(width)
        .zip(out.chunks_exact_mut(2 * width))
    {
        input[..width].copy_from_slice(row);
        input[width..].copy_from_slice(&mean);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use afg_game::GeneratorConfig;

    /// Demands kept by `assign` equal demands recomputed from scratch over the robots
    /// left.
    #[test]
    fn incremental_demand_matches_a_fresh_count() {
        let inst = GeneratorConfig::paper(40, 5, 3).generate().unwrap();
        let mut state = PriceState::new(&inst);
        for i in 0..25u32 {
            state.assign(RobotId(i), TaskId(i % 5));
        }
        let fresh = PriceState::new(&inst);
        let m = 5;
        let mut near = vec![0.0; m];
        let mut soft = vec![0.0; 2 * m];
        for i in 25..40usize {
            near[fresh.nearest[i] as usize] += 1.0;
            for (s, &w) in soft.iter_mut().zip(&fresh.soft[i * 2 * m..(i + 1) * 2 * m]) {
                *s += f64::from(w);
            }
        }
        for j in 0..m {
            assert_eq!(state.demand_nearest[j], near[j]);
            assert!((state.demand_soft[j] - soft[j]).abs() < 1e-5);
            assert!((state.demand_soft[m + j] - soft[m + j]).abs() < 1e-5);
        }
        // Nearest demand by brute force.
        let by_hand = (25..40u32)
            .filter(|&i| {
                let d0 = inst.distance(RobotId(i), TaskId(0));
                inst.task_ids().all(|j| inst.distance(RobotId(i), j) >= d0)
            })
            .count();
        assert_eq!(state.demand_nearest[0], by_hand as f64);
    }

    #[test]
    fn features_of_the_empty_state_by_hand() {
        let inst = GeneratorConfig::paper(60, 5, 9).generate().unwrap();
        let state = PriceState::new(&inst);
        let mut f = vec![0.0; 5 * TASK_FEATURES];
        state.features(&mut f);
        let soft_total: f32 = (0..5).map(|j| f[j * TASK_FEATURES + 5] * 12.0).sum();
        assert!((soft_total - 60.0).abs() < 1e-3, "soft demands sum to N");
        for j in 0..5 {
            let row = &f[j * TASK_FEATURES..(j + 1) * TASK_FEATURES];
            let t = inst.task(TaskId(j as u32));
            // Empty task: its first member is worth r_j, capped at 4 r_j / eps_j.
            assert_eq!(row[0], (4.0 * t.reward / 12.0) as f32);
            assert_eq!(row[1], 0.0);
            assert_eq!(row[3], 1.0); // 60 robots left, Σ eps = 60
        }
        let mut inputs = vec![0.0; 10 * TASK_FEATURES];
        task_inputs(&f, &mut inputs);
        let mean_supply = inputs[TASK_FEATURES + 3];
        assert!((mean_supply - 1.0).abs() < 1e-6);
    }
}
