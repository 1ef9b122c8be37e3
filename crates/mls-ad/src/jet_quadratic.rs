//! The witness of the jet's degree-2 candidates (heights only, `JetConfig::quadratic`), from
//! the definition in `mls_core::jet`'s documentation, by its own route: dense weighted design
//! matrices, normal equations solved by LU, and the curvature of `F = w − P(u, v)` by
//! hyper-dual differentiation ([`foot_curvature`]).
//!
//! They are sought only where the ladder's choice is not resolved already (`jet::resolved`: its
//! predicted error above 1e-2 max |k| + 1e-4/h; the witness's copy is in [`crate::jet`]) or the
//! ladder has only a lower-degree fallback (or nothing). At a query x, in the ladder's frame
//! `(t1, t2, n)`:
//!
//! - supports `ρ_j = 3h·√2^j`, `j < 4`; the largest `ρ_last` whose ball (every sample, any
//!   normal, distance ≤ ρ) holds at most 2048 samples, or the first;
//! - at each ρ the samples with `|q − x| < ρ` and a normal facing n, in the coordinates
//!   `(u, v, z) = ((q − x)·t1, (q − x)·t2, (q − x)·n)/ρ` with the weight `(1 − d²/ρ²)³` (times
//!   a robust weight τ, the samples of τ = 0 left out);
//! - the degree-2 fit of z on `1, u, v, u², uv, v²` (at least 9 samples); where its scaled
//!   curvatures and slope allow (`max(|c20|, |c02|) + |c11|/2 ≤ 1`, `c10² + c01² ≤ 1`),
//!   refitted up to three times to `z − (c20 u² + c11 uv + c02 v²)³/(u² + v²)` (the osculating
//!   circles' quartic part, from the previous round's coefficients) while the rounds contract
//!   and the bounds hold, else the plain fit; `σ̂² = Σω r²/(Σω − tr(M⁻¹M₂))` and the covariance
//!   `σ̂² M⁻¹M₂M⁻¹`;
//! - the starting frame: the ladder's, unless its normal is over 45° from the estimated normals
//!   averaged with the weights `(1 − d²/ρ_last²)³` (over 60° from it: only those facing it),
//!   or the plain fit at `ρ_last` in it has a slope over 1; then that average's;
//! - the frame turned to the normal of the plain (τ = 1) fit at `ρ_last` (`n − a10 t1 − a01 t2`,
//!   production's tangent basis about it); the plain fit at `ρ_last` in that frame gives every
//!   sample its Tukey biweight τ from its residual (file units, with that fit's circles), the
//!   scale 1.4826 × the median |residual| and the cutoff 4.685 scales; a query whose own
//!   residual (the fit's height at the origin) is not within the cutoff is an outlier;
//! - the high terms: on `ρ_last`, the degree-4 fit (at least 22.5 samples) of the heights less
//!   that support's own degree-2 fit's circles, its cubic and quartic coefficients and their
//!   covariance;
//! - each degree-2 fit's leak `E ĉ_L − c_L = M_LL⁻¹M_LH c_H` (rows c20, c11, c02), its effect
//!   `b` on each principal curvature with the variance `v` it inherits from the high terms,
//!   the bias `√max(b² − v, 0)` and the estimated error `Σ (sd² + bias²)`.

use mls_core::Sample;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::jet::{JetWitness, determined, exponents, foot_curvature};

// mls-core's documented defaults, restated once in [`crate::documented`]: the first
// degree-2 support in h, the number of supports, the most samples the largest may hold, and
// Tukey's biweight cutoff in robust standard deviations; and the rounds of the circles'
// correction and the factor of the median absolute residual that estimates one robust
// standard deviation under Gaussian noise.
use crate::documented::{
    BIWEIGHT_CUTOFF as CUTOFF, QUADRATIC_MAX_SAMPLES as MAX_SAMPLES, QUADRATIC_RADIUS as RADIUS,
    QUADRATIC_SCALES as SCALES,
};
const CIRCLE_ROUNDS: usize = 3;
const MAD_SCALE: f64 = 1.4826;

type Frame = (Vector3<f64>, Vector3<f64>, Vector3<f64>);

