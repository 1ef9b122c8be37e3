//! Curvature of an implicit surface from the gradient and Hessian of its defining function.
//!
//! Convention: the surface normal is `N = ∇g/|∇g|`, which on the MLS surface points the same
//! way as the oriented input normals. Curvature is positive where the surface bends away from
//! `N`: a sphere with outward normals has `k1 = k2 = mean = gauss = 1/R`. The shape operator is
//! `dN = P H P / |∇g|` with `P = I − N Nᵀ`; its two tangent eigenvalues are `k1 ≥ k2`.
//! `mean = (k1 + k2)/2`. Flipping every normal flips g, hence `k1`, `k2` and `mean`, not `gauss`.

use crate::math::{Matrix, Vector, tangent_basis};

/// Principal curvatures and directions, mean and Gaussian curvature at a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvature {
    /// Unit surface normal `∇g/|∇g|`.
    pub normal: Vector,
    /// Larger principal curvature.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// `(k1 + k2) / 2`.
    pub mean: f64,
    /// Gaussian curvature from the bordered determinant (Eq. 6, first line).
    pub gauss: f64,
    /// Unit principal direction of `k1`, tangent.
    pub d1: Vector,
    /// Unit principal direction of `k2`, tangent; `d1 × d2 = normal`.
    pub d2: Vector,
}

/// Curvature of the level set of g through the point where `∇g = gradient`, `H(g) = hessian`.
///
/// Returns `None` when the gradient is zero or anything is not finite. `k1`, `k2` come from the
/// 2 × 2 shape operator `[t_iᵀ H t_j]/|∇g|` in a tangent basis, diagonalised in closed form
/// (`mean ± hypot`), which stays exact at umbilics where `H ± √(H² − K)` loses half the digits.
/// The Gaussian curvature is Eq. 6's bordered determinant, `∇gᵀ adj(H) ∇g / |∇g|⁴`.
pub fn curvature(gradient: &Vector, hessian: &Matrix) -> Option<Curvature> {
    let len = gradient.norm();
    if !(len > 0.0 && len.is_finite() && hessian.iter().all(|v| v.is_finite())) {
        return None;
    }
    let normal = gradient / len;
    let (t1, t2) = tangent_basis(&normal);
    let a = t1.dot(&(hessian * t1)) / len;
    let b = 0.5 * (t1.dot(&(hessian * t2)) + t2.dot(&(hessian * t1))) / len;
    let c = t2.dot(&(hessian * t2)) / len;
    let mean = 0.5 * (a + c);
    let half_gap = (0.5 * (a - c)).hypot(b);
    let angle = 0.5 * b.atan2(0.5 * (a - c));
    let (sin, cos) = angle.sin_cos();
    let d1 = t1 * cos + t2 * sin;
    let d2 = t2 * cos - t1 * sin;
    let gauss = gradient.dot(&(adjugate(hessian) * gradient)) / (len * len * len * len);
    let result = Curvature {
        normal,
        k1: mean + half_gap,
        k2: mean - half_gap,
        mean,
        gauss,
        d1,
        d2,
    };
    [result.k1, result.k2, result.gauss]
        .iter()
        .all(|v| v.is_finite())
        .then_some(result)
}

/// The adjugate (transposed cofactor matrix), so that `det([[H, g], [gᵀ, 0]]) = −gᵀ adj(H) g`.
fn adjugate(m: &Matrix) -> Matrix {
    let c = |r0: usize, r1: usize, c0: usize, c1: usize| {
        m[(r0, c0)] * m[(r1, c1)] - m[(r0, c1)] * m[(r1, c0)]
    };
    Matrix::new(
        c(1, 2, 1, 2),
        -c(0, 2, 1, 2),
        c(0, 1, 1, 2),
        -c(1, 2, 0, 2),
        c(0, 2, 0, 2),
        -c(0, 1, 0, 2),
        c(1, 2, 0, 1),
        -c(0, 2, 0, 1),
        c(0, 1, 0, 1),
    )
}

/// Eq. 6's second line exactly as printed:
/// `−(∇g H ∇gᵀ/|∇g|³ − |∇g|² tr(H)/|∇g|³)`. It equals `k1 + k2` in our convention, twice the
/// mean curvature (erratum E1 in `docs/derivation.md`). Kept for the test that establishes it.
pub fn paper_eq6_mean(gradient: &Vector, hessian: &Matrix) -> f64 {
    let len = gradient.norm();
    let ghg = gradient.dot(&(hessian * gradient));
    -(ghg / len.powi(3) - len * len * hessian.trace() / len.powi(3))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// g = |x|²/R − R has the sphere of radius R as zero set, ∇g = 2x/R, H = 2I/R.
    #[test]
    fn exact_sphere() {
        let r = 2.5;
        let x = Vector::new(1.0, -2.0, 0.5).normalize() * r;
        let c = curvature(&(x * (2.0 / r)), &(Matrix::identity() * (2.0 / r))).unwrap();
        for k in [c.k1, c.k2, c.mean] {
            assert_relative_eq!(k, 1.0 / r, max_relative = 1e-15);
        }
        assert_relative_eq!(c.gauss, 1.0 / (r * r), max_relative = 1e-15);
        assert_relative_eq!(
            paper_eq6_mean(&(x * 2.0), &(Matrix::identity() * 2.0)),
            2.0 / r,
            max_relative = 1e-15
        );
    }

    /// Cylinder x² + y² = R² along z: k1 = 1/R around, k2 = 0 along the axis.
    #[test]
    fn exact_cylinder_and_directions() {
        let r = 0.5;
        let p = Vector::new(r, 0.0, 0.3);
        let grad = Vector::new(2.0 * p.x, 2.0 * p.y, 0.0);
        let hess = Matrix::from_diagonal(&Vector::new(2.0, 2.0, 0.0));
        let c = curvature(&grad, &hess).unwrap();
        assert_relative_eq!(c.k1, 1.0 / r, max_relative = 1e-15);
        assert!(c.k2.abs() < 1e-15 && c.gauss.abs() < 1e-15);
        assert!(
            c.d2.cross(&Vector::z()).norm() < 1e-15,
            "d2 along the axis: {:?}",
            c.d2
        );
        assert!((c.d1.cross(&c.d2) - c.normal).norm() < 1e-15);
    }

    /// Flipping the function flips k1, k2 and mean (swapping them), not gauss.
    #[test]
    fn flip_and_saddle() {
        // z = (x² − y²)/2 at the origin as F = z − (x² − y²)/2: ∇F = e_z, H = diag(−1, 1, 0).
        let grad = Vector::z();
        let hess = Matrix::from_diagonal(&Vector::new(-1.0, 1.0, 0.0));
        let c = curvature(&grad, &hess).unwrap();
        let f = curvature(&-grad, &-hess).unwrap();
        assert_relative_eq!(c.k1, 1.0, max_relative = 1e-15);
        assert_relative_eq!(c.k2, -1.0, max_relative = 1e-15);
        assert_relative_eq!(c.gauss, -1.0, max_relative = 1e-15);
        assert_relative_eq!(f.k1, -c.k2, max_relative = 1e-15);
        assert_relative_eq!(f.k2, -c.k1, max_relative = 1e-15);
        assert_relative_eq!(f.gauss, c.gauss, max_relative = 1e-15);
        assert!(curvature(&Vector::zeros(), &hess).is_none());
    }
}
