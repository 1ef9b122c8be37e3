//! The jet estimator (mls-core, the default method) against its witness (`mls_ad::jet_witness`)
//! on small height-field patches: the quick version of `validate`'s jet rows, so that
//! `cargo test` (and cargo-mutants, which runs it) sees a wrong fit, covariance or scale choice.

use mls_ad::JetRefusal;
use mls_core::{
    JetConfig, MlsConfig, MlsSurface, NormalData, Parallelism, Point, PointStatus, Sample, Vector,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The surface `z = f(x, y)`: a quadric, a cubic and a ripple of amplitude `ripple` that no
/// quartic reproduces, so that bias grows along the ladder and the scale choice has something
/// to weigh. Without the ripple every fit is exact and its predicted error sits at the floor.
fn height(x: f64, y: f64, ripple: f64) -> (f64, [f64; 2]) {
    let (a, b, c, d, k) = (0.8, -0.3, -0.5, 0.4, 9.0);
    let z = 0.5 * a * x * x + b * x * y + 0.5 * c * y * y + d * x * x * y + ripple * (k * x).sin();
    let fx = a * x + b * y + 2.0 * d * x * y + ripple * k * (k * x).cos();
    let fy = b * x + c * y + d * x * x;
    (z, [fx, fy])
}

/// A random patch of `height` of half-width 0.5, with position noise `sigma` along z and
/// normals tilted by up to `tilt` per component; a fraction `odd` of the normals either face
/// away (samples of a far sheet, which the fit leaves out) or lean about 70° (whose slopes it
/// leaves out).
fn patch(
    rng: &mut ChaCha8Rng,
    n: usize,
    (sigma, tilt, odd, ripple): (f64, f64, f64, f64),
) -> (Vec<Point>, Vec<Vector>) {
    (0..n)
        .map(|_| {
            let (x, y) = (rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
            let (z, [fx, fy]) = height(x, y, ripple);
            let noise = sigma * rng.random_range(-1.0..1.0);
            let t = Vector::new(
                rng.random_range(-tilt..=tilt),
                rng.random_range(-tilt..=tilt),
                0.0,
            );
            let mut normal = (Vector::new(-fx, -fy, 1.0).normalize() + t).normalize();
            if rng.random_bool(odd) {
                normal = if rng.random_bool(0.5) {
                    -normal
                } else {
                    (normal + Vector::new(2.7, 0.0, 0.0)).normalize()
                };
            }
            (Point::new(x, y, z + noise), normal)
        })
        .unzip()
}

/// The witness's samples: each point with its normal.
fn samples_of(points: &[Point], normals: &[Vector]) -> Vec<Sample> {
    points
        .iter()
        .zip(normals)
        .map(|(p, v)| Sample {
            point: *p,
            normal: *v,
        })
        .collect()
}

/// Relative thresholds: those of `cargo xtask validate` (k through one solve; the predicted
/// error through M⁻¹ twice and the residuals), both scaled by the fit's conditioning.
const K_THRESHOLD: f64 = 1e-10;
const SD_THRESHOLD: f64 = 1e-5;

#[test]
fn jet_matches_its_witness_with_and_without_slopes() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0003);
    // (points, h in spacings, (position noise, normal tilt, odd normals, ripple)): clean;
    // noisy (the ladder climbs); sparse (heights alone determine only lower degrees at the
    // first scales); a tenth of the normals facing away or leaning; an exact cubic (every
    // predicted error at its floor).
    let cases = [
        (2500, 2.0, (0.0, 0.0, 0.0, 0.02)),
        (2500, 2.0, (2e-3, 0.05, 0.0, 0.02)),
        (700, 1.3, (0.0, 0.02, 0.0, 0.02)),
        (1500, 2.0, (1e-3, 0.02, 0.1, 0.02)),
        (1500, 2.0, (0.0, 0.0, 0.0, 0.0)),
        // A strong ripple (the bias grows fast along the ladder), with and without noise, and
        // strong noise on the quadric and cubic alone, twice (the ladder climbs to 4.2 h,
        // where the width of the confidence intervals of k1 and of k2 decides where it stops).
        (2500, 2.0, (0.0, 0.0, 0.0, 0.1)),
        (2500, 2.0, (2e-3, 0.02, 0.0, 0.1)),
        (2500, 2.0, (5e-3, 0.05, 0.0, 0.0)),
        (2500, 2.0, (2e-2, 0.1, 0.0, 0.0)),
    ];
    let mut compared = 0;
    let mut worst = [0.0f64; 3];
    for (case, &(n, factor, shape)) in cases.iter().enumerate() {
        let (points, normals) = patch(&mut rng, n, shape);
        let h = factor / (n as f64).sqrt();
        let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
        let samples = samples_of(&points, &normals);
        // Queries near the middle (every scale's support inside the patch), on and off the
        // samples.
        let queries: Vec<Point> = (0..12)
            .map(|i| {
                let (x, y) = (rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1));
                let off = if i % 2 == 0 { 0.0 } else { 0.3 * h };
                Point::new(x, y, height(x, y, shape.3).0 + off)
            })
            .chain(
                points
                    .iter()
                    .filter(|p| p.x.abs().max(p.y.abs()) < 0.1)
                    .take(12)
                    .copied(),
            )
            .collect();
        compared += compare_with_witness(
            &format!("case {case}"),
            &surface,
            &samples,
            &queries,
            h,
            &mut worst,
        );
    }
    assert_eq!(compared, cases.len() * 2 * 24);
    eprintln!("worst k1, k2, predicted error, in units of their thresholds: {worst:?}");
}

