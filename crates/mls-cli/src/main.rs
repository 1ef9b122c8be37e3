//! `mlscurv`: signed principal curvatures of point-cloud files on the MLS surface
//! (Yang & Qian 2007). See `mlscurv --help` and the README.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{ArgAction, Args, CommandFactory as _, FromArgMatches as _, Subcommand};
use mls_cli::{AtArg, Format, MethodArg, NormalsArg};
use mls_pipeline::{parse_cutoff, parse_orient, positive_finite};

mod commands;
mod info;
mod render;

#[derive(Debug, clap::Parser)]
#[command(
    name = "mlscurv",
    version,
    about = "Exact curvature of point clouds on the MLS surface (Yang & Qian 2007)"
)]
#[command(after_help = STATUS_HELP)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

const STATUS_HELP: &str = "\
Status codes (column `status`):
  0  ok
  1  no_neighbours              no sample within the kernel support (isolated point)
  2  too_few_neighbours         fewer than 3 samples within the support
  3  normal_undefined           weighted normals cancel: normal field undefined
  4  gradient_vanishes          gradient of g vanishes: level set has no normal
  5  projection_failed          MLS projection found no energy minimum or did not converge
  6  invalid_query              query point has a non-finite coordinate
  7  normal_estimation_failed   normal could not be estimated (degenerate neighbourhood)
  8  outlier                    far off the surface fitted to its neighbours (a stray sample)
Numbers of a point with a non-zero status are NaN.

Sign convention: curvature is positive where the surface bends away from the oriented normal
(a sphere with outward normals has k1 = k2 = mean = 1/R); mean = (k1 + k2)/2; k1 >= k2.";

#[derive(Debug, Subcommand)]
enum Command {
    /// Principal curvatures, directions, mean and Gaussian curvature at every point.
    #[command(after_help = STATUS_HELP)]
    Curvature(CurvatureArgs),
    /// The raw implicit function g, its gradient and Hessian at arbitrary query points.
    Eval(EvalArgs),
    /// Estimate and orient normals only.
    Normals(NormalsArgs),
    /// Project the points onto the MLS surface (denoised points with normals).
    Project(ProjectArgs),
    /// Point count, bounding box, spacing, suggested h, normals.
    Info(InfoArgs),
    /// A PNG picture of a result: each point coloured by its mean, k1, k2, Gaussian
    /// curvature or status, with a colour bar or legend.
    Render(render::RenderArgs),
}

/// How a command runs: threads and chatter.
#[derive(Debug, Args)]
struct RunArgs {
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    threads: Option<u16>,
    /// No summary or progress on stderr (warnings and errors are still printed).
    #[arg(long, short)]
    quiet: bool,
}

/// The Gaussian scale, given or derived from the spacing.
#[derive(Debug, Args)]
struct ScaleArgs {
    /// Gaussian scale h, in the units of the file. Default: --h-factor × the point spacing.
    #[arg(long, value_parser = positive_finite, conflicts_with = "h_factor", allow_negative_numbers = true)]
    h: Option<f64>,
    /// h as a multiple of the median local point spacing.
    #[arg(long, value_parser = positive_finite, default_value_t = mls_core::normals::DEFAULT_H_FACTOR, allow_negative_numbers = true)]
    h_factor: f64,
}

/// Options shared by the commands that build an MLS surface.
#[derive(Debug, Args)]
struct SurfaceArgs {
    #[command(flatten)]
    scale: ScaleArgs,
    /// Kernel cutoff radius in units of h (at least 2), or `none` for the untruncated kernel.
    #[arg(long, value_parser = parse_cutoff, default_value = mls_pipeline::DEFAULT_CUTOFF, allow_negative_numbers = true)]
    cutoff: mls_core::Cutoff,
    /// Where normals come from.
    #[arg(long, value_enum, default_value_t = NormalsArg::Auto)]
    normals: NormalsArg,
    /// Orientation of estimated normals: `mst` (outward, by minimum spanning tree),
    /// `viewpoint:X,Y,Z` (towards a scanner position), `up` (positive z, for airborne scans),
    /// or `none`. `viewpoint` and `up` decide each smooth patch by a vote of its points.
    /// Default: towards each point's own scanner (its scan's pose) for an E57 input whose
    /// scans all have a pose, by the same vote; else `mst`, or `up` when that leaves three
    /// quarters of the normals within 60° of vertical on one side (a sheet seen from above,
    /// such as terrain and roofs; a closed object has half).
    #[arg(long, value_parser = parse_orient)]
    orient: Option<mls_core::normals::Orientation>,
    #[arg(long, value_parser = mls_io::ColumnNames::parse, help = COLUMNS_HELP)]
    columns: Option<mls_io::ColumnNames>,
    #[command(flatten)]
    run: RunArgs,
}

