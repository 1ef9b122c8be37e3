//! The jet estimator on irregular samples and noise: convergence with density, calibration of
//! the predicted error, both against the analytic torus; its single fits in `fit`.

use mls_core::{JetConfig, MlsConfig, MlsSurface, NormalData, Parallelism, Point, Vector};
use mls_shapes::{SurfacePoint, Torus};

mod fit;

const SEED: u64 = 11;

/// Every `step`-th sample as a query; (k1 error, k2 error, predicted k1 error) per query.
fn errors(
    samples: &[SurfacePoint],
    points: &[Point],
    h: f64,
    step: usize,
    data: NormalData,
    quadratic: bool,
) -> Vec<[f64; 3]> {
    let normals: Vec<Vector> = samples.iter().map(|s| s.normal).collect();
    let surface = MlsSurface::new(points, &normals, MlsConfig::new(h)).unwrap();
    let queries: Vec<Point> = points.iter().step_by(step).copied().collect();
    let config = JetConfig {
        normals: data,
        quadratic,
        ..JetConfig::default()
    };
    let torus = Torus::new(6.0, 2.0);
    surface
        .jet_at_points(&queries, &config, Parallelism::Rayon)
        .iter()
        .zip(&queries)
        .zip(samples.iter().step_by(step))
        .map(|((r, q), s)| {
            let r = r.as_ref().expect("every torus point has a jet");
            // Clean clouds: the sample's own truth; noisy: the nearest point's.
            let truth = if *q == s.point {
                *s
            } else {
                torus.closest_point(q)
            };
            let [p1, _] = r.predicted_error();
            [r.curvature.k1 - truth.k1, r.curvature.k2 - truth.k2, p1]
        })
        .collect()
}

fn nrms(e: &[[f64; 3]], i: usize, max_k: f64) -> f64 {
    (e.iter().map(|e| e[i] * e[i]).sum::<f64>() / e.len() as f64).sqrt() / max_k
}

/// h as the CLI chooses it: 2 × the median local spacing.
fn cli_h(points: &[Point]) -> f64 {
    use mls_core::normals::{
        DEFAULT_H_FACTOR, DEFAULT_SPACING_NEIGHBOURS, spacing_statistics, suggest_h,
    };
    let stats = spacing_statistics(points, DEFAULT_SPACING_NEIGHBOURS, Parallelism::Rayon).unwrap();
    suggest_h(&stats, DEFAULT_H_FACTOR).unwrap()
}

/// On area-uniform random samples (where the MLS surface's curvature does not converge) the
/// jet's error falls with density: measured 3.5e-4 → 4.3e-5 for k1 (8×) from 10k to 40k.
#[test]
fn error_falls_with_density_on_random_samples() {
    let torus = Torus::new(6.0, 2.0);
    let mut k1 = Vec::new();
    for n in [10_000, 40_000] {
        let samples = mls_shapes::surface_points(&mls_shapes::random_area_uniform(&torus, n, SEED));
        let points: Vec<Point> = samples.iter().map(|s| s.point).collect();
        let e = errors(
            &samples,
            &points,
            cli_h(&points),
            n / 2000,
            NormalData::Slopes,
            true,
        );
        k1.push(nrms(&e, 0, 0.5));
        eprintln!(
            "random torus, {n} points: k1 nRMS {:.2e}, k2 nRMS {:.2e}",
            nrms(&e, 0, 0.5),
            nrms(&e, 1, 0.5)
        );
    }
    assert!(k1[0] < 1e-3, "10k: k1 nRMS {:.2e}", k1[0]);
    assert!(
        k1[0] / k1[1] >= 4.0,
        "10k → 40k: {:.2e} → {:.2e}",
        k1[0],
        k1[1]
    );
}

/// The predicted error is calibrated: in every decile of the prediction the observed RMS error
/// is within a factor 2 of the predicted one, on a noisy cloud and on a clean random one.
#[test]
fn predicted_error_is_calibrated_by_decile() {
    let torus = Torus::new(6.0, 2.0);
    let n = 20_000;
    let samples = mls_shapes::surface_points(&mls_shapes::random_area_uniform(&torus, n, SEED));
    let clean: Vec<Point> = samples.iter().map(|s| s.point).collect();
    let h = cli_h(&clean);
    // σ = 5 % of the spacing.
    let noisy: Vec<Point> = mls_shapes::add_position_noise(&clean, 0.025 * h, SEED);
    for (name, points) in [("clean", &clean), ("noisy", &noisy)] {
        let e = errors(&samples, points, h, 4, NormalData::Slopes, true);
        assert_calibrated(name, e);
    }
}

