//! Inputs a user can hand the readers: misspelled fields, overflowing numbers, CRLF
//! line ends and byte order marks, assignments that name tasks no instance has; and
//! every invalid game, one test each.

mod common;

use afg_game::io;
use afg_game::realloc::PreviousAssignment;
use afg_game::{Assignment, GameError, GeneratorConfig, Instance, MAX_VALUE, Point, Task, TaskId};

use common::task;

fn instance() -> Instance {
    GeneratorConfig::paper(6, 2, 1).generate().unwrap()
}

/// The instance's JSON with `from` replaced by `to` (which must occur).
fn edited(from: &str, to: &str) -> String {
    let text = instance().to_json();
    assert!(text.contains(from), "{from} not in {text}");
    text.replacen(from, to, 1)
}

#[test]
fn a_misspelled_field_is_an_error_that_names_it() {
    // A task, a robot, the generator and the document itself.
    for (from, to, field) in [
        ("\"eps\":", "\"capcity\":3,\"eps\":", "capcity"),
        ("\"x\":", "\"z\":1,\"x\":", "z"),
        ("\"seed\":", "\"sed\":1,\"seed\":", "sed"),
        ("\"beta\":", "\"betta\":1,\"beta\":", "betta"),
    ] {
        let err = Instance::from_json(&edited(from, to)).unwrap_err();
        assert!(
            matches!(err, GameError::Json { .. }) && err.to_string().contains(field),
            "{err}"
        );
    }
    // In a dataset the line is named too.
    let good = instance().to_json();
    let text = format!("{good}\n{}\n", edited("\"eps\":", "\"capcity\":3,\"eps\":"));
    let err = io::parse_dataset(&text).unwrap_err();
    assert!(err.to_string().contains("line 2") && err.to_string().contains("capcity"));
}

/// A team field that is not a whole number in range is named — robot or task, field,
/// value — not left to the parser's column; good ones read back.
#[test]
fn a_bad_team_field_names_its_task_and_field() {
    for (value, field) in [
        ("-1", "min_team"),
        ("1.5", "min_team"),
        ("2.0", "min_team"),
        ("\"3\"", "min_team"),
        ("0", "min_team"),
    ] {
        let text = edited("\"eps\":", &format!("\"{field}\":{value},\"eps\":"));
        let err = Instance::from_json(&text).unwrap_err().to_string();
        let expected = format!("task 0: {field} must be a whole number of at least 1, got {value}");
        assert_eq!(err, expected);
    }
    let text = edited("\"eps\":", "\"capacity\":-2,\"eps\":");
    let err = Instance::from_json(&text).unwrap_err().to_string();
    assert_eq!(
        err,
        "task 0: capacity must be a whole number of at least 0, got -2"
    );
    let text = edited("\"y\":", "\"skills\":[1,0.5],\"y\":");
    let err = Instance::from_json(&text).unwrap_err().to_string();
    assert_eq!(
        err,
        "robot 0: skills must be a whole number of at least 0, got 0.5"
    );
    let good = edited("\"eps\":", "\"min_team\":3,\"eps\":");
    let inst = Instance::from_json(&good).unwrap();
    assert_eq!(inst.min_team(TaskId(0)), 3);
    assert_eq!(Instance::from_json(&inst.to_json()).unwrap(), inst);
}

#[test]
fn costs_that_overflow_are_refused_with_the_limit() {
    let err = Instance::from_json(&edited("\"beta\":1.0", "\"beta\":1e308")).unwrap_err();
    assert!(matches!(err, GameError::CostTooLarge { .. }), "{err}");
    assert!(err.to_string().contains("1e15"), "{err}");
    let inst = instance();
    let mut robots = inst.robots().to_vec();
    robots[0].x = -1e308;
    robots[1].x = 1e308;
    let err = Instance::new(robots, inst.tasks().to_vec(), 1.0).unwrap_err();
    assert!(matches!(err, GameError::CostTooLarge { .. }), "{err}");
    // Just inside the limit is fine; rewards have the same limit.
    let mut robots = inst.robots().to_vec();
    robots[0].x = MAX_VALUE / 2.0;
    assert!(Instance::new(robots, inst.tasks().to_vec(), 1.0).is_ok());
    let mut tasks = inst.tasks().to_vec();
    tasks[0].reward = 1e300;
    let err = Instance::new(inst.robots().to_vec(), tasks, 1.0).unwrap_err();
    assert!(matches!(err, GameError::InvalidReward { .. }), "{err}");
}

