//! Unit tests of the ladder's private algebra: scales, the failure paths of `advance`, the
//! noise estimate on a scan line and the shrinkage correction.

use super::*;

/// An estimate of a unit sphere at scale `h`.
fn sphere_estimate(h: f64) -> Estimate {
    let (n, x, y) = (Vector::z(), Vector::x(), Vector::y());
    Estimate {
        h,
        point: Point::new(0.0, 0.0, 1.0),
        curvature: Curvature {
            normal: n,
            k1: 1.0,
            k2: 1.0,
            mean: 1.0,
            gauss: 1.0,
            d1: x,
            d2: y,
        },
        unit_scatter: 1.0,
    }
}

#[test]
fn a_failure_ends_the_ladder_at_the_scales_before_it_or_tries_larger_ones() {
    // A scale fails after one estimate: that estimate is chosen, without a partner, and
    // the point is done (a larger h would only include more of what made this one fail).
    let mut state = State {
        estimates: vec![sphere_estimate(0.1)],
        ..State::default()
    };
    advance(&mut state, Err(PointStatus::NormalUndefined), 2.0, false);
    assert_eq!(
        (state.chosen, state.partner, state.done),
        (Some(0), None, true)
    );
    assert_eq!(state.failure, None);
    // After two, the last is chosen and the one before is its partner.
    let mut state = State {
        estimates: vec![sphere_estimate(0.1), sphere_estimate(0.14)],
        ..State::default()
    };
    advance(&mut state, Err(PointStatus::GradientVanishes), 2.0, false);
    assert_eq!(
        (state.chosen, state.partner, state.done),
        (Some(1), Some(0), true)
    );
    // A failure before any estimate: a larger h may still reach enough samples.
    let mut state = State::default();
    advance(&mut state, Err(PointStatus::TooFewNeighbours), 2.0, false);
    assert_eq!((state.chosen, state.done), (None, false));
    assert_eq!(state.failure, Some(PointStatus::TooFewNeighbours));
    advance(&mut state, Err(PointStatus::NoNeighbours), 2.0, true);
    assert!(state.done);
}

#[test]
fn samples_on_a_line_give_the_offset_only_noise_estimate() {
    // A scan line: the cubic in (u, v) is not determined, and σ is the weighted spread of
    // the heights about their weighted mean, with its own degrees of freedom,
    // Σw − Σw²/Σw; a line of three samples has too few and gives 0.
    let h = 0.1;
    let heights = |i: usize| 0.01 * (((i * 7919) % 13) as f64 / 6.0 - 1.0);
    let line = |n: usize| -> Vec<Point> {
        (0..n)
            .map(|i| Point::new((i as f64 - (n / 2) as f64) * 0.02, 0.0, heights(i)))
            .collect()
    };
    let flat = Curvature {
        normal: Vector::z(),
        k1: 0.0,
        k2: 0.0,
        mean: 0.0,
        gauss: 0.0,
        d1: Vector::x(),
        d2: Vector::y(),
    };
    // With `m` samples in the window, an estimate needs more than MIN_DOF samples' worth
    // of degrees of freedom, `dof > 3 Σw/m`; lines of 3 to 12 samples cross that bound.
    let mut near_the_bound = 0;
    for n in (3..=12).chain([41]) {
        let points = line(n);
        let normals = vec![Vector::z(); n];
        let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
        let mut ev = surface.evaluator();
        let got = residual_noise(&mut ev, &Point::origin(), &flat, h);
        let window: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.coords.norm() <= NOISE_WINDOW * h)
            .map(|p| ((-p.coords.norm_squared() / (h * h)).exp(), p.z))
            .collect();
        let m = window.len() as f64;
        let sw: f64 = window.iter().map(|(w, _)| w).sum();
        let mean = window.iter().map(|(w, z)| w * z).sum::<f64>() / sw;
        let spread: f64 = window.iter().map(|(w, z)| w * (z - mean).powi(2)).sum();
        let dof = sw - window.iter().map(|(w, _)| w * w).sum::<f64>() / sw;
        near_the_bound += usize::from(dof > MIN_DOF * sw / m && dof < MIN_DOF + sw / m);
        if dof > MIN_DOF * sw / m {
            let want = (spread / dof).sqrt();
            assert!(
                (got - want).abs() < 1e-12 * want,
                "{n}: σ {got} against {want}"
            );
        } else {
            assert_eq!(got, 0.0, "{n} samples, {dof} degrees of freedom");
        }
    }
    assert!(near_the_bound > 0);
}

