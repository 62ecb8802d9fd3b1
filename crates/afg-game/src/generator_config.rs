//! The generator's configuration: every parameter of a draw, resolved to numbers, so
//! that an instance file records exactly what produced it (the drawing itself is in
//! `generate.rs`; an `Instance` keeps the configuration that drew it).

use serde::{Deserialize, Serialize};

use crate::{GameError, Shape};

/// Inclusive range of whole numbers from which each task's capacity (or threshold) is
/// drawn uniformly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CountRange {
    /// Smallest value.
    pub min: usize,
    /// Largest value.
    pub max: usize,
}

impl CountRange {
    pub(crate) fn check(self, what: &str) -> Result<Self, GameError> {
        if self.min > self.max {
            return Err(GameError::InvalidGenerator(format!(
                "{what} range {}..={} is empty",
                self.min, self.max
            )));
        }
        Ok(self)
    }
}

/// How the generator draws skills: S skills, each robot holding each one with
/// probability `share` (a binary skill matrix), each task requiring each skill in an
/// amount uniform in `requires`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkillDraw {
    /// S, the number of skills.
    pub count: usize,
    /// The probability that a robot holds a skill.
    pub share: f64,
    /// The amount of each skill a task requires.
    pub requires: CountRange,
}

/// Every parameter of the generator, already resolved to numbers, so that an
/// instance file records exactly what produced it.
///
/// Draw order (part of the format: changing it changes every dataset): robot
/// positions `(x, y)` in index order, then per task its position, reward and,
/// if capacities are drawn, its capacity; then, in the team games, every task's
/// threshold, every robot's skills (robot by robot, skill by skill) and every task's
/// requirements. All uniform (skills: each held with probability `share`), from one
/// `ChaCha8Rng::seed_from_u64(seed)`.
///
/// # Examples
/// ```
/// use afg_game::GeneratorConfig;
/// let cfg = GeneratorConfig::paper(20, 5, 7);
/// assert_eq!(cfg.eps, 4.0); // max(2, N/M)
/// assert_eq!((cfg.reward_min, cfg.reward_max), (4.0, 8.0)); // [N/M, 2N/M]
/// let inst = cfg.generate()?;
/// assert_eq!(inst.num_robots(), 20);
/// assert_eq!(inst, cfg.generate()?); // same seed, same instance
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeneratorConfig {
    /// Number of robots N.
    pub robots: usize,
    /// Number of tasks M.
    pub tasks: usize,
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
    /// Lower end of the uniform initial reward.
    pub reward_min: f64,
    /// Upper end of the uniform initial reward.
    pub reward_max: f64,
    /// eps_j, the same for every task.
    pub eps: f64,
    /// Distance penalty beta.
    pub beta: f64,
    /// Capacity range; `None` for unbounded tasks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capacity: Option<CountRange>,
    /// Thresholds (`min_team`) range; `None`: every threshold 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_team: Option<CountRange>,
    /// Skills; `None`: no skill rule.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skills: Option<SkillDraw>,
    /// GRAPE's game: robots may join the void task ([`crate::Instance::with_void`]). Absent
    /// (false) in the paper's game, so the committed datasets read as before.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub allow_void: bool,
    /// How the draw departs from the paper's uniform one (clusters, heavy tails, ε per
    /// task, …) and the named family it is; absent where it does not.
    #[serde(default, skip_serializing_if = "Shape::is_plain")]
    pub shape: Shape,
}
