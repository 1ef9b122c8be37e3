//! The steps of `mlscurv`'s commands, as a library: reading and checking a cloud, choosing h,
//! getting oriented normals, building the surface, evaluating it chunk by chunk into the
//! output columns, and writing them with the input's attributes carried (`output`); the same
//! tile by tile for a cloud larger than memory (`tiled`). The command line (`crates/mls-cli`)
//! adds argument parsing, `info`, `render`, the summaries and the progress bars; the Python
//! package (`crates/mls-py`) calls the same functions on arrays, so that both give the same
//! bits and the same messages. This crate knows no argument parser and no progress bar:
//! progress comes in through [`progress::Progress`].
//!
//! Errors are `anyhow` chains whose one-line form (`{:#}`) is what `mlscurv` prints after
//! `mlscurv: error:`; the Python package raises them with the same text.

mod curvature;
pub mod evaluate;
pub mod output;
pub mod pipeline;
pub mod progress;
pub mod tiled;

pub use curvature::{Cloud, CurvatureRun, curvature, curvature_on};
use mls_core::PointStatus;
use mls_core::normals::Orientation;
use mls_core::{Cutoff, Point};

/// Where normals come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalsMode {
    /// The file's normals if it has them, else estimate.
    Auto,
    /// The file's normals (an error if it has none).
    File,
    /// Estimate from the points, ignoring any normals in the file.
    Estimate,
}

/// Where curvature is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum At {
    /// At the input points: the level set of g through each point.
    Input,
    /// At the input points projected onto the MLS surface.
    Projected,
}

/// The curvature estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Weighted polynomial jets in the frame of the MLS normal: degree 4 on small supports,
    /// and without file normals also degree 2 on large ones (noisy scans), the degree and
    /// support of least predicted error chosen per point, with that error per point (columns
    /// k1_sd, k2_sd). Accurate on irregular samples, scan boundaries and noise
    /// (docs/accuracy.md).
    Jet,
    /// The Amenta-Kil MLS surface in closed form (Yang & Qian 2007): exact for that surface,
    /// accurate on regular grids, biased on irregular samples.
    Paper,
}

/// The options of the commands that build a surface (`curvature`, `project`), without the
/// command line's file and run options.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceOptions {
    /// The Gaussian scale; `None` derives it from the spacing.
    pub h: Option<f64>,
    /// h as a multiple of the median local spacing, when `h` is `None`.
    pub h_factor: f64,
    /// The kernel's cutoff.
    pub cutoff: Cutoff,
    /// Where normals come from.
    pub normals: NormalsMode,
    /// The orientation of estimated normals; `None` for the default: towards each point's own
    /// scanner for an E57 input whose scans all have a pose, else outward (`mst`).
    pub orient: Option<Orientation>,
}

/// The options of `mlscurv curvature` that shape the result.
#[derive(Clone, Copy, Debug)]
pub struct CurvatureOptions {
    /// The surface's options.
    pub surface: SurfaceOptions,
    /// The estimator.
    pub method: Method,
    /// Where curvature is evaluated.
    pub at: At,
    /// A scale per point (`--adaptive`, `--method paper` only).
    pub adaptive: bool,
}

/// The refusal of `--adaptive` with `--method jet`.
pub const ADAPTIVE_NEEDS_PAPER: &str = "--adaptive is the per-point scale of --method paper; the \
    default jet method chooses its support per point by itself (use --method paper --adaptive for \
    the MLS surface)";

/// The value parser of `--h` and `--h-factor`: a finite positive number.
pub fn positive_finite(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be finite and positive, got {s}"))
    }
}

/// The default of `--cutoff` (`mlscurv curvature`, `project`, `eval`), as the command line
/// writes it: the kernel truncated at 5 h (README.md, `--cutoff`).
pub const DEFAULT_CUTOFF: &str = "5";

/// The value parser of `--cutoff`: a factor of at least [`Cutoff::MIN_FACTOR`], or `none`.
pub fn parse_cutoff(s: &str) -> Result<Cutoff, String> {
    if s.eq_ignore_ascii_case("none") {
        return Ok(Cutoff::None);
    }
    let c = positive_finite(s)?;
    if c < Cutoff::MIN_FACTOR {
        return Err(format!(
            "must be at least {} (in units of h) or `none`, got {s}",
            Cutoff::MIN_FACTOR
        ));
    }
    Ok(Cutoff::Radius(c))
}

/// The value parser of `--orient`: `mst`, `up`, `none` or `viewpoint:X,Y,Z`.
pub fn parse_orient(s: &str) -> Result<Orientation, String> {
    match s {
        "mst" => Ok(Orientation::Outward),
        "none" => Ok(Orientation::None),
        "up" => Ok(Orientation::Up),
        _ => {
            let Some(rest) = s.strip_prefix("viewpoint:") else {
                return Err(format!(
                    "expected `mst`, `up`, `none` or `viewpoint:X,Y,Z`, got `{s}`"
                ));
            };
            let v: Vec<f64> = rest
                .split(',')
                .map(|c| c.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect::<Option<_>>()
                .ok_or_else(|| {
                    format!("viewpoint needs three finite numbers X,Y,Z, got `{rest}`")
                })?;
            let [x, y, z] = v[..] else {
                return Err(format!("viewpoint needs three numbers X,Y,Z, got `{rest}`"));
            };
            Ok(Orientation::Viewpoint(Point::new(x, y, z)))
        }
    }
}

/// The numeric status written to files.
pub fn status_code(r: &Result<impl Sized, PointStatus>) -> i32 {
    match r {
        Ok(_) => 0,
        Err(s) => i32::from(s.code()),
    }
}
