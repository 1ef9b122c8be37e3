//! Evaluation of a built surface at every point, streamed chunk by chunk, into the output
//! columns of `mlscurv curvature`, `project` and `normals`.

use mls_core::{
    AdaptiveSurface, Curvature, JetConfig, JetPoint, Location, MlsSurface, NormalData, Parallelism,
    Point, PointResult, PointStatus, Vector,
};
use mls_io::{Axis, Column};

use crate::pipeline::Surface;
use crate::progress::{CHUNK, Progress};
use crate::{At, CurvatureOptions, Method, status_code};

const NAN3: [f64; 3] = [f64::NAN; 3];

/// Vector columns `px py pz` for a prefix `p` (`"n"` gives `nx ny nz`).
pub fn vector_columns<'a>(names: [&'a str; 3], v: &'a [[f64; 3]]) -> [Column<'a>; 3] {
    [
        Column::component(names[0], v, Axis::X),
        Column::component(names[1], v, Axis::Y),
        Column::component(names[2], v, Axis::Z),
    ]
}

/// The jet's configuration for a run: measured normals are data for the jet; estimated ones
/// only give its frame (fitted as slopes they would count the positions twice and bring the
/// covariance's bias).
pub fn jet_config(normals_from_file: bool) -> JetConfig {
    JetConfig {
        normals: if normals_from_file {
            NormalData::Slopes
        } else {
            NormalData::Ignore
        },
        ..JetConfig::default()
    }
}

/// The name of the evaluation stage, for timings and the progress bar.
pub fn curvature_label(at: At) -> &'static str {
    match at {
        At::Input => "curvature",
        At::Projected => "projection",
    }
}

/// The columns of `mlscurv curvature` besides the position, filled result by result (in the
/// streams' order, each at its query's row) so that the full per-point results (about 600
/// bytes each) are held for one chunk at a time only.
#[derive(Debug)]
pub struct CurvatureColumns {
    pub normal: Vec<[f64; 3]>,
    pub k1: Vec<f64>,
    pub k2: Vec<f64>,
    pub mean: Vec<f64>,
    pub gauss: Vec<f64>,
    pub d1: Vec<[f64; 3]>,
    pub d2: Vec<[f64; 3]>,
    pub status: Vec<i32>,
    /// Chosen scale and noise estimate, `--adaptive` only.
    pub h: Vec<f64>,
    pub noise: Vec<f64>,
    /// Predicted errors of k1 and k2, `--method jet` only.
    pub k1_sd: Vec<f64>,
    pub k2_sd: Vec<f64>,
    /// With `--at projected`, the points evaluated at: the projections, and the input
    /// position where a point failed. `None` with `--at input`, where they are the input
    /// points (every estimator then reports the query itself).
    pub projected: Option<Vec<[f64; 3]>>,
    /// Whether the `h` and `noise` columns are part of the table.
    pub adaptive: bool,
    /// Whether the `k1_sd` and `k2_sd` columns are part of the table.
    pub jet: bool,
}

impl CurvatureColumns {
    /// Columns of `n` rows, NaN until `Self::set` (the streams set every row once).
    pub fn new(n: usize, options: &CurvatureOptions) -> Self {
        let adaptive = options.adaptive;
        let jet = options.method == Method::Jet;
        let optional = |wanted: bool| {
            if wanted {
                vec![f64::NAN; n]
            } else {
                Vec::new()
            }
        };
        Self {
            normal: vec![NAN3; n],
            k1: vec![f64::NAN; n],
            k2: vec![f64::NAN; n],
            mean: vec![f64::NAN; n],
            gauss: vec![f64::NAN; n],
            d1: vec![NAN3; n],
            d2: vec![NAN3; n],
            status: vec![0; n],
            h: optional(adaptive),
            noise: optional(adaptive),
            k1_sd: optional(jet),
            k2_sd: optional(jet),
            projected: (options.at == At::Projected).then(|| vec![NAN3; n]),
            adaptive,
            jet,
        }
    }

    /// Sets row `i` from `r`, and the point evaluated at (the projection for `--at
    /// projected`; a failed point keeps its input position `query` and its NaNs).
    fn set(&mut self, i: usize, r: Result<(Point, Curvature), PointStatus>, query: &Point) {
        self.status[i] = status_code(&r);
        let at = match r {
            Ok((at, c)) => {
                self.normal[i] = c.normal.into();
                self.k1[i] = c.k1;
                self.k2[i] = c.k2;
                self.mean[i] = c.mean;
                self.gauss[i] = c.gauss;
                self.d1[i] = c.d1.into();
                self.d2[i] = c.d2.into();
                at
            }
            Err(_) => *query,
        };
        if let Some(projected) = &mut self.projected {
            projected[i] = at.coords.into();
        }
    }

