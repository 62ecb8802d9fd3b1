//! Shapes, permutation invariance, batching, the environment, a gradient step, seeds,
//! the price head.

mod common;

use std::path::PathBuf;

use afg_game::io::read_dataset;
use afg_game::{GeneratorConfig, Instance, Point, RobotId, Task, TaskId};
use afg_graph::{AllocationState, GraphBatch, GraphKind, RobotGraph};
use afg_learn::{
    InferBackend, LearnError, TrainBackend,
    env::Env,
    nets::{GraphTensors, NetworkConfig},
};
use burn::module::AutodiffModule;
use burn::optim::{AdamConfig, GradientsParams, Optimizer};
use burn::tensor::Tensor;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{configs, price_headed};

type B = InferBackend;

/// One uniformly random allowed action: (reward, done).
fn random_step(env: &mut Env<'_>, rng: &mut ChaCha8Rng) -> (f64, bool) {
    let open: Vec<usize> = env
        .action_mask()
        .iter()
        .enumerate()
        .filter(|(_, ok)| **ok)
        .map(|(j, _)| j)
        .collect();
    env.step(TaskId(open[rng.random_range(0..open.len())] as u32))
        .unwrap()
}

/// An instance after `steps` random actions, with the next robot to act.
fn midway(inst: &Instance, steps: usize, seed: u64) -> (AllocationState<'_>, RobotId) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut env = Env::reset(inst, afg_graph::Units::Bounded);
    for _ in 0..steps.min(inst.num_robots() - 1) {
        random_step(&mut env, &mut rng);
    }
    let actor = env.actor().unwrap();
    (env.state().clone(), actor)
}

fn q_values(config: &NetworkConfig, batch: &GraphBatch) -> Vec<f32> {
    let device = Default::default();
    let net = config.init::<B>(&device);
    let q = net.forward(&GraphTensors::new(batch, &device));
    assert_eq!(q.dims(), [batch.num_graphs(), 5]);
    q.into_data().to_vec().unwrap()
}

#[test]
fn shapes_for_several_sizes_and_batches() {
    for n in [1, 2, 20, 137] {
        let insts: Vec<Instance> = (0..7)
            .map(|s| GeneratorConfig::paper(n, 5, s).generate().unwrap())
            .collect();
        for graphs in [1, 7] {
            let mut batch = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
            for (g, inst) in insts.iter().take(graphs).enumerate() {
                let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
                let (state, actor) = midway(inst, g * n / 7, g as u64);
                batch.push(&graph, &state, actor);
            }
            for config in configs() {
                let q = q_values(&config, &batch);
                assert!(q.iter().all(|v| v.is_finite()), "N = {n}, G = {graphs}");
            }
        }
    }
}

#[test]
fn relabelling_robots_does_not_change_q_values() {
    let inst = GeneratorConfig::paper(30, 5, 8).generate().unwrap();
    let (state, actor) = midway(&inst, 17, 2);
    // A permutation of robot labels: reverse, then rotate.
    let n = inst.num_robots();
    let perm: Vec<usize> = (0..n).map(|i| (n - 1 - i + 7) % n).collect(); // new index of old robot i
    let mut robots = vec![Point::new(0.0, 0.0); n];
    let mut tasks = vec![None; n];
    for i in 0..n {
        robots[perm[i]] = inst.robots()[i];
        tasks[perm[i]] = state.assignment().tasks()[i];
    }
    let permuted = Instance::new(robots, inst.tasks().to_vec(), inst.beta()).unwrap();
    let assignment = afg_game::Assignment::from_tasks(&permuted, tasks).unwrap();
    let permuted_state =
        AllocationState::from_assignment(&permuted, assignment, afg_graph::Units::Bounded);
    for config in configs() {
        let mut a = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
        a.push(
            &RobotGraph::build(inst.robots(), GraphKind::default()).unwrap(),
            &state,
            actor,
        );
        let mut b = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
        b.push(
            &RobotGraph::build(permuted.robots(), GraphKind::default()).unwrap(),
            &permuted_state,
            RobotId(perm[actor.index()] as u32),
        );
        let (qa, qb) = (q_values(&config, &a), q_values(&config, &b));
        for (x, y) in qa.iter().zip(&qb) {
            assert!(
                (x - y).abs() < 1e-4 * x.abs().max(1.0),
                "{} {qa:?} vs {qb:?}",
                config.name()
            );
        }
    }
}

#[test]
fn batched_q_values_equal_single_graph_ones() {
    let insts: Vec<Instance> = [7usize, 20, 33, 60]
        .iter()
        .enumerate()
        .map(|(s, &n)| GeneratorConfig::paper(n, 5, s as u64).generate().unwrap())
        .collect();
    let mut batch = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
    let mut singles = Vec::new();
    for (g, inst) in insts.iter().enumerate() {
        let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
        let (state, actor) = midway(inst, inst.num_robots() / 2, g as u64);
        batch.push(&graph, &state, actor);
        let mut one = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
        one.push(&graph, &state, actor);
        singles.push(one);
    }
    for config in configs() {
        let together = q_values(&config, &batch);
        let alone: Vec<f32> = singles.iter().flat_map(|b| q_values(&config, b)).collect();
        for (x, y) in together.iter().zip(&alone) {
            assert!(
                (x - y).abs() < 1e-5 * x.abs().max(1.0),
                "{together:?} vs {alone:?}"
            );
        }
    }
}

