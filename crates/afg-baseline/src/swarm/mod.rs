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

mod grape;
mod network;

use std::time::Duration;

use afg_game::{Assignment, Instance, Point, Preference, RobotId};
use serde::{Deserialize, Serialize};

use crate::{AllocError, Allocator, Optimum, percent_of_opt, timed};

pub(crate) use grape::Grape;
pub use grape::TracePoint;
pub use network::{Failure, Network};

/// A decentralised method run over a [`Network`].
///
/// # Examples
/// ```
/// use afg_baseline::{Failure, Network, Swarm};
/// use afg_game::{GeneratorConfig, Preference};
/// let inst = GeneratorConfig::paper(60, 5, 1).generate()?;
/// let network = Network { loss: 0.3, failure: Some(Failure::new(0.1, 10)), ..Network::default() };
/// let report = Swarm::grape(Preference::Selfish, network, 7).run(&inst)?;
/// assert!(report.converged && report.agreeing == 1.0 && report.stable);
/// assert_eq!(report.survivors, 54);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Swarm {
    /// GRAPE's preference (selfish = the paper's GRAPE DA).
    pub preference: Preference,
    /// The network.
    pub network: Network,
    /// Seeds GRAPE's stamps and, on another stream, the network's draws.
    pub seed: u64,
    /// Rounds after which the run stops unconverged.
    pub max_rounds: u64,
    /// Whether to record the welfare and agreement as the rounds go.
    pub trace: bool,
}

/// What a swarm run did and what it is worth.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SwarmReport {
    /// The method (`grape`).
    pub method: String,
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
    /// Changes on the final partition's chain (moves and removals of crashed robots).
    pub changes: u64,
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
    /// Whether no survivor would move under the run's preference.
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
    /// GRAPE under `preference` over `network`, no trace, a round limit of
    /// 1000 + 4 N (N + 1) per unit of `1 / (1 − loss)` and of activation.
    pub fn grape(preference: Preference, network: Network, seed: u64) -> Self {
        Swarm {
            preference,
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
        let (outcome, wall_time) = timed(|| {
            let mut sim = Grape::new(instance, self.preference, &self.network, self.seed)?;
            if self.trace {
                sim = sim.traced();
            }
            sim.run(self.round_limit(instance.num_robots()), on_round)
        });
        let outcome = outcome?;
        let final_tasks: Vec<_> = outcome.leader.assignment().tasks().to_vec();
        let survivors: Vec<usize> = (0..instance.num_robots())
            .filter(|&i| outcome.alive[i])
            .collect();
        let agreeing = survivors
            .iter()
            .filter(|&&i| {
                let view = &outcome.views[i];
                std::rc::Rc::ptr_eq(view, &outcome.leader)
                    || view.assignment().tasks() == final_tasks
            })
            .count() as f64
            / survivors.len() as f64;
        let (sub, sub_assignment) = survivors_game(instance, &survivors, &final_tasks)?;
        let opt_welfare = sub.welfare(&Optimum.allocate(&sub)?.assignment);
        let welfare = sub.welfare(&sub_assignment);
        let mut assignment = Assignment::unassigned(instance.num_robots(), instance.num_tasks());
        for &i in &survivors {
            assignment.set(RobotId(i as u32), final_tasks[i]);
        }
        Ok(SwarmReport {
            method: "grape".into(),
            robots: instance.num_robots(),
            tasks: instance.num_tasks(),
            network: self.network.clone(),
            seed: self.seed,
            converged: outcome.converged,
            rounds: outcome.rounds,
            changes: outcome.leader.evolution(),
            messages: outcome.messages,
            bytes: outcome.bytes,
            delta_bytes: outcome.delta_bytes,
            survivors: survivors.len(),
            agreeing,
            welfare,
            opt_welfare,
            percent_of_opt: percent_of_opt(welfare, opt_welfare),
            stable: sub.is_stable(&sub_assignment, self.preference),
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
    tasks: &[Option<afg_game::TaskId>],
) -> Result<(Instance, Assignment), AllocError> {
    let points: Vec<Point> = survivors.iter().map(|&i| instance.robots()[i]).collect();
    let sub = Instance::new(points, instance.tasks().to_vec(), instance.beta())?;
    let assignment = Assignment::from_tasks(&sub, survivors.iter().map(|&i| tasks[i]).collect())?;
    Ok((sub, assignment))
}