/// Without file normals (heights only) on a noisy cloud, the thin first scale's own noise
/// estimate is unreliable; it must not stop the climb (`jet::trusted`). With the old rule the
/// top decile's observed error was 2.2× its prediction here (1.2 now). The degree-4 ladder
/// alone: with the degree-2 candidates (the default) this cloud's prediction is 1.6–2.1× the
/// observed error in every decile (observed / predicted 0.48–0.64; issue 37's 0.5–2 not met,
/// `docs/accuracy-noisy.md`), since the bias predicted from the largest support's high terms
/// carries what degree 6 aliases into them.
#[test]
fn heights_only_noisy_cloud_is_calibrated() {
    let torus = Torus::new(6.0, 2.0);
    let samples =
        mls_shapes::surface_points(&mls_shapes::random_area_uniform(&torus, 20_000, SEED));
    let clean: Vec<Point> = samples.iter().map(|s| s.point).collect();
    let h = cli_h(&clean);
    let noisy: Vec<Point> = mls_shapes::add_position_noise(&clean, 0.05 * h, SEED);
    assert_calibrated(
        "noisy, heights only",
        errors(&samples, &noisy, h, 4, NormalData::Ignore, false),
    );
}

/// In every decile of the prediction, observed RMS error / predicted within [0.5, 2].
fn assert_calibrated(name: &str, mut e: Vec<[f64; 3]>) {
    {
        e.sort_unstable_by(|a, b| a[2].total_cmp(&b[2]));
        for d in 0..10 {
            let part = &e[d * e.len() / 10..(d + 1) * e.len() / 10];
            let observed =
                (part.iter().map(|e| e[0] * e[0]).sum::<f64>() / part.len() as f64).sqrt();
            let predicted =
                (part.iter().map(|e| e[2] * e[2]).sum::<f64>() / part.len() as f64).sqrt();
            let ratio = observed / predicted;
            eprintln!("{name}: decile {d}: observed/predicted {ratio:.2}");
            assert!(
                (0.5..=2.0).contains(&ratio),
                "{name}, decile {d}: observed/predicted {ratio:.2}"
            );
        }
    }
}

/// k1 nRMS of the heights-only jet at every 8th point of `points` (truth at the torus's nearest
/// point), skipping `skip`; and how many of the queries came back as [`PointStatus::Outlier`].
fn heights_only(
    points: &[Point],
    normals: &[Vector],
    h: f64,
    config: &JetConfig,
    skip: &[bool],
) -> (f64, Vec<usize>) {
    let torus = Torus::new(6.0, 2.0);
    let surface = MlsSurface::new(points, normals, MlsConfig::new(h)).unwrap();
    let queries: Vec<usize> = (0..points.len()).step_by(8).collect();
    let at: Vec<Point> = queries.iter().map(|&i| points[i]).collect();
    let results = surface.jet_at_points(&at, config, Parallelism::Rayon);
    let (mut sum, mut count, mut outliers) = (0.0, 0usize, Vec::new());
    for (&i, r) in queries.iter().zip(&results) {
        match r {
            Err(mls_core::PointStatus::Outlier) => outliers.push(i),
            _ if skip[i] => {}
            Ok(p) => {
                let e = p.curvature.k1 - torus.closest_point(&points[i]).k1;
                sum += e * e;
                count += 1;
            }
            Err(s) => panic!("point {i}: {s}"),
        }
    }
    ((sum / count as f64).sqrt() / 0.5, outliers)
}

/// The 20k random torus, clean and with position noise of 0.2 spacing (0.1 h), with normals
/// perturbed by 0.2 rad (the frame only: noisy, as estimated ones would be), and h.
fn noisy_torus() -> (Vec<Point>, Vec<Point>, Vec<Vector>, f64) {
    let torus = Torus::new(6.0, 2.0);
    let samples =
        mls_shapes::surface_points(&mls_shapes::random_area_uniform(&torus, 20_000, SEED));
    let clean: Vec<Point> = samples.iter().map(|s| s.point).collect();
    let h = cli_h(&clean);
    let noisy: Vec<Point> = mls_shapes::add_position_noise(&clean, 0.1 * h, SEED);
    let normals = mls_shapes::perturb_normals(
        &samples.iter().map(|s| s.normal).collect::<Vec<_>>(),
        0.2,
        SEED,
    );
    (clean, noisy, normals, h)
}

