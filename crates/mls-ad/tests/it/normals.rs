//! Normal estimation (`estimate_normals`, what the CLI runs without file normals) against the
//! independent weighted covariance and Jacobi eigen-solve of `mls_ad::normal_witness`: the
//! quick version of `validate`'s normal rows, so that `cargo test` sees wrong weights, a wrong
//! centroid or a wrong neighbourhood, which change a normal by less than any angle tolerance.

use mls_core::normals::{DEFAULT_DEGENERACY_TOLERANCE, NormalsConfig, estimate_normals};
use mls_core::{Parallelism, Point};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn estimated_normals_match_the_witness() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0113);
    let mut compared = 0;
    for case in 0..8 {
        // A wavy sheet, randomly sampled, with a little noise off it.
        let n = 600;
        let (amp, freq, noise): (f64, f64, f64) = (
            rng.random_range(0.0..0.2),
            rng.random_range(1.0..6.0),
            rng.random_range(0.0..0.01),
        );
        let points: Vec<Point> = (0..n)
            .map(|_| {
                let (x, y): (f64, f64) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                let z = amp * (freq * x).sin() * (0.7 * freq * y).cos();
                Point::new(x, y, z + noise * rng.random_range(-1.0..1.0))
            })
            .collect();
        let h = rng.random_range(0.05..0.3);
        let config = NormalsConfig {
            h: Some(h),
            ..NormalsConfig::default()
        };
        let est = estimate_normals(&points, &config, Parallelism::Rayon).unwrap();
        for _ in 0..20 {
            let i = rng.random_range(0..n);
            let w = mls_ad::normal_witness(i, &points, config.k, h, DEFAULT_DEGENERACY_TOLERANCE);
            let (e, w) = match (&est.estimates[i], w) {
                (Ok(e), Some(w)) => (e, w),
                (e, w) => panic!("case {case}, point {i}: {e:?} against {w:?}"),
            };
            let [l0, l1, l2] = w.eigenvalues;
            let sin = e.normal.as_vector().cross(&w.normal).norm();
            // The direction is determined to about ε·λ2/(λ1 − λ0).
            assert!(
                sin * (l1 - l0) / l2 < 1e-10,
                "case {case}, point {i}: normal {:?} against {:?}",
                e.normal,
                w.normal
            );
            assert!(
                (e.variation - w.variation).abs() < 1e-10,
                "case {case}, point {i}: variation {} against {}",
                e.variation,
                w.variation
            );
            compared += 1;
        }
    }
    assert_eq!(compared, 160);
}

/// Rings of a cylinder (radius 1) 16 times farther apart than their points: the 16 nearest
/// neighbours of every point lie on its own ring, whose plane gave the axis as the normal
/// (`LINE_RATIO`). Those are estimated again from 64 neighbours, which reach the next rings,
/// in mls-core as in the witness: the same normals, radial.
#[test]
fn normals_of_rings_farther_apart_than_their_neighbours_match_the_witness() {
    let (around, gap) = (1000, 0.1);
    // Jittered by a thousandth of the step, so that no two neighbours tie in distance (the
    // tree and the witness break ties differently).
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0114);
    let mut points = Vec::new();
    for i in -60..=60 {
        for j in -3..=3 {
            let a = (f64::from(i) + rng.random_range(-1e-3..1e-3)) * std::f64::consts::TAU
                / f64::from(around);
            let z = (f64::from(j) + rng.random_range(-1e-3..1e-3)) * gap;
            points.push(Point::new(a.cos(), a.sin(), z));
        }
    }
    let h = 0.032;
    let config = NormalsConfig {
        h: Some(h),
        ..NormalsConfig::default()
    };
    let est = estimate_normals(&points, &config, Parallelism::Rayon).unwrap();
    for (i, p) in points.iter().enumerate() {
        let w = mls_ad::normal_witness(i, &points, config.k, h, DEFAULT_DEGENERACY_TOLERANCE);
        let (e, w) = match (&est.estimates[i], w) {
            (Ok(e), Some(w)) => (e, w),
            (e, w) => panic!("point {i}: {e:?} against {w:?}"),
        };
        let [l0, l1, l2] = w.eigenvalues;
        let sin = e.normal.as_vector().cross(&w.normal).norm();
        assert!(sin * (l1 - l0) / l2 < 1e-10, "point {i}");
        // Radial away from the patch's ends along the rings, where the neighbourhood is one-sided.
        let radial = mls_core::Vector::new(p.x, p.y, 0.0).normalize();
        let inner = p.y.atan2(p.x).abs() < 30.0 * std::f64::consts::TAU / f64::from(around);
        assert!(
            !inner || e.normal.as_vector().dot(&radial).abs() > 0.999,
            "point {i}: normal {:?}",
            e.normal
        );
    }
}
