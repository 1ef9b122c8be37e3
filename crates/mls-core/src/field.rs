//! The closed-form MLS implicit function: normal field n(x) (Eq. 2) with its first and second
//! derivatives, and g(x) (Eq. 7) with its gradient (Sec. 4.2) and Hessian (Eq. 8, Appendix).
//!
//! Notation (see `docs/derivation.md`): for samples `q_i` with unit normals `v_i`,
//! `d_i = x − q_i`, `a = 1/h²`, `w_i = exp(−a|d_i|²)`,
//! $$ m = \sum_i w_i v_i,\qquad n = m/|m|,\qquad J_{ak} = \partial n_a/\partial x_k,\qquad
//!    N_{a,kl} = \partial^2 n_a/\partial x_k \partial x_l, $$
//! $$ B_i = d_i\cdot n,\qquad g = \sum_i 2 w_i (B_i - a B_i^3). $$
//!
//! Every weight is multiplied by the positive constant `exp(a δ²)`, δ the distance to the
//! nearest sample, so that they cannot all underflow far from the cloud. n, J and N do not
//! change; g, ∇g and H are scaled by that constant, which curvature does not see.
//! [`Implicit::log_scale`] records it.

use crate::kernels::{Block, Kernels, LANES, LINE_MOMENTS, LineMoments, dispatch, per_lane};
use crate::math::{Matrix, Point, Vector};
use crate::status::PointStatus;

/// A sample of the cloud: a point with its unit, consistently oriented normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// The position `q_i`.
    pub point: Point,
    /// The unit normal `v_i`.
    pub normal: Vector,
}

/// Below this ratio `|Σ w v| / Σ w` the weighted normals cancel and n(x) (Eq. 2) is undefined:
/// its relative rounding error, about `ε_mach · Σw / |m|`, would exceed 1e-10.
pub const MIN_NORMAL_COHERENCE: f64 = 1e-6;

/// Below this ratio `|∇g| / (2 Σ w)` the gradient is treated as zero and the level set has no
/// defined normal. Near the surface the ratio is about 1.
pub const MIN_GRADIENT_RATIO: f64 = 1e-12;

/// The normal field n(x) of Eq. 2 and its derivatives at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalField {
    /// n(x), unit length.
    pub normal: Vector,
    /// `J[(a, k)] = ∂n_a/∂x_k`.
    pub jacobian: Matrix,
    /// `second[a][(k, l)] = ∂²n_a/∂x_k∂x_l`, each symmetric.
    pub second: [Matrix; 3],
    /// `|Σ w v| / Σ w`, in (0, 1]: how coherent the weighted normals are.
    pub coherence: f64,
}

/// g, ∇g and H(g) at one point, scaled by `exp(log_scale)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Implicit {
    /// `g(x) · exp(log_scale)` (Eq. 7).
    pub value: f64,
    /// `∇g(x) · exp(log_scale)`.
    pub gradient: Vector,
    /// `H(g)(x) · exp(log_scale)`, symmetric.
    pub hessian: Matrix,
    /// The normal field and its derivatives at the same point.
    pub field: NormalField,
    /// `δ²/h²`, δ the distance to the nearest sample: the weights were multiplied by
    /// `exp(log_scale)`.
    pub log_scale: f64,
    /// The scaled sum of weights `Σ w_i` (at least 1 by construction of the shift).
    pub weight_sum: f64,
    /// The number of samples that contributed.
    pub neighbours: usize,
}

impl Implicit {
    /// The unscaled value of g, which underflows to 0 far from the cloud.
    pub fn unscaled_value(&self) -> f64 {
        self.value * (-self.log_scale).exp()
    }
}

/// Reusable per-thread storage so that evaluation does not allocate: the loaded samples in
/// blocks of `LANES`, computed once for both passes.
#[derive(Clone, Debug, Default)]
pub struct FieldScratch {
    blocks: Vec<Block>,
    /// Samples loaded.
    len: usize,
    /// `1/h²` of the loaded offsets.
    inv_h2: f64,
    /// The smallest `|d|²` loaded, `δ²/h²`.
    shift: f64,
    /// Blocks whose weights [`Self::loaded_normal`] computed, for [`Self::line_moments`].
    weighed: usize,
    /// Samples in the blocks since the last [`Self::load`], for [`Self::reload_moved`].
    count: usize,
    /// `Σ w` of the last [`Self::loaded_normal`], unshifted.
    weight_sum: f64,
}

