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
//! (`σ̂² = Σω r² / (Σω − tr(M⁻¹M₂))`, unbiased for independent noise) and λ, their ratio,
//! found in a second solve at the ladder's first scale and taken by every later one. The
//! coefficients' covariance is `σ̂² M⁻¹M₂M⁻¹` for heights alone and the cluster-robust
//! sandwich (one cluster per sample) with slopes. Its (a20, a11, a02) block, pushed through
//! the first-order change of each principal curvature
//! (`δk = −2(c² δa20 + cs δa11 + s² δa02)/|∇F|` along the direction `(c, s)`), is the
//! predicted standard deviation of k1 and k2.
//!
//! **Scale.** Support radii `ρ_j = ρ_0 √2^j` form a ladder, climbed while the confidence
//! intervals `k_j ± Γ sd_j` of every scale so far intersect and the bias has not overtaken
//! the scatter; the returned scale has the least estimated `sd² + bias²` ([`choose_scale`]).
//! Fits too thin to trust their own noise estimate ([`trusted`]) are candidates only. With
//! slopes, a lead scale `ρ_0/√2` is fitted after the climb and joins the candidates when its
//! noise estimate is trusted ([`JetConfig::lead`]).
//! `docs/derivation.md` has the details and `mls_ad::jet_witness` recomputes all of it.

use crate::curvature::{Curvature, curvature};
use crate::math::{Matrix, Point, Vector, tangent_basis};
use crate::status::PointStatus;

mod algebra;
pub(crate) mod anchors;
mod fit;
pub(crate) mod ladder;
mod quadratic;

pub use anchors::{
    ANCHOR_CELL, ANCHOR_MAX_TURN, ANCHOR_MIN_COUNT, ANCHOR_MIN_SUPPORT, ANCHOR_REACH,
    ANCHOR_RESIDUAL,
};
pub(crate) use fit::jet_fit;
pub use fit::{JetScratch, fit};
pub use quadratic::{
    BIWEIGHT_CUTOFF, HighTerms, Leak, QuadraticFit, QuadraticScratch, Sensitivity, high_terms,
    quadratic, robust_weights,
};

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
    /// With [`NormalData::Slopes`], whether a lead scale one √2 step below `radius` is fitted
    /// too, after the climb, as a candidate for the choice where its own noise estimate is
    /// trusted ([`trusted`]); in one round, with the slopes weighted as in the ladder's first
    /// fit (whose noise ratio has more samples behind it). Three equations per sample
    /// determine the jet on a third of the area heights alone need, and the smaller support
    /// has a smaller truncation bias; it takes no part in the stopping rules, which its few
    /// samples would make erratic under noise.
    pub lead: bool,
    /// Γ, the half-width of the confidence intervals, in predicted standard deviations.
    pub confidence: f64,
    /// Whether the samples' normals enter the fit.
    pub normals: NormalData,
    /// With [`NormalData::Ignore`], whether degree-2 fits on supports from
    /// [`QUADRATIC_RADIUS`]·h up to [`QUADRATIC_SCALES`] √2 steps (at most
    /// [`QUADRATIC_MAX_SAMPLES`] samples) join the candidates, each with its truncation bias
    /// predicted from a degree-4 fit on the largest ([`quadratic`]).
    pub quadratic: bool,
    /// With the degree-2 candidates, whether a query where nearby anchors all chose degree 2 on
    /// a support many cells wide takes their blend instead of its own fit ([`ANCHOR_CELL`] and
    /// the constants beside it; `docs/derivation.md`, "Shared supports").
    pub share: bool,
}

/// The first degree-2 support radius, in h.
pub const QUADRATIC_RADIUS: f64 = 3.0;
/// Number of degree-2 supports, each √2 times the previous.
pub const QUADRATIC_SCALES: usize = 4;
/// The most samples a degree-2 support may hold: the largest support is the largest of the
/// ladder within this count.
pub const QUADRATIC_MAX_SAMPLES: usize = 2048;

impl Default for JetConfig {
    fn default() -> Self {
        Self {
            degree: 4,
            radius: 1.5,
            scales: 5,
            lead: true,
            confidence: 3.0,
            normals: NormalData::Slopes,
            quadratic: true,
            share: true,
        }
    }
}

impl JetConfig {
    /// The largest support radius of the ladder, in units of h.
    pub fn max_radius(&self) -> f64 {
        self.radius * std::f64::consts::SQRT_2.powi(self.scales.max(1) as i32 - 1)
    }

    /// How far from a query the samples that decide its result may lie, in units of h (what a
    /// tile's halo must hold): the ladder's top support, or with heights only and
    /// [`Self::quadratic`] the largest degree-2 support, and with [`Self::share`] besides the
    /// blend's reach (the anchors a query blends lie within [`ANCHOR_REACH`] cells, each with
    /// its own support).
    pub fn reach_radius(&self) -> f64 {
        let ladder = self.max_radius();
        if self.quadratic && self.normals == NormalData::Ignore {
            let support = ladder.max(
                QUADRATIC_RADIUS
                    * std::f64::consts::SQRT_2.powi(QUADRATIC_SCALES.max(1) as i32 - 1),
            );
            if self.share {
                support + ANCHOR_REACH * ANCHOR_CELL
            } else {
                support
            }
        } else {
            ladder
        }
    }

