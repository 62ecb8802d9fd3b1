//! The units in which the learned models see an instance: task features, rewards,
//! join gains and edge weights.
//!
//! The paper fixes no normalisation. Two are offered, and every saved network records
//! which one it was trained with:
//!
//! - [`Units::MeanReward`] (the first models): welfare divided by the instance's mean
//!   initial reward, edge weights raw distances. The mean reward grows like N/M, so the
//!   distance part of a task feature, and the gap between the best and second-best
//!   action, shrink like 1/N; kNN edge lengths shrink like 1/√N.
//! - [`Units::ScaleFree`]: welfare in units of β (so a robot's distance cost is its
//!   distance, and per-robot utilities, rewards and action gaps are O(1) at every N),
//!   edge weights divided by the graph's mean edge weight (mean 1 at every N).
//! - [`Units::Bounded`]: as [`Units::ScaleFree`], and the value part of a task feature,
//!   `F_j(n + 1)/(n + 1)`, capped at [`VALUE_CAP`]`· r_j / eps_j`. In the paper's
//!   distribution `r_j / eps_j ≈ 1.5` at every N, and the share of a task with n
//!   members is about that times `eps_j / n` — the same at the same fraction of the
//!   episode — except for tasks with few members: an empty task's share is `r_j`,
//!   which grows like N/M. A model trained at N = 60 meets shares of 200–400 at
//!   N = 1000 that it has never seen; capped, they look like the ones it has.

use afg_game::Instance;
use serde::{Deserialize, Serialize};

use crate::RobotGraph;

/// How features, rewards and edge weights are measured (see the module docs).
///
/// # Examples
/// ```
/// use afg_game::GeneratorConfig;
/// use afg_graph::{GraphKind, RobotGraph, Units};
/// let inst = GeneratorConfig::paper(60, 5, 1).generate()?;
/// let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
/// // β = 1 in the paper's distribution: scale-free welfare is raw welfare.
/// assert_eq!(Units::ScaleFree.welfare_unit(&inst), 1.0);
/// assert!(Units::MeanReward.welfare_unit(&inst) > 12.0); // mean of U[12, 24]
/// assert_eq!(Units::MeanReward.edge_unit(&graph), 1.0);
/// assert!(Units::ScaleFree.edge_unit(&graph) < 0.3); // kNN edges are short
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Units {
    /// Welfare / mean initial reward; raw edge distances. The units of networks saved
    /// before units were recorded.
    MeanReward,
    /// Welfare / β; edge distances / the graph's mean edge length.
    ScaleFree,
    /// [`Units::ScaleFree`] with the value part of the task features capped. The
    /// default: every model trained since uses it.
    #[default]
    Bounded,
}

impl afg_game::Named for Units {
    const ALL: &'static [Self] = &[Units::MeanReward, Units::ScaleFree, Units::Bounded];
    const WHAT: &'static str = "units";

    fn name(self) -> &'static str {
        match self {
            Units::MeanReward => "mean-reward",
            Units::ScaleFree => "scale-free",
            Units::Bounded => "bounded",
        }
    }
}

/// The smallest β, relative to the mean reward, that the scale-free units take as their
/// welfare unit ([`Units::welfare_unit`]).
pub const MIN_BETA_UNIT: f64 = 1e-9;

/// The cap of the value part of a task feature in [`Units::Bounded`], in units of the
/// task's `r_j / eps_j`: the share of a task with fewer than about `eps_j / 4` members.
pub const VALUE_CAP: f64 = 4.0;

impl Units {
    /// The welfare unit: task features, rewards and gains are divided by it.
    ///
    /// In the scale-free units it is β, unless β is below [`MIN_BETA_UNIT`] times the
    /// mean reward (β = 0 among them): distance then hardly matters, and the mean
    /// reward is the unit, so that features stay well inside f32's range.
    pub fn welfare_unit(self, instance: &Instance) -> f64 {
        match self {
            Units::MeanReward => feature_scale(instance),
            Units::ScaleFree | Units::Bounded => {
                let mean = feature_scale(instance);
                if instance.beta() >= MIN_BETA_UNIT * mean {
                    instance.beta()
                } else {
                    mean
                }
            }
        }
    }

    /// The edge unit: edge weights are divided by it. O(E) for [`Units::ScaleFree`].
    pub fn edge_unit(self, graph: &RobotGraph) -> f64 {
        match self {
            Units::MeanReward => 1.0,
            Units::ScaleFree | Units::Bounded => {
                let (sum, count) = (0..graph.num_nodes())
                    .flat_map(|i| graph.weights(afg_game::RobotId(i as u32)))
                    .fold((0.0, 0usize), |(s, c), &w| (s + w, c + 1));
                let mean = if count > 0 { sum / count as f64 } else { 0.0 };
                if mean > 0.0 { mean } else { 1.0 }
            }
        }
    }

    /// The task feature of a task that has no room for the robot, below every real
    /// utility: −1 in mean-reward units (where β·√2 < the mean reward, as in the
    /// paper's distribution), −2 in scale-free units (a utility is at least −β·√2 in
    /// the unit square).
    pub fn full_task_feature(self) -> f32 {
        match self {
            Units::MeanReward => -1.0,
            Units::ScaleFree | Units::Bounded => -2.0,
        }
    }

    /// The largest value part `F_j(n + 1)/(n + 1)` a task feature shows, in raw welfare
    /// (infinite: no cap).
    pub fn value_cap(self, instance: &Instance, task: afg_game::TaskId) -> f64 {
        match self {
            Units::MeanReward | Units::ScaleFree => f64::INFINITY,
            Units::Bounded => {
                let t = instance.task(task);
                VALUE_CAP * t.reward / t.eps
            }
        }
    }
}

/// The mean initial reward `mean_j r_j` of the instance (1 if all rewards are 0): the
/// welfare unit of [`Units::MeanReward`].
pub fn feature_scale(instance: &Instance) -> f64 {
    let mean = instance.tasks().iter().map(|t| t.reward).sum::<f64>() / instance.num_tasks() as f64;
    if mean > 0.0 { mean } else { 1.0 }
}
