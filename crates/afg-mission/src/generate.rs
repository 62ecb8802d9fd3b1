//! Missions drawn from presets: the robots and tasks of the paper's distribution
//! (unit square, rewards N/K to 2N/K, eps = max(2, N/K), β = 1), with workloads,
//! arrival times and failures.

use afg_game::{CountRange, GeneratorConfig, GeneratorKnobs, Point, SkillDraw};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{Failure, Mission, MissionConfig, MissionError, Preset, RobotSpec, TaskSpec};

/// The knobs of a drawn mission besides its preset, size and seed, as every front end
/// spells them (`afg mission gen`, `afg.Mission.generate`), with the one set of
/// defaults: workloads 1–3, speed 1, a unit arena, horizon 40, 4 waves every 5 time
/// units, a Poisson rate of K / 20, 30 % of the robots failing (the instances' twin is
/// [`afg_game::GeneratorKnobs`]).
///
/// # Examples
/// ```
/// use afg_mission::{MissionConfig, MissionKnobs, Preset};
/// let knobs = MissionKnobs { horizon: 60.0, ..MissionKnobs::default() };
/// let config = knobs.config(Preset::Poisson, 40, 10, 1);
/// assert_eq!((config.horizon, config.rate), (60.0, 0.5));
/// assert_eq!(MissionKnobs::default().config(Preset::Waves, 5, 2, 0), MissionConfig::new(Preset::Waves, 5, 2, 0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MissionKnobs {
    /// Workloads are uniform in `[lo, hi]` (one robot does 1 unit per time unit).
    pub workload: (f64, f64),
    /// Every robot's speed (arena units per time unit).
    pub speed: f64,
    /// The arena's side: positions uniform in `[0, arena]²`.
    pub arena: f64,
    /// The mission ends at this time at the latest.
    pub horizon: f64,
    /// Waves of tasks (waves, attrition).
    pub waves: usize,
    /// Time between waves.
    pub interval: f64,
    /// Task arrivals per time unit (poisson; `None`: K / 20).
    pub rate: Option<f64>,
    /// Share of the robots that fail (attrition), at times uniform over the whole
    /// horizon: a run that ends earlier (every task done) sees only the failures before
    /// its end.
    pub fail_share: f64,
    /// Task capacities as the instance generator's `capacity_slack` draws them (≥ 1).
    pub capacity_slack: Option<f64>,
    /// Robots may idle (the void task) when no task is worth their trip.
    pub allow_void: bool,
    /// Task thresholds uniform in `[lo, hi]` (`None`: 1).
    pub min_team: Option<(usize, usize)>,
    /// S skills (`None`: no skills), each robot holding each with probability
    /// `skill_share` (default [`GeneratorKnobs::SKILL_SHARE`]), each task requiring
    /// each in an amount uniform in `requires` (default [`GeneratorKnobs::REQUIRES`]).
    pub skills: Option<usize>,
    /// See `skills`.
    pub skill_share: Option<f64>,
    /// See `skills`.
    pub requires: Option<(usize, usize)>,
}

impl Default for MissionKnobs {
    fn default() -> Self {
        MissionKnobs {
            workload: (1.0, 3.0),
            speed: 1.0,
            arena: 1.0,
            horizon: 40.0,
            waves: 4,
            interval: 5.0,
            rate: None,
            fail_share: 0.3,
            capacity_slack: None,
            allow_void: false,
            min_team: None,
            skills: None,
            skill_share: None,
            requires: None,
        }
    }
}

impl MissionKnobs {
    /// The configuration of a mission of `preset` with `robots`, `tasks` and `seed`
    /// under these knobs (checked when drawn, [`MissionConfig::generate`]).
    pub fn config(&self, preset: Preset, robots: usize, tasks: usize, seed: u64) -> MissionConfig {
        MissionConfig {
            preset,
            robots,
            tasks,
            seed,
            workload_min: self.workload.0,
            workload_max: self.workload.1,
            speed: self.speed,
            arena: self.arena,
            horizon: self.horizon,
            waves: self.waves,
            interval: self.interval,
            rate: self.rate.unwrap_or(tasks as f64 / 20.0),
            fail_share: self.fail_share,
            allow_void: self.allow_void,
            capacity_slack: self.capacity_slack,
            min_team: self.min_team.map(|(min, max)| CountRange { min, max }),
            // A share or requirements without skills stay, as S = 0, for the check.
            skills: (self.skills.is_some_and(|s| s > 0)
                || self.skill_share.is_some()
                || self.requires.is_some())
            .then(|| SkillDraw {
                count: self.skills.unwrap_or(0),
                share: self.skill_share.unwrap_or(GeneratorKnobs::SKILL_SHARE),
                requires: {
                    let (min, max) = self.requires.unwrap_or(GeneratorKnobs::REQUIRES);
                    CountRange { min, max }
                },
            }),
        }
    }
}

impl MissionConfig {
    /// The defaults of [`MissionKnobs::default`].
    pub fn new(preset: Preset, robots: usize, tasks: usize, seed: u64) -> Self {
        MissionKnobs::default().config(preset, robots, tasks, seed)
    }

