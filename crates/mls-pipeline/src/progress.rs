//! Progress, as the front end draws it: the library knows no progress bar. The command line
//! implements [`Progress`] with bars and spinners on stderr; Python, the xtask and tests pass
//! [`NoProgress`].

use std::fmt::Debug;

/// The evaluation's chunk: how often progress moves, and how many full per-point results (about
/// 1.2 KB a point while mls-core collects them, 19 MB here) are held at a time: at 65,536 they
/// were 77 MB, a quarter of the command's peak on a million points. The results do not depend
/// on it (see `mls_core::stream`).
pub const CHUNK: usize = mls_core::DEFAULT_CHUNK;

/// What shows a run's progress. Each call starts an indicator that lasts until the returned
/// [`Meter`] is dropped.
pub trait Progress: Debug + Send + Sync {
    /// A count over `n` items, labelled `label` (the stage), moved by [`Meter::set`].
    fn bar(&self, n: usize, label: &str) -> Box<dyn Meter>;

    /// A stage with no count (read, index, write), labelled `label`.
    fn stage(&self, label: &str) -> Box<dyn Meter>;
}

/// One indicator of [`Progress`], cleared when dropped.
pub trait Meter: Send + Sync {
    /// The first `done` items are finished.
    fn set(&self, done: usize) {
        let _ = done;
    }
}

/// No indicator.
impl Meter for () {}

/// Shows nothing: for Python, the xtask and tests (and `--quiet`).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn bar(&self, _: usize, _: &str) -> Box<dyn Meter> {
        Box::new(())
    }

    fn stage(&self, _: &str) -> Box<dyn Meter> {
        Box::new(())
    }
}
