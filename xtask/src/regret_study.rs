//! The regret diagnosis: where along its greedy rollout a trained model loses welfare,
//! measured against the exact Q\* of every step ([`afg_learn::policy::regret_trace`]).
//!
//! A policy's shortfall telescopes: `OPT − W(final) = Σ_t [max_a Q*(s_t, a) − Q*(s_t,
//! a_t)]`, so each step's regret is its share of the loss.
//!
//! `cargo xtask regret`: where along a rollout a trained model loses welfare, measured
//! against the exact Q* (`afg_learn::policy::regret_trace`).

use std::path::Path;

use afg_baseline::{Allocator, Optimum};
use afg_game::Instance;
use afg_graph::{GraphKind, RobotGraph};
use afg_learn::{LearnError, fast::FastPolicy, policy::regret_trace, run::RunDir};
use serde::Serialize;

use afg_eval::EvalError;

/// What the regret diagnosis reports for one model on one dataset.
#[derive(Clone, Debug, Serialize)]
pub struct RegretSummary {
    /// The run directory.
    pub model: String,
    /// Robots N of the instances.
    pub robots: usize,
    /// Instances rolled out.
    pub instances: usize,
    /// Mean welfare / OPT, percent.
    pub percent_of_opt: f64,
    /// Share of the total regret made in each tenth of the rollout (t / N), percent.
    pub regret_by_decile: [f64; 10],
    /// Steps whose action was not optimal (regret > 1e-9), percent.
    pub wrong_steps: f64,
    /// Q* action gap (best − second best), raw welfare: 10th, 50th, 90th percentiles.
    pub gap_quantiles: [f64; 3],
    /// RMS of the network's error on the action it took, `Q(s, a_t) − Q*(s, a_t)`, in
    /// raw welfare (shaped networks: after adding back the potential).
    pub q_error_rms: f64,
    /// RMS of the error of the network's advantages, `(Q(s, a) − mean Q(s, ·)) −
    /// (Q*(s, a) − mean Q*(s, ·))` over the allowed tasks, raw welfare: the part of the
    /// error that decides actions (the state value cancels).
    pub advantage_error_rms: f64,
    /// Median action gap over the RMS advantage error: below 1 the network cannot tell
    /// actions apart.
    pub gap_over_error: f64,
    /// Mean share of robots on the most common task.
    pub largest_task_share: f64,
    /// Mean over instances of the mean task reward r̄ (the mean-reward welfare unit):
    /// the median gap in that unit is `gap_quantiles[1] / mean_reward`.
    pub mean_reward: f64,
}

