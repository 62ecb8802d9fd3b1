//! The team games: the format's new fields, bad input, and stability judged with
//! thresholds and skills against single moves computed from the welfare and utilities.

mod common;

use afg_game::{
    Assignment, GameError, GeneratorKnobs, Instance, Point, Preference, RobotId, TaskId,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::task;

/// A small game with thresholds and skills (and, every third case, the void task).
fn team_game(rng: &mut ChaCha8Rng, case: usize) -> Instance {
    let knobs = GeneratorKnobs {
        min_team: Some((1, 3)),
        skills: Some(2),
        skill_share: Some(0.5),
        requires: Some((0, 2)),
        allow_void: case % 3 == 2,
        capacity_slack: (case % 2 == 1).then_some(1.5),
        ..GeneratorKnobs::default()
    };
    let (n, m) = (rng.random_range(1..=7), rng.random_range(1..=3));
    knobs
        .config(n, m, rng.random())
        .unwrap()
        .generate()
        .unwrap()
}

/// A random complete (or, with the void, partial) assignment that respects capacities.
fn random_assignment(rng: &mut ChaCha8Rng, inst: &Instance) -> Option<Assignment> {
    let m = inst.num_tasks() as u32 + u32::from(inst.allows_void());
    let tasks = (0..inst.num_robots())
        .map(|_| Some(TaskId(rng.random_range(0..m))).filter(|j| j.index() < inst.num_tasks()))
        .collect();
    Assignment::from_tasks(inst, tasks).ok()
}

/// The places robot i could move to: every task with room for it, and the void where
/// allowed.
fn moves(inst: &Instance, a: &Assignment, i: RobotId) -> Vec<Assignment> {
    let mut places: Vec<Option<TaskId>> = inst
        .task_ids()
        .filter(|&j| a.task_of(i) != Some(j) && a.has_room(inst, i, j))
        .map(Some)
        .collect();
    if inst.allows_void() && a.task_of(i).is_some() {
        places.push(None);
    }
    places
        .into_iter()
        .map(|p| {
            let mut b = a.clone();
            b.set(i, p);
            b
        })
        .collect()
}

/// Robot i's own utility: its coalition's value (when the team is complete and holds
/// the skills) shared equally, minus its travel; 0 in the void.
fn utility(inst: &Instance, a: &Assignment, i: RobotId) -> f64 {
    let Some(j) = a.task_of(i) else { return 0.0 };
    let members: Vec<RobotId> = inst
        .robot_ids()
        .filter(|&r| a.task_of(r) == Some(j))
        .collect();
    let held: Vec<u64> = (0..inst.num_skills())
        .map(|s| members.iter().map(|&r| u64::from(inst.skills(r)[s])).sum())
        .collect();
    let n = members.len();
    let earns = n >= inst.min_team(j) && inst.skills_met(j, &held);
    let value = if earns {
        inst.value_function(j).value(n)
    } else {
        0.0
    };
    value / n as f64 - inst.cost(i, j)
}

#[test]
fn stability_with_teams_is_no_single_move_that_pays() {
    let mut rng = ChaCha8Rng::seed_from_u64(54);
    let (mut unstable, mut checked) = (0, 0);
    for case in 0..400 {
        let inst = team_game(&mut rng, case);
        let Some(a) = random_assignment(&mut rng, &inst) else {
            continue;
        };
        for i in inst.robot_ids() {
            let tol = |x: f64, y: f64| 1e-9 * x.abs().max(y.abs()).max(1.0);
            let w = inst.welfare(&a);
            let welfare_move = moves(&inst, &a, i)
                .iter()
                .any(|b| inst.welfare(b) - w > tol(inst.welfare(b), w));
            let u = if a.task_of(i).is_some() {
                utility(&inst, &a, i)
            } else if inst.allows_void() {
                0.0
            } else {
                f64::NEG_INFINITY
            };
            let selfish_move = moves(&inst, &a, i).iter().any(|b| {
                let v = utility(&inst, b, i);
                u == f64::NEG_INFINITY || v - u > tol(v, u)
            });
            assert_eq!(
                inst.is_satisfied(&a, i, Preference::Balanced),
                !welfare_move,
                "case {case}, robot {i}"
            );
            assert_eq!(
                inst.is_satisfied(&a, i, Preference::Selfish),
                !selfish_move,
                "case {case}, robot {i}"
            );
            checked += 1;
            unstable += usize::from(welfare_move);
        }
    }
    assert!(
        checked > 1000 && unstable > 100,
        "{checked} robots, {unstable} would move"
    );
}

#[test]
fn team_fields_round_trip_and_plain_files_do_not_grow() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for case in 0..20 {
        let inst = team_game(&mut rng, case);
        assert_eq!(Instance::from_json(&inst.to_json()).unwrap(), inst);
    }
    let plain = afg_game::GeneratorConfig::paper(5, 2, 1)
        .generate()
        .unwrap();
    let text = plain.to_json();
    for field in ["min_team", "skills", "requires"] {
        assert!(!text.contains(field), "{field} in {text}");
    }
}

/// A one-robot, two-task instance file with `robot` and `tasks` spliced in.
fn file(robot: &str, tasks: &str) -> String {
    format!(
        r#"{{"format":"afg-instance","version":1,"beta":1.0,"robots":[{robot}],"tasks":[{tasks}]}}"#
    )
}

const TASK: &str = r#"{"position":{"x":0.0,"y":0.0},"reward":1.0,"eps":2.0"#;

