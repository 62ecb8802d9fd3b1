//! Measurements behind `cargo xtask bench-baselines` and `bench-models`: median wall
//! times of allocators, of the networks' forward pass and training step (edge lists
//! against dense adjacency, and against the [`padded_afgnet`] padded-gather model), and of the
//! greedy rollout (Burn path against the fast path).
//!
//! The machine is shared and noisy: compare ratios measured in one run.
//!
//! `cargo xtask bench-baselines`: a Markdown table of allocator times and welfare.

pub mod mission_loop;
pub mod padded_afgnet;
pub mod runs;

use std::convert::Infallible;
use std::time::{Duration, Instant};

use afg_baseline::{Allocator, Method, Optimum};
use afg_game::{GeneratorConfig, Instance, TaskId};
use afg_graph::{GraphBatch, GraphKind, RobotGraph};
use afg_learn::{
    InferBackend, LearnError, TrainBackend,
    env::Env,
    nets::{Activation, GraphTensors, NetworkConfig, QNetwork},
    policy::LearnedPolicy,
};
use burn::optim::{AdamConfig, GradientsParams, Optimizer};
use burn::tensor::Tensor;
use rand::{Rng, SeedableRng};

use afg_eval::EvalError;
use afg_eval::report::duration;

/// Tasks of every instance and network timed here: the paper's M.
const M: usize = GeneratorConfig::PAPER_TASKS;
use padded_afgnet::PaddedGraph;

/// The peak resident set size of this process in MiB (Linux; `None` elsewhere).
///
/// # Examples
/// ```
/// xtask::bench::reset_peak_rss();
/// let peak = xtask::bench::peak_rss_mib();
/// assert!(peak.is_none_or(|mib| mib > 0.0));
/// ```
pub fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// Starts [`peak_rss_mib`] again from the current resident set (Linux ≥ 4.0; elsewhere,
/// or where refused, the peak keeps counting from the start of the process).
pub fn reset_peak_rss() {
    // Writing 5 to clear_refs resets the high-water mark (proc(5)).
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

/// Repeats `run`, which returns how long it took and what it made, until `budget_s`
/// seconds are spent or `max_repeats` runs are done (at least one run): the median
/// time and the last run's output. Every benchmark's timing goes through this.
///
/// # Errors
/// The first error of `run`.
///
/// # Examples
/// ```
/// use std::time::Duration;
/// let mut k = 0;
/// let (median, last) = xtask::bench::median_of(f64::INFINITY, 3, || {
///     k += 1;
///     Ok::<_, ()>((Duration::from_millis(k), k))
/// })?;
/// assert_eq!((median, last), (Duration::from_millis(2), 3));
/// # Ok::<(), ()>(())
/// ```
pub fn median_of<T, E>(
    budget_s: f64,
    max_repeats: usize,
    mut run: impl FnMut() -> Result<(Duration, T), E>,
) -> Result<(Duration, T), E> {
    let (mut times, mut spent) = (Vec::new(), 0.0);
    loop {
        let (took, out) = run()?;
        spent += took.as_secs_f64();
        times.push(took);
        if spent >= budget_s || times.len() >= max_repeats.max(1) {
            times.sort();
            return Ok((times[times.len() / 2], out));
        }
    }
}

/// `job`'s output and how long it took on the wall clock.
///
/// # Errors
/// `job`'s.
pub fn clocked<T, E>(job: impl FnOnce() -> Result<T, E>) -> Result<(Duration, T), E> {
    let start = Instant::now();
    let out = job()?;
    Ok((start.elapsed(), out))
}

/// Median wall time of `alloc` on `instance` over repeated runs (at least one, at most
/// 20, until `budget_s` seconds are spent), and the welfare of its allocation.
///
/// # Errors
/// The allocator's.
pub fn allocator_time(
    alloc: &dyn Allocator,
    instance: &Instance,
    budget_s: f64,
) -> Result<(Duration, f64), EvalError> {
    median_of(budget_s, 20, || {
        let out = alloc.allocate(instance)?;
        Ok((out.stats.wall_time, instance.welfare(&out.assignment)))
    })
}

/// A batch of `size` states from random partial episodes on fresh instances of `n`
/// robots and five tasks (seeded by `n`).
///
/// # Errors
/// `n` = 0, or an instance that cannot be generated.
pub fn random_batch(n: usize, size: usize) -> Result<GraphBatch, EvalError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(n as u64);
    let mut batch = GraphBatch::new(M, afg_graph::Units::Bounded);
    for s in 0..size {
        let inst = GeneratorConfig::paper(n, M, s as u64).generate()?;
        let graph =
            RobotGraph::build(inst.robots(), GraphKind::default()).map_err(LearnError::from)?;
        let mut env = Env::reset(&inst, afg_graph::Units::Bounded);
        for _ in 0..rng.random_range(0..n) {
            env.step(TaskId(rng.random_range(0..M as u32)))?;
        }
        batch.push(&graph, env.state(), env.actor().expect("a robot is left"));
    }
    Ok(batch)
}

