//! The fast inference path: a trained AFGNet or S2V network exported from Burn into
//! plain row-major matrices, and greedy rollouts that do the per-step work with large
//! matrix products (faer) and keep everything that a step does not change.
//!
//! The Burn network stays the source of truth: [`FastPolicy::from_network`] copies its
//! weights, and the parity tests check that both paths give the same Q values and the
//! same actions on every step of full rollouts.
//!
//! # Complexity
//!
//! One network evaluation of AFGNet (N robots, width d, L layers) costs O(L·N·d²)
//! time; an exact rollout is N evaluations, O(L·N²·d²), and a block rollout N/B of
//! them. Memory is O(N·(d + M) + edges). Where that cost comes from:
//!
//! A robot's move changes its own ν (so the neighbour messages η of the robots around
//! it) and one column of μ for *every* robot, so every δ changes and a full pass is
//! needed for exact Q values. The pass does, per layer, one `[N, d] × [d, 2d]` product
//! (`δ [θ6a | θ5a]`, the weighted neighbour mean applied after the product) and one
//! `[N, d] × [d, d]` product (`σ(θ6 …) θ5b`): O(N·d²). Cached between passes:
//! - `σ(θ1 ν + b1)` as a table over the M + 1 possible ν;
//! - per layer, `θ6b η_i + b6`, recomputed only for the neighbours of robots that moved
//!   (η depends on the neighbours' ν and the edge weights only), all of a pass's at once
//!   with two matrix products;
//! - for S2V, the edge term `θ3 Σ_k relu(θ4 w_ik) + b3`, which never changes.
//!
//! μ is rebuilt from the assignment at each pass (O(N·M), negligible next to the
//! products), and the θ2 pre-activations are recomputed from it rather than shifted by
//! the rank-1 update `Δμ_ij θ2[j]`: the shift would save O(N·M·d) of an O(N·d²) pass
//! (under 3 % at M = 5, d = 64) while accumulating rounding drift over N steps.
//!
//! **Block rollout.** With block size B, one pass serves B consecutive robots: each
//! takes its greedy action on the Q values of the block's start state, while the
//! action mask (capacities) and the assignment stay exact. B = 1 is the exact rollout;
//! N/B passes replace N.
//!
//! The loops over the graph's edges live in `kernels` (vectorised at run time).
//! Nothing inside the step loop allocates.

use std::time::{Duration, Instant};

use afg_game::{Assignment, Instance, RobotId, TaskId};
use afg_graph::{
    PriceState, RobotGraph, TASK_FEATURES, Units, join_gain, task_inputs, write_task_column,
};
use burn::tensor::backend::Backend;

mod kernels;
mod net;
mod passes;

use net::{FastAfgLayer, FastAfgNet, FastNet, FastPriceHead, FastS2v, Head, one_hot_table};

use crate::LearnError;
use crate::dense::{Dense, side_by_side};
use crate::qnetwork::{NetworkConfig, QNetwork};
use crate::targets::masked_argmax;

/// A trained Q network in the form the fast rollout uses (see the module docs).
///
/// # Examples
/// ```
/// use afg_game::GeneratorConfig;
/// use afg_graph::{GraphKind, RobotGraph};
/// use afg_learn::{fast::FastPolicy, nets::NetworkConfig};
/// let config = NetworkConfig::afgnet(5, 0);
/// let network = config.init::<afg_learn::InferBackend>(&Default::default());
/// let fast = FastPolicy::from_network(&config, &network);
/// let inst = GeneratorConfig::paper(200, 5, 1).generate()?;
/// let graph = RobotGraph::build(inst.robots(), GraphKind::default())?;
/// let exact = fast.rollout(&inst, &graph, 1)?;
/// let blocked = fast.rollout(&inst, &graph, 20)?; // 10 passes instead of 200
/// assert!(exact.assignment.is_complete() && blocked.assignment.is_complete());
/// assert_eq!(blocked.passes, 10);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct FastPolicy {
    net: FastNet,
    head: Head,
    tasks: usize,
    hidden: usize,
    /// Add the actor's join gain to the Q values (AFGNet's `gain_residual`).
    gain_residual: bool,
    /// The units of the inputs.
    units: Units,
}

/// What a fast rollout returns.
#[derive(Clone, Debug)]
pub struct FastRolloutOutcome {
    /// The complete assignment.
    pub assignment: Assignment,
    /// Full network evaluations (⌈N / B⌉).
    pub passes: usize,
    /// Time spent in the network passes.
    pub network_time: Duration,
}

