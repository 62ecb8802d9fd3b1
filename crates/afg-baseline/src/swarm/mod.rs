//! Decentralised allocation over a failing network: GRAPE's algorithm run round by
//! round where messages are lost (independently or in bursts), late, heard only
//! within range, robots wake at their own times, some crash mid-run, and the swarm
//! may be cut in two for a while.
//!
//! A run reports what a swarm engineer would measure — rounds, messages, bytes on the
//! air (whole partitions, as GRAPE sends them, and as changes only), how many
//! surviving robots hold the final partition — and what it is worth: % of the
//! optimum of the *surviving* robots, whether it is stable under GRAPE's preference,
//! and NS_rate under both preferences.
//!
//! On the perfect network ([`Network::default`]) the run is exactly
//! [`DecentralisedDa`](crate::DecentralisedDa) (tested).

mod auction;
mod grape;
mod links;
mod live_swarm;
mod moving;
mod network;
mod radio;
mod task_news;

use std::time::Duration;

use afg_game::{Assignment, Instance, Point, Preference, RobotId, TaskId};
use serde::{Deserialize, Serialize};

use crate::{AllocError, Allocator, Optimum, percent_of_opt, timed};

use auction::Auction;
pub(crate) use grape::Grape;
pub use live_swarm::{DETECT_AFTER, LiveSwarm};
pub use network::{Failure, Network};

/// A point of a run's trace.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracePoint {
    /// Round (from 1).
    pub round: u64,
    /// Welfare of the partition the living robots are converging on (GRAPE: the
    /// highest view; the auction: the slots each robot believes it holds), crashed
    /// robots left out.
    pub welfare: f64,
    /// Share of the living robots whose local view is that partition.
    pub agreeing: f64,
}

/// Most points a trace keeps: when it is full, every other point goes and the
/// sampling stride doubles.
const TRACE_POINTS: usize = 256;

/// Messages and bytes sent.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Traffic {
    pub messages: u64,
    pub bytes: u64,
    pub delta_bytes: u64,
}

/// What a run left, whatever the method.
pub(crate) struct Outcome {
    /// The final partition (crashed robots unassigned).
    pub tasks: Vec<Option<TaskId>>,
    pub alive: Vec<bool>,
    /// Share of the living robots whose view is the final partition.
    pub agreeing: f64,
    pub converged: bool,
    pub rounds: u64,
    /// GRAPE: changes on the final chain; the auction: bids made.
    pub changes: u64,
    /// GRAPE: changes any robot made, those the mutex discarded included; the
    /// auction: bids made.
    pub proposals: u64,
    /// Views (GRAPE) or table records (the auction) robots took from a neighbour.
    pub adoptions: u64,
    pub traffic: Traffic,
    pub added_edges: usize,
    pub trace: Vec<TracePoint>,
}

/// A decentralised method, round by round.
pub(crate) trait Simulation {
    /// Runs one round; whether any robot changed its mind or its view.
    fn round(&mut self) -> Result<bool, AllocError>;
    /// Nothing left to do and nothing scheduled.
    fn quiet(&self) -> bool;
    /// Rounds run.
    fn rounds(&self) -> u64;
    /// The trace point of now.
    fn sample(&self) -> TracePoint;
}

/// Runs `sim` until a round changes nothing and nothing more can happen (converged)
/// or until `max_rounds`; samples a trace if asked, thinning it as it fills.
pub(crate) fn drive(
    sim: &mut impl Simulation,
    max_rounds: u64,
    trace: bool,
    mut on_round: impl FnMut(u64),
) -> Result<(bool, Vec<TracePoint>), AllocError> {
    let (mut points, mut stride) = (Vec::new(), 1u64);
    let converged = loop {
        let active = sim.round()?;
        let round = sim.rounds();
        on_round(round);
        if trace && round.is_multiple_of(stride) {
            points.push(sim.sample());
            if points.len() >= TRACE_POINTS {
                let mut keep = false;
                points.retain(|_| {
                    keep = !keep;
                    keep
                });
                stride *= 2;
            }
        }
        if !active && sim.quiet() {
            break true;
        }
        if round >= max_rounds {
            break false;
        }
    };
    if trace
        && points
            .last()
            .is_none_or(|p: &TracePoint| p.round != sim.rounds())
    {
        points.push(sim.sample());
    }
    Ok((converged, points))
}

