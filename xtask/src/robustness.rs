//! `cargo xtask robustness`: mls-core on adversarial clouds (mls-shapes' `adversarial`
//! generator), and optionally the cargo-fuzz targets of the mls-io readers.
//!
//! Every cloud is built into a surface, evaluated at its points, at probes and at non-finite
//! queries (`curvature_at_points` and `project_points`), given to `estimate_normals`, and run
//! through the whole pipeline with the estimated normals, inside `catch_unwind`. The run fails
//! on a panic, on a NaN or infinity in any `Ok` result, on a status where none may be, on an
//! unexpected error, and when a coplanar cloud bends or a translated, scaled or duplicated
//! cloud does not reproduce its base. Counts per class and per status go to the terminal and
//! to `target/robustness/report.md`; `docs/robustness.md` explains them.

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use mls_core::normals::{NormalsConfig, NormalsError, estimate_normals};
use mls_core::{
    ConfigError, Cutoff, MlsConfig, MlsSurface, Parallelism, Point, PointResult, PointStatus,
    Vector,
};
use mls_shapes::adversarial::{AdversarialClass, AdversarialCloud, Expectation, ProbeKind};
use rayon::prelude::*;

/// Default first seed; cloud `i` of a run has seed `seed + i`.
const DEFAULT_SEED: u64 = 0x0bad_c10d;
/// Clouds in a full run and in a `--quick` run.
const FULL_CLOUDS: usize = 10_000;
const QUICK_CLOUDS: usize = 400;
/// Most projected queries per cloud: the projection costs several evaluations per point.
const MAX_PROJECTED: usize = 120;

/// A coplanar cloud with its plane's normals is that plane: `max(|k1|, |k2|)·h` or
/// `|gauss|·h²` above this fails. Measured worst over 10⁴ clouds: see `docs/robustness.md`.
pub(crate) const FLAT_TOLERANCE: f64 = 1e-9;
/// A cloud translated by 10⁶ reproduces its base (relative differences, see
/// [`check_match`]) at the points and after projection. The translation rounds each
/// coordinate to a multiple of up to 2⁻³² ≈ 2.3e-10, up to 2e-9 h for the h of these clouds;
/// measured worst over 10⁴ clouds 3.5e-7 at the points, 4.8e-8 after projection.
pub(crate) const OFFSET_TOLERANCE: [f64; 2] = [1e-5, 1e-5];
/// Scaled and duplicated clouds reproduce their base: scaling rounds each coordinate once
/// (relative 1.1e-16), duplicating changes only the order of summation. Measured worst over
/// 10⁴ clouds 1.9e-11 at the points, 4.1e-9 after projection: the projection stops within
/// 1e-12 h of the surface, so base and image land up to that far apart, and where the
/// surface is ill-conditioned (normals nearly cancelling, |k|·h ≫ 1) curvature changes by
/// that much over such a distance. (With the former stopping rule, 1e-10 h, one cloud in 10⁴
/// differed by 1.5e-5.)
pub(crate) const SIMILAR_TOLERANCE: [f64; 2] = [1e-10, 1e-7];

/// Options of `cargo xtask robustness`.
#[derive(Clone, Debug, clap::Args)]
pub(crate) struct Options {
    /// 400 clouds instead of 10,000.
    #[arg(long)]
    pub quick: bool,
    /// Number of clouds.
    #[arg(long)]
    pub clouds: Option<usize>,
    /// Base seed (decimal or 0x hexadecimal).
    #[arg(long, default_value_t = DEFAULT_SEED, value_parser = crate::parse_u64)]
    pub seed: u64,
    /// Run only the cloud of this seed, and print it.
    #[arg(long, value_parser = crate::parse_u64)]
    pub replay: Option<u64>,
    /// Run each cargo-fuzz reader target for this many seconds after the clouds.
    #[arg(long = "fuzz", value_name = "SECONDS")]
    pub fuzz_seconds: Option<u64>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            quick: false,
            clouds: None,
            seed: DEFAULT_SEED,
            replay: None,
            fuzz_seconds: None,
        }
    }
}

impl Options {
    fn cloud_count(&self) -> usize {
        self.clouds.unwrap_or(if self.quick {
            QUICK_CLOUDS
        } else {
            FULL_CLOUDS
        })
    }
}

