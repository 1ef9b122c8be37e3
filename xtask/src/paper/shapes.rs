//! The test shapes at the paper's setups (Tables 1 and 2), reduced for `--quick`.

use mls_shapes::{BSplineSurface, Cylinder, ParametricSurface, Torus, closest_point_newton};

use mls_render::{Up, View};

use super::{Case, NOISE_SEED};

/// Builds the test shapes at the paper's setups (or reduced for `--quick`).
pub(super) fn cases(quick: bool) -> Vec<Case> {
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

pub(super) fn torus_case(quick: bool, sigma: f64) -> Case {
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

pub(super) fn patch_case(
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
