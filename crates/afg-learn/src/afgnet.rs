//! AFGNet (paper eqs. 4–9): robot features, task features and
//! distance-weighted neighbour messages embedded in L rounds.

use afg_graph::Units;
use burn::config::Config;
use burn::module::Module;
use burn::nn::Linear;
use burn::tensor::Tensor;
use burn::tensor::backend::Backend;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::layers::{Activation, QHead, linear_of_concat, seeded_linear, zero_linear};
use crate::price::net::{PRICE_INPUTS, PriceNet};
use crate::tensors::GraphTensors;

/// Shape and seed of an [`AfgNet`].
#[derive(Config, Debug, PartialEq)]
pub struct AfgNetConfig {
    /// Number of tasks M (input width of ν and μ, number of Q values).
    pub tasks: usize,
    /// The units of the inputs and rewards ([`Units`]).
    pub units: Units,
    /// Embedding width d.
    #[config(default = 64)]
    pub hidden: usize,
    /// Number of message-passing layers L.
    #[config(default = 3)]
    pub layers: usize,
    /// The nonlinearity σ.
    #[config(default = "Activation::Relu")]
    pub activation: Activation,
    /// Seed of the weight initialisation.
    #[config(default = 0)]
    pub seed: u64,
    /// Add the actor's join gain (the immediate reward of each action, in the task
    /// features' unit) to the Q values, so the network learns only what comes after
    /// the action: the untrained policy starts close to one-pass greedy. Off in the
    /// paper's model.
    #[config(default = false)]
    pub gain_residual: bool,
    /// Price structure (ours; off in the paper's model):
    /// `Q(s, a) = π_a(s) − β d(t, a) + c_a(s)`, where the price `π_a` comes from one
    /// MLP shared by all tasks ([`PriceNet`](crate::price::PriceNet)) reading the task's summaries
    /// ([`GraphBatch::task_inputs`](afg_graph::GraphBatch::task_inputs)) and the pooled
    /// embedding, and the correction `c` is the paper's head. Both output layers start
    /// at zero, so the untrained network is Nearest.
    #[config(default = false)]
    pub price_head: bool,
}

impl AfgNetConfig {
    /// Builds the network with weights drawn from `seed`.
    pub fn init<B: Backend>(&self, device: &B::Device) -> AfgNet<B> {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let (m, d) = (self.tasks, self.hidden);
        let theta1 = seeded_linear(&mut rng, m, d, device);
        let theta2 = seeded_linear(&mut rng, m, d, device);
        let layers = (0..self.layers)
            .map(|_| AfgLayer {
                theta4: seeded_linear(&mut rng, 1 + m, d, device),
                theta3: seeded_linear(&mut rng, d + 1, d, device),
                theta6: seeded_linear(&mut rng, 2 * d, d, device),
                theta5: seeded_linear(&mut rng, 2 * d, d, device),
            })
            .collect();
        let mut head = QHead::new(&mut rng, d, m, self.activation, device);
        // Drawn after everything else, so the paper's network keeps its weights.
        let price = self.price_head.then(|| {
            head.output = zero_linear(d, m, device);
            PriceNet::seeded(&mut rng, PRICE_INPUTS + d, d, device)
        });
        AfgNet {
            theta1,
            theta2,
            layers,
            head,
            price,
            activation: self.activation,
            gain_residual: self.gain_residual,
            units: self.units,
        }
    }
}

/// One message-passing layer with its own θ3–θ6.
#[derive(Module, Debug)]
pub struct AfgLayer<B: Backend> {
    /// θ4: `[w_ik || ν_k]`, `1 + M → d`.
    pub theta4: Linear<B>,
    /// θ3: `[mean message || |N_i|]`, `d + 1 → d`. (The paper's shape for θ3 is
    /// inconsistent with its input; this is the width the input has.)
    pub theta3: Linear<B>,
    /// θ6: `[mean_k w_ik δ_k || η_i]`, `2d → d`.
    pub theta6: Linear<B>,
    /// θ5: `[δ_i || σ(θ6 …)]`, `2d → d`.
    pub theta5: Linear<B>,
}

/// The AFGNet Q network.
#[derive(Module, Debug)]
pub struct AfgNet<B: Backend> {
    /// θ1: robot features, `M → d`.
    pub theta1: Linear<B>,
    /// θ2: task features, `M → d`.
    pub theta2: Linear<B>,
    /// The L layers.
    pub layers: Vec<AfgLayer<B>>,
    /// θ7 and the Q MLP (with a price head, the correction `c`).
    pub head: QHead<B>,
    /// The price head, when configured ([`AfgNetConfig::price_head`]).
    pub price: Option<PriceNet<B>>,
    #[module(skip)]
    activation: Activation,
    #[module(skip)]
    gain_residual: bool,
    #[module(skip)]
    units: Units,
}

