//! Greedy rollout of a trained Q network as an [`Allocator`].

use std::path::Path;
use std::time::{Duration, Instant};

use afg_baseline::{AllocError, AllocStats, Allocation, Allocator, CentralisedDa};
use afg_game::{Assignment, Instance, Preference};
use afg_graph::{GraphKind, RobotGraph};

use crate::fast::FastPolicy;
use crate::qnetwork::{NetworkConfig, QNetwork};
use crate::weights::load_network;
use crate::{InferBackend, LearnError};

pub use crate::regret::{RegretStep, q_star, q_star_next, regret_trace};
pub use crate::rollout::greedy_rollouts;

/// A trained network used greedily: each robot in index order takes the task with the
/// highest Q value among those with room.
///
/// By default the rollout runs on the fast path ([`FastPolicy`], the same actions as
/// the Burn network, several times faster) one robot per network evaluation;
/// [`LearnedPolicy::with_block`] evaluates the network once per block of robots,
/// [`LearnedPolicy::exact_burn`] switches to the Burn reference path, and
/// [`LearnedPolicy::with_repair`] finishes with balanced best-response sweeps so that
/// the result is Def. 3 stable. Invalid combinations cannot be built.
///
/// # Examples
/// ```
/// use afg_baseline::Allocator;
/// use afg_game::{GeneratorConfig, Preference};
/// use afg_learn::{nets::NetworkConfig, policy::LearnedPolicy};
/// let inst = GeneratorConfig::paper(20, 5, 1).generate()?;
/// let policy = LearnedPolicy::new(NetworkConfig::afgnet(5, 0)); // untrained weights
/// let out = policy.allocate(&inst)?;
/// assert!(out.assignment.is_complete());
/// let policy = policy.with_block(4)?.with_repair(true);
/// let repaired = policy.allocate(&inst)?;
/// assert!(inst.is_stable(&repaired.assignment, Preference::Balanced));
/// assert!(LearnedPolicy::new(NetworkConfig::afgnet(5, 0)).with_block(0).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct LearnedPolicy {
    config: NetworkConfig,
    network: QNetwork<InferBackend>,
    fast: FastPolicy,
    graph: GraphKind,
    path: RolloutPath,
    repair: bool,
}

/// How the rollout evaluates the network.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RolloutPath {
    /// The fast path, one evaluation per `block` robots (≥ 1).
    Fast { block: usize },
    /// The Burn network, one robot at a time (the reference).
    ExactBurn,
}

/// A learned allocation with its cost broken down.
#[derive(Clone, Debug)]
pub struct LearnedRun {
    /// The final assignment (after repair, if asked).
    pub assignment: Assignment,
    /// Welfare of the rollout's assignment, before any repair.
    pub rollout_welfare: f64,
    /// Network evaluations.
    pub passes: usize,
    /// Time of the rollout (graph, features, network, bookkeeping).
    pub rollout_time: Duration,
    /// Robot moves made by the repair.
    pub repair_moves: u64,
    /// Time of the repair.
    pub repair_time: Duration,
}

impl LearnedPolicy {
    fn with_network(config: NetworkConfig, network: QNetwork<InferBackend>) -> Self {
        LearnedPolicy {
            fast: FastPolicy::from_network(&config, &network),
            config,
            network,
            graph: GraphKind::default(),
            path: RolloutPath::Fast { block: 1 },
            repair: false,
        }
    }

    /// A policy with freshly initialised weights from `config`.
    pub fn new(config: NetworkConfig) -> Self {
        let network = config.init(&Default::default());
        Self::with_network(config, network)
    }

    /// A policy from saved weights (see [`load_network`]).
    ///
    /// # Errors
    /// As [`load_network`].
    pub fn load(stem: &Path) -> Result<Self, LearnError> {
        let (config, network) = load_network(stem, &Default::default())?;
        Ok(Self::with_network(config, network))
    }