impl FieldScratch {
    /// Loads the samples within `sqrt(radius2)` of `x` (all of them for an infinite
    /// `radius2`), and returns how many: their offsets `(x − q)/h`, squared lengths and
    /// normals, ready for [`evaluate_loaded`]. The distance test is on `|x − q|²`, in the
    /// units of the points.
    pub fn load(&mut self, x: &Point, samples: &[Sample], radius2: f64, inv_h2: f64) -> usize {
        // Every sample is written to the next free slot and kept by advancing the count (no
        // branch on the distance test), so one slot past the last sample must exist.
        let needed = samples.len() / LANES + 1;
        if self.blocks.len() < needed {
            self.blocks.resize(needed, Block::default());
        }
        let blocks = &mut self.blocks[..needed];
        let (len, shift) = dispatch!(k => k.load_blocks(blocks, x, samples, radius2, inv_h2));
        self.len = len;
        self.inv_h2 = inv_h2;
        self.shift = shift;
        self.weighed = 0;
        self.count = len;
        len
    }

    /// The samples last loaded, loaded again as seen from the point moved by `delta` (file
    /// units), without reading them: what [`Self::load`] of the same samples with an infinite
    /// radius at the moved point gives, up to the rounding of the offsets' update.
    pub(crate) fn reload_moved(&mut self, delta: &Vector) -> usize {
        let delta = delta * self.inv_h2.sqrt();
        let count = self.count;
        let blocks = &mut self.blocks[..];
        self.shift = dispatch!(k => k.offset_blocks(blocks, &delta, count));
        self.len = count;
        self.weighed = 0;
        count
    }
}

impl FieldScratch {
    /// n(x) alone (Eq. 2), without derivatives, from the samples last loaded by
    /// [`FieldScratch::load`]. It uses them up: load again before [`evaluate_loaded`].
    pub(crate) fn loaded_normal(&mut self) -> Result<Vector, PointStatus> {
        self.weight_sum = 0.0;
        if self.len == 0 {
            return Err(PointStatus::NoNeighbours);
        }
        let weight_sum = self.weigh_loaded();
        self.weight_sum = weight_sum * (-self.shift).exp();
        let blocks = &self.blocks[..self.weighed];
        let m = Vector::from_fn(|c, _| {
            let mut sum = [0.0; LANES];
            for block in blocks.iter() {
                sum = per_lane(|l| sum[l] + block.w[l] * block.normal[c][l]);
            }
            sum.iter().sum()
        });
        let r = m.norm();
        if !(r >= MIN_NORMAL_COHERENCE * weight_sum) {
            return Err(PointStatus::NormalUndefined);
        }
        Ok(m / r)
    }

    /// `Σ w` (unshifted) of the samples the last [`Self::loaded_normal`] weighed, or 0.
    pub(crate) fn normal_weight_sum(&self) -> f64 {
        self.weight_sum
    }

    /// The shifted weights of the samples last loaded, in place of their squared lengths (the
    /// samples are then no longer loaded for [`evaluate_loaded`]); returns `Σ w`.
    pub(crate) fn weigh_loaded(&mut self) -> f64 {
        let end = self.len.div_ceil(LANES);
        self.len = 0;
        self.weighed = end;
        let shift = self.shift;
        dispatch!(k => k.weights(&mut self.blocks[..end], shift))
    }

    /// The moments along the line through the loaded point in direction `n` of the samples
    /// [`Self::weigh_loaded`] last weighed.
    pub(crate) fn line_moments(&self, n: &Vector) -> LineMoments {
        let blocks = &self.blocks[..self.weighed];
        let (mut mu, mut reach, mut toward) =
            ([[0.0; LANES]; LINE_MOMENTS], [0.0; LANES], [0.0; LANES]);
        dispatch!(k => k.line_moments(blocks, n, &mut mu, &mut reach, &mut toward));
        LineMoments {
            mu: mu.map(|m| m.iter().sum()),
            reach: reach.iter().fold(0.0, |m: f64, &r| m.max(r)),
            toward: toward.iter().sum(),
            log_scale: self.shift,
        }
    }
}

