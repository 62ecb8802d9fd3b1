//! The alliance formation game of multi-robot task assignment (paper §II; the choices it leaves open are in docs/decisions.md).
//!
//! N robots and M tasks in the plane. A coalition of n robots at task j is worth
//! `F_j(n) = r_j log_{eps_j}(n + eps_j - 1)`, shared equally; robot i pays
//! `beta d(i, j)` to get there, so its utility is `u_i(j, n) = F_j(n)/n - beta d(i, j)`
//! and the welfare of an assignment is the sum of utilities.
//!
//! This crate holds the model and nothing else: validated [`Instance`]s, [`Assignment`]s
//! and their welfare, the balanced and selfish [`Preference`]s, stability and NS_rate,
//! a seeded [`GeneratorConfig`], and versioned JSON / JSON Lines I/O.
//!
//! # Examples
//! ```
//! use afg_game::{Assignment, GeneratorConfig, Preference};
//! let inst = GeneratorConfig::paper(20, 5, 42).generate()?;
//! let mut a = Assignment::unassigned(inst.num_robots(), inst.num_tasks());
//! // Let robots best-respond (balanced) until nobody wants to move.
//! while let Some(i) = inst.robot_ids().find(|&i| !inst.is_satisfied(&a, i, Preference::Balanced)) {
//!     let j = inst.best_response(&a, i, Preference::Balanced);
//!     a.set(i, j);
//! }
//! assert!(inst.is_stable(&a, Preference::Balanced));
//! assert_eq!(inst.ns_rate(&a, Preference::Balanced), 1.0);
//! println!("welfare {:.2}", inst.welfare(&a));
//! # Ok::<(), afg_game::GameError>(())
//! ```

mod assignment;
mod error;
mod family;
pub mod fs;
mod generate;
mod generator_config;
mod ids;
mod instance;
pub mod io;
mod named;
pub mod realloc;
mod stability;
mod teams;

pub use assignment::Assignment;
pub use error::GameError;
pub use family::{Clusters, Family, Shape};
pub use generate::{GameSize, GeneratorKnobs};
pub use generator_config::{CountRange, GeneratorConfig, SkillDraw};
pub use ids::{RobotId, TaskId};
pub use instance::{GOLDEN_RATIO, Instance, MAX_VALUE, Point, Task, ValueFunction};
pub use named::Named;
pub use stability::{Preference, TOLERANCE, strictly_better};
pub use teams::unstaffable_warning;
