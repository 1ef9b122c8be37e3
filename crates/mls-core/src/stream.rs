//! Streaming evaluation: a whole query set evaluated chunk by chunk, each chunk's results
//! handed to a callback with the indices of its queries, so that a caller can draw progress or
//! write results without holding all of them.
//!
//! Chunks follow the queries' Morton order, not their input order: a chunk is then a compact
//! region of space, whatever order the file had. (In input order, a shuffled cloud's chunks
//! were scattered over the whole surface, no two queries of a cluster shared their neighbours,
//! and the paper's method ran 1.6 times slower on a shuffled million-point sphere.)
//!
//! The numbers do not depend on the chunk size nor on the number of threads: each query's
//! result is a function of the query alone. [`MlsSurface::curvature_at_points`] groups nearby
//! queries into clusters that share one neighbour search, but every query's support is then
//! filtered from the cluster's candidates in the samples' storage order, which is the same
//! whatever cluster (hence whatever chunk) the query falls in; projection and the jet gather
//! around each query on its own. The chunk size is therefore only a trade between the
//! callback's granularity and the memory of one chunk's results.

use crate::adaptive::{AdaptiveResult, AdaptiveSurface, Location};
use crate::frame::morton_key;
use crate::jet::{JetConfig, JetPoint};
use crate::math::{Point, Vector};
use crate::par::Parallelism;
use crate::status::PointStatus;
use crate::surface::{MlsSurface, PointResult};

/// A chunk size that keeps rayon's per-call set-up negligible and one chunk's results (about
/// 1.2 KB a point while they are collected) a small part of a large run's memory.
pub const DEFAULT_CHUNK: usize = 1 << 13;

/// The indices of `queries` in the Morton order of their bounding cube, 10 bits per axis (a
/// chunk only needs to be a compact region), the non-finite ones last, equal cells in input
/// order. 4 bytes a query, after a sort of 8-byte keys.
fn spatial_order(queries: &[Point], par: Parallelism) -> Vec<u32> {
    let n = queries.len();
    let finite = |p: &Point| p.iter().all(|c| c.is_finite());
    let inf = Vector::repeat(f64::INFINITY);
    let (lo, hi) = queries
        .iter()
        .filter(|p| finite(p))
        .fold((inf, -inf), |(lo, hi), p| {
            (lo.inf(&p.coords), hi.sup(&p.coords))
        });
    let origin = (lo + hi) * 0.5;
    let half_extent = (hi - lo).amax() * 0.5;
    // The cell's key above the query's index, sorted in place.
    let mut entries: Vec<u64> = par.map(n, 4096, |i| {
        let q = &queries[i];
        // The key's top 30 of 63 bits; one more than the largest for a non-finite query.
        let cell = if finite(q) {
            morton_key(&(q - origin), half_extent) >> 33
        } else {
            1 << 30
        };
        cell << 32 | i as u64
    });
    par.sort_unstable(&mut entries);
    entries.into_iter().map(|e| e as u32).collect()
}

/// Calls `eval` on the queries of consecutive pieces of their [`spatial_order`], at most
/// `chunk` (at least 1) at a time, and `sink` on each piece's query indices with its results.
/// (More queries than a `u32` names, which no cloud in memory reaches, go in input order.)
fn for_each_chunk<R>(
    queries: &[Point],
    chunk: usize,
    par: Parallelism,
    mut eval: impl FnMut(&[Point]) -> Vec<R>,
    mut sink: impl FnMut(&[usize], &[R]),
) {
    if queries.is_empty() {
        return;
    }
    let chunk = chunk.max(1);
    let order = if u32::try_from(queries.len()).is_ok() {
        Some(spatial_order(queries, par))
    } else {
        None
    };
    let (mut indices, mut batch) = (Vec::new(), Vec::new());
    for start in (0..queries.len()).step_by(chunk) {
        let end = (start + chunk).min(queries.len());
        indices.clear();
        match &order {
            Some(order) => indices.extend(order[start..end].iter().map(|&i| i as usize)),
            None => indices.extend(start..end),
        }
        batch.clear();
        batch.extend(indices.iter().map(|&i| queries[i]));
        let results = eval(&batch);
        debug_assert_eq!(results.len(), indices.len());
        sink(&indices, &results);
    }
}

impl MlsSurface {
    /// [`Self::curvature_at_points`] in chunks of `chunk` queries taken in their Morton order:
    /// `sink` receives each chunk's query indices (every index once over the stream) with
    /// their results. The results are bitwise those of one call over all queries, for any
    /// `chunk` and any thread count (see [`crate::stream`]).
    pub fn curvature_stream(
        &self,
        queries: &[Point],
        par: Parallelism,
        chunk: usize,
        sink: impl FnMut(&[usize], &[PointResult]),
    ) {
        for_each_chunk(
            queries,
            chunk,
            par,
            |batch| self.curvature_at_points(batch, par),
            sink,
        );
    }

    /// [`Self::project_points`] in chunks, as [`Self::curvature_stream`].
    pub fn projection_stream(
        &self,
        queries: &[Point],
        par: Parallelism,
        chunk: usize,
        sink: impl FnMut(&[usize], &[PointResult]),
    ) {
        for_each_chunk(
            queries,
            chunk,
            par,
            |batch| self.project_points(batch, par),
            sink,
        );
    }

    /// [`Self::jet_at_points`] in chunks, as [`Self::curvature_stream`].
    pub fn jet_stream(
        &self,
        queries: &[Point],
        config: &JetConfig,
        par: Parallelism,
        chunk: usize,
        sink: impl FnMut(&[usize], &[Result<JetPoint, PointStatus>]),
    ) {
        let anchors = self.anchors(config);
        let mut cache = crate::surface::AnchorCache::new();
        for_each_chunk(
            queries,
            chunk,
            par,
            |batch| self.jet_at_points_with(batch, config, anchors.as_ref(), &mut cache, par),
            sink,
        );
    }
}

impl AdaptiveSurface {
    /// [`Self::curvature_at_points`] in chunks, as [`MlsSurface::curvature_stream`]: each
    /// query's ladder of scales runs on its own, so the results do not depend on `chunk`.
    pub fn curvature_stream(
        &self,
        queries: &[Point],
        at: Location,
        par: Parallelism,
        chunk: usize,
        sink: impl FnMut(&[usize], &[AdaptiveResult]),
    ) {
        for_each_chunk(
            queries,
            chunk,
            par,
            |batch| self.curvature_at_points(batch, at, par),
            sink,
        );
    }
}
