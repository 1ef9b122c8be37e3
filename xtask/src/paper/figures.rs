//! The figures: curvature and error maps of each shape, the scale the adaptive method chose
//! on the noisy torus, and the bunny (Figure 7's counterpart).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use mls_core::normals::{DEFAULT_SPACING_NEIGHBOURS, spacing_statistics};
use mls_core::{
    AdaptiveConfig, Location, MlsConfig, MlsSurface, NormalsConfig, Parallelism, Point, Vector,
    adaptive_curvature, estimate_normals,
};

use mls_render::{ColourScale, Panel, Up, View};

use super::Case;
use super::tables::Maps;

pub(super) fn shape_figure(case: &Case, maps: &Maps, dir: &Path, file: &str) -> Result<()> {
    let pts: Vec<[f64; 3]> = case
        .queries
        .iter()
        .map(|&i| case.points[i].coords.into())
        .collect();
    let nrm: Vec<[f64; 3]> = case.queries.iter().map(|&i| case.exact[i].into()).collect();
    let k1: Vec<f64> = maps.k.iter().map(|k| k.0).collect();
    let k2: Vec<f64> = maps.k.iter().map(|k| k.1).collect();
    // One symmetric error scale for all four error panels, so that fixed and adaptive compare.
    let all: Vec<f64> = [
        &maps.fixed.0,
        &maps.fixed.1,
        &maps.adaptive.0,
        &maps.adaptive.1,
    ]
    .iter()
    .flat_map(|v| v.iter().copied())
    .collect();
    let err = ColourScale::robust_symmetric(&all, "error");
    let panels = vec![
        Panel {
            title: "k1".into(),
            legend: ColourScale::robust_sequential(&k1, "k1").into(),
            values: k1,
        },
        Panel {
            title: "k2".into(),
            legend: ColourScale::robust_sequential(&k2, "k2").into(),
            values: k2,
        },
        Panel {
            title: "k1 error, fixed h, input".into(),
            values: maps.fixed.0.clone(),
            legend: err.clone().into(),
        },
        Panel {
            title: "k2 error, fixed h, input".into(),
            values: maps.fixed.1.clone(),
            legend: err.clone().into(),
        },
        Panel {
            title: "k1 error, adaptive, projected".into(),
            values: maps.adaptive.0.clone(),
            legend: err.clone().into(),
        },
        Panel {
            title: "k2 error, adaptive, projected".into(),
            values: maps.adaptive.1.clone(),
            legend: err.into(),
        },
    ];
    mls_render::splat_panels_png(
        &dir.join(file),
        &format!("{}: {}", case.name, case.setup),
        mls_render::Cloud {
            points: &pts,
            normals: Some(&nrm),
        },
        &panels,
        case.view,
        (400, 360),
        2,
    )
}

/// Where the adaptive scale went on the noisy torus.
pub(super) fn chosen_scale_figure(case: &Case, fig_dir: &Path, md: &mut String) -> Result<()> {
    let q = case.query_points(&case.points);
    let results = adaptive_curvature(
        &case.points,
        &case.exact,
        &q,
        Location::Input,
        &AdaptiveConfig::new(case.h),
        Parallelism::Rayon,
    )?;
    let ratio: Vec<f64> = results
        .iter()
        .map(|r| r.as_ref().map_or(f64::NAN, |p| p.h / case.h))
        .collect();
    let pts: Vec<[f64; 3]> = q.iter().map(|p| p.coords.into()).collect();
    let nrm: Vec<[f64; 3]> = case.queries.iter().map(|&i| case.exact[i].into()).collect();
    mls_render::splat_png(
        &fig_dir.join("torus-noise-1e-3-scale.png"),
        "Noisy torus σ = 1e-3: scale chosen at the input points",
        mls_render::Cloud {
            points: &pts,
            normals: Some(&nrm),
        },
        &ratio,
        &ColourScale {
            min: 1.0,
            max: 4.0,
            label: "chosen h / base h".into(),
            kind: mls_render::ScaleKind::Sequential,
        },
        case.view,
        (560, 460),
    )?;
    md.push_str("![chosen scale](figures/torus-noise-1e-3-scale.png)\n\n");
    Ok(())
}

/// Figure 7's counterpart: k1 and k2 on the real bunny scan, normals estimated.
pub(super) fn bunny(md: &mut String, fig_dir: &Path) -> Result<()> {
    let path = Path::new("tests/data/bunny-stanford.ply");
    let cloud =
        mls_io::read_point_cloud(path).with_context(|| format!("reading {}", path.display()))?;
    let points: Vec<Point> = cloud.points.iter().map(|p| Point::from(*p)).collect();
    let spacing =
        spacing_statistics(&points, DEFAULT_SPACING_NEIGHBOURS, Parallelism::Rayon)?.spacing;
    let h = 2.0 * spacing;
    let est = estimate_normals(
        &points,
        &NormalsConfig {
            h: Some(h),
            ..NormalsConfig::default()
        },
        Parallelism::Rayon,
    )?;
    let (pts, nrm): (Vec<Point>, Vec<Vector>) = points
        .iter()
        .zip(est.normals())
        .filter_map(|(p, n)| n.ok().map(|n| (*p, n)))
        .unzip();
    let surface = MlsSurface::new(&pts, &nrm, MlsConfig::new(h))?;
    let results = surface.curvature_at_points(&pts, Parallelism::Rayon);
    let k1: Vec<f64> = results
        .iter()
        .map(|r| r.as_ref().map_or(f64::NAN, |s| s.curvature.k1))
        .collect();
    let k2: Vec<f64> = results
        .iter()
        .map(|r| r.as_ref().map_or(f64::NAN, |s| s.curvature.k2))
        .collect();
    // The scan's y axis is up; the renderer's is z.
    let up = |v: &Vector| [v.x, -v.z, v.y];
    let splat: Vec<[f64; 3]> = pts.iter().map(|p| up(&p.coords)).collect();
    let normals: Vec<[f64; 3]> = nrm.iter().map(up).collect();
    let both: Vec<f64> = k1.iter().chain(&k2).copied().collect();
    let scale = ColourScale::robust_symmetric(&both, "curvature (1/m)");
    let panels = vec![
        Panel {
            title: "k1".into(),
            values: k1,
            legend: scale.clone().into(),
        },
        Panel {
            title: "k2".into(),
            values: k2,
            legend: scale.into(),
        },
    ];
    mls_render::splat_panels_png(
        &fig_dir.join("bunny.png"),
        &format!(
            "Stanford bunny scan, {} points, normals estimated, h = {h:.2e}",
            pts.len()
        ),
        mls_render::Cloud {
            points: &splat,
            normals: Some(&normals),
        },
        &panels,
        View {
            azimuth_deg: -90.0,
            elevation_deg: 10.0,
            up: Up::Z,
        },
        (420, 420),
        2,
    )?;
    writeln!(
        md,
        "## Figure 7's counterpart: a real scan\n\nThe Stanford bunny (`tests/data/bunny-stanford.ply`, {} points), normals estimated and oriented by `mlscurv`'s estimator, h = 2 spacings = {h:.2e}, curvature at the input points; one symmetric colour scale for both maps.\n\n![bunny](figures/bunny.png)\n",
        pts.len()
    )?;
    Ok(())
}
