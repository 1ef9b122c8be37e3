//! The per-sample loops of the field and of the projection's line search, and the jet's fit,
//! compiled once per instruction set, with the dispatch between them and the branch-free exp
//! they use. They are the only code whose cost grows with the number of samples; `field` and
//! `projection` hold the maths around them (docs/derivation.md) and call them through
//! `Kernels`; the jet's fit lives in `jet/fit.rs`, inlined here.
//!
//! Layout (after kiddo's `float_leaf_simd/`): `field.rs` the loops over the field's sample
//! blocks, `line.rs` the line search's, `exp.rs` the exp; here the lane count, the
//! `Kernels` trait implemented for `Portable` and `Avx2` from one list of loops, and
//! `Isa`, which picks one at run time. (A third copy for AVX-512VL, the same four lanes and
//! bits with 32 registers instead of 16, was measured slower: CPU 1.08× on the paper's
//! curvature of the 1M sphere and 1.03× on the jet, whole-process A/B pairs, 2026-12-07.)

mod exp;
mod field;
mod line;

pub use exp::{exp_any, exp_weight};
pub(crate) use field::{
    Block, coefficients, lane_moments, load_blocks, offset_blocks, weigh, weights,
};
pub(crate) use line::{LINE_MOMENTS, LineBlock, LineMoments, line_energy, line_moments};

use crate::field::Sample;
use crate::jet::{JetConfig, JetFit, JetScratch, jet_fit};
use crate::math::{Point, Vector};

/// Samples per [`Block`]: the per-neighbour sums run on `LANES` independent partial sums,
/// which the compiler turns into SIMD operations (the sums of one lane are then added at the
/// end, a different order than one running sum: results change by rounding only). Four lanes
/// fill an AVX2 register; without AVX2 they take two SSE2 registers each. The count is the
/// same on every CPU, and no code path fuses a multiply and an add, so results are bitwise
/// the same whichever [`Kernels`] run.
pub(crate) const LANES: usize = 4;

/// One value per lane.
pub(crate) type Lanes = [f64; LANES];

/// `[f(0), …, f(LANES − 1)]`, unrolled.
#[inline(always)]
pub(crate) fn per_lane(f: impl Fn(usize) -> f64) -> Lanes {
    const { assert!(LANES == 4) };
    [f(0), f(1), f(2), f(3)]
}

/// Runs `$body` with `$k` bound to the best [`Kernels`] of this CPU (see [`Isa::detect`]).
macro_rules! dispatch {
    ($k:ident => $body:expr) => {
        match $crate::kernels::Isa::detect() {
            #[cfg(target_arch = "x86_64")]
            $crate::kernels::Isa::Avx2($k) => $body,
            $crate::kernels::Isa::Portable($k) => $body,
        }
    };
}
pub(crate) use dispatch;

