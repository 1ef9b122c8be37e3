//! The share of neighbour pairs whose normals agree in sign, recounted from its documented
//! definition (`docs/orientation.md`, "Normals from a file"): the `k` nearest neighbours of
//! every point (itself excluded) found by sorting every distance, the graph symmetrised and
//! each pair counted once, among the pairs that can tell a flip: normals within 60° of
//! parallel or opposed (`|n̂_i·n̂_j| ≥ 1/2`), and a chord within 15° of at least one end's
//! tangent plane (not across a thin wall or gap).

use mls_core::{Point, Vector};

/// Pairs with normals farther than 60° from parallel or opposed straddle a crease: left out.
const CREASE_COSINE: f64 = 0.5;
/// A chord leaving both tangent planes by more than 15° crosses a thin wall or gap: left out.
const THIN_WALL_DEGREES: f64 = 15.0;

/// Neighbour pairs that can tell a flip, and those among them whose normals agree in sign.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PairCount {
    /// Pairs counted.
    pub compared: usize,
    /// Among them, pairs with `n_i · n_j > 0`.
    pub agree: usize,
}

impl PairCount {
    /// `agree / compared`, `None` without pairs.
    pub fn share(&self) -> Option<f64> {
        (self.compared > 0).then(|| self.agree as f64 / self.compared as f64)
    }
}

/// The pairs of the symmetrised `k`-nearest-neighbour graph of `points` whose two ends have a
/// normal (`normals[i]`, `None` where point `i` has none), counted as the module describes.
/// Brute force: O(n² log n), for clouds of a few thousand points.
pub fn pair_agreement(points: &[Point], normals: &[Option<Vector>], k: usize) -> PairCount {
    let n = points.len();
    let mut edges: Vec<(usize, usize)> = Vec::with_capacity(n * k);
    let mut distances: Vec<(f64, usize)> = Vec::with_capacity(n);
    for i in 0..n {
        distances.clear();
        distances.extend(
            (0..n)
                .filter(|&j| j != i)
                .map(|j| ((points[j] - points[i]).norm_squared(), j)),
        );
        // The k nearest in order, equal distances in index order (a stable sort's): selected,
        // then sorted, which is linear rather than n log n for the bunny's 36k points.
        let order = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
        if k < distances.len() {
            distances.select_nth_unstable_by(k, order);
            distances.truncate(k);
        }
        distances.sort_by(order);
        for &(_, j) in distances.iter().take(k) {
            edges.push((i.min(j), i.max(j)));
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let sine = THIN_WALL_DEGREES.to_radians().sin();
    let mut count = PairCount::default();
    for (i, j) in edges {
        let (Some(ni), Some(nj)) = (normals[i], normals[j]) else {
            continue;
        };
        let (ui, uj) = (ni.normalize(), nj.normalize());
        let cosine = ui.dot(&uj);
        if cosine.abs() < CREASE_COSINE {
            continue;
        }
        let chord = points[j] - points[i];
        let across = |u: &Vector| chord.dot(u).abs() > sine * chord.norm();
        if across(&ui) && across(&uj) {
            continue;
        }
        count.compared += 1;
        count.agree += usize::from(cosine > 0.0);
    }
    count
}
