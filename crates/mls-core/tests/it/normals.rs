//! Normal estimation, spacing and orientation against analytic shapes and brute force.

use std::f64::consts::{PI, TAU};

use mls_core::normals::{
    DEFAULT_H_FACTOR, DEFAULT_SPACING_NEIGHBOURS, NeighbourGraph, NormalEstimate, NormalsConfig,
    NormalsError, Orientation, estimate_normals, estimate_unoriented, normal_from_neighbourhood,
    orient_normals, orient_normals_towards, orientation_consistency, spacing_statistics,
    square_grid_rms_distance, suggest_h,
};
use mls_core::{InputError, Matrix, Parallelism, Point, PointStatus, Vector};
use nalgebra::{Rotation3, SymmetricEigen};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Seed of the random sign flips applied before orientation.
const FLIP_SEED: u64 = 0x5EED_F11B;
/// Seed of the in-plane jitter of the plane samples.
const JITTER_SEED: u64 = 0x5EED_0717;
/// Seed of the random clouds compared with brute force.
const CLOUD_SEED: u64 = 0x5EED_C10D;

const SEQ: Parallelism = Parallelism::Sequential;
const PAR: Parallelism = Parallelism::Rayon;

// ---------------------------------------------------------------------------------------------
// Shapes.

/// `n` points on a sphere by the golden-angle spiral: nearly uniform, area `4πR²/n` each.
fn fibonacci_sphere(n: usize, centre: Point, radius: f64) -> Vec<Point> {
    let golden = PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            centre + Vector::new(r * phi.cos(), r * phi.sin(), z) * radius
        })
        .collect()
}

/// An `nx × ny` square grid of the given pitch in the plane z = 0, centred on the origin.
fn square_grid(nx: usize, ny: usize, pitch: f64) -> Vec<Point> {
    let (cx, cy) = ((nx - 1) as f64 / 2.0, (ny - 1) as f64 / 2.0);
    (0..nx)
        .flat_map(|i| {
            (0..ny).map(move |j| Point::new((i as f64 - cx) * pitch, (j as f64 - cy) * pitch, 0.0))
        })
        .collect()
}

/// A torus about the z axis with tube centre radius `big` and tube radius `small`, sampled on
/// a `nu × nv` parameter grid. Returns the points and their tube centres.
fn torus(nu: usize, nv: usize, big: f64, small: f64) -> (Vec<Point>, Vec<Point>) {
    (0..nu)
        .flat_map(|i| (0..nv).map(move |j| (i, j)))
        .map(|(i, j)| {
            let (u, v) = (TAU * i as f64 / nu as f64, TAU * j as f64 / nv as f64);
            let axis = Vector::new(u.cos(), u.sin(), 0.0);
            let centre = Point::from(axis * big);
            let p = centre + (axis * v.cos() + Vector::z() * v.sin()) * small;
            (p, centre)
        })
        .unzip()
}