impl SurfaceArgs {
    /// The options that shape the surface, for the library's pipeline.
    fn options(&self) -> mls_pipeline::SurfaceOptions {
        mls_pipeline::SurfaceOptions {
            h: self.scale.h,
            h_factor: self.scale.h_factor,
            cutoff: self.cutoff,
            normals: self.normals.into(),
            orient: self.orient,
        }
    }
}

const COLUMNS_HELP: &str = "Names of the columns of a text input (.xyz/.txt/.pts/.asc, or .csv \
    instead of its header), e.g. `x,y,z,nx,ny,nz,intensity`: x, y, z and nx, ny, nz are the \
    geometry, `_` skips a column, other names are attributes carried to the output. Without \
    it, columns 4-6 of a headerless file are normals only if they are unit vectors on every \
    row, and other columns are carried as col4, col5 ...";

/// The output file, and the formats of the input and output.
#[derive(Debug, Args)]
struct OutputArgs {
    /// Output file: .ply (binary little endian unless --ascii), .csv, .xyz/.txt/.pts/.asc, .las/.laz; `-` for
    /// standard output (CSV unless --output-format).
    #[arg(short, long)]
    output: PathBuf,
    /// Write PLY as ASCII.
    #[arg(long)]
    ascii: bool,
    /// Replace the output file even if it is read-only (it keeps its permissions).
    #[arg(long)]
    force: bool,
    /// Do not carry the input's other per-point values (colour, intensity, LAS dimensions and
    /// extra bytes, other PLY properties and text columns) to the output; a LAS output then
    /// gets point format 6 and a scale of its own, not the LAS input's.
    #[arg(long)]
    no_attributes: bool,
    #[command(flatten)]
    formats: FormatArgs,
}

/// Formats named on the command line, for standard streams and unusual extensions.
#[derive(Debug, Args)]
struct FormatArgs {
    /// Format of the input, overriding its extension: needed for a file with another
    /// extension; for `-` (standard input) the format is otherwise recognised from the data.
    #[arg(long, value_enum)]
    input_format: Option<Format>,
    /// Format of the output: for `-o -` (default csv); for a file it must agree with the
    /// extension if the extension names a format.
    #[arg(long, value_enum)]
    output_format: Option<Format>,
}

#[derive(Debug, Args)]
struct CurvatureArgs {
    /// Input point cloud: .ply, .xyz/.txt/.pts/.asc, .csv with a header, .las/.laz, or .e57 (every scan); `-` for
    /// standard input.
    input: PathBuf,
    #[command(flatten)]
    out: OutputArgs,
    #[command(flatten)]
    surface: SurfaceArgs,
    /// The estimator: `jet` (default) or `paper` (the closed-form MLS surface).
    #[arg(long, value_enum, default_value_t = MethodArg::Jet)]
    method: MethodArg,
    /// Evaluate at the input points or at their projections onto the surface (the MLS
    /// surface for `--method paper`, the fitted jet for `--method jet`).
    #[arg(long, value_enum, default_value_t = AtArg::Input)]
    at: AtArg,
    /// Choose h per point: from the scale given by --h or --h-factor up to 4 times it, the
    /// largest scale whose estimate agrees with the smaller ones within the local noise, with
    /// the h² bias extrapolated away. Adds the columns `h` and `noise`. For noisy scans; on
    /// clean data use it with `--at projected`. Up to five evaluations per point (the scales share
    /// one index of the samples).
    /// `--method paper` only (the jet chooses its support per point by itself).
    #[arg(long)]
    adaptive: bool,
    /// Memory budget (e.g. `2GiB`, `512M`): an input file that does not fit (about 400 bytes a
    /// point and 64 MiB) is read in batches and evaluated in spatial tiles with halos through
    /// temporary files, with the results of one whole run (bitwise with the file's normals and
    /// a given --h), written to a file in any output format. Default: the machine's available
    /// memory, less a fifth. Refused for standard input, which is read whole.
    #[arg(long, value_parser = mls_pipeline::tiled::parse_size)]
    memory: Option<u64>,
    /// Directory for the temporary tiles of a tiled run (default: the output's directory).
    #[arg(long)]
    temp_dir: Option<PathBuf>,
}

#[derive(Debug, Args)]
struct EvalArgs {
    /// The cloud defining the surface; it must carry normals.
    #[arg(long)]
    cloud: PathBuf,
    /// Names of the columns of the cloud, when it is a text file (see `curvature --help`).
    #[arg(long, value_parser = mls_io::ColumnNames::parse)]
    columns: Option<mls_io::ColumnNames>,
    /// The query points (any supported format, `-` for standard input; normals in it are
    /// ignored). `--at` is a deprecated spelling.
    #[arg(long, alias = "at")]
    queries: PathBuf,
    /// Gaussian scale h. Default: 2 × the point spacing of the cloud.
    #[arg(long, value_parser = positive_finite, allow_negative_numbers = true)]
    h: Option<f64>,
    /// Kernel cutoff radius in units of h, or `none`.
    #[arg(long, value_parser = parse_cutoff, default_value = mls_pipeline::DEFAULT_CUTOFF, allow_negative_numbers = true)]
    cutoff: mls_core::Cutoff,
    /// Output file (.csv, .ply, .xyz/.txt/.pts/.asc, .las/.laz, by extension); standard output (CSV unless
    /// --output-format) when absent or `-`.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace the output file even if it is read-only (it keeps its permissions).
    #[arg(long)]
    force: bool,
    #[command(flatten)]
    formats: FormatArgs,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Debug, Args)]
