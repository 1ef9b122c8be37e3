//! Chunked parallel evaluation with an optional progress bar.

use std::ops::Range;

use indicatif::{ProgressBar, ProgressStyle};

/// Large enough that rayon's per-chunk set-up is negligible, small enough for a live bar and
/// for the full per-point results of one chunk (about 1.2 KB a point while mls-core collects
/// them, 19 MB here) to stay a small part of the peak memory: at 65,536 they were 77 MB, a
/// quarter of the command's peak on a million points.
///
/// `MlsSurface::curvature_at_points` groups the queries of one call into Morton-ordered clusters
/// that share a neighbour search, and the support's order, hence the last bits of a sum, depends
/// on the cluster. Changing this size therefore changes results at the rounding level (about
/// 1e-14 in curvature; more in principal directions where k1 ≈ k2 leaves them undefined).
const CHUNK: usize = 1 << 14;

/// Runs `f` over `0..n` in chunks, in order, drawing a bar on stderr when `show` is set. `f`
/// consumes each chunk's results, so that only one chunk of them is held at a time.
pub fn chunked(n: usize, label: &str, show: bool, mut f: impl FnMut(Range<usize>)) {
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
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK).min(n);
        f(start..end);
        if let Some(bar) = &bar {
            bar.set_position(end as u64);
        }
        start = end;
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
}
