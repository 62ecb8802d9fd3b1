//! The transportation problem, solved exactly by successive shortest paths with potentials
//! (dense Dijkstra: the graphs here are complete bipartite).

/// A transportation problem being solved: what is left to ship, the flows, the potentials.
struct Transport<'a> {
    cost: &'a [Vec<f64>],
    supply: Vec<usize>,
    demand: Vec<usize>,
    flow: Vec<Vec<usize>>,
    pot_l: Vec<f64>,
    pot_r: Vec<f64>,
}

/// Shortest reduced distances from the left nodes with supply, and the paths' last steps.
struct Paths {
    dist_l: Vec<f64>,
    dist_r: Vec<f64>,
    prev_l: Vec<usize>,
    prev_r: Vec<usize>,
}

/// The least cost of shipping `supply[a]` units from each left node and `demand[b]` into
/// each right node (equal totals), `cost[a][b]` per unit (infinite: no arc).
pub(crate) fn min_cost(supply: &[usize], demand: &[usize], cost: &[Vec<f64>]) -> f64 {
    let mut t = Transport {
        cost,
        supply: supply.to_vec(),
        demand: demand.to_vec(),
        flow: vec![vec![0; demand.len()]; supply.len()],
        pot_l: vec![0.0; supply.len()],
        pot_r: vec![0.0; demand.len()],
    };
    let mut total = 0.0;
    loop {
        let paths = t.shortest_paths();
        let Some(sink) = (0..demand.len())
            .filter(|&b| t.demand[b] > 0 && paths.dist_r[b].is_finite())
            .min_by(|&a, &b| paths.dist_r[a].total_cmp(&paths.dist_r[b]))
        else {
            return total;
        };
        t.raise_potentials(&paths, paths.dist_r[sink]);
        total += t.augment(&paths, sink);
    }
}

impl Transport<'_> {
    /// Dijkstra over reduced costs: forward arcs left → right, backward arcs where flow runs.
    fn shortest_paths(&self) -> Paths {
        let (l, r) = (self.supply.len(), self.demand.len());
        let mut p = Paths {
            dist_l: self
                .supply
                .iter()
                .map(|&s| if s > 0 { 0.0 } else { f64::INFINITY })
                .collect(),
            dist_r: vec![f64::INFINITY; r],
            prev_l: vec![usize::MAX; l],
            prev_r: vec![usize::MAX; r],
        };
        let (mut done_l, mut done_r) = (vec![false; l], vec![false; r]);
        loop {
            let next_l = (0..l)
                .filter(|&a| !done_l[a])
                .min_by(|&a, &b| p.dist_l[a].total_cmp(&p.dist_l[b]));
            let next_r = (0..r)
                .filter(|&b| !done_r[b])
                .min_by(|&a, &b| p.dist_r[a].total_cmp(&p.dist_r[b]));
            let left_first = match (next_l, next_r) {
                (Some(a), Some(b)) => p.dist_l[a] <= p.dist_r[b],
                (other, _) => other.is_some(),
            };
            if left_first {
                let a = next_l.expect("chosen");
                if !p.dist_l[a].is_finite() {
                    return p;
                }
                done_l[a] = true;
                for b in (0..r).filter(|&b| !done_r[b] && self.cost[a][b].is_finite()) {
                    let d = p.dist_l[a] + self.cost[a][b] + self.pot_l[a] - self.pot_r[b];
                    if d < p.dist_r[b] {
                        p.dist_r[b] = d;
                        p.prev_r[b] = a;
                    }
                }
            } else {
                let Some(b) = next_r.filter(|&b| p.dist_r[b].is_finite()) else {
                    return p;
                };
                done_r[b] = true;
                for a in (0..l).filter(|&a| !done_l[a] && self.flow[a][b] > 0) {
                    let d = p.dist_r[b] - self.cost[a][b] + self.pot_r[b] - self.pot_l[a];
                    if d < p.dist_l[a] {
                        p.dist_l[a] = d;
                        p.prev_l[a] = b;
                    }
                }
            }
        }
    }

    /// Keeps reduced costs non-negative: raise potentials by the distances (capped at the sink's).
    fn raise_potentials(&mut self, p: &Paths, cap: f64) {
        for (pot, d) in self.pot_l.iter_mut().zip(&p.dist_l) {
            *pot += d.min(cap);
        }
        for (pot, d) in self.pot_r.iter_mut().zip(&p.dist_r) {
            *pot += d.min(cap);
        }
    }

    /// Ships as much as the path to `sink` carries; returns the cost added.
    fn augment(&mut self, p: &Paths, sink: usize) -> f64 {
        let mut amount = self.demand[sink];
        let mut b = sink;
        loop {
            let a = p.prev_r[b];
            if p.prev_l[a] == usize::MAX {
                amount = amount.min(self.supply[a]);
                break;
            }
            b = p.prev_l[a];
            amount = amount.min(self.flow[a][b]);
        }
        let mut added = 0.0;
        self.demand[sink] -= amount;
        let mut b = sink;
        loop {
            let a = p.prev_r[b];
            self.flow[a][b] += amount;
            added += amount as f64 * self.cost[a][b];
            if p.prev_l[a] == usize::MAX {
                self.supply[a] -= amount;
                return added;
            }
            b = p.prev_l[a];
            self.flow[a][b] -= amount;
            added -= amount as f64 * self.cost[a][b];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::min_cost;

    #[test]
    fn a_hand_problem_and_one_that_needs_a_flow_pushed_back() {
        // Two sources of 1, two sinks of 1: the cheap diagonal costs 1 + 1.
        assert_eq!(
            min_cost(&[1, 1], &[1, 1], &[vec![1.0, 5.0], vec![5.0, 1.0]]),
            2.0
        );
        // Greedy takes a→x (1), then b must go to x too and cannot: b→x forbidden pushes a
        // back to y. Optimum a→y (2) + b→x (2) = 4, while greedy would be stuck.
        let inf = f64::INFINITY;
        assert_eq!(
            min_cost(&[1, 1], &[1, 1], &[vec![1.0, 2.0], vec![2.0, inf]]),
            4.0
        );
        // Units: 3 from one source into two sinks of 1 and 2.
        assert_eq!(min_cost(&[3], &[1, 2], &[vec![1.5, 0.5]]), 2.5);
    }
}
