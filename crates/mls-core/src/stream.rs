//! Streaming evaluation: a whole query set evaluated chunk by chunk, each chunk's results
//! handed to a callback in query order, so that a caller can draw progress or write results
//! without holding all of them.
//!
//! The numbers do not depend on the chunk size nor on the number of threads: each query's
//! result is a function of the query alone. [`MlsSurface::curvature_at_points`] groups nearby
//! queries into clusters that share one neighbour search, but every query's support is then
//! filtered from the cluster's candidates in the samples' storage order, which is the same
//! whatever cluster (hence whatever chunk) the query falls in; projection and the jet gather
//! around each query on its own. The chunk size is therefore only a trade between the
//! callback's granularity and the memory of one chunk's results.

use std::ops::Range;

use crate::adaptive::{AdaptiveResult, AdaptiveSurface, Location};
use crate::jet::{JetConfig, JetPoint};
use crate::math::Point;
use crate::status::PointStatus;
use crate::surface::{MlsSurface, Parallelism, PointResult};

/// A chunk size that keeps rayon's per-call set-up negligible and one chunk's results (about
/// 1.2 KB a point while they are collected) a small part of a large run's memory.
pub const DEFAULT_CHUNK: usize = 1 << 14;

/// Calls `eval` on consecutive ranges of `0..n` of at most `chunk` (at least 1) indices, and
/// `sink` on each range with its results.
fn for_each_chunk<R>(
    n: usize,
    chunk: usize,
    mut eval: impl FnMut(Range<usize>) -> Vec<R>,
    mut sink: impl FnMut(Range<usize>, &[R]),
) {
    let chunk = chunk.max(1);
    let mut start = 0;
    while start < n {
        let end = start.saturating_add(chunk).min(n);
        let results = eval(start..end);
        debug_assert_eq!(results.len(), end - start);
        sink(start..end, &results);
        start = end;
    }
}

impl MlsSurface {
    /// [`Self::curvature_at_points`] in chunks of `chunk` queries: `sink` receives each range
    /// of query indices, in order, with its results. The results are bitwise those of one
    /// call over all queries, for any `chunk` and any thread count (see [`crate::stream`]).
    pub fn curvature_stream(
        &self,
        queries: &[Point],
        par: Parallelism,
        chunk: usize,
        sink: impl FnMut(Range<usize>, &[PointResult]),
    ) {
        for_each_chunk(
            queries.len(),
            chunk,
            |r| self.curvature_at_points(&queries[r], par),
            sink,
        );
    }

    /// [`Self::project_points`] in chunks, as [`Self::curvature_stream`].
    pub fn projection_stream(
        &self,
        queries: &[Point],
        par: Parallelism,
        chunk: usize,
        sink: impl FnMut(Range<usize>, &[PointResult]),
    ) {
        for_each_chunk(
            queries.len(),
            chunk,
            |r| self.project_points(&queries[r], par),
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
        sink: impl FnMut(Range<usize>, &[Result<JetPoint, PointStatus>]),
    ) {
        for_each_chunk(
            queries.len(),
            chunk,
            |r| self.jet_at_points(&queries[r], config, par),
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
        sink: impl FnMut(Range<usize>, &[AdaptiveResult]),
    ) {
        for_each_chunk(
            queries.len(),
            chunk,
            |r| self.curvature_at_points(&queries[r], at, par),
            sink,
        );
    }
}
