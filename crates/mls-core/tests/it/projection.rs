//! The Amenta–Kil projection lands on energy minima, never on the spurious sheets (energy
//! maxima, where g = 0 too) about ±h off the surface.

use mls_core::{MlsConfig, MlsSurface, Point, PointStatus, Vector};

use crate::clouds::{fibonacci_sphere, wavy_patch};

const SPACING: f64 = 0.02;

fn plane(h_ratio: f64) -> (MlsSurface, f64) {
    let n = 40;
    let pts: Vec<Point> = (0..n * n)
        .map(|k| {
            Point::new(
                (k % n) as f64 * SPACING - 0.4,
                (k / n) as f64 * SPACING - 0.4,
                0.0,
            )
        })
        .collect();
    let nrm = vec![Vector::z(); pts.len()];
    let h = h_ratio * SPACING;
    (MlsSurface::new(&pts, &nrm, MlsConfig::new(h)).unwrap(), h)
}

#[test]
fn spurious_sheets_exist_where_g_vanishes_with_reversed_gradient() {
    let (surface, h) = plane(2.0);
    let mut ev = surface.evaluator();
    // On a plane with upward normals, g(z) ∝ z − z³/h²: zero at 0 and at ±h.
    for z in [-h, h] {
        let imp = ev.implicit_at(&Point::new(0.0, 0.0, z)).unwrap();
        let scale = imp.gradient.norm() * h;
        assert!(imp.value.abs() < 1e-9 * scale, "g({z}) = {}", imp.value);
        assert!(
            imp.gradient.z < 0.0,
            "∇g points against the normals on the sheet at {z}"
        );
    }
}

#[test]
fn projection_reaches_the_surface_and_never_a_sheet() {
    let (surface, h) = plane(2.0);
    let mut ev = surface.evaluator();
    // From inside the basin, including exactly on the sheets (stationary, e'' < 0).
    for t in [-1.0, -0.99, -0.9, -0.5, -0.1, 0.0, 0.2, 0.7, 0.95, 1.0] {
        let start = Point::new(0.013, -0.007, t * h);
        let r = ev
            .project(&start)
            .unwrap_or_else(|s| panic!("from {t}h: {s}"));
        assert!(
            r.point.z.abs() < 1e-9 * h,
            "from {t}h landed at z = {:e}",
            r.point.z
        );
        assert!(
            (r.point.xy() - start.xy()).norm() < 1e-12,
            "moved sideways on a plane"
        );
        assert!(r.curvature.k1.abs() < 1e-9 && r.curvature.k2.abs() < 1e-9);
    }
    // Beyond the sheets the energy decreases away from the surface: no minimum, and a status
    // rather than a landing on the sheet.
    for t in [-1.3, 1.2, 2.0] {
        let r = ev.project(&Point::new(0.0, 0.0, t * h));
        assert_eq!(r.err(), Some(PointStatus::ProjectionFailed), "from {t}h");
    }
}

#[test]
fn projection_onto_a_sphere_converges_to_a_zero_of_g() {
    let (pts, nrm) = fibonacci_sphere(20_000, 1.0);
    let spacing = (4.0 * std::f64::consts::PI / 20_000.0).sqrt();
    let h = 2.0 * spacing;
    let surface = MlsSurface::new(&pts, &nrm, MlsConfig::new(h)).unwrap();
    let mut ev = surface.evaluator();
    for (i, p) in pts.iter().enumerate().step_by(997) {
        let start = p + nrm[i] * (0.5 * h * ((i % 5) as f64 - 2.0) / 2.0);
        let r = ev.project(&start).unwrap();
        let imp = r.implicit;
        assert!(
            imp.value.abs() < 1e-9 * imp.gradient.norm() * h,
            "g = {:e} at the projection",
            imp.value
        );
        // The MLS sphere lies inside the sampled one by about (k1 + k2) h² / 4.
        let shrink = 1.0 - r.point.coords.norm();
        assert!(
            shrink > 0.0 && shrink < h * h,
            "radius off by {shrink:e} (h² = {:e})",
            h * h
        );
        assert!(
            (r.curvature.normal - p.coords).norm() < 1e-2,
            "normal {:?}",
            r.curvature.normal
        );
    }
}

