//! The price network: one small MLP shared by every task, from a task's inputs to its
//! price π_j; `Q(s, a) = π_a(s) − β d(t, a)`.

use burn::module::{Module, Param};
use burn::nn::Linear;
use burn::tensor::backend::Backend;
use burn::tensor::{Tensor, TensorData};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::dense::{Dense, task_mlp};
use crate::layers::Activation;
use crate::layers::{linear_of_concat, seeded_linear, zero_linear};
use afg_graph::{TASK_FEATURES, task_inputs};

/// Width of a task's network input: its features and the mean of all tasks' features.
pub const PRICE_INPUTS: usize = 2 * TASK_FEATURES;

/// Shape and seed of a [`PriceNet`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriceNetConfig {
    /// Width of the two hidden layers.
    pub hidden: usize,
    /// Seed of the weight initialisation.
    pub seed: u64,
}

impl PriceNetConfig {
    /// Builds the network: hidden layers drawn from `seed`, the output layer zero, so
    /// that every price is 0 and the untrained policy is Nearest.
    pub fn init<B: Backend>(&self, device: &B::Device) -> PriceNet<B> {
        PriceNet::seeded(
            &mut ChaCha8Rng::seed_from_u64(self.seed),
            PRICE_INPUTS,
            self.hidden,
            device,
        )
    }
}

/// The price MLP in Burn, one network shared by every task:
/// `π = out(σ(hidden(σ(input(x)))))`. The price model's network reads a task's inputs
/// with σ = ReLU; AFGNet's price head reads `[task inputs || pooled embedding]` with
/// the network's activation.
#[derive(Module, Debug)]
pub struct PriceNet<B: Backend> {
    /// `inputs → h`.
    pub input: Linear<B>,
    /// `h → h`.
    pub hidden: Linear<B>,
    /// `h → 1`, zero at initialisation.
    pub output: Linear<B>,
}

impl<B: Backend> PriceNet<B> {
    /// A network of `inputs → hidden → hidden → 1`: the hidden layers drawn from
    /// `rng`, the output layer zero, so that every price starts at 0.
    pub(crate) fn seeded(
        rng: &mut ChaCha8Rng,
        inputs: usize,
        hidden: usize,
        device: &B::Device,
    ) -> Self {
        PriceNet {
            input: seeded_linear(rng, inputs, hidden, device),
            hidden: seeded_linear(rng, hidden, hidden, device),
            output: zero_linear(hidden, 1, device),
        }
    }

    /// Prices of a batch of tasks (the price model's network).
    ///
    /// # Shapes
    /// `inputs: [R, PRICE_INPUTS]` → `[R]`
    pub fn forward(&self, inputs: Tensor<B, 2>) -> Tensor<B, 1> {
        self.forward_parts(vec![inputs], Activation::Relu)
    }

    /// Prices of a batch of tasks whose inputs come in `parts`, side by side (their
    /// concatenation is never built), with `activation` after each hidden layer.
    ///
    /// # Shapes
    /// `parts: [R, w_k]` with `Σ w_k` the input width → `[R]`
    pub fn forward_parts(&self, parts: Vec<Tensor<B, 2>>, activation: Activation) -> Tensor<B, 1> {
        let x = activation.apply(linear_of_concat(&self.input, parts));
        let x = activation.apply(self.hidden.forward(x));
        let rows = x.dims()[0];
        self.output.forward(x).reshape([rows])
    }
}

/// A per-task MLP as plain matrices, for inference without Burn (the only form saved):
/// one score per task row — the price model's prices and the staffing model's worths.
///
/// # Examples
/// ```
/// use afg_graph::TASK_FEATURES;
/// use afg_learn::price::{TaskMlp, PriceNetConfig};
/// let config = PriceNetConfig { hidden: 16, seed: 0 };
/// let mlp = TaskMlp::from_burn(&config.init::<afg_learn::InferBackend>(&Default::default()));
/// let mut prices = vec![1.0; 5];
/// mlp.prices(&vec![0.5; 5 * TASK_FEATURES], &mut prices);
/// assert_eq!(prices, vec![0.0; 5]); // untrained: all prices 0 (Nearest)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskMlp {
    layers: [Dense; 3],
}

impl TaskMlp {
    /// Copies the weights of a Burn network.
    pub fn from_burn<B: Backend>(net: &PriceNet<B>) -> Self {
        TaskMlp {
            layers: [
                Dense::from_burn(&net.input),
                Dense::from_burn(&net.hidden),
                Dense::from_burn(&net.output),
            ],
        }
    }

