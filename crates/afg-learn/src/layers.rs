//! Building blocks shared by the networks: seeded linear layers, the activation σ and
//! the Q head.

use burn::module::{Module, Param};
use burn::nn::Linear;
use burn::tensor::activation::{leaky_relu, relu, tanh};
use burn::tensor::backend::Backend;
use burn::tensor::{Tensor, TensorData};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The nonlinearity σ (the paper leaves it open; ReLU by default).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Activation {
    /// max(0, x).
    #[default]
    Relu,
    /// max(0.01 x, x).
    LeakyRelu,
    /// tanh(x).
    Tanh,
}

impl Activation {
    /// Applies σ elementwise.
    ///
    /// # Shapes
    /// Any `[d_1, …, d_D]` in, the same shape out.
    pub fn apply<B: Backend, const D: usize>(self, x: Tensor<B, D>) -> Tensor<B, D> {
        match self {
            Activation::Relu => relu(x),
            Activation::LeakyRelu => leaky_relu(x, 0.01),
            Activation::Tanh => tanh(x),
        }
    }

    /// σ on one value, as [`Activation::apply`] computes it element-wise.
    ///
    /// # Examples
    /// ```
    /// use afg_learn::nets::Activation;
    /// assert_eq!(Activation::Relu.scalar(-2.0), 0.0);
    /// assert_eq!(Activation::LeakyRelu.scalar(-2.0), -0.02);
    /// assert_eq!(Activation::Tanh.scalar(0.0), 0.0);
    /// ```
    #[inline]
    pub fn scalar(self, x: f32) -> f32 {
        match self {
            Activation::Relu => x.max(0.0),
            Activation::LeakyRelu => {
                if x >= 0.0 {
                    x
                } else {
                    0.01 * x
                }
            }
            Activation::Tanh => x.tanh(),
        }
    }
}

/// A linear layer `[.., d_in] → [.., d_out]` with weights and bias drawn uniformly from
/// ±1/√d_in by `rng` (Burn's default scheme, but reproducible from our own seed rather
/// than the backend's global generator).
pub fn seeded_linear<B: Backend>(
    rng: &mut ChaCha8Rng,
    d_in: usize,
    d_out: usize,
    device: &B::Device,
) -> Linear<B> {
    let bound = 1.0 / (d_in as f32).sqrt();
    let mut draw =
        |len: usize| -> Vec<f32> { (0..len).map(|_| rng.random_range(-bound..bound)).collect() };
    let weight = Tensor::from_data(TensorData::new(draw(d_in * d_out), [d_in, d_out]), device);
    let bias = Tensor::from_data(TensorData::new(draw(d_out), [d_out]), device);
    Linear {
        weight: Param::from_tensor(weight),
        bias: Some(Param::from_tensor(bias)),
    }
}

/// A linear layer `[.., d_in] → [.., d_out]` whose weights and bias are all zero: an
/// output layer that makes its network start at exactly 0.
pub fn zero_linear<B: Backend>(d_in: usize, d_out: usize, device: &B::Device) -> Linear<B> {
    let zeros = |shape: Vec<usize>| {
        let len = shape.iter().product();
        TensorData::new(vec![0.0f32; len], shape)
    };
    Linear {
        weight: Param::from_tensor(Tensor::from_data(zeros(vec![d_in, d_out]), device)),
        bias: Some(Param::from_tensor(Tensor::from_data(
            zeros(vec![d_out]),
            device,
        ))),
    }
}

/// `linear` applied to the concatenation of `parts` along the feature axis, without
/// building the concatenation: each part meets its own rows of the weight. (Same
/// values as `linear.forward(Tensor::cat(parts, 1))`; the copy, and its gradient's
/// copy back, were a tenth of a training step.)
///
/// # Shapes
/// `parts: [[R, d_1], .., [R, d_k]]` with `Σ d_i = d_in` → `[R, d_out]`
///
/// # Examples
/// ```
/// use afg_learn::{InferBackend, nets::linear_of_concat};
/// use burn::nn::LinearConfig;
/// use burn::tensor::{Tensor, Tolerance};
///
/// let device = Default::default();
/// let linear = LinearConfig::new(3, 2).init::<InferBackend>(&device);
/// let a = Tensor::<InferBackend, 2>::from_floats([[1.0, 2.0], [3.0, 4.0]], &device);
/// let b = Tensor::<InferBackend, 2>::from_floats([[5.0], [6.0]], &device);
/// let joined = linear.forward(Tensor::cat(vec![a.clone(), b.clone()], 1));
/// linear_of_concat(&linear, vec![a, b])
///     .into_data()
///     .assert_approx_eq::<f32>(&joined.into_data(), Tolerance::default());
/// ```
pub fn linear_of_concat<B: Backend>(linear: &Linear<B>, parts: Vec<Tensor<B, 2>>) -> Tensor<B, 2> {
    let weight = linear.weight.val();
    let mut offset = 0;
    let mut sum: Option<Tensor<B, 2>> = None;
    for part in parts {
        let width = part.dims()[1];
        let term = part.matmul(weight.clone().narrow(0, offset, width));
        offset += width;
        sum = Some(match sum {
            Some(s) => s + term,
            None => term,
        });
    }
    let sum = sum.expect("at least one part");
    match &linear.bias {
        Some(bias) => sum + bias.val().unsqueeze(),
        None => sum,
    }
}

/// The Q head of both networks: graph embedding and acting-robot embedding in,
/// M action values out.
///
/// `s_t = [σ(θ7 pooled) || actor]` (paper eq. 9), then `Q = W2 σ(W1 s_t)`.
#[derive(Module, Debug)]
pub struct QHead<B: Backend> {
    /// θ7: `d → d`, applied to the pooled embedding.
    pub theta7: Linear<B>,
    /// First layer of the MLP: `2d → d`.
    pub hidden: Linear<B>,
    /// Output layer: `d → M`.
    pub output: Linear<B>,
    #[module(skip)]
    activation: Activation,
}

impl<B: Backend> QHead<B> {
    /// A head for embeddings of width `d` and `tasks` actions.
    pub fn new(
        rng: &mut ChaCha8Rng,
        d: usize,
        tasks: usize,
        activation: Activation,
        device: &B::Device,
    ) -> Self {
        QHead {
            theta7: seeded_linear(rng, d, d, device),
            hidden: seeded_linear(rng, 2 * d, d, device),
            output: seeded_linear(rng, d, tasks, device),
            activation,
        }
    }

    /// Q values.
    ///
    /// # Shapes
    /// - `pooled`: `[G, d]`, the mean node embedding of each graph
    /// - `actor`: `[G, d]`, the acting robot's embedding
    /// - output: `[G, M]`
    pub fn forward(&self, pooled: Tensor<B, 2>, actor: Tensor<B, 2>) -> Tensor<B, 2> {
        let s = self.activation;
        let state = vec![s.apply(self.theta7.forward(pooled)), actor];
        self.output
            .forward(s.apply(linear_of_concat(&self.hidden, state)))
    }
}
