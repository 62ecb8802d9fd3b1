//! Training: targets, a smoke run, diverging runs, settings, the price loss, shaping.

mod tiny_runs;

use afg_baseline::{Allocator, Greedy, Optimum};
use afg_game::{Assignment, GeneratorConfig, Instance, TaskId};
use afg_graph::{AllocationState, GraphKind, RobotGraph, Units};
use afg_learn::{
    InferBackend, LearnError,
    env::{Shaping, n_step_reward},
    nets::{AfgNetConfig, GraphTensors, NetworkConfig, QNetwork},
    train::{Algo, TrainConfig, Trainer, double_dqn_target, dqn_target},
};
use proptest::prelude::*;

use tiny_runs::{tiny, weight_bits};

#[test]
fn dqn_and_double_dqn_targets_differ_where_the_nets_disagree() {
    // Online prefers action 2; target prefers action 0.
    let online = [1.0, 0.0, 4.0];
    let target = [6.0, 2.0, 3.0];
    let mask = [true, true, true];
    assert_eq!(dqn_target(0.5, &target, &mask, false), 6.5);
    assert_eq!(double_dqn_target(0.5, &online, &target, &mask, false), 3.5);
    // Masked actions are never chosen, by either rule.
    let mask = [false, true, false];
    assert_eq!(dqn_target(0.5, &target, &mask, false), 2.5);
    assert_eq!(double_dqn_target(0.5, &online, &target, &mask, false), 2.5);
    // Terminal transitions do not bootstrap.
    assert_eq!(dqn_target(-1.0, &target, &[true; 3], true), -1.0);
    assert_eq!(
        double_dqn_target(-1.0, &online, &target, &[true; 3], true),
        -1.0
    );
}

#[test]
fn smoke_run_has_finite_losses_and_validations() {
    for (algo, net) in [
        (Algo::Ddqn, NetworkConfig::afgnet(5, 1)),
        (Algo::Dqn, NetworkConfig::s2v(5, 1)),
        (Algo::QStar, NetworkConfig::afgnet(5, 1)),
    ] {
        let mut t = Trainer::new(tiny(algo, net, 200)).unwrap();
        let (mut losses, mut validations) = (Vec::new(), Vec::new());
        while !t.is_finished() {
            let report = t.step().unwrap();
            losses.push(report.loss);
            if let Some(result) = report.validation {
                assert!((0.0..=1.0).contains(&result.largest_task_share));
                validations.push((result.welfare, result.percent_of_opt))
            }
        }
        assert_eq!(t.steps_done(), 200);
        assert!(matches!(t.step(), Err(LearnError::InvalidConfig(_))));
        assert_eq!(losses.len(), 200);
        assert!(losses.iter().all(|l| l.is_finite()));
        assert_eq!(validations.len(), 2);
        assert!(
            validations
                .iter()
                .all(|(w, p)| w.is_finite() && *p <= 100.0 + 1e-9)
        );
        assert!(t.replay_len() <= 2_000);
    }
}

#[test]
fn a_diverging_run_stops_with_a_clear_error_and_unchanged_weights() {
    let mut c = tiny(Algo::Dqn, NetworkConfig::afgnet(5, 3), 200);
    (c.lr, c.lr_decay, c.huber, c.grad_clip) = (1e30, false, false, None);
    let mut t = Trainer::new(c).unwrap();
    let err = loop {
        let before = weight_bits(&t.network());
        match t.step() {
            Ok(_) => continue,
            Err(e) => {
                assert_eq!(weight_bits(&t.network()), before, "weights changed");
                break e;
            }
        }
    };
    assert!(matches!(err, LearnError::NonFiniteLoss { .. }), "{err}");
    assert!(err.to_string().contains("lower learning rate"), "{err}");
}

/// A step whose loss is finite but whose update overflows a weight is refused too,
/// before the weights change (a learning rate of 1e300 overflows f32 at once).
#[test]
fn an_update_that_overflows_a_weight_stops_with_unchanged_weights() {
    let mut c = tiny(Algo::Dqn, NetworkConfig::afgnet(5, 3), 200);
    (c.lr, c.lr_decay) = (1e300, false);
    let mut t = Trainer::new(c).unwrap();
    let before = weight_bits(&t.network());
    let err = t.step().unwrap_err();
    assert!(
        matches!(err, LearnError::NonFiniteWeights { step: 1 }),
        "{err}"
    );
    assert!(err.to_string().contains("NaN or infinite"), "{err}");
    assert_eq!(weight_bits(&t.network()), before, "weights changed");
}

