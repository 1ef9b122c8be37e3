//! Closest points: offsetting a sample along its normal and projecting back returns it.

use approx::assert_relative_eq;
use mls_shapes::{
    BSplineSurface, Cylinder, Ellipsoid, HeightField, HeightFieldConfig, ParametricSurface, Point,
    Sphere, SurfacePoint, Torus, closest_point_search, grid, random,
};

use crate::seeds;

/// Checks that `project(sample + t n) == sample` for each offset `t`.
fn check_round_trip<S, F>(name: &str, surface: &S, offsets: &[f64], tol: f64, project: F)
where
    S: ParametricSurface,
    F: Fn(&Point) -> SurfacePoint,
{
    for s in random(surface, 50, seeds::PARAMS) {
        let p = s.surface;
        for &t in offsets {
            let q = project(&(p.point + p.normal * t));
            let ctx = format!("{name} at {:?}, offset {t}", s.uv);
            assert!(
                (q.point - p.point).norm() < tol,
                "{ctx}: {} vs {}",
                q.point,
                p.point
            );
            assert!((q.normal - p.normal).norm() < tol, "{ctx}");
            assert!((q.k1 - p.k1).abs() < tol * (1.0 + p.k1.abs()), "{ctx}");
            assert!((q.k2 - p.k2).abs() < tol * (1.0 + p.k2.abs()), "{ctx}");
        }
    }
}

#[test]
fn closed_form_projections() {
    let sphere = Sphere::new(Point::new(-1.0, 0.5, 2.0), 1.5);
    check_round_trip(
        "sphere",
        &sphere,
        &[-1.0, -0.1, 0.0, 0.3, 5.0],
        1e-12,
        |q| sphere.closest_point(q),
    );
    let cylinder = Cylinder::new(0.8, 2.0);
    check_round_trip("cylinder", &cylinder, &[-0.5, 0.0, 0.2, 3.0], 1e-12, |q| {
        cylinder.closest_point(q)
    });
    let torus = Torus::new(2.0, 0.7);
    check_round_trip("torus", &torus, &[-0.6, -0.2, 0.0, 0.2, 1.2], 1e-12, |q| {
        torus.closest_point(q)
    });
}

#[test]
fn cylinder_projection_clamps_to_the_rim() {
    let cylinder = Cylinder::new(1.0, 2.0);
    let q = cylinder.closest_point(&Point::new(0.0, 3.0, 5.0));
    assert!((q.point - Point::new(0.0, 1.0, 1.0)).norm() < 1e-15);
}

#[test]
fn newton_projections() {
    let ellipsoid = Ellipsoid::new(1.0, 0.7, 0.5);
    check_round_trip("ellipsoid", &ellipsoid, &[-0.1, 0.0, 0.2], 1e-10, |q| {
        closest_point_search(&ellipsoid, q, 24).surface
    });
    let field = HeightField::random(&HeightFieldConfig::default(), seeds::HEIGHT_FIELD);
    check_round_trip("height field", &field, &[-0.05, 0.0, 0.05], 1e-10, |q| {
        closest_point_search(&field, q, 24).surface
    });
    let nurbs1 = BSplineSurface::nurbs1();
    check_round_trip("nurbs1", &nurbs1, &[-0.01, 0.0, 0.01], 1e-10, |q| {
        nurbs1.closest_point(q).surface
    });
    let nurbs2 = BSplineSurface::nurbs2();
    check_round_trip("nurbs2", &nurbs2, &[-0.5, 0.0, 0.5], 1e-9, |q| {
        nurbs2.closest_point(q).surface
    });
}

#[test]
fn newton_reports_convergence_and_recovers_parameters() {
    let nurbs1 = BSplineSurface::nurbs1();
    for s in grid(&nurbs1, 5, 5)
        .iter()
        .filter(|s| s.ij.iter().all(|&i| (1..4).contains(&i)))
    {
        let p = s.surface;
        let proj = nurbs1.closest_point(&(p.point + p.normal * 0.005));
        assert!(proj.converged, "{:?}", s.uv);
        assert_relative_eq!(proj.uv[0], s.uv[0], epsilon = 1e-10);
        assert_relative_eq!(proj.uv[1], s.uv[1], epsilon = 1e-10);
    }
}