/// Every query's jet, with and without slopes, against the witness's: degree and radius
/// exactly, k1 and k2 within [`K_THRESHOLD`], the predicted error within [`SD_THRESHOLD`] (both
/// scaled by the fit's conditioning), the foot within 1e-9 h. Returns the number compared and
/// raises `worst` to each error in units of its threshold.
fn compare_with_witness(
    case: &str,
    surface: &MlsSurface,
    samples: &[Sample],
    queries: &[Point],
    h: f64,
    worst: &mut [f64; 3],
) -> usize {
    let mut compared = 0;
    for normals in [NormalData::Slopes, NormalData::Ignore] {
        let config = JetConfig {
            normals,
            ..JetConfig::default()
        };
        let results = surface.jet_at_points(queries, &config, Parallelism::Rayon);
        let mut share = mls_ad::ShareWitness::new(samples, h, &config);
        for (x, r) in queries.iter().zip(results) {
            let w = witness(&mut share, x, samples, h, &config);
            let (j, w) = match (r, w) {
                (Ok(j), Ok(w)) => (j, w),
                // Heights only: a query off the noisy surface by more than its neighbours'
                // residuals allow, on both sides.
                (Err(PointStatus::Outlier), Err(JetRefusal::Outlier)) => {
                    compared += 1;
                    continue;
                }
                (r, w) => panic!("{case} {normals:?} at {x:?}: {r:?} against {w:?}"),
            };
            let what = format!("{case} {normals:?} at {x:?}");
            assert_eq!(
                (j.fit.degree, j.fit.radius),
                (w.degree, w.radius),
                "{what}: degree and radius"
            );
            let kappa = w.k1.abs().max(w.k2.abs()).max(1.0 / h);
            let rounding = 1e3 * f64::EPSILON * w.condition;
            for (got, want, i) in [(j.curvature.k1, w.k1, 0), (j.curvature.k2, w.k2, 1)] {
                let e = (got - want).abs() / kappa;
                worst[i] = worst[i].max(e / rounding.max(K_THRESHOLD));
                assert!(
                    e <= rounding.max(K_THRESHOLD),
                    "{what}: k{} {got} against {want}",
                    i + 1
                );
            }
            let pe = j.predicted_error();
            let we = [0, 1].map(|i| w.sd[i].hypot(w.bias[i]));
            let scale = we[0]
                .max(we[1])
                .max(1e3 * mls_core::jet::SD_FLOOR / w.radius);
            let e = (pe[0] - we[0]).abs().max((pe[1] - we[1]).abs()) / scale;
            worst[2] = worst[2].max(e / rounding.max(SD_THRESHOLD));
            assert!(
                e <= rounding.max(SD_THRESHOLD),
                "{what}: predicted error {pe:?} against {we:?}"
            );
            let foot = j.foot.coords - w.foot;
            assert!(foot.norm() <= 1e-9 * h, "{what}: foot {foot:?}");
            compared += 1;
        }
    }
    compared
}

