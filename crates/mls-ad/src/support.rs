//! The witness's own neighbourhood and its own verdict on degenerate points: a brute-force
//! distance filter over every sample (no spatial index, nothing shared with mls-core's search),
//! and the thresholds of `docs/derivation.md` applied to sums recomputed here.

use mls_core::{PointStatus, Sample};
use nalgebra::{Matrix3, Vector3};
use num_dual::hessian;

use crate::{Witness, implicit, log_scale, witness};

/// Below this ratio `|Σ w v| / Σ w` the weighted normals cancel and n(x) is undefined
/// (`docs/derivation.md`; written here, not imported, so that a changed threshold in mls-core
/// shows as a disagreement).
pub const COHERENCE_FLOOR: f64 = 1e-6;

/// Below this ratio `|∇g| / (2 Σ w)` the gradient counts as zero (same source).
pub const GRADIENT_FLOOR: f64 = 1e-12;

/// The samples within `radius` of `x` (every sample for `None`), by testing each one.
pub fn support(x: &Vector3<f64>, samples: &[Sample], radius: Option<f64>) -> Vec<Sample> {
    match radius {
        None => samples.to_vec(),
        Some(r) => samples
            .iter()
            .filter(|s| (x - s.point.coords).norm_squared() <= r * r)
            .copied()
            .collect(),
    }
}

/// The witness at `x` from its support, or the status a correct implementation must report
/// there: no or too few samples, weighted normals that cancel, or a vanishing gradient.
pub fn classify(
    x: &Vector3<f64>,
    support: &[Sample],
    inv_h2: f64,
    min_neighbours: usize,
) -> Result<Witness, PointStatus> {
    let sum = normal_verdict(x, support, inv_h2, min_neighbours)?;
    let w = witness(x, support, inv_h2);
    gradient_verdict(&w.gradient, sum)?;
    Ok(w)
}

/// [`classify`] for g alone: `(∇g, H)` by one hyper-dual Hessian (no derivatives of n).
pub fn classify_g(
    x: &Vector3<f64>,
    support: &[Sample],
    inv_h2: f64,
    min_neighbours: usize,
) -> Result<(Vector3<f64>, Matrix3<f64>), PointStatus> {
    let sum = normal_verdict(x, support, inv_h2, min_neighbours)?;
    let shift = log_scale(x, support, inv_h2);
    let (_, gradient, hessian) = hessian(|v| implicit(&v, support, inv_h2, shift), x);
    gradient_verdict(&gradient, sum)?;
    Ok((gradient, hessian))
}

/// Too few samples, or weighted normals that cancel; else the shifted `Σ w`.
fn normal_verdict(
    x: &Vector3<f64>,
    support: &[Sample],
    inv_h2: f64,
    min_neighbours: usize,
) -> Result<f64, PointStatus> {
    if support.is_empty() {
        return Err(PointStatus::NoNeighbours);
    }
    if support.len() < min_neighbours {
        return Err(PointStatus::TooFewNeighbours);
    }
    let shift = log_scale(x, support, inv_h2);
    let (sum, m) = support.iter().fold((0.0, Vector3::zeros()), |(s, m), q| {
        let w = (-(x - q.point.coords).norm_squared() * inv_h2 + shift).exp();
        (s + w, m + q.normal * w)
    });
    if !(m.norm() >= COHERENCE_FLOOR * sum) {
        return Err(PointStatus::NormalUndefined);
    }
    Ok(sum)
}

fn gradient_verdict(gradient: &Vector3<f64>, sum: f64) -> Result<(), PointStatus> {
    if !(gradient.norm() > GRADIENT_FLOOR * 2.0 * sum) {
        return Err(PointStatus::GradientVanishes);
    }
    Ok(())
}

/// `Σ w` at `x` without the shift: the unscaled weight sum of the Gaussian kernel.
pub fn weight_sum(x: &Vector3<f64>, support: &[Sample], inv_h2: f64) -> f64 {
    support
        .iter()
        .map(|q| (-(x - q.point.coords).norm_squared() * inv_h2).exp())
        .sum()
}
