//! The scale h: given with `--h` or derived from the point spacing, and checked against the
//! cloud, so that an h that spans the whole cloud is refused or warned about before a long run.

use anyhow::{Context, Result, bail};
use mls_core::normals::{DEFAULT_SPACING_NEIGHBOURS, SpacingStats, suggest_h};
use mls_core::{Cutoff, IndexedCloud, Parallelism, Point};

use super::Length;

/// The chosen h and a sentence on why.
#[derive(Debug)]
pub struct Scale {
    pub h: f64,
    /// How h was derived, without parentheses: `2 × median local spacing … over 12 neighbours`,
    /// or `given with --h`.
    pub why: String,
    pub spacing: Option<SpacingStats>,
    /// The multiple of the spacing, if h was derived from it.
    pub factor: Option<f64>,
}

impl Scale {
    /// h and where it came from, for a summary line; `options` names how to change it.
    pub fn describe(&self, options: &str) -> String {
        if self.spacing.is_some() {
            format!("{} = {}; {options} to change", Length(self.h), self.why)
        } else {
            format!("{}, {}", Length(self.h), self.why)
        }
    }
}

/// Beyond this many times its bounding-box diagonal, h is refused: every sample weighs about
/// alike, and the "surface" is one blob fitted to the whole cloud.
const MAX_H_OVER_DIAGONAL: f64 = 10.0;

/// Points at which the kernel's reach is counted, by brute force, for the warnings.
const SUPPORT_PROBES: usize = 32;

/// At most this many points are counted around each probe (every k-th point of a larger
/// cloud, the count scaled up): a fraction to a few tenths of a percent, in milliseconds on a
/// million points.
const SUPPORT_SAMPLE: usize = 1 << 16;

/// Fewer other samples than this within 2h of a point, on average, and h is called too small:
/// the jet needs 6 at a scale, and with fewer the nearest sample alone shapes the MLS surface.
/// On a uniform sampling of spacing s there are about π(2h/s)² of them: 6 at h ≈ 0.7 s, 50 at
/// the default h = 2 s.
const MIN_NEAR_SAMPLES: f64 = 6.0;

/// Samples per evaluation beyond which a run is called slow: the default h gives a few
/// hundred within the default cutoff (about 35 times fewer).
const SLOW_SUPPORT: f64 = 10_000.0;

