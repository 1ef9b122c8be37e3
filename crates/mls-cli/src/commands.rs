//! The subcommands that compute: `curvature`, `eval`, `normals`, `project` (`info` is in
//! `info.rs`).

use std::path::Path;

use anyhow::Result;
use mls_cli::progress;
use mls_core::{AdaptiveConfig, Frame, Parallelism, Point};
use mls_io::Column;
use mls_pipeline::evaluate::{self, vector_columns};
use mls_pipeline::pipeline::{self, Built, Carried, Loaded, Prepared, Timings};
use mls_pipeline::{At, Cloud, CurvatureOptions, CurvatureRun, Method};

use crate::{CurvatureArgs, EvalArgs, NormalsArgs, OutputArgs, ProjectArgs, interactive};

/// The output of a command with [`OutputArgs`], checked before any work is done.
fn output(inputs: &[&Path], out: &OutputArgs) -> Result<pipeline::Output> {
    pipeline::check_output(
        inputs,
        &out.output,
        out.formats.output_format.map(Into::into),
        out.force,
        out.ascii,
        None,
    )
}

pub fn curvature(a: CurvatureArgs) -> Result<()> {
    let output = output(&[&a.input], &a.out)?;
    let s = &a.surface;
    let options = CurvatureOptions {
        surface: s.options(),
        method: a.method.into(),
        at: a.at.into(),
        adaptive: a.adaptive,
    };
    if options.adaptive && options.method == Method::Jet {
        anyhow::bail!("{}", mls_pipeline::ADAPTIVE_NEEDS_PAPER);
    }
    if let Some((budget, format)) = tiled_budget(&a, &output)? {
        return pipeline::with_threads(s.run.threads, || {
            curvature_tiled(&a, &options, &output, budget, format)
        });
    }
    pipeline::with_threads(s.run.threads, || {
        let mut t = Timings::new(progress::on_stderr(interactive(s.run.quiet)));
        let Loaded {
            points,
            normals,
            viewpoints,
            carried,
        } = pipeline::load(
            &a.input,
            a.out.formats.input_format.map(Into::into),
            s.columns.as_ref(),
            &mut t,
        )?;
        // Before any work, as `normals` and the tiled run do: an attribute the output cannot
        // hold.
        let mut carried = keep(carried, &a.out);
        carried.check(output.format(), &a.input)?;
        let name = pipeline::input_name(&a.input);
        let n = points.len();
        let CurvatureRun {
            columns: mut out,
            scale,
            normals_from_file,
            normals_source,
            jet,
        } = mls_pipeline::curvature(
            Cloud {
                points: &points,
                normals,
                viewpoints: viewpoints.as_deref(),
                name: &name,
            },
            &options,
            &mut t,
            pipeline::print_warning,
        )?;
        drop(viewpoints);
        pipeline::check_any_ok(
            &out.status,
            &pipeline::input_name(&a.input),
            "curvature could be computed",
            "the status codes are explained by `mlscurv --help`",
        )?;
        let pos: Vec<[f64; 3]> = match out.projected.take() {
            Some(projected) => projected,
            // Same layout: the positions column reuses the points' buffer.
            None => points.into_iter().map(|p| p.coords.into()).collect(),
        };
        let columns = out.columns(&pos);
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
                    "  h               adaptive, per point from {} to {}",
                    pipeline::Length(scale.h),
                    pipeline::Length(AdaptiveConfig::new(scale.h).h_max())
                );
                eprintln!("  smallest h      {}", scale.describe(H_OPTIONS));
                eprintln!("  chosen h        {}", pipeline::percentiles(&out.h));
                eprintln!("  noise estimate  {}", pipeline::percentiles(&out.noise));
            } else {
                eprintln!("  h               {}", scale.describe(H_OPTIONS));
            }
            match options.method {
                Method::Jet => eprintln!(
                    "  method          jet: weighted degree-{} fit, support {}{}h to {:.1}h{} chosen per point; normals {}",
                    jet.degree,
                    jet.lead_radius()
                        .map_or(String::new(), |r| format!("{r:.2}h (lead), ")),
                    jet.radius,
                    jet.max_radius(),
                    if jet.quadratic && !normals_from_file {
                        format!(
                            ", or degree 2 on {:.0}h to {:.1}h",
                            mls_core::jet::QUADRATIC_RADIUS,
                            mls_core::jet::QUADRATIC_RADIUS
                                * std::f64::consts::SQRT_2
                                    .powi(mls_core::jet::QUADRATIC_SCALES as i32 - 1)
                        )
                    } else {
                        String::new()
                    },
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
                if options.at == At::Input {
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
            if options.method == Method::Jet {
                eprintln!("  k1 predicted sd {}", pipeline::percentiles(&out.k1_sd));
            }
            print_timings(&t, n, "points");
            eprintln!("  wrote           {}", output.name());
        }
        Ok(())
    })
}

