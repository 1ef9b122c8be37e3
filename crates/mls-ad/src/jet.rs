//! The jet estimator's witness: the same definition (`mls_core::jet`'s documentation) computed
//! by another route. Its own support (a brute-force distance filter over every sample),
//! production's tangent basis (a convention on which the degree test depends), the normal
//! equations formed from the dense weighted design matrix and
//! solved by LU (mls-core accumulates them row by row and uses Cholesky), a cluster-robust
//! covariance from per-sample score vectors, and the curvature of the fitted surface
//! `F = w − P(u, v)` by hyper-dual differentiation and a 3 × 3 eigen-decomposition. With
//! heights only, the degree-2 candidates beside the ladder are [`crate::jet_quadratic`]'s.

use mls_core::Sample;
use nalgebra::{DMatrix, DVector, Matrix3, SVector, Vector3};
use num_dual::{DualNum, hessian};

use crate::witness_curvature;

/// What the witness finds at one query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JetWitness {
    /// Principal curvatures at the foot point.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// Predicted standard deviations of k1 and k2 (noise part).
    pub sd: [f64; 2],
    /// Estimated bias of k1 and k2 from the line through the ladder (its unbiased form); for a
    /// degree-2 candidate, from its predicted leak (`√max(b² − var b, 0)`).
    pub bias: [f64; 2],
    /// Degree fitted (2 for a degree-2 candidate of `JetConfig::quadratic`).
    pub degree: usize,
    /// Support radius chosen.
    pub radius: f64,
    /// Condition number of the fit's normal matrix M (scaled coordinates): rounding in any
    /// route to the solution may move the coefficients by about `condition · ε` relative.
    pub condition: f64,
    /// Foot point.
    pub foot: Vector3<f64>,
    /// λ of the fit's final round (0 without slopes).
    pub slope_weight: f64,
    /// The fitted surface's unit normal at the foot point (`∇F/|∇F|`).
    pub normal: Vector3<f64>,
    /// Principal directions of k1 and k2 (signs arbitrary).
    pub directions: [Vector3<f64>; 2],
    /// σ̂ of the heights, file units, for a degree-2 candidate (NaN for the ladder's fits,
    /// which no blend takes).
    pub noise: f64,
}

/// Whether the weighted design determines its basis. The test is defined on the Cholesky pivots
/// of M = AᵀΩA: a pivot² below 1e-10 of the largest diagonal entry, or below 1e-5 of its own
/// (`DETERMINED_PIVOT`), leaves the basis undetermined.
pub(crate) fn determined(mm: &DMatrix<f64>) -> bool {
    let diag_max = (0..mm.nrows()).map(|i| mm[(i, i)]).fold(0.0f64, f64::max);
    let Some(chol) = nalgebra::Cholesky::new(mm.clone()) else {
        return false;
    };
    let l = chol.l();
    (0..mm.nrows()).all(|i| {
        let pivot2 = l[(i, i)] * l[(i, i)];
        pivot2 > 1e-10 * diag_max && pivot2 > 1e-5 * mm[(i, i)]
    })
}

/// The exponents of the degree-`d` basis, by total degree then by the power of v.
pub(crate) fn exponents(degree: usize) -> Vec<(i32, i32)> {
    let mut out = Vec::new();
    for d in 0..=degree as i32 {
        for j in 0..=d {
            out.push((d - j, j));
        }
    }
    out
}

