//! `cargo xtask paper [--quick] [--check]`: the paper's experiments (Tables 1 and 2, Figure 8,
//! the h and cutoff discussion of Section 6) beside ours, with the adaptive scale, and the
//! figures. Writes `docs/paper.md` and `docs/figures/*.png`; `--check` regenerates the
//! document in memory and fails when the committed one differs; `--quick` runs reduced
//! densities into `target/paper/` for CI.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use mls_core::normals::{DEFAULT_SPACING_NEIGHBOURS, spacing_statistics};
use mls_core::{
    AdaptiveConfig, Curvature, Cutoff, Location, MlsConfig, MlsSurface, NormalsConfig, Parallelism,
    Point, PointResult, Vector, adaptive_curvature, correct_shrinkage, estimate_normals,
};
use mls_shapes::{BSplineSurface, Cylinder, ParametricSurface, Torus, closest_point_newton};

use mls_render::{Axis, ColourScale, Panel, Series, Up, View};

/// Seed of every noise draw, so that the document is reproducible bit for bit.
const NOISE_SEED: u64 = 7;

/// Options of `cargo xtask paper`.
#[derive(Clone, Debug, clap::Args)]
pub(crate) struct Options {
    /// Reduced densities, into target/paper/.
    #[arg(long)]
    quick: bool,
    /// Fail if docs/paper.md is stale instead of writing it.
    #[arg(long)]
    check: bool,
}

impl Options {
    /// `--quick`, as CI runs it.
    pub(crate) fn quick() -> Self {
        Self {
            quick: true,
            check: false,
        }
    }
}

/// Exact (k1, k2) at the point of a shape nearest to a point, starting from a sample index.
type Nearest = Box<dyn Fn(&Point, usize) -> (f64, f64) + Sync>;

/// A test cloud with its exact geometry.
struct Case {
    name: &'static str,
    setup: String,
    points: Vec<Point>,
    /// Normals of the clean surface at each sample.
    exact: Vec<Vector>,
    /// Exact (k1, k2) at each sample of the clean surface.
    truth: Vec<(f64, f64)>,
    /// Samples whose errors are counted (and where the curvature is evaluated).
    queries: Vec<usize>,
    h: f64,
    /// Exact (k1, k2) at the point of the shape nearest to `p`, starting from sample `i`.
    nearest: Nearest,
    /// The paper's printed k1 μ, σ, k2 μ, σ.
    paper: Option<[f64; 4]>,
    view: View,
}

/// k1 and k2 errors.
#[derive(Clone, Copy, Debug, Default)]
struct Errors {
    k1: (f64, f64),
    k2: (f64, f64),
    failed: usize,
    mean_h: f64,
}

fn mean_std(e: &[f64]) -> (f64, f64) {
    let n = e.len().max(1) as f64;
    let m = e.iter().sum::<f64>() / n;
    (
        m,
        (e.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n).sqrt(),
    )
}

/// One evaluated variant: per query the evaluation point, (k1, k2) and h, or None.
type Outcome = Vec<Option<(Point, f64, f64, f64)>>;

