//! Parametric surfaces and their exact differential geometry by automatic differentiation.
//!
//! A shape implements [`ParametricSurface::position`] once, generic over the number type.
//! [`derivatives`] runs it on num-dual's second-order dual numbers to get `r`, `r_u`, `r_v`,
//! `r_uu`, `r_uv`, `r_vv` exactly (to rounding), and [`SurfaceDerivatives::geometry`] turns those
//! into normal, principal curvatures and principal directions through the two fundamental
//! forms. Shapes with a closed form override [`ParametricSurface::at`]; the tests compare the
//! two paths.

use nalgebra::{Matrix2, SVector, Vector2};
use num_dual::{Dual2SVec64, hessian};

use crate::math::{Point, Scalar, Vector};
use crate::surface_point::SurfacePoint;

/// How a parameter interval behaves at its ends; decides how samplers space grid values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntervalKind {
    /// Both ends are ordinary surface points (a boundary curve): grids include both ends,
    /// `t_i = start + i (end − start) / (n − 1)`.
    Closed,
    /// The parameter is an angle: `start` and `end` are the same points, so grids exclude the
    /// end to avoid a duplicated seam, `t_i = start + i (end − start) / n`.
    Periodic,
    /// Each end collapses to a single point where the parametrisation is singular (the poles
    /// of a sphere): grids use cell midpoints, `t_i = start + (i + ½)(end − start) / n`, so no
    /// sample lands on a pole.
    DegenerateEnds,
}

/// The range of one surface parameter and how its ends behave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamInterval {
    /// Lower end.
    pub start: f64,
    /// Upper end.
    pub end: f64,
    /// What happens at the ends.
    pub kind: IntervalKind,
}

impl ParamInterval {
    /// An interval whose ends are boundary curves.
    #[must_use]
    pub const fn closed(start: f64, end: f64) -> Self {
        Self {
            start,
            end,
            kind: IntervalKind::Closed,
        }
    }

    /// An angle-like interval whose ends are identified.
    #[must_use]
    pub const fn periodic(start: f64, end: f64) -> Self {
        Self {
            start,
            end,
            kind: IntervalKind::Periodic,
        }
    }

    /// An interval whose ends are singular points of the parametrisation.
    #[must_use]
    pub const fn degenerate_ends(start: f64, end: f64) -> Self {
        Self {
            start,
            end,
            kind: IntervalKind::DegenerateEnds,
        }
    }

    /// `end − start`.
    #[must_use]
    pub fn len(&self) -> f64 {
        self.end - self.start
    }

    /// The parameter at fraction `t` of the interval, `start + t (end − start)`.
    #[must_use]
    pub fn lerp(&self, t: f64) -> f64 {
        self.start + t * self.len()
    }

    /// The `i`-th of `n` grid values, spaced according to [`IntervalKind`].
    ///
    /// A closed interval with `n == 1` gives its midpoint.
    #[must_use]
    pub fn grid_value(&self, i: usize, n: usize) -> f64 {
        let (i, n) = (i as f64, n as f64);
        let t = match self.kind {
            IntervalKind::Closed if n <= 1.0 => 0.5,
            IntervalKind::Closed => i / (n - 1.0),
            IntervalKind::Periodic => i / n,
            IntervalKind::DegenerateEnds => (i + 0.5) / n,
        };
        self.lerp(t)
    }

    /// The distance between two parameter values, measured around the circle for periodic
    /// intervals (so the two ends are at distance zero).
    #[must_use]
    pub fn distance(&self, a: f64, b: f64) -> f64 {
        let d = (b - a).abs();
        match self.kind {
            IntervalKind::Periodic => {
                let d = d.rem_euclid(self.len().abs());
                d.min(self.len().abs() - d)
            }
            IntervalKind::Closed | IntervalKind::DegenerateEnds => d,
        }
    }

    /// Brings `x` back into the interval: wraps periodic parameters, clamps the others.
    #[must_use]
    pub fn normalize(&self, x: f64) -> f64 {
        match self.kind {
            IntervalKind::Periodic => self.start + (x - self.start).rem_euclid(self.len()),
            IntervalKind::Closed | IntervalKind::DegenerateEnds => x.clamp(self.start, self.end),
        }
    }
}

/// Whether the outward normal is `r_u × r_v` or its opposite.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Orientation {
    /// The outward normal is `r_u × r_v / |r_u × r_v|`.
    #[default]
    Natural,
    /// The outward normal is `−r_u × r_v / |r_u × r_v|`.
    Reversed,
}

