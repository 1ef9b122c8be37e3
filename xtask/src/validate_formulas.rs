//! Rows of `cargo xtask validate` that check a formula on its own, away from any cloud: the
//! branch-free exp of the kernels against the standard library's, and the shrinkage
//! correction on curvatures and scales where the correction is large.

use mls_core::kernels::{exp_any, exp_weight};
use mls_core::{Curvature, Vector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::validate::{Q, Tally};
use crate::validate_sweep::record_shrinkage;

/// Distance in units in the last place between two non-negative values (infinite when one is
/// not finite and the other is).
fn ulps(a: f64, b: f64) -> f64 {
    if a.is_finite() != b.is_finite() {
        return f64::INFINITY;
    }
    a.to_bits().abs_diff(b.to_bits()) as f64
}

/// `exp_weight` over [−746, 0] (and densely near 0, where most weights are) and `exp_any`
/// over [−746, 709.78], `count` arguments each, against `f64::exp`: documented within 1 ulp.
pub(crate) fn exp_sweep(tally: &mut Tally, count: usize) {
    let n = count as f64;
    for i in 0..=count {
        let f = i as f64 / n;
        for x in [-746.0 * f, -f, 693.0 * f] {
            tally.record(Q::ExpWeight, ulps(exp_weight(x), x.exp()), 0);
        }
        for x in [-746.0 * f, 709.78 * f] {
            tally.record(Q::ExpAny, ulps(exp_any(x), x.exp()), 0);
        }
    }
}

/// `correct_shrinkage` on random principal curvatures with |k|·h up to 0.5, where the
/// correction is up to a few per cent of k (on the sweep's clouds it is often below 1e-6).
pub(crate) fn shrinkage_sweep(tally: &mut Tally, seed: u64, count: usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5348_5249_4e4b);
    for _ in 0..count {
        let h = 10f64.powf(rng.random_range(-3.0..1.0));
        let k = [0, 1].map(|_| rng.random_range(-0.5..0.5) / h);
        let (k1, k2) = (k[0].max(k[1]), k[0].min(k[1]));
        let c = Curvature {
            normal: Vector::z(),
            k1,
            k2,
            mean: 0.5 * (k1 + k2),
            gauss: k1 * k2,
            d1: Vector::x(),
            d2: Vector::y(),
        };
        record_shrinkage(tally, seed, &c, h);
    }
}
