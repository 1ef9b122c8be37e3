//! What `mlscurv` adds to the library behind it ([`mls_pipeline`]): the command line's names
//! of the library's choices (for clap), the file formats it names, and the progress bars on
//! stderr. The commands themselves are in the binary (`src/main.rs`).

pub mod progress;

use clap::ValueEnum;
use mls_pipeline::{At, Method, NormalsMode};

/// Where normals come from (`--normals`; [`NormalsMode`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum NormalsArg {
    /// The file's normals if it has them, else estimate.
    Auto,
    /// The file's normals (an error if it has none).
    File,
    /// Estimate from the points, ignoring any normals in the file.
    Estimate,
}

impl From<NormalsArg> for NormalsMode {
    fn from(n: NormalsArg) -> Self {
        match n {
            NormalsArg::Auto => Self::Auto,
            NormalsArg::File => Self::File,
            NormalsArg::Estimate => Self::Estimate,
        }
    }
}

/// Where curvature is evaluated (`--at`; [`At`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AtArg {
    /// At the input points: the level set of g through each point.
    Input,
    /// At the input points projected onto the MLS surface.
    Projected,
}

impl From<AtArg> for At {
    fn from(a: AtArg) -> Self {
        match a {
            AtArg::Input => Self::Input,
            AtArg::Projected => Self::Projected,
        }
    }
}

/// The curvature estimator (`--method`; [`Method`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
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

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Jet => Self::Jet,
            MethodArg::Paper => Self::Paper,
        }
    }
}

/// A point-cloud file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Format {
    /// PLY (ASCII or binary).
    Ply,
    /// Columns separated by whitespace, commas or semicolons (.xyz, .txt, .pts, .asc).
    Xyz,
    /// Comma-separated columns with a header row.
    Csv,
    /// ASPRS LAS (every dimension carried; computed columns as extra bytes on output).
    Las,
    /// LASzip-compressed LAS.
    Laz,
    /// ASTM E57, every scan (input only; estimated normals face each scan's scanner).
    E57,
}

impl From<Format> for mls_io::FileFormat {
    fn from(f: Format) -> Self {
        match f {
            Format::Ply => Self::Ply,
            Format::Xyz => Self::Xyz,
            Format::Csv => Self::Csv,
            Format::Las => Self::Las,
            Format::Laz => Self::Laz,
            Format::E57 => Self::E57,
        }
    }
}
