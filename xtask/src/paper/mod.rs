//! `cargo xtask paper [--quick] [--check]`: the paper's experiments (Tables 1 and 2, Figure 8,
//! the h and cutoff discussion of Section 6) beside ours, with the adaptive scale, and the
//! figures. Writes `docs/paper.md` and `docs/figures/*.png`; `--check` regenerates the
//! document in memory and fails when the committed one differs; `--quick` runs reduced
//! densities into `target/paper/` for CI.

mod evaluate;
mod figures;
mod report;
mod shapes;
mod studies;
mod tables;

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use mls_core::{Point, Vector};

use mls_render::View;

use report::generate;

/// Seed of every noise draw, so that the document is reproducible bit for bit.
const NOISE_SEED: u64 = 7;

/// Options of `cargo xtask paper`.
#[derive(Clone, Debug, clap::Args)]
pub(crate) struct Options {
    /// Reduced densities, into target/paper/.
    #[arg(long)]
    quick: bool,
    /// Fail if docs/paper.md is stale instead of writing it.
    #[arg(long)]
    check: bool,
}

impl Options {
    /// `--quick`, as CI runs it.
    pub(crate) fn quick() -> Self {
        Self {
            quick: true,
            check: false,
        }
    }
}

/// Exact (k1, k2) at the point of a shape nearest to a point, starting from a sample index.
type Nearest = Box<dyn Fn(&Point, usize) -> (f64, f64) + Sync>;

/// A test cloud with its exact geometry.
struct Case {
    name: &'static str,
    setup: String,
    points: Vec<Point>,
    /// Normals of the clean surface at each sample.
    exact: Vec<Vector>,
    /// Exact (k1, k2) at each sample of the clean surface.
    truth: Vec<(f64, f64)>,
    /// Samples whose errors are counted (and where the curvature is evaluated).
    queries: Vec<usize>,
    h: f64,
    /// Exact (k1, k2) at the point of the shape nearest to `p`, starting from sample `i`.
    nearest: Nearest,
    /// The paper's printed k1 μ, σ, k2 μ, σ.
    paper: Option<[f64; 4]>,
    view: View,
}

/// k1 and k2 errors.
#[derive(Clone, Copy, Debug, Default)]
struct Errors {
    k1: (f64, f64),
    k2: (f64, f64),
    failed: usize,
    mean_h: f64,
}

/// One evaluated variant: per query the evaluation point, (k1, k2) and h, or None.
type Outcome = Vec<Option<(Point, f64, f64, f64)>>;

pub(crate) fn run(options: &Options) -> Result<()> {
    let (doc, fig_dir) = if options.quick {
        (
            PathBuf::from("target/paper/paper.md"),
            PathBuf::from("target/paper/figures"),
        )
    } else if options.check {
        let tmp = PathBuf::from("target/paper-check");
        (tmp.join("paper.md"), tmp.join("figures"))
    } else {
        (
            PathBuf::from("docs/paper.md"),
            PathBuf::from("docs/figures"),
        )
    };
    std::fs::create_dir_all(&fig_dir).with_context(|| format!("creating {}", fig_dir.display()))?;
    let md = generate(options.quick, &fig_dir)?;
    if options.check {
        let committed =
            std::fs::read_to_string("docs/paper.md").context("reading docs/paper.md")?;
        if committed != md {
            std::fs::write(&doc, &md)?;
            bail!(
                "docs/paper.md is stale: `cargo xtask paper` regenerates it (fresh copy in {})",
                doc.display()
            );
        }
        println!("docs/paper.md is up to date");
        return Ok(());
    }
    std::fs::write(&doc, &md).with_context(|| format!("writing {}", doc.display()))?;
    println!(
        "wrote {} and figures in {}",
        doc.display(),
        fig_dir.display()
    );
    Ok(())
}
