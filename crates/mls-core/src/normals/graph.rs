//! The k-nearest-neighbour graph of a cloud.

use std::num::NonZeroUsize;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::NormalsError;
use crate::cloud::IndexedCloud;
use crate::error::InputError;
use crate::math::Point;
use crate::par::Parallelism;

/// The `k` nearest neighbours of every point, the point itself excluded, nearest first.
///
/// Stored flat: the neighbours of point `i` are `as_flat()[i·k .. (i+1)·k]`, as `u32` indices
/// into the cloud. Every point has exactly [`k`](Self::k) neighbours, where `k` is the
/// requested size clamped to `len − 1` (a cloud of at most `k` points uses all the other
/// points). Duplicate positions are ordinary neighbours at distance 0: excluding "the point
/// itself" goes by index, not by position.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NeighbourGraph {
    points: usize,
    k: usize,
    neighbours: Vec<u32>,
}

impl NeighbourGraph {
    /// Finds the `k` nearest neighbours of every point with a kd-tree.
    ///
    /// Ties in distance are broken by the kd-tree, not by index, so among equidistant
    /// candidates (a regular grid) which one is kept is unspecified; the distances are exact.
    pub fn build(points: &[Point], k: usize, par: Parallelism) -> Result<Self, NormalsError> {
        if k == 0 {
            return Err(InputError::InvalidNeighbourCount { min: 1, got: 0 }.into());
        }
        Self::build_on(&IndexedCloud::new(points, par)?, k, par)
    }

    /// [`Self::build`] on an indexed cloud, with its tree; indices are the input's.
    pub fn build_on(
        cloud: &IndexedCloud<'_>,
        k: usize,
        par: Parallelism,
    ) -> Result<Self, NormalsError> {
        if k == 0 {
            return Err(InputError::InvalidNeighbourCount { min: 1, got: 0 }.into());
        }
        let n = cloud.len();
        let k_eff = k.min(n.saturating_sub(1));
        let mut neighbours = vec![0_u32; n * k_eff];
        if k_eff == 0 {
            return Ok(Self {
                points: n,
                k: 0,
                neighbours,
            });
        }
        // The queries run in storage (Morton) order, so that consecutive ones walk the same
        // branches of the tree whatever the input order (a shuffled million-point sphere took
        // 2.2 times as long in input order), a chunk at a time; each chunk's rows are then
        // copied to their points' places.
        let order = &cloud.order;
        let fill = |s: usize, row: &mut [u32]| {
            fill_row(&cloud.tree, &cloud.local(s), s, n, row);
            for r in row.iter_mut() {
                *r = order[*r as usize];
            }
        };
        let mut rows = vec![0_u32; GRAPH_CHUNK.min(n) * k_eff];
        for start in (0..n).step_by(GRAPH_CHUNK) {
            let end = (start + GRAPH_CHUNK).min(n);
            let rows = &mut rows[..(end - start) * k_eff];
            let at = |(j, row): (usize, &mut [u32])| fill(start + j, row);
            match par {
                Parallelism::Sequential => rows.chunks_mut(k_eff).enumerate().for_each(at),
                Parallelism::Rayon => rows
                    .par_chunks_mut(k_eff)
                    .with_min_len(256)
                    .enumerate()
                    .for_each(at),
            }
            for (s, row) in (start..end).zip(rows.chunks(k_eff)) {
                let i = order[s] as usize;
                neighbours[i * k_eff..(i + 1) * k_eff].copy_from_slice(row);
            }
        }
        Ok(Self {
            points: n,
            k: k_eff,
            neighbours,
        })
    }

    /// Neighbours per point (the requested `k`, clamped to `len − 1`).
    pub fn k(&self) -> usize {
        self.k
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points
    }

    /// Whether the graph has no points.
    pub fn is_empty(&self) -> bool {
        self.points == 0
    }

    /// The neighbours of point `i`, nearest first (empty if `i` is out of range).
    pub fn neighbours(&self, i: usize) -> &[u32] {
        let start = i.saturating_mul(self.k);
        self.neighbours
            .get(start..start.saturating_add(self.k))
            .unwrap_or(&[])
    }

    /// All neighbour lists, `k` per point.
    pub fn as_flat(&self) -> &[u32] {
        &self.neighbours
    }

    /// All neighbour lists, `k` per point, by value.
    pub fn into_flat(self) -> Vec<u32> {
        self.neighbours
    }
}

/// Points whose neighbour rows are found together before being put in input order.
const GRAPH_CHUNK: usize = 1 << 14;

/// Writes the `row.len()` nearest neighbours of item `i` (at `at`) of a tree of `n` points into
/// `row`.
fn fill_row(tree: &ImmutableKdTree<f64, 3>, at: &[f64; 3], i: usize, n: usize, row: &mut [u32]) {
    let k = row.len();
    // One extra result covers the point itself. With more than k+1 copies of one position the
    // point itself may be missing from the result; then the first k are all valid neighbours.
    let Some(wanted) = NonZeroUsize::new(k + 1) else {
        return;
    };
    let hits = tree
        .query(at)
        .nearest_n::<SquaredEuclidean<f64>>(wanted)
        .execute();
    let mut filled = 0;
    for hit in hits.iter().filter(|h| h.item as usize != i).take(k) {
        row[filled] = hit.item;
        filled += 1;
    }
    // The tree holds at least k + 1 points, so it always returns k others. Should that ever
    // fail, repeating the last neighbour keeps the row valid (a repeated edge is harmless to
    // the covariance and to the spanning tree) where indexing past the hits would panic.
    let last = if filled > 0 {
        row[filled - 1]
    } else {
        ((i + 1) % n) as u32
    };
    row[filled..].fill(last);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The row's fallback for a tree that returns fewer than k others, which `build_on` never
    /// asks of it (its tree holds at least k + 1 points): the last neighbour repeated, or the
    /// next index when there is none.
    #[test]
    fn a_short_row_repeats_its_last_neighbour() {
        let tree =
            ImmutableKdTree::new_from_slice(&[[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
                .unwrap();
        let mut row = [u32::MAX; 4];
        fill_row(&tree, &[5.0, 0.0, 0.0], 1, 3, &mut row);
        assert_eq!(row, [2, 0, 0, 0]);
        let alone = ImmutableKdTree::new_from_slice(&[[0.0, 0.0, 0.0]]).unwrap();
        let mut row = [u32::MAX; 2];
        fill_row(&alone, &[0.0, 0.0, 0.0], 0, 1, &mut row);
        assert_eq!(row, [0, 0]);
    }
}
