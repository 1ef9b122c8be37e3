//! Project tasks: `cargo xtask <task>`. Run without a task for the list.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};

mod accuracy;
mod accuracy_noisy;
mod bench;
mod bench_tiled;
mod clients;
mod defaults;
mod faults;
mod gen_cloud;
mod paper;
mod robustness;
mod validate;
mod validate_adaptive;
mod validate_defaults;
mod validate_e2e;
mod validate_formulas;
mod validate_jet;
mod validate_orient;
mod validate_shapes;
mod validate_sweep;

/// Project tasks of mls-curvature: validation, benchmarks, studies and test clouds.
#[derive(Debug, clap::Parser)]
#[command(
    name = "cargo xtask",
    bin_name = "cargo xtask",
    arg_required_else_help = true
)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Debug, clap::Subcommand)]
enum Task {
    /// Production entry points against the witnesses of mls-ad on seeded random clouds,
    /// analytic shapes, then the robustness sweep; writes target/validate/report.md.
    Validate(validate::Options),
    /// Applies each fault (a misreading of the paper, or a 1e-9 perturbation of one term) to a
    /// copy of the workspace and checks that `validate --quick --differential-only` reports
    /// it; writes target/validate/faults.md.
    Faults {
        /// Only the faults whose names start with one of these.
        #[arg(value_name = "NAME-PREFIX")]
        only: Vec<String>,
    },
    /// mls-core on 10,000 adversarial clouds; writes target/robustness/report.md.
    Robustness(robustness::Options),
    /// Throughput, memory and scaling against issue 5's targets; writes docs/benchmarks.md.
    Bench {
        /// Small clouds, into target/bench/quick.md.
        #[arg(long)]
        quick: bool,
    },
    /// Clouds larger than memory: gen-cloud clouds of N/10 and N points tiled against
    /// in-memory runs, the jet tiled, LAZ read + write; writes the out-of-core section of
    /// docs/benchmarks.md.
    BenchTiled(bench_tiled::Options),
    /// The measurements behind mlscurv's defaults (--h-factor, --at); writes docs/defaults.md.
    Defaults,
    /// The paper's Tables 1-2, Figure 8, h and cutoff studies, adaptive h and figures; writes
    /// docs/paper.md and docs/figures/.
    Paper(paper::Options),
    /// Every estimator on random, jittered, grid, scanline and noisy clouds against the
    /// analytic truth; writes docs/accuracy.md.
    Accuracy {
        /// Random seeds per cloud (about 25 s each on 2 cores).
        #[arg(long, default_value_t = 5)]
        seeds: u64,
    },
    /// The same clouds with several jet settings, printed (for studies); with JET_DIAG=1 also
    /// the make-up of the predicted error by decile.
    AccuracyExplore {
        /// Only the clouds whose name contains this.
        cloud: Option<String>,
    },
    /// Noisy clouds without normals (noise, outliers, line-of-sight noise, an ellipsoid): the
    /// default jet against the peers a user would tune (issue 37), printed.
    AccuracyNoisy {
        /// Only the clouds whose name contains this.
        cloud: Option<String>,
        /// Also the peers (degree-2 and -4 jets on 50 to 200 neighbours, paper --adaptive).
        #[arg(long)]
        peers: bool,
        /// Write docs/accuracy-noisy.md (with --peers: the whole page).
        #[arg(long)]
        write: bool,
    },
    /// A seeded airborne-LiDAR test cloud (terrain, buildings, trees, scan strips) of exactly
    /// N points, streamed as LAS 1.4 point format 6 or LAZ.
    GenCloud(gen_cloud::Args),
    /// Our outputs opened by CloudCompare, pymeshlab, laspy and numpy, and their files by our
    /// reader: every curvature field by name with our values; skips a program not
    /// installed; writes target/clients/.
    Clients,
    /// What CI runs (.ci/run calls it): fmt --check, clippy -D warnings, rustdoc -D
    /// warnings, the tests, validate --quick, paper --quick, the Python package's tests and
    /// clients.
    Ci,
}

/// A seed or count, decimal or `0x` hexadecimal.
pub(crate) fn parse_u64(text: &str) -> Result<u64> {
    Ok(match text.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16)?,
        None => text.parse()?,
    })
}

fn main() {
    use clap::Parser as _;
    let cli = Cli::parse();
    if let Err(e) = run(cli.task) {
        // One line per cause, no backtrace.
        eprintln!("xtask: error: {e:#}");
        std::process::exit(1);
    }
}

fn run(task: Task) -> Result<()> {
    // Outputs named on the command line are relative to where the task was run.
    let invoked_from = std::env::current_dir().context("cannot read the current directory")?;
    std::env::set_current_dir(project_root()).context("cannot change to the project root")?;
    match task {
        Task::Validate(o) => validate::run(&o),
        Task::Faults { only } => faults::run(&only),
        Task::Robustness(o) => robustness::run(&o),
        Task::Bench { quick } => bench::run(quick),
        Task::BenchTiled(o) => bench_tiled::run(&o),
        Task::Defaults => defaults::run(),
        Task::Paper(o) => paper::run(&o),
        Task::Accuracy { seeds } => accuracy::run(seeds),
        Task::AccuracyExplore { cloud } => accuracy::explore(cloud.as_ref()),
        Task::AccuracyNoisy {
            cloud,
            peers,
            write,
        } => accuracy_noisy::explore(cloud.as_ref(), peers, write),
        Task::GenCloud(args) => gen_cloud::run(&args.options(&invoked_from)),
        Task::Clients => clients::run(),
        Task::Ci => ci(),
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

/// The one CI definition, which `.ci/run` calls after its installs: format, lints, the
/// README's test command, the quick validation, the paper task at reduced density, the
/// Python package's suite and the other programs on our files.
fn ci() -> Result<()> {
    run_checked(cargo().args(["fmt", "--all", "--", "--check"]))?;
    run_checked(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--locked",
        "--",
        "-D",
        "warnings",
    ]))?;
    // The API docs' links (a link to a private or renamed item is an error).
    run_checked(
        cargo()
            .args([
                "doc",
                "--workspace",
                "--no-deps",
                "--locked",
                "--exclude",
                "mls-py",
            ])
            .env("RUSTDOCFLAGS", "-D warnings"),
    )?;
    // The README's test command.
    run_checked(cargo().args(["test", "--workspace", "--locked"]))?;
    // Closed form against hyper-dual AD, and the analytic shapes.
    validate::run(&validate::Options {
        quick: true,
        ..validate::Options::default()
    })?;
    // The paper task end to end (tables and figures into target/paper/).
    paper::run(&paper::Options::quick())?;
    // The Python package: pip install with maturin, and its pytest suite.
    run_checked(&mut Command::new(".ci/python"))?;
    // CloudCompare, pymeshlab, laspy and numpy on our files (each skipped if not installed;
    // .ci/run installs them).
    clients::run()
}
