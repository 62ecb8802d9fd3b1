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
#[serde(rename_all = "lowercase")]
pub enum Net {
    /// AFGNet (the paper's network).
    AfgNet,
    /// Structure2Vec (the paper's comparison network).
    S2v,
}

impl afg_game::Named for Net {
    const ALL: &'static [Self] = &[Net::AfgNet, Net::S2v];
    const WHAT: &'static str = "network";

    fn name(self) -> &'static str {
        Net::name(self)
    }
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

/// The largest network shape a file may ask for ([`NetworkConfig::check`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NetworkLimits {
    /// Tasks M (actions; training stores them in a byte, so it takes at most 255).
    pub tasks: usize,
    /// Embedding width d (AFGNet) or p (S2V).
    pub hidden: usize,
    /// Message-passing layers L (AFGNet) or embedding iterations T (S2V).
    pub depth: usize,
}

/// The limits of [`NetworkConfig::check`]: 16 times the paper's d = 64 and L = 3 and
/// far beyond its M = 5, a few hundred MiB of weights at most.
pub const NETWORK_LIMITS: NetworkLimits = NetworkLimits {
    tasks: 4096,
    hidden: 1024,
    depth: 64,
};

/// Which network, with its shape and seed. Serialised beside saved weights, so a
/// weight file is never loaded into a network of another shape.
///
/// Read from JSON, a field that neither network has is an error (Burn's `Config`
/// derive alone would ignore it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "net", rename_all = "lowercase")]
#[serde(try_from = "serde_json::Value")]
pub enum NetworkConfig {
    /// [`AfgNet`].
    AfgNet(AfgNetConfig),
    /// [`S2v`].
    S2v(S2vConfig),
}

/// [`NetworkConfig`] as serde reads it, before the check for unknown fields.
#[derive(Deserialize)]
#[serde(tag = "net", rename_all = "lowercase")]
enum TaggedConfig {
    AfgNet(AfgNetConfig),
    S2v(S2vConfig),
}

impl TryFrom<serde_json::Value> for NetworkConfig {
    type Error = String;
    fn try_from(value: serde_json::Value) -> Result<Self, String> {
        let config = match serde_json::from_value(value.clone()).map_err(|e| e.to_string())? {
            TaggedConfig::AfgNet(c) => NetworkConfig::AfgNet(c),
            TaggedConfig::S2v(c) => NetworkConfig::S2v(c),
        };
        // Every field given must be one that the network writes back.
        let known = serde_json::to_value(&config).expect("a network configuration serialises");
        if let (Some(given), Some(known)) = (value.as_object(), known.as_object())
            && let Some(field) = given.keys().find(|k| !known.contains_key(*k))
        {
            return Err(format!(
                "unknown field `{field}` of a {} network",
                config.name()
            ));
        }
        Ok(config)
    }
}

impl NetworkConfig {
    /// AFGNet with the defaults of docs/models.md (d = 64, L = 3, ReLU) for `tasks` tasks,
    /// in the default [`Units`].
    pub fn afgnet(tasks: usize, seed: u64) -> Self {
        NetworkConfig::AfgNet(AfgNetConfig::new(tasks, Units::default()).with_seed(seed))
    }

    /// S2V with the defaults of docs/models.md (p = 64, T = 4) for `tasks` tasks, in the
    /// default [`Units`].
    pub fn s2v(tasks: usize, seed: u64) -> Self {
        NetworkConfig::S2v(S2vConfig::new(tasks, Units::default()).with_seed(seed))
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
    }

    /// The same network in other units.
    pub fn with_units(self, units: Units) -> Self {
        match self {
            NetworkConfig::AfgNet(c) => NetworkConfig::AfgNet(AfgNetConfig { units, ..c }),
            NetworkConfig::S2v(c) => NetworkConfig::S2v(S2vConfig { units, ..c }),
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

    /// Whether the shape is within [`NETWORK_LIMITS`], so that building it allocates a
    /// bounded amount of memory and a forward pass ends in bounded time. Checked when
    /// a weight file or a training configuration is read, before anything is built.
    ///
    /// # Errors
    /// What is out of range, and the range.
    ///
    /// # Examples
    /// ```
    /// use afg_learn::nets::{AfgNetConfig, NetworkConfig};
    /// assert!(NetworkConfig::afgnet(5, 0).check().is_ok());
    /// let wide = NetworkConfig::AfgNet(AfgNetConfig::new(5, Default::default()).with_hidden(0));
    /// assert!(wide.check().unwrap_err().contains("hidden"));
    /// ```
    pub fn check(&self) -> Result<(), String> {
        let limits = NETWORK_LIMITS;
        let (tasks, hidden, depth, depth_name) = match self {
            NetworkConfig::AfgNet(c) => (c.tasks, c.hidden, c.layers, "layers"),
            NetworkConfig::S2v(c) => (c.tasks, c.hidden, c.iterations, "iterations"),
        };
        for (name, value, max) in [
            ("tasks", tasks, limits.tasks),
            ("hidden", hidden, limits.hidden),
            (depth_name, depth, limits.depth),
        ] {
            if !(1..=max).contains(&value) {
                return Err(format!(
                    "the network's {name} is {value}; it must be between 1 and {max}"
                ));
            }
        }
        Ok(())
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
            QNetwork::AfgNet(n) if n.price.is_some() => {
                GraphBatch::with_task_summaries(tasks, self.units())
            }
            _ => GraphBatch::new(tasks, self.units()),
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
