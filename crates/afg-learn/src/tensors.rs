//! A [`GraphBatch`] as Burn tensors, plus the two graph operations every model needs:
//! gathering neighbour rows and summing edge messages into their receivers.

use afg_graph::GraphBatch;
use burn::tensor::backend::Backend;
use burn::tensor::{IndexingUpdateOp, Int, Tensor, TensorData};

/// Tensors of a packed batch of graphs on one device.
///
/// Shapes use `V` for nodes over all graphs, `E` for directed edges, `G` for graphs
/// and `M` for tasks.
#[derive(Clone, Debug)]
pub struct GraphTensors<B: Backend> {
    /// The units of the batch's features ([`GraphBatch::units`]).
    pub units: afg_graph::Units,
    /// Robot features ν, `[V, M]`.
    pub nu: Tensor<B, 2>,
    /// Task features μ, `[V, M]`.
    pub mu: Tensor<B, 2>,
    /// Degree |N_i|, `[V, 1]`.
    pub degree: Tensor<B, 2>,
    /// `1 / max(|N_i|, 1)`, `[V, 1]`: turns neighbour sums into means.
    pub inv_degree: Tensor<B, 2>,
    /// Receiving node of each edge, `[E]`.
    pub receiver: Tensor<B, 1, Int>,
    /// Sending node of each edge, `[E]`.
    pub sender: Tensor<B, 1, Int>,
    /// Edge weight w_ik, `[E, 1]`.
    pub weight: Tensor<B, 2>,
    /// AFGNet's edge input `[w_ik || ν_k]` (weight, then the sender's robot
    /// features), `[E, 1 + M]`: built here rather than gathered on the device.
    pub edge_features: Tensor<B, 2>,
    /// Graph of each node, `[V]`.
    pub node_graph: Tensor<B, 1, Int>,
    /// `1 / N_g`, `[G, 1]`: turns per-graph sums into means.
    pub inv_graph_size: Tensor<B, 2>,
    /// Global index of each graph's acting robot, `[G]`.
    pub actors: Tensor<B, 1, Int>,
    /// The actor's join gain per task (`GraphBatch::gain`), `[G, M]`.
    pub gain: Tensor<B, 2>,
    /// The actor's distance cost per task (`GraphBatch::cost`), `[G, M]`.
    pub cost: Tensor<B, 2>,
    /// Each task's summaries (`GraphBatch::task_inputs`), `[G M, 2 · TASK_FEATURES]`.
    pub task_inputs: Tensor<B, 2>,
    /// Dense per-graph aggregation matrices, when every graph has the same N ≤
    /// [`DENSE_MAX_NODES`]: a batched matrix product then replaces gather + scatter.
    pub dense: Option<DenseAdjacency<B>>,
}

/// Largest N for which a batch of equal-sized graphs gets [`DenseAdjacency`] (its
/// memory is 2 G N² floats).
pub const DENSE_MAX_NODES: usize = 256;

/// Neighbour aggregation of G graphs of N nodes each as dense matrices.
#[derive(Clone, Debug)]
pub struct DenseAdjacency<B: Backend> {
    /// `[G, N, N]`, entry (i, k) = w_ik / |N_i| for neighbours, 0 otherwise.
    pub weighted_mean: Tensor<B, 3>,
    /// `[G, N, N]`, entry (i, k) = 1 for neighbours, 0 otherwise.
    pub adjacency: Tensor<B, 3>,
    /// Nodes per graph N.
    pub nodes: usize,
}

fn float2<B: Backend>(values: &[f32], cols: usize, device: &B::Device) -> Tensor<B, 2> {
    Tensor::from_data(
        TensorData::new(values.to_vec(), [values.len() / cols.max(1), cols]),
        device,
    )
}

fn int1<B: Backend>(values: &[u32], device: &B::Device) -> Tensor<B, 1, Int> {
    let v: Vec<i64> = values.iter().map(|&x| i64::from(x)).collect();
    Tensor::from_data(TensorData::new(v, [values.len()]), device)
}

impl<B: Backend> GraphTensors<B> {
    /// Stops a network from reading features in units it was not trained in: the
    /// numbers would be meaningful, and wrong.
    ///
    /// # Panics
    /// If the batch's units are not `units`.
    pub fn expect_units(&self, units: afg_graph::Units) {
        assert_eq!(
            self.units, units,
            "a batch with features in {:?} units fed to a network trained in {:?} units",
            self.units, units
        );
    }

    /// Uploads a batch, with dense aggregation matrices where they apply.
    pub fn new(batch: &GraphBatch, device: &B::Device) -> Self {
        let mut g = Self::sparse(batch, device);
        g.dense = dense_adjacency(batch, device);
        g
    }

    /// Uploads a batch using only the edge lists (gather + scatter aggregation).
    pub fn sparse(batch: &GraphBatch, device: &B::Device) -> Self {
        let m = batch.num_tasks;
        let inv_degree: Vec<f32> = batch.degree.iter().map(|&d| 1.0 / d.max(1.0)).collect();
        let inv_size: Vec<f32> = batch.graph_size.iter().map(|&n| 1.0 / n).collect();
        let mut edge_features = Vec::with_capacity(batch.num_edges() * (1 + m));
        for (&w, &k) in batch.edge_weight.iter().zip(&batch.edge_sender) {
            edge_features.push(w);
            edge_features.extend_from_slice(&batch.nu[k as usize * m..(k as usize + 1) * m]);
        }
        GraphTensors {
            units: batch.units,
            nu: float2(&batch.nu, m, device),
            mu: float2(&batch.mu, m, device),
            degree: float2(&batch.degree, 1, device),
            inv_degree: float2(&inv_degree, 1, device),
            receiver: int1(&batch.edge_receiver, device),
            sender: int1(&batch.edge_sender, device),
            weight: float2(&batch.edge_weight, 1, device),
            edge_features: float2(&edge_features, 1 + m, device),
            node_graph: int1(&batch.node_graph, device),
            inv_graph_size: float2(&inv_size, 1, device),
            actors: int1(&batch.actors, device),
            gain: float2(&batch.gain, m, device),
            cost: float2(&batch.cost, m, device),
            task_inputs: float2(&batch.task_inputs, 2 * afg_graph::TASK_FEATURES, device),
            dense: None,
        }
    }

