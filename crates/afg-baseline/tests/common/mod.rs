//! What the allocator tests share: small random instances for brute force.

// Each test binary uses part of it.
#![allow(dead_code)]

use afg_game::{Assignment, GOLDEN_RATIO, GeneratorConfig, Instance, Point, RobotId, Task, TaskId};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A random instance small enough for brute force (N ≤ 7, M ≤ 4), any eps ≥ φ and
/// beta; every second case with tight capacities (total just above N, so many tasks
/// are full). One case in four has eps = φ exactly, where F_j(2) = 2 F_j(1): the first
/// two members of a task are worth the same, so the balanced scores of joining an
/// empty task and a task of one tie (and so do the selfish utilities), and one in eight
/// has β = 0 as well, where every task ties on cost.
pub fn small_instance(rng: &mut ChaCha8Rng, case: usize) -> Instance {
    let n = rng.random_range(1..=7);
    let m = rng.random_range(1..=4);
    let mut cfg = GeneratorConfig::paper(n, m, rng.random());
    cfg.eps = rng.random_range(1.62..6.0);
    cfg.beta = rng.random_range(0.0..3.0);
    if case % 4 >= 2 {
        cfg.eps = GOLDEN_RATIO;
    }
    if case % 8 == 3 {
        cfg.beta = 0.0;
    }
    if case % 2 == 1 {
        cfg = cfg.with_capacity_slack(rng.random_range(1.0..1.5));
    }
    cfg.generate().unwrap()
}

/// `inst` in GRAPE's game: the same tasks and β, the robots three times as far from
/// the origin (so some places are worth less than nothing) and, every second case,
/// capacities that hold only about half the robots.
pub fn into_void(rng: &mut ChaCha8Rng, case: usize, inst: &Instance) -> Instance {
    let n = inst.num_robots();
    let robots = inst
        .robots()
        .iter()
        .map(|p| Point::new(3.0 * p.x, 3.0 * p.y))
        .collect();
    let tasks = inst
        .tasks()
        .iter()
        .map(|t| Task {
            capacity: if case % 2 == 1 {
                Some(rng.random_range(1..=n.div_ceil(2 * inst.num_tasks()).max(1)))
            } else {
                t.capacity
            },
            ..*t
        })
        .collect();
    Instance::with_void(robots, tasks, inst.beta()).unwrap()
}

/// [`small_instance`] in GRAPE's game ([`into_void`]).
pub fn small_void_instance(rng: &mut ChaCha8Rng, case: usize) -> Instance {
    let inst = small_instance(rng, case);
    into_void(rng, case, &inst)
}

/// The best welfare over all M^N assignments that respect capacities ((M + 1)^N where
/// the instance allows the void task).
pub fn brute_force(inst: &Instance) -> f64 {
    brute_force_completion(
        inst,
        &Assignment::unassigned(inst.num_robots(), inst.num_tasks()),
    )
}

/// The best welfare over all complete assignments that respect capacities and keep
/// the robots assigned in `partial` where they are.
pub fn brute_force_completion(inst: &Instance, partial: &Assignment) -> f64 {
    brute_force_fixing(inst, partial, None)
}

/// [`brute_force_completion`] with robot `out`, if any, in the void.
pub fn brute_force_fixing(inst: &Instance, partial: &Assignment, out: Option<RobotId>) -> f64 {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    let places = m + usize::from(inst.allows_void());
    let mut best = f64::NEG_INFINITY;
    let mut code = vec![0usize; n];
    'outer: loop {
        let tasks = code
            .iter()
            .enumerate()
            .map(|(i, &j)| {
                let robot = RobotId(i as u32);
                let place = (j < m).then_some(TaskId(j as u32));
                if Some(robot) == out {
                    None
                } else {
                    partial.task_of(robot).or(place)
                }
            })
            .collect();
        if let Ok(a) = Assignment::from_tasks(inst, tasks) {
            best = best.max(inst.welfare(&a));
        }
        for digit in code.iter_mut() {
            *digit += 1;
            if *digit < places {
                continue 'outer;
            }
            *digit = 0;
        }
        return best;
    }
}

/// A scarce threshold game: thresholds uniform in [N/M, 2N/M] (about 1.5 N in all), so
/// not every task can be staffed.
pub fn scarce(robots: usize, tasks: usize, seed: u64) -> Instance {
    let (min, max) = afg_game::GameSize { robots, tasks }.scarce_thresholds();
    let mut cfg = GeneratorConfig::paper(robots, tasks, seed);
    cfg.min_team = Some(afg_game::CountRange { min, max });
    cfg.generate().unwrap()
}

/// One task at the origin needing two robots and one unit of skill 0 (capacity 2,
/// reward 10), and a spare task at (0, 1) paying nothing; robots at 0.1, 0.2 and 0.5
/// on the x axis, only the furthest holding the skill. The optimum: robots 0 and 2 at
/// the task, robot 1 at the spare one, worth [`skill_by_hand_welfare`].
pub fn skill_by_hand() -> Instance {
    let task = |y: f64, reward: f64, capacity| Task {
        position: Point::new(0.0, y),
        reward,
        eps: 2.0,
        capacity,
    };
    let robots = [0.1, 0.2, 0.5].map(|x| Point::new(x, 0.0)).to_vec();
    Instance::new(
        robots,
        vec![task(0.0, 10.0, Some(2)), task(1.0, 0.0, None)],
        1.0,
    )
    .unwrap()
    .with_teams(vec![2, 1], &[vec![0], vec![0], vec![1]], &[vec![1], vec![]])
    .unwrap()
}

/// The optimum of [`skill_by_hand`], by hand: F(2) = 10 log2 3 less the three robots'
/// distances.
pub fn skill_by_hand_welfare() -> f64 {
    10.0 * 3f64.log2() - 0.1 - 0.5 - (0.2f64.powi(2) + 1.0).sqrt()
}
