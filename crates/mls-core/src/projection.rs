//! The Amenta–Kil projection (Sec. 3, Fig. 2): from `x_j`, find the nearest local minimum of
//! the energy (Eq. 4) along the line `x_j + t n(x_j)`, move there, repeat.
//!
//! Along the line, with `b_i = (x_j − q_i)·n`, `c_i = |x_j − q_i|²`, `B = b_i + t` and
//! `θ_i(t) = exp(−a(c_i + 2 t b_i + t²))`:
//! $$ e'(t) = \sum_i 2\theta_i (B - aB^3),\qquad e''(t) = \sum_i \theta_i (2 - 10aB^2 + 4a^2B^4). $$
//! `e'(0) = g(x_j)` (Eq. 5 = Eq. 7), so g = 0 also at energy *maxima*, the spurious sheets
//! about ±h off the surface. The search walks downhill and brackets a sign change of e' from
//! negative to positive (in the walking direction), so it only ever stops where `e'' ≥ 0`.

use crate::field::{FieldScratch, Sample};
use crate::kernels::{Kernels, LineBlock, LineMoments, dispatch};
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

/// Terms of the exponential's Taylor series in [`LineSeries`]: `(−2atb)^m/m!`, `m ≤ 15`. The
/// derivatives then need the moments up to `b^(15 + 4)`, and the remainder's bound `b^16`.
const SERIES_ORDER: usize = 15;

/// Where the remainder of the series may reach, relative to `Σ w`: below the rounding of the
/// direct sum, whose terms add up to at least `Σ w` (e″'s leading term is `2 Σ w`).
const SERIES_TOLERANCE: f64 = 1e-16;

/// `1/(SERIES_ORDER + 1)!`.
const INV_FACTORIAL_16: f64 = 1.0 / 20_922_789_888_000.0;

/// The energy's derivatives along one line as power series in t, from the moments
/// `μ_j = Σ w_i β_iʲ` of the field's weights at `t = 0` (`β_i = b_i/h`; [`LineMoments`], summed
/// from the blocks n(x) was computed from, so the whole line search adds one light pass over
/// the samples and no exp). In units of h (a = 1), with `τ = t/h`:
///
/// With `θ_i(τ) = w_i exp(−2τβ_i) exp(−τ²)`, expanding `exp(−2τβ_i)` to order 15 and the
/// polynomials in `B = β_i + τ` in powers of `β_i`,
/// $$ e'(τ) = e^{−τ^2} \sum_{m \le 15} \frac{(−2τ)^m}{m!} \sum_{k \le 3} p_k μ_{m+k}, $$
/// `p(β) = 2(β + τ) − 2(β + τ)³`, and e″ likewise with `q(β) = 2 − 10(β + τ)² + 4(β + τ)⁴`.
/// The remainder of each sample's exponential is at most `x¹⁶ e^x / 16!`, `x = 2|τ||β_i|`,
/// so the series is used where `(2|τ|)¹⁶ e^{2|τ| β_max} μ₁₆ P / 16!` (P bounding |p| and |q|
/// with `|β| ≤ β_max`) is below [`SERIES_TOLERANCE`] `· μ₀`: on a line through a point near
/// the surface, all but the first steps of the first line search (|t| up to about h/20).
/// In the file's units `e′ = h e′_τ` and `e″ = e″_τ`, as [`energy_derivatives`] has them.
struct LineSeries {
    moments: LineMoments,
    h: f64,
}

