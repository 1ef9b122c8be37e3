//! Progress on stderr: a bar over the evaluation, a spinner over the other stages. Drawn only
//! when the caller says so (stderr a terminal and no `--quiet`).

use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// The evaluation's chunk: how often the bar moves, and how many full per-point results (about
/// 1.2 KB a point while mls-core collects them, 19 MB here) are held at a time: at 65,536 they
/// were 77 MB, a quarter of the command's peak on a million points. The results do not depend
/// on it (see `mls_core::stream`).
pub const CHUNK: usize = mls_core::DEFAULT_CHUNK;

/// A bar over `n` points, moved at each chunk and cleared when dropped; nothing unless `show`.
/// A single chunk still gets its bar: the slow estimators take seconds for one.
#[derive(Debug)]
pub struct Bar(Option<ProgressBar>);

impl Bar {
    pub fn new(n: usize, label: &str, show: bool) -> Self {
        Self((show && n > 0).then(|| {
            let bar = ProgressBar::new(n as u64).with_message(label.to_string());
            if let Ok(style) =
                ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({eta} left)")
            {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        }))
    }

    /// Marks the first `done` points as finished.
    pub fn set(&self, done: usize) {
        if let Some(bar) = &self.0 {
            bar.set_position(done as u64);
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if let Some(bar) = &self.0 {
            bar.finish_and_clear();
        }
    }
}

/// A spinner with the stage's name and elapsed time, ticking on its own thread (the stage's
/// work gives it no occasion to), cleared when dropped; nothing unless `show`.
#[derive(Debug)]
pub struct Spinner(Option<ProgressBar>);

impl Spinner {
    pub fn new(label: &str, show: bool) -> Self {
        Self(show.then(|| {
            let spinner = ProgressBar::new_spinner().with_message(label.to_string());
            if let Ok(style) = ProgressStyle::with_template("{msg:>12} {spinner} {elapsed}") {
                spinner.set_style(style);
            }
            spinner.enable_steady_tick(Duration::from_millis(100));
            spinner
        }))
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        if let Some(spinner) = &self.0 {
            spinner.finish_and_clear();
        }
    }
}
