//! The projection's line derivatives: the energy (Eq. 4) along `x + t n` differentiated twice
//! in t with hyper-dual numbers, and the magnitudes the differences are measured against.

use mls_core::Sample;
use nalgebra::Vector3;
use num_dual::{Dual2, second_derivative};

use crate::{energy, log_scale, normal_field};

/// e′(t), e″(t) along a line, each scaled by `exp(log_scale)`, with their natural sizes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineWitness {
    /// `e′(t)`.
    pub first: f64,
    /// `e″(t)`.
    pub second: f64,
    /// `Σ θ (2|B| + 2a|B|³)`: the sum of the magnitudes of e′'s terms (B = b + t).
    pub first_scale: f64,
    /// `Σ θ (2 + 10aB² + 4a²B⁴)`: the same for e″.
    pub second_scale: f64,
    /// `a δ²`, δ the distance from `x` to its nearest sample.
    pub log_scale: f64,
}

/// e′(t) and e″(t) of `e(y) = Σ ((y − q)·n)² θ(y, q)` at `y = x + t n` (unit `n`).
pub fn line_witness(
    x: &Vector3<f64>,
    n: &Vector3<f64>,
    samples: &[Sample],
    inv_h2: f64,
    t: f64,
) -> LineWitness {
    let shift = log_scale(x, samples, inv_h2);
    let (_, first, second) = second_derivative(
        |s: Dual2<f64>| {
            let y = x.map(Dual2::from) + n.map(Dual2::from) * s;
            energy(&y, n, samples, inv_h2, shift)
        },
        t,
    );
    let (mut first_scale, mut second_scale) = (0.0, 0.0);
    for q in samples {
        let y = x + n * t;
        let d = y - q.point.coords;
        let b = d.dot(n);
        let theta = (-d.norm_squared() * inv_h2 + shift).exp();
        let ab2 = inv_h2 * b * b;
        first_scale += theta * 2.0 * b.abs() * (1.0 + ab2);
        second_scale += theta * (2.0 + 10.0 * ab2 + 4.0 * ab2 * ab2);
    }
    LineWitness {
        first,
        second,
        first_scale,
        second_scale,
        log_scale: shift,
    }
}

/// The line derivatives at `t = 0` along the witness's own n(x): at a point the projection
/// returned, e′(0) must vanish (to its stopping tolerance) and e″(0) must not be negative.
pub fn stationarity(x: &Vector3<f64>, samples: &[Sample], inv_h2: f64) -> LineWitness {
    let shift = log_scale(x, samples, inv_h2);
    let n = normal_field(x, samples, inv_h2, shift);
    line_witness(x, &n, samples, inv_h2, 0.0)
}