/// One fit: `(coefficients in scaled units, their exponents, condition number of M,
/// covariance of (c20, c11, c02), λ of the final round)`, or `None` when the weighted design
/// does not determine the degree. A `given` λ is used in a single round.
#[allow(clippy::type_complexity)]
fn fit_once(
    rows: &[(f64, f64, f64, Vector3<f64>, f64)],
    degree: usize,
    slopes: bool,
    given: Option<f64>,
) -> Option<(Vec<f64>, Vec<(i32, i32)>, f64, Matrix3<f64>, f64)> {
    let ex = exponents(degree);
    let m = ex.len();
    // Rows: every height, then (if used) two slope rows per sample with a usable normal.
    let mut a_h = Vec::new();
    let mut a_s = Vec::new();
    // The height row each slope row belongs to.
    let mut owner = Vec::new();
    for &(u, v, z, nu, w) in rows {
        a_h.push((
            ex.iter()
                .map(|&(i, j)| u.powi(i) * v.powi(j))
                .collect::<Vec<_>>(),
            z,
            w,
        ));
        if slopes && nu.z > 0.5 {
            let du = ex
                .iter()
                .map(|&(i, j)| {
                    if i > 0 {
                        f64::from(i) * u.powi(i - 1) * v.powi(j)
                    } else {
                        0.0
                    }
                })
                .collect();
            let dv = ex
                .iter()
                .map(|&(i, j)| {
                    if j > 0 {
                        f64::from(j) * u.powi(i) * v.powi(j - 1)
                    } else {
                        0.0
                    }
                })
                .collect();
            a_s.push((du, -nu.x / nu.z, w));
            a_s.push((dv, -nu.y / nu.z, w));
            owner.extend([a_h.len() - 1; 2]);
        }
    }
    let gram = |rows: &[(Vec<f64>, f64, f64)], power: i32| {
        let mut g = DMatrix::<f64>::zeros(m, m);
        for (phi, _, w) in rows {
            let p = DVector::from_column_slice(phi);
            g += &p * p.transpose() * w.powi(power);
        }
        g
    };
    let (h2, s2) = (gram(&a_h, 2), gram(&a_s, 2));
    let wsum_h: f64 = a_h.iter().map(|r| r.2).sum();
    let wsum_s: f64 = a_s.iter().map(|r| r.2).sum();
    let use_slopes = slopes && wsum_s > 0.0;
    let mut lambda = if use_slopes {
        given.unwrap_or(1.0)
    } else {
        0.0
    };
    let mut out = None;
    for _ in 0..if use_slopes && given.is_none() { 2 } else { 1 } {
        // The √ω-scaled dense system.
        let n_rows = a_h.len() + a_s.len();
        let mut a = DMatrix::<f64>::zeros(n_rows, m);
        let mut b = DVector::<f64>::zeros(n_rows);
        for (r, (phi, y, w)) in a_h
            .iter()
            .map(|(p, y, w)| (p, y, *w))
            .chain(a_s.iter().map(|(p, y, w)| (p, y, w * lambda)))
            .enumerate()
        {
            let sw = w.sqrt();
            for c in 0..m {
                a[(r, c)] = phi[c] * sw;
            }
            b[r] = y * sw;
        }
        let mm = a.transpose() * &a;
        if !determined(&mm) {
            return None;
        }
        // LU of the dense normal equations (nalgebra's SVD lost digits on the worst-conditioned
        // systems the pivot test admits, cond(M) up to 1e10: measured c20 wrong in the third
        // digit where both factorisations of M agree).
        let c = mm.clone().lu().solve(&(a.transpose() * &b))?;
        let inv = mm.clone().try_inverse()?;
        let (mut rss_h, mut rss_s) = (0.0, 0.0);
        for (phi, y, w) in &a_h {
            let p: f64 = phi.iter().zip(c.iter()).map(|(x, c)| x * c).sum();
            rss_h += w * (y - p) * (y - p);
        }
        for (phi, y, w) in &a_s {
            let p: f64 = phi.iter().zip(c.iter()).map(|(x, c)| x * c).sum();
            rss_s += w * (y - p) * (y - p);
        }
        let dof_h = wsum_h - (&inv * &h2).trace();
        let dof_s = wsum_s - lambda * (&inv * &s2).trace();
        if !(dof_h > 0.0) {
            return None;
        }
        let var_h = rss_h / dof_h;
        let var_s = if use_slopes && dof_s > 0.0 {
            rss_s / dof_s
        } else {
            0.0
        };
        let samples = a_h.len();
        let cov_full = if use_slopes && samples > m {
            // Cluster-robust sandwich, one cluster per sample (its height and slope rows).
            let mut g = vec![DVector::<f64>::zeros(m); samples];
            for (i, (phi, y, w)) in a_h.iter().enumerate() {
                let p = DVector::from_column_slice(phi);
                let r = y - p.dot(&c);
                g[i] += p * (w * r);
            }
            for ((phi, y, w), &i) in a_s.iter().zip(&owner) {
                let p = DVector::from_column_slice(phi);
                let r = y - p.dot(&c);
                g[i] += p * (w * lambda * r);
            }
            let meat = g.iter().fold(DMatrix::<f64>::zeros(m, m), |acc, g| {
                acc + g * g.transpose()
            });
            &inv * meat * &inv * (samples as f64 / (samples - m) as f64)
        } else {
            &inv * (&h2 * var_h + &s2 * (lambda * lambda * var_s)) * &inv
        };
        let cov = Matrix3::from_fn(|i, j| cov_full[(3 + i, 3 + j)]);
        let eig = mm.clone().symmetric_eigenvalues();
        let condition = eig.max() / eig.min();
        out = Some((
            c.iter().copied().collect(),
            ex.clone(),
            condition,
            cov,
            lambda,
        ));
        if use_slopes {
            lambda = if var_s > 0.0 {
                (var_h / var_s).clamp(1e-4, 1e4)
            } else {
                1e4
            };
        }
    }
    out
}

