//! A mission as a multi-agent environment: at every decision epoch each living robot
//! picks a task from what it sees and hears (the PettingZoo `mission_v0` underneath).

use std::borrow::Cow;

use serde::{Deserialize, Serialize};

use super::{RunOptions, Sim};
use crate::{Mission, MissionError, MissionRun};

/// What each robot perceives in a [`MissionEnv`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Perception {
    /// A robot sees the open tasks within this distance, and remembers them (`None`:
    /// every robot knows every open task).
    pub sensing: Option<f64>,
    /// A robot hears the robots within this distance: what they know of tasks (passed
    /// on one hop per epoch) and where they are heading.
    pub comm_radius: f64,
    /// Also an epoch every this many time units, not only at events.
    pub decide_every: Option<f64>,
    /// Observe teams too: each robot's own skills, and per task its threshold, its
    /// team's progress and the skills it still lacks ([`TEAM_FEATURES`]); tasks no
    /// team of the living robots can staff are masked.
    #[serde(default)]
    pub teams: bool,
}

impl Default for Perception {
    /// Every open task known, neighbours within 0.25, epochs at events only.
    fn default() -> Self {
        Perception {
            sensing: None,
            comm_radius: 0.25,
            decide_every: None,
            teams: false,
        }
    }
}

/// What one step of a [`MissionEnv`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvStep {
    /// The team reward: `Σ r_j` times the work done on each task since the last epoch
    /// (an episode's rewards add up to the value of all the work done).
    pub reward: f64,
    /// Robots that failed since the last epoch (they leave the episode).
    pub failed: Vec<usize>,
    /// Every task is done.
    pub terminated: bool,
    /// The horizon was reached with tasks left.
    pub truncated: bool,
}

/// Features of a robot about itself: x, y, and one-hot idle / travelling / working.
pub const ROBOT_FEATURES: usize = 5;
/// Features of a robot about each task: known and open, dx, dy, distance, reward over
/// the mission's largest, eps, share of the work left, share of the robot's neighbours
/// heading there, and whether it is the robot's own task (all 0 for a task the robot
/// does not know is open).
pub const TASK_FEATURES: usize = 9;
/// With [`Perception::teams`], a robot's own skills (S amounts) follow
/// [`ROBOT_FEATURES`], and each task's [`TASK_FEATURES`] are followed by these four and
/// S more: its threshold over N, the robots present over the threshold, the robots
/// heading there or present over the threshold, whether the present team is complete
/// (threshold and skills), then for each skill the share of its requirement that the
/// robots heading there or present do not hold (0 where it needs none). All 0 for a
/// task the robot does not know is open.
pub const TEAM_FEATURES: usize = 4;

/// A mission driven from outside: at every decision epoch (a task appears or is done,
/// a robot fails or returns, and every [`Perception::decide_every`]) every living
/// robot — an agent — picks a task it knows is open, or keeps its own. The
/// observation is the robot's own: its position and state, the tasks it knows of
/// (seen within [`Perception::sensing`] or heard of from a neighbour within
/// [`Perception::comm_radius`]), and where its neighbours are heading.
///
/// # Examples
/// ```
/// use afg_mission::{MissionConfig, MissionEnv, Perception, Preset};
/// let mission = MissionConfig::new(Preset::Waves, 10, 4, 1).generate()?;
/// let mut env = MissionEnv::new(mission, Perception::default())?;
/// let mut total = 0.0;
/// loop {
///     // Every agent heads for the first task it may take (or keeps its own).
///     let actions: Vec<(usize, usize)> = env.agents().iter()
///         .map(|&i| (i, env.mask(i).iter().position(|&ok| ok).unwrap()))
///         .collect();
///     let step = env.step(&actions)?;
///     total += step.reward;
///     if step.terminated || step.truncated {
///         break;
///     }
/// }
/// let run = env.into_run();
/// assert!((total - run.metrics.work_value).abs() < 1e-9);
/// # Ok::<(), afg_mission::MissionError>(())
/// ```
pub struct MissionEnv {
    sim: Sim<'static, 'static>,
    perception: Perception,
    /// Each robot's knowledge of each task having appeared (row-major, N × K).
    known: Vec<bool>,
    /// The work value at the last epoch.
    value: f64,
    /// Robots that failed: they left the episode (one that comes back idles).
    gone: Vec<bool>,
    over: bool,
    max_reward: f64,
}