/// The memory budget of a tiled run and the input's format, if the input needs one: a file
/// whose points do not fit in `--memory` (default: the available memory less a fifth).
/// Standard input, read whole, refuses `--memory`.
fn tiled_budget(
    a: &CurvatureArgs,
    output: &pipeline::Output,
) -> Result<Option<(u64, mls_io::FileFormat)>> {
    use mls_io::FileFormat;
    let name = pipeline::input_name(&a.input);
    if name == pipeline::STDIN_NAME {
        if let Some(budget) = a.memory {
            anyhow::bail!(
                "{name}: --memory {}: standard input is read whole and its size is not known \
                 before; give the file's path to have it evaluated in tiles",
                mls_pipeline::tiled::describe_size(budget)
            );
        }
        return Ok(None);
    }
    let format = a
        .out
        .formats
        .input_format
        .map(FileFormat::from)
        .or_else(|| FileFormat::from_path(&a.input));
    let Some(format) = format else {
        // An unknown extension: the reader refuses the file, saying so.
        return Ok(None);
    };
    let (budget, given) = match a.memory {
        Some(b) => (b, true),
        None => match mls_pipeline::tiled::available_memory() {
            Some(m) => (m / 5 * 4, false),
            None => return Ok(None),
        },
    };
    // A text file of `size` bytes holds at most `size / 6` points (`0 0 0` and a line end
    // each): when even that many fit, its lines are not counted.
    if matches!(format, FileFormat::Xyz | FileFormat::Csv)
        && let Ok(meta) = std::fs::metadata(&a.input)
        && !given
        && mls_pipeline::tiled::fits_in_memory(meta.len() / 6, budget)
    {
        return Ok(None);
    }
    let points = match format {
        FileFormat::Las | FileFormat::Laz => mls_io::LasReader::open(&a.input)?.len(),
        _ => mls_io::point_count(&a.input, format)?,
    };
    let need = mls_pipeline::tiled::in_memory_bytes(points);
    if mls_pipeline::tiled::fits_in_memory(points, budget) {
        if given && !a.surface.run.quiet {
            eprintln!(
                "mlscurv: note: {name}: {points} points need about {}, within --memory {}: \
                 evaluating in memory",
                mls_pipeline::tiled::describe_size(need),
                mls_pipeline::tiled::describe_size(budget)
            );
        }
        return Ok(None);
    }
    if matches!(output, pipeline::Output::Stdout(_)) {
        anyhow::bail!(
            "{name}: {points} points do not fit in {} of memory and are evaluated in tiles, \
             whose output must be a file",
            mls_pipeline::tiled::describe_size(budget)
        );
    }
    if !a.surface.run.quiet {
        eprintln!(
            "mlscurv: note: {name}: {points} points need about {}, more than {}{}: \
             evaluating in tiles",
            mls_pipeline::tiled::describe_size(need),
            mls_pipeline::tiled::describe_size(budget),
            if given {
                " (--memory)"
            } else {
                " available (--memory sets the budget)"
            }
        );
    }
    Ok(Some((budget, format)))
}