#[test]
fn bad_team_fields_are_clear_errors() {
    let robot = r#"{"x":0.0,"y":0.0}"#;
    for (robot, tasks, needle) in [
        (
            robot.to_owned(),
            format!(r#"{TASK},"min_team":0}}"#),
            "task 0: min_team must be a whole number of at least 1, got 0",
        ),
        (
            robot.to_owned(),
            format!(r#"{TASK},"min_team":2.5}}"#),
            "task 0: min_team must be a whole number of at least 1, got 2.5",
        ),
        (
            robot.to_owned(),
            format!(r#"{TASK},"min_team":-1}}"#),
            "task 0: min_team must be a whole number of at least 1, got -1",
        ),
        (
            r#"{"x":0.0,"y":0.0,"skills":[-1]}"#.to_owned(),
            format!("{TASK}}}"),
            "robot 0: skills must be a whole number of at least 0, got -1",
        ),
        (
            r#"{"x":0.0,"y":0.0,"skills":[1.5]}"#.to_owned(),
            format!("{TASK}}}"),
            "robot 0: skills must be a whole number of at least 0, got 1.5",
        ),
        (
            r#"{"x":0.0,"y":0.0,"skills":[1,0]}"#.to_owned(),
            format!(r#"{TASK},"requires":[1]}}"#),
            "task 0 lists 1 skills but robot 0 lists 2",
        ),
        (
            robot.to_owned(),
            format!(r#"{TASK},"team":2}}"#),
            "unknown field `team`",
        ),
        (
            r#"{"x":0.0,"y":0.0,"skill":[1]}"#.to_owned(),
            format!("{TASK}}}"),
            "unknown field `skill`",
        ),
    ] {
        let err = Instance::from_json(&file(&robot, &tasks)).unwrap_err();
        assert!(err.to_string().contains(needle), "{needle}: {err}");
        assert!(!err.to_string().contains('\n'), "{err}");
    }
}

#[test]
fn unstaffable_tasks_are_legal_and_earn_nothing() {
    // Task 0 needs 3 robots of 2; task 1 needs a skill nobody holds.
    let inst = Instance::new(
        vec![Point::new(0.0, 0.0), Point::new(1.0, 0.0)],
        vec![task(0.0, 0.0, 5.0, 2.0), task(1.0, 0.0, 5.0, 2.0)],
        1.0,
    )
    .unwrap()
    .with_teams(vec![3, 1], &[vec![0], vec![0]], &[vec![], vec![1]])
    .unwrap();
    assert_eq!(inst.unstaffable_tasks(), [TaskId(0), TaskId(1)]);
    let a = Assignment::from_tasks(&inst, vec![Some(TaskId(0)), Some(TaskId(1))]).unwrap();
    assert_eq!(inst.welfare(&a), -0.0 - 0.0);
    assert!(matches!(
        Instance::new(
            vec![Point::new(0.0, 0.0)],
            vec![task(0.0, 0.0, 1.0, 2.0)],
            1.0
        )
        .unwrap()
        .with_teams(vec![1, 2], &[], &[]),
        Err(GameError::TeamListLength {
            what: "min_team",
            len: 2,
            expected: 1
        })
    ));
}

/// The fewest robots among `inst`'s whose skills meet task j's requirements (all of
/// them may join), by trying every subset; `None` where no subset does.
fn fewest_meeting(inst: &Instance, j: TaskId) -> Option<usize> {
    let (n, s) = (inst.num_robots(), inst.num_skills());
    (0u32..1 << n)
        .filter(|&subset| {
            let mut held = vec![0u64; s];
            for i in (0..n).filter(|&i| subset >> i & 1 == 1) {
                for (h, &q) in held.iter_mut().zip(inst.skills(RobotId(i as u32))) {
                    *h += u64::from(q);
                }
            }
            inst.skills_met(j, &held)
        })
        .map(|subset| subset.count_ones() as usize)
        .min()
}

/// `smallest_team` never exceeds the fewest robots that can earn (it is a lower bound:
/// it counts each kind of robot as often as needed), and equals it where every kind is
/// there three times over (as many as any task requires), on random skill games.
#[test]
fn the_smallest_team_is_the_fewest_robots_that_can_earn() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mut raised = 0;
    for case in 0..200 {
        let s = rng.random_range(1..=3);
        let kinds: Vec<Vec<u32>> = (0..rng.random_range(1..=3))
            .map(|_| (0..s).map(|_| rng.random_range(0..=2)).collect())
            .collect();
        let copies = if case % 2 == 0 { 3 } else { 1 };
        let skills: Vec<Vec<u32>> = (kinds.iter())
            .flat_map(|kind| std::iter::repeat_n(kind.clone(), copies))
            .collect();
        let requires: Vec<Vec<u32>> = (0..2)
            .map(|_| (0..s).map(|_| rng.random_range(0..=3)).collect())
            .collect();
        let robots = vec![Point::new(0.0, 0.0); skills.len()];
        let inst = Instance::new(robots, vec![task(0.0, 0.0, 1.0, 2.0); 2], 1.0)
            .unwrap()
            .with_teams(vec![1, 2], &skills, &requires)
            .unwrap();
        for j in inst.task_ids() {
            let Some(smallest) = inst.smallest_team(j) else {
                assert!(inst.unstaffable_tasks().contains(&j), "case {case}");
                continue;
            };
            let fewest = fewest_meeting(&inst, j);
            let at = format!(
                "case {case} task {j:?}: {kinds:?} × {copies}, needs {:?}",
                inst.requires(j)
            );
            if let Some(fewest) = fewest {
                assert!(smallest <= fewest.max(inst.min_team(j)), "{at}");
            }
            if copies == 3 {
                assert_eq!(
                    Some(smallest),
                    fewest.map(|f| f.max(inst.min_team(j))),
                    "{at}"
                );
            }
            raised += usize::from(smallest > inst.min_team(j));
        }
    }
    assert!(raised > 100, "{raised}");
}
