//! Oriented normals for the surface: the file's own, or estimated from the points and
//! oriented by the chosen rule (or towards each E57 scan's scanner), with the sentence that
//! says where they came from for the summary.

use anyhow::{Context, Result, bail};
use mls_core::normals::{
    DEFAULT_NEIGHBOURS, EstimatedNormals, NormalsConfig, Orientation, estimate_normals,
    estimate_normals_on, orient_normals, orient_normals_towards, sampled_consistency,
};
use mls_core::{IndexedCloud, Parallelism, Point, Vector};
use mls_io::PointCloud;

use crate::NormalsMode;

/// Oriented normals, one per point (`None` where none could be had), and their source.
#[derive(Debug)]
pub struct Normals {
    pub normals: Vec<Option<Vector>>,
    pub source: String,
    /// Whether they are the file's (measured data) rather than estimated from the points.
    pub from_file: bool,
    /// For estimated normals, a warning when their orientation left too few neighbour pairs
    /// agreeing in sign ([`estimated_normals_warning`]); `None` for the file's.
    pub warning: Option<String>,
}

/// Points whose neighbour pairs are counted by [`check_file_normals`]: the agreement to about
/// ±0.1 % near the threshold, at a fiftieth of the full graph's cost on a million points.
const CONSISTENCY_SAMPLE: usize = 20_000;

/// The least share of neighbour pairs whose file normals agree in sign before a warning, as
/// `mlscurv info` judges "consistently oriented". Consistent normals measured 99.5–100 % (the
/// bunny's estimated ones 100.0 %, the aerial tile's 99.5 %, a generated airborne scene's exact
/// ones with trees and walls 99.6 %); 1 % of the normals flipped gives 98 %, a tenth 82 %,
/// random signs 50 % (`docs/orientation.md`).
pub const MIN_FILE_CONSISTENCY: f64 = 0.99;

/// The least share of neighbour pairs whose estimated, oriented normals agree in sign (the
/// orientation's own count over the whole graph, as the summary prints it) before a warning:
/// the threshold of file normals and of `mlscurv info`. Estimated normals measured with the
/// default orientation: the bunny 100.00 %, the aerial tile 99.91 % (`up`), the generated
/// airborne scene 99.96 %, noisy random samples of spheres, ellipsoids, tori and height fields
/// 100.00 % (`cargo xtask validate`); an orientation that fails, such as a spanning tree that
/// prefers aligned normals to opposed ones (weights `1 − nᵢ·nⱼ`), left 63.57 % on the bunny
/// with every curvature's sign flipped in most of it, and a fraction f of isolated flips gives
/// 1 − 2f(1 − f) (98 % at 1 %). `docs/orientation.md`.
pub const MIN_ESTIMATED_CONSISTENCY: f64 = 0.99;

/// The warning for estimated normals whose oriented neighbour pairs agree in sign at the share
/// `agree` only, if it is below `MIN_ESTIMATED_CONSISTENCY`. The run goes on: the normals are
/// the best the rule found, and the summary says how far they agree.
pub fn estimated_normals_warning(agree: f64, file: &str) -> Option<String> {
    (agree < MIN_ESTIMATED_CONSISTENCY).then(|| {
        format!(
            "{file}: the estimated normals are not consistently oriented: only {:.2}% of \
             neighbouring pairs agree in sign (at least {:.0}% expected), so curvature has the \
             wrong sign where the orientation flipped; check the --orient rule (mst for a \
             closed object, up or viewpoint:X,Y,Z for a scan seen from one side) or give \
             normals in the file",
            100.0 * agree,
            100.0 * MIN_ESTIMATED_CONSISTENCY
        )
    })
}

/// A warning when the file's `normals` (by input index) are not consistently oriented: both
/// estimators take them as they are, so the curvature near a flipped normal is wrong in sign
/// and size, and nothing else would say so (`mlscurv info` does, with the whole graph).
pub fn check_file_normals(
    cloud: &IndexedCloud<'_>,
    normals: impl Fn(usize) -> Option<Vector> + Sync,
    file: &str,
) -> Option<String> {
    file_normals_warning(file_normals_agreement(cloud, normals)?, file)
}

/// The share of sampled neighbour pairs whose file `normals` agree in sign, as
/// [`check_file_normals`] measures it (`None` when no pair has two normals).
pub fn file_normals_agreement(
    cloud: &IndexedCloud<'_>,
    normals: impl Fn(usize) -> Option<Vector> + Sync,
) -> Option<f64> {
    sampled_consistency(
        cloud,
        DEFAULT_NEIGHBOURS,
        CONSISTENCY_SAMPLE,
        Parallelism::Rayon,
        normals,
    )
}