#[test]
fn crlf_line_ends_and_a_byte_order_mark_are_read() {
    let (a, b) = (
        instance(),
        GeneratorConfig::paper(7, 3, 2).generate().unwrap(),
    );
    let crlf = format!("\u{feff}{}\r\n{}\r\n", a.to_json(), b.to_json());
    assert_eq!(io::parse_instances(&crlf).unwrap(), vec![a.clone(), b]);
    let one = format!("\u{feff}{}\r\n", a.to_json());
    assert_eq!(Instance::from_json(&one).unwrap(), a);
    assert_eq!(io::parse_instances(&one).unwrap(), vec![a.clone()]);
    let assignment =
        "\u{feff}{\"format\":\"afg-assignment\",\"version\":1,\"tasks\":[0,1,0,1,0,1]}\r\n";
    assert!(afg_game::Assignment::from_json(assignment, &a).is_ok());
}

#[test]
fn a_previous_assignment_naming_a_huge_task_is_an_error_not_an_allocation() {
    let now = instance();
    let text = r#"{"format":"afg-assignment","version":1,"tasks":[4294967295,0,0,0,0,0]}"#;
    let err = PreviousAssignment::from_json(text)
        .unwrap()
        .carry_over(&now)
        .unwrap_err();
    assert!(
        err.to_string().contains("task 4294967295 is out of range"),
        "{err}"
    );
    let text = r#"{"format":"afg-assignment","version":1,"tasks":[0,0,0,0,0,0],"left_tasks":[4294967295]}"#;
    assert!(
        PreviousAssignment::from_json(text)
            .unwrap()
            .carry_over(&now)
            .is_err()
    );
    // A task that left may have an index above the new M.
    let text = r#"{"format":"afg-assignment","version":1,"tasks":[0,2,1,1,0,0],"left_tasks":[2]}"#;
    let a = PreviousAssignment::from_json(text)
        .unwrap()
        .carry_over(&now)
        .unwrap();
    assert_eq!(a.tasks()[1], None);
    assert_eq!(a.tasks()[2], Some(TaskId(1)));
}

#[test]
fn atomic_writes_replace_whole_files_and_leave_no_temporary_behind() {
    let dir = std::env::temp_dir().join(format!("afg-atomic-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("out.json");
    afg_game::fs::write_atomic(&path, b"first").unwrap();
    afg_game::fs::write_atomic(&path, b"second").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"second");
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("out.json")]);
    // A failed write leaves the old file as it was.
    let err = afg_game::fs::write_atomic_with(&path, |_| Err(std::io::Error::other("disk full")));
    assert!(err.unwrap_err().to_string().contains("disk full"));
    assert_eq!(std::fs::read(&path).unwrap(), b"second");
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(names.len(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---- invalid games: one test each ----

fn one_task() -> Vec<Task> {
    vec![task(0.5, 0.5, 1.0, 2.0)]
}

#[test]
fn error_no_robots() {
    assert!(matches!(
        Instance::new(vec![], one_task(), 1.0),
        Err(GameError::NoRobots)
    ));
    assert!(matches!(
        GeneratorConfig::paper(0, 5, 1).generate(),
        Err(GameError::NoRobots)
    ));
}

#[test]
fn error_no_tasks() {
    assert!(matches!(
        Instance::new(vec![Point::new(0.0, 0.0)], vec![], 1.0),
        Err(GameError::NoTasks)
    ));
    assert!(matches!(
        GeneratorConfig::paper(5, 0, 1).generate(),
        Err(GameError::NoTasks)
    ));
}

#[test]
fn error_non_finite_coordinates() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let r = Instance::new(
            vec![Point::new(0.0, 0.0), Point::new(bad, 0.0)],
            one_task(),
            1.0,
        );
        assert!(matches!(
            r,
            Err(GameError::NonFiniteCoordinate {
                what: "robot",
                index: 1,
                ..
            })
        ));
        let r = Instance::new(
            vec![Point::new(0.0, 0.0)],
            vec![task(0.0, bad, 1.0, 2.0)],
            1.0,
        );
        assert!(matches!(
            r,
            Err(GameError::NonFiniteCoordinate {
                what: "task",
                index: 0,
                ..
            })
        ));
    }
}

#[test]
fn error_eps_below_golden_ratio() {
    for eps in [1.0, 1.618, f64::NAN, 0.0, -3.0] {
        let r = Instance::new(
            vec![Point::new(0.0, 0.0)],
            vec![task(0.0, 0.0, 1.0, eps)],
            1.0,
        );
        assert!(
            matches!(r, Err(GameError::EpsBelowGoldenRatio { .. })),
            "eps = {eps}"
        );
    }
    let mut cfg = GeneratorConfig::paper(5, 5, 1);
    cfg.eps = 1.5;
    let err = cfg.generate().unwrap_err();
    assert!(err.to_string().contains("golden ratio"), "{err}");
}