/// A sample in the frame, scaled by ρ, with its weight.
#[derive(Clone, Copy)]
struct Row {
    u: f64,
    v: f64,
    z: f64,
    w: f64,
}

/// The samples entering a fit at `rho`: strictly inside the ball, normal facing the frame,
/// robust weight (`tau`, sample by sample; 1 without) above 0.
fn rows(
    x: &Vector3<f64>,
    samples: &[Sample],
    frame: &Frame,
    rho: f64,
    tau: Option<&[f64]>,
) -> Vec<Row> {
    let (t1, t2, n) = frame;
    samples
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let d = s.point.coords - x;
            let t = 1.0 - d.norm_squared() / (rho * rho);
            let tau = tau.map_or(1.0, |tau| tau[i]);
            (t > 0.0 && s.normal.dot(n) > 0.0 && tau > 0.0).then(|| Row {
                u: d.dot(t1) / rho,
                v: d.dot(t2) / rho,
                z: d.dot(n) / rho,
                w: t * t * t * tau,
            })
        })
        .collect()
}

/// The quartic part of the osculating circles of the height `q0 u² + q1 uv + q2 v²`:
/// `κ³r⁴/8 = (κr²/2)³/r²` along each direction, 0 at the origin.
fn circle(q: &[f64; 3], u: f64, v: f64) -> f64 {
    let r2 = u * u + v * v;
    if r2 == 0.0 {
        return 0.0;
    }
    (q[0] * u * u + q[1] * u * v + q[2] * v * v).powi(3) / r2
}

/// A weighted least-squares design on the monomials `ex`: Φ (one row per sample), the weights
/// ω, `M = ΦᵀΩΦ`, `M₂ = ΦᵀΩ²Φ` and `M⁻¹`.
struct Design {
    phi: DMatrix<f64>,
    w: DVector<f64>,
    m: DMatrix<f64>,
    m2: DMatrix<f64>,
    inv: DMatrix<f64>,
}

impl Design {
    /// `None` where the samples do not determine the basis (the pivot test, [`determined`]).
    fn new(rows: &[Row], ex: &[(i32, i32)]) -> Option<Self> {
        let phi = monomials(rows, ex);
        let w = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.w));
        let weighted = weigh(&phi, &w);
        let m = phi.transpose() * &weighted;
        let m = (&m + m.transpose()) * 0.5;
        let m2 = weighted.transpose() * &weighted;
        if !determined(&m) {
            return None;
        }
        let inv = m.clone().try_inverse()?;
        Some(Self { phi, w, m, m2, inv })
    }

    /// The coefficients of the weighted least-squares fit to `y`: `M c = ΦᵀΩy`, by LU.
    fn solve(&self, y: &DVector<f64>) -> Option<DVector<f64>> {
        let rhs = self.phi.transpose() * self.w.component_mul(y);
        self.m.clone().lu().solve(&rhs)
    }

    /// `σ̂² = Σω r²/(Σω − tr(M⁻¹M₂))` of the residuals of `c` against `y`; `None` where the
    /// denominator is not positive.
    fn variance(&self, y: &DVector<f64>, c: &DVector<f64>) -> Option<f64> {
        let r = y - &self.phi * c;
        let rss = self.w.component_mul(&r).dot(&r);
        let dof = self.w.sum() - (&self.inv * &self.m2).trace();
        (dof > 0.0).then(|| rss / dof)
    }

    /// `σ̂² M⁻¹M₂M⁻¹`.
    fn covariance(&self, var: f64) -> DMatrix<f64> {
        &self.inv * &self.m2 * &self.inv * var
    }
}

/// Φ: the monomials `ex` at each row.
fn monomials(rows: &[Row], ex: &[(i32, i32)]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), ex.len(), |r, k| {
        rows[r].u.powi(ex[k].0) * rows[r].v.powi(ex[k].1)
    })
}

/// ΩΦ: each row of Φ times its weight.
fn weigh(phi: &DMatrix<f64>, w: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(phi.nrows(), phi.ncols(), |r, k| phi[(r, k)] * w[r])
}

/// The heights less the circles of the scaled quadratic `q`.
fn less_circles(rows: &[Row], q: &[f64; 3]) -> DVector<f64> {
    DVector::from_iterator(rows.len(), rows.iter().map(|r| r.z - circle(q, r.u, r.v)))
}

