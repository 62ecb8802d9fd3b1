//! The robot communication graph: k-nearest-neighbour (symmetrised), radius-disk or
//! complete, stored as compressed neighbour lists with distances as edge weights.

use afg_game::{Point, RobotId};
use serde::{Deserialize, Serialize};

use crate::GraphError;

/// How robots are linked.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "kind")]
pub enum GraphKind {
    /// Each robot links to its k nearest robots; the union of both directions is kept
    /// (the default, k = 10). Ties are broken by robot index.
    Knn {
        /// Neighbours per robot before symmetrisation.
        k: usize,
    },
    /// Robots within `radius` of each other are linked.
    Radius {
        /// Link distance.
        radius: f64,
    },
    /// Every pair is linked (O(N²) edges: small N only).
    Complete,
}

impl Default for GraphKind {
    fn default() -> Self {
        GraphKind::Knn { k: 10 }
    }
}

/// An undirected graph over robots, no self loops, each edge weighted by the
/// Euclidean distance `w_ik = d(i, k)`. Neighbour lists are sorted by robot index.
///
/// # Examples
/// ```
/// use afg_game::{Point, RobotId};
/// use afg_graph::{GraphKind, RobotGraph};
/// let pts = [Point::new(0.0, 0.0), Point::new(1.0, 0.0), Point::new(5.0, 0.0)];
/// let g = RobotGraph::build(&pts, GraphKind::Knn { k: 1 })?;
/// // 0 and 1 are each other's nearest; 2's nearest is 1, kept in both directions.
/// assert_eq!(g.neighbours(RobotId(1)), &[0, 2]);
/// assert_eq!(g.weights(RobotId(2)), &[4.0]);
/// assert!(g.is_connected());
/// # Ok::<(), afg_graph::GraphError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct RobotGraph {
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
    weights: Vec<f64>,
}

