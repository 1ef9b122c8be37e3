//! Who runs a loop over many points: one thread in order, or rayon's pool. The caller decides
//! (faer's `Par`); the helpers here keep each algorithm to one loop body for both.

use std::cmp::Ordering;

use rayon::prelude::*;

/// Who runs the per-point loop. The caller decides (for example a `--threads` option sets up
/// a rayon pool and installs it around the call).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Parallelism {
    /// One thread, in order.
    Sequential,
    /// rayon's current thread pool.
    #[default]
    Rayon,
}

impl Parallelism {
    /// `[f(0), …, f(n − 1)]`; in parallel, in pieces of at least `min_len` indices.
    pub fn map<T, F>(self, n: usize, min_len: usize, f: F) -> Vec<T>
    where
        T: Send,
        F: Fn(usize) -> T + Sync + Send,
    {
        match self {
            Self::Sequential => (0..n).map(f).collect(),
            Self::Rayon => (0..n)
                .into_par_iter()
                .with_min_len(min_len)
                .map(f)
                .collect(),
        }
    }

    /// [`Self::map`] with per-thread state made by `init` (an evaluator and its buffers):
    /// one for the sequential loop, one per piece of work in parallel.
    pub fn map_init<S, T, I, F>(self, n: usize, min_len: usize, init: I, f: F) -> Vec<T>
    where
        T: Send,
        I: Fn() -> S + Sync + Send,
        F: Fn(&mut S, usize) -> T + Sync + Send,
    {
        match self {
            Self::Sequential => {
                let mut state = init();
                (0..n).map(|i| f(&mut state, i)).collect()
            }
            Self::Rayon => (0..n)
                .into_par_iter()
                .with_min_len(min_len)
                .map_init(init, f)
                .collect(),
        }
    }

    /// The sum (by `add`, associative) of `f(0), …, f(n − 1)` from `zero`.
    pub fn sum<A, F, G>(self, n: usize, min_len: usize, zero: A, f: F, add: G) -> A
    where
        A: Send + Copy + Sync,
        F: Fn(usize) -> A + Sync + Send,
        G: Fn(A, A) -> A + Sync + Send,
    {
        match self {
            Self::Sequential => (0..n).map(f).fold(zero, add),
            Self::Rayon => (0..n)
                .into_par_iter()
                .with_min_len(min_len)
                .map(f)
                .reduce(|| zero, add),
        }
    }

    /// Sorts `v` by `compare`, not stably.
    pub fn sort_unstable_by<T, C>(self, v: &mut [T], compare: C)
    where
        T: Send,
        C: Fn(&T, &T) -> Ordering + Sync,
    {
        match self {
            Self::Sequential => v.sort_unstable_by(compare),
            Self::Rayon => v.par_sort_unstable_by(compare),
        }
    }

    /// Sorts `v`, not stably.
    pub fn sort_unstable<T: Ord + Send>(self, v: &mut [T]) {
        match self {
            Self::Sequential => v.sort_unstable(),
            Self::Rayon => v.par_sort_unstable(),
        }
    }
}
