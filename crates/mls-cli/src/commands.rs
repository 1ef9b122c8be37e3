//! The subcommands that compute: `curvature`, `eval`, `normals`, `project` (`info` is in
//! `info.rs`).

use anyhow::{Context, Result};
use mls_core::{
    AdaptiveConfig, AdaptiveSurface, Curvature, JetConfig, JetPoint, Location, MlsConfig,
    MlsSurface, NormalData, Parallelism, Point, PointStatus, Vector,
};
use mls_io::{Axis, Column};

use crate::pipeline::{self, Prepared, Surface, Timings};
use crate::{
    At, CurvatureArgs, EvalArgs, Method, NormalsArgs, ProjectArgs, interactive, status_code,
};

const NAN3: [f64; 3] = [f64::NAN; 3];

/// Vector columns `px py pz` for a prefix `p` (`"n"` gives `nx ny nz`).
fn vector_columns<'a>(names: [&'a str; 3], v: &'a [[f64; 3]]) -> [Column<'a>; 3] {
    [
        Column::component(names[0], v, Axis::X),
        Column::component(names[1], v, Axis::Y),
        Column::component(names[2], v, Axis::Z),
    ]
}

/// The columns of `mlscurv curvature` besides the position, filled result by result so that
/// the full per-point results (about 600 bytes each) are held for one chunk at a time only.
struct CurvatureColumns {
    normal: Vec<[f64; 3]>,
    k1: Vec<f64>,
    k2: Vec<f64>,
    mean: Vec<f64>,
    gauss: Vec<f64>,
    d1: Vec<[f64; 3]>,
    d2: Vec<[f64; 3]>,
    status: Vec<i32>,
    /// Chosen scale and noise estimate, `--adaptive` only.
    h: Vec<f64>,
    noise: Vec<f64>,
    /// Predicted errors of k1 and k2, `--method jet` only.
    k1_sd: Vec<f64>,
    k2_sd: Vec<f64>,
}

impl CurvatureColumns {
    fn with_capacity(n: usize) -> Self {
        Self {
            normal: Vec::with_capacity(n),
            k1: Vec::with_capacity(n),
            k2: Vec::with_capacity(n),
            mean: Vec::with_capacity(n),
            gauss: Vec::with_capacity(n),
            d1: Vec::with_capacity(n),
            d2: Vec::with_capacity(n),
            status: Vec::with_capacity(n),
            h: Vec::new(),
            noise: Vec::new(),
            k1_sd: Vec::new(),
            k2_sd: Vec::new(),
        }
    }

    /// Appends the row of `r`, and replaces `point` (the query) by the point evaluated at, the
    /// projection for `--at projected`; a failed point keeps its input position.
    fn push(&mut self, r: Result<(Point, Curvature), PointStatus>, point: &mut Point) {
        self.status.push(status_code(&r));
        match r {
            Ok((at, c)) => {
                *point = at;
                self.normal.push(c.normal.into());
                self.k1.push(c.k1);
                self.k2.push(c.k2);
                self.mean.push(c.mean);
                self.gauss.push(c.gauss);
                self.d1.push(c.d1.into());
                self.d2.push(c.d2.into());
            }
            Err(_) => {
                for v in [&mut self.normal, &mut self.d1, &mut self.d2] {
                    v.push(NAN3);
                }
                for v in [&mut self.k1, &mut self.k2, &mut self.mean, &mut self.gauss] {
                    v.push(f64::NAN);
                }
            }
        }
    }
}