    /// Number of nodes V.
    pub fn num_nodes(&self) -> usize {
        self.degree.dims()[0]
    }

    /// Number of graphs G.
    pub fn num_graphs(&self) -> usize {
        self.inv_graph_size.dims()[0]
    }

    /// Rows of the sending node of each edge.
    ///
    /// # Shapes
    /// `x: [V, D]` → `[E, D]`
    pub fn senders_of(&self, x: Tensor<B, 2>) -> Tensor<B, 2> {
        x.select(0, self.sender.clone())
    }

    /// Number of directed edges E.
    pub fn num_edges(&self) -> usize {
        self.receiver.dims()[0]
    }

    /// Mean over each node's neighbours of per-edge messages of width `d`, made by
    /// `messages` (not called when there are no edges: Burn's matmul rejects empty inputs).
    ///
    /// # Shapes
    /// `messages(): [E, d]` → `[V, d]`
    pub fn neighbour_mean(
        &self,
        d: usize,
        messages: impl FnOnce() -> Tensor<B, 2>,
    ) -> Tensor<B, 2> {
        self.neighbour_sum(d, messages) * self.inv_degree.clone()
    }

    /// Sum over each node's neighbours of per-edge messages of width `d` (see
    /// [`GraphTensors::neighbour_mean`]).
    ///
    /// # Shapes
    /// `messages(): [E, d]` → `[V, d]`
    pub fn neighbour_sum(&self, d: usize, messages: impl FnOnce() -> Tensor<B, 2>) -> Tensor<B, 2> {
        let zeros = Tensor::zeros([self.num_nodes(), d], &self.degree.device());
        if self.num_edges() == 0 {
            return zeros;
        }
        zeros.select_assign(0, self.receiver.clone(), messages(), IndexingUpdateOp::Add)
    }

    /// `mean_{k∈N_i} w_ik x_k` for every node.
    ///
    /// # Shapes
    /// `x: [V, d]` → `[V, d]`
    pub fn weighted_neighbour_mean(&self, x: Tensor<B, 2>) -> Tensor<B, 2> {
        match &self.dense {
            Some(dense) => dense.apply(&dense.weighted_mean, x),
            None => self.neighbour_mean(x.dims()[1], || self.senders_of(x) * self.weight.clone()),
        }
    }

    /// `sum_{k∈N_i} x_k` for every node.
    ///
    /// # Shapes
    /// `x: [V, d]` → `[V, d]`
    pub fn neighbour_node_sum(&self, x: Tensor<B, 2>) -> Tensor<B, 2> {
        match &self.dense {
            Some(dense) => dense.apply(&dense.adjacency, x),
            None => self.neighbour_sum(x.dims()[1], || self.senders_of(x)),
        }
    }

    /// Mean over each graph's nodes.
    ///
    /// # Shapes
    /// `x: [V, D]` → `[G, D]`
    pub fn graph_mean(&self, x: Tensor<B, 2>) -> Tensor<B, 2> {
        let d = x.dims()[1];
        let zeros = Tensor::zeros([self.num_graphs(), d], &x.device());
        zeros.select_assign(0, self.node_graph.clone(), x, IndexingUpdateOp::Add)
            * self.inv_graph_size.clone()
    }

    /// Rows of each graph's acting robot.
    ///
    /// # Shapes
    /// `x: [V, D]` → `[G, D]`
    pub fn actor_rows(&self, x: Tensor<B, 2>) -> Tensor<B, 2> {
        x.select(0, self.actors.clone())
    }
}

impl<B: Backend> DenseAdjacency<B> {
    /// Multiplies each graph's rows of `x` by its matrix in `matrix`.
    ///
    /// # Shapes
    /// `matrix: [G, N, N]`, `x: [G N, d]` → `[G N, d]`
    fn apply(&self, matrix: &Tensor<B, 3>, x: Tensor<B, 2>) -> Tensor<B, 2> {
        let [v, d] = x.dims();
        matrix
            .clone()
            .matmul(x.reshape([v / self.nodes, self.nodes, d]))
            .reshape([v, d])
    }
}

fn dense_adjacency<B: Backend>(
    batch: &GraphBatch,
    device: &B::Device,
) -> Option<DenseAdjacency<B>> {
    let n = *batch.graph_size.first()? as usize;
    if n > DENSE_MAX_NODES || batch.graph_size.iter().any(|&s| s as usize != n) {
        return None;
    }
    let g = batch.num_graphs();
    let mut weighted = vec![0.0f32; g * n * n];
    let mut adjacency = vec![0.0f32; g * n * n];
    for e in 0..batch.num_edges() {
        let (r, s) = (
            batch.edge_receiver[e] as usize,
            batch.edge_sender[e] as usize,
        );
        let (graph, i, k) = (r / n, r % n, s % n);
        let at = (graph * n + i) * n + k;
        weighted[at] = batch.edge_weight[e] / batch.degree[r];
        adjacency[at] = 1.0;
    }
    let tensor = |v: Vec<f32>| Tensor::from_data(TensorData::new(v, [g, n, n]), device);
    Some(DenseAdjacency {
        weighted_mean: tensor(weighted),
        adjacency: tensor(adjacency),
        nodes: n,
    })
}
