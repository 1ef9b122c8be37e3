//! The neighbour graph against brute force.

use mls_core::Point;
use mls_core::normals::NeighbourGraph;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{CLOUD_SEED, PAR, SEQ};

/// `n` random points in the box `[−1, 1]² × [−z, z]`.
fn random_slab(n: usize, z: f64, seed: u64) -> Vec<Point> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            Point::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-z..z),
            )
        })
        .collect()
}

/// Asserts that point `i`'s row lists its `k` nearest others, by squared distance against
/// brute force, and never the point itself.
fn assert_row_is_nearest(graph: &NeighbourGraph, points: &[Point], i: usize, k: usize) {
    let p = &points[i];
    let found: Vec<f64> = graph
        .neighbours(i)
        .iter()
        .map(|&j| {
            assert_ne!(j as usize, i, "point {i} lists itself");
            (points[j as usize] - p).norm_squared()
        })
        .collect();
    let mut brute: Vec<f64> = points
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .map(|(_, q)| (q - p).norm_squared())
        .collect();
    brute.select_nth_unstable_by(k, f64::total_cmp);
    brute[..k].sort_by(f64::total_cmp);
    assert_eq!(found, brute[..k], "point {i}");
}

#[test]
fn neighbour_graph_matches_brute_force() {
    let mut points = random_slab(600, 0.2, CLOUD_SEED);
    // Some exact duplicates, including more copies of one position than k.
    points.extend(std::iter::repeat_n(points[3], 15));
    points.extend_from_within(100..110);
    let k = 10;
    let graph = NeighbourGraph::build(&points, k, PAR).unwrap();
    assert_eq!(graph, NeighbourGraph::build(&points, k, SEQ).unwrap());
    assert_eq!((graph.len(), graph.k()), (points.len(), k));
    assert!(!graph.is_empty());
    assert!(NeighbourGraph::build(&[], k, SEQ).unwrap().is_empty());
    assert_eq!(graph.as_flat().len(), points.len() * k);
    assert_eq!(graph.clone().into_flat(), graph.as_flat());
    for i in 0..points.len() {
        assert_row_is_nearest(&graph, &points, i, k);
    }
    // Fewer points than k + 1: every other point.
    let few = &points[..5];
    let small = NeighbourGraph::build(few, 16, SEQ).unwrap();
    assert_eq!(small.k(), 4);
    for i in 0..5 {
        let mut nb: Vec<u32> = small.neighbours(i).to_vec();
        nb.sort_unstable();
        let all: Vec<u32> = (0..5).filter(|&j| j != i as u32).collect();
        assert_eq!(nb, all);
    }
    assert!(small.neighbours(99).is_empty());
}

/// A cloud of several of the graph's chunks of queries (16,384 points each, run in Morton
/// order and put back in input order): every row is still its own point's, checked against
/// brute force on a sample of points, and sequential and parallel runs agree.
#[test]
fn rows_of_a_large_cloud_are_their_own_points() {
    let points = random_slab(40_000, 0.05, CLOUD_SEED + 1);
    let k = 8;
    let graph = NeighbourGraph::build(&points, k, PAR).unwrap();
    assert_eq!(graph, NeighbourGraph::build(&points, k, SEQ).unwrap());
    for i in (0..points.len()).step_by(97) {
        assert_row_is_nearest(&graph, &points, i, k);
    }
}
