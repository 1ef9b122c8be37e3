//! The adaptive scale's witness (`mls_core::adaptive`, `docs/derivation.md`): the ladder of
//! scales walked again from its definitions, with curvature at each scale from the hyper-dual
//! Hessian on a brute-force support, the noise σ from a weighted least-squares cubic solved by
//! QR of the weighted design matrix (mls-core forms the normal equations and uses Cholesky),
//! in the witness's own tangent frame, and the interval test, choice and extrapolation written
//! here.

use mls_core::Sample;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::{classify_g, support, weight_sum, witness_curvature};

/// What the adaptive estimate must be at one query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveWitness {
    /// The chosen scale.
    pub h: f64,
    /// σ estimated at the first usable scale.
    pub noise: f64,
    /// `C σ / (h² √(2 Σw))` at the chosen scale.
    pub scatter: f64,
    /// Principal curvatures, extrapolated when `extrapolated`.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// Whether the h² bias was removed.
    pub extrapolated: bool,
    /// `Σ w r²` of the noise fit (its residual's rounding is about ε times this).
    pub noise_srr: f64,
    /// Residual degrees of freedom of the noise fit.
    pub noise_dof: f64,
    /// Condition number of the noise fit's normal matrix `Σ w φ φᵀ`: a route through it (as
    /// mls-core's Cholesky) carries rounding of about `condition · ε · Σ w r²` in the residual.
    pub noise_condition: f64,
    /// The curvature scale ‖H‖/‖∇g‖ at the chosen scale.
    pub kappa: f64,
    /// `1/(h² √(2 Σw))` at the chosen scale.
    pub unit_scatter: f64,
}

/// The parameters of the ladder (those of `mls_core::AdaptiveConfig`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ladder {
    /// The smallest scale.
    pub h_min: f64,
    /// Number of scales, each √2 times the previous.
    pub scales: usize,
    /// Γ.
    pub confidence: f64,
    /// Scales below this multiple of the local spacing are skipped.
    pub min_h_factor: f64,
    /// The support radius in units of h.
    pub cutoff: f64,
    /// The noise gain C.
    pub gain: f64,
}

struct Estimate {
    h: f64,
    k: [f64; 2],
    unit_scatter: f64,
    kappa: f64,
}

/// The adaptive estimate at `x` (curvature at the query point), or `None` where some scale is
/// degenerate or the noise fit is rank-deficient (no comparison is made there).
pub fn adaptive_witness(
    x: &Vector3<f64>,
    samples: &[Sample],
    ladder: &Ladder,
) -> Option<AdaptiveWitness> {
    let scales = ladder.scales.max(2);
    let mut estimates: Vec<Estimate> = Vec::new();
    let mut noise: Option<NoiseFit> = None;
    let mut lower = [f64::NEG_INFINITY; 2];
    let mut upper = [f64::INFINITY; 2];
    let mut chosen = None;
    let mut partner = None;
    for j in 0..scales {
        let h = ladder.h_min * std::f64::consts::SQRT_2.powi(j as i32);
        let a = 1.0 / (h * h);
        let last = j + 1 == scales;
        let sup = support(x, samples, Some(ladder.cutoff * h));
        let (gradient, hessian) = classify_g(x, &sup, a, 3).ok()?;
        let sw = weight_sum(x, &sup, a);
        let spacing = (std::f64::consts::PI * h * h / sw).sqrt();
        if !(h >= ladder.min_h_factor * spacing) && !last {
            continue;
        }
        let c = witness_curvature(&gradient, &hessian);
        if noise.is_none() {
            noise = Some(noise_fit(x, samples, h, &gradient, &hessian)?);
        }
        estimates.push(Estimate {
            h,
            k: [c.k1, c.k2],
            unit_scatter: 1.0 / (h * h * (2.0 * sw).sqrt()),
            kappa: hessian.norm() / gradient.norm(),
        });
        let index = estimates.len() - 1;
        if chosen.is_some() {
            partner = Some(index);
            break;
        }
        let sd = ladder.gain * noise.map_or(0.0, |n| n.sigma) * estimates[index].unit_scatter;
        let mut agree = true;
        for c in 0..2 {
            lower[c] = lower[c].max(estimates[index].k[c] - ladder.confidence * sd);
            upper[c] = upper[c].min(estimates[index].k[c] + ladder.confidence * sd);
            agree &= lower[c] <= upper[c];
        }
        if !agree && index > 0 {
            chosen = Some(index - 1);
            partner = Some(index);
            break;
        } else if last {
            chosen = Some(index);
            partner = index.checked_sub(1);
        }
    }
    let e = &estimates[chosen?];
    let NoiseFit {
        sigma,
        srr,
        dof,
        condition,
    } = noise.unwrap_or_default();
    let scatter = ladder.gain * sigma * e.unit_scatter;
    let mut k = e.k;
    let mut extrapolated = false;
    if let Some(p) = partner.map(|p| &estimates[p]) {
        // The bias c·h² of each curvature from the two scales, removed when it exceeds twice
        // the predicted scatter.
        let bias = [0, 1].map(|c| (p.k[c] - e.k[c]) / (p.h * p.h - e.h * e.h) * e.h * e.h);
        if bias[0].abs().max(bias[1].abs()) > 2.0 * scatter && p.h != e.h {
            k = [k[0] - bias[0], k[1] - bias[1]];
            extrapolated = true;
        }
    }
    Some(AdaptiveWitness {
        h: e.h,
        noise: sigma,
        scatter,
        k1: k[0].max(k[1]),
        k2: k[0].min(k[1]),
        extrapolated,
        noise_srr: srr,
        noise_dof: dof,
        noise_condition: condition,
        kappa: e.kappa,
        unit_scatter: e.unit_scatter,
    })
}

