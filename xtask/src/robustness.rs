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
//!
//! Here the options, the run over the seeds and the fuzzing; `robustness/checks.rs` holds the
//! checks of one cloud, `robustness/summary.rs` the totals and the report.

mod checks;
mod summary;

use std::cell::RefCell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use mls_shapes::adversarial::{AdversarialClass, AdversarialCloud};
use rayon::prelude::*;

use checks::check_cloud;
use summary::Summary;

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
/// `check_match`) at the points and after projection. The translation rounds each
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