impl Case {
    fn errors(&self, outcome: &Outcome, projected: bool) -> (Errors, Vec<f64>, Vec<f64>) {
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
    fn fixed_errors(&self, h: f64, at: Location) -> Result<Errors> {
        let out = fixed(self, &self.exact, MlsConfig::new(h), at)?;
        Ok(self.errors(&out, at == Location::Projected).0)
    }

    fn query_points(&self, points: &[Point]) -> Vec<Point> {
        self.queries.iter().map(|&i| points[i]).collect()
    }
}

/// Normals estimated by mlscurv's estimator at scale h, globally flipped if needed to agree
/// with the reference orientation (orientation is a convention the user chooses). Fails if
/// any estimate fails: the rows would otherwise mix in exact normals.
fn estimated_normals(points: &[Point], exact: &[Vector], h: f64) -> Result<Vec<Vector>> {
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
fn fixed(case: &Case, normals: &[Vector], config: MlsConfig, at: Location) -> Result<Outcome> {
    let surface = MlsSurface::new(&case.points, normals, config)?;
    Ok(outcome(
        &evaluate_fixed(case, &surface, at),
        config.h,
        |c| *c,
    ))
}

/// The surface's results at the queries of `case`.
fn evaluate_fixed(case: &Case, surface: &MlsSurface, at: Location) -> Vec<PointResult> {
    let q = case.query_points(&case.points);
    match at {
        Location::Input => surface.curvature_at_points(&q, Parallelism::Rayon),
        Location::Projected => surface.project_points(&q, Parallelism::Rayon),
    }
}

/// Results at scale `h` as an [`Outcome`], each curvature passed through `adjust`.
fn outcome(results: &[PointResult], h: f64, adjust: impl Fn(&Curvature) -> Curvature) -> Outcome {
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

fn adaptive(case: &Case, normals: &[Vector], at: Location) -> Result<Outcome> {
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

fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:+.2e}")
    }
}

/// `μ ± σ` of an error.
fn pm((mean, std): (f64, f64)) -> String {
    format!("{} ± {std:.2e}", sci(mean))
}

fn ratio(ours: f64, paper: f64) -> String {
    if paper.abs() > 0.0 {
        let r = ours.abs() / paper.abs();
        if r < 1e3 {
            format!("{r:.2}")
        } else {
            format!("{r:.1e}")
        }
    } else {
        "—".into()
    }
}

/// Builds the test shapes at the paper's setups (or reduced for `--quick`).
fn cases(quick: bool) -> Vec<Case> {
    let d = if quick { 4 } else { 1 };
    let mut out = Vec::new();

    // Sphere: radius 1, near-uniform (Fibonacci), h = 0.025.
    let n = 50_000 / (d * d);
    let samples = mls_shapes::fibonacci_sphere(n, 1.0);
    out.push(Case {
        name: "Sphere",
        setup: format!("radius 1, {n} Fibonacci points, h = {}", 0.025 * d as f64),
        points: samples.iter().map(|s| s.point).collect(),
        exact: samples.iter().map(|s| s.normal).collect(),
        truth: vec![(1.0, 1.0); n],
        queries: (0..n).step_by(5).collect(),
        h: 0.025 * d as f64,
        nearest: Box::new(|_, _| (1.0, 1.0)),
        paper: Some([0.0, 4.024e-11, 0.0, 4.335e-11]),
        view: View::THREE_QUARTER,
    });

    // Cylinder: radius 1, height 1, 628 × 100, h = 0.02, statistics over 60 × 60 interior
    // points.
    let (nu, nv) = (628 / d, 100 / d);
    let cyl = Cylinder::new(1.0, 1.0);
    let grid = mls_shapes::grid(&cyl, nu, nv);
    let (cu, cv) = (60.min(nu) / d.min(2), 60.min(nv) / d.min(2));
    let queries = grid
        .iter()
        .enumerate()
        .filter(|(_, s)| {
            let [i, j] = s.ij;
            i >= (nu - cu) / 2 && i < (nu + cu) / 2 && j >= (nv - cv) / 2 && j < (nv + cv) / 2
        })
        .map(|(k, _)| k)
        .collect();
    out.push(parametric_case(
        "Cylinder",
        format!(
            "radius 1, height 1, {nu} × {nv} grid, h = {}, errors over the central {cu} × {cv} points",
            0.02 * d as f64
        ),
        cyl,
        grid,
        queries,
        0.02 * d as f64,
        Some([0.0, 3.324e-7, 0.0, 1.495e-5]),
        View {
            azimuth_deg: -60.0,
            elevation_deg: 20.0,
            up: Up::Z,
        },
    ));

    // Torus: R = 1, r = 0.2, 500 × 100, h = 0.023.
    out.push(torus_case(quick, 0.0));

    // The B-spline stand-ins for NURBS 1 (1000 × 1000) and NURBS 2 (900 × 900), errors over
    // every 97th point (the surface uses all of them) away from the boundary by 5h.
    let n1 = 1000 / d;
    let h1 = 2.0 / n1 as f64;
    out.push(patch_case(
        "NURBS 1 (bicubic stand-in)",
        BSplineSurface::nurbs1(),
        n1,
        h1,
        Some([-0.0006, 0.0075, 0.0034, 0.0074]),
        format!(
            "bicubic, 33 × 33 control net on [0, 1]², {n1} × {n1} grid, h = {h1} (2 parameter spacings: the paper's h = 0.06 is relative to Piegl's data, whose size is not given)"
        ),
    ));
    let n2 = 900 / d;
    let h2 = 2.0 * d as f64;
    out.push(patch_case(
        "NURBS 2 (bi-quintic face-like stand-in)",
        BSplineSurface::nurbs2(),
        n2,
        h2,
        Some([-0.0016, 0.0092, 0.0010, 0.0111]),
        format!(
            "bi-quintic, 40 × 52 control net on 150 × 200 (mm), {n2} × {n2} grid, h = {h2} (the paper's h = 2)"
        ),
    ));
    out
}

fn torus_case(quick: bool, sigma: f64) -> Case {
    let d = if quick { 4 } else { 1 };
    let torus = Torus {
        major: 1.0,
        minor: 0.2,
    };
    let grid = mls_shapes::grid(&torus, 500 / d, 100 / d);
    let queries = (0..grid.len()).step_by(3).collect();
    let paper = if sigma == 0.0 {
        Some([0.0018, 0.0041, -8.176e-5, 4.141e-4])
    } else if sigma == 1e-4 {
        Some([0.0666, 0.0648, 0.0134, 0.0178])
    } else {
        Some([0.0846, 0.1060, 0.0517, 0.0889])
    };
    let mut case = parametric_case(
        "Torus",
        format!(
            "R = 1, r = 0.2, {} × {} grid, h = {}{}",
            500 / d,
            100 / d,
            0.023 * d as f64,
            if sigma > 0.0 {
                format!(", Gaussian position noise σ = {sigma:e}")
            } else {
                String::new()
            }
        ),
        torus,
        grid,
        queries,
        0.023 * d as f64,
        paper,
        View {
            azimuth_deg: -60.0,
            elevation_deg: 50.0,
            up: Up::Z,
        },
    );
    case.points = mls_shapes::add_position_noise(&case.points, sigma, NOISE_SEED);
    case
}

fn patch_case(
    name: &'static str,
    surface: BSplineSurface,
    n: usize,
    h: f64,
    paper: Option<[f64; 4]>,
    setup: String,
) -> Case {
    let grid = mls_shapes::grid(&surface, n, n);
    // Away from the open boundary, where the MLS surface curls (the paper does not say how it
    // treats the boundary): farther than 5h from the four boundary points of the sample's
    // parameter lines.
    let [du, dv] = surface.domain();
    let bound = 5.0 * h;
    let at = |u: f64, v: f64| mls_shapes::position(&surface, u, v);
    let queries = grid
        .iter()
        .enumerate()
        .filter(|(_, s)| {
            let [u, v] = s.uv;
            [
                at(du.lerp(0.0), v),
                at(du.lerp(1.0), v),
                at(u, dv.lerp(0.0)),
                at(u, dv.lerp(1.0)),
            ]
            .iter()
            .all(|b| (s.surface.point - b).norm() > bound)
        })
        .map(|(k, _)| k)
        .step_by(97)
        .collect();
    parametric_case(
        name,
        setup,
        surface,
        grid,
        queries,
        h,
        paper,
        View {
            azimuth_deg: -60.0,
            elevation_deg: 45.0,
            up: Up::Z,
        },
    )
}

#[expect(clippy::too_many_arguments, reason = "one constructor for every shape")]
fn parametric_case<S: ParametricSurface + Sync + 'static>(
    name: &'static str,
    setup: String,
    shape: S,
    grid: Vec<mls_shapes::Sample>,
    queries: Vec<usize>,
    h: f64,
    paper: Option<[f64; 4]>,
    view: View,
) -> Case {
    let uv: Vec<[f64; 2]> = grid.iter().map(|s| s.uv).collect();
    Case {
        name,
        setup,
        points: grid.iter().map(|s| s.surface.point).collect(),
        exact: grid.iter().map(|s| s.surface.normal).collect(),
        truth: grid.iter().map(|s| (s.surface.k1, s.surface.k2)).collect(),
        queries,
        h,
        nearest: Box::new(move |p, i| {
            let f = closest_point_newton(&shape, p, uv[i]).surface;
            (f.k1, f.k2)
        }),
        paper,
        view,
    }
}

