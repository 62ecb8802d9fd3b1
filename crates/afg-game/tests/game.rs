//! Hand-computed values and properties over random instances for afg-game.

mod common;

use afg_game::io::{dataset_to_jsonl, parse_dataset};
use afg_game::{
    Assignment, GOLDEN_RATIO, GameError, GeneratorConfig, Instance, Point, Preference, RobotId,
    TaskId, strictly_better,
};
use proptest::prelude::*;

use common::task;

#[test]
fn coalition_value_of_one_robot_is_the_reward() {
    let inst = Instance::new(
        vec![Point::new(0.0, 0.0)],
        vec![task(0.0, 0.0, 3.7, 2.5)],
        1.0,
    )
    .unwrap();
    assert_eq!(inst.coalition_value(TaskId(0), 0), 0.0);
    assert!((inst.coalition_value(TaskId(0), 1) - 3.7).abs() < 1e-12);
    assert_eq!(inst.marginal_value(TaskId(0), 1), 3.7);
}

#[test]
fn coalition_value_hand_computed() {
    // eps = 3: F(n) = r log3(n + 2). F(7) = r log3(9) = 2r.
    let inst = Instance::new(
        vec![Point::new(0.0, 0.0)],
        vec![task(0.0, 0.0, 5.0, 3.0)],
        1.0,
    )
    .unwrap();
    assert!((inst.coalition_value(TaskId(0), 7) - 10.0).abs() < 1e-12);
    // Marginals agree with differences of values.
    for n in 1..50 {
        let diff = inst.coalition_value(TaskId(0), n) - inst.coalition_value(TaskId(0), n - 1);
        assert!(
            (inst.marginal_value(TaskId(0), n) - diff).abs() < 1e-12,
            "n = {n}"
        );
    }
}

#[test]
fn coalition_value_is_concave_from_the_golden_ratio_on() {
    for eps in [GOLDEN_RATIO, 1.7, 2.0, 4.0, 12.0, 200.0] {
        let inst = Instance::new(
            vec![Point::new(0.0, 0.0)],
            vec![task(0.0, 0.0, 1.0, eps)],
            1.0,
        )
        .unwrap();
        for n in 1..500 {
            let (a, b) = (
                inst.marginal_value(TaskId(0), n),
                inst.marginal_value(TaskId(0), n + 1),
            );
            assert!(
                b <= a + 1e-15,
                "eps = {eps}, n = {n}: marginal {b} after {a}"
            );
            assert!(b > 0.0);
        }
    }
    // Just below φ the second member is worth more than the first: not concave, so rejected.
    let eps: f64 = 1.6;
    assert!((1.0 + 1.0 / eps).ln() / eps.ln() > 1.0);
    assert!(matches!(
        Instance::new(
            vec![Point::new(0.0, 0.0)],
            vec![task(0.0, 0.0, 1.0, eps)],
            1.0
        ),
        Err(GameError::EpsBelowGoldenRatio { task: 0, .. })
    ));
}

#[test]
fn welfare_of_a_small_assignment_by_hand() {
    // Task 0 at the origin, r = 2, eps = 2; task 1 at (1, 1), r = 4, eps = 3; beta = 0.5.
    let robots = vec![
        Point::new(3.0, 4.0),
        Point::new(0.0, 0.0),
        Point::new(1.0, 0.0),
    ];
    let inst = Instance::new(
        robots,
        vec![task(0.0, 0.0, 2.0, 2.0), task(1.0, 1.0, 4.0, 3.0)],
        0.5,
    )
    .unwrap();
    let a = Assignment::from_tasks(
        &inst,
        vec![Some(TaskId(0)), Some(TaskId(0)), Some(TaskId(1))],
    )
    .unwrap();
    // F_0(2) = 2 log2(3); F_1(1) = 4; costs 0.5 * (5 + 0 + 1).
    let expected = 2.0 * 3f64.log2() + 4.0 - 3.0;
    assert!((inst.welfare(&a) - expected).abs() < 1e-12);
    // Sum of utilities is the same number.
    let utilities: f64 = inst
        .robot_ids()
        .map(|i| {
            let j = a.task_of(i).unwrap();
            inst.utility(i, j, a.size(j))
        })
        .sum();
    assert!((utilities - expected).abs() < 1e-12);
    // A partial assignment: robot 2 out, task 1 empty.
    let mut p = a.clone();
    p.set(RobotId(2), None);
    assert!((inst.welfare(&p) - (2.0 * 3f64.log2() - 2.5)).abs() < 1e-12);
    assert!(!p.is_complete() && a.is_complete());
}

#[test]
fn selfish_score_is_the_utility_after_joining() {
    let inst = GeneratorConfig::paper(10, 3, 5).generate().unwrap();
    let mut a = Assignment::unassigned(10, 3);
    for i in 0..10u32 {
        a.set(RobotId(i), Some(TaskId(i % 3)));
    }
    for i in inst.robot_ids() {
        for j in inst.task_ids() {
            let n = a.others_in(i, j) + 1;
            let s = inst.score(&a, i, j, Preference::Selfish);
            assert!((s - inst.utility(i, j, n)).abs() < 1e-12);
        }
    }
}

#[test]
fn same_seed_same_bytes_different_seed_different_instance() {
    let a = GeneratorConfig::paper(60, 5, 11)
        .generate()
        .unwrap()
        .to_json();
    let b = GeneratorConfig::paper(60, 5, 11)
        .generate()
        .unwrap()
        .to_json();
    let c = GeneratorConfig::paper(60, 5, 12)
        .generate()
        .unwrap()
        .to_json();
    assert_eq!(a, b);
    assert_ne!(a, c);
    let caps = GeneratorConfig::paper(60, 5, 11).with_capacity_slack(1.5);
    assert_eq!(
        caps.generate().unwrap().to_json(),
        caps.generate().unwrap().to_json()
    );
}