/// A thin part: the patch and a far sheet 0.6 spacings beneath it with opposed normals and
/// twice its samples, so that at most queries the weighted average of the support's normals
/// faces the far sheet. The frame then averages only the normals on the nearest sample's side
/// (the near sheet), in mls-core as in the witness, and every jet keeps the near sheet's
/// normal.
#[test]
fn jet_matches_its_witness_across_a_thin_part() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0004);
    let n = 1500;
    let h = 2.0 / (n as f64).sqrt();
    let gap = 0.6 / (n as f64).sqrt();
    let (mut points, mut normals) = patch(&mut rng, n, (0.0, 0.0, 0.0, 0.02));
    let (far, far_normals) = patch(&mut rng, 2 * n, (0.0, 0.0, 0.0, 0.02));
    points.extend(far.iter().map(|p| p - Vector::z() * gap));
    normals.extend(far_normals.iter().map(|v| -v));
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
    let samples = samples_of(&points, &normals);
    let queries: Vec<Point> = points[..n]
        .iter()
        .filter(|p| p.x.abs().max(p.y.abs()) < 0.1)
        .take(24)
        .copied()
        .collect();
    // The queries whose whole average turned away: more than 60° from their own normal.
    let turned = queries
        .iter()
        .filter(|q| {
            let rho = JetConfig::default().radius * h;
            let sum: Vector = samples
                .iter()
                .map(|s| (1.0 - (s.point - *q).norm_squared() / (rho * rho), s.normal))
                .filter(|(t, _)| *t > 0.0)
                .map(|(t, v)| v * (t * t * t))
                .sum();
            sum.angle(&Vector::z()).to_degrees() > 60.0
        })
        .count();
    assert!(turned >= 12, "{turned} of 24 queries turned");
    let mut worst = [0.0; 3];
    let compared = compare_with_witness("thin part", &surface, &samples, &queries, h, &mut worst);
    assert_eq!(compared, 48);
    for config in [
        JetConfig::default(),
        JetConfig {
            normals: NormalData::Ignore,
            ..JetConfig::default()
        },
    ] {
        for (q, r) in
            queries
                .iter()
                .zip(surface.jet_at_points(&queries, &config, Parallelism::Rayon))
        {
            let n = r.unwrap().curvature.normal;
            assert!(n.z > 0.9, "at {q}: normal {n}");
        }
    }
}

/// Rings of a cylinder (radius 1), 6.5 times farther apart than the points along each, with
/// normals tilted along the axis by a few thousandths, as estimated ones are. At the second
/// scale the support holds three rings, on which degree 4 is undetermined: in exact arithmetic
/// the normal equations are singular, but where the frame's tangents are turned away from the
/// rings (about 7° around the cylinder from the x axis here) rounding leaves a squared pivot
/// above 1e-10 of the largest diagonal entry (measured: 1.5e-10, and 6.7e-8 of its own). The
/// rule of `DETERMINED_PIVOT` refuses it, in mls-core as in the witness, until a larger scale
/// holds five rings. Without that rule in mls-core, its degrees and radii differ from the
/// witness's. (The witness's own rounding leaves that pivot below 1e-10 here, so this case does
/// not need the witness's copy of the rule.)
#[test]
fn jet_matches_its_witness_on_rings() {
    let (step, gap, h) = (std::f64::consts::TAU / 400.0, 0.1, 0.08);
    let (mut points, mut normals) = (Vec::new(), Vec::new());
    for i in -32..=48 {
        let a = f64::from(i) * step;
        for j in -6..=6 {
            points.push(Point::new(a.cos(), a.sin(), f64::from(j) * gap));
            normals.push(Vector::new(a.cos(), a.sin(), -4.4e-3).normalize());
        }
    }
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
    let samples = samples_of(&points, &normals);
    let queries: Vec<Point> = points
        .iter()
        .filter(|p| (p.y.atan2(p.x) / step - 8.0).abs() < 3.5 && p.z.abs() < 0.15)
        .copied()
        .collect();
    let mut worst = [0.0; 3];
    let compared = compare_with_witness("rings", &surface, &samples, &queries, h, &mut worst);
    assert_eq!(compared, 2 * queries.len());
    // Heights alone: no query keeps the second scale.
    let config = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    let second = JetConfig::default().radius * h * std::f64::consts::SQRT_2;
    for r in surface.jet_at_points(&queries, &config, Parallelism::Rayon) {
        let r = r.unwrap();
        assert!(
            r.fit.radius > 1.01 * second,
            "radius {} at most {second}",
            r.fit.radius
        );
        assert!(r.curvature.k2.abs() < 1e-3, "k2 {}", r.curvature.k2);
    }
}

