//! Clouds for `validate`: random local patches of analytic shapes for the differential sweep,
//! and whole shapes with exact curvature for the analytic checks.

use std::fmt::Write as _;

use anyhow::Result;
use mls_core::{MlsConfig, MlsSurface, Parallelism, Point, Vector};
use mls_shapes::{
    Cylinder, HeightField, HeightFieldConfig, ParametricSurface, Saddle, Sphere, SurfacePoint,
    Torus, derivatives,
};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// The shapes the differential sweep draws its patches from.
#[derive(Clone, Copy, Debug)]
pub(crate) enum CaseKind {
    SpherePatch,
    TorusPatch,
    Saddle,
    HeightField,
}

impl CaseKind {
    pub const ALL: [CaseKind; 4] = [
        Self::SpherePatch,
        Self::TorusPatch,
        Self::Saddle,
        Self::HeightField,
    ];
}

/// A local cloud around a centre, with the surface points near the centre to query from.
pub(crate) struct Patch {
    pub points: Vec<Point>,
    pub normals: Vec<Vector>,
    pub h: f64,
    /// Surface points within h of the centre, with exact normals.
    near: Vec<(Point, Vector)>,
}

impl Patch {
    /// A random surface point near the centre and its exact normal.
    pub fn query_base(&self, rng: &mut ChaCha8Rng) -> (Point, Vector) {
        self.near[rng.random_range(0..self.near.len())]
    }
}

/// Samples the ball of radius `(5 + 1.5)h` around a random interior point of a random shape of
/// the given kind at spacing `h / h_over_spacing`, normals optionally tilted by up to 0.1 rad.
pub(crate) fn patch(
    kind: CaseKind,
    h_over_spacing: f64,
    perturbed: bool,
    rng: &mut ChaCha8Rng,
) -> Patch {
    let spacing = 0.01 * rng.random_range(0.5..2.0);
    let h = h_over_spacing * spacing;
    let seed = rng.random();
    match kind {
        CaseKind::SpherePatch => sample_ball(
            &Sphere::centered(rng.random_range(0.3..2.0)),
            spacing,
            h,
            perturbed,
            rng,
        ),
        CaseKind::TorusPatch => {
            let torus = Torus {
                major: 1.0,
                minor: rng.random_range(0.15..0.5),
            };
            sample_ball(&torus, spacing, h, perturbed, rng)
        }
        CaseKind::Saddle => sample_ball(
            &Saddle::new(rng.random_range(0.3..2.0), 1.0),
            spacing,
            h,
            perturbed,
            rng,
        ),
        CaseKind::HeightField => {
            let field = HeightField::random(&HeightFieldConfig::default(), seed);
            sample_ball(&field, spacing, h, perturbed, rng)
        }
    }
}

fn sample_ball<S: ParametricSurface>(
    s: &S,
    spacing: f64,
    h: f64,
    perturbed: bool,
    rng: &mut ChaCha8Rng,
) -> Patch {
    let [du, dv] = s.domain();
    // Stay away from boundaries and parametric poles.
    let (u0, v0) = (
        du.lerp(rng.random_range(0.3..0.7)),
        dv.lerp(rng.random_range(0.3..0.7)),
    );
    let centre = s.at(u0, v0).point;
    let radius = 6.5 * h;
    let d = derivatives(s, u0, v0);
    let (su, sv) = (d.du.norm(), d.dv.norm());
    // A parameter box that covers the ball with margin; random uniform samples inside it at
    // the requested density, then the ball is cut out.
    let (hu, hv) = (1.5 * radius / su, 1.5 * radius / sv);
    let count = ((2.0 * hu * su) * (2.0 * hv * sv) / (spacing * spacing)).ceil() as usize;
    let mut points = Vec::with_capacity(count);
    let mut normals = Vec::with_capacity(count);
    let mut near = Vec::new();
    for _ in 0..count {
        let (u, v) = (
            u0 + rng.random_range(-hu..hu),
            v0 + rng.random_range(-hv..hv),
        );
        let sp = s.at(du.normalize(u), dv.normalize(v));
        let dist = (sp.point - centre).norm();
        if dist > radius {
            continue;
        }
        if dist < h {
            near.push((sp.point, sp.normal));
        }
        points.push(sp.point);
        normals.push(sp.normal);
    }
    if perturbed {
        normals = mls_shapes::perturb_normals(&normals, 0.1, rng.random());
    }
    if near.is_empty() {
        near.push((centre, s.at(u0, v0).normal));
    }
    Patch {
        points,
        normals,
        h,
        near,
    }
}

/// The analytic checks' outcome: a markdown section and the names of failed checks.
pub(crate) struct Analytic {
    pub markdown: String,
    pub failures: Vec<String>,
}

