//! Workspace-level end-to-end tests: files through mls-io into mls-core, checked against the
//! analytic truth or the independent AD witness. The CLI's own tests are in crates/mls-cli.

mod robustness;

use std::path::PathBuf;

use mls_core::normals::{NormalsConfig, estimate_normals};
use mls_core::{MlsConfig, MlsSurface, Parallelism, Point, Vector};
use mls_io::{Axis, Column, PlyFormat};

fn bunny() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/bunny-stanford.ply")
}

/// On a real scan with estimated normals, the closed form agrees with hyper-dual AD.
#[test]
fn closed_form_matches_witness_on_the_real_bunny() {
    let cloud = mls_io::read_point_cloud(&bunny()).unwrap();
    let points: Vec<Point> = cloud.points.iter().map(|p| Point::from(*p)).collect();
    let est = estimate_normals(&points, &NormalsConfig::default(), Parallelism::Rayon).unwrap();
    let h = est.h.unwrap();
    let normals: Vec<Vector> = est.normals().into_iter().map(|n| n.unwrap()).collect();
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
    let mut ev = surface.evaluator();
    let a = 1.0 / (h * h);
    let mut worst: f64 = 0.0;
    for p in points.iter().step_by(359) {
        let closed = ev.curvature_at(p).unwrap();
        let support = ev.support_of(p);
        let w = mls_ad::witness(&p.coords, &support, a);
        let dg = (closed.implicit.gradient - w.gradient).norm() / w.gradient.norm();
        let dh = (closed.implicit.hessian - w.hessian).norm() / w.hessian.norm();
        let wc = mls_ad::witness_curvature(&w.gradient, &w.hessian);
        let kappa = w.hessian.norm() / w.gradient.norm();
        let dk = (closed.curvature.k1 - wc.k1)
            .abs()
            .max((closed.curvature.k2 - wc.k2).abs())
            / kappa;
        worst = worst.max(dg).max(dh).max(dk);
    }
    assert!(worst < 1e-10, "worst relative difference {worst:e}");
}

/// A sphere written to PLY, read back, normals estimated and oriented: curvature 1/R.
#[test]
fn sphere_file_round_trip_gives_one_over_r() {
    let r = 0.25;
    let samples = mls_shapes::fibonacci_sphere(20_000, r);
    let pts = mls_shapes::points(&samples);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.ply");
    let cols = [
        Column::component("x", &pts, Axis::X),
        Column::component("y", &pts, Axis::Y),
        Column::component("z", &pts, Axis::Z),
    ];
    mls_io::write_point_cloud(&path, &cols, PlyFormat::BinaryLittleEndian).unwrap();
    let cloud = mls_io::read_point_cloud(&path).unwrap();
    assert_eq!(cloud.points, pts);
    let points: Vec<Point> = cloud.points.iter().map(|p| Point::from(*p)).collect();
    let est = estimate_normals(&points, &NormalsConfig::default(), Parallelism::Rayon).unwrap();
    let normals: Vec<Vector> = est.normals().into_iter().map(|n| n.unwrap()).collect();
    for (p, n) in points.iter().zip(&normals) {
        assert!(n.dot(&p.coords) > 0.0, "inward normal at {p:?}");
    }
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(est.h.unwrap())).unwrap();
    // Away from the Fibonacci lattice's irregular poles. Estimated normals are off by about
    // (spacing·κ)² ≈ 1e-4 rad; the curvature error follows (measured worst 2e-4 relative).
    let queries: Vec<Point> = points
        .iter()
        .step_by(17)
        .filter(|p| p.z.abs() < 0.9 * r)
        .copied()
        .collect();
    for res in surface.curvature_at_points(&queries, Parallelism::Rayon) {
        let c = res.unwrap().curvature;
        assert!(
            (c.k1 * r - 1.0).abs() < 1e-3 && (c.k2 * r - 1.0).abs() < 1e-3,
            "k1 {} k2 {}",
            c.k1,
            c.k2
        );
    }
}
