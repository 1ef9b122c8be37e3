//! The independent witness: the MLS implicit function g written once from its definitions
//! (Eqs. 2, 3, 4, 5 and 7), generic over num-dual's dual numbers, and differentiated
//! automatically.
//!
//! Architecture invariant: this crate uses mls-core's data types ([`Sample`], `PointStatus`)
//! only, never its neighbour search, derivative, projection, normal-estimation, spacing or
//! curvature code: every support is a brute-force distance filter ([`support`]). Generic
//! dual-number code lives here and nowhere else.

mod adaptive;
pub mod documented;
mod jet;
mod jet_quadratic;
mod jet_share;
mod line;
mod normals;
mod orientation;
mod spacing;
mod support;

pub use adaptive::{AdaptiveWitness, Ladder, adaptive_witness};
pub use jet::{JetRefusal, JetWitness, jet_candidates, jet_witness};
pub use jet_share::ShareWitness;
pub use line::{LineWitness, line_witness, stationarity};
use mls_core::Sample;
use nalgebra::{Matrix3, SVector, SymmetricEigen, Vector3};
pub use normals::{NormalWitness, jacobi, normal_witness};
use num_dual::{DualNum, gradient, hessian};
pub use orientation::{PairCount, pair_agreement};
pub use spacing::{SpacingWitness, grid_rms_by_shells, spacing_witness};
pub use support::{COHERENCE_FLOOR, GRADIENT_FLOOR, classify, classify_g, support, weight_sum};

/// Everything the closed form computes, recomputed by automatic differentiation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Witness {
    /// g (Eq. 7), scaled by `exp(log_scale)`.
    pub value: f64,
    /// ∇g, same scale.
    pub gradient: Vector3<f64>,
    /// H(g), same scale.
    pub hessian: Matrix3<f64>,
    /// n(x) (Eq. 2).
    pub normal: Vector3<f64>,
    /// `J[(a, k)] = ∂n_a/∂x_k`.
    pub jacobian: Matrix3<f64>,
    /// `second[a][(k, l)] = ∂²n_a/∂x_k∂x_l`.
    pub second: [Matrix3<f64>; 3],
    /// `a·δ²`, δ the distance to the nearest sample: every weight carries `exp(log_scale)`.
    pub log_scale: f64,
}

/// Curvature recomputed by a route independent of mls-core's: a symmetric 3 × 3
/// eigen-decomposition of the projected Hessian `P H P / |∇g|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WitnessCurvature {
    /// Larger principal curvature.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// `(k1 + k2)/2`.
    pub mean: f64,
    /// `k1 · k2`.
    pub gauss: f64,
    /// Principal direction of k1 (sign arbitrary).
    pub d1: Vector3<f64>,
    /// Principal direction of k2 (sign arbitrary).
    pub d2: Vector3<f64>,
}

/// The Gaussian weight θ (Eq. 3) times the constant `exp(shift)`.
fn theta<D: DualNum<Primitive = f64> + Copy>(
    x: &SVector<D, 3>,
    q: &Vector3<f64>,
    inv_h2: f64,
    shift: f64,
) -> D {
    let d = x - q.map(D::from);
    (-d.dot(&d) * inv_h2 + shift).exp()
}

/// n(x) = Σ v θ / |Σ v θ| (Eq. 2).
pub fn normal_field<D: DualNum<Primitive = f64> + Copy>(
    x: &SVector<D, 3>,
    samples: &[Sample],
    inv_h2: f64,
    shift: f64,
) -> SVector<D, 3> {
    let m = samples.iter().fold(SVector::<D, 3>::zeros(), |m, s| {
        m + s.normal.map(D::from) * theta(x, &s.point.coords, inv_h2, shift)
    });
    let len = m.dot(&m).sqrt();
    m.map(|c| c / len)
}

/// The energy e(y, n) = Σ ((y − q)ᵀ n)² θ(y, q) (Eq. 4) for a fixed direction n.
pub fn energy<D: DualNum<Primitive = f64> + Copy>(
    y: &SVector<D, 3>,
    n: &Vector3<f64>,
    samples: &[Sample],
    inv_h2: f64,
    shift: f64,
) -> D {
    samples.iter().fold(D::zero(), |acc, s| {
        let b = (y - s.point.coords.map(D::from)).dot(&n.map(D::from));
        acc + b * b * theta(y, &s.point.coords, inv_h2, shift)
    })
}

