//! Named families of team games: how a game departs from the paper's uniform draw
//! ([`Shape`]: clustered positions, heavy-tailed thresholds, rewards that grow with
//! the threshold, ε per task, skills on some tasks only), and the [`Family`] names a
//! table cites, each a whole configuration for any size and seed.

use std::fmt;
use std::str::FromStr;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::{
    CountRange, GOLDEN_RATIO, GameError, GeneratorConfig, GeneratorKnobs, Point, SkillDraw,
};

/// Robots and tasks drawn around `count` centres (uniform in the unit square), each
/// point at a normal offset of standard deviation `spread` from a centre chosen
/// uniformly, clamped to the square.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Clusters {
    /// Number of centres (at least 1).
    pub count: usize,
    /// Standard deviation of a point's offset from its centre (finite, positive).
    pub spread: f64,
}

/// How a game departs from the paper's uniform draw; the default departs in nothing
/// (and is left out of an instance file, so that every committed dataset reads as
/// before). Its draws come after all the others, except the clustered positions,
/// which replace the uniform ones.
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, Shape};
/// let mut cfg = GeneratorConfig::paper(40, 8, 1);
/// cfg.min_team = Some(afg_game::CountRange { min: 1, max: 10 });
/// cfg.shape = Shape { threshold_tail: Some(1.2), ..Shape::default() };
/// let inst = cfg.generate()?;
/// let small = inst.task_ids().filter(|&j| inst.min_team(j) <= 3).count();
/// assert!(small >= 4, "{small}"); // most tasks need few robots
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shape {
    /// The named family this configuration is, where it is one (for tables to cite).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub family: Option<Family>,
    /// Clustered positions; `None`: uniform.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clusters: Option<Clusters>,
    /// Heavy-tailed thresholds: `min · u^(−1/α)` for u uniform in (0, 1], cut at the
    /// range's max, with this α (a Pareto tail: most tasks need few robots, a few
    /// many); `None`: uniform in the range.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threshold_tail: Option<f64>,
    /// Each task's reward multiplied by its threshold over the range's mean: a team
    /// that needs more robots is worth more.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub reward_per_member: bool,
    /// Each task's ε uniform in `[eps_min, eps]` instead of `eps` for all.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps_min: Option<f64>,
    /// The share of tasks that require skills (each task draws whether it does); the
    /// others require none. `None`: every task.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skill_tasks: Option<f64>,
}

impl Shape {
    /// Whether this shape departs from the paper's draw in nothing.
    pub fn is_plain(&self) -> bool {
        *self == Shape::default()
    }

    /// Checks every knob's range.
    pub(crate) fn check(&self, eps: f64) -> Result<(), GameError> {
        let bad = |what: String| Err(GameError::InvalidGenerator(what));
        if let Some(c) = self.clusters
            && !(c.count >= 1 && c.spread.is_finite() && c.spread > 0.0)
        {
            return bad(format!(
                "clusters need at least 1 centre and a finite, positive spread (got {} and {})",
                c.count, c.spread
            ));
        }
        if let Some(alpha) = self.threshold_tail
            && !(alpha.is_finite() && alpha > 0.0)
        {
            return bad(format!(
                "the threshold tail α must be finite and positive (got {alpha})"
            ));
        }
        if let Some(lo) = self.eps_min
            && !(lo >= GOLDEN_RATIO && lo <= eps)
        {
            return bad(format!(
                "eps_min must lie between the golden ratio and eps {eps} (got {lo})"
            ));
        }
        if let Some(share) = self.skill_tasks
            && !(0.0..=1.0).contains(&share)
        {
            return bad(format!(
                "the share of tasks with skills must be between 0 and 1 (got {share})"
            ));
        }
        Ok(())
    }

    /// Where points are drawn: the clusters' centres, drawn now (none where positions
    /// are uniform: the paper's draws stay as they were).
    pub(crate) fn positions(&self, rng: &mut ChaCha8Rng) -> Positions {
        Positions {
            spread: self.clusters.map_or(0.0, |c| c.spread),
            centres: (0..self.clusters.map_or(0, |c| c.count))
                .map(|_| uniform_point(rng))
                .collect(),
        }
    }

    /// One threshold from `range`: uniform, or from the heavy tail.
    pub(crate) fn threshold(&self, rng: &mut ChaCha8Rng, range: CountRange) -> usize {
        match self.threshold_tail {
            None => rng.random_range(range.min..=range.max),
            Some(alpha) => {
                let u = 1.0 - rng.random::<f64>(); // in (0, 1]
                let k = range.min as f64 * u.powf(-1.0 / alpha);
                (k.floor() as usize).clamp(range.min, range.max)
            }
        }
    }
}

