//! The metrics of a finished run.

use super::{Metrics, MissionRun, Sim, SwarmState};

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
        };
        MissionRun {
            metrics,
            timeline: self.timeline,
            trace: self.trace,
            frames: self.frames,
        }
    }
}
