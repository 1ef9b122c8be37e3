//! One weighted jet fit: the support in local coordinates, the normal equations read off its
//! weighted moments, and their solution with the noise estimates and the covariance of the
//! curvature coefficients (`docs/derivation.md`, the jet).

use crate::field::Sample;
use crate::kernels::{Kernels, dispatch};
use crate::math::{Matrix, Point, Vector};

use super::algebra::{Factor, Square, symmetric, trace_product};
use super::{
    A02, A11, A20, JetConfig, JetFit, MIN_EQUATIONS_PER_COEFFICIENT, MONOMIALS, NormalData,
    coefficient_count,
};

/// Fits a jet of `config`'s degree and normal data to the `samples` within the support radius
/// `radius` of `centre` (the query, in the samples' frame), in the frame `(t1, t2, n)`. With
/// slopes, `slope_weight` gives λ for a single round instead of the fit's own estimate (two
/// rounds from λ = 1). Returns `None` when no degree ≥ 2 is determined.
///
/// Runs with the CPU's best [`crate::kernels`] (the same bits on each).
pub fn fit(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    radius: f64,
    config: &JetConfig,
    slope_weight: Option<f64>,
    scratch: &mut JetScratch,
) -> Option<JetFit> {
    dispatch!(k => k.jet_fit(samples, centre, frame, radius, config, slope_weight, scratch))
}

/// [`fit`], compiled into each of [`crate::kernels`]' instruction sets: it and everything it
/// calls here are `#[inline(always)]`, since only inlined code takes on the features of the
/// `#[target_feature]` copy. In the one function this makes, arrays are written in place, not
/// returned (returned, they became copies through `memcpy`), and filled by loops, not
/// `std::array::from_fn` (whose closures stayed out of line, compiled for the baseline).
#[inline(always)]
pub(crate) fn jet_fit(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    radius: f64,
    config: &JetConfig,
    slope_weight: Option<f64>,
    scratch: &mut JetScratch,
) -> Option<JetFit> {
    let normals = config.normals;
    let max_degree = config.degree.clamp(2, 4);
    let locals = &mut scratch.locals;
    local_samples(samples, centre, frame, radius, normals, locals);
    let moments = Moments::of(locals);
    let count = moments.heights;
    let slope_rows = 2 * moments.slope_samples;
    // A degree needs 1.5 equations (heights and slopes) per coefficient: a count, so that the
    // choice never hangs on rounding; the pivot test in `solve` only catches degenerate layouts such as a line.
    let mut deg = max_degree;
    while deg > 2
        && ((count + slope_rows) as f64)
            < MIN_EQUATIONS_PER_COEFFICIENT * coefficient_count(deg) as f64
    {
        deg -= 1;
    }
    if ((count + slope_rows) as f64) < MIN_EQUATIONS_PER_COEFFICIENT * coefficient_count(2) as f64 {
        return None;
    }
    loop {
        let fitted = match deg {
            4 => solve::<15>(locals, normals, &moments, slope_weight),
            3 => solve::<10>(locals, normals, &moments, slope_weight),
            _ => solve::<6>(locals, normals, &moments, slope_weight),
        };
        if let Some(solution) = fitted {
            let mut coefficients = [0.0; 15];
            for (k, &(i, j)) in MONOMIALS.iter().enumerate().take(coefficient_count(deg)) {
                // P(u, v) = ρ p(u/ρ, v/ρ): a_ij = c_ij ρ^(1 − i − j).
                coefficients[k] = solution.c[k] * radius.powi(1 - i - j);
            }
            return Some(JetFit {
                degree: deg,
                radius,
                neighbours: count,
                equations: count + slope_rows,
                coefficients,
                noise: solution.height_noise * radius,
                // (a20, a11, a02) = (c20, c11, c02)/ρ.
                covariance: solution.covariance / (radius * radius),
                slope_weight: solution.slope_weight,
            });
        }
        if deg == 2 {
            return None;
        }
        deg -= 1;
    }
}