/// The nominal surface point nearest to a projected point, given the sample it came from.
type FootPoint = Box<dyn Fn(&Point, &SurfacePoint) -> SurfacePoint + Sync>;

struct Shape {
    name: &'static str,
    setup: String,
    samples: Vec<SurfacePoint>,
    /// Indices of the points to evaluate at (interior, away from boundaries and lattice poles).
    queries: Vec<usize>,
    h: f64,
    /// Nominal curvature at the foot point of a projected point.
    closest: FootPoint,
    /// Tolerances on |mean| and standard deviation of the k1 and k2 errors at the input points,
    /// and on the largest direction error (radians, where |k1 − k2| ≥ 10% of max |k|). About
    /// three times the values measured by the full run, rounded up: regression guards. The
    /// exactness claim rests on the differential sweep above, not on these.
    tol: [f64; 2],
    tol_direction: f64,
}

#[derive(Default)]
struct Stats {
    n: usize,
    sum: [f64; 2],
    sum2: [f64; 2],
    max: f64,
    direction: f64,
    failed: usize,
    /// Σ of the first-order shrinkage bias k²(k1 + k2)h²/4 of each k.
    predicted: [f64; 2],
}

impl Stats {
    fn add(&mut self, got: &mls_core::Curvature, want: &SurfacePoint, h: f64) {
        let e = [got.k1 - want.k1, got.k2 - want.k2];
        // The MLS surface lies (k1 + k2)h²/4 inside the sampled one; an offset inward by δ
        // changes each curvature k to k/(1 − kδ) ≈ k + k²δ.
        let delta = (want.k1 + want.k2) * h * h / 4.0;
        let bias = [want.k1 * want.k1 * delta, want.k2 * want.k2 * delta];
        for i in 0..2 {
            self.predicted[i] += bias[i];
            self.sum[i] += e[i];
            self.sum2[i] += e[i] * e[i];
        }
        self.max = self.max.max(e[0].abs()).max(e[1].abs());
        self.n += 1;
        if (want.k1 - want.k2).abs() > 0.1 * want.k1.abs().max(want.k2.abs()) {
            let angle = got.d1.cross(&want.d1).norm().asin();
            self.direction = self.direction.max(angle);
        }
    }
    fn mean(&self, i: usize) -> f64 {
        self.sum[i] / self.n as f64
    }
    fn predicted(&self, i: usize) -> f64 {
        self.predicted[i] / self.n as f64
    }
    fn std(&self, i: usize) -> f64 {
        (self.sum2[i] / self.n as f64 - self.mean(i).powi(2))
            .max(0.0)
            .sqrt()
    }
}

fn shapes(quick: bool) -> Vec<Shape> {
    let every = if quick { 40 } else { 8 };
    let mut out = Vec::new();

    let n = if quick { 20_000 } else { 50_000 };
    let samples = mls_shapes::fibonacci_sphere(n, 1.0);
    let spacing = (4.0 * std::f64::consts::PI / n as f64).sqrt();
    let sphere = Sphere::centered(1.0);
    out.push(Shape {
        name: "sphere",
        setup: format!(
            "R = 1, {n} Fibonacci points, h = 2 × spacing = {:.4}, |z| < 0.95",
            2.0 * spacing
        ),
        queries: (0..n)
            .step_by(every)
            .filter(|&i| samples[i].point.z.abs() < 0.95)
            .collect(),
        samples,
        h: 2.0 * spacing,
        closest: Box::new(move |p, _| sphere.closest_point(p)),
        tol: [3e-8, 1e-8],
        tol_direction: 0.0,
    });

    let cylinder = Cylinder {
        radius: 1.0,
        height: 1.0,
    };
    let grid = mls_shapes::grid(&cylinder, 628, 100);
    out.push(Shape {
        name: "cylinder",
        setup: "R = 1, height 1 (z ∈ [−½, ½]), 628 × 100 grid, h = 0.02, |z| < 0.2".into(),
        queries: (0..grid.len())
            .step_by(every)
            .filter(|&i| grid[i].surface.point.z.abs() < 0.2)
            .collect(),
        samples: grid.iter().map(|s| s.surface).collect(),
        h: 0.02,
        closest: Box::new(move |p, _| cylinder.closest_point(p)),
        tol: [5e-8, 1e-8],
        tol_direction: 1e-10,
    });

    let torus = Torus {
        major: 1.0,
        minor: 0.2,
    };
    let grid = mls_shapes::grid(&torus, 500, 100);
    out.push(Shape {
        name: "torus",
        setup: "R = 1, r = 0.2, 500 × 100 grid, h = 0.023".into(),
        queries: (0..grid.len()).step_by(every).collect(),
        samples: grid.iter().map(|s| s.surface).collect(),
        h: 0.023,
        closest: Box::new(move |p, _| torus.closest_point(p)),
        tol: [1e-4, 3e-3],
        tol_direction: 1e-3,
    });

    let saddle = Saddle::new(1.0, 1.0);
    let grid = mls_shapes::grid(&saddle, 201, 201);
    let uv: Vec<[f64; 2]> = grid.iter().map(|s| s.uv).collect();
    out.push(Shape {
        name: "saddle",
        setup:
            "z = (x² − y²)/2, 201 × 201 grid on [−1, 1]², h = 2 × spacing = 0.02, |x|, |y| < 0.5"
                .into(),
        queries: (0..grid.len())
            .step_by(every / 4)
            .filter(|&i| uv[i][0].abs() < 0.5 && uv[i][1].abs() < 0.5)
            .collect(),
        samples: grid.iter().map(|s| s.surface).collect(),
        h: 0.02,
        closest: Box::new(move |p, from| {
            mls_shapes::closest_point_newton(&saddle, p, [from.point.x, from.point.y]).surface
        }),
        tol: [3e-4, 3e-4],
        tol_direction: 2e-4,
    });
    out
}

