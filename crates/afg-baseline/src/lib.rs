//! Classical allocators for the alliance formation game, all behind one
//! [`Allocator`] trait: GRAPE's decentralised algorithm and its centralised twin
//! ([`DecentralisedDa`], [`CentralisedDa`], selfish or balanced preference), the exact
//! optimum ([`Optimum`]), and the trivial [`Greedy`], [`Nearest`],
//! [`RandomAllocator`] and [`Blind`].
//!
//! # Examples
//! ```
//! use afg_baseline::{Allocator, Method};
//! use afg_game::GeneratorConfig;
//! let inst = GeneratorConfig::paper(60, 5, 1).generate()?;
//! let opt = Method::Opt.allocator(0).allocate(&inst)?;
//! for method in Method::ALL {
//!     let out = method.allocator(0).allocate(&inst)?;
//!     assert!(inst.welfare(&out.assignment) <= inst.welfare(&opt.assignment) + 1e-9);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

/// The README's example, compiled and run as a doc test.
#[doc = include_str!("../../../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

mod climb;
mod dynamics;
mod method;
mod optimum;
mod simple;
mod swarm;

use std::time::{Duration, Instant};

use afg_game::{Assignment, GameError, Instance};
use afg_graph::GraphError;
use serde::{Deserialize, Serialize};
use thiserror::Error;

pub use climb::climb;
pub use dynamics::{CentralisedDa, DecentralisedDa, DecentralisedRun};
pub use method::Method;
pub use optimum::{
    BYTES_PER_PAIR, Certificate, IncrementalOptimum, Optimum, TeamOptimum, TeamProgress,
    TeamRelaxation, TeamSolution, available_memory, exact_memory, verify_optimal,
};
pub use simple::{Blind, Greedy, Nearest, RandomAllocator};
pub use swarm::{
    DETECT_AFTER, Failure, LiveSwarm, Network, Swarm, SwarmMethod, SwarmReport, TracePoint,
};

/// `100 · welfare / opt_welfare`, the one "% of OPT" of every table, command, training
/// validation and summary; `None` when the optimum's welfare is not positive (all
/// rewards zero, or tasks so far away that every robot loses): a ratio to it would
/// flip sign or divide by zero.
///
/// # Examples
/// ```
/// use afg_baseline::percent_of_opt;
/// assert_eq!(percent_of_opt(49.0, 50.0), Some(98.0));
/// assert_eq!(percent_of_opt(-2.0, -1.0), None);
/// assert_eq!(percent_of_opt(0.0, 0.0), None);
/// ```
pub fn percent_of_opt(welfare: f64, opt_welfare: f64) -> Option<f64> {
    (opt_welfare > 0.0).then(|| 100.0 * welfare / opt_welfare)
}

/// The mean over instances of [`percent_of_opt`] for (welfare, optimum's welfare)
/// pairs — a mean of ratios, as every table reports it, not a ratio of sums; `None`
/// for no instances or when one instance's ratio is undefined.
///
/// # Examples
/// ```
/// use afg_baseline::mean_percent_of_opt;
/// assert_eq!(mean_percent_of_opt([(9.0, 10.0), (1.0, 1.0)]), Some(95.0)); // a ratio of sums says 90.9
/// assert_eq!(mean_percent_of_opt([(1.0, 1.0), (1.0, 0.0)]), None);
/// assert_eq!(mean_percent_of_opt([]), None);
/// ```
pub fn mean_percent_of_opt(pairs: impl IntoIterator<Item = (f64, f64)>) -> Option<f64> {
    let (mut total, mut count) = (0.0, 0usize);
    for (welfare, opt) in pairs {
        total += percent_of_opt(welfare, opt)?;
        count += 1;
    }
    (count > 0).then(|| total / count as f64)
}

/// An allocation method: instance in, complete assignment and statistics out.
///
/// `Send + Sync` so that evaluations can run instances on several threads.
pub trait Allocator: Send + Sync {
    /// Short name used in tables and on the command line (e.g. `"opt"`).
    fn name(&self) -> String;

    /// Assigns every robot of `instance` to a task, respecting capacities.
    ///
    /// # Errors
    /// Method-specific; see [`AllocError`].
    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError>;
}

/// What an allocator returns.
#[derive(Clone, Debug)]
pub struct Allocation {
    /// The assignment (complete).
    pub assignment: Assignment,
    /// How it was reached.
    pub stats: AllocStats,
}

