//! GRAPE's game: robots may join the void task (no coalition, utility 0). The format,
//! welfare and stability with the void move, against brute force over every one of the
//! (M + 1)^N assignments of small instances.

use afg_game::{Assignment, GeneratorConfig, Instance, Point, Preference, RobotId, Task, TaskId};
use afg_game::{GameError, strictly_better};
use proptest::prelude::*;

/// A small instance of GRAPE's game from the paper's distribution, with capacities
/// that may hold fewer robots than there are.
fn small_void(n: usize, m: usize, seed: u64, capacity: Option<usize>) -> Instance {
    let inst = GeneratorConfig::paper(n, m, seed).generate().unwrap();
    let tasks = inst
        .tasks()
        .iter()
        .map(|t| Task { capacity, ..*t })
        .collect();
    // Far-away robots make some places worth less than nothing.
    let robots = inst
        .robots()
        .iter()
        .map(|p| Point::new(3.0 * p.x, 3.0 * p.y))
        .collect();
    Instance::with_void(robots, tasks, inst.beta()).unwrap()
}

/// Every assignment of `inst` that respects the capacities, robots in the void too.
fn all_assignments(inst: &Instance) -> Vec<Assignment> {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    let mut out = Vec::new();
    for code in 0..(m + 1).pow(n as u32) {
        let tasks = (0..n)
            .map(|i| {
                let t = code / (m + 1).pow(i as u32) % (m + 1);
                (t < m).then_some(TaskId(t as u32))
            })
            .collect();
        if let Ok(a) = Assignment::from_tasks(inst, tasks) {
            out.push(a);
        }
    }
    out
}

