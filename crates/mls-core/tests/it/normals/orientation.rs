//! Orientation: outward on closed surfaces and flat components, towards one viewpoint or one
//! per point, and the consistency measure.

use mls_core::normals::{
    NeighbourGraph, NormalsConfig, NormalsError, Orientation, estimate_normals, orient_normals,
    orient_normals_towards, orientation_consistency,
};
use mls_core::{Point, Vector};
use nalgebra::Rotation3;

use super::{
    FLIP_SEED, PAR, SEQ, angle_deg, fibonacci_sphere, flat_estimate, flip_randomly, square_grid,
    torus, unoriented, unwrap_normals,
};

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

#[test]
fn consistency_detects_flips_and_matches_the_report() {
    let points = fibonacci_sphere(2000, Point::origin(), 1.0);
    let out = estimate_normals(&points, &NormalsConfig::default(), PAR).unwrap();
    let mut normals: Vec<Vector> = unwrap_normals(&out.estimates);
    let c = orientation_consistency(&points, &out.graph, &normals, PAR).unwrap();
    assert_eq!(c, out.report.consistency);
    assert_eq!(c, Some(1.0));
    for n in normals.iter_mut().step_by(2) {
        *n = -*n;
    }
    let c = orientation_consistency(&points, &out.graph, &normals, SEQ)
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
        orientation_consistency(&points, &out.graph, &scaled, PAR).unwrap(),
        Some(1.0)
    );
}

/// The sampled consistency against brute force: every point's k nearest by sorting all
/// distances, the pairs whose normals agree counted from each sampled point.
#[test]
fn sampled_consistency_counts_the_pairs_of_the_sampled_points() {
    use mls_core::IndexedCloud;
    use mls_core::normals::sampled_consistency;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    let mut rng = ChaCha8Rng::seed_from_u64(FLIP_SEED);
    // Random points (no ties in distance), a fifth of the normals flipped, some missing.
    let n = 600;
    let points: Vec<Point> = (0..n)
        .map(|_| Point::new(rng.random(), rng.random(), 0.1 * rng.random::<f64>()))
        .collect();
    let normals: Vec<Option<Vector>> = (0..n)
        .map(|i| {
            let sign = if rng.random_bool(0.2) { -1.0 } else { 1.0 };
            (i % 17 != 3).then(|| Vector::new(0.1, -0.2, sign).normalize())
        })
        .collect();
    let k = 8;
    let brute = |sampled: &[usize]| -> f64 {
        let (mut all, mut agree) = (0, 0);
        for &i in sampled {
            let Some(ni) = normals[i] else { continue };
            let mut by_distance: Vec<usize> = (0..n).filter(|&j| j != i).collect();
            by_distance.sort_by(|&a, &b| {
                (points[a] - points[i])
                    .norm_squared()
                    .total_cmp(&(points[b] - points[i]).norm_squared())
            });
            for &j in &by_distance[..k] {
                if let Some(tells) =
                    normals[j].and_then(|nj| tells_sign(&points[i], &points[j], &ni, &nj))
                {
                    all += 1;
                    agree += usize::from(tells);
                }
            }
        }
        agree as f64 / all as f64
    };
    let cloud = IndexedCloud::new(&points, PAR).unwrap();
    let normal = |i: usize| normals[i];
    // Every point, in either parallelism: the whole cloud's pairs.
    let all: Vec<usize> = (0..n).collect();
    let want = brute(&all);
    assert!((0.6..0.75).contains(&want), "a fifth flipped: {want}");
    for par in [SEQ, PAR] {
        let got = sampled_consistency(&cloud, k, n, par, normal).unwrap();
        assert!((got - want).abs() < 1e-15, "{got} against {want}");
        assert_eq!(
            sampled_consistency(&cloud, k, 10 * n, par, normal),
            Some(got)
        );
    }
    // A tenth of the points, spread over the storage order: an estimate of the whole's share
    // (480 pairs: a standard error of about 0.02).
    let some = sampled_consistency(&cloud, k, n / 10, PAR, normal).unwrap();
    assert!((some - want).abs() < 0.1, "{some} against {want}");
    // No pair with two normals, or no pair at all.
    assert_eq!(sampled_consistency(&cloud, k, n, PAR, |_| None), None);
    let one = [Point::origin()];
    let single = IndexedCloud::new(&one, PAR).unwrap();
    assert_eq!(
        sampled_consistency(&single, k, 10, PAR, |_| Some(Vector::z())),
        None
    );
    // Perpendicular normals (dot product 0) cannot tell: the pairs of like parity, all
    // agreeing, are what is left.
    assert_eq!(
        sampled_consistency(&cloud, k, n, PAR, |i| Some(if i % 2 == 0 {
            Vector::x()
        } else {
            Vector::z()
        })),
        Some(1.0)
    );
    // Agreement is the sign of the dot product, not its size: unit or not, all agree.
    assert_eq!(
        sampled_consistency(&cloud, k, n, PAR, |i| Some(Vector::z() * (1.0 + i as f64))),
        Some(1.0)
    );
}

