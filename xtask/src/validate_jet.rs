//! The jet rows of `cargo xtask validate`: `MlsSurface::jet_stream` (the CLI's path, in chunks
//! of a random size, bitwise `jet_at_points`) against `mls_ad::jet_witness`.

use mls_core::{MlsSurface, Point};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::validate::{Q, SD_THRESHOLD, THRESHOLD, Tally};
use crate::validate_shapes as cases;
use crate::validate_sweep::streamed;

/// The jet estimator through the whole-cloud entry point against its witness, which filters
/// its support from every sample of the patch by brute force.
pub(crate) fn compare_jets(
    tally: &mut Tally,
    seed: u64,
    patch: &cases::Patch,
    surface: &MlsSurface,
    queries: &[Point],
    rng: &mut ChaCha8Rng,
) {
    let config = mls_core::JetConfig {
        normals: if rng.random_bool(0.5) {
            mls_core::NormalData::Slopes
        } else {
            mls_core::NormalData::Ignore
        },
        ..mls_core::JetConfig::default()
    };
    let samples: Vec<mls_core::Sample> = patch
        .points
        .iter()
        .zip(&patch.normals)
        .map(|(p, n)| mls_core::Sample {
            point: *p,
            normal: n.normalize(),
        })
        .collect();
    // The CLI's path: the stream in chunks of a random size, then against the witness.
    let results = streamed(
        tally,
        seed,
        rng,
        queries.len(),
        ("jet_stream", "jet_at_points"),
        |par, chunk, sink| surface.jet_stream(queries, &config, par, chunk, sink),
        |par| surface.jet_at_points(queries, &config, par),
    );
    for (x, r) in queries.iter().zip(results) {
        let candidates = mls_ad::jet_candidates(&x.coords, &samples, patch.h, &config);
        // The witness's choice; a production choice of another accepted scale whose estimated
        // error ties the least within 1e-4 (the two routes' error estimates agree to ~1e-5)
        // is a tie broken by rounding, not a wrong formula: compare against that scale.
        let witness = candidates.as_ref().and_then(|c| {
            let least = c.iter().map(|(m, _)| *m).fold(f64::INFINITY, f64::min);
            let chosen = c.iter().find(|(m, _)| *m == least).map(|(_, w)| *w);
            match &r {
                Ok(j) => c
                    .iter()
                    .find(|(m, w)| w.radius == j.fit.radius && *m <= least * (1.0 + 1e-4))
                    .map(|(_, w)| *w)
                    .or(chosen),
                Err(_) => chosen,
            }
        });
        match (r, witness) {
            (Ok(j), Some(w)) => {
                let kappa = w.k1.abs().max(w.k2.abs()).max(1.0 / patch.h);
                // A least-squares solution carries rounding of about cond(M)·ε whatever the
                // route; differences are measured against that bound where it exceeds the
                // threshold (reported at the threshold's scale).
                let rounding = (1e3 * f64::EPSILON * w.condition / THRESHOLD).max(1.0);
                tally.record(
                    Q::JetK1,
                    (j.curvature.k1 - w.k1).abs() / kappa / rounding,
                    seed,
                );
                tally.record(
                    Q::JetK2,
                    (j.curvature.k2 - w.k2).abs() / kappa / rounding,
                    seed,
                );
                let pe = j.predicted_error();
                let we = [w.sd[0].hypot(w.bias[0]), w.sd[1].hypot(w.bias[1])];
                let sd = (pe[0] - we[0]).abs().max((pe[1] - we[1]).abs());
                let sd_scale = (w.sd[0].hypot(w.bias[0]))
                    .max(w.sd[1].hypot(w.bias[1]))
                    // Within 1000× of the rounding floor (1e-8/ρ) a predicted error is made of
                    // residuals at rounding level and carries their rounding.
                    .max(1e3 * mls_core::jet::SD_FLOOR / w.radius);
                let sd_rounding = (1e3 * f64::EPSILON * w.condition / SD_THRESHOLD).max(1.0);
                tally.record(Q::JetError, sd / sd_scale / sd_rounding, seed);
                let same = j.fit.degree == w.degree && j.fit.radius == w.radius;
                tally.record(Q::JetChoice, if same { 0.0 } else { 1.0 }, seed);
                tally.evals += 1;
            }
            // Both find the point degenerate: nothing to compare.
            (Err(_), None) => tally.skipped += 1,
            // One side failed where the other did not: as wrong as a different number.
            _ => tally.record(Q::JetChoice, 1.0, seed),
        }
    }
}