pub(crate) fn run(options: &Options) -> Result<()> {
    // Caught panics are reported with their seed; the usual hook comes back afterwards, so
    // a caller such as `validate` keeps its panic messages.
    let usual_hook = std::panic::take_hook();
    install_quiet_panic_hook();
    let seeds: Vec<u64> = match options.replay {
        Some(seed) => vec![seed],
        None => (0..options.cloud_count() as u64)
            .map(|i| options.seed.wrapping_add(i))
            .collect(),
    };
    if let Some(seed) = options.replay {
        let cloud = AdversarialCloud::from_seed(seed);
        println!(
            "replaying seed {seed:#x}: {} ({}), {} points, h = {:e}, cutoff {:?}",
            cloud.class,
            cloud.variant,
            cloud.points.len(),
            cloud.h,
            cloud.cutoff
        );
    }
    let start = Instant::now();
    let outcomes: Vec<Outcome> = seeds.par_iter().map(|&seed| check_seed(seed)).collect();
    std::panic::set_hook(usual_hook);
    let elapsed = start.elapsed().as_secs_f64();
    let summary = Summary::of(&outcomes);
    let report = summary.render(outcomes.len(), options, elapsed);
    println!("{report}");
    let dir = Path::new("target/robustness");
    std::fs::create_dir_all(dir).context("cannot create target/robustness")?;
    std::fs::write(dir.join("report.md"), &report).context("cannot write the report")?;
    println!("wrote target/robustness/report.md");
    if summary.failures > 0 {
        bail!(
            "{} of {} adversarial clouds failed (first seeds above; replay with \
             `cargo xtask robustness --replay SEED`)",
            summary.failures,
            outcomes.len()
        );
    }
    if let Some(seconds) = options.fuzz_seconds {
        fuzz(seconds)?;
    }
    Ok(())
}

thread_local! {
    /// The message and location of the last panic on this thread.
    static LAST_PANIC: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Records panics instead of printing them, so that a caught panic is reported once, with
/// its seed.
fn install_quiet_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "non-string panic".to_owned());
        let location = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        LAST_PANIC.with(|p| *p.borrow_mut() = format!("{message}{location}"));
    }));
}

/// What happened to one cloud.
#[derive(Debug, Default)]
struct Outcome {
    class: Option<AdversarialClass>,
    seed: u64,
    variant: &'static str,
    /// The construction error, when one was expected and got.
    construction_error: Option<&'static str>,
    /// Statuses of `curvature_at_points` (index = code, 0 = ok).
    curvature: [u64; 8],
    projection: [u64; 8],
    /// Statuses of the pipeline: estimated normals, then curvature at the points.
    pipeline: [u64; 8],
    /// Per-point normal estimates: ok, failed.
    normals: [u64; 2],
    normals_error: Option<&'static str>,
    /// Worst `|k|·h` of a flat cloud.
    flat: Option<f64>,
    /// Worst relative difference against the base (curvature at the points, projection),
    /// and the number of status mismatches.
    matched: Option<[f64; 2]>,
    mismatched_statuses: u64,
    /// Property violations; empty when the cloud passed.
    failures: Vec<String>,
}

fn check_seed(seed: u64) -> Outcome {
    let cloud = match catch_unwind(|| AdversarialCloud::from_seed(seed)) {
        Ok(cloud) => cloud,
        Err(_) => {
            let message = LAST_PANIC.with(|p| p.borrow().clone());
            return Outcome {
                seed,
                failures: vec![format!("generator panicked: {message}")],
                ..Outcome::default()
            };
        }
    };
    let mut outcome = Outcome {
        class: Some(cloud.class),
        seed,
        variant: cloud.variant,
        ..Outcome::default()
    };
    if catch_unwind(AssertUnwindSafe(|| check_cloud(&cloud, &mut outcome))).is_err() {
        let message = LAST_PANIC.with(|p| p.borrow().clone());
        outcome.failures.push(format!("panic: {message}"));
    }
    outcome
}

/// The surface parameters of a cloud.
pub(crate) fn config_of(cloud: &AdversarialCloud) -> MlsConfig {
    MlsConfig {
        cutoff: cloud.cutoff.map_or(Cutoff::None, Cutoff::Radius),
        ..MlsConfig::new(cloud.h)
    }
}