/// Evaluates g, ∇g and H at `x` from the given support samples in two passes (the normal-field
/// sums, then the g sums), O(samples).
pub fn evaluate(
    x: &Point,
    samples: &[Sample],
    inv_h2: f64,
    scratch: &mut FieldScratch,
) -> Result<Implicit, PointStatus> {
    scratch.load(x, samples, f64::INFINITY, inv_h2);
    evaluate_loaded(scratch)
}

/// [`evaluate`] on the samples last loaded by [`FieldScratch::load`].
pub fn evaluate_loaded(scratch: &mut FieldScratch) -> Result<Implicit, PointStatus> {
    dispatch!(k => evaluate_with(k, scratch))
}

/// [`evaluate_loaded`] with the per-sample loops of `kernels`.
fn evaluate_with(
    kernels: impl Kernels,
    scratch: &mut FieldScratch,
) -> Result<Implicit, PointStatus> {
    if scratch.len == 0 {
        return Err(PointStatus::NoNeighbours);
    }
    // Offsets are in units of h (see `FieldScratch::load`); the results are scaled back at
    // the end.
    let (inv_h2, shift) = (scratch.inv_h2, scratch.shift);
    let inv_h = inv_h2.sqrt();
    let a = 1.0;
    let blocks = &mut scratch.blocks[..scratch.len.div_ceil(LANES)];
    let weight_sum = kernels.weigh(blocks, shift * a);
    let field = normal_field_weighted(kernels, blocks, weight_sum)?;
    let n = field.normal;
    // K = Jᵀ, so that D = ∂B/∂x = n + K d (the paper's D).
    let jt = field.jacobian.transpose();
    // The sum over samples is split into weighted moments of d, so that per sample only
    // scalar coefficients are formed, and J enters once at the end: with D = n + K d,
    //   Σ c (d Dᵀ + D dᵀ) = V nᵀ + n Vᵀ + Q Kᵀ + K Q     (V = Σ c d, Q = Σ c d dᵀ)
    //   Σ c D Dᵀ = S n nᵀ + n (K V)ᵀ + K V nᵀ + K Q Kᵀ   (S = Σ c).
    kernels.coefficients(blocks, &n);
    let alpha = moments(kernels, blocks, 0);
    let beta = moments(kernels, blocks, 1);
    let bb = moments(kernels, blocks, 2);
    let (sum_alpha, sum_alpha_d) = (alpha.sum, alpha.first);
    let (sum_beta, sum_beta_d) = (beta.sum, beta.first);
    // The D dᵀ-free part of ∂(2wα d)/∂x: c_dd = −2aα.
    let q_dd = alpha.second.matrix() * (-2.0 * a);
    // The coefficient of the (D dᵀ + d Dᵀ) term is c_sym = 6a²B² − 2a = −2aβ: its moments are
    // β's (bit for bit: both round 3aB² once, and the factor 2 is exact).
    let (v_sym, q_sym) = (sum_beta_d * (-2.0 * a), beta.second.matrix() * (-2.0 * a));
    let (s_bb, v_bb, q_bb) = (bb.sum, bb.first, bb.second.matrix());
    // g = Σ 2w(B − aB³) = −Σ 2wα / (2a).
    let value = -sum_alpha / (2.0 * a);
    // ∇g = Σ 2w (α d + β D).
    let gradient = sum_alpha_d + n * sum_beta + jt * sum_beta_d;
    let kq = jt * q_sym;
    let kv = jt * v_bb;
    let nvt = v_sym * n.transpose();
    let nkv = kv * n.transpose();
    let mut hessian = q_dd
        + nvt
        + nvt.transpose()
        + kq
        + kq.transpose()
        + n * n.transpose() * s_bb
        + nkv
        + nkv.transpose()
        + jt * q_bb * jt.transpose()
        + Matrix::from_diagonal_element(sum_alpha);
    // Σ 2wβ ∂D/∂x with ∂D/∂x = J + Jᵀ + Σ_a d_a ∂²n_a (Appendix), the sums factored out.
    hessian += (field.jacobian + jt) * sum_beta
        + field.second[0] * sum_beta_d.x
        + field.second[1] * sum_beta_d.y
        + field.second[2] * sum_beta_d.z;
    if !(gradient.norm() > MIN_GRADIENT_RATIO * 2.0 * weight_sum) {
        return Err(PointStatus::GradientVanishes);
    }
    // Back to world units: g is a length, ∇g dimensionless, H, J an inverse length, ∂²n an
    // inverse area.
    let field = NormalField {
        jacobian: field.jacobian * inv_h,
        second: field.second.map(|m| m * inv_h2),
        ..field
    };
    Ok(Implicit {
        value: value / inv_h,
        gradient,
        hessian: hessian * inv_h,
        field,
        log_scale: shift * a,
        weight_sum,
        neighbours: scratch.len,
    })
}

