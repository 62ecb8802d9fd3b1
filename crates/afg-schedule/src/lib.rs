//! Schedules for team and skill tasks over time.
//!
//! Robots leave their depots and perform *sequences* of tasks; a task needs a team (a
//! number of robots, or skills that its members hold together) present at once, and runs
//! for its duration once the team is complete; the score is the **makespan**, when the
//! last robot is back. This is the problem of DCMRTA's and HeteroMRTA's test sets, and
//! this crate reads them exactly ([`ScheduleInstance`]), plays a schedule under their
//! simulators' rules ([`ScheduleInstance::evaluate`]), draws instances of both families,
//! plans whole schedules and bounds the makespan from below.
//!
//! # Examples
//! ```
//! use afg_schedule::{Schedule, ScheduleInstance};
//! let inst = ScheduleInstance::from_json(r#"{"speed":1,"max_wait":10,"depots":[[0,0]],
//!   "robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],
//!   "tasks":[{"x":0,"y":2,"min_team":2,"duration":1},{"x":0,"y":4,"min_team":1,"duration":3}]}"#)?;
//! let run = inst.evaluate(&Schedule { routes: vec![vec![0, 1], vec![0]] })?;
//! // Both at task 0 at t = 2, done at 3; robot 0 reaches task 1 at 5, done at 8, home at 12.
//! assert_eq!(run.makespan, 12.0);
//! assert!(run.is_valid());
//! # Ok::<(), afg_schedule::ScheduleError>(())
//! ```

mod anneal;
mod bound;
mod decode;
mod error;
mod evaluate;
mod generate;
mod instance;
mod solve;
mod transport;

pub use bound::{Bound, TRANSPORT_LIMIT};
pub use error::ScheduleError;
pub use evaluate::{
    Evaluation, LongWait, Role, Schedule, ScheduleRecord, TimeUse, Visit, read_schedules,
};
pub use generate::{Family, Generate, MAX_SIZE};
pub use instance::{Metric, Place, Robot, Rules, ScheduleInstance, Task, read_instances};
pub use solve::{SolveOptions, Solved};
