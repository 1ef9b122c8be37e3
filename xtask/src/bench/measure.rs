//! The measurements: best-of-n timings with CPU seconds, the stages of a cloud, I/O, the
//! machine's peak arithmetic rate and the closed form against automatic differentiation.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use anyhow::{Result, bail};
use mls_bench::{Cloud, default_h};
use mls_core::field::{FieldScratch, evaluate};
use mls_core::normals::{NormalsConfig, estimate_normals};
use mls_core::{Cutoff, MlsSurface, Parallelism, Point, PointResult, Sample, Vector, curvature};
use mls_io::{Column, PlyFormat, PointCloud, read_point_cloud, write_ply};

use super::*;

/// Cores available to rayon's global pool.
pub(super) fn cores() -> usize {
    rayon::current_num_threads()
}

// ---------------------------------------------------------------------------------------
// Measurements

/// One timed whole-cloud run.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Run {
    pub(super) seconds: f64,
    /// Process CPU time of the same run (all threads), NaN if unknown.
    pub(super) cpu_seconds: f64,
    /// Points (or queries) per second of wall-clock time.
    pub(super) rate: f64,
    /// Mean support size over the successful points (curvature, projection).
    pub(super) neighbours: f64,
    /// Points that succeeded (status ok, or normal oriented outward).
    pub(super) ok: usize,
    /// Points attempted.
    pub(super) count: usize,
}

impl Run {
    /// Points per CPU-second: what each core does when it is not shared.
    pub(super) fn cpu_rate(&self) -> f64 {
        self.count as f64 / self.cpu_seconds
    }
}

/// Wall-clock and CPU time of one run.
#[derive(Clone, Copy, Debug)]
pub(super) struct Timing {
    pub(super) wall: f64,
    /// CPU time of the whole process (all threads), NaN if unknown.
    pub(super) cpu: f64,
}

/// Runs `f` `reps` times and keeps the least wall-clock time and, separately, the least CPU
/// time; the value of the last run is returned.
pub(super) fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> (Timing, T) {
    let mut best = Timing {
        wall: f64::INFINITY,
        cpu: f64::INFINITY,
    };
    let mut last = None;
    for _ in 0..reps.max(1) {
        // Drop the previous result first: a 1M-point result is half a gigabyte.
        drop(last.take());
        let cpu = process_cpu_seconds();
        let t = Instant::now();
        let v = f();
        best.wall = best.wall.min(t.elapsed().as_secs_f64());
        best.cpu = best.cpu.min(process_cpu_seconds() - cpu);
        last = Some(v);
    }
    (best, last.expect("at least one repetition"))
}

/// CPU time so far of all threads of this process, from the scheduler's nanosecond counters
/// (`/proc/self/task/*/schedstat`); NaN where unavailable. Under load from other processes
/// wall-clock rates drop while CPU-time rates do not, so the report shows both.
pub(crate) fn process_cpu_seconds() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return f64::NAN;
    };
    let mut ns = 0_u64;
    for task in tasks.flatten() {
        let Ok(text) = std::fs::read_to_string(task.path().join("schedstat")) else {
            return f64::NAN;
        };
        match text
            .split_whitespace()
            .next()
            .and_then(|v| v.parse::<u64>().ok())
        {
            Some(v) => ns += v,
            None => return f64::NAN,
        }
    }
    ns as f64 * 1e-9
}

/// CPU time so far of the calling thread (`/proc/thread-self/schedstat`), NaN if unknown.
pub(super) fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(f64::NAN, |ns| ns as f64 * 1e-9)
}

pub(super) fn summarise(t: Timing, results: &[PointResult]) -> Run {
    let ok: Vec<usize> = results
        .iter()
        .filter_map(|r| r.as_ref().ok().map(|s| s.implicit.neighbours))
        .collect();
    Run {
        seconds: t.wall,
        cpu_seconds: t.cpu,
        rate: results.len() as f64 / t.wall,
        neighbours: ok.iter().sum::<usize>() as f64 / ok.len().max(1) as f64,
        ok: ok.len(),
        count: results.len(),
    }
}