impl FastPolicy {
    /// Copies the weights of `network`, built from `config`.
    ///
    /// # Panics
    /// If `network` is not the kind of network `config` describes.
    pub fn from_network<B: Backend>(config: &NetworkConfig, network: &QNetwork<B>) -> Self {
        match (config, network) {
            (NetworkConfig::AfgNet(c), QNetwork::AfgNet(n)) => {
                let s = c.activation;
                let d = c.hidden;
                let layers = n
                    .layers
                    .iter()
                    .map(|l| {
                        let theta4 = Dense::from_burn(&l.theta4);
                        let theta3 = Dense::from_burn(&l.theta3);
                        let theta6 = Dense::from_burn(&l.theta6);
                        let theta5 = Dense::from_burn(&l.theta5);
                        FastAfgLayer {
                            edge_weight: theta4.row(0).to_vec(),
                            edge_task: theta4.rows_with_bias(1..theta4.inputs),
                            eta_message: theta3.rows_with_bias(0..d),
                            eta_degree: theta3.row(d).to_vec(),
                            eta_term: theta6.rows_with_bias(d..2 * d),
                            mix: side_by_side(&theta6.rows(0..d), &theta5.rows(0..d)),
                            inner: theta5.rows(d..2 * d),
                            next_bias: theta5.bias.clone(),
                        }
                    })
                    .collect();
                FastPolicy {
                    net: FastNet::AfgNet(FastAfgNet {
                        robot_table: one_hot_table(&Dense::from_burn(&n.theta1), |x| s.scalar(x)),
                        theta2: Dense::from_burn(&n.theta2),
                        layers,
                        price: n.price.as_ref().map(FastPriceHead::from_burn),
                    }),
                    head: Head::from_burn(&n.head, s),
                    tasks: c.tasks,
                    hidden: d,
                    gain_residual: c.gain_residual,
                    units: config.units(),
                }
            }
            (NetworkConfig::S2v(c), QNetwork::S2v(n)) => FastPolicy {
                net: FastNet::S2v(FastS2v {
                    robot_table: one_hot_table(&Dense::from_burn(&n.theta1), |x| x),
                    theta2: Dense::from_burn(&n.theta2),
                    theta3: Dense::from_burn(&n.theta3),
                    theta4: Dense::from_burn(&n.theta4),
                    iterations: c.iterations,
                }),
                head: Head::from_burn(&n.head, c.activation),
                tasks: c.tasks,
                hidden: c.hidden,
                gain_residual: false,
                units: config.units(),
            },
            _ => panic!("the network is not the kind its configuration describes"),
        }
    }

    /// Number of tasks M the network was built for.
    pub fn tasks(&self) -> usize {
        self.tasks
    }

    /// The units of the network's inputs (and of its Q values).
    pub fn units(&self) -> Units {
        self.units
    }

    /// Greedy rollout in index order with one network pass per block of `block`
    /// robots (`block = 1`: exact, one pass per robot).
    ///
    /// # Errors
    /// [`LearnError::InvalidAction`] if the instance's M differs from the network's or
    /// the graph belongs to another instance; [`LearnError::InvalidConfig`] for
    /// `block = 0`.
    pub fn rollout(
        &self,
        instance: &Instance,
        graph: &RobotGraph,
        block: usize,
    ) -> Result<FastRolloutOutcome, LearnError> {
        if block == 0 {
            return Err(LearnError::InvalidConfig(
                "block size must be at least 1".into(),
            ));
        }
        let mut run = FastRollout::new(self, instance, graph)?;
        let n = instance.num_robots();
        let mut q = vec![0.0f32; self.tasks];
        let mut mask = vec![false; self.tasks];
        let mut passes = 0;
        let mut network_time = Duration::ZERO;
        for start in (0..n).step_by(block) {
            let t = Instant::now();
            run.evaluate();
            network_time += t.elapsed();
            passes += 1;
            for robot in (start..(start + block).min(n)).map(|r| RobotId(r as u32)) {
                run.q_values(robot, &mut q);
                run.action_mask(robot, &mut mask);
                let task = masked_argmax(&q, &mask).ok_or_else(|| {
                    LearnError::InvalidAction(format!("no task has room for robot {robot}"))
                })?;
                run.assign(robot, TaskId(task as u32));
            }
        }
        Ok(FastRolloutOutcome {
            assignment: run.assignment,
            passes,
            network_time,
        })
    }
}