/// Work counters of one allocation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AllocStats {
    /// Changes of assignment: robot moves for the dynamics (for the decentralised one,
    /// the final evolution number), robots placed for one-pass methods, path shifts for OPT.
    pub iterations: u64,
    /// Synchronous communication rounds (decentralised) or sweeps over all robots.
    pub rounds: u64,
    /// Messages sent (decentralised only).
    pub messages: u64,
    /// Wall-clock time of the allocation.
    #[serde(with = "seconds")]
    pub wall_time: Duration,
    /// Seed of a randomised method.
    pub seed: Option<u64>,
    /// An exact method's proven upper bound on every assignment's welfare: the
    /// welfare itself when proven optimal, above it when stopped by a time limit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound: Option<f64>,
}

impl AllocStats {
    /// The certified relative gap of an exact method's `welfare` under its
    /// [`AllocStats::bound`] (see [`certified_gap`]); `None` for a method that reports
    /// no bound.
    ///
    /// # Examples
    /// ```
    /// use afg_baseline::AllocStats;
    /// let stats = AllocStats { bound: Some(110.0), ..AllocStats::default() };
    /// assert_eq!(stats.gap(100.0), Some(0.1));
    /// assert_eq!(AllocStats::default().gap(100.0), None);
    /// ```
    pub fn gap(&self, welfare: f64) -> Option<f64> {
        self.bound.map(|bound| certified_gap(bound, welfare))
    }
}

/// The certified relative gap `(bound − welfare) / |welfare|` of an assignment whose
/// welfare a proven `bound` caps (never negative; where the welfare is 0, the absolute
/// gap): the one formula behind every gap afg prints.
///
/// # Examples
/// ```
/// assert_eq!(afg_baseline::certified_gap(12.0, 10.0), 0.2);
/// assert_eq!(afg_baseline::certified_gap(10.0, 10.0), 0.0);
/// ```
pub fn certified_gap(bound: f64, welfare: f64) -> f64 {
    (bound - welfare).max(0.0) / welfare.abs().max(1e-12)
}

mod seconds {
    use std::time::Duration;

    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(d.as_secs_f64())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Duration, D::Error> {
        let secs = f64::deserialize(d)?;
        Duration::try_from_secs_f64(secs).map_err(serde::de::Error::custom)
    }
}

/// Errors of the allocators.
#[derive(Debug, Error)]
pub enum AllocError {
    /// The instance or assignment is invalid.
    #[error(transparent)]
    Game(#[from] GameError),
    /// The communication graph could not be built.
    #[error(transparent)]
    Graph(#[from] GraphError),
    /// A method parameter is out of range.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// The instance allows the void task (GRAPE's game), which this method has no
    /// action for (a Q network trained on the paper's game): its answer would put every
    /// robot in a coalition.
    #[error(
        "{method} solves the paper's game only, with no action for the void task, and this instance allows it (\"allow_void\": true)"
    )]
    VoidNotSupported {
        /// The method's name.
        method: String,
    },
    /// The instance is a team game (thresholds or skills) that this method does not
    /// play: its answer would count values the game does not pay.
    #[error(
        "{method} does not play games with {rules}: {reason}; `opt` solves them exactly, and {} play them",
        team_players(.rules)
    )]
    TeamsNotSupported {
        /// The method's name.
        method: String,
        /// "team thresholds" or "skill requirements".
        rules: &'static str,
        /// Why the method cannot play them.
        reason: &'static str,
    },
    /// A method defined outside this crate failed.
    #[error("{method}: {message}")]
    Failed {
        /// The method's name.
        method: String,
        /// What went wrong.
        message: String,
    },
    /// Prices do not prove an assignment optimal ([`verify_optimal`]).
    #[error("not proven optimal: welfare {welfare}, but the prices only bound it by {upper_bound}")]
    NotOptimal {
        /// The assignment's welfare.
        welfare: f64,
        /// The prices' upper bound on every assignment's welfare.
        upper_bound: f64,
    },
    /// The exact solver would need more memory than this machine has available
    /// ([`exact_memory`], [`available_memory`]): refused before any is taken.
    #[error(
        "a {robots} × {tasks} game needs about {:.1} GB for the exact solver ({BYTES_PER_PAIR} bytes per robot–task pair), and this machine has {:.1} GB available: solve fewer robots or tasks at once, or measure a method without the optimum (--no-reference, reference=False)",
        *needed as f64 / 1e9,
        *available as f64 / 1e9
    )]
    TooLarge {
        /// Robots N.
        robots: usize,
        /// Tasks M.
        tasks: usize,
        /// Bytes the solve would need.
        needed: u64,
        /// Bytes available.
        available: u64,
    },
    /// The dynamics did not settle within the safety bound of rounds.
    #[error("no stable partition after {rounds} rounds")]
    NotConverged {
        /// The bound that was hit.
        rounds: u64,
    },
}

