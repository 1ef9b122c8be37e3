//! Chunked parallel evaluation with an optional progress bar.

use std::ops::Range;

use indicatif::{ProgressBar, ProgressStyle};

/// Large enough that rayon's per-chunk set-up is negligible, small enough for a live bar.
const CHUNK: usize = 1 << 16;

/// Runs `f` over `0..n` in chunks, in order, drawing a bar on stderr when `show` is set.
pub fn chunked<T>(
    n: usize,
    label: &str,
    show: bool,
    mut f: impl FnMut(Range<usize>) -> Vec<T>,
) -> Vec<T> {
    let bar = if show && n > CHUNK {
        let bar = ProgressBar::new(n as u64).with_message(label.to_string());
        if let Ok(style) =
            ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({eta} left)")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        Some(bar)
    } else {
        None
    };
    let mut out = Vec::with_capacity(n);
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK).min(n);
        out.extend(f(start..end));
        if let Some(bar) = &bar {
            bar.set_position(end as u64);
        }
        start = end;
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    out
}