/// The rows of one shape: fixed h and adaptive, exact and estimated normals, input and
/// projected points. Returns the rows and the error maps of (fixed input, adaptive) for the
/// figures.
struct Maps {
    k: Vec<(f64, f64)>,
    fixed: (Vec<f64>, Vec<f64>),
    adaptive: (Vec<f64>, Vec<f64>),
}

fn shape_rows(case: &Case, md: &mut String) -> Result<(Maps, Errors, Errors)> {
    let t0 = std::time::Instant::now();
    let h = case.h;
    let estimated = estimated_normals(&case.points, &case.exact, h)?;
    writeln!(md, "### {}\n\n{}.\n", case.name, case.setup)?;
    writeln!(
        md,
        "| normals | h | at | k1 error μ | σ | k2 error μ | σ | failed |\n| --- | --- | --- | --- | --- | --- | --- | --- |"
    )?;
    if let Some([a, b, c, d]) = case.paper {
        writeln!(
            md,
            "| **paper** | theirs | ? | {} | {} | {} | {} | |",
            sci(a),
            sci(b).trim_start_matches('+'),
            sci(c),
            sci(d).trim_start_matches('+')
        )?;
    }
    let mut maps = None;
    let mut best_fixed = Errors::default();
    let mut best_adaptive = Errors::default();
    for (label, normals) in [("exact", &case.exact), ("estimated", &estimated)] {
        // One surface for the three fixed-h rows; the corrected row reuses the projection.
        let surface = MlsSurface::new(&case.points, normals, MlsConfig::new(h))?;
        let input = evaluate_fixed(case, &surface, Location::Input);
        let projected = evaluate_fixed(case, &surface, Location::Projected);
        let variants: Vec<(&str, Outcome, bool)> = vec![
            ("input", outcome(&input, h, |c| *c), false),
            ("projected", outcome(&projected, h, |c| *c), true),
            (
                "projected, shrinkage corrected",
                outcome(&projected, h, |c| correct_shrinkage(c, h)),
                true,
            ),
        ];
        let adaptive_variants: Vec<(&str, Outcome, bool)> = vec![
            ("input", adaptive(case, normals, Location::Input)?, false),
            (
                "projected",
                adaptive(case, normals, Location::Projected)?,
                true,
            ),
        ];
        let mut fixed_input_maps = None;
        for (at, outcome, projected) in &variants {
            let (e, m1, m2) = case.errors(outcome, *projected);
            row(md, label, &format!("{h}"), at, &e)?;
            if label == "exact" && *at == "input" {
                best_fixed = e;
                let k = outcome
                    .iter()
                    .map(|r| r.map_or((f64::NAN, f64::NAN), |r| (r.1, r.2)))
                    .collect();
                fixed_input_maps = Some((k, (m1, m2)));
            }
        }
        for (at, outcome, projected) in &adaptive_variants {
            let (e, m1, m2) = case.errors(outcome, *projected);
            row(
                md,
                label,
                &format!("adaptive (mean {:.3})", e.mean_h),
                at,
                &e,
            )?;
            if label == "exact" && *at == "projected" {
                best_adaptive = e;
                if let Some((k, fixed_maps)) = fixed_input_maps.take() {
                    maps = Some(Maps {
                        k,
                        fixed: fixed_maps,
                        adaptive: (m1, m2),
                    });
                }
            }
        }
    }
    md.push('\n');
    eprintln!(
        "paper: {} in {:.1} s",
        case.name,
        t0.elapsed().as_secs_f64()
    );
    Ok((maps.context("no maps")?, best_fixed, best_adaptive))
}