#[test]
fn bad_settings_are_refused() {
    let base = tiny(Algo::Dqn, NetworkConfig::afgnet(5, 0), 20);
    // Sizes that would allocate without bound.
    for edit in [
        |c: &mut TrainConfig| (c.robots, c.replay_capacity) = (200_000, 1_000_000),
        |c: &mut TrainConfig| c.validation_instances = 1 << 40,
    ] {
        let mut c = base.clone();
        edit(&mut c);
        let err = Trainer::new(c).err().unwrap();
        assert!(err.to_string().contains("at most"), "{err}");
    }
    // Run seeds that would reach the demonstrations' or the validation set's seeds.
    for seed in [1 << 29, 1 << 30] {
        let mut c = base.clone();
        c.seed = seed;
        let err = Trainer::new(c).err().unwrap();
        assert!(err.to_string().contains("validation set"), "{err}");
    }
    let mut c = base.clone();
    c.robots = 1;
    assert!(matches!(Trainer::new(c), Err(LearnError::InvalidConfig(_))));
    let mut c = base.clone();
    c.eps_end = 1.5;
    assert!(matches!(Trainer::new(c), Err(LearnError::InvalidConfig(_))));
    let mut c = base.clone();
    c.lr = 0.0;
    assert!(Trainer::new(c).is_err());
    let mut c = base.clone();
    c.n_step = 0;
    assert!(matches!(Trainer::new(c), Err(LearnError::InvalidConfig(_))));
    let mut c = base;
    c.price_loss = 1.0;
    assert!(
        matches!(Trainer::new(c.clone()), Err(LearnError::InvalidConfig(e)) if e.contains("price head"))
    );
    c.network = price_headed();
    assert!(c.check().is_ok());
    for bad in [-1.0, f64::NAN, f64::INFINITY] {
        c.price_loss = bad;
        assert!(
            matches!(c.check(), Err(LearnError::InvalidConfig(_))),
            "{bad}"
        );
    }
}

fn price_headed() -> NetworkConfig {
    NetworkConfig::AfgNet(
        AfgNetConfig::new(5, afg_graph::Units::MeanReward)
            .with_seed(1)
            .with_price_head(true),
    )
}

/// Mean squared error, over every robot and task of `insts`, of the centred one-shot
/// scores `Q(s_0, i, j) + β d(i, j)` against the centred exact prices (both in the
/// network's welfare unit).
fn one_shot_price_error(network: &QNetwork<InferBackend>, insts: &[Instance]) -> f64 {
    let device = Default::default();
    let centre = |v: &mut [f64]| {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        v.iter_mut().for_each(|x| *x -= mean);
    };
    let (mut sum, mut count) = (0.0, 0);
    for inst in insts {
        let (n, m) = (inst.num_robots(), inst.num_tasks());
        let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
        let state =
            AllocationState::from_assignment(inst, Assignment::unassigned(n, m), network.units());
        let mut batch = network.empty_batch(m);
        for robot in inst.robot_ids() {
            batch.push(&graph, &state, robot);
        }
        let q: Vec<f32> = network
            .forward(&GraphTensors::new(&batch, &device))
            .into_data()
            .to_vec()
            .unwrap();
        let unit = network.units().welfare_unit(inst);
        let (_, mut prices) = Optimum.with_prices(inst);
        prices.iter_mut().for_each(|p| *p /= unit);
        centre(&mut prices);
        for row in 0..n {
            let mut scores: Vec<f64> = (0..m)
                .map(|j| f64::from(q[row * m + j] + batch.cost[row * m + j]))
                .collect();
            centre(&mut scores);
            sum += scores
                .iter()
                .zip(&prices)
                .map(|(s, p)| (s - p).powi(2))
                .sum::<f64>();
            count += m;
        }
    }
    sum / count as f64
}

