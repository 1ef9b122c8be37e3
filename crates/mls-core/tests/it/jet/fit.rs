//! The jet's single fits and what a fit depends on: its reach, the degree its equations
//! determine, the samples it counts, degenerate layouts, rings, thin shells, either instruction
//! set, and the scale choice's bias estimate.

use mls_core::{JetConfig, MlsConfig, MlsSurface, NormalData, Parallelism, Point, Vector};
use mls_shapes::Torus;

use super::{SEED, cli_h};

/// A jet depends on the samples within `tiling::reach` of its query and on no others, which is
/// what lets the out-of-core run cut a cloud into tiles with halos of that width: on a noisy
/// torus (where the ladder climbs to its largest radius, whose fit enters the bias estimate
/// even when a smaller scale is chosen), each query's jet from only the samples within the
/// reach, in the whole cloud's frame, is bitwise the whole cloud's; within 0.99 of the reach,
/// some are not.
#[test]
fn a_jet_needs_exactly_the_samples_within_its_reach() {
    use mls_core::tiling::reach;
    use mls_core::{Cutoff, Frame};
    let torus = Torus::new(6.0, 2.0);
    let samples = mls_shapes::surface_points(&mls_shapes::random_area_uniform(&torus, 8_000, SEED));
    let clean: Vec<Point> = samples.iter().map(|s| s.point).collect();
    let h = cli_h(&clean);
    let points: Vec<Point> = mls_shapes::add_position_noise(&clean, 0.05 * h, SEED);
    let normals: Vec<Vector> = samples.iter().map(|s| s.normal).collect();
    let frame = Frame::of(&points);
    let config = JetConfig::default();
    let whole = MlsSurface::with_frame(&points, &normals, MlsConfig::new(h), frame).unwrap();
    let queries: Vec<Point> = points.iter().step_by(400).copied().collect();
    let expected = whole.jet_at_points(&queries, &config, Parallelism::Sequential);
    let r = reach(h, Cutoff::Radius(5.0), Some(&config), false).unwrap();
    let mut differ = 0;
    for (q, want) in queries.iter().zip(&expected) {
        for (fraction, must_equal) in [(1.0, true), (0.99, false)] {
            let (near, near_normals): (Vec<Point>, Vec<Vector>) = points
                .iter()
                .zip(&normals)
                .filter(|(p, _)| (*p - q).norm() <= fraction * r)
                .map(|(p, n)| (*p, *n))
                .unzip();
            let part =
                MlsSurface::with_frame(&near, &near_normals, MlsConfig::new(h), frame).unwrap();
            let got = part.jet_at_points(&[*q], &config, Parallelism::Sequential);
            if must_equal {
                assert_eq!(
                    &got[0], want,
                    "query {q:?}: the jet changed within its reach"
                );
            } else if &got[0] != want {
                differ += 1;
            }
        }
    }
    assert!(
        differ > 0,
        "no jet needed the samples between 0.99 and 1 of the reach"
    );
}