/// Declares [`Kernels`] from one list of its loops and implements it twice: for
/// [`Portable`], and for [`Avx2`] through a `#[target_feature(enable = "avx2")]` copy of each
/// loop. Each loop is the free function of the same name, `#[inline(always)]` so that it is
/// compiled into both.
macro_rules! kernels {
    ($($(#[$doc:meta])* fn $name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)?;)*) => {
        /// The per-sample loops and the jet's fit, compiled for one instruction set. They are
        /// the only code whose cost grows with the number of samples; the field's per-point
        /// algebra around them is the same for all.
        pub(crate) trait Kernels: Copy {
            $($(#[$doc])* fn $name(self, $($arg: $ty),*) $(-> $ret)?;)*
        }

        impl Kernels for Portable {
            $(fn $name(self, $($arg: $ty),*) $(-> $ret)? {
                $name($($arg),*)
            })*
        }

        #[cfg(target_arch = "x86_64")]
        impl Avx2 {
            $(#[target_feature(enable = "avx2")]
            fn $name($($arg: $ty),*) $(-> $ret)? {
                $name($($arg),*)
            })*
        }

        // SAFETY (each call below): `self` proves that `Avx2::new` found AVX2 on this CPU.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        impl Kernels for Avx2 {
            $(fn $name(self, $($arg: $ty),*) $(-> $ret)? {
                unsafe { Self::$name($($arg),*) }
            })*
        }
    };
}

kernels! {
    /// [`load_blocks`].
    fn load_blocks(
        blocks: &mut [Block],
        x: &Point,
        samples: &[Sample],
        radius2: f64,
        inv_h2: f64
    ) -> (usize, f64);
    /// [`offset_blocks`].
    fn offset_blocks(blocks: &mut [Block], delta: &Vector, len: usize) -> f64;
    /// [`weigh`].
    fn weigh(blocks: &mut [Block], shift: f64) -> f64;
    /// [`weights`].
    fn weights(blocks: &mut [Block], shift: f64) -> f64;
    /// [`coefficients`].
    fn coefficients(blocks: &mut [Block], n: &Vector);
    /// [`lane_moments`].
    fn lane_moments(blocks: &[Block], k: usize, acc: &mut [Lanes; 10]);
    /// [`line_energy`].
    fn line_energy(line: &mut [LineBlock], a: f64, shift: f64, t: f64, acc: &mut [Lanes; 2]);
    /// [`line_moments`].
    fn line_moments(
        blocks: &[Block],
        n: &Vector,
        mu: &mut [Lanes; LINE_MOMENTS],
        reach: &mut Lanes,
        toward: &mut Lanes
    );
    /// [`crate::jet::fit`], whole: its moments and residuals are per-sample loops, and its
    /// 15 × 15 algebra runs along rows, which vectorise.
    #[allow(clippy::too_many_arguments)]
    fn jet_fit(
        samples: &[Sample],
        centre: &Point,
        frame: &(Vector, Vector, Vector),
        radius: f64,
        config: &JetConfig,
        slope_weight: Option<f64>,
        scratch: &mut JetScratch
    ) -> Option<JetFit>;
}

/// The instruction sets [`Kernels`] are compiled for, and the one this CPU runs.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Isa {
    /// The target's baseline (SSE2 on x86-64).
    Portable(Portable),
    /// x86-64 with AVX2: four lanes in one register.
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
}

impl Isa {
    /// The best [`Kernels`] for this CPU (the standard library caches the CPUID answer),
    /// unless this thread asked for the portable ones ([`set_portable_kernels`]).
    #[inline(always)]
    pub(crate) fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if !FORCE_PORTABLE.get()
            && let Some(k) = Avx2::new()
        {
            return Self::Avx2(k);
        }
        Self::Portable(Portable)
    }
}

thread_local! {
    /// Whether this thread runs the portable kernels even where AVX2 exists.
    static FORCE_PORTABLE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Makes the current thread run the portable (baseline) kernels even on a CPU with AVX2, or
/// (with `false`) the best ones again. Results are the same bits either way; this exists so
/// that `cargo xtask validate` can run both paths of the production code on one machine. It
/// affects only the calling thread: for a rayon pool, call it from the pool's start handler.
pub fn set_portable_kernels(portable: bool) {
    FORCE_PORTABLE.set(portable);
}

/// The instruction set the per-sample loops of `evaluate` run with on this CPU: `"avx2"`, or
/// `"baseline"` (the compilation target's own features: SSE2 on x86-64). Results are the same
/// bits with either; only the speed differs.
pub fn kernel_isa() -> &'static str {
    match Isa::detect() {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2(_) => "avx2",
        Isa::Portable(_) => "baseline",
    }
}

/// [`Kernels`] for the target's baseline features.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

/// [`Kernels`] compiled with AVX2. A value exists only on a CPU that has it.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(());

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    pub(crate) fn new() -> Option<Self> {
        std::arch::is_x86_feature_detected!("avx2").then_some(Self(()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both paths give the same bits, so no result shows which ran: `validate` forces the
    /// portable one per thread to compare them, and reports the name. Both must do as told.
    #[test]
    fn the_portable_kernels_can_be_forced_per_thread() {
        #[cfg(target_arch = "x86_64")]
        let best = if std::arch::is_x86_feature_detected!("avx2") {
            "avx2"
        } else {
            "baseline"
        };
        #[cfg(not(target_arch = "x86_64"))]
        let best = "baseline";
        assert_eq!(kernel_isa(), best);
        set_portable_kernels(true);
        assert_eq!(kernel_isa(), "baseline");
        // Another thread is not affected.
        assert_eq!(std::thread::spawn(kernel_isa).join().unwrap(), best);
        set_portable_kernels(false);
        assert_eq!(kernel_isa(), best);
    }
}
