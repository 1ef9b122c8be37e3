//! Times each stage of normal estimation and orientation on a 1M-point Fibonacci sphere.
//!
//! `cargo run -p mls-core --release --example orient_speed [points] [k] [shuffle]`
//!
//! With `shuffle` the points are stored in random order, which defeats the locality of the
//! spiral's index order (a worst case for caches; real scans are usually ordered).

use std::f64::consts::PI;
use std::time::Instant;

use mls_core::normals::{
    DEFAULT_DEGENERACY_TOLERANCE, DEFAULT_H_FACTOR, DEFAULT_SPACING_NEIGHBOURS, NeighbourGraph,
    Orientation, estimate_unoriented, orient_normals, spacing_statistics, suggest_h,
};
use mls_core::{Parallelism, Point, Vector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Seed of the random sign flips applied before orientation.
const FLIP_SEED: u64 = 0x5EED_F11B;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map_or(Ok(1_000_000), |a| a.parse())?;
    let k: usize = args.next().map_or(Ok(10), |a| a.parse())?;
    let shuffle = args.next().as_deref() == Some("shuffle");
    let par = Parallelism::Rayon;
    println!(
        "{n} points on a unit Fibonacci sphere{}, k = {k}, {} rayon threads",
        if shuffle { " (shuffled)" } else { "" },
        rayon::current_num_threads()
    );

    let golden = PI * (3.0 - 5.0_f64.sqrt());
    let mut points: Vec<Point> = (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            Point::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(FLIP_SEED);
    if shuffle {
        // Fisher–Yates with the seeded generator.
        for i in (1..n).rev() {
            points.swap(i, rng.random_range(0..=i));
        }
    }

    let t = Instant::now();
    let stats = spacing_statistics(&points, DEFAULT_SPACING_NEIGHBOURS, par)?;
    let h = suggest_h(&stats, DEFAULT_H_FACTOR)?;
    println!(
        "spacing statistics   {:>7.3} s  (spacing {:.3e}, √(4π/N) {:.3e}, h {h:.3e})",
        t.elapsed().as_secs_f64(),
        stats.spacing,
        (4.0 * PI / n as f64).sqrt()
    );

    let t = Instant::now();
    let graph = NeighbourGraph::build(&points, k, par)?;
    println!("neighbour graph      {:>7.3} s", t.elapsed().as_secs_f64());

    let t = Instant::now();
    let mut estimates = estimate_unoriented(&points, &graph, h, DEFAULT_DEGENERACY_TOLERANCE, par)?;
    println!("unoriented normals   {:>7.3} s", t.elapsed().as_secs_f64());

    for e in estimates.iter_mut().flatten() {
        if rng.random_bool(0.5) {
            e.normal = -e.normal;
        }
    }
    let flipped_input = estimates.clone();

    for (name, par) in [
        ("rayon", Parallelism::Rayon),
        ("sequential", Parallelism::Sequential),
    ] {
        let mut est = flipped_input.clone();
        let t = Instant::now();
        let report = orient_normals(&points, &graph, &mut est, Orientation::Outward, par)?;
        let elapsed = t.elapsed().as_secs_f64();
        let inward = points
            .iter()
            .zip(&est)
            .filter(|(p, e)| {
                e.as_ref().map_or(true, |e| {
                    e.normal.as_vector().dot(&Vector::from(p.coords)) <= 0.0
                })
            })
            .count();
        println!(
            "orientation ({name:<10}) {elapsed:>7.3} s  ({} components, {} flipped, consistency {:?}, {inward} not outward)",
            report.components, report.flipped, report.consistency
        );
    }
    Ok(())
}
