//! Tensor-product B-spline surfaces, evaluated generically so that num-dual differentiates
//! them, and the two test patches standing in for the paper's NURBS 1 and NURBS 2.

use std::f64::consts::{PI, TAU};

use crate::math::{Point, Scalar};
use crate::parametric::{ParamInterval, ParametricSurface, Projection, closest_point_search};

/// A B-spline basis of one parameter: degree and clamped knot vector on `[0, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineBasis {
    degree: usize,
    count: usize,
    knots: Vec<f64>,
}

impl BSplineBasis {
    /// The uniform clamped basis of `count` functions of degree `degree` on `[0, 1]`: knots
    /// `0` and `1` repeated `degree + 1` times and `count − degree − 1` equally spaced interior
    /// knots, so the curve interpolates its end control points.
    ///
    /// # Panics
    ///
    /// If `count <= degree` (too few control points for the degree).
    #[must_use]
    pub fn uniform_clamped(degree: usize, count: usize) -> Self {
        assert!(
            count > degree,
            "a degree-{degree} B-spline needs more than {degree} control points, got {count}"
        );
        let segments = (count - degree) as f64;
        let knots = (0..count + degree + 1)
            .map(|i| (i.saturating_sub(degree).min(count - degree) as f64) / segments)
            .collect();
        Self {
            degree,
            count,
            knots,
        }
    }

    /// Polynomial degree.
    #[must_use]
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// Number of basis functions (control points).
    #[must_use]
    pub fn count(&self) -> usize {
        self.count
    }

    /// The knot vector, `count + degree + 1` values.
    #[must_use]
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// The Greville abscissae `ξ_i = (t_{i+1} + … + t_{i+p}) / p`. Placing control points at
    /// `x_i = ξ_i` makes the spline reproduce `x(u) = u` exactly (linear precision), which
    /// is how the height-field patches get an affine parametrisation in x and y.
    #[must_use]
    pub fn greville(&self) -> Vec<f64> {
        let p = self.degree;
        if p == 0 {
            // Degree 0 has no averages; the midpoints of the knot intervals play their role.
            return (0..self.count)
                .map(|i| 0.5 * (self.knots[i] + self.knots[i + 1]))
                .collect();
        }
        (0..self.count)
            .map(|i| self.knots[i + 1..=i + p].iter().sum::<f64>() / p as f64)
            .collect()
    }

