//! One surface sample with its exact differential geometry.

use crate::math::{Matrix3, Point, Vector};

/// One sample with its exact differential geometry.
///
/// # Conventions
///
/// * `normal` is unit and outward: away from the enclosed volume for closed shapes, towards
///   +z for the open height-field-like surfaces (each shape documents its side).
/// * The principal curvatures are the eigenvalues of the Weingarten map `W = dN` (the
///   derivative of the unit normal along the surface, *not* `−dN`), so curvature is positive
///   where the surface bends away from the normal: a sphere of radius `R` with outward normals
///   has `k1 = k2 = 1/R`, an upward-opening bowl with normal `+z` has negative curvature.
/// * `k1 >= k2`.
/// * `d1`, `d2` are unit tangent principal directions for `k1` and `k2`, and
///   `(d1, d2, normal)` is right-handed: `d1 × d2 = normal`. At an umbilic (`k1 == k2`) they
///   are some orthonormal tangent pair. Their overall sign is arbitrary: compare them up to
///   sign.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Position on the surface.
    pub point: Point,
    /// Unit outward normal.
    pub normal: Vector,
    /// Larger principal curvature.
    pub k1: f64,
    /// Smaller principal curvature.
    pub k2: f64,
    /// Unit principal direction of `k1`.
    pub d1: Vector,
    /// Unit principal direction of `k2`.
    pub d2: Vector,
}

impl SurfacePoint {
    /// Mean curvature `(k1 + k2) / 2` (positive on a sphere with outward normals).
    #[must_use]
    pub fn mean(&self) -> f64 {
        0.5 * (self.k1 + self.k2)
    }

    /// Gaussian curvature `k1 k2`.
    #[must_use]
    pub fn gauss(&self) -> f64 {
        self.k1 * self.k2
    }

    /// The Weingarten map `dN` as a 3 × 3 tensor acting on ambient vectors,
    ///
    /// $$ W = k_1\, d_1 d_1^\top + k_2\, d_2 d_2^\top , $$
    ///
    /// which is zero along the normal. Unlike `(k1, d1, k2, d2)` it is unique at umbilics and
    /// independent of the sign of the directions, so it is the thing to compare against.
    #[must_use]
    pub fn shape_tensor(&self) -> Matrix3 {
        self.d1 * self.d1.transpose() * self.k1 + self.d2 * self.d2.transpose() * self.k2
    }
}