fn row(md: &mut String, normals: &str, h: &str, at: &str, e: &Errors) -> Result<()> {
    writeln!(
        md,
        "| {normals} | {h} | {at} | {} | {:.2e} | {} | {:.2e} | {} |",
        sci(e.k1.0),
        e.k1.1,
        sci(e.k2.0),
        e.k2.1,
        e.failed
    )?;
    Ok(())
}

fn shape_figure(case: &Case, maps: &Maps, dir: &Path, file: &str) -> Result<()> {
    let pts: Vec<[f64; 3]> = case
        .queries
        .iter()
        .map(|&i| case.points[i].coords.into())
        .collect();
    let nrm: Vec<[f64; 3]> = case.queries.iter().map(|&i| case.exact[i].into()).collect();
    let k1: Vec<f64> = maps.k.iter().map(|k| k.0).collect();
    let k2: Vec<f64> = maps.k.iter().map(|k| k.1).collect();
    // One symmetric error scale for all four error panels, so that fixed and adaptive compare.
    let all: Vec<f64> = [
        &maps.fixed.0,
        &maps.fixed.1,
        &maps.adaptive.0,
        &maps.adaptive.1,
    ]
    .iter()
    .flat_map(|v| v.iter().copied())
    .collect();
    let err = ColourScale::robust_symmetric(&all, "error");
    let panels = vec![
        Panel {
            title: "k1".into(),
            legend: ColourScale::robust_sequential(&k1, "k1").into(),
            values: k1,
        },
        Panel {
            title: "k2".into(),
            legend: ColourScale::robust_sequential(&k2, "k2").into(),
            values: k2,
        },
        Panel {
            title: "k1 error, fixed h, input".into(),
            values: maps.fixed.0.clone(),
            legend: err.clone().into(),
        },
        Panel {
            title: "k2 error, fixed h, input".into(),
            values: maps.fixed.1.clone(),
            legend: err.clone().into(),
        },
        Panel {
            title: "k1 error, adaptive, projected".into(),
            values: maps.adaptive.0.clone(),
            legend: err.clone().into(),
        },
        Panel {
            title: "k2 error, adaptive, projected".into(),
            values: maps.adaptive.1.clone(),
            legend: err.into(),
        },
    ];
    mls_render::splat_panels_png(
        &dir.join(file),
        &format!("{}: {}", case.name, case.setup),
        mls_render::Cloud {
            points: &pts,
            normals: Some(&nrm),
        },
        &panels,
        case.view,
        (400, 360),
        2,
    )
}

