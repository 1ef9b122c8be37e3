//! Progress on stderr: a bar over the evaluation, a spinner over the other stages, drawn for
//! the library's [`Progress`] only when the caller says so (stderr a terminal and no
//! `--quiet`).

use std::sync::Arc;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use mls_pipeline::progress::{Meter, NoProgress, Progress};

/// The progress of a command: bars and spinners on stderr if `show`, else none.
pub fn on_stderr(show: bool) -> Arc<dyn Progress> {
    if show {
        Arc::new(Stderr)
    } else {
        Arc::new(NoProgress)
    }
}

/// Bars and spinners on stderr.
#[derive(Clone, Copy, Debug)]
pub struct Stderr;

impl Progress for Stderr {
    fn bar(&self, n: usize, label: &str) -> Box<dyn Meter> {
        Box::new(Bar::new(n, label, true))
    }

    fn stage(&self, label: &str) -> Box<dyn Meter> {
        Box::new(Spinner::new(label, true))
    }
}

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
}

impl Meter for Bar {
    /// Marks the first `done` points as finished.
    fn set(&self, done: usize) {
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

impl Meter for Spinner {}

impl Drop for Spinner {
    fn drop(&mut self) {
        if let Some(spinner) = &self.0 {
            spinner.finish_and_clear();
        }
    }
}