/// Reusable storage for [`fit`]: the support in local coordinates, kept for the residual
/// passes.
#[derive(Debug, Default)]
pub struct JetScratch {
    locals: Vec<Local>,
}

/// One sample of the support in scaled local coordinates `(u, v, z) = (q − x)·(t1, t2, n)/ρ`.
#[derive(Clone, Copy, Debug)]
struct Local {
    u: f64,
    v: f64,
    z: f64,
    /// The weight ω of its equations.
    w: f64,
    /// The slopes `(∂P/∂u, ∂P/∂v)` its normal asks for, when it enters the fit.
    slope: Option<[f64; 2]>,
}

/// Fills `locals` with the samples within the support whose normal faces the frame.
#[inline(always)]
fn local_samples(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    radius: f64,
    normals: NormalData,
    locals: &mut Vec<Local>,
) {
    let (t1, t2, n) = frame;
    let inv_r2 = 1.0 / (radius * radius);
    locals.clear();
    for sample in samples {
        let d = sample.point - centre;
        let s = d.norm_squared() * inv_r2;
        if !(s < 1.0) {
            continue;
        }
        // A sample whose normal faces away from the frame lies on another sheet (the far
        // side of a thin part): its height would pull the fit between the two.
        let c = sample.normal.dot(n);
        if !(c > 0.0) {
            continue;
        }
        let slope = (normals == NormalData::Slopes && c > 0.5).then(|| {
            let nu = &sample.normal;
            let (a, b) = (nu.dot(t1), nu.dot(t2));
            [-a / c, -b / c]
        });
        // Scaled coordinates keep the normal equations O(1) whatever the units.
        locals.push(Local {
            u: d.dot(t1) / radius,
            v: d.dot(t2) / radius,
            z: d.dot(n) / radius,
            w: (1.0 - s) * (1.0 - s) * (1.0 - s),
            slope,
        });
    }
}

/// Index of `u^p v^q` among the monomials ordered by total degree (the order of
/// [`MONOMIALS`], continued to higher degrees).
const fn moment(p: i32, q: i32) -> usize {
    let d = (p + q) as usize;
    d * (d + 1) / 2 + q as usize
}

/// The exponents `(p, q)` of the monomials of degree ≤ 8 in the order of [`moment`].
const EXPONENTS: [(usize, usize); 45] = {
    let mut t = [(0, 0); 45];
    let mut d = 0;
    while d <= 8 {
        let mut q = 0;
        while q <= d {
            t[d * (d + 1) / 2 + q] = (d - q, q);
            q += 1;
        }
        d += 1;
    }
    t
};

/// The first `K` monomials `u^p v^q` in the order of [`moment`] into `out`, each a product of
/// two powers (independent products, not a chain).
#[inline(always)]
pub(super) fn powers<const K: usize>(u: f64, v: f64, out: &mut [f64; K]) {
    let (mut up, mut vp) = ([1.0; 9], [1.0; 9]);
    for i in 1..9 {
        up[i] = up[i - 1] * u;
        vp[i] = vp[i - 1] * v;
    }
    // Written out, entry by entry with constant indices (checked against [`EXPONENTS`] at
    // compile time): a loop over the table kept the indices as loads, 10 % of the run time.
    macro_rules! monomials {
        ($($k:literal => ($p:literal, $q:literal)),*) => {
            $(
                const { assert!(EXPONENTS[$k].0 == $p && EXPONENTS[$k].1 == $q) };
                if $k < K {
                    out[$k] = up[$p] * vp[$q];
                }
            )*
        };
    }
    #[rustfmt::skip]
    monomials!(
        0 => (0, 0),
        1 => (1, 0), 2 => (0, 1),
        3 => (2, 0), 4 => (1, 1), 5 => (0, 2),
        6 => (3, 0), 7 => (2, 1), 8 => (1, 2), 9 => (0, 3),
        10 => (4, 0), 11 => (3, 1), 12 => (2, 2), 13 => (1, 3), 14 => (0, 4),
        15 => (5, 0), 16 => (4, 1), 17 => (3, 2), 18 => (2, 3), 19 => (1, 4),
            20 => (0, 5),
        21 => (6, 0), 22 => (5, 1), 23 => (4, 2), 24 => (3, 3), 25 => (2, 4),
            26 => (1, 5), 27 => (0, 6),
        28 => (7, 0), 29 => (6, 1), 30 => (5, 2), 31 => (4, 3), 32 => (3, 4),
            33 => (2, 5), 34 => (1, 6), 35 => (0, 7),
        36 => (8, 0), 37 => (7, 1), 38 => (6, 2), 39 => (5, 3), 40 => (4, 4),
            41 => (3, 5), 42 => (2, 6), 43 => (1, 7), 44 => (0, 8)
    );
}

