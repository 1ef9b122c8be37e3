//! Weighted polynomial jets: a second-order-and-beyond curvature estimator that converges on
//! irregularly sampled clouds, where the Amenta–Kil surface does not.
//!
//! At a query x with frame normal n (the input normals averaged with the jet's weight) and
//! tangents t1, t2, every sample q within the support radius ρ whose normal faces the frame
//! gets local coordinates `(u, v, w) = ((q − x)·t1, (q − x)·t2, (q − x)·n)` and the weight
//! `ω = (1 − |q − x|²/ρ²)³`. The heights `w`, and with [`NormalData::Slopes`] the slopes of
//! the samples' normals, are fitted by weighted least squares with a polynomial of total
//! degree 4 in `(u, v)` (15 coefficients `a_ij` of `u^i v^j`; lower degrees when the
//! neighbourhood cannot determine it):
//!
//! $$ \min_a \sum_i ω_i \big(w_i − P_a(u_i, v_i)\big)^2
//!    + λ \sum_i ω_i \big|∇P_a(u_i, v_i) − s_i\big|^2. $$
//!
//! The fitted surface is the zero set of `F(y) = w − P(u, v)` in the frame, and at its foot
//! point `(0, 0, a00)` above x
//!
//! $$ ∇F = n − a_{10} t_1 − a_{01} t_2, \qquad
//!    H = −\big(2a_{20}\, t_1t_1^T + a_{11}(t_1t_2^T + t_2t_1^T) + 2a_{02}\, t_2t_2^T\big), $$
//!
//! which [`crate::curvature()`] turns into k1, k2 and directions with the product's sign
//! convention. The frame normal only has to be roughly right: the linear terms absorb a tilt.
//!
//! **Noise and predicted error.** The residuals of each kind of data give its noise estimate
//! (`σ̂² = Σω r² / (Σω − tr(M⁻¹M₂))`, unbiased for independent noise) and λ, their ratio. The
//! coefficients' covariance is `σ̂² M⁻¹M₂M⁻¹` for heights alone and the cluster-robust
//! sandwich (one cluster per sample) with slopes. Its (a20, a11, a02) block, pushed through
//! the first-order change of each principal curvature
//! (`δk = −2(c² δa20 + cs δa11 + s² δa02)/|∇F|` along the direction `(c, s)`), is the
//! predicted standard deviation of k1 and k2.
//!
//! **Scale.** Support radii `ρ_j = ρ_0 √2^j` form a ladder, climbed while the confidence
//! intervals `k_j ± Γ sd_j` of every scale so far intersect and the bias has not overtaken
//! the scatter; the returned scale has the least estimated `sd² + bias²` ([`choose_scale`]).
//! `docs/derivation.md` has the details and `mls_ad::jet_witness` recomputes all of it.

use nalgebra::{Cholesky, SMatrix, SVector};

use crate::curvature::{Curvature, curvature};
use crate::field::Sample;
use crate::math::{Matrix, Point, Vector, tangent_basis};
use crate::status::PointStatus;

/// Exponents `(i, j)` of the monomials `u^i v^j`, by total degree: the first
/// `(d + 1)(d + 2)/2` are the basis of degree `d`.
pub const MONOMIALS: [(i32, i32); 15] = [
    (0, 0),
    (1, 0),
    (0, 1),
    (2, 0),
    (1, 1),
    (0, 2),
    (3, 0),
    (2, 1),
    (1, 2),
    (0, 3),
    (4, 0),
    (3, 1),
    (2, 2),
    (1, 3),
    (0, 4),
];

const A10: usize = 1;
const A01: usize = 2;
const A20: usize = 3;
const A11: usize = 4;
const A02: usize = 5;

/// Number of coefficients of a jet of total degree `degree`.
pub const fn coefficient_count(degree: usize) -> usize {
    (degree + 1) * (degree + 2) / 2
}

