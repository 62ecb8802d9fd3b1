//! The fast rollout's two neighbourhood loops, written so that the accumulators stay
//! in registers ([`LANES`] columns at a time) and compiled for the widest vector
//! instructions the CPU has, chosen at run time (`pulp`). Each output element sees the
//! same floating-point operations in the same order as a plain scalar loop (Rust never
//! fuses a multiply and an add on its own), so the results do not depend on the CPU.

use afg_game::{Assignment, RobotId};
use afg_graph::RobotGraph;

use super::net::FastAfgLayer;
use crate::layers::Activation;

/// Columns accumulated at once.
const LANES: usize = 16;

/// A loop nest to run with σ as a concrete function (so that it vectorises).
trait Kernel {
    fn activation(&self) -> Activation;
    fn run(self, s: impl Fn(f32) -> f32);
}

/// A [`Kernel`] as a `pulp` operation: `with_simd` and the kernel are inlined into a
/// function compiled for the detected instruction set.
struct Vectorised<K>(K);

impl<K: Kernel> pulp::WithSimd for Vectorised<K> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let kernel = self.0;
        match kernel.activation() {
            Activation::Relu => kernel.run(|x| Activation::Relu.scalar(x)),
            Activation::LeakyRelu => kernel.run(|x| Activation::LeakyRelu.scalar(x)),
            Activation::Tanh => kernel.run(|x| Activation::Tanh.scalar(x)),
        }
    }
}

fn vectorised(kernel: impl Kernel) {
    pulp::Arch::new().dispatch(Vectorised(kernel));
}

/// What the weighted neighbour mean of one AFGNet layer reads (eqs. 6–7).
pub(super) struct NeighbourMean<'a> {
    pub(super) graph: &'a RobotGraph,
    /// Multiplies every edge weight.
    pub(super) inv_edge_unit: f32,
    /// Row k's first `d` entries are `δ_k θ6a`; rows are `stride` apart.
    pub(super) rows: &'a [f32],
    pub(super) stride: usize,
    /// `θ6b η_i + b6`, `[N, d]`.
    pub(super) cached: &'a [f32],
    pub(super) activation: Activation,
}

impl NeighbourMean<'_> {
    /// `out_i = σ(mean_k w_ik (δ_k θ6a) + θ6b η_i + b6)` for every robot, into `out`
    /// (`[N, d]`).
    pub(super) fn run(&self, d: usize, out: &mut [f32]) {
        vectorised((self, d, out));
    }

    #[inline(always)]
    fn run_with(&self, s: impl Fn(f32) -> f32, d: usize, out: &mut [f32]) {
        let full = d / LANES * LANES;
        for (i, (acc, extra)) in out
            .chunks_exact_mut(d)
            .zip(self.cached.chunks_exact(d))
            .enumerate()
        {
            for c0 in (0..full).step_by(LANES) {
                self.columns::<LANES>(&s, RobotId(i as u32), c0, acc, extra);
            }
            for c0 in full..d {
                self.columns::<1>(&s, RobotId(i as u32), c0, acc, extra);
            }
        }
    }

    /// Columns `c0..c0 + W` of robot `i`'s row.
    #[inline(always)]
    fn columns<const W: usize>(
        &self,
        s: &impl Fn(f32) -> f32,
        i: RobotId,
        c0: usize,
        acc: &mut [f32],
        extra: &[f32],
    ) {
        let neighbours = self.graph.neighbours(i);
        let mut a = [0.0f32; W];
        for (&k, &w) in neighbours.iter().zip(self.graph.weights(i)) {
            let w = w as f32 * self.inv_edge_unit;
            let start = k as usize * self.stride + c0;
            let row = &self.rows[start..start + W];
            for l in 0..W {
                a[l] += row[l] * w;
            }
        }
        let inv_degree = 1.0 / neighbours.len().max(1) as f32;
        for l in 0..W {
            acc[c0 + l] = s(a[l] * inv_degree + extra[c0 + l]);
        }
    }
}

/// What the edge messages of one AFGNet layer read (eq. 5).
pub(super) struct EdgeMessages<'a> {
    pub(super) graph: &'a RobotGraph,
    pub(super) assignment: &'a Assignment,
    /// Multiplies every edge weight.
    pub(super) inv_edge_unit: f32,
    pub(super) layer: &'a FastAfgLayer,
    pub(super) activation: Activation,
}