/// Weighted moments of the support. A product of two monomials is a monomial, so every entry
/// of the normal equations is one of these sums: 45 per sample (degree ≤ 8) build the 120
/// distinct entries of each 15 × 15 matrix, and the slopes' matrices reuse them.
struct Moments {
    /// `Σ ω u^p v^q` over the heights, degree ≤ 8.
    h: [f64; 45],
    /// `Σ ω² u^p v^q` over the heights, for the variance of the coefficients.
    h2: [f64; 45],
    /// `Σ ω z u^p v^q`, degree ≤ 4.
    hz: [f64; 15],
    /// `Σ ω u^p v^q` over the samples with slopes, degree ≤ 6.
    s: [f64; 28],
    /// `Σ ω² u^p v^q` over the samples with slopes.
    s2: [f64; 28],
    /// `Σ ω s_u u^p v^q` and `Σ ω s_v u^p v^q`, degree ≤ 3.
    su: [f64; 10],
    sv: [f64; 10],
    /// Samples, and samples with slopes.
    heights: usize,
    slope_samples: usize,
    /// `Σ ω` over the height equations, and over the slope equations (two per sample).
    weight_h: f64,
    weight_s: f64,
}

impl Moments {
    /// The moments of `locals`.
    #[inline(always)]
    fn of(locals: &[Local]) -> Self {
        let mut m = Self {
            h: [0.0; 45],
            h2: [0.0; 45],
            hz: [0.0; 15],
            s: [0.0; 28],
            s2: [0.0; 28],
            su: [0.0; 10],
            sv: [0.0; 10],
            heights: locals.len(),
            slope_samples: 0,
            weight_h: 0.0,
            weight_s: 0.0,
        };
        // Where every sample has a slope (the rule on a smooth surface) the slopes' weighted
        // moments are the heights' own, summed in the same order: copied, not summed twice.
        let all_slopes = locals.iter().all(|l| l.slope.is_some());
        // The next sample's monomials are computed while this one's are summed, into the
        // other half of a double buffer. Read back right after being written, a 16-byte load
        // spanning two of the stores that wrote them could not be forwarded and waited for the
        // store buffer to drain (16 % of the time on a LiDAR tile). The residual passes, with
        // fewer stores per sample, were 4 % slower with it.
        let mut buffer = [[0.0; 45]; 2];
        if let Some(first) = locals.first() {
            powers(first.u, first.v, &mut buffer[0]);
        }
        for (i, l) in locals.iter().enumerate() {
            if let Some(next) = locals.get(i + 1) {
                powers(next.u, next.v, &mut buffer[(i + 1) & 1]);
            }
            let p = &buffer[i & 1];
            let (w, w2) = (l.w, l.w * l.w);
            for ((h, h2), &p) in m.h.iter_mut().zip(&mut m.h2).zip(p) {
                *h += w * p;
                *h2 += w2 * p;
            }
            let wz = w * l.z;
            for (hz, &p) in m.hz.iter_mut().zip(p) {
                *hz += wz * p;
            }
            m.weight_h += w;
            if let Some([a, b]) = l.slope {
                if !all_slopes {
                    for ((s, s2), &p) in m.s.iter_mut().zip(&mut m.s2).zip(p) {
                        *s += w * p;
                        *s2 += w2 * p;
                    }
                }
                let (wa, wb) = (w * a, w * b);
                for ((su, sv), &p) in m.su.iter_mut().zip(&mut m.sv).zip(p) {
                    *su += wa * p;
                    *sv += wb * p;
                }
                m.weight_s += 2.0 * w;
                m.slope_samples += 1;
            }
        }
        if all_slopes {
            let n = m.s.len();
            m.s.copy_from_slice(&m.h[..n]);
            m.s2.copy_from_slice(&m.h2[..n]);
        }
        m
    }

