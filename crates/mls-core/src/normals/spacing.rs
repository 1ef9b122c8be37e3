//! Sample spacing of a cloud, and a Gaussian scale derived from it.

use std::num::NonZeroUsize;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::{NormalsError, bounding_box_centre, check_points, check_scale};
use crate::error::InputError;
use crate::math::{Matrix, Point, Vector};
use crate::par::Parallelism;

/// Neighbours per point that [`spacing_statistics`] uses by default.
///
/// With 12 neighbours the calibrated spacing agrees within 0.5 % between a square and a
/// hexagonal lattice of the same density, and within 1 % of `√(4πR²/N)` on a Fibonacci sphere;
/// fewer neighbours make the estimate depend on the lattice (the k-th neighbour shell of a
/// square and of a hexagonal lattice lie at different radii).
pub const DEFAULT_SPACING_NEIGHBOURS: usize = 12;

/// Positions at which [`crate::IndexedCloud::spacing`] measures a larger cloud: every
/// `⌈n / SPACING_SAMPLE⌉`-th stored point, an even spread over the cloud's Morton order.
///
/// The spacing is a median, and the median of 65,536 draws has a standard error of about
/// `1.25 s/√65536 ≈ 0.5 %` of the local spacings' standard deviation `s`; that is 0.05–0.15 % of
/// h on clouds whose local spacing varies by 10–30 %, far below what h's factor of 2 is chosen
/// to. On a million points it is 1/16 of the neighbour queries, and the run's h no longer
/// waits on them (0.6 of 3.3 s of `mlscurv curvature --method paper` on 2 cores).
pub const SPACING_SAMPLE: usize = 1 << 16;

/// Default ratio of the Gaussian scale to the spacing: `h = 2 × spacing`.
///
/// The paper's examples use 1.6–2× the spacing. Placeholder, to be tuned by measurement.
pub const DEFAULT_H_FACTOR: f64 = 2.0;

/// Order statistics of a per-point distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceStats {
    /// Smallest value.
    pub min: f64,
    /// 10th percentile.
    pub p10: f64,
    /// Median.
    pub median: f64,
    /// Arithmetic mean.
    pub mean: f64,
    /// 90th percentile.
    pub p90: f64,
    /// Largest value.
    pub max: f64,
}

impl DistanceStats {
    /// Statistics of `values` (sorted here); percentiles interpolate linearly between order
    /// statistics. All NaN for an empty slice.
    fn of(values: &mut [f64], par: Parallelism) -> Self {
        par.sort_unstable_by(values, f64::total_cmp);
        let q = |p: f64| quantile(values, p);
        Self {
            min: q(0.0),
            p10: q(0.1),
            median: q(0.5),
            mean: values.iter().sum::<f64>() / values.len() as f64,
            p90: q(0.9),
            max: q(1.0),
        }
    }
}

/// Linear interpolation between the order statistics of a sorted slice (NaN when empty).
fn quantile(sorted: &[f64], p: f64) -> f64 {
    let Some(last) = sorted.len().checked_sub(1) else {
        return f64::NAN;
    };
    let x = p * last as f64;
    let lo = x.floor() as usize;
    let hi = (lo + 1).min(last);
    let t = x - lo as f64;
    sorted[lo] * (1.0 - t) + sorted[hi] * t
}

/// Spacing of a cloud: distances from each distinct position to its neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpacingStats {
    /// The spacing `s`: the median of [`local_spacing`](Self::local_spacing). On a surface
    /// sampled uniformly it is `√(area per sample)`: the pitch of a square grid,
    /// `√(4πR²/N)` for `N` points on a sphere of radius `R`.
    pub spacing: f64,
    /// Neighbours per point actually used (the requested `k`, clamped to `distinct − 1`).
    pub k: usize,
    /// Number of distinct positions; the statistics are over these.
    pub distinct: usize,
    /// Number of points that repeat an earlier position exactly.
    pub duplicates: usize,
    /// Positions the statistics were measured at: `distinct`, or an even sample of them
    /// ([`crate::IndexedCloud::spacing`]).
    pub measured: usize,
    /// Distance to the nearest other position.
    pub nearest: DistanceStats,
    /// Distance to the k-th nearest other position.
    pub kth: DistanceStats,
    /// Per-point spacing: the root mean square distance to the `k` nearest positions divided
    /// by the same quantity on the unit square grid ([`square_grid_rms_distance`]).
    pub local_spacing: DistanceStats,
}