    /// Evaluates the network once per `block` robots on the fast path (1, the default,
    /// is the exact greedy rollout).
    ///
    /// # Errors
    /// [`LearnError::InvalidConfig`] for block 0.
    pub fn with_block(mut self, block: usize) -> Result<Self, LearnError> {
        if block == 0 {
            return Err(LearnError::InvalidConfig(
                "a block holds at least one robot".into(),
            ));
        }
        self.path = RolloutPath::Fast { block };
        Ok(self)
    }

    /// Rolls out with the Burn network, one robot at a time (the reference path).
    pub fn exact_burn(mut self) -> Self {
        self.path = RolloutPath::ExactBurn;
        self
    }

    /// Whether balanced best-response sweeps follow the rollout.
    pub fn with_repair(mut self, repair: bool) -> Self {
        self.repair = repair;
        self
    }

    /// The robot graph the network reads (kNN, k = 10 by default).
    pub fn with_graph(mut self, graph: GraphKind) -> Self {
        self.graph = graph;
        self
    }

    /// Robots per network evaluation (1 on the Burn path).
    pub fn block(&self) -> usize {
        match self.path {
            RolloutPath::Fast { block } => block,
            RolloutPath::ExactBurn => 1,
        }
    }

    /// Whether the rollout is repaired.
    pub fn repairs(&self) -> bool {
        self.repair
    }

    /// The network's configuration.
    pub fn config(&self) -> &NetworkConfig {
        &self.config
    }

    /// The network.
    pub fn network(&self) -> &QNetwork<InferBackend> {
        &self.network
    }

    /// The rollout (and repair) with its cost.
    ///
    /// # Errors
    /// [`LearnError::InvalidAction`] if the instance's task count differs from the
    /// network's, and graph errors.
    pub fn run(&self, instance: &Instance) -> Result<LearnedRun, LearnError> {
        let start = Instant::now();
        let (mut assignment, passes) = if let RolloutPath::Fast { block } = self.path {
            let graph = RobotGraph::build(instance.robots(), self.graph)?;
            let out = self.fast.rollout(instance, &graph, block)?;
            (out.assignment, out.passes)
        } else {
            let mut out = crate::rollout::greedy_rollouts(
                &self.network,
                self.config.tasks(),
                std::slice::from_ref(instance),
                self.graph,
                &Default::default(),
            )?;
            (
                out.pop().expect("one rollout per instance"),
                instance.num_robots(),
            )
        };
        let rollout_time = start.elapsed();
        let rollout_welfare = instance.welfare(&assignment);
        let start = Instant::now();
        let repair_moves = if self.repair {
            CentralisedDa::new(Preference::Balanced)
                .improve(instance, &mut assignment)
                .0
        } else {
            0
        };
        Ok(LearnedRun {
            assignment,
            rollout_welfare,
            passes,
            rollout_time,
            repair_moves,
            repair_time: start.elapsed(),
        })
    }

    /// The final assignment of [`LearnedPolicy::run`].
    ///
    /// # Errors
    /// As [`LearnedPolicy::run`].
    pub fn rollout(&self, instance: &Instance) -> Result<Assignment, LearnError> {
        Ok(self.run(instance)?.assignment)
    }
}

impl Allocator for LearnedPolicy {
    fn name(&self) -> String {
        self.config.name().into()
    }

    /// Stats: `iterations` = robots placed + repair moves, `rounds` = network passes.
    fn allocate(&self, instance: &Instance) -> Result<Allocation, AllocError> {
        afg_baseline::paper_game_only(instance, self)?;
        afg_baseline::check_game(
            instance,
            self,
            afg_baseline::Plays::Concave(crate::TRAINED_CONCAVE),
        )?;
        let start = Instant::now();
        let run = self.run(instance).map_err(|e| AllocError::Failed {
            method: self.name(),
            message: e.to_string(),
        })?;
        let stats = AllocStats {
            iterations: instance.num_robots() as u64 + run.repair_moves,
            rounds: run.passes as u64,
            wall_time: start.elapsed(),
            ..AllocStats::default()
        };
        Ok(Allocation {
            assignment: run.assignment,
            stats,
        })
    }
}