pub fn curvature(a: CurvatureArgs) -> Result<()> {
    let output = pipeline::output(&[&a.input], &a.out)?;
    if a.adaptive && a.method == Method::Jet {
        anyhow::bail!(
            "--adaptive is the per-point scale of --method paper; the default jet method chooses \
             its support per point by itself (use --method paper --adaptive for the MLS surface)"
        );
    }
    let s = &a.surface;
    pipeline::with_threads(s.run.threads, || {
        let mut t = Timings::default();
        let par = Parallelism::Rayon;
        let Prepared {
            mut points,
            scale,
            normals_source,
            normals_from_file,
            surface,
            carried,
        } = pipeline::prepare(
            &a.input,
            a.out.formats.input_format,
            s,
            &mut t,
            |p, n, h, cutoff| {
                Ok(if a.adaptive {
                    let config = AdaptiveConfig {
                        surface: MlsConfig {
                            cutoff,
                            ..MlsConfig::new(h)
                        },
                        ..AdaptiveConfig::new(h)
                    };
                    Surface::Adaptive(AdaptiveSurface::new(p, n, &config)?)
                } else {
                    Surface::Fixed(pipeline::fixed_surface(p, n, h, cutoff)?)
                })
            },
        )?;
        let mut carried = keep(carried, &a.out);
        carried.check(output.format(), &a.input)?;
        let label = match a.at {
            At::Input => "curvature",
            At::Projected => "projection",
        };
        // Measured normals are data for the jet; estimated ones only give its frame (fitted
        // as slopes they would count the positions twice and bring the covariance's bias).
        let jet = JetConfig {
            normals: if normals_from_file {
                NormalData::Slopes
            } else {
                NormalData::Ignore
            },
            ..JetConfig::default()
        };
        let n = points.len();
        let mut out = CurvatureColumns::with_capacity(n);
        t.time(label, || {
            crate::progress::chunked(n, label, interactive(s.run.quiet), |range| {
                let chunk = &mut points[range];
                match &surface {
                    Surface::Fixed(surface) if a.method == Method::Jet => {
                        for (r, p) in surface.jet_at_points(chunk, &jet, par).iter().zip(chunk) {
                            let at = |j: &JetPoint| match a.at {
                                At::Input => *p,
                                At::Projected => j.foot,
                            };
                            out.push(r.as_ref().map(|j| (at(j), j.curvature)).map_err(|e| *e), p);
                            let sd = r.as_ref().map_or([f64::NAN; 2], |j| j.predicted_error());
                            out.k1_sd.push(sd[0]);
                            out.k2_sd.push(sd[1]);
                        }
                    }
                    Surface::Fixed(surface) => {
                        let results = match a.at {
                            At::Input => surface.curvature_at_points(chunk, par),
                            At::Projected => surface.project_points(chunk, par),
                        };
                        for (r, p) in results.iter().zip(chunk) {
                            out.push(
                                r.as_ref().map(|s| (s.point, s.curvature)).map_err(|e| *e),
                                p,
                            );
                        }
                    }
                    Surface::Adaptive(surface) => {
                        let at = match a.at {
                            At::Input => Location::Input,
                            At::Projected => Location::Projected,
                        };
                        for (r, p) in surface
                            .curvature_at_points(chunk, at, par)
                            .iter()
                            .zip(chunk)
                        {
                            out.push(
                                r.as_ref().map(|s| (s.point, s.curvature)).map_err(|e| *e),
                                p,
                            );
                            let (h, noise) =
                                r.as_ref().map_or((f64::NAN, f64::NAN), |s| (s.h, s.noise));
                            out.h.push(h);
                            out.noise.push(noise);
                        }
                    }
                }
            })
        });
        // The surface's samples and tree are not needed for writing.
        drop(surface);
        // Same layout: the positions column reuses the points' buffer.
        let pos: Vec<[f64; 3]> = points.into_iter().map(|p| p.coords.into()).collect();
        let mut columns = Vec::with_capacity(17);
        columns.extend(vector_columns(["x", "y", "z"], &pos));
        columns.extend(vector_columns(["nx", "ny", "nz"], &out.normal));
        columns.extend([
            Column::f64("k1", &out.k1),
            Column::f64("k2", &out.k2),
            Column::f64("mean", &out.mean),
            Column::f64("gauss", &out.gauss),
        ]);
        columns.extend(vector_columns(["d1x", "d1y", "d1z"], &out.d1));
        columns.extend(vector_columns(["d2x", "d2y", "d2z"], &out.d2));
        if a.adaptive {
            columns.push(Column::f64("h", &out.h));
            columns.push(Column::f64("noise", &out.noise));
        }
        if a.method == Method::Jet {
            columns.push(Column::f64("k1_sd", &out.k1_sd));
            columns.push(Column::f64("k2_sd", &out.k2_sd));
        }
        columns.push(Column::i32("status", &out.status));
        carried.rename_clashes(&columns, &a.input);
        let columns = carried.insert(columns, 6);
        t.time("write", || {
            output.write(&columns, a.out.ascii, carried.las.as_ref())
        })?;
        if !s.run.quiet {
            eprintln!("mlscurv curvature: {}", pipeline::input_name(&a.input));
            eprintln!("  points read     {n}");
            if a.adaptive {
                eprintln!(
                    "  h               adaptive, per point from {:.6} to {:.6}",
                    scale.h,
                    AdaptiveConfig::new(scale.h).h_max()
                );
                eprintln!("  smallest h      {}", scale.describe(H_OPTIONS));
                eprintln!("  chosen h        {}", pipeline::percentiles(&out.h));
                eprintln!("  noise estimate  {}", pipeline::percentiles(&out.noise));
            } else {
                eprintln!("  h               {}", scale.describe(H_OPTIONS));
            }
            match a.method {
                Method::Jet => eprintln!(
                    "  method          jet: weighted degree-{} fit, support {}h to {:.1}h chosen per point; normals {}",
                    jet.degree,
                    jet.radius,
                    jet.max_radius(),
                    if normals_from_file {
                        "fitted as slopes"
                    } else {
                        "give the frame only"
                    }
                ),
                Method::Paper => {
                    eprintln!("  method          paper: closed-form curvature of the MLS surface");
                    eprintln!("  cutoff          {}", cutoff_text(s.cutoff));
                }
            }
            eprintln!("  normals         {normals_source}");
            eprintln!(
                "  evaluated at    {}",
                if a.at == At::Input {
                    "input points"
                } else {
                    "projected points"
                }
            );
            eprintln!("  status          {}", pipeline::status_counts(&out.status));
            eprintln!("  k1              {}", pipeline::percentiles(&out.k1));
            eprintln!("  k2              {}", pipeline::percentiles(&out.k2));
            eprintln!("  mean            {}", pipeline::percentiles(&out.mean));
            eprintln!("  gauss           {}", pipeline::percentiles(&out.gauss));
            if a.method == Method::Jet {
                eprintln!("  k1 predicted sd {}", pipeline::percentiles(&out.k1_sd));
            }
            print_timings(&t, n);
            eprintln!("  wrote           {}", output.name());
        }
        Ok(())
    })
}