/// [`check_file_normals`]'s warning for a measured agreement `agree`, if it is too low.
pub fn file_normals_warning(agree: f64, file: &str) -> Option<String> {
    (agree < MIN_FILE_CONSISTENCY).then(|| {
        format!(
            "{file}: the file's normals are not consistently oriented: only {:.1}% of \
             neighbouring pairs agree in sign (at least {:.0}% expected); they are used as they \
             are, so curvature near the flipped ones is wrong in sign and size. Use \
             `--normals estimate` to estimate and orient normals from the points",
            100.0 * agree,
            100.0 * MIN_FILE_CONSISTENCY
        )
    })
}

/// The scanner position of each point of an E57 input whose scans all have a pose, for the
/// default orientation ([`normals`]); `None` for other inputs.
pub fn scan_viewpoints(cloud: &PointCloud) -> Option<Vec<Point>> {
    let viewpoints = cloud.scans.as_ref()?.viewpoints()?;
    Some(viewpoints.into_iter().map(Point::from).collect())
}

/// Normals from `file_normals` (the file's, consumed here so that they are not held beside
/// the converted ones) or estimated from `points`, as `mode` says, and oriented as
/// `orientation` says; without one (the default), towards `viewpoints` (one per point: each
/// point's own scanner, [`scan_viewpoints`]) if given, else outward. `cloud`, `points`
/// indexed, serves the estimation's neighbour search when given.
#[allow(clippy::too_many_arguments)]
pub fn normals(
    file_normals: Option<Vec<[f64; 3]>>,
    points: &[Point],
    cloud: Option<&IndexedCloud<'_>>,
    mode: NormalsMode,
    orientation: Option<Orientation>,
    viewpoints: Option<&[Point]>,
    h: f64,
    par: Parallelism,
    file: &str,
) -> Result<Normals> {
    let from_file = match (mode, file_normals) {
        (NormalsMode::File, None) => {
            bail!("{file}: --normals file given but the file has no normals (nx, ny, nz)")
        }
        (NormalsMode::File | NormalsMode::Auto, Some(n)) => Some(n),
        _ => None,
    };
    if let Some(file_normals) = from_file {
        let normals: Vec<Option<Vector>> = file_normals
            .into_iter()
            .map(|n| {
                mls_core::UnitNormal::new(Vector::from(n))
                    .ok()
                    .map(|u| u.into_inner())
            })
            .collect();
        let bad = normals.iter().filter(|n| n.is_none()).count();
        let source = if bad == 0 {
            "from the file".to_string()
        } else {
            format!("from the file ({bad} zero normals left out of the surface)")
        };
        return Ok(Normals {
            normals,
            source,
            from_file: true,
            warning: None,
        });
    }
    // Per-scan viewpoints: estimated unoriented, then oriented by the per-point vote.
    let per_scan = match (orientation, viewpoints) {
        (None, Some(v)) => Some(v),
        _ => None,
    };
    let defaulted = orientation.is_none() && per_scan.is_none();
    let mut orientation = orientation.unwrap_or_default();
    let config = NormalsConfig {
        k: DEFAULT_NEIGHBOURS,
        h: Some(h),
        orientation: if per_scan.is_some() {
            Orientation::None
        } else {
            orientation
        },
        ..NormalsConfig::default()
    };
    let mut est = match cloud {
        Some(cloud) => estimate_normals_on(cloud, points, &config, par),
        None => estimate_normals(points, &config, par),
    }
    .with_context(|| format!("{file}: normal estimation"))?;
    if let Some(viewpoints) = per_scan {
        est.report =
            orient_normals_towards(points, &est.graph, &mut est.estimates, viewpoints, par)
                .with_context(|| format!("{file}: normal orientation"))?;
    }
    // The default outward rule, on a sheet seen from above, gives way to `up`.
    let mut chosen = String::new();
    if defaulted && let Some(level) = seen_from_above(&est) {
        est.report = orient_normals(points, &est.graph, &mut est.estimates, Orientation::Up, par)
            .with_context(|| format!("{file}: normal orientation"))?;
        orientation = Orientation::Up;
        chosen = format!(
            " (default for a sheet seen from above: outward left {level:.1}% of the normals \
             within 60° of vertical on one side; --orient mst for outward)"
        );
    }
    let orient = match orientation {
        _ if per_scan.is_some() => "oriented towards each scan's scanner position (E57 pose) by \
            minimum spanning tree and a vote per smooth patch"
            .to_string(),
        Orientation::Outward => "oriented outward by minimum spanning tree".to_string(),
        Orientation::Viewpoint(v) => format!(
            "oriented towards the viewpoint ({}, {}, {}) by minimum spanning tree and a vote per smooth patch",
            v.x, v.y, v.z
        ),
        Orientation::Up => {
            format!("oriented up (+z) by minimum spanning tree and a vote per smooth patch{chosen}")
        }
        Orientation::None => "not oriented (--orient none)".to_string(),
    };
    let r = &est.report;
    let mut checks = Vec::new();
    if let Some(f) = r.facing {
        let towards = match orientation {
            _ if per_scan.is_some() => "face their scanner",
            Orientation::Up => "point up",
            _ => "face the viewpoint",
        };
        if let Some(share) = f.share() {
            checks.push(format!("{:.2}% of normals {towards}", 100.0 * share));
        }
        if let Some(share) = f.decisive_share() {
            checks.push(format!(
                "{:.2}% of the {} within 60° of the line of sight",
                100.0 * share,
                f.decisive
            ));
        }
    }
    if let Some(c) = r.consistency {
        checks.push(format!("{:.2}% of neighbour pairs agree", 100.0 * c));
    }
    let pieces = if r.patches > r.components {
        format!("{} component(s) in {} patches", r.components, r.patches)
    } else {
        format!("{} component(s)", r.components)
    };
    let checks = if checks.is_empty() {
        String::new()
    } else {
        format!(", {}", checks.join(", "))
    };
    let source = format!(
        "estimated (weighted covariance, {} neighbours), {orient}: {pieces}{checks}; {} failed",
        DEFAULT_NEIGHBOURS,
        est.failed()
    );
    // `--orient none` asks for the signs as estimated: no warning about them.
    let warning = r
        .consistency
        .filter(|_| per_scan.is_some() || orientation != Orientation::None)
        .and_then(|c| estimated_normals_warning(c, file));
    Ok(Normals {
        normals: est.normals().into_iter().map(Result::ok).collect(),
        source,
        from_file: false,
        warning,
    })
}

