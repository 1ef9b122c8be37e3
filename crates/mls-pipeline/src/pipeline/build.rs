//! Building the surface from the stages before it: h, its checks and the oriented normals,
//! timed one by one, and the surface built from the points that have a normal, in the frame
//! of the whole cloud.

use std::path::Path;

use anyhow::{Context, Result, bail};
use mls_core::{
    AdaptiveSurface, ConfigError, Cutoff, Frame, IndexedCloud, MlsConfig, MlsSurface, Parallelism,
    Point, Vector,
};
use mls_io::PointCloud;

use super::{
    Carried, MIN_POINTS, Normals, Scale, Timings, check_file_normals, check_scale, choose_h_on,
    input_name, normals, print_warning, read, scan_viewpoints,
};
use crate::SurfaceOptions;

/// The surface `mlscurv eval` evaluates: the cloud's own `normals` (every one non-zero), h
/// given or from the spacing (the default factor), checked against the cloud (its warnings
/// passed to `warn`), the kernel truncated at `cutoff`.
pub fn eval_surface(
    points: &[Point],
    normals: &[[f64; 3]],
    h: Option<f64>,
    cutoff: Cutoff,
    file: &str,
    t: &mut Timings,
    mut warn: impl FnMut(String),
) -> Result<(Scale, MlsSurface)> {
    let par = Parallelism::Rayon;
    let cloud = t.time("index", || index(points, Frame::of(points), file))?;
    let scale = t.time("spacing", || {
        choose_h_on(&cloud, h, mls_core::normals::DEFAULT_H_FACTOR, par, file)
    })?;
    for w in check_scale(points, &scale, cutoff, file)? {
        warn(w);
    }
    let normals: Vec<Vector> = normals.iter().map(|n| Vector::from(*n)).collect();
    let check = t.time("normals", || {
        check_file_normals(&cloud, |i| Some(normals[i]), file)
    });
    if let Some(w) = check {
        warn(w);
    }
    let surface = t.time("index", || {
        fixed_surface(cloud, &normals, scale.h, cutoff).with_context(|| file.to_owned())
    })?;
    Ok((scale, surface))
}

/// Everything a command needs before evaluating, besides the points: h, where the normals
/// came from, and the surface. The file's normals and the oriented normals are not kept: the
/// surface holds its own copy, and a cloud's worth of memory counts at a million points.
#[derive(Debug)]
pub struct Built<S = MlsSurface> {
    pub scale: Scale,
    /// Where the normals came from, for the summary.
    pub normals_source: String,
    /// Whether the normals are the file's.
    pub normals_from_file: bool,
    pub surface: S,
}

/// [`Built`], the input points it was built from, in file order, and what they carry to the
/// output.
#[derive(Debug)]
pub struct Prepared<S = MlsSurface> {
    pub points: Vec<Point>,
    pub built: Built<S>,
    /// The input's attributes and LAS layout (all of them: the command drops them for
    /// `--no-attributes`).
    pub carried: Carried,
}

/// The surface `mlscurv curvature` evaluates: one scale, or a per-point scale (`--adaptive`).
#[derive(Debug)]
pub enum Surface {
    Fixed(MlsSurface),
    Adaptive(AdaptiveSurface),
}

/// Builds one fixed-scale surface over `cloud` with its `normals`.
pub fn fixed_surface(
    cloud: IndexedCloud<'_>,
    normals: &[Vector],
    h: f64,
    cutoff: Cutoff,
) -> Result<MlsSurface, ConfigError> {
    MlsSurface::from_cloud(
        cloud,
        normals,
        MlsConfig {
            cutoff,
            ..MlsConfig::new(h)
        },
    )
}

/// `points` checked and indexed in `frame` (see `mls_core::IndexedCloud`).
pub fn index<'a>(points: &'a [Point], frame: Frame, file: &str) -> Result<IndexedCloud<'a>> {
    IndexedCloud::with_frame(points, frame, Parallelism::Rayon)
        .map_err(ConfigError::from)
        .with_context(|| file.to_owned())
}

/// What builds a surface over an indexed cloud and its normals (in input order), with h and
/// the cutoff: a fixed scale ([`fixed_surface`]) or the adaptive ladder.
pub trait BuildSurface<S>:
    for<'a> FnOnce(IndexedCloud<'a>, &[Vector], f64, Cutoff) -> Result<S, ConfigError>
{
}
impl<S, F: for<'a> FnOnce(IndexedCloud<'a>, &[Vector], f64, Cutoff) -> Result<S, ConfigError>>
    BuildSurface<S> for F
{
}

/// A cloud read from a file, before any work: its points in file order, the file's normals,
/// each point's scanner ([`scan_viewpoints`]) and what the points carry to the output.
#[derive(Debug)]
pub struct Loaded {
    pub points: Vec<Point>,
    pub normals: Option<Vec<[f64; 3]>>,
    pub viewpoints: Option<Vec<Point>>,
    /// The input's attributes and LAS layout (all of them: the command drops them for
    /// `--no-attributes`).
    pub carried: Carried,
}