/// Two queries every surface must reject as `InvalidQuery`.
const NON_FINITE_QUERIES: [[f64; 3]; 2] = [[f64::NAN, 0.0, 0.0], [0.0, f64::NEG_INFINITY, 1.0]];

fn check_cloud(cloud: &AdversarialCloud, out: &mut Outcome) {
    // Alternate the two entry points; rayon inside rayon is fine.
    let par = if cloud.seed.is_multiple_of(8) {
        Parallelism::Rayon
    } else {
        Parallelism::Sequential
    };
    check_surface(cloud, par, out);
    check_normals(cloud, par, out);
}

fn check_surface(cloud: &AdversarialCloud, par: Parallelism, out: &mut Outcome) {
    let built = MlsSurface::new(&cloud.points, &cloud.normals, config_of(cloud));
    let surface = match (&cloud.expectation, built) {
        (
            Expectation::NonFinitePoint { index },
            Err(ConfigError::NonFinitePoint { index: got }),
        ) if got == *index => {
            out.construction_error = Some("NonFinitePoint");
            return;
        }
        (Expectation::BadNormal { index }, Err(ConfigError::BadNormal { index: got, .. }))
            if got == *index =>
        {
            out.construction_error = Some("BadNormal");
            return;
        }
        (Expectation::NonFinitePoint { .. } | Expectation::BadNormal { .. }, other) => {
            out.failures.push(format!(
                "expected {:?} at construction, got {:?}",
                cloud.expectation,
                other.map(|_| "a surface")
            ));
            return;
        }
        (_, Err(e)) => {
            out.failures.push(format!("construction failed: {e}"));
            return;
        }
        (_, Ok(surface)) => surface,
    };

    let mut queries = cloud.points.clone();
    queries.extend(cloud.probes.iter().map(|p| p.point));
    queries.extend(NON_FINITE_QUERIES.map(Point::from));
    let curvature = surface.curvature_at_points(&queries, par);
    let projected_queries = projection_subset(cloud, &queries);
    let projection = surface.project_points(&projected_queries, par);

    for (label, asked, results, counts) in [
        ("curvature", &queries, &curvature, &mut out.curvature),
        (
            "projection",
            &projected_queries,
            &projection,
            &mut out.projection,
        ),
    ] {
        for (q, r) in asked.iter().zip(results) {
            count(counts, r);
            if let Some(problem) = invalid_result(r, label == "projection") {
                out.failures.push(format!("{label} at {q:?}: {problem}"));
            }
        }
        // The last two queries are the non-finite ones.
        for r in &results[results.len() - 2..] {
            if *r != Err(PointStatus::InvalidQuery) {
                out.failures
                    .push(format!("{label} at a non-finite query: {r:?}"));
            }
        }
    }
    check_probes(cloud, &curvature[cloud.points.len()..], &projection, out);

    match &cloud.expectation {
        Expectation::Flat => {
            let worst = curvature
                .iter()
                .chain(&projection)
                .flatten()
                .map(|s| {
                    let c = s.curvature;
                    // gauss, not √gauss: its rounding error is ε|H|²/|∇g|², and H is large
                    // across the plane even where it vanishes along it.
                    (c.k1.abs().max(c.k2.abs()) * cloud.h).max(c.gauss.abs() * cloud.h * cloud.h)
                })
                .fold(0.0, f64::max);
            out.flat = Some(worst);
            if !(worst <= FLAT_TOLERANCE) {
                out.failures
                    .push(format!("flat cloud bends: |k|·h = {worst:e}"));
            }
        }
        Expectation::Matches {
            base,
            scale,
            offset,
        } => check_match(cloud, &surface, base, *scale, offset, par, out),
        _ => {}
    }
}

/// The queries projected: every point of a small cloud, else a stride through them, then the
/// probes and the non-finite queries.
fn projection_subset(cloud: &AdversarialCloud, queries: &[Point]) -> Vec<Point> {
    let n = cloud.points.len();
    let stride = n.div_ceil(MAX_PROJECTED).max(1);
    let mut subset: Vec<Point> = cloud.points.iter().step_by(stride).copied().collect();
    subset.extend_from_slice(&queries[n..]);
    subset
}

