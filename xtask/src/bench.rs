//! `cargo xtask bench [--quick]`: end-to-end throughput, memory and scaling on generated
//! clouds, against the targets of issue 5. The full run writes `docs/benchmarks.md`; `--quick`
//! runs small sizes in well under a minute (after compilation) and writes
//! `target/bench/quick.md`, so that CI can check the task still works without overwriting the
//! measured report.
//!
//! Every measurement uses mlscurv's defaults (h = 2 × the median local spacing, cutoff 5h)
//! and rayon's global pool (all cores) unless it says otherwise. Times are the best of a few
//! repetitions: the machine is shared, and the best run is the least disturbed one.

use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use anyhow::{Context, Result, bail};
use mls_bench::{Cloud, default_h};
use mls_core::field::{FieldScratch, evaluate};
use mls_core::normals::{NormalsConfig, estimate_normals};
use mls_core::{Cutoff, MlsSurface, Parallelism, Point, PointResult, Sample, Vector, curvature};
use mls_io::{Column, PlyFormat, PointCloud, read_point_cloud, write_ply};

/// Curvature at the input points with given normals, 1M points, 2 cores (points/s).
const TARGET_CURVATURE_RATE: f64 = 250_000.0;
/// AD witness time / closed-form time per evaluation.
const TARGET_AD_RATIO: f64 = 5.0;
/// Normal estimation plus orientation of 1M points (s), as a rate.
const TARGET_NORMALS_RATE: f64 = 1e6 / 5.0;
/// Reading or writing a 1M-point binary PLY (s), as a rate.
const TARGET_IO_RATE: f64 = 1e6 / 0.5;
/// Peak resident memory of `mlscurv curvature` per input point (bytes).
const TARGET_BYTES_PER_POINT: f64 = 300.0;
/// "Linear in the number of points": the log-log slope of time against points from the
/// smallest to the largest cloud must not exceed this (1 is linear; n log n over 100k → 1M
/// gives 1.18 for log n, and a cache-bound algorithm shows some excess too).
const MAX_LINEAR_SLOPE: f64 = 1.1;

/// Floating-point operations per neighbour of `mls_core::field::evaluate`, counted by reading
/// `crates/mls-core/src/field.rs` (the version whose FNV-1a hash is [`FLOPS_COUNTED_HASH`]).
///
/// Counting rules: one flop per f64 add, subtract, multiply or divide (a fused multiply-add
/// counts as two); comparisons, min and sign changes count as none. Lengths are in units of h
/// (`d = (x − q)/h`, formed once per neighbour and reused by both passes), so `a = 1` and products by
/// `a` or constants of it fold away at compile time. `exp` counts as [`EXP_FLOPS`] (field.rs's
/// own branch-free `exp_weight`: range reduction, a degree-5 polynomial in a rational form with
/// one division, and the scaling by 2^k, 28 operations).
/// Per-point work (the 3 × 3 algebra after the loops, the curvature, the neighbour query) is
/// not in this count, nor are the candidates beyond the cutoff that the curvature path tests
/// and rejects (about a third more than the neighbours on a sphere; each costs the first row).
const FLOPS_PER_NEIGHBOUR: &[(&str, u32)] = &[
    (
        "offset e = x − q and the cutoff test ‖e‖² (3 sub, 3 mul, 2 add), d = e/h (3 mul), ‖d‖² (3 mul, 2 add)",
        16,
    ),
    ("shifted weight exp(−(‖d‖² − δ²)) (sub; exp)", 1 + EXP_FLOPS),
    ("d dᵀ, shared by both passes (6 mul)", 6),
    (
        "pass 1, normal field: w v_c (3), and for each c the moments Σ w v_c (1), Σ w v_c d (6), Σ w v_c d dᵀ (12), so m, S1 and S2_c (57); Σw (1)",
        61,
    ),
    (
        "pass 2, g sums: B = d·n (5), B² (1), α = 2B(B² − 1) (3), β = 1 − 3B² (2), 2w (1), c_bb (1), the coefficients 2wα, 2wβ, 2w c_bb (3); moments of each (19: Σ c, Σ c d, Σ c d dᵀ; the (D dᵀ + d Dᵀ) coefficient is −2β, so its moments are β's)",
        73,
    ),
];
/// The flops of one `exp`.
const EXP_FLOPS: u32 = 28;
/// FNV-1a hash of the `field.rs` that [`FLOPS_PER_NEIGHBOUR`] was counted from. When the
/// compiled file ([`FIELD_RS`]) differs, the report says that the count may be stale.
const FLOPS_COUNTED_HASH: u64 = 0x63a3_1090_5b4a_1e5a;

/// The `field.rs` this binary was compiled with (cargo rebuilds the xtask when it changes).
const FIELD_RS: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../crates/mls-core/src/field.rs"
));

#[derive(Clone, Copy, Debug)]
struct Sizes {
    small: usize,
    mid: usize,
    large: usize,
    /// At most this many projection queries per cloud (every k-th input point).
    projection_queries: usize,
    /// Query points for the closed-form / AD comparison.
    ad_queries: usize,
    /// Repetitions (best of) for clouds up to `mid`, and for `large`.
    reps: usize,
    reps_large: usize,
}

const FULL: Sizes = Sizes {
    small: 100_000,
    mid: 300_000,
    large: 1_000_000,
    projection_queries: 100_000,
    ad_queries: 32,
    reps: 3,
    reps_large: 2,
};

const QUICK: Sizes = Sizes {
    small: 10_000,
    mid: 30_000,
    large: 100_000,
    projection_queries: 10_000,
    ad_queries: 8,
    reps: 2,
    reps_large: 1,
};

