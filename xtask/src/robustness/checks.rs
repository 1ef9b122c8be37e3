//! The checks of one adversarial cloud: the surface built from it (or the construction error
//! it must give), evaluated at its points, at probes and at non-finite queries; compared with
//! its base cloud when it is translated, scaled or duplicated; and its normals estimated and
//! run through the whole pipeline. Each broken property is a failure in the [`Outcome`].

use mls_core::InputError;
use mls_core::normals::{NormalsConfig, NormalsError, estimate_normals};
use mls_core::{
    ConfigError, Cutoff, MlsConfig, MlsSurface, Parallelism, Point, PointResult, PointStatus,
    Vector,
};
use mls_shapes::adversarial::{AdversarialClass, AdversarialCloud, Expectation, ProbeKind};

use super::{FLAT_TOLERANCE, MAX_PROJECTED, OFFSET_TOLERANCE, Outcome, SIMILAR_TOLERANCE};

/// The surface parameters of a cloud.
pub(crate) fn config_of(cloud: &AdversarialCloud) -> MlsConfig {
    MlsConfig {
        cutoff: cloud.cutoff.map_or(Cutoff::None, Cutoff::Radius),
        ..MlsConfig::new(cloud.h)
    }
}

/// Two queries every surface must reject as `InvalidQuery`.
const NON_FINITE_QUERIES: [[f64; 3]; 2] = [[f64::NAN, 0.0, 0.0], [0.0, f64::NEG_INFINITY, 1.0]];

pub(super) fn check_cloud(cloud: &AdversarialCloud, out: &mut Outcome) {
    // Alternate the two entry points; rayon inside rayon is fine.
    let par = if cloud.seed.is_multiple_of(8) {
        Parallelism::Rayon
    } else {
        Parallelism::Sequential
    };
    check_surface(cloud, par, out);
    check_normals(cloud, par, out);
}

fn check_surface(cloud: &AdversarialCloud, par: Parallelism, out: &mut Outcome) {
    let built = MlsSurface::new(&cloud.points, &cloud.normals, config_of(cloud));
    let surface = match (&cloud.expectation, built) {
        (
            Expectation::NonFinitePoint { index },
            Err(ConfigError::Input(InputError::NonFinitePoint { index: got })),
        ) if got == *index => {
            out.construction_error = Some("NonFinitePoint");
            return;
        }
        (Expectation::BadNormal { index }, Err(ConfigError::BadNormal { index: got, .. }))
            if got == *index =>
        {
            out.construction_error = Some("BadNormal");
            return;
        }
        (Expectation::NonFinitePoint { .. } | Expectation::BadNormal { .. }, other) => {
            out.failures.push(format!(
                "expected {:?} at construction, got {:?}",
                cloud.expectation,
                other.map(|_| "a surface")
            ));
            return;
        }
        (_, Err(e)) => {
            out.failures.push(format!("construction failed: {e}"));
            return;
        }
        (_, Ok(surface)) => surface,
    };

    let mut queries = cloud.points.clone();
    queries.extend(cloud.probes.iter().map(|p| p.point));
    queries.extend(NON_FINITE_QUERIES.map(Point::from));
    let curvature = surface.curvature_at_points(&queries, par);
    let projected_queries = projection_subset(cloud, &queries);
    let projection = surface.project_points(&projected_queries, par);

    for (label, asked, results, counts) in [
        ("curvature", &queries, &curvature, &mut out.curvature),
        (
            "projection",
            &projected_queries,
            &projection,
            &mut out.projection,
        ),
    ] {
        for (q, r) in asked.iter().zip(results) {
            count(counts, r);
            if let Some(problem) = invalid_result(r, label == "projection") {
                out.failures.push(format!("{label} at {q:?}: {problem}"));
            }
        }
        // The last two queries are the non-finite ones.
        for r in &results[results.len() - 2..] {
            if *r != Err(PointStatus::InvalidQuery) {
                out.failures
                    .push(format!("{label} at a non-finite query: {r:?}"));
            }
        }
    }
    check_probes(cloud, &curvature[cloud.points.len()..], &projection, out);

    match &cloud.expectation {
        Expectation::Flat => {
            let worst = curvature
                .iter()
                .chain(&projection)
                .flatten()
                .map(|s| {
                    let c = s.curvature;
                    // gauss, not √gauss: its rounding error is ε|H|²/|∇g|², and H is large
                    // across the plane even where it vanishes along it.
                    (c.k1.abs().max(c.k2.abs()) * cloud.h).max(c.gauss.abs() * cloud.h * cloud.h)
                })
                .fold(0.0, f64::max);
            out.flat = Some(worst);
            if !(worst <= FLAT_TOLERANCE) {
                out.failures
                    .push(format!("flat cloud bends: |k|·h = {worst:e}"));
            }
        }
        Expectation::Matches {
            base,
            scale,
            offset,
        } => check_match(cloud, &surface, base, *scale, offset, par, out),
        _ => {}
    }
}