/// Parameters of the jet estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JetConfig {
    /// Highest total degree of the polynomial (2 to 4).
    pub degree: usize,
    /// Support radius of the first scale, in units of the surface's h.
    pub radius: f64,
    /// Number of scales, each √2 times the previous.
    pub scales: usize,
    /// Γ, the half-width of the confidence intervals, in predicted standard deviations.
    pub confidence: f64,
    /// Whether the samples' normals enter the fit.
    pub normals: NormalData,
}

impl Default for JetConfig {
    fn default() -> Self {
        Self {
            degree: 4,
            radius: 1.5,
            scales: 5,
            confidence: 3.0,
            normals: NormalData::Slopes,
        }
    }
}

impl JetConfig {
    /// The largest support radius of the ladder, in units of h.
    pub fn max_radius(&self) -> f64 {
        self.radius * std::f64::consts::SQRT_2.powi(self.scales.max(1) as i32 - 1)
    }
}

/// One weighted fit at one support radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JetFit {
    /// The degree actually fitted (lower than asked when the neighbourhood is too thin).
    pub degree: usize,
    /// Support radius ρ.
    pub radius: f64,
    /// Samples within the support.
    pub neighbours: usize,
    /// Coefficients `a_ij` of `u^i v^j` in the frame, in file units; unused ones are 0.
    pub coefficients: [f64; 15],
    /// Estimated position noise σ̂ (residual standard deviation of the heights), file units.
    pub noise: f64,
    /// Estimated covariance of `(a20, a11, a02)`.
    pub covariance: Matrix,
}

/// Curvature from a jet, with its predicted error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JetPoint {
    /// The foot point of the query on the fitted surface (`x + a00 n`).
    pub foot: Point,
    /// Principal curvatures and directions at the foot point.
    pub curvature: Curvature,
    /// Predicted standard deviations of k1 and k2 from the noise of the fit.
    pub sd: [f64; 2],
    /// Estimated bias of k1 and k2 at this scale, from the line through the ladder's estimates
    /// ([`choose_scale`]); 0 when only one scale was fitted.
    pub bias: [f64; 2],
    /// The fit the result comes from.
    pub fit: JetFit,
}

/// Normal equations of one kind of data (heights, or slopes from normals).
#[derive(Clone, Copy)]
struct Equations {
    /// `Σ ω φ φᵀ`.
    m: SMatrix<f64, 15, 15>,
    /// `Σ ω² φ φᵀ`, for the variance of the coefficients.
    m2: SMatrix<f64, 15, 15>,
    /// `Σ ω φ y`.
    rhs: SVector<f64, 15>,
    /// `Σ ω` over the equations.
    weight: f64,
}

impl Equations {
    fn new() -> Self {
        Self {
            m: SMatrix::zeros(),
            m2: SMatrix::zeros(),
            rhs: SVector::zeros(),
            weight: 0.0,
        }
    }

    /// Adds the row `φ · c = y` with weight `w`, to the upper triangles only: column `a`'s
    /// rows `0..=a` are contiguous in the column-major storage, so the loop vectorises.
    fn add(&mut self, phi: &[f64; 15], y: f64, w: f64, terms: usize) {
        let (m, m2) = (self.m.as_mut_slice(), self.m2.as_mut_slice());
        for a in 0..terms {
            let wa = w * phi[a];
            let wwa = wa * w;
            self.rhs[a] += wa * y;
            let column = a * 15..a * 15 + a + 1;
            for ((c, c2), &pb) in m[column.clone()]
                .iter_mut()
                .zip(&mut m2[column])
                .zip(&phi[..=a])
            {
                *c += wa * pb;
                *c2 += wwa * pb;
            }
        }
        self.weight += w;
    }

    fn symmetrise(&mut self, terms: usize) {
        for a in 0..terms {
            for b in 0..a {
                self.m[(a, b)] = self.m[(b, a)];
                self.m2[(a, b)] = self.m2[(b, a)];
            }
        }
    }
}

/// Whether, and how, the samples' normals enter the fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalData {
    /// Heights only.
    Ignore,
    /// Heights and the slopes `−ν_u/ν_w`, `−ν_v/ν_w` of each sample's normal ν (within 60° of
    /// the frame normal), weighted against the heights by their estimated noise.
    Slopes,
}

