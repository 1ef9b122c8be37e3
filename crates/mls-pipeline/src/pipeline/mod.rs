//! Shared steps: read and check the input, choose h, get oriented normals, build the surface.
//!
//! One file per stage: `input.rs` reads the cloud, `scale.rs` chooses and checks h,
//! `oriented.rs` gets oriented normals, `build.rs` runs the three and builds the surface. Here
//! the timing of the stages, the thread pool and the summaries of the results, which every
//! command shares. Everything is re-exported, so callers name it `pipeline::…`.

mod build;
mod input;
mod oriented;
mod scale;

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use mls_core::PointStatus;

use crate::progress::{NoProgress, Progress};

pub use self::build::{
    BuildSurface, Built, Loaded, Prepared, Surface, build_surface, eval_surface, fixed_surface,
    index, load, prepare, surface, surface_in,
};
pub(crate) use self::input::is_stdio;
pub use self::input::{
    STDIN_NAME, STDOUT_NAME, check_count, format_name, input_name, read, read_any, read_outcome,
    read_quietly, to_points,
};
pub use self::oriented::{
    MIN_ESTIMATED_CONSISTENCY, MIN_FILE_CONSISTENCY, Normals, check_file_normals,
    estimated_normals_warning, file_normals_agreement, file_normals_warning, normals,
    scan_viewpoints,
};
pub use self::scale::{Scale, check_scale, choose_h_on, print_warning};
pub use crate::output::{Carried, Output, check_output, write_stdout};

/// A length for a summary line: six decimals where they show its digits (from 1e-3 to below
/// 1e9 in the file's units), else six significant digits with an exponent, so that a stray
/// 1e300 coordinate or a scan in kilometres reads as a number, not as 300 digits or 0.000000.
#[derive(Clone, Copy, Debug)]
pub struct Length(pub f64);

impl std::fmt::Display for Length {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() || (1e-3..1e9).contains(&x.abs()) {
            write!(f, "{x:.6}")
        } else {
            write!(f, "{x:.5e}")
        }
    }
}

/// The smallest cloud a neighbourhood can be built from: a covariance normal needs 3 points
/// besides the centre, the MLS evaluation at least 3 samples.
pub const MIN_POINTS: usize = 4;

/// Wall-clock time of the named stages, for the summary, and the progress shown while one runs
/// ([`Timings::default`] shows none).
#[derive(Debug)]
pub struct Timings(pub Vec<(&'static str, f64)>, Arc<dyn Progress>);

impl Default for Timings {
    fn default() -> Self {
        Self::new(Arc::new(NoProgress))
    }
}

impl Timings {
    /// Timings that show their stages through `progress`.
    pub fn new(progress: Arc<dyn Progress>) -> Self {
        Self(Vec::new(), progress)
    }

    /// Where progress is shown, for a stage that draws its own ([`Self::measure`]).
    pub fn progress(&self) -> Arc<dyn Progress> {
        Arc::clone(&self.1)
    }

    /// Runs and times `stage`, shown as a stage without a count ([`Progress::stage`]).
    pub fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let _stage = self.1.stage(stage);
        self.measure(stage, f)
    }

    /// Runs and times `stage`, which draws its own progress. A stage timed twice (the index:
    /// the cloud's, then the surface made from it) is reported once, with the sum.
    pub fn measure<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let out = f();
        let seconds = t.elapsed().as_secs_f64();
        match self.0.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, total)) => *total += seconds,
            None => self.0.push((stage, seconds)),
        }
        out
    }
}

/// Runs `f` on a rayon pool with the requested number of threads (all cores by default).
pub fn with_threads<T: Send>(
    threads: Option<u16>,
    f: impl FnOnce() -> Result<T> + Send,
) -> Result<T> {
    match threads {
        None => f(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(usize::from(n))
            .build()
            .context("cannot start the worker threads")?
            .install(f),
    }
}

/// Refuses a result in which no point succeeded: a file of NaN rows with exit status 0 would
/// pass a script's check. `what` is the quantity, as in "no {what} at any of its points".
pub fn check_any_ok(codes: &[i32], name: &str, what: &str, why: &str) -> anyhow::Result<()> {
    if !codes.is_empty() && codes.iter().all(|&c| c != 0) {
        anyhow::bail!(
            "{name}: no {what} at any of its {} points ({}); nothing written ({why})",
            codes.len(),
            status_counts(codes)
        );
    }
    Ok(())
}

/// Counts of each status, in code order.
pub fn status_counts(codes: &[i32]) -> String {
    let ok = codes.iter().filter(|&&c| c == 0).count();
    let mut parts = vec![format!("ok {ok}")];
    for s in PointStatus::ALL {
        let n = codes.iter().filter(|&&c| c == i32::from(s.code())).count();
        if n > 0 {
            parts.push(format!("{} {n}", s.name()));
        }
    }
    parts.join(", ")
}

/// A few percentiles of the finite values.
pub fn percentiles(values: &[f64]) -> String {
    let mut v: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return "no values".into();
    }
    v.sort_unstable_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    format!(
        "p1 {:+.4e}  p5 {:+.4e}  p25 {:+.4e}  p50 {:+.4e}  p75 {:+.4e}  p95 {:+.4e}  p99 {:+.4e}",
        q(0.01),
        q(0.05),
        q(0.25),
        q(0.5),
        q(0.75),
        q(0.95),
        q(0.99)
    )
}
