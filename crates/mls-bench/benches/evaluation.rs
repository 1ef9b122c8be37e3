//! One evaluation: the closed form (g, ∇g, H and curvature, mls-core) against the hyper-dual
//! AD witness (mls-ad) on the same neighbourhood, and the neighbour query that gathers it.
//!
//! The number to watch is the ratio AD / closed form, printed at the end (target ≥ 5×, issue
//! 5). Two AD variants are timed: `ad_g` differentiates g alone (`num_dual::hessian` of
//! `mls_ad::implicit`), the like-for-like comparison; `ad_witness` is `mls_ad::witness`,
//! which also differentiates n(x) three times to get J and ∂²n, as the closed form does.
//!
//! `cargo bench -p mls-bench --bench evaluation`

use std::hint::black_box;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use mls_bench::{Cloud, default_h};
use mls_core::field::{FieldScratch, evaluate};
use mls_core::{Cutoff, Point, Sample, Vector, curvature};

/// Points on the benchmark sphere; h and the neighbour count follow from it.
const CLOUD_POINTS: usize = 100_000;

/// Total (iterations, time) per benchmark name, filled by `iter_custom` so that the ratio can
/// be printed after criterion has measured both.
static TALLY: Mutex<Vec<(&'static str, u64, Duration)>> = Mutex::new(Vec::new());

fn tally(name: &'static str, iters: u64, elapsed: Duration) {
    let mut t = TALLY.lock().unwrap_or_else(|e| e.into_inner());
    match t.iter_mut().find(|(n, _, _)| *n == name) {
        Some(entry) => {
            entry.1 += iters;
            entry.2 += elapsed;
        }
        None => t.push((name, iters, elapsed)),
    }
}

/// Runs `f` `iters` times, records the time under `name` and returns it.
fn timed<T>(name: &'static str, iters: u64, mut f: impl FnMut() -> T) -> Duration {
    let start = Instant::now();
    for _ in 0..iters {
        black_box(f());
    }
    let elapsed = start.elapsed();
    tally(name, iters, elapsed);
    elapsed
}

/// A query point near the sphere but on no sample (so that no distance is exactly zero),
/// and its support at h = 2 × spacing, cutoff 5h.
fn neighbourhood() -> (Point, Vec<Sample>, f64) {
    let cloud = Cloud::sphere(CLOUD_POINTS);
    let h = default_h(&cloud.points);
    let surface = cloud.surface(h, Cutoff::DEFAULT);
    let i = CLOUD_POINTS / 3;
    let (p, n) = (cloud.points[i], cloud.normals[i]);
    let tangent = n.cross(&Vector::z()).normalize();
    let x = p + (n * 0.1 + tangent * 0.3) * h;
    let support = surface.evaluator().support_of(&x);
    (x, support, 1.0 / (h * h))
}

fn evaluation(c: &mut Criterion) {
    let (x, samples, inv_h2) = neighbourhood();
    let mut group = c.benchmark_group(format!("evaluation/{}_neighbours", samples.len()));
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    let mut scratch = FieldScratch::default();
    group.bench_function("closed_form", |b| {
        b.iter_custom(|iters| {
            timed("closed_form", iters, || {
                let implicit = evaluate(black_box(&x), &samples, inv_h2, &mut scratch)
                    .expect("the support is a clean sphere patch");
                curvature(&implicit.gradient, &implicit.hessian)
            })
        });
    });
    let xv = x.coords;
    group.bench_function("ad_g", |b| {
        b.iter_custom(|iters| {
            timed("ad_g", iters, || {
                let shift = mls_ad::log_scale(black_box(&xv), &samples, inv_h2);
                let (_, grad, hess) = num_dual::hessian(
                    |v| mls_ad::implicit(&v, &samples, inv_h2, shift),
                    black_box(&xv),
                );
                mls_ad::witness_curvature(&grad, &hess)
            })
        });
    });
    group.bench_function("ad_witness", |b| {
        b.iter_custom(|iters| {
            timed("ad_witness", iters, || {
                let w = mls_ad::witness(black_box(&xv), &samples, inv_h2);
                mls_ad::witness_curvature(&w.gradient, &w.hessian)
            })
        });
    });
    group.finish();

    // Curvature from (∇g, H) alone, to see its share of `closed_form`.
    let implicit = evaluate(&x, &samples, inv_h2, &mut scratch).expect("clean patch");
    c.bench_function("curvature_from_gradient_and_hessian", |b| {
        b.iter(|| curvature(black_box(&implicit.gradient), black_box(&implicit.hessian)));
    });
}

fn neighbour_query(c: &mut Criterion) {
    let cloud = Cloud::sphere(CLOUD_POINTS);
    let h = default_h(&cloud.points);
    let queries: Vec<Point> = cloud.points.iter().step_by(100).copied().collect();
    let mut group = c.benchmark_group("neighbour_query");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(queries.len() as u64));
    for factor in [3.0, 5.0] {
        let surface = cloud.surface(h, Cutoff::Radius(factor));
        let mut ev = surface.evaluator();
        // `support_of` copies the support into a new Vec: one allocation per query that the
        // curvature path (which reuses the evaluator's buffer) does not make.
        group.bench_function(BenchmarkId::new("support_of", format!("{factor}h")), |b| {
            b.iter(|| {
                queries
                    .iter()
                    .map(|q| ev.support_of(q).len())
                    .sum::<usize>()
            });
        });
    }
    group.finish();
}

/// Prints AD / closed-form time per evaluation from the tallies.
fn ratio(_: &mut Criterion) {
    let t = TALLY.lock().unwrap_or_else(|e| e.into_inner());
    let per_eval = |name: &str| {
        t.iter()
            .find(|(n, iters, _)| *n == name && *iters > 0)
            .map(|(_, iters, d)| d.as_secs_f64() / *iters as f64)
    };
    let Some(closed) = per_eval("closed_form") else {
        return;
    };
    println!("\nclosed form: {:.2} µs per evaluation", closed * 1e6);
    for name in ["ad_g", "ad_witness"] {
        if let Some(ad) = per_eval(name) {
            println!(
                "{name}: {:.2} µs per evaluation, {:.1}× the closed form (target ≥ 5×)",
                ad * 1e6,
                ad / closed
            );
        }
    }
}

criterion_group!(benches, evaluation, neighbour_query, ratio);
criterion_main!(benches);
