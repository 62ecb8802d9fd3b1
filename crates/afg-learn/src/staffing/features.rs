//! What the staffing network reads of a task: the root relaxation's verdict on it and
//! the geometry of its threshold, all in units free of N, M and the reward scale, so
//! that one model serves any size.

use afg_baseline::TeamRelaxation;
use afg_game::Instance;

/// Features per task.
pub const STAFF_FEATURES: usize = 10;

/// Feature 3: the threshold over the mean share.
pub(crate) const SIZE: usize = 3;
/// Feature 6: a member's value at the threshold less its nearest robots' cost.
pub(crate) const MARGIN: usize = 6;

/// Width of a task's network input: its features and the mean of all tasks' features.
pub const STAFF_INPUTS: usize = 2 * STAFF_FEATURES;

/// The features of every task (`[M, STAFF_FEATURES]`, row-major) of `instance` and its
/// root relaxation `root`; with `share` = N / M and `v_j = F_j(k_j) / k_j` (a member's
/// value in a team of exactly its threshold), `v̄` their mean over the tasks:
///
/// | # | feature |
/// |---|---|
/// | 0 | the relaxed coalition over the threshold, `n_j / k_j`, at most 3 |
/// | 1 | 1 where the relaxation leaves the task empty |
/// | 2 | 1 where it staffs the task in full (`n_j ≥ k_j`) |
/// | 3 | the threshold over the mean share, `k_j / share` |
/// | 4 | `v_j / v̄` |
/// | 5 | the task's price in the relaxation, over `v̄` |
/// | 6 | `v_j` less the mean cost of the task's `k_j` nearest robots, over `v̄` |
/// | 7 | the thresholds of the tasks the relaxation fills more (ties: lower index) over N |
/// | 8 | every task's threshold together over N (the same for all tasks) |
/// | 9 | 1 where no team can staff the task |
///
/// # Examples
/// ```
/// use afg_baseline::TeamOptimum;
/// use afg_game::GeneratorConfig;
/// use afg_learn::staffing::{STAFF_FEATURES, staffing_features};
/// let mut cfg = GeneratorConfig::paper(30, 5, 1);
/// cfg.min_team = Some(afg_game::CountRange { min: 6, max: 12 });
/// let inst = cfg.generate()?;
/// let features = staffing_features(&inst, &TeamOptimum::relax(&inst));
/// assert_eq!(features.len(), 5 * STAFF_FEATURES);
/// assert!(features.iter().all(|x| x.is_finite()));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Panics
/// If `root` is not a relaxation of an instance with `instance`'s number of tasks.
pub fn staffing_features(instance: &Instance, root: &TeamRelaxation) -> Vec<f32> {
    let (n, m) = (instance.num_robots(), instance.num_tasks());
    assert_eq!(root.sizes.len(), m, "a relaxation of this instance");
    let share = n as f64 / m as f64;
    let member_value = |j| {
        let k = instance.min_team(j);
        instance.value_function(j).value(k) / k as f64
    };
    let values: Vec<f64> = instance.task_ids().map(member_value).collect();
    let unit = (values.iter().sum::<f64>() / m as f64).max(1e-12);
    let fill: Vec<f64> = instance
        .task_ids()
        .map(|j| (root.sizes[j.index()] as f64 / instance.min_team(j) as f64).min(3.0))
        .collect();
    let thresholds: usize = instance.task_ids().map(|j| instance.min_team(j)).sum();
    let unstaffable = instance.unstaffable_tasks();
    let mut costs = vec![0.0; n];
    let mut out = Vec::with_capacity(m * STAFF_FEATURES);
    for j in instance.task_ids() {
        let (t, k) = (j.index(), instance.min_team(j));
        let size = root.sizes[t];
        for (c, i) in costs.iter_mut().zip(instance.robot_ids()) {
            *c = instance.cost(i, j);
        }
        let nearest = k.clamp(1, n);
        costs.select_nth_unstable_by(nearest - 1, f64::total_cmp);
        let near_cost = costs[..nearest].iter().sum::<f64>() / nearest as f64;
        let ahead: usize = instance
            .task_ids()
            .filter(|o| fill[o.index()] > fill[t] || (fill[o.index()] == fill[t] && o.index() < t))
            .map(|o| instance.min_team(o))
            .sum();
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        out.extend(
            [
                fill[t],
                flag(size == 0),
                flag(size >= k),
                k as f64 / share,
                values[t] / unit,
                root.prices[t] / unit,
                (values[t] - near_cost) / unit,
                ahead as f64 / n as f64,
                thresholds as f64 / n as f64,
                flag(unstaffable.contains(&j)),
            ]
            .map(|x| x as f32),
        );
    }
    out
}

/// The network inputs of every task: its features, then the mean of all tasks'
/// (`[M, STAFF_INPUTS]`).
pub(crate) fn staffing_inputs(features: &[f32]) -> Vec<f32> {
    let mut inputs = vec![0.0; 2 * features.len()];
    afg_graph::rows_with_mean(features, STAFF_FEATURES, &mut inputs);
    inputs
}
