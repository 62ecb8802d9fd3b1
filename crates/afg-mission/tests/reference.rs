//! Event times against a fine-step reference: each arrival and completion of the
//! event-driven run happens, in a simulation stepped with a fine clock that replays
//! the run's decisions, within a step or so of its time.

mod common;

use afg_baseline::Optimum;
use afg_game::Point;
use afg_mission::internal::{Replan, simulate};
use afg_mission::{Mission, MissionConfig, MissionRun, Preset, TraceEvent, work_rate};

use common::{check_run, traced};

/// The run's decisions, and the mission's failures and returns (robot, back), at
/// their times.
#[allow(clippy::type_complexity)]
fn scheduled(
    mission: &Mission,
    run: &MissionRun,
) -> (Vec<(f64, Vec<i64>)>, Vec<(f64, usize, bool)>) {
    let decisions = (run.trace.iter())
        .filter_map(|e| match e {
            TraceEvent::Decision { time, tasks, .. } => Some((*time, tasks.clone())),
            _ => None,
        })
        .collect();
    let mut failures: Vec<(f64, usize, bool)> = (mission.failures.iter())
        .flat_map(|f| {
            std::iter::once((f.time, f.robot, false)).chain(f.returns.map(|r| (r, f.robot, true)))
        })
        .collect();
    failures.sort_by(|a, b| a.0.total_cmp(&b.0));
    (decisions, failures)
}

/// Robot positions and task work stepped with a fine clock `dt`, replaying the run's
/// decisions at their times: when each task is done, and every (robot, task, time)
/// arrival.
fn reference(mission: &Mission, run: &MissionRun, dt: f64) -> (Vec<f64>, Vec<(usize, usize, f64)>) {
    let n = mission.robots.len();
    let mut pos: Vec<Point> = mission.robots.iter().map(|r| r.position).collect();
    let mut task: Vec<Option<usize>> = vec![None; n];
    let mut remaining: Vec<f64> = mission.tasks.iter().map(|t| t.workload).collect();
    let mut done = vec![f64::NAN; remaining.len()];
    let mut arrived = vec![f64::NAN; n];
    let mut arrivals: Vec<(usize, usize, f64)> = Vec::new();
    let (decisions, failures) = scheduled(mission, run);
    let mut alive = vec![true; n];
    let (mut t, mut next, mut next_failure) = (0.0, 0, 0);
    while t < run.metrics.end + dt {
        while next_failure < failures.len() && failures[next_failure].0 <= t + 1e-12 {
            let (_, i, back) = failures[next_failure];
            alive[i] = back;
            (task[i], arrived[i]) = (None, f64::NAN);
            next_failure += 1;
        }
        while next < decisions.len() && decisions[next].0 <= t + 1e-12 {
            for (i, &j) in decisions[next].1.iter().enumerate() {
                let j = usize::try_from(j).ok().filter(|_| alive[i]);
                if j != task[i] {
                    arrived[i] = f64::NAN;
                }
                task[i] = j;
            }
            next += 1;
        }
        let mut present = vec![0usize; remaining.len()];
        let mut held = vec![vec![0u32; mission.num_skills()]; remaining.len()];
        for i in 0..n {
            let Some(j) = task[i] else { continue };
            let target = mission.tasks[j].position;
            let d = pos[i].distance(target);
            let step = mission.robots[i].speed * dt;
            if d <= step {
                pos[i] = target;
                if arrived[i].is_nan() {
                    arrived[i] = t;
                    arrivals.push((i, j, t));
                }
                present[j] += 1;
                for (h, s) in held[j].iter_mut().zip(&mission.robots[i].skills) {
                    *h += s;
                }
            } else {
                pos[i] = Point::new(
                    pos[i].x + step * (target.x - pos[i].x) / d,
                    pos[i].y + step * (target.y - pos[i].y) / d,
                );
            }
        }
        for (j, r) in remaining.iter_mut().enumerate() {
            let spec = &mission.tasks[j];
            // Work only while the team present meets the threshold and the skills.
            let complete = present[j] >= spec.min_team.max(1)
                && (spec.requires.iter().zip(&held[j])).all(|(need, have)| have >= need);
            if *r > 0.0 && complete {
                let rate = work_rate(present[j], spec.eps);
                *r -= rate * dt;
                // Done within a step of the end: the run's decision at its end (which
                // may take the robots away) comes no earlier than this step's.
                if *r <= rate * dt {
                    *r = 0.0;
                    done[j] = t + dt;
                    // The task's robots are free.
                    let freed: Vec<usize> = (0..n).filter(|&i| task[i] == Some(j)).collect();
                    for i in freed {
                        (task[i], arrived[i]) = (None, f64::NAN);
                    }
                }
            }
        }
        t += dt;
    }
    (done, arrivals)
}

/// Each arrival and completion of the event-driven run happens in the fine-step
/// reference within a step or so of its time.
fn check_against_reference(mission: &Mission, run: &MissionRun, dt: f64) {
    let (done, arrivals) = reference(mission, run, dt);
    let speed = mission.robots.iter().map(|r| r.speed).fold(0.0, f64::max);
    // The same tasks done: none the run leaves out, none it adds.
    for (task, &at) in done.iter().enumerate() {
        let reported = (run.trace.iter())
            .any(|e| matches!(*e, TraceEvent::TaskDone { task: t, .. } if t == task));
        let settled = at.is_nan() || at < run.metrics.end - 3.0 * dt * (1.0 + speed);
        assert!(
            !settled || reported != at.is_nan(),
            "task {task}: the reference has it done at {at}, the run {}",
            if reported { "too" } else { "never" }
        );
    }
    for e in &run.trace {
        match *e {
            TraceEvent::TaskDone { time, task } => {
                assert!(
                    (done[task] - time).abs() <= 3.0 * dt * (1.0 + speed),
                    "task {task}: done at {time}, the reference at {}",
                    done[task]
                );
            }
            TraceEvent::Arrival { time, robot, task } => {
                let nearest = arrivals
                    .iter()
                    .filter(|&&(i, j, _)| (i, j) == (robot, task))
                    .map(|&(_, _, t)| (t - time).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest <= 2.0 * dt,
                    "robot {robot} at task {task}: arrived at {time}, the reference {nearest} away"
                );
            }
            _ => {}
        }
    }
}

/// The event-driven run against the fine-step reference, for allocators that keep
/// robots where they are (nearest), move them between decisions (greedy, the
/// optimum) and, on missions whose tasks need teams, make robots wait.
#[test]
fn event_times_equal_a_fine_step_reference() {
    let allocators: [&dyn afg_baseline::Allocator; 3] =
        [&afg_baseline::Nearest, &afg_baseline::Greedy, &Optimum];
    for seed in 0..3 {
        for preset in [Preset::Static, Preset::Waves, Preset::Attrition] {
            let mut config = MissionConfig::new(preset, 6, 3, seed);
            config.horizon = 20.0;
            // Tight capacities on every other seed: some robots idle.
            config.capacity_slack = (seed % 2 == 1).then_some(1.0);
            let mission = config.generate().unwrap();
            config.capacity_slack = None;
            config.min_team = Some(afg_game::CountRange { min: 1, max: 3 });
            let teams = config.generate().unwrap();
            for allocator in allocators {
                for mission in [&mission, &teams] {
                    let run = simulate(mission, Replan::Scratch(allocator), traced()).unwrap();
                    let name = allocator.name();
                    assert!(run.metrics.tasks_done > 0, "{name}, seed {seed}");
                    check_against_reference(mission, &run, 1e-4);
                    check_run(mission, &run, true);
                }
            }
        }
    }
}
