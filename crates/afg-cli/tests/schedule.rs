//! `afg schedule` as a user meets it: draw, plan, score and show, the published set
//! scored as published, and refusals in one line.

use std::path::PathBuf;
use std::process::{Command, Output};

fn afg(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_afg"))
        .args(args)
        .output()
        .expect("afg runs")
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn fresh(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("afg-schedule-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn dataset(file: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../datasets/dcmrta-20a50t")
        .join(file)
        .display()
        .to_string()
}

#[test]
fn gen_solve_score_and_show_agree_with_each_other() {
    let dir = fresh("round");
    let (inst, plans, svg) = (dir.join("i.jsonl"), dir.join("s.jsonl"), dir.join("g.svg"));
    let (inst, plans, svg) = (
        inst.to_str().unwrap(),
        plans.to_str().unwrap(),
        svg.to_str().unwrap(),
    );
    for family in ["dcmrta", "heteromrta"] {
        let out = afg(&[
            "schedule", "gen", "--family", family, "--robots", "9", "--tasks", "20", "--count",
            "2", "--out", inst,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let out = afg(&[
            "schedule", "solve", "--input", inst, "--steps", "2000", "--json", "--out", plans,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let solved: Vec<serde_json::Value> = stdout(&out)
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let out = afg(&[
            "schedule",
            "score",
            "--input",
            inst,
            "--schedule",
            plans,
            "--json",
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let scored: Vec<serde_json::Value> = stdout(&out)
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        assert_eq!(solved.len(), 2);
        for (s, c) in solved.iter().zip(&scored) {
            assert_eq!(s["makespan"], c["makespan"]);
            assert_eq!(c["valid"], true);
            assert_eq!(s["time_use"], c["time_use"]);
            let parts: f64 = ["working", "driving", "waiting", "idle"]
                .iter()
                .map(|p| s["time_use"][p].as_f64().unwrap())
                .sum();
            assert!((parts - s["makespan"].as_f64().unwrap()).abs() < 1e-9);
            assert!(s["bound"].as_f64().unwrap() <= s["makespan"].as_f64().unwrap());
            let gap = 1.0 - s["bound"].as_f64().unwrap() / s["makespan"].as_f64().unwrap();
            assert!((s["gap"].as_f64().unwrap() - gap).abs() < 1e-12);
        }
        let out = afg(&[
            "schedule",
            "show",
            "--input",
            inst,
            "--schedule",
            plans,
            "--line",
            "1",
            "--out",
            svg,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let drawn = std::fs::read_to_string(svg).unwrap();
        assert!(
            drawn.starts_with("<svg")
                && drawn.contains(&format!(
                    "makespan {:.2}",
                    solved[1]["makespan"].as_f64().unwrap()
                ))
        );
    }
}

#[test]
fn the_published_routes_score_as_published_and_their_long_waits_are_named() {
    let (inst, routes) = (
        dataset("dcmrta-20a50t.jsonl"),
        dataset("dcmrta-20a50t-routes.jsonl"),
    );
    let out = afg(&["schedule", "score", "--input", &inst, "--schedule", &routes]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stdout(&out)
            .starts_with("line 0: makespan 41.898399  travel 44.977347  mean wait 7.616267"),
        "{}",
        stdout(&out)
    );
    let out = afg(&[
        "schedule",
        "score",
        "--input",
        &inst,
        "--schedule",
        &routes,
        "--max-wait",
        "10",
    ]);
    let text = stdout(&out);
    assert!(text.contains("line 0: makespan 41.898399") && text.contains("INVALID"));
    assert!(
        text.contains("robot 9 waits 12.145 at task 48, longer than max_wait 10"),
        "{text}"
    );
}

#[test]
fn bad_input_is_refused_in_one_line() {
    let dir = fresh("refusals");
    let inst = dir.join("i.jsonl");
    let inst = inst.to_str().unwrap();
    std::fs::write(
        inst,
        r#"{"speed":1,"max_wait":10,"depots":[[0,0]],"robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],"tasks":[{"x":1,"y":0,"min_team":2,"duration":1},{"x":0,"y":1,"min_team":2,"duration":1}]}"#,
    )
    .unwrap();
    // Scores the one-line schedule `routes` against the instance.
    let score = |name: &str, routes: &str| {
        let file = dir.join(name);
        std::fs::write(&file, format!("{{\"routes\":{routes}}}\n")).unwrap();
        afg(&[
            "schedule",
            "score",
            "--input",
            inst,
            "--schedule",
            file.to_str().unwrap(),
        ])
    };
    let out = score("d.jsonl", "[[0,1],[1,0]]");
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("deadlocks: robot 0 waits at task 0, robot 1 waits at task 1"),
        "{}",
        stderr(&out)
    );
    let out = score("l.jsonl", "[[0],[0]]");
    assert!(
        stderr(&out).contains("leaves out task 1"),
        "{}",
        stderr(&out)
    );
    for (args, says) in [
        (
            vec!["schedule", "solve", "--input", inst, "--time-limit", "-1"],
            "time limit",
        ),
        (
            vec!["schedule", "solve", "--input", inst, "--max-wait", "nan"],
            "max_wait",
        ),
        (
            vec!["schedule", "gen", "--family", "swarm", "--out", inst],
            "unknown family",
        ),
        (
            vec!["schedule", "gen", "--robots", "0", "--out", inst],
            "1 to",
        ),
    ] {
        let out = afg(&args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = stderr(&out);
        assert!(
            err.contains(says) && err.lines().count() == 1,
            "{args:?}: {err}"
        );
    }
}

#[test]
fn instances_solved_at_once_come_out_as_one_at_a_time_in_order() {
    let dir = fresh("jobs");
    let inst = dir.join("i.jsonl");
    let inst = inst.to_str().unwrap();
    // A larger instance first, so that the small ones after it are done before it.
    let mut lines = String::new();
    for (robots, tasks, count) in [("12", "60", "1"), ("6", "12", "4")] {
        let out = afg(&[
            "schedule", "gen", "--robots", robots, "--tasks", tasks, "--count", count, "--out",
            inst,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        lines += &std::fs::read_to_string(inst).unwrap();
    }
    std::fs::write(inst, lines).unwrap();
    // Each run's lines without their timing, and its schedules.
    let run = |jobs: &str| {
        let plans = dir.join(format!("s{jobs}.jsonl"));
        let out = afg(&[
            "schedule",
            "solve",
            "--input",
            inst,
            "--steps",
            "3000",
            "--json",
            "--jobs",
            jobs,
            "--out",
            plans.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let lines: Vec<serde_json::Value> = stdout(&out)
            .lines()
            .map(|l| {
                let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                v.as_object_mut().unwrap().remove("seconds");
                v
            })
            .collect();
        (lines, std::fs::read_to_string(plans).unwrap())
    };
    let one = run("1");
    assert_eq!(one.0.len(), 5);
    assert!(one.0.iter().enumerate().all(|(k, v)| v["line"] == k));
    assert_eq!(run("3"), one);
    assert_eq!(run("0"), one);

    // The second of three instances has no schedule within its own max_wait: the first
    // is printed, the error names line 2, and nothing is written.
    let bad = dir.join("bad.jsonl");
    let ok = r#"{"speed":1,"max_wait":10,"depots":[[0,0]],"robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],"tasks":[{"x":1,"y":0,"min_team":2,"duration":1}]}"#;
    let apart = r#"{"speed":1,"max_wait":0.5,"depots":[[0,0],[5,0]],"robots":[{"x":0,"y":0,"depot":0},{"x":5,"y":0,"depot":1}],"tasks":[{"x":1,"y":0,"min_team":2,"duration":1}]}"#;
    std::fs::write(&bad, format!("{ok}\n{apart}\n{ok}\n")).unwrap();
    let plans = dir.join("never.jsonl");
    let out = afg(&[
        "schedule",
        "solve",
        "--input",
        bad.to_str().unwrap(),
        "--steps",
        "100",
        "--jobs",
        "3",
        "--out",
        plans.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stdout(&out).starts_with("line 0: makespan"),
        "{}",
        stdout(&out)
    );
    assert!(!stdout(&out).contains("line 2:"), "{}", stdout(&out));
    assert!(stderr(&out).contains("line 2"), "{}", stderr(&out));
    assert!(!plans.exists());
}

#[test]
fn a_search_started_from_its_own_schedules_never_loses_ground() {
    let dir = fresh("start");
    let (inst, first, second) = (
        dir.join("i.jsonl"),
        dir.join("a.jsonl"),
        dir.join("b.jsonl"),
    );
    let (inst, first, second) = (
        inst.to_str().unwrap(),
        first.to_str().unwrap(),
        second.to_str().unwrap(),
    );
    let out = afg(&[
        "schedule", "gen", "--robots", "8", "--tasks", "20", "--count", "3", "--out", inst,
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let makespans = |out: &Output| -> Vec<f64> {
        stdout(out)
            .lines()
            .map(|l| {
                serde_json::from_str::<serde_json::Value>(l).unwrap()["makespan"]
                    .as_f64()
                    .unwrap()
            })
            .collect()
    };
    let out = afg(&[
        "schedule", "solve", "--input", inst, "--steps", "3000", "--json", "--out", first,
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let before = makespans(&out);
    let out = afg(&[
        "schedule", "solve", "--input", inst, "--steps", "0", "--seed", "7", "--json", "--start",
        first, "--out", second,
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let after = makespans(&out);
    assert_eq!(after.len(), 3);
    assert!(
        before.iter().zip(&after).all(|(b, a)| a <= b),
        "{before:?} {after:?}"
    );

    // A start that names a task the instance lacks is refused, naming its file and line.
    let one = std::fs::read_to_string(first).unwrap();
    let mut lines: Vec<String> = one.lines().map(String::from).collect();
    let mut bad: serde_json::Value = serde_json::from_str(&lines[1]).unwrap();
    bad["routes"][0] = serde_json::json!([999]);
    lines[1] = bad.to_string();
    std::fs::write(second, lines.join("\n")).unwrap();
    let out = afg(&[
        "schedule", "solve", "--input", inst, "--steps", "0", "--start", second,
    ]);
    assert_eq!(out.status.code(), Some(1));
    let text = stderr(&out);
    assert!(
        text.contains(&format!("started from {second} line 2"))
            && text.contains("sends robot 0 to task 999"),
        "{text}"
    );

    // One schedule for three instances is refused before any search.
    std::fs::write(second, one.lines().next().unwrap()).unwrap();
    let out = afg(&["schedule", "solve", "--input", inst, "--start", second]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("holds 1 schedule(s) for the 3 instance(s)"),
        "{}",
        stderr(&out)
    );
}
