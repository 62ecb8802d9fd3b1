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
        let mut s = AllocationState::new(&inst);
        // A sequential episode, then some re-moves (as repair dynamics would make).
        let order: Vec<RobotId> = inst.robot_ids().chain((0..n).map(|_| RobotId(rng.random_range(0..n as u32)))).collect();
        for i in order {
            let open: Vec<TaskId> = inst.task_ids().filter(|&j| s.is_available(i, j)).collect();
            let j = open[rng.random_range(0..open.len())];
            s.assign(i, j);
            let rebuilt = AllocationState::from_assignment(&inst, s.assignment().clone());
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
        let mut s = AllocationState::with_units(&inst, Assignment::unassigned(8, 3), units);
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