/// A rollout in progress on the fast path: the assignment, the cached terms and the
/// buffers of one pass. Drive it with [`FastRollout::evaluate`],
/// [`FastRollout::q_values`] and [`FastRollout::assign`], or let
/// [`FastPolicy::rollout`] do it.
#[derive(Debug)]
pub struct FastRollout<'a> {
    policy: &'a FastPolicy,
    instance: &'a Instance,
    graph: &'a RobotGraph,
    assignment: Assignment,
    /// The welfare unit of the gains ([`Units::welfare_unit`]).
    scale: f64,
    /// Edge weights are multiplied by this (1 / [`Units::edge_unit`]).
    inv_edge_unit: f32,
    /// Task features μ, `[N, M]`.
    mu: Vec<f32>,
    /// Node embeddings of the last pass, `[N, d]`.
    delta: Vec<f32>,
    /// `[N, 2d]` products.
    wide: Vec<f32>,
    /// `[N, d]` scratch.
    scratch: Vec<f32>,
    /// AFGNet: per layer, `θ6b η_i + b6` (`[N, d]` each). S2V: the edge term `[N, d]`.
    cached: Vec<Vec<f32>>,
    /// Robots whose ν changed since the last pass.
    moved: Vec<RobotId>,
    /// The neighbours of the robots in `moved`, whose cache the next pass refreshes.
    stale: Vec<RobotId>,
    /// Per robot, the pass at which its cache was last refreshed (dedupes `stale`).
    refreshed_at: Vec<usize>,
    passes: usize,
    /// `b_hidden + σ(θ7 pooled) W_hidden,pooled` of the last pass, `[d]`.
    head_state: Vec<f32>,
    /// `[d]` scratch vectors.
    vec_a: Vec<f32>,
    vec_b: Vec<f32>,
    /// With a price head: the tasks' summaries and the prices of the last pass.
    price: Option<PricePass<'a>>,
}

/// What a rollout of a network with a price head keeps between passes.
#[derive(Debug)]
struct PricePass<'a> {
    /// The tasks' summaries, kept up to date by [`FastRollout::assign`].
    state: PriceState<'a>,
    /// `[M, TASK_FEATURES]`.
    features: Vec<f32>,
    /// `[M, 2 · TASK_FEATURES]`.
    inputs: Vec<f32>,
    /// The pooled embedding's term of the head's first layer, `[d]`.
    pooled_term: Vec<f32>,
    /// The prices of the last pass, `[M]`.
    prices: Vec<f32>,
}

impl<'a> FastRollout<'a> {
    /// Starts a rollout on `instance` with every robot unassigned.
    ///
    /// # Errors
    /// [`LearnError::InvalidAction`] if M differs from the network's or the graph has
    /// another number of nodes.
    pub fn new(
        policy: &'a FastPolicy,
        instance: &'a Instance,
        graph: &'a RobotGraph,
    ) -> Result<Self, LearnError> {
        let (n, m, d) = (instance.num_robots(), instance.num_tasks(), policy.hidden);
        if m != policy.tasks {
            return Err(LearnError::InvalidAction(format!(
                "the network was built for M = {} tasks, the instance has {m}",
                policy.tasks
            )));
        }
        if graph.num_nodes() != n {
            return Err(LearnError::InvalidAction(format!(
                "the graph has {} nodes, the instance {n} robots",
                graph.num_nodes()
            )));
        }
        let mut run = FastRollout {
            policy,
            instance,
            graph,
            assignment: Assignment::unassigned(n, m),
            scale: policy.units.welfare_unit(instance),
            inv_edge_unit: (1.0 / policy.units.edge_unit(graph)) as f32,
            mu: vec![0.0; n * m],
            delta: vec![0.0; n * d],
            wide: vec![0.0; n * 2 * d],
            scratch: vec![0.0; n * d],
            cached: Vec::new(),
            moved: Vec::new(),
            stale: Vec::with_capacity(n),
            refreshed_at: vec![0; n],
            passes: 0,
            head_state: vec![0.0; d],
            vec_a: vec![0.0; d],
            vec_b: vec![0.0; d],
            price: matches!(&policy.net, FastNet::AfgNet(net) if net.price.is_some()).then(|| {
                PricePass {
                    state: PriceState::new(instance),
                    features: vec![0.0; m * TASK_FEATURES],
                    inputs: vec![0.0; 2 * m * TASK_FEATURES],
                    pooled_term: vec![0.0; d],
                    prices: vec![0.0; m],
                }
            }),
        };
        run.cached = match &policy.net {
            FastNet::AfgNet(net) => {
                let mut cached = vec![vec![0.0; n * d]; net.layers.len()];
                let everyone: Vec<RobotId> = instance.robot_ids().collect();
                run.eta_terms(net, &everyone, &mut cached);
                cached
            }
            FastNet::S2v(net) => vec![run.s2v_edge_term(net)],
        };
        Ok(run)
    }

