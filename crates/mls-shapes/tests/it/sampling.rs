//! Sampler counts, spacing and reproducibility; noise statistics.

use std::f64::consts::{PI, TAU};

use approx::assert_relative_eq;
use mls_shapes::{
    Cylinder, ParametricSurface, Point, Sphere, Torus, Vector, add_position_noise,
    fibonacci_sphere, grid, normals, perturb_normals, points, random, surface_points,
};

use crate::seeds;

#[test]
fn grid_counts_order_and_spacing() {
    let cylinder = Cylinder::new(1.0, 2.0);
    let g = grid(&cylinder, 8, 5);
    assert_eq!(g.len(), 40);
    for (k, s) in g.iter().enumerate() {
        assert_eq!(s.ij, [k / 5, k % 5]);
    }
    // Closed parameter: both ends present. Periodic parameter: the seam is not duplicated.
    assert_eq!((g[0].uv[1], g[4].uv[1]), (-1.0, 1.0));
    assert_eq!(g[0].uv[0], 0.0);
    assert_relative_eq!(g[35].uv[0], TAU * 7.0 / 8.0);

    let torus = Torus::new(1.0, 0.25);
    let pts: Vec<Point> = grid(&torus, 12, 6)
        .iter()
        .map(|s| s.surface.point)
        .collect();
    assert_eq!(pts.len(), 72);
    let min_gap = pts
        .iter()
        .enumerate()
        .flat_map(|(i, p)| pts[i + 1..].iter().map(move |q| (p - q).norm()))
        .fold(f64::INFINITY, f64::min);
    assert!(min_gap > 0.1, "duplicated seam point: gap {min_gap}");

    // Degenerate ends: no sample on a pole, symmetric about the equator.
    let sphere = Sphere::centered(1.0);
    let g = grid(&sphere, 4, 3);
    assert_relative_eq!(g[0].uv[0], PI / 8.0);
    assert_relative_eq!(g[11].uv[0], 7.0 * PI / 8.0);
}

#[test]
fn random_is_reproducible_and_in_domain() {
    let torus = Torus::new(1.0, 0.25);
    let a = random(&torus, 500, seeds::PARAMS);
    let b = random(&torus, 500, seeds::PARAMS);
    let c = random(&torus, 500, seeds::PARAMS + 1);
    assert_eq!(a.len(), 500);
    assert_eq!(a, b);
    assert_ne!(a, c);
    let [du, dv] = torus.domain();
    for (k, s) in a.iter().enumerate() {
        assert_eq!(s.ij, [k, 0]);
        assert!(du.start < s.uv[0] && s.uv[0] < du.end && dv.start < s.uv[1] && s.uv[1] < dv.end);
    }
    assert_eq!(surface_points(&a).len(), 500);
}

#[test]
fn fibonacci_sphere_is_near_uniform() {
    let (n, radius) = (800, 2.0);
    let pts = fibonacci_sphere(n, radius);
    assert_eq!(pts.len(), n);
    assert_eq!(pts, fibonacci_sphere(n, radius));
    let spacing = (4.0 * PI * radius * radius / n as f64).sqrt();
    let mut centroid = Vector::zeros();
    for (i, p) in pts.iter().enumerate() {
        crate::assert_frame(p, 1e-12, "fibonacci");
        assert_relative_eq!(p.point.coords.norm(), radius, epsilon = 1e-12);
        assert!((p.normal - p.point.coords / radius).norm() < 1e-12);
        assert_relative_eq!(p.k1, 0.5, epsilon = 1e-15);
        let nearest = pts
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, q)| (q.point - p.point).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest > 0.5 * spacing && nearest < 1.5 * spacing,
            "point {i}: nearest {nearest}, spacing {spacing}"
        );
        centroid += p.point.coords / n as f64;
    }
    assert!(centroid.norm() < 1e-2 * radius, "centroid {centroid}");
}

#[test]
fn array_helpers() {
    let pts = fibonacci_sphere(10, 1.0);
    let (p, n) = (points(&pts), normals(&pts));
    assert_eq!((p.len(), n.len()), (10, 10));
    assert_eq!(p[3], [pts[3].point.x, pts[3].point.y, pts[3].point.z]);
    assert_eq!(n[7], [pts[7].normal.x, pts[7].normal.y, pts[7].normal.z]);
}

#[test]
fn position_noise_statistics() {
    let clean = vec![[1.0, -2.0, 3.0]; 20_000];
    let sigma = 0.05;
    let noisy = add_position_noise(&clean, sigma, seeds::POSITION_NOISE);
    assert_eq!(
        noisy,
        add_position_noise(&clean, sigma, seeds::POSITION_NOISE)
    );
    assert_ne!(
        noisy,
        add_position_noise(&clean, sigma, seeds::POSITION_NOISE + 1)
    );
    for axis in 0..3 {
        let d: Vec<f64> = noisy
            .iter()
            .zip(&clean)
            .map(|(a, b)| a[axis] - b[axis])
            .collect();
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        let std = (d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / d.len() as f64).sqrt();
        assert!(
            mean.abs() < 4.0 * sigma / (d.len() as f64).sqrt(),
            "axis {axis}: mean {mean}"
        );
        assert_relative_eq!(std, sigma, max_relative = 0.03);
    }
    // Works on nalgebra points too, and sigma = 0 is the identity.
    let pts: Vec<Point> = fibonacci_sphere(5, 1.0).iter().map(|p| p.point).collect();
    assert_eq!(add_position_noise(&pts, 0.0, seeds::POSITION_NOISE), pts);
}

#[test]
fn normal_perturbation_angles() {
    let base: Vec<Vector> = fibonacci_sphere(5_000, 1.0)
        .iter()
        .map(|p| p.normal)
        .collect();
    let max_angle = 0.2;
    let perturbed = perturb_normals(&base, max_angle, seeds::NORMAL_NOISE);
    assert_eq!(
        perturbed,
        perturb_normals(&base, max_angle, seeds::NORMAL_NOISE)
    );
    let mut largest: f64 = 0.0;
    let mut axis_sum = Vector::zeros();
    for (n, m) in base.iter().zip(&perturbed) {
        assert_relative_eq!(m.norm(), 1.0, epsilon = 1e-14);
        let angle = n.cross(m).norm().atan2(n.dot(m));
        assert!(angle <= max_angle + 1e-12, "angle {angle}");
        largest = largest.max(angle);
        // Rotated about the normal's frame: the deviation direction should average out.
        axis_sum += (m - n) / base.len() as f64;
    }
    assert!(largest > 0.95 * max_angle, "largest angle {largest}");
    assert!(axis_sum.norm() < 0.01, "biased deviation {axis_sum}");
    // Zero vectors pass through untouched, lengths are preserved.
    let odd = perturb_normals(
        &[[0.0, 0.0, 0.0], [0.0, 0.0, 3.0]],
        0.5,
        seeds::NORMAL_NOISE,
    );
    assert_eq!(odd[0], [0.0, 0.0, 0.0]);
    assert_relative_eq!(Vector::from(odd[1]).norm(), 3.0, epsilon = 1e-14);
}