/// Reads the input (timed as `read`), printing the reader's notes on stderr.
pub fn load(
    input: &Path,
    format: Option<mls_io::FileFormat>,
    columns: Option<&mls_io::ColumnNames>,
    t: &mut Timings,
) -> Result<Loaded> {
    let cloud = t.time("read", || read(input, format, columns))?;
    let viewpoints = scan_viewpoints(&cloud);
    let PointCloud {
        points,
        normals,
        attributes,
        las,
        scans: _,
    } = cloud;
    // `[f64; 3]` and `Point` have the same layout: the conversion reuses the buffer.
    let points: Vec<Point> = points.into_iter().map(Point::from).collect();
    Ok(Loaded {
        points,
        normals,
        viewpoints,
        carried: Carried::new(attributes, las, true),
    })
}

/// Reads the input ([`load`]), then builds the surface as [`build_surface`] does, timing each
/// stage and printing the warnings on stderr.
pub fn prepare<S>(
    input: &Path,
    format: Option<mls_io::FileFormat>,
    columns: Option<&mls_io::ColumnNames>,
    s: &SurfaceOptions,
    t: &mut Timings,
    build: impl BuildSurface<S>,
) -> Result<Prepared<S>> {
    let Loaded {
        points,
        normals,
        viewpoints,
        carried,
    } = load(input, format, columns, t)?;
    let built = build_surface(
        &points,
        normals,
        viewpoints.as_deref(),
        &input_name(input),
        s,
        t,
        print_warning,
        build,
    )?;
    Ok(Prepared {
        points,
        built,
        carried,
    })
}

/// Chooses h, checks it against the cloud (passing its warnings to `warn` at once), gets
/// oriented normals (`file_normals`, or estimated, as `s.normals` says) and builds the surface
/// with `build` (points, normals, h, cutoff), timing each stage. `viewpoints`, one per point,
/// are the default orientation's ([`normals`]). `file` names the cloud in
/// messages; `points` must be finite (the readers refuse other values) and at least
/// [`MIN_POINTS`] ([`check_count`](super::check_count)).
#[allow(clippy::too_many_arguments)]
pub fn build_surface<S>(
    points: &[Point],
    file_normals: Option<Vec<[f64; 3]>>,
    viewpoints: Option<&[Point]>,
    file: &str,
    s: &SurfaceOptions,
    t: &mut Timings,
    mut warn: impl FnMut(String),
    build: impl BuildSurface<S>,
) -> Result<Built<S>> {
    let par = Parallelism::Rayon;
    // One index for the spacing and the surface.
    let cloud = t.time("index", || index(points, Frame::of(points), file))?;
    let scale = t.time("spacing", || {
        choose_h_on(&cloud, s.h, s.h_factor, par, file)
    })?;
    for w in check_scale(points, &scale, s.cutoff, file)? {
        warn(w);
    }
    let Normals {
        normals,
        source,
        from_file,
        warning,
    } = t.time("normals", || {
        normals(
            file_normals,
            points,
            Some(&cloud),
            s.normals,
            s.orient,
            viewpoints,
            scale.h,
            par,
            file,
        )
    })?;
    if let Some(w) = warning {
        warn(w);
    }
    if from_file {
        let check = t.time("normals", || {
            check_file_normals(&cloud, |i| normals[i], file)
        });
        if let Some(w) = check {
            warn(w);
        }
    }
    let surface = t.time("index", || {
        surface(cloud, points, normals, scale.h, s.cutoff, file, build)
    })?;
    Ok(Built {
        scale,
        normals_source: source,
        normals_from_file: from_file,
        surface,
    })
}

/// Builds the surface from the points that have normals, consuming the normals, in the frame
/// of all `points` (those without a normal too): so a tile of a cloud, built in the whole
/// cloud's frame, gives bitwise the whole cloud's results (see `mls_core::tiling`), whichever
/// points lack a normal. `cloud` is `points` indexed in their frame: it becomes the surface's
/// index when every point has a normal.
pub fn surface<S>(
    cloud: IndexedCloud<'_>,
    points: &[Point],
    normals: Vec<Option<Vector>>,
    h: f64,
    cutoff: Cutoff,
    file: &str,
    build: impl BuildSurface<S>,
) -> Result<S> {
    if normals.iter().all(Option::is_some) {
        let n: Vec<Vector> = normals.into_iter().flatten().collect();
        return build(cloud, &n, h, cutoff).with_context(|| file.to_owned());
    }
    let frame = cloud.frame();
    drop(cloud);
    surface_in(points, normals, h, cutoff, frame, file, build)
}

/// [`surface`] in a given frame: a tile's, the whole cloud's.
pub fn surface_in<S>(
    points: &[Point],
    normals: Vec<Option<Vector>>,
    h: f64,
    cutoff: Cutoff,
    frame: Frame,
    file: &str,
    build: impl BuildSurface<S>,
) -> Result<S> {
    // Usually every point has a normal: the points are then passed as they are, not copied.
    let with_normal = normals.iter().filter(|n| n.is_some()).count();
    let kept: Option<Vec<Point>> = (with_normal < points.len()).then(|| {
        points
            .iter()
            .zip(&normals)
            .filter_map(|(p, n)| n.map(|_| *p))
            .collect()
    });
    let n: Vec<Vector> = normals.into_iter().flatten().collect();
    let p = kept.as_deref().unwrap_or(points);
    if p.len() < MIN_POINTS {
        bail!(
            "{file}: only {} point(s) have a normal; at least {MIN_POINTS} are needed",
            p.len()
        );
    }
    let cloud = index(p, frame, file)?;
    build(cloud, &n, h, cutoff).with_context(|| file.to_owned())
}
