//! Normals for clouds that come without them (Sec. 4.1), consistently oriented.
//!
//! The MLS normal field n(x) (Eq. 2) needs an oriented unit normal `v_i` at every sample. When
//! the input has none, this module estimates them in four steps, each usable on its own:
//!
//! 1. [`NeighbourGraph`]: the `k` nearest neighbours of every point (the point itself
//!    excluded), found with a kd-tree.
//! 2. [`spacing_statistics`] and [`suggest_h`]: the sample spacing of the cloud and a Gaussian
//!    scale `h` derived from it, for when the caller does not choose `h`.
//! 3. [`estimate_unoriented`]: the eigenvector of the smallest eigenvalue of the weighted
//!    covariance of each neighbourhood (Sec. 4.1, with the centroid normalised: erratum
//!    E-normal, see [`normal_from_neighbourhood`]).
//! 4. [`orient_normals`]: a consistent sign for the normals along a minimum spanning tree of
//!    the neighbour graph (Hoppe et al. 1992), one sign per connected component chosen by the
//!    [`Orientation`] rule (outward, or a vote of the points towards a viewpoint or upwards).
//!
//! [`estimate_normals`] runs all four; where step 3 fails with `k` neighbours (too few,
//! collinear, or along one line: scan lines farther apart than `k` neighbours reach) it tries
//! again with `4k` and `16k`. A point whose normal cannot be estimated then gets
//! [`PointStatus::NormalEstimationFailed`] and takes no part in the orientation; that is data,
//! not an error. [`NormalsError`] is for invalid parameters and
//! input the whole computation cannot proceed with.

mod estimate;
mod graph;
mod orient;
mod spacing;

pub use estimate::{
    DEFAULT_DEGENERACY_TOLERANCE, LINE_RATIO, NormalEstimate, estimate_unoriented,
    normal_from_neighbourhood,
};
pub use graph::NeighbourGraph;
pub use orient::{
    Facing, Orientation, OrientationReport, orient_normals, orient_normals_towards,
    orientation_consistency, sampled_consistency,
};
pub use spacing::{
    DEFAULT_H_FACTOR, DEFAULT_SPACING_NEIGHBOURS, DistanceStats, SPACING_SAMPLE, SpacingStats,
    spacing_statistics, square_grid_rms_distance, suggest_h,
};
pub(crate) use spacing::{spacing_of_local, spacing_on_tree, stride};

use crate::cloud::IndexedCloud;
use crate::error::InputError;
use crate::math::{Point, Vector};
use crate::par::Parallelism;
use crate::status::PointStatus;

/// The default neighbourhood size of normal estimation and orientation.
///
/// 16 neighbours reach about 2.3 spacings on a uniformly sampled surface: enough for the
/// covariance to average out sampling irregularity, few enough to stay local on curved parts.
pub const DEFAULT_NEIGHBOURS: usize = 16;

/// Invalid parameters or input for normal estimation. Per-point failures are not errors: they
/// are [`PointStatus::NormalEstimationFailed`] in the result.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NormalsError {
    /// The points themselves, or the neighbourhood size, are unusable.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The neighbour graph has more edges than the orientation's 32-bit edge numbering holds
    /// (points × k above 2³²).
    #[error("neighbour graph too large to orient: {0} edges (at most {max})", max = u32::MAX)]
    GraphTooLarge(usize),
    /// The Gaussian scale `h` must be finite, strictly positive, and have a finite `1/h²`.
    #[error("Gaussian scale h must be finite and positive, got {0}")]
    InvalidScale(f64),
    /// The factor of [`suggest_h`] must be finite and strictly positive.
    #[error("h factor must be finite and positive, got {0}")]
    InvalidFactor(f64),
    /// The degeneracy tolerance must lie in `[0, 1)`.
    #[error("degeneracy tolerance must lie in [0, 1), got {0}")]
    InvalidTolerance(f64),
    /// The viewpoint of [`Orientation::Viewpoint`] has a NaN or infinite coordinate.
    #[error("viewpoint has a non-finite coordinate")]
    InvalidViewpoint,
    /// Spacing needs at least two distinct positions; the cloud has fewer (it is empty, a
    /// single point, or copies of one point).
    #[error("spacing needs at least two distinct points, the cloud has {distinct}")]
    TooFewDistinctPoints {
        /// Number of distinct positions in the cloud.
        distinct: usize,
    },
    /// The spacing is zero or not finite, so no scale can be derived from it.
    #[error("spacing {0} cannot give a Gaussian scale")]
    DegenerateSpacing(f64),
    /// Arrays that must pair up one to one with the points do not.
    #[error("{points} points but {other} {what}")]
    LengthMismatch {
        /// Number of points.
        points: usize,
        /// Length of the other array.
        other: usize,
        /// What the other array holds ("normals", "graph nodes").
        what: &'static str,
    },
}

