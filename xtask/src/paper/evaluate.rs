//! Evaluating a case: errors against the exact curvature, fixed-h and adaptive outcomes, and
//! estimated normals.

use anyhow::{Result, bail};
use mls_core::{
    AdaptiveConfig, Curvature, Location, MlsConfig, MlsSurface, NormalsConfig, Parallelism, Point,
    PointResult, Vector, adaptive_curvature, estimate_normals,
};

use super::{Case, Errors, Outcome};

fn mean_std(e: &[f64]) -> (f64, f64) {
    let n = e.len().max(1) as f64;
    let m = e.iter().sum::<f64>() / n;
    (
        m,
        (e.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt(),
    )
}

impl Case {
    pub(super) fn errors(
        &self,
        outcome: &Outcome,
        projected: bool,
    ) -> (Errors, Vec<f64>, Vec<f64>) {
        let mut e1 = Vec::new();
        let mut e2 = Vec::new();
        let mut hs = 0.0;
        let mut failed = 0;
        let mut map1 = vec![f64::NAN; self.queries.len()];
        let mut map2 = vec![f64::NAN; self.queries.len()];
        for (q, (&i, r)) in self.queries.iter().zip(outcome).enumerate() {
            let Some((p, k1, k2, h)) = r else {
                failed += 1;
                continue;
            };
            let (t1, t2) = if projected {
                (self.nearest)(p, i)
            } else {
                self.truth[i]
            };
            e1.push(k1 - t1);
            e2.push(k2 - t2);
            map1[q] = k1 - t1;
            map2[q] = k2 - t2;
            hs += h;
        }
        let n = e1.len().max(1) as f64;
        (
            Errors {
                k1: mean_std(&e1),
                k2: mean_std(&e2),
                failed,
                mean_h: hs / n,
            },
            map1,
            map2,
        )
    }

    /// Errors of one fixed-h evaluation with the exact normals.
    pub(super) fn fixed_errors(&self, h: f64, at: Location) -> Result<Errors> {
        let out = fixed(self, &self.exact, MlsConfig::new(h), at)?;
        Ok(self.errors(&out, at == Location::Projected).0)
    }

    pub(super) fn query_points(&self, points: &[Point]) -> Vec<Point> {
        self.queries.iter().map(|&i| points[i]).collect()
    }
}

/// Normals estimated by mlscurv's estimator at scale h, globally flipped if needed to agree
/// with the reference orientation (orientation is a convention the user chooses). Fails if
/// any estimate fails: the rows would otherwise mix in exact normals.
pub(super) fn estimated_normals(points: &[Point], exact: &[Vector], h: f64) -> Result<Vec<Vector>> {
    let config = NormalsConfig {
        h: Some(h),
        ..NormalsConfig::default()
    };
    let est = estimate_normals(points, &config, Parallelism::Rayon)?;
    if est.failed() > 0 {
        bail!(
            "{} of {} normal estimates failed",
            est.failed(),
            points.len()
        );
    }
    let normals: Vec<Vector> = est.normals().into_iter().flatten().collect();
    let agree: f64 = normals
        .iter()
        .zip(exact)
        .map(|(n, e)| n.dot(e).signum())
        .sum();
    Ok(if agree < 0.0 {
        normals.iter().map(|n| -n).collect()
    } else {
        normals
    })
}

/// Curvature at the queries of `case` on the surface of the given normals and configuration.
pub(super) fn fixed(
    case: &Case,
    normals: &[Vector],
    config: MlsConfig,
    at: Location,
) -> Result<Outcome> {
    let surface = MlsSurface::new(&case.points, normals, config)?;
    Ok(outcome(
        &evaluate_fixed(case, &surface, at),
        config.h,
        |c| *c,
    ))
}

/// The surface's results at the queries of `case`.
pub(super) fn evaluate_fixed(case: &Case, surface: &MlsSurface, at: Location) -> Vec<PointResult> {
    let q = case.query_points(&case.points);
    match at {
        Location::Input => surface.curvature_at_points(&q, Parallelism::Rayon),
        Location::Projected => surface.project_points(&q, Parallelism::Rayon),
    }
}

/// Results at scale `h` as an [`Outcome`], each curvature passed through `adjust`.
pub(super) fn outcome(
    results: &[PointResult],
    h: f64,
    adjust: impl Fn(&Curvature) -> Curvature,
) -> Outcome {
    results
        .iter()
        .map(|r| {
            r.as_ref().ok().map(|s| {
                let c = adjust(&s.curvature);
                (s.point, c.k1, c.k2, h)
            })
        })
        .collect()
}

pub(super) fn adaptive(case: &Case, normals: &[Vector], at: Location) -> Result<Outcome> {
    let q = case.query_points(&case.points);
    let results = adaptive_curvature(
        &case.points,
        normals,
        &q,
        at,
        &AdaptiveConfig::new(case.h),
        Parallelism::Rayon,
    )?;
    Ok(results
        .iter()
        .map(|r| {
            r.as_ref()
                .ok()
                .map(|p| (p.point, p.curvature.k1, p.curvature.k2, p.h))
        })
        .collect())
}
