//! Degree-2 candidates beside the degree-4 ladder, for noisy heights without usable normals.
//!
//! Under position noise a degree-4 fit's curvature scatters several times more than a degree-2
//! fit's on the same support, and the degree-2 fit's truncation bias (the surface's cubic and
//! quartic terms, leaking into its quadratic coefficients) is what limits it. That leak is
//! linear in the omitted terms: with `M` the weighted normal matrix split into the fitted
//! monomials `L` (degree ≤ 2) and the omitted ones `H` (degrees 3 and 4), the degree-2
//! coefficients have the expectation
//!
//! $$ E\,\hat c_L = c_L + M_{LL}^{-1} M_{LH}\, c_H $$
//!
//! (the omitted-variable bias of least squares). Most of a curved surface's quartic part is its
//! normal sections' osculating circles, a function of the quadratic part alone: each fit
//! subtracts them from the heights ([`circle_term`]). What is left, `c_H`, comes from one
//! degree-4 fit on the largest degree-2 support, where its scatter is least, with its
//! covariance; each degree-2 candidate carries its predicted bias and that bias's own variance,
//! and joins the degree-4 ladder's candidates in the choice of least estimated mean squared
//! error. Every fit weighs the samples by Tukey's biweight of their residuals to the largest
//! support's plain fit ([`robust_weights`]), so that stray samples take no part
//! (`docs/derivation.md`, "Degree").

use crate::field::Sample;
use crate::math::{Matrix, Point, Vector};

use super::JetFit;
use super::algebra::{Factor, Square};
use super::fit::PRODUCT;

/// The cubic and quartic coefficients of a degree-4 fit (the monomials 6..15 of
/// [`super::MONOMIALS`]), in file units, with their covariance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HighTerms {
    /// `a_ij` of `u^i v^j`, `i + j ∈ {3, 4}`.
    pub coefficients: [f64; 9],
    /// Their estimated covariance.
    pub covariance: [[f64; 9]; 9],
}

/// The predicted truncation bias of a degree-2 fit's `(a20, a11, a02)`, file units, with its
/// covariance (from that of the [`HighTerms`] it was computed from).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Leak {
    /// `S a_H`: the expected shift of `(a20, a11, a02)`.
    pub bias: Vector,
    /// `S Cov(a_H) Sᵀ`.
    pub covariance: Matrix,
}

/// One sample in scaled local coordinates with its weight.
#[derive(Clone, Copy, Debug)]
struct Local {
    u: f64,
    v: f64,
    z: f64,
    w: f64,
}

/// Reusable storage for the fits of this module.
#[derive(Debug, Default)]
pub struct QuadraticScratch {
    locals: Vec<Local>,
    residuals: Vec<f64>,
}

/// Samples within `radius` of `centre` whose normal faces the frame, as [`super::fit`] takes
/// them, in scaled coordinates.
fn local_samples(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    radius: f64,
    robust: Option<&[f64]>,
    locals: &mut Vec<Local>,
) {
    let (t1, t2, n) = frame;
    let inv_r2 = 1.0 / (radius * radius);
    locals.clear();
    for (i, sample) in samples.iter().enumerate() {
        let d = sample.point - centre;
        let s = d.norm_squared() * inv_r2;
        let tau = robust.map_or(1.0, |r| r[i]);
        if !(s < 1.0) || !(sample.normal.dot(n) > 0.0) || !(tau > 0.0) {
            continue;
        }
        locals.push(Local {
            u: d.dot(t1) / radius,
            v: d.dot(t2) / radius,
            z: d.dot(n) / radius,
            w: (1.0 - s) * (1.0 - s) * (1.0 - s) * tau,
        });
    }
}

/// Tukey's biweight cutoff in robust standard deviations (95 % efficiency under Gaussian
/// noise).
pub const BIWEIGHT_CUTOFF: f64 = 4.685;