/// Where the ladder's first supports hold no slope they can fit (every normal within 2.3 h
/// leans about 70°, alternately either way, so that their mean is still upright) but the larger
/// ones do, the λ of 0 of the first fit the ladder keeps is not handed on: each later scale
/// weighs its slopes itself. Under noise the ladder climbs and a later scale is chosen, so a 0
/// handed on (heights only above the first scales) would move k away from the witness
/// (cargo-mutants' `l > 0` → `l >= 0` in `handed_slope_weight`).
#[test]
fn a_first_support_without_slopes_hands_no_noise_ratio_on() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0004);
    let n = 2500;
    let h = 2.0 / (n as f64).sqrt();
    let inner = 2.3 * h;
    let (points, mut normals) = patch(&mut rng, n, (5e-3, 0.02, 0.0, 0.0));
    for (i, (p, v)) in points.iter().zip(normals.iter_mut()).enumerate() {
        if p.x.hypot(p.y) < inner {
            let side = if i % 2 == 0 { 2.7 } else { -2.7 };
            *v = (*v + Vector::new(side, 0.0, 0.0)).normalize();
        }
    }
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
    let samples = samples_of(&points, &normals);
    let queries: Vec<Point> = (0..16)
        .map(|_| {
            let (x, y) = (
                rng.random_range(-0.1..0.1) * h,
                rng.random_range(-0.1..0.1) * h,
            );
            Point::new(x, y, height(x, y, 0.0).0)
        })
        .collect();
    let config = JetConfig::default();
    let mut later_with_slopes = 0;
    for (x, r) in queries
        .iter()
        .zip(surface.jet_at_points(&queries, &config, Parallelism::Rayon))
    {
        let j = r.unwrap();
        let w = mls_ad::jet_witness(&x.coords, &samples, h, &config).unwrap();
        assert_eq!(j.fit.radius, w.radius, "at {x:?}");
        if j.fit.radius > config.radius * h * 1.01 && w.slope_weight > 0.0 {
            later_with_slopes += 1;
        }
        let kappa = w.k1.abs().max(w.k2.abs()).max(1.0 / h);
        let tolerance = (1e3 * f64::EPSILON * w.condition).max(K_THRESHOLD);
        for (got, want) in [(j.curvature.k1, w.k1), (j.curvature.k2, w.k2)] {
            assert!(
                (got - want).abs() <= tolerance * kappa,
                "at {x:?}: {got} against {want} (radius {}, λ {} against {})",
                w.radius,
                j.fit.slope_weight,
                w.slope_weight
            );
        }
    }
    // The case the test is for: a chosen scale above the first, with slopes of its own.
    assert!(later_with_slopes >= 8, "{later_with_slopes} of 16");
}

/// The witness of `jet_at_points` at `x`: the anchors' blend where they share `x`
/// (`mls_ad::ShareWitness`), else the query's own jet.
fn witness(
    share: &mut mls_ad::ShareWitness<'_>,
    x: &Point,
    samples: &[Sample],
    h: f64,
    config: &JetConfig,
) -> Result<mls_ad::JetWitness, JetRefusal> {
    share
        .shared(&x.coords)
        .map_or_else(|| mls_ad::jet_witness(&x.coords, samples, h, config), Ok)
}

/// A standard normal deviate (Box–Muller).
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let (a, b): (f64, f64) = (rng.random(), rng.random());
    (-2.0 * (1.0 - a).ln()).sqrt() * (std::f64::consts::TAU * b).cos()
}