    /// `Σ ω z φ`.
    #[inline(always)]
    fn height_rhs<const N: usize>(&self) -> [f64; N] {
        let mut rhs = [0.0; N];
        rhs.copy_from_slice(&self.hz[..N]);
        rhs
    }

    /// `Σ ω (s_u ∂_u φ + s_v ∂_v φ)`.
    #[inline(always)]
    fn slope_rhs<const N: usize>(&self) -> [f64; N] {
        let mut rhs = [0.0; N];
        for (r, &(fu, iu, fv, iv)) in rhs.iter_mut().zip(&DERIVATIVE) {
            *r = fu * self.su[iu] + fv * self.sv[iv];
        }
        rhs
    }
}

/// The coefficients of `∂_u` and `∂_v` of `Σ_k x_k φ_k` on the monomials of degree ≤ 3
/// (`x` has 15 entries, zero past the fitted ones).
#[inline(always)]
fn gradient_coefficients<T: Copy + Default + std::ops::Mul<f64, Output = T>>(
    x: &[T; 15],
) -> ([T; 10], [T; 10]) {
    let (mut du, mut dv) = ([T::default(); 10], [T::default(); 10]);
    for (k, &(i, j)) in MONOMIALS.iter().enumerate().take(10) {
        du[k] = x[moment(i + 1, j)] * f64::from(i + 1);
        dv[k] = x[moment(i, j + 1)] * f64::from(j + 1);
    }
    (du, dv)
}

/// A solved fit in scaled coordinates.
struct Solution {
    c: [f64; 15],
    /// σ̂ of the heights (scaled by 1/ρ).
    height_noise: f64,
    /// Covariance of (c20, c11, c02).
    covariance: Matrix,
    /// λ of the final round.
    slope_weight: f64,
}

/// Relative weight of slope equations against height equations is bounded: the ratio of two
/// noise estimates is unreliable beyond this.
const MAX_SLOPE_WEIGHT: f64 = 1e4;

/// `∂_u φ_a = f_u φ[i_u]` and `∂_v φ_a = f_v φ[i_v]` for each monomial `a` (a factor 0 where
/// the monomial has no `u`, or no `v`).
const DERIVATIVE: [(f64, usize, f64, usize); 15] = {
    let mut t = [(0.0, 0, 0.0, 0); 15];
    let mut a = 0;
    while a < 15 {
        let (i, j) = MONOMIALS[a];
        if i > 0 {
            t[a].0 = i as f64;
            t[a].1 = moment(i - 1, j);
        }
        if j > 0 {
            t[a].2 = j as f64;
            t[a].3 = moment(i, j - 1);
        }
        a += 1;
    }
    t
};

/// `(i_a + i_b, j_a + j_b)` as a [`moment`] index, for every pair of monomials: the entry
/// `(a, b)` of the heights' normal matrix.
pub(super) const PRODUCT: [[usize; 15]; 15] = {
    let mut t = [[0; 15]; 15];
    let mut a = 0;
    while a < 15 {
        let mut b = 0;
        while b < 15 {
            t[a][b] = moment(
                MONOMIALS[a].0 + MONOMIALS[b].0,
                MONOMIALS[a].1 + MONOMIALS[b].1,
            );
            b += 1;
        }
        a += 1;
    }
    t
};

