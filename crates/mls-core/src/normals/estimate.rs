//! Unoriented normals from the weighted covariance of each neighbourhood (Sec. 4.1).

use std::iter;

use nalgebra::SymmetricEigen;

use super::{NeighbourGraph, NormalsError, check_points, check_scale, check_tolerance};
use crate::math::{Matrix, Point, UnitNormal, Vector};
use crate::par::Parallelism;
use crate::status::PointStatus;

/// Default relative eigenvalue gap below which a normal is undefined: `λ1 − λ0 ≤ 10⁻⁶ λ2`.
///
/// Eigenvalues are squared extents, so this rejects neighbourhoods whose second-largest
/// extent is below 10⁻³ of the largest: collinear points, up to rounding and slight jitter.
pub const DEFAULT_DEGENERACY_TOLERANCE: f64 = 1e-6;

/// Below this ratio `λ1/λ2` a neighbourhood lies along one line, straight or curved (its
/// second extent under a tenth of its first), and its smallest eigenvector is not the
/// surface's normal: on scan lines or rings farther apart than the neighbourhood reaches, the
/// points of one line span the line's own plane, and a ring of a cylinder gives the axis.
/// Measured `λ1/λ2` of 16-neighbour neighbourhoods: at least 0.29 on the bunny; 0.37 on a
/// cylinder whose rings are 6.5 times farther apart than their points (the neighbours reach
/// the next rings); 1.8e-4 on one whose rings are 16 times farther apart (they do not); below
/// 1e-2 at 0.05 % of an aerial LiDAR tile's points (wires) and 0.3 % of scan lines over a torus
/// (line ends at its rim).
pub const LINE_RATIO: f64 = 1e-2;

/// An estimated unit normal with the planarity of its neighbourhood.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalEstimate {
    /// The normal, unit length. Its sign is arbitrary until oriented.
    pub normal: UnitNormal,
    /// Surface variation `σ = λ0 / (λ0 + λ1 + λ2)` of the weighted covariance (Pauly 2003):
    /// 0 for a flat neighbourhood, at most 1/3 for an isotropic one.
    pub variation: f64,
}

impl NormalEstimate {
    /// How well the neighbourhood defines a plane, `1 − 3σ` in `[0, 1]`: 1 when flat, 0 when
    /// isotropic. The orientation prefers confident points as seeds.
    pub fn confidence(&self) -> f64 {
        (1.0 - 3.0 * self.variation).clamp(0.0, 1.0)
    }
}