/// Angle between two vectors in degrees; atan2 keeps small angles accurate, unlike acos.
fn angle_deg(a: &Vector, b: &Vector) -> f64 {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

/// Angle between the lines spanned by `a` and `b` (sign ignored), in degrees.
fn line_angle_deg(a: &Vector, b: &Vector) -> f64 {
    let d = angle_deg(a, b);
    d.min(180.0 - d)
}

fn unwrap_normals(est: &[Result<NormalEstimate, PointStatus>]) -> Vec<Vector> {
    est.iter()
        .enumerate()
        .map(|(i, e)| match e {
            Ok(e) => e.normal.into_inner(),
            Err(s) => panic!("normal {i} failed: {s}"),
        })
        .collect()
}

/// Flips about half of the normals, chosen by `seed`; returns how many were flipped.
fn flip_randomly(est: &mut [Result<NormalEstimate, PointStatus>], seed: u64) -> usize {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut count = 0;
    for e in est.iter_mut().flatten() {
        if rng.random_bool(0.5) {
            e.normal = -e.normal;
            count += 1;
        }
    }
    count
}

/// Configuration that leaves the signs as estimated.
fn unoriented(k: usize) -> NormalsConfig {
    NormalsConfig {
        k,
        orientation: Orientation::None,
        ..NormalsConfig::default()
    }
}

// ---------------------------------------------------------------------------------------------
// Accuracy and orientation on closed surfaces.

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

#[test]
fn orientation_recovers_outward_normals_from_random_flips() {
    let centre = Point::new(-2.0, 0.5, 0.0);
    let points = fibonacci_sphere(3000, centre, 0.8);
    let mut est = estimate_normals(&points, &unoriented(12), PAR)
        .unwrap()
        .estimates;
    flip_randomly(&mut est, FLIP_SEED);
    let graph = NeighbourGraph::build(&points, 12, PAR).unwrap();
    let inward = points
        .iter()
        .zip(&unwrap_normals(&est))
        .filter(|(p, n)| n.dot(&(*p - centre)) < 0.0)
        .count();
    assert!(
        inward > 1000,
        "the flips should leave many normals inward ({inward})"
    );
    let mut seq = est.clone();
    let report = orient_normals(&points, &graph, &mut est, Orientation::Outward, PAR).unwrap();
    let report_seq = orient_normals(&points, &graph, &mut seq, Orientation::Outward, SEQ).unwrap();
    assert_eq!(est, seq, "orientation must not depend on parallelism");
    assert_eq!(report, report_seq);
    assert_eq!(report.flipped, inward);
    assert_eq!(report.consistency, Some(1.0));
    for (p, n) in points.iter().zip(unwrap_normals(&est)) {
        assert!(n.dot(&(p - centre)) > 0.0, "inward normal at {p}");
    }
}

#[test]
fn torus_is_oriented_outward_with_full_consistency() {
    let (points, tube_centres) = torus(160, 48, 1.0, 0.3);
    let mut est = estimate_normals(&points, &unoriented(16), PAR)
        .unwrap()
        .estimates;
    flip_randomly(&mut est, FLIP_SEED);
    let graph = NeighbourGraph::build(&points, 16, PAR).unwrap();
    let report = orient_normals(&points, &graph, &mut est, Orientation::Outward, PAR).unwrap();
    assert_eq!(report.components, 1);
    assert_eq!(report.consistency, Some(1.0));
    let normals = unwrap_normals(&est);
    let mut worst: f64 = 0.0;
    for ((p, c), n) in points.iter().zip(&tube_centres).zip(&normals) {
        let radial = p - c;
        assert!(n.dot(&radial) > 0.0, "inward normal at {p}");
        worst = worst.max(angle_deg(n, &radial));
    }
    // The parameter grid is anisotropic on the inner side; the normals stay close anyway.
    assert!(worst < 3.0, "worst angle to the tube radial {worst}°");
}

#[test]
fn two_disjoint_spheres_are_two_outward_components() {
    let (c1, c2) = (Point::new(0.0, 0.0, 0.0), Point::new(4.0, 1.0, 0.0));
    let mut points = fibonacci_sphere(2000, c1, 1.0);
    let first = points.len();
    points.extend(fibonacci_sphere(1000, c2, 0.5));
    let out = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
    assert_eq!(out.report.components, 2);
    assert_eq!(out.report.consistency, Some(1.0));
    for (i, (p, n)) in points
        .iter()
        .zip(unwrap_normals(&out.estimates))
        .enumerate()
    {
        let c = if i < first { c1 } else { c2 };
        assert!(n.dot(&(p - c)) > 0.0, "inward normal at point {i}");
    }
}

#[test]
fn viewpoint_orients_a_plane_towards_the_viewer() {
    let points = square_grid(40, 40, 0.05);
    let graph = NeighbourGraph::build(&points, 16, PAR).unwrap();
    let base = estimate_normals(&points, &unoriented(16), PAR)
        .unwrap()
        .estimates;
    for (eye, sign) in [
        (Point::new(0.0, 0.0, 10.0), 1.0),
        (Point::new(0.3, -0.2, -10.0), -1.0),
    ] {
        let mut est = base.clone();
        flip_randomly(&mut est, FLIP_SEED);
        let report =
            orient_normals(&points, &graph, &mut est, Orientation::Viewpoint(eye), PAR).unwrap();
        assert_eq!(report.components, 1);
        for n in unwrap_normals(&est) {
            assert!(n.z * sign > 1.0 - 1e-12, "normal {n} seen from {eye}");
        }
    }
    // Through the convenience entry point as well.
    let config = NormalsConfig {
        orientation: Orientation::Viewpoint(Point::new(5.0, 5.0, -1.0)),
        ..NormalsConfig::default()
    };
    let out = estimate_normals(&points, &config, SEQ).unwrap();
    assert!(
        unwrap_normals(&out.estimates)
            .iter()
            .all(|n| n.z < -0.999_999)
    );
}

#[test]
fn per_point_viewpoints_orient_each_scan_towards_its_own_scanner() {
    // Two patches of the plane z = 0, ten apart: the first scanned from above, the second
    // from below. No single viewpoint gives both signs; one per point does.
    let first = square_grid(40, 40, 0.05);
    let second: Vec<Point> = first
        .iter()
        .map(|p| p + Vector::new(10.0, 0.0, 0.0))
        .collect();
    let points: Vec<Point> = first.iter().chain(&second).copied().collect();
    let (above, below) = (Point::new(0.3, 0.0, 10.0), Point::new(10.0, -0.2, -10.0));
    let viewpoints: Vec<Point> = (0..points.len())
        .map(|i| if i < first.len() { above } else { below })
        .collect();
    let graph = NeighbourGraph::build(&points, 16, PAR).unwrap();
    let mut est = estimate_normals(&points, &unoriented(16), PAR)
        .unwrap()
        .estimates;
    flip_randomly(&mut est, FLIP_SEED);
    let report = orient_normals_towards(&points, &graph, &mut est, &viewpoints, PAR).unwrap();
    assert_eq!(report.components, 2);
    let facing = report.facing.unwrap();
    assert_eq!(facing.facing, points.len());
    for (i, n) in unwrap_normals(&est).iter().enumerate() {
        let sign = if i < first.len() { 1.0 } else { -1.0 };
        assert!(n.z * sign > 1.0 - 1e-12, "normal {n} at point {i}");
    }
    // One viewpoint per point, each finite.
    assert!(matches!(
        orient_normals_towards(&points, &graph, &mut est, &viewpoints[1..], PAR),
        Err(NormalsError::LengthMismatch { .. })
    ));
    let mut bad = viewpoints.clone();
    bad[7] = Point::new(0.0, f64::INFINITY, 0.0);
    assert_eq!(
        orient_normals_towards(&points, &graph, &mut est, &bad, PAR),
        Err(NormalsError::InvalidViewpoint)
    );
}

#[test]
fn outward_on_a_flat_component_is_deterministic() {
    // A plane has no outside: the seed's largest normal component is made positive.
    let tilt = Vector::new(1.0, 2.0, -3.0).normalize();
    let rot = Rotation3::rotation_between(&Vector::z(), &tilt).unwrap();
    let points: Vec<Point> = square_grid(30, 30, 0.1)
        .iter()
        .map(|p| rot * p + Vector::new(5.0, 0.0, 1.0))
        .collect();
    let out = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
    assert_eq!(out.report.consistency, Some(1.0));
    for n in unwrap_normals(&out.estimates) {
        assert!(angle_deg(&n, &-tilt) < 1e-6, "normal {n}");
    }
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

// ---------------------------------------------------------------------------------------------
// Degenerate input: per-point failures, never a panic.

#[test]
fn collinear_points_fail_per_point() {
    let points: Vec<Point> = (0..50)
        .map(|i| Point::new(0.1 * i as f64, 0.2 * i as f64, -0.05 * i as f64))
        .collect();
    let out = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
    assert!(
        out.estimates
            .iter()
            .all(|e| *e == Err(PointStatus::NormalEstimationFailed))
    );
    assert_eq!(out.report.oriented, 0);
    assert_eq!(out.report.consistency, None);
}

#[test]
fn tiny_clouds_do_not_panic() {
    for n in 0..3 {
        let points: Vec<Point> = (0..n).map(|i| Point::new(i as f64, 0.0, 0.0)).collect();
        let out = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
        assert_eq!(out.estimates.len(), n);
        assert_eq!(out.failed(), n);
        assert_eq!(out.graph.k(), n.saturating_sub(1));
    }
    // Three points in general position do define a plane.
    let triangle = [
        Point::new(0.0, 0.0, 1.0),
        Point::new(1.0, 0.0, 1.0),
        Point::new(0.0, 1.0, 1.0),
    ];
    let out = estimate_normals(&triangle, &NormalsConfig::default(), PAR).unwrap();
    for n in unwrap_normals(&out.estimates) {
        assert!(line_angle_deg(&n, &Vector::z()) < 1e-9);
    }
}

#[test]
fn empty_cloud_gives_an_empty_result() {
    let out = estimate_normals(&[], &NormalsConfig::default(), PAR).unwrap();
    assert!(out.estimates.is_empty() && out.graph.is_empty());
    assert_eq!(out.h, None);
    assert_eq!(out.report.components, 0);
    assert_eq!(
        spacing_statistics(&[], 8, PAR),
        Err(NormalsError::TooFewDistinctPoints { distinct: 0 })
    );
}

#[test]
fn duplicates_are_harmless() {
    // Copies of a single point: no normal anywhere, no panic.
    let same = vec![Point::new(1.0, 2.0, 3.0); 1000];
    let out = estimate_normals(&same, &NormalsConfig::default(), PAR).unwrap();
    assert_eq!(out.failed(), same.len());
    assert_eq!(out.h, None);

    // Every sample of a sphere three times: same spacing, still radial and outward.
    let centre = Point::new(0.0, 1.0, 0.0);
    let single = fibonacci_sphere(2000, centre, 1.0);
    let tripled: Vec<Point> = single.iter().flat_map(|p| [*p; 3]).collect();
    let s1 = spacing_statistics(&single, DEFAULT_SPACING_NEIGHBOURS, PAR).unwrap();
    let s3 = spacing_statistics(&tripled, DEFAULT_SPACING_NEIGHBOURS, PAR).unwrap();
    assert_eq!(s1.spacing, s3.spacing);
    assert_eq!(s3.duplicates, 2 * single.len());
    let out = estimate_normals(&tripled, &NormalsConfig::default(), PAR).unwrap();
    assert_eq!(out.report.consistency, Some(1.0));
    for (p, n) in tripled.iter().zip(unwrap_normals(&out.estimates)) {
        assert!(angle_deg(&n, &(p - centre)) < 1.5, "at {p}");
    }
}

#[test]
fn extreme_coordinates_do_not_panic() {
    let clouds = [
        vec![
            Point::new(1e300, 0.0, 0.0),
            Point::new(-1e300, 1.0, 0.0),
            Point::origin(),
        ],
        fibonacci_sphere(50, Point::origin(), 1e-150),
        fibonacci_sphere(50, Point::new(1e15, 0.0, 0.0), 1e-3),
    ];
    for points in &clouds {
        for orientation in [
            Orientation::Outward,
            Orientation::Viewpoint(Point::new(0.0, 0.0, 1.0)),
        ] {
            let config = NormalsConfig {
                orientation,
                ..NormalsConfig::default()
            };
            // An error (an unusable spacing) is acceptable; a panic is not.
            let _ = estimate_normals(points, &config, PAR);
        }
    }
}

#[test]
fn invalid_parameters_are_errors() {
    let points = fibonacci_sphere(100, Point::origin(), 1.0);
    let with = |f: fn(&mut NormalsConfig)| {
        let mut c = NormalsConfig::default();
        f(&mut c);
        estimate_normals(&points, &c, PAR).map(|_| ())
    };
    assert_eq!(
        with(|c| c.k = 0),
        Err(NormalsError::Input(InputError::InvalidNeighbourCount {
            min: 1,
            got: 0
        }))
    );
    assert_eq!(
        with(|c| c.h = Some(0.0)),
        Err(NormalsError::InvalidScale(0.0))
    );
    assert!(matches!(
        with(|c| c.h = Some(f64::NAN)),
        Err(NormalsError::InvalidScale(_))
    ));
    assert_eq!(
        with(|c| c.h = Some(1e-200)),
        Err(NormalsError::InvalidScale(1e-200))
    );
    assert_eq!(
        with(|c| c.degeneracy_tolerance = 1.0),
        Err(NormalsError::InvalidTolerance(1.0))
    );
    assert_eq!(
        with(|c| c.orientation = Orientation::Viewpoint(Point::new(f64::NAN, 0.0, 0.0))),
        Err(NormalsError::InvalidViewpoint)
    );
    let mut bad = points.clone();
    bad[7].y = f64::INFINITY;
    assert_eq!(
        estimate_normals(&bad, &NormalsConfig::default(), PAR).map(|_| ()),
        Err(NormalsError::Input(InputError::NonFinitePoint { index: 7 }))
    );
    let graph = NeighbourGraph::build(&points, 8, PAR).unwrap();
    assert!(matches!(
        orientation_consistency(&graph, &[Vector::z(); 3], PAR),
        Err(NormalsError::LengthMismatch {
            points: 100,
            other: 3,
            ..
        })
    ));
    let stats = spacing_statistics(&points, 8, PAR).unwrap();
    assert_eq!(
        suggest_h(&stats, -1.0),
        Err(NormalsError::InvalidFactor(-1.0))
    );
    assert!(matches!(
        suggest_h(&stats, f64::INFINITY),
        Err(NormalsError::InvalidFactor(_))
    ));
}

// ---------------------------------------------------------------------------------------------
// Neighbour graph against brute force.

#[test]
fn neighbour_graph_matches_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(CLOUD_SEED);
    let mut points: Vec<Point> = (0..600)
        .map(|_| {
            Point::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-0.2..0.2),
            )
        })
        .collect();
    // Some exact duplicates, including more copies of one position than k.
    points.extend(std::iter::repeat_n(points[3], 15));
    points.extend_from_within(100..110);
    let k = 10;
    let graph = NeighbourGraph::build(&points, k, PAR).unwrap();
    assert_eq!(graph, NeighbourGraph::build(&points, k, SEQ).unwrap());
    assert_eq!((graph.len(), graph.k()), (points.len(), k));
    assert_eq!(graph.as_flat().len(), points.len() * k);
    for (i, p) in points.iter().enumerate() {
        let found: Vec<f64> = graph
            .neighbours(i)
            .iter()
            .map(|&j| {
                assert_ne!(j as usize, i, "point {i} lists itself");
                (points[j as usize] - p).norm_squared()
            })
            .collect();
        let mut brute: Vec<f64> = points
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, q)| (q - p).norm_squared())
            .collect();
        brute.sort_by(f64::total_cmp);
        assert_eq!(found, brute[..k], "point {i}");
    }
    // Fewer points than k + 1: every other point.
    let few = &points[..5];
    let small = NeighbourGraph::build(few, 16, SEQ).unwrap();
    assert_eq!(small.k(), 4);
    for i in 0..5 {
        let mut nb: Vec<u32> = small.neighbours(i).to_vec();
        nb.sort_unstable();
        let all: Vec<u32> = (0..5).filter(|&j| j != i as u32).collect();
        assert_eq!(nb, all);
    }
    assert!(small.neighbours(99).is_empty());
}