/// `Σ c`, `Σ c d` and (when `SECOND`) `Σ c d dᵀ` over the loaded samples, for per-sample
/// coefficients `c`.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    sum: f64,
    first: Vector,
    second: Sym,
}

/// The [`Moments`] of the coefficients `block.coef[k]`.
fn moments(kernels: impl Kernels, blocks: &[Block], k: usize) -> Moments {
    let mut acc = [[0.0; LANES]; 10];
    kernels.lane_moments(blocks, k, &mut acc);
    let [s, x, y, z, xx, xy, xz, yy, yz, zz] = acc.map(|lanes| lanes.iter().sum::<f64>());
    Moments {
        sum: s,
        first: Vector::new(x, y, z),
        second: Sym([xx, xy, xz, yy, yz, zz]),
    }
}

/// The first pass. With `m = Σ w v`, `∇w = −2a w d` and `∇∇w = w(4a² d dᵀ − 2a I)`:
/// `M1 = ∂m/∂x = −2a Σ w v dᵀ`, `M2_a = 4a² Σ w v_a d dᵀ − 2a m_a I`, and with `r = |m|`,
/// `P = I − n nᵀ`, `u = M1ᵀ n` (= ∇r):
/// $$ J = P M_1 / r,\qquad
///    N_a = \big( (P M_2)_a - J_{a\cdot} u^T - u J_{a\cdot}^T - n_a J^T M_1 \big) / r. $$
/// The loaded offsets are `(x − q)/h`: lengths are in units of h, hence `a = 1`; the caller
/// scales J and ∂²n back. `weight_sum` is `Σ w`.
fn normal_field_weighted(
    kernels: impl Kernels,
    blocks: &[Block],
    weight_sum: f64,
) -> Result<NormalField, PointStatus> {
    let a = 1.0;
    // Row c of S1 = Σ w v dᵀ and s2[c] = Σ w v_c d dᵀ (symmetric) are the moments of w v_c.
    let [mx, my, mz] = [0, 1, 2].map(|c| moments(kernels, blocks, c));
    let m = Vector::new(mx.sum, my.sum, mz.sum);
    let s1 = Matrix::from_rows(&[
        mx.first.transpose(),
        my.first.transpose(),
        mz.first.transpose(),
    ]);
    let s2 = [mx.second, my.second, mz.second];
    let r = m.norm();
    let coherence = r / weight_sum;
    if !(coherence >= MIN_NORMAL_COHERENCE) {
        return Err(PointStatus::NormalUndefined);
    }
    let n = m / r;
    let m1 = s1 * (-2.0 * a);
    // M2_c = 4a² Σ w v_c d dᵀ − 2a m_c I, but only P M2 is used and P m = 0 (m ∥ n): the
    // identity part never contributes, so it is not formed (mutation testing showed that
    // changing it changed nothing).
    let m2: [Matrix; 3] = std::array::from_fn(|c| s2[c].matrix() * (4.0 * a * a));
    let p = Matrix::identity() - n * n.transpose();
    let jacobian = p * m1 / r;
    let u = m1.transpose() * n;
    let jtm1 = jacobian.transpose() * m1;
    let second = std::array::from_fn(|c| {
        // (P M2)_c = Σ_b P_cb M2_b.
        let pm2 = m2[0] * p[(c, 0)] + m2[1] * p[(c, 1)] + m2[2] * p[(c, 2)];
        let jrow = jacobian.row(c).transpose();
        let ju = jrow * u.transpose();
        (pm2 - ju - ju.transpose() - jtm1 * n[c]) / r
    });
    Ok(NormalField {
        normal: n,
        jacobian,
        second,
        coherence,
    })
}