/// The queries projected: every point of a small cloud, else a stride through them, then the
/// probes and the non-finite queries.
fn projection_subset(cloud: &AdversarialCloud, queries: &[Point]) -> Vec<Point> {
    let n = cloud.points.len();
    let stride = n.div_ceil(MAX_PROJECTED).max(1);
    let mut subset: Vec<Point> = cloud.points.iter().step_by(stride).copied().collect();
    subset.extend_from_slice(&queries[n..]);
    subset
}

fn count(counts: &mut [u64; 8], r: &PointResult) {
    let code = r.as_ref().map_or_else(|s| s.code() as usize, |_| 0);
    counts[code.min(7)] += 1;
}

/// What is wrong with one result, if anything: a non-finite number in an `Ok` result, a
/// broken invariant (unit normal, `k1 ≥ k2`, `mean = (k1 + k2)/2`), or a status the entry
/// point cannot return.
pub(crate) fn invalid_result(r: &PointResult, projection: bool) -> Option<String> {
    match r {
        Ok(s) => {
            let c = &s.curvature;
            let vectors = [s.point.coords, c.normal, c.d1, c.d2];
            let scalars = [c.k1, c.k2, c.mean, c.gauss];
            if !(vectors.iter().all(|v| v.iter().all(|x| x.is_finite()))
                && scalars.iter().all(|x| x.is_finite()))
            {
                return Some(format!("non-finite value in an Ok result: {s:?}"));
            }
            if !((c.normal.norm() - 1.0).abs() < 1e-9 && c.k1 >= c.k2) {
                return Some(format!("broken invariant (|n| = 1, k1 ≥ k2): {c:?}"));
            }
            let scale = c.k1.abs().max(c.k2.abs());
            if !((c.mean - 0.5 * (c.k1 + c.k2)).abs() <= 1e-12 * scale) {
                return Some(format!("mean is not (k1 + k2)/2: {c:?}"));
            }
            None
        }
        Err(PointStatus::NormalEstimationFailed) => {
            Some("status normal_estimation_failed from the surface".to_owned())
        }
        Err(PointStatus::ProjectionFailed) if !projection => {
            Some("status projection_failed without projection".to_owned())
        }
        Err(_) => None,
    }
}

/// Probes: no sample within twice the support gives `NoNeighbours`; a sample alone gives
/// `TooFewNeighbours`; the mirror plane of opposite sheets gives `NormalUndefined`, with and
/// without projection.
fn check_probes(
    cloud: &AdversarialCloud,
    curvature: &[PointResult],
    projection: &[PointResult],
    out: &mut Outcome,
) {
    let projected_probes = &projection[projection.len() - 2 - cloud.probes.len()..];
    for ((probe, c), p) in cloud.probes.iter().zip(curvature).zip(projected_probes) {
        let expected = match probe.kind {
            ProbeKind::Void => PointStatus::NoNeighbours,
            ProbeKind::Alone => PointStatus::TooFewNeighbours,
            ProbeKind::Cancelling => PointStatus::NormalUndefined,
        };
        if *c != Err(expected) {
            out.failures
                .push(format!("{probe:?}: curvature {c:?}, expected {expected}"));
        }
        if probe.kind == ProbeKind::Cancelling && *p != Err(expected) {
            out.failures
                .push(format!("{probe:?}: projection {p:?}, expected {expected}"));
        }
    }
}

/// The cloud is `base` mapped by `x ↦ s x + t`: compare curvature at the images of the base's
/// points, and the projections of some of them.
///
/// Differences are relative: `|s·k − k_base| / (|k_base| + 1/h)` for k1, k2 and mean (so
/// that curvature small against 1/h is compared absolutely), the same with `s²` and `1/h²`
/// for gauss, `|Δn|`, and the distance between projected points over `h`.
fn check_match(
    cloud: &AdversarialCloud,
    surface: &MlsSurface,
    base: &AdversarialCloud,
    scale: f64,
    offset: &Vector,
    par: Parallelism,
    out: &mut Outcome,
) {
    let base_surface = match MlsSurface::new(&base.points, &base.normals, config_of(base)) {
        Ok(s) => s,
        Err(e) => {
            out.failures.push(format!("base construction failed: {e}"));
            return;
        }
    };
    let image = |q: &Point| Point::from(q.coords * scale + offset);
    let images: Vec<Point> = base.points.iter().map(image).collect();
    let stride = base.points.len().div_ceil(MAX_PROJECTED / 2).max(1);
    let few: Vec<Point> = base.points.iter().step_by(stride).copied().collect();
    let few_images: Vec<Point> = few.iter().map(image).collect();
    let pairs = [
        (
            base_surface.curvature_at_points(&base.points, par),
            surface.curvature_at_points(&images, par),
        ),
        (
            base_surface.project_points(&few, par),
            surface.project_points(&few_images, par),
        ),
    ];
    let (h, inv_h) = (base.h, 1.0 / base.h);
    let mut worst = [0.0f64; 2];
    for (kind, (expected, got)) in pairs.iter().enumerate() {
        for (e, g) in expected.iter().zip(got) {
            match (e, g) {
                (Ok(e), Ok(g)) => {
                    let (ce, cg) = (&e.curvature, &g.curvature);
                    let rel = |a: f64, b: f64, floor: f64| (a - b).abs() / (b.abs() + floor);
                    let d = [
                        rel(cg.k1 * scale, ce.k1, inv_h),
                        rel(cg.k2 * scale, ce.k2, inv_h),
                        rel(cg.mean * scale, ce.mean, inv_h),
                        rel(cg.gauss * scale * scale, ce.gauss, inv_h * inv_h),
                        (cg.normal - ce.normal).norm(),
                        (g.point.coords - image(&e.point).coords).norm() / (scale * h),
                    ];
                    worst[kind] = d.into_iter().fold(worst[kind], f64::max);
                }
                (e, g) if e == g => {}
                _ => out.mismatched_statuses += 1,
            }
        }
    }
    out.matched = Some(worst);
    let tolerance = match_tolerance(cloud.class);
    for (kind, label) in ["curvature at the points", "projection"].iter().enumerate() {
        if !(worst[kind] <= tolerance[kind]) {
            out.failures.push(format!(
                "{}: {label} differs from the base by {:e} (tolerance {:e})",
                cloud.class, worst[kind], tolerance[kind]
            ));
        }
    }
    if out.mismatched_statuses > 0 {
        out.failures.push(format!(
            "{}: {} statuses differ from the base's",
            cloud.class, out.mismatched_statuses
        ));
    }
}