#[test]
fn episode_return_equals_final_welfare_on_every_dataset_instance() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for n in [20, 60, 100, 500, 1000] {
        let path =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../datasets/n{n}.jsonl"));
        for inst in read_dataset(&path).unwrap() {
            let mut env = Env::reset(&inst, afg_graph::Units::Bounded);
            let mut ret = 0.0;
            let mut done = false;
            while !done {
                let (r, d) = random_step(&mut env, &mut rng);
                ret += r;
                done = d;
            }
            let w = inst.welfare(env.state().assignment());
            assert!(
                (ret - w).abs() < 1e-9 * w.abs().max(1.0),
                "N = {n}: return {ret} vs welfare {w}"
            );
            assert!(matches!(
                env.step(TaskId(0)),
                Err(LearnError::InvalidAction(_))
            ));
        }
    }
}

#[test]
fn full_tasks_are_refused() {
    let task = |x| Task {
        position: Point::new(x, 0.0),
        reward: 1.0,
        eps: 2.0,
        capacity: Some(1),
    };
    let inst = Instance::new(
        vec![Point::new(0.0, 0.0); 2],
        vec![task(0.0), task(1.0)],
        1.0,
    )
    .unwrap();
    let mut env = Env::reset(&inst, afg_graph::Units::Bounded);
    env.step(TaskId(0)).unwrap();
    assert_eq!(env.action_mask(), vec![false, true]);
    assert!(matches!(
        env.step(TaskId(0)),
        Err(LearnError::InvalidAction(_))
    ));
    assert!(matches!(
        env.step(TaskId(9)),
        Err(LearnError::InvalidAction(_))
    ));
    assert!(
        env.step(TaskId(1)).unwrap().1,
        "the last robot ends the episode"
    );
}

#[test]
fn one_adam_step_reduces_a_fixed_mse() {
    let device = Default::default();
    let inst = GeneratorConfig::paper(20, 5, 4).generate().unwrap();
    let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    let mut batch = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
    for g in 0..8 {
        let (state, actor) = midway(&inst, 2 * g, g as u64);
        batch.push(&graph, &state, actor);
    }
    let target = Tensor::<TrainBackend, 2>::ones([8, 5], &device);
    for config in configs() {
        let mut net = config.init::<TrainBackend>(&device);
        let g = GraphTensors::new(&batch, &device);
        let loss = |net: &afg_learn::nets::QNetwork<TrainBackend>| {
            (net.forward(&g) - target.clone()).powi_scalar(2).mean()
        };
        let before = loss(&net);
        let before_value: f32 = before.clone().into_scalar();
        let mut optim = AdamConfig::new().init();
        let grads = GradientsParams::from_grads(before.backward(), &net);
        net = optim.step(1e-3, net, grads);
        let after: f32 = loss(&net).into_scalar();
        assert!(
            after < before_value,
            "{}: {before_value} -> {after}",
            config.name()
        );
        // The inference view computes the same thing.
        let valid: f32 = (net.valid().forward(&GraphTensors::new(&batch, &device))
            - Tensor::ones([8, 5], &device))
        .powi_scalar(2)
        .mean()
        .into_scalar();
        assert!((valid - after).abs() < 1e-5);
    }
}

#[test]
fn same_seed_same_weights() {
    let device = Default::default();
    let inst = GeneratorConfig::paper(20, 5, 1).generate().unwrap();
    let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    let mut batch = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
    let (state, actor) = midway(&inst, 5, 0);
    batch.push(&graph, &state, actor);
    let g = GraphTensors::<B>::new(&batch, &device);
    let q = |c: NetworkConfig| -> Vec<f32> {
        c.init::<B>(&device)
            .forward(&g)
            .into_data()
            .to_vec()
            .unwrap()
    };
    assert_eq!(
        q(NetworkConfig::afgnet(5, 9)),
        q(NetworkConfig::afgnet(5, 9))
    );
    assert_ne!(
        q(NetworkConfig::afgnet(5, 9)),
        q(NetworkConfig::afgnet(5, 10))
    );
}

#[test]
fn dense_and_edge_list_aggregation_agree() {
    let device = Default::default();
    let mut batch = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
    for s in 0..6u64 {
        let inst = GeneratorConfig::paper(25, 5, s).generate().unwrap();
        let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
        let (state, actor) = midway(&inst, 3 * s as usize, s);
        batch.push(&graph, &state, actor);
    }
    let dense = GraphTensors::<B>::new(&batch, &device);
    assert!(
        dense.dense.is_some(),
        "equal-sized graphs get dense matrices"
    );
    let sparse = GraphTensors::<B>::sparse(&batch, &device);
    for config in configs() {
        let net = config.init::<B>(&device);
        let a: Vec<f32> = net.forward(&dense).into_data().to_vec().unwrap();
        let b: Vec<f32> = net.forward(&sparse).into_data().to_vec().unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!(
                (x - y).abs() < 1e-5 * x.abs().max(1.0),
                "{}: {a:?} vs {b:?}",
                config.name()
            );
        }
    }
}

