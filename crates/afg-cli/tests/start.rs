//! `afg solve --method opt --start FILE`: the exact optimum from the assignments a user
//! already has, and a start that does not fit refused in one line.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn afg(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_afg"))
        .args(args)
        .output()
        .expect("afg runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("afg-start-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// The mean welfare and every row's `proven` of `afg solve --json` on `input`.
fn solve(input: &Path, extra: &[&str]) -> (f64, Vec<bool>) {
    let args = [
        &[
            "solve",
            "--input",
            input.to_str().unwrap(),
            "--no-reference",
            "--json",
        ],
        extra,
    ]
    .concat();
    let out = afg(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let proven = (report["rows"].as_array().unwrap().iter())
        .map(|row| row["reference"]["proven"].as_bool().unwrap())
        .collect();
    (report["mean"]["welfare"].as_f64().unwrap(), proven)
}

#[test]
fn the_exact_optimum_starts_from_a_file_and_refuses_one_that_does_not_fit() {
    let games = scratch("games.jsonl");
    let g = games.to_str().unwrap();
    let made = afg(&[
        "gen",
        "--family",
        "sparse-skills",
        "--robots",
        "30",
        "--tasks",
        "6",
        "--count",
        "2",
        "--seed",
        "6",
        "--out",
        g,
    ]);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let first = scratch("first.jsonl");
    let (welfare, proven) = solve(
        &games,
        &["--method", "opt", "--out", first.to_str().unwrap()],
    );
    assert_eq!(proven, [true, true]);
    // From its own answers, the solver proves the same optimum.
    let (again, proven) = solve(
        &games,
        &["--method", "opt", "--start", first.to_str().unwrap()],
    );
    assert_eq!(proven, [true, true]);
    assert!((again - welfare).abs() < 1e-9, "{again} vs {welfare}");
    // Stopped at its first certified gap under 50 %, the search alone answers its
    // first dives' assignments, short of the optima; from the optima, the optima.
    let f = first.to_str().unwrap();
    let (alone, _) = solve(&games, &["--method", "opt", "--gap", "0.5"]);
    assert!(alone < welfare - 1e-9, "{alone} vs {welfare}");
    let (started, _) = solve(&games, &["--method", "opt", "--gap", "0.5", "--start", f]);
    assert!((started - welfare).abs() < 1e-9, "{started} vs {welfare}");

    let refused = |extra: &[&str], says: &str| {
        let args = [&["solve", "--input", g, "--no-reference"], extra].concat();
        let out = afg(&args);
        let text = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(1), "{text}");
        assert_eq!(text.lines().count(), 1, "{text}");
        assert!(text.contains(says), "{text} lacks {says:?}");
    };
    refused(
        &["--method", "da", "--start", f],
        "--start is for the exact optimum",
    );
    // A warm start from an earlier assignment (--from) is another thing: refused by
    // the argument parser beside --start.
    let both = afg(&[
        "solve", "--input", g, "--method", "opt", "--start", f, "--from", f,
    ]);
    assert_eq!(both.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&both.stderr).contains("cannot be used with"));
    let one = scratch("one.jsonl");
    let text = std::fs::read_to_string(&first).unwrap();
    std::fs::write(&one, text.lines().next().unwrap()).unwrap();
    refused(
        &["--method", "opt", "--start", one.to_str().unwrap()],
        "1 assignment lines for 2 instances",
    );
    let short = scratch("short.jsonl");
    let line = r#"{"format":"afg-assignment","version":1,"tasks":[0,1]}"#;
    std::fs::write(&short, format!("{line}\n{line}\n")).unwrap();
    refused(
        &["--method", "opt", "--start", short.to_str().unwrap()],
        "line 1",
    );
}