pub(crate) fn run(args: &[String]) -> Result<()> {
    let mut quick = false;
    for a in args {
        match a.as_str() {
            "--quick" => quick = true,
            other => bail!("unknown option `{other}` for bench (usage: bench [--quick])"),
        }
    }
    let sizes = if quick { QUICK } else { FULL };
    let started = Instant::now();
    let load_before = load_average();
    let work = target_dir().join("bench");
    std::fs::create_dir_all(&work).with_context(|| format!("cannot create {}", work.display()))?;
    println!(
        "bench: {} run, scratch files in {}",
        if quick { "quick" } else { "full" },
        work.display()
    );

    // Built first, so that it is compiled from the same sources as this binary as nearly as
    // possible (other work may be editing them).
    let exe = build_mlscurv();
    let peak = peak_flops();
    println!("peak: {:.1} GFLOP/s per core", peak / 1e9);

    // Per shape and size: curvature, projection, normals.
    let mut stages = Vec::new();
    for (shape, counts) in [
        ("sphere", vec![sizes.small, sizes.mid, sizes.large]),
        ("torus", vec![sizes.small, sizes.large]),
    ] {
        for n in counts {
            let cloud = if shape == "sphere" {
                Cloud::sphere(n)
            } else {
                Cloud::torus(n)
            };
            let with_io = n == sizes.large && shape == "sphere";
            let s = stage_measurements(&cloud, &sizes, &work, with_io)?;
            println!(
                "{shape} {}: curvature {:.0}/s ({:.0}/CPU-s, {:.0} neighbours), projection \
                 {:.0}/s, normals {:.0}/s ({:.0}/CPU-s)",
                s.points,
                s.curvature.rate,
                s.curvature.cpu_rate(),
                s.curvature.neighbours,
                s.projection.rate,
                s.normals.rate,
                s.normals.cpu_rate()
            );
            stages.push(s);
        }
    }

    // Cutoff and threads on the mid sphere.
    let cloud = Cloud::sphere(sizes.mid);
    let h = default_h(&cloud.points);
    let mut cutoffs = Vec::new();
    for c in [3.0, 4.0, 5.0, 6.0] {
        let surface = cloud.surface(h, Cutoff::Radius(c));
        let run = curvature_run(&surface, &cloud.points, sizes.reps);
        println!(
            "cutoff {c}h: {:.0}/s ({:.0}/CPU-s), {:.0} neighbours",
            run.rate,
            run.cpu_rate(),
            run.neighbours
        );
        cutoffs.push((c, run));
    }
    let surface = cloud.surface(h, Cutoff::DEFAULT);
    let mut threads = Vec::new();
    // The pools live until the end: a pool's threads exit asynchronously when it is dropped,
    // and a thread that exits during a measurement would take its CPU time out of the sum.
    let pools = (1..=cores().max(2))
        .map(|t| rayon::ThreadPoolBuilder::new().num_threads(t).build())
        .collect::<Result<Vec<_>, _>>()?;
    for (pool, t) in pools.iter().zip(1..) {
        let run = pool.install(|| curvature_run(&surface, &cloud.points, sizes.reps));
        let normals = pool.install(|| normals_run(&cloud, sizes.reps))?;
        println!(
            "{t} thread(s): curvature {:.0}/s ({:.0}/CPU-s), normals {:.0}/s ({:.0}/CPU-s)",
            run.rate,
            run.cpu_rate(),
            normals.rate,
            normals.cpu_rate()
        );
        threads.push((t, run, normals));
    }
    drop(surface);

    // Closed form against AD on neighbourhoods of the large sphere.
    let big = Cloud::sphere(sizes.large);
    let ad = ad_comparison(&big, sizes.ad_queries);
    println!(
        "closed form {:.2} µs, AD g {:.2} µs ({:.1}×), AD witness {:.2} µs ({:.1}×)",
        ad.closed * 1e6,
        ad.ad_g * 1e6,
        ad.ad_g / ad.closed,
        ad.witness * 1e6,
        ad.witness / ad.closed
    );

    // The whole command, as a subprocess, for its peak memory.
    let cli = cli_measurements(exe, &big, &work, !quick);
    drop(big);
    let load_after = load_average();

    let env = Environment {
        quick,
        sizes,
        peak,
        load_before,
        load_after,
        elapsed: started.elapsed(),
    };
    let mut md = render(&env, &stages, &cutoffs, &threads, &ad, &cli);
    if !quick {
        // The out-of-core and Dask sections are kept: they take much longer to measure.
        let old = std::fs::read_to_string("docs/benchmarks.md").unwrap_or_default();
        for markers in crate::bench_tiled::KEPT {
            if let Some(section) = crate::bench_tiled::section(&old, markers) {
                md = crate::bench_tiled::replace_section(&md, markers, section);
            }
        }
    }
    let out = if quick {
        work.join("quick.md")
    } else {
        PathBuf::from("docs/benchmarks.md")
    };
    std::fs::write(&out, &md).with_context(|| format!("cannot write {}", out.display()))?;
    println!("{md}");
    println!(
        "wrote {} in {:.0} s",
        out.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Cores available to rayon's global pool.
fn cores() -> usize {
    rayon::current_num_threads()
}

// ---------------------------------------------------------------------------------------
// Measurements

/// One timed whole-cloud run.
#[derive(Clone, Copy, Debug, Default)]
struct Run {
    seconds: f64,
    /// Process CPU time of the same run (all threads), NaN if unknown.
    cpu_seconds: f64,
    /// Points (or queries) per second of wall-clock time.
    rate: f64,
    /// Mean support size over the successful points (curvature, projection).
    neighbours: f64,
    /// Points that succeeded (status ok, or normal oriented outward).
    ok: usize,
    /// Points attempted.
    count: usize,
}

impl Run {
    /// Points per CPU-second: what each core does when it is not shared.
    fn cpu_rate(&self) -> f64 {
        self.count as f64 / self.cpu_seconds
    }
}

/// Wall-clock and CPU time of one run.
#[derive(Clone, Copy, Debug)]
struct Timing {
    wall: f64,
    /// CPU time of the whole process (all threads), NaN if unknown.
    cpu: f64,
}

/// Runs `f` `reps` times and keeps the least wall-clock time and, separately, the least CPU
/// time; the value of the last run is returned.
fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> (Timing, T) {
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
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|t| t.split_whitespace().next()?.parse::<u64>().ok())
        .map_or(f64::NAN, |ns| ns as f64 * 1e-9)
}

fn summarise(t: Timing, results: &[PointResult]) -> Run {
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

fn curvature_run(surface: &MlsSurface, points: &[Point], reps: usize) -> Run {
    let (s, results) = best_of(reps, || {
        surface.curvature_at_points(points, Parallelism::Rayon)
    });
    summarise(s, &results)
}

/// Normal estimation and orientation with mlscurv's defaults (automatic h, 16 neighbours,
/// outward by minimum spanning tree); `ok` counts normals that agree in sign with the exact
/// outward normal.
fn normals_run(cloud: &Cloud, reps: usize) -> Result<Run> {
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
struct Stages {
    shape: &'static str,
    points: usize,
    h: f64,
    spacing_seconds: f64,
    index_seconds: f64,
    curvature: Run,
    projection: Run,
    normals: Run,
    /// Binary PLY timings, for the one cloud that measures them.
    io: Option<Io>,
}

#[derive(Debug)]
struct Io {
    write_input: f64,
    input_bytes: u64,
    read_input: f64,
    write_output: f64,
    output_bytes: u64,
}

fn stage_measurements(cloud: &Cloud, sizes: &Sizes, work: &Path, with_io: bool) -> Result<Stages> {
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
fn io_measurements(cloud: &Cloud, results: &[PointResult], work: &Path) -> Result<Io> {
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
fn peak_flops() -> f64 {
    #[cfg(target_arch = "x86_64")]
    if mls_core::kernels::kernel_isa() == "avx2" {
        return peak_avx2::<16>().max(peak_avx2::<32>());
    }
    peak_baseline::<16>().max(peak_baseline::<32>())
}

#[inline(never)]
fn peak_baseline<const L: usize>() -> f64 {
    peak_kernel::<L>()
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
fn peak_avx2<const L: usize>() -> f64 {
    #[target_feature(enable = "avx2")]
    fn run<const L: usize>() -> f64 {
        peak_kernel::<L>()
    }
    // SAFETY: called only where mls-core found AVX2 on this CPU.
    unsafe { run::<L>() }
}

#[inline(always)]
fn peak_kernel<const L: usize>() -> f64 {
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
struct AdComparison {
    closed: f64,
    ad_g: f64,
    witness: f64,
    neighbours: f64,
    /// Largest |H_closed − H_AD| / |H_AD| (Frobenius) over the queries: the two must agree
    /// for the comparison to mean anything.
    worst_hessian_difference: f64,
}

/// Times g, ∇g, H and curvature at query points near the sphere, by the closed form
/// (`field::evaluate` + `curvature`) and by AD, on the same support.
fn ad_comparison(cloud: &Cloud, queries: usize) -> AdComparison {
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
fn per_call<T>(n: u32, mut f: impl FnMut() -> T) -> f64 {
    let (t, ()) = best_of(3, || {
        for _ in 0..n {
            black_box(f());
        }
    });
    t.wall / f64::from(n)
}

// ---------------------------------------------------------------------------------------
// The mlscurv command as a subprocess

#[derive(Debug)]
struct CliRun {
    label: &'static str,
    points: usize,
    /// Peak resident set size in bytes, or why it is unknown.
    peak_rss: Result<u64, String>,
    wall_seconds: f64,
    /// mlscurv's own per-stage times line.
    stage_times: String,
    /// How the peak was read.
    method: &'static str,
}

#[derive(Debug)]
struct Cli {
    runs: Vec<CliRun>,
    /// Why the command could not be measured at all.
    error: Option<String>,
    /// A flat profile of each run (label, report), when asked for.
    profiles: Vec<(&'static str, String)>,
}

fn cli_measurements(exe: Result<PathBuf>, cloud: &Cloud, work: &Path, profile: bool) -> Cli {
    match exe.and_then(|exe| cli_measurements_inner(&exe, cloud, work, profile)) {
        Ok(cli) => cli,
        Err(e) => Cli {
            runs: Vec::new(),
            error: Some(format!("{e:#}")),
            profiles: Vec::new(),
        },
    }
}

fn cli_measurements_inner(exe: &Path, cloud: &Cloud, work: &Path, profile: bool) -> Result<Cli> {
    let points: Vec<[f64; 3]> = cloud.points.iter().map(|p| p.coords.into()).collect();
    let with = PointCloud {
        points: points.clone(),
        normals: Some(cloud.normals.iter().map(|&v| v.into()).collect()),
        ..PointCloud::default()
    };
    let without = PointCloud {
        points,
        normals: None,
        ..PointCloud::default()
    };
    let mut runs = Vec::new();
    let mut profiles = Vec::new();
    let out = work.join("cli-output.ply");
    for (label, pc) in [
        ("points only: normals estimated and oriented", &without),
        ("points and normals: file normals", &with),
    ] {
        let input = work.join("cli-input.ply");
        write_ply(&input, &pc.columns(), PlyFormat::BinaryLittleEndian)?;
        let mut run = run_with_peak(exe, &input, &out)?;
        run.label = label;
        run.points = pc.len();
        runs.push(run);
        if profile {
            profiles.push((label, perf_profile(exe, &input, work)));
        }
        let _ = std::fs::remove_file(&input);
        let _ = std::fs::remove_file(&out);
    }
    Ok(Cli {
        runs,
        error: None,
        profiles,
    })
}

/// Builds the release `mlscurv` and returns its path (from cargo's JSON messages).
pub(crate) fn build_mlscurv() -> Result<PathBuf> {
    let output = crate::cargo()
        .args([
            "build",
            "--release",
            "-p",
            "mls-cli",
            "--bin",
            "mlscurv",
            "--message-format=json-render-diagnostics",
        ])
        .stderr(Stdio::inherit())
        .output()
        .context("cannot run cargo build")?;
    if !output.status.success() {
        bail!("cargo build --release -p mls-cli failed");
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    stdout
        .lines()
        .filter(|l| l.contains("\"reason\":\"compiler-artifact\""))
        .filter_map(|l| json_string_field(l, "executable"))
        .find(|p| p.ends_with("mlscurv") || p.ends_with("mlscurv.exe"))
        .map(PathBuf::from)
        .context("cargo did not report the mlscurv executable")
}

/// The string value of `"key":"…"` in one line of cargo's JSON (paths need no unescaping on
/// the platforms this runs on, apart from `\\`).
fn json_string_field(line: &str, key: &str) -> Option<String> {
    let start = line.find(&format!("\"{key}\":\""))? + key.len() + 4;
    let rest = &line[start..];
    let end = rest.find('"')?;
    Some(rest[..end].replace("\\\\", "\\"))
}

/// Runs `mlscurv curvature IN -o OUT` and reads its peak RSS: from `/usr/bin/time -v` when
/// installed (exact: the kernel's rusage of the child), else by polling VmHWM in
/// `/proc/<pid>/status` (the high-water mark, so only growth in the last few milliseconds
/// before exit could be missed).
fn run_with_peak(exe: &Path, input: &Path, output: &Path) -> Result<CliRun> {
    // Issue 5's targets are the MLS surface's (`--method paper`); the jet, the default since
    // issue 11, is timed in docs/accuracy.md.
    let args = [
        "curvature".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "--method".as_ref(),
        "paper".as_ref(),
    ];
    let time = Path::new("/usr/bin/time");
    let t = Instant::now();
    let (stderr, peak_rss, method) = if time.exists() {
        let out = Command::new(time)
            .arg("-v")
            .arg(exe)
            .args(args)
            .output()
            .context("cannot run /usr/bin/time")?;
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        if !out.status.success() {
            bail!("mlscurv failed ({}):\n{stderr}", out.status);
        }
        let kb = stderr
            .lines()
            .find_map(|l| l.trim().strip_prefix("Maximum resident set size (kbytes):"))
            .and_then(|v| v.trim().parse::<u64>().ok());
        let peak = kb
            .map(|kb| kb * 1024)
            .ok_or_else(|| "no peak in /usr/bin/time's output".to_owned());
        (stderr, peak, "/usr/bin/time -v (maximum resident set size)")
    } else {
        let mut child = Command::new(exe)
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .context("cannot run mlscurv")?;
        let status_path = format!("/proc/{}/status", child.id());
        let mut stderr_pipe = child.stderr.take().context("no stderr pipe")?;
        let reader = std::thread::spawn(move || {
            let mut s = String::new();
            let _ = std::io::Read::read_to_string(&mut stderr_pipe, &mut s);
            s
        });
        let mut peak = 0;
        let status = loop {
            if let Ok(text) = std::fs::read_to_string(&status_path)
                && let Some(kb) = text
                    .lines()
                    .find_map(|l| l.strip_prefix("VmHWM:"))
                    .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            {
                peak = peak.max(kb * 1024);
            }
            if let Some(status) = child.try_wait()? {
                break status;
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        let stderr = reader.join().unwrap_or_default();
        if !status.success() {
            bail!("mlscurv failed ({status}):\n{stderr}");
        }
        let peak = if peak > 0 {
            Ok(peak)
        } else {
            Err("VmHWM not readable".to_owned())
        };
        (stderr, peak, "VmHWM polled from /proc every 5 ms")
    };
    let wall_seconds = t.elapsed().as_secs_f64();
    let stage_times = stderr
        .lines()
        .find_map(|l| l.trim().strip_prefix("time (s)"))
        .map(|s| s.trim().to_owned())
        .unwrap_or_default();
    Ok(CliRun {
        label: "",
        points: 0,
        peak_rss,
        wall_seconds,
        stage_times,
        method,
    })
}

/// A flat profile (self time by symbol) of `mlscurv curvature INPUT`, by `perf record` with
/// the software cpu-clock event (hardware counters are often unavailable in virtual
/// machines). Returns the report's top lines, or why there is none.
fn perf_profile(exe: &Path, input: &Path, work: &Path) -> String {
    let run = || -> Result<String> {
        let output = work.join("perf-output.ply");
        let data = work.join("perf.data");
        let status = Command::new("perf")
            .args(["record", "-e", "cpu-clock", "-F", "999", "-o"])
            .arg(&data)
            .arg("--")
            .arg(exe)
            .arg("curvature")
            .args(["--method", "paper"])
            .arg(input)
            .arg("-o")
            .arg(&output)
            .arg("--quiet")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .context("perf is not installed")?;
        let _ = std::fs::remove_file(&output);
        if !status.success() {
            bail!("perf record failed ({status})");
        }
        let report = Command::new("perf")
            .args([
                "report",
                "--stdio",
                "--no-children",
                "--sort",
                "symbol",
                "--percent-limit",
                "1",
                "-i",
            ])
            .arg(&data)
            .stderr(Stdio::null())
            .output()
            .context("perf report failed")?;
        let _ = std::fs::remove_file(&data);
        let text = String::from_utf8_lossy(&report.stdout);
        let lines: Vec<String> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| shorten_symbol(l.trim()))
            .collect();
        if lines.is_empty() {
            bail!("perf report was empty");
        }
        Ok(lines.join("\n"))
    };
    run().unwrap_or_else(|e| format!("(no profile: {e:#})"))
}

/// One line of `perf report`: the percentage, `[.]` or `[k]` and the symbol, with the empty
/// trailing columns and the padding removed, cut to fit a page.
fn shorten_symbol(line: &str) -> String {
    let mut words: Vec<&str> = line.split_whitespace().collect();
    while words.last() == Some(&"-") {
        words.pop();
    }
    let line = words.join(" ");
    match line.char_indices().nth(140) {
        Some((i, _)) => format!("{}…", &line[..i]),
        None => line,
    }
}

// ---------------------------------------------------------------------------------------
// Environment

#[derive(Debug)]
struct Environment {
    quick: bool,
    sizes: Sizes,
    /// Measured multiply-add peak of one core, FLOP/s.
    peak: f64,
    load_before: String,
    load_after: String,
    elapsed: Duration,
}

/// Where cargo builds: `CARGO_TARGET_DIR` or `target`.
pub(crate) fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from("target"), PathBuf::from)
}

/// The 1, 5 and 15 minute load averages.
pub(crate) fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(", "))
        .unwrap_or_else(|| "unknown".to_owned())
}

/// CPU model, logical CPU count, MHz and total memory from /proc.
pub(crate) fn machine() -> String {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |name: &str| {
        cpuinfo.lines().find_map(|l| {
            let (k, v) = l.split_once(':')?;
            (k.trim() == name).then(|| v.trim().to_owned())
        })
    };
    let cpus = cpuinfo
        .lines()
        .filter(|l| l.starts_with("processor"))
        .count();
    let model = field("model name").unwrap_or_else(|| "unknown CPU".to_owned());
    let mhz = field("cpu MHz").unwrap_or_else(|| "?".to_owned());
    let flags = field("flags").unwrap_or_default();
    let simd: Vec<&str> = ["sse2", "avx2", "fma", "avx512f"]
        .into_iter()
        .filter(|f| flags.split_whitespace().any(|g| g == *f))
        .collect();
    let mem = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|m| {
            m.lines()
                .find_map(|l| l.strip_prefix("MemTotal:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or_else(
            || "?".to_owned(),
            |kb| format!("{:.1} GiB", kb / 1024.0 / 1024.0),
        );
    format!(
        "{model}, {cpus} logical CPUs at {mhz} MHz ({}), {mem} RAM; rayon uses {} threads",
        simd.join(", "),
        rayon::current_num_threads()
    )
}

/// Today's date (UTC) from the system clock, `YYYY-MM-DD HH:MM UTC`.
pub(crate) fn now_utc() -> String {
    let secs = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02} UTC",
        rem / 3600,
        rem % 3600 / 60
    )
}

/// FNV-1a, 64 bits.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

// ---------------------------------------------------------------------------------------
// The report

/// A target: at least or at most a value.
#[derive(Clone, Copy, Debug)]
enum Goal {
    AtLeast(f64),
    AtMost(f64),
}

fn verdict(value: f64, goal: Goal) -> String {
    match goal {
        Goal::AtLeast(t) if value >= t => format!("**met**, {:.2}× the target", value / t),
        Goal::AtLeast(t) => format!(
            "**not met**: {:.2}× the target ({:.2}× short)",
            value / t,
            t / value
        ),
        Goal::AtMost(t) if value <= t => format!("**met**, {:.2}× under", t / value),
        Goal::AtMost(t) => format!("**not met**: {:.2}× over", value / t),
    }
}

fn thousands(x: f64) -> String {
    let n = x.round() as i64;
    let digits = n.unsigned_abs().to_string();
    let mut out = String::new();
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    if n < 0 { format!("-{out}") } else { out }
}

/// Seconds per point of a run: CPU time when known (it does not grow when other processes
/// take the cores), else wall-clock time.
fn seconds_per_point(run: &Run) -> f64 {
    let s = if run.cpu_seconds.is_finite() {
        run.cpu_seconds
    } else {
        run.seconds
    };
    s / run.count.max(1) as f64
}

/// The log-log slope of total time against cloud size between two clouds (1 = linear), from
/// the time per point, so that it also applies to subsampled queries.
fn slope(n0: usize, r0: &Run, n1: usize, r1: &Run) -> f64 {
    1.0 + (seconds_per_point(r1) / seconds_per_point(r0)).ln() / (n1 as f64 / n0 as f64).ln()
}

/// "X points/s (wall); Y per CPU-second, so Z on `cores` idle cores".
fn rates(run: &Run) -> String {
    format!(
        "{} points/s ({:.2} s); {} per CPU-s → ≈ {} on {} idle cores",
        thousands(run.rate),
        run.seconds,
        thousands(run.cpu_rate()),
        thousands(run.cpu_rate() * cores() as f64),
        cores()
    )
}

/// Verdicts for a rate target: on this machine as it was, and estimated for idle cores.
fn rate_verdicts(run: &Run, target: f64) -> String {
    format!(
        "{}; idle estimate {}",
        verdict(run.rate, Goal::AtLeast(target)),
        verdict(run.cpu_rate() * cores() as f64, Goal::AtLeast(target))
    )
}

#[allow(clippy::too_many_lines)]
fn render(
    env: &Environment,
    stages: &[Stages],
    cutoffs: &[(f64, Run)],
    threads: &[(usize, Run, Run)],
    ad: &AdComparison,
    cli: &Cli,
) -> String {
    let sz = env.sizes;
    let mut md = String::new();
    let w = &mut md;
    let command = if env.quick {
        "cargo xtask bench --quick"
    } else {
        "cargo xtask bench"
    };
    let _ = writeln!(w, "# Benchmarks\n");
    let _ = writeln!(
        w,
        "Generated by `{command}` on {}, in {:.0} s. Do not edit by hand: rerun the command.\n",
        now_utc(),
        env.elapsed.as_secs_f64()
    );
    if env.quick {
        let _ = writeln!(
            w,
            "**Quick run**: clouds of {}, {} and {} points instead of 100k, 300k and 1M. The \
             verdicts compare rates, so they are indicative only.\n",
            thousands(sz.small as f64),
            thousands(sz.mid as f64),
            thousands(sz.large as f64)
        );
    }
    let _ = writeln!(w, "- Machine: {}.", machine());
    let _ = writeln!(
        w,
        "- Load average (1, 5, 15 min) before the run: {}; after: {}. The machine is shared: \
         other processes (other engineers' builds and tests) may have been running. With a \
         load above the core count the wall-clock rates are lower than an idle machine's, so \
         each parallel stage is also given per CPU-second of this process (from the \
         scheduler's counters, `/proc/self/task/*/schedstat`), and the idle estimate is that \
         times the cores; it assumes the parallel efficiency shown under \"Scaling with \
         threads\".",
        env.load_before, env.load_after
    );
    let _ = writeln!(
        w,
        "- Settings: mlscurv's defaults (h = 2 × median local spacing, cutoff 5h), rayon's \
         global pool, release profile (x86-64 baseline target, with the field's per-sample \
         loops also compiled for AVX2 and chosen at run time: here {isa}). Each time is the \
         best of {} runs ({} for {}-point clouds). Clouds: the unit Fibonacci sphere, and the \
         torus R = {}, r = {} on a parameter grid (spacing ±30 % between the inner and outer \
         equators), both with exact normals, generated by `mls-bench`.\n",
        sz.reps,
        sz.reps_large,
        thousands(sz.large as f64),
        mls_bench::TORUS_MAJOR,
        mls_bench::TORUS_MINOR,
        isa = mls_core::kernels::kernel_isa(),
    );

    // Targets.
    let _ = writeln!(w, "## Targets (issue 5)\n");
    let _ = writeln!(w, "| target | cloud | measured | goal | verdict |");
    let _ = writeln!(w, "| --- | --- | --- | --- | --- |");
    let large: Vec<&Stages> = stages
        .iter()
        .filter(|s| s.points >= sz.large - sz.large / 100)
        .collect();
    for s in &large {
        let _ = writeln!(
            w,
            "| curvature at input points, given normals | {} {} | {} | ≥ 250,000 points/s on 2 cores | {} |",
            thousands(s.points as f64),
            s.shape,
            rates(&s.curvature),
            rate_verdicts(&s.curvature, TARGET_CURVATURE_RATE)
        );
    }
    for (what, ad_time) in [
        (
            "AD of g alone (`num_dual::hessian` of `mls_ad::implicit`)",
            ad.ad_g,
        ),
        (
            "the full AD witness (`mls_ad::witness`: g, n, J, ∂²n)",
            ad.witness,
        ),
    ] {
        let ratio = ad_time / ad.closed;
        let _ = writeln!(
            w,
            "| closed form vs {what}, per evaluation | {:.0} neighbours | {ratio:.1}× ({:.2} µs vs {:.1} µs) | ≥ 5× | {} |",
            ad.neighbours,
            ad.closed * 1e6,
            ad_time * 1e6,
            verdict(ratio, Goal::AtLeast(TARGET_AD_RATIO))
        );
    }
    for s in &large {
        let _ = writeln!(
            w,
            "| normal estimation + MST orientation | {} {} | {} | ≤ 5 s per 1M points (≥ 200,000 points/s) | {} |",
            thousands(s.points as f64),
            s.shape,
            rates(&s.normals),
            rate_verdicts(&s.normals, TARGET_NORMALS_RATE)
        );
    }
    if let Some(s) = stages.iter().find(|s| s.io.is_some())
        && let Some(io) = &s.io
    {
        let n = s.points as f64;
        for (what, secs, bytes) in [
            (
                "read binary PLY (x y z nx ny nz, double; file in the page cache)",
                io.read_input,
                io.input_bytes,
            ),
            (
                "write binary PLY (x y z nx ny nz, double; atomic: temporary file, fsync, rename)",
                io.write_input,
                io.input_bytes,
            ),
            (
                "write mlscurv's output (17 columns, binary PLY, atomic)",
                io.write_output,
                io.output_bytes,
            ),
        ] {
            let _ = writeln!(
                w,
                "| {what} | {} points, {:.0} MB | {secs:.3} s ({} points/s) | ≤ 0.5 s per 1M points | {} |",
                thousands(n),
                bytes as f64 / 1e6,
                thousands(n / secs),
                verdict(n / secs, Goal::AtLeast(TARGET_IO_RATE))
            );
        }
    }
    for run in &cli.runs {
        match &run.peak_rss {
            Ok(bytes) => {
                let per = *bytes as f64 / run.points as f64;
                let _ = writeln!(
                    w,
                    "| peak memory of `mlscurv curvature` ({}) | {} sphere | {:.0} MB, {per:.0} bytes/point | ≤ 300 bytes/point | {} |",
                    run.label,
                    thousands(run.points as f64),
                    *bytes as f64 / 1e6,
                    verdict(per, Goal::AtMost(TARGET_BYTES_PER_POINT))
                );
            }
            Err(e) => {
                let _ = writeln!(
                    w,
                    "| peak memory of `mlscurv curvature` ({}) | | not measured: {e} | ≤ 300 bytes/point | — |",
                    run.label
                );
            }
        }
    }
    if let Some(e) = &cli.error {
        let _ = writeln!(
            w,
            "| peak memory of `mlscurv curvature` | | not measured: {} | ≤ 300 bytes/point | — |",
            e.lines().next().unwrap_or_default()
        );
    }
    let spheres: Vec<&Stages> = stages.iter().filter(|s| s.shape == "sphere").collect();
    if let (Some(first), Some(last)) = (spheres.first(), spheres.last()) {
        for (what, r0, r1) in [
            ("curvature", &first.curvature, &last.curvature),
            ("projection", &first.projection, &last.projection),
            ("normals + orientation", &first.normals, &last.normals),
        ] {
            let k = slope(first.points, r0, last.points, r1);
            let _ = writeln!(
                w,
                "| run time linear in points: {what} (log-log slope of CPU time) | sphere {} → {} | {k:.2} | ≤ {MAX_LINEAR_SLOPE} | {} |",
                thousands(first.points as f64),
                thousands(last.points as f64),
                verdict(k, Goal::AtMost(MAX_LINEAR_SLOPE))
            );
        }
    }
    let _ = writeln!(
        w,
        "\n\"Idle estimate\" is the CPU-time rate times {} cores (see above). For comparison, \
         the issue quotes on this class of machine: CGAL jet fitting 51,000 points/s (2 \
         threads), MeshLab APSS curvature 18,000 points/s (1 thread), PCL normals + unsigned \
         curvature 96,000 points/s, Open3D normals alone 242,000 points/s and its MST \
         orientation of a 1M-point sphere 47 s. Those tools were not run here.\n",
        cores()
    );

    // Arithmetic bound.
    let flops: u32 = FLOPS_PER_NEIGHBOUR.iter().map(|(_, f)| f).sum();
    let hash = fnv1a(FIELD_RS);
    let _ = writeln!(w, "## Arithmetic bound\n");
    let _ = writeln!(
        w,
        "**Machine peak**, measured: independent f64 multiply-adds (`a = a·x + y` on 16 or 32 \
         accumulators) compiled for the instruction set the field's per-sample loops run with \
         here, **{isa}** ({lanes}, no FMA), run at **{:.1} GFLOP/s per core** (per CPU-second \
         of the thread, so other processes do not lower it). The field's loops are chosen at \
         run time (`mls_core::kernels::kernel_isa`): AVX2 where the CPU has it, else the x86-64 \
         baseline (SSE2, 2 lanes); both give the same bits. Multiply and add stay separate \
         roundings, so FMA is not used; AVX-512 (8 lanes) is not used either.\n",
        env.peak / 1e9,
        isa = mls_core::kernels::kernel_isa(),
        lanes = if mls_core::kernels::kernel_isa() == "avx2" {
            "4 lanes"
        } else {
            "2 lanes"
        },
    );
    let _ = writeln!(
        w,
        "**Work per point**: `field::evaluate` makes two passes over the support. Per neighbour \
         it costs **{flops} flops**, counted by reading `crates/mls-core/src/field.rs`: one \
         flop per f64 add, subtract or multiply (none for comparisons, min or sign changes); \
         lengths are in units of h, so a = 1/h² is 1 and its products fold away at compile \
         time, while the 3 multiplies of each d = (x − q)/h are counted; `exp` as {EXP_FLOPS} \
         (field.rs's branch-free `exp_weight`: range reduction, degree-5 polynomial, one division, \
         scaling by 2^k). The neighbour query, the \
         per-point 3 × 3 algebra and the curvature are not counted.\n"
    );
    let _ = writeln!(w, "| part | flops |\n| --- | --- |");
    for (what, f) in FLOPS_PER_NEIGHBOUR {
        let _ = writeln!(w, "| {what} | {f} |");
    }
    let _ = writeln!(w, "| **total** | **{flops}** |\n");
    if hash != FLOPS_COUNTED_HASH {
        let _ = writeln!(
            w,
            "**The count may be stale**: the `field.rs` measured here is not the one counted \
             (FNV-1a {hash:#018x}, counted {FLOPS_COUNTED_HASH:#018x}); recount \
             `FLOPS_PER_NEIGHBOUR` in `xtask/src/bench.rs`.\n"
        );
    }
    let _ = writeln!(
        w,
        "The bound is peak / (neighbours × flops per neighbour), per core; measured is points \
         per CPU-second of curvature at input points (all threads' CPU time).\n"
    );
    let _ = writeln!(
        w,
        "| cloud | threads | neighbours / point | flops / point | bound (points / CPU-s) | measured (points / CPU-s) | fraction of bound | achieved GFLOP/s per core |"
    );
    let _ = writeln!(w, "| --- | --- | --- | --- | --- | --- | --- | --- |");
    let bound_row = |w: &mut String, label: String, t: usize, run: &Run| {
        let per_point = run.neighbours * f64::from(flops);
        let bound = env.peak / per_point;
        let _ = writeln!(
            w,
            "| {label} | {t} | {:.0} | {} | {} | {} | {:.0} % | {:.1} |",
            run.neighbours,
            thousands(per_point),
            thousands(bound),
            thousands(run.cpu_rate()),
            100.0 * run.cpu_rate() / bound,
            run.cpu_rate() * per_point / 1e9
        );
    };
    for s in &large {
        bound_row(
            w,
            format!("{} {}", thousands(s.points as f64), s.shape),
            cores(),
            &s.curvature,
        );
    }
    for (t, run, _) in threads {
        bound_row(w, format!("{} sphere", thousands(sz.mid as f64)), *t, run);
    }
    let _ = writeln!(
        w,
        "\nWhat the fraction leaves out is the neighbour query, the per-point work and memory \
         stalls; the flat profile under \"The whole command\" and the criterion benches \
         (`cargo bench -p mls-bench`: evaluation alone vs `support_of`) split it.\n"
    );

    // Throughput tables.
    let _ = writeln!(w, "## Throughput by stage and size\n");
    let _ = writeln!(
        w,
        "Points per second of wall-clock time, all threads, and in brackets per CPU-second. \
         Curvature: at the input points with the exact normals. Projection: `--at projected`, \
         the MLS projection of input points then curvature there (at most {} queries per \
         cloud). Normals: estimation (16 neighbours, automatic h) and MST orientation from \
         scratch; \"outward\" is the share that agrees in sign with the exact normal.\n",
        thousands(sz.projection_queries as f64)
    );
    let _ = writeln!(
        w,
        "| cloud | points | h | spacing (s) | k-d tree (s) | curvature | neighbours | ok | projection | normals | outward |"
    );
    let _ = writeln!(
        w,
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for s in stages {
        let _ = writeln!(
            w,
            "| {} | {} | {:.3e} | {:.3} | {:.3} | {} ({}) | {:.0} | {:.2} % | {} ({}) | {} ({}) | {:.2} % |",
            s.shape,
            thousands(s.points as f64),
            s.h,
            s.spacing_seconds,
            s.index_seconds,
            thousands(s.curvature.rate),
            thousands(s.curvature.cpu_rate()),
            s.curvature.neighbours,
            100.0 * s.curvature.ok as f64 / s.curvature.count.max(1) as f64,
            thousands(s.projection.rate),
            thousands(s.projection.cpu_rate()),
            thousands(s.normals.rate),
            thousands(s.normals.cpu_rate()),
            100.0 * s.normals.ok as f64 / s.normals.count.max(1) as f64,
        );
    }
    let _ = writeln!(
        w,
        "\n### Scaling with point count\n\nSphere; log-log slope of CPU time against points \
         between consecutive sizes (1 = linear):\n"
    );
    let _ = writeln!(
        w,
        "| from → to | curvature | projection | normals + orientation |\n| --- | --- | --- | --- |"
    );
    for pair in spheres.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let _ = writeln!(
            w,
            "| {} → {} | {:.2} | {:.2} | {:.2} |",
            thousands(a.points as f64),
            thousands(b.points as f64),
            slope(a.points, &a.curvature, b.points, &b.curvature),
            slope(a.points, &a.projection, b.points, &b.projection),
            slope(a.points, &a.normals, b.points, &b.normals),
        );
    }

    let _ = writeln!(
        w,
        "\n### Scaling with cutoff\n\n{} sphere, curvature at input points:\n",
        thousands(sz.mid as f64)
    );
    let _ = writeln!(
        w,
        "| cutoff | neighbours / point | points/s | points / CPU-s | CPU ns per neighbour |\n| --- | --- | --- | --- | --- |"
    );
    for (c, run) in cutoffs {
        let _ = writeln!(
            w,
            "| {c}h | {:.0} | {} | {} | {:.1} |",
            run.neighbours,
            thousands(run.rate),
            thousands(run.cpu_rate()),
            1e9 / (run.cpu_rate() * run.neighbours)
        );
    }

    let _ = writeln!(
        w,
        "\n### Scaling with threads\n\n{} sphere, a rayon pool of the given size installed \
         around the call. Parallel efficiency is points per CPU-second relative to one thread \
         (1 = no parallel overhead); the wall-clock speed-up also depends on what else ran.\n",
        thousands(sz.mid as f64)
    );
    let _ = writeln!(
        w,
        "| threads | curvature points/s | speed-up | parallel efficiency | normals points/s | speed-up | parallel efficiency |\n| --- | --- | --- | --- | --- | --- | --- |"
    );
    if let Some((_, c1, n1)) = threads.first() {
        for (t, c, n) in threads {
            let _ = writeln!(
                w,
                "| {t} | {} | {:.2} | {:.2} | {} | {:.2} | {:.2} |",
                thousands(c.rate),
                c.rate / c1.rate,
                c.cpu_rate() / c1.cpu_rate(),
                thousands(n.rate),
                n.rate / n1.rate,
                n.cpu_rate() / n1.cpu_rate()
            );
        }
    }

    let _ = writeln!(w, "\n## Closed form against automatic differentiation\n");
    let _ = writeln!(
        w,
        "{} query points near the {}-point sphere, each a little off the surface and off the \
         samples, {:.0} neighbours on average, the same support for both; one thread, wall \
         clock, best of 3 batches. Closed form: `field::evaluate` + `curvature` ({:.2} µs). AD \
         of g alone: `num_dual::hessian` of `mls_ad::implicit` + `witness_curvature` ({:.1} \
         µs, {:.1}×). Full witness: `mls_ad::witness`, which also differentiates n three times \
         for J and ∂²n (the closed form computes those too), + `witness_curvature` ({:.1} µs, \
         {:.1}×). Largest relative difference of the two Hessians: {:.1e}.\n",
        sz.ad_queries,
        thousands(sz.large as f64),
        ad.neighbours,
        ad.closed * 1e6,
        ad.ad_g * 1e6,
        ad.ad_g / ad.closed,
        ad.witness * 1e6,
        ad.witness / ad.closed,
        ad.worst_hessian_difference
    );

    let _ = writeln!(w, "## The whole command\n");
    if let Some(e) = &cli.error {
        let _ = writeln!(w, "Not measured: {e}\n");
    }
    for run in &cli.runs {
        let _ = writeln!(
            w,
            "- `mlscurv curvature IN.ply -o OUT.ply` on {} sphere points ({}): {:.2} s wall \
             ({} points/s), peak RSS {} (read by {}). Its own stage times (s): {}.",
            thousands(run.points as f64),
            run.label,
            run.wall_seconds,
            thousands(run.points as f64 / run.wall_seconds),
            run.peak_rss.as_ref().map_or_else(
                |e| format!("unknown ({e})"),
                |b| format!(
                    "{:.0} MB = {:.0} bytes/point",
                    *b as f64 / 1e6,
                    *b as f64 / run.points as f64
                )
            ),
            run.method,
            run.stage_times
        );
    }
    if !cli.profiles.is_empty() {
        let _ = writeln!(
            w,
            "\nFlat profiles of the same two commands, by `perf record -e cpu-clock` (self time \
             by symbol, entries ≥ 1 %, all threads). Inlined code is attributed to the function \
             it was inlined into; entries named `Map<I,F>::fold` are iterator closures compiled \
             into a fold (`perf annotate` on the symbol shows their source lines). `[k]` is \
             kernel time (page faults of fresh allocations)."
        );
    }
    for (label, p) in &cli.profiles {
        let _ = writeln!(w, "\n{label}:\n\n```text\n{p}\n```");
    }

    let _ = writeln!(
        w,
        "\n## Criterion benches\n\n`cargo bench -p mls-bench` (a few minutes) times the pieces \
         on a 100k-point sphere: `evaluation` (one closed-form evaluation against `ad_g` and \
         `ad_witness` on the same support, printing the ratio at the end; the curvature from \
         ∇g and H alone; `support_of`, the neighbour query, at 3h and 5h) and `cloud` (the \
         k-nearest-neighbour graph, covariance normals, MST orientation, all of \
         `estimate_normals`, projection, and whole-cloud curvature sequential and parallel). \
         Criterion keeps its history under `target/criterion`, so a change shows as a ratio \
         against the previous run."
    );
    md
}