/// The noise fit's outcome.
#[derive(Clone, Copy, Debug, Default)]
struct NoiseFit {
    sigma: f64,
    srr: f64,
    dof: f64,
    condition: f64,
}

/// σ of the samples within 2h of `x` off the local quadric `n·d + ½ dᵀ S d` (S the shape
/// operator `P H P/|∇g|`), less a weighted least-squares cubic in tangent coordinates /h,
/// weights `exp(−|d|²/h²)`: `(σ, Σ w r², dof)`, σ = √(RSS/dof) with
/// `dof = Σw − Σ w_i h_ii` (h_ii the hat matrix's diagonal), 0 when `dof ≤ 3 Σw/rows`.
fn noise_fit(
    x: &Vector3<f64>,
    samples: &[Sample],
    h: f64,
    gradient: &Vector3<f64>,
    hessian: &Matrix3<f64>,
) -> Option<NoiseFit> {
    let len = gradient.norm();
    let n = gradient / len;
    let p = Matrix3::identity() - n * n.transpose();
    let shape = p * hessian * p / len;
    // A tangent frame of the witness's own: the axis least aligned with n, made orthogonal.
    let axis = (0..3)
        .min_by(|&i, &j| n[i].abs().total_cmp(&n[j].abs()))
        .map(|i| Vector3::ith(i, 1.0))?;
    let t1 = (axis - n * n.dot(&axis)).normalize();
    let t2 = n.cross(&t1);
    let rows: Vec<(f64, [f64; 10], f64)> = support(x, samples, Some(2.0 * h))
        .iter()
        .map(|s| {
            let d = s.point.coords - x;
            let r = n.dot(&d) + 0.5 * d.dot(&(shape * d));
            let (u, v) = (t1.dot(&d) / h, t2.dot(&d) / h);
            let phi = [
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
            ];
            ((-d.norm_squared() / (h * h)).exp(), phi, r)
        })
        .collect();
    let m = rows.len();
    if m < 10 {
        return None;
    }
    let design = DMatrix::from_fn(m, 10, |i, j| rows[i].0.sqrt() * rows[i].1[j]);
    let b = DVector::from_fn(m, |i, _| rows[i].0.sqrt() * rows[i].2);
    let qr = design.qr();
    let r = qr.r();
    let big = r.diagonal().amax();
    if !(r.diagonal().amin() > 1e-10 * big) {
        return None;
    }
    let q = qr.q();
    let qtb = q.transpose() * &b;
    let rss = (&b - &q * &qtb).norm_squared();
    let sw: f64 = rows.iter().map(|r| r.0).sum();
    let leverage: f64 = (0..m).map(|i| rows[i].0 * q.row(i).norm_squared()).sum();
    let srr = b.norm_squared();
    let dof = sw - leverage;
    let singular = r.singular_values();
    let condition = (singular.max() / singular.min()).powi(2);
    let sigma = if sw > 0.0 && dof > 3.0 * sw / m as f64 {
        (rss.max(0.0) / dof).sqrt()
    } else {
        0.0
    };
    Some(NoiseFit {
        sigma,
        srr,
        dof,
        condition,
    })
}