/// The normal at `centre` from its neighbourhood `Q` (Sec. 4.1), with the centroid
/// normalised.
///
/// With weights `θ_i = exp(−|q − q_i|²/h²)` (Eq. 3),
///
/// $$ \mathbf c = \frac{\sum_i \theta_i\, \mathbf q_i}{\sum_i \theta_i}, \qquad
///    C = \sum_i \theta_i\, (\mathbf q_i - \mathbf c)(\mathbf q_i - \mathbf c)^T, $$
///
/// and the normal is the eigenvector of the smallest eigenvalue `λ0 ≤ λ1 ≤ λ2` of `C`.
///
/// **Erratum E-normal.** The paper prints `c = Σ θ_i q_i` without the division by `Σ θ_i`.
/// That `c` is not a point of the neighbourhood unless the weights sum to one: it moves with
/// the origin (by `(1 − Σθ)·t` under a translation `t`), and then so does the normal. The
/// normalised centroid is translation-invariant.
///
/// The neighbourhood should contain `centre` itself if it is a sample (it does in
/// [`estimate_unoriented`]). Coordinates are taken relative to `centre` and scaled by the
/// neighbourhood radius, so neither a far origin nor very small or large units cost
/// precision. Fails with [`PointStatus::NormalEstimationFailed`] when fewer than 3 points are
/// given, when a coordinate is not finite, when every point coincides or the weights
/// underflow, when the smallest two eigenvalues are nearly equal
/// (`λ1 − λ0 ≤ tolerance · λ2`: collinear points, for which the normal is undefined), or when
/// the points lie along one line, straight or curved (`λ1 < LINE_RATIO · λ2`, see
/// [`LINE_RATIO`]).
pub fn normal_from_neighbourhood<'a, I>(
    centre: &Point,
    neighbourhood: I,
    h: f64,
    tolerance: f64,
) -> Result<NormalEstimate, PointStatus>
where
    I: IntoIterator<Item = &'a Point>,
    I::IntoIter: Clone,
{
    const FAILED: PointStatus = PointStatus::NormalEstimationFailed;
    let points = neighbourhood.into_iter();
    let inv_h2 = 1.0 / (h * h);
    // `f64::max` ignores NaN, so finiteness is tracked on its own.
    let (count, radius, finite) = points
        .clone()
        .fold((0_usize, 0.0_f64, true), |(n, r, f), q| {
            let d = (q - centre).norm();
            (n + 1, r.max(d), f && d.is_finite())
        });
    if count < 3 || !(finite && radius > 0.0 && inv_h2.is_finite()) {
        return Err(FAILED);
    }
    let weighted = points.map(|q| {
        let d = q - centre;
        ((-d.norm_squared() * inv_h2).exp(), d / radius)
    });
    let (wsum, moment) = weighted
        .clone()
        .fold((0.0, Vector::zeros()), |(s, m), (w, e)| (s + w, m + e * w));
    if wsum.is_nan() || wsum <= 0.0 {
        return Err(FAILED);
    }
    let c = moment / wsum;
    // A second pass about the centroid, rather than Σθ e eᵀ − (Σθ) c cᵀ, avoids cancellation
    // when the neighbourhood is small compared with its offset from `centre`.
    let cov = weighted.fold(Matrix::zeros(), |acc, (w, e)| {
        let r = e - c;
        acc + r * r.transpose() * (w / wsum)
    });
    if !cov.iter().all(|v| v.is_finite()) {
        return Err(FAILED);
    }
    // An iteration cap instead of `SymmetricEigen::new`, which loops until convergence.
    let eigen = SymmetricEigen::try_new(cov, f64::EPSILON, 1000).ok_or(FAILED)?;
    let mut order = [0, 1, 2];
    order.sort_unstable_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
    let [l0, l1, l2] = order.map(|i| eigen.eigenvalues[i].max(0.0));
    if !(l2 > 0.0 && l1 - l0 > tolerance * l2 && l1 >= LINE_RATIO * l2) {
        return Err(FAILED);
    }
    let normal =
        UnitNormal::new(eigen.eigenvectors.column(order[0]).into_owned()).map_err(|_| FAILED)?;
    Ok(NormalEstimate {
        normal,
        variation: l0 / (l0 + l1 + l2),
    })
}

/// Unoriented normals of every point from itself and its neighbours in `graph`
/// ([`normal_from_neighbourhood`] with Gaussian scale `h`).
///
/// Fails only on invalid parameters: `h`, `tolerance` outside `[0, 1)`, a graph of another
/// size, non-finite points. Degenerate neighbourhoods are per-point
/// [`PointStatus::NormalEstimationFailed`].
pub fn estimate_unoriented(
    points: &[Point],
    graph: &NeighbourGraph,
    h: f64,
    tolerance: f64,
    par: Parallelism,
) -> Result<Vec<Result<NormalEstimate, PointStatus>>, NormalsError> {
    check_scale(h)?;
    check_tolerance(tolerance)?;
    if graph.len() != points.len() {
        return Err(NormalsError::LengthMismatch {
            points: points.len(),
            other: graph.len(),
            what: "graph nodes",
        });
    }
    check_points(points)?;
    let at = |(i, p): (usize, &Point)| {
        let others = graph
            .neighbours(i)
            .iter()
            .filter_map(|&j| points.get(j as usize));
        normal_from_neighbourhood(p, iter::once(p).chain(others), h, tolerance)
    };
    Ok(par.map(points.len(), 256, |i| at((i, &points[i]))))
}
