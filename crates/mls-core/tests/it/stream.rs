//! Streaming evaluation: results bitwise independent of the chunk size and of the thread
//! count, for the paper's curvature, the projection, the jet and the adaptive scale.

use mls_core::{
    AdaptiveConfig, AdaptiveSurface, JetConfig, Location, MlsConfig, MlsSurface, Parallelism,
    Point, Vector,
};
use mls_shapes::Torus;

const CLOUD_SEED: u64 = 23;
const QUERY_SEED: u64 = 29;

/// 4,000 samples at random parameters of a torus (uneven density), and 17,002 queries: the
/// samples, points off the surface by up to ±0.1 (a twentieth of the tube radius), one
/// non-finite and one far outside the cloud. More queries than the largest chunk tried, so
/// that every chunk size cuts the Morton clusters of a whole-set call differently.
fn torus_cloud() -> (MlsSurface, Vec<Point>) {
    let torus = Torus::new(6.0, 2.0);
    let samples = mls_shapes::random(&torus, 4_000, CLOUD_SEED);
    let points: Vec<Point> = samples.iter().map(|s| s.surface.point).collect();
    let normals: Vec<Vector> = samples.iter().map(|s| s.surface.normal).collect();
    let surface = MlsSurface::new(&points, &normals, MlsConfig::new(0.7)).unwrap();
    let mut queries = points;
    let off = mls_shapes::random(&torus, 13_000, QUERY_SEED);
    queries.extend(off.iter().enumerate().map(|(k, s)| {
        let t = 0.1 * ((k % 21) as f64 / 10.0 - 1.0);
        s.surface.point + s.surface.normal * t
    }));
    queries.push(Point::new(f64::NAN, 0.0, 0.0));
    queries.push(Point::new(100.0, 0.0, 0.0));
    (surface, queries)
}

/// Collects a stream's chunks into query order, checking that no chunk is empty and that
/// every query comes exactly once.
fn collect<R: Clone>(n: usize, stream: impl FnOnce(&mut dyn FnMut(&[usize], &[R]))) -> Vec<R> {
    let mut out: Vec<Option<R>> = vec![None; n];
    stream(&mut |indices, chunk| {
        assert!(!indices.is_empty(), "an empty chunk");
        assert_eq!(indices.len(), chunk.len());
        for (&i, r) in indices.iter().zip(chunk) {
            assert!(out[i].is_none(), "query {i} came twice");
            out[i] = Some(r.clone());
        }
    });
    out.into_iter()
        .enumerate()
        .map(|(i, r)| r.unwrap_or_else(|| panic!("query {i} never came")))
        .collect()
}

/// Runs `f` in a rayon pool of `threads` threads.
fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// Asserts that two result lists are bitwise equal: `{:?}` prints an f64 as the shortest
/// decimal that reads back to the same bits (and tells −0 from 0), which `==` does not.
fn assert_bitwise<R: std::fmt::Debug>(a: &[R], b: &[R], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}");
    for (i, (a, b)) in a.iter().zip(b).enumerate() {
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "{what}: query {i}");
    }
}

type Run = (
    Vec<mls_core::PointResult>,
    Vec<mls_core::PointResult>,
    Vec<Result<mls_core::JetPoint, mls_core::PointStatus>>,
);

fn assert_same_run(a: &Run, b: &Run, what: &str) {
    assert_bitwise(&a.0, &b.0, &format!("curvature, {what}"));
    assert_bitwise(&a.1, &b.1, &format!("projection, {what}"));
    assert_bitwise(&a.2, &b.2, &format!("jet, {what}"));
}

#[test]
fn stream_results_do_not_depend_on_chunk_size_or_threads() {
    let (surface, queries) = torus_cloud();
    let n = queries.len();
    let jet = JetConfig::default();
    let par = Parallelism::Rayon;
    // The projection costs ten times the others: it runs on every fourth query, in chunks a
    // quarter as large.
    let few: Vec<Point> = queries.iter().step_by(4).copied().collect();
    let run = |chunk: usize, par: Parallelism| -> Run {
        (
            collect(n, |sink| {
                surface.curvature_stream(&queries, par, chunk, sink)
            }),
            collect(few.len(), |sink| {
                surface.projection_stream(&few, par, chunk.div_ceil(4), sink)
            }),
            collect(n, |sink| {
                surface.jet_stream(&queries, &jet, par, chunk, sink)
            }),
        )
    };
    let reference = with_threads(2, || run(n, par));
    let ok = reference.0.iter().filter(|r| r.is_ok()).count();
    assert!(ok > n * 9 / 10, "{ok} of {n} curvatures");
    // The whole-set calls give the stream's bits.
    assert_bitwise(
        &reference.0,
        &surface.curvature_at_points(&queries, par),
        "curvature_at_points",
    );
    assert_bitwise(
        &reference.1,
        &surface.project_points(&few, par),
        "project_points",
    );
    for chunk in [1_000, 7_000, 16_384] {
        let other = with_threads(2, || run(chunk, par));
        assert_same_run(&reference, &other, &format!("chunk {chunk}"));
    }
    for threads in [1, 3] {
        let other = with_threads(threads, || run(7_000, par));
        assert_same_run(&reference, &other, &format!("{threads} threads"));
    }
    let sequential = collect(n, |sink| {
        surface.curvature_stream(&queries, Parallelism::Sequential, 1_000, sink)
    });
    assert_bitwise(&reference.0, &sequential, "curvature, sequential");
}