fn count(counts: &mut [u64; 8], r: &PointResult) {
    let code = r.as_ref().map_or_else(|s| s.code() as usize, |_| 0);
    counts[code.min(7)] += 1;
}

/// What is wrong with one result, if anything: a non-finite number in an `Ok` result, a
/// broken invariant (unit normal, `k1 ≥ k2`, `mean = (k1 + k2)/2`), or a status the entry
/// point cannot return.
pub(crate) fn invalid_result(r: &PointResult, projection: bool) -> Option<String> {
    match r {
        Ok(s) => {
            let c = &s.curvature;
            let vectors = [s.point.coords, c.normal, c.d1, c.d2];
            let scalars = [c.k1, c.k2, c.mean, c.gauss];
            if !(vectors.iter().all(|v| v.iter().all(|x| x.is_finite()))
                && scalars.iter().all(|x| x.is_finite()))
            {
                return Some(format!("non-finite value in an Ok result: {s:?}"));
            }
            if !((c.normal.norm() - 1.0).abs() < 1e-9 && c.k1 >= c.k2) {
                return Some(format!("broken invariant (|n| = 1, k1 ≥ k2): {c:?}"));
            }
            let scale = c.k1.abs().max(c.k2.abs());
            if !((c.mean - 0.5 * (c.k1 + c.k2)).abs() <= 1e-12 * scale) {
                return Some(format!("mean is not (k1 + k2)/2: {c:?}"));
            }
            None
        }
        Err(PointStatus::NormalEstimationFailed) => {
            Some("status normal_estimation_failed from the surface".to_owned())
        }
        Err(PointStatus::ProjectionFailed) if !projection => {
            Some("status projection_failed without projection".to_owned())
        }
        Err(_) => None,
    }
}

/// Probes: no sample within twice the support gives `NoNeighbours`; a sample alone gives
/// `TooFewNeighbours`; the mirror plane of opposite sheets gives `NormalUndefined`, with and
/// without projection.
fn check_probes(
    cloud: &AdversarialCloud,
    curvature: &[PointResult],
    projection: &[PointResult],
    out: &mut Outcome,
) {
    let projected_probes = &projection[projection.len() - 2 - cloud.probes.len()..];
    for ((probe, c), p) in cloud.probes.iter().zip(curvature).zip(projected_probes) {
        let expected = match probe.kind {
            ProbeKind::Void => PointStatus::NoNeighbours,
            ProbeKind::Alone => PointStatus::TooFewNeighbours,
            ProbeKind::Cancelling => PointStatus::NormalUndefined,
        };
        if *c != Err(expected) {
            out.failures
                .push(format!("{probe:?}: curvature {c:?}, expected {expected}"));
        }
        if probe.kind == ProbeKind::Cancelling && *p != Err(expected) {
            out.failures
                .push(format!("{probe:?}: projection {p:?}, expected {expected}"));
        }
    }
}

