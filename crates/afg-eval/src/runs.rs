//! What the logs of training runs show: validation curves ([`read_curve`], drawn by
//! [`crate::figures::curves_svg`]) and the summary table of finished runs
//! ([`report_markdown`]).

use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};

use afg_baseline::Method;
use afg_learn::{
    run::{LogEvent, RunDir, ValidationLine},
    train::TrainConfig,
};

use crate::EvalError;

/// The validation curve of one run.
pub struct Curve {
    /// "net_algo (N = n)".
    pub label: String,
    /// (gradient step, mean validation welfare).
    pub points: Vec<(f64, f64)>,
    /// Mean welfare of the classical methods on the validation set, as logged.
    pub baselines: Vec<(Method, f64)>,
}

/// What a run's log says about its training: the configuration and classical
/// baselines of its start event, its validations and the last elapsed time.
struct RunLog {
    config: Box<TrainConfig>,
    baselines: BTreeMap<Method, f64>,
    validations: Vec<ValidationLine>,
    elapsed_s: f64,
}

impl RunLog {
    /// Reads `dir/log.jsonl`, cut after gradient step `at_step` if given.
    fn read(dir: &Path, at_step: Option<u64>) -> Result<Self, EvalError> {
        let mut events = RunDir::new(dir).log()?;
        if let Some(last) = at_step {
            events.retain(|e| e.step().is_none_or(|s| s <= last));
        }
        let elapsed_s = events
            .iter()
            .rev()
            .find_map(LogEvent::elapsed_s)
            .unwrap_or(0.0);
        let mut start = None;
        let mut validations = Vec::new();
        for event in events {
            match event {
                LogEvent::Start {
                    config, baselines, ..
                } => start = Some((config, baselines)),
                LogEvent::Validation(v) => validations.push(v),
                _ => {}
            }
        }
        let (config, baselines) = start.ok_or_else(|| EvalError::Log {
            path: dir.display().to_string(),
            what: "no start event",
        })?;
        Ok(Self {
            config,
            baselines,
            validations,
            elapsed_s,
        })
    }
}

/// Reads the validation curve from `dir/log.jsonl`.
///
/// # Errors
/// A missing or unreadable log, or one without a start event.
pub fn read_curve(dir: &Path) -> Result<Curve, EvalError> {
    let log = RunLog::read(dir, None)?;
    let config = &log.config;
    Ok(Curve {
        label: format!(
            "{} ({}_{}, N = {})",
            RunDir::new(dir).name(),
            config.network.name(),
            config.algo.name(),
            config.robots
        ),
        points: log
            .validations
            .iter()
            .map(|v| (v.step as f64, v.welfare))
            .collect(),
        baselines: [Method::Opt, Method::Greedy, Method::Nearest, Method::Random]
            .into_iter()
            .filter_map(|m| Some((m, *log.baselines.get(&m)?)))
            .collect(),
    })
}

/// A Markdown table of training runs: final and best validation welfare against the
/// classical methods on the same validation set (all read from the runs' logs), then
/// the classical methods on each distinct validation set. With `at_step`, each run is
/// cut after that gradient step (runs compared at equal steps, or a stopped run
/// against a finished one).
///
/// # Errors
/// A missing log, or a log without a start event or a validation (up to `at_step`).
pub fn report_markdown(dirs: &[PathBuf], at_step: Option<u64>) -> Result<String, EvalError> {
    let mut out = String::from(
        "| run | N | steps | wall time | final validation welfare | % of OPT | best (step) | collapsed validations |\n|---|---|---|---|---|---|---|---|\n",
    );
    // Keyed by the scale's name: N, with M when it is not the paper's 5.
    let mut baseline_rows: Vec<(String, BTreeMap<Method, f64>)> = Vec::new();
    for dir in dirs {
        let run = RunDir::new(dir);
        let RunLog {
            config,
            baselines: logged,
            validations: vals,
            elapsed_s: wall,
        } = RunLog::read(dir, at_step)?;
        let last = vals.last().ok_or_else(|| EvalError::Log {
            path: dir.display().to_string(),
            what: "no validation",
        })?;
        let best = vals
            .iter()
            .max_by(|a, b| a.welfare.total_cmp(&b.welfare))
            .expect("non-empty");
        let n = match config.network.tasks() {
            crate::dataset::TASKS => config.robots.to_string(),
            m => format!("{} (M = {m})", config.robots),
        };
        // Validations where most robots took one task (logged since the collapse check
        // exists; "–" for older logs).
        let flagged: Vec<bool> = vals.iter().filter_map(|v| v.collapsed).collect();
        let collapsed = if flagged.is_empty() {
            "–".to_owned()
        } else {
            format!(
                "{} of {}",
                flagged.iter().filter(|&&c| c).count(),
                flagged.len()
            )
        };
        let _ = writeln!(
            out,
            "| {} | {n} | {} | {:.0} min | {:.3} | {:.2} % | {:.3} ({}) | {collapsed} |",
            run.name(),
            last.step,
            wall / 60.0,
            last.welfare,
            last.percent_of_opt,
            best.welfare,
            best.step
        );
        if !baseline_rows.iter().any(|(m, _)| *m == n) {
            baseline_rows.push((n.clone(), logged));
        }
    }
    out += "\nClassical methods on the same validation sets (mean welfare):\n\n";
    let methods = Method::CENTRALISED;
    let header: Vec<&str> = methods.iter().map(|m| m.label()).collect();
    let _ = writeln!(out, "| N | {} |", header.join(" | "));
    let _ = writeln!(out, "|---|{}", "---|".repeat(methods.len()));
    for (n, b) in baseline_rows {
        let cells: Vec<String> = methods
            .iter()
            .map(|m| b.get(m).map_or("–".into(), |v| format!("{v:.3}")))
            .collect();
        let _ = writeln!(out, "| {n} | {} |", cells.join(" | "));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_report_reads_a_log_up_to_a_step() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/paper/afgnet_ddqn_n20");
        let validations: Vec<ValidationLine> = RunDir::new(&dir)
            .log()
            .unwrap()
            .into_iter()
            .filter_map(|e| match e {
                LogEvent::Validation(v) => Some(v),
                _ => None,
            })
            .collect();
        let cut = validations[3].step + 1;
        let row = |at: Option<u64>| {
            let report = report_markdown(std::slice::from_ref(&dir), at).unwrap();
            report.lines().nth(2).unwrap().to_owned()
        };
        let whole = row(None);
        let early = row(Some(cut));
        let last = validations.last().unwrap();
        assert!(whole.contains(&format!("| {} |", last.step)), "{whole}");
        assert!(whole.contains(&format!("{:.3}", last.welfare)), "{whole}");
        assert!(
            early.contains(&format!("| {} |", validations[3].step)),
            "{early}"
        );
        assert!(
            early.contains(&format!("{:.3}", validations[3].welfare)),
            "{early}"
        );
        assert!(report_markdown(&[dir], Some(0)).is_err());
    }
}
