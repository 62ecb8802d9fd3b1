//! The fast inference path against the Burn network: same Q values, same actions.

use std::path::{Path, PathBuf};

use afg_game::io::read_dataset;
use afg_game::{GeneratorConfig, Instance, TaskId};
use afg_graph::{AllocationState, GraphKind, RobotGraph};
use afg_learn::{
    InferBackend, LearnError,
    fast::{FastPolicy, FastRollout},
    nets::{Activation, GraphTensors, NetworkConfig, QNetwork, load_network},
    policy::greedy_rollouts,
    train::masked_argmax,
};

type B = InferBackend;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

fn dataset(n: usize) -> Vec<Instance> {
    read_dataset(&repo(&format!("datasets/n{n}.jsonl"))).unwrap()
}

/// Steps both paths through a full exact rollout: at every step the Burn Q values
/// and the fast ones agree within 1e-4 and both choose the same task. Returns the
/// largest difference seen.
fn assert_parity(config: &NetworkConfig, network: &QNetwork<B>, inst: &Instance) -> f32 {
    let device = Default::default();
    let m = inst.num_tasks();
    let fast = FastPolicy::from_network(config, network);
    let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    let mut run = FastRollout::new(&fast, inst, &graph).unwrap();
    // The Burn side sees the state in the network's units, as the trainer builds it.
    let empty = afg_game::Assignment::unassigned(inst.num_robots(), m);
    let mut state = AllocationState::from_assignment(inst, empty, config.units());
    let (mut q_fast, mut mask) = (vec![0.0; m], vec![false; m]);
    let mut worst = 0.0f32;
    for robot in inst.robot_ids() {
        let mut batch = network.empty_batch(m);
        batch.push(&graph, &state, robot);
        let q_burn: Vec<f32> = network
            .forward(&GraphTensors::new(&batch, &device))
            .into_data()
            .to_vec()
            .unwrap();
        run.evaluate();
        run.q_values(robot, &mut q_fast);
        run.action_mask(robot, &mut mask);
        assert_eq!(mask, batch.mask, "robot {robot}");
        for (a, b) in q_burn.iter().zip(&q_fast) {
            let diff = (a - b).abs();
            assert!(
                diff <= 1e-4 * a.abs().max(1.0),
                "robot {robot}: Burn {q_burn:?}, fast {q_fast:?}"
            );
            worst = worst.max(diff);
        }
        let chosen = masked_argmax(&q_burn, &batch.mask).unwrap();
        assert_eq!(
            masked_argmax(&q_fast, &mask),
            Some(chosen),
            "robot {robot}: Burn {q_burn:?}, fast {q_fast:?}"
        );
        state.assign(robot, TaskId(chosen as u32));
        run.assign(robot, TaskId(chosen as u32));
    }
    assert_eq!(run.assignment(), state.assignment());
    worst
}

#[test]
fn fast_path_matches_burn_with_random_weights_on_the_datasets() {
    let device = Default::default();
    let configs = [
        NetworkConfig::afgnet(5, 11),
        NetworkConfig::s2v(5, 11),
        // Other activations and depths go through the same code.
        NetworkConfig::AfgNet(
            afg_learn::nets::AfgNetConfig::new(5, afg_graph::Units::MeanReward)
                .with_activation(Activation::Tanh)
                .with_layers(2)
                .with_hidden(16)
                .with_seed(4),
        ),
        NetworkConfig::AfgNet(
            afg_learn::nets::AfgNetConfig::new(5, afg_graph::Units::MeanReward)
                .with_gain_residual(true)
                .with_seed(6),
        ),
        // Scale-free units: μ, gains and edge weights rescaled on both paths.
        NetworkConfig::afgnet(5, 12).with_units(afg_graph::Units::ScaleFree),
        NetworkConfig::s2v(5, 12).with_units(afg_graph::Units::ScaleFree),
        NetworkConfig::afgnet(5, 13).with_units(afg_graph::Units::Bounded),
        NetworkConfig::AfgNet(
            afg_learn::nets::AfgNetConfig::new(5, afg_graph::Units::MeanReward)
                .with_gain_residual(true)
                .with_seed(7),
        )
        .with_units(afg_graph::Units::ScaleFree),
    ];
    for config in &configs {
        let network = config.init::<B>(&device);
        // Every instance in the first units; the other units (which change only the
        // inputs' scale, the same code path) on the first 20 of each set.
        let count = if config.units() == afg_graph::Units::MeanReward {
            100
        } else {
            20
        };
        for n in [20, 60, 100] {
            for inst in dataset(n).iter().take(count) {
                let worst = assert_parity(config, &network, inst);
                assert!(worst.is_finite());
            }
        }
    }
}

/// A price-headed AFGNet whose two zero-initialised output layers are replaced by
/// seeded random ones, so that every part of the head counts.
fn price_headed(seed: u64, units: afg_graph::Units) -> (NetworkConfig, QNetwork<B>) {
    use burn::module::Param;
    use burn::nn::Linear;
    use burn::tensor::{Tensor, TensorData};
    use rand::{Rng, SeedableRng};
    let device = Default::default();
    let config = NetworkConfig::AfgNet(
        afg_learn::nets::AfgNetConfig::new(5, afg_graph::Units::MeanReward)
            .with_price_head(true)
            .with_seed(seed),
    )
    .with_units(units);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut random = |d_in: usize, d_out: usize| {
        let mut draw =
            |len: usize| -> Vec<f32> { (0..len).map(|_| rng.random_range(-0.3..0.3)).collect() };
        Linear {
            weight: Param::from_tensor(Tensor::from_data(
                TensorData::new(draw(d_in * d_out), [d_in, d_out]),
                &device,
            )),
            bias: Some(Param::from_tensor(Tensor::from_data(
                TensorData::new(draw(d_out), [d_out]),
                &device,
            ))),
        }
    };
    let QNetwork::AfgNet(mut net) = config.init::<B>(&device) else {
        unreachable!("an AFGNet configuration")
    };
    net.head.output = random(64, 5);
    net.price.as_mut().expect("a price head").output = random(64, 1);
    (config, QNetwork::AfgNet(net))
}

