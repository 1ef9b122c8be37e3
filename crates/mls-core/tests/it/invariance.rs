//! Curvature is a property of the shape: rotating, translating, permuting the cloud or scaling
//! it together with h must transform the results accordingly.

use mls_core::{Cutoff, MlsConfig, MlsSurface, Point, SurfacePoint, Vector};
use nalgebra::{Rotation3, Translation3};
use proptest::prelude::*;

use crate::clouds::wavy_patch;

const SPACING: f64 = 0.05;

fn eval(points: &[Point], normals: &[Vector], h: f64, x: &Point) -> SurfacePoint {
    let surface = MlsSurface::new(
        points,
        normals,
        MlsConfig {
            cutoff: Cutoff::None,
            ..MlsConfig::new(h)
        },
    )
    .unwrap();
    surface
        .evaluator()
        .curvature_at(x)
        .expect("defined near the patch centre")
}

/// Tolerance on curvature: relative to the curvature scale, a few hundred ulps of the sums.
fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-9 * scale.max(1.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn rigid_motion_and_permutation(seed in 0u64..1000, ax in -3.0f64..3.0, ay in -3.0f64..3.0, az in -3.0f64..3.0,
                                     t in prop::array::uniform3(-100.0f64..100.0), h_ratio in 1.0f64..4.0) {
        let (p, n) = wavy_patch(seed, SPACING, 0.5, 0.05);
        let h = h_ratio * SPACING;
        let x = Point::new(0.01, -0.02, 0.0);
        let base = eval(&p, &n, h, &x);
        let rot = Rotation3::new(Vector::new(ax, ay, az));
        let tr = Translation3::new(t[0], t[1], t[2]);
        let mut moved: Vec<(Point, Vector)> = p.iter().zip(&n).map(|(p, n)| (tr * (rot * p), rot * n)).collect();
        moved.reverse();
        let len = moved.len();
        moved.rotate_left(seed as usize % len);
        let (mp, mn): (Vec<Point>, Vec<Vector>) = moved.into_iter().unzip();
        let other = eval(&mp, &mn, h, &(tr * (rot * x)));
        let scale = base.curvature.k1.abs().max(base.curvature.k2.abs());
        prop_assert!(close(base.curvature.k1, other.curvature.k1, scale), "{base:?} vs {other:?}");
        prop_assert!(close(base.curvature.k2, other.curvature.k2, scale));
        prop_assert!(close(base.curvature.gauss, other.curvature.gauss, scale * scale));
        prop_assert!((rot * base.curvature.normal - other.curvature.normal).norm() < 1e-9);
        prop_assert!((rot * base.curvature.d1).cross(&other.curvature.d1).norm() < 1e-6);
    }

    #[test]
    fn scaling_points_and_h_scales_curvature(seed in 0u64..1000, s in 0.01f64..100.0, h_ratio in 1.0f64..4.0) {
        let (p, n) = wavy_patch(seed, SPACING, 0.5, 0.05);
        let h = h_ratio * SPACING;
        let x = Point::new(0.03, 0.01, 0.0);
        let base = eval(&p, &n, h, &x);
        let sp: Vec<Point> = p.iter().map(|p| p * s).collect();
        let scaled = eval(&sp, &n, h * s, &(x * s));
        let scale = base.curvature.k1.abs().max(base.curvature.k2.abs());
        prop_assert!(close(base.curvature.k1, scaled.curvature.k1 * s, scale));
        prop_assert!(close(base.curvature.k2, scaled.curvature.k2 * s, scale));
        prop_assert!(close(base.curvature.mean, scaled.curvature.mean * s, scale));
    }

    #[test]
    fn flipping_normals_flips_k1_k2_mean_not_gauss(seed in 0u64..1000, h_ratio in 1.0f64..4.0) {
        let (p, n) = wavy_patch(seed, SPACING, 0.5, 0.05);
        let h = h_ratio * SPACING;
        let x = Point::new(-0.02, 0.04, 0.01);
        let base = eval(&p, &n, h, &x);
        let flipped: Vec<Vector> = n.iter().map(|n| -n).collect();
        let f = eval(&p, &flipped, h, &x);
        let scale = base.curvature.k1.abs().max(base.curvature.k2.abs());
        prop_assert!(close(f.curvature.k1, -base.curvature.k2, scale));
        prop_assert!(close(f.curvature.k2, -base.curvature.k1, scale));
        prop_assert!(close(f.curvature.mean, -base.curvature.mean, scale));
        prop_assert!(close(f.curvature.gauss, base.curvature.gauss, scale * scale));
        prop_assert!((f.curvature.normal + base.curvature.normal).norm() < 1e-12);
    }

    #[test]
    fn hessian_symmetric_and_gauss_is_k1_k2(seed in 0u64..1000, h_ratio in 1.0f64..4.0, off in -1.0f64..1.0) {
        let (p, n) = wavy_patch(seed, SPACING, 0.5, 0.1);
        let h = h_ratio * SPACING;
        let r = eval(&p, &n, h, &Point::new(0.0, 0.0, off * h));
        let hs = r.implicit.hessian;
        prop_assert!((hs - hs.transpose()).norm() <= 1e-13 * hs.norm());
        let c = r.curvature;
        let scale = c.k1.abs().max(c.k2.abs());
        prop_assert!((c.gauss - c.k1 * c.k2).abs() <= 1e-9 * scale * scale.max(1.0));
    }
}