/// The degree a fit can afford: 1.5 equations per coefficient (`MIN_EQUATIONS_PER_COEFFICIENT`),
/// at its boundaries. Heights alone on an exact quartic: 23 samples determine degree 4 (22.5
/// equations needed), 22 only degree 3; 15 still degree 3 (15 needed), 14 only degree 2; 9
/// degree 2, 8 none. With slopes each sample brings three equations: 8 samples determine
/// degree 4 (24 ≥ 22.5).
#[test]
fn a_fit_takes_the_highest_degree_its_equations_determine() {
    use mls_core::Sample;
    use mls_core::jet::{JetScratch, fit, frame};
    use rand::{Rng, SeedableRng};
    let quartic = |u: f64, v: f64| {
        let z = 0.3 * u * u - 0.2 * u * v + 0.1 * v * v * v + 0.05 * u * u * u * v;
        let (zu, zv) = (
            0.6 * u - 0.2 * v + 0.15 * u * u * v,
            -0.2 * u + 0.3 * v * v + 0.05 * u * u * u,
        );
        (z, Vector::new(-zu, -zv, 1.0).normalize())
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(SEED);
    let mut cloud = |n: usize| -> Vec<Sample> {
        (0..n)
            .map(|_| {
                // Within 0.84 of the axis and 0.4 of the plane: inside the radius-1 support.
                let (r, t) = (
                    rng.random_range(0.05f64..0.7).sqrt(),
                    rng.random_range(0.0..std::f64::consts::TAU),
                );
                let (u, v) = (r * t.cos(), r * t.sin());
                let (z, normal) = quartic(u, v);
                Sample {
                    point: Point::new(u, v, z),
                    normal,
                }
            })
            .collect()
    };
    let frame = frame(&Vector::z());
    let mut scratch = JetScratch::default();
    let mut degree = |samples: &[Sample], normals: NormalData| {
        fit(
            samples,
            &Point::origin(),
            &frame,
            1.0,
            &JetConfig {
                normals,
                ..JetConfig::default()
            },
            None,
            &mut scratch,
        )
        .map(|f| (f.degree, f.equations))
    };
    for (n, want) in [
        (23, Some(4)),
        (22, Some(3)),
        (15, Some(3)),
        (14, Some(2)),
        (9, Some(2)),
        (8, None),
    ] {
        let got = degree(&cloud(n), NormalData::Ignore);
        assert_eq!(got.map(|g| g.0), want, "{n} heights: {got:?}");
    }
    assert_eq!(degree(&cloud(8), NormalData::Slopes), Some((4, 24)));
    assert_eq!(degree(&cloud(7), NormalData::Slopes), Some((3, 21)));
    // Normals more than 60° off the frame give heights but no slopes: 8 heights and one
    // sample's two slopes are 10 equations, enough for degree 2 (9).
    let mut few_slopes = cloud(8);
    for s in &mut few_slopes[1..] {
        s.normal = Vector::new(0.9, 0.0, 0.3).normalize();
    }
    assert_eq!(degree(&few_slopes, NormalData::Slopes), Some((2, 10)));
}

/// One fit at `radius` around the origin in the frame of +z, degree 4 asked.
fn fit_at(
    samples: &[mls_core::Sample],
    radius: f64,
    normals: NormalData,
) -> Option<mls_core::jet::JetFit> {
    use mls_core::jet::{JetScratch, fit, frame};
    fit(
        samples,
        &Point::origin(),
        &frame(&Vector::z()),
        radius,
        &JetConfig {
            normals,
            ..JetConfig::default()
        },
        None,
        &mut JetScratch::default(),
    )
}

/// `n` samples of the height field `z(u, v)` at random within 0.84 of the axis, with the
/// normals of `z` (`gradient` gives ∂z/∂u, ∂z/∂v).
fn height_field(
    n: usize,
    seed: u64,
    z: impl Fn(f64, f64) -> f64,
    gradient: impl Fn(f64, f64) -> (f64, f64),
) -> Vec<mls_core::Sample> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let (r, t) = (
                rng.random_range(0.05f64..0.7).sqrt(),
                rng.random_range(0.0..std::f64::consts::TAU),
            );
            let (u, v) = (r * t.cos(), r * t.sin());
            let (zu, zv) = gradient(u, v);
            mls_core::Sample {
                point: Point::new(u, v, z(u, v)),
                normal: Vector::new(-zu, -zv, 1.0).normalize(),
            }
        })
        .collect()
}

#[test]
fn a_fit_counts_only_the_samples_it_weighs_and_whose_normals_face_it() {
    let plane = |n| height_field(n, SEED, |u, _| 0.1 * u, |_, _| (0.1, 0.0));
    let degree =
        |s: &[mls_core::Sample], data| fit_at(s, 1.0, data).map(|f| (f.degree, f.equations));
    assert_eq!(degree(&plane(22), NormalData::Ignore), Some((3, 22)));
    // On the support's boundary the weight is 0: not an equation.
    let mut boundary = plane(22);
    boundary.push(mls_core::Sample {
        point: Point::new(1.0, 0.0, 0.0),
        normal: Vector::z(),
    });
    assert_eq!(degree(&boundary, NormalData::Ignore), Some((3, 22)));
    // A normal at exactly 90° to the frame: another sheet, left out.
    let mut edge_on = plane(22);
    edge_on.push(mls_core::Sample {
        point: Point::new(0.1, 0.2, 0.01),
        normal: Vector::x(),
    });
    assert_eq!(degree(&edge_on, NormalData::Ignore), Some((3, 22)));
    // A normal at exactly 60° gives a height but no slopes: 7 samples with slopes (21
    // equations) and this one's height are 22, short of degree 4's 22.5.
    let mut sixty = plane(7);
    sixty.push(mls_core::Sample {
        point: Point::new(0.1, 0.2, 0.01),
        normal: Vector::new(0.75f64.sqrt(), 0.0, 0.5),
    });
    assert_eq!(degree(&sixty, NormalData::Slopes), Some((3, 22)));
}

