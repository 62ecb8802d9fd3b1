//! The shortest paths that route each unit of imbalance: Dijkstra over the dense task
//! graph, from the side of the imbalance with fewer nodes, and the augment along the
//! path found.

use super::*;

impl Flow {
    /// Dijkstra with reduced costs between a node with excess and the nearest node on
    /// the other side of the imbalance: forward, from the node with most excess along
    /// the edges to the nearest node short of units; or `backward`, from the node most
    /// short of units against the edges (the labels are then distances to it) to the
    /// nearest node with excess. Updates the potentials (keeping every reduced cost
    /// non-negative and the path's zero) and returns the node where the search ended;
    /// `via` leads from it back to the start (forward) or on to the start (backward).
    pub(super) fn search(&mut self, backward: bool) -> usize {
        let m = self.level.m();
        let t = sink(m);
        // One start, the node with the largest imbalance (searching from all of them
        // would settle every one at distance 0 first).
        let start = if backward {
            (0..=m).min_by_key(|&u| (self.excess[u], u))
        } else {
            (0..=m).max_by_key(|&u| (self.excess[u], Reverse(u)))
        };
        self.start_search(start.expect("a problem has nodes"));
        let end = loop {
            let u = self.settle_nearest();
            let found = if backward {
                self.excess[u] > 0
            } else {
                self.excess[u] < 0
            };
            if found {
                break u;
            }
            match (backward, u == t) {
                (false, true) => self.relax_from_sink(),
                (false, false) => self.relax_from_task(u),
                (true, true) => self.relax_into_sink(),
                (true, false) => self.relax_into_task(u),
            }
        };
        let (reach, sign) = (self.dist[end], if backward { -1.0 } else { 1.0 });
        for (p, &d) in self.potential.iter_mut().zip(&self.dist) {
            *p += sign * d.min(reach);
        }
        end
    }

    /// Every label infinite and unsettled but `start`'s, at 0.
    fn start_search(&mut self, start: usize) {
        self.dist.fill(f64::INFINITY);
        self.done.fill(false);
        self.dist[start] = 0.0;
        self.via[start] = SOURCE;
    }

    /// Settles and returns the nearest unsettled node, the lowest index among equals.
    /// The graph is dense (an edge between every two tasks), so a scan of the M + 1
    /// labels finds it rather than a heap.
    fn settle_nearest(&mut self) -> usize {
        let mut u = None;
        let mut nearest = f64::INFINITY;
        for (v, (&d, &done)) in self.dist.iter().zip(&self.done).enumerate() {
            if !done && d < nearest {
                (u, nearest) = (Some(v), d);
            }
        }
        let u = u.expect("the other side of the imbalance is reachable");
        self.done[u] = true;
        u
    }

    fn relax(&mut self, to: usize, from: usize, reduced: f64) {
        // Rounding can leave a tight edge a hair below zero.
        let d = self.dist[from] + reduced.max(0.0);
        if d < self.dist[to] {
            self.dist[to] = d;
            self.via[to] = from as u32;
        }
    }

    fn relax_from_task(&mut self, j: usize) {
        let m = self.level.m();
        let (here, from) = (self.dist[j], self.potential[j]);
        // A missing edge has an infinite key and never improves a distance; a settled
        // node is nearer than `here` and is not improved either.
        let keys = self.movers.keys(j);
        let (dist, via) = (&mut self.dist[..m], &mut self.via[..m]);
        for (k, (&key, &price)) in keys.iter().zip(&self.potential[..m]).enumerate() {
            let d = here + (key + from - price).max(0.0);
            if d < dist[k] {
                dist[k] = d;
                via[k] = j as u32;
            }
        }
        let t = sink(m);
        if !self.done[t] && self.bought[j] < self.level.capacity(j) {
            let cost = -self.level.marginal(j, self.bought[j] + 1);
            self.relax(t, j, cost + self.potential[j] - self.potential[t]);
        }
    }

    fn relax_from_sink(&mut self) {
        let m = self.level.m();
        for j in 0..m {
            if !self.done[j] && self.bought[j] > 0 {
                let cost = self.level.marginal(j, self.bought[j]);
                self.relax(
                    j,
                    sink(m),
                    cost + self.potential[sink(m)] - self.potential[j],
                );
            }
        }
    }

    /// The edges into task `v`: shifts from every task, and its count going down (from
    /// the sink).
    fn relax_into_task(&mut self, v: usize) {
        let m = self.level.m();
        let (here, to) = (self.dist[v], self.potential[v]);
        for u in 0..m {
            let d = here + (self.movers.keys(u)[v] + self.potential[u] - to).max(0.0);
            if d < self.dist[u] {
                self.dist[u] = d;
                self.via[u] = v as u32;
            }
        }
        let t = sink(m);
        if !self.done[t] && self.bought[v] > 0 {
            let cost = self.level.marginal(v, self.bought[v]);
            self.relax(t, v, cost + self.potential[t] - to);
        }
    }

    /// The edges into the sink: every task's count going up.
    fn relax_into_sink(&mut self) {
        let m = self.level.m();
        for u in 0..m {
            if !self.done[u] && self.bought[u] < self.level.capacity(u) {
                let cost = -self.level.marginal(u, self.bought[u] + 1);
                self.relax(
                    u,
                    sink(m),
                    cost + self.potential[u] - self.potential[sink(m)],
                );
            }
        }
    }

    /// One unit along the edge from node `from` to node `to`.
    fn step(&mut self, from: usize, to: usize) {
        let t = sink(self.level.m());
        if to == t {
            self.bought[from] += 1;
        } else if from == t {
            self.bought[to] -= 1;
        } else {
            let robot = self.movers.robot(from, to);
            self.place(robot as usize, from, to);
        }
    }

    /// Sends one unit along the last search's path, which `via` walks from `end` to the
    /// start: against the unit's way after a forward search (`end` is where it goes),
    /// along it after a backward one (`end` is where it comes from). The path's pairs of
    /// tasks are distinct, so each shift moves the mover the search saw, or one at the
    /// same key.
    pub(super) fn augment(&mut self, end: usize, backward: bool) {
        let mut at = end;
        while self.via[at] != SOURCE {
            let next = self.via[at] as usize;
            if backward {
                self.step(at, next);
            } else {
                self.step(next, at);
            }
            at = next;
        }
        let (source, target) = if backward { (end, at) } else { (at, end) };
        self.excess[source] -= 1;
        self.excess[target] += 1;
    }
}
