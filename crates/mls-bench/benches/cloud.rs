//! Whole-cloud stages on a 100k-point unit sphere at mlscurv's defaults (h = 2 × spacing,
//! cutoff 5h): normal estimation (neighbour graph, covariance normals, orientation),
//! projection, and curvature at every point, sequential and parallel.
//!
//! `cargo bench -p mls-bench --bench cloud`. The end-to-end figures against the issue's
//! targets (1M points, file I/O, memory, scaling) come from `cargo xtask bench`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use mls_bench::{Cloud, default_h};
use mls_core::normals::{
    DEFAULT_DEGENERACY_TOLERANCE, DEFAULT_NEIGHBOURS, NeighbourGraph, Orientation,
    estimate_unoriented, orient_normals,
};
use mls_core::{Cutoff, NormalsConfig, Parallelism, estimate_normals};

const CLOUD_POINTS: usize = 100_000;

/// One in this many points is a projection query.
const PROJECTION_STEP: usize = 50;

fn normals(c: &mut Criterion) {
    let cloud = Cloud::sphere(CLOUD_POINTS);
    let points = &cloud.points;
    let h = default_h(points);
    let par = Parallelism::Rayon;
    let mut group = c.benchmark_group("normals");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements(points.len() as u64));
    group.bench_function("neighbour_graph_k16", |b| {
        b.iter(|| NeighbourGraph::build(black_box(points), DEFAULT_NEIGHBOURS, par));
    });
    let graph = NeighbourGraph::build(points, DEFAULT_NEIGHBOURS, par).expect("valid cloud");
    group.bench_function("covariance_normals", |b| {
        b.iter(|| estimate_unoriented(points, &graph, h, DEFAULT_DEGENERACY_TOLERANCE, par));
    });
    // Orientation from arbitrary signs: every other normal flipped.
    let mut unoriented = estimate_unoriented(points, &graph, h, DEFAULT_DEGENERACY_TOLERANCE, par)
        .expect("valid parameters");
    for e in unoriented.iter_mut().step_by(2).flatten() {
        e.normal = -e.normal;
    }
    group.bench_function("orientation_mst", |b| {
        b.iter_batched_ref(
            || unoriented.clone(),
            |est| orient_normals(points, &graph, est, Orientation::Outward, par),
            BatchSize::LargeInput,
        );
    });
    // The whole of what mlscurv does for a cloud without normals (also derives h).
    group.bench_function("estimate_normals_all_stages", |b| {
        b.iter(|| estimate_normals(points, &NormalsConfig::default(), par));
    });
    group.finish();
}

fn projection(c: &mut Criterion) {
    let cloud = Cloud::sphere(CLOUD_POINTS);
    let h = default_h(&cloud.points);
    let surface = cloud.surface(h, Cutoff::DEFAULT);
    // Queries a third of h off the surface, the scale of scanner noise at these settings.
    let queries = cloud.offset_queries(PROJECTION_STEP, h / 3.0);
    let mut group = c.benchmark_group("projection");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Elements(queries.len() as u64));
    group.bench_function("project_points_sequential", |b| {
        b.iter(|| surface.project_points(black_box(&queries), Parallelism::Sequential));
    });
    group.finish();
}

fn whole_cloud_curvature(c: &mut Criterion) {
    let cloud = Cloud::sphere(CLOUD_POINTS);
    let h = default_h(&cloud.points);
    let surface = cloud.surface(h, Cutoff::DEFAULT);
    let mut group = c.benchmark_group(format!(
        "curvature_at_points/{}k_sphere/{}_threads",
        CLOUD_POINTS / 1000,
        rayon::current_num_threads()
    ));
    // Each iteration is a whole cloud (about a second): ten samples, no warm-up beyond one.
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_secs(5))
        .throughput(Throughput::Elements(cloud.len() as u64));
    for (name, par) in [
        ("sequential", Parallelism::Sequential),
        ("rayon", Parallelism::Rayon),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| surface.curvature_at_points(black_box(&cloud.points), par));
        });
    }
    group.finish();
}

criterion_group!(benches, normals, projection, whole_cloud_curvature);
criterion_main!(benches);