/// The cloud is `base` mapped by `x ↦ s x + t`: compare curvature at the images of the base's
/// points, and the projections of some of them.
///
/// Differences are relative: `|s·k − k_base| / (|k_base| + 1/h)` for k1, k2 and mean (so
/// that curvature small against 1/h is compared absolutely), the same with `s²` and `1/h²`
/// for gauss, `|Δn|`, and the distance between projected points over `h`.
fn check_match(
    cloud: &AdversarialCloud,
    surface: &MlsSurface,
    base: &AdversarialCloud,
    scale: f64,
    offset: &Vector,
    par: Parallelism,
    out: &mut Outcome,
) {
    let base_surface = match MlsSurface::new(&base.points, &base.normals, config_of(base)) {
        Ok(s) => s,
        Err(e) => {
            out.failures.push(format!("base construction failed: {e}"));
            return;
        }
    };
    let image = |q: &Point| Point::from(q.coords * scale + offset);
    let images: Vec<Point> = base.points.iter().map(image).collect();
    let stride = base.points.len().div_ceil(MAX_PROJECTED / 2).max(1);
    let few: Vec<Point> = base.points.iter().step_by(stride).copied().collect();
    let few_images: Vec<Point> = few.iter().map(image).collect();
    let pairs = [
        (
            base_surface.curvature_at_points(&base.points, par),
            surface.curvature_at_points(&images, par),
        ),
        (
            base_surface.project_points(&few, par),
            surface.project_points(&few_images, par),
        ),
    ];
    let (h, inv_h) = (base.h, 1.0 / base.h);
    let mut worst = [0.0f64; 2];
    for (kind, (expected, got)) in pairs.iter().enumerate() {
        for (e, g) in expected.iter().zip(got) {
            match (e, g) {
                (Ok(e), Ok(g)) => {
                    let (ce, cg) = (&e.curvature, &g.curvature);
                    let rel = |a: f64, b: f64, floor: f64| (a - b).abs() / (b.abs() + floor);
                    let d = [
                        rel(cg.k1 * scale, ce.k1, inv_h),
                        rel(cg.k2 * scale, ce.k2, inv_h),
                        rel(cg.mean * scale, ce.mean, inv_h),
                        rel(cg.gauss * scale * scale, ce.gauss, inv_h * inv_h),
                        (cg.normal - ce.normal).norm(),
                        (g.point.coords - image(&e.point).coords).norm() / (scale * h),
                    ];
                    worst[kind] = d.into_iter().fold(worst[kind], f64::max);
                }
                (e, g) if e == g => {}
                _ => out.mismatched_statuses += 1,
            }
        }
    }
    out.matched = Some(worst);
    let tolerance = match_tolerance(cloud.class);
    for (kind, label) in ["curvature at the points", "projection"].iter().enumerate() {
        if !(worst[kind] <= tolerance[kind]) {
            out.failures.push(format!(
                "{}: {label} differs from the base by {:e} (tolerance {:e})",
                cloud.class, worst[kind], tolerance[kind]
            ));
        }
    }
    if out.mismatched_statuses > 0 {
        out.failures.push(format!(
            "{}: {} statuses differ from the base's",
            cloud.class, out.mismatched_statuses
        ));
    }
}

/// The tolerances of a matched class: curvature at the points, and after projection.
pub(crate) fn match_tolerance(class: AdversarialClass) -> [f64; 2] {
    match class {
        AdversarialClass::Offset => OFFSET_TOLERANCE,
        _ => SIMILAR_TOLERANCE,
    }
}

fn check_normals(cloud: &AdversarialCloud, par: Parallelism, out: &mut Outcome) {
    let config = NormalsConfig::default();
    let estimated = estimate_normals(&cloud.points, &config, par);
    let est = match (&cloud.expectation, estimated) {
        (
            Expectation::NonFinitePoint { index },
            Err(NormalsError::NonFinitePoint { index: got }),
        ) if got == *index => {
            out.normals_error = Some("NonFinitePoint");
            return;
        }
        (Expectation::NonFinitePoint { .. }, other) => {
            out.failures.push(format!(
                "estimate_normals: expected NonFinitePoint, got {:?}",
                other.map(|_| "normals")
            ));
            return;
        }
        (_, Err(e)) => {
            out.failures.push(format!("estimate_normals failed: {e}"));
            return;
        }
        (_, Ok(est)) => est,
    };
    if est.estimates.len() != cloud.points.len() {
        out.failures
            .push("estimate_normals: wrong length".to_owned());
        return;
    }
    for (i, e) in est.estimates.iter().enumerate() {
        match e {
            Ok(e) => {
                out.normals[0] += 1;
                let n = e.normal.into_inner();
                let unit = n.iter().all(|c| c.is_finite()) && (n.norm() - 1.0).abs() < 1e-12;
                let variation = e.variation.is_finite() && (0.0..=0.34).contains(&e.variation);
                if !(unit && variation) {
                    out.failures
                        .push(format!("estimate_normals at point {i}: {e:?}"));
                }
            }
            Err(PointStatus::NormalEstimationFailed) => out.normals[1] += 1,
            Err(s) => out
                .failures
                .push(format!("estimate_normals at point {i}: status {s}")),
        }
    }
    let all_fail = match cloud.class {
        AdversarialClass::Collinear | AdversarialClass::SinglePoint => true,
        AdversarialClass::Duplicates => cloud.variant == "every point a copy of one",
        _ => false,
    };
    if all_fail && out.normals[0] > 0 {
        out.failures.push(format!(
            "estimate_normals: {} normals on a degenerate cloud",
            out.normals[0]
        ));
    }
    if matches!(cloud.class, AdversarialClass::Coplanar) {
        let plane = cloud.normals.first().copied().unwrap_or_else(Vector::z);
        let worst = est
            .estimates
            .iter()
            .flatten()
            .map(|e| 1.0 - e.normal.into_inner().dot(&plane).abs())
            .fold(0.0, f64::max);
        if out.normals[1] > 0 || !(worst < 1e-9) {
            out.failures.push(format!(
                "estimate_normals on a plane: {} failed, worst 1 − |n·v| = {worst:e}",
                out.normals[1]
            ));
        }
    }
    // The whole pipeline, as the CLI runs it: the points with a normal, at the estimated h.
    let Some(h) = est.h else { return };
    let (points, normals): (Vec<Point>, Vec<Vector>) = cloud
        .points
        .iter()
        .zip(est.normals())
        .filter_map(|(p, n)| n.ok().map(|n| (*p, n)))
        .unzip();
    match MlsSurface::new(&points, &normals, MlsConfig::new(h)) {
        Ok(surface) => {
            for r in surface.curvature_at_points(&points, par) {
                count(&mut out.pipeline, &r);
                if let Some(problem) = invalid_result(&r, false) {
                    out.failures.push(format!("pipeline: {problem}"));
                }
            }
        }
        Err(e) => out
            .failures
            .push(format!("pipeline construction failed (h = {h:e}): {e}")),
    }
}