    /// Draws the mission.
    ///
    /// # Errors
    /// [`MissionError::Invalid`] for knobs out of range (no robots or tasks, workloads,
    /// speed, arena, horizon, interval or rate not finite and positive, a share outside
    /// `[0, 1]`, no waves), or a mission that fails [`Mission::check`] (a wave after
    /// the horizon).
    ///
    /// # Examples
    /// ```
    /// use afg_mission::{MissionConfig, Preset};
    /// let a = MissionConfig::new(Preset::Poisson, 30, 10, 7).generate()?;
    /// assert_eq!(a, MissionConfig::new(Preset::Poisson, 30, 10, 7).generate()?);
    /// assert_ne!(a, MissionConfig::new(Preset::Poisson, 30, 10, 8).generate()?);
    /// # Ok::<(), afg_mission::MissionError>(())
    /// ```
    pub fn generate(&self) -> Result<Mission, MissionError> {
        self.check()?;
        let mut paper = GeneratorConfig::paper(self.robots, self.tasks, self.seed);
        if let Some(slack) = self.capacity_slack {
            paper = paper.with_capacity_slack(slack);
        }
        paper.min_team = self.min_team;
        paper.skills = self.skills;
        let game = paper.generate()?;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ 0x6d69_7373_696f_6e00);
        let scale = |p: Point| Point::new(self.arena * p.x, self.arena * p.y);
        let robots = game
            .robot_ids()
            .map(|i| RobotSpec {
                position: scale(game.robots()[i.index()]),
                speed: self.speed,
                skills: game.skills(i).to_vec(),
            })
            .collect();
        let appears = self.arrival_times(&mut rng);
        let tasks = game
            .task_ids()
            .zip(appears)
            .map(|(j, appears)| {
                let t = game.task(j);
                TaskSpec {
                    position: scale(t.position),
                    reward: t.reward,
                    eps: t.eps,
                    capacity: t.capacity,
                    workload: rng.random_range(self.workload_min..=self.workload_max),
                    appears,
                    min_team: game.min_team(j),
                    requires: game.requires(j).to_vec(),
                }
            })
            .collect();
        let failures = if self.preset == Preset::Attrition {
            let count = (self.fail_share * self.robots as f64).round() as usize;
            let mut order: Vec<usize> = (0..self.robots).collect();
            for k in 0..count {
                let pick = rng.random_range(k..self.robots);
                order.swap(k, pick);
            }
            let mut failures: Vec<Failure> = order[..count]
                .iter()
                .map(|&robot| Failure {
                    robot,
                    time: rng.random_range(0.0..self.horizon),
                    returns: None,
                })
                .collect();
            failures.sort_by(|a, b| a.time.total_cmp(&b.time).then(a.robot.cmp(&b.robot)));
            failures
        } else {
            Vec::new()
        };
        let beta = game.beta() / self.arena;
        let mission = Mission::new(beta, self.allow_void, self.horizon, robots, tasks, failures)?;
        Ok(mission.with_generator(self.clone()))
    }

    /// The K arrival times of the preset, in task order.
    fn arrival_times(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        let k = self.tasks;
        match self.preset {
            Preset::Static => vec![0.0; k],
            Preset::Waves | Preset::Attrition => (0..k)
                .map(|j| (j * self.waves / k) as f64 * self.interval)
                .collect(),
            Preset::Poisson => {
                let mut t = 0.0;
                (0..k)
                    .map(|j| {
                        if j > 0 {
                            let u: f64 = rng.random_range(f64::EPSILON..1.0);
                            t += -u.ln() / self.rate;
                        }
                        // Arrivals past the horizon are folded back into it.
                        t.min(self.horizon * (1.0 - 1e-9))
                    })
                    .collect()
            }
        }
    }

    fn check(&self) -> Result<(), MissionError> {
        let bad = |what: &str| Err(MissionError::Invalid(what.into()));
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if self.robots == 0 || self.tasks == 0 {
            return bad("a mission needs at least one robot and one task");
        }
        if !(positive(self.workload_min) && self.workload_max >= self.workload_min) {
            return bad("workloads must be finite, positive, and min ≤ max");
        }
        if !self.workload_max.is_finite() {
            return bad("the largest workload must be finite");
        }
        if !(positive(self.speed) && positive(self.arena) && positive(self.horizon)) {
            return bad("speed, arena and horizon must be finite and positive");
        }
        if !(positive(self.interval) && positive(self.rate)) || self.waves == 0 {
            return bad("the interval and rate must be finite and positive, waves at least 1");
        }
        if self
            .capacity_slack
            .is_some_and(|s| !(s.is_finite() && s >= 1.0))
        {
            return bad("the capacity slack must be at least 1");
        }
        if !(0.0..=1.0).contains(&self.fail_share) {
            return bad("the share of robots that fail must be in [0, 1]");
        }
        if self.min_team.is_some_and(|r| r.min == 0) {
            return bad("thresholds (min_team) must be at least 1");
        }
        if self.skills.is_some_and(|d| d.count == 0) {
            return bad("a skill share or requirements need skills (a number of skills S ≥ 1)");
        }
        Ok(())
    }
}
