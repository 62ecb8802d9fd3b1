//! Greedy rollout of a trained Q network as an [`Allocator`], and weight files.
//!
//! Weights are stored as two files with one stem: `STEM.json`, a manifest
//! (`{"format": "afg-weights", "version": 1, "network": {..config..}}`), and
//! `STEM.mpk`, Burn's named MessagePack record in full precision. Loading checks the
//! manifest and then every parameter's shape against the configured network.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use afg_baseline::{AllocError, AllocStats, Allocation, Allocator, CentralisedDa};
use afg_game::{Assignment, GameError, Instance, Preference};
use afg_graph::{GraphError, GraphKind, RobotGraph};
use burn::module::{Module, ModuleVisitor, Param};
use burn::record::{FullPrecisionSettings, NamedMpkFileRecorder};
use burn::tensor::Tensor;
use burn::tensor::backend::Backend;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::{FastPolicy, InferBackend, NetworkConfig, QNetwork};

/// Errors of the learning crate.
#[derive(Debug, Error)]
pub enum LearnError {
    /// Invalid instance or assignment.
    #[error(transparent)]
    Game(#[from] GameError),
    /// The robot graph could not be built.
    #[error(transparent)]
    Graph(#[from] GraphError),
    /// An action that the environment does not allow.
    #[error("invalid action: {0}")]
    InvalidAction(String),
    /// Training settings that cannot work.
    #[error("invalid training configuration: {0}")]
    InvalidConfig(String),
    /// A training checkpoint that cannot be used.
    #[error("{path}: {reason}")]
    Checkpoint {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: String,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// A weight file that cannot be used.
    #[error("{path}: {reason}")]
    Weights {
        /// The file.
        path: String,
        /// What is wrong, and what to do.
        reason: String,
    },
}

fn weights_error(path: &Path, reason: impl Into<String>) -> LearnError {
    LearnError::Weights {
        path: path.display().to_string(),
        reason: reason.into(),
    }
}

const WEIGHTS_FORMAT: &str = "afg-weights";
const WEIGHTS_VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    format: String,
    version: u32,
    network: NetworkConfig,
}

fn with_extension(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// Saves `network` (built from `config`) as `stem.json` + `stem.mpk`, each written to a
/// temporary file first and renamed, so existing weights are never half-overwritten.
///
/// # Errors
/// [`LearnError::Weights`] if a file cannot be written.
pub fn save_network<B: Backend>(
    network: QNetwork<B>,
    config: &NetworkConfig,
    stem: &Path,
) -> Result<(), LearnError> {
    // Burn replaces the extension of the path it is given, so give it one ending in .mpk.
    let record = with_extension(stem, "mpk");
    let tmp = with_extension(stem, &format!("{}-tmp.mpk", std::process::id()));
    let recorder = NamedMpkFileRecorder::<FullPrecisionSettings>::new();
    network
        .save_file(tmp.clone(), &recorder)
        .map_err(|e| weights_error(&record, e.to_string()))?;
    std::fs::rename(&tmp, &record).map_err(|e| weights_error(&record, e.to_string()))?;
    let manifest = Manifest {
        format: WEIGHTS_FORMAT.into(),
        version: WEIGHTS_VERSION,
        network: config.clone(),
    };
    let json = serde_json::to_string_pretty(&manifest).expect("a manifest always serialises");
    afg_game::io::write_atomic(&with_extension(stem, "json"), json.as_bytes())?;
    Ok(())
}

/// Collects parameter shapes in visiting order.
struct Shapes(Vec<Vec<usize>>);

impl<B: Backend> ModuleVisitor<B> for Shapes {
    fn visit_float<const D: usize>(&mut self, param: &Param<Tensor<B, D>>) {
        self.0.push(param.val().dims().to_vec());
    }
}

fn shapes<B: Backend>(network: &QNetwork<B>) -> Vec<Vec<usize>> {
    let mut v = Shapes(Vec::new());
    network.visit(&mut v);
    v.0
}

/// Loads weights saved by [`save_network`].
///
/// # Errors
/// [`LearnError::Weights`] for a missing or malformed manifest, a manifest of another
/// format or version, a corrupt or truncated record, or parameters whose shapes differ
/// from the network the manifest describes.
pub fn load_network<B: Backend>(
    stem: &Path,
    device: &B::Device,
) -> Result<(NetworkConfig, QNetwork<B>), LearnError> {
    let manifest_path = with_extension(stem, "json");
    let text = std::fs::read_to_string(&manifest_path)
        .map_err(|e| weights_error(&manifest_path, e.to_string()))?;
    let manifest: Manifest = serde_json::from_str(&text)
        .map_err(|e| weights_error(&manifest_path, format!("not a weights manifest: {e}")))?;
    if manifest.format != WEIGHTS_FORMAT || manifest.version != WEIGHTS_VERSION {
        return Err(weights_error(
            &manifest_path,
            format!(
                "format {} version {}, expected {WEIGHTS_FORMAT} version {WEIGHTS_VERSION}",
                manifest.format, manifest.version
            ),
        ));
    }
    let fresh = manifest.network.init::<B>(device);
    let expected = shapes(&fresh);
    let recorder = NamedMpkFileRecorder::<FullPrecisionSettings>::new();
    let record_path = with_extension(stem, "mpk");
    // Burn panics when a record holds another network variant; report that as an error too.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        fresh.load_file(record_path.clone(), &recorder, device)
    }));
    let network = match loaded {
        Ok(Ok(network)) => network,
        Ok(Err(e)) => {
            return Err(weights_error(
                &record_path,
                format!("unreadable weights ({e}); corrupt or truncated?"),
            ));
        }
        Err(_) => {
            return Err(weights_error(
                &record_path,
                "the record holds another kind of network than its manifest says",
            ));
        }
    };
    if shapes(&network) != expected {
        return Err(weights_error(
            &record_path,
            format!(
                "parameter shapes differ from the {} network its manifest describes",
                manifest.network.name()
            ),
        ));
    }
    Ok((manifest.network, network))
}

