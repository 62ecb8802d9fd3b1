//! The peers of the team benchmarks: `scripts/teams_milp.py` (CP-SAT or HiGHS) on an
//! instance file, its answer scored by afg.

use std::path::Path;
use std::process::Command;

use afg_game::{Assignment, Instance, TaskId};
use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

/// What a peer did at one budget.
#[derive(Serialize)]
pub(crate) struct Peer {
    pub(super) solver: String,
    pub(super) budget: f64,
    pub(super) status: String,
    /// The welfare of its assignment, computed by afg (`None`: none found).
    pub(crate) welfare: Option<f64>,
    /// Its proven bound (`None`: none yet).
    pub(super) bound: Option<f64>,
    pub(crate) seconds: f64,
}

/// Runs `scripts/teams_milp.py` with `solver` at `budget` seconds on `file`.
pub(crate) fn peer(
    python: &Path,
    solver: &str,
    budget: f64,
    threads: Option<usize>,
    file: &Path,
    inst: &Instance,
) -> Result<Peer> {
    #[derive(Deserialize)]
    struct Solved {
        status: String,
        seconds: f64,
        bound: Option<f64>,
        tasks: Option<Vec<i64>>,
    }
    let out = file.with_extension(format!("{solver}-{budget}.json"));
    let script = crate::repo_root().join("scripts").join("teams_milp.py");
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let status = Command::new(python)
        .arg(&script)
        .args([file, &out])
        .args(["--solver", solver, "--time-limit", &budget.to_string()])
        .args(["--threads", &threads.to_string()])
        .stdout(std::process::Stdio::null())
        .status()?;
    if !status.success() {
        bail!(
            "{} --solver {solver} failed on {}",
            script.display(),
            file.display()
        );
    }
    let mut solved: Vec<Solved> = serde_json::from_slice(&std::fs::read(&out)?)?;
    let solved = solved.pop().context("the peer returned no result")?;
    let welfare = match solved.tasks {
        Some(tasks) => {
            let tasks = tasks
                .iter()
                .map(|&j| u32::try_from(j).ok().map(TaskId))
                .collect();
            Some(inst.welfare(&Assignment::from_tasks(inst, tasks)?))
        }
        None => None,
    };
    Ok(Peer {
        solver: solver.to_owned(),
        budget,
        status: solved.status,
        welfare,
        bound: solved.bound,
        seconds: solved.seconds,
    })
}
