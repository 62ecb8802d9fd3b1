//! Missions against what they must be: the static preset is the static game (event
//! times against a fine-step reference are in `reference.rs`), no robot outruns its speed, capacities hold,
//! failed robots never act again, the incremental optimum is the optimum at every
//! decision, and a seed gives one trace.

use afg_baseline::{Method, Network, Optimum, SwarmMethod, verify_optimal};
use afg_game::{Assignment, GeneratorConfig, Instance, Point, TaskId};
use afg_graph::GraphKind;
use afg_mission::internal::{Decentralised, Replan, RunOptions, simulate};
use afg_mission::{Latency, Mission, MissionConfig, MissionRun, Preset, TraceEvent};
use proptest::prelude::*;

mod common;

use common::{check_run, traced};

/// The first decision's assignment of a run, robot by robot.
fn first_decision(run: &MissionRun) -> Vec<i64> {
    run.trace
        .iter()
        .find_map(|e| match e {
            TraceEvent::Decision { tasks, .. } => Some(tasks.clone()),
            _ => None,
        })
        .expect("a decision")
}

fn assignment(inst: &Instance, tasks: &[i64]) -> Assignment {
    let tasks = tasks
        .iter()
        .map(|&t| u32::try_from(t).ok().map(TaskId))
        .collect();
    Assignment::from_tasks(inst, tasks).unwrap()
}

