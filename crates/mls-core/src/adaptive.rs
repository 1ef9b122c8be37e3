//! Curvature with a per-point scale: the adaptive h that Section 6 of the paper proposes.
//!
//! One fixed h trades two errors. The MLS curvature is biased by about `c(x) h²` (smoothing;
//! `c` depends on the local sampling and on curvature variation), and under position noise of
//! standard deviation σ its scatter is about `C σ / (h² √N)` with `N ≈ 2 Σw` the effective
//! number of samples in the kernel. Here each point picks its own scale from a ladder
//! `h_j = h_min · √2^j`:
//!
//! 1. **Local spacing.** Scales below `min_h_factor` × the local spacing at the query (from the
//!    kernel's own weight sum there, `s = √(π h² / Σw)` for a uniform density) under-resolve
//!    the sampling and are skipped, so `h_min` may be set for the densest region. Measured at
//!    the query, not at its projection, a skipped scale costs no projection.
//! 2. **Noise.** σ is estimated at the first usable scale from the samples within 2h: their
//!    heights over the local quadric of the MLS normal and principal curvatures, less a
//!    weighted least-squares cubic in the tangent coordinates (so that a tilt, a curvature
//!    error and varying curvature do not read as noise), scaled to be unbiased for independent
//!    noise. It is turned into a predicted scatter `sd_j = C σ / (h_j² √(2 Σw_j))` with [`NOISE_GAIN`] = C calibrated once
//!    on a noisy plane (no bias, all error is noise).
//! 3. **Scale choice (intersection of confidence intervals).** Going up the ladder, the scale
//!    is kept while the intervals `k_j ± Γ sd_j` of all scales so far still intersect, for k1
//!    and k2: while the estimates agree within their noise, the larger h only removes noise.
//!    The first disagreement means the bias has become visible; the previous scale is chosen.
//! 4. **Bias removal.** With the bias ∝ h², the pair of the chosen scale and its neighbour on
//!    the ladder estimates it (`c h² = h² (k_b − k_a)/(h_b² − h_a²)`), and the estimate is
//!    extrapolated to h = 0 (Richardson) when that bias exceeds twice the predicted scatter,
//!    the point where extrapolating (which doubles the scatter) lowers the expected error.
//!
//! On noisy data the scale grows until the bias shows. On clean data the estimate of σ is what
//! the cubic leaves of the surface (about 1e-5 on the paper's torus of tube radius 0.2), so
//! the scale still grows where the bias at the input points is small; at the projected points,
//! whose shrinkage bias is large, the smallest scales are kept and extrapolation removes the
//! bias. `docs/paper.md` measures both.

use crate::cloud::IndexedCloud;
use crate::curvature::Curvature;
use crate::error::ConfigError;
use crate::math::{Point, Vector};
use crate::par::Parallelism;
use crate::status::PointStatus;
use crate::surface::{MlsConfig, MlsSurface};

/// `C` in the predicted scatter `C σ / (h² √(2 Σw))` of each principal curvature under
/// position noise σ, for the Gaussian kernel with cutoff 5h. Measured on noisy planes (the
/// test `noise_gain_matches_a_noisy_plane` re-measures it).
pub const NOISE_GAIN: f64 = 2.0;

/// Ratio of successive scales of the ladder.
pub const SCALE_RATIO: f64 = std::f64::consts::SQRT_2;

/// Where the curvature is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// At the query point (the level set of g through it).
    Input,
    /// At the query's projection onto the MLS surface of each scale.
    Projected,
}

/// Parameters of [`adaptive_curvature`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveConfig {
    /// The smallest scale of the ladder.
    pub h_min: f64,
    /// Number of scales, each [`SCALE_RATIO`] times the previous (at least 2).
    pub scales: usize,
    /// Γ, the half-width of the confidence intervals in predicted standard deviations.
    pub confidence: f64,
    /// Scales below this multiple of the local spacing are not used at a point.
    pub min_h_factor: f64,
    /// Cutoff, minimum neighbours and projection rules; its `h` is ignored.
    pub surface: MlsConfig,
}

