//! The field's loops over blocks of samples: loading, weights, coefficients, moments.

use super::{LANES, Lanes, exp_weight, per_lane};
use crate::field::Sample;
use crate::math::{Point, Vector};

/// `LANES` loaded samples, one field per quantity (structure of arrays within the block, so
/// that the per-neighbour loops read whole lane arrays). Unused lanes of the last block hold
/// zero offsets, normals and weights, and add exactly zero to every sum.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Block {
    /// `d = (x − q)/h`, per axis.
    pub(crate) d: [Lanes; 3],
    /// The unit normal `v`, per axis.
    pub(crate) normal: [Lanes; 3],
    /// `|d|²` while loading, then the shifted weight `exp(−(|d|² − δ²/h²))`.
    pub(crate) w: Lanes,
    /// The distinct entries of `d dᵀ`: xx, xy, xz, yy, yz, zz.
    pub(crate) dd: [Lanes; 6],
    /// The per-sample coefficients whose moments are summed: `w·v_x`, `w·v_y`, `w·v_z` in the
    /// first pass, then `2w·α`, `2w·β`, `2w·c_bb` in the second.
    pub(crate) coef: [Lanes; 3],
}

/// The loop of [`FieldScratch::load`]: fills `blocks` and returns the count and the shift.
#[inline(always)]
pub(crate) fn load_blocks(
    blocks: &mut [Block],
    x: &Point,
    samples: &[Sample],
    radius2: f64,
    inv_h2: f64,
) -> (usize, f64) {
    let inv_h = inv_h2.sqrt();
    let mut len = 0;
    for s in samples {
        let e = x - s.point;
        let keep = !(e.norm_squared() > radius2);
        // Lengths are in units of h from here on (d ← d/h, so a = 1/h² becomes 1): every
        // sum is then of order one at any scale of the cloud, and no power of 1/h² can
        // overflow (a² alone overflows for h below about 1e-77).
        let d = e * inv_h;
        let (block, lane) = (&mut blocks[len / LANES], len % LANES);
        block.d[0][lane] = d.x;
        block.d[1][lane] = d.y;
        block.d[2][lane] = d.z;
        block.normal[0][lane] = s.normal.x;
        block.normal[1][lane] = s.normal.y;
        block.normal[2][lane] = s.normal.z;
        block.w[lane] = d.norm_squared();
        len += usize::from(keep);
    }
    // The free lanes of the last block: exp(−∞) = 0 makes their weights exactly zero.
    let end = len.div_ceil(LANES);
    for slot in len..end * LANES {
        let (block, lane) = (&mut blocks[slot / LANES], slot % LANES);
        for k in 0..3 {
            block.d[k][lane] = 0.0;
            block.normal[k][lane] = 0.0;
        }
        block.w[lane] = f64::INFINITY;
    }
    // The shift δ²/h², outside the loop above so that it has no branch.
    let mut nearest = [f64::INFINITY; LANES];
    for block in &blocks[..end] {
        for (m, &w) in nearest.iter_mut().zip(&block.w) {
            *m = if w < *m { w } else { *m };
        }
    }
    let shift = nearest.into_iter().fold(f64::INFINITY, f64::min);
    (len, shift)
}

/// The blocks of `len` loaded samples seen from a point moved by `delta` (in units of h):
/// `d + delta`, and `|d|²` in place of the weights, the unused lanes after the last sample
/// kept at zero offset and infinite length as [`load_blocks`] leaves them. Returns the shift,
/// the smallest `|d|²`. Cheaper than loading again: the samples are not read.
#[inline(always)]
pub(crate) fn offset_blocks(blocks: &mut [Block], delta: &Vector, len: usize) -> f64 {
    let end = len.div_ceil(LANES);
    let mut nearest = [f64::INFINITY; LANES];
    for block in &mut blocks[..end] {
        let [x, y, z] = block.d;
        let d = [
            per_lane(|l| x[l] + delta.x),
            per_lane(|l| y[l] + delta.y),
            per_lane(|l| z[l] + delta.z),
        ];
        block.d = d;
        block.w = per_lane(|l| d[0][l] * d[0][l] + d[1][l] * d[1][l] + d[2][l] * d[2][l]);
        nearest = per_lane(|l| {
            if block.w[l] < nearest[l] {
                block.w[l]
            } else {
                nearest[l]
            }
        });
    }
    for slot in len..end * LANES {
        let (block, lane) = (&mut blocks[slot / LANES], slot % LANES);
        for k in 0..3 {
            block.d[k][lane] = 0.0;
        }
        block.w[lane] = f64::INFINITY;
    }
    nearest.into_iter().fold(f64::INFINITY, f64::min)
}