pub(crate) fn run(options: &Options) -> Result<()> {
    let (doc, fig_dir) = if options.quick {
        (
            PathBuf::from("target/paper/paper.md"),
            PathBuf::from("target/paper/figures"),
        )
    } else if options.check {
        let tmp = PathBuf::from("target/paper-check");
        (tmp.join("paper.md"), tmp.join("figures"))
    } else {
        (
            PathBuf::from("docs/paper.md"),
            PathBuf::from("docs/figures"),
        )
    };
    std::fs::create_dir_all(&fig_dir).with_context(|| format!("creating {}", fig_dir.display()))?;
    let md = generate(options.quick, &fig_dir)?;
    if options.check {
        let committed =
            std::fs::read_to_string("docs/paper.md").context("reading docs/paper.md")?;
        if committed != md {
            std::fs::write(&doc, &md)?;
            bail!(
                "docs/paper.md is stale: `cargo xtask paper` regenerates it (fresh copy in {})",
                doc.display()
            );
        }
        println!("docs/paper.md is up to date");
        return Ok(());
    }
    std::fs::write(&doc, &md).with_context(|| format!("writing {}", doc.display()))?;
    println!(
        "wrote {} and figures in {}",
        doc.display(),
        fig_dir.display()
    );
    Ok(())
}

