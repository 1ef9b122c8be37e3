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
    walk_to_minimum(|t| energy_derivatives(line, a, shift, t), toward, h, cfg)
}

/// The search of [`line_minimum`] on any `f(t) = (e′(t), e″(t))`: downhill from `t = 0` (at
/// a stationary point that is not a minimum, the way `toward` points) in steps of at most
/// h/4, Newton's where it heads downhill, until e′ changes sign; then safeguarded Newton in
/// the bracket.
fn walk_to_minimum(
    mut f: impl FnMut(f64) -> (f64, f64),
    toward: f64,
    h: f64,
    cfg: &ProjectionConfig,
) -> Option<f64> {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// [`walk_to_minimum`] on `f`, with the number of evaluations it made.
    fn walk(f: impl Fn(f64) -> (f64, f64), toward: f64, h: f64) -> (Option<f64>, usize) {
        let mut calls = 0;
        let t = walk_to_minimum(
            |t| {
                calls += 1;
                f(t)
            },
            toward,
            h,
            &ProjectionConfig::default(),
        );
        (t, calls)
    }

    /// e = (t − t0)², t0 = ±0.6h: the start, two capped steps of h/4, and the Newton step
    /// from 0.5h, which is exact: four evaluations (bisection would take about forty).
    #[test]
    fn newton_steps_capped_at_a_quarter_h_reach_a_quadratic_minimum() {
        for h in [1.0, 1e-3, 1e3] {
            for sign in [1.0, -1.0] {
                let t0 = sign * 0.6 * h;
                let (t, calls) = walk(|t| (2.0 * (t - t0), 2.0), 0.0, h);
                let t = t.unwrap();
                assert!((t - t0).abs() <= 1e-15 * h, "h {h}: {t} for {t0}");
                assert!(calls <= 4, "h {h}: {calls} evaluations");
            }
        }
    }

    /// e′ = sinh((t − t0)/h): Newton converges quadratically, to the stopping tolerance
    /// 1e-12 h, whatever the scale.
    #[test]
    fn newton_converges_to_the_tolerance_in_a_few_steps() {
        for h in [1.0, 1e-4, 1e4] {
            let t0 = 0.2 * h;
            let f = |t: f64| (((t - t0) / h).sinh(), ((t - t0) / h).cosh() / h);
            let (t, calls) = walk(f, 0.0, h);
            let t = t.unwrap();
            assert!((t - t0).abs() <= 1e-12 * h, "h {h}: {t} for {t0}");
            assert!(calls <= 5, "h {h}: {calls} evaluations");
        }
    }

    /// e′ = 0.7 − exp(−t/h): concave, so Newton approaches the root t0 = h ln(1/0.7) from
    /// below without crossing it, and the walk itself must stop on a step below 1e-12 h. The
    /// root is not a double, so e′ never vanishes exactly on the way.
    #[test]
    fn a_one_sided_newton_walk_stops_at_the_tolerance() {
        for h in [1.0, 1e-4, 1e4] {
            let t0 = h * (1.0f64 / 0.7).ln();
            let f = |t: f64| (0.7 - (-t / h).exp(), (-t / h).exp() / h);
            let (t, calls) = walk(f, 0.0, h);
            let t = t.unwrap_or_else(|| panic!("h {h}: no minimum"));
            assert!((t - t0).abs() <= 1e-12 * h, "h {h}: {t} for {t0}");
            assert!(calls <= 8, "h {h}: {calls} evaluations");
        }
    }

    /// e′ = atan((t − t0)/w) with w = h/100: Newton from the bracket's ends overshoots far
    /// outside it (beyond |t − t0| ≈ 1.4 w it diverges), so the bracket is bisected until
    /// Newton's basin is reached, then Newton converges.
    #[test]
    fn a_sharp_root_is_bracketed_and_bisected_into_newtons_reach() {
        for h in [1.0, 1e-3] {
            for t0 in [0.3 * h, -0.45 * h, 0.9 * h] {
                let w = 0.01 * h;
                let f = |t: f64| {
                    let x = (t - t0) / w;
                    (x.atan(), 1.0 / (w * (1.0 + x * x)))
                };
                let (t, calls) = walk(f, 0.0, h);
                let t = t.unwrap();
                assert!((t - t0).abs() <= 1e-12 * h, "h {h}: {t} for {t0}");
                // At most 4 walking steps of h/4, 5 halvings of an h/4 bracket down to
                // Newton's reach (about 1.4 w), 5 Newton steps.
                assert!(calls <= 14, "h {h}, t0 {t0}: {calls} evaluations");
            }
        }
    }

    /// Where e″ < 0 the walk takes a full step of h/4 downhill (Newton would head uphill),
    /// here past the minimum, then Newton inside the bracket: e = (t² − 1)² from t = ±0.3,
    /// h = 4 (steps of 1), finds ±1 in seven evaluations.
    #[test]
    fn a_concave_start_walks_downhill_to_the_next_minimum() {
        let f = |t: f64| (4.0 * t * (t * t - 1.0), 12.0 * t * t - 4.0);
        for (start, want) in [(0.3, 1.0), (-0.3, -1.0)] {
            let (t, calls) = walk(|t| f(t + start), 0.0, 4.0);
            let t = t.unwrap() + start;
            assert!((t - want).abs() <= 4e-12, "from {start}: {t}");
            assert!(calls <= 8, "from {start}: {calls} evaluations");
        }
        // At the maximum itself (e′ = 0, e″ < 0) the samples' side decides.
        for (toward, want) in [(-1.0, -1.0), (1.0, 1.0), (0.0, 1.0)] {
            let (t, _) = walk(f, toward, 4.0);
            assert!((t.unwrap() - want).abs() <= 4e-12, "toward {toward}: {t:?}");
        }
    }

    /// e = (t − 1/2)²/2 + sin(6t)/3 from 0 (h = 4, steps of 1): downhill to −1, then −2,
    /// where e′ changes sign. Newton from the bracket's midpoint −1.5 lands at −0.86, behind
    /// the bracket (−2, −1) and beside the maximum at −0.917; only the bracket's own minimum,
    /// at −1.148, may be returned.
    #[test]
    fn newton_steps_outside_the_bracket_are_not_taken() {
        let f = |t: f64| {
            (
                t - 0.5 + 2.0 * (6.0 * t).cos(),
                1.0 - 12.0 * (6.0 * t).sin(),
            )
        };
        let (t, _) = walk(f, 0.0, 4.0);
        let t = t.unwrap();
        let (e1, e2) = f(t);
        assert!(-2.0 < t && t < -1.0, "{t} is outside the bracket");
        assert!(
            e1.abs() < 1e-12 && e2 > 0.0,
            "not a minimum at {t}: e′ {e1}, e″ {e2}"
        );
    }

    #[test]
    fn a_minimum_at_the_start_is_returned_at_once() {
        assert_eq!(walk(|t| (2.0 * t, 2.0), 1.0, 1.0), (Some(0.0), 1));
        // A flat maximum (e = −t⁴/4: e′ = e″ = 0 at 0) is left, and nothing lies downhill.
        assert_eq!(walk(|t| (-t * t * t, -3.0 * t * t), 1.0, 1.0).0, None);
    }

    /// No sign change within `max_travel · h` (1.5 h: six steps of h/4), or a non-finite
    /// derivative, is no minimum.
    #[test]
    fn no_minimum_within_reach_is_none() {
        assert_eq!(walk(|_| (-1.0, 0.0), 0.0, 2.0), (None, 7));
        // The minimum at 1.6 h lies beyond reach; at 1.4 h it is found.
        assert_eq!(walk(|t| (2.0 * (t - 3.2), 2.0), 0.0, 2.0).0, None);
        assert!(walk(|t| (2.0 * (t - 2.8), 2.0), 0.0, 2.0).0.is_some());
        // A Newton step below the tolerance with e″ > 0 has converged, sign change or not.
        assert_eq!(walk(|_| (-1e-15, 1e3), 0.0, 1.0), (Some(1e-18), 2));
        // Newton steps of 1e-9 h that never reach a sign change: the walk gives up after
        // MAX_WALK_STEPS of them rather than crawl the 1.5 h (10⁹ steps).
        assert_eq!(walk(|_| (-1e-6, 1e3), 0.0, 1.0), (None, MAX_WALK_STEPS + 1));
        for bad in [f64::NAN, f64::INFINITY] {
            assert_eq!(walk(|_| (bad, 1.0), 0.0, 1.0), (None, 1));
            assert_eq!(walk(|_| (1.0, bad), 0.0, 1.0), (None, 1));
            assert_eq!(
                walk(
                    |t| if t == 0.0 { (-1.0, 0.0) } else { (bad, 1.0) },
                    0.0,
                    1.0
                ),
                (None, 2)
            );
        }
    }
}