impl RobotGraph {
    /// Builds the graph of `kind` over `points`.
    ///
    /// # Complexity
    /// kNN and radius use a uniform grid: about O(N k) for points spread over a
    /// square. Complete is O(N²).
    ///
    /// # Errors
    /// [`GraphError::InvalidParameter`] for k = 0 or a radius that is not finite
    /// and positive, [`GraphError::NonFinite`] for a NaN or infinite coordinate.
    pub fn build(points: &[Point], kind: GraphKind) -> Result<Self, GraphError> {
        if let Some(i) = points
            .iter()
            .position(|p| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(GraphError::NonFinite(i));
        }
        let pairs = match kind {
            GraphKind::Knn { k } => {
                if k == 0 {
                    return Err(GraphError::InvalidParameter("k must be at least 1".into()));
                }
                let grid = Grid::new(points, 2.0);
                let mut pairs = Vec::with_capacity(points.len() * k * 2);
                for i in 0..points.len() {
                    for j in grid.nearest(points, i, k).0 {
                        pairs.push((i as u32, j));
                        pairs.push((j, i as u32));
                    }
                }
                pairs
            }
            GraphKind::Radius { radius } => {
                if !(radius.is_finite() && radius > 0.0) {
                    return Err(GraphError::InvalidParameter(format!(
                        "radius {radius} must be finite and positive"
                    )));
                }
                let grid = Grid::new(points, 2.0);
                (0..points.len())
                    .flat_map(|i| {
                        grid.within(points, i, radius)
                            .into_iter()
                            .map(move |j| (i as u32, j))
                    })
                    .collect()
            }
            GraphKind::Complete => {
                let n = points.len() as u32;
                (0..n)
                    .flat_map(|i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
                    .collect()
            }
        };
        Ok(Self::from_pairs(points, pairs))
    }

    /// Builds from directed pairs (both directions must be present); duplicates are merged.
    fn from_pairs(points: &[Point], mut pairs: Vec<(u32, u32)>) -> Self {
        pairs.sort_unstable();
        pairs.dedup();
        let mut offsets = vec![0; points.len() + 1];
        for &(i, _) in &pairs {
            offsets[i as usize + 1] += 1;
        }
        for i in 0..points.len() {
            offsets[i + 1] += offsets[i];
        }
        let weights = pairs
            .iter()
            .map(|&(i, j)| points[i as usize].distance(points[j as usize]))
            .collect();
        let neighbours = pairs.into_iter().map(|(_, j)| j).collect();
        RobotGraph {
            offsets,
            neighbours,
            weights,
        }
    }

    /// Number of robots.
    pub fn num_nodes(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of undirected edges.
    pub fn num_edges(&self) -> usize {
        self.neighbours.len() / 2
    }

    /// Neighbours of a robot (indices, sorted).
    #[inline]
    pub fn neighbours(&self, robot: RobotId) -> &[u32] {
        &self.neighbours[self.offsets[robot.index()]..self.offsets[robot.index() + 1]]
    }

    /// Edge weights `d(i, k)`, aligned with [`RobotGraph::neighbours`].
    #[inline]
    pub fn weights(&self, robot: RobotId) -> &[f64] {
        &self.weights[self.offsets[robot.index()]..self.offsets[robot.index() + 1]]
    }

    /// Degree |N_i|.
    #[inline]
    pub fn degree(&self, robot: RobotId) -> usize {
        self.offsets[robot.index() + 1] - self.offsets[robot.index()]
    }

    /// Connected components: a component label per robot, labels `0..count` in order
    /// of their smallest robot.
    pub fn components(&self) -> (Vec<u32>, usize) {
        let n = self.num_nodes();
        let mut label = vec![u32::MAX; n];
        let mut count = 0;
        let mut stack = Vec::new();
        for start in 0..n {
            if label[start] != u32::MAX {
                continue;
            }
            label[start] = count as u32;
            stack.push(start);
            while let Some(v) = stack.pop() {
                for &u in self.neighbours(RobotId(v as u32)) {
                    if label[u as usize] == u32::MAX {
                        label[u as usize] = count as u32;
                        stack.push(u as usize);
                    }
                }
            }
            count += 1;
        }
        (label, count)
    }

    /// Whether every robot can reach every other.
    pub fn is_connected(&self) -> bool {
        self.components().1 <= 1
    }

    /// Makes the graph connected: while it has several components, each component
    /// other than robot 0's gets an edge from its closest member to the closest robot
    /// outside it. Returns the number of edges added (0 for a connected graph).
    ///
    /// # Complexity
    /// O(|C| N) per small component C; free when the graph is connected.
    pub fn connect_components(&mut self, points: &[Point]) -> usize {
        let mut added = 0;
        loop {
            let (label, count) = self.components();
            if count <= 1 {
                return added;
            }
            let mut pairs: Vec<(u32, u32)> = (0..self.num_nodes())
                .flat_map(|i| {
                    self.neighbours(RobotId(i as u32))
                        .iter()
                        .map(move |&j| (i as u32, j))
                })
                .collect();
            for c in 1..count as u32 {
                let members: Vec<usize> = (0..label.len()).filter(|&i| label[i] == c).collect();
                let best = members
                    .iter()
                    .flat_map(|&i| {
                        (0..label.len())
                            .filter(|&j| label[j] != c)
                            .map(move |j| (points[i].distance(points[j]), i, j))
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .expect("another component exists");
                pairs.push((best.1 as u32, best.2 as u32));
                pairs.push((best.2 as u32, best.1 as u32));
                added += 1;
            }
            *self = Self::from_pairs(points, pairs);
        }
    }
}

/// A uniform bucket grid over the box that holds the central 98 % of the points along
/// each axis: one far outlier does not stretch the cells until every other point shares
/// one. Points outside the box are clamped into its border cells, which keeps the ring
/// bound of [`Grid::nearest`] (clamping never brings a cell nearer than its points).
/// Within a cell, points at the same position form one *site* (a run of `order`, by
/// index), so that many robots at one spot cost one distance, not one each.
struct Grid {
    min: Point,
    cell: f64,
    side: usize,
    /// Robot indices sorted by cell, then by position, then by index, with
    /// `starts[c]..starts[c + 1]` the robots of cell c.
    order: Vec<u32>,
    starts: Vec<usize>,
    /// For each place t of `order`, the end of the run of robots at its position.
    site_end: Vec<usize>,
}

/// The share of points left out of the grid's box at each end of each axis.
const OUTLIER_SHARE: f64 = 0.01;

impl Grid {
    /// A grid with about `per_cell` points per cell.
    fn new(points: &[Point], per_cell: f64) -> Self {
        let (min, max) = Self::central_box(points);
        let extent = (max.x - min.x).max(max.y - min.y).max(f64::MIN_POSITIVE);
        let side = ((points.len() as f64 / per_cell).sqrt().floor() as usize).clamp(1, 1 << 12);
        let cell = extent / side as f64 * (1.0 + 1e-12);
        let mut grid = Grid {
            min,
            cell,
            side,
            order: Vec::new(),
            starts: vec![0; side * side + 1],
            site_end: Vec::new(),
        };
        let cells: Vec<usize> = points.iter().map(|&p| grid.cell_of(p)).collect();
        for &c in &cells {
            grid.starts[c + 1] += 1;
        }
        for c in 0..side * side {
            grid.starts[c + 1] += grid.starts[c];
        }
        let mut fill = grid.starts.clone();
        grid.order = vec![0; points.len()];
        for (i, &c) in cells.iter().enumerate() {
            grid.order[fill[c]] = i as u32;
            fill[c] += 1;
        }
        let at = |i: u32| points[i as usize];
        let by_position = |a: Point, b: Point| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y));
        grid.site_end = vec![0; points.len()];
        for c in 0..side * side {
            let robots = &mut grid.order[grid.starts[c]..grid.starts[c + 1]];
            // Counting sort kept the index order; a stable sort by position keeps it per site.
            robots.sort_by(|&a, &b| by_position(at(a), at(b)));
            let mut end = grid.starts[c + 1];
            for t in (grid.starts[c]..grid.starts[c + 1]).rev() {
                if t + 1 < end && by_position(at(grid.order[t]), at(grid.order[t + 1])).is_ne() {
                    end = t + 1;
                }
                grid.site_end[t] = end;
            }
        }
        grid
    }

    /// The lower and upper corners of the box holding all but [`OUTLIER_SHARE`] of the
    /// points at each end of each axis (the whole bounding box below 100 points).
    fn central_box(points: &[Point]) -> (Point, Point) {
        let n = points.len();
        if n == 0 {
            return (Point::new(0.0, 0.0), Point::new(0.0, 0.0));
        }
        let skip = (n as f64 * OUTLIER_SHARE) as usize;
        let range = |mut v: Vec<f64>| {
            let lo = *v.select_nth_unstable_by(skip, f64::total_cmp).1;
            let hi = *v.select_nth_unstable_by(n - 1 - skip, f64::total_cmp).1;
            (lo, hi)
        };
        let (x0, x1) = range(points.iter().map(|p| p.x).collect());
        let (y0, y1) = range(points.iter().map(|p| p.y).collect());
        (Point::new(x0, y0), Point::new(x1, y1))
    }

    /// The cell of a point, clamped into the grid (a float-to-integer cast saturates,
    /// so points below the box land in column or row 0).
    fn coords(&self, p: Point) -> (usize, usize) {
        let cx = (((p.x - self.min.x) / self.cell) as usize).min(self.side - 1);
        let cy = (((p.y - self.min.y) / self.cell) as usize).min(self.side - 1);
        (cx, cy)
    }

    fn cell_of(&self, p: Point) -> usize {
        let (cx, cy) = self.coords(p);
        cy * self.side + cx
    }

    /// Calls `f` with every site (its robots, by index) in the cells at Chebyshev ring
    /// distance `r` from (cx, cy).
    fn ring(&self, (cx, cy): (usize, usize), r: usize, mut f: impl FnMut(&[u32])) {
        let (cx, cy, r, side) = (cx as isize, cy as isize, r as isize, self.side as isize);
        let mut visit = |x: isize, y: isize| {
            let c = (y * side + x) as usize;
            let mut t = self.starts[c];
            while t < self.starts[c + 1] {
                f(&self.order[t..self.site_end[t]]);
                t = self.site_end[t];
            }
        };
        for y in (cy - r).max(0)..=(cy + r).min(side - 1) {
            if (y - cy).abs() == r {
                for x in (cx - r).max(0)..=(cx + r).min(side - 1) {
                    visit(x, y);
                }
            } else {
                // Inside the ring's rows only the two end columns belong to the ring.
                if cx - r >= 0 {
                    visit(cx - r, y);
                }
                if cx + r < side {
                    visit(cx + r, y);
                }
            }
        }
    }

    /// The k nearest robots to robot i (fewer if N - 1 < k), ties by index, and the
    /// number of sites looked at (a measure of the work, for tests).
    fn nearest(&self, points: &[Point], i: usize, k: usize) -> (Vec<u32>, usize) {
        let p = points[i];
        let home = self.coords(p);
        let mut best: Vec<(f64, u32)> = Vec::with_capacity(k + 1);
        let mut sites = 0;
        for r in 0..self.side {
            self.ring(home, r, |site| {
                sites += 1;
                let d = p.distance(points[site[0] as usize]);
                // A site's robots are in index order: once one is not among the best,
                // none after it is.
                for &j in site.iter().filter(|&&j| j as usize != i) {
                    let cand = (d, j);
                    if best.len() == k && cmp(&cand, &best[k - 1]).is_ge() {
                        break;
                    }
                    let at = best.partition_point(|b| cmp(b, &cand).is_lt());
                    best.insert(at, cand);
                    best.truncate(k);
                }
            });
            // Every robot beyond ring r is at least r cells away.
            if best.len() == k && best[k - 1].0 <= r as f64 * self.cell {
                break;
            }
        }
        (best.into_iter().map(|(_, j)| j).collect(), sites)
    }

    /// All robots within `radius` of robot i, excluding i.
    fn within(&self, points: &[Point], i: usize, radius: f64) -> Vec<u32> {
        let p = points[i];
        let rings = ((radius / self.cell).ceil() as usize)
            .saturating_add(1)
            .min(self.side);
        let mut out = Vec::new();
        for r in 0..rings {
            self.ring(self.coords(p), r, |site| {
                if p.distance(points[site[0] as usize]) <= radius {
                    out.extend(site.iter().filter(|&&j| j as usize != i));
                }
            });
        }
        out
    }
}

fn cmp(a: &(f64, u32), b: &(f64, u32)) -> std::cmp::Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mean number of sites a kNN query looks at over all robots.
    fn mean_sites(points: &[Point], k: usize) -> f64 {
        let grid = Grid::new(points, 2.0);
        let total: usize = (0..points.len())
            .map(|i| grid.nearest(points, i, k).1)
            .sum();
        total as f64 / points.len() as f64
    }

    fn spread(n: usize) -> Vec<Point> {
        let side = (n as f64).sqrt().ceil() as usize;
        (0..n)
            .map(|i| Point::new((i % side) as f64, (i / side) as f64))
            .collect()
    }

    /// Many robots at one spot, or one robot far away, no longer put every robot in
    /// one cell: a query looks at a bounded number of sites, as for spread points.
    #[test]
    fn duplicates_and_a_far_outlier_keep_queries_local() {
        let n = 20_000;
        let usual = mean_sites(&spread(n), 10);
        assert!(usual < 60.0, "{usual}");

        let same_spot = vec![Point::new(0.5, 0.5); n];
        assert!(mean_sites(&same_spot, 10) <= 1.0);
        let mut half = spread(n);
        half.iter_mut()
            .step_by(2)
            .for_each(|p| *p = Point::new(3.0, 3.0));
        assert!(mean_sites(&half, 10) < usual, "{}", mean_sites(&half, 10));

        let mut outlier = spread(n);
        outlier[7] = Point::new(1e12, -1e12);
        // The outlier's own query scans every site once; the others stay local.
        let with_outlier = mean_sites(&outlier, 10);
        assert!(with_outlier < usual + 2.0, "{with_outlier} vs {usual}");
    }
}
