//! One case of the differential sweep: a random patch, its production results through the
//! entry points users run, and the witnesses of mls-ad on supports they filter themselves.

use std::sync::OnceLock;

use mls_core::normals::{
    DEFAULT_DEGENERACY_TOLERANCE, DEFAULT_H_FACTOR, DEFAULT_SPACING_NEIGHBOURS, spacing_statistics,
    suggest_h,
};
use mls_core::{
    Cutoff, DEFAULT_CHUNK, MlsConfig, MlsSurface, NormalsConfig, Parallelism, Point, Sample,
    Vector, correct_shrinkage, estimate_normals,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::{ThreadPool, ThreadPoolBuilder};

use crate::validate::{Q, Tally};
use crate::validate_shapes::{self as cases, CaseKind};

/// Query points per random cloud.
pub(crate) const QUERIES_PER_CASE: usize = 24;

/// How a production entry point is run: sequentially on this thread, or in a rayon pool of
/// `threads` threads; with the best kernels of the CPU or the portable ones.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Variant {
    pub(crate) threads: usize,
    pub(crate) portable: bool,
}

impl Variant {
    pub(crate) fn random(rng: &mut ChaCha8Rng) -> Self {
        Self {
            threads: rng.random_range(0..=3),
            portable: rng.random_bool(0.5),
        }
    }

    pub(crate) fn name(&self, entry: &str) -> String {
        let isa = if self.portable {
            "portable"
        } else {
            mls_core::kernels::kernel_isa()
        };
        match self.threads {
            0 => format!("`{entry}`, sequential, {isa} kernels"),
            n => format!("`{entry}`, rayon pool of {n}, {isa} kernels"),
        }
    }

    /// The name of a streaming entry point run in chunks of `chunk` of `n` queries.
    pub(crate) fn chunked_name(&self, entry: &str, chunk: usize, n: usize) -> String {
        let size = if chunk == DEFAULT_CHUNK {
            format!("chunk {chunk} (the CLI's default)")
        } else if chunk == n {
            format!("chunk {chunk} (all queries)")
        } else {
            format!("chunk {chunk}")
        };
        self.name(entry).replacen(", ", &format!(", {size}, "), 1)
    }

    /// Runs `f` with the parallelism and kernels of this variant.
    pub(crate) fn run<T: Send>(&self, f: impl FnOnce(Parallelism) -> T + Send) -> T {
        if self.threads == 0 {
            mls_core::kernels::set_portable_kernels(self.portable);
            let out = f(Parallelism::Sequential);
            mls_core::kernels::set_portable_kernels(false);
            return out;
        }
        pool(self.threads, self.portable).install(|| f(Parallelism::Rayon))
    }
}

/// The rayon pools of 1–3 threads, with the CPU's kernels and with the portable ones (each
/// pool thread sets its kernels when it starts).
fn pool(threads: usize, portable: bool) -> &'static ThreadPool {
    static POOLS: OnceLock<Vec<ThreadPool>> = OnceLock::new();
    let pools = POOLS.get_or_init(|| {
        (0..6)
            .map(|i| {
                let portable = i % 2 == 1;
                ThreadPoolBuilder::new()
                    .num_threads(i / 2 + 1)
                    .start_handler(move |_| mls_core::kernels::set_portable_kernels(portable))
                    .build()
                    .expect("a rayon pool of at most 3 threads")
            })
            .collect()
    });
    &pools[(threads - 1) * 2 + usize::from(portable)]
}

