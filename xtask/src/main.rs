//! Project tasks: `cargo xtask <task>`. Run without a task for the list.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

mod accuracy;
mod bench;
mod bench_tiled;
mod defaults;
mod faults;
mod gen_cloud;
mod paper;
mod robustness;
mod validate;
mod validate_adaptive;
mod validate_formulas;
mod validate_jet;
mod validate_shapes;
mod validate_sweep;

const TASKS: &str = "\
Tasks:
  validate [--quick] [--seed N] [--evals N] [--replay SEED] [--differential-only]
                 Production entry points against the witnesses of mls-ad on seeded random
                 clouds, analytic shapes, then the robustness sweep.
                 Writes target/validate/report.md. --quick: a small run for CI.
  faults [NAME-PREFIX...]
                 Applies each fault (a misreading of the paper, or a 1e-9 perturbation of one
                 term) to a copy of the workspace and checks that `validate --quick
                 --differential-only` reports it; only the named ones if prefixes are given.
                 Writes target/validate/faults.md.
  robustness [--quick] [--clouds N] [--seed N] [--replay SEED] [--fuzz SECONDS]
                 mls-core on 10,000 adversarial clouds (--quick: 400); --fuzz also runs each
                 cargo-fuzz reader target for SECONDS. Writes target/robustness/report.md.
  bench [--quick] Throughput, memory and scaling against issue 5's targets; writes
                 docs/benchmarks.md. --quick: small clouds, writes target/bench/quick.md.
  bench-tiled [--quick] [--points N] [--memory SIZE] [--io-only]
                 Clouds larger than memory: gen-cloud clouds of N/10 and N points
                 (default 10^8) tiled in SIZE (default 2GiB) against in-memory runs, the jet
                 tiled, LAZ read + write; writes the out-of-core section of docs/benchmarks.md.
                 --io-only: the LAZ read + write timing alone, replacing its line there.
  defaults       The measurements behind mlscurv's defaults (--h-factor, --at); writes docs/defaults.md.
  paper [--quick] [--check]
                 The paper's Tables 1-2, Figure 8, h and cutoff studies, adaptive h and figures;
                 writes docs/paper.md and docs/figures/. --check: fails if docs/paper.md is stale.
                 --quick: reduced densities into target/paper/.
  accuracy [--seeds N]
                 Every estimator on random, jittered, grid, scanline and noisy clouds against
                 the analytic truth; writes docs/accuracy.md.
  accuracy-explore [CLOUD]
                 The same clouds with several jet settings, printed (for studies); with
                 JET_DIAG=1 also the make-up of the predicted error by decile.
  gen-cloud --points N -o OUT.las|OUT.laz [--seed S] [--noise SIGMA] [--normals] [--tiles RxC]
                 A seeded airborne-LiDAR test cloud (terrain, buildings, trees, scan strips) of
                 exactly N points, streamed as LAS 1.4 point format 6 or LAZ; --normals adds the
                 true normals as f64 extra bytes nx ny nz; --tiles writes OUT_r{i}_c{j}.laz.
                 A relative OUT is taken from the directory the task was run from.
  ci             fmt --check, clippy -D warnings, tests, validate --quick.";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // Outputs named on the command line are relative to where the task was run.
    let invoked_from = std::env::current_dir().context("cannot read the current directory")?;
    std::env::set_current_dir(project_root()).context("cannot change to the project root")?;
    let Some(task) = args.first() else {
        println!("{TASKS}");
        return Ok(());
    };
    if matches!(task.as_str(), "--help" | "-h" | "help") {
        println!("{TASKS}");
        return Ok(());
    }
    let rest = &args[1..];
    match task.as_str() {
        "validate" => validate::run(&validate::Options::parse(rest)?),
        "accuracy" => accuracy::run(rest),
        "accuracy-explore" => accuracy::explore(rest),
        "faults" => faults::run(rest),
        "robustness" => robustness::run(&robustness::Options::parse(rest)?),
        "bench" => bench::run(rest),
        "bench-tiled" => bench_tiled::run(rest),
        "defaults" => defaults::run(),
        "paper" => paper::run(&paper::Options::parse(rest)?),
        "gen-cloud" => gen_cloud::run(&gen_cloud::Options::parse(rest, &invoked_from)?),
        "ci" => ci(),
        other => bail!("unknown task `{other}`\n{TASKS}"),
    }
}

/// The workspace root: the xtask manifest's parent.
fn project_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// The cargo that invoked us, so toolchain overrides carry through.
pub(crate) fn cargo() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

pub(crate) fn run_checked(cmd: &mut Command) -> Result<()> {
    let status = cmd
        .status()
        .with_context(|| format!("cannot run {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed with {status}");
    }
    Ok(())
}

fn ci() -> Result<()> {
    run_checked(cargo().args(["fmt", "--all", "--", "--check"]))?;
    run_checked(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]))?;
    run_checked(cargo().args(["test", "--workspace"]))?;
    validate::run(&validate::Options {
        quick: true,
        ..validate::Options::default()
    })
}
