//! Missions over time for the alliance formation game: tasks appear with a workload
//! and are worked off, robots travel at their speed and may fail, and an allocator —
//! any [`afg_baseline::Allocator`] — decides at every event.
//!
//! - [`Mission`]: the robots, tasks, failures and horizon, with its JSON format
//!   (`afg-mission`, versioned, unknown fields refused) and its checks.
//! - [`MissionConfig`]: missions drawn from presets ([`Preset`]: static, waves,
//!   Poisson arrivals, attrition) with every knob.
//! - [`MissionPlan`]: the one front door — who decides and how (a built-in method,
//!   GRAPE or the auction over the radio with their [`SwarmKnobs`], or an allocator
//!   passed in), checked once into a [`Planner`] that runs missions.
//! - [`Planner::run`]: the event-driven run (from scratch, warm-started, or the exact
//!   optimum re-solved from its previous prices), with an optional decision latency
//!   ([`Latency`]) and replanning interval, returning the [`Metrics`], a timeline and,
//!   if asked, every event ([`TraceEvent`]).
//! - [`internal`]: the simulator's own door beneath the plan, for this crate's tests.
//!
//! The model, in brief (docs/missions.md has it in full): robots move in straight
//! lines towards their task; the `n` robots present at a task do
//! `log_eps(n + eps − 1)` units of work per time unit ([`work_rate`]), so the paper's
//! coalition value `F_j(n)` is the task's reward rate; a task is done when its
//! workload is, and its robots are free. At every event (a task appears or is done, a
//! robot fails or returns) the allocator is handed the paper's game of the current
//! state — the living robots where they are, the open tasks as they are (their reward,
//! not scaled by the work left) — and robots act on its answer once it is made.
//!
//! # Examples
//! ```
//! use afg_baseline::Method;
//! use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset};
//! let mission = MissionConfig::new(Preset::Waves, 40, 8, 2).generate()?;
//! let run = |plan: MissionPlan| plan.planner()?.run(&mission, Default::default(), |_| {});
//! let greedy = run(MissionPlan { method: MissionMethod::Central(Method::Greedy), ..MissionPlan::default() })?;
//! let opt = run(MissionPlan { warm: true, ..MissionPlan::default() })?;
//! assert_eq!(greedy.metrics.tasks, 8);
//! assert!(opt.metrics.decisions >= 4); // at least one per wave
//! # Ok::<(), afg_mission::MissionError>(())
//! ```

mod generate;
mod mission;
mod mission_config;
mod plan;
mod sim;

pub use generate::MissionKnobs;
pub use mission::{Failure, MISSION_FORMAT, MISSION_VERSION, Mission, RobotSpec, TaskSpec};
pub use mission_config::{MissionConfig, Preset};
pub use plan::{MissionMethod, MissionPlan, Planner, RadioKnobs, Recording, SwarmKnobs};
pub use sim::{
    EnvStep, Frame, Latency, Metrics, MissionEnv, MissionRun, Perception, ROBOT_FEATURES,
    SwarmMetrics, TASK_FEATURES, TEAM_FEATURES, TimelinePoint, TraceEvent, Waiting, work_rate,
};

/// The simulator beneath [`MissionPlan`]: a run with a replanning rule and options
/// given directly, each checked at every run. Internal: it is here for this crate's
/// tests (custom allocators, radio settings no plan names) and may change without
/// notice; everyone else runs missions through [`MissionPlan::planner`].
#[doc(hidden)]
pub mod internal {
    pub use crate::sim::{Decentralised, Replan, RunOptions, simulate, simulate_with};
}

use afg_baseline::AllocError;
use afg_game::GameError;
use thiserror::Error;

/// What can go wrong with a mission.
#[derive(Debug, Error)]
pub enum MissionError {
    /// Malformed JSON, an unknown or a missing field.
    #[error("invalid mission JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A file of another format or version.
    #[error("expected format \"afg-mission\" version 1, found {found}")]
    Format {
        /// What the file declares.
        found: String,
    },
    /// A value out of range.
    #[error("invalid mission: {0}")]
    Invalid(String),
    /// The game of a decision could not be built.
    #[error(transparent)]
    Game(#[from] GameError),
    /// The allocator failed.
    #[error(transparent)]
    Alloc(#[from] AllocError),
    /// The allocator failed at a decision (a Q network built for another number of
    /// tasks than are open then, for instance).
    #[error("the decision at time {time:.3} ({robots} robots, {tasks} open tasks): {source}")]
    Decision {
        /// Mission time.
        time: f64,
        /// Robots in the decision's game.
        robots: usize,
        /// Open tasks in it.
        tasks: usize,
        /// What the allocator said.
        #[source]
        source: AllocError,
    },
}
