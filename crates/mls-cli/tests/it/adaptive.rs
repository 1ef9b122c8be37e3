//! `curvature --adaptive`: the per-point scale through the CLI, on the paper's noisy torus,
//! against the exact curvature and against the library.

use mls_core::{AdaptiveConfig, Location, Parallelism, Point, Vector, adaptive_curvature};
use mls_shapes::{Torus, add_position_noise, grid};

use crate::common::{Table, mlscurv, run_ok, write_xyz};

#[test]
fn adaptive_columns_match_the_library_and_beat_one_h_under_noise() {
    // R = 1, r = 0.2, 250 × 50 grid (spacing about 0.025), position noise σ = 2e-3 (0.08
    // spacings, as the paper's σ = 1e-3 on its 500 × 100 grid, at a quarter of the points).
    let samples = grid(&Torus::new(1.0, 0.2), 250, 50);
    let clean: Vec<[f64; 3]> = samples.iter().map(|s| s.surface.point.into()).collect();
    let p = add_position_noise(&clean, 2e-3, 3);
    let n: Vec<[f64; 3]> = samples.iter().map(|s| s.surface.normal.into()).collect();
    let truth: Vec<f64> = samples.iter().map(|s| s.surface.k1).collect();
    let h = 2.0 * 2.0 * std::f64::consts::PI * 0.2 / 50.0;

    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("torus.xyz");
    write_xyz(&input, &p, Some(&n));
    let run = |adaptive: bool| {
        let out = dir.path().join(format!("out-{adaptive}.csv"));
        let mut cmd = mlscurv();
        cmd.arg("curvature").arg(&input).arg("-o").arg(&out);
        cmd.args([
            "--method",
            "paper",
            "--normals",
            "file",
            "--h",
            &h.to_string(),
            "--quiet",
        ]);
        if adaptive {
            cmd.arg("--adaptive");
        }
        run_ok(&mut cmd);
        Table::parse_csv(&std::fs::read_to_string(&out).unwrap())
    };
    let spread = |t: &Table| {
        let k1 = t.col("k1");
        let e: Vec<f64> = t.rows.iter().zip(&truth).map(|(r, k)| r[k1] - k).collect();
        let m = e.iter().sum::<f64>() / e.len() as f64;
        (e.iter().map(|x| (x - m).powi(2)).sum::<f64>() / e.len() as f64).sqrt()
    };
    let fixed = run(false);
    let adaptive = run(true);
    assert!(fixed.header.iter().all(|c| c != "h" && c != "noise"));
    let (hc, noise) = (adaptive.col("h"), adaptive.col("noise"));

    // The same numbers as the library.
    let pts: Vec<Point> = p.iter().map(|&q| Point::from(q)).collect();
    let nrm: Vec<Vector> = n.iter().map(|&v| Vector::from(v)).collect();
    let config = AdaptiveConfig::new(h);
    let lib = adaptive_curvature(
        &pts,
        &nrm,
        &pts,
        Location::Input,
        &config,
        Parallelism::Rayon,
    )
    .unwrap();
    let k1 = adaptive.col("k1");
    for (i, (row, r)) in adaptive.rows.iter().zip(&lib).enumerate() {
        let r = r.as_ref().unwrap_or_else(|s| panic!("row {i}: {s:?}"));
        assert_eq!(row[hc], r.h, "row {i}: h");
        assert!((row[k1] - r.curvature.k1).abs() <= 1e-9 * r.curvature.k1.abs().max(1.0));
        assert!(
            (row[noise] - r.noise).abs() <= 1e-9 * r.noise.max(1e-12),
            "row {i}: noise"
        );
    }
    // The noise estimate finds σ, and the per-point scale cuts the scatter of k1 (0.31 at one
    // h of 2 spacings, 0.13 measured). The paper's setting and target are tested in mls-core.
    let mut est: Vec<f64> = adaptive.rows.iter().map(|r| r[noise]).collect();
    est.sort_by(f64::total_cmp);
    let median = est[est.len() / 2];
    assert!(
        (median / 2e-3 - 1.0).abs() < 0.1,
        "median noise estimate {median:e}"
    );
    let (sf, sa) = (spread(&fixed), spread(&adaptive));
    assert!(sa < 0.5 * sf, "k1 error σ: fixed {sf}, adaptive {sa}");
}