/// A degree-2 fit with the circles' correction: scaled coefficients, design, σ̂² and the
/// scaled quadratic `(c20, c11, c02)` whose circles were subtracted (zeros for the plain fit).
struct Quadratic {
    c: DVector<f64>,
    design: Design,
    var: f64,
    circles: [f64; 3],
}

/// Whether the circles' series applies to the scaled coefficients `c`: `max(|c20|, |c02|) +
/// |c11|/2 ≤ 1` (every scaled normal curvature |κρ| ≤ 2) and `c10² + c01² ≤ 1` (slope ≤ 45°).
fn circles_hold(c: &DVector<f64>) -> bool {
    c[3].abs().max(c[5].abs()) + 0.5 * c[4].abs() <= 1.0 && c[1] * c[1] + c[2] * c[2] <= 1.0
}

fn quadratic(rows: &[Row]) -> Option<Quadratic> {
    if (rows.len() as f64) < 1.5 * 6.0 {
        return None;
    }
    let design = Design::new(rows, &exponents(2))?;
    let q = |c: &DVector<f64>| [c[3], c[4], c[5]];
    let plain = design.solve(&less_circles(rows, &[0.0; 3]))?;
    let mut c = plain.clone();
    let mut circled = circles_hold(&c);
    if circled {
        // The rounds go on while they contract (the change of the quadratic part no larger
        // than the round before's) and the bounds hold; else the plain fit, without circles.
        let mut previous = f64::INFINITY;
        for _ in 0..CIRCLE_ROUNDS {
            let before = q(&c);
            c = design.solve(&less_circles(rows, &before))?;
            let change = (0..3)
                .map(|k| (c[3 + k] - before[k]).abs())
                .fold(0.0f64, f64::max);
            if !circles_hold(&c) || !(change <= previous) {
                c = plain.clone();
                circled = false;
                break;
            }
            previous = change;
        }
    }
    let circles = if circled { q(&c) } else { [0.0; 3] };
    let var = design.variance(&less_circles(rows, &circles), &c)?;
    Some(Quadratic {
        c,
        design,
        var,
        circles,
    })
}