/// A trained network used greedily: each robot in index order takes the task with the
/// highest Q value among those with room.
///
/// By default the rollout runs on the fast path ([`FastPolicy`], the same actions as
/// the Burn network, several times faster); [`LearnedPolicy::exact_burn`] switches to
/// the Burn reference path. [`LearnedPolicy::block`] evaluates the network once per
/// block of robots, and [`LearnedPolicy::repair`] finishes with balanced best-response
/// sweeps so that the result is Def. 3 stable.
///
/// # Examples
/// ```
/// use afg_baseline::Allocator;
/// use afg_game::{GeneratorConfig, Preference};
/// use afg_learn::{LearnedPolicy, NetworkConfig};
/// let inst = GeneratorConfig::paper(20, 5, 1).generate()?;
/// let mut policy = LearnedPolicy::new(NetworkConfig::afgnet(5, 0)); // untrained weights
/// let out = policy.allocate(&inst)?;
/// assert!(out.assignment.is_complete());
/// (policy.block, policy.repair) = (4, true);
/// let repaired = policy.allocate(&inst)?;
/// assert!(inst.is_stable(&repaired.assignment, Preference::Balanced));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct LearnedPolicy {
    config: NetworkConfig,
    network: QNetwork<InferBackend>,
    fast: FastPolicy,
    /// The robot graph the network reads (kNN, k = 10 by default).
    pub graph: GraphKind,
    /// Robots per network evaluation (1 = the exact greedy rollout).
    pub block: usize,
    /// Balanced best-response sweeps after the rollout.
    pub repair: bool,
    /// Roll out with the Burn network instead of the fast path (reference; B = 1 only).
    pub exact_burn: bool,
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
            block: 1,
            repair: false,
            exact_burn: false,
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
    /// network's, [`LearnError::InvalidConfig`] for block 0 or a block above 1 with
    /// `exact_burn`, and graph errors.
    pub fn run(&self, instance: &Instance) -> Result<LearnedRun, LearnError> {
        let start = Instant::now();
        let (mut assignment, passes) = if self.exact_burn {
            if self.block != 1 {
                return Err(LearnError::InvalidConfig(
                    "the Burn reference path rolls out one robot at a time (block 1)".into(),
                ));
            }
            let mut out = crate::greedy_rollouts(
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
        } else {
            let graph = RobotGraph::build(instance.robots(), self.graph)?;
            let out = self.fast.rollout(instance, &graph, self.block)?;
            (out.assignment, out.passes)
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