/// Totals per class.
#[derive(Debug, Default)]
struct ClassTotals {
    clouds: u64,
    failed: u64,
    construction_errors: BTreeMap<&'static str, u64>,
    curvature: [u64; 8],
    projection: [u64; 8],
    pipeline: [u64; 8],
    normals: [u64; 2],
    flat: Option<f64>,
    matched: Option<[f64; 2]>,
    variants: BTreeMap<&'static str, u64>,
}

#[derive(Debug, Default)]
struct Summary {
    classes: BTreeMap<AdversarialClass, ClassTotals>,
    failures: usize,
    /// The first failures, with their seeds.
    first_failures: Vec<String>,
}

impl Summary {
    fn of(outcomes: &[Outcome]) -> Self {
        let mut s = Self::default();
        for o in outcomes {
            if !o.failures.is_empty() {
                s.failures += 1;
                if s.first_failures.len() < 20 {
                    let class = o.class.map_or("?", AdversarialClass::name);
                    s.first_failures.push(format!(
                        "seed {:#x} ({class}, {}): {}",
                        o.seed,
                        o.variant,
                        o.failures[..o.failures.len().min(3)].join("; ")
                    ));
                }
            }
            let Some(class) = o.class else { continue };
            let t = s.classes.entry(class).or_default();
            t.clouds += 1;
            t.failed += u64::from(!o.failures.is_empty());
            if let Some(e) = o.construction_error {
                *t.construction_errors.entry(e).or_default() += 1;
            }
            *t.variants.entry(o.variant).or_default() += 1;
            for (sum, add) in [
                (&mut t.curvature, &o.curvature),
                (&mut t.projection, &o.projection),
                (&mut t.pipeline, &o.pipeline),
            ] {
                for (a, b) in sum.iter_mut().zip(add) {
                    *a += b;
                }
            }
            t.normals[0] += o.normals[0];
            t.normals[1] += o.normals[1];
            if let Some(v) = o.flat {
                t.flat = Some(t.flat.map_or(v, |w| w.max(v)));
            }
            if let Some([c, p]) = o.matched {
                t.matched = Some(t.matched.map_or([c, p], |[wc, wp]| [wc.max(c), wp.max(p)]));
            }
        }
        s
    }