/// The decentralised methods.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "name")]
pub enum SwarmMethod {
    /// GRAPE with its distributed mutex, robots following `preference`.
    Grape {
        /// Selfish = the paper's GRAPE DA.
        preference: Preference,
    },
    /// The consensus-based auction on task places: robots bid for the k-th place of
    /// a task (worth `F_j(k) − F_j(k−1)`), raising its price by at least `epsilon`;
    /// prices and winners spread by max-consensus. On a game of team thresholds, the
    /// tasks a shared rule staffs have their first k places worth the same large bonus
    /// (ours, see the module docs of `swarm::auction`).
    Auction {
        /// The least price increment (the result is within 2N·ε of the optimum).
        epsilon: f64,
    },
}

impl SwarmMethod {
    /// The preference the result's stability is judged under: GRAPE's own, or the
    /// welfare (balanced) rule for the auction, which aims at the optimum.
    pub fn preference(&self) -> Preference {
        match *self {
            SwarmMethod::Grape { preference } => preference,
            SwarmMethod::Auction { .. } => Preference::Balanced,
        }
    }
}

/// A decentralised method run over a [`Network`].
///
/// # Examples
/// ```
/// use afg_baseline::{Failure, Network, Swarm};
/// use afg_game::{GeneratorConfig, Preference};
/// let inst = GeneratorConfig::paper(60, 5, 1).generate()?;
/// let network = Network { loss: 0.3, failure: Some(Failure::new(0.1, 10)), ..Network::default() };
/// let grape = Swarm::grape(Preference::Selfish, network.clone(), 7).run(&inst)?;
/// assert!(grape.converged && grape.agreeing == 1.0 && grape.stable);
/// assert_eq!(grape.survivors, 54);
/// let auction = Swarm::auction(1e-3, network, 7).run(&inst)?;
/// assert!(auction.converged && auction.agreeing == 1.0);
/// assert!(auction.percent_of_opt.unwrap() > 99.9);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Swarm {
    /// The method.
    pub method: SwarmMethod,
    /// The network.
    pub network: Network,
    /// Seeds the method's own draws and, on another stream, the network's.
    pub seed: u64,
    /// Rounds after which the run stops unconverged (0: 1000 + 4 N (N + 1), stretched
    /// by `(1 + max_delay) / ((1 − loss) · activation)`).
    pub max_rounds: u64,
    /// Whether to record the welfare and agreement as the rounds go.
    pub trace: bool,
}

