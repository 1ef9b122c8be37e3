//! `project` on a noisy sphere: the projection removes most of the radial noise.

use crate::common::{SPHERE_N, SPHERE_R, Table, mlscurv, run_ok, sphere, std_dev, write_xyz};

/// Seed of the position noise.
const NOISE_SEED: u64 = 0x5eed_0001;

/// Standard deviation of the noise per coordinate, relative to R.
const NOISE_SIGMA: f64 = 0.002;

/// Measured ratio of projected to input radial spread: 0.20 (9.9e-4 → 2.0e-4); required < 0.3.
const MAX_SPREAD_RATIO: f64 = 0.3;

/// The spread of the points' distances from the centre: std of |p| − mean |p|.
fn radial_spread(points: &[[f64; 3]]) -> f64 {
    let r: Vec<f64> = points
        .iter()
        .map(|p| nalgebra::Vector3::from(*p).norm())
        .collect();
    std_dev(&r)
}

#[test]
fn projecting_a_noisy_sphere_shrinks_its_radial_spread_and_every_status_is_ok() {
    let (p, n) = sphere();
    let noisy = mls_shapes::add_position_noise(&p, NOISE_SIGMA * SPHERE_R, NOISE_SEED);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("noisy.xyz");
    write_xyz(&input, &noisy, Some(&n));
    let out = dir.path().join("projected.csv");
    run_ok(
        mlscurv()
            .arg("project")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .arg("--quiet"),
    );
    let t = Table::parse_csv(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(t.header, ["x", "y", "z", "nx", "ny", "nz", "status"]);
    assert_eq!(t.rows.len(), SPHERE_N);
    let bad = t.column("status").iter().filter(|&&s| s != 0.0).count();
    assert_eq!(bad, 0, "{bad} points with non-zero status");
    let (before, after) = (
        radial_spread(&noisy),
        radial_spread(&t.arrays(["x", "y", "z"])),
    );
    let ratio = after / before;
    eprintln!("project: radial spread {before:e} -> {after:e}, ratio {ratio}");
    assert!(
        ratio < MAX_SPREAD_RATIO,
        "radial spread {before} -> {after}, ratio {ratio}"
    );
}