pub(crate) fn one_case(seed: u64, queries: usize) -> Tally {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let kind = CaseKind::ALL[rng.random_range(0..CaseKind::ALL.len())];
    let h_over_spacing = rng.random_range(1.0..4.0);
    let perturbed = rng.random_bool(0.5);
    let cutoff = if rng.random_bool(0.5) {
        Cutoff::DEFAULT
    } else {
        Cutoff::None
    };
    let patch = cases::patch(kind, h_over_spacing, perturbed, &mut rng);
    let mut tally = Tally::default();
    let config = MlsConfig {
        cutoff,
        ..MlsConfig::new(patch.h)
    };
    let Ok(surface) = MlsSurface::new(&patch.points, &patch.normals, config) else {
        // Every patch is a valid cloud: a construction error is a failure.
        tally.record(Q::Status, 1.0, seed);
        return tally;
    };
    // The witness's cloud, in world coordinates with unit normals.
    let samples: Vec<Sample> = patch
        .points
        .iter()
        .zip(&patch.normals)
        .map(|(p, n)| Sample {
            point: *p,
            normal: n.normalize(),
        })
        .collect();
    let a = 1.0 / (patch.h * patch.h);
    // On the surface near the centre, or off it by up to ±h along the normal.
    let mut points = Vec::with_capacity(queries);
    let mut normals = Vec::with_capacity(queries);
    let mut offsets = Vec::with_capacity(queries);
    for _ in 0..queries {
        let (base, normal) = patch.query_base(&mut rng);
        let offset = if rng.random_bool(0.5) {
            0.0
        } else {
            rng.random_range(-1.0..1.0) * patch.h
        };
        points.push(base + normal * offset);
        normals.push(normal);
        offsets.push(offset);
    }
    // The witness's support and fewest neighbours as documented (`mls_ad::documented`), not
    // taken from the surface: a changed default must fail here.
    let radius = match cutoff {
        Cutoff::None => None,
        _ => Some(mls_ad::documented::CUTOFF * patch.h),
    };
    let ctx = Ctx {
        seed,
        h: patch.h,
        a,
        samples: &samples,
        radius,
        min_neighbours: mls_ad::documented::MIN_NEIGHBOURS,
    };

    // The CLI's path: the stream, in chunks of a random size, against the witness.
    let results = streamed(
        &mut tally,
        seed,
        &mut rng,
        points.len(),
        ("curvature_stream", "curvature_at_points"),
        |par, chunk, sink| surface.curvature_stream(&points, par, chunk, sink),
        |par| surface.curvature_at_points(&points, par),
    );
    for (x, r) in points.iter().zip(&results) {
        ctx.check_point(&mut tally, x, r);
    }

    // Queries spread wider than the support, one at a time through the per-query evaluator
    // (`Evaluator::curvature_at`, whose support `SampleIndex::samples_within` gathers; the
    // clustered streams above gather theirs in storage order and never reach it): samples
    // anywhere in the patch (up to 6.5h from its centre, sparse near its rim), moved up to
    // ±2h along a random direction.
    let mut evaluator = surface.evaluator();
    for _ in 0..SCATTERED_QUERIES {
        let p = patch.points[rng.random_range(0..patch.points.len())];
        let d = Vector::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let x = p + d * (2.0 * patch.h * rng.random_range(0.0..1.0) / d.norm().max(1e-3));
        let r = evaluator.curvature_at(&x);
        ctx.check_per_query(&mut tally, &x, &r);
    }
    tally.entry(
        "`Evaluator::curvature_at`, scattered queries".into(),
        SCATTERED_QUERIES,
    );

    // The projection from the queries within h/2 of the surface (about h off it lie the
    // spurious sheets of energy maxima, beyond which a failed projection is right).
    let near: Vec<Point> = points
        .iter()
        .zip(&offsets)
        .filter(|(_, o)| o.abs() < 0.5 * patch.h)
        .map(|(x, _)| *x)
        .take(8)
        .collect();
    let projected = streamed(
        &mut tally,
        seed,
        &mut rng,
        near.len(),
        ("projection_stream", "project_points"),
        |par, chunk, sink| surface.projection_stream(&near, par, chunk, sink),
        |par| surface.project_points(&near, par),
    );
    for r in &projected {
        let Ok(p) = r else {
            tally.record(Q::Status, 1.0, seed);
            continue;
        };
        ctx.check_point(&mut tally, &p.point, r);
        ctx.check_projected(&mut tally, p);
    }

    ctx.check_lines(&mut tally, &points, &normals, &mut rng);
    check_normals(&mut tally, seed, &patch, &mut rng);
    check_spacing(&mut tally, seed, &patch, &mut rng);
    // The adaptive estimate walks five scales: every third case is enough.
    if rng.random_bool(1.0 / 3.0) {
        crate::validate_adaptive::check_adaptive(&mut tally, seed, &patch, &points, &mut rng);
    }
    crate::validate_jet::compare_jets(&mut tally, seed, &patch, &surface, &points, &mut rng);
    tally
}