fn generate(quick: bool, fig_dir: &Path) -> Result<String> {
    let mut md = String::from(include_str!("paper_intro.md"));
    if quick {
        md.push_str("\n**Quick run: densities reduced 4× per direction, h 4× larger.**\n");
    }
    md.push_str("\n## Table 1: synthetic shapes\n\n");
    let mut summary = Vec::new();
    for (case, file) in cases(quick).iter().zip([
        "sphere.png",
        "cylinder.png",
        "torus.png",
        "nurbs1.png",
        "nurbs2.png",
    ]) {
        let (maps, f, a) = shape_rows(case, &mut md)?;
        writeln!(md, "![{}](figures/{file})\n", case.name)?;
        shape_figure(case, &maps, fig_dir, file)?;
        summary.push((case.name, case.paper, f, a));
    }
    md.push_str("## Table 2: the torus with Gaussian noise\n\n");
    for sigma in [1e-4, 1e-3] {
        let case = torus_case(quick, sigma);
        let (maps, f, a) = shape_rows(&case, &mut md)?;
        let file = if sigma == 1e-4 {
            "torus-noise-1e-4.png"
        } else {
            "torus-noise-1e-3.png"
        };
        writeln!(md, "![noisy torus](figures/{file})\n")?;
        shape_figure(&case, &maps, fig_dir, file)?;
        if sigma == 1e-3 {
            chosen_scale_figure(&case, fig_dir, &mut md)?;
        }
        summary.push((
            if sigma == 1e-4 {
                "Torus σ = 1e-4"
            } else {
                "Torus σ = 1e-3"
            },
            case.paper,
            f,
            a,
        ));
    }
    md.push_str("## Against the paper\n\nσ of our errors over the paper's (below 1: we are more exact). Fixed h: exact normals at the input points; adaptive: exact normals at the projected points.\n\n| shape | paper k1 σ | fixed k1 σ (ratio) | adaptive k1 σ (ratio) | paper k2 σ | fixed k2 σ (ratio) | adaptive k2 σ (ratio) |\n| --- | --- | --- | --- | --- | --- | --- |\n");
    for (name, paper, f, a) in &summary {
        let [_, p1, _, p2] = paper.unwrap_or([f64::NAN; 4]);
        writeln!(
            md,
            "| {name} | {p1:.2e} | {:.2e} ({}) | {:.2e} ({}) | {p2:.2e} | {:.2e} ({}) | {:.2e} ({}) |",
            f.k1.1,
            ratio(f.k1.1, p1),
            a.k1.1,
            ratio(a.k1.1, p1),
            f.k2.1,
            ratio(f.k2.1, p2),
            a.k2.1,
            ratio(a.k2.1, p2)
        )?;
    }
    md.push('\n');
    density_study(quick, &mut md, fig_dir)?;
    h_study(quick, &mut md)?;
    cutoff_study(quick, &mut md)?;
    bunny(&mut md, fig_dir)?;
    md.push('\n');
    md.push_str(include_str!("paper_outro.md"));
    Ok(md)
}

/// Where the adaptive scale went on the noisy torus.
fn chosen_scale_figure(case: &Case, fig_dir: &Path, md: &mut String) -> Result<()> {
    let q = case.query_points(&case.points);
    let results = adaptive_curvature(
        &case.points,
        &case.exact,
        &q,
        Location::Input,
        &AdaptiveConfig::new(case.h),
        Parallelism::Rayon,
    )?;
    let ratio: Vec<f64> = results
        .iter()
        .map(|r| r.as_ref().map_or(f64::NAN, |p| p.h / case.h))
        .collect();
    let pts: Vec<[f64; 3]> = q.iter().map(|p| p.coords.into()).collect();
    let nrm: Vec<[f64; 3]> = case.queries.iter().map(|&i| case.exact[i].into()).collect();
    mls_render::splat_png(
        &fig_dir.join("torus-noise-1e-3-scale.png"),
        "Noisy torus σ = 1e-3: scale chosen at the input points",
        mls_render::Cloud {
            points: &pts,
            normals: Some(&nrm),
        },
        &ratio,
        &ColourScale {
            min: 1.0,
            max: 4.0,
            label: "chosen h / base h".into(),
            kind: mls_render::ScaleKind::Sequential,
        },
        case.view,
        (560, 460),
    )?;
    md.push_str("![chosen scale](figures/torus-noise-1e-3-scale.png)\n\n");
    Ok(())
}

