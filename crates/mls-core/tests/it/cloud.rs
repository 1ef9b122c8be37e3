//! The indexed cloud: its spacing is bitwise that of the points, with and without duplicates,
//! and a surface built from it equals one built from the points.

use mls_core::normals::spacing_statistics;
use mls_core::{IndexedCloud, MlsConfig, MlsSurface, Parallelism, Point, Vector};
use mls_shapes::Torus;

fn torus(n: usize, seed: u64) -> (Vec<Point>, Vec<Vector>) {
    let s = mls_shapes::random(&Torus::new(6.0, 2.0), n, seed);
    (
        s.iter().map(|s| s.surface.point).collect(),
        s.iter().map(|s| s.surface.normal).collect(),
    )
}

#[test]
fn spacing_on_the_index_is_the_spacing_of_the_points() {
    let (mut points, _) = torus(3_000, 41);
    for par in [Parallelism::Sequential, Parallelism::Rayon] {
        for k in [1, 12, 40] {
            let cloud = IndexedCloud::new(&points, par).unwrap();
            assert_eq!(
                cloud.spacing_statistics(k, par).unwrap(),
                spacing_statistics(&points, k, par).unwrap(),
                "k = {k}, {par:?}"
            );
        }
    }
    // Exact duplicates (and a −0.0 against 0.0) are left out of the statistics on both paths.
    points.extend_from_within(..500);
    points.push(Point::new(-0.0, 0.0, 0.0));
    points.push(Point::new(0.0, -0.0, 0.0));
    let cloud = IndexedCloud::new(&points, Parallelism::Rayon).unwrap();
    let stats = cloud.spacing_statistics(12, Parallelism::Rayon).unwrap();
    assert_eq!(stats.duplicates, 501);
    assert_eq!(
        stats,
        spacing_statistics(&points, 12, Parallelism::Rayon).unwrap()
    );
    assert!(cloud.spacing_statistics(0, Parallelism::Rayon).is_err());
    // More neighbours asked for than the cloud has: both clamp k to the others' count.
    let few = &points[..5];
    let cloud = IndexedCloud::new(few, Parallelism::Rayon).unwrap();
    let stats = cloud.spacing_statistics(12, Parallelism::Rayon).unwrap();
    assert_eq!(stats.k, 4);
    assert_eq!(
        stats,
        spacing_statistics(few, 12, Parallelism::Rayon).unwrap()
    );
    let one = IndexedCloud::new(&points[..1], Parallelism::Rayon).unwrap();
    assert_eq!(
        one.spacing_statistics(12, Parallelism::Rayon),
        spacing_statistics(&points[..1], 12, Parallelism::Rayon)
    );
}

/// The spacing h comes from: every point of a cloud of at most `SPACING_SAMPLE` points (then
/// bitwise the full statistics), an even sample of a larger one, whose median is the full
/// median's to well within 1 % on an irregular cloud, at a sixteenth of the queries.
#[test]
fn the_spacing_of_a_large_cloud_is_measured_on_a_sample_that_keeps_its_median() {
    use mls_core::normals::SPACING_SAMPLE;
    let par = Parallelism::Rayon;
    let (points, _) = torus(5_000, 47);
    let cloud = IndexedCloud::new(&points, par).unwrap();
    let full = cloud.spacing_statistics(12, par).unwrap();
    assert_eq!(full.measured, full.distinct);
    assert_eq!(cloud.spacing(12, par).unwrap(), full);
    // 300,000 random points: the local spacing varies by tens of per cent from point to point.
    let (mut points, _) = torus(300_000, 53);
    let cloud = IndexedCloud::new(&points, par).unwrap();
    let full = cloud.spacing_statistics(12, par).unwrap();
    let sampled = cloud.spacing(12, par).unwrap();
    assert_eq!(full.measured, 300_000);
    let stride = 300_000_usize.div_ceil(SPACING_SAMPLE);
    assert_eq!(sampled.measured, 300_000_usize.div_ceil(stride));
    assert!(sampled.measured <= SPACING_SAMPLE && sampled.measured > SPACING_SAMPLE / 2);
    let spread = (full.local_spacing.p90 - full.local_spacing.p10) / full.spacing;
    assert!(spread > 0.2, "the cloud is irregular: {spread}");
    // Four standard errors of a median of that many draws, `1.25 sd/√m`, the local spacings'
    // sd read off their 10–90 % range (2.56 sd for a normal law).
    let tolerance = |m: usize| 4.0 * 1.2533 * (spread / 2.563) / (m as f64).sqrt();
    let relative = (sampled.spacing / full.spacing - 1.0).abs();
    assert!(
        relative < tolerance(sampled.measured),
        "sampled median off by {relative:e}"
    );
    // A duplicate at a measured point sends the sample to the distinct positions: the
    // duplicates are counted and left out, as in the full statistics.
    points.extend_from_within(..30_000);
    let cloud = IndexedCloud::new(&points, par).unwrap();
    let sampled = cloud.spacing(12, par).unwrap();
    assert_eq!((sampled.distinct, sampled.duplicates), (300_000, 30_000));
    let stride = 300_000_usize.div_ceil(SPACING_SAMPLE);
    assert_eq!(sampled.measured, 300_000_usize.div_ceil(stride));
    let relative = (sampled.spacing / full.spacing - 1.0).abs();
    assert!(
        relative < tolerance(sampled.measured),
        "sampled median off by {relative:e}"
    );
    assert!(cloud.spacing(0, par).is_err());
}

#[test]
fn a_surface_from_the_index_equals_one_from_the_points() {
    let (points, normals) = torus(3_000, 43);
    let config = MlsConfig::new(0.8);
    let cloud = IndexedCloud::new(&points, Parallelism::Rayon).unwrap();
    let indexed = MlsSurface::from_cloud(cloud, &normals, config).unwrap();
    let direct = MlsSurface::new(&points, &normals, config).unwrap();
    let a = indexed.curvature_at_points(&points, Parallelism::Rayon);
    let b = direct.curvature_at_points(&points, Parallelism::Rayon);
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    // A bad normal is named by its input index.
    let mut bad = normals.clone();
    bad[1234] = Vector::zeros();
    let cloud = IndexedCloud::new(&points, Parallelism::Rayon).unwrap();
    let err = MlsSurface::from_cloud(cloud, &bad, config).unwrap_err();
    assert!(err.to_string().starts_with("normal 1234:"), "{err}");
    let cloud = IndexedCloud::new(&points, Parallelism::Rayon).unwrap();
    assert!(MlsSurface::from_cloud(cloud, &normals[1..], config).is_err());
}