/// Robust weights of `samples` (index by index) from their residuals to `fit` (a degree-2 fit
/// about `centre`, with its circles): Tukey's biweight `(1 − (r/cs)²)²`,
/// `s = 1.4826 · median |r|` over the samples the fit took, `c` = [`BIWEIGHT_CUTOFF`]; 1 for
/// the samples outside the fit's support, and for all where `s` is 0 (exact data). Returns the
/// cutoff `cs` (file units; 0 on exact data).
pub fn robust_weights(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    fit: &QuadraticFit,
    out: &mut Vec<f64>,
    scratch: &mut QuadraticScratch,
) -> f64 {
    let (t1, t2, n) = frame;
    let a = &fit.fit.coefficients;
    let r2 = fit.fit.radius * fit.fit.radius;
    let q = fit.circles;
    out.clear();
    let residual = |sample: &Sample| -> Option<f64> {
        let d = sample.point - centre;
        if !(d.norm_squared() < r2) || !(sample.normal.dot(n) > 0.0) {
            return None;
        }
        let (u, v, z) = (d.dot(t1), d.dot(t2), d.dot(n));
        Some(
            z - a[0]
                - a[1] * u
                - a[2] * v
                - a[3] * u * u
                - a[4] * u * v
                - a[5] * v * v
                - circle_term(&q, u, v),
        )
    };
    out.extend(samples.iter().map(|s| residual(s).unwrap_or(f64::NAN)));
    let abs = &mut scratch.residuals;
    abs.clear();
    abs.extend(out.iter().filter(|r| r.is_finite()).map(|r| r.abs()));
    let scale = if abs.is_empty() {
        0.0
    } else {
        let mid = abs.len() / 2;
        let (_, m, _) = abs.select_nth_unstable_by(mid, f64::total_cmp);
        1.4826 * *m
    };
    let cut = BIWEIGHT_CUTOFF * scale;
    for r in out.iter_mut() {
        *r = if r.is_finite() && cut > 0.0 {
            let x = *r / cut;
            if x.abs() < 1.0 {
                let y = 1.0 - x * x;
                y * y
            } else {
                0.0
            }
        } else {
            1.0
        };
    }
    cut
}

/// Exponents of the 15 monomials of degree ≤ 4 ([`super::MONOMIALS`]).
const EXP: [(i32, i32); 15] = super::MONOMIALS;

/// The first `K` monomials `u^p v^q` by total degree, then by the power of v (degree ≤ 8 for
/// `K` = 45), as the degree-4 fit computes them.
#[inline]
fn powers<const K: usize>(u: f64, v: f64) -> [f64; K] {
    let mut out = [0.0; K];
    super::fit::powers(u, v, &mut out);
    out
}

/// `Σ ω φ` over the first `H` monomials, `Σ ω² φ` over the first `H2`, `Σ ω z φ` over the
/// first `Z` (`H2, Z ≤ H`), and `Σ ω`.
fn moments<const H: usize, const H2: usize, const Z: usize>(
    locals: &[Local],
) -> ([f64; H], [f64; H2], [f64; Z], f64) {
    let (mut h, mut h2, mut hz) = ([0.0; H], [0.0; H2], [0.0; Z]);
    let mut weight = 0.0;
    for l in locals {
        let p = powers::<H>(l.u, l.v);
        let (w, w2, wz) = (l.w, l.w * l.w, l.w * l.z);
        for (h, p) in h.iter_mut().zip(&p) {
            *h += w * p;
        }
        for (h2, p) in h2.iter_mut().zip(&p) {
            *h2 += w2 * p;
        }
        for (hz, p) in hz.iter_mut().zip(&p) {
            *hz += wz * p;
        }
        weight += w;
    }
    (h, h2, hz, weight)
}

/// A heights-only fit of degree 4 at `radius` to the heights less the circles' quartic part of
/// `circle` (`a20, a11, a02` in file units), for the cubic and quartic terms left; `None`
/// where the support does not determine degree 4.
pub fn high_terms(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    radius: f64,
    circle: &[f64; 3],
    robust: Option<&[f64]>,
    scratch: &mut QuadraticScratch,
) -> Option<HighTerms> {
    local_samples(samples, centre, frame, radius, robust, &mut scratch.locals);
    let q = circle.map(|a| a * radius);
    for l in &mut scratch.locals {
        l.z -= circle_term(&q, l.u, l.v);
    }
    let locals = &scratch.locals;
    if (locals.len() as f64) < super::MIN_EQUATIONS_PER_COEFFICIENT * 15.0 {
        return None;
    }
    let (h, h2, hz, weight) = moments::<45, 45, 15>(locals);
    let (mut m, mut m2) = ([[0.0; 15]; 15], [[0.0; 15]; 15]);
    for a in 0..15 {
        for b in 0..15 {
            m[a][b] = h[PRODUCT[a][b]];
            m2[a][b] = h2[PRODUCT[a][b]];
        }
    }
    let (c, inv) = solve(&m, &hz)?;
    let rss: f64 = locals
        .iter()
        .map(|l| {
            let p = powers::<15>(l.u, l.v);
            let r = l.z - dot(&c, &p);
            l.w * r * r
        })
        .sum();
    let dof = weight - super::algebra::trace_product(&inv, &m2);
    if !(dof > 0.0) {
        return None;
    }
    let var = rss / dof;
    // Covariance of the scaled coefficients: σ̂² M⁻¹ M₂ M⁻¹, the rows and columns 6..15.
    let mut left = [[0.0; 15]; 9];
    for (a, row) in left.iter_mut().enumerate() {
        for (b, x) in row.iter_mut().enumerate() {
            *x = (0..15).map(|k| inv[a + 6][k] * m2[k][b]).sum();
        }
    }
    let mut covariance = [[0.0; 9]; 9];
    // Scaled c_ij = a_ij ρ^(i+j−1): a = c ρ^(1−i−j).
    let unscale = |k: usize| radius.powi(1 - EXP[k].0 - EXP[k].1);
    for a in 0..9 {
        for b in 0..9 {
            let s: f64 = (0..15).map(|k| left[a][k] * inv[k][b + 6]).sum();
            covariance[a][b] = var * s * unscale(a + 6) * unscale(b + 6);
        }
    }
    let mut coefficients = [0.0; 9];
    for (k, x) in coefficients.iter_mut().enumerate() {
        *x = c[k + 6] * unscale(k + 6);
    }
    Some(HighTerms {
        coefficients,
        covariance,
    })
}

