//! Training: targets, a smoke run, bit-identical resume, bad checkpoints.

use std::path::PathBuf;

use afg_learn::{
    Algo, InferBackend, LearnError, NetworkConfig, QNetwork, TrainConfig, TrainEvent, Trainer,
    double_dqn_target, dqn_target,
};
use burn::module::{Module, ModuleVisitor, Param};
use burn::tensor::Tensor;
use burn::tensor::backend::Backend;

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
    ] {
        let mut t = Trainer::new(tiny(algo, net, 200)).unwrap();
        let (mut losses, mut validations) = (Vec::new(), Vec::new());
        t.run_until(u64::MAX, |e| match e {
            TrainEvent::Step { loss, .. } => losses.push(*loss),
            TrainEvent::Validation {
                welfare,
                percent_of_opt,
                ..
            } => validations.push((*welfare, *percent_of_opt)),
        })
        .unwrap();
        assert_eq!(t.step(), 200);
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

/// Every parameter value, in visiting order.
struct Values(Vec<f32>);
impl<B: Backend> ModuleVisitor<B> for Values {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        self.0
            .extend(param.val().into_data().to_vec::<f32>().unwrap());
    }
}
fn values(net: &QNetwork<InferBackend>) -> Vec<u32> {
    let mut v = Values(Vec::new());
    net.visit(&mut v);
    v.0.into_iter().map(f32::to_bits).collect()
}

#[test]
fn resumed_run_ends_with_bit_identical_weights() {
    let config = tiny(Algo::Ddqn, NetworkConfig::afgnet(5, 2), 60);
    let mut straight = Trainer::new(config.clone()).unwrap();
    straight.run_until(60, |_| {}).unwrap();

    let dir = temp_dir("resume");
    let mut first = Trainer::new(config).unwrap();
    first.run_until(25, |_| {}).unwrap();
    first.save_checkpoint(&dir).unwrap();
    drop(first); // "killed"
    let mut resumed = Trainer::resume(&dir).unwrap();
    assert_eq!(resumed.step(), 25);
    resumed.run_until(60, |_| {}).unwrap();
    assert_eq!(values(&resumed.network()), values(&straight.network()));
    // A later checkpoint replaces the earlier one.
    resumed.save_checkpoint(&dir).unwrap();
    assert_eq!(Trainer::resume(&dir).unwrap().step(), 60);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn truncated_or_missing_checkpoints_are_clear_errors() {
    let dir = temp_dir("bad");
    assert!(matches!(
        Trainer::resume(&dir),
        Err(LearnError::Checkpoint { .. })
    ));
    let mut t = Trainer::new(tiny(Algo::Dqn, NetworkConfig::s2v(5, 0), 20)).unwrap();
    t.run_until(5, |_| {}).unwrap();
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
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_settings_are_refused() {
    let base = tiny(Algo::Dqn, NetworkConfig::afgnet(5, 0), 20);
    let mut c = base.clone();
    c.robots = 1;
    assert!(matches!(Trainer::new(c), Err(LearnError::InvalidConfig(_))));
    let mut c = base.clone();
    c.eps_end = 1.5;
    assert!(matches!(Trainer::new(c), Err(LearnError::InvalidConfig(_))));
    let mut c = base.clone();
    c.lr = 0.0;
    assert!(Trainer::new(c).is_err());
    let mut c = base;
    c.n_step = 0;
    assert!(matches!(Trainer::new(c), Err(LearnError::InvalidConfig(_))));
}

#[test]
fn epsilon_decays_linearly_then_stays() {
    let c = TrainConfig::new(20, Algo::Ddqn, NetworkConfig::afgnet(5, 0), 1000, 0);
    assert_eq!(c.epsilon(0), 1.0);
    assert!((c.epsilon(50) - 0.525).abs() < 1e-12);
    assert!((c.epsilon(100) - 0.05).abs() < 1e-12);
    assert!((c.epsilon(900) - 0.05).abs() < 1e-12);
}
