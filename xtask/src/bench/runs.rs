//! What the benchmarks that compare afg with outside solvers share: the folder for the
//! instance files they read, the check that the peers' Python is ready, and the loop
//! that measures each case under a progress bar (a JSON line per row with `--json`).

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, ensure};
use serde::Serialize;

/// The folder for instance files: `dir`, or a fresh one for `job` under the system's
/// temp folder.
pub fn scratch_dir(dir: Option<&Path>, job: &str) -> Result<PathBuf> {
    let dir = match dir {
        Some(d) => d.to_path_buf(),
        None => std::env::temp_dir().join(format!("afg-{job}-{}", std::process::id())),
    };
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    Ok(dir)
}

/// Checks that `python` imports every one of `modules` (the pip packages of the same
/// names), with the command that installs them where it does not.
pub fn check_python(python: &Path, modules: &[&str]) -> Result<()> {
    let ok = Command::new(python)
        .args(["-c", &format!("import {}", modules.join(", "))])
        .status()
        .with_context(|| format!("running {}", python.display()))?;
    ensure!(
        ok.success(),
        "{} cannot import {}: install them with `{0} -m pip install {}`",
        python.display(),
        modules.join(", "),
        modules.join(" ")
    );
    Ok(())
}

/// Measures every case in order under a progress bar named `job` (each described by
/// `describe`), printing each row as a JSON line as it comes when `json`.
pub fn measure_rows<C, R: Serialize>(
    job: &str,
    cases: &[C],
    json: bool,
    describe: impl Fn(&C) -> String,
    mut measure: impl FnMut(&C) -> Result<R>,
) -> Result<Vec<R>> {
    let bar = afg_eval::report::progress(cases.len() as u64, job);
    let mut rows = Vec::new();
    for case in cases {
        bar.set_message(format!("{job} {}", describe(case)));
        let row = measure(case)?;
        if json {
            bar.suspend(|| println!("{}", serde_json::to_string(&row).expect("a row")));
        }
        rows.push(row);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(rows)
}