/// Runs a stream of `n` results in chunks of a random size and one unchunked call of the same
/// entry point (same kernels, another random thread count), names both in the report and
/// records whether they agree bit for bit. Returns the streamed results, or the unchunked
/// ones if the stream did not deliver every index once, in order (the bitwise row has failed).
pub(crate) fn streamed<R: Clone + Send + std::fmt::Debug>(
    tally: &mut Tally,
    seed: u64,
    rng: &mut ChaCha8Rng,
    n: usize,
    (stream_name, whole_name): (&str, &str),
    stream: impl FnOnce(Parallelism, usize, &mut dyn FnMut(&[usize], &[R])) + Send,
    whole: impl FnOnce(Parallelism) -> Vec<R> + Send,
) -> Vec<R> {
    let variant = Variant::random(rng);
    let chunk = random_chunk(rng, n);
    let results = variant.run(|par| collect_stream(n, |sink| stream(par, chunk, sink)));
    tally.entry(variant.chunked_name(stream_name, chunk, n), n);
    let unchunked_variant = Variant {
        threads: rng.random_range(0..=3),
        ..variant
    };
    let unchunked = unchunked_variant.run(whole);
    tally.entry(unchunked_variant.name(whole_name), n);
    record_bitwise(tally, seed, &results, &unchunked);
    results.unwrap_or(unchunked)
}

/// A chunk size for the streaming entry points: one query per chunk, a small prime that leaves
/// a partial last chunk, all `n` queries in one chunk, or the CLI's default (larger than any
/// case, so also one chunk, through the default's own arithmetic).
pub(crate) fn random_chunk(rng: &mut ChaCha8Rng, n: usize) -> usize {
    [1, 7, n.max(1), DEFAULT_CHUNK][rng.random_range(0..4)]
}

/// The results a stream delivers to its sink, put at their queries' indices, or `None` unless
/// every index of `0..n` comes exactly once, each with one result.
pub(crate) fn collect_stream<R: Clone>(
    n: usize,
    stream: impl FnOnce(&mut dyn FnMut(&[usize], &[R])),
) -> Option<Vec<R>> {
    let mut out: Vec<Option<R>> = vec![None; n];
    let mut tiled = true;
    stream(&mut |indices: &[usize], results: &[R]| {
        tiled &= indices.len() == results.len();
        for (&i, r) in indices.iter().zip(results) {
            match out.get_mut(i) {
                Some(slot @ None) => *slot = Some(r.clone()),
                _ => tiled = false,
            }
        }
    });
    if !tiled {
        return None;
    }
    out.into_iter().collect()
}

/// 1 unless the streamed results are bitwise those of the unchunked call. `Debug` prints each
/// f64 in its shortest round-trip form, so equal text means equal bits (−0.0 and 0.0 differ).
pub(crate) fn record_bitwise<R: std::fmt::Debug>(
    tally: &mut Tally,
    seed: u64,
    streamed: &Option<Vec<R>>,
    whole: &[R],
) {
    let same = streamed
        .as_ref()
        .is_some_and(|s| format!("{s:?}") == format!("{whole:?}"));
    tally.record(Q::StreamBitwise, if same { 0.0 } else { 1.0 }, seed);
}

