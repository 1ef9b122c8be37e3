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

use crate::math::{Matrix, Point, Vector};
use crate::projection::{LineBlock, line_energy};
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

/// Samples per [`Block`]: the per-neighbour sums run on `LANES` independent partial sums,
/// which the compiler turns into SIMD operations (the sums of one lane are then added at the
/// end, a different order than one running sum: results change by rounding only). Four lanes
/// fill an AVX2 register; without AVX2 they take two SSE2 registers each. The count is the
/// same on every CPU, and no code path fuses a multiply and an add, so results are bitwise
/// the same whichever [`Kernels`] run.
const LANES: usize = 4;

/// One value per lane.
type Lanes = [f64; LANES];

/// `LANES` loaded samples, one field per quantity (structure of arrays within the block, so
/// that the per-neighbour loops read whole lane arrays). Unused lanes of the last block hold
/// zero offsets, normals and weights, and add exactly zero to every sum.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Block {
    /// `d = (x − q)/h`, per axis.
    d: [Lanes; 3],
    /// The unit normal `v`, per axis.
    normal: [Lanes; 3],
    /// `|d|²` while loading, then the shifted weight `exp(−(|d|² − δ²/h²))`.
    w: Lanes,
    /// The distinct entries of `d dᵀ`: xx, xy, xz, yy, yz, zz.
    dd: [Lanes; 6],
    /// The per-sample coefficients whose moments are summed: `w·v_x`, `w·v_y`, `w·v_z` in the
    /// first pass, then `2w·α`, `2w·β`, `2w·c_bb` in the second.
    coef: [Lanes; 3],
}

/// Reusable per-thread storage so that evaluation does not allocate: the loaded samples in
/// blocks of [`LANES`], computed once for both passes.
#[derive(Clone, Debug, Default)]
pub struct FieldScratch {
    blocks: Vec<Block>,
    /// Samples loaded.
    len: usize,
    /// `1/h²` of the loaded offsets.
    inv_h2: f64,
    /// The smallest `|d|²` loaded, `δ²/h²`.
    shift: f64,
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
        let (len, shift) = match Isa::detect() {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(k) => k.load_blocks(blocks, x, samples, radius2, inv_h2),
            Isa::Portable(k) => k.load_blocks(blocks, x, samples, radius2, inv_h2),
        };
        self.len = len;
        self.inv_h2 = inv_h2;
        self.shift = shift;
        len
    }
}

impl FieldScratch {
    /// n(x) alone (Eq. 2), without derivatives, from the samples last loaded by
    /// [`FieldScratch::load`]. It uses them up: load again before [`evaluate_loaded`].
    pub(crate) fn loaded_normal(&mut self) -> Result<Vector, PointStatus> {
        if self.len == 0 {
            return Err(PointStatus::NoNeighbours);
        }
        let blocks = &mut self.blocks[..self.len.div_ceil(LANES)];
        self.len = 0;
        let shift = self.shift;
        let weight_sum = match Isa::detect() {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(k) => k.weights(blocks, shift),
            Isa::Portable(k) => k.weights(blocks, shift),
        };
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
}

/// The loop of [`FieldScratch::load`]: fills `blocks` and returns the count and the shift.
#[inline(always)]
fn load_blocks(
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
    match Isa::detect() {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2(k) => evaluate_with(k, scratch),
        Isa::Portable(k) => evaluate_with(k, scratch),
    }
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

/// Declares [`Kernels`] from one list of its loops and implements it twice: for
/// [`Portable`], and for [`Avx2`] through a `#[target_feature(enable = "avx2")]` copy of each
/// loop. Each loop is the free function of the same name, `#[inline(always)]` so that it is
/// compiled into both.
macro_rules! kernels {
    ($($(#[$doc:meta])* fn $name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)?;)*) => {
        /// The per-sample loops, compiled for one instruction set. They are the only code whose
        /// cost grows with the number of samples; the per-point algebra around them is the same
        /// for all.
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
    /// [`weigh`].
    fn weigh(blocks: &mut [Block], shift: f64) -> f64;
    /// [`weights`].
    fn weights(blocks: &mut [Block], shift: f64) -> f64;
    /// [`coefficients`].
    fn coefficients(blocks: &mut [Block], n: &Vector);
    /// [`lane_moments`].
    fn lane_moments(blocks: &[Block], k: usize, acc: &mut [Lanes; 10]);
    /// [`crate::projection::line_energy`].
    fn line_energy(line: &mut [LineBlock], a: f64, shift: f64, t: f64, acc: &mut [Lanes; 2]);
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

/// The instruction set the per-sample loops of [`evaluate`] run with on this CPU: `"avx2"`, or
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
    fn new() -> Option<Self> {
        std::arch::is_x86_feature_detected!("avx2").then_some(Self(()))
    }
}

/// The shifted weights `exp(−(|d|² − shift))` in place of the squared lengths, and the
/// `d dᵀ` products both passes use. The first pass's coefficients `w v` go to `coef`.
/// Returns `Σ w`.
#[inline(always)]
fn weigh(blocks: &mut [Block], shift: f64) -> f64 {
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
fn weights(blocks: &mut [Block], shift: f64) -> f64 {
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
fn exponentiate(blocks: &mut [Block], shift: f64) {
    for block in blocks.iter_mut() {
        block.w = per_lane(|l| exp_weight(shift - block.w[l]));
    }
}

/// `[f(0), …, f(LANES − 1)]`, unrolled.
#[inline(always)]
pub(crate) fn per_lane(f: impl Fn(usize) -> f64) -> Lanes {
    const { assert!(LANES == 4) };
    [f(0), f(1), f(2), f(3)]
}

/// The second pass's per-sample coefficients for the normal `n`: `2wα`, `2wβ` and `2w c_bb`
/// with `B = d·n`, `α = 2aB(aB² − 1)`, `β = 1 − 3aB²`, `c_bb = −6aB` (a = 1: lengths are in
/// units of h).
#[inline(always)]
fn coefficients(blocks: &mut [Block], n: &Vector) {
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
fn lane_moments(blocks: &[Block], k: usize, acc: &mut [Lanes; 10]) {
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

/// Every [`Kernels`] implementation this CPU can run gives the same bits: the lane count is
/// fixed and no path fuses operations.
#[cfg(all(test, target_arch = "x86_64"))]
mod isa_tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn run(kernels: impl Kernels, x: &Point, samples: &[Sample]) -> Result<Implicit, PointStatus> {
        let mut scratch = FieldScratch::default();
        let needed = samples.len() / LANES + 1;
        scratch.blocks.resize(needed, Block::default());
        let (len, shift) = kernels.load_blocks(&mut scratch.blocks, x, samples, 0.25, 100.0);
        (scratch.len, scratch.inv_h2, scratch.shift) = (len, 100.0, shift);
        evaluate_with(kernels, &mut scratch)
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
            crate::projection::LineBlock::fill(&mut line, &x, &n, &samples[..599]);
            let mut other = line.clone();
            for t in [-0.03, 0.0, 0.02] {
                let (mut p, mut q) = ([[0.0; LANES]; 2], [[0.0; LANES]; 2]);
                Portable.line_energy(&mut line, 100.0, 0.0, t, &mut p);
                avx2.line_energy(&mut other, 100.0, 0.0, t, &mut q);
                assert!(p[0].iter().all(|v| v.is_finite() && *v != 0.0));
                assert_eq!(p, q);
            }
        }
    }
}
