//! The "plain" AFGNet of the project's first Burn notes, kept as the reference that
//! `bench-models` measures our training step against: every node's neighbours padded
//! to the batch's largest degree, gathered with `select`, reshaped to `[V, D, ·]` and
//! summed over the slots — no dense per-graph path. It reads the parameters of an
//! [`AfgNet`] and computes the same Q values (tested below).

use afg_graph::GraphBatch;
use afg_learn::nets::{Activation, AfgNet, GraphTensors};
use burn::tensor::backend::Backend;
use burn::tensor::{Int, Tensor, TensorData};

/// A batch with padded neighbour slots.
pub struct PaddedGraph<B: Backend> {
    /// Node features, degrees, pooling and actors (edge lists unused).
    base: GraphTensors<B>,
    /// Neighbour of each slot, `[V · D]` (a padding slot names the node itself).
    index: Tensor<B, 1, Int>,
    /// Edge weight of each slot, 0 for padding, `[V · D, 1]`.
    weight: Tensor<B, 2>,
    /// 1 for a real neighbour, 0 for padding, `[V · D, 1]`.
    mask: Tensor<B, 2>,
    slots: usize,
}

impl<B: Backend> PaddedGraph<B> {
    /// Uploads `batch` with its neighbour lists padded to the largest degree.
    pub fn new(batch: &GraphBatch, device: &B::Device) -> Self {
        let v = batch.num_nodes();
        let mut lists: Vec<Vec<(u32, f32)>> = vec![Vec::new(); v];
        for e in 0..batch.num_edges() {
            lists[batch.edge_receiver[e] as usize]
                .push((batch.edge_sender[e], batch.edge_weight[e]));
        }
        let slots = lists.iter().map(Vec::len).max().unwrap_or(0).max(1);
        let (mut index, mut weight, mut mask) = (Vec::new(), Vec::new(), Vec::new());
        for (i, list) in lists.iter().enumerate() {
            for s in 0..slots {
                let (k, w, m) = list
                    .get(s)
                    .map_or((i as i64, 0.0, 0.0), |&(k, w)| (i64::from(k), w, 1.0));
                index.push(k);
                weight.push(w);
                mask.push(m);
            }
        }
        let column = |x: Vec<f32>| Tensor::from_data(TensorData::new(x, [v * slots, 1]), device);
        PaddedGraph {
            base: GraphTensors::sparse(batch, device),
            index: Tensor::from_data(TensorData::new(index, [v * slots]), device),
            weight: column(weight),
            mask: column(mask),
            slots,
        }
    }

    /// `Σ_slots x[slot]` per node, divided by the degree: `[V · D, d]` → `[V, d]`.
    fn slot_mean(&self, x: Tensor<B, 2>) -> Tensor<B, 2> {
        let (v, d) = (self.base.num_nodes(), x.dims()[1]);
        x.reshape([v, self.slots, d]).sum_dim(1).reshape([v, d]) * self.base.inv_degree.clone()
    }
}

/// AFGNet's Q values (eqs. 4–9) with padded gathers; σ = `activation`.
pub fn forward<B: Backend>(
    net: &AfgNet<B>,
    activation: Activation,
    g: &PaddedGraph<B>,
) -> Tensor<B, 2> {
    let s = activation;
    let b = &g.base;
    let mut delta =
        s.apply(net.theta1.forward(b.nu.clone())) + s.apply(net.theta2.forward(b.mu.clone()));
    let edge_input = Tensor::cat(
        vec![g.weight.clone(), b.nu.clone().select(0, g.index.clone())],
        1,
    );
    for layer in &net.layers {
        let messages =
            g.slot_mean(s.apply(layer.theta4.forward(edge_input.clone())) * g.mask.clone());
        let eta = s.apply(
            layer
                .theta3
                .forward(Tensor::cat(vec![messages, b.degree.clone()], 1)),
        );
        let weighted = g.slot_mean(delta.clone().select(0, g.index.clone()) * g.weight.clone());
        let inner = s.apply(layer.theta6.forward(Tensor::cat(vec![weighted, eta], 1)));
        delta = s.apply(layer.theta5.forward(Tensor::cat(vec![delta, inner], 1)));
    }
    net.head
        .forward(b.graph_mean(delta.clone()), b.actor_rows(delta))
}

#[cfg(test)]
mod tests {
    use super::*;
    use afg_learn::{
        InferBackend,
        nets::{NetworkConfig, QNetwork},
    };

    #[test]
    fn the_plain_model_computes_our_q_values() {
        let device = Default::default();
        for n in [20, 60] {
            let batch = super::super::random_batch(n, 8).unwrap();
            let net = NetworkConfig::afgnet(5, 0).init::<InferBackend>(&device);
            let QNetwork::AfgNet(afgnet) = &net else {
                unreachable!("an AFGNet configuration")
            };
            let ours: Vec<f32> = net
                .forward(&GraphTensors::new(&batch, &device))
                .into_data()
                .to_vec()
                .unwrap();
            let plain: Vec<f32> =
                forward(afgnet, Activation::Relu, &PaddedGraph::new(&batch, &device))
                    .into_data()
                    .to_vec()
                    .unwrap();
            assert_eq!(ours.len(), plain.len());
            let gap = ours
                .iter()
                .zip(&plain)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max);
            assert!(gap < 1e-4, "N = {n}: {gap}");
            assert!(
                ours.iter().any(|q| q.abs() > 1e-3),
                "Q values must not all vanish"
            );
        }
    }
}