pub(super) fn curvature_run(surface: &MlsSurface, points: &[Point], reps: usize) -> Run {
    let (s, results) = best_of(reps, || {
        surface.curvature_at_points(points, Parallelism::Rayon)
    });
    summarise(s, &results)
}

/// Normal estimation and orientation with mlscurv's defaults (automatic h, 16 neighbours,
/// outward by minimum spanning tree); `ok` counts normals that agree in sign with the exact
/// outward normal.
pub(super) fn normals_run(cloud: &Cloud, reps: usize) -> Result<Run> {
    let (t, est) = best_of(reps, || {
        estimate_normals(&cloud.points, &NormalsConfig::default(), Parallelism::Rayon)
    });
    let est = est?;
    let ok = est
        .normals()
        .iter()
        .zip(&cloud.normals)
        .filter(|(n, exact)| n.as_ref().is_ok_and(|n| n.dot(exact) > 0.0))
        .count();
    Ok(Run {
        seconds: t.wall,
        cpu_seconds: t.cpu,
        rate: cloud.len() as f64 / t.wall,
        neighbours: 0.0,
        ok,
        count: cloud.len(),
    })
}

/// What one cloud measured.
#[derive(Debug)]
pub(super) struct Stages {
    pub(super) shape: &'static str,
    pub(super) points: usize,
    pub(super) h: f64,
    pub(super) spacing_seconds: f64,
    pub(super) index_seconds: f64,
    pub(super) curvature: Run,
    pub(super) projection: Run,
    pub(super) normals: Run,
    /// Binary PLY timings, for the one cloud that measures them.
    pub(super) io: Option<Io>,
}

#[derive(Debug)]
pub(super) struct Io {
    pub(super) write_input: f64,
    pub(super) input_bytes: u64,
    pub(super) read_input: f64,
    pub(super) write_output: f64,
    pub(super) output_bytes: u64,
}

pub(super) fn stage_measurements(
    cloud: &Cloud,
    sizes: &Sizes,
    work: &Path,
    with_io: bool,
) -> Result<Stages> {
    let n = cloud.len();
    let reps = if n >= sizes.large {
        sizes.reps_large
    } else {
        sizes.reps
    };
    let t = Instant::now();
    let h = default_h(&cloud.points);
    let spacing_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let surface = cloud.surface(h, Cutoff::DEFAULT);
    let index_seconds = t.elapsed().as_secs_f64();

    let (s, results) = best_of(reps, || {
        surface.curvature_at_points(&cloud.points, Parallelism::Rayon)
    });
    let curvature = summarise(s, &results);
    // The output table is written from the real results, as mlscurv writes it.
    let io = if with_io {
        Some(io_measurements(cloud, &results, work)?)
    } else {
        None
    };
    drop(results);

    let step = n.div_ceil(sizes.projection_queries).max(1);
    let queries: Vec<Point> = cloud.points.iter().step_by(step).copied().collect();
    let (s, results) = best_of(if n >= sizes.large { 1 } else { reps }, || {
        surface.project_points(&queries, Parallelism::Rayon)
    });
    let projection = summarise(s, &results);
    drop(results);
    drop(surface);

    let normals = normals_run(cloud, reps)?;
    Ok(Stages {
        shape: cloud.name,
        points: n,
        h,
        spacing_seconds,
        index_seconds,
        curvature,
        projection,
        normals,
        io,
    })
}

