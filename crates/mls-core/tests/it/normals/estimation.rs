//! Estimation accuracy: radial normals on a sphere, the normalised centroid (erratum
//! E-normal), equivariance under rigid motions.

use std::f64::consts::PI;

use mls_core::normals::{
    DEFAULT_H_FACTOR, NeighbourGraph, NormalsConfig, estimate_normals, estimate_unoriented,
    normal_from_neighbourhood,
};
use mls_core::{Matrix, Point, Vector};
use nalgebra::{Rotation3, SymmetricEigen};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{
    JITTER_SEED, PAR, SEQ, angle_deg, fibonacci_sphere, line_angle_deg, square_grid, unwrap_normals,
};

#[test]
fn sphere_normals_are_radial_within_one_degree_and_outward() {
    let centre = Point::new(0.3, -0.2, 1.0);
    let points = fibonacci_sphere(4000, centre, 1.5);
    let out = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
    assert_eq!(out.failed(), 0);
    let normals = unwrap_normals(&out.estimates);
    let worst = points
        .iter()
        .zip(&normals)
        .map(|(p, n)| angle_deg(n, &(p - centre)))
        .fold(0.0, f64::max);
    assert!(worst < 1.0, "worst angle to the radial direction {worst}°");
    assert_eq!(out.report.components, 1);
    assert_eq!(out.report.consistency, Some(1.0));
    let h = out.h.unwrap();
    let expected = DEFAULT_H_FACTOR * (4.0 * PI * 1.5 * 1.5 / 4000.0).sqrt();
    assert!(
        (h / expected - 1.0).abs() < 0.1,
        "h = {h}, expected ≈ {expected}"
    );
}

// ---------------------------------------------------------------------------------------------
// Erratum E-normal: the centroid must be normalised.

/// Sec. 4.1 exactly as printed: `c = Σ θ_i q_i`, without dividing by `Σ θ_i`.
fn paper_unnormalised_normal(centre: &Point, neighbourhood: &[Point], h: f64) -> Vector {
    let theta = |q: &Point| (-(q - centre).norm_squared() / (h * h)).exp();
    let c: Vector = neighbourhood.iter().map(|q| q.coords * theta(q)).sum();
    let cov: Matrix = neighbourhood
        .iter()
        .map(|q| {
            let r = q.coords - c;
            r * r.transpose() * theta(q)
        })
        .sum();
    let eigen = SymmetricEigen::new(cov);
    eigen
        .eigenvectors
        .column(eigen.eigenvalues.imin())
        .into_owned()
}

#[test]
fn normalised_centroid_is_origin_independent_and_the_printed_one_is_not() {
    let mut rng = ChaCha8Rng::seed_from_u64(JITTER_SEED);
    let pitch = 0.1;
    let points: Vec<Point> = square_grid(30, 30, pitch)
        .into_iter()
        .map(|p| {
            let jitter = Vector::new(
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                0.0,
            );
            p + jitter * pitch
        })
        .collect();
    let k = 16;
    let h = 2.0 * pitch;
    let graph = NeighbourGraph::build(&points, k, SEQ).unwrap();
    let neighbourhood = |cloud: &[Point], i: usize| -> Vec<Point> {
        std::iter::once(i as u32)
            .chain(graph.neighbours(i).iter().copied())
            .map(|j| cloud[j as usize])
            .collect()
    };
    let ours_at_origin = estimate_unoriented(&points, &graph, h, 1e-6, SEQ).unwrap();
    for t in [Vector::new(0.5, -0.3, 1.0), Vector::new(1e6, -2e6, 3e6)] {
        let moved: Vec<Point> = points.iter().map(|p| p + t).collect();
        let ours_moved = estimate_unoriented(&moved, &graph, h, 1e-6, SEQ).unwrap();
        let mut paper_worst: f64 = 0.0;
        for i in 0..points.len() {
            let (a, b) = (
                ours_at_origin[i].unwrap().normal.into_inner(),
                ours_moved[i].unwrap().normal.into_inner(),
            );
            assert!(
                line_angle_deg(&a, &Vector::z()) < 1e-6,
                "ours at origin, point {i}"
            );
            assert!(
                line_angle_deg(&b, &Vector::z()) < 1e-6,
                "ours moved by {t}, point {i}"
            );
            let paper = paper_unnormalised_normal(&moved[i], &neighbourhood(&moved, i), h);
            paper_worst = paper_worst.max(line_angle_deg(&paper, &Vector::z()));
        }
        assert!(
            paper_worst > 10.0,
            "the printed centroid should go wrong under translation {t}: worst {paper_worst}°"
        );
    }
    // The public single-neighbourhood entry point agrees.
    let nb = neighbourhood(&points, 0);
    let single = normal_from_neighbourhood(&points[0], &nb, h, 1e-6).unwrap();
    assert_eq!(single, ours_at_origin[0].unwrap());
}