/// The fitted height polynomial `ρ p(u/ρ, v/ρ)` at dual `(u, v)`.
fn height<D: DualNum<Primitive = f64> + Copy>(
    u: D,
    v: D,
    c: &[f64],
    ex: &[(i32, i32)],
    rho: f64,
) -> D {
    let (su, sv) = (u * (1.0 / rho), v * (1.0 / rho));
    ex.iter()
        .zip(c)
        .map(|(&(i, j), &c)| su.powi(i) * sv.powi(j) * c)
        .fold(D::from(0.0), |a, b| a + b)
        * rho
}

/// `F(y) = w − P(u, v)` with `(u, v, w)` the coordinates of `y − x` in the frame.
fn fitted<D: DualNum<Primitive = f64> + Copy>(
    y: &SVector<D, 3>,
    x: &Vector3<f64>,
    frame: &(Vector3<f64>, Vector3<f64>, Vector3<f64>),
    c: &[f64],
    ex: &[(i32, i32)],
    rho: f64,
) -> D {
    let d = y - x.map(D::from);
    let (u, v, w) = (
        d.dot(&frame.0.map(D::from)),
        d.dot(&frame.1.map(D::from)),
        d.dot(&frame.2.map(D::from)),
    );
    w - height(u, v, c, ex, rho)
}

/// A fit's curvature at its foot point `x + a00 n`.
pub(crate) struct FootCurvature {
    pub(crate) foot: Vector3<f64>,
    /// `∇F/|∇F|` at the foot point.
    pub(crate) normal: Vector3<f64>,
    /// The principal directions.
    pub(crate) directions: [Vector3<f64>; 2],
    /// k1, k2 of `F = w − P(u, v)` by hyper-dual differentiation.
    pub(crate) k: [f64; 2],
    /// `g_i = (c², cs, s²)·2/|∇F|`, `(c, s)` principal direction i on `(t1, t2)`: the first
    /// order change of k_i per change of `(a20, a11, a02)`, with a sign.
    pub(crate) rows: [Vector3<f64>; 2],
    /// `√(g_iᵀ cov g_i)`, at least 1e-8/ρ (`SD_FLOOR`).
    pub(crate) sd: [f64; 2],
}

/// The curvature of the fit of scaled coefficients `c` (exponents `ex`) at radius `rho`, with
/// the predicted standard deviations from `cov`, the covariance of the file-unit `(a20, a11,
/// a02)`.
pub(crate) fn foot_curvature(
    x: &Vector3<f64>,
    frame: &(Vector3<f64>, Vector3<f64>, Vector3<f64>),
    c: &[f64],
    ex: &[(i32, i32)],
    rho: f64,
    cov: &Matrix3<f64>,
) -> FootCurvature {
    let (t1, t2, n) = frame;
    let foot = x + n * (c[0] * rho);
    let (_, grad, hess) = hessian(|y| fitted(&y, x, frame, c, ex, rho), &foot);
    let wc = witness_curvature(&grad, &hess);
    let rows = [wc.d1, wc.d2].map(|d| {
        let (cs, sn) = (d.dot(t1), d.dot(t2));
        Vector3::new(cs * cs, cs * sn, sn * sn) * (2.0 / grad.norm())
    });
    let sd = rows.map(|g| (g.dot(&(cov * g))).max(0.0).sqrt().max(1e-8 / rho));
    FootCurvature {
        foot,
        normal: grad.normalize(),
        directions: [wc.d1, wc.d2],
        k: [wc.k1, wc.k2],
        rows,
        sd,
    }
}

/// Why the witness has no jet at a query.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JetRefusal {
    /// No fit: too few samples, or none that determines a degree (production returns one of
    /// its failure statuses; the witness does not tell them apart).
    NoFit,
    /// Heights only with `config.quadratic`: the query lies beyond the robust cutoff of the
    /// largest degree-2 support's plain fit (`PointStatus::Outlier`).
    Outlier,
}

