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
                    for j in grid.nearest(points, i, k) {
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

/// A uniform bucket grid over the bounding box of the points.
struct Grid {
    min: Point,
    cell: f64,
    side: usize,
    /// Robot indices sorted by cell, with `starts[c]..starts[c + 1]` the robots of cell c.
    order: Vec<u32>,
    starts: Vec<usize>,
}

impl Grid {
    /// A grid with about `per_cell` points per cell.
    fn new(points: &[Point], per_cell: f64) -> Self {
        let (mut min, mut max) = (
            Point::new(f64::INFINITY, f64::INFINITY),
            Point::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for p in points {
            min = Point::new(min.x.min(p.x), min.y.min(p.y));
            max = Point::new(max.x.max(p.x), max.y.max(p.y));
        }
        let extent = (max.x - min.x).max(max.y - min.y).max(f64::MIN_POSITIVE);
        let side = ((points.len() as f64 / per_cell).sqrt().floor() as usize).clamp(1, 1 << 12);
        let cell = extent / side as f64 * (1.0 + 1e-12);
        let mut grid = Grid {
            min,
            cell,
            side,
            order: Vec::new(),
            starts: vec![0; side * side + 1],
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
        grid
    }

    fn coords(&self, p: Point) -> (usize, usize) {
        let cx = (((p.x - self.min.x) / self.cell) as usize).min(self.side - 1);
        let cy = (((p.y - self.min.y) / self.cell) as usize).min(self.side - 1);
        (cx, cy)
    }

    fn cell_of(&self, p: Point) -> usize {
        let (cx, cy) = self.coords(p);
        cy * self.side + cx
    }

    /// Calls `f` with every robot in the cells at Chebyshev ring distance `r` from (cx, cy).
    fn ring(&self, (cx, cy): (usize, usize), r: usize, mut f: impl FnMut(u32)) {
        let (cx, cy, r, side) = (cx as isize, cy as isize, r as isize, self.side as isize);
        let mut visit = |x: isize, y: isize| {
            let c = (y * side + x) as usize;
            for &i in &self.order[self.starts[c]..self.starts[c + 1]] {
                f(i);
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

    /// The k nearest robots to robot i (fewer if N - 1 < k), ties by index.
    fn nearest(&self, points: &[Point], i: usize, k: usize) -> Vec<u32> {
        let p = points[i];
        let home = self.coords(p);
        let mut best: Vec<(f64, u32)> = Vec::with_capacity(k + 1);
        for r in 0..self.side {
            self.ring(home, r, |j| {
                if j as usize == i {
                    return;
                }
                let cand = (p.distance(points[j as usize]), j);
                if best.len() == k && cmp(&cand, &best[k - 1]).is_ge() {
                    return;
                }
                let at = best.partition_point(|b| cmp(b, &cand).is_lt());
                best.insert(at, cand);
                best.truncate(k);
            });
            // Every robot beyond ring r is at least r cells away.
            if best.len() == k && best[k - 1].0 <= r as f64 * self.cell {
                break;
            }
        }
        best.into_iter().map(|(_, j)| j).collect()
    }

    /// All robots within `radius` of robot i, excluding i.
    fn within(&self, points: &[Point], i: usize, radius: f64) -> Vec<u32> {
        let p = points[i];
        let rings = ((radius / self.cell).ceil() as usize)
            .saturating_add(1)
            .min(self.side);
        let mut out = Vec::new();
        for r in 0..rings {
            self.ring(self.coords(p), r, |j| {
                if j as usize != i && p.distance(points[j as usize]) <= radius {
                    out.push(j);
                }
            });
        }
        out
    }
}

fn cmp(a: &(f64, u32), b: &(f64, u32)) -> std::cmp::Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}
