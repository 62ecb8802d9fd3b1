//! Seeded instance generator: the paper's distribution with the defaults of docs/decisions.md.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::{GameError, Instance, Point, Task};

/// Inclusive range from which each task's capacity is drawn uniformly.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CapacityRange {
    /// Smallest capacity.
    pub min: usize,
    /// Largest capacity.
    pub max: usize,
}

/// Every parameter of the generator, already resolved to numbers, so that an
/// instance file records exactly what produced it.
///
/// Draw order (part of the format: changing it changes every dataset): robot
/// positions `(x, y)` in index order, then per task its position, reward and,
/// if capacities are drawn, its capacity. All uniform, from one
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
    pub capacity: Option<CapacityRange>,
    /// GRAPE's game: robots may join the void task ([`Instance::with_void`]). Absent
    /// (false) in the paper's game, so the committed datasets read as before.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub allow_void: bool,
}

/// The generator's knobs as a user gives them (`afg gen`, `afg.generate`, the gym
/// environments): each `None` keeps the paper's default of [`GeneratorConfig::paper`].
/// [`GeneratorKnobs::config`] checks them the same way for every front end.
///
/// # Examples
/// ```
/// use afg_game::GeneratorKnobs;
/// let knobs = GeneratorKnobs { capacity_slack: Some(1.2), beta: Some(0.5), ..GeneratorKnobs::default() };
/// let cfg = knobs.config(20, 4, 7)?;
/// assert_eq!((cfg.beta, cfg.seed), (0.5, 7));
/// assert!(cfg.capacity.is_some());
/// let bad = GeneratorKnobs { capacity_slack: Some(0.5), ..GeneratorKnobs::default() };
/// assert_eq!(
///     bad.config(20, 4, 7).unwrap_err().to_string(),
///     "invalid generator parameter: capacity slack must be at least 1 (got 0.5)"
/// );
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GeneratorKnobs {
    /// Capacities drawn from `ceil(N/M) ..= ceil(slack · N/M)` (slack ≥ 1); `None`: no
    /// capacities.
    pub capacity_slack: Option<f64>,
    /// The base eps of every task's log (default `max(2, N/M)`).
    pub eps: Option<f64>,
    /// The distance penalty β (default 1).
    pub beta: Option<f64>,
    /// Initial rewards uniform in `[lo, hi]` (default `[N/M, 2N/M]`).
    pub rewards: Option<(f64, f64)>,
    /// Draw instances of GRAPE's game, where robots may join the void task.
    pub allow_void: bool,
}

impl GeneratorKnobs {
    /// The configuration of `robots`, `tasks` and `seed` with these knobs.
    ///
    /// # Errors
    /// [`GameError::InvalidGenerator`] for a capacity slack below 1 or not finite; the
    /// other knobs are checked when the instance is drawn ([`GeneratorConfig::generate`]).
    pub fn config(
        &self,
        robots: usize,
        tasks: usize,
        seed: u64,
    ) -> Result<GeneratorConfig, GameError> {
        let mut cfg = GeneratorConfig::paper(robots, tasks, seed);
        cfg.allow_void = self.allow_void;
        if let Some(eps) = self.eps {
            cfg.eps = eps;
        }
        if let Some(beta) = self.beta {
            cfg.beta = beta;
        }
        if let Some((lo, hi)) = self.rewards {
            (cfg.reward_min, cfg.reward_max) = (lo, hi);
        }
        if let Some(slack) = self.capacity_slack {
            if !(slack.is_finite() && slack >= 1.0) {
                return Err(GameError::InvalidGenerator(format!(
                    "capacity slack must be at least 1 (got {slack})"
                )));
            }
            cfg = cfg.with_capacity_slack(slack);
        }
        Ok(cfg)
    }
}

impl GeneratorConfig {
    /// The paper's number of tasks in every experiment, M = 5.
    pub const PAPER_TASKS: usize = 5;

    /// The paper's setting: positions uniform in the unit square, rewards uniform in
    /// `[N/M, 2N/M]`, beta = 1; our defaults `eps = max(2, N/M)` and no capacities.
    pub fn paper(robots: usize, tasks: usize, seed: u64) -> Self {
        let per_task = robots as f64 / tasks.max(1) as f64;
        GeneratorConfig {
            robots,
            tasks,
            seed,
            reward_min: per_task,
            reward_max: 2.0 * per_task,
            eps: per_task.max(2.0),
            beta: 1.0,
            capacity: None,
            allow_void: false,
        }
    }

    /// Adds capacities drawn uniformly from `ceil(N/M) ..= ceil(slack * N/M)`; their
    /// total is then at least N. `slack` must be at least 1.
    pub fn with_capacity_slack(mut self, slack: f64) -> Self {
        let per_task = self.robots as f64 / self.tasks.max(1) as f64;
        let min = per_task.ceil() as usize;
        let max = (slack * per_task).ceil().max(min as f64) as usize;
        self.capacity = Some(CapacityRange { min, max });
        self
    }

    /// Draws the instance.
    ///
    /// # Errors
    /// [`GameError::InvalidGenerator`] for a reward range that is not finite and
    /// ordered or an empty capacity range, and any error of [`Instance::new`]
    /// (N = 0, M = 0, eps < φ, capacities below N, ...).
    pub fn generate(&self) -> Result<Instance, GameError> {
        if !(self.reward_min.is_finite()
            && self.reward_max.is_finite()
            && self.reward_min <= self.reward_max)
        {
            return Err(GameError::InvalidGenerator(format!(
                "reward range [{}, {}] must be finite and ordered",
                self.reward_min, self.reward_max
            )));
        }
        if let Some(c) = self.capacity
            && c.min > c.max
        {
            return Err(GameError::InvalidGenerator(format!(
                "capacity range {}..={} is empty",
                c.min, c.max
            )));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let point = |rng: &mut ChaCha8Rng| Point::new(rng.random::<f64>(), rng.random::<f64>());
        let robots: Vec<Point> = (0..self.robots).map(|_| point(&mut rng)).collect();
        let tasks = (0..self.tasks)
            .map(|_| {
                let position = point(&mut rng);
                let reward =
                    self.reward_min + (self.reward_max - self.reward_min) * rng.random::<f64>();
                let capacity = self.capacity.map(|c| rng.random_range(c.min..=c.max));
                Task {
                    position,
                    reward,
                    eps: self.eps,
                    capacity,
                }
            })
            .collect();
        let instance = if self.allow_void {
            Instance::with_void(robots, tasks, self.beta)?
        } else {
            Instance::new(robots, tasks, self.beta)?
        };
        Ok(instance.with_generator(self.clone()))
    }
}
