//! `afg mission` as a new user meets it: knobs that do not apply are refused, output
//! paths never overwrite inputs, rows of the same kind of model are told apart, and a
//! NaN in a mission file is named.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn afg(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_afg"))
        .args(args)
        .output()
        .expect("afg runs")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A fresh directory holding a small waves mission, `m.json`.
fn mission_dir(name: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("afg-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mission = dir.join("m.json");
    let args = [
        "mission", "gen", "--preset", "waves", "--robots", "12", "--tasks", "4",
    ];
    let made = afg(&[&args[..], &["--out", mission.to_str().unwrap()]].concat());
    assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    (dir, mission)
}

/// Exit 1 with one line on stderr holding `needle`.
fn refused(out: &Output, needle: &str) {
    assert_eq!(out.status.code(), Some(1), "{}", stderr(out));
    let err = stderr(out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{err}");
}

#[test]
fn a_radio_knob_with_a_central_method_is_refused_and_runs_with_grape() {
    let (dir, mission) = mission_dir("radio-knob");
    let path = mission.to_str().unwrap();
    for knob in [
        &["--radius", "0.3"][..],
        &["--loss", "0.2"],
        &["--knn", "3"],
        &["--activation", "0.5"],
    ] {
        let out = afg(&[
            &["mission", "run", "--mission", path, "--method", "greedy"][..],
            knob,
        ]
        .concat());
        refused(&out, "for grape and auction");
    }
    let out = afg(&[
        "mission",
        "run",
        "--mission",
        path,
        "--method",
        "grape",
        "--loss",
        "0.2",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_output_path_that_is_an_input_is_refused_and_the_input_kept() {
    let (dir, mission) = mission_dir("overwrite");
    let path = mission.to_str().unwrap();
    let before = std::fs::read(&mission).unwrap();
    for flag in ["--animate", "--trace"] {
        let out = afg(&["mission", "run", "--mission", path, flag, path]);
        refused(&out, &format!("{} {path} is an input", &flag[2..]));
        assert_eq!(std::fs::read(&mission).unwrap(), before);
    }
    // The same file by another spelling of its path.
    let other = dir.join(".").join("m.json");
    let out = afg(&[
        "mission",
        "compare",
        "--mission",
        path,
        "--svg",
        other.to_str().unwrap(),
    ]);
    refused(&out, "is an input");
    assert_eq!(std::fs::read(&mission).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn two_models_of_the_same_kind_get_rows_of_their_own() {
    let (dir, mission) = mission_dir("two-models");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let a = root.join("models/ours/price_n60");
    let b = root.join("models/ablations/price_expert_n60");
    let out = afg(&[
        "mission",
        "compare",
        "--mission",
        mission.to_str().unwrap(),
        "--methods",
        "greedy",
        "--model",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<&str> = (rows.as_array().unwrap().iter())
        .map(|r| r["method"].as_str().unwrap())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
    assert_eq!(names[0], "greedy");
    assert_ne!(names[1], names[2], "{names:?}");
    assert!(
        names[1].contains("price_n60") && names[2].contains("price_expert_n60"),
        "{names:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_nan_in_a_mission_file_is_named_with_its_field() {
    let (dir, mission) = mission_dir("nan");
    let text = std::fs::read_to_string(&mission).unwrap();
    let at = text.find("\"workload\":").unwrap() + "\"workload\":".len();
    let end = at + text[at..].find([',', '}']).unwrap();
    std::fs::write(&mission, format!("{}NaN{}", &text[..at], &text[end..])).unwrap();
    let out = afg(&["mission", "run", "--mission", mission.to_str().unwrap()]);
    refused(&out, "`NaN`");
    let err = stderr(&out);
    assert!(
        err.contains("field `workload`") && err.contains("JSON has no NaN or Infinity"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_animation_ends_on_the_final_state_and_shows_coalition_sizes() {
    let (dir, mission) = mission_dir("animate");
    let page = dir.join("a.html");
    let out = afg(&[
        "mission",
        "run",
        "--mission",
        mission.to_str().unwrap(),
        "--json",
        "--animate",
        page.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let metrics: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    let data = html
        .split("const D = ")
        .nth(1)
        .unwrap()
        .split(";\n")
        .next()
        .unwrap();
    let data: serde_json::Value = serde_json::from_str(&data.replace("<\\/", "</")).unwrap();
    let last = data["frames"].as_array().unwrap().last().unwrap();
    assert_eq!(last["time"].as_f64(), metrics["end"].as_f64());
    // Every task done in the final frame: no work left anywhere.
    assert_eq!(metrics["tasks_done"], 4);
    assert!(
        last["left"]
            .as_array()
            .unwrap()
            .iter()
            .all(|l| l.as_f64() == Some(0.0))
    );
    assert!(html.contains("sizes[j]") && html.contains("\"replay\""));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn team_knobs_out_of_range_are_refused_and_nothing_is_written() {
    let (dir, _) = mission_dir("team-knobs");
    let out_path = dir.join("teams.json");
    let out = out_path.to_str().unwrap();
    let generate = |knobs: &[&str]| {
        let base = [
            "mission", "gen", "--preset", "waves", "--robots", "12", "--tasks", "4",
        ];
        afg(&[&base[..], knobs, &["--out", out]].concat())
    };
    for (knobs, needle) in [
        (&["--requires", "1,2"][..], "need skills"),
        (&["--skill-share", "0.5"], "need skills"),
        (&["--min-team", "0,2"], "min_team"),
        (&["--min-team", "3"], "--min-team takes two numbers"),
    ] {
        refused(&generate(knobs), needle);
        assert!(!out_path.exists(), "{knobs:?} wrote {out}");
    }
    // A team mission runs; a time limit that is not a positive number, or one given to
    // a method other than opt, is refused.
    let made = generate(&["--min-team", "2,3"]);
    assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    let run = |extra: &[&str]| afg(&[&["mission", "run", "--mission", out][..], extra].concat());
    let ran = run(&["--method", "opt", "--time-limit", "5"]);
    assert_eq!(ran.status.code(), Some(0), "{}", stderr(&ran));
    let text = String::from_utf8_lossy(&ran.stdout);
    assert!(
        text.contains("waiting") && text.contains("largest gap"),
        "{text}"
    );
    refused(
        &run(&["--method", "opt", "--time-limit", "0"]),
        "finite and positive",
    );
    refused(
        &run(&["--method", "greedy", "--time-limit", "1"]),
        "for the exact optimum",
    );
    // The auction runs it, at ε = 0.01 by default on a team mission (its name says
    // so); given 0.001, the paper's game's default, it says that teams want more.
    for given in [&[][..], &["--epsilon", "0.03"]] {
        let auction = run(&[&["--method", "auction"][..], given].concat());
        assert_eq!(auction.status.code(), Some(0), "{}", stderr(&auction));
        assert!(!stderr(&auction).contains("note:"), "{}", stderr(&auction));
        let text = String::from_utf8_lossy(&auction.stdout);
        let epsilon = if given.is_empty() { "0.01" } else { "0.03" };
        assert!(text.contains(&format!("ε {epsilon})")), "{text}");
    }
    let noted = run(&["--method", "auction", "--epsilon", "0.001"]);
    assert_eq!(noted.status.code(), Some(0), "{}", stderr(&noted));
    assert!(
        stderr(&noted).contains(
            "note: the auction on a mission whose tasks need teams or skills wants --epsilon 0.01"
        ),
        "{}",
        stderr(&noted)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The staffing model decides team missions from its run directory: on waves of tasks
/// that need teams it finishes what the exact solver finishes, with at least 95 % of
/// its reward and at most 5 % more travel (nearest, the negative control, does not); a mission whose tasks need skills is refused in one line, and played by
/// the model trained on skill games as well as by the exact solver.
#[test]
fn the_staffing_model_decides_team_missions() {
    let (dir, _) = mission_dir("staffing");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let model = root.join("models/ours/staffing_teams");
    let model = model.to_str().unwrap();
    let mission = dir.join("teams.json");
    let path = mission.to_str().unwrap();
    let generate = |extra: &[&str]| {
        let base = [
            "mission",
            "gen",
            "--preset",
            "waves",
            "--robots",
            "60",
            "--tasks",
            "12",
            "--min-team",
            "4,8",
            "--seed",
            "3",
            "--out",
            path,
        ];
        let made = afg(&[&base[..], extra].concat());
        assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    };
    // Whether the last row (the model, or nearest as the negative control) finishes
    // what the exact solver finishes, with 95 % of its reward, its robots travelling
    // at most 5 % further.
    let as_well_as_opt = |methods: &str, model: Option<&str>| -> bool {
        let model = model.map_or(vec![], |m| vec!["--model", m]);
        let out = afg(&[
            &[
                "mission",
                "compare",
                "--mission",
                path,
                "--methods",
                methods,
                "--json",
            ][..],
            &model,
        ]
        .concat());
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let rows: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(rows[0]["method"], "opt");
        let last = rows.len() - 1;
        if !model.is_empty() {
            assert!(rows[last]["method"].as_str().unwrap().contains("staffing"));
        }
        let metric = |row: usize, key: &str| rows[row]["missions"][0][key].as_f64().unwrap();
        metric(last, "tasks_done") == metric(0, "tasks_done")
            && metric(last, "reward_done") >= 0.95 * metric(0, "reward_done")
            && metric(last, "distance") <= 1.05 * metric(0, "distance")
    };
    generate(&[]);
    assert!(as_well_as_opt("opt", Some(model)));
    // The criterion can fail: nearest, on the same mission, does not meet it.
    assert!(!as_well_as_opt("opt,nearest", None));
    generate(&["--skills", "2", "--requires", "1,1"]);
    // With its default methods, a comparison on the skill mission shows those that play
    // it and names those that refuse it.
    let compared = afg(&["mission", "compare", "--mission", path, "--json"]);
    assert_eq!(compared.status.code(), Some(0), "{}", stderr(&compared));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&compared.stdout).unwrap();
    let shown: Vec<&str> = rows.iter().map(|r| r["method"].as_str().unwrap()).collect();
    assert!(
        shown.contains(&"opt") && !shown.contains(&"greedy"),
        "{shown:?}"
    );
    assert!(
        stderr(&compared)
            .contains("note: greedy left out: greedy does not play games with skill requirements"),
        "{}",
        stderr(&compared)
    );
    refused(
        &afg(&["mission", "run", "--mission", path, "--model", model]),
        "staffing does not play games with skill requirements",
    );
    // The model trained on skill games plays it, as well as the exact solver.
    assert!(as_well_as_opt(
        "opt",
        Some(root.join("models/ours/staffing_skills").to_str().unwrap())
    ));
    std::fs::remove_dir_all(dir).unwrap();
}

/// `--still` writes one moment of the run as a PNG (where the most robots wait, or at
/// `--still-at`); a negative time is refused and nothing is written.
#[test]
fn a_still_of_a_team_mission_is_a_png() {
    let (dir, _) = mission_dir("still");
    let mission = dir.join("teams.json");
    let path = mission.to_str().unwrap();
    let made = afg(&[
        "mission",
        "gen",
        "--preset",
        "waves",
        "--robots",
        "20",
        "--tasks",
        "4",
        "--min-team",
        "3,5",
        "--out",
        path,
    ]);
    assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
    let still = dir.join("still.png");
    let out = still.to_str().unwrap();
    for extra in [&[][..], &["--still-at", "1.5"]] {
        let ran = afg(&[
            &["mission", "run", "--mission", path, "--still", out][..],
            extra,
        ]
        .concat());
        assert_eq!(ran.status.code(), Some(0), "{}", stderr(&ran));
        let png = std::fs::read(&still).unwrap();
        assert!(png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 100);
        std::fs::remove_file(&still).unwrap();
    }
    refused(
        &afg(&[
            "mission",
            "run",
            "--mission",
            path,
            "--still",
            out,
            "--still-at=-1",
        ]),
        "--still-at must be a finite time",
    );
    assert!(!still.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

/// `afg mission gen` warns of tasks no team of its robots can staff, as `afg gen`
/// does, and writes the mission all the same.
#[test]
fn mission_gen_warns_of_tasks_no_team_can_staff() {
    let (dir, _) = mission_dir("unstaffable");
    let out = dir.join("big-teams.json");
    let generate = |min_team: &str| {
        let args = [
            "mission", "gen", "--preset", "static", "--robots", "4", "--tasks", "2",
        ];
        let made = afg(&[
            &args[..],
            &["--min-team", min_team, "--out", out.to_str().unwrap()],
        ]
        .concat());
        assert_eq!(made.status.code(), Some(0), "{}", stderr(&made));
        stderr(&made)
    };
    let warned = generate("5,5");
    assert!(
        warned.contains("warning: no team can staff tasks 0, 1"),
        "{warned}"
    );
    assert!(out.exists());
    let fine = generate("2,2");
    assert!(!fine.contains("warning"), "{fine}");
    std::fs::remove_dir_all(dir).unwrap();
}