#[test]
fn the_price_loss_fits_the_one_shot_scores_to_the_exact_prices() {
    let insts: Vec<Instance> = (0..8)
        .map(|s| GeneratorConfig::paper(10, 5, 900 + s).generate().unwrap())
        .collect();
    let untrained = one_shot_price_error(&price_headed().init(&Default::default()), &insts);
    let trained = |weight: f64| {
        let mut c = tiny(Algo::QStar, price_headed(), 80);
        c.price_loss = weight;
        let mut t = Trainer::new(c).unwrap();
        while !t.is_finished() {
            assert!(t.step().unwrap().loss.is_finite());
        }
        one_shot_price_error(&t.network(), &insts)
    };
    let (with, without) = (trained(10.0), trained(0.0));
    assert!(
        with < 0.5 * untrained && with < without,
        "untrained {untrained}, Q* only {without}, with the price loss {with}"
    );
}

#[test]
fn epsilon_decays_linearly_then_stays() {
    let c = TrainConfig::new(20, Algo::Ddqn, NetworkConfig::afgnet(5, 0), 1000, 0);
    assert_eq!(c.epsilon(0), 1.0);
    assert!((c.epsilon(50) - 0.525).abs() < 1e-12);
    assert!((c.epsilon(100) - 0.05).abs() < 1e-12);
    assert!((c.epsilon(900) - 0.05).abs() < 1e-12);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// n-step rewards add up: splitting an episode into chunks of any length gives the
    /// same total, which is the final welfare unshaped and the final welfare minus the
    /// greedy allocation's or the optimum's shaped (the potential telescopes).
    #[test]
    fn n_step_rewards_telescope(seed in 0u64..1000, n in 2usize..12, m in 1usize..5,
                                chunk in 1usize..6, picks in prop::collection::vec(0u32..5, 12)) {
        let inst = GeneratorConfig::paper(n, m, seed).with_capacity_slack(1.5).generate().unwrap();
        // A feasible episode: each robot takes its pick, or the next task with room.
        let mut a = Assignment::unassigned(n, m);
        let mut actions = Vec::new();
        for (i, pick) in picks.iter().take(n).enumerate() {
            let robot = afg_game::RobotId(i as u32);
            let task = (0..m as u32)
                .map(|k| TaskId((pick + k) % m as u32))
                .find(|&j| a.has_room(&inst, robot, j))
                .unwrap();
            a.set(robot, Some(task));
            actions.push(task);
        }
        let greedy = inst.welfare(&Greedy.allocate(&inst).unwrap().assignment);
        let opt = inst.welfare(&Optimum.allocate(&inst).unwrap().assignment);
        for (shaping, completed) in [(Shaping::None, 0.0), (Shaping::Greedy, greedy), (Shaping::Optimal, opt)] {
            let mut state = Assignment::unassigned(n, m);
            let mut total = 0.0;
            for start in (0..n).step_by(chunk) {
                let end = (start + chunk).min(n);
                total += n_step_reward(&inst, &mut state, start, &actions[start..end], shaping);
            }
            prop_assert_eq!(&state, &a);
            let want = inst.welfare(&a) - completed;
            prop_assert!((total - want).abs() < 1e-9 * want.abs().max(1.0), "{} vs {}", total, want);
        }
    }
}

#[test]
fn scale_free_and_shaped_runs_train() {
    let net = NetworkConfig::afgnet(5, 1).with_units(Units::ScaleFree);
    let mut c = tiny(Algo::Ddqn, net, 60);
    c.shaping = Shaping::Greedy;
    c.n_step = 3;
    let mut t = Trainer::new(c).unwrap();
    let mut losses = Vec::new();
    while !t.is_finished() {
        losses.push(t.step().unwrap().loss);
    }
    assert_eq!(losses.len(), 60);
    assert!(losses.iter().all(|l| l.is_finite()));
    assert_eq!(t.network().units(), Units::ScaleFree);
}

#[test]
fn the_gain_residual_refuses_shaping() {
    let net = NetworkConfig::AfgNet(
        afg_learn::nets::AfgNetConfig::new(5, afg_graph::Units::MeanReward)
            .with_gain_residual(true),
    );
    let mut c = tiny(Algo::Ddqn, net, 10);
    for shaping in [Shaping::Greedy, Shaping::Optimal] {
        c.shaping = shaping;
        assert!(matches!(c.check(), Err(LearnError::InvalidConfig(_))));
    }
}