impl LineSeries {
    /// `(e′(t), e″(t))` scaled by `exp(moments.log_scale)`, or `None` where the series'
    /// remainder could exceed [`SERIES_TOLERANCE`].
    fn at(&self, t: f64) -> Option<(f64, f64)> {
        let LineMoments { mu, reach, .. } = &self.moments;
        let tau = t / self.h;
        let x = 2.0 * tau.abs();
        let x_max = x * reach;
        if !(x_max <= 1.0) {
            return None;
        }
        let r = reach + tau.abs();
        let bound_first = 2.0 * r + 2.0 * r * r * r;
        let bound_second = 2.0 + 10.0 * r * r + 4.0 * r * r * r * r;
        let remainder = x.powi(SERIES_ORDER as i32 + 1)
            * INV_FACTORIAL_16
            * x_max.exp()
            * mu[SERIES_ORDER + 1]
            * bound_first.max(bound_second);
        if !(remainder <= SERIES_TOLERANCE * mu[0]) {
            return None;
        }
        let (t2, t3, t4) = (tau * tau, tau * tau * tau, tau * tau * tau * tau);
        let p = [2.0 * tau - 2.0 * t3, 2.0 - 6.0 * t2, -6.0 * tau, -2.0];
        let q = [
            2.0 - 10.0 * t2 + 4.0 * t4,
            -20.0 * tau + 16.0 * t3,
            -10.0 + 24.0 * t2,
            16.0 * tau,
            4.0,
        ];
        // c_m = (−2τ)^m / m!, summed from the highest order down so that the small terms
        // are added first.
        let mut c = [0.0; SERIES_ORDER + 1];
        c[0] = 1.0;
        for m in 1..=SERIES_ORDER {
            c[m] = c[m - 1] * (-2.0 * tau) / m as f64;
        }
        let (mut first, mut second) = (0.0, 0.0);
        for m in (0..=SERIES_ORDER).rev() {
            let d1: f64 = (0..4).map(|k| p[k] * mu[m + k]).sum();
            let d2: f64 = (0..5).map(|k| q[k] * mu[m + k]).sum();
            first += c[m] * d1;
            second += c[m] * d2;
        }
        let scale = (-t2).exp();
        Some((first * scale * self.h, second * scale))
    }
}

/// One line `x + t n` of the projection: its series near `t = 0`, and its samples, put in
/// blocks the first time a `t` lies beyond the series.
struct Line<'a> {
    series: LineSeries,
    x: &'a Point,
    n: &'a Vector,
    samples: &'a [Sample],
    a: f64,
    blocks: &'a mut Vec<LineBlock>,
    /// The blocks' shift, once they are filled.
    shift: Option<f64>,
}

impl Line<'_> {
    /// `(e′(t), e″(t))`, from the series where it is exact to rounding, else from the samples;
    /// each scaled by a positive constant (`exp` of the shift of the weights it used), which
    /// the search, reading signs and the ratio `e′/e″` of one evaluation, does not see.
    fn derivatives(&mut self, t: f64) -> (f64, f64) {
        if let Some(d) = self.series.at(t) {
            return d;
        }
        let shift = *self
            .shift
            .get_or_insert_with(|| LineBlock::fill(self.blocks, self.x, self.n, self.samples));
        energy_derivatives(self.blocks, self.a, shift, t)
    }
}

