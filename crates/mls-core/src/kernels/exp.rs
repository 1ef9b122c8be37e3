//! A branch-free `exp` within 1 ulp of the standard library's, which the compiler runs on
//! every lane of a block at once.

/// `exp(x)` for `x ≤ 693` (the weights have `x ≤ 0`), within 1 ulp of `f64::exp`,
/// branch-free so that the compiler runs it on every lane of a block at once (a call to the C
/// library's `exp` per sample cost as much as the first pass). [`exp_any`] covers the whole
/// range, at one more select per value.
#[inline(always)]
pub fn exp_weight(x: f64) -> f64 {
    exp_impl::<false>(x)
}

/// `exp(x)` for every `x`, as [`exp_weight`]: the projection's line energy also meets positive
/// arguments, up to `a·shift`.
#[inline(always)]
pub fn exp_any(x: f64) -> f64 {
    exp_impl::<true>(x)
}

/// [`exp_weight`] and, when `LARGE`, correct up to overflow.
///
/// fdlibm's algorithm: `x = k ln 2 + r` with `|r| ≤ ln 2 / 2` (`ln 2` split in a high part
/// whose products with k are exact and a low part), then a degree-5 minimax polynomial `R`
/// with `exp(r) = 1 + 2r/(R(r) − r)` arranged as below, and the result scaled by `2^k`.
/// Results below `f64::MIN_POSITIVE` are subnormal, rounded once as `f64::exp` rounds them;
/// below about −745.1, −∞ and NaN give 0; with `LARGE`, above about 709.78 and +∞ give +∞.
#[inline(always)]
fn exp_impl<const LARGE: bool>(x: f64) -> f64 {
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    const INV_LN2: f64 = std::f64::consts::LOG2_E;
    const P1: f64 = 1.666_666_666_666_660_2e-1;
    const P2: f64 = -2.777_777_777_701_559_3e-3;
    const P3: f64 = 6.613_756_321_437_934e-5;
    const P4: f64 = -1.653_390_220_546_525_2e-6;
    const P5: f64 = 4.138_136_797_057_238_5e-8;
    // Adding 1.5·2⁵² rounds to an integer, which then sits in the low bits of the sum.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    // Beyond |k| = 1000, 2^k is applied in two steps (2^(k ∓ 200), then 2^±200) so that the
    // first stays normal and the result is rounded (or overflows) once.
    const SPLIT: f64 = 200.0;
    let xc = if LARGE {
        x.clamp(-746.0, 746.0)
    } else {
        x.max(-746.0)
    };
    let kf = (xc * INV_LN2 + ROUND) - ROUND;
    let hi = xc - kf * LN2_HI;
    let lo = kf * LN2_LO;
    let r = hi - lo;
    let t = r * r;
    let c = r - t * (P1 + t * (P2 + t * (P3 + t * (P4 + t * P5))));
    let y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
    // Everything in f64 (SSE2 has no 64-bit integer comparison): the biased exponent
    // k + 1023, in [147, 1900], is an integer in the low bits of `ROUND + k + 1023`, and the
    // shift keeps exactly those 11 bits.
    let low = kf < -1000.0;
    let high = LARGE && kf > 1000.0;
    let k1 = if low {
        kf + SPLIT
    } else if high {
        kf - SPLIT
    } else {
        kf
    };
    let scale = f64::from_bits((k1 + (1023.0 + ROUND)).to_bits() << 52);
    let tail = if low {
        f64::from_bits((1023 - SPLIT as u64) << 52)
    } else if high {
        f64::from_bits((1023 + SPLIT as u64) << 52)
    } else {
        1.0
    };
    let e = y * scale * tail;
    if x >= -746.0 { e } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::{exp_any, exp_weight};

    /// Distance in units in the last place between two non-negative finite values.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn exp_weight_is_within_one_ulp_of_std() {
        // A dense sweep of the weights' range, the subnormal range and the ends.
        let mut worst = 0;
        for i in 0..=2_000_000 {
            let x = -(i as f64) * 746.0 / 2_000_000.0;
            worst = worst.max(ulps(exp_weight(x), x.exp()));
        }
        for i in 0..=200_000 {
            let x = -(i as f64) * 1e-6;
            worst = worst.max(ulps(exp_weight(x), x.exp()));
        }
        // Positive arguments: up to 693 for both, up to the largest finite result for exp_any.
        for i in 0..=2_000_000 {
            let x = (i as f64) * 709.78 / 2_000_000.0;
            worst = worst.max(ulps(exp_any(x), x.exp()));
            if x <= 693.0 {
                worst = worst.max(ulps(exp_weight(x), x.exp()));
            }
        }
        for i in 0..=2_000_000 {
            let x = -(i as f64) * 746.0 / 2_000_000.0;
            worst = worst.max(ulps(exp_any(x), x.exp()));
        }
        assert!(worst <= 1, "worst {worst} ulps");
        assert_eq!(exp_any(709.79), f64::INFINITY);
        assert_eq!(exp_any(1e300), f64::INFINITY);
        assert_eq!(exp_any(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp_any(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_any(f64::NAN), 0.0);
        assert_eq!(exp_weight(f64::NAN), 0.0);
        assert_eq!(exp_weight(0.0), 1.0);
        assert_eq!(exp_weight(-0.0), 1.0);
        assert_eq!(exp_weight(-746.0), 0.0);
        assert_eq!(exp_weight(f64::NEG_INFINITY), 0.0);
        assert_eq!(exp_weight(-1e300), 0.0);
    }
}
