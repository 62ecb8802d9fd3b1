//! `cargo xtask bench-baselines`: a Markdown table of allocator times and welfare.

use std::time::Duration;

use afg_baseline::{Allocator, Method, Optimum};
use afg_eval::tables::duration;
use afg_game::GeneratorConfig;
use afg_learn::{QNetwork, TrainBackend};
use anyhow::Result;
use burn::tensor::Tensor;
use clap::Args;

#[derive(Args)]
pub struct BenchArgs {
    /// Robot counts to sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [100, 1_000, 10_000, 100_000])]
    sizes: Vec<usize>,
    /// Number of tasks M.
    #[arg(long, default_value_t = 5)]
    tasks: usize,
    /// Largest N for the decentralised DA (its simulation keeps N views).
    #[arg(long, default_value_t = 1_000)]
    max_decentralised: usize,
    /// Time budget per measurement: repeat until it is spent (at least once, at most 20 runs).
    #[arg(long, default_value_t = 1.0)]
    seconds: f64,
}

/// Median wall time of repeated runs.
fn median_time(
    alloc: &dyn Allocator,
    inst: &afg_game::Instance,
    budget: f64,
) -> Result<(Duration, f64)> {
    let mut times = Vec::new();
    let mut welfare = 0.0;
    let mut spent = 0.0;
    while times.is_empty() || (spent < budget && times.len() < 20) {
        let out = alloc.allocate(inst)?;
        welfare = inst.welfare(&out.assignment);
        spent += out.stats.wall_time.as_secs_f64();
        times.push(out.stats.wall_time);
    }
    times.sort();
    Ok((times[times.len() / 2], welfare))
}

pub fn run(args: BenchArgs) -> Result<()> {
    let methods = [
        Method::Opt,
        Method::Da,
        Method::DaBalanced,
        Method::Greedy,
        Method::Nearest,
        Method::DaDecentralised,
    ];
    println!(
        "M = {}; instance seed 7, paper distribution; median wall time on one core, welfare as % of OPT.\n",
        args.tasks
    );
    print!("| N |");
    for m in methods {
        print!(" {m} |");
    }
    println!();
    println!("|---|{}", "---|".repeat(methods.len()));
    for &n in &args.sizes {
        let inst = GeneratorConfig::paper(n, args.tasks, 7).generate()?;
        let opt = inst.welfare(&Optimum.allocate(&inst)?.assignment);
        print!("| {n} |");
        for m in methods {
            if m == Method::DaDecentralised && n > args.max_decentralised {
                print!(" – |");
                continue;
            }
            let (t, w) = median_time(m.allocator(0).as_ref(), &inst, args.seconds)?;
            print!(" {} ({:.2} %) |", duration(t), 100.0 * w / opt);
        }
        println!();
    }
    Ok(())
}

#[derive(Args)]
pub struct ModelBenchArgs {
    /// Robot counts for the batched forward pass and training step.
    #[arg(long, value_delimiter = ',', default_values_t = [20, 60, 100])]
    sizes: Vec<usize>,
    /// States per batch.
    #[arg(long, default_value_t = 256)]
    batch: usize,
    /// Robot count of the greedy rollout.
    #[arg(long, default_value_t = 1_000)]
    rollout: usize,
    /// Repetitions per measurement (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
}

/// A batch of `size` states from random partial episodes on fresh instances.
pub(crate) fn random_batch(n: usize, size: usize) -> Result<afg_graph::GraphBatch> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(n as u64);
    let mut batch = afg_graph::GraphBatch::new(5);
    for s in 0..size {
        let inst = GeneratorConfig::paper(n, 5, s as u64).generate()?;
        let graph = afg_graph::RobotGraph::build(inst.robots(), afg_graph::GraphKind::default())?;
        let mut env = afg_learn::Env::reset(&inst);
        for _ in 0..rng.random_range(0..n) {
            env.step(afg_game::TaskId(rng.random_range(0..5)))?;
        }
        batch.push(&graph, env.state(), env.actor().expect("a robot is left"));
    }
    Ok(batch)
}

fn median<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<Duration> {
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let start = std::time::Instant::now();
        f()?;
        times.push(start.elapsed());
    }
    times.sort();
    Ok(times[times.len() / 2])
}