/// Every scale `Evaluator::jet_at` may return at `x`, each with its estimated squared error,
/// from all `samples` of the cloud: those the intervals accept, or the single lower-degree
/// fallback (its error +∞: any degree-2 candidate replaces it), then with heights only and
/// `config.quadratic` the degree-2 candidates in increasing radius (where the ladder's choice
/// is not resolved already). Never empty; [`JetRefusal`] where there is nothing, or where the
/// degree-2 candidates find the query an outlier.
pub fn jet_candidates(
    x: &Vector3<f64>,
    samples: &[Sample],
    h: f64,
    config: &mls_core::JetConfig,
) -> Result<Vec<(f64, JetWitness)>, JetRefusal> {
    let slopes = config.normals == mls_core::NormalData::Slopes;
    let mut frame: Option<(Vector3<f64>, Vector3<f64>, Vector3<f64>)> = None;
    let mut best: Option<JetWitness> = None;
    let mut ladder: Vec<JetWitness> = Vec::new();
    let mut accepted = 0;
    // Full-degree fits with fewer than 3 equations per coefficient: candidates at the front
    // of the ladder that neither narrow the intervals nor stop the climb.
    let mut early = 0;
    let mut fallback: Option<JetWitness> = None;
    let (mut lo, mut hi) = ([f64::NEG_INFINITY; 2], [f64::INFINITY; 2]);
    // One scale: `None` when fewer than 6 samples lie within ρ, `Some(None)` when no degree
    // is determined, else the fit with its number of equations. The first scale with samples
    // sets the frame.
    let fit_scale = |rho: f64,
                     given: Option<f64>,
                     frame: &mut Option<(Vector3<f64>, Vector3<f64>, Vector3<f64>)>|
     -> Option<Option<(JetWitness, usize)>> {
        let near: Vec<(Vector3<f64>, Vector3<f64>, f64)> = samples
            .iter()
            .filter_map(|s| {
                let d = s.point.coords - x;
                let t = 1.0 - d.norm_squared() / (rho * rho);
                (t > 0.0).then_some((d, s.normal, t * t * t))
            })
            .collect();
        if near.len() < 6 {
            return None;
        }
        let (t1, t2, n) = *frame.get_or_insert_with(|| {
            // The weighted average of the normals, unless it lies more than 60° from the
            // nearest sample's normal (the far sheet of a thin part turned it): then only the
            // normals on the nearest sample's side.
            let own = samples
                .iter()
                .map(|s| ((s.point.coords - x).norm_squared(), s.normal))
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map_or_else(Vector3::zeros, |(_, nu)| nu);
            let all: Vector3<f64> = near.iter().map(|(_, nu, w)| nu * *w).sum();
            let sum: Vector3<f64> = if all.angle(&own).to_degrees() < 60.0 {
                all
            } else {
                near.iter()
                    .filter(|(_, nu, _)| nu.dot(&own) > 0.0)
                    .map(|(_, nu, w)| nu * *w)
                    .sum()
            };
            let n = sum.normalize();
            // Production's tangent basis. The fit is rotation-invariant in (u, v), but which
            // degree the samples determine is not: the pivot test asks how much of each
            // monomial u^i v^j lies outside the span of those before it, and turning the
            // basis changes the monomials. With another basis a layout near the threshold
            // (a squared pivot at 0.985 × 1e-5 of its own entry on a sphere patch of 8
            // samples) was fitted at degree 4 here and 3 there, and every scale after it
            // took another λ. The basis is a convention, not a formula under test: AD of F
            // still checks the closed form's gradient and Hessian for it.
            let (t1, t2) = mls_core::math::tangent_basis(&n);
            (t1, t2, n)
        });
        // Samples facing away from the frame belong to another sheet.
        let near: Vec<_> = near
            .into_iter()
            .filter(|(_, nu, _)| nu.dot(&n) > 0.0)
            .collect();
        let rows: Vec<_> = near
            .iter()
            .map(|(d, nu, w)| {
                (
                    d.dot(&t1) / rho,
                    d.dot(&t2) / rho,
                    d.dot(&n) / rho,
                    Vector3::new(nu.dot(&t1), nu.dot(&t2), nu.dot(&n)),
                    *w,
                )
            })
            .collect();
        let equations = rows.len()
            + if slopes {
                2 * rows.iter().filter(|r| r.3.z > 0.5).count()
            } else {
                0
            };
        let solution = (2..=config.degree.clamp(2, 4))
            .rev()
            .filter(|&d| equations as f64 >= 1.5 * ((d + 1) * (d + 2) / 2) as f64)
            .find_map(|d| fit_once(&rows, d, slopes, given).map(|f| (d, f)));
        let Some((degree, (c, ex, condition, cov, slope_weight))) = solution else {
            return Some(None);
        };
        let at = foot_curvature(x, &(t1, t2, n), &c, &ex, rho, &(cov / (rho * rho)));
        Some(Some((
            JetWitness {
                k1: at.k[0],
                k2: at.k[1],
                sd: at.sd,
                bias: [0.0; 2],
                condition,
                degree,
                radius: rho,
                foot: at.foot,
                slope_weight,
                normal: at.normal,
                directions: at.directions,
                noise: f64::NAN,
            },
            equations,
        )))
    };
    for j in 0..config.scales.max(1) {
        let rho = config.radius * h * 2f64.sqrt().powi(j as i32);
        // After the ladder's first fit, each scale takes its λ in one round (unless it is 0:
        // that fit had no slopes).
        let given = ladder.first().map(|w| w.slope_weight).filter(|&l| l > 0.0);
        let Some(fitted) = fit_scale(rho, given, &mut frame) else {
            continue;
        };
        let Some((here, equations)) = fitted else {
            if best.is_some() {
                break;
            }
            continue;
        };
        let (degree, sd) = (here.degree, here.sd);
        if best.is_none() && degree < config.degree.clamp(2, 4) {
            fallback = fallback.or(Some(here));
            continue;
        }
        if best.is_none() && (equations as f64) < 3.0 * ((degree + 1) * (degree + 2) / 2) as f64 {
            ladder.push(here);
            early += 1;
            continue;
        }
        let k = [here.k1, here.k2];
        let mut agree = true;
        for i in 0..2 {
            lo[i] = lo[i].max(k[i] - config.confidence * sd[i]);
            hi[i] = hi[i].min(k[i] + config.confidence * sd[i]);
            agree &= lo[i] <= hi[i];
        }
        ladder.push(here);
        if !agree {
            accepted = ladder.len() - 1;
            break;
        }
        accepted = ladder.len();
        best = Some(here);
        // Stop once the previous scale's bias (from the last step, ∝ ρ⁴) exceeds its scatter.
        if let [.., a, b] = &ladder[early..] {
            let bias2 = ((b.k1 - a.k1) / 3.0).powi(2) + ((b.k2 - a.k2) / 3.0).powi(2);
            let floor = 2e-8 / a.radius;
            if bias2 > a.sd[0].powi(2) + a.sd[1].powi(2) || (a.sd[0] <= floor && a.sd[1] <= floor) {
                break;
            }
        }
    }
    // No scale accepted: the lower-degree fallback (if any), with an unknown error.
    let fallback_only = best.is_none() && early == 0;
    if best.is_none() {
        accepted = early;
    }
    // With slopes, the lead scale one √2 step below the first joins the candidates when it
    // has the full degree and 3 equations per coefficient; the climb's frame is kept, and
    // the first fit's λ is used in one round.
    if slopes && config.lead && !fallback_only {
        let rho = config.radius / 2f64.sqrt() * h;
        let full = config.degree.clamp(2, 4);
        let given = Some(ladder[0].slope_weight).filter(|&l| l > 0.0);
        if let Some(Some((here, equations))) = fit_scale(rho, given, &mut frame)
            && here.degree == full
            && equations as f64 >= 3.0 * ((full + 1) * (full + 2) / 2) as f64
        {
            ladder.insert(0, here);
            accepted += 1;
        }
    }
    // Least estimated squared error among the accepted scales; for the choice the bias of
    // scale j is t_j √(c² + var c) from the weighted line k = k* + c t, t = (ρ/ρ₀)⁴, through
    // every fit; the candidate carries t_j √max(c² − var c, 0), the unbiased estimate.
    let t = |w: &JetWitness| (w.radius / ladder[0].radius).powi(4);
    let growth = [0, 1].map(|i| {
        if ladder.len() < 2 {
            return (0.0, 0.0);
        }
        let pts: Vec<(f64, f64, f64)> = ladder
            .iter()
            .map(|w| {
                (
                    t(w),
                    if i == 0 { w.k1 } else { w.k2 },
                    1.0 / w.sd[i].powi(2),
                )
            })
            .collect();
        // The normal equations of the 2-parameter weighted line, solved by nalgebra.
        let a = nalgebra::Matrix2::new(
            pts.iter().map(|p| p.2).sum::<f64>(),
            pts.iter().map(|p| p.2 * p.0).sum::<f64>(),
            pts.iter().map(|p| p.2 * p.0).sum::<f64>(),
            pts.iter().map(|p| p.2 * p.0 * p.0).sum::<f64>(),
        );
        let b = nalgebra::Vector2::new(
            pts.iter().map(|p| p.2 * p.1).sum::<f64>(),
            pts.iter().map(|p| p.2 * p.0 * p.1).sum::<f64>(),
        );
        let inv = a.try_inverse().unwrap_or_else(nalgebra::Matrix2::zeros);
        let c = (inv * b)[1];
        (c * c, inv[(1, 1)])
    });
    let mut candidates: Vec<(f64, JetWitness)> = if fallback_only {
        fallback.map(|w| (f64::INFINITY, w)).into_iter().collect()
    } else {
        (0..accepted)
            .map(|j| {
                let cautious = growth.map(|(c2, var)| (c2 + var).sqrt() * t(&ladder[j]));
                let mse = (0..2)
                    .map(|i| ladder[j].sd[i].powi(2) + cautious[i].powi(2))
                    .sum::<f64>();
                let bias = growth.map(|(c2, var)| (c2 - var).max(0.0).sqrt() * t(&ladder[j]));
                (mse, JetWitness { bias, ..ladder[j] })
            })
            .collect()
    };
    // Heights only: the degree-2 candidates, from the ladder's frame, after the ladder's own,
    // so that one wins only with a strictly smaller estimated error (the first of equals is
    // kept); not sought where the ladder's choice is resolved already (`jet::resolved`), but
    // sought where the ladder has only a fallback or nothing (wherever a frame exists).
    if !slopes
        && config.quadratic
        && let Some(frame) = &frame
        && !resolved(&candidates, h)
    {
        let quadratic = crate::jet_quadratic::quadratic_candidates(x, samples, h, frame)
            .map_err(|_| JetRefusal::Outlier)?;
        candidates.extend(quadratic);
    }
    if candidates.is_empty() {
        return Err(JetRefusal::NoFit);
    }
    Ok(candidates)
}