#[test]
fn error_negative_reward() {
    let r = Instance::new(
        vec![Point::new(0.0, 0.0)],
        vec![task(0.0, 0.0, -1.0, 2.0)],
        1.0,
    );
    assert!(matches!(r, Err(GameError::InvalidReward { task: 0, .. })));
}

#[test]
fn error_invalid_beta() {
    for beta in [-1.0, f64::NAN] {
        let r = Instance::new(vec![Point::new(0.0, 0.0)], one_task(), beta);
        assert!(matches!(r, Err(GameError::InvalidBeta(_))));
    }
}

#[test]
fn error_capacities_below_n() {
    let mut tasks = vec![task(0.0, 0.0, 1.0, 2.0), task(1.0, 0.0, 1.0, 2.0)];
    tasks[0].capacity = Some(1);
    tasks[1].capacity = Some(1);
    let robots = vec![Point::new(0.0, 0.0); 3];
    assert!(matches!(
        Instance::new(robots.clone(), tasks.clone(), 1.0),
        Err(GameError::CapacityTooSmall {
            total: 2,
            robots: 3
        })
    ));
    // One unbounded task makes any total enough.
    tasks[1].capacity = None;
    assert!(Instance::new(robots, tasks, 1.0).is_ok());
}

#[test]
fn error_assignment_of_wrong_length() {
    let inst = GeneratorConfig::paper(4, 2, 1).generate().unwrap();
    let r = Assignment::from_tasks(&inst, vec![None; 3]);
    assert!(matches!(
        r,
        Err(GameError::AssignmentLength {
            expected: 4,
            got: 3
        })
    ));
}

#[test]
fn error_assignment_task_out_of_range() {
    let inst = GeneratorConfig::paper(4, 2, 1).generate().unwrap();
    let r = Assignment::from_tasks(&inst, vec![None, Some(TaskId(2)), None, None]);
    assert!(matches!(
        r,
        Err(GameError::TaskOutOfRange {
            robot: 1,
            task: 2,
            tasks: 2
        })
    ));
    let r = Assignment::from_json(
        r#"{"format":"afg-assignment","version":1,"tasks":[0,0,0,7]}"#,
        &inst,
    );
    assert!(matches!(r, Err(GameError::TaskOutOfRange { robot: 3, .. })));
}

#[test]
fn error_assignment_over_capacity() {
    let inst = GeneratorConfig::paper(6, 2, 1)
        .with_capacity_slack(1.0)
        .generate()
        .unwrap();
    let r = Assignment::from_tasks(&inst, vec![Some(TaskId(0)); 6]);
    assert!(matches!(
        r,
        Err(GameError::CapacityExceeded {
            task: 0,
            size: 6,
            capacity: 3
        })
    ));
}

#[test]
fn error_json_of_another_version() {
    let inst = GeneratorConfig::paper(4, 2, 1).generate().unwrap();
    let text = inst.to_json().replace("\"version\":1", "\"version\":2");
    assert!(matches!(
        Instance::from_json(&text),
        Err(GameError::UnsupportedVersion { found: 2, .. })
    ));
}

#[test]
fn error_json_of_another_format() {
    let inst = GeneratorConfig::paper(4, 2, 1).generate().unwrap();
    let a = Assignment::unassigned(4, 2).to_json();
    assert!(matches!(
        Instance::from_json(&a),
        Err(GameError::Json { .. })
    ));
    let text = inst.to_json().replace("afg-instance", "afg-assignment");
    assert!(matches!(
        Instance::from_json(&text),
        Err(GameError::WrongFormat { .. })
    ));
    let text = a.replace("afg-assignment", "afg-instance");
    assert!(matches!(
        Assignment::from_json(&text, &inst),
        Err(GameError::WrongFormat { .. })
    ));
}

#[test]
fn error_json_of_wrong_shape() {
    for text in [
        "",
        "[1,2]",
        "{\"format\":\"afg-instance\"}",
        "{\"robots\": 3}",
        "not json",
    ] {
        assert!(
            matches!(
                Instance::from_json(text),
                Err(GameError::Json { line: None, .. })
            ),
            "{text}"
        );
    }
    let inst = GeneratorConfig::paper(4, 2, 1).generate().unwrap();
    let jsonl = format!("{}\n{{\"oops\":1}}\n", inst.to_json());
    assert!(matches!(
        io::parse_dataset(&jsonl),
        Err(GameError::Json { line: Some(2), .. })
    ));
    // Validation applies inside JSON too.
    let text = inst.to_json().replacen("\"reward\":", "\"reward\":-", 1);
    assert!(matches!(
        Instance::from_json(&text),
        Err(GameError::InvalidReward { .. })
    ));
}