/// A point uniform in the unit square: x, then y.
fn uniform_point(rng: &mut ChaCha8Rng) -> Point {
    Point::new(rng.random(), rng.random())
}

/// Draws the points of one game: uniform, or around the clusters' centres.
pub(crate) struct Positions {
    centres: Vec<Point>,
    spread: f64,
}

impl Positions {
    /// One point.
    pub(crate) fn draw(&self, rng: &mut ChaCha8Rng) -> Point {
        if self.centres.is_empty() {
            return uniform_point(rng);
        }
        let centre = self.centres[rng.random_range(0..self.centres.len())];
        // Box–Muller: two uniforms, a normal offset in each direction
        let (u, v): (f64, f64) = (1.0 - rng.random::<f64>(), rng.random());
        let radius = self.spread * (-2.0 * u.ln()).sqrt();
        let angle = std::f64::consts::TAU * v;
        Point::new(
            (centre.x + radius * angle.cos()).clamp(0.0, 1.0),
            (centre.y + radius * angle.sin()).clamp(0.0, 1.0),
        )
    }
}

/// A named family of team games: a whole generator configuration for any size N × M
/// and seed, so that a table can say which games a claim holds on. `scarce` and
/// `skills` are the games every committed team benchmark and model was drawn from;
/// the others depart from them along one axis each, and `mixed` along all at once.
///
/// # Examples
/// ```
/// use afg_game::Family;
/// let cfg = Family::Clustered.config(60, 6, 3)?;
/// assert_eq!(cfg.shape.family, Some(Family::Clustered));
/// assert_eq!(cfg.generate()?, Family::Clustered.config(60, 6, 3)?.generate()?); // seeded
/// assert_eq!("heavy-tail".parse::<Family>()?, Family::HeavyTail);
/// assert_eq!(Family::ALL.len(), 10);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    /// Thresholds uniform in [N/M, 2N/M] (they add up to about 1.5 N: not every task
    /// can be staffed), the paper's positions and rewards.
    Scarce,
    /// `scarce` with 2 skills, each robot holding each with probability 0.5, each task
    /// requiring 1–2 of each.
    Skills,
    /// `scarce` with robots and tasks in 4 clusters (spread 0.05).
    Clustered,
    /// Heavy-tailed thresholds: from 1 up to N/4, most tasks needing 1–3 robots.
    HeavyTail,
    /// Every threshold the same, ⌈1.5 N/M⌉.
    Constant,
    /// `scarce` with rewards growing with the threshold and ε per task in [φ, 2N/M].
    TeamRewards,
    /// Heavy-tailed thresholds with 4 skills, each held by 30 % of robots, required
    /// 0–3 on about half of the tasks.
    SparseSkills,
    /// `scarce` with 6 skills, each held by 20 % of robots, each task requiring 0–1 of
    /// each.
    ManySkills,
    /// `scarce` in GRAPE's game (robots may stay out), capacities from ⌈N/M⌉ to
    /// ⌈1.5 N/M⌉, and β = 2.
    VoidCapacity,
    /// Every axis at once, varying by seed: clusters, heavy-tailed thresholds, rewards
    /// growing with them, ε per task, `sparse-skills`' skills, the void in a third of
    /// the games, β from 0.5 to 2.
    Mixed,
}

impl Family {
    /// Every family, the committed ones first.
    pub const ALL: [Family; 10] = [
        Family::Scarce,
        Family::Skills,
        Family::Clustered,
        Family::HeavyTail,
        Family::Constant,
        Family::TeamRewards,
        Family::SparseSkills,
        Family::ManySkills,
        Family::VoidCapacity,
        Family::Mixed,
    ];

    /// Whether the family's games carry skills.
    ///
    /// # Examples
    /// ```
    /// use afg_game::Family;
    /// for family in Family::ALL {
    ///     assert_eq!(family.draws_skills(), family.config(20, 4, 0)?.skills.is_some());
    /// }
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn draws_skills(self) -> bool {
        matches!(
            self,
            Family::Skills | Family::SparseSkills | Family::ManySkills | Family::Mixed
        )
    }