/// Asserts that the jet at `x` chose the witness's degree and radius and has its k1 and k2
/// within 1e-9 of max |k|; returns the larger relative difference.
fn same_choice_and_k(x: &Point, j: &mls_core::JetPoint, w: &mls_ad::JetWitness) -> f64 {
    assert_eq!(
        (j.fit.degree, j.fit.radius),
        (w.degree, w.radius),
        "at {x:?}: degree and radius"
    );
    let kappa = w.k1.abs().max(w.k2.abs());
    [(j.curvature.k1, w.k1), (j.curvature.k2, w.k2)]
        .into_iter()
        .map(|(got, want)| {
            let e = (got - want).abs() / kappa;
            assert!(e <= 1e-9, "at {x:?}: {got} against {want}");
            e
        })
        .fold(0.0, f64::max)
}

/// Heights only on a noisy sphere patch (radius 1, 2000 points on a cap of 0.5 rad, Gaussian
/// position noise of 0.2 spacings per coordinate, exact normals as the frame only): the
/// degree-2 candidates (`JetConfig::quadratic`, on supports of 3h to 8.5h with the leak of the
/// cubic and quartic terms predicted from a degree-4 fit on the largest) win at most queries,
/// and the jet agrees with its witness there as on the ladder: the same degree and radius, k1
/// and k2 within 1e-9 of max |k|, the predicted error (sd and the leak's bias) within
/// `SD_THRESHOLD`.
#[test]
fn degree_two_candidates_match_their_witness_on_a_noisy_sphere() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0005);
    let (n, cap) = (2000, 0.5f64);
    let spacing = (std::f64::consts::TAU * (1.0 - cap.cos()) / n as f64).sqrt();
    let h = 2.0 * spacing;
    let (points, normals): (Vec<Point>, Vec<Vector>) = (0..n)
        .map(|_| {
            // Uniform on the cap: cos θ uniform in [cos cap, 1].
            let z = rng.random_range(cap.cos()..1.0);
            let phi = rng.random_range(0.0..std::f64::consts::TAU);
            let r = (1.0 - z * z).sqrt();
            let normal = Vector::new(r * phi.cos(), r * phi.sin(), z);
            let noise = Vector::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng));
            (Point::from(normal + noise * (0.2 * spacing)), normal)
        })
        .unzip();
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
    let samples = samples_of(&points, &normals);
    // Every support (8.5h at most, 0.33) inside the cap: queries within 0.1 of the pole, half
    // of them samples, half points of the sphere.
    let queries: Vec<Point> = points
        .iter()
        .filter(|p| p.x.hypot(p.y) < 0.1)
        .take(25)
        .copied()
        .chain((0..25).map(|_| {
            let (x, y) = (rng.random_range(-0.07..0.07), rng.random_range(-0.07..0.07));
            Point::new(x, y, (1.0 - x * x - y * y).sqrt())
        }))
        .collect();
    assert_eq!(queries.len(), 50);
    let config = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    let (mut quadratic, mut worst_k, mut worst_error) = (0, 0.0f64, 0.0f64);
    let results = surface.jet_at_points(&queries, &config, Parallelism::Rayon);
    let mut share = mls_ad::ShareWitness::new(&samples, h, &config);
    for (x, r) in queries.iter().zip(results) {
        let j = r.unwrap();
        let w = witness(&mut share, x, &samples, h, &config).unwrap();
        worst_k = worst_k.max(same_choice_and_k(x, &j, &w));
        quadratic += usize::from(w.degree == 2);
        let pe = j.predicted_error();
        let we = [0, 1].map(|i| w.sd[i].hypot(w.bias[i]));
        let e = (pe[0] - we[0]).abs().max((pe[1] - we[1]).abs()) / we[0].max(we[1]);
        worst_error = worst_error.max(e);
        assert!(
            e <= SD_THRESHOLD,
            "at {x:?}: predicted error {pe:?} against {we:?}"
        );
        let foot = j.foot.coords - w.foot;
        assert!(foot.norm() <= 1e-9 * h, "at {x:?}: foot {foot:?}");
    }
    eprintln!(
        "degree 2 at {quadratic} of 50; worst k {worst_k:.2e} of max |k|, predicted error {worst_error:.2e}"
    );
    assert!(quadratic > 25, "degree 2 at {quadratic} of 50");
}