/// Curvature of whole analytic shapes with exact normals, at the input points and at their
/// projections, against the nominal surface.
pub(crate) fn analytic_checks(quick: bool) -> Result<Analytic> {
    let mut md = String::from(
        "## Analytic shapes (exact normals)\n\nErrors of k1 and k2 against the nominal surface: at the input points \
         (the level set of g through them) and at their MLS projections (nominal curvature at the foot point). \
         The MLS surface lies about (k1 + k2)h²/4 inside the sampled surface, which shifts each curvature by \
         k²(k1 + k2)h²/4 at the projected points: the *predicted* column. A row fails on any status other than ok, \
         a |μ − predicted| or σ above its tolerance (for projected rows the mean tolerance is widened by 10% of \
         the larger prediction, the accuracy of a first-order model), or a direction error above its tolerance.\n\n\
         | shape | setup | at | points | k1 error μ ± σ | k2 error μ ± σ | predicted μ (k1, k2) | max abs | max direction error (rad) | tolerance μ, σ, direction | result |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let mut failures = Vec::new();
    for shape in shapes(quick) {
        let points: Vec<Point> = shape.samples.iter().map(|s| s.point).collect();
        let normals: Vec<Vector> = shape.samples.iter().map(|s| s.normal).collect();
        let surface = MlsSurface::new(&points, &normals, MlsConfig::new(shape.h))?;
        let queries: Vec<Point> = shape.queries.iter().map(|&i| points[i]).collect();
        let tol = shape.tol;
        for (at, results) in [
            (
                "input",
                surface.curvature_at_points(&queries, Parallelism::Rayon),
            ),
            (
                "projected",
                surface.project_points(&queries, Parallelism::Rayon),
            ),
        ] {
            let projected = at == "projected";
            let mut st = Stats::default();
            for (r, &i) in results.iter().zip(&shape.queries) {
                match r {
                    Ok(sp) => {
                        let want = if projected {
                            (shape.closest)(&sp.point, &shape.samples[i])
                        } else {
                            shape.samples[i]
                        };
                        st.add(&sp.curvature, &want, shape.h);
                    }
                    Err(_) => st.failed += 1,
                }
            }
            let pred = |i: usize| if projected { st.predicted(i) } else { 0.0 };
            let ok = st.failed == 0
                && st.n > 0
                && (0..2).all(|i| {
                    (st.mean(i) - pred(i)).abs() <= tol[0] + 0.1 * pred(0).abs().max(pred(1).abs())
                        && st.std(i) <= tol[1]
                })
                && st.direction <= shape.tol_direction;
            if !ok {
                failures.push(format!("{} at {at} points", shape.name));
            }
            writeln!(
                md,
                "| {} | {} | {at} | {} | {:+.2e} ± {:.2e} | {:+.2e} ± {:.2e} | {:+.2e}, {:+.2e} | {:.2e} | {:.1e} | {:.0e}, {:.0e}, {:.0e} | {} |",
                shape.name,
                shape.setup.replace('|', "\\|"),
                st.n,
                st.mean(0),
                st.std(0),
                st.mean(1),
                st.std(1),
                pred(0),
                pred(1),
                st.max,
                st.direction,
                tol[0],
                tol[1],
                shape.tol_direction,
                if ok {
                    "pass".to_string()
                } else {
                    format!("**FAIL** ({} statuses)", st.failed)
                }
            )?;
        }
    }
    md.push('\n');
    Ok(Analytic {
        markdown: md,
        failures,
    })
}