#[test]
fn an_untrained_price_head_is_nearest() {
    // Both output layers start at zero: Q(s, a) = −β d(t, a) in the features' unit,
    // so the greedy action is the nearest task with room, and every price is 0.
    let device = Default::default();
    let config = price_headed(5);
    let net = config.init::<B>(&device);
    for (n, seed) in [(20, 1), (60, 2), (100, 3)] {
        let mut inst = GeneratorConfig::paper(n, 5, seed).generate().unwrap();
        if n == 20 {
            // Capacities, so that some nearest tasks are full.
            let tasks = inst
                .tasks()
                .iter()
                .map(|t| Task {
                    capacity: Some(5),
                    ..*t
                })
                .collect();
            inst = Instance::new(inst.robots().to_vec(), tasks, inst.beta()).unwrap();
        }
        let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
        let mut batch = GraphBatch::with_task_summaries(5, afg_graph::Units::Bounded);
        for k in 0..8 {
            let (state, actor) = midway(&inst, k * n / 8, k as u64);
            // In the network's units, as the trainer and the policies build states.
            let state =
                AllocationState::from_assignment(&inst, state.assignment().clone(), config.units());
            batch.push(&graph, &state, actor);
        }
        let g = GraphTensors::new(&batch, &device);
        let q: Vec<f32> = net.forward(&g).into_data().to_vec().unwrap();
        let afg_learn::nets::QNetwork::AfgNet(afgnet) = &net else {
            unreachable!()
        };
        let prices: Vec<f32> = afgnet.prices(&g).unwrap().into_data().to_vec().unwrap();
        assert!(prices.iter().all(|&p| p == 0.0));
        for k in 0..8 {
            let actor = RobotId(batch.actors[k] - (k * n) as u32);
            let row = &q[k * 5..(k + 1) * 5];
            let mask = &batch.mask[k * 5..(k + 1) * 5];
            for j in 0..5 {
                let cost = inst.cost(actor, TaskId(j as u32)) as f32; // β = 1
                assert!((row[j] + cost).abs() < 1e-6, "{row:?}");
            }
            let nearest = (0..5)
                .filter(|&j| mask[j])
                .min_by(|&a, &b| {
                    inst.distance(actor, TaskId(a as u32))
                        .total_cmp(&inst.distance(actor, TaskId(b as u32)))
                })
                .unwrap();
            assert_eq!(afg_learn::train::masked_argmax(row, mask), Some(nearest));
        }
    }
}

#[test]
fn a_price_head_is_off_unless_asked_and_leaves_the_papers_weights_alone() {
    let json = r#"{"net":"afgnet","tasks":5,"hidden":64,"layers":3,"activation":"relu","seed":0,"gain_residual":false,"price_head":false,"units":"bounded"}"#;
    let config: NetworkConfig = serde_json::from_str(json).unwrap();
    let NetworkConfig::AfgNet(c) = &config else {
        unreachable!()
    };
    assert!(!c.price_head);
    // The price head draws its weights after everything else: the paper's network
    // keeps the weights of its seed.
    let device = Default::default();
    let (plain, headed) = (
        config.init::<B>(&device),
        price_headed(0).init::<B>(&device),
    );
    let (afg_learn::nets::QNetwork::AfgNet(a), afg_learn::nets::QNetwork::AfgNet(b)) =
        (&plain, &headed)
    else {
        unreachable!()
    };
    let theta = |l: &burn::nn::Linear<B>| l.weight.val().into_data().to_vec::<f32>().unwrap();
    assert_eq!(theta(&a.theta1), theta(&b.theta1));
    assert_eq!(theta(&a.head.hidden), theta(&b.head.hidden));
    assert!(theta(&b.head.output).iter().all(|&w| w == 0.0));
    assert!(a.price.is_none() && b.price.is_some());
}

/// A network reads only batches in the units it was trained in.
#[test]
fn a_network_refuses_features_in_other_units() {
    let inst = GeneratorConfig::paper(12, 5, 2).generate().unwrap();
    let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    let device = Default::default();
    for config in configs() {
        let net = config.init::<B>(&device);
        let other = [afg_graph::Units::MeanReward, afg_graph::Units::Bounded]
            .into_iter()
            .find(|&u| u != net.units())
            .unwrap();
        let state = AllocationState::new(&inst, other);
        let mut batch = GraphBatch::new(5, other);
        batch.push(&graph, &state, RobotId(0));
        let tensors = GraphTensors::<B>::new(&batch, &device);
        let refused =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| net.forward(&tensors)));
        assert!(refused.is_err(), "{config:?}");
        // In its own units it answers.
        let mut own = net.empty_batch(5);
        own.push(
            &graph,
            &AllocationState::new(&inst, net.units()),
            RobotId(0),
        );
        let q = net.forward(&GraphTensors::<B>::new(&own, &device));
        assert_eq!(q.dims(), [1, 5]);
    }
}