/// A parametric surface: position as a function of `(u, v)`, written once generic over the
/// number type so that num-dual can differentiate it.
pub trait ParametricSurface {
    /// The parameter ranges of `u` and `v`, in that order.
    fn domain(&self) -> [ParamInterval; 2];

    /// The point at parameters `(u, v)`.
    ///
    /// Written generic over [`Scalar`] so that the same code gives plain positions (`f64`)
    /// and exact derivatives (dual numbers). Must be smooth (at least C²) in the interior.
    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3];

    /// Which side of `r_u × r_v` is outward. All shapes in this crate are parametrised so that
    /// it is [`Orientation::Natural`]; the hook exists for parametrisations that are not.
    fn orientation(&self) -> Orientation {
        Orientation::Natural
    }

    /// The sample at `(u, v)` with its exact differential geometry.
    ///
    /// The default uses automatic differentiation ([`differential_geometry`]); shapes with a
    /// closed form override it, and the tests check the two agree.
    fn at(&self, u: f64, v: f64) -> SurfacePoint {
        differential_geometry(self, u, v)
    }
}

/// A surface point with its first and second partial derivatives with respect to `(u, v)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceDerivatives {
    /// `r(u, v)`.
    pub point: Point,
    /// `∂r/∂u`.
    pub du: Vector,
    /// `∂r/∂v`.
    pub dv: Vector,
    /// `∂²r/∂u²`.
    pub duu: Vector,
    /// `∂²r/∂u∂v`.
    pub duv: Vector,
    /// `∂²r/∂v²`.
    pub dvv: Vector,
}

impl SurfaceDerivatives {
    /// The first fundamental form `I = [[r_u·r_u, r_u·r_v], [r_v·r_u, r_v·r_v]]`.
    #[must_use]
    pub fn first_fundamental_form(&self) -> Matrix2<f64> {
        let f = self.du.dot(&self.dv);
        Matrix2::new(self.du.norm_squared(), f, f, self.dv.norm_squared())
    }

    /// The second fundamental form `II_ij = r_ij · N` for the unit normal `normal`.
    #[must_use]
    pub fn second_fundamental_form(&self, normal: &Vector) -> Matrix2<f64> {
        let m = self.duv.dot(normal);
        Matrix2::new(self.duu.dot(normal), m, m, self.dvv.dot(normal))
    }

    /// The area element `|r_u × r_v|`, so that `dA = |r_u × r_v| du dv`.
    #[must_use]
    pub fn area_element(&self) -> f64 {
        self.du.cross(&self.dv).norm()
    }