/// A symmetric 3 × 3 accumulator holding the six distinct entries.
#[derive(Clone, Copy, Debug, Default)]
struct Sym([f64; 6]);

impl Sym {
    fn matrix(&self) -> Matrix {
        let [xx, xy, xz, yy, yz, zz] = self.0;
        Matrix::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
    }
}

/// The projection's reload from a moved point sees what a fresh load there sees.
#[cfg(test)]
mod reload_tests {
    use super::*;

    #[test]
    fn reloading_from_a_moved_point_matches_loading_there() {
        let samples: Vec<Sample> = (0..37)
            .map(|i| {
                let (u, v) = (f64::from(i % 7) * 0.1 - 0.3, f64::from(i / 7) * 0.1 - 0.25);
                Sample {
                    point: Point::new(u, v, 0.2 * u * v),
                    normal: Vector::new(-0.2 * v, -0.2 * u, 1.0).normalize(),
                }
            })
            .collect();
        let (x, delta, inv_h2) = (
            Point::new(0.01, 0.02, 0.05),
            Vector::new(0.0, 0.01, -0.04),
            25.0,
        );
        let mut fresh = FieldScratch::default();
        fresh.load(&(x + delta), &samples, f64::INFINITY, inv_h2);
        let mut moved = FieldScratch::default();
        moved.load(&x, &samples, f64::INFINITY, inv_h2);
        moved.loaded_normal().unwrap();
        assert_eq!(moved.reload_moved(&delta), samples.len());
        assert!((moved.shift - fresh.shift).abs() < 1e-15);
        let n = fresh.loaded_normal().unwrap();
        let m = moved.loaded_normal().unwrap();
        assert!((n - m).norm() < 1e-15, "{n} against {m}");
        // The unused lanes of the last block stay weightless.
        let last = &moved.blocks[samples.len() / LANES];
        assert!(last.w[samples.len() % LANES..].iter().all(|&w| w == 0.0));
    }
}

