//! The ring torus.

use std::f64::consts::TAU;

use crate::math::{Point, Scalar, Vector};
use crate::parametric::{ParamInterval, ParametricSurface};
use crate::surface_point::SurfacePoint;

/// A ring torus about the z axis, centred on the origin, with outward normals (away from the
/// tube's core circle). Requires `0 < minor < major`.
///
/// Parameters, both periodic on `[0, 2π)`: `u = θ`, the angle around the z axis from `+x`,
/// and `v = φ`, the angle around the tube, `φ = 0` on the outer equator and `φ = π/2` on top,
///
/// $$ r(\theta, \varphi) = \big((R + r\cos\varphi)\cos\theta,\ (R + r\cos\varphi)\sin\theta,\
///    r\sin\varphi\big), $$
///
/// for which `r_θ × r_φ = r (R + r cos φ) · (outward unit normal)`.
///
/// Principal curvatures: `k1 = 1/r` around the tube, and
/// `k2 = cos φ / (R + r cos φ)` along the parallels, positive on the outer half (elliptic
/// points), negative on the inner half (hyperbolic), zero on the top and bottom circles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Torus {
    /// Distance `R` from the z axis to the tube's core circle.
    pub major: f64,
    /// Tube radius `r`.
    pub minor: f64,
}

impl Torus {
    /// A torus with the given major and minor radii.
    #[must_use]
    pub const fn new(major: f64, minor: f64) -> Self {
        Self { major, minor }
    }

    /// The parameters `(θ, φ)` of the point nearest to `p`: project onto the core circle,
    /// then radially onto the tube. Undefined (returns some angle) on the z axis and on the
    /// core circle, where the nearest point is not unique.
    #[must_use]
    pub fn closest_parameters(&self, p: &Point) -> [f64; 2] {
        let theta = p.y.atan2(p.x).rem_euclid(TAU);
        let phi = p.z.atan2(p.x.hypot(p.y) - self.major).rem_euclid(TAU);
        [theta, phi]
    }

    /// What a scanner looking straight down sees: the points where vertical rays on the lines
    /// `y = −(R + r) + j · between` (spaced `along` in x along each line) hit the upper half
    /// `z > 0` of the torus. The half is open: where the rays graze the equators, the sampling
    /// thins out and stops, a scan boundary.
    #[must_use]
    pub fn top_down_scan(&self, along: f64, between: f64) -> Vec<SurfacePoint> {
        let extent = self.major + self.minor;
        let steps = |d: f64| (2.0 * extent / d).floor() as usize + 1;
        let mut out = Vec::new();
        for j in 0..steps(between) {
            let y = -extent + j as f64 * between;
            for i in 0..steps(along) {
                let x = -extent + i as f64 * along;
                let d = x.hypot(y) - self.major;
                if d.abs() < self.minor {
                    let z = ((self.minor - d) * (self.minor + d)).sqrt();
                    out.push(self.at(y.atan2(x).rem_euclid(TAU), z.atan2(d)));
                }
            }
        }
        out
    }

    /// The point nearest to `p`, with its geometry.
    #[must_use]
    pub fn closest_point(&self, p: &Point) -> SurfacePoint {
        let [theta, phi] = self.closest_parameters(p);
        self.at(theta, phi)
    }
}

impl ParametricSurface for Torus {
    fn domain(&self) -> [ParamInterval; 2] {
        [
            ParamInterval::periodic(0.0, TAU),
            ParamInterval::periodic(0.0, TAU),
        ]
    }

    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        let (st, ct) = u.sin_cos();
        let (sp, cp) = v.sin_cos();
        let rho = cp * self.minor + self.major;
        [rho * ct, rho * st, sp * self.minor]
    }

    /// Closed form: `N = (cos φ cos θ, cos φ sin θ, sin φ)`; `dN/dφ = r_φ / r` and
    /// `dN/dθ = cos φ / (R + r cos φ) · r_θ`, so `k1 = 1/r` along
    /// `d1 = e_φ = (−sin φ cos θ, −sin φ sin θ, cos φ)` and `k2 = cos φ / (R + r cos φ)` along
    /// `d2 = −e_θ = (sin θ, −cos θ, 0)` (the sign makes `d1 × d2 = N`).
    fn at(&self, u: f64, v: f64) -> SurfacePoint {
        let (st, ct) = u.sin_cos();
        let (sp, cp) = v.sin_cos();
        let rho = self.major + self.minor * cp;
        SurfacePoint {
            point: Point::new(rho * ct, rho * st, self.minor * sp),
            normal: Vector::new(cp * ct, cp * st, sp),
            k1: 1.0 / self.minor,
            k2: cp / rho,
            d1: Vector::new(-sp * ct, -sp * st, cp),
            d2: Vector::new(st, -ct, 0.0),
        }
    }
}