#[test]
fn a_degenerate_layout_falls_back_to_the_degree_it_determines() {
    // Heights on two circles: (u² + v² − a²)(u² + v² − b²) vanishes on every sample, so
    // degree 4 is not determined although 40 equations would afford it; degree 3 is. The
    // cubic is recovered exactly.
    let cubic = |u: f64, v: f64| 0.3 * u * u - 0.2 * u * v + 0.1 * v * v * v + 0.05 * u * u * u;
    let samples: Vec<mls_core::Sample> = (0..40)
        .map(|i| {
            let r = if i % 2 == 0 { 0.4 } else { 0.75 };
            let t = 0.37 + i as f64 * std::f64::consts::TAU / 40.0 * 1.7;
            let (u, v) = (r * t.cos(), r * t.sin());
            mls_core::Sample {
                point: Point::new(u, v, cubic(u, v)),
                normal: Vector::z(),
            }
        })
        .collect();
    let fit = fit_at(&samples, 1.0, NormalData::Ignore).expect("degree 3 is determined");
    assert_eq!(fit.degree, 3);
    let want = [0.0, 0.0, 0.0, 0.3, -0.2, 0.0, 0.05, 0.0, 0.0, 0.1];
    for (k, (&got, &want)) in fit.coefficients.iter().zip(&want).enumerate() {
        assert!(
            (got - want).abs() < 1e-10,
            "coefficient {k}: {got} vs {want}"
        );
    }
}

#[test]
fn the_noise_estimate_is_in_the_files_units() {
    // A plane with heights off by ±σ, alternately: σ̂ ≈ σ whatever the support radius.
    use rand::{Rng, SeedableRng};
    let sigma = 0.003;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(SEED);
    let radius = 2.5;
    let samples: Vec<mls_core::Sample> = height_field(400, SEED, |_, _| 0.0, |_, _| (0.0, 0.0))
        .into_iter()
        .map(|s| mls_core::Sample {
            point: Point::new(
                s.point.x * radius,
                s.point.y * radius,
                if rng.random_bool(0.5) { sigma } else { -sigma },
            ),
            ..s
        })
        .collect();
    let fit = fit_at(&samples, radius, NormalData::Ignore).unwrap();
    assert!(
        (fit.noise / sigma - 1.0).abs() < 0.15,
        "σ̂ = {} for σ = {sigma}",
        fit.noise
    );
}

#[test]
fn slopes_asked_where_no_normal_gives_one_is_the_heights_only_fit() {
    // Every normal more than 60° off the frame: heights only, whatever was asked, and the
    // same numbers (a slope block of zeros must not switch on the slopes' noise model).
    let samples: Vec<mls_core::Sample> = height_field(
        40,
        SEED,
        |u, v| 0.2 * u * u - 0.1 * v * v * v,
        |u, v| (0.4 * u, -0.3 * v * v),
    )
    .into_iter()
    .map(|s| mls_core::Sample {
        normal: Vector::new(0.9, 0.1, 0.3).normalize(),
        ..s
    })
    .collect();
    let slopes = fit_at(&samples, 1.0, NormalData::Slopes).unwrap();
    let heights = fit_at(&samples, 1.0, NormalData::Ignore).unwrap();
    assert_eq!(slopes, heights);
}

