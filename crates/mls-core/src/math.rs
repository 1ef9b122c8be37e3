//! Type aliases and small geometric helpers shared by every algorithm in the crate.

/// A position in space.
pub type Point = nalgebra::Point3<f64>;
/// A free vector (difference of points, normal, gradient).
pub type Vector = nalgebra::Vector3<f64>;
/// A 3 × 3 matrix (Jacobian, Hessian, covariance).
pub type Matrix = nalgebra::Matrix3<f64>;

/// A vector of unit length, checked at construction.
///
/// Normals are a precondition of the MLS normal field (Eq. 2), so the type carries it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnitNormal(Vector);

/// Why a vector could not be made a [`UnitNormal`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NormalError {
    /// The vector has a NaN or infinite component.
    #[error("normal has a non-finite component")]
    NonFinite,
    /// The vector is zero, or its largest component is subnormal (below 2.2e-308) so that its
    /// direction has lost precision.
    #[error("normal has zero length")]
    Zero,
}

impl UnitNormal {
    /// Normalises `v`, rejecting zero, NaN and infinite input.
    pub fn new(v: Vector) -> Result<Self, NormalError> {
        if !v.iter().all(|c| c.is_finite()) {
            return Err(NormalError::NonFinite);
        }
        // Scale by the largest component first: |v| itself overflows or underflows for
        // lengths beyond about 1e±154, which are still valid directions. Subnormal components
        // have lost precision: treated as zero.
        let largest = v.amax();
        if !(largest >= f64::MIN_POSITIVE) {
            return Err(NormalError::Zero);
        }
        let scaled = v / largest;
        Ok(Self(scaled / scaled.norm()))
    }

    /// Wraps a vector the caller knows to be unit length.
    pub fn new_unchecked(v: Vector) -> Self {
        debug_assert!((v.norm() - 1.0).abs() < 1e-9, "not a unit vector: {v:?}");
        Self(v)
    }

    /// The unit vector.
    pub fn into_inner(self) -> Vector {
        self.0
    }

    /// The unit vector by reference.
    pub fn as_vector(&self) -> &Vector {
        &self.0
    }
}

impl std::ops::Neg for UnitNormal {
    type Output = Self;
    fn neg(self) -> Self {
        Self(-self.0)
    }
}

/// An orthonormal tangent basis `(t1, t2)` with `t1 × t2 = n` for a unit `n`.
///
/// Branchless construction of Duff et al., "Building an Orthonormal Basis, Revisited" (JCGT 2017);
/// unlike cross products with a fixed axis it has no direction where it loses precision.
pub fn tangent_basis(n: &Vector) -> (Vector, Vector) {
    let sign = 1.0_f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t1 = Vector::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let t2 = Vector::new(b, sign + n.y * n.y * a, -n.y);
    (t1, t2)
}

/// The centre of the bounding box (zero for no points). Coordinates are taken relative to it
/// before any geometry, so that clouds far from the origin (georeferenced scans) keep their
/// precision in `x − q`.
pub fn bounding_box_centre(points: &[Point]) -> Vector {
    let Some(first) = points.first() else {
        return Vector::zeros();
    };
    let (lo, hi) = points
        .iter()
        .fold((first.coords, first.coords), |(lo, hi), p| {
            (lo.inf(&p.coords), hi.sup(&p.coords))
        });
    (lo + hi) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tangent_basis_is_orthonormal_and_right_handed() {
        for n in [
            Vector::z(),
            -Vector::z(),
            Vector::x(),
            Vector::new(1.0, -2.0, 0.5).normalize(),
            Vector::new(1e-9, 0.0, -1.0).normalize(),
        ] {
            let (t1, t2) = tangent_basis(&n);
            assert!((t1.norm() - 1.0).abs() < 1e-14 && (t2.norm() - 1.0).abs() < 1e-14);
            assert!(t1.dot(&t2).abs() < 1e-14 && t1.dot(&n).abs() < 1e-14);
            assert!((t1.cross(&t2) - n).norm() < 1e-14, "n = {n:?}");
        }
    }

    #[test]
    fn bounding_box_centre_is_the_middle_of_the_extremes() {
        let points = [
            Point::new(500_000.0, -2.0, 7.0),
            Point::new(500_004.0, 6.0, 1.0),
            Point::new(500_001.0, 0.0, 3.0),
        ];
        assert_eq!(
            bounding_box_centre(&points),
            Vector::new(500_002.0, 2.0, 4.0)
        );
        assert_eq!(bounding_box_centre(&[]), Vector::zeros());
    }

    #[test]
    fn unit_normal_rejects_bad_input() {
        assert_eq!(UnitNormal::new(Vector::zeros()), Err(NormalError::Zero));
        assert_eq!(
            UnitNormal::new(Vector::new(f64::NAN, 0.0, 1.0)),
            Err(NormalError::NonFinite)
        );
        assert_eq!(
            UnitNormal::new(Vector::new(f64::INFINITY, 0.0, 1.0)),
            Err(NormalError::NonFinite)
        );
        let n = UnitNormal::new(Vector::new(0.0, 3.0, 4.0)).unwrap();
        assert!((n.as_vector() - Vector::new(0.0, 0.6, 0.8)).norm() < 1e-15);
    }
}