    /// Builds the Burn network with these weights (to continue training).
    pub fn to_burn<B: Backend>(&self, device: &B::Device) -> PriceNet<B> {
        let linear = |d: &Dense| Linear {
            weight: Param::from_tensor(Tensor::from_data(
                TensorData::new(d.weight.clone(), [d.inputs, d.outputs]),
                device,
            )),
            bias: Some(Param::from_tensor(Tensor::from_data(
                TensorData::new(d.bias.clone(), [d.outputs]),
                device,
            ))),
        };
        PriceNet {
            input: linear(&self.layers[0]),
            hidden: linear(&self.layers[1]),
            output: linear(&self.layers[2]),
        }
    }

    /// Width of the hidden layers.
    pub fn hidden(&self) -> usize {
        self.layers[0].outputs
    }

    /// Whether the layer shapes are those of a price network of width `hidden`
    /// (checked when a file is loaded).
    pub fn has_shape(&self, hidden: usize) -> bool {
        self.has_layers(PRICE_INPUTS, hidden)
    }

    /// Whether the layers are `inputs → hidden → hidden → 1` with finite weights: the
    /// shape of any network of this form (the staffing model's too).
    pub(crate) fn has_layers(&self, inputs: usize, hidden: usize) -> bool {
        let shapes = [(inputs, hidden), (hidden, hidden), (hidden, 1)];
        self.layers.iter().zip(shapes).all(|(d, (i, o))| {
            d.inputs == i
                && d.outputs == o
                && d.weight.len() == i * o
                && d.bias.len() == o
                && d.weight.iter().chain(&d.bias).all(|w| w.is_finite())
        })
    }

    /// The network's output for each row of `inputs` (`[R, inputs]`) into `out` (`[R]`),
    /// with ReLU after each hidden layer.
    pub(crate) fn forward_rows(&self, inputs: &[f32], out: &mut [f32]) {
        let h = self.hidden();
        self.forward_rows_with(inputs, out, (&mut vec![0.0; h], &mut vec![0.0; h]));
    }

    /// [`TaskMlp::forward_rows`] with two `[h]` scratch rows.
    fn forward_rows_with(&self, inputs: &[f32], out: &mut [f32], rows: (&mut [f32], &mut [f32])) {
        let [first, hidden, output] = &self.layers;
        task_mlp(
            [first, hidden, output],
            inputs,
            None,
            Activation::Relu,
            rows,
            out,
        );
    }

    /// The price of every task from [`super::PriceState::features`] (`[M, TASK_FEATURES]`)
    /// into `prices` (`[M]`). Allocates its scratch rows; the crate's own rollouts, which
    /// ask at every step, reuse theirs.
    pub fn prices(&self, features: &[f32], prices: &mut [f32]) {
        self.prices_with(features, prices, &mut PriceScratch::default());
    }

    /// [`TaskMlp::prices`] with reused scratch rows: allocates only the first time.
    pub(crate) fn prices_with(
        &self,
        features: &[f32],
        prices: &mut [f32],
        scratch: &mut PriceScratch,
    ) {
        let h = self.hidden();
        let PriceScratch { inputs, a, b } = scratch;
        inputs.resize(2 * features.len(), 0.0);
        a.resize(h, 0.0);
        b.resize(h, 0.0);
        task_inputs(features, inputs);
        self.forward_rows_with(inputs, prices, (a, b));
    }
}

/// Scratch rows of [`TaskMlp::prices_with`]: the network inputs and two hidden rows.
#[derive(Clone, Debug, Default)]
pub(crate) struct PriceScratch {
    inputs: Vec<f32>,
    a: Vec<f32>,
    b: Vec<f32>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::InferBackend;
    use crate::dense::to_vec;

    #[test]
    fn plain_and_burn_forward_agree_and_round_trip() {
        let device = Default::default();
        let config = PriceNetConfig { hidden: 8, seed: 3 };
        let mut net = config.init::<InferBackend>(&device);
        // Give the output layer weights so the comparison is not 0 = 0.
        net.output = seeded_linear(&mut ChaCha8Rng::seed_from_u64(9), 8, 1, &device);
        let mlp = TaskMlp::from_burn(&net);
        let features: Vec<f32> = (0..3 * TASK_FEATURES)
            .map(|i| (i as f32 * 0.37).sin())
            .collect();
        let mut plain = vec![0.0; 3];
        mlp.prices(&features, &mut plain);
        let mut inputs = vec![0.0; 2 * features.len()];
        task_inputs(&features, &mut inputs);
        let x = Tensor::<InferBackend, 2>::from_data(
            TensorData::new(inputs, [3, PRICE_INPUTS]),
            &device,
        );
        let burn = to_vec(net.forward(x));
        for (p, q) in plain.iter().zip(&burn) {
            assert!((p - q).abs() < 1e-5, "{p} vs {q}");
        }
        assert!(plain.iter().any(|p| p.abs() > 1e-3));
        assert_eq!(
            TaskMlp::from_burn(&mlp.to_burn::<InferBackend>(&device)),
            mlp
        );
        assert!(mlp.has_shape(8) && !mlp.has_shape(16));
    }
}