impl JetPoint {
    /// k1 (`i = 0`) or k2 (`i = 1`).
    pub fn curvature_k(&self, i: usize) -> f64 {
        if i == 0 {
            self.curvature.k1
        } else {
            self.curvature.k2
        }
    }

    /// Predicted error of k1 and k2: `√(sd² + bias²)`.
    pub fn predicted_error(&self) -> [f64; 2] {
        [0, 1].map(|i| self.sd[i].hypot(self.bias[i]))
    }
}

/// Whether climbing further cannot lower the error: the previous scale's bias, estimated from
/// the last step, already exceeds its scatter (`Σ b² > Σ sd²` over k1, k2), or that scatter
/// is at the rounding floor. Beyond that point the bias grows fourfold per step while the
/// scatter falls at most √8-fold (`∝ 1/(ρ² √N)`).
pub fn past_optimum(ladder: &[JetPoint]) -> bool {
    let [.., a, b] = ladder else {
        return false;
    };
    let (bias2, sd2): (f64, f64) = (0..2)
        .map(|i| {
            let bias = (b.curvature_k(i) - a.curvature_k(i)).abs() / 3.0;
            (bias * bias, a.sd[i] * a.sd[i])
        })
        .fold((0.0, 0.0), |(x, y), (p, q)| (x + p, y + q));
    // A scatter at the rounding floor leaves no noise to average away either.
    let floor = 2.0 * SD_FLOOR / a.fit.radius;
    bias2 > sd2 || a.sd.iter().all(|&sd| sd <= floor)
}

/// The scale of least estimated mean squared error among the scales the confidence intervals
/// accepted.
///
/// `ladder` holds the fits in increasing radius; the first `accepted` are the candidates (a
/// last one may be the fit the intervals rejected). The bias of a degree-4 fit grows as ρ⁴, so
/// every fit of the ladder, rejected one included, enters one weighted least-squares line
/// `k_j = k* + c t_j`, `t_j = (ρ_j/ρ_0)⁴`, weights `1/sd_j²`, per principal curvature; scale
/// j's bias is `t_j √(c² + var c)`. With two fits this is the step between them over 3 with
/// the step's own scatter; with more, the steps average. Counting `var c` keeps a scale whose
/// step is small by chance from being chosen with an under-predicted error. The chosen point
/// carries that bias, which enters its predicted error. Under noise the scatter falls with the
/// scale and a larger one wins; on clean data the bias grows and the smallest wins.
///
/// # Panics
/// If `accepted` is 0.
pub fn choose_scale(ladder: &[JetPoint], accepted: usize) -> JetPoint {
    let growth = bias_growth(ladder);
    let r0 = ladder[0].fit.radius;
    let mut best: Option<(f64, JetPoint)> = None;
    for p in &ladder[..accepted] {
        let t = (p.fit.radius / r0).powi(4);
        let bias = growth.map(|g| t * g);
        let candidate = JetPoint { bias, ..*p };
        let [e1, e2] = candidate.predicted_error();
        let mse = e1 * e1 + e2 * e2;
        if best.as_ref().is_none_or(|(m, _)| mse < *m) {
            best = Some((mse, candidate));
        }
    }
    best.map(|(_, p)| p).expect("a non-empty ladder")
}

/// `√(c² + var c)` of the weighted line `k_j = k* + c (ρ_j/ρ_0)⁴` through the ladder, for k1
/// and k2; 0 with fewer than two fits.
fn bias_growth(ladder: &[JetPoint]) -> [f64; 2] {
    if ladder.len() < 2 {
        return [0.0; 2];
    }
    let r0 = ladder[0].fit.radius;
    [0, 1].map(|i| {
        let (mut sw, mut swt, mut swtt, mut swk, mut swtk) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for p in ladder {
            let t = (p.fit.radius / r0).powi(4);
            let w = 1.0 / (p.sd[i] * p.sd[i]);
            let k = p.curvature_k(i);
            sw += w;
            swt += w * t;
            swtt += w * t * t;
            swk += w * k;
            swtk += w * t * k;
        }
        let det = sw * swtt - swt * swt;
        let c = (sw * swtk - swt * swk) / det;
        (c * c + sw / det).sqrt()
    })
}

