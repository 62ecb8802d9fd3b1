//! Incremental features equal a full rebuild; hand-checked feature values.

use afg_game::{Assignment, GeneratorConfig, Preference, RobotId, TaskId};
use afg_graph::{AllocationState, Units, feature_scale};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn incremental_update_equals_rebuild(n in 1..40usize, m in 1..6usize, seed in any::<u64>(), caps in any::<bool>()) {
        let mut cfg = GeneratorConfig::paper(n, m, seed);
        if caps {
            cfg = cfg.with_capacity_slack(1.2);
        }
        let inst = cfg.generate().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut s = AllocationState::new(&inst, afg_graph::Units::Bounded);
        // A sequential episode, then some re-moves (as repair dynamics would make).
        let order: Vec<RobotId> = inst.robot_ids().chain((0..n).map(|_| RobotId(rng.random_range(0..n as u32)))).collect();
        for i in order {
            let open: Vec<TaskId> = inst.task_ids().filter(|&j| s.is_available(i, j)).collect();
            let j = open[rng.random_range(0..open.len())];
            s.assign(i, j);
            let rebuilt = AllocationState::from_assignment(&inst, s.assignment().clone(), afg_graph::Units::Bounded);
            prop_assert_eq!(&s, &rebuilt);
        }
    }
}

#[test]
fn features_match_the_utility_definition() {
    let inst = GeneratorConfig::paper(8, 3, 4)
        .with_capacity_slack(1.0)
        .generate()
        .unwrap();
    // Mean-reward units divide by the mean of r_j; scale-free ones by β (= 1 here).
    let mean_reward = inst.tasks().iter().map(|t| t.reward).sum::<f64>() / 3.0;
    assert_eq!(feature_scale(&inst), mean_reward);
    for (units, scale, full) in [
        (Units::MeanReward, mean_reward, -1.0),
        (Units::ScaleFree, inst.beta(), -2.0),
    ] {
        // (Bounded units only cap the share of nearly empty tasks: a test of its own.)
        let mut s = AllocationState::from_assignment(&inst, Assignment::unassigned(8, 3), units);
        for i in 0..8u32 {
            let j = TaskId(i % 3);
            if s.is_available(RobotId(i), j) {
                s.assign(RobotId(i), j);
            }
        }
        let a: &Assignment = s.assignment();
        for i in inst.robot_ids() {
            for j in inst.task_ids() {
                let others = a.others_in(i, j);
                let got = s.mu(i)[j.index()];
                if others >= inst.capacity(j) {
                    assert_eq!(got, full);
                    assert!(!s.action_mask(i)[j.index()]);
                } else {
                    let want = inst.utility(i, j, others + 1) / scale;
                    assert!((got as f64 - want).abs() < 1e-6, "{got} vs {want}");
                    // Same as the selfish score of afg-game.
                    assert!((inst.score(a, i, j, Preference::Selfish) / scale - want).abs() < 1e-9);
                }
            }
        }
    }
}

#[test]
fn bounded_units_cap_the_value_part_only() {
    // One task with r = 30, eps = 5: the cap is 4 · 30 / 5 = 24. An empty task's share
    // is F(1) = r = 30, capped to 24; with two members a newcomer's share is
    // F(3)/3 = 30 · log_5(7) / 3 ≈ 12.09, below the cap.
    let task = afg_game::Task {
        position: afg_game::Point::new(1.0, 0.0),
        reward: 30.0,
        eps: 5.0,
        capacity: None,
    };
    let robots = vec![afg_game::Point::new(0.0, 0.0); 3];
    let inst = afg_game::Instance::new(robots, vec![task], 1.0).unwrap();
    let empty =
        AllocationState::from_assignment(&inst, Assignment::unassigned(3, 1), Units::Bounded);
    assert!((f64::from(empty.mu(RobotId(0))[0]) - (24.0 - 1.0)).abs() < 1e-5);
    let free =
        AllocationState::from_assignment(&inst, Assignment::unassigned(3, 1), Units::ScaleFree);
    assert!((f64::from(free.mu(RobotId(0))[0]) - (30.0 - 1.0)).abs() < 1e-5);
    let mut two = Assignment::unassigned(3, 1);
    two.set(RobotId(0), Some(TaskId(0)));
    two.set(RobotId(1), Some(TaskId(0)));
    let s = AllocationState::from_assignment(&inst, two, Units::Bounded);
    let want = 30.0 * 7f64.ln() / 5f64.ln() / 3.0 - 1.0;
    assert!((f64::from(s.mu(RobotId(2))[0]) - want).abs() < 1e-5);
}

