//! Training: targets, a smoke run, bit-identical resume, bad checkpoints.

use std::path::PathBuf;

use afg_baseline::{Allocator, Greedy, Optimum};
use afg_game::{Assignment, GeneratorConfig, Instance, TaskId};
use afg_graph::{AllocationState, GraphKind, RobotGraph, Units};
use afg_learn::{
    InferBackend, LearnError,
    env::{Shaping, n_step_reward},
    nets::{AfgNetConfig, GraphTensors, NetworkConfig, QNetwork, parameter_values},
    policy::LearnedPolicy,
    run::{LogEvent, RunDir},
    train::{Algo, Session, TrainConfig, Trainer, double_dqn_target, dqn_target},
};
use proptest::prelude::*;

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

fn tiny(algo: Algo, net: NetworkConfig, steps: u64) -> TrainConfig {
    let mut c = TrainConfig::new(10, algo, net, steps, 3);
    c.batch = 32;
    c.parallel_envs = 4;
    c.warmup = 64;
    c.replay_capacity = 2_000;
    c.validation_instances = 4;
    c.validate_every = steps / 2;
    c.target_sync = 10;
    c
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("afg-train-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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

fn run_to(trainer: &mut Trainer, steps: u64) {
    while trainer.steps_done() < steps {
        trainer.step().unwrap();
    }
}

#[test]
fn a_diverging_run_stops_with_a_clear_error_and_unchanged_weights() {
    let mut c = tiny(Algo::Dqn, NetworkConfig::afgnet(5, 3), 200);
    (c.lr, c.lr_decay, c.huber, c.grad_clip) = (1e30, false, false, None);
    let mut t = Trainer::new(c).unwrap();
    let err = loop {
        let before = values(&t.network());
        match t.step() {
            Ok(_) => continue,
            Err(e) => {
                assert_eq!(values(&t.network()), before, "weights changed");
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
    let before = values(&t.network());
    let err = t.step().unwrap_err();
    assert!(
        matches!(err, LearnError::NonFiniteWeights { step: 1 }),
        "{err}"
    );
    assert!(err.to_string().contains("NaN or infinite"), "{err}");
    assert_eq!(values(&t.network()), before, "weights changed");
}

fn values(net: &QNetwork<InferBackend>) -> Vec<u32> {
    parameter_values(net)
        .into_iter()
        .map(f32::to_bits)
        .collect()
}

#[test]
fn resumed_run_ends_with_bit_identical_weights() {
    let config = tiny(Algo::Ddqn, NetworkConfig::afgnet(5, 2), 60);
    let mut straight = Trainer::new(config.clone()).unwrap();
    run_to(&mut straight, 60);

    let dir = temp_dir("resume");
    let mut first = Trainer::new(config).unwrap();
    run_to(&mut first, 25);
    first.save_checkpoint(&dir).unwrap();
    drop(first); // "killed"
    let mut resumed = Trainer::resume(&dir).unwrap();
    assert_eq!(resumed.steps_done(), 25);
    run_to(&mut resumed, 60);
    assert_eq!(values(&resumed.network()), values(&straight.network()));
    // A later checkpoint replaces the earlier one.
    resumed.save_checkpoint(&dir).unwrap();
    assert_eq!(Trainer::resume(&dir).unwrap().steps_done(), 60);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_session_logs_and_saves_its_run_and_refuses_a_second_writer() {
    let dir = temp_dir("session").join("run");
    let config = tiny(Algo::Ddqn, NetworkConfig::s2v(5, 4), 40);
    let mut session = Session::start(&dir, config.clone(), Some("abc".into())).unwrap();
    // The directory is locked while the session lives.
    assert!(matches!(
        Session::resume(&dir),
        Err(LearnError::RunInUse { .. })
    ));
    let mut seen = 0;
    let v = session
        .run(std::time::Duration::from_secs(3600), |r| {
            seen += 1;
            assert_eq!(r.step, seen);
        })
        .unwrap();
    assert_eq!(seen, 40);
    drop(session);
    let run = RunDir::new(&dir);
    let log = run.log().unwrap();
    let LogEvent::Start {
        version,
        config: logged,
        git_revision,
        baselines,
    } = &log[0]
    else {
        panic!("the log starts with {:?}", log[0]);
    };
    assert_eq!(
        (**logged == config, git_revision.as_deref(), *version),
        (true, Some("abc"), afg_learn::run::RUN_FORMAT_VERSION)
    );
    assert!(baselines[&afg_baseline::Method::Opt] >= baselines[&afg_baseline::Method::Greedy]);
    let steps: Vec<u64> = log
        .iter()
        .filter(|e| matches!(e, LogEvent::Step { .. }))
        .map(|e| e.step().unwrap())
        .collect();
    assert_eq!(steps, [10, 20, 30, 40]);
    let validations = log
        .iter()
        .filter(|e| matches!(e, LogEvent::Validation(_)))
        .count();
    assert_eq!(validations, 2);
    assert!(matches!(log.last(), Some(LogEvent::End { step: 40, .. })));
    let manifest = run.manifest_from_log("train it".into()).unwrap();
    assert_eq!(
        (manifest.command.as_str(), manifest.seed, manifest.kind()),
        ("train it", config.seed, afg_learn::run::ModelKind::QNetwork)
    );
    assert_eq!(manifest.git_revision.as_deref(), Some("abc"));
    let afg_learn::run::RunRecord::QNetwork {
        steps,
        final_validation,
    } = manifest.record
    else {
        unreachable!("a Q network's run")
    };
    assert_eq!((steps, final_validation.map(|v| v.step)), (40, Some(40)));
    // The final weights are the trainer's: the same validation.
    let policy = LearnedPolicy::load(&run.weights()).unwrap();
    assert_eq!(policy.config(), &config.network);
    assert_eq!(Trainer::resume(&dir).unwrap().validate().unwrap(), v);
    // A second run into the same directory is refused; resuming a finished one is not.
    assert!(Session::start(&dir, config, None).is_err());
    Session::resume(&dir).unwrap();
    std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
}

#[test]
fn truncated_or_missing_checkpoints_are_clear_errors() {
    let dir = temp_dir("bad");
    assert!(matches!(
        Trainer::resume(&dir),
        Err(LearnError::Checkpoint { .. })
    ));
    let mut t = Trainer::new(tiny(Algo::Dqn, NetworkConfig::s2v(5, 0), 20)).unwrap();
    run_to(&mut t, 5);
    t.save_checkpoint(&dir).unwrap();
    let state = dir.join("checkpoint/state.json");
    let text = std::fs::read_to_string(&state).unwrap();
    std::fs::write(&state, &text[..text.len() / 2]).unwrap();
    let err = Trainer::resume(&dir).err().unwrap();
    assert!(err.to_string().contains("corrupt or truncated"), "{err}");
    std::fs::write(&state, &text).unwrap();
    let optim = dir.join("checkpoint/optim.mpk");
    let bytes = std::fs::read(&optim).unwrap();
    std::fs::write(&optim, &bytes[..bytes.len() / 3]).unwrap();
    assert!(matches!(
        Trainer::resume(&dir),
        Err(LearnError::Weights { .. })
    ));
    std::fs::write(&optim, &bytes).unwrap();
    // A state that parses but cannot be this run's: an action beyond M, an episode of
    // the wrong length, an unknown field.
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 3] = [
        ("takes task 9", |v| v["running"][0]["actions"][0] = 9.into()),
        ("has 11 actions", |v| {
            let actions = v["running"][0]["actions"].as_array_mut().unwrap();
            actions.resize(11, 0.into());
        }),
        ("unknown field", |v| v["extra"] = 1.into()),
    ];
    for (says, edit) in edits {
        let mut v = value.clone();
        edit(&mut v);
        std::fs::write(&state, v.to_string()).unwrap();
        let err = Trainer::resume(&dir).err().unwrap();
        assert!(err.to_string().contains(says), "{says}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_broken_checkpoint_falls_back_to_the_previous_one() {
    let config = tiny(Algo::Dqn, NetworkConfig::s2v(5, 0), 30);
    let dir = temp_dir("fallback");
    let mut t = Trainer::new(config.clone()).unwrap();
    run_to(&mut t, 10);
    t.save_checkpoint(&dir).unwrap();
    run_to(&mut t, 20);
    t.save_checkpoint(&dir).unwrap();
    assert!(
        dir.join("checkpoint.old").exists(),
        "the previous one is kept"
    );
    assert_eq!(Trainer::resume(&dir).unwrap().steps_done(), 20);
    // The newest truncated (as by a full disk), or gone (a crash between the renames).
    let state = dir.join("checkpoint/state.json");
    std::fs::write(&state, "{\"format\":").unwrap();
    assert_eq!(Trainer::resume(&dir).unwrap().steps_done(), 10);
    std::fs::remove_dir_all(dir.join("checkpoint")).unwrap();
    let mut resumed = Trainer::resume(&dir).unwrap();
    assert_eq!(resumed.steps_done(), 10);
    // And the run from the older one ends where an uninterrupted run does.
    run_to(&mut resumed, 30);
    let mut straight = Trainer::new(config).unwrap();
    run_to(&mut straight, 30);
    assert_eq!(values(&resumed.network()), values(&straight.network()));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_run_stopped_before_its_first_checkpoint_starts_again_on_resume() {
    let dir = temp_dir("early").join("run");
    let config = tiny(Algo::Ddqn, NetworkConfig::s2v(5, 4), 20);
    drop(Session::start(&dir, config.clone(), None).unwrap()); // killed at once
    assert!(!dir.join("checkpoint").exists());
    let mut session = Session::resume(&dir).unwrap();
    assert_eq!(session.trainer().steps_done(), 0);
    session
        .run(std::time::Duration::from_secs(3600), |_| {})
        .unwrap();
    let mut straight = Trainer::new(config).unwrap();
    run_to(&mut straight, 20);
    assert_eq!(
        values(&session.trainer().network()),
        values(&straight.network())
    );
    std::fs::remove_dir_all(dir.parent().unwrap()).unwrap();
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
