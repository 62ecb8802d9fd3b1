//! Seeded instances of the two families of the field's test sets.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::{Metric, Robot, Rules, ScheduleError, ScheduleInstance, Task};

/// The most robots, and the most tasks, the generator draws.
pub const MAX_SIZE: usize = 10_000;

/// A family of instances.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    /// DCMRTA's: every robot at one depot, tasks needing 1–5 robots (`min_team`).
    Dcmrta,
    /// HeteroMRTA's: 5 species, each with one skill and its own depot; tasks require 1–5
    /// distinct skills (one unit each); robots skip tasks already staffed.
    Heteromrta,
}

impl Family {
    /// The family's name as typed on a command line.
    pub fn name(self) -> &'static str {
        match self {
            Family::Dcmrta => "dcmrta",
            Family::Heteromrta => "heteromrta",
        }
    }

    /// Parses a family's name.
    pub fn from_name(name: &str) -> Result<Self, ScheduleError> {
        match name {
            "dcmrta" => Ok(Family::Dcmrta),
            "heteromrta" => Ok(Family::Heteromrta),
            other => Err(ScheduleError::Setting(format!(
                "unknown family {other:?}: dcmrta or heteromrta"
            ))),
        }
    }
}

/// What to draw: the family, the size and the seed.
///
/// Both families: tasks uniform in the unit square, durations uniform in (0, 5), speed
/// 0.2, robots back at their depot at the end, `max_wait` 10 (the rule DCMRTA's learned
/// policies were tested under).
///
/// # Examples
/// ```
/// use afg_schedule::{Family, Generate};
/// let inst = Generate { family: Family::Heteromrta, robots: 15, tasks: 40, seed: 7 }.instance()?;
/// assert_eq!((inst.num_robots(), inst.num_tasks(), inst.num_skills()), (15, 40, 5));
/// assert_eq!(inst, Generate { family: Family::Heteromrta, robots: 15, tasks: 40, seed: 7 }.instance()?);
/// # Ok::<(), afg_schedule::ScheduleError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Generate {
    /// The family.
    pub family: Family,
    /// Number of robots (HeteroMRTA: spread over min(5, robots) species, in turn).
    pub robots: usize,
    /// Number of tasks.
    pub tasks: usize,
    /// The seed (ChaCha8).
    pub seed: u64,
}

impl Generate {
    /// One task: uniform in the unit square, a duration in (0, 5), and its team's needs.
    fn task(&self, rng: &mut ChaCha8Rng, species: usize) -> Task {
        let (x, y) = (rng.random::<f64>(), rng.random::<f64>());
        let duration = 5.0 * rng.random::<f64>();
        let (min_team, requires) = match self.family {
            Family::Dcmrta => (
                Some(rng.random_range(1..=5u32.min(self.robots as u32))),
                None,
            ),
            Family::Heteromrta => {
                let count = rng.random_range(1..=species);
                let mut skills: Vec<usize> = (0..species).collect();
                for k in 0..count {
                    skills.swap(k, rng.random_range(k..species));
                }
                let mut requires = vec![0; species];
                for &s in &skills[..count] {
                    requires[s] = 1;
                }
                (None, Some(requires))
            }
        };
        Task {
            x,
            y,
            min_team,
            requires,
            duration,
        }
    }

    /// Draws the instance.
    pub fn instance(&self) -> Result<ScheduleInstance, ScheduleError> {
        if self.robots == 0 || self.tasks == 0 || self.robots > MAX_SIZE || self.tasks > MAX_SIZE {
            return Err(ScheduleError::Setting(format!(
                "{} robots and {} tasks: each must be 1 to {}",
                self.robots, self.tasks, MAX_SIZE
            )));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let point = |rng: &mut ChaCha8Rng| [rng.random::<f64>(), rng.random::<f64>()];
        let species = match self.family {
            Family::Dcmrta => 1,
            Family::Heteromrta => self.robots.min(5),
        };
        let depots: Vec<[f64; 2]> = (0..species).map(|_| point(&mut rng)).collect();
        let robots = (0..self.robots)
            .map(|i| {
                let s = i % species;
                let skills = (self.family == Family::Heteromrta)
                    .then(|| (0..species).map(|k| u32::from(k == s)).collect());
                let species = (self.family == Family::Heteromrta).then_some(s);
                Robot {
                    x: depots[s][0],
                    y: depots[s][1],
                    depot: s,
                    skills,
                    species,
                }
            })
            .collect();
        let tasks = (0..self.tasks)
            .map(|_| self.task(&mut rng, species))
            .collect();
        let inst = ScheduleInstance {
            source: Some(format!(
                "afg schedule gen --family {} --robots {} --tasks {} --seed {}",
                self.family.name(),
                self.robots,
                self.tasks,
                self.seed
            )),
            licence: None,
            set: None,
            rules: match self.family {
                Family::Dcmrta => Rules::Dcmrta,
                Family::Heteromrta => Rules::Heteromrta,
            },
            index: None,
            speed: 0.2,
            metric: Metric::Euclidean,
            max_wait: 10.0,
            max_wait_rl_test: None,
            max_wait_pickled: None,
            horizon: None,
            return_to_depot: true,
            skills: (self.family == Family::Heteromrta).then_some(species),
            depots,
            robots,
            tasks,
        };
        inst.validate()?;
        Ok(inst)
    }
}
