//! `cargo xtask bench [--quick]`: end-to-end throughput, memory and scaling on generated
//! clouds, against the targets of issue 5. The full run writes `docs/benchmarks.md`; `--quick`
//! runs small sizes in well under a minute (after compilation) and writes
//! `target/bench/quick.md`, so that CI can check the task still works without overwriting the
//! measured report.
//!
//! Every measurement uses mlscurv's defaults (h = 2 × the median local spacing, cutoff 5h)
//! and rayon's global pool (all cores) unless it says otherwise. Times are the best of a few
//! repetitions: the machine is shared, and the best run is the least disturbed one.

mod cli;
mod environment;
mod measure;
mod report;

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use mls_bench::{Cloud, default_h};
use mls_core::Cutoff;

use cli::*;
use environment::*;
use measure::*;
use report::*;

pub(crate) use cli::build_mlscurv;
pub(crate) use environment::{load_average, machine, now_utc, target_dir};
pub(crate) use measure::process_cpu_seconds;

/// Curvature at the input points with given normals, 1M points, 2 cores (points/s).
pub(super) const TARGET_CURVATURE_RATE: f64 = 250_000.0;
/// AD witness time / closed-form time per evaluation.
pub(super) const TARGET_AD_RATIO: f64 = 5.0;
/// Normal estimation plus orientation of 1M points (s), as a rate.
pub(super) const TARGET_NORMALS_RATE: f64 = 1e6 / 5.0;
/// Reading or writing a 1M-point binary PLY (s), as a rate.
pub(super) const TARGET_IO_RATE: f64 = 1e6 / 0.5;
/// Peak resident memory of `mlscurv curvature` per input point (bytes).
pub(super) const TARGET_BYTES_PER_POINT: f64 = 300.0;
/// "Linear in the number of points": the log-log slope of time against points from the
/// smallest to the largest cloud must not exceed this (1 is linear; n log n over 100k → 1M
/// gives 1.18 for log n, and a cache-bound algorithm shows some excess too).
pub(super) const MAX_LINEAR_SLOPE: f64 = 1.1;

/// Floating-point operations per neighbour of `mls_core::field::evaluate`, counted by reading
/// its per-sample loops, [`COUNTED_SOURCES`] (the versions whose FNV-1a hash is
/// [`FLOPS_COUNTED_HASH`]).
///
/// Counting rules: one flop per f64 add, subtract, multiply or divide (a fused multiply-add
/// counts as two); comparisons, min and sign changes count as none. Lengths are in units of h
/// (`d = (x − q)/h`, formed once per neighbour and reused by both passes), so `a = 1` and products by
/// `a` or constants of it fold away at compile time. `exp` counts as [`EXP_FLOPS`] (mls-core's
/// own branch-free `exp_weight`: range reduction, a degree-5 polynomial in a rational form with
/// one division, and the scaling by 2^k, 28 operations).
/// Per-point work (the 3 × 3 algebra after the loops, the curvature, the neighbour query) is
/// not in this count, nor are the candidates beyond the cutoff that the curvature path tests
/// and rejects (about a third more than the neighbours on a sphere; each costs the first row).
pub(super) const FLOPS_PER_NEIGHBOUR: &[(&str, u32)] = &[
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
pub(super) const EXP_FLOPS: u32 = 28;
/// FNV-1a hash of the [`COUNTED_SOURCES`] that [`FLOPS_PER_NEIGHBOUR`] was counted from,
/// concatenated in their order. When the compiled files differ, the report says that the count
/// may be stale. Recounted after 262487a, which added `offset_blocks` (the projection's reload,
/// not part of `evaluate`) and left `evaluate`'s loops as counted.
pub(super) const FLOPS_COUNTED_HASH: u64 = 0xde88_3f39_d7f8_f0ad;

/// The files that hold every per-neighbour operation of `field::evaluate` (its loops and their
/// exp), as this binary was compiled (cargo rebuilds the xtask when they change). `field.rs`
/// itself holds only per-point algebra, which the count leaves out.
pub(super) const COUNTED_SOURCES: [(&str, &[u8]); 2] = [
    (
        "crates/mls-core/src/kernels/field.rs",
        include_bytes!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../crates/mls-core/src/kernels/field.rs"
        )),
    ),
    (
        "crates/mls-core/src/kernels/exp.rs",
        include_bytes!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../crates/mls-core/src/kernels/exp.rs"
        )),
    ),
];

#[derive(Clone, Copy, Debug)]
pub(super) struct Sizes {
    pub(super) small: usize,
    pub(super) mid: usize,
    pub(super) large: usize,
    /// At most this many projection queries per cloud (every k-th input point).
    pub(super) projection_queries: usize,
    /// Query points for the closed-form / AD comparison.
    pub(super) ad_queries: usize,
    /// Repetitions (best of) for clouds up to `mid`, and for `large`.
    pub(super) reps: usize,
    pub(super) reps_large: usize,
}

pub(super) const FULL: Sizes = Sizes {
    small: 100_000,
    mid: 300_000,
    large: 1_000_000,
    projection_queries: 100_000,
    ad_queries: 32,
    reps: 3,
    reps_large: 2,
};

pub(super) const QUICK: Sizes = Sizes {
    small: 10_000,
    mid: 30_000,
    large: 100_000,
    projection_queries: 10_000,
    ad_queries: 8,
    reps: 2,
    reps_large: 1,
};

pub(crate) fn run(quick: bool) -> Result<()> {
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