#[test]
fn the_shrinkage_correction_undoes_the_parallel_surface() {
    // A surface of curvatures 2 and 0.5 seen through an MLS surface of scale h lying
    // δ = (k1 + k2) h²/4 inside it, whose curvatures are k/(1 − kδ).
    let h = 0.1;
    let (k1, k2) = (2.0, 0.5);
    let delta = (k1 + k2) * h * h / 4.0;
    let (m1, m2) = (k1 / (1.0 - k1 * delta), k2 / (1.0 - k2 * delta));
    let measured = Curvature {
        normal: Vector::z(),
        k1: m1,
        k2: m2,
        mean: 0.5 * (m1 + m2),
        gauss: m1 * m2,
        d1: Vector::x(),
        d2: Vector::y(),
    };
    let c = correct_shrinkage(&measured, h);
    // First order (δ is taken from the measured curvatures): all but O((kδ)²) of the
    // shrinkage's bias goes.
    for (got, want, measured) in [(c.k1, k1, m1), (c.k2, k2, m2)] {
        assert!(
            (got - want).abs() < 0.05 * (measured - want).abs(),
            "{got} against {want} (measured {measured})"
        );
    }
    // Exactly the documented formula, and a consistent result.
    let d = 0.5 * measured.mean * h * h;
    assert_eq!((c.k1, c.k2), (m1 / (1.0 + m1 * d), m2 / (1.0 + m2 * d)));
    assert_eq!((c.mean, c.gauss), (0.5 * (c.k1 + c.k2), c.k1 * c.k2));
    assert_eq!(
        (c.normal, c.d1, c.d2),
        (measured.normal, measured.d1, measured.d2)
    );
}

#[test]
fn the_ladder_runs_from_h_min_by_root_two() {
    let c = AdaptiveConfig::new(0.5);
    assert_eq!(c.scale(0), 0.5);
    assert!((c.scale(3) / c.scale(1) - 2.0).abs() < 1e-15);
    // Five scales: the largest is 4 h_min, as the summary says.
    assert!((c.h_max() - 2.0).abs() < 1e-15, "{}", c.h_max());
    // At least two scales, whatever is asked.
    for scales in [0, 1, 2] {
        let c = AdaptiveConfig { scales, ..c };
        assert!(
            (c.h_max() - 0.5 * SCALE_RATIO).abs() < 1e-15,
            "{scales} scales"
        );
    }
}

/// A grid plane z = 0 with Gaussian noise in z, exact normals: all curvature is noise.
fn noisy_plane(n: usize, spacing: f64, sigma: f64, seed: u64) -> Vec<Point> {
    // A small LCG + Box–Muller keeps the test free of extra dependencies.
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
    let mut uniform = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut out = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let g = (-2.0 * uniform().ln()).sqrt() * (2.0 * std::f64::consts::PI * uniform()).cos();
            out.push(Point::new(
                i as f64 * spacing,
                j as f64 * spacing,
                sigma * g,
            ));
        }
    }
    out
}

#[test]
fn noise_gain_matches_a_noisy_plane() {
    let (n, spacing, sigma) = (120, 1.0, 0.05);
    let points = noisy_plane(n, spacing, sigma, 3);
    let normals = vec![Vector::z(); points.len()];
    let centre = 0.5 * (n - 1) as f64 * spacing;
    for factor in [2.0, 3.0, 4.0] {
        let h = factor * spacing;
        let surface = MlsSurface::new(&points, &normals, MlsConfig::new(h)).unwrap();
        let queries: Vec<Point> = points
            .iter()
            .filter(|p| (p.x - centre).abs().max((p.y - centre).abs()) < centre - 6.0 * h)
            .copied()
            .collect();
        let mut ev = surface.evaluator();
        let (mut sum_sq, mut predicted, mut noise) = (0.0, 0.0, 0.0);
        for q in &queries {
            let r = ev.curvature_at(q).unwrap();
            // The mean curvature averages the two normal sections: per-section scatter
            // is √2 times its own.
            sum_sq += 2.0 * r.curvature.mean * r.curvature.mean;
            let wsum = r.implicit.weight_sum * (-r.implicit.log_scale).exp();
            predicted += 1.0 / (h * h * (2.0 * wsum).sqrt());
            noise += residual_noise(&mut ev, q, &r.curvature, h);
        }
        let m = queries.len() as f64;
        let gain = (sum_sq / m).sqrt() / (sigma * predicted / m);
        assert!(
            (gain / NOISE_GAIN - 1.0).abs() < 0.15,
            "h = {factor} spacings: measured gain {gain}"
        );
        // The residual estimate recovers σ.
        let estimated = noise / m;
        assert!(
            (estimated / sigma - 1.0).abs() < 0.05,
            "h = {factor} spacings: σ estimated {estimated}, true {sigma}"
        );
    }
}
