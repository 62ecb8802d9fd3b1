//! The grid-based graphs agree with brute force.

use afg_game::{GeneratorConfig, Point, RobotId};
use afg_graph::{GraphError, GraphKind, RobotGraph};
use proptest::prelude::*;

/// Brute-force symmetrised kNN with ties by index.
fn brute_knn(points: &[Point], k: usize) -> Vec<Vec<u32>> {
    let n = points.len();
    let mut adj = vec![Vec::new(); n];
    for i in 0..n {
        let mut others: Vec<(f64, usize)> = (0..n)
            .filter(|&j| j != i)
            .map(|j| (points[i].distance(points[j]), j))
            .collect();
        others.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(_, j) in others.iter().take(k) {
            adj[i].push(j as u32);
            adj[j].push(i as u32);
        }
    }
    for l in &mut adj {
        l.sort_unstable();
        l.dedup();
    }
    adj
}

fn points(n: usize, seed: u64) -> Vec<Point> {
    GeneratorConfig::paper(n, 1, seed)
        .generate()
        .unwrap()
        .robots()
        .to_vec()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn knn_matches_brute_force(n in 1..300usize, k in 1..14usize, seed in any::<u64>()) {
        let pts = points(n, seed);
        let g = RobotGraph::build(&pts, GraphKind::Knn { k }).unwrap();
        let brute = brute_knn(&pts, k);
        for i in 0..n {
            let id = RobotId(i as u32);
            prop_assert_eq!(g.neighbours(id), brute[i].as_slice(), "robot {}", i);
            for (&j, &w) in g.neighbours(id).iter().zip(g.weights(id)) {
                prop_assert_eq!(w, pts[i].distance(pts[j as usize]));
            }
        }
    }

    /// Robots drawn from a few spots (many at exactly the same position), with far
    /// outliers: kNN and radius graphs still equal brute force, ties by index.
    #[test]
    fn duplicates_and_outliers_match_brute_force(
        n in 1..250usize,
        spots in 1..12usize,
        outliers in 0..4usize,
        k in 1..14usize,
        radius in 0.01..0.5f64,
        seed in any::<u64>(),
    ) {
        let pool = points(spots, seed);
        let mut pts: Vec<Point> = (0..n).map(|i| pool[(i * 7 + i / 3) % spots]).collect();
        for (o, p) in pts.iter_mut().step_by(5).take(outliers).enumerate() {
            *p = Point::new(1e9 * (o as f64 + 1.0), -3e8 * o as f64);
        }
        let g = RobotGraph::build(&pts, GraphKind::Knn { k }).unwrap();
        let brute = brute_knn(&pts, k);
        let disk = RobotGraph::build(&pts, GraphKind::Radius { radius }).unwrap();
        for i in 0..n {
            prop_assert_eq!(g.neighbours(RobotId(i as u32)), brute[i].as_slice(), "robot {}", i);
            let near: Vec<u32> = (0..n)
                .filter(|&j| j != i && pts[i].distance(pts[j]) <= radius)
                .map(|j| j as u32)
                .collect();
            prop_assert_eq!(disk.neighbours(RobotId(i as u32)), near.as_slice());
        }
    }

    #[test]
    fn radius_matches_brute_force(n in 1..200usize, radius in 0.01..0.5f64, seed in any::<u64>()) {
        let pts = points(n, seed);
        let g = RobotGraph::build(&pts, GraphKind::Radius { radius }).unwrap();
        for i in 0..n {
            let brute: Vec<u32> = (0..n)
                .filter(|&j| j != i && pts[i].distance(pts[j]) <= radius)
                .map(|j| j as u32)
                .collect();
            prop_assert_eq!(g.neighbours(RobotId(i as u32)), brute.as_slice());
        }
    }

    #[test]
    fn connecting_components_links_everything(n in 1..120usize, seed in any::<u64>()) {
        let pts = points(n, seed);
        let mut g = RobotGraph::build(&pts, GraphKind::Radius { radius: 0.05 }).unwrap();
        let before = g.components().1;
        let added = g.connect_components(&pts);
        prop_assert!(g.is_connected());
        prop_assert!(added >= before - 1);
    }
}

#[test]
fn complete_graph_has_all_pairs() {
    let pts = points(7, 1);
    let g = RobotGraph::build(&pts, GraphKind::Complete).unwrap();
    assert_eq!(g.num_edges(), 21);
    assert!((0..7).all(|i| g.degree(RobotId(i)) == 6));
}

#[test]
fn far_clusters_are_joined_by_their_closest_pair() {
    let pts = vec![
        Point::new(0.0, 0.0),
        Point::new(0.1, 0.0),
        Point::new(5.0, 0.0),
        Point::new(5.2, 0.0),
    ];
    let mut g = RobotGraph::build(&pts, GraphKind::Knn { k: 1 }).unwrap();
    assert_eq!(g.components().1, 2);
    assert_eq!(g.connect_components(&pts), 1);
    assert_eq!(g.neighbours(RobotId(1)), &[0, 2]);
}

#[test]
fn bad_parameters_are_errors() {
    let pts = points(5, 1);
    assert!(matches!(
        RobotGraph::build(&pts, GraphKind::Knn { k: 0 }),
        Err(GraphError::InvalidParameter(_))
    ));
    for radius in [0.0, -1.0, f64::NAN] {
        assert!(RobotGraph::build(&pts, GraphKind::Radius { radius }).is_err());
    }
    let bad = vec![Point::new(0.0, f64::NAN)];
    assert!(matches!(
        RobotGraph::build(&bad, GraphKind::default()),
        Err(GraphError::NonFinite(0))
    ));
}
