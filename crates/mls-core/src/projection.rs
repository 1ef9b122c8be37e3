//! The Amenta–Kil projection (Sec. 3, Fig. 2): from `x_j`, find the nearest local minimum of
//! the energy (Eq. 4) along the line `x_j + t n(x_j)`, move there, repeat.
//!
//! Along the line, with `b_i = (x_j − q_i)·n`, `c_i = |x_j − q_i|²`, `B = b_i + t` and
//! `θ_i(t) = exp(−a(c_i + 2 t b_i + t²))`:
//! $$ e'(t) = \sum_i 2\theta_i (B - aB^3),\qquad e''(t) = \sum_i \theta_i (2 - 10aB^2 + 4a^2B^4). $$
//! `e'(0) = g(x_j)` (Eq. 5 = Eq. 7), so g = 0 also at energy *maxima*, the spurious sheets
//! about ±h off the surface. The search walks downhill and brackets a sign change of e' from
//! negative to positive (in the walking direction), so it only ever stops where `e'' ≥ 0`.

use crate::field::Sample;
use crate::kernels::{Kernels, LineBlock, dispatch};
use crate::math::{Point, Vector};

/// Stopping rules of the projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionConfig {
    /// Stop when a step is shorter than `tolerance · h` (or than the rounding of the position,
    /// if that is larger). 1e-12 by default: two clouds that differ only by rounding then
    /// project to points whose curvatures agree to about 1e-8 even where the surface is
    /// ill-conditioned; 1e-10 let them differ by 1e-5 (`cargo xtask robustness`).
    pub tolerance: f64,
    /// Give up (status `ProjectionFailed`) after this many line searches.
    pub max_iterations: usize,
    /// The farthest a single line search may walk, in units of h. Beyond about h from the
    /// surface the energy decreases away from it (it tends to 0 at infinity), so a point that
    /// far finds no minimum and is reported, not dragged onto a spurious sheet.
    pub max_travel: f64,
}

impl Default for ProjectionConfig {
    fn default() -> Self {
        Self {
            tolerance: 1e-12,
            max_iterations: 100,
            max_travel: 1.5,
        }
    }
}

/// `(e'(t), e''(t))`, both scaled by the same positive constant `exp(a·shift)`.
fn energy_derivatives(line: &mut [LineBlock], a: f64, shift: f64, t: f64) -> (f64, f64) {
    let mut acc = [[0.0; 4]; 2];
    dispatch!(k => k.line_energy(line, a, shift, t, &mut acc));
    (acc[0].iter().sum(), acc[1].iter().sum())
}

/// e′(t) and e″(t) along the line `x + t n`, by the same code as the projection's line
/// search, both scaled by the positive constant `exp(a·shift)` (`shift` the smallest squared
/// distance from `x` to a sample, returned as `a·shift`). For independent verification
/// (`cargo xtask validate`): the projection itself calls the same [`energy_derivatives`].
pub fn line_derivatives(
    x: &Point,
    n: &Vector,
    samples: &[Sample],
    inv_h2: f64,
    t: f64,
) -> LineDerivatives {
    let mut line = Vec::new();
    LineBlock::fill(&mut line, x, n, samples);
    let shift = line_shift(&line);
    let (first, second) = energy_derivatives(&mut line, inv_h2, shift, t);
    LineDerivatives {
        first,
        second,
        log_scale: inv_h2 * shift,
    }
}

/// e′(t), e″(t) along a line, scaled by `exp(log_scale)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineDerivatives {
    /// `e′(t) · exp(log_scale)`.
    pub first: f64,
    /// `e″(t) · exp(log_scale)`.
    pub second: f64,
    /// `a·δ²`, δ the distance from the line's origin to the nearest sample.
    pub log_scale: f64,
}

/// The smallest squared distance from the line's origin to a sample: the weights are shifted
/// by it so that they cannot all underflow.
fn line_shift(line: &[LineBlock]) -> f64 {
    line.iter().flat_map(|s| s.c).fold(f64::INFINITY, f64::min)
}

/// The most steps one downhill walk may take before its line search gives up.
const MAX_WALK_STEPS: usize = 1000;

/// The local minimum of `e(t)` reached by walking downhill from `t = 0`, or `None` when there
/// is none within `max_travel`.
pub(crate) fn line_minimum(
    line: &mut [LineBlock],
    a: f64,
    h: f64,
    cfg: &ProjectionConfig,
) -> Option<f64> {
    let shift = line_shift(line);
    let toward: f64 = line.iter().flat_map(|s| s.b).map(|b| -b).sum();
    let mut f = |t: f64| energy_derivatives(line, a, shift, t);
    let tol = cfg.tolerance * h;
    let max_step = 0.25 * h;
    let (mut e1, mut e2) = f(0.0);
    if !(e1.is_finite() && e2.is_finite()) {
        return None;
    }
    if e1 == 0.0 && e2 > 0.0 {
        return Some(0.0);
    }
    // Downhill; at an exact stationary point that is not a minimum, head towards the samples.
    let dir = if e1 != 0.0 {
        -e1.signum()
    } else if toward < 0.0 {
        -1.0
    } else {
        1.0
    };
    // March until e' changes sign (a minimum is bracketed) or Newton converges on the way.
    let mut t = 0.0;
    // Bounded: Newton converges in a handful of steps and h/4 steps reach max_travel in six;
    // a walk that does neither within the bound is reported, not continued.
    let mut walk = 0;
    let (lo, hi, at_hi) = loop {
        walk += 1;
        if walk > MAX_WALK_STEPS {
            return None;
        }
        let newton = if e2 > 0.0 { -e1 / e2 } else { f64::NAN };
        let step = if newton * dir > 0.0 {
            newton.abs().min(max_step)
        } else {
            max_step
        };
        let t_new = t + dir * step;
        if t_new.abs() > cfg.max_travel * h {
            return None;
        }
        let (n1, n2) = f(t_new);
        if !(n1.is_finite() && n2.is_finite()) {
            return None;
        }
        if n1 == 0.0 || n1.signum() == dir {
            break (t, t_new, (n1, n2));
        }
        if step < tol && n2 > 0.0 {
            return Some(t_new);
        }
        (t, e1, e2) = (t_new, n1, n2);
    };
    // Safeguarded Newton inside the bracket: e'·dir < 0 at `lo`, ≥ 0 at `hi`.
    let (mut lo, mut hi) = (lo, hi);
    let mut t = hi;
    // The walk has just evaluated e' and e'' at `hi`.
    let mut known = Some(at_hi);
    for _ in 0..200 {
        let (n1, n2) = known.take().unwrap_or_else(|| f(t));
        if n1 == 0.0 {
            return Some(t);
        }
        if n1.signum() == dir {
            hi = t;
        } else {
            lo = t;
        }
        let newton = t - n1 / n2;
        // A Newton step below the tolerance has converged, also when rounding puts it on the
        // bracket's end at `t` or just past it; bisecting from there would only walk back to
        // the same root in several more evaluations.
        if n2 > 0.0 && (newton - t).abs() < tol {
            return Some(newton.clamp(lo.min(hi), lo.max(hi)));
        }
        let inside = (newton - lo) * (newton - hi) < 0.0;
        let next = if n2 > 0.0 && inside {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - t).abs() < tol || (hi - lo).abs() < tol {
            return Some(next);
        }
        t = next;
    }
    Some(0.5 * (lo + hi))
}
