//! The studies: error against density (Figure 8), the choice of h and the kernel cutoff
//! (Section 6).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use mls_core::normals::{DEFAULT_SPACING_NEIGHBOURS, spacing_statistics};
use mls_core::{Cutoff, Location, MlsConfig, Parallelism};
use mls_shapes::BSplineSurface;

use mls_render::{Axis, Series};

use super::evaluate::{adaptive, fixed};
use super::shapes::{patch_case, torus_case};
use super::tables::pm;

/// Figure 8: NURBS 1 at growing density with h proportional to the spacing.
pub(super) fn density_study(quick: bool, md: &mut String, fig_dir: &Path) -> Result<()> {
    let sizes: &[usize] = if quick {
        &[60, 90, 120]
    } else {
        &[100, 150, 200, 300, 400, 600]
    };
    md.push_str("## Figure 8: error against sampling density (NURBS 1)\n\nn × n grid, h = 2/n (the paper's rule h_i = 60/n_i, scaled to our patch), exact normals.\n\n| n | h | fixed, input: k1 μ ± σ | k2 μ ± σ | fixed, projected | adaptive, projected: k1 | k2 |\n| --- | --- | --- | --- | --- | --- | --- |\n");
    let mut series: Vec<Series> = [
        "k1 σ, fixed h",
        "k2 σ, fixed h",
        "k1 σ, adaptive",
        "k2 σ, adaptive",
    ]
    .iter()
    .map(|s| Series {
        name: (*s).into(),
        points: Vec::new(),
    })
    .collect();
    for &n in sizes {
        let h = 2.0 / n as f64;
        let case = patch_case(
            "NURBS 1",
            BSplineSurface::nurbs1(),
            n,
            h,
            None,
            String::new(),
        );
        let fi = case.fixed_errors(h, Location::Input)?;
        let fp = case.fixed_errors(h, Location::Projected)?;
        let ap = case
            .errors(&adaptive(&case, &case.exact, Location::Projected)?, true)
            .0;
        writeln!(
            md,
            "| {n} | {h:.4} | {} | {} | k1 {} | {} | {} |",
            pm(fi.k1),
            pm(fi.k2),
            pm(fp.k1),
            pm(ap.k1),
            pm(ap.k2)
        )?;
        let x = n as f64;
        series[0].points.push((x, fi.k1.1));
        series[1].points.push((x, fi.k2.1));
        series[2].points.push((x, ap.k1.1));
        series[3].points.push((x, ap.k2.1));
    }
    mls_render::line_chart_png(
        &fig_dir.join("figure8-density.png"),
        "NURBS 1: error σ against density (h = 2/n)",
        &Axis::linear("n (points per direction)"),
        &Axis::log("σ of the curvature error"),
        &series,
        (640, 440),
    )?;
    md.push_str("\n![error against density](figures/figure8-density.png)\n\n");
    Ok(())
}

/// h / spacing from 1 to 4 on the torus, clean and noisy.
pub(super) fn h_study(quick: bool, md: &mut String) -> Result<()> {
    md.push_str("## The choice of h (Section 6): the torus\n\nh as a multiple of the median local spacing (`spacing_statistics`), exact normals.\n\n| noise σ | h / spacing | input: k1 μ ± σ | k2 μ ± σ | projected: k1 μ ± σ | k2 μ ± σ |\n| --- | --- | --- | --- | --- | --- |\n");
    for sigma in [0.0, 1e-3] {
        let case = torus_case(quick, sigma);
        let spacing =
            spacing_statistics(&case.points, DEFAULT_SPACING_NEIGHBOURS, Parallelism::Rayon)?
                .spacing;
        for factor in [1.0, 1.5, 2.0, 3.0, 4.0] {
            let h = factor * spacing;
            let i = case.fixed_errors(h, Location::Input)?;
            let p = case.fixed_errors(h, Location::Projected)?;
            writeln!(
                md,
                "| {sigma:e} | {factor} | {} | {} | {} | {} |",
                pm(i.k1),
                pm(i.k2),
                pm(p.k1),
                pm(p.k2)
            )?;
        }
    }
    md.push('\n');
    Ok(())
}

/// Kernel truncation from 3h to 7h on the torus at the paper's h.
pub(super) fn cutoff_study(quick: bool, md: &mut String) -> Result<()> {
    md.push_str("## The kernel cutoff: the torus at the paper's h\n\nChange of k1 and k2 against the untruncated kernel (every sample contributes), at the input points, exact normals.\n\n| cutoff | max abs change of k1 | of k2 | k1 error μ ± σ |\n| --- | --- | --- | --- |\n");
    let case = torus_case(quick, 0.0);
    let reference = fixed(
        &case,
        &case.exact,
        MlsConfig {
            cutoff: Cutoff::None,
            ..MlsConfig::new(case.h)
        },
        Location::Input,
    )?;
    for c in [3.0, 4.0, 5.0, 6.0, 7.0] {
        let out = fixed(
            &case,
            &case.exact,
            MlsConfig {
                cutoff: Cutoff::Radius(c),
                ..MlsConfig::new(case.h)
            },
            Location::Input,
        )?;
        let (mut d1, mut d2) = (0.0f64, 0.0f64);
        for (a, b) in out.iter().zip(&reference) {
            if let (Some(a), Some(b)) = (a, b) {
                d1 = d1.max((a.1 - b.1).abs());
                d2 = d2.max((a.2 - b.2).abs());
            }
        }
        let e = case.errors(&out, false).0;
        writeln!(md, "| {c}h | {d1:.1e} | {d2:.1e} | {} |", pm(e.k1))?;
    }
    md.push('\n');
    Ok(())
}