/// Median wall time of `repeats` (at least one) calls of `f`.
fn median<T, E>(repeats: usize, mut f: impl FnMut() -> Result<T, E>) -> Result<Duration, E> {
    median_of(f64::INFINITY, repeats, || clocked(&mut f)).map(|(time, _)| time)
}

/// Median time of one training step (forward, backward, Adam) on a fixed batch, with
/// `forward` computing the `[rows, M]` Q values; the loss is the MSE to zero.
fn step_time(
    repeats: usize,
    config: &NetworkConfig,
    rows: usize,
    forward: impl Fn(&QNetwork<TrainBackend>) -> Tensor<TrainBackend, 2>,
) -> Duration {
    let device = Default::default();
    let mut train = config.init::<TrainBackend>(&device);
    let mut optim = AdamConfig::new().init();
    let target = Tensor::<TrainBackend, 2>::zeros([rows, config.tasks()], &device);
    let Ok(time) = median(repeats, || {
        let loss = (forward(&train) - target.clone()).powi_scalar(2).mean();
        let grads = GradientsParams::from_grads(loss.backward(), &train);
        train = optim.step(1e-4, train.clone(), grads);
        Ok::<_, Infallible>(())
    });
    time
}

/// One network's forward pass and training step on one batch, with edge lists and with
/// dense adjacency.
#[derive(Clone, Debug)]
pub struct NetworkTiming {
    /// The network's name.
    pub network: &'static str,
    /// Robots N of the batch's states.
    pub robots: usize,
    /// Forward pass with edge lists, then with dense adjacency.
    pub forward: [Duration; 2],
    /// Training step with edge lists, then with dense adjacency.
    pub step: [Duration; 2],
}

/// [`NetworkTiming`] of AFGNet and S2V (M = 5) for each N of `sizes`, on a
/// [`random_batch`] of `batch` states, medians of `repeats` runs.
///
/// # Errors
/// An instance that cannot be generated.
pub fn network_timings(
    sizes: &[usize],
    batch: usize,
    repeats: usize,
) -> Result<Vec<NetworkTiming>, EvalError> {
    let device = Default::default();
    let mut out = Vec::new();
    for &n in sizes {
        let states = random_batch(n, batch)?;
        for config in [NetworkConfig::afgnet(M, 0), NetworkConfig::s2v(M, 0)] {
            let mut forward = [Duration::ZERO; 2];
            let mut step = [Duration::ZERO; 2];
            for (k, dense) in [false, true].into_iter().enumerate() {
                let upload = |b: &GraphBatch| {
                    if dense {
                        GraphTensors::<InferBackend>::new(b, &device)
                    } else {
                        GraphTensors::sparse(b, &device)
                    }
                };
                let net = config.init::<InferBackend>(&device);
                let Ok(time) = median(repeats, || {
                    Ok::<_, Infallible>(net.forward(&upload(&states)).into_data())
                });
                forward[k] = time;
                step[k] = step_time(repeats, &config, batch, |net| {
                    net.forward(&if dense {
                        GraphTensors::<TrainBackend>::new(&states, &device)
                    } else {
                        GraphTensors::sparse(&states, &device)
                    })
                });
            }
            out.push(NetworkTiming {
                network: config.name(),
                robots: n,
                forward,
                step,
            });
        }
    }
    Ok(out)
}