    /// The assignment so far.
    pub fn assignment(&self) -> &Assignment {
        &self.assignment
    }

    /// Puts `robot` in `task` (the network is not re-evaluated until
    /// [`FastRollout::evaluate`]).
    ///
    /// # Panics
    /// If the task has no room for the robot.
    pub fn assign(&mut self, robot: RobotId, task: TaskId) {
        assert!(
            self.assignment.has_room(self.instance, robot, task),
            "task {task} is full for robot {robot}"
        );
        self.assignment.set(robot, Some(task));
        self.moved.push(robot);
        if let Some(price) = &mut self.price {
            price.state.assign(robot, task);
        }
    }

    /// Which tasks have room for `robot`, into `mask` (length M).
    pub fn action_mask(&self, robot: RobotId, mask: &mut [bool]) {
        for (j, ok) in mask.iter_mut().enumerate() {
            *ok = self
                .assignment
                .has_room(self.instance, robot, TaskId(j as u32));
        }
    }

    /// Evaluates the network on the current assignment (one full pass; see the module
    /// docs for what is cached).
    pub fn evaluate(&mut self) {
        self.passes += 1;
        let (n, m, d) = (
            self.instance.num_robots(),
            self.instance.num_tasks(),
            self.policy.hidden,
        );
        let policy = self.policy;
        match &policy.net {
            FastNet::AfgNet(net) => {
                let mut cached = std::mem::take(&mut self.cached);
                let mut stale = std::mem::take(&mut self.stale);
                for &a in &self.moved {
                    for &k in self.graph.neighbours(a) {
                        if self.refreshed_at[k as usize] != self.passes {
                            self.refreshed_at[k as usize] = self.passes;
                            stale.push(RobotId(k));
                        }
                    }
                }
                self.moved.clear();
                self.eta_terms(net, &stale, &mut cached);
                stale.clear();
                self.stale = stale;
                self.cached = cached;
                for j in self.instance.task_ids() {
                    write_task_column(
                        self.instance,
                        &self.assignment,
                        self.policy.units,
                        j,
                        &mut self.mu,
                    );
                }
                self.afgnet_pass(net, n, m, d);
            }
            FastNet::S2v(net) => {
                self.moved.clear();
                self.s2v_pass(net, n, d);
            }
        }
        self.head_pass(n, d);
        self.price_pass();
    }

    /// The prices of the current state, with a price head (after
    /// [`FastRollout::head_pass`], which leaves the pooled embedding in `vec_b`).
    fn price_pass(&mut self) {
        let (FastNet::AfgNet(net), Some(pass)) = (&self.policy.net, &mut self.price) else {
            return;
        };
        let head = net
            .price
            .as_ref()
            .expect("a price pass only with a price head");
        pass.state.features(&mut pass.features);
        task_inputs(&pass.features, &mut pass.inputs);
        head.input_pooled
            .apply_row(&self.vec_b, &mut pass.pooled_term);
        head.prices(
            &pass.inputs,
            &pass.pooled_term,
            self.policy.head.activation,
            (&mut self.vec_a, &mut self.scratch[..self.policy.hidden]),
            &mut pass.prices,
        );
    }

    /// Q values of `robot` acting in the state of the last [`FastRollout::evaluate`],
    /// into `q` (length M).
    pub fn q_values(&mut self, robot: RobotId, q: &mut [f32]) {
        let head = &self.policy.head;
        let d = self.policy.hidden;
        let s = head.activation;
        let row = &self.delta[robot.index() * d..(robot.index() + 1) * d];
        head.hidden_actor.apply_row(row, &mut self.vec_a);
        for (h, &g) in self.vec_a.iter_mut().zip(&self.head_state) {
            *h = s.scalar(*h + g);
        }
        head.output.apply_row(&self.vec_a, q);
        if let Some(pass) = &self.price {
            for (j, (q, &price)) in q.iter_mut().zip(&pass.prices).enumerate() {
                *q += price - (self.instance.cost(robot, TaskId(j as u32)) / self.scale) as f32;
            }
        }
        if self.policy.gain_residual {
            for (j, q) in q.iter_mut().enumerate() {
                *q += join_gain(
                    self.instance,
                    &self.assignment,
                    robot,
                    TaskId(j as u32),
                    self.scale,
                );
            }
        }
    }
}