impl MissionEnv {
    /// The environment of `mission`, run to its first decision epoch.
    ///
    /// # Errors
    /// [`MissionError::Invalid`] for a perception knob out of range.
    pub fn new(mission: Mission, perception: Perception) -> Result<Self, MissionError> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if perception.sensing.is_some_and(|s| !positive(s))
            || perception.comm_radius.is_nan()
            || perception.comm_radius < 0.0
        {
            return Err(MissionError::Invalid(
                "the sensing radius must be positive and the communication radius ≥ 0".into(),
            ));
        }
        let options = RunOptions {
            replan_every: perception.decide_every,
            ..RunOptions::default()
        };
        super::check_options(&options)?;
        let (n, k) = (mission.robots.len(), mission.tasks.len());
        let max_reward = mission.tasks.iter().map(|t| t.reward).fold(0.0, f64::max);
        let mut env = MissionEnv {
            sim: Sim::new(Cow::Owned(mission), None, options),
            perception,
            known: vec![false; n * k],
            value: 0.0,
            gone: vec![false; n],
            over: false,
            max_reward,
        };
        env.over = !env.run_to_epoch()?;
        Ok(env)
    }

    /// Robots in the mission (the possible agents).
    pub fn num_robots(&self) -> usize {
        self.sim.robots.len()
    }

    /// Tasks in the mission; actions are `0..num_tasks()` (head for that task) and
    /// `num_tasks()` (keep one's own task, or stay idle).
    pub fn num_tasks(&self) -> usize {
        self.sim.tasks.len()
    }

    /// Length of an observation: [`ROBOT_FEATURES`] + [`TASK_FEATURES`] per task; with
    /// [`Perception::teams`], S more for the robot and [`TEAM_FEATURES`] + S more per
    /// task (S skills).
    pub fn observation_len(&self) -> usize {
        let (robot, task) = self.widths();
        robot + task * self.num_tasks()
    }

    /// The widths of a robot's own features and of each task's.
    fn widths(&self) -> (usize, usize) {
        if self.perception.teams {
            let s = self.sim.mission.num_skills();
            (ROBOT_FEATURES + s, TASK_FEATURES + TEAM_FEATURES + s)
        } else {
            (ROBOT_FEATURES, TASK_FEATURES)
        }
    }

    /// The mission time now.
    pub fn time(&self) -> f64 {
        self.sim.now
    }

    /// The robots to act now: those that have not failed (none once the episode is
    /// over). A robot that fails leaves the episode for good: if the mission brings it
    /// back, it idles.
    pub fn agents(&self) -> Vec<usize> {
        if self.over {
            return Vec::new();
        }
        (0..self.num_robots()).filter(|&i| !self.gone[i]).collect()
    }

    fn knows_open(&self, robot: usize, task: usize) -> bool {
        self.known[robot * self.num_tasks() + task] && self.sim.tasks[task].open
    }

    /// The actions `robot` may take: the tasks it knows are open (with
    /// [`Perception::teams`], those a team of the living robots can staff), and keeping
    /// its own.
    pub fn mask(&self, robot: usize) -> Vec<bool> {
        let staffable = self.perception.teams.then(|| self.staffable());
        let mut mask: Vec<bool> = (0..self.num_tasks())
            .map(|j| self.knows_open(robot, j) && staffable.as_ref().is_none_or(|s| s[j]))
            .collect();
        mask.push(true);
        mask
    }

    /// Whether each task's threshold and skills are within what the living robots
    /// hold together.
    fn staffable(&self) -> Vec<bool> {
        let mission = &self.sim.mission;
        let living: Vec<usize> = (0..self.num_robots())
            .filter(|&i| self.sim.robots[i].alive)
            .collect();
        let mut held = vec![0u64; mission.num_skills()];
        for &i in &living {
            for (h, &q) in held.iter_mut().zip(&mission.robots[i].skills) {
                *h += u64::from(q);
            }
        }
        mission
            .tasks
            .iter()
            .map(|t| {
                t.min_team <= living.len()
                    && t.requires
                        .iter()
                        .zip(&held)
                        .all(|(&r, &h)| u64::from(r) <= h)
            })
            .collect()
    }

    /// Robot `robot`'s observation (see [`ROBOT_FEATURES`] and [`TASK_FEATURES`]).
    pub fn observe(&self, robot: usize) -> Vec<f32> {
        let here = self.sim.position(robot);
        let r = &self.sim.robots[robot];
        let state = match (r.task, r.there) {
            (None, _) => 0,
            (Some(_), false) => 1,
            (Some(_), true) => 2,
        };
        let (robot_width, task_width) = self.widths();
        let mut obs = vec![0.0f32; self.observation_len()];
        obs[0] = here.x as f32;
        obs[1] = here.y as f32;
        obs[2 + state] = 1.0;
        if self.perception.teams {
            for (o, &q) in obs[ROBOT_FEATURES..robot_width]
                .iter_mut()
                .zip(&self.sim.mission.robots[robot].skills)
            {
                *o = q as f32;
            }
        }
        let neighbours = self.neighbours(robot);
        let heading = |j: usize| {
            let count = neighbours
                .iter()
                .filter(|&&b| self.sim.robots[b].task == Some(j))
                .count();
            count as f32 / neighbours.len().max(1) as f32
        };
        for j in (0..self.num_tasks()).filter(|&j| self.knows_open(robot, j)) {
            let spec = &self.sim.mission.tasks[j];
            let row = &mut obs[robot_width + task_width * j..][..task_width];
            let (dx, dy) = (spec.position.x - here.x, spec.position.y - here.y);
            if self.perception.teams {
                self.observe_team(j, &mut row[TASK_FEATURES..]);
            }
            row[..TASK_FEATURES].copy_from_slice(&[
                1.0,
                dx as f32,
                dy as f32,
                here.distance(spec.position) as f32,
                (spec.reward / self.max_reward) as f32,
                spec.eps as f32,
                (self.sim.tasks[j].remaining / spec.workload) as f32,
                heading(j),
                f32::from(u8::from(r.task == Some(j))),
            ]);
        }
        obs
    }

    /// Task j's [`TEAM_FEATURES`] and the share of each skill it lacks, into `row`.
    fn observe_team(&self, j: usize, row: &mut [f32]) {
        let mission = &self.sim.mission;
        let spec = &mission.tasks[j];
        let k = spec.min_team as f32;
        let bound: Vec<usize> = (0..self.num_robots())
            .filter(|&i| self.sim.robots[i].alive && self.sim.robots[i].task == Some(j))
            .collect();
        let mut held = vec![0u64; mission.num_skills()];
        for &i in &bound {
            for (h, &q) in held.iter_mut().zip(&mission.robots[i].skills) {
                *h += u64::from(q);
            }
        }
        row[0] = k / self.num_robots() as f32;
        row[1] = self.sim.tasks[j].present as f32 / k;
        row[2] = bound.len() as f32 / k;
        row[3] = f32::from(u8::from(self.sim.team_complete(j)));
        for ((o, &need), &have) in row[TEAM_FEATURES..]
            .iter_mut()
            .zip(&spec.requires)
            .zip(&held)
        {
            if need > 0 {
                *o = u64::from(need).saturating_sub(have) as f32 / need as f32;
            }
        }
    }

    /// The living robots within the communication radius of `robot` (not itself).
    fn neighbours(&self, robot: usize) -> Vec<usize> {
        let here = self.sim.position(robot);
        (0..self.num_robots())
            .filter(|&b| b != robot && self.sim.robots[b].alive)
            .filter(|&b| here.distance(self.sim.position(b)) <= self.perception.comm_radius)
            .collect()
    }

    /// The agents act — `(robot, action)`: head for task `action`, or keep one's own
    /// for `action == num_tasks()`; an action the mask forbids also keeps one's own —
    /// and the mission runs to the next epoch.
    ///
    /// # Errors
    /// [`MissionError::Invalid`] after the episode's end or for a robot or action out
    /// of range.
    pub fn step(&mut self, actions: &[(usize, usize)]) -> Result<EnvStep, MissionError> {
        if self.over {
            return Err(MissionError::Invalid(
                "the episode is over; reset it".into(),
            ));
        }
        let (n, k) = (self.num_robots(), self.num_tasks());
        if let Some(&(i, a)) = actions.iter().find(|&&(i, a)| i >= n || a > k) {
            return Err(MissionError::Invalid(format!(
                "action {a} for robot {i}: robots are 0..{n}, actions 0..={k}"
            )));
        }
        for &(i, a) in actions {
            if a < k && !self.gone[i] && self.sim.robots[i].alive && self.knows_open(i, a) {
                self.sim.send(i, a);
            }
        }
        self.sim.log_decision(self.sim.now, 0.0, None);
        self.sim.decisions += 1;
        let alive: Vec<bool> = self.sim.robots.iter().map(|r| r.alive).collect();
        let going_on = self.sim.move_on() && self.run_to_epoch()? && !self.sim.over();
        let value = self.sim.work_value();
        let reward = value - self.value;
        self.value = value;
        let failed: Vec<usize> = (0..n)
            .filter(|&i| alive[i] && !self.gone[i] && !self.sim.robots[i].alive)
            .collect();
        for &i in &failed {
            self.gone[i] = true;
        }
        self.over = !going_on;
        let terminated = self.sim.over();
        Ok(EnvStep {
            reward,
            failed,
            terminated,
            truncated: !going_on && !terminated,
        })
    }

    /// Runs the mission from now to its next decision epoch (or its end); whether the
    /// episode goes on. The robots learn what they see and hear at the epoch.
    fn run_to_epoch(&mut self) -> Result<bool, MissionError> {
        loop {
            if self.sim.events_now()? {
                self.perceive();
                return Ok(true);
            }
            if !self.sim.move_on() {
                return Ok(false);
            }
        }
    }

    /// Each living robot sees the open tasks in range and hears what its neighbours
    /// knew (one hop).
    fn perceive(&mut self) {
        let (n, k) = (self.num_robots(), self.num_tasks());
        let before = self.known.clone();
        for i in (0..n).filter(|&i| self.sim.robots[i].alive) {
            let here = self.sim.position(i);
            for j in (0..k).filter(|&j| self.sim.tasks[j].open) {
                let place = self.sim.mission.tasks[j].position;
                if self
                    .perception
                    .sensing
                    .is_none_or(|s| here.distance(place) <= s)
                {
                    self.known[i * k + j] = true;
                }
            }
            for b in self.neighbours(i) {
                for j in 0..k {
                    self.known[i * k + j] |= before[b * k + j];
                }
            }
        }
    }

    /// The mission being played.
    pub fn mission(&self) -> &Mission {
        &self.sim.mission
    }

    /// The whole state now, as an animation's frame (for drawing).
    pub fn frame(&self) -> crate::Frame {
        self.sim.frame()
    }

    /// The run so far: its metrics, timeline and trace.
    pub fn into_run(self) -> MissionRun {
        self.sim.finish()
    }
}
