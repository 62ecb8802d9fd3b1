//! A trained network's weights, split by the inputs each part reads.

use burn::tensor::backend::Backend;

use crate::dense::{Dense, task_mlp};
use crate::layers::Activation;
use crate::layers::QHead;
use crate::price::PRICE_INPUTS;
use crate::price::PriceNet;

/// The Q head: `Q = out(σ(hidden [σ(θ7 pooled) || δ_actor]))`.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Head {
    pub(super) theta7: Dense,
    /// `hidden` rows for `σ(θ7 pooled)`, with hidden's bias.
    pub(super) hidden_pooled: Dense,
    /// `hidden` rows for the actor's embedding.
    pub(super) hidden_actor: Dense,
    pub(super) output: Dense,
    pub(super) activation: Activation,
}

impl Head {
    pub(super) fn from_burn<B: Backend>(head: &QHead<B>, activation: Activation) -> Self {
        let hidden = Dense::from_burn(&head.hidden);
        let d = hidden.outputs;
        Head {
            theta7: Dense::from_burn(&head.theta7),
            hidden_pooled: hidden.rows_with_bias(0..d),
            hidden_actor: hidden.rows(d..2 * d),
            output: Dense::from_burn(&head.output),
            activation,
        }
    }
}

/// AFGNet's price head: `π_j = out(σ(hidden(σ(input [x_j || pooled]))))`.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct FastPriceHead {
    /// `input`'s rows for a task's inputs, with its bias.
    pub(super) input_task: Dense,
    /// `input`'s rows for the pooled embedding.
    pub(super) input_pooled: Dense,
    pub(super) hidden: Dense,
    pub(super) output: Dense,
}

impl FastPriceHead {
    pub(super) fn from_burn<B: Backend>(head: &PriceNet<B>) -> Self {
        let input = Dense::from_burn(&head.input);
        FastPriceHead {
            input_task: input.rows_with_bias(0..PRICE_INPUTS),
            input_pooled: input.rows(PRICE_INPUTS..input.inputs),
            hidden: Dense::from_burn(&head.hidden),
            output: Dense::from_burn(&head.output),
        }
    }

    /// Every task's price into `prices` from the tasks' inputs (`[M, PRICE_INPUTS]`)
    /// and the pooled embedding's contribution `pooled_term` (`input_pooled` applied
    /// to it); `scratch` is two `[d]` rows.
    pub(super) fn prices(
        &self,
        inputs: &[f32],
        pooled_term: &[f32],
        activation: Activation,
        scratch: (&mut [f32], &mut [f32]),
        prices: &mut [f32],
    ) {
        task_mlp(
            [&self.input_task, &self.hidden, &self.output],
            inputs,
            Some(pooled_term),
            activation,
            scratch,
            prices,
        );
    }
}

/// AFGNet's layer ℓ, split by the inputs each part reads.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct FastAfgLayer {
    /// θ4's row for the edge weight w_ik.
    pub(super) edge_weight: Vec<f32>,
    /// θ4's rows for ν_k, with θ4's bias.
    pub(super) edge_task: Dense,
    /// θ3's rows for the mean message, with θ3's bias.
    pub(super) eta_message: Dense,
    /// θ3's row for |N_i|.
    pub(super) eta_degree: Vec<f32>,
    /// θ6's rows for η, with θ6's bias: the cached term `θ6b η_i + b6`.
    pub(super) eta_term: Dense,
    /// `[θ6a | θ5a]`: θ6's rows for the weighted neighbour mean, θ5's rows for δ.
    pub(super) mix: Dense,
    /// θ5's rows for `σ(θ6 …)`.
    pub(super) inner: Dense,
    /// θ5's bias.
    pub(super) next_bias: Vec<f32>,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct FastAfgNet {
    /// `σ(θ1 ν + b1)` for ν = 0 (row 0) and ν = e_j (row 1 + j).
    pub(super) robot_table: Vec<f32>,
    /// θ2 with its bias.
    pub(super) theta2: Dense,
    pub(super) layers: Vec<FastAfgLayer>,
    /// The price head, when the network has one.
    pub(super) price: Option<FastPriceHead>,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) struct FastS2v {
    /// `θ1 ν + b1` for ν = 0 (row 0) and ν = e_j (row 1 + j).
    pub(super) robot_table: Vec<f32>,
    pub(super) theta2: Dense,
    pub(super) theta3: Dense,
    pub(super) theta4: Dense,
    pub(super) iterations: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub(super) enum FastNet {
    AfgNet(FastAfgNet),
    S2v(FastS2v),
}

/// `table[0] = f(b)`, `table[1 + j] = f(b + W[j])`: a layer's output for every one-hot
/// input.
pub(super) fn one_hot_table(layer: &Dense, f: impl Fn(f32) -> f32) -> Vec<f32> {
    let mut table: Vec<f32> = layer.bias.iter().map(|&b| f(b)).collect();
    for j in 0..layer.inputs {
        table.extend(
            layer
                .row(j)
                .iter()
                .zip(&layer.bias)
                .map(|(&w, &b)| f(b + w)),
        );
    }
    table
}