/// Robot i's score in each place it could move to, by the definitions: tasks with room
/// (its own excluded) by the preference's rule, the void task at 0 when it is in one.
fn alternatives(
    inst: &Instance,
    a: &Assignment,
    i: RobotId,
    pref: Preference,
) -> Vec<(Option<TaskId>, f64)> {
    let mut out: Vec<(Option<TaskId>, f64)> = inst
        .task_ids()
        .filter(|&j| Some(j) != a.task_of(i) && a.others_in(i, j) < inst.capacity(j))
        .map(|j| {
            let k = a.others_in(i, j) + 1;
            let value = match pref {
                Preference::Balanced => inst.coalition_value(j, k) - inst.coalition_value(j, k - 1),
                Preference::Selfish => inst.coalition_value(j, k) / k as f64,
            };
            (Some(j), value - inst.cost(i, j))
        })
        .collect();
    if a.task_of(i).is_some() {
        out.push((None, 0.0));
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// A robot is satisfied exactly when no place scores strictly more than its own
    /// (the void's 0 included), and a robot that moves goes to a best place.
    #[test]
    fn stability_with_the_void_move_is_brute_forced(
        n in 1usize..=4, m in 1usize..=2, seed in 0u64..1000, cap in proptest::option::of(1usize..=2),
    ) {
        let inst = small_void(n, m, seed, cap);
        for a in all_assignments(&inst) {
            for pref in [Preference::Balanced, Preference::Selfish] {
                for i in inst.robot_ids() {
                    let here = inst.current_score(&a, i, pref);
                    // By the definitions: in task j with k robots (itself among them),
                    // F_j(k) − F_j(k − 1) balanced or F_j(k) / k selfish, less its travel;
                    // in the void, 0.
                    let here_by_hand = a.task_of(i).map_or(0.0, |j| {
                        let k = a.others_in(i, j) + 1;
                        let value = match pref {
                            Preference::Balanced => inst.coalition_value(j, k) - inst.coalition_value(j, k - 1),
                            Preference::Selfish => inst.coalition_value(j, k) / k as f64,
                        };
                        value - inst.cost(i, j)
                    });
                    prop_assert!((here - here_by_hand).abs() <= 1e-12 * (1.0 + here.abs()), "{} vs {}", here, here_by_hand);
                    let alts = alternatives(&inst, &a, i, pref);
                    let best = alts.iter().map(|&(_, s)| s).fold(f64::NEG_INFINITY, f64::max);
                    let wants = strictly_better(best, here);
                    prop_assert_eq!(inst.is_satisfied(&a, i, pref), !wants);
                    if let Some(to) = inst.best_move(&a, i, pref) {
                        let s = alts.iter().find(|&&(p, _)| p == to).map(|&(_, s)| s);
                        prop_assert!(s.is_some_and(|s| s >= best - 1e-12), "{:?}", to);
                    }
                }
                let stable = inst.robot_ids().all(|i| inst.is_satisfied(&a, i, pref));
                prop_assert_eq!(inst.is_stable(&a, pref), stable);
            }
        }
    }
}

#[test]
fn a_void_robot_adds_nothing_to_welfare_and_an_unprofitable_one_leaves() {
    // Task 0 at the origin worth 1 (eps 2: F(1) = 1); robot 0 beside it, robot 1 far away.
    let task = Task {
        position: Point::new(0.0, 0.0),
        reward: 1.0,
        eps: 2.0,
        capacity: None,
    };
    let robots = vec![Point::new(0.25, 0.0), Point::new(4.0, 0.0)];
    let inst = Instance::with_void(robots, vec![task], 1.0).unwrap();
    let mut a = Assignment::unassigned(2, 1);
    a.set(RobotId(0), Some(TaskId(0)));
    assert_eq!(inst.welfare(&a), 1.0 - 0.25);
    assert!(inst.is_stable(&a, Preference::Balanced));
    a.set(RobotId(1), Some(TaskId(0)));
    // F(2) = log2(3); robot 1 adds log2(3) − 1 − 4 < 0, so it would rather be out.
    assert_eq!(
        inst.best_move(&a, RobotId(1), Preference::Balanced),
        Some(None)
    );
    assert_eq!(inst.ns_rate(&a, Preference::Balanced), 0.5);
}

#[test]
fn the_void_option_round_trips_and_files_of_the_paper_game_are_unchanged() {
    let paper = GeneratorConfig::paper(6, 2, 3).generate().unwrap();
    assert!(!paper.allows_void() && !paper.to_json().contains("allow_void"));
    let void = Instance::with_void(paper.robots().to_vec(), paper.tasks().to_vec(), 1.0).unwrap();
    let text = void.to_json();
    assert!(text.contains(r#""allow_void":true"#), "{text}");
    let back = Instance::from_json(&text).unwrap();
    assert!(back.allows_void());
    assert_eq!(back, void);
    // Less room than robots: refused in the paper's game, allowed with the void.
    let tasks: Vec<Task> = paper
        .tasks()
        .iter()
        .map(|t| Task {
            capacity: Some(1),
            ..*t
        })
        .collect();
    assert!(matches!(
        Instance::new(paper.robots().to_vec(), tasks.clone(), 1.0),
        Err(GameError::CapacityTooSmall { .. })
    ));
    assert!(Instance::with_void(paper.robots().to_vec(), tasks, 1.0).is_ok());
}

#[test]
fn assignment_files_write_minus_one_and_read_it_and_null() {
    let inst = GeneratorConfig::paper(3, 2, 1).generate().unwrap();
    let mut a = Assignment::unassigned(3, 2);
    a.set(RobotId(1), Some(TaskId(1)));
    assert!(a.to_json().contains(r#""tasks":[-1,1,-1]"#));
    let old = r#"{"format":"afg-assignment","version":1,"tasks":[null,1,null]}"#;
    assert_eq!(Assignment::from_json(old, &inst).unwrap(), a);
    let bad = r#"{"format":"afg-assignment","version":1,"tasks":[0,-2,1]}"#;
    let err = Assignment::from_json(bad, &inst).unwrap_err();
    assert!(err.to_string().contains("robot 1 has task -2"), "{err}");
}