/// AFGNet's training step, [`padded_afgnet`] model against ours (dense), for each N of `sizes`
/// on a [`random_batch`] of `batch` states: `(N, plain, ours)`.
///
/// # Errors
/// An instance that cannot be generated.
pub fn plain_timings(
    sizes: &[usize],
    batch: usize,
    repeats: usize,
) -> Result<Vec<(usize, Duration, Duration)>, EvalError> {
    let device = Default::default();
    let config = NetworkConfig::afgnet(M, 0);
    let plain_q = |net: &QNetwork<TrainBackend>, b: &GraphBatch| match net {
        QNetwork::AfgNet(a) => {
            padded_afgnet::forward(a, Activation::Relu, &PaddedGraph::new(b, &device))
        }
        QNetwork::S2v(_) => unreachable!("an AFGNet configuration"),
    };
    let mut out = Vec::new();
    for &n in sizes {
        let states = random_batch(n, batch)?;
        let plain = step_time(repeats, &config, batch, |net| plain_q(net, &states));
        let ours = step_time(repeats, &config, batch, |net| {
            net.forward(&GraphTensors::new(&states, &device))
        });
        out.push((n, plain, ours));
    }
    Ok(out)
}

/// The greedy rollout of untrained AFGNet and S2V on one instance of `robots` robots
/// (seed 7, M = 5): `(network, Burn path, fast path)`, the fast path the median of
/// three runs.
///
/// # Errors
/// An instance that cannot be generated, or a failed rollout.
pub fn rollout_timings(
    robots: usize,
) -> Result<Vec<(&'static str, Duration, Duration)>, EvalError> {
    let inst = GeneratorConfig::paper(robots, M, 7).generate()?;
    let mut out = Vec::new();
    for config in [NetworkConfig::afgnet(M, 0), NetworkConfig::s2v(M, 0)] {
        let policy = LearnedPolicy::new(config.clone());
        let fast = median(3, || policy.allocate(&inst))?;
        let policy = policy.exact_burn();
        let burn = median(1, || policy.allocate(&inst))?;
        out.push((config.name(), burn, fast));
    }
    Ok(out)
}

/// The table of `cargo xtask bench-baselines`: for each N of `sizes`, every centralised
/// allocator and the decentralised DA (up to N = `max_decentralised`) on one instance
/// of the paper's distribution (seed 7, M = `tasks`): median wall time over a budget of
/// `seconds` per allocator ([`allocator_time`]) and welfare as % of OPT.
///
/// # Errors
/// An instance that cannot be generated, or an allocator failure.
pub fn allocators_markdown(
    sizes: &[usize],
    tasks: usize,
    max_decentralised: usize,
    seconds: f64,
) -> Result<String, EvalError> {
    let mut methods = Method::CENTRALISED.to_vec();
    methods.retain(|&m| m != Method::Random);
    methods.push(Method::DaDecentralised);
    let mut md = format!(
        "M = {tasks}; instance seed 7, paper distribution; median wall time (opt and nearest spread their N · M loops over all cores), welfare as % of OPT.\n\n| N |"
    );
    for m in &methods {
        md += &format!(" {m} |");
    }
    md += &format!("\n|---|{}\n", "---|".repeat(methods.len()));
    for &n in sizes {
        let inst = GeneratorConfig::paper(n, tasks, 7).generate()?;
        let opt = inst.welfare(&Optimum.allocate(&inst)?.assignment);
        md += &format!("| {n} |");
        for &m in &methods {
            if m == Method::DaDecentralised && n > max_decentralised {
                md += " – |";
                continue;
            }
            let (t, w) = allocator_time(m.allocator(0).as_ref(), &inst, seconds)?;
            md += &format!(" {} ({:.2} %) |", duration(t), 100.0 * w / opt);
        }
        md.push('\n');
    }
    Ok(md)
}