/// What the input carries to the output, unless `--no-attributes`.
fn keep(carried: pipeline::Carried, out: &crate::OutputArgs) -> pipeline::Carried {
    pipeline::Carried::new(carried.attributes, carried.las, !out.no_attributes)
}

/// The options that set h, for the summaries.
const H_OPTIONS: &str = "--h or --h-factor";

fn cutoff_text(c: mls_core::Cutoff) -> String {
    match c {
        mls_core::Cutoff::Radius(r) => format!("{r} h"),
        mls_core::Cutoff::None => "none (untruncated kernel)".into(),
    }
}

fn print_timings(t: &Timings, n: usize) {
    let total: f64 = t.0.iter().map(|(_, s)| s).sum();
    let stages: Vec<String> =
        t.0.iter()
            .map(|(name, s)| format!("{name} {s:.3}"))
            .collect();
    eprintln!(
        "  time (s)        {}; total {total:.3} ({:.0} points/s)",
        stages.join(", "),
        n as f64 / total.max(1e-9)
    );
}

pub fn eval(a: EvalArgs) -> Result<()> {
    let output = match &a.output {
        Some(path) => pipeline::check_output(
            &[&a.cloud, &a.queries],
            path,
            a.formats.output_format,
            a.force,
            false,
            None,
        )?,
        None => pipeline::Output::Stdout(
            a.formats
                .output_format
                .map_or(mls_io::FileFormat::Csv, Into::into),
        ),
    };
    if matches!(
        output.format(),
        mls_io::FileFormat::Ply | mls_io::FileFormat::Las | mls_io::FileFormat::Laz
    ) && matches!(output, pipeline::Output::Stdout(_))
        && std::io::IsTerminal::is_terminal(&std::io::stdout())
    {
        anyhow::bail!(
            "{}: refusing to write binary PLY or LAS to a terminal; redirect it",
            pipeline::STDOUT_NAME
        );
    }
    if pipeline::input_name(&a.cloud) == pipeline::input_name(&a.queries)
        && pipeline::input_name(&a.cloud) == pipeline::STDIN_NAME
    {
        anyhow::bail!(
            "{}: --cloud and --queries cannot both be standard input",
            pipeline::STDIN_NAME
        );
    }
    pipeline::with_threads(a.run.threads, || eval_with(&a, &output))
}