/// What a swarm run did and what it is worth.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SwarmReport {
    /// The method.
    pub method: SwarmMethod,
    /// Robots at the start.
    pub robots: usize,
    /// Tasks.
    pub tasks: usize,
    /// The network it ran over.
    pub network: Network,
    /// Seed of the run.
    pub seed: u64,
    /// Whether it stopped by itself (a round with nothing to do and nothing in
    /// flight) rather than at the round limit.
    pub converged: bool,
    /// Rounds run, the last quiet one included.
    pub rounds: u64,
    /// GRAPE: changes on the final partition's chain (moves and removals of crashed
    /// robots); the auction: bids made.
    pub changes: u64,
    /// GRAPE: changes any robot made to its view, those the mutex discarded
    /// included; the auction: bids made (as `changes`).
    pub proposals: u64,
    /// Views (GRAPE) or table records (the auction) robots took from a neighbour:
    /// each is a robot reconsidering, the simulation's unit of work.
    pub adoptions: u64,
    /// Messages sent: every awake robot broadcasts to each neighbour every round.
    pub messages: u64,
    /// Bytes of those messages carrying whole partitions, as GRAPE sends them.
    pub bytes: u64,
    /// Bytes had each message carried only the changes its receiver lacked (a header
    /// alone when it lacked none; the whole partition when it was on another branch).
    pub delta_bytes: u64,
    /// Robots alive at the end.
    pub survivors: usize,
    /// Share of the survivors whose view is the final partition.
    pub agreeing: f64,
    /// Welfare of the final partition over the survivors.
    pub welfare: f64,
    /// The optimum over the survivors.
    pub opt_welfare: f64,
    /// `100 · welfare / opt_welfare` (`None` when the optimum is not positive).
    pub percent_of_opt: Option<f64>,
    /// Whether no survivor would move under [`SwarmMethod::preference`].
    pub stable: bool,
    /// NS_rate of the survivors under the balanced preference.
    pub ns_rate_balanced: f64,
    /// NS_rate of the survivors under the selfish preference.
    pub ns_rate_selfish: f64,
    /// Edges added to connect the graph (at the start and after the crash).
    pub added_edges: usize,
    /// Wall-clock time of the simulation, seconds.
    pub wall_time_s: f64,
    /// Welfare (survivors) and agreement by round, sampled (empty unless asked for).
    pub trace: Vec<TracePoint>,
    /// The final partition over all the robots (crashed ones unassigned).
    #[serde(skip)]
    pub assignment: Option<Assignment>,
}

impl Swarm {
    /// GRAPE under `preference` over `network`, no trace, the default round limit.
    pub fn grape(preference: Preference, network: Network, seed: u64) -> Self {
        Self::new(SwarmMethod::Grape { preference }, network, seed)
    }

    /// The auction with least increment `epsilon` over `network`, no trace, the
    /// default round limit.
    pub fn auction(epsilon: f64, network: Network, seed: u64) -> Self {
        Self::new(SwarmMethod::Auction { epsilon }, network, seed)
    }

    fn new(method: SwarmMethod, network: Network, seed: u64) -> Self {
        Swarm {
            method,
            network,
            seed,
            max_rounds: 0,
            trace: false,
        }
    }

    /// The round limit for `n` robots: [`Swarm::max_rounds`] if set, else GRAPE's
    /// bound on changes, stretched by how often a message gets through.
    fn round_limit(&self, n: usize) -> u64 {
        if self.max_rounds > 0 {
            return self.max_rounds;
        }
        let base = 1000.0 + 4.0 * n as f64 * (n as f64 + 1.0);
        let stretch = (1.0 + self.network.max_delay as f64)
            / ((1.0 - self.network.loss) * self.network.activation);
        (base * stretch).min(u64::MAX as f64 / 2.0) as u64
    }