/// The shifted weights `exp(−(|d|² − shift))` in place of the squared lengths, and the
/// `d dᵀ` products both passes use. The first pass's coefficients `w v` go to `coef`.
/// Returns `Σ w`.
#[inline(always)]
pub(crate) fn weigh(blocks: &mut [Block], shift: f64) -> f64 {
    let mut sum = [0.0; LANES];
    for block in blocks {
        // One exp per lane, written out: the compiler does not unroll a loop around a body this
        // long, and only unrolled copies become one SIMD sequence.
        let w = per_lane(|l| exp_weight(shift - block.w[l]));
        block.w = w;
        sum = per_lane(|l| sum[l] + w[l]);
        let [x, y, z] = block.d;
        let mul = |u: Lanes, v: Lanes| per_lane(|l| u[l] * v[l]);
        block.dd = [
            mul(x, x),
            mul(x, y),
            mul(x, z),
            mul(y, y),
            mul(y, z),
            mul(z, z),
        ];
        block.coef = block.normal.map(|v| mul(w, v));
    }
    sum.iter().sum()
}

/// The shifted weights alone, in place of the squared lengths (for n(x) without derivatives).
/// Returns `Σ w`.
#[inline(always)]
pub(crate) fn weights(blocks: &mut [Block], shift: f64) -> f64 {
    exponentiate(blocks, shift);
    let mut sum = [0.0; LANES];
    for block in blocks.iter() {
        sum = per_lane(|l| sum[l] + block.w[l]);
    }
    sum.iter().sum()
}

/// `exp(−(|d|² − shift))` in place of each `|d|²`: a loop that only computes and stores the
/// exps, each lane written out, which is the shape the compiler reliably vectorises (with the
/// sum in the same loop the exp stayed scalar). [`weigh`]'s fused loop is vectorised too, but
/// fragilely: one more select in [`exp_weight`] made it scalar (`cargo xtask bench` shows it).
#[inline(always)]
pub(crate) fn exponentiate(blocks: &mut [Block], shift: f64) {
    for block in blocks.iter_mut() {
        block.w = per_lane(|l| exp_weight(shift - block.w[l]));
    }
}

/// The second pass's per-sample coefficients for the normal `n`: `2wα`, `2wβ` and `2w c_bb`
/// with `B = d·n`, `α = 2aB(aB² − 1)`, `β = 1 − 3aB²`, `c_bb = −6aB` (a = 1: lengths are in
/// units of h).
#[inline(always)]
pub(crate) fn coefficients(blocks: &mut [Block], n: &Vector) {
    let a = 1.0;
    for block in blocks {
        for lane in 0..LANES {
            let b = block.d[0][lane] * n.x + block.d[1][lane] * n.y + block.d[2][lane] * n.z;
            let b2 = b * b;
            let alpha = 2.0 * a * b * (a * b2 - 1.0);
            let beta = 1.0 - 3.0 * a * b2;
            let w2 = 2.0 * block.w[lane];
            let c_bb = -6.0 * a * b;
            block.coef[0][lane] = w2 * alpha;
            block.coef[1][lane] = w2 * beta;
            block.coef[2][lane] = w2 * c_bb;
        }
    }
}

/// The partial sums of [`moments`] of `block.coef[k]`, one per lane: `acc[0]` of `c`,
/// `acc[1..4]` of `c d`, `acc[4..10]` of `c d dᵀ`.
#[inline(always)]
pub(crate) fn lane_moments(blocks: &[Block], k: usize, acc: &mut [Lanes; 10]) {
    let mut sum = [0.0; LANES];
    let mut first = [[0.0; LANES]; 3];
    let mut second = [[0.0; LANES]; 6];
    for block in blocks {
        let c = block.coef[k];
        for lane in 0..LANES {
            sum[lane] += c[lane];
            for (f, d) in first.iter_mut().zip(&block.d) {
                f[lane] += c[lane] * d[lane];
            }
            for (s, dd) in second.iter_mut().zip(&block.dd) {
                s[lane] += c[lane] * dd[lane];
            }
        }
    }
    acc[0] = sum;
    acc[1..4].copy_from_slice(&first);
    acc[4..].copy_from_slice(&second);
}