/// Figure 8: NURBS 1 at growing density with h proportional to the spacing.
fn density_study(quick: bool, md: &mut String, fig_dir: &Path) -> Result<()> {
    let sizes: &[usize] = if quick {
        &[60, 90, 120]
    } else {
        &[100, 150, 200, 300, 400, 600]
    };
    md.push_str("## Figure 8: error against sampling density (NURBS 1)\n\nn × n grid, h = 2/n (the paper's rule h_i = 60/n_i, scaled to our patch), exact normals.\n\n| n | h | fixed, input: k1 μ ± σ | k2 μ ± σ | fixed, projected | adaptive, projected: k1 | k2 |\n| --- | --- | --- | --- | --- | --- | --- |\n");
    let mut series: Vec<Series> = [
        "k1 σ, fixed h",
        "k2 σ, fixed h",
        "k1 σ, adaptive",
        "k2 σ, adaptive",
    ]
    .iter()
    .map(|s| Series {
        name: (*s).into(),
        points: Vec::new(),
    })
    .collect();
    for &n in sizes {
        let h = 2.0 / n as f64;
        let case = patch_case(
            "NURBS 1",
            BSplineSurface::nurbs1(),
            n,
            h,
            None,
            String::new(),
        );
        let fi = case.fixed_errors(h, Location::Input)?;
        let fp = case.fixed_errors(h, Location::Projected)?;
        let ap = case
            .errors(&adaptive(&case, &case.exact, Location::Projected)?, true)
            .0;
        writeln!(
            md,
            "| {n} | {h:.4} | {} | {} | k1 {} | {} | {} |",
            pm(fi.k1),
            pm(fi.k2),
            pm(fp.k1),
            pm(ap.k1),
            pm(ap.k2)
        )?;
        let x = n as f64;
        series[0].points.push((x, fi.k1.1));
        series[1].points.push((x, fi.k2.1));
        series[2].points.push((x, ap.k1.1));
        series[3].points.push((x, ap.k2.1));
    }
    mls_render::line_chart_png(
        &fig_dir.join("figure8-density.png"),
        "NURBS 1: error σ against density (h = 2/n)",
        &Axis::linear("n (points per direction)"),
        &Axis::log("σ of the curvature error"),
        &series,
        (640, 440),
    )?;
    md.push_str("\n![error against density](figures/figure8-density.png)\n\n");
    Ok(())
}

/// h / spacing from 1 to 4 on the torus, clean and noisy.
fn h_study(quick: bool, md: &mut String) -> Result<()> {
    md.push_str("## The choice of h (Section 6): the torus\n\nh as a multiple of the median local spacing (`spacing_statistics`), exact normals.\n\n| noise σ | h / spacing | input: k1 μ ± σ | k2 μ ± σ | projected: k1 μ ± σ | k2 μ ± σ |\n| --- | --- | --- | --- | --- | --- |\n");
    for sigma in [0.0, 1e-3] {
        let case = torus_case(quick, sigma);
        let spacing =
            spacing_statistics(&case.points, DEFAULT_SPACING_NEIGHBOURS, Parallelism::Rayon)?
                .spacing;
        for factor in [1.0, 1.5, 2.0, 3.0, 4.0] {
            let h = factor * spacing;
            let i = case.fixed_errors(h, Location::Input)?;
            let p = case.fixed_errors(h, Location::Projected)?;
            writeln!(
                md,
                "| {sigma:e} | {factor} | {} | {} | {} | {} |",
                pm(i.k1),
                pm(i.k2),
                pm(p.k1),
                pm(p.k2)
            )?;
        }
    }
    md.push('\n');
    Ok(())
}