/// A degree-2 fit's sensitivity to the omitted terms: `(a20, a11, a02)` move by `S a_H` for
/// cubic and quartic coefficients `a_H` (file units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensitivity(pub [[f64; 9]; 3]);

impl Sensitivity {
    /// The leak of `high` into the fit's curvature coefficients.
    pub fn leak(&self, high: &HighTerms) -> Leak {
        let s = &self.0;
        let mut bias = Vector::zeros();
        let mut covariance = Matrix::zeros();
        for a in 0..3 {
            bias[a] = (0..9).map(|b| s[a][b] * high.coefficients[b]).sum();
            for b in 0..3 {
                covariance[(a, b)] = (0..9)
                    .map(|i| s[a][i] * (0..9).map(|j| high.covariance[i][j] * s[b][j]).sum::<f64>())
                    .sum();
            }
        }
        Leak { bias, covariance }
    }
}

/// A heights-only fit of degree 2 at `radius` to the heights less its own circles' quartic
/// part (`circle_term`, refitted `CIRCLE_ROUNDS` times), with its sensitivity to the
/// terms it omits; `None` where the support does not determine degree 2.
pub fn quadratic(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    radius: f64,
    robust: Option<&[f64]>,
    scratch: &mut QuadraticScratch,
) -> Option<QuadraticFit> {
    local_samples(samples, centre, frame, radius, robust, &mut scratch.locals);
    let locals = &scratch.locals;
    if (locals.len() as f64) < super::MIN_EQUATIONS_PER_COEFFICIENT * 6.0 {
        return None;
    }
    // Moments: Σω φ to degree 6 (the matrix and its cross terms with degrees 3 and 4), Σω² φ
    // to degree 4, Σωz φ to degree 2.
    let (h, h2, hz, weight) = moments::<28, 15, 6>(locals);
    let (mut m, mut m2) = ([[0.0; 6]; 6], [[0.0; 6]; 6]);
    let mut cross = [[0.0; 9]; 6];
    for a in 0..6 {
        for b in 0..6 {
            m[a][b] = h[PRODUCT[a][b]];
            m2[a][b] = h2[PRODUCT[a][b]];
        }
        for b in 0..9 {
            cross[a][b] = h[PRODUCT[a][b + 6]];
        }
    }
    let (mut c, inv) = solve(&m, &hz)?;
    // The circles' quartic part, from the fit's own quadratic, refitted (it is O(κ³ρ⁴): a few
    // rounds converge) while the rounds contract, every scaled normal curvature |κρ| ≤ 2 and
    // the frame within 45° of the fit's normal. Else (a frame far off the surface, a fold,
    // a support wider than the curvature allows) the plain fit.
    let plain = c;
    let mut circled = circles_hold(&c);
    // The change of the quadratic part in the last round: the rounds must contract.
    let mut step = f64::INFINITY;
    if circled {
        for _ in 0..CIRCLE_ROUNDS {
            let before = [c[3], c[4], c[5]];
            let q = [c[3], c[4], c[5]];
            let mut r = hz;
            for l in locals {
                let t = l.w * circle_term(&q, l.u, l.v);
                let p = powers::<6>(l.u, l.v);
                for a in 0..6 {
                    r[a] -= t * p[a];
                }
            }
            c = [0.0; 15];
            for a in 0..6 {
                c[a] = (0..6).map(|b| inv[a][b] * r[b]).sum();
            }
            let change = (0..3).fold(0.0f64, |m, k| m.max((c[k + 3] - before[k]).abs()));
            if !circles_hold(&c) || !(change <= step) {
                (c, circled) = (plain, false);
                break;
            }
            step = change;
        }
    }
    let q = if circled {
        [c[3], c[4], c[5]]
    } else {
        [0.0; 3]
    };
    let rss: f64 = locals
        .iter()
        .map(|l| {
            let mut p = [0.0; 15];
            p[..6].copy_from_slice(&powers::<6>(l.u, l.v));
            let r = l.z - circle_term(&q, l.u, l.v) - dot(&c, &p);
            l.w * r * r
        })
        .sum();
    let dof = weight - super::algebra::trace_product(&inv, &m2);
    if !(dof > 0.0) {
        return None;
    }
    let var = rss / dof;
    // Rows 3..6 of M⁻¹ (c20, c11, c02).
    let sel = |a: usize, k: usize| inv[a + 3][k];
    let mut cov = Matrix::zeros();
    for a in 0..3 {
        for b in 0..3 {
            let s: f64 = (0..6)
                .map(|k| sel(a, k) * (0..6).map(|j| m2[k][j] * sel(b, j)).sum::<f64>())
                .sum();
            cov[(a, b)] = var * s;
        }
    }
    // d(scaled c_L)/d(scaled c_H) = M⁻¹ M_LH; scaled c_H = a_H ρ^(i+j−1), (a20, …) = c/ρ.
    let scale = |k: usize| radius.powi(EXP[k].0 + EXP[k].1 - 1);
    let mut s = [[0.0; 9]; 3];
    for (a, row) in s.iter_mut().enumerate() {
        for (b, x) in row.iter_mut().enumerate() {
            *x = (0..6).map(|k| sel(a, k) * cross[k][b]).sum::<f64>() * scale(b + 6) / radius;
        }
    }
    let mut coefficients = [0.0; 15];
    for k in 0..6 {
        coefficients[k] = c[k] * radius.powi(1 - EXP[k].0 - EXP[k].1);
    }
    Some(QuadraticFit {
        fit: JetFit {
            degree: 2,
            radius,
            neighbours: locals.len(),
            equations: locals.len(),
            coefficients,
            noise: var.sqrt() * radius,
            covariance: cov / (radius * radius),
            slope_weight: 0.0,
        },
        sensitivity: Sensitivity(s),
        circles: q.map(|x| x / radius),
    })
}