/// The tolerances of a matched class: curvature at the points, and after projection.
pub(crate) fn match_tolerance(class: AdversarialClass) -> [f64; 2] {
    match class {
        AdversarialClass::Offset => OFFSET_TOLERANCE,
        _ => SIMILAR_TOLERANCE,
    }
}

fn check_normals(cloud: &AdversarialCloud, par: Parallelism, out: &mut Outcome) {
    let config = NormalsConfig::default();
    let estimated = estimate_normals(&cloud.points, &config, par);
    let est = match (&cloud.expectation, estimated) {
        (
            Expectation::NonFinitePoint { index },
            Err(NormalsError::Input(InputError::NonFinitePoint { index: got })),
        ) if got == *index => {
            out.normals_error = Some("NonFinitePoint");
            return;
        }
        (Expectation::NonFinitePoint { .. }, other) => {
            out.failures.push(format!(
                "estimate_normals: expected NonFinitePoint, got {:?}",
                other.map(|_| "normals")
            ));
            return;
        }
        (_, Err(e)) => {
            out.failures.push(format!("estimate_normals failed: {e}"));
            return;
        }
        (_, Ok(est)) => est,
    };
    if est.estimates.len() != cloud.points.len() {
        out.failures
            .push("estimate_normals: wrong length".to_owned());
        return;
    }
    for (i, e) in est.estimates.iter().enumerate() {
        match e {
            Ok(e) => {
                out.normals[0] += 1;
                let n = e.normal.into_inner();
                let unit = n.iter().all(|c| c.is_finite()) && (n.norm() - 1.0).abs() < 1e-12;
                let variation = e.variation.is_finite() && (0.0..=0.34).contains(&e.variation);
                if !(unit && variation) {
                    out.failures
                        .push(format!("estimate_normals at point {i}: {e:?}"));
                }
            }
            Err(PointStatus::NormalEstimationFailed) => out.normals[1] += 1,
            Err(s) => out
                .failures
                .push(format!("estimate_normals at point {i}: status {s}")),
        }
    }
    let all_fail = match cloud.class {
        AdversarialClass::Collinear | AdversarialClass::SinglePoint => true,
        AdversarialClass::Duplicates => cloud.variant == "every point a copy of one",
        _ => false,
    };
    if all_fail && out.normals[0] > 0 {
        out.failures.push(format!(
            "estimate_normals: {} normals on a degenerate cloud",
            out.normals[0]
        ));
    }
    if matches!(cloud.class, AdversarialClass::Coplanar) {
        let plane = cloud.normals.first().copied().unwrap_or_else(Vector::z);
        let worst = est
            .estimates
            .iter()
            .flatten()
            .map(|e| 1.0 - e.normal.into_inner().dot(&plane).abs())
            .fold(0.0, f64::max);
        if out.normals[1] > 0 || !(worst < 1e-9) {
            out.failures.push(format!(
                "estimate_normals on a plane: {} failed, worst 1 − |n·v| = {worst:e}",
                out.normals[1]
            ));
        }
    }
    // The whole pipeline, as the CLI runs it: the points with a normal, at the estimated h.
    let Some(h) = est.h else { return };
    let (points, normals): (Vec<Point>, Vec<Vector>) = cloud
        .points
        .iter()
        .zip(est.normals())
        .filter_map(|(p, n)| n.ok().map(|n| (*p, n)))
        .unzip();
    match MlsSurface::new(&points, &normals, MlsConfig::new(h)) {
        Ok(surface) => {
            for r in surface.curvature_at_points(&points, par) {
                count(&mut out.pipeline, &r);
                if let Some(problem) = invalid_result(&r, false) {
                    out.failures.push(format!("pipeline: {problem}"));
                }
            }
        }
        Err(e) => out
            .failures
            .push(format!("pipeline construction failed (h = {h:e}): {e}")),
    }
}
