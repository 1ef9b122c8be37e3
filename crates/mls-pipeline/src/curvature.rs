//! The one curvature entry: build the surface, configure the jet, evaluate. The command
//! (`mlscurv curvature`), Python's `mlscurv.curvature` and the xtask's end-to-end check call
//! [`curvature`]; a tile of the out-of-core run, whose surface is built in the whole cloud's
//! frame, calls [`curvature_on`], its second half.

use anyhow::Result;
use mls_core::{JetConfig, Point};

use crate::evaluate::{self, CurvatureColumns, curvature_label, curvature_surface, jet_config};
use crate::pipeline::{Built, Scale, Surface, Timings, build_surface};
use crate::progress::Progress;
use crate::{CurvatureOptions, Method};

/// A cloud to compute the curvature of.
#[derive(Debug)]
pub struct Cloud<'a> {
    /// The points: finite (the readers refuse other values), at least
    /// [`MIN_POINTS`](crate::pipeline::MIN_POINTS).
    pub points: &'a [Point],
    /// Measured normals (a file's `nx ny nz`), used as
    /// [`SurfaceOptions::normals`](crate::SurfaceOptions::normals) says.
    pub normals: Option<Vec<[f64; 3]>>,
    /// Each point's scanner, for the default orientation of estimated normals (E57 scans with
    /// poses; [`crate::pipeline::normals`]).
    pub viewpoints: Option<&'a [Point]>,
    /// The cloud's name in messages: the file, or `points` in Python.
    pub name: &'a str,
}

/// What [`curvature`] computed: the columns, and how, for the summary.
#[derive(Debug)]
pub struct CurvatureRun {
    pub columns: CurvatureColumns,
    pub scale: Scale,
    /// Where the normals came from.
    pub normals_source: String,
    /// Whether the normals are the cloud's own ([`Cloud::normals`]).
    pub normals_from_file: bool,
    /// The jet's configuration ([`jet_config`]); used with [`Method::Jet`] only.
    pub jet: JetConfig,
}

/// The curvature of `cloud` as `options` say: h, oriented normals and the surface
/// ([`build_surface`], each stage timed in `t`, the warnings passed to `warn`), then
/// [`curvature_on`] at every point, timed as the evaluation's stage and moving a bar of
/// `t`'s progress. The surface is dropped before returning: the columns are what is written.
///
/// `--adaptive` with the jet is refused first
/// ([`ADAPTIVE_NEEDS_PAPER`](crate::ADAPTIVE_NEEDS_PAPER)).
pub fn curvature(
    cloud: Cloud<'_>,
    options: &CurvatureOptions,
    t: &mut Timings,
    warn: impl FnMut(String),
) -> Result<CurvatureRun> {
    if options.adaptive && options.method == Method::Jet {
        anyhow::bail!("{}", crate::ADAPTIVE_NEEDS_PAPER);
    }
    let Cloud {
        points,
        normals,
        viewpoints,
        name,
    } = cloud;
    let Built {
        scale,
        normals_source,
        normals_from_file,
        surface,
    } = build_surface(
        points,
        normals,
        viewpoints,
        name,
        &options.surface,
        t,
        warn,
        curvature_surface(options.adaptive),
    )?;
    let progress = t.progress();
    let (columns, jet) = t.measure(curvature_label(options.at), || {
        curvature_on(points, &surface, normals_from_file, options, &*progress)
    });
    Ok(CurvatureRun {
        columns,
        scale,
        normals_source,
        normals_from_file,
        jet,
    })
}

/// The curvature at `points` of a built `surface`: the jet configured for where its normals
/// came from ([`jet_config`]), then the streamed evaluation ([`evaluate::curvature`]). Returns
/// the columns and the jet's configuration.
pub fn curvature_on(
    points: &[Point],
    surface: &Surface,
    normals_from_file: bool,
    options: &CurvatureOptions,
    progress: &dyn Progress,
) -> (CurvatureColumns, JetConfig) {
    let jet = jet_config(normals_from_file);
    let columns = evaluate::curvature(points, surface, options, &jet, progress);
    (columns, jet)
}