/// Whether the circles' correction applies to the scaled coefficients `c`: the quadratic
/// part's normal curvatures `|κρ| ≤ 2` (`2(max(|c20|, |c02|) + |c11|/2)` bounds them) and the
/// slope `c10² + c01² ≤ 1`.
fn circles_hold(c: &[f64; 15]) -> bool {
    c[3].abs().max(c[5].abs()) + 0.5 * c[4].abs() <= 1.0 && c[1] * c[1] + c[2] * c[2] <= 1.0
}

/// A degree-2 fit with what the candidates and the high terms need of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadraticFit {
    /// The fit (its coefficients with the circles' part removed from the heights).
    pub fit: JetFit,
    /// Its sensitivity to the omitted cubic and quartic terms.
    pub sensitivity: Sensitivity,
    /// The quadratic `(a20, a11, a02)` (file units) whose circles were subtracted; zeros where
    /// the circles' series does not hold and the fit is plain.
    pub circles: [f64; 3],
}

/// Rounds of the circles' correction after the plain fit.
const CIRCLE_ROUNDS: usize = 3;

/// The quartic part `q³/r²` of the normal sections' osculating circles, for the quadratic
/// height `q = c20 u² + c11 uv + c02 v²` (coefficients `q`): along a direction of normal
/// curvature κ the circle is `z = κr²/2 + κ³r⁴/8 + …`, and `κ³r⁴/8 = (κr²/2)³/r²`.
#[inline]
fn circle_term(q: &[f64; 3], u: f64, v: f64) -> f64 {
    let r2 = u * u + v * v;
    if r2 > 0.0 {
        let z2 = q[0] * u * u + q[1] * u * v + q[2] * v * v;
        z2 * z2 * z2 / r2
    } else {
        0.0
    }
}

/// Solution and inverse of the symmetric system `m c = rhs`; `None` where the Cholesky
/// factor's pivot test finds the basis undetermined.
fn solve<const N: usize>(m: &Square<N>, rhs: &[f64; N]) -> Option<([f64; 15], Square<N>)> {
    let mut factor = Factor {
        l: *m,
        inv_diag: [0.0; N],
    };
    if !factor.factor() {
        return None;
    }
    let mut inv = [[0.0; N]; N];
    factor.inverse(&mut inv);
    let mut c = [0.0; 15];
    c[..N].copy_from_slice(&factor.solve(rhs));
    Some((c, inv))
}

fn dot(c: &[f64; 15], p: &[f64; 15]) -> f64 {
    c.iter().zip(p).map(|(c, p)| c * p).sum()
}