/// Whether the ladder's choice among `candidates` (the first of least estimated error, which
/// must be finite: a fallback's is not) has a predicted error `|(√(sd1² + b1²), √(sd2² + b2²))|` (its bias in the unbiased form) of at
/// most 1e-2 of max(|k1|, |k2|) plus 1e-4/h: mls-core's `RESOLVED_RELATIVE` and
/// `RESOLVED_ABSOLUTE`, restated.
fn resolved(candidates: &[(f64, JetWitness)], h: f64) -> bool {
    let Some((_, w)) = candidates
        .iter()
        .fold(None::<&(f64, JetWitness)>, |acc, c| match acc {
            Some(a) if a.0 <= c.0 => acc,
            _ => Some(c),
        })
    else {
        return false;
    };
    if !candidates.iter().any(|(m, _)| m.is_finite()) {
        return false;
    }
    let e = (0..2)
        .map(|i| w.sd[i].powi(2) + w.bias[i].powi(2))
        .sum::<f64>()
        .sqrt();
    e <= 1e-2 * w.k1.abs().max(w.k2.abs()) + 1e-4 / h
}

/// The witness of `Evaluator::jet_at` at `x`, from all `samples` of the cloud: the candidate of
/// least estimated squared error among [`jet_candidates`] (the first of equals), or why there
/// is none.
pub fn jet_witness(
    x: &Vector3<f64>,
    samples: &[Sample],
    h: f64,
    config: &mls_core::JetConfig,
) -> Result<JetWitness, JetRefusal> {
    let candidates = jet_candidates(x, samples, h, config)?;
    candidates
        .into_iter()
        .fold(None::<(f64, JetWitness)>, |acc, (m, w)| match acc {
            Some((am, _)) if am <= m => acc,
            _ => Some((m, w)),
        })
        .map(|(_, w)| w)
        .ok_or(JetRefusal::NoFit)
}
