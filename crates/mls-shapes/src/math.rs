//! Type aliases and small vector helpers shared by every module, so that the shapes, the
//! samplers and the tests read the same.

use num_dual::DualNum;

/// A point in 3D space.
pub type Point = nalgebra::Point3<f64>;

/// A vector in 3D space (normals, principal directions, offsets).
pub type Vector = nalgebra::Vector3<f64>;

/// A 3 × 3 matrix (shape tensors, Jacobians).
pub type Matrix3 = nalgebra::Matrix3<f64>;

/// The number types a surface parametrisation is written over: `f64` itself and num-dual's
/// dual numbers, which carry exact derivatives through the same code.
///
/// num-dual 0.15 spells the bound `DualNum<Primitive = f64> + Copy`; this alias keeps the
/// signatures short. Remember that scalar operations only work with the dual number on the
/// left (`d * 2.0`, not `2.0 * d`) and that `f64` data is lifted with `D::from(v)`.
pub trait Scalar: DualNum<Primitive = f64> + Copy {}

impl<D: DualNum<Primitive = f64> + Copy> Scalar for D {}

/// A right-handed orthonormal tangent basis `(t1, t2)` for the unit vector `n`, so that
/// `t1 × t2 = n`.
///
/// Uses the branch-free construction of Duff et al., "Building an orthonormal basis,
/// revisited" (JCGT 2017), which stays accurate for every direction, unlike the classic
/// "cross with the least aligned axis" which has a discontinuity and loses digits near it.
///
/// The caller must pass a unit vector; the result is undefined otherwise.
#[must_use]
pub fn tangent_basis(n: &Vector) -> (Vector, Vector) {
    let sign = 1.0_f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t1 = Vector::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let t2 = Vector::new(b, sign + n.y * n.y * a, -n.y);
    (t1, t2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_basis_is_right_handed_and_orthonormal() {
        let dirs = [
            Vector::new(0.0, 0.0, 1.0),
            Vector::new(0.0, 0.0, -1.0),
            Vector::new(1.0, 0.0, 0.0),
            Vector::new(0.3, -0.4, 0.2).normalize(),
            Vector::new(-0.1, 0.7, -0.9).normalize(),
            Vector::new(1e-9, -1e-9, -1.0).normalize(),
        ];
        for n in dirs {
            let (t1, t2) = tangent_basis(&n);
            assert!((t1.norm() - 1.0).abs() < 1e-14, "{n:?}");
            assert!((t2.norm() - 1.0).abs() < 1e-14, "{n:?}");
            assert!(t1.dot(&t2).abs() < 1e-14, "{n:?}");
            assert!(t1.dot(&n).abs() < 1e-14, "{n:?}");
            assert!((t1.cross(&t2) - n).norm() < 1e-14, "{n:?}");
        }
    }
}