/// `spacing_statistics` then `suggest_h` (the CLI's default scale) against the brute-force
/// witness, on the points of the patch nearest to one of them (150–300, or 2–12 to reach the
/// clamped k), with a few exact duplicates, k and the factor at their defaults or random.
fn check_spacing(tally: &mut Tally, seed: u64, patch: &cases::Patch, rng: &mut ChaCha8Rng) {
    let n = if rng.random_bool(0.1) {
        rng.random_range(2..=12)
    } else {
        rng.random_range(150..=300)
    };
    let centre = patch.points[rng.random_range(0..patch.points.len())];
    let mut points = patch.points.clone();
    points.sort_by(|p, q| (p - centre).norm().total_cmp(&(q - centre).norm()));
    points.truncate(n);
    for _ in 0..rng.random_range(0..4) {
        let copy = points[rng.random_range(0..points.len())];
        points.push(copy);
    }
    // The defaults (the CLI's) on production's side, their documented values on the
    // witness's.
    let (k, witness_k) = if rng.random_bool(0.5) {
        (
            DEFAULT_SPACING_NEIGHBOURS,
            mls_ad::documented::SPACING_NEIGHBOURS,
        )
    } else {
        let k = rng.random_range(1..=24);
        (k, k)
    };
    let (factor, witness_factor) = if rng.random_bool(0.5) {
        (DEFAULT_H_FACTOR, mls_ad::documented::H_FACTOR)
    } else {
        let f = rng.random_range(0.5..4.0);
        (f, f)
    };
    let variant = Variant::random(rng);
    let production = variant.run(|par| {
        spacing_statistics(&points, k, par)
            .and_then(|stats| Ok((stats, suggest_h(&stats, factor)?)))
    });
    tally.entry(variant.name("spacing_statistics"), 1);
    let witness = mls_ad::spacing_witness(&points, witness_k, witness_factor);
    let value = match (production, witness) {
        (Ok((stats, h)), Some(w)) if (stats.k, stats.distinct) == (w.k, w.distinct) => {
            (h - w.h).abs() / w.h
        }
        (Err(_), None) => 0.0,
        _ => 1.0,
    };
    tally.record(Q::SpacingH, value, seed);
}

/// Queries per case spread wider than the support, through `Evaluator::curvature_at`.
const SCATTERED_QUERIES: usize = 6;

/// What every check of one case needs.
struct Ctx<'a> {
    seed: u64,
    h: f64,
    a: f64,
    samples: &'a [Sample],
    radius: Option<f64>,
    min_neighbours: usize,
}

