//! The adaptive scale on the paper's torus (R = 1, r = 0.2, 500 × 100 grid), clean and noisy,
//! against the exact curvature: the targets of issue 4, on a subsample of the points.

use mls_core::{
    AdaptiveConfig, Location, MlsConfig, MlsSurface, Parallelism, Point, Vector,
    adaptive_curvature, correct_shrinkage,
};
use mls_shapes::Torus;

struct Cloud {
    points: Vec<Point>,
    normals: Vec<Vector>,
    /// Indices of the evaluated points and their exact (k1, k2).
    queries: Vec<(usize, f64, f64)>,
}

/// Grid spacing along the tube, 2π r / 100.
const SPACING: f64 = 2.0 * std::f64::consts::PI * 0.2 / 100.0;

fn torus(sigma: f64) -> Cloud {
    let grid = mls_shapes::grid(
        &Torus {
            major: 1.0,
            minor: 0.2,
        },
        500,
        100,
    );
    let clean: Vec<Point> = grid.iter().map(|s| s.surface.point).collect();
    Cloud {
        points: mls_shapes::add_position_noise(&clean, sigma, 11),
        normals: grid.iter().map(|s| s.surface.normal).collect(),
        queries: (0..grid.len())
            .step_by(37)
            .map(|i| (i, grid[i].surface.k1, grid[i].surface.k2))
            .collect(),
    }
}

fn mean_std(e: &[f64]) -> (f64, f64) {
    let n = e.len() as f64;
    let m = e.iter().sum::<f64>() / n;
    (
        m,
        (e.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt(),
    )
}

/// k1 and k2 errors as (mean, std) pairs.
fn errors(cloud: &Cloud, k: &[(f64, f64)]) -> [(f64, f64); 2] {
    assert_eq!(k.len(), cloud.queries.len());
    let e1: Vec<f64> = k
        .iter()
        .zip(&cloud.queries)
        .map(|(k, q)| k.0 - q.1)
        .collect();
    let e2: Vec<f64> = k
        .iter()
        .zip(&cloud.queries)
        .map(|(k, q)| k.1 - q.2)
        .collect();
    [mean_std(&e1), mean_std(&e2)]
}

fn adaptive(cloud: &Cloud, at: Location) -> [(f64, f64); 2] {
    let queries: Vec<Point> = cloud.queries.iter().map(|q| cloud.points[q.0]).collect();
    let config = AdaptiveConfig::new(2.0 * SPACING);
    let results = adaptive_curvature(
        &cloud.points,
        &cloud.normals,
        &queries,
        at,
        &config,
        Parallelism::Rayon,
    )
    .unwrap();
    let k: Vec<(f64, f64)> = results
        .iter()
        .map(|r| {
            let p = r.as_ref().expect("every torus point has a curvature");
            assert!(p.h >= config.h_min && p.h <= config.scale(config.scales - 1));
            (p.curvature.k1, p.curvature.k2)
        })
        .collect();
    errors(cloud, &k)
}

#[test]
fn clean_torus_projected_meets_the_targets() {
    // Fixed h at 2 spacings: k1 +0.019 ± 9e-4 here (shrinkage). Targets: |mean| ≤ 1e-4 and
    // std < 4e-4 for both.
    let [(m1, s1), (m2, s2)] = adaptive(&torus(0.0), Location::Projected);
    assert!(m1.abs() <= 1e-4 && s1 < 4e-4, "k1 error {m1:e} ± {s1:e}");
    assert!(m2.abs() <= 1e-4 && s2 < 4e-4, "k2 error {m2:e} ± {s2:e}");
}

#[test]
fn noisy_torus_meets_the_target() {
    // σ = 1e-3 (0.08 spacings). Fixed h = 2 spacings scatters k1 by 0.57; target std ≤ 0.1.
    let cloud = torus(1e-3);
    for at in [Location::Input, Location::Projected] {
        let [(m1, s1), (_, s2)] = adaptive(&cloud, at);
        assert!(
            m1.abs() < 0.02 && s1 <= 0.1,
            "{at:?}: k1 error {m1:e} ± {s1:e}"
        );
        assert!(s2 <= 0.1, "{at:?}: k2 error std {s2:e}");
    }
}

#[test]
fn shrinkage_correction_removes_the_projected_bias() {
    let cloud = torus(0.0);
    let h = 2.0 * SPACING;
    let surface = MlsSurface::new(&cloud.points, &cloud.normals, MlsConfig::new(h)).unwrap();
    let queries: Vec<Point> = cloud.queries.iter().map(|q| cloud.points[q.0]).collect();
    let projected = surface.project_points(&queries, Parallelism::Rayon);
    let raw: Vec<(f64, f64)> = projected
        .iter()
        .map(|r| {
            let c = r.as_ref().unwrap().curvature;
            (c.k1, c.k2)
        })
        .collect();
    let corrected: Vec<(f64, f64)> = projected
        .iter()
        .map(|r| {
            let c = correct_shrinkage(&r.as_ref().unwrap().curvature, h);
            (c.k1, c.k2)
        })
        .collect();
    let [(raw1, _), _] = errors(&cloud, &raw);
    let [(m1, s1), (m2, _)] = errors(&cloud, &corrected);
    // The bias k²(k1 + k2)h²/4 ≈ 0.02 on k1; what remains is second order.
    assert!(raw1 > 0.015, "uncorrected k1 bias {raw1:e}");
    assert!(m1.abs() < 0.05 * raw1, "corrected k1 bias {m1:e} ± {s1:e}");
    assert!(m2.abs() < 2e-3, "corrected k2 bias {m2:e}");
}