/// Refuses an h far beyond the size of the cloud and returns warnings, each starting with
/// `file`, when the kernel's weight spans most of the cloud, or when its support holds so many
/// samples that the run will be slow. The binary prints them on stderr even with --quiet (the
/// results would look fine; see [`print_warning`]). At h = 1000 on the 0.25 m bunny every point
/// came out "ok", with k ≈ 1e-6, after a run 300 times longer than usual.
pub fn check_scale(
    points: &[Point],
    scale: &Scale,
    cutoff: Cutoff,
    file: &str,
) -> Result<Vec<String>> {
    let h = scale.h;
    let Some(first) = points.first() else {
        return Ok(Vec::new());
    };
    let (lo, hi) = points
        .iter()
        .fold((first.coords, first.coords), |(lo, hi), p| {
            (lo.inf(&p.coords), hi.sup(&p.coords))
        });
    let diagonal = (hi - lo).norm();
    if !(diagonal > 0.0) {
        return Ok(Vec::new());
    }
    if h > MAX_H_OVER_DIAGONAL * diagonal {
        bail!(
            "{file}: h = {h} is {:.0} times the diagonal {} of the cloud's bounding box: \
             every point would weigh alike and the curvature would be that of one blob, not of the \
             surface; choose h well below the size of the cloud (`mlscurv info` suggests one)",
            h / diagonal,
            Length(diagonal)
        );
    }
    // The weight is 1.2e-4 at 3h: what lies within 3h is what shapes the surface. The cutoff
    // (5h by default) only bounds the work, and on a small cloud holds most of it harmlessly.
    let weighty = 3.0 * h;
    let support = match cutoff {
        Cutoff::Radius(c) => Some(c * h),
        Cutoff::None => None,
    };
    let n = points.len();
    let probes = n.min(SUPPORT_PROBES);
    let step = n / probes;
    let stride = n.div_ceil(SUPPORT_SAMPLE);
    let sampled = n.div_ceil(stride);
    // The weight is e⁻⁴ = 0.018 at 2h: the samples within it carry a fit.
    let near = 2.0 * h;
    let (mut within_weighty, mut within_support, mut within_near) = (0usize, 0usize, 0usize);
    for i in 0..probes {
        let q = points[i * step];
        for p in points.iter().step_by(stride) {
            let d2 = (p - q).norm_squared();
            within_weighty += usize::from(d2 <= weighty * weighty);
            within_support += usize::from(support.is_none_or(|r| d2 <= r * r));
            within_near += usize::from(d2 > 0.0 && d2 <= near * near);
        }
    }
    let fraction = within_weighty as f64 / (probes * sampled) as f64;
    let scaled = |count: usize| count as f64 / probes as f64 * (n as f64 / sampled as f64);
    let per_point = scaled(within_support);
    let neighbours = scaled(within_near);
    let mut warnings = Vec::new();
    if h > diagonal {
        warnings.push(format!(
            "h = {h} exceeds the cloud's extent (bounding-box diagonal {})",
            Length(diagonal)
        ));
    } else if fraction > 0.5 {
        warnings.push(format!(
            "h = {h}: the kernel's weight (within 3h = {}) spans on average {:.0}% of \
             the {n} points",
            Length(weighty),
            100.0 * fraction
        ));
    }
    if let Some(w) = warnings.first_mut() {
        w.push_str(
            "; the curvature will be that of an overall smoothed shape, not of local detail",
        );
        // With the default factor, h is what `info` would suggest: the cloud is then too
        // small for local detail, and saying "choose another h" would be no help.
        match scale.factor {
            None => w.push_str("; `mlscurv info` suggests an h"),
            Some(f) if f > mls_core::normals::DEFAULT_H_FACTOR => {
                w.push_str(&format!(
                    "; a smaller --h-factor than {f} gives a smaller h"
                ));
            }
            Some(_) => w.push_str("; the cloud has too few points for a local fit"),
        }
    }
    // (A cloud already too small for h has few samples near any point whatever h is.)
    if warnings.is_empty() && neighbours < MIN_NEAR_SAMPLES {
        warnings.push(format!(
            "h = {h}: a point has on average {neighbours:.1} other samples within 2h = \
             {}, where the weight is above 0.018: too few for a fit, so points may fail \
             and the curvature follows the sampling more than the surface (the default h, 2 × \
             the median local spacing, has about 50; `mlscurv info` suggests one)",
            Length(near)
        ));
    }
    if per_point > SLOW_SUPPORT {
        warnings.push(format!(
            "h = {h}: the kernel's support ({}) holds about {per_point:.0} of the {n} points at \
             each evaluation; expect a long run",
            match support {
                Some(r) => format!("cutoff {}", Length(r)),
                None => "no cutoff".to_owned(),
            }
        ));
    }
    Ok(warnings
        .into_iter()
        .map(|w| format!("{file}: {w}"))
        .collect())
}

/// Prints a warning of [`check_scale`] on stderr, as the binary does even with `--quiet`.
pub fn print_warning(warning: String) {
    eprintln!("mlscurv: warning: {warning}");
}

/// h given, or `factor` × the spacing of `cloud` measured at up to
/// [`mls_core::normals::SPACING_SAMPLE`] points spread over it ([`IndexedCloud::spacing`]).
pub fn choose_h_on(
    cloud: &IndexedCloud<'_>,
    h: Option<f64>,
    factor: f64,
    par: Parallelism,
    file: &str,
) -> Result<Scale> {
    choose_h_from(h, factor, file, || {
        cloud.spacing(DEFAULT_SPACING_NEIGHBOURS, par)
    })
}

/// h given, or `factor` × the spacing that `stats` measures.
fn choose_h_from(
    h: Option<f64>,
    factor: f64,
    file: &str,
    stats: impl FnOnce() -> Result<SpacingStats, mls_core::NormalsError>,
) -> Result<Scale> {
    if let Some(h) = h {
        return Ok(Scale {
            h,
            why: "given with --h".into(),
            spacing: None,
            factor: None,
        });
    }
    let stats = stats().with_context(|| format!("{file}: cannot measure the point spacing"))?;
    let h = suggest_h(&stats, factor)
        .with_context(|| format!("{file}: cannot derive h from the spacing"))?;
    let at = if stats.measured < stats.distinct {
        format!(" at {} of {} points", stats.measured, stats.distinct)
    } else {
        String::new()
    };
    Ok(Scale {
        h,
        why: format!(
            "{factor} × median local spacing {} over {} neighbours{at}",
            Length(stats.spacing),
            stats.k
        ),
        spacing: Some(stats),
        factor: Some(factor),
    })
}