impl Ctx<'_> {
    /// A production result at `x` against the witness on its own support, or its status
    /// against the witness's verdict.
    fn check_point(&self, tally: &mut Tally, x: &Point, r: &mls_core::PointResult) {
        let support = mls_ad::support(&x.coords, self.samples, self.radius);
        let verdict = mls_ad::classify(&x.coords, &support, self.a, self.min_neighbours);
        match (r, verdict) {
            (Ok(closed), Ok(w)) => {
                compare(tally, self.seed, self.h, closed, &w, x, &support, self.a);
                tally.record(Q::Status, 0.0, self.seed);
                tally.evals += 1;
            }
            (Err(s), Err(ws)) if *s == ws => {
                tally.record(Q::Status, 0.0, self.seed);
                tally.skipped += 1;
            }
            _ => tally.record(Q::Status, 1.0, self.seed),
        }
    }

    /// A result of the per-query evaluator at `x` against the witness: n, g, k1 and k2 as in
    /// their rows, the largest of them recorded in the per-query row, or 1 where the status
    /// differs from the witness's verdict.
    fn check_per_query(&self, tally: &mut Tally, x: &Point, r: &mls_core::PointResult) {
        let support = mls_ad::support(&x.coords, self.samples, self.radius);
        let verdict = mls_ad::classify(&x.coords, &support, self.a, self.min_neighbours);
        let value = match (r, verdict) {
            (Ok(closed), Ok(w)) => {
                let imp = &closed.implicit;
                let rescale = (w.log_scale - imp.log_scale).exp();
                let gnorm = w.gradient.norm();
                let kappa = w.hessian.norm() / gnorm;
                let wc = mls_ad::witness_curvature(&w.gradient, &w.hessian);
                let c = &closed.curvature;
                [
                    (imp.field.normal - w.normal).norm(),
                    (imp.value * rescale - w.value).abs() / (gnorm * self.h),
                    (c.k1 - wc.k1).abs() / kappa,
                    (c.k2 - wc.k2).abs() / kappa,
                ]
                .into_iter()
                .fold(0.0, f64::max)
            }
            (Err(s), Err(ws)) if *s == ws => 0.0,
            _ => 1.0,
        };
        tally.record(Q::PerQuery, value, self.seed);
    }

    /// A projected point: e′(0) vanishes along n there and e″(0) is not negative; the
    /// shrinkage correction of its curvature against the formula.
    fn check_projected(&self, tally: &mut Tally, p: &mls_core::SurfacePoint) {
        // The support of the projection's last line search.
        let reach = self.radius.map(|r| r + 1.5 * self.h);
        let support = mls_ad::support(&p.point.coords, self.samples, reach);
        let s = mls_ad::stationarity(&p.point.coords, &support, self.a);
        let value = if s.second < -1e-10 * s.second_scale {
            1.0
        } else {
            s.first.abs() / (s.second_scale * self.h)
        };
        tally.record(Q::Stationarity, value, self.seed);
        record_shrinkage(tally, self.seed, &p.curvature, self.h);
    }

    /// e′, e″ of production's line code against hyper-dual derivatives of the energy, on
    /// lines through the queries in directions near the surface normal, at t within ±h and
    /// near 0.
    fn check_lines(
        &self,
        tally: &mut Tally,
        points: &[Point],
        normals: &[Vector],
        rng: &mut ChaCha8Rng,
    ) {
        let reach = self.radius.map(|r| r + 1.5 * self.h);
        for (x, n) in points.iter().zip(normals).take(6) {
            let tilt = Vector::new(
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
            );
            let n = (n + tilt).normalize();
            // Half within ±h, where the line code sums the samples; half at |t| from 1e-10 h
            // to h/10, log-uniform, where it sums its series (`projection::LineSeries`).
            let t = if rng.random_bool(0.5) {
                rng.random_range(-1.0..1.0) * self.h
            } else {
                let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                sign * 10f64.powf(rng.random_range(-10.0..-1.0)) * self.h
            };
            let support = mls_ad::support(&x.coords, self.samples, reach);
            if support.is_empty() {
                continue;
            }
            let p = mls_core::projection::line_derivatives(x, &n, &support, self.a, t);
            let w = mls_ad::line_witness(&x.coords, &n, &support, self.a, t);
            let rescale = (w.log_scale - p.log_scale).exp();
            tally.record(
                Q::LineFirst,
                (p.first * rescale - w.first).abs() / w.first_scale,
                self.seed,
            );
            tally.record(
                Q::LineSecond,
                (p.second * rescale - w.second).abs() / w.second_scale,
                self.seed,
            );
        }
    }
}

/// `correct_shrinkage` against the formula of `docs/derivation.md`, on the same input.
pub(crate) fn record_shrinkage(tally: &mut Tally, seed: u64, c: &mls_core::Curvature, h: f64) {
    let corrected = correct_shrinkage(c, h);
    let delta = (c.k1 + c.k2) * h * h / 4.0;
    let k1 = c.k1 / (1.0 + c.k1 * delta);
    let k2 = c.k2 / (1.0 + c.k2 * delta);
    let kmax = c.k1.abs().max(c.k2.abs());
    let scale = |k: f64, kc: f64| (k - kc).abs().max(1e-5 * kmax);
    let d = ((corrected.k1 - k1).abs() / scale(c.k1, k1))
        .max((corrected.k2 - k2).abs() / scale(c.k2, k2))
        .max((corrected.mean - 0.5 * (k1 + k2)).abs() / scale(c.mean, 0.5 * (k1 + k2)))
        .max(
            (corrected.gauss - k1 * k2).abs()
                / (k1 * k2 - c.k1 * c.k2).abs().max(1e-5 * kmax * kmax),
        );
    tally.record(Q::Shrinkage, d, seed);
}