/// Spacing statistics of a cloud, over its distinct positions.
///
/// For every distinct position `p`, with `d_1 ≤ … ≤ d_k` the distances to its `k` nearest
/// other positions, the local spacing is
///
/// $$ s(p) = \frac{\sqrt{\tfrac1k \sum_{j=1}^{k} d_j^2}}{\rho_k},
///    \qquad \rho_k = \sqrt{\tfrac1k \sum_{j=1}^{k} \delta_j^2}, $$
///
/// where `δ_j` are the same distances on the square grid of unit pitch, so that `s = pitch`
/// on any square grid, exactly. The spacing is the median of `s(p)`.
///
/// Why this definition: for a uniform density `ρ` on a surface, the j-th neighbour lies at
/// `d_j² ≈ j/(πρ)`, so the mean of `d_j²` measures the area per sample `1/ρ` through all `k`
/// neighbours, while a single `d_k` jumps between lattice shells. The result is `√(1/ρ)`
/// whatever the local lattice (0.5 % between square and hexagonal at `k = 12`). Exact
/// duplicates are removed first, as repeated points (merged scans) would otherwise pull the
/// distances to zero; the median makes it robust to a minority of near-duplicates and
/// outliers. On anisotropic scan lines (pitch `a` along, `b` across) it tends to `√(ab)`, the
/// spacing of the same density, not the smaller `a`; where the `k` neighbours all lie along one
/// line ([`super::LINE_RATIO`]: lines farther apart than `k` reach) `s(p)` is measured again
/// with `4k`, then `16k` neighbours (and their `ρ`), and the first that spans a surface is
/// kept; a point whose `16k` neighbours still lie along one line (a wire) keeps its `k`.
///
/// `k = 0` is rejected; a cloud with at most `k` distinct positions uses all of them.
pub fn spacing_statistics(
    points: &[Point],
    k: usize,
    par: Parallelism,
) -> Result<SpacingStats, NormalsError> {
    if k == 0 {
        return Err(InputError::InvalidNeighbourCount { min: 1, got: 0 }.into());
    }
    check_points(points)?;
    let centre = bounding_box_centre(points);
    let coords: Vec<[f64; 3]> = points.iter().map(|p| (p.coords - centre).into()).collect();
    spacing_of_local(coords, k, None, par)
}

/// [`spacing_statistics`] of points already relative to their bounding-box centre (and
/// checked), on a tree of their distinct positions. `k` ≥ 1.
///
/// With `sample`, at most that many positions are measured, every `⌈distinct / sample⌉`-th in
/// the sorted order.
pub(crate) fn spacing_of_local(
    mut coords: Vec<[f64; 3]>,
    k: usize,
    sample: Option<usize>,
    par: Parallelism,
) -> Result<SpacingStats, NormalsError> {
    let total = coords.len();
    // `+ 0.0` turns −0.0 into 0.0 so that the bitwise-total order below sees one zero.
    for c in &mut coords {
        *c = c.map(|c| c + 0.0);
    }
    let lexicographic = |a: &[f64; 3], b: &[f64; 3]| {
        a[0].total_cmp(&b[0])
            .then(a[1].total_cmp(&b[1]))
            .then(a[2].total_cmp(&b[2]))
    };
    par.sort_unstable_by(&mut coords, lexicographic);
    coords.dedup();
    let distinct = coords.len();
    if distinct < 2 {
        return Err(NormalsError::TooFewDistinctPoints { distinct });
    }
    let k_eff = k.min(distinct - 1);
    let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&coords)
        .map_err(|_| InputError::TooManyPoints(total))?;
    let stride = sample.map_or(1, |m| stride(distinct, m));
    let stats = spacing_on_tree(&tree, distinct, |i| coords[i], k_eff, stride, par, false)
        .expect("distinct positions have no duplicates to report");
    Ok(SpacingStats {
        duplicates: total - distinct,
        ..stats
    })
}

/// The step that measures at most `sample` of `n` positions, evenly spread.
pub(crate) fn stride(n: usize, sample: usize) -> usize {
    n.div_ceil(sample.max(1)).max(1)
}

/// The statistics over the points `0, stride, 2·stride, …` of the `n` points of `tree` (item
/// `i` at `coord(i)`) with `k` neighbours each, `k < n`. With `detect_duplicates`, `None` as
/// soon as a measured point has another at distance 0 (the statistics are over distinct
/// positions: the caller removes duplicates first).
pub(crate) fn spacing_on_tree(
    tree: &ImmutableKdTree<f64, 3>,
    n: usize,
    coord: impl Fn(usize) -> [f64; 3] + Sync + Send,
    k: usize,
    stride: usize,
    par: Parallelism,
    detect_duplicates: bool,
) -> Option<SpacingStats> {
    // Where k neighbours lie along one line (scan lines farther apart than they reach) they
    // measure the spacing along it: it is measured again with 4k, then 16k, and the first that
    // spans a surface is kept. A point still on one line with 16k (a wire) keeps its k.
    let ks = [k, (4 * k).min(n - 1), (16 * k).min(n - 1)];
    let rho = ks.map(square_grid_rms_distance);
    let measured = n.div_ceil(stride);
    let per_point = |j: usize| {
        let i = j * stride;
        let (mut row, mut line) = local_distances(tree, &coord, i, k, rho[0], detect_duplicates)?;
        let mut level = 0;
        while line && level < 2 && ks[level + 1] > ks[level] {
            level += 1;
            let (grown, grown_line) =
                local_distances(tree, &coord, i, ks[level], rho[level], false)?;
            if !grown_line {
                row[2] = grown[2];
            }
            line = grown_line;
        }
        Some(row)
    };
    let rows: Vec<Option<[f64; 3]>> = par.map(measured, 256, per_point);
    let rows: Vec<[f64; 3]> = rows.into_iter().collect::<Option<_>>()?;
    let column = |c: usize| {
        let mut v: Vec<f64> = rows.iter().map(|r| r[c]).collect();
        DistanceStats::of(&mut v, par)
    };
    let (nearest, kth, local_spacing) = (column(0), column(1), column(2));
    Some(SpacingStats {
        spacing: local_spacing.median,
        k,
        distinct: n,
        duplicates: 0,
        measured,
        nearest,
        kth,
        local_spacing,
    })
}