/// Writes the cloud as binary PLY (x y z nx ny nz, doubles) and reads it back, then writes
/// mlscurv's 17-column output table from `results`.
pub(super) fn io_measurements(cloud: &Cloud, results: &[PointResult], work: &Path) -> Result<Io> {
    let pc = PointCloud {
        points: cloud.points.iter().map(|p| p.coords.into()).collect(),
        normals: Some(cloud.normals.iter().map(|&v| v.into()).collect()),
        ..PointCloud::default()
    };
    let input = work.join("io-input.ply");
    let (
        Timing {
            wall: write_input, ..
        },
        w,
    ) = best_of(2, || {
        write_ply(&input, &pc.columns(), PlyFormat::BinaryLittleEndian)
    });
    w?;
    let input_bytes = std::fs::metadata(&input)?.len();
    let (
        Timing {
            wall: read_input, ..
        },
        back,
    ) = best_of(2, || read_point_cloud(&input));
    if back?.len() != cloud.len() {
        bail!("read back a different number of points");
    }
    std::fs::remove_file(&input)?;

    let nan = f64::NAN;
    let mut table: Vec<Vec<f64>> = (0..10).map(|_| Vec::with_capacity(results.len())).collect();
    let mut status = Vec::with_capacity(results.len());
    for r in results {
        let row = match r {
            Ok(s) => {
                let c = &s.curvature;
                [
                    c.k1, c.k2, c.mean, c.gauss, c.d1.x, c.d1.y, c.d1.z, c.d2.x, c.d2.y, c.d2.z,
                ]
            }
            Err(_) => [nan; 10],
        };
        for (col, v) in table.iter_mut().zip(row) {
            col.push(v);
        }
        status.push(r.as_ref().err().map_or(0, |e| i32::from(e.code())));
    }
    let names = [
        "k1", "k2", "mean", "gauss", "d1x", "d1y", "d1z", "d2x", "d2y", "d2z",
    ];
    let mut columns = pc.columns();
    columns.extend(names.iter().zip(&table).map(|(n, d)| Column::f64(n, d)));
    columns.push(Column::i32("status", &status));
    let output = work.join("io-output.ply");
    let (
        Timing {
            wall: write_output, ..
        },
        w,
    ) = best_of(2, || {
        write_ply(&output, &columns, PlyFormat::BinaryLittleEndian)
    });
    w?;
    let output_bytes = std::fs::metadata(&output)?.len();
    std::fs::remove_file(&output)?;
    Ok(Io {
        write_input,
        input_bytes,
        read_input,
        write_output,
        output_bytes,
    })
}

/// Sustained f64 multiply + add rate of one core (FLOP/s of its CPU time, so that other
/// processes do not lower it), compiled for the instruction set that mls-core's per-sample
/// loops run with ([`mls_core::kernels::kernel_isa`]: AVX2, four f64 lanes, or the x86-64
/// baseline SSE2, two lanes; neither fuses multiply and add): the best of 16 and 32
/// independent accumulators, as how well the compiler vectorises and schedules each varies.
pub(super) fn peak_flops() -> f64 {
    #[cfg(target_arch = "x86_64")]
    if mls_core::kernels::kernel_isa() == "avx2" {
        return peak_avx2::<16>().max(peak_avx2::<32>());
    }
    peak_baseline::<16>().max(peak_baseline::<32>())
}

