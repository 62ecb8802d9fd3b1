//! What a user sees when a command fails: one line on stderr and exit status 1, whatever
//! `RUST_BACKTRACE` says; usage errors exit with 2.

use std::process::{Command, Output};

fn afg(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_afg"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("afg runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_failing_command_prints_one_line_and_exits_1_even_with_backtraces_on() {
    let missing = std::env::temp_dir().join(format!("afg-no-such-{}.json", std::process::id()));
    let out = afg(&[
        "solve",
        "--method",
        "opt",
        "--input",
        missing.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let text = stderr(&out);
    assert_eq!(text.lines().count(), 1, "{text}");
    assert!(
        text.starts_with("error: ") && text.contains("afg-no-such"),
        "{text}"
    );
    // Each cause once, even where an error prints its source in its own message.
    assert_eq!(text.matches("No such file").count(), 1, "{text}");

    // A failed `gen` (instances or a mission) creates no file.
    let out_path = std::env::temp_dir().join(format!("afg-not-made-{}.jsonl", std::process::id()));
    let out_arg = out_path.to_str().unwrap();
    let out = afg(&[
        "gen",
        "--robots",
        "10",
        "--capacity-slack",
        "0.5",
        "--out",
        out_arg,
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr(&out),
        "error: invalid generator parameter: capacity slack must be at least 1 (got 0.5)\n"
    );
    assert!(!out_path.exists());
    let mission = [
        "mission", "gen", "--preset", "waves", "--robots", "5", "--tasks", "2",
    ];
    let out = afg(&[&mission[..], &["--speed=-1", "--out", out_arg]].concat());
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(!out_path.exists());
}

#[test]
fn a_usage_error_exits_2() {
    let out = afg(&["swarm", "--preference", "kind"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("[possible values: balanced, selfish]"));
}

/// `afg score` on GRAPE's published runs: their utility, to the printed digit; and each
/// kind of bad assignment (a task ≥ M, −1 in the paper's game, a wrong length) is one
/// line and exit 1.
#[test]
fn afg_score_reads_grapes_runs_and_refuses_bad_assignments_in_one_line() {
    let dataset = concat!(env!("CARGO_MANIFEST_DIR"), "/../../datasets/grape-fig7");
    let out = afg(&[
        "score",
        "--input",
        &format!("{dataset}/instances.jsonl"),
        "--assignment",
        &format!("{dataset}/grape-partitions.jsonl"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    // GRAPE's published utilities (published.json), to three decimals.
    for utility in ["461790.574", "350669.082", "309411.453"] {
        assert!(text.contains(utility), "{text}");
    }
    let dir = std::env::temp_dir().join(format!("afg-score-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let instance = dir.join("paper.json");
    let made = afg(&[
        "gen",
        "--robots",
        "3",
        "--tasks",
        "2",
        "--out",
        instance.to_str().unwrap(),
    ]);
    assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    let assignment = dir.join("a.json");
    for (tasks, needle) in [
        ("[0,1,2]", "task 2"),
        ("[0,-1,1]", "robot 1 has no task (-1)"),
        ("[0,1]", "2 entries"),
    ] {
        let line = format!(r#"{{"format":"afg-assignment","version":1,"tasks":{tasks}}}"#);
        std::fs::write(&assignment, line).unwrap();
        let out = afg(&[
            "score",
            "--input",
            instance.to_str().unwrap(),
            "--assignment",
            assignment.to_str().unwrap(),
        ]);
        let text = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{tasks}: {text}");
        assert_eq!(text.lines().count(), 1, "{text}");
        assert!(text.contains(needle), "{tasks}: {text}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `afg mission`: a generated mission runs (JSON metrics, a trace of JSON Lines), and a
/// broken mission file is one line and exit 1.
#[test]
fn afg_mission_runs_and_refuses_a_broken_mission_in_one_line() {
    let dir = std::env::temp_dir().join(format!("afg-mission-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mission = dir.join("m.json");
    let path = mission.to_str().unwrap();
    let args = ["mission", "gen", "--preset", "attrition", "--robots", "12"];
    let made = afg(&[&args[..], &["--tasks", "4", "--out", path]].concat());
    assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    // A knob out of range: one line, exit 1, and the file already there untouched.
    let before = std::fs::read(&mission).unwrap();
    let bad = ["--tasks", "4", "--fail-share", "2", "--out", path];
    let refused = afg(&[&args[..], &bad].concat());
    assert_eq!(refused.status.code(), Some(1));
    let err = stderr(&refused);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("share of robots that fail"), "{err}");
    assert_eq!(std::fs::read(&mission).unwrap(), before);
    let trace = dir.join("t.jsonl");
    let trace_path = trace.to_str().unwrap();
    let ran = afg(&[
        "mission",
        "run",
        "--mission",
        path,
        "--method",
        "da",
        "--warm",
        "--json",
        "--trace",
        trace_path,
    ]);
    assert_eq!(ran.status.code(), Some(0), "{}", stderr(&ran));
    let metrics: serde_json::Value = serde_json::from_slice(&ran.stdout).unwrap();
    assert_eq!(metrics["tasks"], 4);
    let events = std::fs::read_to_string(&trace).unwrap();
    assert!(
        events
            .lines()
            .all(|l| serde_json::from_str::<serde_json::Value>(l).is_ok())
    );
    assert!(events.contains("\"event\":\"robot_fails\""));
    // GRAPE over the radio: its rounds and traffic in the JSON; a central knob with it
    // is one line and exit 1, the trace already written untouched.
    let grape = ["mission", "run", "--mission", path, "--method", "grape"];
    let ran = afg(&[&grape[..], &["--radius", "0.5", "--loss", "0.2", "--json"]].concat());
    assert_eq!(ran.status.code(), Some(0), "{}", stderr(&ran));
    let metrics: serde_json::Value = serde_json::from_slice(&ran.stdout).unwrap();
    assert!(metrics["swarm"]["rounds"].as_u64().unwrap() > 0);
    assert!(metrics["swarm"]["messages"].as_u64().unwrap() > 0);
    let before = std::fs::read(&trace).unwrap();
    let refused = afg(&[&grape[..], &["--latency", "1", "--trace", trace_path]].concat());
    assert_eq!(refused.status.code(), Some(1));
    let err = stderr(&refused);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("decentralised"), "{err}");
    assert_eq!(std::fs::read(&trace).unwrap(), before);
    // A Q network built for M = 5 among 4 open tasks: the decision says so.
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/paper/afgnet_ddqn_n20"
    );
    let out = afg(&["mission", "run", "--mission", path, "--model", model]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("the decision at time 0.000") && err.contains("M = 5"),
        "{err}"
    );
    let text = std::fs::read_to_string(&mission).unwrap();
    std::fs::write(
        &mission,
        text.replacen("\"speed\":1.0", "\"speed\":\"fast\"", 1),
    )
    .unwrap();
    let out = afg(&["mission", "run", "--mission", path]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("m.json") && err.contains("invalid mission JSON"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Skill knobs without `--skills`, or a malformed `--requires`, are refused before
/// anything is written.
#[test]
fn afg_train_staffing_refuses_skill_knobs_without_skills() {
    let dir = std::env::temp_dir().join(format!("afg-staffing-knobs-{}", std::process::id()));
    let out_dir = dir.to_str().unwrap();
    for (flags, says) in [
        (
            &["--skill-share", "0.2"][..],
            "a skill share or requirements need skills (a number of skills S ≥ 1)",
        ),
        (
            &["--skills", "2", "--requires", "1,2,3"][..],
            "--requires takes two numbers, LO,HI",
        ),
        (
            &["--skills", "2", "--requires", "3,1"][..],
            "requires range 3..=1 is empty",
        ),
        (
            &["--skills", "1000000"][..],
            "at most 64 skills (got 1000000)",
        ),
    ] {
        let out = afg(&[&["train-staffing", "--out", out_dir][..], flags].concat());
        assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
        assert!(stderr(&out).contains(says), "{}", stderr(&out));
        assert!(!dir.exists(), "{flags:?} wrote {}", dir.display());
    }
}

#[test]
fn afg_train_staffing_keeps_an_existing_model_unless_forced() {
    let dir = std::env::temp_dir().join(format!("afg-staffing-kept-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("staffing.json");
    std::fs::write(&model, "a model already trained").unwrap();
    let out = afg(&["train-staffing", "--out", dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert_eq!(
        stderr(&out),
        format!(
            "error: {} exists; pass --force to replace it\n",
            model.display()
        )
    );
    assert_eq!(
        std::fs::read_to_string(&model).unwrap(),
        "a model already trained"
    );
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `afg solve … | head`: a reader that closes the pipe ends the command quietly, with
/// no panic and no stack trace (even with backtraces on).
#[test]
fn a_closed_pipe_ends_the_command_quietly() {
    let dataset = concat!(env!("CARGO_MANIFEST_DIR"), "/../../datasets/n100.jsonl");
    let mut child = Command::new(env!("CARGO_BIN_EXE_afg"))
        .args(["solve", "--method", "greedy", "--input", dataset, "--json"])
        .env("RUST_BACKTRACE", "1")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("afg runs");
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{:?}: {}", out.status, stderr(&out));
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
}

/// "% of OPT" on a team game: measured against the exact optimum within
/// --reference-time-limit (against its certified bound, said so, where not proven),
/// or not at all with --no-reference.
#[test]
fn afg_solve_measures_team_games_within_a_time_limit_or_not_at_all() {
    let dir = std::env::temp_dir().join(format!("afg-reference-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scarce.jsonl");
    let file = file.to_str().unwrap();
    let made = afg(&[
        "gen",
        "--robots",
        "100",
        "--tasks",
        "10",
        "--min-team",
        "10,20",
        "--seed",
        "1",
        "--out",
        file,
    ]);
    assert!(made.status.success(), "{}", stderr(&made));
    let solve = |extra: &[&str]| -> serde_json::Value {
        let args = [
            &["solve", "--method", "nearest", "--input", file, "--json"][..],
            extra,
        ]
        .concat();
        let out = afg(&args);
        assert!(out.status.success(), "{}", stderr(&out));
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let exact = &solve(&[])["rows"][0];
    assert_eq!(exact["reference"]["proven"], true);
    let rushed = &solve(&["--reference-time-limit", "1e-9"])["rows"][0];
    let bound = rushed["reference"]["bound"].as_f64().unwrap();
    assert_eq!(rushed["reference"]["proven"], false);
    assert!(bound > exact["opt_welfare"].as_f64().unwrap());
    let percent = rushed["percent_of_opt"].as_f64().unwrap();
    assert!((percent - 100.0 * rushed["welfare"].as_f64().unwrap() / bound).abs() < 1e-9);
    let alone = &solve(&["--no-reference"])["rows"][0];
    assert!(alone["percent_of_opt"].is_null() && alone.get("reference").is_none());
    let bad = afg(&[
        "solve",
        "--method",
        "nearest",
        "--input",
        file,
        "--reference-time-limit",
        "0",
    ]);
    assert_eq!(bad.status.code(), Some(1));
    assert!(
        stderr(&bad).contains("finite and positive"),
        "{}",
        stderr(&bad)
    );
    std::fs::remove_dir_all(dir).unwrap();
}