/// Rolls the model of run directory `dir` out greedily on each of `instances` (at
/// least one) and measures every step against the exact Q\* ([`regret_trace`]);
/// `on_instance` is called after each instance (for a progress bar).
///
/// # Errors
/// No instance, a run directory without config or weights, or a failed rollout.
pub fn summarise(
    dir: &Path,
    instances: &[Instance],
    mut on_instance: impl FnMut(),
) -> Result<RegretSummary, EvalError> {
    if instances.is_empty() {
        return Err(EvalError::NoInstances);
    }
    let run = RunDir::new(dir);
    let config = run.config()?;
    let policy = afg_learn::run::load_q_network(dir)?;
    let fast = FastPolicy::from_network(policy.config(), policy.network());
    let (mut by_decile, mut total_regret) = ([0.0f64; 10], 0.0);
    let (mut gaps, mut sq_error, mut wrong, mut steps) = (Vec::new(), 0.0, 0usize, 0usize);
    let (mut sq_advantage, mut advantages) = (0.0, 0usize);
    let (mut pct, mut share, mut mean_reward) = (0.0, 0.0, 0.0);
    for inst in instances {
        let n = inst.num_robots();
        let graph =
            RobotGraph::build(inst.robots(), GraphKind::default()).map_err(LearnError::from)?;
        let (trace, final_assignment) = regret_trace(&fast, inst, &graph)?;
        let opt = inst.welfare(&Optimum.allocate(inst)?.assignment);
        pct += afg_eval::percent_of_opt(inst.welfare(&final_assignment), opt)
            .ok_or(EvalError::PercentUndefined)?;
        mean_reward += afg_graph::feature_scale(inst);
        share += *final_assignment.sizes().iter().max().unwrap_or(&0) as f64 / n as f64;
        let mut before = afg_game::Assignment::unassigned(n, inst.num_tasks());
        for s in &trace {
            by_decile[(10 * s.t / n).min(9)] += s.regret;
            total_regret += s.regret;
            wrong += usize::from(s.regret > 1e-9);
            steps += 1;
            gaps.push(s.gap);
            let unit = if config.reward_scaling { s.unit } else { 1.0 };
            // A shaped network learns Q − Φ, Φ(s) = W(completion of s) − W(s).
            let potential = config.shaping.potential(inst, &before);
            let error = s.q[s.action.index()] * unit + potential - s.q_star_taken;
            sq_error += error * error;
            let allowed: Vec<(f64, f64)> =
                s.q.iter()
                    .zip(&s.q_star)
                    .filter_map(|(&q, star)| star.map(|star| (q * unit, star)))
                    .collect();
            let count = allowed.len() as f64;
            let (mean_q, mean_star) = allowed.iter().fold((0.0, 0.0), |(a, b), (q, star)| {
                (a + q / count, b + star / count)
            });
            for (q, star) in &allowed {
                let e = (q - mean_q) - (star - mean_star);
                sq_advantage += e * e;
                advantages += 1;
            }
            before.set(afg_game::RobotId(s.t as u32), Some(s.action));
        }
        on_instance();
    }
    gaps.sort_by(f64::total_cmp);
    let quantile = |q: f64| gaps[((gaps.len() - 1) as f64 * q).round() as usize];
    let k = instances.len() as f64;
    let q_error_rms = (sq_error / steps as f64).sqrt();
    let advantage_error_rms = (sq_advantage / advantages as f64).sqrt();
    Ok(RegretSummary {
        model: dir.display().to_string(),
        robots: instances[0].num_robots(),
        instances: instances.len(),
        percent_of_opt: pct / k,
        regret_by_decile: by_decile.map(|r| 100.0 * r / total_regret.max(1e-12)),
        wrong_steps: 100.0 * wrong as f64 / steps as f64,
        gap_quantiles: [quantile(0.1), quantile(0.5), quantile(0.9)],
        q_error_rms,
        advantage_error_rms,
        gap_over_error: quantile(0.5) / advantage_error_rms,
        largest_task_share: share / k,
        mean_reward: mean_reward / k,
    })
}

/// The summaries as a Markdown table, one row per model.
pub fn markdown(rows: &[RegretSummary]) -> String {
    let mut out = String::from(
        "| model | N | % of OPT | regret by tenth of the rollout (% of the total) | wrong steps | Q* gap p10 / p50 / p90 | gap p50 / r̄ | Q error (RMS) | advantage error (RMS) | gap p50 / advantage error | largest task |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let deciles: Vec<String> = r
            .regret_by_decile
            .iter()
            .map(|d| format!("{d:.0}"))
            .collect();
        out += &format!(
            "| {} | {} | {:.2} % | {} | {:.1} % | {:.3} / {:.3} / {:.3} | {:.4} | {:.3} | {:.3} | {:.2} | {:.2} |\n",
            r.model,
            r.robots,
            r.percent_of_opt,
            deciles.join(" · "),
            r.wrong_steps,
            r.gap_quantiles[0],
            r.gap_quantiles[1],
            r.gap_quantiles[2],
            r.gap_quantiles[1] / r.mean_reward,
            r.q_error_rms,
            r.advantage_error_rms,
            r.gap_over_error,
            r.largest_task_share
        );
    }
    out
}

// The command.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

/// The options of `cargo xtask regret`.
#[derive(Args)]
pub struct RegretArgs {
    /// Run directories (each with config.json and model.*).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Robots N of the committed dataset to roll out on (datasets/n{N}.jsonl).
    #[arg(long)]
    dataset: usize,
    /// Use the first K instances only (each costs N·M optimal completions).
    #[arg(long, default_value_t = 20)]
    instances: usize,
    /// Also write the summaries as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `cargo xtask regret` and prints its table.
pub fn run(args: RegretArgs) -> Result<()> {
    let mut instances = crate::datasets::load(args.dataset)?;
    instances.truncate(args.instances.max(1));
    let rows = args
        .dirs
        .iter()
        .map(|d| {
            let bar = afg_eval::report::progress(
                instances.len() as u64,
                &format!("regret {}", d.display()),
            );
            let summary = summarise(d, &instances, || bar.inc(1));
            bar.finish_and_clear();
            summary
        })
        .collect::<Result<Vec<_>, _>>()?;
    print!("{}", markdown(&rows));
    if let Some(path) = &args.json {
        afg_game::fs::write_atomic(path, serde_json::to_string_pretty(&rows)?.as_bytes())?;
    }
    Ok(())
}