/// g(x) = Σ 2θ (B − B³/h²), B = (x − q)ᵀ n(x) (Eq. 7).
pub fn implicit<D: DualNum<Primitive = f64> + Copy>(
    x: &SVector<D, 3>,
    samples: &[Sample],
    inv_h2: f64,
    shift: f64,
) -> D {
    let n = normal_field(x, samples, inv_h2, shift);
    samples.iter().fold(D::zero(), |acc, s| {
        let b = (x - s.point.coords.map(D::from)).dot(&n);
        acc + theta(x, &s.point.coords, inv_h2, shift) * (b - b * b * b * inv_h2) * 2.0
    })
}

/// g by its definition Eq. 5: `n(x)ᵀ ∂e(y, n(x))/∂y` at `y = x`, the y-derivative by dual
/// numbers. Agrees with [`implicit`] (Eq. 7) when the paper's reduction is right.
pub fn implicit_from_energy(x: &Vector3<f64>, samples: &[Sample], inv_h2: f64, shift: f64) -> f64 {
    let n = normal_field(x, samples, inv_h2, shift);
    let (_, de_dy) = gradient(|y| energy(&y, &n, samples, inv_h2, shift), x);
    n.dot(&de_dy)
}

/// The shift `a·δ²` that mls-core applies, recomputed here from its definition.
pub fn log_scale(x: &Vector3<f64>, samples: &[Sample], inv_h2: f64) -> f64 {
    samples
        .iter()
        .map(|s| (x - s.point.coords).norm_squared())
        .fold(f64::INFINITY, f64::min)
        * inv_h2
}

/// g, ∇g, H(g), n, J and ∂²n at `x`, all by automatic differentiation.
pub fn witness(x: &Vector3<f64>, samples: &[Sample], inv_h2: f64) -> Witness {
    let shift = log_scale(x, samples, inv_h2);
    let (value, grad_g, hess_g) = hessian(|v| implicit(&v, samples, inv_h2, shift), x);
    let mut normal = Vector3::zeros();
    let mut jacobian = Matrix3::zeros();
    let mut second = [Matrix3::zeros(); 3];
    for c in 0..3 {
        let (nc, grad, hess) = hessian(|v| normal_field(&v, samples, inv_h2, shift)[c], x);
        normal[c] = nc;
        jacobian.set_row(c, &grad.transpose());
        second[c] = hess;
    }
    Witness {
        value,
        gradient: grad_g,
        hessian: hess_g,
        normal,
        jacobian,
        second,
        log_scale: shift,
    }
}

/// Curvature from (∇g, H) by eigen-decomposition of the 3 × 3 shape operator `P H P / |∇g|`.
/// Its eigenvalue along ∇g is 0; the other two are the principal curvatures.
pub fn witness_curvature(gradient: &Vector3<f64>, hessian: &Matrix3<f64>) -> WitnessCurvature {
    let len = gradient.norm();
    let n = gradient / len;
    let p = Matrix3::identity() - n * n.transpose();
    let shape = p * hessian * p / len;
    let sym = (shape + shape.transpose()) * 0.5;
    let eig = SymmetricEigen::new(sym);
    // Drop the eigenvector closest to the normal; order the other two.
    let normal_index = (0..3)
        .max_by(|&i, &j| {
            let ai = eig.eigenvectors.column(i).dot(&n).abs();
            let aj = eig.eigenvectors.column(j).dot(&n).abs();
            ai.total_cmp(&aj)
        })
        .unwrap_or(0);
    let mut tangent: Vec<usize> = (0..3).filter(|&i| i != normal_index).collect();
    tangent.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    let (i1, i2) = (tangent[0], tangent[1]);
    let (k1, k2) = (eig.eigenvalues[i1], eig.eigenvalues[i2]);
    WitnessCurvature {
        k1,
        k2,
        mean: 0.5 * (k1 + k2),
        gauss: k1 * k2,
        d1: eig.eigenvectors.column(i1).into_owned(),
        d2: eig.eigenvectors.column(i2).into_owned(),
    }
}
