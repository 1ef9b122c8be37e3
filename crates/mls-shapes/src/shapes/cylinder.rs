//! The open circular cylinder.

use std::f64::consts::TAU;

use crate::math::{Point, Scalar, Vector};
use crate::parametric::{ParamInterval, ParametricSurface};
use crate::surface_point::SurfacePoint;

/// An open circular cylinder (no caps) about the z axis, centred on the origin, with
/// `z ∈ [−height/2, height/2]` and outward normals: `k1 = 1/radius` around the axis, `k2 = 0`
/// along it.
///
/// Parameters: `u = φ ∈ [0, 2π)`, the azimuth from `+x` (periodic), and
/// `v = z ∈ [−height/2, height/2]` (closed),
///
/// $$ r(\varphi, z) = (R\cos\varphi,\ R\sin\varphi,\ z), $$
///
/// for which `r_φ × r_z = R · (outward unit normal)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Radius, positive.
    pub radius: f64,
    /// Length along the axis, positive.
    pub height: f64,
}

impl Cylinder {
    /// A cylinder of the given radius and height.
    #[must_use]
    pub const fn new(radius: f64, height: f64) -> Self {
        Self { radius, height }
    }

    /// The parameters `(φ, z)` of the point nearest to `p`: radial projection with `z`
    /// clamped to the cylinder's extent. On the axis, where a whole circle is nearest, it
    /// takes `φ = 0`.
    #[must_use]
    pub fn closest_parameters(&self, p: &Point) -> [f64; 2] {
        let half = 0.5 * self.height;
        [p.y.atan2(p.x).rem_euclid(TAU), p.z.clamp(-half, half)]
    }

    /// The point nearest to `p`, with its geometry.
    #[must_use]
    pub fn closest_point(&self, p: &Point) -> SurfacePoint {
        let [phi, z] = self.closest_parameters(p);
        self.at(phi, z)
    }
}

impl ParametricSurface for Cylinder {
    fn domain(&self) -> [ParamInterval; 2] {
        let half = 0.5 * self.height;
        [
            ParamInterval::periodic(0.0, TAU),
            ParamInterval::closed(-half, half),
        ]
    }

    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        let (s, c) = u.sin_cos();
        [c * self.radius, s * self.radius, v]
    }

    /// Closed form: `N = (cos φ, sin φ, 0)`, `k1 = 1/R` along `d1 = e_φ = (−sin φ, cos φ, 0)`,
    /// `k2 = 0` along `d2 = +z`.
    fn at(&self, u: f64, v: f64) -> SurfacePoint {
        let (s, c) = u.sin_cos();
        SurfacePoint {
            point: Point::new(c * self.radius, s * self.radius, v),
            normal: Vector::new(c, s, 0.0),
            k1: 1.0 / self.radius,
            k2: 0.0,
            d1: Vector::new(-s, c, 0.0),
            d2: Vector::z(),
        }
    }
}