impl<B: Backend> AfgNet<B> {
    /// The units of the inputs the network expects.
    pub fn units(&self) -> Units {
        self.units
    }

    /// Node embeddings δ^L.
    ///
    /// # Shapes
    /// output: `[V, d]`
    ///
    /// # Panics
    /// If the batch's features are in other units than the network's.
    pub fn embed(&self, g: &GraphTensors<B>) -> Tensor<B, 2> {
        g.expect_units(self.units);
        let s = self.activation;
        // eq. 4: δ_i = σ(θ1 ν_i) + σ(θ2 μ_i)                        [V, d]
        let mut delta =
            s.apply(self.theta1.forward(g.nu.clone())) + s.apply(self.theta2.forward(g.mu.clone()));
        let d = delta.dims()[1];
        if self.layers.is_empty() {
            return delta;
        }
        // eq. 5's messages σ(θ4 [w_ik || ν_k]) depend on the graph and the assignment
        // only, not on δ: all layers' messages are made in one product and summed into
        // their receivers in one pass, then each layer takes its d columns.  [V, L d]
        let width = d * self.layers.len();
        let all_messages = g.neighbour_mean(width, || {
            let weight = Tensor::cat(
                self.layers.iter().map(|l| l.theta4.weight.val()).collect(),
                1,
            );
            let bias = Tensor::cat(
                self.layers
                    .iter()
                    .map(|l| l.theta4.bias.as_ref().expect("θ4 has a bias").val())
                    .collect(),
                0,
            );
            s.apply(g.edge_features.clone().matmul(weight) + bias.unsqueeze())
        });
        for (l, layer) in self.layers.iter().enumerate() {
            // eq. 5: η_i = σ(θ3 [mean_k σ(θ4 [w_ik || ν_k]) || |N_i|])   [V, d]
            let messages = all_messages.clone().narrow(1, l * d, d);
            let eta = s.apply(linear_of_concat(
                &layer.theta3,
                vec![messages, g.degree.clone()],
            ));
            // eqs. 6–7: mean_k w_ik δ_k                               [V, d]
            let weighted = g.weighted_neighbour_mean(delta.clone());
            let inner = s.apply(linear_of_concat(&layer.theta6, vec![weighted, eta]));
            // eq. 8: δ'_i = σ(θ5 [δ_i || σ(θ6 [..])])                 [V, d]
            delta = s.apply(linear_of_concat(&layer.theta5, vec![delta, inner]));
        }
        delta
    }

    /// The task prices π of each graph (no actor involved), `None` without a price
    /// head: the one-shot mode gives every robot `argmin_j [β d(i, j) − π_j]` with the
    /// prices of the empty state.
    ///
    /// # Shapes
    /// output: `[G, M]`
    pub fn prices(&self, g: &GraphTensors<B>) -> Option<Tensor<B, 2>> {
        let price = self.price.as_ref()?;
        let pooled = g.graph_mean(self.embed(g));
        Some(self.prices_of(price, g, pooled))
    }

    /// Q values of each graph's acting robot (eq. 9 and the head).
    ///
    /// # Shapes
    /// output: `[G, M]`
    pub fn forward(&self, g: &GraphTensors<B>) -> Tensor<B, 2> {
        let delta = self.embed(g);
        let pooled = g.graph_mean(delta.clone());
        let mut q = self.head.forward(pooled.clone(), g.actor_rows(delta));
        if let Some(price) = &self.price {
            q = q + self.prices_of(price, g, pooled) - g.cost.clone();
        }
        if self.gain_residual {
            q + g.gain.clone()
        } else {
            q
        }
    }

    /// Every task's price by the price head, from the tasks' summaries and the pooled
    /// embedding.
    ///
    /// # Shapes
    /// - `pooled`: `[G, d]`
    /// - output: `[G, M]`
    fn prices_of(
        &self,
        price: &PriceNet<B>,
        g: &GraphTensors<B>,
        pooled: Tensor<B, 2>,
    ) -> Tensor<B, 2> {
        let [graphs, d] = pooled.dims();
        let m = g.cost.dims()[1];
        assert_eq!(
            g.task_inputs.dims()[0],
            graphs * m,
            "a price head reads the tasks' summaries: pack the batch with GraphBatch::with_task_summaries (QNetwork::empty_batch)"
        );
        // Each graph's pooled embedding beside each of its tasks.       [G M, d]
        let pooled = pooled
            .unsqueeze_dim::<3>(1)
            .repeat_dim(1, m)
            .reshape([graphs * m, d]);
        price
            .forward_parts(vec![g.task_inputs.clone(), pooled], self.activation)
            .reshape([graphs, m])
    }
}