/// Median time of one training step (forward, backward, Adam) on a fixed batch, with
/// `forward` computing the `[rows, M]` Q values; the loss is the MSE to zero.
fn step_time(
    repeats: usize,
    config: &afg_learn::NetworkConfig,
    rows: usize,
    forward: impl Fn(&QNetwork<TrainBackend>) -> Tensor<TrainBackend, 2>,
) -> Result<Duration> {
    use burn::optim::{AdamConfig, GradientsParams, Optimizer};
    let device = Default::default();
    let mut train = config.init::<TrainBackend>(&device);
    let mut optim = AdamConfig::new().init();
    let target = Tensor::<TrainBackend, 2>::zeros([rows, config.tasks()], &device);
    median(repeats, || {
        let loss = (forward(&train) - target.clone()).powi_scalar(2).mean();
        let grads = GradientsParams::from_grads(loss.backward(), &train);
        train = optim.step(1e-4, train.clone(), grads);
        Ok(())
    })
}

pub fn run_models(args: ModelBenchArgs) -> Result<()> {
    use crate::plain::PaddedGraph;
    use afg_learn::{Activation, GraphTensors, InferBackend, NetworkConfig};
    let device = Default::default();
    println!(
        "Median of {} runs; batch of {} states from random partial episodes (M = 5); CPU ndarray back end; {} allocator.\n",
        args.repeats,
        args.batch,
        crate::ALLOCATOR_NAME
    );
    println!(
        "| network | N | forward, edge lists | forward, dense | train step, edge lists | train step, dense | speed-up of the step |"
    );
    println!("|---|---|---|---|---|---|---|");
    for &n in &args.sizes {
        let batch = random_batch(n, args.batch)?;
        for config in [NetworkConfig::afgnet(5, 0), NetworkConfig::s2v(5, 0)] {
            let mut forward = Vec::new();
            let mut step = Vec::new();
            for dense in [false, true] {
                let upload = |b: &afg_graph::GraphBatch| {
                    if dense {
                        GraphTensors::<InferBackend>::new(b, &device)
                    } else {
                        GraphTensors::sparse(b, &device)
                    }
                };
                let net = config.init::<InferBackend>(&device);
                forward.push(median(args.repeats, || {
                    Ok(net.forward(&upload(&batch)).into_data())
                })?);
                step.push(step_time(args.repeats, &config, args.batch, |net| {
                    net.forward(&if dense {
                        GraphTensors::<TrainBackend>::new(&batch, &device)
                    } else {
                        GraphTensors::sparse(&batch, &device)
                    })
                })?);
            }
            println!(
                "| {} | {n} | {} | {} | {} | {} | {:.1}× |",
                config.name(),
                duration(forward[0]),
                duration(forward[1]),
                duration(step[0]),
                duration(step[1]),
                step[0].as_secs_f64() / step[1].as_secs_f64()
            );
        }
    }
    println!(
        "\nAFGNet's training step against the plain model of the first Burn notes of this project \
         (neighbours padded to the largest degree, gather + reshape + sum; same parameters, \
         same Q values: tested in xtask/src/plain.rs), in the same run:\n"
    );
    println!("| N | train step, plain (padded gather) | train step, ours (dense) | speed-up |");
    println!("|---|---|---|---|");
    let config = NetworkConfig::afgnet(5, 0);
    let plain_q = |net: &QNetwork<TrainBackend>, batch: &afg_graph::GraphBatch| match net {
        QNetwork::AfgNet(a) => {
            crate::plain::forward(a, Activation::Relu, &PaddedGraph::new(batch, &device))
        }
        QNetwork::S2v(_) => unreachable!("an AFGNet configuration"),
    };
    for &n in &args.sizes {
        let batch = random_batch(n, args.batch)?;
        let plain = step_time(args.repeats, &config, args.batch, |net| {
            plain_q(net, &batch)
        })?;
        let ours = step_time(args.repeats, &config, args.batch, |net| {
            net.forward(&GraphTensors::new(&batch, &device))
        })?;
        println!(
            "| {n} | {} | {} | {:.1}× |",
            duration(plain),
            duration(ours),
            plain.as_secs_f64() / ours.as_secs_f64()
        );
    }
    let inst = GeneratorConfig::paper(args.rollout, 5, 7).generate()?;
    println!(
        "\n| network | greedy rollout, N = {}, Burn path | fast path (B = 1) | speed-up |",
        args.rollout
    );
    println!("|---|---|---|---|");
    for config in [NetworkConfig::afgnet(5, 0), NetworkConfig::s2v(5, 0)] {
        let policy = afg_learn::LearnedPolicy::new(config.clone());
        let fast = median(3, || Ok(policy.allocate(&inst)?))?;
        let policy = policy.exact_burn();
        let burn = median(1, || Ok(policy.allocate(&inst)?))?;
        println!(
            "| {} | {} | {} | {:.1}× |",
            config.name(),
            duration(burn),
            duration(fast),
            burn.as_secs_f64() / fast.as_secs_f64()
        );
    }
    Ok(())
}