#[test]
fn fast_path_matches_burn_with_a_price_head() {
    for (seed, units) in [
        (21, afg_graph::Units::Bounded),
        (22, afg_graph::Units::MeanReward),
    ] {
        let (config, network) = price_headed(seed, units);
        for n in [20, 60, 100] {
            for inst in dataset(n).iter().take(10) {
                assert_parity(&config, &network, inst);
            }
        }
    }
}

#[test]
fn fast_path_matches_burn_with_the_committed_weights() {
    let device = Default::default();
    for name in [
        "paper/afgnet_ddqn_n20",
        "paper/s2v_ddqn_n20",
        "paper/afgnet_ddqn_n60",
        "ours/afgnet_qstar_price_n60",
    ] {
        let stem = repo(&format!("models/{name}/model"));
        let (config, network) = load_network::<B>(&stem, &device).unwrap();
        for n in [20, 60, 100] {
            for inst in dataset(n).iter().take(5) {
                assert_parity(&config, &network, inst);
            }
        }
    }
}

#[test]
fn fast_rollout_equals_the_batched_burn_rollout() {
    let device = Default::default();
    let config = NetworkConfig::afgnet(5, 2);
    let network = config.init::<B>(&device);
    let fast = FastPolicy::from_network(&config, &network);
    let insts: Vec<Instance> = (0..4)
        .map(|s| {
            GeneratorConfig::paper(30 + 7 * s as usize, 5, s)
                .generate()
                .unwrap()
        })
        .collect();
    let burn = greedy_rollouts(&network, 5, &insts, GraphKind::default(), &device).unwrap();
    for (inst, expected) in insts.iter().zip(&burn) {
        let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
        let out = fast.rollout(inst, &graph, 1).unwrap();
        assert_eq!(&out.assignment, expected);
        assert_eq!(out.passes, inst.num_robots());
    }
}

#[test]
fn blocks_cut_the_passes_and_respect_capacities() {
    let config = NetworkConfig::afgnet(5, 1);
    let network = config.init::<B>(&Default::default());
    let fast = FastPolicy::from_network(&config, &network);
    // Tight capacities: 21 per task, 105 places for 103 robots.
    let inst = GeneratorConfig::paper(103, 5, 9)
        .with_capacity_slack(1.0)
        .generate()
        .unwrap();
    let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    for block in [1, 2, 10, 64, 103, 1000] {
        let out = fast.rollout(&inst, &graph, block).unwrap();
        assert_eq!(out.passes, 103usize.div_ceil(block), "block {block}");
        assert!(out.assignment.is_complete());
        for j in inst.task_ids() {
            assert!(out.assignment.size(j) <= inst.capacity(j), "block {block}");
        }
    }
    // Block 1 is the exact rollout; the same block gives the same result.
    let a = fast.rollout(&inst, &graph, 10).unwrap().assignment;
    assert_eq!(a, fast.rollout(&inst, &graph, 10).unwrap().assignment);
}

#[test]
fn bad_rollout_inputs_are_errors() {
    let config = NetworkConfig::s2v(5, 1);
    let network = config.init::<B>(&Default::default());
    let fast = FastPolicy::from_network(&config, &network);
    let inst = GeneratorConfig::paper(20, 5, 1).generate().unwrap();
    let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    assert!(matches!(
        fast.rollout(&inst, &graph, 0),
        Err(LearnError::InvalidConfig(_))
    ));
    let other = GeneratorConfig::paper(20, 4, 1).generate().unwrap();
    assert!(matches!(
        fast.rollout(&other, &graph, 1),
        Err(LearnError::InvalidAction(_))
    ));
    let bigger = GeneratorConfig::paper(21, 5, 1).generate().unwrap();
    assert!(matches!(
        fast.rollout(&bigger, &graph, 1),
        Err(LearnError::InvalidAction(_))
    ));
}

#[test]
fn repair_ends_balanced_stable_and_never_lowers_welfare() {
    use afg_baseline::Allocator;
    use afg_game::Preference;
    use afg_learn::policy::LearnedPolicy;
    for (seed, net) in [NetworkConfig::afgnet(5, 5), NetworkConfig::s2v(5, 5)]
        .into_iter()
        .enumerate()
    {
        let mut policy = LearnedPolicy::new(net);
        for (k, n) in [1, 2, 7, 20, 60, 150].into_iter().enumerate() {
            let inst = GeneratorConfig::paper(n, 5, 100 * seed as u64 + k as u64)
                .with_capacity_slack(1.3)
                .generate()
                .unwrap();
            for block in [1, 3, n] {
                policy = policy.with_block(block).unwrap().with_repair(true);
                let run = policy.run(&inst).unwrap();
                assert!(
                    inst.is_stable(&run.assignment, Preference::Balanced),
                    "N = {n}, block {block}"
                );
                assert!(inst.welfare(&run.assignment) >= run.rollout_welfare - 1e-9);
                policy = policy.with_repair(false);
                let plain = policy.allocate(&inst).unwrap();
                assert!(
                    (inst.welfare(&plain.assignment) - run.rollout_welfare).abs() < 1e-9,
                    "the repair starts from the rollout"
                );
                assert_eq!(run.repair_moves == 0, plain.assignment == run.assignment);
            }
        }
    }
}