/// Every [`Kernels`] implementation this CPU can run gives the same bits: the lane count is
/// fixed and no path fuses operations.
#[cfg(all(test, target_arch = "x86_64"))]
mod isa_tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::kernels::{Avx2, Lanes, LineBlock, Portable};

    fn run(kernels: impl Kernels, x: &Point, samples: &[Sample]) -> Result<Implicit, PointStatus> {
        let mut scratch = FieldScratch::default();
        let needed = samples.len() / LANES + 1;
        scratch.blocks.resize(needed, Block::default());
        let (len, shift) = kernels.load_blocks(&mut scratch.blocks, x, samples, 0.25, 100.0);
        (scratch.len, scratch.inv_h2, scratch.shift) = (len, 100.0, shift);
        evaluate_with(kernels, &mut scratch)
    }

    /// The line moments' per-lane sums along `x + t n`, by `kernels`.
    fn line_moments_with(
        kernels: impl Kernels,
        x: &Point,
        samples: &[Sample],
        n: &Vector,
    ) -> ([Lanes; LINE_MOMENTS], Lanes, Lanes) {
        let mut scratch = FieldScratch::default();
        scratch.load(x, samples, f64::INFINITY, 100.0);
        scratch.weigh_loaded();
        let (mut mu, mut reach, mut toward) =
            ([[0.0; LANES]; LINE_MOMENTS], [0.0; LANES], [0.0; LANES]);
        let blocks = &scratch.blocks[..scratch.weighed];
        kernels.line_moments(blocks, n, &mut mu, &mut reach, &mut toward);
        (mu, reach, toward)
    }

    #[test]
    fn avx2_and_portable_kernels_agree_bitwise() {
        let Some(avx2) = Avx2::new() else {
            eprintln!("no AVX2 on this CPU: only the portable kernels exist here");
            return;
        };
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        // A bumpy unit-sphere patch of 600 samples with perturbed normals (the ragged last
        // block and the cutoff both exercised), queried off the surface.
        let samples: Vec<Sample> = (0..600)
            .map(|_| {
                let v = Vector::new(
                    rng.random_range(-0.4..0.4),
                    rng.random_range(-0.4..0.4),
                    1.0,
                )
                .normalize();
                let r = 1.0 + 0.01 * rng.random_range(-1.0..1.0);
                let tilt = Vector::new(rng.random_range(-0.1..0.1), 0.0, 0.0);
                Sample {
                    point: Point::from(v * r),
                    normal: (v + tilt).normalize(),
                }
            })
            .collect();
        for _ in 0..20 {
            let x = Point::new(
                rng.random_range(-0.2..0.2),
                rng.random_range(-0.2..0.2),
                rng.random_range(0.95..1.05),
            );
            let (a, b) = (run(Portable, &x, &samples), run(avx2, &x, &samples));
            let a = a.expect("evaluates");
            assert!(a.neighbours > 100 && a.neighbours < 600, "{}", a.neighbours);
            assert_eq!(Ok(a), b);

            // The weights alone (the projection's n(x)).
            let weights = |kernels: &dyn Fn(&mut [Block], f64) -> f64| {
                let mut scratch = FieldScratch::default();
                scratch
                    .blocks
                    .resize(samples.len() / LANES + 1, Block::default());
                let (len, shift) =
                    Portable.load_blocks(&mut scratch.blocks, &x, &samples, 0.25, 100.0);
                let blocks = &mut scratch.blocks[..len.div_ceil(LANES)];
                let sum = kernels(blocks, shift);
                (sum, blocks.iter().map(|b| b.w).collect::<Vec<_>>())
            };
            assert_eq!(
                weights(&|b, s| Portable.weights(b, s)),
                weights(&|b, s| avx2.weights(b, s))
            );

            // The projection's line energy, at a few points along a line.
            let n = Vector::new(0.1, -0.2, 1.0).normalize();
            let mut line = Vec::new();
            LineBlock::fill(&mut line, &x, &n, &samples[..599]);
            let mut other = line.clone();
            for t in [-0.03, 0.0, 0.02] {
                let (mut p, mut q) = ([[0.0; LANES]; 2], [[0.0; LANES]; 2]);
                Portable.line_energy(&mut line, 100.0, 0.0, t, &mut p);
                avx2.line_energy(&mut other, 100.0, 0.0, t, &mut q);
                assert!(p[0].iter().all(|v| v.is_finite() && *v != 0.0));
                assert_eq!(p, q);
            }

            // The projection's reload from a moved point.
            let moved = |kernels: &dyn Fn(&mut [Block], usize) -> f64| {
                let mut scratch = FieldScratch::default();
                scratch.load(&x, &samples[..599], f64::INFINITY, 100.0);
                let shift = kernels(&mut scratch.blocks, scratch.count);
                let blocks = &scratch.blocks[..599usize.div_ceil(LANES)];
                (shift, blocks.iter().map(|b| (b.d, b.w)).collect::<Vec<_>>())
            };
            let delta = Vector::new(0.01, -0.02, 0.03);
            assert_eq!(
                moved(&|b, len| Portable.offset_blocks(b, &delta, len)),
                moved(&|b, len| avx2.offset_blocks(b, &delta, len))
            );

            // The moments of the projection's series along that line, from the weighed blocks.
            let by_portable = line_moments_with(Portable, &x, &samples[..599], &n);
            assert!(by_portable.0[LINE_MOMENTS - 1].iter().all(|v| *v != 0.0));
            assert_eq!(
                by_portable,
                line_moments_with(avx2, &x, &samples[..599], &n)
            );
        }
    }
}