#[inline(never)]
pub(super) fn peak_baseline<const L: usize>() -> f64 {
    peak_kernel::<L>()
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
pub(super) fn peak_avx2<const L: usize>() -> f64 {
    #[target_feature(enable = "avx2")]
    pub(super) fn run<const L: usize>() -> f64 {
        peak_kernel::<L>()
    }
    // SAFETY: called only where mls-core found AVX2 on this CPU.
    unsafe { run::<L>() }
}

#[inline(always)]
pub(super) fn peak_kernel<const L: usize>() -> f64 {
    let iters = 200_000_000 / L as u64;
    let mut best = 0.0_f64;
    for _ in 0..3 {
        let (x, y) = (black_box(0.999_999_9), black_box(1e-7));
        let start = thread_cpu_seconds();
        let mut acc = [0.0_f64; L];
        for (i, a) in acc.iter_mut().enumerate() {
            *a = i as f64 * 1e-3;
        }
        for _ in 0..iters {
            for a in acc.iter_mut() {
                *a = *a * x + y;
            }
        }
        black_box(acc.iter().sum::<f64>());
        let cpu = thread_cpu_seconds() - start;
        best = best.max((iters * L as u64 * 2) as f64 / cpu);
    }
    best
}

/// Per-evaluation times (s) of the closed form and the two AD variants.
#[derive(Debug)]
pub(super) struct AdComparison {
    pub(super) closed: f64,
    pub(super) ad_g: f64,
    pub(super) witness: f64,
    pub(super) neighbours: f64,
    /// Largest |H_closed − H_AD| / |H_AD| (Frobenius) over the queries: the two must agree
    /// for the comparison to mean anything.
    pub(super) worst_hessian_difference: f64,
}

/// Times g, ∇g, H and curvature at query points near the sphere, by the closed form
/// (`field::evaluate` + `curvature`) and by AD, on the same support.
pub(super) fn ad_comparison(cloud: &Cloud, queries: usize) -> AdComparison {
    let h = default_h(&cloud.points);
    let surface = cloud.surface(h, Cutoff::DEFAULT);
    let mut ev = surface.evaluator();
    let inv_h2 = 1.0 / (h * h);
    let mut scratch = FieldScratch::default();
    let (mut closed, mut ad_g, mut witness) = (0.0, 0.0, 0.0);
    let (mut neighbours, mut worst) = (0usize, 0.0_f64);
    let step = (cloud.len() / queries.max(1)).max(1);
    let mut count = 0;
    for i in (step / 2..cloud.len()).step_by(step).take(queries) {
        let (p, n) = (cloud.points[i], cloud.normals[i]);
        // Off the samples (no zero distance), a little off the surface.
        let tangent = n
            .cross(&Vector::z())
            .try_normalize(1e-9)
            .unwrap_or(Vector::x());
        let x = p + (n * 0.1 + tangent * 0.3) * h;
        let samples: Vec<Sample> = ev.support_of(&x);
        neighbours += samples.len();
        let closed_once = |scratch: &mut FieldScratch| {
            let implicit = evaluate(black_box(&x), &samples, inv_h2, scratch).ok()?;
            curvature(&implicit.gradient, &implicit.hessian).map(|_| implicit.hessian)
        };
        let xv = x.coords;
        let ad_once = || {
            let shift = mls_ad::log_scale(black_box(&xv), &samples, inv_h2);
            let (_, grad, hess) =
                num_dual::hessian(|v| mls_ad::implicit(&v, &samples, inv_h2, shift), &xv);
            mls_ad::witness_curvature(&grad, &hess);
            hess
        };
        let witness_once = || {
            let w = mls_ad::witness(black_box(&xv), &samples, inv_h2);
            mls_ad::witness_curvature(&w.gradient, &w.hessian)
        };
        closed += per_call(200, || closed_once(&mut scratch));
        ad_g += per_call(20, ad_once);
        witness += per_call(10, witness_once);
        if let Some(hc) = closed_once(&mut scratch) {
            let ha = ad_once();
            worst = worst.max((hc - ha).norm() / ha.norm());
        } else {
            worst = f64::INFINITY;
        }
        count += 1;
    }
    let c = count.max(1) as f64;
    AdComparison {
        closed: closed / c,
        ad_g: ad_g / c,
        witness: witness / c,
        neighbours: neighbours as f64 / c,
        worst_hessian_difference: worst,
    }
}

/// Mean time of one call over `n` calls, the best of three batches.
pub(super) fn per_call<T>(n: u32, mut f: impl FnMut() -> T) -> f64 {
    let (t, ()) = best_of(3, || {
        for _ in 0..n {
            black_box(f());
        }
    });
    t.wall / f64::from(n)
}

// ---------------------------------------------------------------------------------------
// The mlscurv command as a subprocess