fn curvature_tiled(
    a: &CurvatureArgs,
    options: &CurvatureOptions,
    output: &pipeline::Output,
    budget: u64,
    input_format: mls_io::FileFormat,
) -> Result<()> {
    let s = &a.surface;
    let pipeline::Output::File(path, format) = output else {
        anyhow::bail!("a tiled run writes a file");
    };
    let mut t = Timings::new(progress::on_stderr(interactive(s.run.quiet)));
    let run = mls_pipeline::tiled::TiledRun {
        input: &a.input,
        input_format,
        columns: s.columns.as_ref(),
        output: path,
        format: *format,
        ascii: a.out.ascii,
        options,
        budget,
        temp_dir: a.temp_dir.as_deref(),
        keep_attributes: !a.out.no_attributes,
    };
    let r = mls_pipeline::tiled::curvature(&run, &mut t)?;
    if !s.run.quiet {
        eprintln!("mlscurv curvature: {}", pipeline::input_name(&a.input));
        eprintln!("  points read     {}", r.points);
        eprintln!("  h               {}", r.scale.describe(H_OPTIONS));
        eprintln!(
            "  tiles           {} within {} MiB: at most {} points loaded in one, {:.3} loaded per point (halo {})",
            r.tiles,
            budget >> 20,
            r.largest_tile,
            r.load_factor,
            pipeline::Length(r.reach)
        );
        eprintln!("  normals         {}", r.normals_source);
        if let Some((agree, compared)) = r.agreement {
            eprintln!(
                "  overlaps        {:.2}% of {compared} overlap points have the same normal sign in both tiles",
                100.0 * agree as f64 / compared.max(1) as f64
            );
        }
        eprintln!("  status          {}", r.status);
        eprintln!("  k1              {}", pipeline::percentiles(&r.k1));
        eprintln!("  k2              {}", pipeline::percentiles(&r.k2));
        eprintln!("  mean            {}", pipeline::percentiles(&r.mean));
        eprintln!("  gauss           {}", pipeline::percentiles(&r.gauss));
        if options.method == Method::Jet {
            eprintln!("  k1 predicted sd {}", pipeline::percentiles(&r.k1_sd));
        }
        print_timings(&t, r.points as usize, "points");
        eprintln!("  wrote           {}", output.name());
    }
    Ok(())
}

/// What the input carries to the output, unless `--no-attributes`.
fn keep(carried: Carried, out: &OutputArgs) -> Carried {
    Carried::new(carried.attributes, carried.las, !out.no_attributes)
}

/// The options that set h, for the summaries.
const H_OPTIONS: &str = "--h or --h-factor";

fn cutoff_text(c: mls_core::Cutoff) -> String {
    match c {
        mls_core::Cutoff::Radius(r) => format!("{r} h"),
        mls_core::Cutoff::None => "none (untruncated kernel)".into(),
    }
}

/// Fewer items than this and the summary gives no rate: the fixed costs (reading, the
/// index, the scale) would be most of the time, and the rate would say nothing about the
/// throughput (3 queries: "12 points/s").
const MIN_RATE_ITEMS: usize = 1000;

/// The summary's line of stage times; with the rate of `n` `items` (`points`, `queries`) per
/// second over the total, when there are enough of them to make it mean something.
fn print_timings(t: &Timings, n: usize, items: &str) {
    let total: f64 = t.0.iter().map(|(_, s)| s).sum();
    let stages: Vec<String> =
        t.0.iter()
            .map(|(name, s)| format!("{name} {s:.3}"))
            .collect();
    let rate = if n >= MIN_RATE_ITEMS {
        format!(" ({:.0} {items}/s)", n as f64 / total.max(1e-9))
    } else {
        String::new()
    };
    eprintln!(
        "  time (s)        {}; total {total:.3}{rate}",
        stages.join(", ")
    );
}