impl AdaptiveConfig {
    /// Five scales from `h_min` to `4 h_min`, Γ = 2, scales of at least 2 local spacings.
    pub fn new(h_min: f64) -> Self {
        Self {
            h_min,
            scales: 5,
            confidence: 2.0,
            min_h_factor: crate::normals::DEFAULT_H_FACTOR,
            surface: MlsConfig::new(h_min),
        }
    }

    /// The scale `h_j`.
    pub fn scale(&self, j: usize) -> f64 {
        self.h_min * SCALE_RATIO.powi(j as i32)
    }

    /// The largest scale of the ladder.
    pub fn h_max(&self) -> f64 {
        self.scale(self.scales.max(2) - 1)
    }

    /// The surface's configuration at scale `j`.
    fn surface_at(&self, j: usize) -> MlsConfig {
        MlsConfig {
            h: self.scale(j),
            ..self.surface
        }
    }
}

/// The adaptive estimate at one query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptivePoint {
    /// Where the curvature was evaluated (the query, or its projection at scale `h`).
    pub point: Point,
    /// The curvature; `k1`, `k2`, `mean`, `gauss` extrapolated when `extrapolated` is set,
    /// normal and directions those of scale `h`.
    pub curvature: Curvature,
    /// The chosen scale.
    pub h: f64,
    /// Estimated position noise σ around the point.
    pub noise: f64,
    /// Predicted standard deviation of k1 and k2 from noise at the chosen scale (before any
    /// extrapolation, which roughly doubles it).
    pub scatter: f64,
    /// Whether the h² bias was removed by extrapolation.
    pub extrapolated: bool,
}

/// Outcome for one query point.
pub type AdaptiveResult = Result<AdaptivePoint, PointStatus>;

#[derive(Clone, Copy, Debug)]
struct Estimate {
    h: f64,
    point: Point,
    curvature: Curvature,
    /// `1 / (h² √(2 Σw))`: the scatter per unit of σ·C.
    unit_scatter: f64,
}

#[derive(Clone, Debug, Default)]
struct State {
    estimates: Vec<Estimate>,
    noise: Option<f64>,
    /// Intersection of the confidence intervals so far, `[k1, k2]`.
    lower: [f64; 2],
    upper: [f64; 2],
    chosen: Option<usize>,
    /// The scale the chosen one is compared with for the bias.
    partner: Option<usize>,
    failure: Option<PointStatus>,
    done: bool,
}

/// Curvature at each query with a per-point scale chosen from the ladder of `config`: builds
/// an [`AdaptiveSurface`] and evaluates it once.
///
/// Errors are per point as in [`MlsSurface::curvature_at_points`]; the outer error is a bad
/// configuration or cloud.
pub fn adaptive_curvature(
    points: &[Point],
    normals: &[Vector],
    queries: &[Point],
    at: Location,
    config: &AdaptiveConfig,
    par: Parallelism,
) -> Result<Vec<AdaptiveResult>, ConfigError> {
    Ok(AdaptiveSurface::new(points, normals, config)?.curvature_at_points(queries, at, par))
}

/// The MLS surfaces of one cloud at every scale of the ladder, built once and evaluated in as
/// many batches of queries as wanted. Holds one [`MlsSurface`] per scale, all sharing one set of
/// samples and one k-d tree ([`MlsSurface::with_config`]).
#[derive(Debug)]
pub struct AdaptiveSurface {
    config: AdaptiveConfig,
    ladder: Vec<MlsSurface>,
}

impl AdaptiveSurface {
    /// Builds the surfaces of the ladder (at least two scales).
    pub fn new(
        points: &[Point],
        normals: &[Vector],
        config: &AdaptiveConfig,
    ) -> Result<Self, ConfigError> {
        let first = MlsSurface::new(points, normals, config.surface_at(0))?;
        Self::over(first, config)
    }

    /// The surfaces of the ladder over an indexed cloud with its `normals` (in input order).
    pub fn from_cloud(
        cloud: IndexedCloud<'_>,
        normals: &[Vector],
        config: &AdaptiveConfig,
    ) -> Result<Self, ConfigError> {
        let first = MlsSurface::from_cloud(cloud, normals, config.surface_at(0))?;
        Self::over(first, config)
    }