    /// The lead scale's support radius in units of h, when it is fitted (see [`Self::lead`]).
    pub fn lead_radius(&self) -> Option<f64> {
        (self.lead && self.normals == NormalData::Slopes)
            .then(|| self.radius / std::f64::consts::SQRT_2)
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
    /// Equations of the fit: one height per sample, and two slopes per sample whose normal
    /// enters the fit.
    pub equations: usize,
    /// Coefficients `a_ij` of `u^i v^j` in the frame, in file units; unused ones are 0.
    pub coefficients: [f64; 15],
    /// Estimated position noise σ̂ (residual standard deviation of the heights), file units.
    pub noise: f64,
    /// Estimated covariance of `(a20, a11, a02)`.
    pub covariance: Matrix,
    /// λ, the weight of the slope equations against the heights in the final round (0
    /// without slopes).
    pub slope_weight: f64,
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
    /// (its unbiased form, [`choose_scale`]); 0 when only one scale was fitted.
    pub bias: [f64; 2],
    /// The fit the result comes from.
    pub fit: JetFit,
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
/// `k_j = k* + c t_j`, `t_j = (ρ_j/ρ_0)⁴`, weights `1/sd_j²`, per principal curvature. The
/// choice takes scale j's bias as `t_j √(c² + var c)`: with two fits this is the step between
/// them over 3 with the step's own scatter; with more, the steps average. Counting `var c`
/// keeps a scale whose step is small by chance from being chosen. Under noise the scatter
/// falls with the scale and a larger one wins; on clean data the bias grows and the smallest
/// wins.
///
/// The chosen point carries `t_j √max(c² − var c, 0)` as its bias, which enters its
/// predicted error: `ĉ² − var ĉ` is the unbiased estimate of `c²` (`E ĉ² = c² + var ĉ`), so
/// the predicted error estimates the RMS error instead of exceeding it by `t_j² var c`
/// (`cargo xtask accuracy`: the top decile of the 10k random torus with file normals
/// over-predicted by 2.08×, now 1.92×).
///
/// # Panics
/// If `accepted` is 0.
pub fn choose_scale(ladder: &[JetPoint], accepted: usize) -> JetPoint {
    choose_scale_with_mse(ladder, accepted).1
}

/// [`choose_scale`] with the estimated mean squared error (summed over k1 and k2) it chose by.
///
/// # Panics
/// If `accepted` is 0.
pub fn choose_scale_with_mse(ladder: &[JetPoint], accepted: usize) -> (f64, JetPoint) {
    let lines = bias_lines(ladder);
    let r0 = ladder[0].fit.radius;
    let t = |p: &JetPoint| (p.fit.radius / r0).powi(4);
    let mut best: Option<(f64, &JetPoint)> = None;
    for p in &ladder[..accepted] {
        let bias = lines.map(|(c2, var)| t(p) * (c2 + var).sqrt());
        let candidate = JetPoint { bias, ..*p };
        let [e1, e2] = candidate.predicted_error();
        let mse = e1 * e1 + e2 * e2;
        if best.as_ref().is_none_or(|(m, _)| mse < *m) {
            best = Some((mse, p));
        }
    }
    let (mse, p) = best.expect("a non-empty ladder");
    (
        mse,
        JetPoint {
            bias: lines.map(|(c2, var)| t(p) * (c2 - var).max(0.0).sqrt()),
            ..*p
        },
    )
}

/// The predicted error below which the degree-2 candidates are not sought: a fraction
/// [`RESOLVED_RELATIVE`] of the larger |k|, plus [`RESOLVED_ABSOLUTE`]/h (so that a plane is not
/// asked for relative digits it cannot have).
pub const RESOLVED_RELATIVE: f64 = 1e-2;
/// See [`RESOLVED_RELATIVE`].
pub const RESOLVED_ABSOLUTE: f64 = 1e-4;

/// Whether `p`'s predicted error (√(e1² + e2²)) is already below what a user can see:
/// [`RESOLVED_RELATIVE`] of max(|k1|, |k2|) plus [`RESOLVED_ABSOLUTE`]/h. On clean and quantized
/// clouds the degree-4 ladder is there, and the degree-2 candidates (orders less accurate) are
/// not computed.
pub fn resolved(p: &JetPoint, h: f64) -> bool {
    let [e1, e2] = p.predicted_error();
    let k = p.curvature.k1.abs().max(p.curvature.k2.abs());
    e1.hypot(e2) <= RESOLVED_RELATIVE * k + RESOLVED_ABSOLUTE / h
}

/// The degree-2 candidate of a fit with its predicted [`Leak`], and the estimated mean squared
/// error (summed over k1 and k2) to choose it by: `sd² + max(b² − var b, 0)` per principal
/// curvature, `b` the leak's effect on it and `var b` that effect's variance (`E b² = bias² +
/// var b`). The candidate carries `√max(b² − var b, 0)` as its bias. The leak is not
/// subtracted: the high terms of one degree-4 fit are too uncertain, and where they are certain
/// the degree-4 fit itself wins.
pub fn quadratic_candidate(
    x: &Point,
    frame: &(Vector, Vector, Vector),
    fit: &JetFit,
    leak: &Leak,
) -> Option<(f64, JetPoint)> {
    let p = jet_curvature(x, frame, fit).ok()?;
    let (t1, t2, n) = frame;
    let len = (n - t1 * fit.coefficients[A10] - t2 * fit.coefficients[A01]).norm();
    let bias = [p.curvature.d1, p.curvature.d2].map(|d| {
        let g = curvature_gradient(&d, t1, t2, len);
        let (b, v) = (g.dot(&leak.bias), g.dot(&(leak.covariance * g)).max(0.0));
        (b * b - v).max(0.0).sqrt()
    });
    let point = JetPoint { bias, ..p };
    let [e1, e2] = point.predicted_error();
    Some((e1 * e1 + e2 * e2, point))
}

/// `(c², var c)` of the weighted line `k_j = k* + c (ρ_j/ρ_0)⁴` through the ladder, for k1 and
/// k2; zeros with fewer than two fits.
fn bias_lines(ladder: &[JetPoint]) -> [(f64, f64); 2] {
    if ladder.len() < 2 {
        return [(0.0, 0.0); 2];
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
        (c * c, sw / det)
    })
}

/// Equations per coefficient for a fit to enter the ladder's stopping rules (see [`trusted`]).
pub const TRUSTED_EQUATIONS_PER_COEFFICIENT: f64 = 3.0;

/// Whether a fit has enough equations for its own noise estimate to be trusted by the ladder's
/// stopping rules: 3 per coefficient. The weight `(1 − d²/ρ²)³` leaves an effective sample
/// size `(Σω)²/Σω²` of 7/16 of the count on a uniform disc, so at 1.5 equations per coefficient
/// (enough to determine the fit) the weighted residuals have almost no degrees of freedom left,
/// σ̂ is unreliable, and one wild fit would stop the climb. Such a fit stays a candidate for
/// the final choice, where on clean data its small bias wins.
pub fn trusted(fit: &JetFit) -> bool {
    fit.equations as f64 >= TRUSTED_EQUATIONS_PER_COEFFICIENT * coefficient_count(fit.degree) as f64
}

/// Equations (heights and slopes) per coefficient a degree needs.
pub const MIN_EQUATIONS_PER_COEFFICIENT: f64 = 1.5;

/// A degree is determined by its samples when every basis function `u^i v^j`, weighted over
/// them, keeps at least `√DETERMINED_PIVOT` ≈ 0.3 % of its norm outside the span of the
/// functions before it (the squared Cholesky pivot of the normal equations against its
/// diagonal entry). Samples on a few lines (scan lines, the rings of a profile scanner) leave
/// the terms that vanish on those lines nearly free; fitted, they follow the truncation
/// residual and give curvatures wrong by O(1) with a small predicted error. Measured
/// (docs/accuracy.md, "Determined degree"): on well-spread clouds a few fits in 10⁵ fall below
/// 1e-5 and their rows of the accuracy table are unchanged; on scan lines every value from 1e-5
/// to 3e-4 gives the same errors, 1e-6 about half the gain.
pub const DETERMINED_PIVOT: f64 = 1e-5;

/// Predicted standard deviations never fall below this fraction of `1/ρ`: below it an exact
/// fit's residual is rounding, and a zero-width interval would make the scale choice follow it.
pub const SD_FLOOR: f64 = 1e-8;

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
        let g = curvature_gradient(&d, t1, t2, len);
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

/// The first-order change of a principal curvature along the unit direction `d` with the
/// coefficients `(a20, a11, a02)`: `δk = −2(c² δa20 + cs δa11 + s² δa02)/|∇F|`, `(c, s)` the
/// components of `d` on `(t1, t2)` and `len` = |∇F|.
fn curvature_gradient(d: &Vector, t1: &Vector, t2: &Vector, len: f64) -> Vector {
    let (cs, sn) = (d.dot(t1), d.dot(t2));
    Vector::new(cs * cs, cs * sn, sn * sn) * (-2.0 / len)
}

/// A right-handed frame `(t1, t2, n)` around the unit normal `n`.
pub fn frame(n: &Vector) -> (Vector, Vector, Vector) {
    let (t1, t2) = tangent_basis(n);
    (t1, t2, *n)
}
