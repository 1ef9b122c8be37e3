//! The rows of Tables 1 and 2, and the number formats of every table.

use std::fmt::Write as _;

use anyhow::{Context, Result};
use mls_core::{Location, MlsConfig, MlsSurface, correct_shrinkage};

use super::evaluate::{adaptive, estimated_normals, evaluate_fixed, outcome};
use super::{Case, Errors, Outcome};

fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:+.2e}")
    }
}

/// `μ ± σ` of an error.
pub(super) fn pm((mean, std): (f64, f64)) -> String {
    format!("{} ± {std:.2e}", sci(mean))
}

pub(super) fn ratio(ours: f64, paper: f64) -> String {
    if paper.abs() > 0.0 {
        let r = ours.abs() / paper.abs();
        if r < 1e3 {
            format!("{r:.2}")
        } else {
            format!("{r:.1e}")
        }
    } else {
        "—".into()
    }
}

/// The rows of one shape: fixed h and adaptive, exact and estimated normals, input and
/// projected points. Returns the rows and the error maps of (fixed input, adaptive) for the
/// figures.
pub(super) struct Maps {
    pub(super) k: Vec<(f64, f64)>,
    pub(super) fixed: (Vec<f64>, Vec<f64>),
    pub(super) adaptive: (Vec<f64>, Vec<f64>),
}

pub(super) fn shape_rows(case: &Case, md: &mut String) -> Result<(Maps, Errors, Errors)> {
    let t0 = std::time::Instant::now();
    let h = case.h;
    let estimated = estimated_normals(&case.points, &case.exact, h)?;
    writeln!(md, "### {}\n\n{}.\n", case.name, case.setup)?;
    writeln!(
        md,
        "| normals | h | at | k1 error μ | σ | k2 error μ | σ | failed |\n| --- | --- | --- | --- | --- | --- | --- | --- |"
    )?;
    if let Some([a, b, c, d]) = case.paper {
        writeln!(
            md,
            "| **paper** | theirs | ? | {} | {} | {} | {} | |",
            sci(a),
            sci(b).trim_start_matches('+'),
            sci(c),
            sci(d).trim_start_matches('+')
        )?;
    }
    let mut maps = None;
    let mut best_fixed = Errors::default();
    let mut best_adaptive = Errors::default();
    for (label, normals) in [("exact", &case.exact), ("estimated", &estimated)] {
        // One surface for the three fixed-h rows; the corrected row reuses the projection.
        let surface = MlsSurface::new(&case.points, normals, MlsConfig::new(h))?;
        let input = evaluate_fixed(case, &surface, Location::Input);
        let projected = evaluate_fixed(case, &surface, Location::Projected);
        let variants: Vec<(&str, Outcome, bool)> = vec![
            ("input", outcome(&input, h, |c| *c), false),
            ("projected", outcome(&projected, h, |c| *c), true),
            (
                "projected, shrinkage corrected",
                outcome(&projected, h, |c| correct_shrinkage(c, h)),
                true,
            ),
        ];
        let adaptive_variants: Vec<(&str, Outcome, bool)> = vec![
            ("input", adaptive(case, normals, Location::Input)?, false),
            (
                "projected",
                adaptive(case, normals, Location::Projected)?,
                true,
            ),
        ];
        let mut fixed_input_maps = None;
        for (at, outcome, projected) in &variants {
            let (e, m1, m2) = case.errors(outcome, *projected);
            row(md, label, &format!("{h}"), at, &e)?;
            if label == "exact" && *at == "input" {
                best_fixed = e;
                let k = outcome
                    .iter()
                    .map(|r| r.map_or((f64::NAN, f64::NAN), |r| (r.1, r.2)))
                    .collect();
                fixed_input_maps = Some((k, (m1, m2)));
            }
        }
        for (at, outcome, projected) in &adaptive_variants {
            let (e, m1, m2) = case.errors(outcome, *projected);
            row(
                md,
                label,
                &format!("adaptive (mean {:.3})", e.mean_h),
                at,
                &e,
            )?;
            if label == "exact" && *at == "projected" {
                best_adaptive = e;
                if let Some((k, fixed_maps)) = fixed_input_maps.take() {
                    maps = Some(Maps {
                        k,
                        fixed: fixed_maps,
                        adaptive: (m1, m2),
                    });
                }
            }
        }
    }
    md.push('\n');
    eprintln!(
        "paper: {} in {:.1} s",
        case.name,
        t0.elapsed().as_secs_f64()
    );
    Ok((maps.context("no maps")?, best_fixed, best_adaptive))
}

fn row(md: &mut String, normals: &str, h: &str, at: &str, e: &Errors) -> Result<()> {
    writeln!(
        md,
        "| {normals} | {h} | {at} | {} | {:.2e} | {} | {:.2e} | {} |",
        sci(e.k1.0),
        e.k1.1,
        sci(e.k2.0),
        e.k2.1,
        e.failed
    )?;
    Ok(())
}
