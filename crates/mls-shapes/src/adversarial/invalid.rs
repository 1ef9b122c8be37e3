//! Invalid or inconsistent input: unoriented normals, non-finite coordinates, bad normals.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::patch::{random_unit, smooth_draft};
use super::{Draft, Expectation};
use crate::math::Vector;

pub(super) fn unoriented(rng: &mut ChaCha8Rng) -> Draft {
    let mut draft = smooth_draft(rng, "");
    let mode = rng.random_range(0..3);
    draft.variant = ["random signs", "10% flipped", "random directions"][mode];
    for (_, n) in &mut draft.points {
        *n = match mode {
            0 if rng.random_bool(0.5) => -*n,
            1 if rng.random_bool(0.1) => -*n,
            2 => random_unit(rng),
            _ => *n,
        };
    }
    draft
}

pub(super) fn non_finite(rng: &mut ChaCha8Rng) -> Draft {
    let mut draft = smooth_draft(rng, "NaN and infinite coordinates");
    let len = draft.points.len();
    let bad = rng.random_range(1..=3);
    let mut first = len;
    for _ in 0..bad {
        let index = rng.random_range(0..len);
        let value = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][rng.random_range(0..3)];
        draft.points[index].0[rng.random_range(0..3)] = value;
        first = first.min(index);
    }
    draft.expectation = Expectation::NonFinitePoint { index: first };
    draft
}

pub(super) fn bad_normals(rng: &mut ChaCha8Rng) -> Draft {
    let mut draft = smooth_draft(rng, "");
    let len = draft.points.len();
    if rng.random_bool(0.25) {
        // Finite, non-zero normals of any length are valid input: the surface normalises them.
        // 1e±150, not more: normals of length 1e±200 are rejected (their squared length
        // leaves the double range), see docs/robustness.md.
        let exponent: i32 = if rng.random_bool(0.5) { 150 } else { -150 };
        let factor = 10f64.powi(exponent);
        for (_, n) in &mut draft.points {
            *n *= factor;
        }
        draft.variant = if exponent > 0 {
            "normals of length 1e150"
        } else {
            "normals of length 1e-150"
        };
        return draft;
    }
    let bad = rng.random_range(1..=3);
    let mut first = len;
    for _ in 0..bad {
        let index = rng.random_range(0..len);
        let normal = &mut draft.points[index].1;
        match rng.random_range(0..4) {
            0 => *normal = Vector::zeros(),
            1 => normal[rng.random_range(0..3)] = f64::NAN,
            2 => normal[rng.random_range(0..3)] = f64::INFINITY,
            // Subnormal: the length is below the smallest normal double.
            _ => *normal *= 1e-310,
        }
        first = first.min(index);
    }
    draft.variant = "zero, NaN, infinite or subnormal normals";
    draft.expectation = Expectation::BadNormal { index: first };
    draft
}