    /// The knot span `i` with `t_i <= u < t_{i+1}` and `degree <= i < count`, so that the
    /// basis functions nonzero at `u` are `N_{i−p} … N_i`. Values outside `[0, 1]` use the end
    /// spans (polynomial extension); `u = 1` uses the last span.
    #[must_use]
    pub fn span(&self, u: f64) -> usize {
        let (p, n) = (self.degree, self.count);
        if u >= self.knots[n] {
            return n - 1;
        }
        if u <= self.knots[p] {
            return p;
        }
        // Binary search for the last knot <= u among t_p .. t_n.
        let (mut lo, mut hi) = (p, n);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if u < self.knots[mid] {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        lo
    }

    /// The `degree + 1` basis functions nonzero at `u`, with the index of the first:
    /// returns `(first, [N_first(u), …, N_{first+p}(u)])`.
    ///
    /// Cox–de Boor recursion in the triangular form of Piegl & Tiller, *The NURBS Book*,
    /// Algorithm A2.2, written generic over [`Scalar`]: the span is chosen from the real part,
    /// and within a span each basis function is a polynomial in `u`, so dual numbers carry
    /// exact derivatives through it.
    #[must_use]
    pub fn eval<D: Scalar>(&self, u: D) -> (usize, Vec<D>) {
        let p = self.degree;
        let span = self.span(u.re());
        let zero = D::from(0.0);
        let mut n = vec![zero; p + 1];
        let mut left = vec![zero; p + 1];
        let mut right = vec![zero; p + 1];
        n[0] = D::from(1.0);
        for j in 1..=p {
            left[j] = u - self.knots[span + 1 - j];
            right[j] = -(u - self.knots[span + j]);
            let mut saved = zero;
            for r in 0..j {
                let temp = n[r] / (right[r + 1] + left[j - r]);
                n[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            n[j] = saved;
        }
        (span - p, n)
    }
}

/// A non-rational tensor-product B-spline surface on `[0, 1]²` with uniform clamped knots.
///
/// Parameters `u`, `v`, both closed on `[0, 1]`; the normal is `r_u × r_v` normalised (for the
/// two test patches, which are height fields increasing in x with u and in y with v, that is
/// the `+z` side).
///
/// $$ r(u, v) = \sum_{i,j} N_{i,p}(u)\, N_{j,q}(v)\, P_{ij} $$
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineSurface {
    basis: [BSplineBasis; 2],
    /// Row-major: `P_ij` at `i * count_v + j`.
    control: Vec<Point>,
}

impl BSplineSurface {
    /// A surface of degrees `degree = [p, q]` on a `counts = [nu, nv]` control net, stored
    /// row-major (`P_ij` at `i * nv + j`, `i` along u).
    ///
    /// # Panics
    ///
    /// If `control.len() != nu * nv` or a count does not exceed its degree.
    #[must_use]
    pub fn new(degree: [usize; 2], counts: [usize; 2], control: Vec<Point>) -> Self {
        assert_eq!(
            control.len(),
            counts[0] * counts[1],
            "control net size must be nu * nv"
        );
        let basis = [
            BSplineBasis::uniform_clamped(degree[0], counts[0]),
            BSplineBasis::uniform_clamped(degree[1], counts[1]),
        ];
        Self { basis, control }
    }

    /// A height-field patch over the rectangle `[x0, x1] × [y0, y1]` (`extent = [[x0, x1],
    /// [y0, y1]]`): control point `P_ij = (x(ξ_i), y(η_j), height(x(ξ_i), y(η_j)))` at the
    /// Greville abscissae mapped affinely to the rectangle. By linear precision the surface is
    /// then exactly `r(u, v) = (x(u), y(v), s(u, v))`, a graph over the rectangle, and its
    /// height is a smoothed version of `height`.
    ///
    /// # Panics
    ///
    /// As [`BSplineSurface::new`].
    #[must_use]
    pub fn from_height_fn(
        degree: [usize; 2],
        counts: [usize; 2],
        extent: [[f64; 2]; 2],
        height: impl Fn(f64, f64) -> f64,
    ) -> Self {
        let xs = BSplineBasis::uniform_clamped(degree[0], counts[0]).greville();
        let ys = BSplineBasis::uniform_clamped(degree[1], counts[1]).greville();
        let lerp = |[a, b]: [f64; 2], t: f64| a + t * (b - a);
        let control = xs
            .iter()
            .flat_map(|&s| {
                let x = lerp(extent[0], s);
                ys.iter().map(move |&t| (x, lerp(extent[1], t)))
            })
            .map(|(x, y)| Point::new(x, y, height(x, y)))
            .collect();
        Self::new(degree, counts, control)
    }

    /// Stand-in for the paper's "NURBS 1": a bicubic patch on a 33 × 33 control net over
    /// `[0, 1]²` (unit size), a smooth wavy height field of height up to about ±0.2 whose
    /// curvature varies across the patch (a product wave, an oblique wave and one bump).
    #[must_use]
    pub fn nurbs1() -> Self {
        Self::from_height_fn([3, 3], [33, 33], [[0.0, 1.0], [0.0, 1.0]], |x, y| {
            let bump = (-((x - 0.65).powi(2) + (y - 0.35).powi(2)) / (2.0 * 0.1 * 0.1)).exp();
            0.08 * (TAU * x).sin() * (PI * y).cos()
                + 0.05 * (3.0 * PI * (x + 0.5 * y)).sin()
                + 0.06 * bump
        })
    }

    /// Stand-in for the paper's "NURBS 2": a bi-quintic "face-like" patch on a 40 × 52 control
    /// net over `[−75, 75] × [−100, 100]` (millimetres, the size of a face scan, so that the
    /// paper's `h = 2` is a sensible kernel width). Height, with `y` up the face: a shallow
    /// dome (about 40 at the centre) with a nose ridge and tip (+28), eye sockets (−10), a
    /// brow ridge, cheeks, lips and a chin.
    #[must_use]
    pub fn nurbs2() -> Self {
        Self::from_height_fn(
            [5, 5],
            [40, 52],
            [[-75.0, 75.0], [-100.0, 100.0]],
            face_height,
        )
    }

    /// The bases in u and v.
    #[must_use]
    pub fn basis(&self) -> &[BSplineBasis; 2] {
        &self.basis
    }

    /// Control-net size `[nu, nv]`.
    #[must_use]
    pub fn counts(&self) -> [usize; 2] {
        [self.basis[0].count, self.basis[1].count]
    }

    /// Control point `P_ij`.
    ///
    /// # Panics
    ///
    /// If `i` or `j` is out of range.
    #[must_use]
    pub fn control_point(&self, i: usize, j: usize) -> Point {
        let nv = self.basis[1].count;
        assert!(
            i < self.basis[0].count && j < nv,
            "control index out of range"
        );
        self.control[i * nv + j]
    }

    /// The point nearest to `p`: the best of a 33 × 33 parameter grid, refined by Newton
    /// (see [`closest_point_search`]).
    #[must_use]
    pub fn closest_point(&self, p: &Point) -> Projection {
        closest_point_search(self, p, 33)
    }
}

impl ParametricSurface for BSplineSurface {
    fn domain(&self) -> [ParamInterval; 2] {
        [
            ParamInterval::closed(0.0, 1.0),
            ParamInterval::closed(0.0, 1.0),
        ]
    }

    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        let (iu, bu) = self.basis[0].eval(u);
        let (iv, bv) = self.basis[1].eval(v);
        let nv = self.basis[1].count;
        let zero = D::from(0.0);
        let mut out = [zero; 3];
        for (a, &nu) in bu.iter().enumerate() {
            // Sum each row in v first, so only one product per row involves the u weight.
            let mut row = [zero; 3];
            for (b, &nvb) in bv.iter().enumerate() {
                let p = self.control[(iu + a) * nv + iv + b];
                for k in 0..3 {
                    row[k] += nvb * p[k];
                }
            }
            for k in 0..3 {
                out[k] += nu * row[k];
            }
        }
        out
    }
}

/// The face-like height behind [`BSplineSurface::nurbs2`], in millimetres, `y` up the face.
fn face_height(x: f64, y: f64) -> f64 {
    // Anisotropic Gaussian bump centred at (cx, cy).
    let g = |cx: f64, cy: f64, sx: f64, sy: f64| {
        let (dx, dy) = ((x - cx) / sx, (y - cy) / sy);
        (-0.5 * (dx * dx + dy * dy)).exp()
    };
    let dome = 40.0 - 30.0 * (x / 75.0).powi(2) - 15.0 * (y / 100.0).powi(2);
    let nose = 22.0 * g(0.0, 5.0, 8.0, 20.0) + 6.0 * g(0.0, -12.0, 7.0, 6.0);
    let eyes = -10.0 * (g(-30.0, 30.0, 12.0, 8.0) + g(30.0, 30.0, 12.0, 8.0));
    let brow = 5.0 * g(0.0, 45.0, 40.0, 6.0);
    let cheeks = 6.0 * (g(-38.0, -5.0, 15.0, 15.0) + g(38.0, -5.0, 15.0, 15.0));
    let lips = 3.5 * (g(0.0, -36.0, 15.0, 3.5) + g(0.0, -46.0, 13.0, 3.5));
    let chin = 6.0 * g(0.0, -78.0, 16.0, 10.0);
    dome + nose + eyes + brow + cheeks + lips + chin
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_knots() {
        let b = BSplineBasis::uniform_clamped(3, 6);
        assert_eq!(
            b.knots(),
            &[0.0, 0.0, 0.0, 0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0, 1.0, 1.0, 1.0]
        );
        assert_eq!(b.span(0.0), 3);
        assert_eq!(b.span(0.5), 4);
        assert_eq!(b.span(1.0), 5);
    }
}