#[test]
fn a_batch_carries_the_actors_costs_and_the_tasks_summaries() {
    use afg_graph::{GraphBatch, GraphKind, PriceState, RobotGraph, TASK_FEATURES};
    let inst = GeneratorConfig::paper(30, 5, 4).generate().unwrap();
    let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    let mut a = Assignment::unassigned(30, 5);
    for i in 0..12u32 {
        a.set(RobotId(i), Some(TaskId((i * 7) % 5)));
    }
    // One batch per units: a batch holds states in its own units only.
    let mut batches = Vec::new();
    for units in [Units::MeanReward, Units::Bounded] {
        let state = AllocationState::from_assignment(&inst, a.clone(), units);
        let (mut batch, mut plain) = (
            GraphBatch::with_task_summaries(5, units),
            GraphBatch::new(5, units),
        );
        for _ in 0..2 {
            batch.push(&graph, &state, RobotId(12));
            plain.push(&graph, &state, RobotId(12));
        }
        // Without summaries the batch is the same but for them.
        assert!(plain.task_inputs.is_empty());
        assert_eq!(
            GraphBatch {
                task_inputs: Vec::new(),
                task_summaries: false,
                ..batch.clone()
            },
            plain
        );
        batches.push(batch);
    }
    // Costs: β d(12, j) in each state's welfare unit (the mean reward, then β = 1).
    for (batch, unit) in batches.iter().zip([feature_scale(&inst), 1.0]) {
        for g in 0..2 {
            for j in 0..5 {
                let by_hand = inst.distance(RobotId(12), TaskId(j as u32)) / unit;
                assert!((f64::from(batch.cost[g * 5 + j]) - by_hand).abs() < 1e-6);
            }
        }
    }
    // A state in other units than the batch's is refused.
    let bounded = AllocationState::from_assignment(&inst, a.clone(), Units::Bounded);
    let refused = std::panic::catch_unwind(|| {
        GraphBatch::new(5, Units::MeanReward).push(&graph, &bounded, RobotId(12))
    });
    assert!(refused.is_err());
    // Task summaries: the same for both units, and those of the robots placed in
    // order; after each task's own features comes the mean over the tasks.
    let batch = &batches[0];
    assert_eq!(batches[0].task_inputs, batches[1].task_inputs);
    let mut sequential = PriceState::new(&inst);
    for i in 0..12u32 {
        sequential.assign(RobotId(i), TaskId((i * 7) % 5));
    }
    let mut f = vec![0.0; 5 * TASK_FEATURES];
    sequential.features(&mut f);
    let width = 2 * TASK_FEATURES;
    assert_eq!(batch.task_inputs.len(), 2 * 5 * width);
    for g in 0..2 {
        for j in 0..5 {
            let row = &batch.task_inputs[(g * 5 + j) * width..(g * 5 + j + 1) * width];
            assert_eq!(
                &row[..TASK_FEATURES],
                &f[j * TASK_FEATURES..(j + 1) * TASK_FEATURES]
            );
            let mean_occupancy = (0..5).map(|k| f[k * TASK_FEATURES + 1]).sum::<f32>() / 5.0;
            assert!((row[TASK_FEATURES + 1] - mean_occupancy).abs() < 1e-6);
        }
    }
}