/// A surface made from another by `with_config` (shared samples and tree, another h and
/// cutoff) gives bitwise the results of one built from scratch with that configuration.
#[test]
fn a_surface_sharing_its_index_equals_one_built_from_scratch() {
    let (surface, queries) = torus_cloud();
    let torus = Torus::new(6.0, 2.0);
    let samples = mls_shapes::random(&torus, 4_000, CLOUD_SEED);
    let points: Vec<Point> = samples.iter().map(|s| s.surface.point).collect();
    let normals: Vec<Vector> = samples.iter().map(|s| s.surface.normal).collect();
    for config in [
        MlsConfig::new(1.1),
        MlsConfig {
            cutoff: mls_core::Cutoff::Radius(3.0),
            ..MlsConfig::new(0.45)
        },
    ] {
        let shared = surface.with_config(config).unwrap();
        let fresh = MlsSurface::new(&points, &normals, config).unwrap();
        let par = Parallelism::Rayon;
        let what = format!("h = {}", config.h);
        assert_bitwise(
            &shared.curvature_at_points(&queries, par),
            &fresh.curvature_at_points(&queries, par),
            &format!("curvature, {what}"),
        );
        assert_bitwise(
            &shared.jet_at_points(&queries, &JetConfig::default(), par),
            &fresh.jet_at_points(&queries, &JetConfig::default(), par),
            &format!("jet, {what}"),
        );
    }
    assert!(surface.with_config(MlsConfig::new(-1.0)).is_err());
}

/// The adaptive ladder's stream equals its whole-set call, at the input points and at the
/// projections, and a stream of no queries delivers nothing.
#[test]
fn adaptive_stream_equals_the_whole_set_call() {
    let torus = Torus::new(6.0, 2.0);
    let samples = mls_shapes::random(&torus, 4_000, CLOUD_SEED);
    let points: Vec<Point> = samples.iter().map(|s| s.surface.point).collect();
    let normals: Vec<Vector> = samples.iter().map(|s| s.surface.normal).collect();
    let surface = AdaptiveSurface::new(&points, &normals, &AdaptiveConfig::new(0.7)).unwrap();
    let par = Parallelism::Rayon;
    let queries: Vec<Point> = points.iter().step_by(16).copied().collect();
    let n = queries.len();
    for at in [Location::Input, Location::Projected] {
        let whole = surface.curvature_at_points(&queries, at, par);
        assert!(whole.iter().filter(|r| r.is_ok()).count() > n * 9 / 10);
        for chunk in [1, 37, n] {
            let streamed = collect(n, |sink| {
                surface.curvature_stream(&queries, at, par, chunk, sink)
            });
            assert_bitwise(
                &whole,
                &streamed,
                &format!("adaptive {at:?}, chunk {chunk}"),
            );
        }
    }
    let mut calls = 0;
    surface.curvature_stream(&[], Location::Input, par, 8, |_, _| calls += 1);
    assert_eq!(calls, 0, "a stream of no queries called its sink");
}

/// Chunks are compact regions whatever the input order: over a shuffled cloud, sixteen chunks'
/// bounding boxes add up to less than four times the whole cloud's box (in input order each
/// chunk would span about all of it, sixteen boxes in all; the Morton curve's jumps make some
/// boxes long), and the results are those of the unshuffled queries.
#[test]
fn chunks_follow_space_not_input_order() {
    let (surface, queries) = torus_cloud();
    let finite: Vec<Point> = queries
        .iter()
        .filter(|q| q.iter().all(|c| c.is_finite()) && q.x < 50.0)
        .copied()
        .collect();
    // A fixed shuffle: a multiplicative step coprime to the count visits every index once.
    let n = finite.len();
    let step = (1..)
        .map(|k| 7919 * k + 1)
        .find(|s| gcd(*s, n) == 1)
        .unwrap();
    let shuffled: Vec<Point> = (0..n).map(|i| finite[i * step % n]).collect();
    let volume = |points: &mut dyn Iterator<Item = Point>| {
        let first = points.next().unwrap().coords;
        let (lo, hi) = points.fold((first, first), |(lo, hi), p| {
            (lo.inf(&p.coords), hi.sup(&p.coords))
        });
        (hi - lo).product()
    };
    let whole = volume(&mut shuffled.iter().copied());
    let mut boxes = 0.0;
    let mut results = Vec::new();
    surface.curvature_stream(
        &shuffled,
        Parallelism::Rayon,
        n.div_ceil(16),
        |indices, chunk| {
            boxes += volume(&mut indices.iter().map(|&i| shuffled[i]));
            results.extend(indices.iter().copied().zip(chunk.iter().cloned()));
        },
    );
    assert!(
        boxes < 4.0 * whole,
        "chunks' boxes {boxes} against the cloud's {whole}"
    );
    let direct = surface.curvature_at_points(&finite, Parallelism::Rayon);
    results.sort_by_key(|(i, _)| i * step % n);
    let streamed: Vec<_> = results.into_iter().map(|(_, r)| r).collect();
    assert_bitwise(&direct, &streamed, "shuffled");
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a } else { gcd(b, a % b) }
}