    /// Normal, principal curvatures and principal directions at this point.
    ///
    /// With `N = ± r_u × r_v / |r_u × r_v|` (sign from `orientation`), the Weingarten map
    /// `W = dN` has the matrix `−I⁻¹ II` in the parameter basis (because
    /// `N_i · r_j = −N · r_ij`). It is written in the orthonormal tangent basis
    /// `e1 = r_u / |r_u|`, `e2 = N × e1`, where it becomes symmetric: with `J = [r_u r_v]`
    /// and `A = [e1 e2]ᵀ J` (upper triangular),
    ///
    /// $$ M = -A^{-\top}\, \mathrm{II}\, A^{-1}, $$
    ///
    /// and its 2 × 2 symmetric eigen-decomposition gives `k1 >= k2` and the rotation angle of
    /// `d1` from `e1`. Since `e1 × e2 = N`, so is `d1 × d2`.
    ///
    /// The result is NaN where the parametrisation is singular (`r_u × r_v = 0`).
    #[must_use]
    pub fn geometry(&self, orientation: Orientation) -> SurfacePoint {
        let mut normal = self.du.cross(&self.dv).normalize();
        if orientation == Orientation::Reversed {
            normal = -normal;
        }
        let e1 = self.du.normalize();
        let e2 = normal.cross(&e1);
        // A = [[|r_u|, e1·r_v], [0, e2·r_v]]; its inverse is written out because it is
        // triangular by construction.
        let (alpha, beta, gamma) = (self.du.norm(), e1.dot(&self.dv), e2.dot(&self.dv));
        let a_inv = Matrix2::new(1.0 / alpha, -beta / (alpha * gamma), 0.0, 1.0 / gamma);
        let m = -(a_inv.transpose() * self.second_fundamental_form(&normal) * a_inv);
        let eig = SymmetricEigen2::new(m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
        let (c, s) = (eig.cos, eig.sin);
        SurfacePoint {
            point: self.point,
            normal,
            k1: eig.larger,
            k2: eig.smaller,
            d1: e1 * c + e2 * s,
            d2: e2 * c - e1 * s,
        }
    }
}

/// Closed-form eigen-decomposition of the symmetric matrix `[[a, b], [b, c]]`.
#[derive(Debug, Clone, Copy)]
struct SymmetricEigen2 {
    larger: f64,
    smaller: f64,
    /// `(cos θ, sin θ)` is the unit eigenvector of `larger`.
    cos: f64,
    sin: f64,
}

impl SymmetricEigen2 {
    fn new(a: f64, b: f64, c: f64) -> Self {
        let mean = 0.5 * (a + c);
        let half_diff = 0.5 * (a - c);
        let radius = half_diff.hypot(b);
        // θ = ½ atan2(2b, a − c) rotates e1 onto the larger eigenvalue's eigenvector; at an
        // umbilic atan2(0, 0) = 0, which picks e1, as good a choice as any.
        let theta = 0.5 * b.atan2(half_diff);
        let (sin, cos) = theta.sin_cos();
        Self {
            larger: mean + radius,
            smaller: mean - radius,
            cos,
            sin,
        }
    }
}

/// `r` and its first and second partial derivatives at `(u, v)`, exact by num-dual.
#[must_use]
pub fn derivatives<S: ParametricSurface + ?Sized>(
    surface: &S,
    u: f64,
    v: f64,
) -> SurfaceDerivatives {
    // One coordinate's value, gradient and Hessian with respect to (u, v).
    type Coordinate = (f64, Vector2<f64>, Matrix2<f64>);
    let [x, y, z] = hessian(
        |p: SVector<Dual2SVec64<2>, 2>| surface.position(p[0], p[1]),
        &Vector2::new(u, v),
    );
    let vec = |f: fn(&Coordinate) -> f64| Vector::new(f(&x), f(&y), f(&z));
    SurfaceDerivatives {
        point: Point::from(vec(|c| c.0)),
        du: vec(|c| c.1[0]),
        dv: vec(|c| c.1[1]),
        duu: vec(|c| c.2[(0, 0)]),
        duv: vec(|c| c.2[(0, 1)]),
        dvv: vec(|c| c.2[(1, 1)]),
    }
}

/// The exact differential geometry at `(u, v)` by automatic differentiation: [`derivatives`]
/// followed by [`SurfaceDerivatives::geometry`] with the surface's orientation.
#[must_use]
pub fn differential_geometry<S: ParametricSurface + ?Sized>(
    surface: &S,
    u: f64,
    v: f64,
) -> SurfacePoint {
    derivatives(surface, u, v).geometry(surface.orientation())
}

/// The plain `f64` position at `(u, v)`.
#[must_use]
pub fn position<S: ParametricSurface + ?Sized>(surface: &S, u: f64, v: f64) -> Point {
    Point::from(surface.position(u, v))
}

/// The result of a closest-point search in parameter space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projection {
    /// Parameters of the foot point.
    pub uv: [f64; 2],
    /// The foot point with its differential geometry.
    pub surface: SurfacePoint,
    /// Newton iterations used.
    pub iterations: usize,
    /// Whether the step fell below tolerance before the iteration limit. A foot point on the
    /// domain boundary (where the clamped step vanishes) also counts as converged.
    pub converged: bool,
}