#[test]
fn an_exact_plane_with_exact_normals_is_flat() {
    // Every residual is exactly 0, so are both noise estimates: the slopes' weight must not
    // become 0/0 (a machined face sampled without noise is a real cloud).
    let plane = height_field(60, SEED, |_, _| 0.0, |_, _| (0.0, 0.0));
    assert!(
        plane
            .iter()
            .all(|s| s.point.z == 0.0 && s.normal == Vector::z())
    );
    let fit = fit_at(&plane, 1.0, NormalData::Slopes).expect("a plane is determined");
    assert_eq!(fit.degree, 4);
    assert!(
        fit.coefficients.iter().all(|&c| c == 0.0),
        "{:?}",
        fit.coefficients
    );
    assert_eq!(fit.noise, 0.0);
}

#[test]
fn a_nearly_degenerate_layout_is_judged_by_its_relative_pivots() {
    // Heights on two circles pulled apart by δ: degree 4 is determined in exact arithmetic,
    // but with a squared Cholesky pivot below 1e-10 of the largest diagonal entry, or below
    // `DETERMINED_PIVOT` of its own, it is not trusted (`jet::fit`), and degree 3 is fitted.
    // The pivots are computed here independently (nalgebra) from the weighted monomials of
    // the samples.
    use mls_core::jet::{DETERMINED_PIVOT, MONOMIALS};
    let layout = |delta: f64| -> Vec<mls_core::Sample> {
        (0..40)
            .map(|i| {
                let t = 0.37 + i as f64 * std::f64::consts::TAU / 40.0 * 1.7;
                let r = if i % 2 == 0 { 0.4 } else { 0.75 } + delta * (3.0 * t).sin();
                mls_core::Sample {
                    point: Point::new(r * t.cos(), r * t.sin(), 0.0),
                    normal: Vector::z(),
                }
            })
            .collect()
    };
    // The smallest squared pivot against the largest diagonal entry, and against its own.
    let relative_pivots = |samples: &[mls_core::Sample]| {
        let mut m = nalgebra::SMatrix::<f64, 15, 15>::zeros();
        for s in samples {
            let (u, v) = (s.point.x, s.point.y);
            let w = (1.0 - u * u - v * v).powi(3);
            let phi = nalgebra::SVector::<f64, 15>::from_fn(|k, _| {
                let (i, j) = MONOMIALS[k];
                u.powi(i) * v.powi(j)
            });
            m += phi * phi.transpose() * w;
        }
        let l = m.cholesky().expect("positive definite").l();
        let pivot = |i: usize| l[(i, i)] * l[(i, i)];
        let to_largest = (0..15).map(pivot).fold(f64::INFINITY, f64::min) / m.diagonal().max();
        let to_own = (0..15)
            .map(|i| pivot(i) / m[(i, i)])
            .fold(f64::INFINITY, f64::min);
        (to_largest, to_own)
    };
    let (mut below_largest, mut below_own) = (0, 0);
    for k in 0..28 {
        let delta = 10f64.powf(-(k as f64) / 4.0 - 1.0);
        let samples = layout(delta);
        let (to_largest, to_own) = relative_pivots(&samples);
        // Within a factor 2 of a threshold, rounding may decide either way.
        if (to_largest / 1e-10).log2().abs() < 1.0 || (to_own / DETERMINED_PIVOT).log2().abs() < 1.0
        {
            continue;
        }
        let determined = to_largest > 1e-10 && to_own > DETERMINED_PIVOT;
        let want = if determined { 4 } else { 3 };
        below_largest += usize::from((1e-12..1e-10).contains(&to_largest));
        below_own += usize::from(
            to_largest > 1e-10 && (DETERMINED_PIVOT / 100.0..DETERMINED_PIVOT).contains(&to_own),
        );
        let got = fit_at(&samples, 1.0, NormalData::Ignore).map(|f| f.degree);
        assert_eq!(
            got,
            Some(want),
            "δ = {delta:e}: relative pivots {to_largest:e}, {to_own:e}"
        );
    }
    assert!(
        below_largest > 0,
        "no layout just below the first threshold"
    );
    assert!(
        below_own > 0,
        "no layout decided by the pivot against its own entry alone"
    );
}