/// Parameters of [`estimate_normals`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalsConfig {
    /// Neighbours per point (the point itself excluded) for the covariance and the
    /// orientation graph. Clouds with at most `k` points use all the other points.
    pub k: usize,
    /// Gaussian scale of the covariance weights θ. `None` derives it from the cloud:
    /// `h = DEFAULT_H_FACTOR × spacing` ([`suggest_h`]).
    pub h: Option<f64>,
    /// How to choose the sign of the normals.
    pub orientation: Orientation,
    /// Relative eigenvalue gap below which the normal is undefined
    /// (see [`DEFAULT_DEGENERACY_TOLERANCE`]).
    pub degeneracy_tolerance: f64,
}

impl Default for NormalsConfig {
    /// `k = 16`, automatic `h`, outward orientation, default degeneracy tolerance.
    fn default() -> Self {
        Self {
            k: DEFAULT_NEIGHBOURS,
            h: None,
            orientation: Orientation::Outward,
            degeneracy_tolerance: DEFAULT_DEGENERACY_TOLERANCE,
        }
    }
}

/// The output of [`estimate_normals`].
#[derive(Clone, Debug)]
pub struct EstimatedNormals {
    /// Per point, in input order: the (oriented) normal with its planarity, or why there is
    /// none.
    pub estimates: Vec<Result<NormalEstimate, PointStatus>>,
    /// The Gaussian scale used; `None` only when it was to be derived and the cloud has fewer
    /// than two distinct positions (every estimate then failed).
    pub h: Option<f64>,
    /// The spacing statistics `h` was derived from, when it was derived.
    pub spacing: Option<SpacingStats>,
    /// The neighbour graph, kept for later consistency checks.
    pub graph: NeighbourGraph,
    /// What the orientation did, and the consistency it reached.
    pub report: OrientationReport,
}

impl EstimatedNormals {
    /// The normals alone, in input order.
    pub fn normals(&self) -> Vec<Result<Vector, PointStatus>> {
        self.estimates
            .iter()
            .map(|e| (*e).map(|e| e.normal.into_inner()))
            .collect()
    }

    /// Number of points whose normal could not be estimated.
    pub fn failed(&self) -> usize {
        self.estimates.iter().filter(|e| e.is_err()).count()
    }
}

/// Estimates and orients a normal at every point: neighbour graph, automatic `h` if none is
/// given, weighted covariance normals (Sec. 4.1), and orientation.
///
/// An empty cloud gives an empty result. Errors are only for invalid parameters and
/// non-finite or too many points; degenerate neighbourhoods are per-point statuses.
pub fn estimate_normals(
    points: &[Point],
    config: &NormalsConfig,
    par: Parallelism,
) -> Result<EstimatedNormals, NormalsError> {
    // The parameters are checked before the points, as the points are the costlier check.
    check_config(config)?;
    estimate_normals_on(&IndexedCloud::new(points, par)?, points, config, par)
}

/// Checks h (when given), the degeneracy tolerance and k.
fn check_config(config: &NormalsConfig) -> Result<(), NormalsError> {
    if let Some(h) = config.h {
        check_scale(h)?;
    }
    check_tolerance(config.degeneracy_tolerance)?;
    if config.k == 0 {
        return Err(InputError::InvalidNeighbourCount { min: 1, got: 0 }.into());
    }
    Ok(())
}

