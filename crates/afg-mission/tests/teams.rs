//! Missions whose tasks need teams: work advances only while the robots present meet
//! the task's threshold and skills; the robots that arrive first wait, and the waiting
//! is measured. Hand-computed cases, the file format, the generator and the refusals.

use afg_baseline::{Greedy, Optimum};
use afg_game::Point;
use afg_mission::internal::{Replan, RunOptions, simulate};
use afg_mission::{
    Failure, Mission, MissionConfig, MissionError, Preset, RobotSpec, TaskSpec, work_rate,
};

fn robot(x: f64, skills: Vec<u32>) -> RobotSpec {
    RobotSpec {
        position: Point::new(x, 0.0),
        speed: 1.0,
        skills,
    }
}

/// One task at x = 1 of workload `w` (reward 1, eps 2).
fn task(w: f64, min_team: usize, requires: Vec<u32>) -> TaskSpec {
    TaskSpec {
        position: Point::new(1.0, 0.0),
        reward: 1.0,
        eps: 2.0,
        capacity: None,
        workload: w,
        appears: 0.0,
        min_team,
        requires,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-9 * b.abs().max(1.0)
}

/// Robots at x = 0 and x = 4 and one task at x = 1 of workload 3 that needs both.
fn pair_at_one_task() -> Mission {
    Mission::new(
        1.0,
        false,
        50.0,
        vec![robot(0.0, vec![]), robot(4.0, vec![])],
        vec![task(3.0, 2, vec![])],
        vec![],
    )
    .unwrap()
}

#[test]
fn two_robots_needed_the_work_starts_when_the_second_arrives() {
    // Robot 0 reaches the task at t = 1, robot 1 at t = 3; the task needs both. From
    // t = 3 the pair works at log2(3) per time unit: done at 3 + 3 / log2(3). Robot 0
    // waited 2 time units.
    let mission = pair_at_one_task();
    for replan in [Replan::Scratch(&Optimum), Replan::Scratch(&Greedy)] {
        let run = simulate(&mission, replan, RunOptions::default()).unwrap();
        let done = 3.0 + 3.0 / work_rate(2, 2.0);
        assert!(
            close(run.metrics.makespan.unwrap(), done),
            "{:?}",
            run.metrics.makespan
        );
        let waiting = run.metrics.waiting.expect("a mission with teams");
        assert!(close(waiting.total, 2.0), "{}", waiting.total);
        assert_eq!(waiting.by_task.len(), 1);
    }
    // The animation's frames mark robot 0 waiting between t = 1 and t = 3 only.
    let options = RunOptions {
        frame_every: Some(0.5),
        ..RunOptions::default()
    };
    let run = simulate(&mission, Replan::Scratch(&Optimum), options).unwrap();
    let at_an_event = |t: f64| close(t, 1.0) || close(t, 3.0);
    assert!(run.frames.iter().any(|f| f.time > 1.0 && f.time < 3.0));
    for f in run.frames.iter().filter(|f| !at_an_event(f.time)) {
        let expected: &[u32] = if f.time > 1.0 && f.time < 3.0 {
            &[0]
        } else {
            &[]
        };
        assert_eq!(f.waiting, expected, "at {}", f.time);
    }
}

#[test]
fn a_skill_nobody_present_holds_stops_the_work() {
    // One robot is enough, but only robot 1 (arriving at t = 3) holds the skill.
    let mission = Mission::new(
        1.0,
        false,
        50.0,
        vec![robot(0.0, vec![0]), robot(4.0, vec![1])],
        vec![task(3.0, 1, vec![1])],
        vec![],
    )
    .unwrap();
    let run = simulate(&mission, Replan::Scratch(&Optimum), RunOptions::default()).unwrap();
    assert!(close(
        run.metrics.makespan.unwrap(),
        3.0 + 3.0 / work_rate(2, 2.0)
    ));
    assert!(close(run.metrics.waiting.unwrap().total, 2.0));
}

#[test]
fn a_team_that_falls_below_its_threshold_stops_until_staffed_again() {
    // Both robots start at the task (x = 1); robot 1 fails at t = 1 and is back at
    // t = 2. Work: log2(3) per unit on [0, 1], none on [1, 2] (robot 0 waits), then
    // log2(3) again: done at 1 + W / log2(3).
    let w = 10.0;
    let failures = vec![Failure {
        robot: 1,
        time: 1.0,
        returns: Some(2.0),
    }];
    let mission = Mission::new(
        1.0,
        false,
        50.0,
        vec![robot(1.0, vec![]), robot(1.0, vec![])],
        vec![task(w, 2, vec![])],
        failures,
    )
    .unwrap();
    let run = simulate(&mission, Replan::Scratch(&Optimum), RunOptions::default()).unwrap();
    assert!(close(
        run.metrics.makespan.unwrap(),
        1.0 + w / work_rate(2, 2.0)
    ));
    assert!(close(run.metrics.waiting.unwrap().total, 1.0));
}

#[test]
fn team_fields_round_trip_and_bad_ones_are_refused() {
    let mut config = MissionConfig::new(Preset::Waves, 30, 6, 4);
    config.min_team = Some(afg_game::CountRange { min: 2, max: 4 });
    let mission = config.generate().unwrap();
    assert!(mission.has_teams());
    assert!(mission.tasks.iter().all(|t| (2..=4).contains(&t.min_team)));
    let text = mission.to_json();
    assert_eq!(Mission::from_json(&text).unwrap(), mission);
    assert!(text.contains("\"min_team\""));
    // A mission without teams writes none of the fields.
    let plain = MissionConfig::new(Preset::Waves, 30, 6, 4)
        .generate()
        .unwrap();
    assert!(!plain.has_teams());
    assert!(!plain.to_json().contains("min_team"));
    let run = simulate(&plain, Replan::Scratch(&Greedy), RunOptions::default()).unwrap();
    assert!(run.metrics.waiting.is_none());

    let one = |robots: Vec<RobotSpec>, tasks: Vec<TaskSpec>| {
        Mission::new(1.0, false, 10.0, robots, tasks, vec![]).unwrap_err()
    };
    let message = |e: MissionError| e.to_string();
    assert!(
        message(one(vec![robot(0.0, vec![])], vec![task(1.0, 0, vec![])])).contains("min_team 0")
    );
    assert!(
        message(one(
            vec![robot(0.0, vec![1]), robot(0.0, vec![])],
            vec![task(1.0, 1, vec![])]
        ))
        .contains("robot 1 holds 0 skills")
    );
    assert!(
        message(one(
            vec![robot(0.0, vec![1])],
            vec![task(1.0, 1, vec![1, 1])]
        ))
        .contains("requires 2 skills")
    );
    let text = plain
        .to_json()
        .replace("\"workload\"", "\"min_team\":1.5,\"workload\"");
    assert!(Mission::from_json(&text).is_err());
}

#[test]
fn generated_team_missions_repeat_and_refuse_what_cannot_play_them() {
    let mut config = MissionConfig::new(Preset::Waves, 40, 8, 9);
    config.min_team = Some(afg_game::CountRange { min: 2, max: 5 });
    config.skills = Some(afg_game::SkillDraw {
        count: 2,
        share: 0.5,
        requires: afg_game::CountRange { min: 0, max: 1 },
    });
    let mission = config.generate().unwrap();
    assert_eq!(mission, config.generate().unwrap());
    assert!(mission.robots.iter().all(|r| r.skills.len() == 2));
    let run = simulate(&mission, Replan::Scratch(&Optimum), RunOptions::default()).unwrap();
    let again = simulate(&mission, Replan::Scratch(&Optimum), RunOptions::default()).unwrap();
    assert_eq!(run.timeline, again.timeline); // the same run (compute times aside)
    assert_eq!(run.metrics.waiting, again.metrics.waiting);
    assert!(run.metrics.waiting.is_some());
    // Greedy counts robots, not skills: it refuses in one line.
    let refused = simulate(&mission, Replan::Scratch(&Greedy), RunOptions::default()).unwrap_err();
    assert!(refused.to_string().contains("skill"), "{refused}");
    // The warm optimum reuses a flow's prices: refused on any team game.
    let refused = simulate(&mission, Replan::WarmOpt, RunOptions::default()).unwrap_err();
    assert!(refused.to_string().contains("without --warm"), "{refused}");
    config.skills = Some(afg_game::SkillDraw {
        count: 0,
        share: 0.5,
        requires: afg_game::CountRange { min: 1, max: 1 },
    });
    assert!(
        config
            .generate()
            .unwrap_err()
            .to_string()
            .contains("need skills")
    );
}

#[test]
fn the_exact_solver_in_the_loop_records_its_gap_per_decision() {
    use afg_mission::{MissionPlan, Recording, TraceEvent};
    let mut config = MissionConfig::new(Preset::Static, 60, 6, 5);
    config.min_team = Some(afg_game::CountRange { min: 10, max: 20 });
    let mission = config.generate().unwrap();
    let plan = MissionPlan {
        time_limit: Some(5.0),
        ..MissionPlan::default()
    };
    let recording = Recording {
        trace: true,
        frame_every: None,
    };
    let run = plan
        .planner()
        .unwrap()
        .run(&mission, recording, |_| {})
        .unwrap();
    let gaps: Vec<f64> = run
        .trace
        .iter()
        .filter_map(|e| match e {
            TraceEvent::Decision { gap, .. } => Some(gap.expect("opt reports its gap")),
            _ => None,
        })
        .collect();
    assert_eq!(gaps.len() as u64, run.metrics.decisions);
    // Small games: every decision proven within the limit.
    assert_eq!(run.metrics.gap_max, Some(0.0));
    assert!(gaps.iter().all(|&g| g == 0.0));
    // A limit of a nanosecond stops each decision inside its root's relaxation: the
    // first decision of this scarce game is not proven there.
    let rushed = MissionPlan {
        time_limit: Some(1e-9),
        ..MissionPlan::default()
    };
    let run = rushed
        .planner()
        .unwrap()
        .run(&mission, recording, |_| {})
        .unwrap();
    // Its gap is the one the exact solver under that limit certifies on the first
    // game (the whole static mission at the robots' starts), for the assignment it
    // took; the bound of a stopped root is no lower than the root's own.
    let tasks = mission.tasks.iter().map(|t| t.task()).collect();
    let starts = mission.robots.iter().map(|r| r.position).collect();
    assert!(!mission.allow_void);
    let first = afg_game::Instance::new(starts, tasks, mission.beta)
        .unwrap()
        .with_teams(mission.tasks.iter().map(|t| t.min_team).collect(), &[], &[])
        .unwrap();
    let cut = afg_baseline::TeamOptimum::with_time_limit(1e-9)
        .unwrap()
        .solve(&first)
        .unwrap();
    let root = afg_baseline::TeamOptimum::relax(&first).bound;
    let Some(TraceEvent::Decision { gap, tasks, .. }) = run
        .trace
        .iter()
        .find(|e| matches!(e, TraceEvent::Decision { .. }))
    else {
        unreachable!("the mission decides")
    };
    let taken = (tasks.iter())
        .map(|&j| u32::try_from(j).ok().map(afg_game::TaskId))
        .collect();
    let welfare = first.welfare(&afg_game::Assignment::from_tasks(&first, taken).unwrap());
    assert!(
        (welfare - cut.welfare).abs() < 1e-9,
        "{welfare} vs {}",
        cut.welfare
    );
    let expected = cut.gap();
    assert!(expected >= afg_baseline::certified_gap(root, welfare) - 1e-9);
    assert!(expected > 0.0);
    assert!(
        (gap.unwrap() - expected).abs() < 1e-9,
        "{gap:?} against {expected}"
    );
    assert!(run.metrics.gap_max.unwrap() >= expected - 1e-9);
}

/// A time limit is refused where it does not apply or is not a positive number.
#[test]
fn a_mission_time_limit_is_refused_where_it_does_not_apply() {
    use afg_mission::{MissionMethod, MissionPlan};
    let refused = |plan: MissionPlan| plan.planner().err().unwrap().to_string();
    let greedy = MissionMethod::Central(afg_baseline::Method::Greedy);
    for plan in [
        MissionPlan {
            time_limit: Some(1.0),
            method: greedy,
            ..MissionPlan::default()
        },
        MissionPlan {
            time_limit: Some(1.0),
            warm: true,
            ..MissionPlan::default()
        },
    ] {
        assert!(refused(plan).contains("for the exact optimum"));
    }
    for seconds in [0.0, -1.0, f64::NAN] {
        let plan = MissionPlan {
            time_limit: Some(seconds),
            ..MissionPlan::default()
        };
        assert!(refused(plan).contains("finite and positive"));
    }
    let grape = MissionPlan {
        time_limit: Some(1.0),
        method: MissionMethod::Grape,
        ..MissionPlan::default()
    };
    assert!(refused(grape).contains("time-limit is for central decisions"));
}

/// Both decentralised methods play thresholds in a mission (the auction staffing
/// every task of the waves with a team); with skills GRAPE refuses in one line and the
/// auction (its skill places) still does every task.
#[test]
fn grape_and_the_auction_over_the_radio_play_thresholds_and_the_auction_skills() {
    use afg_mission::{MissionMethod, MissionPlan, Recording};
    let mut config = MissionConfig::new(Preset::Waves, 30, 6, 2);
    config.min_team = Some(afg_game::CountRange { min: 2, max: 4 });
    let mission = config.generate().unwrap();
    let plan = |method| {
        let mut plan = MissionPlan {
            method,
            ..MissionPlan::default()
        };
        plan.swarm.epsilon = 0.03;
        plan
    };
    let run = |method, mission| {
        plan(method)
            .planner()
            .unwrap()
            .run(mission, Recording::default(), |_| {})
    };
    for method in [MissionMethod::Grape, MissionMethod::Auction] {
        let done = run(method, &mission).unwrap();
        assert!(done.metrics.waiting.is_some() && done.metrics.swarm.is_some());
        if method == MissionMethod::Auction {
            assert_eq!(done.metrics.tasks_done, mission.tasks.len());
        }
    }
    config.skills = Some(afg_game::SkillDraw {
        count: 2,
        share: 0.5,
        requires: afg_game::CountRange { min: 1, max: 1 },
    });
    let skilled = config.generate().unwrap();
    let refused = run(MissionMethod::Grape, &skilled).unwrap_err().to_string();
    assert!(
        refused.contains("grape does not play games with skill requirements"),
        "{refused}"
    );
    let done = run(MissionMethod::Auction, &skilled).unwrap();
    assert_eq!(done.metrics.tasks_done, skilled.tasks.len());
}

/// GRAPE over the radio on the hand mission of two robots and one task that needs
/// both: its distributed mutex lets one robot of a neighbourhood change per round, so
/// robot 0 joins at round 0 and robot 1 at round 1 (t = 0.01 at 100 rounds per time
/// unit); robot 1 arrives at 3.01, the pair works from then, and robot 0 waited 2.01.
#[test]
fn grape_on_a_hand_team_mission_joins_one_robot_per_round() {
    use afg_mission::{MissionMethod, MissionPlan, Recording};
    let mission = pair_at_one_task();
    let plan = MissionPlan {
        method: MissionMethod::Grape,
        ..MissionPlan::default()
    };
    assert_eq!(plan.swarm.rounds_per_time, 100.0);
    let run = plan
        .planner()
        .unwrap()
        .run(&mission, Recording::default(), |_| {})
        .unwrap();
    let round = 0.01;
    let makespan = run.metrics.makespan.unwrap();
    assert!(
        close(makespan, round + 3.0 + 3.0 / work_rate(2, 2.0)),
        "{makespan}"
    );
    let waiting = run.metrics.waiting.unwrap().total;
    assert!(close(waiting, 2.0 + round), "{waiting}");
}