    /// The table as written, in the order of `mlscurv curvature`'s output: `x y z nx ny nz k1
    /// k2 mean gauss d1x d1y d1z d2x d2y d2z`, then `h noise` (adaptive), `k1_sd k2_sd` (jet)
    /// and `status`. `positions` are the `x y z` columns: [`Self::projected`] if any, else the
    /// input points.
    pub fn columns<'a>(&'a self, positions: &'a [[f64; 3]]) -> Vec<Column<'a>> {
        let mut columns = Vec::with_capacity(21);
        columns.extend(vector_columns(["x", "y", "z"], positions));
        columns.extend(vector_columns(["nx", "ny", "nz"], &self.normal));
        columns.extend([
            Column::f64("k1", &self.k1),
            Column::f64("k2", &self.k2),
            Column::f64("mean", &self.mean),
            Column::f64("gauss", &self.gauss),
        ]);
        columns.extend(vector_columns(["d1x", "d1y", "d1z"], &self.d1));
        columns.extend(vector_columns(["d2x", "d2y", "d2z"], &self.d2));
        if self.adaptive {
            columns.push(Column::f64("h", &self.h));
            columns.push(Column::f64("noise", &self.noise));
        }
        if self.jet {
            columns.push(Column::f64("k1_sd", &self.k1_sd));
            columns.push(Column::f64("k2_sd", &self.k2_sd));
        }
        columns.push(Column::i32("status", &self.status));
        columns
    }
}

/// Evaluates `surface` at every one of `points` through mls-core's streams, in chunks of
/// [`CHUNK`] results, moving a bar of `progress`. The binary and the Python
/// package both go through here, so they give the same columns; the results do not depend on
/// the chunk (see `mls_core::stream`).
///
/// `jet` is used with [`Method::Jet`] ([`jet_config`]); `--adaptive` requires `surface` to be
/// [`Surface::Adaptive`].
pub fn curvature(
    points: &[Point],
    surface: &Surface,
    options: &CurvatureOptions,
    jet: &JetConfig,
    progress: &dyn Progress,
) -> CurvatureColumns {
    let par = Parallelism::Rayon;
    let n = points.len();
    let mut out = CurvatureColumns::new(n, options);
    let bar = progress.bar(n, curvature_label(options.at));
    let mut done = 0;
    match surface {
        Surface::Fixed(surface) if options.method == Method::Jet => {
            surface.jet_stream(points, jet, par, CHUNK, |indices, results| {
                for (&i, r) in indices.iter().zip(results) {
                    let p = &points[i];
                    let at = |j: &JetPoint| match options.at {
                        At::Input => *p,
                        At::Projected => j.foot,
                    };
                    out.set(
                        i,
                        r.as_ref().map(|j| (at(j), j.curvature)).map_err(|e| *e),
                        p,
                    );
                    let sd = r.as_ref().map_or([f64::NAN; 2], |j| j.predicted_error());
                    out.k1_sd[i] = sd[0];
                    out.k2_sd[i] = sd[1];
                }
                done += indices.len();
                bar.set(done);
            });
        }
        Surface::Fixed(surface) => {
            let mut sink = |indices: &[usize], results: &[PointResult]| {
                for (&i, r) in indices.iter().zip(results) {
                    let s = r.as_ref().map(|s| (s.point, s.curvature)).map_err(|e| *e);
                    out.set(i, s, &points[i]);
                }
                done += indices.len();
                bar.set(done);
            };
            match options.at {
                At::Input => surface.curvature_stream(points, par, CHUNK, &mut sink),
                At::Projected => surface.projection_stream(points, par, CHUNK, &mut sink),
            }
        }
        Surface::Adaptive(surface) => {
            let at = match options.at {
                At::Input => Location::Input,
                At::Projected => Location::Projected,
            };
            surface.curvature_stream(points, at, par, CHUNK, |indices, results| {
                for (&i, r) in indices.iter().zip(results) {
                    let s = r.as_ref().map(|s| (s.point, s.curvature)).map_err(|e| *e);
                    out.set(i, s, &points[i]);
                    let (h, noise) = r.as_ref().map_or((f64::NAN, f64::NAN), |s| (s.h, s.noise));
                    out.h[i] = h;
                    out.noise[i] = noise;
                }
                done += indices.len();
                bar.set(done);
            });
        }
    }
    out
}

/// Builds the surface `mlscurv curvature` evaluates, for [`crate::pipeline::prepare`]'s
/// `build`: one scale, or a scale per point with `adaptive`.
pub fn curvature_surface(adaptive: bool) -> impl crate::pipeline::BuildSurface<Surface> {
    move |cloud, n: &[Vector], h, cutoff| {
        Ok(if adaptive {
            let config = mls_core::AdaptiveConfig {
                surface: mls_core::MlsConfig {
                    cutoff,
                    ..mls_core::MlsConfig::new(h)
                },
                ..mls_core::AdaptiveConfig::new(h)
            };
            Surface::Adaptive(AdaptiveSurface::from_cloud(cloud, n, &config)?)
        } else {
            Surface::Fixed(crate::pipeline::fixed_surface(cloud, n, h, cutoff)?)
        })
    }
}