/// The static preset's first decision is the static game of `afg solve`: the same
/// instance, and every method's answer on it.
#[test]
fn the_static_preset_is_the_static_game() {
    for seed in 0..4 {
        let (n, k) = (30, 5);
        let mission = MissionConfig::new(Preset::Static, n, k, seed)
            .generate()
            .unwrap();
        let game = GeneratorConfig::paper(n, k, seed).generate().unwrap();
        for method in [
            Method::Opt,
            Method::Da,
            Method::DaBalanced,
            Method::Greedy,
            Method::Nearest,
        ] {
            let allocator = method.allocator(seed);
            let run = simulate(&mission, Replan::Scratch(allocator.as_ref()), traced()).unwrap();
            let first = assignment(&game, &first_decision(&run));
            let solved = allocator.allocate(&game).unwrap().assignment;
            assert_eq!(first.tasks(), solved.tasks(), "seed {seed} {method}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Random missions of every preset, with capacities, failures that return, and
    /// every replanning rule: the run's invariants hold, and the same seed gives the
    /// same trace (compute times aside).
    #[test]
    fn every_run_keeps_the_rules_and_repeats(
        seed in 0u64..1000,
        preset in prop_oneof![
            Just(Preset::Static), Just(Preset::Waves), Just(Preset::Poisson), Just(Preset::Attrition)
        ],
        robots in 2usize..30,
        tasks in 1usize..8,
        capped in any::<bool>(),
    ) {
        let mut config = MissionConfig::new(preset, robots, tasks, seed);
        config.horizon = 30.0;
        config.capacity_slack = capped.then_some(1.2);
        let mut mission = config.generate().unwrap();
        if let Some(f) = mission.failures.first_mut() {
            f.returns = Some((f.time + 3.0).min(29.0)).filter(|&b| b > f.time);
        }
        let allocator = Method::Greedy.allocator(seed);
        let grape = Decentralised {
            sensing: capped.then_some(0.3),
            rounds_per_time: 20.0,
            seed,
            ..Decentralised::new(
                SwarmMethod::Grape { preference: afg_game::Preference::Selfish },
                Network { graph: GraphKind::Radius { radius: 0.4 }, loss: 0.2, ..Network::default() },
            )
        };
        let auction = Decentralised { method: SwarmMethod::Auction { epsilon: 1e-3 }, ..grape.clone() };
        let swarm = if seed % 2 == 0 { &grape } else { &auction };
        // Every replanning rule on every mission drawn.
        let rules = [
            Replan::Scratch(allocator.as_ref()),
            Replan::Warm { first: allocator.as_ref(), preference: afg_game::Preference::Balanced },
            Replan::WarmOpt,
            Replan::Scratch(&Optimum),
            Replan::Decentralised(swarm),
        ];
        for (rule, replan) in rules.into_iter().enumerate() {
            let options = RunOptions { replan_every: (rule == 3).then_some(2.5), ..traced() };
            let run = simulate(&mission, replan, options).unwrap();
            // Robots acting on views not yet settled may crowd a task past its capacity.
            check_run(&mission, &run, rule != 4);
            prop_assert_eq!(run.metrics.swarm.is_some(), rule == 4);
            let again = simulate(&mission, replan, options).unwrap();
            prop_assert_eq!(strip(&run), strip(&again));
            prop_assert_eq!(run.metrics.reward_done, again.metrics.reward_done);
        }
    }

    /// Random team and skill missions with failures that return, decided by the exact
    /// solver under a time limit, the auction over a lossy radio and the staffing
    /// models: the work rebuilt from the trace (done only while the present team meets
    /// its threshold and skills) and the waiting match the run, and the rules hold.
    #[test]
    fn team_missions_keep_their_work_and_waiting(
        seed in 0u64..1000,
        preset in prop_oneof![Just(Preset::Static), Just(Preset::Waves), Just(Preset::Attrition)],
        robots in 6usize..30,
        tasks in 1usize..6,
        skills in any::<bool>(),
    ) {
        let mut config = MissionConfig::new(preset, robots, tasks, seed);
        config.horizon = 30.0;
        config.min_team = Some(afg_game::CountRange { min: 1, max: 4 });
        if skills {
            config.skills = Some(afg_game::SkillDraw {
                count: 2,
                share: 0.5,
                requires: afg_game::CountRange { min: 0, max: 1 },
            });
        }
        let mut mission = config.generate().unwrap();
        for f in &mut mission.failures {
            f.returns = Some((f.time + 3.0).min(29.0)).filter(|&b| b > f.time);
        }
        let opt = afg_baseline::TeamOptimum::with_time_limit(0.05).unwrap();
        let auction = Decentralised {
            rounds_per_time: 20.0,
            seed,
            ..Decentralised::new(
                SwarmMethod::Auction { epsilon: 0.01 },
                Network { loss: 0.2, ..Network::default() },
            )
        };
        let model = if skills { "staffing_skills" } else { "staffing_teams" };
        let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/ours").join(model);
        let staffing = afg_learn::run::load_model(&model, Default::default()).unwrap();
        for replan in [
            Replan::Scratch(&opt),
            Replan::Decentralised(&auction),
            Replan::Scratch(staffing.as_ref()),
        ] {
            let run = simulate(&mission, replan, traced()).unwrap();
            prop_assert_eq!(run.metrics.waiting.is_some(), mission.has_teams());
            check_run(&mission, &run, false);
        }
    }
}

/// A trace without compute times (which vary from run to run).
fn strip(r: &MissionRun) -> Vec<TraceEvent> {
    r.trace
        .iter()
        .cloned()
        .map(|e| match e {
            TraceEvent::Decision {
                time,
                asked,
                tasks,
                positions,
                gap,
                ..
            } => TraceEvent::Decision {
                time,
                asked,
                tasks,
                positions,
                compute_s: 0.0,
                gap,
            },
            e => e,
        })
        .collect()
}

/// The incremental optimum is the optimum of every decision's game, with prices that
/// prove it: the game is rebuilt from the trace and solved from scratch.
#[test]
fn the_incremental_optimum_is_the_optimum_at_every_decision() {
    for seed in 0..6 {
        let preset = [Preset::Waves, Preset::Poisson, Preset::Attrition][seed as usize % 3];
        let mission = MissionConfig::new(preset, 40, 10, seed).generate().unwrap();
        let run = simulate(&mission, Replan::WarmOpt, traced()).unwrap();
        let (mut open, mut alive) = (vec![false; 10], vec![true; 40]);
        let mut checked = 0;
        for e in &run.trace {
            match e {
                TraceEvent::TaskAppears { task, .. } => open[*task] = true,
                TraceEvent::TaskDone { task, .. } => open[*task] = false,
                TraceEvent::RobotFails { robot, .. } => alive[*robot] = false,
                TraceEvent::Decision {
                    tasks, positions, ..
                } => {
                    let robots: Vec<usize> = (0..40).filter(|&i| alive[i]).collect();
                    let columns: Vec<usize> = (0..10).filter(|&j| open[j]).collect();
                    let game = Instance::new(
                        robots
                            .iter()
                            .map(|&i| Point::new(positions[i][0], positions[i][1]))
                            .collect(),
                        columns.iter().map(|&j| mission.tasks[j].task()).collect(),
                        mission.beta,
                    )
                    .unwrap();
                    let chosen: Vec<i64> = robots
                        .iter()
                        .map(|&i| {
                            columns
                                .iter()
                                .position(|&j| j as i64 == tasks[i])
                                .map_or(-1, |k| k as i64)
                        })
                        .collect();
                    let a = assignment(&game, &chosen);
                    let (opt, prices) = Optimum.with_prices(&game);
                    let best = game.welfare(&opt);
                    assert!(
                        (game.welfare(&a) - best).abs() <= 1e-9 * best.abs().max(1.0),
                        "seed {seed}: {} vs {best}",
                        game.welfare(&a)
                    );
                    verify_optimal(&game, &opt, &prices).unwrap();
                    checked += 1;
                }
                _ => {}
            }
        }
        assert!(checked >= 3, "seed {seed}: {checked} decisions");
    }
}

/// A decision latency delays every decision; the mission's outcome is no better.
#[test]
fn latency_delays_decisions() {
    let mission = MissionConfig::new(Preset::Waves, 30, 8, 3)
        .generate()
        .unwrap();
    let instant = simulate(&mission, Replan::WarmOpt, traced()).unwrap();
    let slow = RunOptions {
        latency: Latency::Fixed { delay: 0.5 },
        ..traced()
    };
    let late = simulate(&mission, Replan::WarmOpt, slow).unwrap();
    for e in &late.trace {
        if let TraceEvent::Decision { time, asked, .. } = e {
            assert!((time - asked - 0.5).abs() < 1e-12);
        }
    }
    let (a, b) = (&instant.metrics, &late.metrics);
    assert!(b.latency_mean.unwrap() > a.latency_mean.unwrap());
}

#[test]
fn bad_missions_are_refused_in_one_line() {
    let mission = MissionConfig::new(Preset::Attrition, 10, 3, 1)
        .generate()
        .unwrap();
    let text = mission.to_json();
    let cases = [
        (
            text.replacen("\"speed\":1.0", "\"speed\":-1.0", 1),
            "speed -1",
        ),
        (
            text.replacen("\"workload\":", "\"workload\":-", 1),
            "workload -",
        ),
        (
            text.replace("\"horizon\":40.0", "\"horizon\":0.5"),
            "outside the mission",
        ),
        (
            text.replacen("\"robot\":", "\"robot\":9", 1),
            "names robot 9",
        ),
        (text.replace("afg-mission", "afg-instance"), "afg-instance"),
        (text.replacen("\"beta\"", "\"betta\"", 1), "unknown field"),
    ];
    for (bad, needle) in cases {
        assert_ne!(bad, text, "{needle}");
        let err = Mission::from_json(&bad).unwrap_err().to_string();
        assert!(err.contains(needle), "{needle}: {err}");
        assert!(!err.contains('\n'));
    }
    assert!(
        simulate(
            &mission,
            Replan::WarmOpt,
            RunOptions {
                replan_every: Some(0.0),
                ..RunOptions::default()
            }
        )
        .is_err()
    );
}

/// Commitment: a robot that reached its task keeps it until the task is done.
/// Hysteresis ∞ as well: no robot ever switches from one task to another.
#[test]
fn commitment_and_hysteresis_keep_robots_on_their_task() {
    let mut held_back = 0;
    for seed in 0..4 {
        let mut config = MissionConfig::new(Preset::Attrition, 30, 10, seed);
        config.capacity_slack = (seed % 2 == 1).then_some(1.2);
        let mission = config.generate().unwrap();
        let committed = RunOptions {
            commit: true,
            ..traced()
        };
        let run = simulate(&mission, Replan::Scratch(&Optimum), committed).unwrap();
        check_run(&mission, &run, true);
        let mut working: Vec<Option<usize>> = vec![None; 30];
        for e in &run.trace {
            match e {
                TraceEvent::Arrival { robot, task, .. } => working[*robot] = Some(*task),
                TraceEvent::TaskDone { task, .. } => {
                    for w in working.iter_mut().filter(|w| **w == Some(*task)) {
                        *w = None;
                    }
                }
                TraceEvent::RobotFails { robot, .. } => working[*robot] = None,
                TraceEvent::Decision { tasks, .. } => {
                    for (i, w) in working.iter().enumerate() {
                        if let Some(j) = w {
                            assert_eq!(tasks[i], *j as i64, "seed {seed}: robot {i} left task {j}");
                        }
                    }
                }
                _ => {}
            }
        }
        let frozen = RunOptions {
            commit: true,
            hysteresis: Some(f64::INFINITY),
            ..traced()
        };
        let run = simulate(&mission, Replan::Scratch(&Optimum), frozen).unwrap();
        check_run(&mission, &run, true);
        assert_eq!(run.metrics.reassignments, 0, "seed {seed}");
        let free = simulate(&mission, Replan::Scratch(&Optimum), traced()).unwrap();
        held_back += free.metrics.reassignments;
    }
    assert!(held_back > 0, "nothing to hold back");
}

/// A decentralised method in a mission: central options and a round rate out of range
/// are refused with what is wrong; over a perfect network where everyone hears
/// everyone, GRAPE settles after every event of a static mission and its robots all
/// work.
#[test]
fn grape_runs_inside_missions() {
    let mission = MissionConfig::new(Preset::Waves, 20, 6, 4)
        .generate()
        .unwrap();
    let grape = Decentralised::new(
        SwarmMethod::Grape {
            preference: afg_game::Preference::Selfish,
        },
        Network {
            graph: GraphKind::Radius { radius: 2.0 },
            ..Network::default()
        },
    );
    let replan = Replan::Decentralised(&grape);
    let late = RunOptions {
        latency: Latency::Fixed { delay: 1.0 },
        ..RunOptions::default()
    };
    let error = simulate(&mission, replan, late).unwrap_err().to_string();
    assert!(error.contains("decentralised"), "{error}");
    let stalled = Decentralised {
        rounds_per_time: 0.0,
        ..grape.clone()
    };
    let error = simulate(
        &mission,
        Replan::Decentralised(&stalled),
        RunOptions::default(),
    );
    assert!(error.unwrap_err().to_string().contains("rounds per time"));
    let run = simulate(&mission, replan, traced()).unwrap();
    check_run(&mission, &run, true);
    let swarm = run.metrics.swarm.as_ref().unwrap();
    assert_eq!(run.metrics.tasks_done, 6);
    // Every wave's arrivals settle before the mission ends; only the last completion
    // cannot (the run stops there).
    assert!(swarm.response_mean.unwrap() > 0.0);
    assert!(swarm.unsettled <= 1, "{swarm:?}");
    assert_eq!(swarm.rounds, run.metrics.decisions);
}

/// A plan's options are checked once, when its planner is made; what a run records
/// is checked at the run, for every method.
#[test]
fn a_plan_is_checked_at_planner_and_a_recording_at_run() {
    use afg_mission::{MissionMethod, MissionPlan, Recording};
    let mission = MissionConfig::new(Preset::Static, 10, 3, 1)
        .generate()
        .unwrap();
    let bad_replan = MissionPlan {
        replan_every: Some(0.0),
        ..MissionPlan::default()
    };
    let refused = bad_replan.planner().err().expect("a zero interval");
    assert!(
        refused.to_string().contains("replanning interval"),
        "{refused}"
    );
    for method in [MissionMethod::Central(Method::Greedy), MissionMethod::Grape] {
        let planner = MissionPlan {
            method,
            ..MissionPlan::default()
        }
        .planner()
        .unwrap();
        for every in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let frames = Recording {
                frame_every: Some(every),
                ..Recording::default()
            };
            let refused = planner.run(&mission, frames, |_| {}).unwrap_err();
            assert!(
                refused.to_string().contains("between frames"),
                "{method}: {refused}"
            );
        }
        let frames = Recording {
            frame_every: Some(0.5),
            ..Recording::default()
        };
        assert!(
            !planner
                .run(&mission, frames, |_| {})
                .unwrap()
                .frames
                .is_empty()
        );
    }
}