/// Finds the point of `surface` nearest to `target` by damped Newton iteration on
/// `f(u, v) = ½ |r(u, v) − target|²` from the parameters `start`.
///
/// The Newton matrix is `I + [(r − p)·r_ij]`; where it is not positive definite the step falls
/// back to Gauss–Newton (`I` alone, always positive definite on a regular surface). Steps are
/// halved until the distance does not grow. Periodic parameters wrap, the others are clamped,
/// so the result is a local minimum of the distance over the domain near `start`, not
/// necessarily the global one: start close (for example from a coarse grid search).
#[must_use]
pub fn closest_point_newton<S: ParametricSurface + ?Sized>(
    surface: &S,
    target: &Point,
    start: [f64; 2],
) -> Projection {
    const MAX_ITERATIONS: usize = 50;
    const MAX_HALVINGS: usize = 40;
    let dom = surface.domain();
    let normalize =
        |uv: Vector2<f64>| Vector2::new(dom[0].normalize(uv[0]), dom[1].normalize(uv[1]));
    // Scale the stopping tolerance with the domain so it means "a few ulps of the parameter".
    let tol = 1e-14 * dom[0].len().abs().max(dom[1].len().abs()).max(1.0);
    let dist2 = |uv: &Vector2<f64>| (position(surface, uv[0], uv[1]) - target).norm_squared();

    let mut uv = normalize(Vector2::from(start));
    let mut iterations = 0;
    let mut converged = false;
    while iterations < MAX_ITERATIONS {
        iterations += 1;
        let d = derivatives(surface, uv[0], uv[1]);
        let r = d.point - target;
        let grad = Vector2::new(r.dot(&d.du), r.dot(&d.dv));
        let gauss_newton = d.first_fundamental_form();
        let newton = gauss_newton + d.second_fundamental_form(&r);
        let step = newton
            .cholesky()
            .or_else(|| gauss_newton.cholesky())
            .map_or_else(Vector2::zeros, |ch| -ch.solve(&grad));
        let current = r.norm_squared();
        let full = normalize(uv + step);
        // Convergence is judged on the full (clamped) Newton step, measured around the circle
        // for periodic parameters, never on a step shortened by the line search.
        let full_move = dom[0]
            .distance(uv[0], full[0])
            .max(dom[1].distance(uv[1], full[1]));
        // Near the minimum the distance changes by O(step²), below rounding of `current`, so
        // a little slack keeps the line search from rejecting good final steps.
        let acceptable = current + 1e-10 * current + f64::MIN_POSITIVE;
        let mut next = full;
        let mut scale = 1.0;
        for _ in 0..MAX_HALVINGS {
            if dist2(&next) <= acceptable {
                break;
            }
            scale *= 0.5;
            next = normalize(uv + step * scale);
        }
        uv = next;
        if full_move <= tol {
            converged = true;
            break;
        }
    }
    let uv = [uv[0], uv[1]];
    Projection {
        uv,
        surface: surface.at(uv[0], uv[1]),
        iterations,
        converged,
    }
}

/// Finds the point of `surface` nearest to `target`: the nearest of a `coarse × coarse`
/// parameter grid (spaced as [`ParamInterval::grid_value`]), refined by
/// [`closest_point_newton`].
///
/// The grid only has to land in the right basin of attraction, so `coarse` should resolve the
/// surface's features; the cost is `coarse²` position evaluations.
#[must_use]
pub fn closest_point_search<S: ParametricSurface + ?Sized>(
    surface: &S,
    target: &Point,
    coarse: usize,
) -> Projection {
    let [du, dv] = surface.domain();
    let coarse = coarse.max(1);
    let mut best = ([du.lerp(0.5), dv.lerp(0.5)], f64::INFINITY);
    for i in 0..coarse {
        let u = du.grid_value(i, coarse);
        for j in 0..coarse {
            let v = dv.grid_value(j, coarse);
            let d2 = (position(surface, u, v) - target).norm_squared();
            if d2 < best.1 {
                best = ([u, v], d2);
            }
        }
    }
    closest_point_newton(surface, target, best.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen2_orders_and_rotates() {
        let e = SymmetricEigen2::new(1.0, 0.0, 3.0);
        assert_eq!((e.larger, e.smaller), (3.0, 1.0));
        // The larger eigenvalue's eigenvector is e2 = (0, ±1).
        assert!(e.cos.abs() < 1e-15 && (e.sin.abs() - 1.0).abs() < 1e-15);

        let (a, b, c) = (0.3, -1.7, 2.2);
        let e = SymmetricEigen2::new(a, b, c);
        let m = Matrix2::new(a, b, b, c);
        let v = Vector2::new(e.cos, e.sin);
        assert!((m * v - v * e.larger).norm() < 1e-14);
        let w = Vector2::new(-e.sin, e.cos);
        assert!((m * w - w * e.smaller).norm() < 1e-14);
    }

    #[test]
    fn grid_values_follow_interval_kind() {
        let closed = ParamInterval::closed(0.0, 1.0);
        assert_eq!(
            (closed.grid_value(0, 5), closed.grid_value(4, 5)),
            (0.0, 1.0)
        );
        let periodic = ParamInterval::periodic(0.0, 4.0);
        assert_eq!(
            (periodic.grid_value(0, 4), periodic.grid_value(3, 4)),
            (0.0, 3.0)
        );
        let poles = ParamInterval::degenerate_ends(0.0, 4.0);
        assert_eq!((poles.grid_value(0, 4), poles.grid_value(3, 4)), (0.5, 3.5));
        assert!((periodic.normalize(-1.0) - 3.0).abs() < 1e-15);
        assert_eq!(closed.normalize(1.5), 1.0);
    }
}