/// The line of sight of a voting rule: the unit direction to the viewpoint, finite for a
/// viewpoint as far as 1e300 or as near as 1e-300, none at the viewpoint itself or for the
/// rules that do not vote.
#[test]
fn line_of_sight_is_the_unit_direction_to_the_viewpoint() {
    let p = Point::new(1.0, 2.0, 3.0);
    let towards = |v: Point| Orientation::Viewpoint(v).line_of_sight(&p);
    let close = |a: Vector, b: Vector| (a - b).norm() < 1e-15;
    assert!(close(
        towards(Point::new(4.0, 6.0, 3.0)).unwrap(),
        Vector::new(0.6, 0.8, 0.0)
    ));
    // From the origin, where an offset of 1e-300 is not lost to rounding.
    let o = Point::origin();
    for offset in [1e300, 1e-300] {
        let v = Point::from(Vector::new(-3.0, 0.0, 4.0) * offset);
        let sight = Orientation::Viewpoint(v).line_of_sight(&o).unwrap();
        assert!(
            close(sight, Vector::new(-0.6, 0.0, 0.8)),
            "{offset}: {sight:?}"
        );
    }
    assert_eq!(towards(p), None);
    assert_eq!(towards(Point::new(f64::INFINITY, 0.0, 0.0)), None);
    assert_eq!(Orientation::Up.line_of_sight(&p), Some(Vector::z()));
    assert_eq!(Orientation::Outward.line_of_sight(&p), None);
    assert_eq!(Orientation::None.line_of_sight(&p), None);
}

#[test]
fn facing_shares_are_the_fractions_that_face() {
    use mls_core::normals::Facing;
    let f = Facing {
        normals: 8,
        facing: 6,
        decisive: 4,
        decisive_facing: 1,
    };
    assert_eq!((f.share(), f.decisive_share()), (Some(0.75), Some(0.25)));
    let none = Facing {
        normals: 0,
        facing: 0,
        decisive: 0,
        decisive_facing: 0,
    };
    assert_eq!((none.share(), none.decisive_share()), (None, None));
}

/// `Orientation::None` leaves every sign as estimated: no components, patches or flips.
#[test]
fn no_orientation_leaves_the_signs_alone() {
    let points = fibonacci_sphere(500, Point::origin(), 1.0);
    let mut out = estimate_normals(&points, &unoriented(16), PAR).unwrap();
    flip_randomly(&mut out.estimates, FLIP_SEED);
    let before = unwrap_normals(&out.estimates);
    let report = orient_normals(
        &points,
        &out.graph,
        &mut out.estimates,
        Orientation::None,
        PAR,
    )
    .unwrap();
    assert_eq!(unwrap_normals(&out.estimates), before);
    assert_eq!(
        (report.components, report.patches, report.flipped),
        (0, 0, 0)
    );
    assert!(report.consistency.unwrap() < 0.7, "random signs");
}