fn eval_with(a: &EvalArgs, output: &pipeline::Output) -> Result<()> {
    let mut t = Timings::default();
    let cloud_name = pipeline::input_name(&a.cloud);
    let cloud = t.time("read", || {
        pipeline::read(&a.cloud, a.formats.input_format, a.columns.as_ref())
    })?;
    let Some(file_normals) = &cloud.normals else {
        anyhow::bail!(
            "{cloud_name}: the cloud has no normals (nx, ny, nz); eval needs an oriented cloud"
        );
    };
    let queries = t.time("read queries", || {
        pipeline::read_quietly(&a.queries, a.formats.input_format)
    })?;
    let points = pipeline::to_points(&cloud);
    let par = Parallelism::Rayon;
    let scale = t.time("spacing", || {
        pipeline::choose_h(
            &points,
            a.h,
            mls_core::normals::DEFAULT_H_FACTOR,
            par,
            &a.cloud,
        )
    })?;
    let h = scale.h;
    pipeline::check_scale(&points, &scale, a.cutoff, &cloud_name)?;
    let normals: Vec<Vector> = file_normals.iter().map(|n| Vector::from(*n)).collect();
    let surface = t.time("index", || {
        MlsSurface::new(
            &points,
            &normals,
            MlsConfig {
                cutoff: a.cutoff,
                ..MlsConfig::new(h)
            },
        )
        .with_context(|| cloud_name.clone())
    })?;
    let q: Vec<Point> = queries.points.iter().map(|p| Point::from(*p)).collect();
    let results = t.time("evaluation", || surface.curvature_at_points(&q, par));
    const NAMES: [&str; 21] = [
        "x", "y", "z", "g", "gx", "gy", "gz", "hxx", "hxy", "hxz", "hyy", "hyz", "hzz", "nx", "ny",
        "nz", "k1", "k2", "mean", "gauss", "status",
    ];
    let mut cols: Vec<Vec<f64>> = (0..20).map(|_| Vec::with_capacity(q.len())).collect();
    let mut status = Vec::with_capacity(q.len());
    for (r, p) in results.iter().zip(&q) {
        status.push(status_code(r));
        let row: [f64; 20] = match r {
            Ok(sp) => {
                // Undo the underflow shift: these are the true g, ∇g and H (0 where they underflow).
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
        for (c, v) in cols.iter_mut().zip(row) {
            c.push(v);
        }
    }
    let mut columns: Vec<Column<'_>> = NAMES[..20]
        .iter()
        .zip(&cols)
        .map(|(name, c)| Column::f64(name, c))
        .collect();
    columns.push(Column::i32("status", &status));
    // Attributes belong to the cloud's points, not to the queries.
    t.time("write", || output.write(&columns, false, None))?;
    if !a.run.quiet {
        eprintln!("mlscurv eval: {cloud_name}");
        eprintln!("  points read     {}", points.len());
        eprintln!(
            "  queries         {} from {}",
            q.len(),
            pipeline::input_name(&a.queries)
        );
        eprintln!("  h               {}", scale.describe("--h"));
        eprintln!("  cutoff          {}", cutoff_text(a.cutoff));
        eprintln!("  status          {}", pipeline::status_counts(&status));
        print_timings(&t, q.len());
        eprintln!("  wrote           {}", output.name());
    }
    Ok(())
}

pub fn normals(a: NormalsArgs) -> Result<()> {
    let output = pipeline::output(&[&a.input], &a.out)?;
    pipeline::with_threads(a.run.threads, || {
        let mut t = Timings::default();
        let par = Parallelism::Rayon;
        let mut cloud = t.time("read", || {
            pipeline::read(&a.input, a.out.formats.input_format, a.columns.as_ref())
        })?;
        let mut carried = pipeline::Carried::new(
            std::mem::take(&mut cloud.attributes),
            cloud.las.take(),
            !a.out.no_attributes,
        );
        carried.check(output.format(), &a.input)?;
        let points = pipeline::to_points(&cloud);
        let scale = t.time("spacing", || {
            pipeline::choose_h(&points, a.scale.h, a.scale.h_factor, par, &a.input)
        })?;
        let est = t.time("normals", || {
            // Estimated whatever the file holds: its normals are not passed.
            pipeline::normals(
                None,
                &points,
                crate::NormalsMode::Estimate,
                a.orient,
                scale.h,
                par,
                &a.input,
            )
        })?;
        let nrm: Vec<[f64; 3]> = est
            .normals
            .iter()
            .map(|n| n.map_or([0.0; 3], Into::into))
            .collect();
        let status: Vec<i32> = est
            .normals
            .iter()
            .map(|n| {
                if n.is_some() {
                    0
                } else {
                    i32::from(PointStatus::NormalEstimationFailed.code())
                }
            })
            .collect();
        let mut columns = Vec::new();
        columns.extend(vector_columns(["x", "y", "z"], &cloud.points));
        columns.extend(vector_columns(["nx", "ny", "nz"], &nrm));
        // Many XYZ readers take only 3 or 6 columns: keep XYZ output to the 6 every tool reads
        // back.
        if output.format() != mls_io::FileFormat::Xyz {
            columns.push(Column::i32("status", &status));
        }
        carried.rename_clashes(&columns, &a.input);
        let columns = carried.insert(columns, 6);
        t.time("write", || {
            output.write(&columns, a.out.ascii, carried.las.as_ref())
        })?;
        if !a.run.quiet {
            eprintln!("mlscurv normals: {}", pipeline::input_name(&a.input));
            eprintln!("  points read     {}", points.len());
            eprintln!("  h               {}", scale.describe(H_OPTIONS));
            eprintln!("  normals         {}", est.source);
            eprintln!(
                "  status          {} (failed normals are written as 0 0 0)",
                pipeline::status_counts(&status)
            );
            print_timings(&t, points.len());
            eprintln!("  wrote           {}", output.name());
        }
        Ok(())
    })
}

pub fn project(a: ProjectArgs) -> Result<()> {
    let output = pipeline::output(&[&a.input], &a.out)?;
    let s = &a.surface;
    pipeline::with_threads(s.run.threads, || {
        let mut t = Timings::default();
        let par = Parallelism::Rayon;
        let Prepared {
            mut points,
            scale,
            normals_source,
            surface,
            carried,
            ..
        } = pipeline::prepare(
            &a.input,
            a.out.formats.input_format,
            s,
            &mut t,
            pipeline::fixed_surface,
        )?;
        let mut carried = keep(carried, &a.out);
        carried.check(output.format(), &a.input)?;
        let n = points.len();
        let mut nrm = Vec::with_capacity(n);
        let mut status = Vec::with_capacity(n);
        // How far each projected point moved, for the summary.
        let mut moved = Vec::new();
        t.time("projection", || {
            crate::progress::chunked(n, "projection", interactive(s.run.quiet), |range| {
                let chunk = &mut points[range];
                let results = surface.project_points(chunk, par);
                for (r, p) in results.iter().zip(chunk) {
                    status.push(status_code(r));
                    match r {
                        Ok(sp) => {
                            moved.push(dist(&sp.point.coords.into(), &p.coords.into()));
                            *p = sp.point;
                            nrm.push(sp.curvature.normal.into());
                        }
                        // A failed point keeps its input position.
                        Err(_) => nrm.push(NAN3),
                    }
                }
            })
        });
        drop(surface);
        let pos: Vec<[f64; 3]> = points.into_iter().map(|p| p.coords.into()).collect();
        let mut columns = Vec::new();
        columns.extend(vector_columns(["x", "y", "z"], &pos));
        columns.extend(vector_columns(["nx", "ny", "nz"], &nrm));
        columns.push(Column::i32("status", &status));
        carried.rename_clashes(&columns, &a.input);
        let columns = carried.insert(columns, 6);
        t.time("write", || {
            output.write(&columns, a.out.ascii, carried.las.as_ref())
        })?;
        if !s.run.quiet {
            eprintln!("mlscurv project: {}", pipeline::input_name(&a.input));
            eprintln!("  points read     {n}");
            eprintln!("  h               {}", scale.describe(H_OPTIONS));
            eprintln!("  normals         {normals_source}");
            eprintln!("  status          {}", pipeline::status_counts(&status));
            eprintln!("  displacement    {}", pipeline::percentiles(&moved));
            print_timings(&t, n);
            eprintln!("  wrote           {}", output.name());
        }
        Ok(())
    })
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}
