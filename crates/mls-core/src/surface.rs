//! The whole-cloud MLS surface: built once from points, oriented normals, h and cutoff, then
//! evaluated at many query points, sequentially or in parallel.
//!
//! Here the configuration, the construction (samples in Morton order and their k-d tree) and
//! the calls over many queries; `surface/evaluator.rs` holds the [`Evaluator`] that answers
//! one query at a time.

mod evaluator;

pub use evaluator::Evaluator;

use std::sync::Arc;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use crate::cloud::IndexedCloud;
use crate::curvature::Curvature;
use crate::error::ConfigError;
use crate::field::{Implicit, Sample};
pub use crate::frame::Frame;
use crate::frame::morton_key;
use crate::jet::anchors::{ANCHOR_CELL, Anchors};
use crate::jet::{JetConfig, JetPoint, NormalData};
use crate::kernel::{Cutoff, Kernel};
use crate::math::{Point, UnitNormal, Vector};
pub use crate::par::Parallelism;
use crate::projection::ProjectionConfig;
use crate::status::PointStatus;

/// The anchors' jets evaluated so far, by anchor.
pub(crate) type AnchorCache = std::collections::HashMap<u32, Result<JetPoint, PointStatus>>;

/// Parameters of the MLS surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MlsConfig {
    /// Gaussian scale h (Eq. 3), in the units of the points.
    pub h: f64,
    /// Kernel truncation.
    pub cutoff: Cutoff,
    /// Fewer samples than this within the support give status `TooFewNeighbours`.
    pub min_neighbours: usize,
    /// Stopping rules of the projection.
    pub projection: ProjectionConfig,
}

impl MlsConfig {
    /// Defaults for scale `h`: cutoff 5h, at least 3 neighbours, default projection.
    pub fn new(h: f64) -> Self {
        Self {
            h,
            cutoff: Cutoff::DEFAULT,
            min_neighbours: 3,
            projection: ProjectionConfig::default(),
        }
    }
}

/// Checks that every normal can be normalised, naming the first (in input order) that cannot.
fn check_normals(normals: &[Vector]) -> Result<(), ConfigError> {
    match normals.iter().position(|n| UnitNormal::new(*n).is_err()) {
        None => Ok(()),
        Some(index) => Err(ConfigError::BadNormal {
            index,
            source: UnitNormal::new(normals[index]).unwrap_err(),
        }),
    }
}

/// Curvature at a point of the MLS surface, with the implicit-function data behind it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Where the curvature was evaluated (the query point, or the projected point).
    pub point: Point,
    /// Principal curvatures, directions, mean and Gaussian curvature.
    pub curvature: Curvature,
    /// g, ∇g, H and the normal field there.
    pub implicit: Implicit,
}

/// Outcome for one query point.
pub type PointResult = Result<SurfacePoint, PointStatus>;

/// The MLS surface of an oriented point cloud.
#[derive(Debug)]
pub struct MlsSurface {
    /// Shared by the surfaces of one cloud at other scales ([`Self::with_config`]).
    index: Arc<SampleIndex>,
    kernel: Kernel,
    config: MlsConfig,
}

/// The oriented samples of a surface in storage (Morton) order and their k-d tree: what does
/// not depend on h, built once per cloud.
#[derive(Debug)]
struct SampleIndex {
    /// Points are stored relative to `origin` (their bounding-box centre) so that coordinates
    /// far from zero (georeferenced scans) do not cost precision in `x − q`.
    origin: Vector,
    samples: Vec<Sample>,
    tree: ImmutableKdTree<f64, 3>,
}

impl MlsSurface {
    /// Builds the surface. Normals must be non-zero and consistently oriented; they are
    /// normalised here.
    pub fn new(
        points: &[Point],
        normals: &[Vector],
        config: MlsConfig,
    ) -> Result<Self, ConfigError> {
        Self::with_frame(points, normals, config, Frame::of(points))
    }

    /// [`Self::new`] in a given frame (see [`Frame`]): a part of a larger cloud built in the
    /// whole cloud's frame gives bitwise the whole cloud's results wherever it holds every
    /// sample within reach. The frame's cube should hold the points (a point outside is
    /// ordered as if on its face, which costs only locality).
    pub fn with_frame(
        points: &[Point],
        normals: &[Vector],
        config: MlsConfig,
        frame: Frame,
    ) -> Result<Self, ConfigError> {
        Kernel::new(config.h, config.cutoff)?;
        if points.len() != normals.len() {
            return Err(ConfigError::LengthMismatch {
                points: points.len(),
                normals: normals.len(),
            });
        }
        // The cloud checks the points and `from_cloud` the normals, in that order.
        let cloud = IndexedCloud::with_frame(points, frame, Parallelism::Rayon)?;
        Self::from_cloud(cloud, normals, config)
    }

