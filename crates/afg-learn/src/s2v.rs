//! structure2vec (Dai et al. 2017), the paper's S2V baseline: robot features only.

use afg_graph::Units;
use burn::config::Config;
use burn::module::Module;
use burn::nn::Linear;
use burn::tensor::Tensor;
use burn::tensor::activation::relu;
use burn::tensor::backend::Backend;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::layers::{Activation, QHead, seeded_linear};
use crate::tensors::GraphTensors;

/// Shape and seed of an [`S2v`].
#[derive(Config, Debug, PartialEq)]
pub struct S2vConfig {
    /// Number of tasks M.
    pub tasks: usize,
    /// The units of the inputs and rewards ([`Units`]).
    pub units: Units,
    /// Embedding width p.
    #[config(default = 64)]
    pub hidden: usize,
    /// Embedding iterations T.
    #[config(default = 4)]
    pub iterations: usize,
    /// Nonlinearity of the Q head (the embedding itself uses ReLU, as in Dai et al.).
    #[config(default = "Activation::Relu")]
    pub activation: Activation,
    /// Seed of the weight initialisation.
    #[config(default = 0)]
    pub seed: u64,
}

impl S2vConfig {
    /// Builds the network with weights drawn from `seed`.
    pub fn init<B: Backend>(&self, device: &B::Device) -> S2v<B> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let (m, p) = (self.tasks, self.hidden);
        S2v {
            theta1: seeded_linear(&mut rng, m, p, device),
            theta2: seeded_linear(&mut rng, p, p, device),
            theta3: seeded_linear(&mut rng, p, p, device),
            theta4: seeded_linear(&mut rng, 1, p, device),
            head: QHead::new(&mut rng, p, m, self.activation, device),
            iterations: self.iterations,
            units: self.units,
        }
    }
}

/// The S2V Q network.
#[derive(Module, Debug)]
pub struct S2v<B: Backend> {
    /// θ1: robot features x_v = ν_v, `M → p`.
    pub theta1: Linear<B>,
    /// θ2: sum of neighbour embeddings, `p → p`.
    pub theta2: Linear<B>,
    /// θ3: sum of edge-weight embeddings, `p → p`.
    pub theta3: Linear<B>,
    /// θ4: edge weight, `1 → p`.
    pub theta4: Linear<B>,
    /// Pooling and Q MLP, as in AFGNet.
    pub head: QHead<B>,
    #[module(skip)]
    iterations: usize,
    #[module(skip)]
    units: Units,
}

impl<B: Backend> S2v<B> {
    /// The units of the inputs the network expects.
    pub fn units(&self) -> Units {
        self.units
    }

    /// Node embeddings μ^T:
    /// `μ_v ← relu(θ1 x_v + θ2 Σ_{u∈N(v)} μ_u + θ3 Σ_u relu(θ4 w_uv))`, from μ = 0.
    ///
    /// # Shapes
    /// output: `[V, p]`
    ///
    /// # Panics
    /// If the batch's features are in other units than the network's.
    pub fn embed(&self, g: &GraphTensors<B>) -> Tensor<B, 2> {
        g.expect_units(self.units);
        let own = self.theta1.forward(g.nu.clone());
        let p = own.dims()[1];
        // The edge term does not change between iterations.
        let edges = self
            .theta3
            .forward(g.neighbour_sum(p, || relu(self.theta4.forward(g.weight.clone()))));
        let base = own + edges;
        let mut mu = Tensor::zeros(base.dims(), &base.device());
        for _ in 0..self.iterations {
            let neighbours = self.theta2.forward(g.neighbour_node_sum(mu));
            mu = relu(base.clone() + neighbours);
        }
        mu
    }

    /// Q values of each graph's acting robot.
    ///
    /// # Shapes
    /// output: `[G, M]`
    pub fn forward(&self, g: &GraphTensors<B>) -> Tensor<B, 2> {
        let mu = self.embed(g);
        self.head
            .forward(g.graph_mean(mu.clone()), g.actor_rows(mu))
    }
}