    /// Runs the swarm on `instance`; `on_round` sees each round's number (a
    /// progress bar).
    ///
    /// # Errors
    /// [`AllocError::InvalidParameter`] for a network knob out of range,
    /// [`AllocError::Graph`] if a graph cannot be built, and the optimum's errors.
    pub fn run_with(
        &self,
        instance: &Instance,
        on_round: impl FnMut(u64),
    ) -> Result<SwarmReport, AllocError> {
        refuse_teams(self.method, instance)?;
        let limit = self.round_limit(instance.num_robots());
        let (outcome, wall_time) = timed(|| match self.method {
            SwarmMethod::Grape { preference } => {
                let mut sim = Grape::new(instance, preference, &self.network, self.seed)?;
                let (converged, trace) = drive(&mut sim, limit, self.trace, on_round)?;
                Ok::<_, AllocError>(sim.finish(converged, trace).0)
            }
            SwarmMethod::Auction { epsilon } => {
                let mut sim = Auction::new(instance, epsilon, &self.network, self.seed)?;
                let (converged, trace) = drive(&mut sim, limit, self.trace, on_round)?;
                Ok(sim.finish(converged, trace))
            }
        });
        let outcome = outcome?;
        let survivors: Vec<usize> = (0..instance.num_robots())
            .filter(|&i| outcome.alive[i])
            .collect();
        let (sub, sub_assignment) = survivors_game(instance, &survivors, &outcome.tasks)?;
        let opt_welfare = sub.welfare(&Optimum.allocate(&sub)?.assignment);
        let welfare = sub.welfare(&sub_assignment);
        let assignment = partition_of(&outcome.tasks, instance.num_tasks());
        Ok(SwarmReport {
            method: self.method,
            robots: instance.num_robots(),
            tasks: instance.num_tasks(),
            network: self.network.clone(),
            seed: self.seed,
            converged: outcome.converged,
            rounds: outcome.rounds,
            changes: outcome.changes,
            proposals: outcome.proposals,
            adoptions: outcome.adoptions,
            messages: outcome.traffic.messages,
            bytes: outcome.traffic.bytes,
            delta_bytes: outcome.traffic.delta_bytes,
            survivors: survivors.len(),
            agreeing: outcome.agreeing,
            welfare,
            opt_welfare,
            percent_of_opt: percent_of_opt(welfare, opt_welfare),
            stable: sub.is_stable(&sub_assignment, self.method.preference()),
            ns_rate_balanced: sub.ns_rate(&sub_assignment, Preference::Balanced),
            ns_rate_selfish: sub.ns_rate(&sub_assignment, Preference::Selfish),
            added_edges: outcome.added_edges,
            wall_time_s: Duration::as_secs_f64(&wall_time),
            trace: outcome.trace,
            assignment: Some(assignment),
        })
    }

    /// [`Swarm::run_with`] without a progress callback.
    ///
    /// # Errors
    /// As [`Swarm::run_with`].
    pub fn run(&self, instance: &Instance) -> Result<SwarmReport, AllocError> {
        self.run_with(instance, |_| {})
    }
}

/// The game of the surviving robots (same tasks) and the partition restricted to them.
fn survivors_game(
    instance: &Instance,
    survivors: &[usize],
    tasks: &[Option<TaskId>],
) -> Result<(Instance, Assignment), AllocError> {
    let points: Vec<Point> = survivors.iter().map(|&i| instance.robots()[i]).collect();
    let kept: Vec<RobotId> = survivors.iter().map(|&i| RobotId(i as u32)).collect();
    let sub = instance.with_robots_at(&kept, points)?;
    let kept: Vec<Option<TaskId>> = survivors.iter().map(|&i| tasks[i]).collect();
    Ok((sub, partition_of(&kept, instance.num_tasks())))
}

/// The assignment giving robot i `tasks[i]`, over `m` tasks. Capacities are not
/// checked: robots of a run cut short may overfill a task (a converged run cannot).
pub(crate) fn partition_of(tasks: &[Option<TaskId>], m: usize) -> Assignment {
    let mut assignment = Assignment::unassigned(tasks.len(), m);
    for (i, &task) in tasks.iter().enumerate() {
        assignment.set(RobotId(i as u32), task);
    }
    assignment
}

/// Refuses a game with skill requirements for GRAPE, which does not play it: its
/// robots judge a move by the coalitions' sizes they hear of (the threshold game's
/// values, as GRAPE DA does), not by the skills the coalitions hold. The auction plays
/// it (skill places, [`auction`]'s teams).
fn refuse_teams(method: SwarmMethod, instance: &Instance) -> Result<(), AllocError> {
    if !instance.has_skill_rules() {
        return Ok(());
    }
    let (method, reason) = match method {
        SwarmMethod::Grape { .. } => (
            "grape",
            "its robots hear of a coalition's size, not of the skills it holds",
        ),
        SwarmMethod::Auction { .. } => return Ok(()),
    };
    Err(AllocError::TeamsNotSupported {
        method: method.into(),
        rules: "skill requirements",
        reason,
    })
}
