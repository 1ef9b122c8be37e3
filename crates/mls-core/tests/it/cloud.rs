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
