//! The witness's own neighbourhood and its own verdict on degenerate points: a brute-force
//! distance filter over every sample (no spatial index, nothing shared with mls-core's search),
//! and the thresholds of `docs/derivation.md` applied to sums recomputed here.

use mls_core::{PointStatus, Sample};
use nalgebra::Vector3;

use crate::{Witness, log_scale, witness};

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
    let w = witness(x, support, inv_h2);
    if !(w.gradient.norm() > GRADIENT_FLOOR * 2.0 * sum) {
        return Err(PointStatus::GradientVanishes);
    }
    Ok(w)
}

/// `Σ w` at `x` without the shift: the unscaled weight sum of the Gaussian kernel.
pub fn weight_sum(x: &Vector3<f64>, support: &[Sample], inv_h2: f64) -> f64 {
    support
        .iter()
        .map(|q| (-(x - q.point.coords).norm_squared() * inv_h2).exp())
        .sum()
}