/// The columns of `mlscurv project` besides the position.
#[derive(Debug, Default)]
pub struct Projection {
    /// The projected points; a failed point keeps its input position.
    pub points: Vec<[f64; 3]>,
    /// The surface normal at the projection (NaN where the point failed).
    pub normal: Vec<[f64; 3]>,
    pub status: Vec<i32>,
    /// How far each projected point moved (failed points left out), for the summary.
    pub moved: Vec<f64>,
}

/// Projects every one of `points` onto `surface` through mls-core's stream, as `mlscurv
/// project` does.
pub fn projection(points: &[Point], surface: &MlsSurface, progress: &dyn Progress) -> Projection {
    let par = Parallelism::Rayon;
    let n = points.len();
    // A failed point keeps its input position and has no normal.
    let mut out = Projection {
        points: points.iter().map(|p| p.coords.into()).collect(),
        normal: vec![NAN3; n],
        status: vec![0; n],
        moved: Vec::new(),
    };
    let bar = progress.bar(n, "projection");
    let mut done = 0;
    surface.projection_stream(points, par, CHUNK, |indices, results| {
        for (&i, r) in indices.iter().zip(results) {
            out.status[i] = status_code(r);
            if let Ok(sp) = r {
                out.moved
                    .push(dist(&sp.point.coords.into(), &points[i].coords.into()));
                out.points[i] = sp.point.coords.into();
                out.normal[i] = sp.curvature.normal.into();
            }
        }
        done += indices.len();
        bar.set(done);
    });
    out
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The columns of `mlscurv normals` besides the position: each normal, `0 0 0` where it could
/// not be estimated, and its status (0, or [`PointStatus::NormalEstimationFailed`]).
pub fn normals_columns(normals: &[Option<Vector>]) -> (Vec<[f64; 3]>, Vec<i32>) {
    let nrm = normals
        .iter()
        .map(|n| n.map_or([0.0; 3], Into::into))
        .collect();
    let status = normals
        .iter()
        .map(|n| {
            if n.is_some() {
                0
            } else {
                i32::from(PointStatus::NormalEstimationFailed.code())
            }
        })
        .collect();
    (nrm, status)
}

/// The columns of `mlscurv eval`, in order: the query, g, ∇g, H's six distinct entries, the
/// normal field, the curvatures and the status.
pub const EVAL_COLUMNS: [&str; 21] = [
    "x", "y", "z", "g", "gx", "gy", "gz", "hxx", "hxy", "hxz", "hyy", "hyz", "hzz", "nx", "ny",
    "nz", "k1", "k2", "mean", "gauss", "status",
];

/// The table of `mlscurv eval`: one column of values per name of [`EVAL_COLUMNS`] but the
/// status, and the status codes. A failed query keeps its coordinates and has NaN elsewhere.
#[derive(Debug)]
pub struct EvalTable {
    pub values: Vec<Vec<f64>>,
    pub status: Vec<i32>,
}

impl EvalTable {
    /// The table of `results` at `queries`.
    pub fn new(results: &[PointResult], queries: &[Point]) -> Self {
        let mut values: Vec<Vec<f64>> =
            (0..20).map(|_| Vec::with_capacity(queries.len())).collect();
        let mut status = Vec::with_capacity(queries.len());
        for (r, p) in results.iter().zip(queries) {
            status.push(status_code(r));
            let row: [f64; 20] = match r {
                Ok(sp) => {
                    // Undo the underflow shift: the true g, ∇g and H (0 where they underflow).
                    let s = (-sp.implicit.log_scale).exp();
                    let (g, gr, hs, c) = (
                        sp.implicit.value * s,
                        sp.implicit.gradient * s,
                        sp.implicit.hessian * s,
                        sp.curvature,
                    );
                    let n = sp.implicit.field.normal;
                    [
                        p.x,
                        p.y,
                        p.z,
                        g,
                        gr.x,
                        gr.y,
                        gr.z,
                        hs[(0, 0)],
                        hs[(0, 1)],
                        hs[(0, 2)],
                        hs[(1, 1)],
                        hs[(1, 2)],
                        hs[(2, 2)],
                        n.x,
                        n.y,
                        n.z,
                        c.k1,
                        c.k2,
                        c.mean,
                        c.gauss,
                    ]
                }
                Err(_) => {
                    let mut row = [f64::NAN; 20];
                    row[..3].copy_from_slice(&[p.x, p.y, p.z]);
                    row
                }
            };
            for (c, v) in values.iter_mut().zip(row) {
                c.push(v);
            }
        }
        Self { values, status }
    }

    /// The table as written.
    pub fn columns(&self) -> Vec<Column<'_>> {
        let mut columns: Vec<Column<'_>> = EVAL_COLUMNS[..20]
            .iter()
            .zip(&self.values)
            .map(|(name, c)| Column::f64(name, c))
            .collect();
        columns.push(Column::i32("status", &self.status));
        columns
    }
}
