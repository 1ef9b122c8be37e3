//! The triaxial ellipsoid.

use std::f64::consts::{PI, TAU};

use crate::math::{Point, Scalar};
use crate::parametric::{ParamInterval, ParametricSurface};

/// An axis-aligned ellipsoid `x²/a² + y²/b² + z²/c² = 1` centred on the origin, with outward
/// normals. Its geometry comes from automatic differentiation (no closed-form override).
///
/// Parameters as for the sphere: `u = θ ∈ [0, π]` from `+z` (degenerate ends: the points
/// `(0, 0, ±c)`), `v = φ ∈ [0, 2π)` from `+x` (periodic),
///
/// $$ r(\theta, \varphi) = (a\sin\theta\cos\varphi,\ b\sin\theta\sin\varphi,\ c\cos\theta). $$
///
/// At the end `(a, 0, 0)` of the a-axis the principal curvatures are `a/b²` (towards y) and
/// `a/c²` (towards z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipsoid {
    /// Semi-axis along x.
    pub a: f64,
    /// Semi-axis along y.
    pub b: f64,
    /// Semi-axis along z.
    pub c: f64,
}

impl Ellipsoid {
    /// An ellipsoid with semi-axes `a`, `b`, `c` along x, y, z.
    #[must_use]
    pub const fn new(a: f64, b: f64, c: f64) -> Self {
        Self { a, b, c }
    }

    /// `h(p) = sqrt(x²/a⁴ + y²/b⁴ + z²/c⁴)`, half the norm of the gradient of the implicit
    /// function, which the closed forms below share.
    fn h(&self, p: &Point) -> f64 {
        (p.x * p.x / self.a.powi(4) + p.y * p.y / self.b.powi(4) + p.z * p.z / self.c.powi(4))
            .sqrt()
    }

    /// Closed-form Gaussian curvature at a point `p` on the surface,
    ///
    /// $$ K = \frac{1}{a^2 b^2 c^2\, h^4}, \qquad h^2 = \frac{x^2}{a^4} + \frac{y^2}{b^4} + \frac{z^2}{c^4}, $$
    ///
    /// an independent check on the automatic-differentiation path.
    #[must_use]
    pub fn gauss_at(&self, p: &Point) -> f64 {
        let abc = self.a * self.b * self.c;
        1.0 / (abc * abc * self.h(p).powi(4))
    }

    /// Closed-form mean curvature at a point `p` on the surface, in this crate's sign
    /// convention (positive, as the ellipsoid is convex with outward normals),
    ///
    /// $$ H = \frac{a^2 + b^2 + c^2 - |p|^2}{2\, a^2 b^2 c^2\, h^3}. $$
    #[must_use]
    pub fn mean_at(&self, p: &Point) -> f64 {
        let abc = self.a * self.b * self.c;
        let s = self.a * self.a + self.b * self.b + self.c * self.c;
        (s - p.coords.norm_squared()) / (2.0 * abc * abc * self.h(p).powi(3))
    }
}

impl ParametricSurface for Ellipsoid {
    fn domain(&self) -> [ParamInterval; 2] {
        [
            ParamInterval::degenerate_ends(0.0, PI),
            ParamInterval::periodic(0.0, TAU),
        ]
    }

    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        let (st, ct) = u.sin_cos();
        let (sp, cp) = v.sin_cos();
        [st * cp * self.a, st * sp * self.b, ct * self.c]
    }
}
