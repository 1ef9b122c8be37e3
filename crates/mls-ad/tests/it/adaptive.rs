//! The adaptive scale (`--adaptive`) against its witness (`mls_ad::adaptive_witness`) at
//! query points between the samples, clean (the h² bias extrapolated away) and noisy: the
//! quick version of `validate`'s adaptive rows. Off the
//! samples the field's exponent shift is not 0, so the weight sum that sets the local spacing
//! and the predicted scatter must be unshifted correctly (at a sample the shift is 0 and a
//! wrong unshifting would go unseen).

use mls_core::{
    AdaptiveConfig, Location, Parallelism, Point, Sample, Vector, adaptive::NOISE_GAIN,
    adaptive_curvature,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn adaptive_scale_between_the_samples_matches_its_witness() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0ada);
    let (mut compared, mut extrapolated) = (0, 0);
    for case in 0..6 {
        // A noisy patch of the unit sphere, normals exact.
        let n = 400;
        let h = 0.08;
        // Clean patches first: the scatter is then about 0 and the h² bias is removed
        // (extrapolated); noisy ones keep their scale's estimate.
        let sigma = if case < 2 {
            0.0
        } else {
            rng.random_range(0.02..0.1) * h
        };
        let (points, normals): (Vec<Point>, Vec<Vector>) = (0..n)
            .map(|_| {
                let dir = Vector::new(
                    rng.random_range(-0.4..0.4),
                    rng.random_range(-0.4..0.4),
                    1.0,
                )
                .normalize();
                (
                    Point::from(dir * (1.0 + sigma * rng.random_range(-1.0..1.0))),
                    dir,
                )
            })
            .unzip();
        let queries: Vec<Point> = (0..4)
            .map(|_| {
                let dir = Vector::new(
                    rng.random_range(-0.15..0.15),
                    rng.random_range(-0.15..0.15),
                    1.0,
                )
                .normalize();
                Point::from(dir)
            })
            .collect();
        let config = AdaptiveConfig::new(0.5 * h);
        let results = adaptive_curvature(
            &points,
            &normals,
            &queries,
            Location::Input,
            &config,
            Parallelism::Sequential,
        )
        .unwrap();
        let samples: Vec<Sample> = points
            .iter()
            .zip(&normals)
            .map(|(p, n)| Sample {
                point: *p,
                normal: *n,
            })
            .collect();
        let ladder = mls_ad::Ladder {
            h_min: config.h_min,
            scales: config.scales,
            confidence: config.confidence,
            min_h_factor: config.min_h_factor,
            cutoff: 5.0,
            gain: NOISE_GAIN,
        };
        for (x, r) in queries.iter().zip(results) {
            let Some(w) = mls_ad::adaptive_witness(&x.coords, &samples, &ladder) else {
                continue;
            };
            let p =
                r.unwrap_or_else(|s| panic!("case {case}: {s:?} where the witness has a result"));
            assert_eq!(
                (p.h, p.extrapolated),
                (w.h, w.extrapolated),
                "case {case} at {x:?}"
            );
            let dk = (p.curvature.k1 - w.k1)
                .abs()
                .max((p.curvature.k2 - w.k2).abs());
            assert!(dk < 1e-9 * w.kappa, "case {case}: k off by {dk:e}");
            let c = &p.curvature;
            let dmean = (c.mean - 0.5 * (w.k1 + w.k2)).abs() / w.kappa;
            let dgauss = (c.gauss - w.k1 * w.k2).abs() / (w.kappa * w.kappa);
            assert!(
                dmean.max(dgauss) < 1e-9,
                "case {case}: mean {dmean:e}, gauss {dgauss:e}"
            );
            // The frame stays right-handed when extrapolation swaps k1 and k2.
            assert!(
                (c.d1.cross(&c.d2) - c.normal).norm() < 1e-12,
                "case {case}: d1 × d2 ≠ n"
            );
            // σ² = RSS/dof through the residual sum of squares, against the rounding of a route
            // through the normal matrix (as validate does).
            let rss = |s: f64| s * s * w.noise_dof;
            let rounding = (1e3 * f64::EPSILON * w.noise_condition / 1e-10).max(1.0);
            let dn = (rss(p.noise) - rss(w.noise)).abs() / w.noise_srr / rounding;
            assert!(
                dn < 1e-10,
                "case {case}: noise {} against {}",
                p.noise,
                w.noise
            );
            // The scatter C σ/(h² √(2Σw)) from the witness's unshifted weight sum.
            let scatter = NOISE_GAIN * p.noise * w.unit_scatter;
            assert!(
                (p.scatter - scatter).abs() <= 1e-12 * scatter,
                "case {case}: scatter {} against {scatter}",
                p.scatter
            );
            compared += 1;
            extrapolated += usize::from(p.extrapolated);
        }
    }
    assert!(compared >= 12, "only {compared} comparisons");
    assert!(
        extrapolated > 0 && extrapolated < compared,
        "{extrapolated} of {compared} extrapolated"
    );
}