/// A projection stops once the steps still to come, shrinking geometrically, would add up to
/// less than its tolerance. Where it stops lies within that tolerance of where a tolerance 100
/// times smaller takes it, and on the zero set of g to within 10 tolerances: g sums the
/// kernel's support, the line searches also the samples up to 1.5h beyond it, whose weights
/// are below exp(−25) ≈ 1.4e-11 of the nearest sample's. On a wavy, jittered patch with
/// tilted normals, where the normal field turns along the way (on a sphere the first step
/// lands).
#[test]
fn a_projection_stops_within_its_tolerance_of_the_converged_point() {
    use mls_core::ProjectionConfig;

    let spacing = 0.02;
    let (pts, nrm) = wavy_patch(7, spacing, 0.5, 0.1);
    let h = 2.0 * spacing;
    let tolerance = ProjectionConfig::default().tolerance;
    let surface = MlsSurface::new(&pts, &nrm, MlsConfig::new(h)).unwrap();
    let mut tighter = MlsConfig::new(h);
    tighter.projection.tolerance = 0.01 * tolerance;
    let reference = MlsSurface::new(&pts, &nrm, tighter).unwrap();
    let (mut ev, mut full) = (surface.evaluator(), reference.evaluator());
    let mut tested = 0;
    for (i, p) in pts.iter().enumerate().step_by(5) {
        if p.x.abs().max(p.y.abs()) > 0.25 {
            continue;
        }
        // Off the surface by up to 0.6h, along a direction tilted from the normal.
        let f = (i % 7) as f64 / 3.0 - 1.0;
        let start = p + Vector::new(0.3 * f, -0.2, 1.0) * (0.6 * h * f);
        let stopped = ev.project(&start).unwrap();
        let off = stopped.implicit.value / stopped.implicit.gradient.norm();
        assert!(
            off.abs() <= 10.0 * tolerance * h,
            "from {start}: {:e} h off the zero set of g",
            off / h
        );
        let converged = full.project(&start).unwrap().point;
        let apart = (stopped.point - converged).norm();
        assert!(
            apart <= tolerance * h,
            "from {start}: {:e} h from the converged point",
            apart / h
        );
        tested += 1;
    }
    assert!(tested > 100, "{tested} projections");
}

#[test]
fn projection_of_a_far_point_is_a_status() {
    let (surface, _) = plane(2.0);
    let r = surface.evaluator().project(&Point::new(0.0, 0.0, 50.0));
    assert_eq!(r.err(), Some(PointStatus::NoNeighbours));
    let nan = surface.evaluator().project(&Point::new(f64::NAN, 0.0, 0.0));
    assert_eq!(nan.err(), Some(PointStatus::InvalidQuery));
}

/// Seed of the shuffle and the offsets in [`projection_in_morton_order_equals_per_query`].
const SHUFFLE_SEED: u64 = 0x5eed_c1a5;

/// `project_points` takes the queries in Morton order, in clusters; each query must still land
/// exactly where [`mls_core::Evaluator::project`] takes it on its own, and come back in input
/// order. Queries in random order, some on the samples, some up to 0.9h off, plus an invalid
/// and a far query.
#[test]
fn projection_in_morton_order_equals_per_query() {
    use mls_core::Parallelism;
    use rand::seq::SliceRandom;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    let n = 4000;
    let (pts, nrm) = fibonacci_sphere(n, 1.0);
    let mut rng = ChaCha8Rng::seed_from_u64(SHUFFLE_SEED);
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rng);
    let (pts, nrm): (Vec<Point>, Vec<Vector>) = order.iter().map(|&i| (pts[i], nrm[i])).unzip();
    let h = 2.0 * (4.0 * std::f64::consts::PI / n as f64).sqrt();
    let surface = MlsSurface::new(&pts, &nrm, MlsConfig::new(h)).unwrap();
    let mut queries: Vec<Point> = pts
        .iter()
        .zip(&nrm)
        .enumerate()
        .map(|(i, (p, v))| match i % 3 {
            0 => *p,
            _ => p + v * (h * rng.random_range(-0.9..0.9)),
        })
        .collect();
    queries.extend([Point::new(f64::NAN, 0.0, 0.0), Point::new(0.0, 0.0, 50.0)]);

    let mut ev = surface.evaluator();
    let alone: Vec<_> = queries.iter().map(|q| ev.project(q)).collect();
    assert!(alone[..n].iter().all(|r| r.is_ok()));
    assert_eq!(alone[n], Err(PointStatus::InvalidQuery));
    assert_eq!(alone[n + 1], Err(PointStatus::NoNeighbours));
    for par in [Parallelism::Sequential, Parallelism::Rayon] {
        assert!(
            surface.project_points(&queries, par) == alone,
            "{par:?} differs from per-query projection"
        );
    }
}
