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
/// each right node (equal totals), `cost[a][b]` per unit (infinite: no arc), and the
/// flows that cost it.
pub(crate) fn min_cost(
    supply: &[usize],
    demand: &[usize],
    cost: &[Vec<f64>],
) -> (f64, Vec<Vec<usize>>) {
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
            return (total, t.flow);
        };
        t.raise_potentials(&paths, paths.dist_r[sink]);
        total += t.augment(&paths, sink);
    }
}

/// A lower bound on [`min_cost`] where, among the first `shared` nodes of each side (left
/// `a` and right `a` one place), no two that `cuttable` names ship to each other both ways:
/// `x[a][b] + x[b][a] <= min(supply[a], supply[b])` for each such pair. The pairs' limits
/// are priced into the costs (a Lagrangian relaxation), and the prices set by `rounds`
/// subgradient steps (Polyak's, towards a tenth above the best value, halved after three
/// rounds without a better one); every round's value is a bound, and the best is
/// returned (never below `min_cost`'s, which is round 0).
pub(crate) fn min_cost_one_way(
    supply: &[usize],
    demand: &[usize],
    cost: &[Vec<f64>],
    shared: usize,
    cuttable: impl Fn(usize, usize) -> bool,
    rounds: usize,
) -> f64 {
    let limit = |a: usize, b: usize| supply[a].min(supply[b]) as f64;
    let pairs: Vec<(usize, usize)> = (0..shared)
        .flat_map(|a| (a + 1..shared).map(move |b| (a, b)))
        .filter(|&(a, b)| cuttable(a, b) && cost[a][b].is_finite() && limit(a, b) > 0.0)
        .collect();
    let mut price = vec![0.0; pairs.len()];
    let mut priced = cost.to_vec();
    let (mut best, mut step_scale, mut stalled) = (f64::NEG_INFINITY, 1.0, 0);
    for _ in 0..=rounds {
        let (shipped, flow) = min_cost(supply, demand, &priced);
        let value = shipped - price.iter().sum::<f64>();
        if value - best > 1e-9 * value.abs() {
            (best, stalled) = (value, 0);
        } else {
            stalled += 1;
            if stalled >= 3 {
                (step_scale, stalled) = (step_scale / 2.0, 0);
            }
        }
        // How far each pair's flow both ways goes over its limit (as a share of it).
        let over: Vec<f64> = pairs
            .iter()
            .zip(&price)
            .map(|(&(a, b), &p)| {
                let g = (flow[a][b] + flow[b][a]) as f64 / limit(a, b) - 1.0;
                if p > 0.0 || g > 0.0 { g } else { 0.0 }
            })
            .collect();
        let norm: f64 = over.iter().map(|g| g * g).sum();
        if norm == 0.0 {
            break;
        }
        let step = step_scale * 0.1 * best.abs().max(1e-9) / norm;
        for (((a, b), p), g) in pairs.iter().zip(&mut price).zip(&over) {
            *p = (*p + step * g).max(0.0);
            priced[*a][*b] = cost[*a][*b] + *p / limit(*a, *b);
            priced[*b][*a] = cost[*b][*a] + *p / limit(*a, *b);
        }
    }
    best
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
    use super::{min_cost, min_cost_one_way};

    #[test]
    fn a_hand_problem_and_one_that_needs_a_flow_pushed_back() {
        // Two sources of 1, two sinks of 1: the cheap diagonal costs 1 + 1.
        assert_eq!(
            min_cost(&[1, 1], &[1, 1], &[vec![1.0, 5.0], vec![5.0, 1.0]]),
            (2.0, vec![vec![1, 0], vec![0, 1]])
        );
        // Greedy takes a→x (1), then b must go to x too and cannot: b→x forbidden pushes a
        // back to y. Optimum a→y (2) + b→x (2) = 4, while greedy would be stuck.
        let inf = f64::INFINITY;
        assert_eq!(
            min_cost(&[1, 1], &[1, 1], &[vec![1.0, 2.0], vec![2.0, inf]]),
            (4.0, vec![vec![0, 1], vec![1, 0]])
        );
        // Units: 3 from one source into two sinks of 1 and 2.
        assert_eq!(
            min_cost(&[3], &[1, 2], &[vec![1.5, 0.5]]),
            (2.5, vec![vec![1, 2]])
        );
    }

    /// Tasks a and b (one robot each) beside each other, far from the one robot's start
    /// and home: shipping a → b and b → a costs 2, but one robot must go out to one, on
    /// to the other and home: 10 + 1 + 10. Priced, the one-way limit finds that 21 (the
    /// linear relaxation's value too), and never goes above it.
    #[test]
    fn the_one_way_limit_between_two_tasks_closes_their_short_cycle() {
        let inf = f64::INFINITY;
        // Left: a, b, the start; right: a, b, the home.
        let cost = [
            vec![inf, 1.0, 10.0],
            vec![1.0, inf, 10.0],
            vec![10.0, 10.0, 0.0],
        ];
        let (supply, demand) = ([1, 1, 1], [1, 1, 1]);
        assert_eq!(min_cost(&supply, &demand, &cost).0, 2.0);
        let one_way = |rounds| min_cost_one_way(&supply, &demand, &cost, 2, |_, _| true, rounds);
        assert_eq!(one_way(0), 2.0);
        let priced = one_way(200);
        assert!((20.9..=21.0 + 1e-9).contains(&priced), "{priced}");
        // A pair left out of the limit keeps its cycle.
        let uncut = min_cost_one_way(&supply, &demand, &cost, 2, |_, _| false, 200);
        assert_eq!(uncut, 2.0);
    }
}
