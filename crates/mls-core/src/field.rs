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

/// Reusable per-thread storage so that evaluation does not allocate.
#[derive(Clone, Debug, Default)]
pub struct FieldScratch {
    weights: Vec<f64>,
    /// `(x − q)/h` per sample, computed once for both passes.
    offsets: Vec<Vector>,
}

/// Evaluates g, ∇g and H at `x` from the given support samples in two passes (the normal-field
/// sums, then the g sums), O(samples).
pub fn evaluate(
    x: &Point,
    samples: &[Sample],
    inv_h2: f64,
    scratch: &mut FieldScratch,
) -> Result<Implicit, PointStatus> {
    if samples.is_empty() {
        return Err(PointStatus::NoNeighbours);
    }
    // Lengths are measured in units of h below (d ← d/h, so a = 1/h² becomes 1): every sum is
    // then of order one at any scale of the cloud, and no power of 1/h² can overflow (a² alone
    // overflows for h below about 1e-77). The results are scaled back at the end.
    let inv_h = inv_h2.sqrt();
    let a = 1.0;
    // Offsets in units of h and their squared lengths first, then the shifted weights in place.
    let offsets = &mut scratch.offsets;
    offsets.clear();
    offsets.extend(samples.iter().map(|s| (x - s.point) * inv_h));
    let weights = &mut scratch.weights;
    weights.clear();
    weights.extend(offsets.iter().map(|d| d.norm_squared()));
    let shift = weights.iter().copied().fold(f64::INFINITY, f64::min);
    for w in weights.iter_mut() {
        *w = (-(*w - shift) * a).exp();
    }

    let field = normal_field_weighted(samples, offsets, weights)?;
    let n = field.normal;
    // K = Jᵀ, so that D = ∂B/∂x = n + K d (the paper's D).
    let jt = field.jacobian.transpose();
    // The sum over samples is split into weighted moments of d, so that per sample only
    // scalars, vectors and symmetric d dᵀ products are accumulated, and J enters once at the
    // end: with D = n + K d,
    //   Σ c (d Dᵀ + D dᵀ) = V nᵀ + n Vᵀ + Q Kᵀ + K Q     (V = Σ c d, Q = Σ c d dᵀ)
    //   Σ c D Dᵀ = S n nᵀ + n (K V)ᵀ + K V nᵀ + K Q Kᵀ   (S = Σ c).
    let mut value = 0.0;
    let mut sum_alpha = 0.0;
    let mut sum_alpha_d = Vector::zeros();
    let mut sum_beta = 0.0;
    let mut sum_beta_d = Vector::zeros();
    let mut q_dd = Sym::default();
    let (mut v_sym, mut q_sym) = (Vector::zeros(), Sym::default());
    let (mut s_bb, mut v_bb, mut q_bb) = (0.0, Vector::zeros(), Sym::default());
    for (&d, &w) in offsets.iter().zip(weights.iter()) {
        let b = d.dot(&n);
        let b2 = b * b;
        let alpha = 2.0 * a * b * (a * b2 - 1.0);
        let beta = 1.0 - 3.0 * a * b2;
        let w2 = 2.0 * w;
        value += w2 * (b - a * b * b2);
        let c_dd = -2.0 * a * alpha;
        let c_sym = 6.0 * a * a * b2 - 2.0 * a;
        let c_bb = -6.0 * a * b;
        let dd = Sym::outer(&d);
        sum_alpha += w2 * alpha;
        sum_alpha_d += d * (w2 * alpha);
        sum_beta += w2 * beta;
        sum_beta_d += d * (w2 * beta);
        q_dd.add_scaled(&dd, w2 * c_dd);
        v_sym += d * (w2 * c_sym);
        q_sym.add_scaled(&dd, w2 * c_sym);
        s_bb += w2 * c_bb;
        v_bb += d * (w2 * c_bb);
        q_bb.add_scaled(&dd, w2 * c_bb);
    }
    // ∇g = Σ 2w (α d + β D).
    let gradient = sum_alpha_d + n * sum_beta + jt * sum_beta_d;
    let (q_sym, q_bb) = (q_sym.matrix(), q_bb.matrix());
    let kq = jt * q_sym;
    let kv = jt * v_bb;
    let nvt = v_sym * n.transpose();
    let nkv = kv * n.transpose();
    let mut hessian = q_dd.matrix()
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
    let weight_sum: f64 = weights.iter().sum();
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
        neighbours: samples.len(),
    })
}

/// The first pass. With `m = Σ w v`, `∇w = −2a w d` and `∇∇w = w(4a² d dᵀ − 2a I)`:
/// `M1 = ∂m/∂x = −2a Σ w v dᵀ`, `M2_a = 4a² Σ w v_a d dᵀ − 2a m_a I`, and with `r = |m|`,
/// `P = I − n nᵀ`, `u = M1ᵀ n` (= ∇r):
/// $$ J = P M_1 / r,\qquad
///    N_a = \big( (P M_2)_a - J_{a\cdot} u^T - u J_{a\cdot}^T - n_a J^T M_1 \big) / r. $$
/// `offsets` are `(x − q)/h`: lengths are in units of h, hence `a = 1`; the caller scales J and
/// ∂²n back.
fn normal_field_weighted(
    samples: &[Sample],
    offsets: &[Vector],
    weights: &[f64],
) -> Result<NormalField, PointStatus> {
    let a = 1.0;
    let mut m = Vector::zeros();
    let mut s1 = Matrix::zeros();
    // s2[c] = Σ w v_c d dᵀ, symmetric.
    let mut s2 = [Sym::default(); 3];
    let mut weight_sum = 0.0;
    for ((s, &d), &w) in samples.iter().zip(offsets).zip(weights) {
        let wv = s.normal * w;
        m += wv;
        s1 += wv * d.transpose();
        let dd = Sym::outer(&d);
        s2[0].add_scaled(&dd, wv.x);
        s2[1].add_scaled(&dd, wv.y);
        s2[2].add_scaled(&dd, wv.z);
        weight_sum += w;
    }
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
    /// `d dᵀ`.
    fn outer(d: &Vector) -> Self {
        Self([
            d.x * d.x,
            d.x * d.y,
            d.x * d.z,
            d.y * d.y,
            d.y * d.z,
            d.z * d.z,
        ])
    }

    fn add_scaled(&mut self, other: &Self, c: f64) {
        for (a, b) in self.0.iter_mut().zip(other.0) {
            *a += c * b;
        }
    }

    fn matrix(&self) -> Matrix {
        let [xx, xy, xz, yy, yz, zz] = self.0;
        Matrix::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
    }
}