/// Refuses an instance that allows the void task for a method that solves the paper's
/// game only ([`AllocError::VoidNotSupported`]), rather than answering a different game.
///
/// # Errors
/// [`AllocError::VoidNotSupported`] naming `method`.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Greedy};
/// use afg_game::{Instance, Point, Task};
/// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
/// let inst = Instance::with_void(vec![Point::new(1.0, 0.0)], vec![task], 1.0)?;
/// let err = afg_baseline::paper_game_only(&inst, &Greedy).unwrap_err();
/// assert!(err.to_string().starts_with("greedy solves the paper's game only"));
/// assert!(Greedy.allocate(&inst).is_ok()); // greedy itself plays GRAPE's game
/// # Ok::<(), afg_game::GameError>(())
/// ```
pub fn paper_game_only(instance: &Instance, method: &dyn Allocator) -> Result<(), AllocError> {
    if instance.allows_void() {
        return Err(AllocError::VoidNotSupported {
            method: method.name(),
        });
    }
    Ok(())
}

/// Which games a method plays correctly (see [`check_game`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plays {
    /// The paper's concave game only (the method reads values as a flow's prices, or
    /// was trained there), with the reason.
    Concave(&'static str),
    /// Team thresholds too (the method reads a coalition's value from its size, which
    /// [`Instance::coalition_value`] gives with the threshold), but not skills.
    Counts,
}

/// Refuses a team game that `method` does not play ([`AllocError::TeamsNotSupported`]),
/// rather than answering as if values were paid that the game does not pay.
///
/// # Errors
/// [`AllocError::TeamsNotSupported`] naming the method, the rules and the reason.
///
/// # Examples
/// ```
/// use afg_baseline::{Greedy, Plays, check_game};
/// use afg_game::{Instance, Point, Task};
/// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
/// let inst = Instance::new(vec![Point::new(1.0, 0.0)], vec![task], 1.0)?.with_teams(vec![2], &[], &[])?;
/// assert!(check_game(&inst, &Greedy, Plays::Counts).is_ok());
/// let err = check_game(&inst, &Greedy, Plays::Concave("its bids are prices")).unwrap_err();
/// assert!(err.to_string().starts_with("greedy does not play games with team thresholds: its bids are prices"));
/// # Ok::<(), afg_game::GameError>(())
/// ```
pub fn check_game(
    instance: &Instance,
    method: &dyn Allocator,
    plays: Plays,
) -> Result<(), AllocError> {
    let (rules, reason) = match plays {
        Plays::Concave(reason) if instance.has_skill_rules() => ("skill requirements", reason),
        Plays::Counts if instance.has_skill_rules() => (
            "skill requirements",
            "it values a coalition by its count of robots, not by the skills they hold",
        ),
        Plays::Concave(reason) if instance.has_teams() => ("team thresholds", reason),
        _ => return Ok(()),
    };
    Err(AllocError::TeamsNotSupported {
        method: method.name(),
        rules,
        reason,
    })
}

/// The other built-in methods that play games with `rules` ("skill requirements" or
/// "team thresholds"), for [`AllocError::TeamsNotSupported`]'s message.
fn team_players(rules: &str) -> &'static str {
    if rules == "skill requirements" {
        "`nearest`, `random`, `blind`, the auction over the radio and the staffing model \
         trained on skills (models/ours/staffing_skills)"
    } else {
        "`greedy`, the DA family, `nearest`, `random`, `blind`, the auction over the radio and \
         the staffing models"
    }
}

/// Runs `f` and measures its wall time.
fn timed<T>(f: impl FnOnce() -> T) -> (T, Duration) {
    let start = Instant::now();
    let out = f();
    (out, start.elapsed())
}