/// e′(t) and e″(t) along the line `x + t n`, by the same code as the projection's line
/// search (its series near `t = 0`, the samples' sums farther), both scaled by the positive
/// constant `exp(log_scale)` (about `a δ²`, δ the distance from `x` to the nearest sample).
/// For independent verification (`cargo xtask validate`).
pub fn line_derivatives(
    x: &Point,
    n: &Vector,
    samples: &[Sample],
    inv_h2: f64,
    t: f64,
) -> LineDerivatives {
    let mut scratch = FieldScratch::default();
    scratch.load(x, samples, f64::INFINITY, inv_h2);
    scratch.weigh_loaded();
    let moments = scratch.line_moments(n);
    let mut blocks = Vec::new();
    let mut line = Line {
        series: LineSeries {
            moments,
            h: inv_h2.sqrt().recip(),
        },
        x,
        n,
        samples,
        a: inv_h2,
        blocks: &mut blocks,
        shift: None,
    };
    let (first, second) = line.derivatives(t);
    LineDerivatives {
        first,
        second,
        log_scale: line.shift.map_or(moments.log_scale, |s| inv_h2 * s),
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

/// The most steps one downhill walk may take before its line search gives up.
const MAX_WALK_STEPS: usize = 1000;

/// The local minimum of `e(t)` along `x + t n` reached by walking downhill from `t = 0`, or
/// `None` when there is none within `max_travel`. `moments` are those of `samples` along the
/// line ([`FieldScratch::line_moments`]); `blocks` is storage for the samples' sums.
pub(crate) fn line_minimum(
    moments: LineMoments,
    (x, n): (&Point, &Vector),
    samples: &[Sample],
    blocks: &mut Vec<LineBlock>,
    a: f64,
    h: f64,
    cfg: &ProjectionConfig,
) -> Option<f64> {
    let mut line = Line {
        series: LineSeries { moments, h },
        x,
        n,
        samples,
        a,
        blocks,
        shift: None,
    };
    walk_to_minimum(|t| line.derivatives(t), moments.toward, h, cfg)
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

    /// A patch of a sphere of radius 1 around +z, `n` samples at a spacing of about `s`,
    /// jittered, with their normals.
    fn sphere_patch(n: usize, s: f64) -> Vec<Sample> {
        let side = (n as f64).sqrt().ceil() as usize;
        (0..n)
            .map(|i| {
                let (u, v) = ((i % side) as f64, (i / side) as f64);
                let c = (side as f64 - 1.0) / 2.0;
                // A fixed irrational jitter, so that no two samples line up.
                let j = |k: f64| 0.3 * ((k * 0.754_877_666).fract() - 0.5);
                let dir = Vector::new(
                    (u - c + j(i as f64)) * s,
                    (v - c + j(i as f64 + 0.5)) * s,
                    1.0,
                )
                .normalize();
                Sample {
                    point: Point::from(dir),
                    normal: dir,
                }
            })
            .collect()
    }

    /// The series agrees with the samples' sums wherever it answers, answers over the range
    /// of t a converging projection walks, and declines far out.
    #[test]
    fn the_line_series_matches_the_direct_sums_where_it_answers() {
        let s = 0.01;
        let samples = sphere_patch(900, s);
        let h = 2.0 * s;
        let a = 1.0 / (h * h);
        for (x, n) in [
            (Point::new(0.0, 0.0, 1.0), Vector::z()),
            (
                Point::new(0.003, -0.002, 1.004),
                Vector::new(0.2, 0.1, 1.0).normalize(),
            ),
            (
                Point::new(0.01, 0.0, 0.99),
                Vector::new(0.0, -0.3, 1.0).normalize(),
            ),
        ] {
            let mut line = Vec::new();
            let shift = LineBlock::fill(&mut line, &x, &n, &samples);
            let mut scratch = FieldScratch::default();
            scratch.load(&x, &samples, f64::INFINITY, a);
            scratch.weigh_loaded();
            let series = LineSeries {
                moments: scratch.line_moments(&n),
                h,
            };
            // |t| from h·5e-14 to h/3: a converging walk's last steps, then its first ones.
            let fractions = (-12..=0).map(|e| 0.05 * 10f64.powi(e)).chain([
                1.0 / 40.0,
                1.0 / 20.0,
                0.1,
                0.125,
                0.2,
                0.25,
                1.0 / 3.0,
            ]);
            for f in fractions {
                for sign in [-1.0, 1.0] {
                    let t = sign * h * f;
                    let direct = energy_derivatives(&mut line, a, shift, t);
                    let Some(by_series) = series.at(t) else {
                        // It declines where 2|τ|·reach > 1 or its remainder bound exceeds
                        // rounding: beyond h/8 on these lines.
                        assert!(f > 0.1, "t = {t:e} not answered");
                        continue;
                    };
                    // The sums' terms are of the order of h Σw and 2Σw.
                    let sum = series.moments.mu[0];
                    assert!(
                        (by_series.0 - direct.0).abs() < 1e-13 * h * sum
                            && (by_series.1 - direct.1).abs() < 1e-13 * sum,
                        "t = {t:e}: series {by_series:?}, direct {direct:?}"
                    );
                }
            }
            assert!(series.at(0.5 * h).is_none());
        }
    }

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