/// A cylinder sampled as a profile scanner sees it: rings 6.5 times farther apart than the
/// points along each, with estimated normals. Their frame is tilted by a few thousandths, so
/// on a support of three rings the terms that vanish on those rings are nearly, not exactly,
/// free; fitted to heights alone, they gave k2 ≈ 0.9 with a predicted error that stopped the
/// climb (RMS k1 error 3.1e-2, k2 1.3e-1 over the middle rings). Degree 4 now waits for a
/// support that determines it: 6.1e-5 and 1.3e-6 (6.5e-5 before the spacing measured its
/// one-line neighbourhoods again, which moved h from 0.0801 to 0.0787).
#[test]
fn rings_farther_apart_than_their_points_give_the_cylinders_curvature() {
    use mls_core::normals::{NormalsConfig, estimate_normals};
    let (around, along, length) = (400, 40, 4.0);
    let mut points = Vec::new();
    for i in 0..around {
        let a = i as f64 * std::f64::consts::TAU / around as f64;
        for j in 0..along {
            let z = j as f64 * length / (along - 1) as f64 - length / 2.0;
            points.push(Point::new(a.cos(), a.sin(), z));
        }
    }
    let h = cli_h(&points);
    let config = NormalsConfig {
        h: Some(h),
        ..NormalsConfig::default()
    };
    let estimated = estimate_normals(&points, &config, Parallelism::Rayon).unwrap();
    let normals: Vec<Vector> = estimated
        .normals()
        .into_iter()
        .map(|n| n.expect("every ring point has a normal"))
        .collect();
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
    let config = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    // The middle rings: the support reaches at most 0.5 along the axis.
    let middle: Vec<Point> = points.iter().filter(|p| p.z.abs() < 1.5).copied().collect();
    let results = surface.jet_at_points(&middle, &config, Parallelism::Rayon);
    let (mut e1, mut e2) = (0.0, 0.0);
    for r in &results {
        let r = r.as_ref().expect("every point has a jet");
        e1 += (r.curvature.k1 - 1.0).powi(2);
        e2 += r.curvature.k2.powi(2);
    }
    let n = results.len() as f64;
    let (e1, e2) = ((e1 / n).sqrt(), (e2 / n).sqrt());
    assert!(
        e1 < 1e-3 && e2 < 1e-3,
        "RMS k1 error {e1:e}, k2 error {e2:e}"
    );
}

/// The fit is compiled for the baseline and for AVX2 (`mls_core::kernels`); neither fuses a
/// multiply with an add, so both give the same bits, with all slopes, with some, and without.
#[test]
fn the_fit_gives_the_same_bits_with_either_instruction_set() {
    use mls_core::kernels::set_portable_kernels;
    let mut samples = height_field(
        300,
        SEED,
        |u, v| 0.3 * u * u - 0.2 * v * v + 0.1 * u * u * u * v,
        |u, v| (0.6 * u + 0.3 * u * u * v, -0.4 * v + 0.1 * u * u * u),
    );
    let all_slopes = samples.clone();
    // Normals past 60° from the frame give a height and no slope.
    for s in samples.iter_mut().step_by(7) {
        s.normal = Vector::new(0.9, 0.0, 0.3).normalize();
    }
    let fits = |portable: bool| {
        set_portable_kernels(portable);
        let fits: Vec<_> = [&all_slopes, &samples]
            .into_iter()
            .flat_map(|s| {
                [0.3, 0.6, 0.84]
                    .into_iter()
                    .flat_map(|r| [NormalData::Slopes, NormalData::Ignore].map(|d| fit_at(s, r, d)))
            })
            .collect();
        set_portable_kernels(false);
        fits
    };
    let (best, portable) = (fits(false), fits(true));
    assert!(best.iter().all(Option::is_some));
    // Debug prints each f64 in its shortest round-trip form: equal text is equal bits.
    assert_eq!(format!("{best:?}"), format!("{portable:?}"));
}