    /// The surface of an indexed cloud with its `normals` (in input order, non-zero and
    /// consistently oriented; normalised here): the cloud's order and tree become the
    /// surface's, so nothing is sorted or indexed again. Bitwise [`Self::with_frame`] of the
    /// same points in the cloud's frame.
    pub fn from_cloud(
        cloud: IndexedCloud<'_>,
        normals: &[Vector],
        config: MlsConfig,
    ) -> Result<Self, ConfigError> {
        let kernel = Kernel::new(config.h, config.cutoff)?;
        if cloud.len() != normals.len() {
            return Err(ConfigError::LengthMismatch {
                points: cloud.len(),
                normals: normals.len(),
            });
        }
        check_normals(normals)?;
        let local = |s: usize| cloud.local(s);
        // Neighbours of a query are then mostly adjacent in memory, whatever the input order
        // (scan order, or a Fibonacci spiral whose neighbours are thousands of indices apart).
        let samples: Vec<Sample> = Parallelism::Rayon.map(cloud.len(), 4096, |s| {
            let normal = UnitNormal::new(normals[cloud.order[s] as usize]).expect("checked above");
            Sample {
                point: Point::from(local(s)),
                normal: normal.into_inner(),
            }
        });
        Ok(Self {
            index: Arc::new(SampleIndex {
                origin: cloud.frame.origin,
                samples,
                tree: cloud.tree,
            }),
            kernel,
            config,
        })
    }

    /// The surface of the same samples with another configuration (another h, cutoff…): the
    /// samples and their tree are shared, not rebuilt, and its results are bitwise those of
    /// [`Self::with_frame`] with the same points, normals and frame.
    pub fn with_config(&self, config: MlsConfig) -> Result<Self, ConfigError> {
        Ok(Self {
            index: Arc::clone(&self.index),
            kernel: Kernel::new(config.h, config.cutoff)?,
            config,
        })
    }

    /// The configuration the surface was built with.
    pub fn config(&self) -> &MlsConfig {
        &self.config
    }

