//! `info`: point count, suggested h and the state of the normals.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::common::{
    BUNNY_POINTS, SPHERE_N, bunny_path, mlscurv, run_ok, sphere, sphere_spacing, write_xyz,
};

/// Seed of the random normal flips.
const FLIP_SEED: u64 = 0xf11b_0002;

/// The value after a `label` at the start of a line of `info`'s output.
fn field<'a>(stdout: &'a str, label: &str) -> &'a str {
    stdout
        .lines()
        .find_map(|l| l.strip_prefix(label))
        .unwrap_or_else(|| panic!("no {label:?} line in:\n{stdout}"))
        .trim()
}

/// The number at the start of the `suggested h` line.
fn suggested_h(stdout: &str) -> f64 {
    let text = field(stdout, "suggested h");
    text.split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap_or_else(|_| panic!("suggested h: {text}"))
}

fn info(path: &std::path::Path) -> String {
    run_ok(mlscurv().arg("info").arg(path)).stdout
}

#[test]
fn info_on_the_bunny_reports_the_point_count_a_suggested_h_and_absent_normals() {
    let out = info(&bunny_path());
    assert_eq!(field(&out, "points"), BUNNY_POINTS.to_string());
    let h = suggested_h(&out);
    // The scan's points are about 1 mm apart and its ears about 1 cm thick: h must be a
    // few spacings, well below the ears' thickness.
    assert!(h > 0.001 && h < 0.01, "suggested h {h}");
    assert!(field(&out, "normals").starts_with("absent"), "{out}");
}

#[test]
fn info_on_the_sphere_reports_its_spacing_scale_and_consistent_normals() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.xyz");
    let (p, n) = sphere();
    write_xyz(&path, &p, Some(&n));
    let out = info(&path);
    assert_eq!(field(&out, "points"), SPHERE_N.to_string());
    // h is a small multiple of the spacing sqrt(area / n).
    let ratio = suggested_h(&out) / sphere_spacing();
    assert!(
        (1.0..6.0).contains(&ratio),
        "suggested h is {ratio} × the spacing"
    );
    let normals = field(&out, "normals");
    assert!(
        normals.contains("consistently oriented") && !normals.contains("NOT"),
        "{normals}"
    );
}

#[test]
fn info_reports_randomly_flipped_normals_as_not_consistently_oriented() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.xyz");
    let (p, n) = sphere();
    let mut rng = ChaCha8Rng::seed_from_u64(FLIP_SEED);
    let flipped: Vec<[f64; 3]> = n
        .iter()
        .map(|v| {
            if rng.random_bool(0.5) {
                v.map(|c| -c)
            } else {
                *v
            }
        })
        .collect();
    write_xyz(&path, &p, Some(&flipped));
    let normals = field(&info(&path), "normals").to_owned();
    assert!(normals.contains("NOT consistently oriented"), "{normals}");
}

/// The numbers of a `label` line, in order (brackets, commas and `×` stripped).
fn numbers(stdout: &str, label: &str) -> Vec<f64> {
    field(stdout, label)
        .split(|c: char| c.is_whitespace() || "[],×".contains(c))
        .filter_map(|w| w.parse().ok())
        .collect()
}

#[test]
fn info_prints_huge_and_tiny_lengths_with_their_digits() {
    let dir = tempfile::tempdir().unwrap();
    // A stray coordinate of 1e300: the box must read as 1e300, not as 300 digits.
    let huge = dir.path().join("huge.xyz");
    let mut p: Vec<[f64; 3]> = (0..50).map(|i| [f64::from(i), 1.0, 2.0]).collect();
    p.push([1e300, 1.0, 2.0]);
    write_xyz(&huge, &p, None);
    let out = info(&huge);
    let line = field(&out, "bounding box");
    assert!(line.len() < 100, "{line}");
    assert_eq!(
        numbers(&out, "bounding box"),
        [0.0, 1.0, 2.0, 1e300, 1.0, 2.0]
    );
    assert_eq!(numbers(&out, "size"), [1e300, 0.0, 0.0]);
    // A grid of pitch 2.5e-6: six decimals would print its spacing as 0.000003.
    let tiny = dir.path().join("tiny.xyz");
    let pitch = 2.5e-6;
    let p: Vec<[f64; 3]> = (0..400)
        .map(|i| [f64::from(i % 20) * pitch, f64::from(i / 20) * pitch, 0.0])
        .collect();
    write_xyz(&tiny, &p, None);
    let out = info(&tiny);
    let spacing = numbers(&out, "spacing")[0];
    assert!((spacing / pitch - 1.0).abs() < 1e-5, "{out}");
    let h = suggested_h(&out);
    assert!((h / (2.0 * pitch) - 1.0).abs() < 1e-5, "{out}");
}
