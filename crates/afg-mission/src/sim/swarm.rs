//! A decentralised method inside the mission: rounds at a fixed rate over the radio,
//! each robot heading where its own view says.

use std::time::Instant;

use afg_baseline::{LiveSwarm, Network, SwarmMethod};
use afg_game::Point;
use serde::{Deserialize, Serialize};

use super::{Sim, mission_game};
use crate::{Mission, MissionError};

/// A decentralised method run inside a mission (docs/missions.md): the robots run it
/// round by round, `rounds_per_time` rounds per time unit, over `network` with links
/// between the robots where they are, and each heads for the task its own view gives
/// it, settled or not.
///
/// # Examples
/// ```
/// use afg_baseline::{Network, SwarmMethod};
/// use afg_game::Preference;
/// use afg_mission::internal::{Decentralised, Replan, RunOptions, simulate};
/// use afg_mission::{MissionConfig, Preset};
/// let mission = MissionConfig::new(Preset::Waves, 30, 6, 1).generate()?;
/// let grape = Decentralised::new(SwarmMethod::Grape { preference: Preference::Selfish }, Network::default());
/// let run = simulate(&mission, Replan::Decentralised(&grape), RunOptions::default())?;
/// let swarm = run.metrics.swarm.expect("a decentralised run has swarm metrics");
/// assert!(swarm.rounds > 0 && swarm.messages > 0);
/// # Ok::<(), afg_mission::MissionError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Decentralised {
    /// The method: GRAPE, or the auction (restarted in a new epoch by every news).
    pub method: SwarmMethod,
    /// The radio: who hears whom (re-evaluated every round as robots move), losses,
    /// delays, asynchrony. Its own failures are refused: robots fail at the mission's.
    pub network: Network,
    /// Rounds per mission time unit.
    pub rounds_per_time: f64,
    /// Robots see tasks within this distance and hear of others from their
    /// neighbours (`None`: every robot hears of every task at once).
    pub sensing: Option<f64>,
    /// Seeds the method's draws and the network's.
    pub seed: u64,
}

impl Decentralised {
    /// `method` over `network`, at the rounds per time unit and sensing of
    /// [`SwarmKnobs::default`](crate::SwarmKnobs), seed 0.
    pub fn new(method: SwarmMethod, network: Network) -> Self {
        let knobs = crate::SwarmKnobs::default();
        Decentralised {
            method,
            network,
            rounds_per_time: knobs.rounds_per_time,
            sensing: knobs.sensing,
            seed: 0,
        }
    }
}

/// What a decentralised run adds to the metrics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwarmMetrics {
    /// Robots in the swarm (failed ones included).
    pub robots: usize,
    /// Rounds run.
    pub rounds: u64,
    /// Messages sent (every awake robot to each neighbour every round).
    pub messages: u64,
    /// Bytes on the air (whole partitions, as GRAPE sends them, and news of tasks).
    pub bytes: u64,
    /// Response time: from an event (a task appears or is done, a robot fails or
    /// returns) until every living robot's view agrees again with nothing left to do;
    /// the mean over the events that settled.
    pub response_mean: Option<f64>,
    /// Its maximum.
    pub response_max: Option<f64>,
    /// Events after which the swarm had not settled by the end.
    pub unsettled: usize,
}

/// The swarm's state in a run.
pub(super) struct SwarmState {
    live: LiveSwarm,
    robots: usize,
    rounds_per_time: f64,
    /// The next round's index (round k runs at time k / rounds_per_time).
    next: u64,
    /// Times of the events since the swarm last settled.
    awaiting: Vec<f64>,
    responses: Vec<f64>,
}

impl SwarmState {
    /// The swarm of `mission`: every robot at its start, every task, none known yet.
    pub fn new(mission: &Mission, config: &Decentralised) -> Result<Self, MissionError> {
        let rate = config.rounds_per_time;
        if !(rate.is_finite() && rate > 0.0) {
            return Err(MissionError::Invalid(
                "the rounds per time unit must be finite and positive".into(),
            ));
        }
        let robots: Vec<usize> = (0..mission.robots.len()).collect();
        let tasks: Vec<usize> = (0..mission.tasks.len()).collect();
        let positions = mission.robots.iter().map(|r| r.position).collect();
        let game = mission_game(mission, &robots, positions, &tasks)?;
        let live = LiveSwarm::new(
            game,
            config.method,
            &config.network,
            config.sensing,
            config.seed,
        )?;
        Ok(SwarmState {
            live,
            robots: mission.robots.len(),
            rounds_per_time: rate,
            next: 0,
            awaiting: Vec::new(),
            responses: Vec::new(),
        })
    }

    /// When the next round runs.
    pub fn next_round(&self) -> f64 {
        self.next as f64 / self.rounds_per_time
    }

    /// The swarm hears of a task's appearance (or completion) at `time`.
    pub fn task(&mut self, task: usize, done: bool, time: f64) {
        if done {
            self.live.task_done(task);
        } else {
            self.live.task_appears(task);
        }
        self.awaiting.push(time);
    }

    /// A robot fails (or, `back`, returns) at `time`.
    pub fn robot(&mut self, robot: usize, back: bool, time: f64) -> Result<(), MissionError> {
        if back {
            self.live.revive(robot)?;
        } else {
            self.live.fail(robot)?;
        }
        self.awaiting.push(time);
        Ok(())
    }

    /// The metrics of the run so far.
    pub fn metrics(&self) -> SwarmMetrics {
        let n = self.responses.len();
        SwarmMetrics {
            robots: self.robots,
            rounds: self.live.rounds(),
            messages: self.live.messages(),
            bytes: self.live.bytes(),
            response_mean: (n > 0).then(|| self.responses.iter().sum::<f64>() / n as f64),
            response_max: self.responses.iter().copied().reduce(f64::max),
            unsettled: self.awaiting.len(),
        }
    }
}

impl Sim<'_, '_> {
    /// One round of the swarm with the robots where they are now; each living robot
    /// then heads where its own view says (or stops, if that task is not open).
    pub(super) fn swarm_round(&mut self) -> Result<(), MissionError> {
        let positions: Vec<Point> = (0..self.robots.len()).map(|i| self.position(i)).collect();
        let swarm = self.swarm.as_mut().expect("a swarm round needs a swarm");
        let start = Instant::now();
        swarm.live.round(&positions)?;
        let compute_s = start.elapsed().as_secs_f64();
        self.compute.push(compute_s);
        swarm.next += 1;
        if swarm.live.settled() {
            let now = self.now;
            swarm
                .responses
                .extend(swarm.awaiting.drain(..).map(|t| now - t));
        }
        let targets: Vec<Option<usize>> = (0..self.robots.len())
            .map(|i| swarm.live.task_of(i))
            .collect();
        self.decisions += 1;
        let mut moved = false;
        for (i, target) in targets.into_iter().enumerate() {
            let r = &self.robots[i];
            let target = target.filter(|&j| self.tasks[j].open);
            if !r.alive || r.task == target {
                continue;
            }
            moved = true;
            match target {
                Some(j) => self.send(i, j),
                None => self.stop(i),
            }
        }
        if moved {
            self.log_decision(self.now, compute_s, None);
        }
        Ok(())
    }
}
