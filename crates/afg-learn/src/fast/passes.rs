//! One network pass of a fast rollout: AFGNet or S2V layers, then the head.

use afg_game::RobotId;
use faer::{Accum, MatMut, MatRef};

use super::FastRollout;
use super::kernels::{EdgeMessages, NeighbourMean};
use super::net::{FastAfgNet, FastS2v};

impl FastRollout<'_> {
    pub(super) fn task_index(&self, robot: usize) -> usize {
        self.assignment
            .task_of(RobotId(robot as u32))
            .map_or(0, |j| 1 + j.index())
    }

    /// Refreshes `θ6b η_i + b6` (eq. 5) of every robot in `robots`, in every layer:
    /// the neighbour messages robot by robot, then two matrix products for all of them.
    /// Uses `scratch` and `wide` as work space (the next pass overwrites them).
    pub(super) fn eta_terms(
        &mut self,
        net: &FastAfgNet,
        robots: &[RobotId],
        cached: &mut [Vec<f32>],
    ) {
        let d = self.policy.hidden;
        let r = robots.len();
        if r == 0 {
            return;
        }
        let s = self.policy.head.activation;
        for (layer, cache) in net.layers.iter().zip(cached.iter_mut()) {
            // mean_k σ(θ4 [w_ik || ν_k]), one row per robot
            EdgeMessages {
                graph: self.graph,
                assignment: &self.assignment,
                inv_edge_unit: self.inv_edge_unit,
                layer,
                activation: s,
            }
            .run(robots, d, &mut self.scratch[..r * d]);
            // η = σ(θ3 [message || |N_i|])
            let (eta, term) = self.wide.split_at_mut(r * d);
            layer.eta_message.product_into(
                MatRef::from_row_major_slice(&self.scratch[..r * d], r, d),
                MatMut::from_row_major_slice_mut(eta, r, d),
                Accum::Replace,
            );
            for (row, &i) in eta.chunks_exact_mut(d).zip(robots) {
                let degree = self.graph.neighbours(i).len() as f32;
                for ((e, &b), &wd) in row
                    .iter_mut()
                    .zip(&layer.eta_message.bias)
                    .zip(&layer.eta_degree)
                {
                    *e = s.scalar(*e + b + degree * wd);
                }
            }
            // θ6b η + b6, into the robots' rows of the cache
            let term = &mut term[..r * d];
            layer.eta_term.product_into(
                MatRef::from_row_major_slice(eta, r, d),
                MatMut::from_row_major_slice_mut(term, r, d),
                Accum::Replace,
            );
            for (row, &i) in term.chunks_exact(d).zip(robots) {
                let out = &mut cache[i.index() * d..(i.index() + 1) * d];
                for ((o, &t), &b) in out.iter_mut().zip(row).zip(&layer.eta_term.bias) {
                    *o = t + b;
                }
            }
        }
    }

    pub(super) fn afgnet_pass(&mut self, net: &FastAfgNet, n: usize, m: usize, d: usize) {
        let s = self.policy.head.activation;
        // eq. 4: δ_i = σ(θ1 ν_i) + σ(θ2 μ_i)
        for i in 0..n {
            let t = self.task_index(i);
            let own = &net.robot_table[t * d..(t + 1) * d];
            let out = &mut self.delta[i * d..(i + 1) * d];
            net.theta2.apply_row(&self.mu[i * m..(i + 1) * m], out);
            for (o, &r) in out.iter_mut().zip(own) {
                *o = s.scalar(*o) + r;
            }
        }
        for (layer, cache) in net.layers.iter().zip(&self.cached) {
            // wide = δ [θ6a | θ5a]
            layer.mix.product_into(
                MatRef::from_row_major_slice(&self.delta, n, d),
                MatMut::from_row_major_slice_mut(&mut self.wide, n, 2 * d),
                Accum::Replace,
            );
            // inner_i = σ(mean_k w_ik (δ_k θ6a) + θ6b η_i + b6)    (eqs. 6–7)
            NeighbourMean {
                graph: self.graph,
                inv_edge_unit: self.inv_edge_unit,
                rows: &self.wide,
                stride: 2 * d,
                cached: cache,
                activation: s,
            }
            .run(d, &mut self.scratch);
            // wide[:, d..] += inner θ5b;  δ' = σ(wide[:, d..] + b5)     (eq. 8)
            layer.inner.product_into(
                MatRef::from_row_major_slice(&self.scratch, n, d),
                MatMut::from_row_major_slice_mut(&mut self.wide, n, 2 * d).subcols_mut(d, d),
                Accum::Add,
            );
            for i in 0..n {
                let pre = &self.wide[i * 2 * d + d..(i + 1) * 2 * d];
                for ((o, &p), &b) in self.delta[i * d..(i + 1) * d]
                    .iter_mut()
                    .zip(pre)
                    .zip(&layer.next_bias)
                {
                    *o = s.scalar(p + b);
                }
            }
        }
    }

    /// S2V's state-independent edge term `θ3 Σ_k relu(θ4 w_ik) + b3`, `[N, d]`.
    pub(super) fn s2v_edge_term(&mut self, net: &FastS2v) -> Vec<f32> {
        let d = self.policy.hidden;
        let n = self.instance.num_robots();
        let mut out = vec![0.0; n * d];
        for i in self.instance.robot_ids() {
            self.vec_a.fill(0.0);
            for &w in self.graph.weights(i) {
                let w = w as f32 * self.inv_edge_unit;
                for c in 0..d {
                    self.vec_a[c] += (w * net.theta4.weight[c] + net.theta4.bias[c]).max(0.0);
                }
            }
            net.theta3
                .apply_row(&self.vec_a, &mut out[i.index() * d..(i.index() + 1) * d]);
        }
        out
    }

    pub(super) fn s2v_pass(&mut self, net: &FastS2v, n: usize, d: usize) {
        // μ⁰ = 0;  μ^{t+1}_i = relu(θ1 ν_i + edge_i + θ2 Σ_{k ∈ N(i)} μ^t_k + b2)
        self.delta.fill(0.0);
        for _ in 0..net.iterations {
            for i in 0..n {
                let acc = &mut self.scratch[i * d..(i + 1) * d];
                acc.fill(0.0);
                for &k in self.graph.neighbours(RobotId(i as u32)) {
                    let row = &self.delta[k as usize * d..(k as usize + 1) * d];
                    for (a, &x) in acc.iter_mut().zip(row) {
                        *a += x;
                    }
                }
            }
            let wide = &mut self.wide[..n * d];
            net.theta2.product_into(
                MatRef::from_row_major_slice(&self.scratch, n, d),
                MatMut::from_row_major_slice_mut(wide, n, d),
                Accum::Replace,
            );
            for i in 0..n {
                let t = self.task_index(i);
                let own = &net.robot_table[t * d..(t + 1) * d];
                let edge = &self.cached[0][i * d..(i + 1) * d];
                for c in 0..d {
                    self.delta[i * d + c] =
                        (own[c] + edge[c] + self.wide[i * d + c] + net.theta2.bias[c]).max(0.0);
                }
            }
        }
    }

    /// Mean pooling and the pooled half of the head (eq. 9).
    pub(super) fn head_pass(&mut self, n: usize, d: usize) {
        let head = &self.policy.head;
        let s = head.activation;
        self.vec_b.fill(0.0);
        for row in self.delta.chunks_exact(d) {
            for (p, &x) in self.vec_b.iter_mut().zip(row) {
                *p += x;
            }
        }
        let inv_n = 1.0 / n as f32;
        for p in &mut self.vec_b {
            *p *= inv_n;
        }
        head.theta7.apply_row(&self.vec_b, &mut self.vec_a);
        for x in &mut self.vec_a {
            *x = s.scalar(*x);
        }
        head.hidden_pooled
            .apply_row(&self.vec_a, &mut self.head_state);
    }
}
