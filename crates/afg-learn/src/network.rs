//! One type for "a Q network": AFGNet or S2V, chosen by configuration.

use afg_graph::{GraphBatch, Units};
use burn::module::Module;
use burn::tensor::Tensor;
use burn::tensor::backend::Backend;
use serde::{Deserialize, Serialize};

use crate::afgnet::{AfgNet, AfgNetConfig};
use crate::s2v::{S2v, S2vConfig};
use crate::tensors::GraphTensors;

/// The kind of a Q network.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Net {
    /// AFGNet (the paper's network).
    #[cfg_attr(feature = "cli", value(name = "afgnet"))]
    AfgNet,
    /// Structure2Vec (the paper's comparison network).
    S2v,
}

impl Net {
    /// `afgnet` or `s2v`.
    pub fn name(self) -> &'static str {
        match self {
            Net::AfgNet => "afgnet",
            Net::S2v => "s2v",
        }
    }
}

/// Which network, with its shape and seed. Serialised beside saved weights, so a
/// weight file is never loaded into a network of another shape.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "net", rename_all = "lowercase")]
pub enum NetworkConfig {
    /// [`AfgNet`].
    AfgNet(AfgNetConfig),
    /// [`S2v`].
    S2v(S2vConfig),
}

impl NetworkConfig {
    /// AFGNet with the defaults of docs/models.md (d = 64, L = 3, ReLU) for `tasks` tasks.
    pub fn afgnet(tasks: usize, seed: u64) -> Self {
        NetworkConfig::AfgNet(AfgNetConfig::new(tasks).with_seed(seed))
    }

    /// S2V with the defaults of docs/models.md (p = 64, T = 4) for `tasks` tasks.
    pub fn s2v(tasks: usize, seed: u64) -> Self {
        NetworkConfig::S2v(S2vConfig::new(tasks).with_seed(seed))
    }

    /// Number of tasks (actions).
    pub fn tasks(&self) -> usize {
        match self {
            NetworkConfig::AfgNet(c) => c.tasks,
            NetworkConfig::S2v(c) => c.tasks,
        }
    }

    /// The units of the network's inputs and rewards.
    pub fn units(&self) -> Units {
        match self {
            NetworkConfig::AfgNet(c) => c.units,
            NetworkConfig::S2v(c) => c.units,
        }
        .unwrap_or_default()
    }

    /// The same network in other units (`None` for [`Units::MeanReward`], so that the
    /// configuration files of such networks stay as they were).
    pub fn with_units(self, units: Units) -> Self {
        let units = (units != Units::MeanReward).then_some(units);
        match self {
            NetworkConfig::AfgNet(c) => NetworkConfig::AfgNet(c.with_units(units)),
            NetworkConfig::S2v(c) => NetworkConfig::S2v(c.with_units(units)),
        }
    }

    /// Whether `other` is this network up to the seed of its initial weights (so that
    /// weights of one can start the other).
    pub fn same_shape(&self, other: &Self) -> bool {
        let unseeded = |c: &Self| match c.clone() {
            NetworkConfig::AfgNet(a) => NetworkConfig::AfgNet(a.with_seed(0)),
            NetworkConfig::S2v(s) => NetworkConfig::S2v(s.with_seed(0)),
        };
        unseeded(self) == unseeded(other)
    }

    /// The kind of network.
    pub fn net(&self) -> Net {
        match self {
            NetworkConfig::AfgNet(_) => Net::AfgNet,
            NetworkConfig::S2v(_) => Net::S2v,
        }
    }

    /// Short name: `afgnet` or `s2v`.
    pub fn name(&self) -> &'static str {
        self.net().name()
    }

    /// Builds the network.
    pub fn init<B: Backend>(&self, device: &B::Device) -> QNetwork<B> {
        match self {
            NetworkConfig::AfgNet(c) => QNetwork::AfgNet(c.init(device)),
            NetworkConfig::S2v(c) => QNetwork::S2v(c.init(device)),
        }
    }
}

/// A Q network of either kind.
// Both variants are a few hundred bytes of parameter handles; one network lives per
// policy or trainer, so boxing would only add indirection.
#[allow(clippy::large_enum_variant)]
#[derive(Module, Debug)]
pub enum QNetwork<B: Backend> {
    /// AFGNet.
    AfgNet(AfgNet<B>),
    /// structure2vec.
    S2v(S2v<B>),
}

impl<B: Backend> QNetwork<B> {
    /// The units of the inputs the network expects (from its configuration).
    pub fn units(&self) -> Units {
        match self {
            QNetwork::AfgNet(n) => n.units(),
            QNetwork::S2v(n) => n.units(),
        }
    }

    /// An empty batch for `tasks` tasks holding what this network reads: with the
    /// tasks' summaries for an AFGNet with a price head
    /// ([`GraphBatch::with_task_summaries`]), without them otherwise.
    pub fn empty_batch(&self, tasks: usize) -> GraphBatch {
        match self {
            QNetwork::AfgNet(n) if n.price.is_some() => GraphBatch::with_task_summaries(tasks),
            _ => GraphBatch::new(tasks),
        }
    }

    /// Q values of each graph's acting robot.
    ///
    /// # Shapes
    /// output: `[G, M]`
    pub fn forward(&self, g: &GraphTensors<B>) -> Tensor<B, 2> {
        match self {
            QNetwork::AfgNet(n) => n.forward(g),
            QNetwork::S2v(n) => n.forward(g),
        }
    }
}