/// The entry `(a, b)` of the slopes' normal matrix as `f_u μ[i_u] + f_v μ[i_v]`: the moments
/// of `∂_u φ_a ∂_u φ_b = i_a i_b u^(i_a+i_b−2) v^(j_a+j_b)` and of its `v` counterpart
/// (a factor 0 where a monomial has no `u`, or no `v`).
const SLOPE_PRODUCT: [[(f64, usize, f64, usize); 15]; 15] = {
    let mut t = [[(0.0, 0, 0.0, 0); 15]; 15];
    let mut a = 0;
    while a < 15 {
        let mut b = 0;
        while b < 15 {
            let ((ia, ja), (ib, jb)) = (MONOMIALS[a], MONOMIALS[b]);
            if ia > 0 && ib > 0 {
                t[a][b].0 = (ia * ib) as f64;
                t[a][b].1 = moment(ia + ib - 2, ja + jb);
            }
            if ja > 0 && jb > 0 {
                t[a][b].2 = (ja * jb) as f64;
                t[a][b].3 = moment(ia + ib, ja + jb - 2);
            }
            b += 1;
        }
        a += 1;
    }
    t
};

/// `Σ ω φ φᵀ` of the heights from their moments `mu`, into `m`.
#[inline(always)]
fn height_matrix<const N: usize>(mu: &[f64], m: &mut Square<N>) {
    symmetric(m, |a, b| mu[PRODUCT[a][b]]);
}

/// `Σ ω (∂_u φ ∂_u φᵀ + ∂_v φ ∂_v φᵀ)` of the slopes from their moments `mu`, into `m`.
#[inline(always)]
fn slope_matrix<const N: usize>(mu: &[f64], m: &mut Square<N>) {
    symmetric(m, |a, b| {
        let (fu, iu, fv, iv) = SLOPE_PRODUCT[a][b];
        fu * mu[iu] + fv * mu[iv]
    });
}