/// Kernel truncation from 3h to 7h on the torus at the paper's h.
fn cutoff_study(quick: bool, md: &mut String) -> Result<()> {
    md.push_str("## The kernel cutoff: the torus at the paper's h\n\nChange of k1 and k2 against the untruncated kernel (every sample contributes), at the input points, exact normals.\n\n| cutoff | max abs change of k1 | of k2 | k1 error μ ± σ |\n| --- | --- | --- | --- |\n");
    let case = torus_case(quick, 0.0);
    let reference = fixed(
        &case,
        &case.exact,
        MlsConfig {
            cutoff: Cutoff::None,
            ..MlsConfig::new(case.h)
        },
        Location::Input,
    )?;
    for c in [3.0, 4.0, 5.0, 6.0, 7.0] {
        let out = fixed(
            &case,
            &case.exact,
            MlsConfig {
                cutoff: Cutoff::Radius(c),
                ..MlsConfig::new(case.h)
            },
            Location::Input,
        )?;
        let (mut d1, mut d2) = (0.0f64, 0.0f64);
        for (a, b) in out.iter().zip(&reference) {
            if let (Some(a), Some(b)) = (a, b) {
                d1 = d1.max((a.1 - b.1).abs());
                d2 = d2.max((a.2 - b.2).abs());
            }
        }
        let e = case.errors(&out, false).0;
        writeln!(md, "| {c}h | {d1:.1e} | {d2:.1e} | {} |", pm(e.k1))?;
    }
    md.push('\n');
    Ok(())
}

/// Figure 7's counterpart: k1 and k2 on the real bunny scan, normals estimated.
fn bunny(md: &mut String, fig_dir: &Path) -> Result<()> {
    let path = Path::new("tests/data/bunny-stanford.ply");
    let cloud =
        mls_io::read_point_cloud(path).with_context(|| format!("reading {}", path.display()))?;
    let points: Vec<Point> = cloud.points.iter().map(|p| Point::from(*p)).collect();
    let spacing =
        spacing_statistics(&points, DEFAULT_SPACING_NEIGHBOURS, Parallelism::Rayon)?.spacing;
    let h = 2.0 * spacing;
    let est = estimate_normals(
        &points,
        &NormalsConfig {
            h: Some(h),
            ..NormalsConfig::default()
        },
        Parallelism::Rayon,
    )?;
    let (pts, nrm): (Vec<Point>, Vec<Vector>) = points
        .iter()
        .zip(est.normals())
        .filter_map(|(p, n)| n.ok().map(|n| (*p, n)))
        .unzip();
    let surface = MlsSurface::new(&pts, &nrm, MlsConfig::new(h))?;
    let results = surface.curvature_at_points(&pts, Parallelism::Rayon);
    let k1: Vec<f64> = results
        .iter()
        .map(|r| r.as_ref().map_or(f64::NAN, |s| s.curvature.k1))
        .collect();
    let k2: Vec<f64> = results
        .iter()
        .map(|r| r.as_ref().map_or(f64::NAN, |s| s.curvature.k2))
        .collect();
    // The scan's y axis is up; the renderer's is z.
    let up = |v: &Vector| [v.x, -v.z, v.y];
    let splat: Vec<[f64; 3]> = pts.iter().map(|p| up(&p.coords)).collect();
    let normals: Vec<[f64; 3]> = nrm.iter().map(up).collect();
    let both: Vec<f64> = k1.iter().chain(&k2).copied().collect();
    let scale = ColourScale::robust_symmetric(&both, "curvature (1/m)");
    let panels = vec![
        Panel {
            title: "k1".into(),
            values: k1,
            legend: scale.clone().into(),
        },
        Panel {
            title: "k2".into(),
            values: k2,
            legend: scale.into(),
        },
    ];
    mls_render::splat_panels_png(
        &fig_dir.join("bunny.png"),
        &format!(
            "Stanford bunny scan, {} points, normals estimated, h = {h:.2e}",
            pts.len()
        ),
        mls_render::Cloud {
            points: &splat,
            normals: Some(&normals),
        },
        &panels,
        View {
            azimuth_deg: -90.0,
            elevation_deg: 10.0,
            up: Up::Z,
        },
        (420, 420),
        2,
    )?;
    writeln!(
        md,
        "## Figure 7's counterpart: a real scan\n\nThe Stanford bunny (`tests/data/bunny-stanford.ply`, {} points), normals estimated and oriented by `mlscurv`'s estimator, h = 2 spacings = {h:.2e}, curvature at the input points; one symmetric colour scale for both maps.\n\n![bunny](figures/bunny.png)\n",
        pts.len()
    )?;
    Ok(())
}
