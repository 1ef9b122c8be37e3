//! Tests of the scene: determinism, chunking, counts, normals, noise and bad input.

use super::*;

const SEED: u64 = 0x5EED_0014;

fn scene(points: u64, noise: f64) -> Scene {
    let config = SceneConfig {
        seed: SEED,
        range_noise: noise,
        ..SceneConfig::default()
    };
    Scene::new(config, points).expect("valid config")
}

#[test]
fn scene_is_deterministic() {
    let a: Vec<_> = scene(20_000, 0.02).scan().collect();
    let b: Vec<_> = scene(20_000, 0.02).scan().collect();
    assert_eq!(a, b);
    let other = Scene::new(
        SceneConfig {
            seed: SEED + 1,
            ..SceneConfig::default()
        },
        20_000,
    )
    .expect("valid config");
    assert_ne!(a, other.scan().collect::<Vec<_>>());
}

#[test]
fn scene_chunking_does_not_change_points() {
    let s = scene(150_000, 0.02);
    let collect = |chunk: usize| {
        let mut scan = s.scan();
        let (mut all, mut buf) = (Vec::new(), Vec::new());
        while scan.fill(&mut buf, chunk) > 0 {
            all.extend_from_slice(&buf);
        }
        all
    };
    let small = collect(1000);
    assert_eq!(small.len(), 150_000);
    assert_eq!(small, collect(65_536));
    assert_eq!(small[77_777], s.point(77_777));
    assert_eq!(s.scan_from(149_990).count(), 10);
}

#[test]
fn scene_counts_are_exact() {
    for n in [1, 2, 642, 643, 644, 999, 123_457] {
        let s = scene(n, 0.0);
        assert_eq!(s.len(), n);
        assert_eq!(s.scan().count() as u64, n, "{n}");
        assert_eq!(s.scan().size_hint(), (n as usize, Some(n as usize)));
    }
    // The layout of a large run, without generating it.
    for n in [100_000_000, 1_000_000_007] {
        let s = scene(n, 0.02);
        let (per_line, lines) = s.line_layout();
        let per_strip = per_line * lines;
        assert!(
            s.strips() * per_strip >= n && (s.strips() - 1) * per_strip < n,
            "{n}"
        );
        let area = s.area();
        let (w, l) = (area.max.x - area.min.x, area.max.y - area.min.y);
        assert!(
            w / l > 0.5 && w / l < 2.0,
            "{n}: {w} × {l} is not near square"
        );
    }
}

#[test]
fn scene_normals_match_the_surfaces_hit() {
    let s = scene(200_000, 0.0);
    let area = s.area();
    let (mut walls, mut roofs, mut vegetation, mut ground) = (0, 0, 0, 0);
    let mut last_time = f64::NEG_INFINITY;
    for (i, p) in s.scan().enumerate() {
        let n = p.normal;
        assert!((n.norm() - 1.0).abs() < 1e-12, "point {i}: {n:?}");
        let to_sensor = s.sensor_position(i as u64) - p.position;
        assert!(
            n.dot(&to_sensor) > 0.0,
            "point {i} faces away from the sensor"
        );
        assert!(p.gps_time > last_time, "point {i}: time not increasing");
        last_time = p.gps_time;
        assert!(p.position.x >= area.min.x - 1e-6 && p.position.x <= area.max.x + 1e-6);
        assert!(p.position.y >= area.min.y - 1e-6 && p.position.y <= area.max.y + 1e-6);
        assert!(p.position.z >= area.min.z - 1e-6 && p.position.z <= area.max.z);
        assert_eq!(p.return_number, 1);
        match p.class {
            SurfaceClass::Ground => {
                ground += 1;
                let (x, y) = (p.position.x, p.position.y);
                assert!(
                    (p.position.z - s.ground_height(x, y)).abs() < 1e-6,
                    "point {i}"
                );
                assert!((n - s.ground_normal(x, y)).norm() < 1e-9, "point {i}");
                assert!(n.z > 0.9, "point {i}: {n:?}");
            }
            SurfaceClass::Building if n.z.abs() < 1e-12 => walls += 1,
            SurfaceClass::Building => {
                roofs += 1;
                assert!(n.z > 0.5, "point {i}: roof normal {n:?}");
                assert!(p.position.z > s.ground_height(p.position.x, p.position.y) + 3.0);
            }
            SurfaceClass::Vegetation => vegetation += 1,
        }
    }
    assert!(ground > 100_000, "{ground} ground points");
    assert!(
        walls > 0 && roofs > 1000 && vegetation > 500,
        "{walls} {roofs} {vegetation}"
    );
}

#[test]
fn scene_noise_moves_points_along_the_ray() {
    let exact = scene(5000, 0.0);
    let noisy = scene(5000, 0.05);
    let mut sum = 0.0;
    for i in 0..5000 {
        let (a, b) = (exact.point(i), noisy.point(i));
        let ray = (a.position - exact.sensor_position(i)).normalize();
        let offset = b.position - a.position;
        assert!(offset.cross(&ray).norm() < 1e-6, "point {i}");
        sum += offset.norm_squared();
        assert_eq!(a.normal, b.normal);
    }
    let sd = (sum / 5000.0).sqrt();
    assert!((sd - 0.05).abs() < 0.005, "range noise {sd}");
}

#[test]
fn scene_rejects_bad_input() {
    assert_eq!(
        Scene::new(SceneConfig::default(), 0).err(),
        Some(SceneError::NoPoints)
    );
    for config in [
        SceneConfig {
            point_pitch: 0.0,
            ..SceneConfig::default()
        },
        SceneConfig {
            range_noise: f64::NAN,
            ..SceneConfig::default()
        },
        SceneConfig {
            max_scan_angle_deg: 80.0,
            ..SceneConfig::default()
        },
    ] {
        assert!(matches!(
            Scene::new(config, 10),
            Err(SceneError::InvalidParameter { .. })
        ));
    }
    let tiny = SceneConfig {
        point_pitch: 100.0,
        line_spacing: 1e-6,
        ..SceneConfig::default()
    };
    assert!(matches!(
        Scene::new(tiny, u64::MAX),
        Err(SceneError::TooManyStrips { .. })
    ));
}
