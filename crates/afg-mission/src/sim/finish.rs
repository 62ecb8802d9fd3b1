//! What a run records as it goes (frames, the trace, the timeline, the work done) and
//! the metrics of a finished run.

use super::{
    Frame, Metrics, MissionRun, Sim, SwarmState, TimelinePoint, TraceEvent, Waiting, work_rate,
};

impl Sim<'_, '_> {
    /// The run's metrics, timeline and trace.
    pub(super) fn finish(mut self) -> MissionRun {
        // The last frame is the final state (the animation ends on it).
        let stale = self.frames.last().is_some_and(|f| f.time < self.now);
        if self.options.frame_every.is_some() && stale {
            let last = self.frame();
            self.frames.push(last);
        }
        let mut latencies: Vec<f64> = self
            .tasks
            .iter()
            .zip(&self.mission.tasks)
            .filter_map(|(t, spec)| t.done_at.map(|d| d - spec.appears))
            .collect();
        latencies.sort_by(f64::total_cmp);
        let n = latencies.len();
        let p95 = (n > 0).then(|| latencies[(0.95 * n as f64).ceil() as usize - 1]);
        let makespan = self
            .tasks
            .iter()
            .map(|t| t.done_at)
            .collect::<Option<Vec<f64>>>()
            .map(|done| done.into_iter().fold(0.0, f64::max));
        // Legs still under way count up to where the robots are now.
        let travelling: f64 = (0..self.robots.len())
            .filter(|&i| {
                let r = &self.robots[i];
                r.alive && r.task.is_some() && !r.there
            })
            .map(|i| self.robots[i].from.distance(self.position(i)))
            .sum();
        let work_done = self.work().map(|(w, _)| w).sum();
        let work_value = self.work_value();
        let total: f64 = self.compute.iter().sum();
        let metrics = Metrics {
            tasks_done: n,
            tasks: self.tasks.len(),
            reward_done: self.reward_done(),
            reward_total: self
                .mission
                .tasks
                .iter()
                .map(|t| t.reward * t.workload)
                .sum(),
            latency_mean: (n > 0).then(|| latencies.iter().sum::<f64>() / n as f64),
            latency_p95: p95,
            latency_max: latencies.last().copied(),
            makespan,
            end: self.now,
            distance: self.distance + travelling,
            reassignments: self.reassignments,
            decisions: self.decisions,
            pairs: self.pairs,
            compute_mean_s: if self.compute.is_empty() {
                0.0
            } else {
                total / self.compute.len() as f64
            },
            compute_max_s: self.compute.iter().copied().fold(0.0, f64::max),
            compute_total_s: total,
            work_done,
            work_value,
            swarm: self.swarm.as_ref().map(SwarmState::metrics),
            gap_max: self.gaps.iter().copied().reduce(f64::max),
            waiting: self.mission.has_teams().then(|| Waiting {
                total: self.waiting.iter().sum(),
                by_task: self.waiting.clone(),
            }),
        };
        MissionRun {
            metrics,
            timeline: self.timeline,
            trace: self.trace,
            frames: self.frames,
        }
    }

    /// A frame, if one is due.
    pub(super) fn snapshot(&mut self) {
        let (Some(due), Some(every)) = (self.next_frame, self.options.frame_every) else {
            return;
        };
        if due > self.now {
            return;
        }
        self.next_frame = Some(due + every);
        let frame = self.frame();
        self.frames.push(frame);
    }

