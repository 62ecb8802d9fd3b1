//! Linear layers as plain row-major matrices, for the inference paths that leave Burn
//! ([`crate::fast::FastPolicy`], [`crate::PricePolicy`]).

use std::ops::Range;

use burn::nn::Linear;
use burn::tensor::backend::Backend;
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use serde::{Deserialize, Serialize};

/// A linear layer as a row-major `[inputs, outputs]` matrix and a bias (`x W + b`,
/// Burn's convention).
///
/// # Shapes
/// `weight`: `[inputs, outputs]` (row-major), `bias`: `[outputs]`; applied to rows
/// `x`: `[rows, inputs]` → `[rows, outputs]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Dense {
    pub(crate) weight: Vec<f32>,
    pub(crate) bias: Vec<f32>,
    pub(crate) inputs: usize,
    pub(crate) outputs: usize,
}

pub(crate) fn to_vec<B: Backend, const D: usize>(t: burn::tensor::Tensor<B, D>) -> Vec<f32> {
    t.into_data()
        .convert::<f32>()
        .to_vec()
        .expect("float parameters convert to f32")
}

impl Dense {
    pub(crate) fn from_burn<B: Backend>(linear: &Linear<B>) -> Self {
        let [inputs, outputs] = linear.weight.val().dims();
        let bias = linear
            .bias
            .as_ref()
            .map_or_else(|| vec![0.0; outputs], |b| to_vec(b.val()));
        Dense {
            weight: to_vec(linear.weight.val()),
            bias,
            inputs,
            outputs,
        }
    }

    /// The rows `rows` of the weight (the part of the layer that reads those inputs),
    /// with a zero bias.
    pub(crate) fn rows(&self, rows: Range<usize>) -> Dense {
        Dense {
            weight: self.weight[rows.start * self.outputs..rows.end * self.outputs].to_vec(),
            bias: vec![0.0; self.outputs],
            inputs: rows.len(),
            outputs: self.outputs,
        }
    }

    /// The rows `rows` of the weight with the layer's own bias: the part that reads
    /// those inputs, plus the constant term.
    pub(crate) fn rows_with_bias(&self, rows: Range<usize>) -> Dense {
        Dense {
            bias: self.bias.clone(),
            ..self.rows(rows)
        }
    }

    /// Row `r` of the weight: the layer's response to input `r`.
    pub(crate) fn row(&self, r: usize) -> &[f32] {
        &self.weight[r * self.outputs..(r + 1) * self.outputs]
    }

    /// `out = x W` for a row-major `[rows, inputs]` x, into `out` (`[rows, outputs]`,
    /// any row stride via `MatMut`), replacing or adding.
    pub(crate) fn product_into(&self, x: MatRef<'_, f32>, out: MatMut<'_, f32>, accum: Accum) {
        let w = MatRef::from_row_major_slice(&self.weight, self.inputs, self.outputs);
        matmul(out, accum, x, w, 1.0, Par::Seq);
    }

    /// `out = b + x W` for one input row (a vector–matrix product).
    pub(crate) fn apply_row(&self, x: &[f32], out: &mut [f32]) {
        out.copy_from_slice(&self.bias);
        for (&xi, w) in x.iter().zip(self.weight.chunks_exact(self.outputs)) {
            if xi != 0.0 {
                for (o, &wi) in out.iter_mut().zip(w) {
                    *o += xi * wi;
                }
            }
        }
    }
}

/// A three-layer MLP shared by every task, `π = out(σ(hidden(σ(first(x) + shift))))`,
/// applied to each row of `inputs` (`[M, first.inputs]`) into `prices` (`[M]`); `shift`
/// (`[h]`, zero when `None`) is a per-state term added before the first activation, and
/// `a` and `b` are `[h]` scratch rows. The price model's MLP and AFGNet's price head.
pub(crate) fn task_mlp(
    [first, hidden, output]: [&Dense; 3],
    inputs: &[f32],
    shift: Option<&[f32]>,
    activation: crate::layers::Activation,
    (a, b): (&mut [f32], &mut [f32]),
    prices: &mut [f32],
) {
    let mut out = [0.0f32];
    for (x, price) in inputs.chunks_exact(first.inputs).zip(prices) {
        first.apply_row(x, a);
        if let Some(shift) = shift {
            a.iter_mut().zip(shift).for_each(|(h, &s)| *h += s);
        }
        a.iter_mut().for_each(|h| *h = activation.scalar(*h));
        hidden.apply_row(a, b);
        b.iter_mut().for_each(|h| *h = activation.scalar(*h));
        output.apply_row(b, &mut out);
        *price = out[0];
    }
}

/// Two weight matrices side by side: `[A | B]`, `[inputs, a + b]`.
pub(crate) fn side_by_side(a: &Dense, b: &Dense) -> Dense {
    assert_eq!(a.inputs, b.inputs);
    let mut weight = Vec::with_capacity(a.inputs * (a.outputs + b.outputs));
    for r in 0..a.inputs {
        weight.extend_from_slice(a.row(r));
        weight.extend_from_slice(b.row(r));
    }
    Dense {
        weight,
        bias: vec![0.0; a.outputs + b.outputs],
        inputs: a.inputs,
        outputs: a.outputs + b.outputs,
    }
}