    /// The name tables and command lines use.
    pub fn name(self) -> &'static str {
        match self {
            Family::Scarce => "scarce",
            Family::Skills => "skills",
            Family::Clustered => "clustered",
            Family::HeavyTail => "heavy-tail",
            Family::Constant => "constant",
            Family::TeamRewards => "team-rewards",
            Family::SparseSkills => "sparse-skills",
            Family::ManySkills => "many-skills",
            Family::VoidCapacity => "void-capacity",
            Family::Mixed => "mixed",
        }
    }

    /// The configuration of this family at `robots` × `tasks` and `seed`.
    ///
    /// # Errors
    /// [`GameError::InvalidGenerator`] where the size has no robots or tasks.
    pub fn config(
        self,
        robots: usize,
        tasks: usize,
        seed: u64,
    ) -> Result<GeneratorConfig, GameError> {
        if robots == 0 || tasks == 0 {
            return Err(GameError::InvalidGenerator(format!(
                "a family needs robots and tasks (got {robots} × {tasks})"
            )));
        }
        let per_task = robots as f64 / tasks as f64;
        let scarce = CountRange {
            min: (robots / tasks).max(1),
            max: 2 * (robots / tasks).max(1),
        };
        let heavy = CountRange {
            min: 1,
            max: (robots / 4).max(1),
        };
        let skills = |count, share, lo, hi| SkillDraw {
            count,
            share,
            requires: CountRange { min: lo, max: hi },
        };
        let mut cfg = GeneratorConfig::paper(robots, tasks, seed);
        cfg.min_team = Some(scarce);
        match self {
            Family::Scarce => {}
            Family::Skills => {
                let (lo, hi) = GeneratorKnobs::REQUIRES;
                cfg.skills = Some(skills(2, GeneratorKnobs::SKILL_SHARE, lo, hi));
            }
            Family::Clustered => cfg.shape.clusters = Some(CLUSTERS),
            Family::HeavyTail => {
                cfg.min_team = Some(heavy);
                cfg.shape.threshold_tail = Some(TAIL);
            }
            Family::Constant => {
                let k = (1.5 * per_task).ceil() as usize;
                cfg.min_team = Some(CountRange { min: k, max: k });
            }
            Family::TeamRewards => {
                cfg.shape.reward_per_member = true;
                cfg.eps = (2.0 * per_task).max(2.0);
                cfg.shape.eps_min = Some(GOLDEN_RATIO);
            }
            Family::SparseSkills => {
                cfg.min_team = Some(heavy);
                cfg.shape.threshold_tail = Some(TAIL);
                cfg.skills = Some(skills(4, 0.3, 0, 3));
                cfg.shape.skill_tasks = Some(0.5);
            }
            Family::ManySkills => cfg.skills = Some(skills(6, 0.2, 0, 1)),
            Family::VoidCapacity => {
                cfg.allow_void = true;
                cfg.beta = 2.0;
                cfg = cfg.with_capacity_slack(1.5);
            }
            Family::Mixed => {
                // the per-game axes from the seed's own stream, apart from the draw
                let mut rng = ChaCha8Rng::seed_from_u64(seed ^ MIXED_STREAM);
                cfg.min_team = Some(heavy);
                cfg.skills = Some(skills(4, 0.3, 0, 3));
                cfg.allow_void = rng.random_bool(1.0 / 3.0);
                cfg.beta = rng.random_range(0.5..=2.0);
                cfg.eps = (2.0 * per_task).max(2.0);
                cfg.shape = Shape {
                    clusters: Some(CLUSTERS),
                    threshold_tail: Some(TAIL),
                    reward_per_member: true,
                    eps_min: Some(GOLDEN_RATIO),
                    skill_tasks: Some(0.5),
                    family: None,
                };
            }
        }
        cfg.shape.family = Some(self);
        Ok(cfg)
    }
}

/// The clustered families' clusters.
const CLUSTERS: Clusters = Clusters {
    count: 4,
    spread: 0.05,
};
/// The heavy-tailed families' α.
const TAIL: f64 = 1.2;
/// Mixes the seed of `mixed`'s per-game axes away from the draw's own stream.
const MIXED_STREAM: u64 = 0x6d69_7865_6400_0001;

impl fmt::Display for Family {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Family {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        Family::ALL
            .into_iter()
            .find(|family| family.name() == text)
            .ok_or_else(|| {
                let names: Vec<&str> = Family::ALL.iter().map(|f| f.name()).collect();
                format!("unknown family `{text}`: one of {}", names.join(", "))
            })
    }
}