/// A shell thinner than its sampling: two concentric spheres 0.62 spacings apart, each with its
/// own outward-facing normals (away from the material between them). A fit across both sheets
/// has heights ±gap within a spacing, a curvature error of order gap/spacing² ≈ 10 (measured
/// up to 1e3 before the frame looked at the nearest sample's normal: averaged over both
/// sheets, it turned over at 9 % of the points). Kept on its own sheet, with a frame within 60°
/// of its normal, a fit errs by a few 1e-2 at most (measured: RMS 6.5e-4, max 2.5e-2).
#[test]
fn a_shell_thinner_than_its_spacing_keeps_its_sheets_apart() {
    use mls_shapes::Sphere;

    let per_sheet = 4000;
    let (outer, inner) = (1.0, 0.965);
    let spacing = (4.0 * std::f64::consts::PI / per_sheet as f64).sqrt();
    assert!(outer - inner < 0.7 * spacing, "spacing {spacing}");
    let sheet = |radius: f64, seed: u64, sign: f64| -> Vec<(Point, Vector, f64)> {
        let sphere = Sphere::centered(radius);
        mls_shapes::surface_points(&mls_shapes::random_area_uniform(&sphere, per_sheet, seed))
            .iter()
            .map(|s| (s.point, s.normal * sign, sign / radius))
            .collect()
    };
    let all: Vec<(Point, Vector, f64)> = sheet(outer, SEED, 1.0)
        .into_iter()
        .chain(sheet(inner, SEED + 1, -1.0))
        .collect();
    let points: Vec<Point> = all.iter().map(|a| a.0).collect();
    let normals: Vec<Vector> = all.iter().map(|a| a.1).collect();
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(2.0 * spacing)).unwrap();
    let results = surface.jet_at_points(&points, &JetConfig::default(), Parallelism::Rayon);
    let mut worst: f64 = 0.0;
    let mut sum2 = 0.0;
    for (r, (p, n, k)) in results.iter().zip(&all) {
        let r = r.as_ref().expect("every shell point has a jet");
        assert!(
            r.curvature.normal.dot(n) > 0.99,
            "at {p}: normal {} against the sheet's {n}",
            r.curvature.normal
        );
        let e = (r.curvature.k1 - k).abs().max((r.curvature.k2 - k).abs());
        worst = worst.max(e);
        sum2 += e * e;
    }
    let rms = (sum2 / all.len() as f64).sqrt();
    eprintln!("shell: curvature error RMS {rms:.2e}, max {worst:.2e}");
    assert!(
        worst < 0.1,
        "curvature error up to {worst:.2e} (RMS {rms:.2e})"
    );
}

/// The bias a chosen point carries is the unbiased estimate `t √max(c² − var c, 0)` of the
/// line through the ladder; the choice itself weighs the cautious `t √(c² + var c)`. Two fits
/// at ρ and √2 ρ (t = 1 and 4) with sd 0.05: k1 steps by 0.3, so c = 0.1 and
/// var c = 2 · 0.05² / 3², giving a bias of √(0.01 − 0.0025/4.5) at the first; k2 steps by
/// 0.01, less than its own scatter, so its bias is 0 (the cautious form would say 0.024).
#[test]
fn the_chosen_scale_carries_the_unbiased_bias_estimate() {
    use mls_core::jet::choose_scale;
    use mls_core::{Curvature, JetFit, JetPoint, Matrix};

    let point = |radius: f64, k1: f64, k2: f64| JetPoint {
        foot: Point::origin(),
        curvature: Curvature {
            normal: Vector::z(),
            k1,
            k2,
            mean: 0.5 * (k1 + k2),
            gauss: k1 * k2,
            d1: Vector::x(),
            d2: Vector::y(),
        },
        sd: [0.05; 2],
        bias: [0.0; 2],
        fit: JetFit {
            degree: 4,
            radius,
            neighbours: 100,
            equations: 100,
            coefficients: [0.0; 15],
            noise: 0.0,
            covariance: Matrix::zeros(),
            slope_weight: 0.0,
        },
    };
    let ladder = [
        point(1.0, 1.0, 0.5),
        point(std::f64::consts::SQRT_2, 1.3, 0.51),
    ];
    let chosen = choose_scale(&ladder, 2);
    assert_eq!(chosen.fit.radius, 1.0);
    let var_c = 2.0 * 0.05 * 0.05 / 9.0;
    let want = (0.1f64 * 0.1 - var_c).sqrt();
    assert!(
        (chosen.bias[0] - want).abs() < 1e-12,
        "k1 bias {}",
        chosen.bias[0]
    );
    assert_eq!(chosen.bias[1], 0.0);
    let [e1, e2] = chosen.predicted_error();
    assert!((e1 - 0.05f64.hypot(want)).abs() < 1e-12 && e2 == 0.05);
}
