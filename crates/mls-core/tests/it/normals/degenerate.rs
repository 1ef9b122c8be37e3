//! Degenerate input (collinear, tiny, empty, duplicated, extreme, invalid parameters, arbitrary
//! small clouds): per-point failures or errors, never a panic.

use mls_core::normals::{
    DEFAULT_SPACING_NEIGHBOURS, NeighbourGraph, NormalsConfig, NormalsError, Orientation,
    estimate_normals, orientation_consistency, spacing_statistics, suggest_h,
};
use mls_core::{InputError, Point, PointStatus, Vector};
use proptest::prelude::*;

use super::{PAR, SEQ, angle_deg, fibonacci_sphere, line_angle_deg, unwrap_normals};

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
    // Squared distances between the first cloud's points overflow: refused, naming the point.
    assert_eq!(
        estimate_normals(&clouds[0], &NormalsConfig::default(), PAR).err(),
        Some(NormalsError::Input(InputError::CoordinateTooLarge {
            index: 0
        }))
    );
    let mut near_limit = clouds[0].clone();
    near_limit[0].x = 1e153;
    near_limit[1].x = -1e153;
    assert!(mls_core::check_points(&near_limit).is_ok());
    near_limit[1].x = -1.0000000000000002e153;
    assert_eq!(
        mls_core::check_points(&near_limit),
        Err(InputError::CoordinateTooLarge { index: 1 })
    );
    // A non-finite coordinate is named as such, also after a large one.
    near_limit[2].z = f64::NAN;
    near_limit[1].x = 0.0;
    assert_eq!(
        mls_core::check_points(&near_limit),
        Err(InputError::NonFinitePoint { index: 2 })
    );
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
    // h² is a subnormal here, not 0: 1/h² overflows.
    assert_eq!(
        with(|c| c.h = Some(1e-160)),
        Err(NormalsError::InvalidScale(1e-160))
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
    // The parameters are checked before the points, and also where no scale can be measured
    // (every point at one position), which skips the estimation that checks them again.
    let loose = NormalsConfig {
        degeneracy_tolerance: 1.0,
        ..NormalsConfig::default()
    };
    assert_eq!(
        estimate_normals(&bad, &loose, PAR).map(|_| ()),
        Err(NormalsError::InvalidTolerance(1.0))
    );
    let one_position = vec![Point::new(1.0, 2.0, 3.0); 20];
    assert_eq!(
        estimate_normals(&one_position, &loose, PAR).map(|_| ()),
        Err(NormalsError::InvalidTolerance(1.0))
    );
    let graph = NeighbourGraph::build(&points, 8, PAR).unwrap();
    assert!(matches!(
        orientation_consistency(&points, &graph, &[Vector::z(); 3], PAR),
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