/// The tables of `cargo xtask bench-models`: [`network_timings`] at each N of `sizes`
/// (batches of `batch` states, median of `repeats`), [`plain_timings`] and
/// [`rollout_timings`] at N = `rollout`; `allocator` names the global allocator of the
/// build for the header.
///
/// # Errors
/// As [`network_timings`], [`plain_timings`] and [`rollout_timings`].
pub fn networks_markdown(
    sizes: &[usize],
    batch: usize,
    rollout: usize,
    repeats: usize,
    allocator: &str,
) -> Result<String, EvalError> {
    let ratio = |a: Duration, b: Duration| a.as_secs_f64() / b.as_secs_f64();
    let mut md = format!(
        "Median of {repeats} runs; batch of {batch} states from random partial episodes (M = {M}); CPU ndarray back end; {allocator} allocator.\n\n\
         | network | N | forward, edge lists | forward, dense | train step, edge lists | train step, dense | speed-up of the step |\n|---|---|---|---|---|---|---|\n"
    );
    for t in network_timings(sizes, batch, repeats)? {
        md += &format!(
            "| {} | {} | {} | {} | {} | {} | {:.1}× |\n",
            t.network,
            t.robots,
            duration(t.forward[0]),
            duration(t.forward[1]),
            duration(t.step[0]),
            duration(t.step[1]),
            ratio(t.step[0], t.step[1])
        );
    }
    md += "\nAFGNet's training step against the plain model of the first Burn notes of this project \
           (neighbours padded to the largest degree, gather + reshape + sum; same parameters, \
           same Q values: tested in xtask/src/bench/padded_afgnet.rs), in the same run:\n\n\
           | N | train step, plain (padded gather) | train step, ours (dense) | speed-up |\n|---|---|---|---|\n";
    for (n, plain, ours) in plain_timings(sizes, batch, repeats)? {
        let (p, o, x) = (duration(plain), duration(ours), ratio(plain, ours));
        md += &format!("| {n} | {p} | {o} | {x:.1}× |\n");
    }
    md += &format!(
        "\n| network | greedy rollout, N = {rollout}, Burn path | fast path (B = 1) | speed-up |\n|---|---|---|---|\n"
    );
    for (network, burn, fast) in rollout_timings(rollout)? {
        let (b, f, x) = (duration(burn), duration(fast), ratio(burn, fast));
        md += &format!("| {network} | {b} | {f} | {x:.1}× |\n");
    }
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_benchmark_tables_have_a_row_per_case() {
        let md = allocators_markdown(&[12, 30], 3, 12, 0.0).unwrap();
        let rows: Vec<&str> = md
            .lines()
            .filter(|l| l.starts_with("| 12 |") || l.starts_with("| 30 |"))
            .collect();
        assert_eq!(rows.len(), 2, "{md}");
        // OPT is the first column, at 100 % of itself; DA decentralised only up to 12.
        assert!(rows.iter().all(|r| r.contains("(100.00 %)")), "{md}");
        assert!(
            rows[1].ends_with(" – |") && !rows[0].ends_with(" – |"),
            "{md}"
        );
        let md = networks_markdown(&[8], 4, 20, 1, "system").unwrap();
        assert_eq!(
            md.lines().filter(|l| l.starts_with("| afgnet |")).count(),
            2,
            "{md}"
        );
        assert_eq!(
            md.lines().filter(|l| l.starts_with("| s2v |")).count(),
            2,
            "{md}"
        );
        assert_eq!(
            md.lines().filter(|l| l.starts_with("| 8 |")).count(),
            1,
            "{md}"
        );
    }
}

// The command.
use anyhow::Result;
use clap::Args;

/// The options of `cargo xtask bench-baselines`.
#[derive(Args)]
pub struct BenchArgs {
    /// Robot counts to sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [100, 1_000, 10_000, 100_000])]
    sizes: Vec<usize>,
    /// Number of tasks M.
    #[arg(long, default_value_t = afg_eval::dataset::TASKS)]
    tasks: usize,
    /// Largest N for the decentralised DA (its synchronous rounds take time about quadratic in N).
    #[arg(long, default_value_t = 1_000)]
    max_decentralised: usize,
    /// Time budget per measurement: repeat until it is spent (at least once, at most 20 runs).
    #[arg(long, default_value_t = 1.0)]
    seconds: f64,
}

/// Runs `cargo xtask bench-baselines`: prints the allocators' timing table.
pub fn run(args: BenchArgs) -> Result<()> {
    let (tasks, max_decentralised) = (args.tasks, args.max_decentralised);
    let md = allocators_markdown(&args.sizes, tasks, max_decentralised, args.seconds)?;
    print!("{md}");
    Ok(())
}

/// The options of `cargo xtask bench-models`.
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

/// Runs `cargo xtask bench-models`: prints the networks' timing table.
pub fn run_models(args: ModelBenchArgs) -> Result<()> {
    let (sizes, batch, rollout) = (&args.sizes, args.batch, args.rollout);
    let md = networks_markdown(sizes, batch, rollout, args.repeats, crate::ALLOCATOR_NAME)?;
    print!("{md}");
    Ok(())
}