struct NormalsArgs {
    /// Input point cloud; `-` for standard input.
    input: PathBuf,
    #[command(flatten)]
    out: OutputArgs,
    #[command(flatten)]
    scale: ScaleArgs,
    /// Orientation: `mst`, `viewpoint:X,Y,Z`, `up`, or `none`. Default: towards each
    /// point's own scanner for an E57 input whose scans all have a pose, else `mst`, or `up`
    /// for a sheet seen from above (as for `curvature`).
    #[arg(long, value_parser = parse_orient)]
    orient: Option<mls_core::normals::Orientation>,
    #[arg(long, value_parser = mls_io::ColumnNames::parse, help = COLUMNS_HELP)]
    columns: Option<mls_io::ColumnNames>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Debug, Args)]
struct ProjectArgs {
    /// Input point cloud; `-` for standard input.
    input: PathBuf,
    #[command(flatten)]
    out: OutputArgs,
    #[command(flatten)]
    surface: SurfaceArgs,
}

#[derive(Debug, Args)]
struct InfoArgs {
    /// Input point cloud; `-` for standard input.
    input: PathBuf,
    #[arg(long, value_parser = mls_io::ColumnNames::parse, help = COLUMNS_HELP)]
    columns: Option<mls_io::ColumnNames>,
    /// Format of the input, overriding its extension (see `curvature --help`).
    #[arg(long, value_enum)]
    input_format: Option<Format>,
}

/// Whether progress bars may be drawn.
fn interactive(quiet: bool) -> bool {
    !quiet && std::io::stderr().is_terminal()
}

/// The help option: `--help` only. `-h` is refused with a pointer to `--h` and `--help` (see
/// [`refuse_short_h`]), because `curvature -h 0.01 …` printing help and exiting 0 looked like
/// success to scripts that meant the scale.
fn help_arg() -> clap::Arg {
    clap::Arg::new("help")
        .long("help")
        .action(ArgAction::Help)
        .help("Print help")
}

/// Exits with a usage error (status 2) if an argument is `-h`, `-hVALUE` or `-h=VALUE`: the
/// scale is `--h`, help is `--help`. Arguments after `--` are operands and not looked at.
fn refuse_short_h(cmd: &mut clap::Command, args: &[std::ffi::OsString]) {
    let mut subcommand = None;
    for arg in args.iter().skip(1) {
        let Some(arg) = arg.to_str() else { continue };
        if arg == "--" {
            break;
        }
        if subcommand.is_none() && cmd.find_subcommand(arg).is_some() {
            subcommand = Some(arg.to_owned());
        }
        if arg.starts_with("-h") {
            let (name, has_scale) = match &subcommand {
                Some(name) => {
                    let has_scale = cmd
                        .find_subcommand(name)
                        .is_some_and(|c| c.get_arguments().any(|a| a.get_long() == Some("h")));
                    (format!("mlscurv {name}"), has_scale)
                }
                None => ("mlscurv".to_owned(), false),
            };
            let scale = if has_scale {
                "the Gaussian scale is `--h H` (two dashes) and "
            } else {
                ""
            };
            let message = format!("`{arg}` is not an option of `{name}`: {scale}help is `--help`");
            // The subcommand's own usage line, which `build` has given its full name.
            cmd.build();
            let mut target = subcommand
                .as_deref()
                .and_then(|name| cmd.find_subcommand(name))
                .unwrap_or(cmd)
                .clone();
            target
                .error(clap::error::ErrorKind::UnknownArgument, message)
                .exit();
        }
    }
}

fn main() -> ExitCode {
    let mut cmd = Cli::command()
        .disable_help_flag(true)
        .arg(help_arg())
        .mut_subcommands(|c| c.disable_help_flag(true).arg(help_arg()));
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    refuse_short_h(&mut cmd, &args);
    let cli = match cmd
        .try_get_matches_from_mut(&args)
        .and_then(|m| Cli::from_arg_matches(&m))
    {
        Ok(cli) => cli,
        Err(e) => e.format(&mut cmd).exit(),
    };
    let result = match cli.command {
        Command::Curvature(a) => commands::curvature(a),
        Command::Eval(a) => commands::eval(a),
        Command::Normals(a) => commands::normals(a),
        Command::Project(a) => commands::project(a),
        Command::Info(a) => info::info(a),
        Command::Render(a) => render::render(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("mlscurv: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