// ---------------------------------------------------------------------------------------------
// Spacing.

#[test]
fn square_grid_rms_distance_has_known_values() {
    assert_eq!(square_grid_rms_distance(1), 1.0);
    assert_eq!(square_grid_rms_distance(4), 1.0);
    assert!((square_grid_rms_distance(8) - 1.5_f64.sqrt()).abs() < 1e-15);
    assert!((square_grid_rms_distance(12) - (28.0_f64 / 12.0).sqrt()).abs() < 1e-15);
    // 4 at 1, 4 at √2, 4 at 2, 8 at √5.
    assert!((square_grid_rms_distance(20) - (68.0_f64 / 20.0).sqrt()).abs() < 1e-15);
    assert!(square_grid_rms_distance(0).is_nan());
}

#[test]
fn spacing_of_a_square_grid_is_its_pitch() {
    let pitch = 0.37;
    let rot = Rotation3::from_euler_angles(0.7, 0.2, -0.4);
    let t = Vector::new(12.0, -5.0, 1e4);
    let grid: Vec<Point> = square_grid(50, 50, pitch)
        .iter()
        .map(|p| rot * p + t)
        .collect();
    for k in [4, 6, 8, 12, 16, 24] {
        let stats = spacing_statistics(&grid, k, PAR).unwrap();
        assert!(
            (stats.spacing / pitch - 1.0).abs() < 0.01,
            "k = {k}: spacing {} for pitch {pitch}",
            stats.spacing
        );
        assert!((stats.nearest.median / pitch - 1.0).abs() < 1e-9);
        assert_eq!(stats.k, k);
        assert_eq!(stats.duplicates, 0);
        assert!(stats.nearest.min <= stats.nearest.p10 && stats.nearest.p90 <= stats.nearest.max);
    }
    let stats = spacing_statistics(&grid, 8, SEQ).unwrap();
    assert_eq!(stats, spacing_statistics(&grid, 8, PAR).unwrap());
    let h = suggest_h(&stats, DEFAULT_H_FACTOR).unwrap();
    assert!((h - DEFAULT_H_FACTOR * stats.spacing).abs() < 1e-15);
}