    /// The kernel (h and cutoff).
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.index.samples.len()
    }

    /// Whether the cloud is empty.
    pub fn is_empty(&self) -> bool {
        self.index.samples.is_empty()
    }

    /// Curvature at each query point (the level set of g through it), in query order.
    ///
    /// Queries are processed in Morton order, in clusters of nearby points that share one
    /// neighbour search (the k-d tree query is a third of the cost of a point otherwise). Each
    /// query's support is summed in storage order, so its result does not depend on the
    /// other queries of the call (see [`crate::stream`]).
    pub fn curvature_at_points(&self, queries: &[Point], par: Parallelism) -> Vec<PointResult> {
        let Some(radius) = self.kernel.support_radius() else {
            return self.map_queries(queries, par, |ev, q| ev.curvature_at(q));
        };
        self.map_clusters(queries, WIDE_CLUSTER, par, |ev, cluster| {
            ev.curvature_of_cluster(queries, cluster, radius)
        })
    }

    /// Curvature of a weighted polynomial jet at each query point, in query order (see
    /// [`crate::jet`]).
    pub fn jet_at_points(
        &self,
        queries: &[Point],
        config: &JetConfig,
        par: Parallelism,
    ) -> Vec<Result<JetPoint, PointStatus>> {
        let anchors = self.anchors(config);
        self.jet_at_points_with(
            queries,
            config,
            anchors.as_ref(),
            &mut AnchorCache::new(),
            par,
        )
    }

    /// The anchors of [`crate::jet::anchors`] where `config` shares supports.
    pub(crate) fn anchors(&self, config: &JetConfig) -> Option<Anchors> {
        (config.share && config.quadratic && config.normals == NormalData::Ignore).then(|| {
            Anchors::new(
                &self.index.samples,
                &self.index.origin,
                ANCHOR_CELL * self.kernel.h(),
            )
        })
    }

    /// [`Self::jet_at_points`] with the surface's `anchors` (if it shares supports) and the
    /// anchors' jets evaluated so far, which the call extends and then prunes to those within
    /// reach of its queries (a stream's next chunk is mostly their neighbour).
    pub(crate) fn jet_at_points_with(
        &self,
        queries: &[Point],
        config: &JetConfig,
        anchors: Option<&Anchors>,
        cache: &mut AnchorCache,
        par: Parallelism,
    ) -> Vec<Result<JetPoint, PointStatus>> {
        let Some(anchors) = anchors else {
            return par.map_init(
                queries.len(),
                256,
                || self.evaluator(),
                |ev, i| ev.jet_at(&queries[i], config),
            );
        };
        let origin = self.index.origin;
        let finite = |p: &Point| p.iter().all(|c| c.is_finite());
        let near: Vec<Vec<(u32, f64)>> = par.map(queries.len(), 256, |i| {
            let mut near = Vec::new();
            if finite(&queries[i]) {
                anchors.near(&(queries[i] - origin), &mut near);
            }
            near
        });
        let mut needed: Vec<u32> = near.iter().flatten().map(|&(a, _)| a).collect();
        needed.sort_unstable();
        needed.dedup();
        let missing: Vec<u32> = needed
            .iter()
            .copied()
            .filter(|a| !cache.contains_key(a))
            .collect();
        let values = par.map_init(
            missing.len(),
            16,
            || self.evaluator(),
            |ev, k| {
                let at = anchors.point(missing[k] as usize);
                ev.jet_at_local(&(at + origin), at, config)
            },
        );
        cache.extend(missing.into_iter().zip(values));
        let cache_ref = &*cache;
        let results = par.map_init(
            queries.len(),
            256,
            || (self.evaluator(), Vec::new()),
            |(ev, shared), i| {
                let x = &queries[i];
                if !finite(x) {
                    return Err(PointStatus::InvalidQuery);
                }
                let local = x - origin;
                shared.clear();
                let mut own = None;
                for &(a, d2) in &near[i] {
                    let value = &cache_ref[&a];
                    if d2 == 0.0 && *anchors.point(a as usize) == local {
                        own = Some(value);
                    }
                    if let Ok(p) = value {
                        shared.push((d2, p));
                    }
                }
                if shared.len() == near[i].len()
                    && let Some(p) = anchors.blend(x, &local, &origin, shared)
                {
                    return Ok(p);
                }
                match own {
                    // The anchor's own jet, evaluated at the same internal point; only the
                    // foot point moves with the world position.
                    Some(value) => value.map(|p| JetPoint {
                        foot: x + (p.foot - (local + origin)),
                        ..p
                    }),
                    None => ev.jet_at_local(x, &local, config),
                }
            },
        );
        cache.retain(|a, _| needed.binary_search(a).is_ok());
        results
    }

    /// Projects each query point onto the MLS surface and evaluates curvature there.
    ///
    /// Queries are processed in Morton order, so that consecutive projections touch nearby
    /// samples and tree nodes; each runs on its own, exactly as [`Evaluator::project`].
    /// (Sharing one neighbour search per cluster of queries, as [`Self::curvature_at_points`]
    /// does, was measured and did not pay here: filtering each line search's support from the
    /// cluster's candidates cost as many instructions as the searches it saved.)
    pub fn project_points(&self, queries: &[Point], par: Parallelism) -> Vec<PointResult> {
        self.map_clusters(queries, CLUSTER, par, |ev, cluster| {
            cluster
                .iter()
                .map(|&i| (i, ev.project(&queries[i])))
                .collect()
        })
    }

    /// [`Self::project_points`] where the kernel's weight sum at the query is at least
    /// `min_weight_sum` ([`Evaluator::project_resolved`]); `None` elsewhere.
    pub(crate) fn project_points_resolved(
        &self,
        queries: &[Point],
        min_weight_sum: f64,
        par: Parallelism,
    ) -> Vec<Result<Option<SurfacePoint>, PointStatus>> {
        self.map_clusters(queries, CLUSTER, par, |ev, cluster| {
            cluster
                .iter()
                .map(|&i| (i, ev.project_resolved(&queries[i], min_weight_sum)))
                .collect()
        })
    }

    /// Runs `run` on clusters of `size` queries (indices into `queries`) taken in Morton
    /// order, so that a cluster's queries are close together and consecutive clusters touch
    /// neighbouring samples, and returns the results in query order.
    fn map_clusters<T, F>(&self, queries: &[Point], size: usize, par: Parallelism, run: F) -> Vec<T>
    where
        T: Copy + Send + Sync,
        F: Fn(&mut Evaluator<'_>, &[usize]) -> Vec<(usize, T)> + Sync,
    {
        let half_extent = queries
            .iter()
            .filter(|q| q.iter().all(|c| c.is_finite()))
            .fold(0.0f64, |m, q| m.max((q - self.index.origin).coords.amax()));
        let key = |i: &usize| morton_key(&(queries[*i] - self.index.origin), half_extent);
        let mut order: Vec<usize> = (0..queries.len()).collect();
        // One vector of results per cluster, the clusters in `order`: collected by index, so
        // that no result is copied on the way (they are several hundred bytes each).
        let clusters: Vec<Vec<(usize, T)>> = match par {
            Parallelism::Sequential => {
                order.sort_by_cached_key(key);
                let mut ev = self.evaluator();
                order.chunks(size).map(|c| run(&mut ev, c)).collect()
            }
            Parallelism::Rayon => {
                order.par_sort_by_cached_key(key);
                order
                    .par_chunks(size)
                    .map_init(|| self.evaluator(), |ev, c| run(ev, c))
                    .collect()
            }
        };
        // Each result is gathered into query order (in parallel: at a million results, a
        // sequential scatter was a few per cent of the whole run).
        debug_assert!(
            clusters
                .iter()
                .flatten()
                .zip(&order)
                .all(|((i, _), j)| i == j)
        );
        let mut rank = vec![0; queries.len()];
        for (k, &i) in order.iter().enumerate() {
            rank[i] = k;
        }
        let gather = |i: usize| clusters[rank[i] / size][rank[i] % size].1;
        par.map(queries.len(), 1, gather)
    }

    fn map_queries<F>(&self, queries: &[Point], par: Parallelism, f: F) -> Vec<PointResult>
    where
        F: Fn(&mut Evaluator<'_>, &Point) -> PointResult + Sync,
    {
        // Pieces of a few hundred points amortise the evaluator set-up and keep each
        // thread's buffers warm.
        par.map_init(
            queries.len(),
            256,
            || self.evaluator(),
            |ev, i| f(ev, &queries[i]),
        )
    }
}

impl SampleIndex {
    /// Appends to `out` the samples within `radius` of `x` (internal frame), in tree order.
    fn samples_within(&self, x: &Point, radius: f64, out: &mut Vec<Sample>) {
        self.tree
            .query(&x.coords.into())
            .within::<SquaredEuclidean<f64>>(radius * radius)
            .unsorted()
            .visit(|hit| out.push(self.samples[hit.item as usize]));
    }

    /// Appends to `out` the samples within `radius` of `x` (internal frame), in storage order.
    /// The tree's order depends on `x`; storage order does not, so a support filtered from
    /// these samples sums in the same order whichever point they were gathered around.
    fn samples_within_ordered(
        &self,
        x: &Point,
        radius: f64,
        hits: &mut Hits,
        out: &mut Vec<Sample>,
    ) {
        let Hits { items, marks } = hits;
        items.clear();
        let (mut lo, mut hi) = (u32::MAX, 0);
        self.tree
            .query(&x.coords.into())
            .within::<SquaredEuclidean<f64>>(radius * radius)
            .unsorted()
            .visit(|hit| {
                lo = lo.min(hit.item);
                hi = hi.max(hit.item);
                items.push(hit.item);
            });
        let Some(span) = (hi as usize + 1).checked_sub(lo as usize) else {
            return;
        };
        // Storage is in Morton order, so a ball's samples usually lie in a few runs of
        // indices: marking them in a bitmap of the span and reading it back in order costs
        // less than sorting. A ball that straddles a jump of the curve spans more: sort.
        if span <= 32 * items.len() {
            marks.clear();
            marks.resize(span.div_ceil(64), 0);
            for &i in items.iter() {
                let d = (i - lo) as usize;
                marks[d / 64] |= 1 << (d % 64);
            }
            for (w, &word) in marks.iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let i = lo as usize + w * 64 + bits.trailing_zeros() as usize;
                    out.push(self.samples[i]);
                    bits &= bits - 1;
                }
            }
        } else {
            items.sort_unstable();
            out.extend(items.iter().map(|&i| self.samples[i as usize]));
        }
    }
}

/// Scratch of [`SampleIndex::samples_within_ordered`]: the tree's hits and a bitmap of them.
#[derive(Debug, Default)]
pub(crate) struct Hits {
    items: Vec<u32>,
    marks: Vec<u64>,
}

/// Queries sharing one neighbour search in [`MlsSurface::curvature_at_points`]; also the unit
/// of work of [`MlsSurface::project_points`].
const CLUSTER: usize = 16;

/// Queries sharing one neighbour search in [`MlsSurface::curvature_at_points`] where they lie
/// close enough, each group of [`CLUSTER`] then filtering the candidates again. The search's
/// cost grows with its hits, not per call: 64 took it from 19 % to 12 % of the 1M sphere's
/// profile; 256 gained nothing more (the groups then filter a larger list each).
const WIDE_CLUSTER: usize = 64;