/// Fits a jet to the `samples` within the support radius `radius` of `centre` (the query, in
/// the samples' frame), in the frame `(t1, t2, n)`. Returns `None` when no degree ≥ 2 is
/// determined.
pub fn fit(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    radius: f64,
    degree: usize,
    normals: NormalData,
    scratch: &mut JetScratch,
) -> Option<JetFit> {
    let inv_r2 = 1.0 / (radius * radius);
    let max_degree = degree.clamp(2, 4);
    let terms = coefficient_count(max_degree);
    let mut heights = Equations::new();
    let mut slopes = Equations::new();
    let mut count = 0;
    let mut slope_rows = 0;
    let rows = &mut scratch.rows;
    rows.clear();
    for_each_row(samples, centre, frame, inv_r2, radius, normals, |row| {
        rows.push(row)
    });
    for row in rows.iter() {
        match *row {
            Row::Height { phi, z, w } => {
                heights.add(&phi, z, w, terms);
                count += 1;
            }
            Row::Slope { phi, slope, w } => {
                slopes.add(&phi, slope, w, terms);
                slope_rows += 1;
            }
        };
    }
    heights.symmetrise(terms);
    slopes.symmetrise(terms);
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
            4 => solve::<15>(rows, normals, &heights, &slopes),
            3 => solve::<10>(rows, normals, &heights, &slopes),
            _ => solve::<6>(rows, normals, &heights, &slopes),
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
                coefficients,
                noise: solution.height_noise * radius,
                // (a20, a11, a02) = (c20, c11, c02)/ρ.
                covariance: solution.covariance / (radius * radius),
            });
        }
        if deg == 2 {
            return None;
        }
        deg -= 1;
    }
}

/// Reusable storage for [`fit`]: the equations of one fit, kept for the residual passes.
#[derive(Debug, Default)]
pub struct JetScratch {
    rows: Vec<Row>,
}

/// One equation of the fit, in scaled coordinates.
#[derive(Clone, Copy, Debug)]
enum Row {
    /// `P(u, v) = z` with weight `w`.
    Height { phi: [f64; 15], z: f64, w: f64 },
    /// `∂P/∂u = slope` (or `∂P/∂v`) with weight `w`.
    Slope { phi: [f64; 15], slope: f64, w: f64 },
}

/// Calls `f` with every equation the samples within the support give.
fn for_each_row(
    samples: &[Sample],
    centre: &Point,
    frame: &(Vector, Vector, Vector),
    inv_r2: f64,
    radius: f64,
    normals: NormalData,
    mut f: impl FnMut(Row),
) {
    let (t1, t2, n) = frame;
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
        let w = (1.0 - s) * (1.0 - s) * (1.0 - s);
        // Scaled coordinates keep the normal equations O(1) whatever the units.
        let (u, v, z) = (d.dot(t1) / radius, d.dot(t2) / radius, d.dot(n) / radius);
        f(Row::Height {
            phi: monomials(u, v),
            z,
            w,
        });
        if normals == NormalData::Slopes {
            let nu = &sample.normal;
            let (a, b) = (nu.dot(t1), nu.dot(t2));
            if c > 0.5 {
                let (du, dv) = monomial_gradients(u, v);
                f(Row::Slope {
                    phi: du,
                    slope: -a / c,
                    w,
                });
                f(Row::Slope {
                    phi: dv,
                    slope: -b / c,
                    w,
                });
            }
        }
    }
}

/// A solved fit in scaled coordinates.
struct Solution {
    c: [f64; 15],
    /// σ̂ of the heights (scaled by 1/ρ).
    height_noise: f64,
    /// Covariance of (c20, c11, c02).
    covariance: Matrix,
}