/// `estimate_normals` (the CLI's normal estimation, orientation included) on the patch's
/// points against the brute-force witness at a few random points, up to sign.
fn check_normals(tally: &mut Tally, seed: u64, patch: &cases::Patch, rng: &mut ChaCha8Rng) {
    let config = NormalsConfig {
        h: Some(patch.h),
        ..NormalsConfig::default()
    };
    let variant = Variant::random(rng);
    let Ok(est) = variant.run(|par| estimate_normals(&patch.points, &config, par)) else {
        tally.record(Q::NormalStatus, 1.0, seed);
        return;
    };
    let picks = 12.min(patch.points.len());
    tally.entry(variant.name("estimate_normals"), picks);
    for _ in 0..picks {
        let i = rng.random_range(0..patch.points.len());
        let w = mls_ad::normal_witness(
            i,
            &patch.points,
            mls_ad::documented::NORMAL_NEIGHBOURS,
            patch.h,
            DEFAULT_DEGENERACY_TOLERANCE,
        );
        match (&est.estimates[i], w) {
            (Ok(e), Some(w)) => {
                let [l0, l1, l2] = w.eigenvalues;
                let sin = e.normal.as_vector().cross(&w.normal).norm();
                tally.record(Q::NormalDirection, sin * (l1 - l0) / l2, seed);
                tally.record(Q::NormalVariation, (e.variation - w.variation).abs(), seed);
                tally.record(Q::NormalStatus, 0.0, seed);
            }
            (Err(_), None) => tally.record(Q::NormalStatus, 0.0, seed),
            _ => tally.record(Q::NormalStatus, 1.0, seed),
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn compare(
    tally: &mut Tally,
    seed: u64,
    h: f64,
    closed: &mls_core::SurfacePoint,
    w: &mls_ad::Witness,
    x: &Point,
    support: &[Sample],
    a: f64,
) {
    let imp = &closed.implicit;
    let f = &imp.field;
    // The production's weights carry exp(its shift), the witness's exp(its own): equal up to
    // rounding of the nearest distance, but compared on the witness's scale.
    let rescale = (w.log_scale - imp.log_scale).exp();
    let gnorm = w.gradient.norm();
    let hnorm = w.hessian.norm();
    let d2scale: f64 = w
        .second
        .iter()
        .map(|m| m.norm())
        .sum::<f64>()
        .max(1.0 / (h * h));
    let d2diff: f64 = (0..3).map(|c| (f.second[c] - w.second[c]).norm()).sum();
    tally.record(Q::N, (f.normal - w.normal).norm(), seed);
    tally.record(
        Q::J,
        (f.jacobian - w.jacobian).norm() / w.jacobian.norm().max(1.0 / h),
        seed,
    );
    tally.record(Q::D2N, d2diff / d2scale, seed);
    tally.record(
        Q::G,
        (imp.value * rescale - w.value).abs() / (gnorm * h),
        seed,
    );
    tally.record(
        Q::GradG,
        (imp.gradient * rescale - w.gradient).norm() / gnorm,
        seed,
    );
    tally.record(
        Q::H,
        (imp.hessian * rescale - w.hessian).norm() / hnorm,
        seed,
    );
    let wc = mls_ad::witness_curvature(&w.gradient, &w.hessian);
    let c = &closed.curvature;
    let kappa = hnorm / gnorm;
    tally.record(Q::Gauss, (c.gauss - wc.gauss).abs() / (kappa * kappa), seed);
    tally.record(Q::Mean, (c.mean - wc.mean).abs() / kappa, seed);
    tally.record(Q::K1, (c.k1 - wc.k1).abs() / kappa, seed);
    tally.record(Q::K2, (c.k2 - wc.k2).abs() / kappa, seed);
    let gap = (wc.k1 - wc.k2) / kappa;
    let sin1 = c.d1.cross(&wc.d1).norm();
    let sin2 = c.d2.cross(&wc.d2).norm();
    tally.record(Q::Directions, sin1.max(sin2) * gap, seed);
    let eq5 = mls_ad::implicit_from_energy(&x.coords, support, a, w.log_scale);
    tally.record(Q::Eq5, (eq5 - w.value).abs() / (gnorm * h), seed);
}
