//! What every traced mission run must satisfy, rebuilt from its trace alone: shared
//! by the mission tests.

use afg_game::Point;
use afg_mission::internal::RunOptions;
use afg_mission::{Mission, MissionRun, TraceEvent, work_rate};

/// Run options that keep the trace.
pub fn traced() -> RunOptions {
    RunOptions {
        trace: true,
        ..RunOptions::default()
    }
}

/// What every traced run must satisfy: robots no faster than their speed (an arrival
/// comes exactly distance / speed after the decision that sent the robot there),
/// coalitions within capacity, failed robots idle, work conserved.
pub fn check_run(mission: &Mission, run: &MissionRun, capacities: bool) {
    let n = mission.robots.len();
    let mut sent: Vec<Option<(f64, [f64; 2], i64)>> = vec![None; n];
    let mut failed = vec![false; n];
    for e in &run.trace {
        match e {
            TraceEvent::Decision {
                time,
                tasks,
                positions,
                ..
            } => {
                let mut sizes = vec![0usize; mission.tasks.len()];
                for (i, &j) in tasks.iter().enumerate() {
                    if j < 0 {
                        sent[i] = None;
                        continue;
                    }
                    assert!(!failed[i], "failed robot {i} given task {j}");
                    sizes[j as usize] += 1;
                    if sent[i].is_none_or(|(_, _, old)| old != j) {
                        sent[i] = Some((*time, positions[i], j));
                    }
                }
                for (j, &size) in sizes.iter().enumerate() {
                    let cap = mission.tasks[j].capacity.unwrap_or(usize::MAX);
                    assert!(
                        !capacities || size <= cap,
                        "task {j}: {size} robots, capacity {cap}"
                    );
                }
            }
            TraceEvent::Arrival { time, robot, task } => {
                assert!(!failed[*robot], "failed robot {robot} arrived");
                let (t0, [x, y], j) = sent[*robot].expect("sent before arriving");
                assert_eq!(j as usize, *task);
                let d = Point::new(x, y).distance(mission.tasks[*task].position);
                let need = d / mission.robots[*robot].speed;
                assert!(
                    (time - t0 - need).abs() <= 1e-9 * (1.0 + time),
                    "robot {robot}: {} time units for {need}",
                    time - t0
                );
            }
            TraceEvent::RobotFails { robot, .. } => failed[*robot] = true,
            TraceEvent::RobotReturns { robot, .. } => failed[*robot] = false,
            _ => {}
        }
    }
    check_work(mission, run);
}

/// Work conserved: each task's work rebuilt from the trace alone is its workload
/// when it is done, less when not, and adds up to the run's `work_done`; the waiting
/// rebuilt with it is the run's.
fn check_work(mission: &Mission, run: &MissionRun) {
    // Work conserved: each task's work rebuilt from the trace alone is its workload
    // when it is done, less when not, and adds up to the run's `work_done`.
    let (work, waiting) = work_from_trace(mission, run);
    // Waiting rebuilt the same way is the run's, task by task (missions with teams).
    match &run.metrics.waiting {
        Some(measured) => {
            for (j, (w, m)) in waiting.iter().zip(&measured.by_task).enumerate() {
                assert!(
                    (w - m).abs() <= 1e-6 * (1.0 + m),
                    "task {j}: waited {w}, run says {m}"
                );
            }
        }
        None => assert!(waiting.iter().all(|&w| w == 0.0), "{waiting:?}"),
    }
    let done: Vec<bool> = (0..mission.tasks.len())
        .map(|j| {
            (run.trace.iter()).any(|e| matches!(e, TraceEvent::TaskDone { task, .. } if *task == j))
        })
        .collect();
    for (j, (&w, spec)) in work.iter().zip(&mission.tasks).enumerate() {
        let tolerance = 1e-6 * (1.0 + spec.workload);
        if done[j] {
            assert!(
                (w - spec.workload).abs() <= tolerance,
                "task {j}: {w} of {}",
                spec.workload
            );
        } else {
            assert!(
                w <= spec.workload + tolerance,
                "task {j} open with {w} of {}",
                spec.workload
            );
        }
    }
    let total: f64 = (work.iter().zip(&mission.tasks))
        .map(|(w, t)| w.min(t.workload))
        .sum();
    let m = &run.metrics;
    assert!(
        (total - m.work_done).abs() <= 1e-6 * (1.0 + total),
        "{total} vs {}",
        m.work_done
    );
}

/// When `event` happened.
fn time_of(event: &TraceEvent) -> f64 {
    match event {
        TraceEvent::TaskAppears { time, .. }
        | TraceEvent::TaskDone { time, .. }
        | TraceEvent::RobotFails { time, .. }
        | TraceEvent::RobotReturns { time, .. }
        | TraceEvent::Arrival { time, .. }
        | TraceEvent::Decision { time, .. } => *time,
    }
}

/// Each task's work and the robot-time waited there, from the trace alone: between
/// consecutive events the robots that arrived at a task and have not left it (sent
/// elsewhere, failed, or freed by the task being done) work at `work_rate(present,
/// eps)` while they meet the task's threshold and hold its skills, and wait otherwise.
fn work_from_trace(mission: &Mission, run: &MissionRun) -> (Vec<f64>, Vec<f64>) {
    let (n, k) = (mission.robots.len(), mission.tasks.len());
    let mut at: Vec<Option<usize>> = vec![None; n];
    let mut assigned = vec![-1i64; n];
    let mut done = vec![false; k];
    let (mut work, mut waiting) = (vec![0.0; k], vec![0.0; k]);
    let mut last = 0.0;
    let mut work_until = |time: f64, at: &[Option<usize>], done: &[bool], work: &mut [f64]| {
        let mut present = vec![0usize; k];
        let mut held = vec![vec![0u32; mission.num_skills()]; k];
        for (i, &j) in at.iter().enumerate() {
            if let Some(j) = j {
                present[j] += 1;
                for (h, s) in held[j].iter_mut().zip(&mission.robots[i].skills) {
                    *h += s;
                }
            }
        }
        for j in (0..k).filter(|&j| !done[j] && present[j] > 0) {
            let spec = &mission.tasks[j];
            let complete = present[j] >= spec.min_team
                && spec
                    .requires
                    .iter()
                    .zip(&held[j])
                    .all(|(need, have)| have >= need);
            if complete {
                work[j] += work_rate(present[j], spec.eps) * (time - last);
            } else {
                waiting[j] += present[j] as f64 * (time - last);
            }
        }
        last = time;
    };
    for event in &run.trace {
        work_until(time_of(event), &at, &done, &mut work);
        match event {
            TraceEvent::Decision { tasks, .. } => {
                for (i, &j) in tasks.iter().enumerate() {
                    if j != assigned[i] {
                        at[i] = None;
                    }
                    assigned[i] = j;
                }
            }
            TraceEvent::Arrival { robot, task, .. } => at[*robot] = Some(*task),
            TraceEvent::RobotFails { robot, .. } => (at[*robot], assigned[*robot]) = (None, -1),
            TraceEvent::TaskDone { task, .. } => {
                done[*task] = true;
                for i in 0..n {
                    if assigned[i] == *task as i64 {
                        (at[i], assigned[i]) = (None, -1);
                    }
                }
            }
            TraceEvent::TaskAppears { .. } | TraceEvent::RobotReturns { .. } => {}
        }
    }
    work_until(run.metrics.end, &at, &done, &mut work);
    (work, waiting)
}