/// Equations (heights and slopes) per coefficient a degree needs.
pub const MIN_EQUATIONS_PER_COEFFICIENT: f64 = 1.5;

/// Predicted standard deviations never fall below this fraction of `1/ρ`: below it an exact
/// fit's residual is rounding, and a zero-width interval would make the scale choice follow it.
pub const SD_FLOOR: f64 = 1e-8;

/// Relative weight of slope equations against height equations is bounded: the ratio of two
/// noise estimates is unreliable beyond this.
const MAX_SLOPE_WEIGHT: f64 = 1e4;

/// Solves the leading `N × N` block, with the slope equations weighted by the ratio of the
/// two estimated noise variances (one re-weighting from an equal start).
fn solve<const N: usize>(
    rows: &[Row],
    normals: NormalData,
    heights: &Equations,
    slopes: &Equations,
) -> Option<Solution> {
    let block = |m: &SMatrix<f64, 15, 15>| -> SMatrix<f64, N, N> {
        m.fixed_view::<N, N>(0, 0).into_owned()
    };
    let (hp, hp2, sp, sp2) = (
        block(&heights.m),
        block(&heights.m2),
        block(&slopes.m),
        block(&slopes.m2),
    );
    let (rp, rs) = (
        heights.rhs.fixed_view::<N, 1>(0, 0).into_owned(),
        slopes.rhs.fixed_view::<N, 1>(0, 0).into_owned(),
    );
    let use_slopes = normals == NormalData::Slopes && slopes.weight > 0.0;
    let mut lambda = if use_slopes { 1.0 } else { 0.0 };
    let rounds = if use_slopes { 2 } else { 1 };
    let mut result = None;
    for round in 0..rounds {
        // The covariance is kept from the last round only: its sandwich is formed there.
        let last = round + 1 == rounds;
        let a = hp + sp * lambda;
        let chol = Cholesky::new(a)?;
        // A pivot far below the diagonal's scale means the basis is not determined by the
        // samples (too few, or on a line): treat as singular rather than fit noise.
        let l = chol.l_dirty();
        let max_diag = (0..N).map(|i| a[(i, i)]).fold(0.0f64, f64::max);
        if (0..N).any(|i| !(l[(i, i)] * l[(i, i)] > 1e-10 * max_diag)) {
            return None;
        }
        let solved = chol.solve(&(rp + rs * lambda));
        let mut c = [0.0; 15];
        c[..N].copy_from_slice(solved.as_slice());
        let inv = chol.inverse();
        // Weighted residuals from the samples again (yᵀΩy − cᵀAᵀΩy loses the digits of a
        // small residual).
        let (mut rss_h, mut rss_s) = (0.0, 0.0);
        // With slopes, each sample's height and slope errors share its displacement: the
        // covariance is the cluster-robust sandwich M⁻¹ (Σ_samples g gᵀ) M⁻¹, g = Σ ω r φ over
        // the sample's rows (a height row opens each sample).
        let mut meat = SMatrix::<f64, N, N>::zeros();
        let mut g = SVector::<f64, N>::zeros();
        let mut samples = 0usize;
        for row in rows {
            let (phi, y, w) = match *row {
                Row::Height { phi, z, w } => {
                    if samples > 0 && use_slopes && last {
                        meat += g * g.transpose();
                    }
                    g.fill(0.0);
                    samples += 1;
                    (phi, z, w)
                }
                Row::Slope { phi, slope, w } => (phi, slope, w * lambda),
            };
            let p: f64 = (0..N).map(|k| c[k] * phi[k]).sum();
            let r = y - p;
            match row {
                Row::Height { .. } => rss_h += w * r * r,
                Row::Slope { .. } => rss_s += w / lambda * r * r,
            }
            if use_slopes && last {
                for k in 0..N {
                    g[k] += w * r * phi[k];
                }
            }
        }
        if use_slopes && last {
            meat += g * g.transpose();
        }
        // Degrees of freedom left to each kind of data: Σω − its share of the hat matrix's
        // trace (exact for one kind of data with independent noise).
        // tr(M⁻¹M₂) as the Frobenius product (both symmetric): 225 products, not 3375.
        let dof_h = heights.weight - inv.dot(&hp2);
        let dof_s = slopes.weight - lambda * inv.dot(&sp2);
        if !(dof_h > 0.0) {
            return None;
        }
        let var_h = rss_h / dof_h;
        let var_s = if use_slopes && dof_s > 0.0 {
            rss_s / dof_s
        } else {
            0.0
        };
        let sel = inv.fixed_columns::<3>(A20).into_owned();
        let cov_m = if use_slopes && samples > N {
            // Small-sample factor n/(n − p) of the sandwich.
            meat * (samples as f64 / (samples - N) as f64)
        } else {
            hp2 * var_h + sp2 * (lambda * lambda * var_s)
        };
        let cov = sel.transpose() * cov_m * sel;
        result = Some(Solution {
            c,
            height_noise: var_h.sqrt(),
            covariance: Matrix::from_fn(|i, j| cov[(i, j)]),
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

/// The monomials `u^i v^j` in [`MONOMIALS`] order.
fn monomials(u: f64, v: f64) -> [f64; 15] {
    let (u2, v2) = (u * u, v * v);
    let (u3, v3) = (u2 * u, v2 * v);
    [
        1.0,
        u,
        v,
        u2,
        u * v,
        v2,
        u3,
        u2 * v,
        u * v2,
        v3,
        u2 * u2,
        u3 * v,
        u2 * v2,
        u * v3,
        v2 * v2,
    ]
}

/// `(∂/∂u, ∂/∂v)` of the monomials, in [`MONOMIALS`] order.
fn monomial_gradients(u: f64, v: f64) -> ([f64; 15], [f64; 15]) {
    let (u2, v2, uv) = (u * u, v * v, u * v);
    let du = [
        0.0,
        1.0,
        0.0,
        2.0 * u,
        v,
        0.0,
        3.0 * u2,
        2.0 * uv,
        v2,
        0.0,
        4.0 * u2 * u,
        3.0 * u2 * v,
        2.0 * u * v2,
        v2 * v,
        0.0,
    ];
    let dv = [
        0.0,
        0.0,
        1.0,
        0.0,
        u,
        2.0 * v,
        0.0,
        u2,
        2.0 * uv,
        3.0 * v2,
        0.0,
        u2 * u,
        2.0 * u2 * v,
        3.0 * u * v2,
        4.0 * v2 * v,
    ];
    (du, dv)
}

/// Curvature of a fit at its foot point, with the predicted standard deviations.
pub fn jet_curvature(
    x: &Point,
    frame: &(Vector, Vector, Vector),
    fit: &JetFit,
) -> Result<JetPoint, PointStatus> {
    let (t1, t2, n) = frame;
    let a = &fit.coefficients;
    let gradient = n - t1 * a[A10] - t2 * a[A01];
    let hessian = -(t1 * t1.transpose() * (2.0 * a[A20])
        + (t1 * t2.transpose() + t2 * t1.transpose()) * a[A11]
        + t2 * t2.transpose() * (2.0 * a[A02]));
    let c = curvature(&gradient, &hessian).ok_or(PointStatus::GradientVanishes)?;
    let len = gradient.norm();
    let sd = [c.d1, c.d2].map(|d| {
        let (cs, sn) = (d.dot(t1), d.dot(t2));
        let g = Vector::new(cs * cs, cs * sn, sn * sn) * (2.0 / len);
        g.dot(&(fit.covariance * g))
            .max(0.0)
            .sqrt()
            .max(SD_FLOOR / fit.radius)
    });
    Ok(JetPoint {
        foot: x + n * a[0],
        curvature: c,
        sd,
        bias: [0.0; 2],
        fit: *fit,
    })
}

/// A right-handed frame `(t1, t2, n)` around the unit normal `n`.
pub fn frame(n: &Vector) -> (Vector, Vector, Vector) {
    let (t1, t2) = tangent_basis(n);
    (t1, t2, *n)
}
