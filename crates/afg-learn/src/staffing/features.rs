//! What the staffing network reads of a task: the root relaxation's verdict on it, the
//! geometry of its threshold and, in a game with skills, how near the skills it
//! requires are, all in units free of N, M and the reward scale, so that one model
//! serves any size.

use afg_baseline::TeamRelaxation;
use afg_game::{Instance, RobotId, TaskId};

/// Features per task: [`COUNT_FEATURES`] that count robots, then three of skills (0,
/// 0 and 3 in a game without skills).
pub const STAFF_FEATURES: usize = 13;

/// The features that count robots (the first ten), all that a model trained on
/// threshold games reads.
pub const COUNT_FEATURES: usize = 10;

/// Feature 3: the threshold over the mean share.
pub(crate) const SIZE: usize = 3;
/// Feature 6: a member's value at the threshold less its nearest robots' cost.
pub(crate) const MARGIN: usize = 6;

/// Width of a task's network input: the features the model reads (all of them where
/// it reads skills, else the first [`COUNT_FEATURES`]) and their means over the tasks.
///
/// # Examples
/// ```
/// use afg_learn::staffing::staffing_input_width;
/// assert_eq!((staffing_input_width(false), staffing_input_width(true)), (20, 26));
/// ```
pub const fn staffing_input_width(reads_skills: bool) -> usize {
    2 * if reads_skills {
        STAFF_FEATURES
    } else {
        COUNT_FEATURES
    }
}

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
/// | 10 | skill cover: the least, over the skills the task requires, of what its `k_j` nearest robots hold over the requirement, at most 1 (1 without requirements) |
/// | 11 | skill reach: how much further than its `k_j`-th nearest robot the nearest holders of every required skill are (the largest such cost difference, at least 0, over `v̄`; 0 where too few robots hold a skill) |
/// | 12 | skill supply: the least, over the skills the task requires, of all robots' holding over all tasks' requirement, at most 3 (3 without requirements) |
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
    let supply = skill_supply(instance);
    let mut costs = vec![0.0; n];
    let mut out = Vec::with_capacity(m * STAFF_FEATURES);
    for j in instance.task_ids() {
        let (t, k) = (j.index(), instance.min_team(j));
        let size = root.sizes[t];
        for (c, i) in costs.iter_mut().zip(instance.robot_ids()) {
            *c = instance.cost(i, j);
        }
        let nearest = k.clamp(1, n);
        let (cover, reach) = skill_cover_and_reach(instance, j, &costs, nearest);
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
                cover,
                reach / unit,
                supply[t],
            ]
            .map(|x| x as f32),
        );
    }
    out
}

/// Task j's skill cover and reach (features 10 and 11, the reach not yet over `v̄`)
/// from every robot's cost to it, `nearest` = its threshold (at least 1).
fn skill_cover_and_reach(
    instance: &Instance,
    j: TaskId,
    costs: &[f64],
    nearest: usize,
) -> (f64, f64) {
    let requires = instance.requires(j);
    if requires.iter().all(|&r| r == 0) {
        return (1.0, 0.0);
    }
    let mut order: Vec<usize> = (0..costs.len()).collect();
    order.sort_by(|&a, &b| costs[a].total_cmp(&costs[b]).then(a.cmp(&b)));
    let skills = |at: usize| instance.skills(RobotId(order[at] as u32));
    let mut held = vec![0u64; requires.len()];
    for at in 0..nearest {
        for (h, &q) in held.iter_mut().zip(skills(at)) {
            *h += u64::from(q);
        }
    }
    let cover = requires
        .iter()
        .zip(&held)
        .filter(|&(&r, _)| r > 0)
        .map(|(&r, &h)| (h as f64 / f64::from(r)).min(1.0))
        .fold(1.0, f64::min);
    // The cost of the nearest robot at which every skill's requirement is held.
    let mut held = vec![0u64; requires.len()];
    let reached = (0..order.len()).find(|&at| {
        for (h, &q) in held.iter_mut().zip(skills(at)) {
            *h += u64::from(q);
        }
        instance.skills_met(j, &held)
    });
    let reach = reached.map_or(0.0, |at| {
        (costs[order[at]] - costs[order[nearest - 1]]).max(0.0)
    });
    (cover, reach)
}

/// Every task's skill supply (feature 12).
fn skill_supply(instance: &Instance) -> Vec<f64> {
    let s = instance.num_skills();
    let (mut held, mut required) = (vec![0.0f64; s], vec![0.0f64; s]);
    for i in instance.robot_ids() {
        for (h, &q) in held.iter_mut().zip(instance.skills(i)) {
            *h += f64::from(q);
        }
    }
    for j in instance.task_ids() {
        for (r, &q) in required.iter_mut().zip(instance.requires(j)) {
            *r += f64::from(q);
        }
    }
    instance
        .task_ids()
        .map(|j| {
            (0..s)
                .filter(|&k| instance.requires(j)[k] > 0)
                .map(|k| (held[k] / required[k]).min(3.0))
                .fold(3.0, f64::min)
        })
        .collect()
}

/// The network inputs of every task: the features the model reads (all where it
/// `reads_skills`, else the first [`COUNT_FEATURES`]), then their mean over the tasks
/// (`[M, staffing_input_width(reads_skills)]`).
pub(crate) fn staffing_inputs(features: &[f32], reads_skills: bool) -> Vec<f32> {
    let read = staffing_input_width(reads_skills) / 2;
    let chosen: Vec<f32> = features
        .chunks_exact(STAFF_FEATURES)
        .flat_map(|row| row[..read].iter().copied())
        .collect();
    let mut inputs = vec![0.0; 2 * chosen.len()];
    afg_graph::rows_with_mean(&chosen, read, &mut inputs);
    inputs
}
