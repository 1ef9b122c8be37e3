//! The adaptive-scale rows of `cargo xtask validate`: the adaptive stream (the CLI's
//! `--adaptive`) on a noisy copy of each case's cloud against `mls_ad::adaptive_witness`.

use mls_core::{
    AdaptiveConfig, AdaptiveSurface, Location, Point, Sample, adaptive::NOISE_GAIN,
    adaptive_curvature,
};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::validate::{Q, THRESHOLD, Tally};
use crate::validate_shapes as cases;

/// Queries per case for the adaptive estimate (each walks five scales).
const QUERIES: usize = 4;

pub(crate) fn check_adaptive(
    tally: &mut Tally,
    seed: u64,
    patch: &cases::Patch,
    queries: &[Point],
    rng: &mut ChaCha8Rng,
) {
    // Uniform position noise along the normals, up to a tenth of h: the noise estimate then has
    // something to measure and the scale choice is not always the smallest.
    let sigma = rng.random_range(0.0..0.1) * patch.h;
    let points: Vec<Point> = patch
        .points
        .iter()
        .zip(&patch.normals)
        .map(|(p, n)| p + n.normalize() * (sigma * rng.random_range(-1.0..1.0)))
        .collect();
    let config = AdaptiveConfig::new(0.5 * patch.h);
    let queries = &queries[..QUERIES.min(queries.len())];
    let Ok(surface) = AdaptiveSurface::new(&points, &patch.normals, &config) else {
        tally.record(Q::AdaptiveChoice, 1.0, seed);
        return;
    };
    // The CLI's path (the stream, in chunks of a random size) against one whole call.
    let results = crate::validate_sweep::streamed(
        tally,
        seed,
        rng,
        queries.len(),
        ("adaptive curvature_stream", "adaptive_curvature"),
        |par, chunk, sink| surface.curvature_stream(queries, Location::Input, par, chunk, sink),
        |par| {
            adaptive_curvature(
                &points,
                &patch.normals,
                queries,
                Location::Input,
                &config,
                par,
            )
            .unwrap_or_default()
        },
    );
    let samples: Vec<Sample> = points
        .iter()
        .zip(&patch.normals)
        .map(|(p, n)| Sample {
            point: *p,
            normal: n.normalize(),
        })
        .collect();
    let ladder = mls_ad::Ladder {
        h_min: config.h_min,
        // The documented defaults, not the configuration's (`mls_ad::documented`).
        scales: mls_ad::documented::ADAPTIVE_SCALES,
        confidence: mls_ad::documented::ADAPTIVE_CONFIDENCE,
        min_h_factor: mls_ad::documented::ADAPTIVE_MIN_H_FACTOR,
        cutoff: mls_ad::documented::CUTOFF,
        gain: 2.0,
    };
    // The gain is a measured constant, not a formula: the witness takes the documented value
    // and the row below fails if the code's drifts from it.
    tally.record(
        Q::AdaptiveChoice,
        f64::from(NOISE_GAIN != ladder.gain),
        seed,
    );
    for (x, r) in queries.iter().zip(results) {
        let Some(w) = mls_ad::adaptive_witness(&x.coords, &samples, &ladder) else {
            continue;
        };
        let Ok(p) = r else {
            tally.record(Q::AdaptiveChoice, 1.0, seed);
            continue;
        };
        let same = p.h == w.h && p.extrapolated == w.extrapolated;
        tally.record(Q::AdaptiveChoice, f64::from(!same), seed);
        tally.evals += 1;
        if !same {
            continue;
        }
        let dk = (p.curvature.k1 - w.k1)
            .abs()
            .max((p.curvature.k2 - w.k2).abs());
        tally.record(Q::AdaptiveK, dk / w.kappa, seed);
        let dmean = (p.curvature.mean - 0.5 * (w.k1 + w.k2)).abs() / w.kappa;
        let dgauss = (p.curvature.gauss - w.k1 * w.k2).abs() / (w.kappa * w.kappa);
        tally.record(Q::AdaptiveK, dmean.max(dgauss), seed);
        // σ² = RSS/dof, with RSS formed by the production as Σwr² − explained, explained
        // through the normal matrix: compared through RSS against Σwr², the size its
        // cancellation is relative to, and against the rounding cond·ε of any route through
        // the normal matrix where that exceeds the threshold (as for the jet).
        let rss = |s: f64| s * s * w.noise_dof;
        let rounding = (1e3 * f64::EPSILON * w.noise_condition / THRESHOLD).max(1.0);
        tally.record(
            Q::AdaptiveNoise,
            (rss(p.noise) - rss(w.noise)).abs() / w.noise_srr / rounding,
            seed,
        );
        // The scatter's own formula C σ/(h² √(2Σw)), on the production's σ.
        let scatter = ladder.gain * p.noise * w.unit_scatter;
        tally.record(Q::AdaptiveScatter, relative(p.scatter, scatter), seed);
    }
}

fn relative(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { (a - b).abs() / b.abs() }
}