/// Heights only (no file normals) under position noise of 0.2 spacing: the degree-2
/// candidates take the k1 error well below the degree-4 ladder's (measured on this cloud:
/// 2.4e-2 against 2.0e-1; `docs/accuracy-noisy.md` for the peers).
#[test]
fn degree_two_candidates_win_under_noise_without_normals() {
    let (_, noisy, normals, h) = noisy_torus();
    let config = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    let none = vec![false; noisy.len()];
    let (with, _) = heights_only(&noisy, &normals, h, &config, &none);
    let without = JetConfig {
        quadratic: false,
        ..config
    };
    let (ladder, _) = heights_only(&noisy, &normals, h, &without, &none);
    eprintln!("k1 nRMS: with degree 2 {with:.2e}, degree 4 only {ladder:.2e}");
    assert!(with < 0.4 * ladder, "{with:.2e} against {ladder:.2e}");
    assert!(with < 5e-2, "{with:.2e}");
}

/// 1 % of the queries moved 5 spacings along their normal: they get the outlier status, no
/// other point does, and the others' curvature is as good as without them (measured: k1 nRMS
/// 1.44e-2 both; all 25 flagged).
#[test]
fn outliers_are_flagged_and_do_not_spoil_their_neighbours() {
    let torus = Torus::new(6.0, 2.0);
    let samples =
        mls_shapes::surface_points(&mls_shapes::random_area_uniform(&torus, 20_000, SEED));
    let clean: Vec<Point> = samples.iter().map(|s| s.point).collect();
    let h = cli_h(&clean);
    let noisy: Vec<Point> = mls_shapes::add_position_noise(&clean, 0.025 * h, SEED);
    let normals: Vec<Vector> = samples.iter().map(|s| s.normal).collect();
    let config = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    // Every 100th query (every 800th point), moved 2.5 h = 5 spacings off the surface.
    let mut moved = noisy.clone();
    let mut stray = vec![false; moved.len()];
    for i in (0..moved.len()).step_by(800) {
        moved[i] += normals[i] * (2.5 * h);
        stray[i] = true;
    }
    let (base, _) = heights_only(&noisy, &normals, h, &config, &stray);
    let (spoiled, flagged) = heights_only(&moved, &normals, h, &config, &stray);
    let strays = stray.iter().filter(|&&s| s).count();
    eprintln!(
        "k1 nRMS {base:.2e} without, {spoiled:.2e} with the strays; {} of {strays} flagged",
        flagged.len()
    );
    assert!(flagged.iter().all(|&i| stray[i]), "an inlier was flagged");
    assert_eq!(flagged.len(), strays);
    assert!(spoiled < 1.2 * base, "{spoiled:.2e} against {base:.2e}");
}

/// Shared supports (`mls_core::jet::anchors`): under noise of 0.2 spacing with heights only
/// (where 90 % of the queries choose degree 2 on 6h or more), blending the anchors' jets is
/// more accurate than each query fitting its own (measured on this cloud: k1 nRMS 1.94e-2
/// blended, 2.35e-2 own fits: the blend smooths a little more); on the clean torus, where the
/// degree-4 ladder resolves, no query is blended and every curvature is bitwise the unshared
/// one's.
#[test]
fn shared_supports_blend_under_noise_only() {
    let (clean, noisy, normals, h) = noisy_torus();
    let shared = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    let own = JetConfig {
        share: false,
        ..shared
    };
    let none = vec![false; noisy.len()];
    let (blended, _) = heights_only(&noisy, &normals, h, &shared, &none);
    let (fitted, _) = heights_only(&noisy, &normals, h, &own, &none);
    eprintln!("k1 nRMS: blended {blended:.2e}, own fits {fitted:.2e}");
    assert!(blended < fitted, "{blended:.2e} against {fitted:.2e}");

    let surface = MlsSurface::new(&clean, &normals, MlsConfig::new(h)).unwrap();
    let queries: Vec<Point> = clean.iter().step_by(4).copied().collect();
    let a = surface.jet_at_points(&queries, &shared, Parallelism::Rayon);
    let b = surface.jet_at_points(&queries, &own, Parallelism::Rayon);
    for (i, (a, b)) in a.iter().zip(&b).enumerate() {
        let (a, b) = (a.as_ref().unwrap(), b.as_ref().unwrap());
        assert_eq!(
            (a.curvature, a.sd, a.bias, a.fit),
            (b.curvature, b.sd, b.bias, b.fit),
            "query {i}"
        );
    }
}