/// Solves the leading `N × N` block, with the slope equations weighted by the ratio of the
/// two estimated noise variances (one re-weighting from an equal start), or by a given λ in
/// one round.
#[inline(always)]
fn solve<const N: usize>(
    locals: &[Local],
    normals: NormalData,
    moments: &Moments,
    given: Option<f64>,
) -> Option<Solution> {
    let (mut hp, mut hp2, mut sp, mut sp2) =
        ([[0.0; N]; N], [[0.0; N]; N], [[0.0; N]; N], [[0.0; N]; N]);
    height_matrix(&moments.h, &mut hp);
    height_matrix(&moments.h2, &mut hp2);
    slope_matrix(&moments.s, &mut sp);
    slope_matrix(&moments.s2, &mut sp2);
    let mut factor = Factor {
        l: [[0.0; N]; N],
        inv_diag: [0.0; N],
    };
    let mut inv = [[0.0; N]; N];
    let (rp, rs) = (moments.height_rhs::<N>(), moments.slope_rhs::<N>());
    let (weight_h, weight_s) = (moments.weight_h, moments.weight_s);
    let use_slopes = normals == NormalData::Slopes && weight_s > 0.0;
    let mut lambda = if use_slopes {
        given.unwrap_or(1.0)
    } else {
        0.0
    };
    let rounds = if use_slopes && given.is_none() { 2 } else { 1 };
    let mut result = None;
    for round in 0..rounds {
        // The covariance is kept from the last round only: its sandwich is formed there.
        let sandwich = use_slopes && round + 1 == rounds;
        // M = Mʰ + λ Mˢ, factored where it is formed.
        for ((row, h), s) in factor.l.iter_mut().zip(&hp).zip(&sp) {
            for ((x, h), s) in row.iter_mut().zip(h).zip(s) {
                *x = h + s * lambda;
            }
        }
        let mut rhs = rp;
        for (x, s) in rhs.iter_mut().zip(&rs) {
            *x += s * lambda;
        }
        if !factor.factor() {
            return None;
        }
        factor.inverse(&mut inv);
        let mut c = [0.0; 15];
        c[..N].copy_from_slice(&factor.solve(&rhs));
        let (cu, cv) = gradient_coefficients(&c);
        // The columns of M⁻¹ that give (c20, c11, c02), as rows per coefficient.
        let mut sel = [Vector::zeros(); 15];
        for (k, s) in sel.iter_mut().enumerate().take(N) {
            *s = Vector::new(inv[k][A20], inv[k][A11], inv[k][A02]);
        }
        let (sel_u, sel_v) = gradient_coefficients(&sel);
        // Weighted residuals from the samples again (yᵀΩy − cᵀAᵀΩy loses the digits of a
        // small residual).
        let (mut rss_h, mut rss_s) = (0.0, 0.0);
        // With slopes, each sample's height and slope errors share its displacement: the
        // covariance is the cluster-robust sandwich M⁻¹ (Σ_samples g gᵀ) M⁻¹, g = Σ ω r φ over
        // the sample's equations; only its (c20, c11, c02) block is formed.
        let mut meat = Matrix::zeros();
        for l in locals {
            // Recomputed, not kept from the moments: storing them cost more than these
            // products (a store-to-load forwarding stall on the copy).
            let mut p = [0.0; 15];
            powers(l.u, l.v, &mut p);
            let p = &p;
            let r = l.z - dot(&c, p);
            rss_h += l.w * r * r;
            let mut g = Vector::zeros();
            if sandwich {
                g = combine(&sel, p) * (l.w * r);
            }
            if let (true, Some([a, b])) = (use_slopes, l.slope) {
                let (ru, rv) = (a - dot(&cu, p), b - dot(&cv, p));
                rss_s += l.w * (ru * ru + rv * rv);
                if sandwich {
                    g += (combine(&sel_u, p) * ru + combine(&sel_v, p) * rv) * (l.w * lambda);
                }
            }
            if sandwich {
                meat += g * g.transpose();
            }
        }
        // Degrees of freedom left to each kind of data: Σω − its share of the hat matrix's
        // trace (exact for one kind of data with independent noise).
        let dof_h = weight_h - trace_product(&inv, &hp2);
        let dof_s = weight_s - lambda * trace_product(&inv, &sp2);
        if !(dof_h > 0.0) {
            return None;
        }
        let var_h = rss_h / dof_h;
        let var_s = if use_slopes && dof_s > 0.0 {
            rss_s / dof_s
        } else {
            0.0
        };
        let samples = moments.heights;
        let covariance = if round + 1 < rounds {
            // This round only weighs the slopes for the next.
            Matrix::zeros()
        } else if sandwich && samples > N {
            // Small-sample factor n/(n − p) of the sandwich.
            meat * (samples as f64 / (samples - N) as f64)
        } else {
            // selᵀ (M₂ʰ σ̂ₕ² + M₂ˢ λ² σ̂ₛ²) sel.
            let var_s = lambda * lambda * var_s;
            (0..N).fold(Matrix::zeros(), |cov, j| {
                let column: Vector = (0..N)
                    .map(|i| sel[i] * (hp2[i][j] * var_h + sp2[i][j] * var_s))
                    .sum();
                cov + column * sel[j].transpose()
            })
        };
        result = Some(Solution {
            c,
            height_noise: var_h.sqrt(),
            covariance,
            slope_weight: lambda,
        });
        if use_slopes {
            lambda = if var_s > 0.0 {
                (var_h / var_s).clamp(1.0 / MAX_SLOPE_WEIGHT, MAX_SLOPE_WEIGHT)
            } else {
                MAX_SLOPE_WEIGHT
            };
        }
    }
    result
}

/// `Σ_k x_k p_k` over the first `x.len()` monomials.
#[inline(always)]
fn dot(x: &[f64], p: &[f64; 15]) -> f64 {
    x.iter().zip(p).map(|(x, p)| x * p).sum()
}

/// `Σ_k s_k p_k` for 3-vectors `s_k`.
#[inline(always)]
fn combine(s: &[Vector], p: &[f64; 15]) -> Vector {
    s.iter()
        .zip(p)
        .fold(Vector::zeros(), |acc, (s, &p)| acc + s * p)
}