/// The noisy sphere of [`degree_two_candidates_match_their_witness_on_a_noisy_sphere`] with
/// stray samples: 2 % of the points (every 50th) moved along the normal by 3 to 10 spacings,
/// either way. Heights only, the degree-2 candidates' robust fit (Tukey's biweight from the
/// largest support's plain fit) flags a query beyond its cutoff as `PointStatus::Outlier` and
/// weighs the stray samples out of every other query's fits: jet_at and its witness agree on
/// which queries are outliers, and elsewhere on the degree, the radius and k (1e-9 of max |k|).
#[test]
fn outliers_and_robust_weights_match_their_witness_on_a_noisy_sphere() {
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed_0006);
    let (n, cap) = (2000, 0.5f64);
    let spacing = (std::f64::consts::TAU * (1.0 - cap.cos()) / n as f64).sqrt();
    let h = 2.0 * spacing;
    let mut stray = Vec::new();
    let (points, normals): (Vec<Point>, Vec<Vector>) = (0..n)
        .map(|i| {
            let z = rng.random_range(cap.cos()..1.0);
            let phi = rng.random_range(0.0..std::f64::consts::TAU);
            let r = (1.0 - z * z).sqrt();
            let normal = Vector::new(r * phi.cos(), r * phi.sin(), z);
            let noise = Vector::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng));
            let mut p = Point::from(normal + noise * (0.2 * spacing));
            if i % 20 == 0 {
                let side = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                p += normal * (side * rng.random_range(3.0..10.0) * spacing);
                stray.push(i);
            }
            (p, normal)
        })
        .unzip();
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
    let samples = samples_of(&points, &normals);
    // Queries within 0.15 of the pole: every stray sample there, inlier samples, and points of
    // the sphere (whose supports hold stray samples: the robust weights drop them).
    let near = |p: &Point| p.x.hypot(p.y) < 0.15;
    let strays: Vec<Point> = stray
        .iter()
        .map(|&i| points[i])
        .filter(|p| near(p))
        .collect();
    let queries: Vec<Point> = strays
        .iter()
        .copied()
        .chain(
            points
                .iter()
                .enumerate()
                .filter(|(i, p)| i % 20 != 0 && near(p))
                .take(20)
                .map(|(_, p)| *p),
        )
        .chain((0..20).map(|_| {
            let (x, y) = (rng.random_range(-0.07..0.07), rng.random_range(-0.07..0.07));
            Point::new(x, y, (1.0 - x * x - y * y).sqrt())
        }))
        .collect();
    assert!(strays.len() >= 4, "{} stray queries", strays.len());
    let config = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    let (mut flagged, mut stray_flagged, mut quadratic, mut worst_k) = (0, 0, 0, 0.0f64);
    let results = surface.jet_at_points(&queries, &config, Parallelism::Rayon);
    let mut share = mls_ad::ShareWitness::new(&samples, h, &config);
    for (i, (x, r)) in queries.iter().zip(results).enumerate() {
        let w = witness(&mut share, x, &samples, h, &config);
        let (j, w) = match (r, w) {
            (Ok(j), Ok(w)) => (j, w),
            (Err(PointStatus::Outlier), Err(JetRefusal::Outlier)) => {
                flagged += 1;
                stray_flagged += usize::from(i < strays.len());
                continue;
            }
            (r, w) => panic!("at {x:?} (query {i}): {r:?} against {w:?}"),
        };
        worst_k = worst_k.max(same_choice_and_k(x, &j, &w));
        quadratic += usize::from(w.degree == 2);
    }
    eprintln!(
        "{flagged} outliers flagged by both ({stray_flagged} of {} stray queries), degree 2 at \
         {quadratic} of {} others; worst k {worst_k:.2e} of max |k|",
        strays.len(),
        queries.len() - flagged
    );
    // The rule is exercised: most stray queries are flagged (the nearest ones, 3 spacings off
    // among noise of 0.2, may stay within the cutoff), and no query on the sphere is.
    assert!(
        2 * stray_flagged >= strays.len(),
        "{stray_flagged} of {}",
        strays.len()
    );
    assert_eq!(flagged, stray_flagged, "inlier queries flagged");
}
