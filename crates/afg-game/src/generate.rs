//! Seeded instance generator: the paper's distribution with the defaults of docs/decisions.md.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{
    CountRange, Family, GameError, GeneratorConfig, Instance, Point, Shape, SkillDraw, Task,
};

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
    /// Thresholds uniform in `[lo, hi]` (default: none, every threshold 1).
    pub min_team: Option<(usize, usize)>,
    /// S, the number of skills (default 0: no skill rule).
    pub skills: Option<usize>,
    /// The probability that a robot holds a skill (default 0.5).
    pub skill_share: Option<f64>,
    /// Each task requires each skill in an amount uniform in `[lo, hi]` (default 1, 2).
    pub requires: Option<(usize, usize)>,
    /// A named family to start from instead of the paper's game ([`Family::config`]);
    /// the knobs given beside it override its values.
    pub family: Option<Family>,
}

impl GeneratorKnobs {
    /// The default share of robots holding a skill.
    pub const SKILL_SHARE: f64 = 0.5;
    /// The default range of a task's requirement of a skill.
    pub const REQUIRES: (usize, usize) = (1, 2);
    /// The most skills the generator draws: every robot and task carries one amount
    /// per skill, so S multiplies the file and the memory of every game.
    pub const MAX_SKILLS: usize = 64;
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
        let mut cfg = match self.family {
            Some(family) => family.config(robots, tasks, seed)?,
            None => GeneratorConfig::paper(robots, tasks, seed),
        };
        cfg.allow_void |= self.allow_void;
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
        if let Some((min, max)) = self.min_team {
            if min == 0 {
                return Err(GameError::InvalidGenerator(
                    "thresholds (min_team) must be at least 1".into(),
                ));
            }
            cfg.min_team = Some(CountRange { min, max }.check("threshold (min_team)")?);
        }
        if let Some(draw) = self.skill_draw()? {
            cfg.skills = Some(draw);
        }
        Ok(cfg)
    }

    /// The skills these knobs draw (`None`: no skill rule), their defaults filled in.
    ///
    /// # Errors
    /// [`GameError::InvalidGenerator`] for more than [`GeneratorKnobs::MAX_SKILLS`]
    /// skills, a share outside [0, 1], an empty requirement range, or a share or
    /// requirements without skills.
    ///
    /// # Examples
    /// ```
    /// use afg_game::GeneratorKnobs;
    /// let knobs = GeneratorKnobs { skills: Some(2), ..GeneratorKnobs::default() };
    /// let draw = knobs.skill_draw()?.expect("two skills");
    /// assert_eq!((draw.count, draw.share), (2, GeneratorKnobs::SKILL_SHARE));
    /// let alone = GeneratorKnobs { skill_share: Some(0.2), ..GeneratorKnobs::default() };
    /// assert!(alone.skill_draw().is_err());
    /// let many = GeneratorKnobs { skills: Some(1_000_000), ..GeneratorKnobs::default() };
    /// assert!(many.skill_draw().unwrap_err().to_string().contains("at most 64 skills"));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn skill_draw(&self) -> Result<Option<SkillDraw>, GameError> {
        match self.skills {
            Some(count) if count > Self::MAX_SKILLS => Err(GameError::InvalidGenerator(format!(
                "at most {} skills (got {count}): every robot and task carries one amount per skill, {count} in each of N + M rows",
                Self::MAX_SKILLS
            ))),
            Some(count) if count > 0 => {
                let share = self.skill_share.unwrap_or(Self::SKILL_SHARE);
                if !(0.0..=1.0).contains(&share) {
                    return Err(GameError::InvalidGenerator(format!(
                        "skill share must be between 0 and 1 (got {share})"
                    )));
                }
                let (min, max) = self.requires.unwrap_or(Self::REQUIRES);
                let requires = CountRange { min, max }.check("requires")?;
                Ok(Some(SkillDraw {
                    count,
                    share,
                    requires,
                }))
            }
            _ if self.skill_share.is_some() || self.requires.is_some() => {
                Err(GameError::InvalidGenerator(
                    "a skill share or requirements need skills (a number of skills S ≥ 1)".into(),
                ))
            }
            _ => Ok(None),
        }
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
            min_team: None,
            skills: None,
            allow_void: false,
            shape: Shape::default(),
        }
    }

    /// Adds capacities drawn uniformly from `ceil(N/M) ..= ceil(slack * N/M)`; their
    /// total is then at least N. `slack` must be at least 1.
    pub fn with_capacity_slack(mut self, slack: f64) -> Self {
        let per_task = self.robots as f64 / self.tasks.max(1) as f64;
        let min = per_task.ceil() as usize;
        let max = (slack * per_task).ceil().max(min as f64) as usize;
        self.capacity = Some(CountRange { min, max });
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
        for (range, what) in [
            (self.capacity, "capacity"),
            (self.min_team, "threshold (min_team)"),
        ] {
            if let Some(range) = range {
                range.check(what)?;
            }
        }
        if let Some(draw) = self.skills {
            draw.requires.check("requires")?;
            if !(0.0..=1.0).contains(&draw.share) {
                return Err(GameError::InvalidGenerator(format!(
                    "skill share must be between 0 and 1 (got {})",
                    draw.share
                )));
            }
        }
        self.shape.check(self.eps)?;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let positions = self.shape.positions(&mut rng);
        let robots: Vec<Point> = (0..self.robots).map(|_| positions.draw(&mut rng)).collect();
        let mut tasks: Vec<Task> = (0..self.tasks)
            .map(|_| {
                let position = positions.draw(&mut rng);
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
        let mut teams = self.draw_teams(&mut rng);
        self.draw_shape(&mut rng, &mut tasks, teams.as_mut());
        let instance = if self.allow_void {
            Instance::with_void(robots, tasks, self.beta)?
        } else {
            Instance::new(robots, tasks, self.beta)?
        };
        let instance = match teams {
            Some(Teams {
                min_team,
                skills,
                requires,
            }) => instance.with_teams(min_team, &skills, &requires)?,
            None => instance,
        };
        Ok(instance.with_generator(self.clone()))
    }
}

/// The team rules of one draw: each task's threshold (empty: all 1), each robot's
/// skills and each task's requirements (empty: none).
struct Teams {
    min_team: Vec<usize>,
    skills: Vec<Vec<u32>>,
    requires: Vec<Vec<u32>>,
}

impl GeneratorConfig {
    /// Draws the thresholds and skills (after everything else: the paper's game keeps
    /// its draws); `None` in the paper's game.
    fn draw_teams(&self, rng: &mut ChaCha8Rng) -> Option<Teams> {
        if self.min_team.is_none() && self.skills.is_none() {
            return None;
        }
        let min_team = match self.min_team {
            Some(range) => (0..self.tasks)
                .map(|_| self.shape.threshold(rng, range))
                .collect(),
            None => Vec::new(),
        };
        let (skills, requires) = match self.skills {
            Some(draw) => {
                let skills: Vec<Vec<u32>> = (0..self.robots)
                    .map(|_| {
                        (0..draw.count)
                            .map(|_| u32::from(rng.random_bool(draw.share)))
                            .collect()
                    })
                    .collect();
                let (lo, hi) = (draw.requires.min, draw.requires.max);
                let requires: Vec<Vec<u32>> = (0..self.tasks)
                    .map(|_| {
                        (0..draw.count)
                            .map(|_| u32::try_from(rng.random_range(lo..=hi)).unwrap_or(u32::MAX))
                            .collect()
                    })
                    .collect();
                (skills, requires)
            }
            None => (Vec::new(), Vec::new()),
        };
        Some(Teams {
            min_team,
            skills,
            requires,
        })
    }

    /// The shape's own draws, last: which tasks keep their skill requirements, then
    /// each task's ε; and the rewards scaled by the thresholds.
    fn draw_shape(&self, rng: &mut ChaCha8Rng, tasks: &mut [Task], teams: Option<&mut Teams>) {
        let shape = &self.shape;
        if let Some(teams) = teams {
            if let Some(share) = shape.skill_tasks {
                for requires in &mut teams.requires {
                    if !rng.random_bool(share) {
                        requires.fill(0);
                    }
                }
            }
            if let (true, Some(range)) = (shape.reward_per_member, self.min_team) {
                let mean = (range.min + range.max) as f64 / 2.0;
                for (task, &k) in tasks.iter_mut().zip(&teams.min_team) {
                    task.reward *= k as f64 / mean;
                }
            }
        }
        if let Some(lo) = shape.eps_min {
            for task in tasks.iter_mut() {
                task.eps = rng.random_range(lo..=self.eps);
            }
        }
    }
}

/// A game's size, N robots and M tasks, written `NxM` (`100x10`) on command lines.
///
/// # Examples
/// ```
/// use afg_game::GameSize;
/// let size: GameSize = "300x20".parse()?;
/// assert_eq!((size.robots, size.tasks), (300, 20));
/// assert_eq!(size.to_string(), "300x20");
/// assert!("300".parse::<GameSize>().is_err() && "0x5".parse::<GameSize>().is_err());
/// # Ok::<(), String>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GameSize {
    /// Robots N.
    pub robots: usize,
    /// Tasks M.
    pub tasks: usize,
}

impl GameSize {
    /// The thresholds of a scarce team game of this size, uniform in [N/M, 2N/M]: they
    /// add up to about 1.5 N, so not every task can be staffed (the team games'
    /// benchmarks and the staffing model's training games).
    ///
    /// # Examples
    /// ```
    /// let size = afg_game::GameSize { robots: 100, tasks: 10 };
    /// assert_eq!(size.scarce_thresholds(), (10, 20));
    /// ```
    pub fn scarce_thresholds(self) -> (usize, usize) {
        let per_task = (self.robots / self.tasks).max(1);
        (per_task, 2 * per_task)
    }
}

impl std::str::FromStr for GameSize {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (n, m) = text
            .split_once('x')
            .ok_or_else(|| format!("`{text}`: write a size as NxM, e.g. 1000x5"))?;
        let count = |s: &str| match s.parse::<usize>() {
            Ok(0) => Err(format!("`{text}`: must be at least 1")),
            Ok(k) => Ok(k),
            Err(e) => Err(format!("`{text}`: {e}")),
        };
        Ok(GameSize {
            robots: count(n)?,
            tasks: count(m)?,
        })
    }
}

impl std::fmt::Display for GameSize {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.robots, self.tasks)
    }
}