#[test]
fn spacing_of_a_fibonacci_sphere_is_the_root_of_area_per_point() {
    for (n, radius) in [(5000, 2.0), (800, 0.01)] {
        let points = fibonacci_sphere(n, Point::new(3.0, 3.0, 3.0), radius);
        let stats = spacing_statistics(&points, DEFAULT_SPACING_NEIGHBOURS, PAR).unwrap();
        let expected = (4.0 * PI * radius * radius / n as f64).sqrt();
        let rel = stats.spacing / expected - 1.0;
        assert!(
            rel.abs() < 0.1,
            "N = {n}: spacing {} vs {expected}",
            stats.spacing
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Consistency.

#[test]
fn consistency_detects_flips_and_matches_the_report() {
    let points = fibonacci_sphere(2000, Point::origin(), 1.0);
    let out = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
    let mut normals: Vec<Vector> = unwrap_normals(&out.estimates);
    let c = orientation_consistency(&out.graph, &normals, PAR).unwrap();
    assert_eq!(c, out.report.consistency);
    assert_eq!(c, Some(1.0));
    for n in normals.iter_mut().step_by(2) {
        *n = -*n;
    }
    let c = orientation_consistency(&out.graph, &normals, SEQ)
        .unwrap()
        .unwrap();
    assert!(c < 0.7, "half flipped, consistency {c}");
    // Zero normals (missing) are ignored, non-unit ones are fine.
    let scaled: Vec<Vector> = unwrap_normals(&out.estimates)
        .iter()
        .enumerate()
        .map(|(i, n)| if i % 3 == 0 { Vector::zeros() } else { n * 7.0 })
        .collect();
    assert_eq!(
        orientation_consistency(&out.graph, &scaled, PAR).unwrap(),
        Some(1.0)
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Arbitrary small clouds, with duplicates from coarse coordinates: never a panic, and the
    /// parallel result equals the sequential one.
    #[test]
    fn small_clouds_never_panic(
        coords in prop::collection::vec((-4i32..4, -4i32..4, -4i32..4), 0..40),
        k in 1usize..20,
        outward in any::<bool>(),
    ) {
        let points: Vec<Point> = coords
            .iter()
            .map(|&(x, y, z)| Point::new(x as f64 * 0.5, y as f64 * 0.25, z as f64))
            .collect();
        let config = NormalsConfig {
            k,
            orientation: if outward {
                Orientation::Outward
            } else {
                Orientation::Viewpoint(Point::new(1.0, 2.0, 3.0))
            },
            ..NormalsConfig::default()
        };
        let seq = estimate_normals(&points, &config, SEQ).unwrap();
        let par = estimate_normals(&points, &config, PAR).unwrap();
        prop_assert_eq!(&seq.estimates, &par.estimates);
        prop_assert_eq!(seq.report, par.report);
        for e in seq.estimates.iter().flatten() {
            prop_assert!((e.normal.as_vector().norm() - 1.0).abs() < 1e-12);
            prop_assert!((0.0..=1.0 / 3.0 + 1e-12).contains(&e.variation));
        }
    }
}