/// Each neighbour pair counts once: on the line 0, 1, 3 with one neighbour each, 0 ↔ 1 is
/// mutual and 3 → 1 is not, so the pairs are {0, 1} (normals opposed) and {1, 3} (agreeing).
#[test]
fn consistency_counts_each_neighbour_pair_once() {
    let points = [
        Point::new(0.0, 0.0, 0.0),
        Point::new(1.0, 0.0, 0.0),
        Point::new(3.0, 0.0, 0.0),
    ];
    let graph = NeighbourGraph::build(&points, 1, SEQ).unwrap();
    let normals = [Vector::z(), -Vector::z(), -Vector::z()];
    assert_eq!(
        orientation_consistency(&points, &graph, &normals, SEQ).unwrap(),
        Some(0.5)
    );
    // Perpendicular normals (dot product 0) cannot tell: only {1, 3} counts.
    let normals = [Vector::x(), Vector::z(), Vector::z()];
    assert_eq!(
        orientation_consistency(&points, &graph, &normals, SEQ).unwrap(),
        Some(1.0)
    );
    // Normals 110° apart cannot tell either, whatever their lengths (3 and 5 here; their dot
    // product, −5.1, is not compared with the unit normals' bound 1/2 but with 7.5).
    let tilted = Vector::new(0.0, 110f64.to_radians().sin(), 110f64.to_radians().cos()) * 5.0;
    let normals = [Vector::z() * 3.0, tilted, tilted];
    assert_eq!(
        orientation_consistency(&points, &graph, &normals, SEQ).unwrap(),
        Some(1.0)
    );
    // A repeated point (chord 0, on no side of either tangent plane) can tell: the pairs are
    // {0, 1}, opposed, and {2, 3}, agreeing.
    let points = [
        Point::new(0.0, 0.0, 0.0),
        Point::new(0.0, 0.0, 0.0),
        Point::new(3.0, 0.0, 0.0),
        Point::new(4.0, 0.0, 0.0),
    ];
    let graph = NeighbourGraph::build(&points, 1, SEQ).unwrap();
    let normals = [Vector::z(), -Vector::z(), Vector::z(), Vector::z()];
    assert_eq!(
        orientation_consistency(&points, &graph, &normals, SEQ).unwrap(),
        Some(0.5)
    );
}

/// The facing counts of a voting rule: a normal 17° above horizontal faces `up` but is not
/// decisive (within 60° of vertical), a vertical one is both. Creases (73° apart) make each
/// point its own patch, voting up already, so nothing is flipped.
#[test]
fn facing_counts_decisive_normals_apart() {
    use mls_core::normals::Facing;
    let points = [
        Point::new(0.0, 0.0, 0.0),
        Point::new(1.0, 0.0, 0.0),
        Point::new(3.0, 0.0, 0.0),
    ];
    let graph = NeighbourGraph::build(&points, 1, SEQ).unwrap();
    let low = Vector::new(0.3f64.mul_add(-0.3, 1.0).sqrt(), 0.0, 0.3);
    let mut estimates = vec![
        flat_estimate(low),
        flat_estimate(Vector::z()),
        flat_estimate(low),
    ];
    let report = orient_normals(&points, &graph, &mut estimates, Orientation::Up, SEQ).unwrap();
    assert_eq!(report.flipped, 0);
    assert_eq!(
        report.facing,
        Some(Facing {
            normals: 3,
            facing: 3,
            decisive: 1,
            decisive_facing: 1,
        })
    );
}

/// Whether the normals `ni` at `pi` and `nj` at `pj` agree in sign, `None` when the pair
/// cannot tell, in angles: normals between 60° and 120° apart, or a chord within 75° of both
/// normals or their opposites (more than 15° out of both tangent planes).
fn tells_sign(pi: &Point, pj: &Point, ni: &Vector, nj: &Vector) -> Option<bool> {
    let between = ni.angle(nj).to_degrees();
    if between > 60.0 && between < 120.0 {
        return None;
    }
    let chord = pj - pi;
    let off_plane = |n: &Vector| !(75.0..=105.0).contains(&chord.angle(n).to_degrees());
    if chord.norm() > 0.0 && off_plane(ni) && off_plane(nj) {
        return None;
    }
    Some(between < 90.0)
}
