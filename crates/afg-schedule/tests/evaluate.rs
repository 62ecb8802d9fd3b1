//! The evaluator on hand-computed schedules, and every refusal.

use afg_schedule::{Role, Rules, Schedule, ScheduleError, ScheduleInstance};

/// Robots at the origin, speed 1, tasks given as (x, y, min_team, duration).
fn line(robots: usize, tasks: &[(f64, f64, u32, f64)], max_wait: f64) -> ScheduleInstance {
    let robots: Vec<String> = (0..robots)
        .map(|_| r#"{"x":0,"y":0,"depot":0}"#.to_string())
        .collect();
    let tasks: Vec<String> = tasks
        .iter()
        .map(|(x, y, k, d)| format!(r#"{{"x":{x},"y":{y},"min_team":{k},"duration":{d}}}"#))
        .collect();
    ScheduleInstance::from_json(&format!(
        r#"{{"speed":1,"max_wait":{max_wait},"depots":[[0,0]],"robots":[{}],"tasks":[{}]}}"#,
        robots.join(","),
        tasks.join(",")
    ))
    .unwrap()
}

fn routes(r: &[&[usize]]) -> Schedule {
    Schedule {
        routes: r.iter().map(|v| v.to_vec()).collect(),
    }
}

#[test]
fn a_team_waits_for_its_last_member_and_the_makespan_is_the_last_return() {
    // Robot 1 first does task 1 at (0, 3) alone (3 there, 1 work), then 5 to (4, 0).
    // Robot 0 reaches task 0 at (4, 0) at 4 and waits for robot 1, there at 9.
    let inst = line(2, &[(4.0, 0.0, 2, 2.0), (0.0, 3.0, 1, 1.0)], 10.0);
    let run = inst.evaluate(&routes(&[&[0], &[1, 0]])).unwrap();
    assert_eq!(run.start, vec![9.0, 3.0]);
    assert_eq!(run.finish, vec![11.0, 4.0]);
    assert_eq!(run.back, vec![15.0, 15.0]);
    assert_eq!(run.makespan, 15.0);
    assert_eq!(run.travel, 8.0 + 3.0 + 5.0 + 4.0);
    assert_eq!(run.longest_wait, 5.0);
    assert_eq!(
        run.waiting, 2.5,
        "robot 0 waited 5, robot 1 nothing: the mean is 2.5"
    );
    assert!(run.is_valid());
    // Per robot: working (2 + 3) / 2, driving (8 + 12) / 2, waiting 5 / 2, no one idle.
    let use_ = run.time_use();
    assert_eq!(
        (use_.working, use_.driving, use_.waiting, use_.idle),
        (2.5, 10.0, 2.5, 0.0)
    );
    // Under a rule of 4, robot 0's wait of 5 breaks it, and the report says who and where.
    let strict = inst.evaluate_with(&routes(&[&[0], &[1, 0]]), 4.0).unwrap();
    assert!(!strict.is_valid());
    assert_eq!(strict.long_waits.len(), 1);
    assert_eq!(
        (
            strict.long_waits[0].robot,
            strict.long_waits[0].task,
            strict.long_waits[0].wait
        ),
        (0, 0, 5.0)
    );
}

#[test]
fn robots_that_wait_for_each_other_in_a_cycle_deadlock_and_are_named() {
    let inst = line(2, &[(1.0, 0.0, 2, 1.0), (0.0, 1.0, 2, 1.0)], 10.0);
    match inst.evaluate(&routes(&[&[0, 1], &[1, 0]])) {
        Err(ScheduleError::Deadlock { waiting }) => assert_eq!(waiting, vec![(0, 0), (1, 1)]),
        other => panic!("expected a deadlock, got {other:?}"),
    }
    let message = inst
        .evaluate(&routes(&[&[0, 1], &[1, 0]]))
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("robot 0 waits at task 0") && message.contains("robot 1 waits at task 1"),
        "{message}"
    );
}

#[test]
fn an_extra_robot_is_released_at_the_finish_or_skips_the_task_under_heteromrta() {
    // Three robots set off at 0 for a task 3 away needing 2: robots 0 and 1 are its team
    // (commitment order: ties by index), robot 2 an extra.
    let mut inst = line(3, &[(3.0, 4.0, 2, 2.0)], 10.0);
    let run = inst.evaluate(&routes(&[&[0], &[0], &[0]])).unwrap();
    assert_eq!(run.visits[2][0].role, Role::Extra);
    assert_eq!(run.visits[2][0].leave, 7.0);
    assert_eq!((run.makespan, run.travel), (12.0, 30.0));
    // The extra waits from its arrival at 5 to its release at 7; it works nothing.
    let use_ = run.time_use();
    assert_eq!(
        (
            use_.working * 3.0,
            use_.driving * 3.0,
            use_.waiting * 3.0,
            use_.idle
        ),
        (4.0, 30.0, 2.0, 0.0)
    );
    inst.rules = Rules::Heteromrta;
    let run = inst.evaluate(&routes(&[&[0], &[0], &[0]])).unwrap();
    assert_eq!(run.visits[2][0].role, Role::Skipped);
    assert_eq!((run.makespan, run.travel, run.back[2]), (12.0, 20.0, 0.0));
    // The robot that skips never leaves: idle all 12.
    let use_ = run.time_use();
    assert_eq!(
        (
            use_.working * 3.0,
            use_.driving * 3.0,
            use_.waiting,
            use_.idle * 3.0
        ),
        (4.0, 20.0, 0.0, 12.0)
    );
}

#[test]
fn an_extra_that_arrives_after_the_finish_is_reported() {
    // Robot 2 first does a far task, then sets off for task 0 after it started.
    let inst = line(3, &[(1.0, 0.0, 2, 0.5), (0.0, 10.0, 1, 1.0)], 10.0);
    let run = inst.evaluate(&routes(&[&[0], &[0], &[1, 0]])).unwrap();
    assert_eq!(run.visits[2][1].role, Role::Extra);
    assert_eq!(run.released_before_arrival, vec![(2, 0)]);
    assert!(!run.is_valid());
}

#[test]
fn a_skill_team_is_complete_when_its_members_hold_what_the_task_requires() {
    let inst = ScheduleInstance::from_json(
        r#"{"speed":1,"max_wait":10,"skills":2,"depots":[[0,0]],
        "robots":[{"x":0,"y":0,"depot":0,"skills":[1,0]},{"x":0,"y":0,"depot":0,"skills":[1,0]},
                  {"x":0,"y":2,"depot":0,"skills":[0,1]}],
        "tasks":[{"x":0,"y":4,"requires":[1,1],"duration":1}]}"#,
    )
    .unwrap();
    // Robots 0 and 1 hold only skill 0: the task waits for robot 2 (2 away), and robot 1,
    // committed before robot 2, is part of the team though it adds nothing.
    let run = inst.evaluate(&routes(&[&[0], &[0], &[0]])).unwrap();
    assert_eq!(run.start, vec![4.0]);
    assert!(run.visits.iter().all(|v| v[0].role == Role::Team));
    match inst.evaluate(&routes(&[&[0], &[0], &[]])) {
        Err(ScheduleError::Deadlock { waiting }) => assert_eq!(waiting, vec![(0, 0), (1, 0)]),
        other => panic!("no one holds skill 1: {other:?}"),
    }
}

#[test]
fn schedules_that_do_not_fit_are_refused_in_one_line() {
    let inst = line(2, &[(1.0, 0.0, 1, 1.0), (0.0, 1.0, 1, 1.0)], 10.0);
    let refusal = |s: Schedule| inst.evaluate(&s).unwrap_err().to_string();
    assert!(refusal(routes(&[&[0, 5], &[1]])).contains("task 5"));
    assert!(refusal(routes(&[&[0], &[]])).contains("leaves out task 1"));
    assert!(refusal(routes(&[&[0, 0, 1], &[]])).contains("twice"));
    assert!(refusal(routes(&[&[0, 1]])).contains("1 routes for 2 robots"));
    assert!(inst.evaluate_with(&routes(&[&[0, 1], &[]]), 0.0).is_err());
}

#[test]
fn instances_that_cannot_be_right_are_refused_with_the_field_named() {
    let base = r#""max_wait":10,"depots":[[0,0]],"robots":[{"x":0,"y":0,"depot":0}]"#;
    let refuse = |text: String| ScheduleInstance::from_json(&text).unwrap_err().to_string();
    let task = r#""tasks":[{"x":0,"y":1,"min_team":1,"duration":1}]"#;
    assert!(refuse(format!(r#"{{"speed":-1,{base},{task}}}"#)).contains("speed is -1"));
    assert!(
        refuse(format!(r#"{{"speed":1,"colour":"red",{base},{task}}}"#))
            .contains("unknown field `colour`")
    );
    let needs_two = r#""tasks":[{"x":0,"y":1,"min_team":2,"duration":1}]"#;
    assert!(
        refuse(format!(r#"{{"speed":1,{base},{needs_two}}}"#))
            .contains("task 0 can never be staffed")
    );
    let negative = r#""tasks":[{"x":0,"y":1,"min_team":1,"duration":-1}]"#;
    assert!(refuse(format!(r#"{{"speed":1,{base},{negative}}}"#)).contains("task 0's duration"));
    let skill = r#""skills":1,"max_wait":10,"depots":[[0,0]],"robots":[{"x":0,"y":0,"depot":0,"skills":[0]}],"tasks":[{"x":0,"y":1,"requires":[1],"duration":1}]"#;
    assert!(refuse(format!(r#"{{"speed":1,{skill}}}"#)).contains("requires 1 of skill 0"));
    let bad_depot = r#""max_wait":10,"depots":[[0,0]],"robots":[{"x":0,"y":0,"depot":3}]"#;
    assert!(
        refuse(format!(r#"{{"speed":1,{bad_depot},{task}}}"#)).contains("robot 0's depot is 3")
    );
}
