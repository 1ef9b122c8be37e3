//! The projection's loop along its line: four samples seen from the line per block, and the
//! energy's first two derivatives.

use super::{Block, Lanes, exp_any, per_lane};
use crate::field::Sample;
use crate::math::{Point, Vector};

/// Four samples seen from the line: `b = (x − q)·n` and `c = |x − q|²` of each (structure of
/// arrays, so that the four are computed side by side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LineBlock {
    pub b: [f64; 4],
    pub c: [f64; 4],
    /// The weights at the last `t` evaluated. Only scratch, but written to memory: the
    /// compiler vectorises the exp only when its results are stored.
    pub w: [f64; 4],
}

impl LineBlock {
    /// The line of `samples` through `x` in direction `n`, in blocks of four; the last block
    /// is padded with samples infinitely far away (weight exactly zero, `b = 0`). Returns the
    /// smallest `c`, by which the weights are shifted so that they cannot all underflow.
    pub(crate) fn fill(out: &mut Vec<Self>, x: &Point, n: &Vector, samples: &[Sample]) -> f64 {
        out.clear();
        let mut shift = f64::INFINITY;
        out.extend(samples.chunks(4).map(|group| {
            let mut block = Self {
                b: [0.0; 4],
                c: [f64::INFINITY; 4],
                w: [0.0; 4],
            };
            for (l, q) in group.iter().enumerate() {
                let d = x - q.point;
                block.b[l] = d.dot(n);
                block.c[l] = d.norm_squared();
                shift = f64::min(shift, block.c[l]);
            }
            block
        }));
        shift
    }
}

/// The loop of [`energy_derivatives`], compiled once per instruction set (see
/// `field::Kernels`): four partial sums each of e' and e'' into `acc`. Stored through a
/// reference, as the field's moments are, so that the compiler pairs the lanes into one
/// register (it found no vector code in a version that returned the sums).
#[inline(always)]
pub(crate) fn line_energy(
    line: &mut [LineBlock],
    a: f64,
    shift: f64,
    t: f64,
    acc: &mut [[f64; 4]; 2],
) {
    // Two loops, the weights first: the compiler vectorises the exp only in a loop that
    // stores its results.
    for block in line.iter_mut() {
        let (b, c) = (block.b, block.c);
        // The branch-free exp: here the argument can be positive, at most a·shift.
        block.w = per_lane(|l| exp_any(-a * (c[l] + 2.0 * t * b[l] + t * t - shift)));
    }
    let mut e1 = [0.0; 4];
    let mut e2 = [0.0; 4];
    for block in line.iter() {
        let theta = block.w;
        let bb = per_lane(|l| block.b[l] + t);
        let ab2 = per_lane(|l| a * bb[l] * bb[l]);
        e1 = per_lane(|l| e1[l] + 2.0 * theta[l] * bb[l] * (1.0 - ab2[l]));
        e2 = per_lane(|l| e2[l] + theta[l] * (2.0 - 10.0 * ab2[l] + 4.0 * ab2[l] * ab2[l]));
    }
    *acc = [e1, e2];
}

/// Powers of `b` summed by [`line_moments`]: `b^0` to `b^(LINE_MOMENTS − 1)`.
pub(crate) const LINE_MOMENTS: usize = 20;

/// The weighted moments of the samples along a line `x + t n`, in units of h: what
/// `projection` sums the energy's derivatives from near `t = 0` as a series, without another
/// pass over the samples.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LineMoments {
    /// `μ_j = Σ w βʲ`, `β = (x − q)·n / h`, with the field's shifted weights at `x`.
    pub mu: [f64; LINE_MOMENTS],
    /// The largest `|β|`.
    pub reach: f64,
    /// `−Σ β`, unweighted: which way the samples lie along the line.
    pub toward: f64,
    /// The weights' shift `δ²/h²` (they are multiplied by `exp(log_scale)`).
    pub log_scale: f64,
}

/// The sums of [`LineMoments`] from the field's blocks once their weights are computed, per
/// lane: `mu`, the largest `|β|` in `reach`, `−Σ β` in `toward`. Unused lanes (zero offset and
/// weight) add nothing.
#[inline(always)]
pub(crate) fn line_moments(
    blocks: &[Block],
    n: &Vector,
    mu: &mut [Lanes; LINE_MOMENTS],
    reach: &mut Lanes,
    toward: &mut Lanes,
) {
    *mu = [[0.0; 4]; LINE_MOMENTS];
    let (mut far, mut sum): (Lanes, Lanes) = ([0.0; 4], [0.0; 4]);
    for block in blocks {
        let [x, y, z] = block.d;
        let b = per_lane(|l| x[l] * n.x + y[l] * n.y + z[l] * n.z);
        let mut p = block.w;
        for m in mu.iter_mut() {
            *m = per_lane(|l| m[l] + p[l]);
            p = per_lane(|l| p[l] * b[l]);
        }
        far = per_lane(|l| far[l].max(b[l].abs()));
        sum = per_lane(|l| sum[l] - b[l]);
    }
    *reach = far;
    *toward = sum;
}