    fn render(&self, clouds: usize, options: &Options, seconds: f64) -> String {
        let mut md = String::new();
        let (first, last) = (options.seed, options.seed.wrapping_add(clouds as u64) - 1);
        let _ = writeln!(
            md,
            "# Adversarial clouds\n\n{clouds} clouds (seeds {first:#x}..={last:#x}) in \
             {seconds:.1} s; {} failed.\n",
            self.failures
        );
        let _ = writeln!(
            md,
            "Statuses are counted per query: `ok`, then codes 1–7 (no_neighbours, \
             too_few_neighbours, normal_undefined, gradient_vanishes, projection_failed, \
             invalid_query, normal_estimation_failed).\n"
        );
        md.push_str(
            "| class | clouds | failed | construction error | curvature ok/1/2/3/4/5/6 | \
             projection ok/1/2/3/4/5/6 | normals ok/failed | pipeline ok/1/2/3/4 | worst |\n\
             | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
        );
        let statuses = |c: &[u64; 8], n: usize| {
            c[..n]
                .iter()
                .map(u64::to_string)
                .collect::<Vec<_>>()
                .join("/")
        };
        for (class, t) in &self.classes {
            let errors = if t.construction_errors.is_empty() {
                "—".to_owned()
            } else {
                t.construction_errors
                    .iter()
                    .map(|(e, n)| format!("{e} × {n}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let worst = match (t.flat, t.matched) {
                (Some(f), _) => format!("\\|k\\|·h ≤ {f:.1e}"),
                (_, Some([c, p])) => format!("Δ ≤ {c:.1e} / {p:.1e}"),
                _ => "—".to_owned(),
            };
            let _ = writeln!(
                md,
                "| {class} | {} | {} | {errors} | {} | {} | {}/{} | {} | {worst} |",
                t.clouds,
                t.failed,
                statuses(&t.curvature, 7),
                statuses(&t.projection, 7),
                t.normals[0],
                t.normals[1],
                statuses(&t.pipeline, 5),
            );
        }
        md.push_str("\nVariants: ");
        let variants: Vec<String> = self
            .classes
            .iter()
            .map(|(class, t)| {
                let v: Vec<String> = t
                    .variants
                    .iter()
                    .map(|(name, n)| format!("{name} × {n}"))
                    .collect();
                format!("{class}: {}", v.join(", "))
            })
            .collect();
        md.push_str(&variants.join("; "));
        md.push('\n');
        let totals = self.classes.values().fold([0u64; 3], |acc, t| {
            [
                acc[0] + t.curvature.iter().sum::<u64>(),
                acc[1] + t.projection.iter().sum::<u64>(),
                acc[2] + t.pipeline.iter().sum::<u64>(),
            ]
        });
        let _ = writeln!(
            md,
            "\nEvaluations: {} curvature, {} projection, {} pipeline. Tolerances: flat \
             {FLAT_TOLERANCE:e}, offset {OFFSET_TOLERANCE:?}, scale and duplicates \
             {SIMILAR_TOLERANCE:?} (at the points, after projection).",
            totals[0], totals[1], totals[2]
        );
        if !self.first_failures.is_empty() {
            md.push_str("\n## Failures\n\n");
            for f in &self.first_failures {
                let _ = writeln!(md, "- {f}");
            }
        }
        md
    }
}

/// Runs each cargo-fuzz target of mls-io for `seconds`, on the stable toolchain with
/// `RUSTC_BOOTSTRAP=1` (libFuzzer needs `-Z` flags). Needs `cargo install cargo-fuzz`.
fn fuzz(seconds: u64) -> Result<()> {
    let dir = Path::new("crates/mls-io");
    for (target, dict) in [
        ("ply", "fuzz/ply.dict"),
        ("xyz", "fuzz/text.dict"),
        ("csv", "fuzz/text.dict"),
    ] {
        let corpus = format!("fuzz/corpus/{target}");
        std::fs::create_dir_all(dir.join(&corpus))?;
        let mut cmd = crate::cargo();
        cmd.current_dir(dir)
            .env("RUSTC_BOOTSTRAP", "1")
            .args(["fuzz", "run", target, &corpus])
            .arg(format!("fuzz/seeds/{target}"))
            .args([
                "--",
                "-rss_limit_mb=512",
                "-timeout=10",
                "-print_final_stats=1",
            ])
            .arg(format!("-max_total_time={seconds}"))
            .arg(format!("-dict={dict}"));
        println!("fuzzing {target} for {seconds} s");
        crate::run_checked(&mut cmd).with_context(|| {
            format!(
                "fuzz target {target} failed (is cargo-fuzz installed? `cargo install cargo-fuzz`)"
            )
        })?;
    }
    Ok(())
}