/// [`estimate_normals`] of `points` indexed as `cloud` (its tree serves the neighbour graph
/// and the spacing).
pub fn estimate_normals_on(
    cloud: &IndexedCloud<'_>,
    points: &[Point],
    config: &NormalsConfig,
    par: Parallelism,
) -> Result<EstimatedNormals, NormalsError> {
    check_config(config)?;
    if cloud.len() != points.len() {
        return Err(NormalsError::LengthMismatch {
            points: points.len(),
            other: cloud.len(),
            what: "indexed points",
        });
    }
    let graph = NeighbourGraph::build_on(cloud, config.k, par)?;
    let (h, spacing) = match config.h {
        Some(h) => (Some(h), None),
        None => match cloud.spacing(DEFAULT_SPACING_NEIGHBOURS, par) {
            Ok(stats) => (Some(suggest_h(&stats, DEFAULT_H_FACTOR)?), Some(stats)),
            // Fewer than two distinct positions: no covariance can have rank 2 either, so
            // every point fails below without needing a scale.
            Err(NormalsError::TooFewDistinctPoints { .. }) => (None, None),
            Err(e) => return Err(e),
        },
    };
    let mut estimates = match h {
        Some(h) => estimate_unoriented(points, &graph, h, config.degeneracy_tolerance, par)?,
        None => vec![Err(PointStatus::NormalEstimationFailed); points.len()],
    };
    if let Some(h) = h {
        regrow_failed(cloud, points, config, h, &mut estimates, par);
    }
    let report = orient_normals(points, &graph, &mut estimates, config.orientation, par)?;
    Ok(EstimatedNormals {
        estimates,
        h,
        spacing,
        graph,
        report,
    })
}

/// Neighbourhoods of [`regrow_failed`], in multiples of the configured `k`.
const REGROWN: [usize; 2] = [4, 16];

/// Estimates again, from 4k and then 16k nearest neighbours, the normals that failed with k:
/// on scan lines or rings farther apart than k neighbours reach, those lie along one line
/// ([`LINE_RATIO`]). The Gaussian scale is widened to half the grown neighbourhood's radius
/// where h is smaller, so that the other lines weigh in. A normal that fails with 16k too
/// stays failed. Clouds whose k-neighbourhoods all span a surface are untouched.
fn regrow_failed(
    cloud: &IndexedCloud<'_>,
    points: &[Point],
    config: &NormalsConfig,
    h: f64,
    estimates: &mut [Result<NormalEstimate, PointStatus>],
    par: Parallelism,
) {
    let failed: Vec<usize> = (0..estimates.len())
        .filter(|&i| estimates[i].is_err())
        .collect();
    if failed.is_empty() {
        return;
    }
    let mut rank = vec![0_usize; cloud.len()];
    for (s, &i) in cloud.order.iter().enumerate() {
        rank[i as usize] = s;
    }
    let regrown = par.map(failed.len(), 16, |f| {
        let i = failed[f];
        let at = cloud.local(rank[i]);
        let mut result = Err(PointStatus::NormalEstimationFailed);
        for times in REGROWN {
            let Some(wanted) = std::num::NonZeroUsize::new((config.k * times + 1).min(cloud.len()))
            else {
                break;
            };
            let hits = cloud
                .tree
                .query(&at)
                .nearest_n::<kiddo::SquaredEuclidean<f64>>(wanted)
                .execute();
            let neighbourhood: Vec<Point> = hits
                .iter()
                .map(|hit| points[cloud.order[hit.item as usize] as usize])
                .collect();
            let radius = hits.last().map_or(0.0, |hit| hit.distance.sqrt());
            result = normal_from_neighbourhood(
                &points[i],
                &neighbourhood,
                h.max(radius / 2.0),
                config.degeneracy_tolerance,
            );
            if result.is_ok() || wanted.get() == cloud.len() {
                break;
            }
        }
        result
    });
    for (&i, e) in failed.iter().zip(regrown) {
        if e.is_ok() {
            estimates[i] = e;
        }
    }
}

/// Checks a Gaussian scale: finite, positive, with a finite `1/h²`.
fn check_scale(h: f64) -> Result<(), NormalsError> {
    if h.is_finite() && h > 0.0 && (1.0 / (h * h)).is_finite() {
        Ok(())
    } else {
        Err(NormalsError::InvalidScale(h))
    }
}

fn check_tolerance(t: f64) -> Result<(), NormalsError> {
    if (0.0..1.0).contains(&t) {
        Ok(())
    } else {
        Err(NormalsError::InvalidTolerance(t))
    }
}

pub(crate) use crate::error::check_points;

pub(crate) use crate::math::bounding_box_centre;