impl EdgeMessages<'_> {
    /// `mean_k σ(θ4 [w_ik || ν_k])` for each robot of `robots`, row by row into `out`
    /// (`[robots.len(), d]`).
    pub(super) fn run(&self, robots: &[RobotId], d: usize, out: &mut [f32]) {
        vectorised((self, robots, d, out));
    }

    #[inline(always)]
    fn run_with(&self, s: impl Fn(f32) -> f32, robots: &[RobotId], d: usize, out: &mut [f32]) {
        let full = d / LANES * LANES;
        for (message, &i) in out.chunks_exact_mut(d).zip(robots) {
            for c0 in (0..full).step_by(LANES) {
                self.columns::<LANES>(&s, i, c0, message);
            }
            for c0 in full..d {
                self.columns::<1>(&s, i, c0, message);
            }
        }
    }

    /// Columns `c0..c0 + W` of robot `i`'s message.
    #[inline(always)]
    fn columns<const W: usize>(
        &self,
        s: &impl Fn(f32) -> f32,
        i: RobotId,
        c0: usize,
        message: &mut [f32],
    ) {
        let layer = self.layer;
        let edge = &layer.edge_weight[c0..c0 + W];
        let base = &layer.edge_task.bias[c0..c0 + W];
        let neighbours = self.graph.neighbours(i);
        let mut a = [0.0f32; W];
        for (&k, &w) in neighbours.iter().zip(self.graph.weights(i)) {
            let w = w as f32 * self.inv_edge_unit;
            match self.assignment.task_of(RobotId(k)) {
                Some(j) => {
                    let row = &layer.edge_task.row(j.index())[c0..c0 + W];
                    for l in 0..W {
                        a[l] += s(w * edge[l] + row[l] + base[l]);
                    }
                }
                None => {
                    for l in 0..W {
                        a[l] += s(w * edge[l] + base[l]);
                    }
                }
            }
        }
        let inv_degree = 1.0 / neighbours.len().max(1) as f32;
        for l in 0..W {
            message[c0 + l] = a[l] * inv_degree;
        }
    }
}

impl Kernel for (&NeighbourMean<'_>, usize, &mut [f32]) {
    fn activation(&self) -> Activation {
        self.0.activation
    }

    #[inline(always)]
    fn run(self, s: impl Fn(f32) -> f32) {
        self.0.run_with(s, self.1, self.2);
    }
}

impl Kernel for (&EdgeMessages<'_>, &[RobotId], usize, &mut [f32]) {
    fn activation(&self) -> Activation {
        self.0.activation
    }

    #[inline(always)]
    fn run(self, s: impl Fn(f32) -> f32) {
        self.0.run_with(s, self.1, self.2, self.3);
    }
}

#[cfg(test)]
mod tests {
    use afg_game::GeneratorConfig;
    use afg_graph::GraphKind;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// The weighted neighbour mean as a plain loop, one column at a time.
    fn plain_mean(m: &NeighbourMean<'_>, d: usize, n: usize) -> Vec<f32> {
        let mut out = vec![0.0; n * d];
        for i in 0..n {
            let robot = RobotId(i as u32);
            let neighbours = m.graph.neighbours(robot);
            for c in 0..d {
                let mut a = 0.0f32;
                for (&k, &w) in neighbours.iter().zip(m.graph.weights(robot)) {
                    a += m.rows[k as usize * m.stride + c] * (w as f32 * m.inv_edge_unit);
                }
                let inv_degree = 1.0 / neighbours.len().max(1) as f32;
                out[i * d + c] = m.activation.scalar(a * inv_degree + m.cached[i * d + c]);
            }
        }
        out
    }

    #[test]
    fn the_vectorised_neighbour_mean_is_bit_for_bit_the_plain_loop() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        // d = 37: two full blocks of 16 and five single columns.
        for (n, d) in [(50, 37), (120, 16), (30, 5)] {
            let inst = GeneratorConfig::paper(n, 5, n as u64).generate().unwrap();
            let graph = RobotGraph::build(inst.robots(), GraphKind::default()).unwrap();
            let stride = 2 * d;
            let rows: Vec<f32> = (0..n * stride)
                .map(|_| rng.random_range(-1.0..1.0))
                .collect();
            let cached: Vec<f32> = (0..n * d).map(|_| rng.random_range(-1.0..1.0)).collect();
            for activation in [Activation::Relu, Activation::LeakyRelu, Activation::Tanh] {
                let mean = NeighbourMean {
                    graph: &graph,
                    inv_edge_unit: 3.7,
                    rows: &rows,
                    stride,
                    cached: &cached,
                    activation,
                };
                let mut out = vec![0.0; n * d];
                mean.run(d, &mut out);
                let plain = plain_mean(&mean, d, n);
                assert!(
                    out.iter()
                        .zip(&plain)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "N = {n}, d = {d}, {activation:?}"
                );
            }
        }
    }
}
