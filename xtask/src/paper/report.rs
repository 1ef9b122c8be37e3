//! The document: Tables 1 and 2 with their figures, the comparison with the paper and the
//! studies, between the fixed introduction and conclusion.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use super::figures::{bunny, chosen_scale_figure, shape_figure};
use super::shapes::{cases, torus_case};
use super::studies::{cutoff_study, density_study, h_study};
use super::tables::{ratio, shape_rows};

pub(super) fn generate(quick: bool, fig_dir: &Path) -> Result<String> {
    let mut md = String::from(include_str!("../paper_intro.md"));
    if quick {
        md.push_str("\n**Quick run: densities reduced 4× per direction, h 4× larger.**\n");
    }
    md.push_str("\n## Table 1: synthetic shapes\n\n");
    let mut summary = Vec::new();
    for (case, file) in cases(quick).iter().zip([
        "sphere.png",
        "cylinder.png",
        "torus.png",
        "nurbs1.png",
        "nurbs2.png",
    ]) {
        let (maps, f, a) = shape_rows(case, &mut md)?;
        writeln!(md, "![{}](figures/{file})\n", case.name)?;
        shape_figure(case, &maps, fig_dir, file)?;
        summary.push((case.name, case.paper, f, a));
    }
    md.push_str("## Table 2: the torus with Gaussian noise\n\n");
    for sigma in [1e-4, 1e-3] {
        let case = torus_case(quick, sigma);
        let (maps, f, a) = shape_rows(&case, &mut md)?;
        let file = if sigma == 1e-4 {
            "torus-noise-1e-4.png"
        } else {
            "torus-noise-1e-3.png"
        };
        writeln!(md, "![noisy torus](figures/{file})\n")?;
        shape_figure(&case, &maps, fig_dir, file)?;
        if sigma == 1e-3 {
            chosen_scale_figure(&case, fig_dir, &mut md)?;
        }
        summary.push((
            if sigma == 1e-4 {
                "Torus σ = 1e-4"
            } else {
                "Torus σ = 1e-3"
            },
            case.paper,
            f,
            a,
        ));
    }
    md.push_str("## Against the paper\n\nσ of our errors over the paper's (below 1: we are more exact). Fixed h: exact normals at the input points; adaptive: exact normals at the projected points.\n\n| shape | paper k1 σ | fixed k1 σ (ratio) | adaptive k1 σ (ratio) | paper k2 σ | fixed k2 σ (ratio) | adaptive k2 σ (ratio) |\n| --- | --- | --- | --- | --- | --- | --- |\n");
    for (name, paper, f, a) in &summary {
        let [_, p1, _, p2] = paper.unwrap_or([f64::NAN; 4]);
        writeln!(
            md,
            "| {name} | {p1:.2e} | {:.2e} ({}) | {:.2e} ({}) | {p2:.2e} | {:.2e} ({}) | {:.2e} ({}) |",
            f.k1.1,
            ratio(f.k1.1, p1),
            a.k1.1,
            ratio(a.k1.1, p1),
            f.k2.1,
            ratio(f.k2.1, p2),
            a.k2.1,
            ratio(a.k2.1, p2)
        )?;
    }
    md.push('\n');
    density_study(quick, &mut md, fig_dir)?;
    h_study(quick, &mut md)?;
    cutoff_study(quick, &mut md)?;
    bunny(&mut md, fig_dir)?;
    md.push('\n');
    md.push_str(include_str!("../paper_outro.md"));
    Ok(md)
}
