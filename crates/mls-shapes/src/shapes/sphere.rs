//! The round sphere.

use std::f64::consts::{PI, TAU};

use crate::math::{Point, Scalar, Vector};
use crate::parametric::{ParamInterval, ParametricSurface};
use crate::surface_point::SurfacePoint;

/// A sphere with outward normals, so `k1 = k2 = 1/radius` everywhere.
///
/// Parameters: `u = θ ∈ [0, π]`, the polar angle from `+z` (degenerate ends: the poles), and
/// `v = φ ∈ [0, 2π)`, the azimuth from `+x` (periodic),
///
/// $$ r(\theta, \varphi) = c + R\,(\sin\theta\cos\varphi,\ \sin\theta\sin\varphi,\ \cos\theta), $$
///
/// for which `r_θ × r_φ = R² sin θ · (outward unit normal)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Point,
    /// Radius, positive.
    pub radius: f64,
}

impl Sphere {
    /// A sphere of the given centre and radius.
    #[must_use]
    pub const fn new(center: Point, radius: f64) -> Self {
        Self { center, radius }
    }

    /// A sphere of the given radius centred at the origin.
    #[must_use]
    pub fn centered(radius: f64) -> Self {
        Self::new(Point::origin(), radius)
    }

    /// The parameters `(θ, φ)` of the point nearest to `p` (radial projection).
    ///
    /// At the centre, where every point is nearest, it returns the north pole.
    #[must_use]
    pub fn closest_parameters(&self, p: &Point) -> [f64; 2] {
        let d = p - self.center;
        let theta = d.xy().norm().atan2(d.z);
        let phi = d.y.atan2(d.x).rem_euclid(TAU);
        [theta, phi]
    }

    /// The point nearest to `p`, with its geometry.
    #[must_use]
    pub fn closest_point(&self, p: &Point) -> SurfacePoint {
        let [theta, phi] = self.closest_parameters(p);
        self.at(theta, phi)
    }
}

impl ParametricSurface for Sphere {
    fn domain(&self) -> [ParamInterval; 2] {
        [
            ParamInterval::degenerate_ends(0.0, PI),
            ParamInterval::periodic(0.0, TAU),
        ]
    }

    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        let (st, ct) = u.sin_cos();
        let (sp, cp) = v.sin_cos();
        let c = self.center;
        [
            st * cp * self.radius + c.x,
            st * sp * self.radius + c.y,
            ct * self.radius + c.z,
        ]
    }

    /// Closed form: `N = e_r`, `k1 = k2 = 1/R`, `d1 = e_θ`, `d2 = e_φ` (so `d1 × d2 = e_r`).
    /// Unlike the automatic-differentiation path, this is also valid at the poles.
    fn at(&self, u: f64, v: f64) -> SurfacePoint {
        let (st, ct) = u.sin_cos();
        let (sp, cp) = v.sin_cos();
        let normal = Vector::new(st * cp, st * sp, ct);
        let k = 1.0 / self.radius;
        SurfacePoint {
            point: self.center + normal * self.radius,
            normal,
            k1: k,
            k2: k,
            d1: Vector::new(ct * cp, ct * sp, -st),
            d2: Vector::new(-sp, cp, 0.0),
        }
    }
}