/// The robust weights τ of `samples` (index by index) from their residuals to `plain`, the
/// degree-2 fit at `rho` in `frame`, and the cutoff (file units): Tukey's biweight
/// `(1 − (r/cut)²)²` (0 beyond the cutoff), `cut = 4.685 · 1.4826 · m` with `m` the element at
/// `len/2` of the ascending |r| over the samples of the fit's support (within ρ, normal facing
/// the frame), the residuals in file units with the fit's circles; τ = 1 outside that
/// support, and for all where the cutoff is 0.
fn robust_weights(
    x: &Vector3<f64>,
    samples: &[Sample],
    frame: &Frame,
    rho: f64,
    plain: &Quadratic,
) -> (Vec<f64>, f64) {
    let (t1, t2, n) = frame;
    let ex = exponents(2);
    // File units: a_ij = c_ij ρ^(1−i−j); the circles' quadratic likewise (c/ρ).
    let a: Vec<f64> = (0..6)
        .map(|k| plain.c[k] * rho.powi(1 - ex[k].0 - ex[k].1))
        .collect();
    let circles = plain.circles.map(|c| c / rho);
    let residuals: Vec<Option<f64>> = samples
        .iter()
        .map(|s| {
            let d = s.point.coords - x;
            if !(d.norm_squared() < rho * rho) || !(s.normal.dot(n) > 0.0) {
                return None;
            }
            let (u, v, z) = (d.dot(t1), d.dot(t2), d.dot(n));
            let p: f64 = ex
                .iter()
                .zip(&a)
                .map(|(&(i, j), a)| a * u.powi(i) * v.powi(j))
                .sum();
            Some(z - p - circle(&circles, u, v))
        })
        .collect();
    let mut abs: Vec<f64> = residuals.iter().flatten().map(|r| r.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let cut = abs
        .get(abs.len() / 2)
        .map_or(0.0, |m| CUTOFF * MAD_SCALE * m);
    let tau = residuals
        .iter()
        .map(|r| match r {
            Some(r) if cut > 0.0 => {
                let t = r / cut;
                if t.abs() < 1.0 {
                    (1.0 - t * t).powi(2)
                } else {
                    0.0
                }
            }
            _ => 1.0,
        })
        .collect();
    (tau, cut)
}

/// The cubic and quartic coefficients `a_ij` (exponents 6..15 of [`exponents`]`(4)`) of the
/// degree-4 fit at `rho` to the heights less the circles of the scaled quadratic `circles` (the
/// ones that support's degree-2 fit subtracted), in file units, with their covariance.
fn high_terms(rows: &[Row], rho: f64, circles: &[f64; 3]) -> Option<(DVector<f64>, DMatrix<f64>)> {
    if (rows.len() as f64) < 1.5 * 15.0 {
        return None;
    }
    let ex = exponents(4);
    let design = Design::new(rows, &ex)?;
    let y = less_circles(rows, circles);
    let c = design.solve(&y)?;
    let cov = design.covariance(design.variance(&y, &c)?);
    // Scaled c_ij = a_ij ρ^(i+j−1).
    let unscale = |k: usize| rho.powi(1 - ex[k].0 - ex[k].1);
    Some((
        DVector::from_fn(9, |k, _| c[6 + k] * unscale(6 + k)),
        DMatrix::from_fn(9, 9, |a, b| {
            cov[(6 + a, 6 + b)] * unscale(6 + a) * unscale(6 + b)
        }),
    ))
}

/// The degree-2 candidate at `rho` with its estimated error, given the high terms.
fn candidate(
    x: &Vector3<f64>,
    frame: &Frame,
    rows: &[Row],
    rho: f64,
    fit: &Quadratic,
    (high, high_cov): &(DVector<f64>, DMatrix<f64>),
) -> Option<(f64, JetWitness)> {
    let cov = fit.design.covariance(fit.var);
    let cov = Matrix3::from_fn(|a, b| cov[(3 + a, 3 + b)]) / (rho * rho);
    // M_LH = Σ ω φ_L φ_Hᵀ over the cubic and quartic monomials; the leak of the scaled
    // coefficients is M_LL⁻¹ M_LH c_H.
    let ex = exponents(4);
    let m_lh = fit.design.phi.transpose() * weigh(&monomials(rows, &ex[6..]), &fit.design.w);
    let leak = fit.design.m.clone().lu().solve(&m_lh)?;
    // In file units: (a20, a11, a02) = c/ρ, c_H = a_H ρ^(i+j−1).
    let s = DMatrix::from_fn(3, 9, |a, b| {
        leak[(3 + a, b)] * rho.powi(ex[6 + b].0 + ex[6 + b].1 - 1) / rho
    });
    let bias = &s * high;
    let bias_cov = &s * high_cov * s.transpose();
    let at = foot_curvature(x, frame, fit.c.as_slice(), &exponents(2), rho, &cov);
    // δk_i = −g_i·δ(a20, a11, a02).
    let bias = at.rows.map(|g| {
        let g = DVector::from_column_slice((-g).as_slice());
        let b = g.dot(&bias);
        let v = g.dot(&(&bias_cov * &g)).max(0.0);
        (b * b - v).max(0.0).sqrt()
    });
    let mse = (0..2).map(|i| at.sd[i].powi(2) + bias[i].powi(2)).sum();
    let eig = fit.design.m.clone().symmetric_eigenvalues();
    Some((
        mse,
        JetWitness {
            k1: at.k[0],
            k2: at.k[1],
            sd: at.sd,
            bias,
            degree: 2,
            radius: rho,
            condition: eig.max() / eig.min(),
            foot: at.foot,
            slope_weight: 0.0,
            normal: at.normal,
            directions: at.directions,
            noise: fit.var.sqrt() * rho,
        },
    ))
}

/// The frame of the samples' normals averaged with the weights `(1 − d²/ρ²)³` over `|q − x| < ρ`;
/// where that average is over 60° from the ladder's normal (`cos 60° = 0.5`: across a thin
/// part), the average of only the normals facing it; the ladder's frame where the average
/// vanishes.
fn wide_frame(x: &Vector3<f64>, samples: &[Sample], rho: f64, ladder: &Frame) -> Frame {
    let average = |keep: &dyn Fn(&Sample) -> bool| -> Vector3<f64> {
        samples
            .iter()
            .filter(|s| keep(s))
            .map(|s| {
                let s2 = (s.point.coords - x).norm_squared() / (rho * rho);
                if s2 < 1.0 {
                    s.normal * (1.0 - s2).powi(3)
                } else {
                    Vector3::zeros()
                }
            })
            .sum()
    };
    let own = ladder.2;
    let mut sum = average(&|_| true);
    if !(sum.dot(&own) > 0.5 * sum.norm()) {
        sum = average(&|s| s.normal.dot(&own) > 0.0);
    }
    if !(sum.norm() > 0.0) {
        return *ladder;
    }
    let n = sum.normalize();
    let (t1, t2) = mls_core::math::tangent_basis(&n);
    (t1, t2, n)
}

/// The query is an outlier: beyond the robust cutoff of the largest support's plain fit
/// (`PointStatus::Outlier`).
pub(crate) struct Outlier;

/// The degree-2 candidates at `x`, in increasing radius, each with its estimated squared error
/// (summed over k1 and k2); none where the fits of the largest support or the high terms
/// cannot be fitted; [`Outlier`] where the query lies beyond the robust cutoff.
pub(crate) fn quadratic_candidates(
    x: &Vector3<f64>,
    samples: &[Sample],
    h: f64,
    frame: &Frame,
) -> Result<Vec<(f64, JetWitness)>, Outlier> {
    let radii: Vec<f64> = (0..SCALES)
        .map(|j| RADIUS * h * 2f64.sqrt().powi(j as i32))
        .collect();
    let last = radii
        .iter()
        .rposition(|r| {
            let inside = samples
                .iter()
                .filter(|s| (s.point.coords - x).norm_squared() <= r * r)
                .count();
            inside <= MAX_SAMPLES
        })
        .unwrap_or(0);
    let top = radii[last];
    // The starting frame: the ladder's, unless its normal is over 45° from the normals averaged
    // over the largest support or the plain fit in it is steeper than 45° at the query; then
    // that average's.
    let wide = wide_frame(x, samples, top, frame);
    let tilted_in = |frame: &Frame| {
        quadratic(&rows(x, samples, frame, top, None))
            .filter(|t| (t.c[1] * t.c[1] + t.c[2] * t.c[2]).sqrt() <= 1.0)
    };
    let from_ladder = if frame.2.dot(&wide.2) >= 0.5f64.sqrt() {
        tilted_in(frame).map(|t| (*frame, t))
    } else {
        None
    };
    let Some((frame, tilted)) = from_ladder.or_else(|| tilted_in(&wide).map(|t| (wide, t))) else {
        return Ok(Vec::new());
    };
    let frame = &frame;
    // The frame turned to the normal of the largest support's plain fit (its slopes a10, a01:
    // the scaled c10, c01 are the file-unit ones).
    let (t1, t2, n) = frame;
    let turned = (n - t1 * tilted.c[1] - t2 * tilted.c[2]).normalize();
    let (u1, u2) = mls_core::math::tangent_basis(&turned);
    let frame = &(u1, u2, turned);
    let Some(plain) = quadratic(&rows(x, samples, frame, top, None)) else {
        return Ok(Vec::new());
    };
    let (tau, cut) = robust_weights(x, samples, frame, top, &plain);
    // The query's own residual: the fit's height at the origin, a00 = c00 ρ.
    if cut > 0.0 && !((plain.c[0] * top).abs() < cut) {
        return Err(Outlier);
    }
    let fits: Vec<(f64, Vec<Row>, Option<Quadratic>)> = radii[..=last]
        .iter()
        .map(|&rho| {
            let rows = rows(x, samples, frame, rho, Some(&tau));
            let fit = quadratic(&rows);
            (rho, rows, fit)
        })
        .collect();
    let Some(circles) = fits[last].2.as_ref().map(|f| f.circles) else {
        return Ok(Vec::new());
    };
    let Some(high) = high_terms(&fits[last].1, top, &circles) else {
        return Ok(Vec::new());
    };
    Ok(fits
        .iter()
        .filter_map(|(rho, rows, fit)| candidate(x, frame, rows, *rho, fit.as_ref()?, &high))
        .collect())
}
