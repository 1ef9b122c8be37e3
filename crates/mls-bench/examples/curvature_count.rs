//! Curvature at every point of a generated sphere, sequentially, for instruction counting:
//! `valgrind --tool=callgrind --toggle-collect='*curvature_at_points*' \
//!   target/release/examples/curvature_count 50000`
//! then divide the collected instructions by the point count. Callgrind's counts are
//! deterministic, unlike wall-clock time on a shared machine. With a second argument
//! `rayon`, the run is parallel and also timed (best of three, wall clock).

use std::hint::black_box;

use mls_bench::{Cloud, default_h};
use mls_core::{Cutoff, Parallelism};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(50_000, |s| s.parse().expect("point count"));
    let cloud = Cloud::sphere(n);
    let h = default_h(&cloud.points);
    let surface = cloud.surface(h, Cutoff::DEFAULT);
    let par = match std::env::args().nth(2).as_deref() {
        Some("rayon") => Parallelism::Rayon,
        _ => Parallelism::Sequential,
    };
    let mut results = Vec::new();
    let mut best = f64::INFINITY;
    for _ in 0..if par == Parallelism::Rayon { 3 } else { 1 } {
        let start = std::time::Instant::now();
        results = surface.curvature_at_points(black_box(&cloud.points), par);
        best = best.min(start.elapsed().as_secs_f64());
    }
    println!("{:.0} points/s ({par:?}, best run)", n as f64 / best);
    let ok = results.iter().filter(|r| r.is_ok()).count();
    let mean: f64 = results
        .iter()
        .flatten()
        .map(|r| r.curvature.mean)
        .sum::<f64>()
        / ok as f64;
    println!("{n} points, {ok} ok, mean curvature {mean:.12}");
}
