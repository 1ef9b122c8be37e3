//! The hyperbolic paraboloid.

use crate::math::Scalar;
use crate::parametric::{ParamInterval, ParametricSurface};

/// The saddle (hyperbolic paraboloid) height field `z = (x² − y²) / (2a)` over the square
/// `[−half_width, half_width]²`, with the normal on the `+z` side. Its geometry comes from
/// automatic differentiation.
///
/// Parameters: `u = x`, `v = y`, both closed. At the origin the normal is `+z`; the surface
/// bends towards the normal along x (`k = −1/a`, direction `±x`) and away from it along y
/// (`k = +1/a`, direction `±y`), so `k1 = 1/a`, `k2 = −1/a`, mean 0, Gaussian `−1/a²`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Saddle {
    /// Scale `a > 0`: the principal curvatures at the origin are `±1/a`.
    pub a: f64,
    /// Half the side of the square parameter domain.
    pub half_width: f64,
}

impl Saddle {
    /// A saddle with scale `a` over `[−half_width, half_width]²`.
    #[must_use]
    pub const fn new(a: f64, half_width: f64) -> Self {
        Self { a, half_width }
    }

    /// The height `z(x, y)`.
    #[must_use]
    pub fn height<D: Scalar>(&self, x: D, y: D) -> D {
        (x * x - y * y) * (0.5 / self.a)
    }
}

impl ParametricSurface for Saddle {
    fn domain(&self) -> [ParamInterval; 2] {
        let w = self.half_width;
        [ParamInterval::closed(-w, w), ParamInterval::closed(-w, w)]
    }

    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        [u, v, self.height(u, v)]
    }
}
