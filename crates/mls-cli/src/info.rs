//! `mlscurv info`: what a cloud holds and how the other commands would read it.

use std::fmt::Write as _;

use anyhow::{Context as _, Result, anyhow};
use mls_core::normals::{DEFAULT_NEIGHBOURS, NeighbourGraph, orientation_consistency};
use mls_core::{IndexedCloud, Parallelism, Vector};

use mls_pipeline::pipeline::{self, Length};

use crate::InfoArgs;

pub fn info(a: InfoArgs) -> Result<()> {
    // The report is collected and written at once: `println!` panics when the reader of a pipe
    // (`mlscurv info x.ply | head -3`) has gone.
    let mut out = String::new();
    let result = info_report(&a, &mut out);
    pipeline::write_stdout(out.as_bytes())?;
    result
}

fn info_report(a: &InfoArgs, out: &mut String) -> Result<()> {
    // Writing to a String cannot fail.
    macro_rules! println {
        ($($arg:tt)*) => {{
            let _ = writeln!(out, $($arg)*);
        }};
    }
    let cloud = pipeline::read_any(&a.input, a.input_format.map(Into::into), a.columns.as_ref())?;
    let points = pipeline::to_points(&cloud);
    println!("file            {}", pipeline::input_name(&a.input));
    println!("points          {}", points.len());
    if points.is_empty() {
        return Ok(());
    }
    let (lo, hi) = points
        .iter()
        .fold((points[0].coords, points[0].coords), |(lo, hi), p| {
            (lo.inf(&p.coords), hi.sup(&p.coords))
        });
    println!(
        "bounding box    [{}, {}, {}] .. [{}, {}, {}]",
        Length(lo.x),
        Length(lo.y),
        Length(lo.z),
        Length(hi.x),
        Length(hi.y),
        Length(hi.z)
    );
    let size = hi - lo;
    println!(
        "size            {} × {} × {}",
        Length(size.x),
        Length(size.y),
        Length(size.z)
    );
    let name = pipeline::input_name(&a.input);
    // One tree for the spacing and the normals' neighbour graph, as in the other commands.
    let indexed = IndexedCloud::new(&points, Parallelism::Rayon)
        .map_err(anyhow::Error::from)
        .with_context(|| name.clone());
    let scale = indexed
        .as_ref()
        .map_err(|e| anyhow!("{e:#}"))
        .and_then(|c| {
            pipeline::choose_h_on(
                c,
                None,
                mls_core::normals::DEFAULT_H_FACTOR,
                Parallelism::Rayon,
                &name,
            )
        });
    // The commands derive h from a sample of a large cloud; the statistics here are over
    // every point (their extremes and the duplicates need all of them).
    let full = indexed.as_ref().ok().map(|c| {
        c.spacing_statistics(
            mls_core::normals::DEFAULT_SPACING_NEIGHBOURS,
            Parallelism::Rayon,
        )
    });
    match scale {
        Ok(scale) => {
            if let Some(Ok(s)) = full {
                println!(
                    "spacing         {} (median local); nearest neighbour min {}, median {}, p90 {}, max {}",
                    Length(s.spacing),
                    Length(s.nearest.min),
                    Length(s.nearest.median),
                    Length(s.nearest.p90),
                    Length(s.nearest.max)
                );
                println!("duplicates      {}", s.duplicates);
            }
            println!("suggested h     {} = {}", Length(scale.h), scale.why);
        }
        Err(e) => println!("spacing         unavailable: {e:#}"),
    }
    match &cloud.normals {
        None => println!("normals         absent (curvature will estimate and orient them)"),
        Some(n) => {
            let normals: Vec<Vector> = n.iter().map(|n| Vector::from(*n)).collect();
            let zero = normals
                .iter()
                .filter(|n| mls_core::UnitNormal::new(**n).is_err())
                .count();
            let graph =
                NeighbourGraph::build_on(&indexed?, DEFAULT_NEIGHBOURS, Parallelism::Rayon)?;
            let consistency =
                orientation_consistency(&points, &graph, &normals, Parallelism::Rayon)?;
            let verdict = match consistency {
                Some(c) if c >= 0.99 => format!(
                    "consistently oriented ({:.2}% of neighbour pairs agree)",
                    100.0 * c
                ),
                Some(c) => format!(
                    "NOT consistently oriented: {:.2}% of neighbour pairs agree (use --normals estimate)",
                    100.0 * c
                ),
                None => "orientation unknown (no neighbour pairs with normals)".into(),
            };
            println!("normals         present, {zero} zero or invalid; {verdict}");
        }
    }
    if let Some(scans) = &cloud.scans {
        let posed = scans.origins.iter().filter(|o| o.is_some()).count();
        let default = if posed == scans.origins.len() {
            "estimated normals face each point's own scanner by default"
        } else {
            "not every scan has a pose: estimated normals are oriented outward (mst), or up \
             for a sheet seen from above, by default"
        };
        println!(
            "scans           {} ({posed} with a pose); {default}",
            scans.origins.len()
        );
        for (s, origin) in scans.origins.iter().enumerate() {
            if let Some([x, y, z]) = origin {
                println!(
                    "  scan {s:<9} scanner at ({}, {}, {})",
                    Length(*x),
                    Length(*y),
                    Length(*z)
                );
            }
        }
    }
    if !cloud.attributes.is_empty() {
        let list: Vec<String> = cloud
            .attributes
            .iter()
            .map(|a| format!("{} ({})", a.name, a.data.ty().name()))
            .collect();
        println!(
            "attributes      {} (carried to the output): {}",
            list.len(),
            list.join(", ")
        );
    }
    Ok(())
}