    /// The ladder from its first surface: one set of samples and one tree for every scale.
    fn over(first: MlsSurface, config: &AdaptiveConfig) -> Result<Self, ConfigError> {
        let mut ladder = Vec::with_capacity(config.scales.max(2));
        for j in 1..config.scales.max(2) {
            ladder.push(first.with_config(config.surface_at(j))?);
        }
        ladder.insert(0, first);
        Ok(Self {
            config: *config,
            ladder,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &AdaptiveConfig {
        &self.config
    }

    /// Curvature at each query, in query order, each at its own scale.
    pub fn curvature_at_points(
        &self,
        queries: &[Point],
        at: Location,
        par: Parallelism,
    ) -> Vec<AdaptiveResult> {
        let config = &self.config;
        let scales = self.ladder.len();
        let mut states = vec![
            State {
                lower: [f64::NEG_INFINITY; 2],
                upper: [f64::INFINITY; 2],
                ..State::default()
            };
            queries.len()
        ];
        for (j, surface) in self.ladder.iter().enumerate() {
            let active: Vec<usize> = (0..queries.len()).filter(|&i| !states[i].done).collect();
            if active.is_empty() {
                break;
            }
            let h = surface.kernel().h();
            let at_scale: Vec<Point> = active.iter().map(|&i| queries[i]).collect();
            let last = j + 1 == scales;
            // A scale is used where it resolves the local spacing s = √(π h² / Σw) at the
            // query (Σw its kernel's weight sum there), h ≥ min_h_factor · s; the largest
            // scale is the best there is in a sparse region.
            let min_weight_sum = if last {
                0.0
            } else {
                std::f64::consts::PI * config.min_h_factor * config.min_h_factor
            };
            let results = match at {
                Location::Input => surface
                    .curvature_at_points(&at_scale, par)
                    .into_iter()
                    .map(|r| {
                        r.map(|r| {
                            let weight_sum = r.implicit.weight_sum * (-r.implicit.log_scale).exp();
                            (weight_sum >= min_weight_sum).then_some(r)
                        })
                    })
                    .collect(),
                // Tested before projecting: where most of a cloud is sparser than the first
                // scale resolves, that saves a projection per point.
                Location::Projected => {
                    surface.project_points_resolved(&at_scale, min_weight_sum, par)
                }
            };
            // Admissible estimates, with the noise estimate where the point has none yet.
            let needs_noise: Vec<bool> =
                active.iter().map(|&i| states[i].noise.is_none()).collect();
            let step = |ev: &mut crate::surface::Evaluator<'_>, k: usize| {
                let Some(r) = results[k]? else {
                    return Ok(None);
                };
                let weight_sum = r.implicit.weight_sum * (-r.implicit.log_scale).exp();
                let noise = needs_noise[k].then(|| residual_noise(ev, &r.point, &r.curvature, h));
                Ok(Some((
                    Estimate {
                        h,
                        point: r.point,
                        curvature: r.curvature,
                        unit_scatter: 1.0 / (h * h * (2.0 * weight_sum).sqrt()),
                    },
                    noise,
                )))
            };
            type Step = Result<Option<(Estimate, Option<f64>)>, PointStatus>;
            let steps: Vec<Step> = par.map_init(
                active.len(),
                64,
                || surface.evaluator(),
                |ev, k| step(ev, k),
            );
            for (&i, step) in active.iter().zip(steps) {
                advance(&mut states[i], step, config.confidence, last);
            }
        }
        states.iter().map(finish).collect()
    }
}

/// Takes one scale's outcome into a point's state.
fn advance(
    state: &mut State,
    step: Result<Option<(Estimate, Option<f64>)>, PointStatus>,
    confidence: f64,
    last: bool,
) {
    match step {
        Err(status) => {
            // A larger h may still reach enough samples; once estimates exist, the ladder
            // stops at the last good one.
            if state.estimates.is_empty() {
                state.failure = Some(status);
            } else if state.chosen.is_none() {
                state.chosen = Some(state.estimates.len() - 1);
                state.partner = state.estimates.len().checked_sub(2);
            }
            state.done = state.done || !state.estimates.is_empty() || last;
        }
        Ok(None) => state.done = last,
        Ok(Some((estimate, noise))) => {
            if let Some(noise) = noise {
                state.noise = Some(noise);
            }
            state.estimates.push(estimate);
            let index = state.estimates.len() - 1;
            if state.chosen.is_some() {
                // This scale was only wanted as the partner of the chosen one.
                state.partner = Some(index);
                state.done = true;
                return;
            }
            let sd = NOISE_GAIN * state.noise.unwrap_or(0.0) * estimate.unit_scatter;
            let k = [estimate.curvature.k1, estimate.curvature.k2];
            let mut agree = true;
            for (c, k) in k.into_iter().enumerate() {
                let lower = state.lower[c].max(k - confidence * sd);
                let upper = state.upper[c].min(k + confidence * sd);
                agree &= lower <= upper;
                state.lower[c] = lower;
                state.upper[c] = upper;
            }
            if !agree && index > 0 {
                state.chosen = Some(index - 1);
                state.partner = Some(index);
                state.done = true;
            } else if last {
                state.chosen = Some(index);
                state.partner = index.checked_sub(1);
                state.done = true;
            }
        }
    }
}

fn finish(state: &State) -> AdaptiveResult {
    let Some(chosen) = state.chosen.and_then(|c| state.estimates.get(c)) else {
        return Err(state.failure.unwrap_or(PointStatus::TooFewNeighbours));
    };
    let noise = state.noise.unwrap_or(0.0);
    let scatter = NOISE_GAIN * noise * chosen.unit_scatter;
    let mut curvature = chosen.curvature;
    let mut extrapolated = false;
    if let Some(partner) = state.partner.and_then(|p| state.estimates.get(p)) {
        let (ha2, hb2) = (chosen.h * chosen.h, partner.h * partner.h);
        let bias = |a: f64, b: f64| ha2 * (b - a) / (hb2 - ha2);
        let b1 = bias(chosen.curvature.k1, partner.curvature.k1);
        let b2 = bias(chosen.curvature.k2, partner.curvature.k2);
        if b1.abs().max(b2.abs()) > 2.0 * scatter {
            let (k1, k2) = (curvature.k1 - b1, curvature.k2 - b2);
            // Extrapolation keeps the order except near umbilics; if it swaps them, the
            // directions follow, keeping d1 × d2 = normal.
            if k1 >= k2 {
                (curvature.k1, curvature.k2) = (k1, k2);
            } else {
                (curvature.k1, curvature.k2) = (k2, k1);
                (curvature.d1, curvature.d2) = (curvature.d2, -curvature.d1);
            }
            let (k1, k2) = (curvature.k1, curvature.k2);
            curvature.mean = 0.5 * (k1 + k2);
            curvature.gauss = k1 * k2;
            extrapolated = true;
        }
    }
    Ok(AdaptivePoint {
        point: chosen.point,
        curvature,
        h: chosen.h,
        noise,
        scatter,
        extrapolated,
    })
}

/// Residuals are taken within this many h of the point: farther out the quartic terms of the
/// real surface, which the fitted cubic lacks, would pass for noise; closer in, too few samples
/// are left after fitting ten terms (the estimate's own scatter then stops the scale too early
/// at some points).
const NOISE_WINDOW: f64 = 2.0;

/// Fewer residual degrees of freedom than about this many samples' worth give no estimate.
const MIN_DOF: f64 = 3.0;

/// σ of the samples around `x` off the local surface, Gaussian-weighted at scale `h` within
/// [`NOISE_WINDOW`]` · h`, unbiased for independent noise (the residual sum of squares over its
/// expectation per unit variance); 0 when too few samples.
///
/// The residuals are those of a weighted least-squares cubic in the tangent coordinates
/// (`u = d1·d`, `v = d2·d`; all ten terms: offset, tilt, quadric and cubic) to the heights
/// `n·d`: on clean data with varying curvature the cubic terms would otherwise pass for noise
/// and push the scale up. The MLS quadric `−½(k1 u² + k2 v²)` is subtracted from the heights
/// first; the fit would absorb it anyway (any change of it of degree ≤ 2 leaves σ as it is, up
/// to rounding), so it only keeps the fitted coefficients small.
fn residual_noise(ev: &mut crate::surface::Evaluator<'_>, x: &Point, c: &Curvature, h: f64) -> f64 {
    type Basis = nalgebra::SVector<f64, 10>;
    let a = 1.0 / (h * h);
    let reach2 = (NOISE_WINDOW * h).powi(2);
    // (weight, basis, residual) of each sample in the window.
    let rows: Vec<(f64, Basis, f64)> = ev
        .support_of(x)
        .iter()
        .filter_map(|s| {
            let d = s.point - x;
            let d2 = d.norm_squared();
            (d2 <= reach2).then(|| {
                let (u, v) = (c.d1.dot(&d), c.d2.dot(&d));
                let r = c.normal.dot(&d) + 0.5 * (c.k1 * u * u + c.k2 * v * v);
                // In units of h, so that the normal equations stay well conditioned.
                let (u, v) = (u / h, v / h);
                let phi = Basis::from_column_slice(&[
                    1.0,
                    u,
                    v,
                    u * u,
                    u * v,
                    v * v,
                    u * u * u,
                    u * u * v,
                    u * v * v,
                    v * v * v,
                ]);
                ((-a * d2).exp(), phi, r)
            })
        })
        .collect();
    type Square = nalgebra::SMatrix<f64, 10, 10>;
    let (mut normal, mut normal2) = (Square::zeros(), Square::zeros());
    let mut rhs = Basis::zeros();
    let (mut sw, mut srr) = (0.0, 0.0);
    for (w, phi, r) in &rows {
        let outer = phi * phi.transpose();
        normal += *w * outer;
        normal2 += (w * w) * outer;
        rhs += *w * *r * phi;
        sw += w;
        srr += w * r * r;
    }
    // Residual sum of squares of the weighted fit, and its expectation per unit σ²:
    // E[Σ w e²] = σ² (Σ w − Σ w² φᵀ A⁻¹ φ) for independent noise of variance σ², the last
    // sum being tr(A⁻¹ Σ w² φ φᵀ).
    let (explained, leverage) = match normal.cholesky() {
        Some(ch) => (
            rhs.dot(&ch.solve(&rhs)),
            ch.inverse().component_mul(&normal2).sum(),
        ),
        // Samples on a line do not determine the cubic terms: the offset alone.
        None => (
            rhs[0] * rhs[0] / sw,
            rows.iter().map(|(w, _, _)| w * w).sum::<f64>() / sw,
        ),
    };
    let dof = sw - leverage;
    if !(sw > 0.0 && dof > MIN_DOF * sw / rows.len().max(1) as f64) {
        return 0.0;
    }
    ((srr - explained).max(0.0) / dof).sqrt()
}

/// First-order correction of curvature at a projected point for the shrinkage of the MLS
/// surface of scale `h`.
///
/// The MLS surface of a smooth sampled surface lies about `δ = (k1 + k2) h²/4` inside it
/// (towards the centres of curvature; `docs/validation.md`), and the parallel surface at that
/// distance has curvatures `k/(1 − kδ)`. Inverting, `k_true ≈ k/(1 + kδ)` with δ from the
/// measured curvatures. Only for curvature at projected points: at the input points the level
/// set through the point is not shrunk.
pub fn correct_shrinkage(curvature: &Curvature, h: f64) -> Curvature {
    let delta = 0.5 * curvature.mean * h * h;
    let k1 = curvature.k1 / (1.0 + curvature.k1 * delta);
    let k2 = curvature.k2 / (1.0 + curvature.k2 * delta);
    Curvature {
        k1,
        k2,
        mean: 0.5 * (k1 + k2),
        gauss: k1 * k2,
        ..*curvature
    }
}

#[cfg(test)]
mod tests;
