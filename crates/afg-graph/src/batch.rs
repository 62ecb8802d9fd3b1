//! Several allocation feature graphs packed into flat arrays, ready to become a few
//! large tensors: nodes of all graphs stacked, edges as (receiver, sender) lists with
//! global node indices, and per-graph pooling and acting-robot indices.

use afg_game::RobotId;

use crate::{AllocationState, PriceState, RobotGraph, TASK_FEATURES, Units, task_inputs};

/// A batch of graph states (one acting robot each), in flat row-major arrays.
///
/// # Examples
/// ```
/// use afg_game::{GeneratorConfig, RobotId};
/// use afg_graph::{AllocationState, GraphBatch, GraphKind, RobotGraph};
/// let inst = GeneratorConfig::paper(12, 3, 1).generate()?;
/// let graph = RobotGraph::build(inst.robots(), GraphKind::Knn { k: 4 }).unwrap();
/// let state = AllocationState::new(&inst, afg_graph::Units::Bounded);
/// let mut batch = GraphBatch::new(3, afg_graph::Units::Bounded);
/// batch.push(&graph, &state, RobotId(0));
/// batch.push(&graph, &state, RobotId(5));
/// assert_eq!((batch.num_graphs(), batch.num_nodes()), (2, 24));
/// assert_eq!(batch.actors, vec![0, 17]);
/// # Ok::<(), afg_game::GameError>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GraphBatch {
    /// Number of tasks M (feature width).
    pub num_tasks: usize,
    /// The units of every feature, gain and cost in the batch: a network checks that
    /// they are the ones it was trained in.
    pub units: Units,
    /// Robot features ν, `[nodes, M]`.
    pub nu: Vec<f32>,
    /// Task features μ, `[nodes, M]`.
    pub mu: Vec<f32>,
    /// Degree |N_i| of each node, `[nodes]`.
    pub degree: Vec<f32>,
    /// Receiving node i of each directed edge, `[edges]`.
    pub edge_receiver: Vec<u32>,
    /// Sending neighbour k of each directed edge, `[edges]`.
    pub edge_sender: Vec<u32>,
    /// Weight w_ik = d(i, k) of each edge in the state's edge unit
    /// ([`Units::edge_unit`](crate::Units::edge_unit)), `[edges]`.
    pub edge_weight: Vec<f32>,
    /// Graph of each node, `[nodes]`.
    pub node_graph: Vec<u32>,
    /// Node count of each graph, `[graphs]`.
    pub graph_size: Vec<f32>,
    /// Global node index of each graph's acting robot, `[graphs]`.
    pub actors: Vec<u32>,
    /// Action mask of each graph's acting robot, `[graphs, M]`.
    pub mask: Vec<bool>,
    /// Per graph, the actor's [`join_gain`](crate::join_gain) for each task, `[G × M]`.
    pub gain: Vec<f32>,
    /// Per graph, the actor's distance cost `β d(actor, j)` for each task, in the
    /// state's welfare unit ([`Units::welfare_unit`](crate::Units::welfare_unit)),
    /// `[G × M]`.
    pub cost: Vec<f32>,
    /// Per graph and task, the task's [`PriceState::features`] and the mean of all
    /// tasks' ([`task_inputs`]), `[G × M, 2 · TASK_FEATURES]`: what AFGNet's price
    /// head reads. Empty unless the batch was made by
    /// [`GraphBatch::with_task_summaries`].
    pub task_inputs: Vec<f32>,
    /// Whether [`GraphBatch::push`] fills [`GraphBatch::task_inputs`] (O(N·M) per
    /// graph, so only for the networks that read them).
    pub task_summaries: bool,
}

impl GraphBatch {
    /// An empty batch for instances with `num_tasks` tasks and states with features in
    /// `units`, without the tasks' summaries.
    pub fn new(num_tasks: usize, units: Units) -> Self {
        GraphBatch {
            num_tasks,
            units,
            ..Default::default()
        }
    }

    /// An empty batch that also packs every task's summaries
    /// ([`GraphBatch::task_inputs`]), for a network with a price head.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{GeneratorConfig, RobotId};
    /// use afg_graph::{AllocationState, GraphBatch, GraphKind, RobotGraph, TASK_FEATURES};
    /// let inst = GeneratorConfig::paper(12, 3, 1).generate()?;
    /// let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
    /// let state = AllocationState::new(&inst, afg_graph::Units::Bounded);
    /// let (mut plain, mut full) = (GraphBatch::new(3, afg_graph::Units::Bounded), GraphBatch::with_task_summaries(3, afg_graph::Units::Bounded));
    /// plain.push(&graph, &state, RobotId(0));
    /// full.push(&graph, &state, RobotId(0));
    /// assert!(plain.task_inputs.is_empty());
    /// assert_eq!(full.task_inputs.len(), 3 * 2 * TASK_FEATURES);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn with_task_summaries(num_tasks: usize, units: Units) -> Self {
        GraphBatch {
            task_summaries: true,
            ..GraphBatch::new(num_tasks, units)
        }
    }

    /// Number of graphs.
    pub fn num_graphs(&self) -> usize {
        self.actors.len()
    }

    /// Number of nodes over all graphs.
    pub fn num_nodes(&self) -> usize {
        self.degree.len()
    }

    /// Number of directed edges over all graphs.
    pub fn num_edges(&self) -> usize {
        self.edge_receiver.len()
    }

    /// Appends one graph in `state`, with `actor` about to act.
    ///
    /// # Panics
    /// If the state's task count or units differ from the batch's, or the graph was
    /// built for another number of robots.
    pub fn push(&mut self, graph: &RobotGraph, state: &AllocationState<'_>, actor: RobotId) {
        let inst = state.instance();
        assert_eq!(
            inst.num_tasks(),
            self.num_tasks,
            "every graph of a batch has the same M"
        );
        assert_eq!(
            state.units(),
            self.units,
            "a state in other units than the batch's"
        );
        assert_eq!(
            graph.num_nodes(),
            inst.num_robots(),
            "graph of another instance"
        );
        let offset = self.num_nodes() as u32;
        let g = self.num_graphs() as u32;
        let edge_unit = state.units().edge_unit(graph);
        for i in inst.robot_ids() {
            self.nu.extend(state.nu(i));
            self.mu.extend_from_slice(state.mu(i));
            self.degree.push(graph.degree(i) as f32);
            self.node_graph.push(g);
            for (&k, &w) in graph.neighbours(i).iter().zip(graph.weights(i)) {
                self.edge_receiver.push(offset + i.0);
                self.edge_sender.push(offset + k);
                self.edge_weight.push((w / edge_unit) as f32);
            }
        }
        self.graph_size.push(inst.num_robots() as f32);
        self.actors.push(offset + actor.0);
        self.mask.extend(state.action_mask(actor));
        self.gain.extend(state.gains(actor));
        let unit = state.units().welfare_unit(inst);
        self.cost
            .extend(inst.task_ids().map(|j| (inst.cost(actor, j) / unit) as f32));
        if self.task_summaries {
            let mut features = vec![0.0; inst.num_tasks() * TASK_FEATURES];
            PriceState::from_assignment(inst, state.assignment()).features(&mut features);
            let at = self.task_inputs.len();
            self.task_inputs.resize(at + 2 * features.len(), 0.0);
            task_inputs(&features, &mut self.task_inputs[at..]);
        }
    }
}
