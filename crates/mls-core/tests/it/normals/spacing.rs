//! Spacing statistics and the grid calibration of h.

use std::f64::consts::PI;

use mls_core::normals::{
    DEFAULT_H_FACTOR, DEFAULT_SPACING_NEIGHBOURS, spacing_statistics, square_grid_rms_distance,
    suggest_h,
};
use mls_core::{Point, Vector};
use nalgebra::Rotation3;

use super::{PAR, SEQ, fibonacci_sphere, square_grid};

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
        // Every nearest distance is the pitch (up to the rotation's rounding): so is the mean.
        assert!((stats.nearest.mean / pitch - 1.0).abs() < 1e-9);
        assert_eq!(stats.k, k);
        assert_eq!(stats.duplicates, 0);
        assert!(stats.nearest.min <= stats.nearest.p10 && stats.nearest.p90 <= stats.nearest.max);
    }
    let stats = spacing_statistics(&grid, 8, SEQ).unwrap();
    assert_eq!(stats, spacing_statistics(&grid, 8, PAR).unwrap());
    let h = suggest_h(&stats, DEFAULT_H_FACTOR).unwrap();
    assert!((h - DEFAULT_H_FACTOR * stats.spacing).abs() < 1e-15);
}

/// Scan lines 20 times farther apart than the points along them: the 12 nearest neighbours lie
/// on one line and measured 2.5 steps along it (0.025 here). Such neighbourhoods are measured
/// again with 48, then 192, which reach the next lines: the spacing is the root of the area
/// per sample, `√(ab)` (0.0447), within 10 %. A single line keeps the 12's measure.
#[test]
fn spacing_of_scan_lines_farther_apart_than_the_neighbours_reach_is_the_root_of_area_per_point() {
    let (along, across) = (0.01, 0.2);
    let rot = Rotation3::from_euler_angles(0.3, -0.5, 1.1);
    let lines: Vec<Point> = (0..40)
        .flat_map(|j| {
            (0..400).map(move |i| Point::new(f64::from(i) * along, f64::from(j) * across, 0.0))
        })
        .map(|p| rot * p)
        .collect();
    let stats = spacing_statistics(&lines, DEFAULT_SPACING_NEIGHBOURS, PAR).unwrap();
    let want = (along * across).sqrt();
    assert!(
        (stats.spacing / want - 1.0).abs() < 0.1,
        "spacing {} for √(ab) = {want}",
        stats.spacing
    );
    // One line alone (a wire) stays on one line with 192 neighbours too, and keeps the 12's
    // measure, 2.55 steps (192 would give about 10).
    let wire: Vec<Point> = lines[..400].to_vec();
    let stats = spacing_statistics(&wire, DEFAULT_SPACING_NEIGHBOURS, PAR).unwrap();
    assert!(
        (stats.spacing / along - 2.55).abs() < 0.01,
        "wire spacing {}",
        stats.spacing / along
    );
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

/// −0.0 and 0.0 are one position: a point and its copy with a negated zero coordinate are
/// duplicates. In the lexicographic order that finds duplicates, −0.0 would sort before every
/// point of the grid's column x = 0, away from its twin.
#[test]
fn a_negative_zero_is_the_same_position() {
    let mut points: Vec<Point> = square_grid(5, 5, 1.0);
    assert!(points.contains(&Point::new(0.0, 1.0, 0.0)));
    points.push(Point::new(-0.0, 1.0, 0.0));
    let stats = spacing_statistics(&points, 4, SEQ).unwrap();
    assert_eq!((stats.distinct, stats.duplicates), (25, 1));
    assert_eq!(stats.nearest.min, 1.0);
}

/// Two distinct positions are enough for a spacing, one is not (duplicates do not count).
#[test]
fn two_distinct_positions_have_a_spacing() {
    use mls_core::normals::NormalsError;
    let p = Point::new(1.0, 2.0, 3.0);
    let q = Point::new(1.0, 2.0, 3.5);
    let stats = spacing_statistics(&[p, p, q], 4, SEQ).unwrap();
    assert_eq!((stats.distinct, stats.duplicates, stats.k), (2, 1, 1));
    assert_eq!(stats.nearest.median, 0.5);
    assert_eq!(
        spacing_statistics(&[p, p, p], 4, SEQ).err(),
        Some(NormalsError::TooFewDistinctPoints { distinct: 1 })
    );
}

/// `suggest_h` names what is wrong: a factor that is not positive, or a spacing that is zero
/// or not finite, rather than the scale they would give.
#[test]
fn suggest_h_names_a_bad_factor_or_spacing() {
    use mls_core::normals::NormalsError;
    let grid = square_grid(6, 6, 0.5);
    let stats = spacing_statistics(&grid, 4, SEQ).unwrap();
    assert_eq!(suggest_h(&stats, 2.0), Ok(2.0 * stats.spacing));
    assert_eq!(
        suggest_h(&stats, 0.0),
        Err(NormalsError::InvalidFactor(0.0))
    );
    for spacing in [0.0, f64::INFINITY] {
        let bad = mls_core::normals::SpacingStats { spacing, ..stats };
        assert_eq!(
            suggest_h(&bad, 2.0),
            Err(NormalsError::DegenerateSpacing(spacing))
        );
    }
}
