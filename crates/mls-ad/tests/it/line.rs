//! The projection's line derivatives e′(t), e″(t) (`projection::line_derivatives`, the code
//! the line search runs) against the hyper-dual derivatives of the energy along the line
//! (`mls_ad::line_witness`), at t away from 0: the quick version of `validate`'s line rows.
//! At t = 0 the terms in t vanish, so a test that only looked at the line's origin (as every
//! converged projection does) could not see them.

use mls_core::projection::line_derivatives;
use mls_core::{Point, Vector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{cloud, rel};

/// A random line: 60 samples on a patch of the unit sphere, h, and a point within `±offset·h`
/// of it with a direction within about 0.3 rad of the patch's normal.
fn random_line(rng: &mut ChaCha8Rng, offset: f64) -> (Vec<mls_core::Sample>, f64, Point, Vector) {
    let samples = cloud(rng, 60);
    let h = rng.random_range(0.05..0.3);
    let x = Point::new(
        rng.random_range(-0.1..0.1),
        rng.random_range(-0.1..0.1),
        1.0 + rng.random_range(-offset..offset) * h,
    );
    let n = Vector::new(
        rng.random_range(-0.3..0.3),
        rng.random_range(-0.3..0.3),
        1.0,
    )
    .normalize();
    (samples, h, x, n)
}

/// The relative differences of e′(t) and e″(t) between the line code and the witness.
fn differences(x: &Point, n: &Vector, samples: &[mls_core::Sample], h: f64, t: f64) -> [f64; 2] {
    let a = 1.0 / (h * h);
    let p = line_derivatives(x, n, samples, a, t);
    let w = mls_ad::line_witness(&x.coords, n, samples, a, t);
    let rescale = (w.log_scale - p.log_scale).exp();
    [
        rel(p.first * rescale, w.first, w.first_scale),
        rel(p.second * rescale, w.second, w.second_scale),
    ]
}

#[test]
fn line_derivatives_away_from_the_origin_match_the_witness() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0111);
    let mut worst = [0.0f64; 2];
    for case in 0..40 {
        let (samples, h, x, n) = random_line(&mut rng, 0.5);
        // |t| from h/4 to h, either side: the t and t² terms of the squared distance matter.
        let t = rng.random_range(0.25..1.0) * h * if case % 2 == 0 { 1.0 } else { -1.0 };
        let errs = differences(&x, &n, &samples, h, t);
        for (k, e) in errs.iter().enumerate() {
            worst[k] = worst[k].max(*e);
            assert!(
                *e < 1e-10,
                "case {case}: line derivative {} differs by {e:e} (t = {t}, h = {h})",
                k + 1
            );
        }
    }
    eprintln!("worst relative differences e', e'': {worst:?}");
}

/// Near t = 0, where a converging projection spends its line searches, the line code sums
/// the energy's Taylor series from the samples' moments instead of the samples: it must match
/// the witness there as the direct sums do farther out.
#[test]
fn line_derivatives_near_the_origin_match_the_witness() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0113);
    for case in 0..40 {
        let (samples, h, x, n) = random_line(&mut rng, 0.1);
        // |t| from 1e-10 h to h/10, log-uniform, either side.
        let t =
            10f64.powf(rng.random_range(-10.0..-1.0)) * h * if case % 2 == 0 { 1.0 } else { -1.0 };
        for (k, e) in differences(&x, &n, &samples, h, t).into_iter().enumerate() {
            assert!(
                e < 1e-12,
                "case {case}: line derivative {} differs by {e:e} (t = {t:e}, h = {h})",
                k + 1
            );
        }
    }
}

/// Far from every sample (40 h) every weight exp(−|x − q|²/h²) underflows unless shifted by
/// the nearest squared distance, as the line code does; the shifted derivatives still match.
#[test]
fn line_derivatives_far_from_the_samples_do_not_underflow() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0112);
    let samples = cloud(&mut rng, 60);
    let h = 0.1;
    let a = 1.0 / (h * h);
    let x = Point::new(0.0, 0.0, 1.0 + 40.0 * h);
    let n = Vector::new(0.1, 0.0, 1.0).normalize();
    for t in [-0.5 * h, 0.0, 0.5 * h] {
        let p = line_derivatives(&x, &n, &samples, a, t);
        let w = mls_ad::line_witness(&x.coords, &n, &samples, a, t);
        assert!(p.log_scale > 1000.0, "log scale {}", p.log_scale);
        let rescale = (w.log_scale - p.log_scale).exp();
        assert!(rel(p.first * rescale, w.first, w.first_scale) < 1e-10);
        assert!(rel(p.second * rescale, w.second, w.second_scale) < 1e-10);
        assert!(p.first != 0.0 && p.second != 0.0);
    }
}