/// For item `i`: the distances to its nearest and its `k`-th nearest other position and its
/// local spacing, and whether those `k` neighbours with it lie along one line, straight or
/// curved (the second eigenvalue of their covariance below [`super::LINE_RATIO`] of the
/// largest). `None` with `detect_duplicates` when another position coincides with it.
fn local_distances(
    tree: &ImmutableKdTree<f64, 3>,
    coord: &impl Fn(usize) -> [f64; 3],
    i: usize,
    k: usize,
    rho: f64,
    detect_duplicates: bool,
) -> Option<([f64; 3], bool)> {
    let Some(wanted) = NonZeroUsize::new(k + 1) else {
        return Some(([f64::NAN; 3], false));
    };
    let at = coord(i);
    let hits = tree
        .query(&at)
        .nearest_n::<SquaredEuclidean<f64>>(wanted)
        .execute();
    // Positions are distinct, so the point itself is the only hit to skip.
    let others = || hits.iter().filter(|h| h.item as usize != i).take(k);
    let d2: Vec<f64> = others().map(|h| h.distance).collect();
    if detect_duplicates && d2.first().is_some_and(|&d| d == 0.0) {
        return None;
    }
    let (Some(&first), Some(&last)) = (d2.first(), d2.last()) else {
        return Some(([f64::NAN; 3], false));
    };
    let mean_d2 = d2.iter().sum::<f64>() / d2.len() as f64;
    // The covariance of the neighbourhood, the point included, about its mean.
    let centre = Vector::from(at);
    let offsets = || {
        others()
            .map(|h| Vector::from(coord(h.item as usize)) - centre)
            .chain(std::iter::once(Vector::zeros()))
    };
    let mean = offsets().sum::<Vector>() / (d2.len() + 1) as f64;
    let cov = offsets().fold(Matrix::zeros(), |c, d| {
        let r = d - mean;
        c + r * r.transpose()
    });
    // Eigenvalues only; the QR iteration has no cap, so nothing not finite enters it.
    let line = cov.iter().all(|v| v.is_finite()) && {
        let values = cov.symmetric_eigenvalues();
        let mut l = [0, 1, 2].map(|j| values[j].max(0.0));
        l.sort_unstable_by(f64::total_cmp);
        l[2] > 0.0 && l[1] < super::LINE_RATIO * l[2]
    };
    Some(([first.sqrt(), last.sqrt(), mean_d2.sqrt() / rho], line))
}

/// The root mean square distance from a node of the square grid of unit pitch to its `k`
/// nearest other nodes: `ρ_k = √(Σ_{j≤k} δ_j² / k)` (1 for `k ≤ 4`, `√1.5` for `k = 8`).
///
/// This is the calibration constant of [`spacing_statistics`]. Returns NaN for `k = 0`.
pub fn square_grid_rms_distance(k: usize) -> f64 {
    if k == 0 {
        return f64::NAN;
    }
    // A square of half-width m ≥ √k + 2 contains the disc of radius m, and that disc holds
    // more than k + 1 nodes, so the k nearest nodes are all inside the square.
    let m = (k as f64).sqrt().ceil() as i64 + 2;
    let mut d2: Vec<i64> = (-m..=m)
        .flat_map(|x| (-m..=m).map(move |y| x * x + y * y))
        .filter(|&d| d > 0)
        .collect();
    d2.sort_unstable();
    let sum: i64 = d2.iter().take(k).sum();
    (sum as f64 / k as f64).sqrt()
}

/// A Gaussian scale from the spacing: `h = factor × spacing`.
///
/// [`DEFAULT_H_FACTOR`] is the default factor. Fails for a non-positive or non-finite factor,
/// for a zero or non-finite spacing, and when `h` would not be a valid scale (`1/h²`
/// overflowing).
pub fn suggest_h(stats: &SpacingStats, factor: f64) -> Result<f64, NormalsError> {
    if !(factor.is_finite() && factor > 0.0) {
        return Err(NormalsError::InvalidFactor(factor));
    }
    if !(stats.spacing.is_finite() && stats.spacing > 0.0) {
        return Err(NormalsError::DegenerateSpacing(stats.spacing));
    }
    let h = factor * stats.spacing;
    check_scale(h)?;
    Ok(h)
}