/// Whether a cloud oriented outward is a sheet seen from above rather than a closed object,
/// and then the share (%) of its normals within 60° of vertical that lie on the majority's
/// side of the horizontal.
///
/// A closed surface has no net flux: over it `Σ n_z` cancels, and about half of its normals
/// within 60° of vertical point down (the bunny 47 %, a sphere 50 %). An open sheet that is a
/// height field, such as terrain and roofs seen from above, has them nearly all on one side
/// (the aerial tile in `tests/data` 95.5 % up after the outward rule, which carried the sign
/// across creases wrongly for the rest, and so flipped their curvature). The sheet is
/// recognised when at least three quarters lie on one side, halfway between the two; on it
/// `up` is the orientation a scan from above has, and outward (away from the centroid) is not
/// defined. Fewer than 100 such normals decide nothing.
fn seen_from_above(est: &EstimatedNormals) -> Option<f64> {
    let (mut level, mut up) = (0usize, 0usize);
    for e in est.estimates.iter().flatten() {
        let z = e.normal.into_inner().z;
        if z.abs() >= 0.5 {
            level += 1;
            up += usize::from(z > 0.0);
        }
    }
    let majority = up.max(level - up) as f64 / level as f64;
    (level >= 100 && majority >= 0.75).then_some(100.0 * majority)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimated_normals_are_warned_about_below_99_percent_of_pairs_agreeing() {
        // The bunny with the spanning tree's weights 1 − nᵢ·nⱼ: 63.57 % (issue 40).
        let w = estimated_normals_warning(0.6357, "bunny.ply").expect("a warning");
        assert!(w.contains("bunny.ply: the estimated normals are not consistently oriented"));
        assert!(w.contains("63.57%"), "{w}");
        assert!(estimated_normals_warning(0.9899, "x").is_some());
        // Consistent clouds measured 99.90–100 %.
        assert!(estimated_normals_warning(0.99, "x").is_none());
        assert!(estimated_normals_warning(0.999, "x").is_none());
        assert!(estimated_normals_warning(1.0, "x").is_none());
    }
}