#[test]
fn generator_follows_the_paper_distribution() {
    let cfg = GeneratorConfig::paper(100, 5, 3).with_capacity_slack(1.5);
    let inst = cfg.generate().unwrap();
    assert_eq!(inst.generator(), Some(&cfg));
    for p in inst.robots() {
        assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y));
    }
    for t in inst.tasks() {
        assert!((20.0..=40.0).contains(&t.reward));
        assert_eq!(t.eps, 20.0);
        assert!((20..=30).contains(&t.capacity.unwrap()));
    }
}

#[test]
fn json_round_trips_instances_assignments_and_datasets() {
    let insts: Vec<Instance> = (0..3)
        .map(|s| {
            GeneratorConfig::paper(7, 3, s)
                .with_capacity_slack(2.0)
                .generate()
                .unwrap()
        })
        .collect();
    for inst in &insts {
        let back = Instance::from_json(&inst.to_json()).unwrap();
        assert_eq!(&back, inst);
        assert_eq!(back.to_json(), inst.to_json());
    }
    assert_eq!(parse_dataset(&dataset_to_jsonl(&insts)).unwrap(), insts);
    let a =
        Assignment::from_tasks(&insts[0], (0..7).map(|i| Some(TaskId(i % 3))).collect()).unwrap();
    assert_eq!(Assignment::from_json(&a.to_json(), &insts[0]).unwrap(), a);
}

#[test]
fn atomic_write_replaces_the_file() {
    let dir = std::env::temp_dir().join(format!("afg-game-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("inst.json");
    let inst = GeneratorConfig::paper(5, 2, 1).generate().unwrap();
    std::fs::write(&path, "old").unwrap();
    inst.write(&path).unwrap();
    assert_eq!(Instance::read(&path).unwrap(), inst);
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "no temporary file left behind"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---- properties ----

/// A random instance (N robots, M tasks, optional capacities) and a random complete
/// assignment of it that respects capacities.
fn instance_and_assignment(max_n: usize) -> impl Strategy<Value = (Instance, Assignment)> {
    (
        1..=max_n,
        1..=4usize,
        any::<u64>(),
        any::<bool>(),
        1.62..8.0f64,
        0.0..2.0f64,
    )
        .prop_flat_map(move |(n, m, seed, caps, eps, beta)| {
            let mut cfg = GeneratorConfig::paper(n, m, seed);
            cfg.eps = eps;
            cfg.beta = beta;
            if caps {
                cfg = cfg.with_capacity_slack(1.6);
            }
            let inst = cfg.generate().unwrap();
            proptest::collection::vec(any::<u32>(), n).prop_map(move |choices| {
                // Fill robots in order, each into its drawn task or the next one with room.
                let mut a = Assignment::unassigned(n, m);
                for (i, c) in choices.into_iter().enumerate() {
                    let start = c as usize % m;
                    let j = (0..m)
                        .map(|k| TaskId(((start + k) % m) as u32))
                        .find(|&j| a.has_room(&inst, RobotId(i as u32), j))
                        .unwrap();
                    a.set(RobotId(i as u32), Some(j));
                }
                (inst.clone(), a)
            })
        })
}

/// Every single-robot move with room: (robot, from, to).
fn single_moves(inst: &Instance, a: &Assignment) -> Vec<(RobotId, TaskId)> {
    inst.robot_ids()
        .flat_map(|i| inst.task_ids().map(move |j| (i, j)))
        .filter(|&(i, j)| a.task_of(i) != Some(j) && a.has_room(inst, i, j))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn balanced_move_changes_welfare_by_the_score_difference((inst, a) in instance_and_assignment(12)) {
        let before = inst.welfare(&a);
        for (i, j) in single_moves(&inst, &a) {
            let k = a.task_of(i).unwrap();
            let predicted = inst.score(&a, i, j, Preference::Balanced) - inst.score(&a, i, k, Preference::Balanced);
            let mut b = a.clone();
            b.set(i, Some(j));
            let actual = inst.welfare(&b) - before;
            prop_assert!((predicted - actual).abs() < 1e-9 * (1.0 + before.abs()), "{predicted} vs {actual}");
            // A move the balanced rule accepts raises welfare by exactly that difference.
            if strictly_better(inst.score(&a, i, j, Preference::Balanced), inst.score(&a, i, k, Preference::Balanced)) {
                prop_assert!(actual > 0.0);
            }
        }
    }

    #[test]
    fn balanced_stable_iff_no_single_move_raises_welfare((inst, a) in instance_and_assignment(6)) {
        let before = inst.welfare(&a);
        let tol = 1e-9 * before.abs().max(1.0);
        let improving = single_moves(&inst, &a).into_iter().any(|(i, j)| {
            let mut b = a.clone();
            b.set(i, Some(j));
            inst.welfare(&b) > before + tol
        });
        prop_assert_eq!(inst.is_stable(&a, Preference::Balanced), !improving);
    }

    #[test]
    fn ns_rate_counts_satisfied_robots((inst, a) in instance_and_assignment(10)) {
        for pref in [Preference::Balanced, Preference::Selfish] {
            let rate = inst.ns_rate(&a, pref);
            prop_assert!((0.0..=1.0).contains(&rate));
            prop_assert_eq!(rate == 1.0, inst.is_stable(&a, pref));
        }
    }
}