pub fn eval(a: EvalArgs) -> Result<()> {
    let output = match &a.output {
        Some(path) => pipeline::check_output(
            &[&a.cloud, &a.queries],
            path,
            a.formats.output_format.map(Into::into),
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
    let mut t = Timings::new(progress::on_stderr(interactive(a.run.quiet)));
    let cloud_name = pipeline::input_name(&a.cloud);
    let cloud = t.time("read", || {
        pipeline::read(
            &a.cloud,
            a.formats.input_format.map(Into::into),
            a.columns.as_ref(),
        )
    })?;
    let Some(file_normals) = &cloud.normals else {
        anyhow::bail!(
            "{cloud_name}: the cloud has no normals (nx, ny, nz); eval needs an oriented cloud"
        );
    };
    let queries = t.time("read queries", || {
        pipeline::read_quietly(&a.queries, a.formats.input_format.map(Into::into))
    })?;
    let points = pipeline::to_points(&cloud);
    let (scale, surface) = pipeline::eval_surface(
        &points,
        file_normals,
        a.h,
        a.cutoff,
        &cloud_name,
        &mut t,
        pipeline::print_warning,
    )?;
    let q: Vec<Point> = queries.points.iter().map(|p| Point::from(*p)).collect();
    let results = t.time("evaluation", || {
        surface.curvature_at_points(&q, Parallelism::Rayon)
    });
    let table = evaluate::EvalTable::new(&results, &q);
    let status = &table.status;
    let columns = table.columns();
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
        eprintln!("  status          {}", pipeline::status_counts(status));
        print_timings(&t, q.len(), "queries");
        eprintln!("  wrote           {}", output.name());
    }
    Ok(())
}

pub fn normals(a: NormalsArgs) -> Result<()> {
    let output = output(&[&a.input], &a.out)?;
    pipeline::with_threads(a.run.threads, || {
        let mut t = Timings::new(progress::on_stderr(interactive(a.run.quiet)));
        let par = Parallelism::Rayon;
        let mut cloud = t.time("read", || {
            pipeline::read(
                &a.input,
                a.out.formats.input_format.map(Into::into),
                a.columns.as_ref(),
            )
        })?;
        let mut carried = Carried::new(
            std::mem::take(&mut cloud.attributes),
            cloud.las.take(),
            !a.out.no_attributes,
        );
        carried.check(output.format(), &a.input)?;
        let points = pipeline::to_points(&cloud);
        let viewpoints = pipeline::scan_viewpoints(&cloud);
        let name = pipeline::input_name(&a.input);
        let index = t.time("index", || {
            pipeline::index(&points, Frame::of(&points), &name)
        })?;
        let scale = t.time("spacing", || {
            pipeline::choose_h_on(&index, a.scale.h, a.scale.h_factor, par, &name)
        })?;
        let est = t.time("normals", || {
            // Estimated whatever the file holds: its normals are not passed.
            pipeline::normals(
                None,
                &points,
                Some(&index),
                mls_pipeline::NormalsMode::Estimate,
                a.orient,
                viewpoints.as_deref(),
                scale.h,
                par,
                &name,
            )
        })?;
        if let Some(w) = est.warning.clone() {
            pipeline::print_warning(w);
        }
        let (nrm, status) = evaluate::normals_columns(&est.normals);
        pipeline::check_any_ok(
            &status,
            &name,
            "normal could be estimated",
            "points on a line, or fewer than needed for a neighbourhood, have no surface normal",
        )?;
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
            print_timings(&t, points.len(), "points");
            eprintln!("  wrote           {}", output.name());
        }
        Ok(())
    })
}

pub fn project(a: ProjectArgs) -> Result<()> {
    let output = output(&[&a.input], &a.out)?;
    let s = &a.surface;
    pipeline::with_threads(s.run.threads, || {
        let mut t = Timings::new(progress::on_stderr(interactive(s.run.quiet)));
        let Prepared {
            points,
            built:
                Built {
                    scale,
                    normals_source,
                    surface,
                    ..
                },
            carried,
        } = pipeline::prepare(
            &a.input,
            a.out.formats.input_format.map(Into::into),
            s.columns.as_ref(),
            &s.options(),
            &mut t,
            pipeline::fixed_surface,
        )?;
        let mut carried = keep(carried, &a.out);
        carried.check(output.format(), &a.input)?;
        let n = points.len();
        let progress = t.progress();
        let out = t.measure("projection", || {
            evaluate::projection(&points, &surface, &*progress)
        });
        drop(surface);
        drop(points);
        pipeline::check_any_ok(
            &out.status,
            &pipeline::input_name(&a.input),
            "projection could be computed",
            "the status codes are explained by `mlscurv --help`",
        )?;
        let mut columns = Vec::new();
        columns.extend(vector_columns(["x", "y", "z"], &out.points));
        columns.extend(vector_columns(["nx", "ny", "nz"], &out.normal));
        columns.push(Column::i32("status", &out.status));
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
            eprintln!("  status          {}", pipeline::status_counts(&out.status));
            eprintln!("  displacement    {}", pipeline::percentiles(&out.moved));
            print_timings(&t, n, "points");
            eprintln!("  wrote           {}", output.name());
        }
        Ok(())
    })
}
