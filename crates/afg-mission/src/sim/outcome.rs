//! What a run gives back: its metrics, timeline, trace and frames.

use serde::{Deserialize, Serialize};

use super::SwarmMetrics;

/// One event of a run, for `--trace` (JSON Lines).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "event")]
pub enum TraceEvent {
    /// A task appeared.
    TaskAppears {
        /// Mission time.
        time: f64,
        /// The task.
        task: usize,
    },
    /// A task's workload was done.
    TaskDone {
        /// Mission time.
        time: f64,
        /// The task.
        task: usize,
    },
    /// A robot failed.
    RobotFails {
        /// Mission time.
        time: f64,
        /// The robot.
        robot: usize,
    },
    /// A robot came back.
    RobotReturns {
        /// Mission time.
        time: f64,
        /// The robot.
        robot: usize,
    },
    /// A robot reached its task.
    Arrival {
        /// Mission time.
        time: f64,
        /// The robot.
        robot: usize,
        /// Its task.
        task: usize,
    },
    /// A decision took effect.
    Decision {
        /// When it took effect.
        time: f64,
        /// When it was asked for.
        asked: f64,
        /// Every robot's task from then on (−1: none).
        tasks: Vec<i64>,
        /// Every robot's position then.
        positions: Vec<[f64; 2]>,
        /// The allocator's compute time (seconds).
        compute_s: f64,
        /// The exact team solver's certified gap at this decision (0: proven optimal;
        /// above 0 where its time limit stopped it); `None` for other allocators.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        gap: Option<f64>,
    },
}

/// Where the mission stood after an event.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TimelinePoint {
    /// Mission time.
    pub time: f64,
    /// Tasks appeared and not yet done.
    pub open: usize,
    /// Tasks done.
    pub done: usize,
    /// Reward of the tasks done (`Σ r_j W_j`).
    pub reward: f64,
}

/// The metrics of a run (docs/missions.md defines each).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Tasks whose workload was done by the horizon.
    pub tasks_done: usize,
    /// Tasks in the mission.
    pub tasks: usize,
    /// `Σ r_j W_j` over the tasks done: the score to rank methods by.
    pub reward_done: f64,
    /// `Σ r_j W_j` over all tasks: the most a run can score.
    pub reward_total: f64,
    /// Mean time from a task's appearance to its completion, over the tasks done.
    pub latency_mean: Option<f64>,
    /// Its 95th percentile (nearest rank).
    pub latency_p95: Option<f64>,
    /// Its maximum.
    pub latency_max: Option<f64>,
    /// When the last task was done, if every task was.
    pub makespan: Option<f64>,
    /// When the run stopped: the makespan, or the horizon.
    pub end: f64,
    /// Distance travelled by all robots.
    pub distance: f64,
    /// Robots switching from one task to another.
    pub reassignments: u64,
    /// Decisions taken.
    pub decisions: u64,
    /// Robot–task pairs of the decisions' games (Σ robots × open tasks): what any exact
    /// method must read at least once.
    pub pairs: u64,
    /// The allocator's compute time per decision, mean (seconds).
    pub compute_mean_s: f64,
    /// Its maximum.
    pub compute_max_s: f64,
    /// In total.
    pub compute_total_s: f64,
    /// Work done on every task (done or not) by the end.
    pub work_done: f64,
    /// `Σ r_j` times the work done on each task (done or not): the reward done plus
    /// the value of the work on tasks left unfinished.
    pub work_value: f64,
    /// A decentralised method's rounds, traffic and response times (for it, each
    /// round counts as a decision).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub swarm: Option<SwarmMetrics>,
    /// In a mission with teams: the robot-time spent at tasks whose team was
    /// incomplete (robots that arrived first, waiting for the rest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub waiting: Option<Waiting>,
    /// The exact team solver in the loop: the largest certified gap of its decisions
    /// (0 when every one was proven optimal; above 0 where its time limit stopped it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gap_max: Option<f64>,
}

/// Robot-time spent waiting at tasks whose team was incomplete.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Waiting {
    /// Over every task.
    pub total: f64,
    /// Per task, in mission order.
    pub by_task: Vec<f64>,
}

/// A finished run: its metrics, its timeline, and (if asked) every event.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MissionRun {
    /// The metrics.
    pub metrics: Metrics,
    /// Open and done tasks and reward after every event.
    pub timeline: Vec<TimelinePoint>,
    /// Every event and decision, if [`Recording::trace`](crate::Recording::trace).
    pub trace: Vec<TraceEvent>,
    /// Snapshots every [`Recording::frame_every`](crate::Recording::frame_every) time units.
    pub frames: Vec<Frame>,
}

/// The whole state at one moment (for animations).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Mission time.
    pub time: f64,
    /// Every robot's position.
    pub positions: Vec<[f32; 2]>,
    /// Every robot's task (−1: none; −2: failed).
    pub tasks: Vec<i32>,
    /// Every task's work left as a share of its workload (−1: not yet appeared; 0: done).
    pub left: Vec<f32>,
    /// The robots waiting at a task whose team is incomplete (missions with teams).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub waiting: Vec<u32>,
}

impl MissionRun {
    /// The trace as JSON Lines, one event a line (`afg mission run --trace`).
    ///
    /// # Examples
    /// ```
    /// use afg_mission::{MissionConfig, MissionPlan, Preset, Recording};
    /// let mission = MissionConfig::new(Preset::Static, 5, 2, 1).generate()?;
    /// let traced = Recording { trace: true, ..Recording::default() };
    /// let run = MissionPlan::default().planner()?.run(&mission, traced, |_| {})?;
    /// assert_eq!(run.trace_jsonl().lines().count(), run.trace.len());
    /// # Ok::<(), afg_mission::MissionError>(())
    /// ```
    pub fn trace_jsonl(&self) -> String {
        self.trace
            .iter()
            .map(|e| serde_json::to_string(e).expect("an event serialises") + "\n")
            .collect()
    }
}