#[test]
fn normals_are_rotation_and_translation_equivariant() {
    let points = fibonacci_sphere(1500, Point::origin(), 1.0);
    let rot = Rotation3::from_euler_angles(0.3, -1.1, 2.0);
    let t = Vector::new(1e5, -3.0, 7.0);
    let moved: Vec<Point> = points.iter().map(|p| rot * p + t).collect();
    let a = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
    let b = estimate_normals(&moved, &NormalsConfig::default(), PAR).unwrap();
    for (na, nb) in unwrap_normals(&a.estimates)
        .iter()
        .zip(unwrap_normals(&b.estimates))
    {
        assert!(angle_deg(&(rot * na), &nb) < 1e-6);
    }
}

/// Confidence is `1 − 3σ`, clamped to `[0, 1]`: 1 for a flat neighbourhood, 0 for an
/// isotropic one (σ = 1/3), and the orientation's seed prefers the larger.
#[test]
fn confidence_is_one_minus_three_times_the_variation() {
    use mls_core::UnitNormal;
    use mls_core::normals::NormalEstimate;
    let e = |variation: f64| NormalEstimate {
        normal: UnitNormal::new(Vector::z()).unwrap(),
        variation,
    };
    assert_eq!(e(0.0).confidence(), 1.0);
    assert_eq!(e(0.1).confidence(), 1.0 - 3.0 * 0.1);
    assert_eq!(e(0.25).confidence(), 0.25);
    assert_eq!(e(1.0 / 3.0).confidence(), 0.0);
    assert_eq!(e(0.5).confidence(), 0.0);
}

/// The corners of a box `(±a, ±b, ±c)` about the centre are equidistant from it, so equally
/// weighted: the covariance is `diag(a², b², c²)` up to a factor, the normal is the z axis, the
/// variation is `c²/(a² + b² + c²)`, and the neighbourhood is refused as degenerate exactly
/// when `(b² − c²)/a² ≤ tolerance`.
#[test]
fn the_degeneracy_test_and_the_variation_on_a_box() {
    let centre = Point::new(3.0, -2.0, 1.0);
    let (a, c) = (1.0f64, 0.3f64);
    let tolerance = 0.25;
    for (b, accepted) in [(0.6f64, true), (0.55, false)] {
        let mut box_corners = vec![centre];
        for i in 0..8 {
            let s = |bit: usize| if i & bit == 0 { 1.0 } else { -1.0 };
            box_corners.push(centre + Vector::new(s(1) * a, s(2) * b, s(4) * c));
        }
        let r = normal_from_neighbourhood(&centre, &box_corners, 1.0, tolerance);
        let ratio = (b * b - c * c) / (a * a);
        assert_eq!(r.is_ok(), accepted, "b = {b}: (b² − c²)/a² = {ratio}");
        if let Ok(e) = r {
            assert!(e.normal.as_vector().cross(&Vector::z()).norm() < 1e-12);
            let variation = c * c / (a * a + b * b + c * c);
            assert!((e.variation - variation).abs() < 1e-12, "{}", e.variation);
        }
    }
}
