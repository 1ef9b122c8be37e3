//! Closed form (mls-core) against the automatic derivative (mls-ad) on small random clouds.
//! The exhaustive sweep is `cargo xtask validate`; this is the quick version run by `cargo test`.

use mls_core::field::{FieldScratch, evaluate};
use mls_core::{Point, Sample, Vector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod adaptive;
mod jet;
mod line;
mod normals;

const SEED: u64 = 0x5eed_0002;

fn rel(a: f64, b: f64, scale: f64) -> f64 {
    (a - b).abs() / scale.max(f64::MIN_POSITIVE)
}

/// A random patch of a sphere of radius 1 with normals tilted by up to 0.1 rad.
fn cloud(rng: &mut ChaCha8Rng, n: usize) -> Vec<Sample> {
    (0..n)
        .map(|_| {
            let dir = Vector::new(
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                1.0,
            )
            .normalize();
            let tilt = Vector::new(
                rng.random_range(-0.06..0.06),
                rng.random_range(-0.06..0.06),
                rng.random_range(-0.06..0.06),
            );
            Sample {
                point: Point::from(dir),
                normal: (dir + tilt).normalize(),
            }
        })
        .collect()
}

#[test]
fn closed_form_matches_hyper_dual_witness() {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut scratch = FieldScratch::default();
    let mut worst = [0.0f64; 6];
    for case in 0..50 {
        let samples = cloud(&mut rng, 60);
        let h = rng.random_range(0.05..0.3);
        let a = 1.0 / (h * h);
        let x = Point::new(
            rng.random_range(-0.1..0.1),
            rng.random_range(-0.1..0.1),
            1.0 + rng.random_range(-0.5..0.5) * h,
        );
        let closed = evaluate(&x, &samples, a, &mut scratch).expect("defined");
        let w = mls_ad::witness(&x.coords, &samples, a);
        let gscale = w.gradient.norm();
        let hscale = w.hessian.norm();
        let n2scale: f64 = w.second.iter().map(|m| m.norm()).sum();
        let errs = [
            rel(closed.value, w.value, gscale * h),
            (closed.gradient - w.gradient).norm() / gscale,
            (closed.hessian - w.hessian).norm() / hscale,
            (closed.field.normal - w.normal).norm(),
            (closed.field.jacobian - w.jacobian).norm() / w.jacobian.norm().max(1.0 / h),
            (0..3)
                .map(|c| (closed.field.second[c] - w.second[c]).norm())
                .sum::<f64>()
                / n2scale.max(1.0 / (h * h)),
        ];
        for (k, e) in errs.iter().enumerate() {
            worst[k] = worst[k].max(*e);
            assert!(
                *e < 1e-10,
                "case {case} (seed {SEED:#x}) quantity {k}: relative difference {e:e}"
            );
        }
        // The same shift, formed in units of h by mls-core and in world units here.
        assert!((closed.log_scale - w.log_scale).abs() <= 1e-14 * w.log_scale.max(1.0));
        let unshifted = mls_ad::implicit(&x.coords, &samples, a, 0.0);
        assert!(
            rel(
                closed.unscaled_value(),
                unshifted,
                gscale * h * (-w.log_scale).exp()
            ) < 1e-10
        );
        // Curvature by mls-core's 2 × 2 closed form against the witness's 3 × 3 eigen-decomposition.
        let c = mls_core::curvature(&closed.gradient, &closed.hessian).expect("regular point");
        let wc = mls_ad::witness_curvature(&w.gradient, &w.hessian);
        let kappa = hscale / gscale;
        for (got, want, what) in [
            (c.k1, wc.k1, "k1"),
            (c.k2, wc.k2, "k2"),
            (c.mean, wc.mean, "mean"),
        ] {
            assert!(
                rel(got, want, kappa) < 1e-10,
                "case {case}: {what} {got} vs {want}"
            );
        }
        assert!(
            rel(c.gauss, wc.gauss, kappa * kappa) < 1e-10,
            "case {case}: gauss {} vs {}",
            c.gauss,
            wc.gauss
        );
        assert!((c.normal - w.gradient / gscale).norm() < 1e-12);
        // Directions up to sign, weighted by the eigengap that makes them meaningful.
        let gap = (wc.k1 - wc.k2) / kappa;
        for (d, wd) in [(c.d1, wc.d1), (c.d2, wc.d2)] {
            assert!(
                d.cross(&wd).norm() * gap < 1e-10,
                "case {case}: direction {d:?} vs {wd:?}"
            );
            assert!((d.norm() - 1.0).abs() < 1e-12 && d.dot(&c.normal).abs() < 1e-12);
        }
        assert!((c.d1.cross(&c.d2) - c.normal).norm() < 1e-12, "d1 × d2 = n");
        let eq5 = mls_ad::implicit_from_energy(&x.coords, &samples, a, w.log_scale);
        assert!(
            rel(eq5, w.value, gscale * h) < 1e-12,
            "Eq. 5 and Eq. 7 disagree: {eq5} vs {}",
            w.value
        );
    }
    eprintln!("worst relative differences g, grad, H, n, J, d2n: {worst:?}");
}

/// The spacing witness: the grid calibration's documented values, the pitch of a square grid,
/// and `suggest_h` on small random clouds with duplicates (the full sweep is in validate).
#[test]
fn spacing_witness_matches_suggest_h() {
    use mls_core::Parallelism;
    use mls_core::normals::{spacing_statistics, suggest_h};
    assert_eq!(mls_ad::grid_rms_by_shells(4), 1.0);
    assert_eq!(mls_ad::grid_rms_by_shells(8), 1.5f64.sqrt());
    // 20 × 20 nodes: the 16 × 16 at least two from the border, whose 12 nearest lie inside,
    // are most of them, so the median is the pitch.
    let grid: Vec<Point> = (0..400)
        .map(|i| Point::new(0.3 * f64::from(i % 20), 0.3 * f64::from(i / 20), 0.0))
        .collect();
    let w = mls_ad::spacing_witness(&grid, 12, 2.0).unwrap();
    assert!(
        rel(w.spacing, 0.3, 0.3) < 1e-12,
        "grid spacing {}",
        w.spacing
    );
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    for _ in 0..20 {
        let n = rng.random_range(3..80);
        let mut points: Vec<Point> = (0..n)
            .map(|_| {
                Point::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-0.1..0.1),
                )
            })
            .collect();
        points.push(points[0]);
        let k = rng.random_range(1..20);
        let factor = rng.random_range(1.0..4.0);
        let stats = spacing_statistics(&points, k, Parallelism::Sequential).unwrap();
        let h = suggest_h(&stats, factor).unwrap();
        let w = mls_ad::spacing_witness(&points, k, factor).unwrap();
        assert_eq!((w.k, w.distinct), (stats.k, stats.distinct));
        assert!(rel(h, w.h, w.h) < 1e-12, "h {h} against {}", w.h);
    }
}