    /// The whole state now.
    pub(super) fn frame(&self) -> Frame {
        let positions = (0..self.robots.len())
            .map(|i| {
                let p = self.position(i);
                [p.x as f32, p.y as f32]
            })
            .collect();
        let tasks = self
            .robots
            .iter()
            .map(|r| match (r.alive, r.task) {
                (false, _) => -2,
                (true, None) => -1,
                (true, Some(j)) => j as i32,
            })
            .collect();
        let left = self
            .tasks
            .iter()
            .zip(&self.mission.tasks)
            .map(|(t, spec)| {
                if t.open || t.done_at.is_some() {
                    (t.remaining / spec.workload) as f32
                } else {
                    -1.0
                }
            })
            .collect();
        let waiting = (0..self.robots.len())
            .filter(|&i| {
                let r = &self.robots[i];
                r.alive && r.there && r.task.is_some_and(|j| !self.team_complete(j))
            })
            .map(|i| i as u32)
            .collect();
        Frame {
            time: self.now,
            positions,
            tasks,
            left,
            waiting,
        }
    }

    /// Moves time to `to`: work is done at the present coalitions' rates (robots'
    /// positions follow from their legs).
    pub(super) fn advance(&mut self, to: f64) {
        let dt = to - self.now;
        for j in 0..self.tasks.len() {
            let t = self.tasks[j];
            if !t.open || t.present == 0 {
                continue;
            }
            if self.team_complete(j) {
                let rate = work_rate(t.present, self.mission.tasks[j].eps);
                self.tasks[j].remaining = (t.remaining - rate * dt).max(0.0);
            } else {
                self.waiting[j] += t.present as f64 * dt;
            }
        }
        self.now = to;
    }

    /// Whether the robots present at task j meet its threshold and hold its skills.
    pub(super) fn team_complete(&self, j: usize) -> bool {
        let spec = &self.mission.tasks[j];
        let s = self.mission.num_skills();
        self.tasks[j].present >= spec.min_team
            && spec
                .requires
                .iter()
                .zip(&self.held[j * s..][..s])
                .all(|(&need, &have)| have >= u64::from(need))
    }

    /// Task j's work rate now: its present coalition's, once its team is complete.
    pub(super) fn rate(&self, j: usize) -> f64 {
        if self.team_complete(j) {
            work_rate(self.tasks[j].present, self.mission.tasks[j].eps)
        } else {
            0.0
        }
    }

    /// Robot i arrives at task j (`joins`) or leaves it: the count and skills present.
    pub(super) fn present(&mut self, i: usize, j: usize, joins: bool) {
        let s = self.mission.num_skills();
        let skills = &self.mission.robots[i].skills;
        let held = &mut self.held[j * s..][..s];
        if joins {
            self.tasks[j].present += 1;
            held.iter_mut()
                .zip(skills)
                .for_each(|(h, &q)| *h += u64::from(q));
        } else {
            self.tasks[j].present -= 1;
            held.iter_mut()
                .zip(skills)
                .for_each(|(h, &q)| *h -= u64::from(q));
        }
    }

    pub(super) fn log(&mut self, event: TraceEvent) {
        if self.options.trace {
            self.trace.push(event);
        }
    }

    pub(super) fn record(&mut self) {
        let point = TimelinePoint {
            time: self.now,
            open: self.tasks.iter().filter(|t| t.open).count(),
            done: self.tasks.iter().filter(|t| t.done_at.is_some()).count(),
            reward: self.reward_done(),
        };
        if self.timeline.last() != Some(&point) {
            self.timeline.push(point);
        }
    }

    /// Work done on each task so far, with its task's spec.
    pub(super) fn work(&self) -> impl Iterator<Item = (f64, &crate::TaskSpec)> + '_ {
        (self.tasks.iter())
            .zip(&self.mission.tasks)
            .map(|(t, spec)| (spec.workload - t.remaining, spec))
    }

    /// `Σ r_j` times the work done on each task so far.
    pub(super) fn work_value(&self) -> f64 {
        self.work().map(|(w, spec)| spec.reward * w).sum()
    }

    pub(super) fn reward_done(&self) -> f64 {
        self.tasks
            .iter()
            .zip(&self.mission.tasks)
            .filter(|(t, _)| t.done_at.is_some())
            .map(|(_, spec)| spec.reward * spec.workload)
            .sum()
    }
}
