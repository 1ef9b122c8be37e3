//! Shared steps: read and check the input, choose h, get oriented normals, build the surface.

use std::io::{IsTerminal as _, Read as _};
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use mls_core::normals::{
    DEFAULT_NEIGHBOURS, DEFAULT_SPACING_NEIGHBOURS, NormalsConfig, Orientation, SpacingStats,
    estimate_normals, orient_normals_towards, spacing_statistics, suggest_h,
};
use mls_core::{
    AdaptiveSurface, ConfigError, Cutoff, Frame, MlsConfig, MlsSurface, Parallelism, Point,
    PointStatus, Vector,
};
use mls_io::{FileFormat, PointCloud, ReadError};

pub use crate::output::{Carried, Output, check_output, write_stdout};
use crate::{Format, NormalsMode, SurfaceOptions};

/// The smallest cloud a neighbourhood can be built from: a covariance normal needs 3 points
/// besides the centre, the MLS evaluation at least 3 samples.
pub const MIN_POINTS: usize = 4;

/// Wall-clock time of the named stages, for the summary, and whether to show a spinner on
/// stderr while one runs ([`Timings::default`] shows none).
#[derive(Debug, Default)]
pub struct Timings(pub Vec<(&'static str, f64)>, bool);

impl Timings {
    /// Timings that show progress if `show` (stderr a terminal and no `--quiet`).
    pub fn new(show: bool) -> Self {
        Self(Vec::new(), show)
    }

    /// Whether progress is shown.
    pub fn show(&self) -> bool {
        self.1
    }

    /// Runs and times `stage` under a spinner.
    pub fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let _spinner = crate::progress::Spinner::new(stage, self.1);
        self.measure(stage, f)
    }

    /// Runs and times `stage`, which draws its own progress.
    pub fn measure<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let out = f();
        self.0.push((stage, t.elapsed().as_secs_f64()));
        out
    }
}

/// The path that means standard input (as an input) or standard output (as `-o`).
const STDIO: &str = "-";

/// The name of standard input in messages.
pub const STDIN_NAME: &str = "<stdin>";

/// The name of standard output in messages.
pub const STDOUT_NAME: &str = "<stdout>";

pub(crate) fn is_stdio(path: &Path) -> bool {
    path.as_os_str() == STDIO
}

/// How an input is named in messages: its path, or `<stdin>` for `-`.
pub fn input_name(path: &Path) -> String {
    if is_stdio(path) {
        STDIN_NAME.to_owned()
    } else {
        path.display().to_string()
    }
}

/// The name of a format on the command line.
pub fn format_name(format: FileFormat) -> &'static str {
    match format {
        FileFormat::Ply => "ply",
        FileFormat::Xyz => "xyz",
        FileFormat::Csv => "csv",
        FileFormat::Las => "las",
        FileFormat::Laz => "laz",
        FileFormat::E57 => "e57",
    }
}

/// Reads a cloud (see [`read_outcome`]) and prints the reader's notes on stderr, even with
/// `--quiet`: they say how the columns were understood.
pub fn read_any(
    path: &Path,
    format: Option<Format>,
    columns: Option<&mls_io::ColumnNames>,
) -> Result<PointCloud> {
    let mls_io::ReadOutcome { cloud, notes } = read_outcome(path, format, columns)?;
    for note in notes {
        eprintln!("mlscurv: note: {note}");
    }
    Ok(cloud)
}

/// Reads a cloud whose columns beyond x, y, z do not matter (eval's queries), without the
/// reader's notes.
pub fn read_quietly(path: &Path, format: Option<Format>) -> Result<PointCloud> {
    Ok(read_outcome(path, format, None)?.cloud)
}

/// Reads a cloud in `format` if given, else in the format its extension names; `-` reads
/// standard input, whose format is otherwise recognised from the data. The column names of
/// `--columns`, if given, name the columns of a text input, from a file or standard input.
pub fn read_outcome(
    path: &Path,
    format: Option<Format>,
    columns: Option<&mls_io::ColumnNames>,
) -> Result<mls_io::ReadOutcome> {
    let options = mls_io::ReadOptions {
        columns: columns.cloned(),
    };
    Ok(if is_stdio(path) {
        let stdin = std::io::stdin();
        if stdin.is_terminal() {
            bail!(
                "{STDIN_NAME}: standard input is a terminal; pipe or redirect a point cloud into it"
            );
        }
        let mut bytes = Vec::new();
        stdin
            .lock()
            .read_to_end(&mut bytes)
            .map_err(|e| anyhow!("{STDIN_NAME}: {e}"))?;
        let format = format.map_or_else(|| sniff(&bytes), FileFormat::from);
        mls_io::read_point_cloud_from_with(&bytes[..], STDIN_NAME, format, &options)?
    } else {
        match format {
            Some(format) => mls_io::read_point_cloud_as_with(path, format.into(), &options)?,
            None => mls_io::read_point_cloud_with(path, &options).map_err(|e| match e {
                ReadError::NoExtension { .. } | ReadError::UnknownExtension { .. } => {
                    anyhow!("{e}; or name the format with --input-format ply|xyz|csv|las|laz|e57")
                }
                e => e.into(),
            })?,
        }
    })
}

/// The format of data without a file name: PLY, LAS/LAZ or E57 by its magic word, else CSV if the first line
/// that is not blank or a `#` comment has a comma (its header row), else XYZ.
fn sniff(bytes: &[u8]) -> FileFormat {
    if bytes.starts_with(b"ply") {
        return FileFormat::Ply;
    }
    // LAS and LAZ alike: the reader takes the compression from the header.
    if bytes.starts_with(b"LASF") {
        return FileFormat::Las;
    }
    if bytes.starts_with(b"ASTM-E57") {
        return FileFormat::E57;
    }
    let first = bytes
        .split(|&b| b == b'\n')
        .map(<[u8]>::trim_ascii)
        .find(|line| !line.is_empty() && !line.starts_with(b"#"));
    match first {
        Some(line) if line.contains(&b',') => FileFormat::Csv,
        _ => FileFormat::Xyz,
    }
}

/// Reads a cloud (see [`read_any`]) and checks it has enough points.
pub fn read(
    path: &Path,
    format: Option<Format>,
    columns: Option<&mls_io::ColumnNames>,
) -> Result<PointCloud> {
    let cloud = read_any(path, format, columns)?;
    check_count(cloud.points.len(), &input_name(path))?;
    Ok(cloud)
}

/// Refuses a cloud of fewer than [`MIN_POINTS`] points; `file` names it.
pub fn check_count(n: usize, file: &str) -> Result<()> {
    if n < MIN_POINTS {
        bail!("{file}: {n} point(s); at least {MIN_POINTS} are needed to build a neighbourhood");
    }
    Ok(())
}

pub fn to_points(cloud: &PointCloud) -> Vec<Point> {
    cloud.points.iter().map(|p| Point::from(*p)).collect()
}

/// The chosen h and a sentence on why.
#[derive(Debug)]
pub struct Scale {
    pub h: f64,
    /// How h was derived, without parentheses: `2 × median local spacing … over 12 neighbours`,
    /// or `given with --h`.
    pub why: String,
    pub spacing: Option<SpacingStats>,
    /// The multiple of the spacing, if h was derived from it.
    pub factor: Option<f64>,
}

impl Scale {
    /// h and where it came from, for a summary line; `options` names how to change it.
    pub fn describe(&self, options: &str) -> String {
        if self.spacing.is_some() {
            format!("{:.6} = {}; {options} to change", self.h, self.why)
        } else {
            format!("{:.6}, {}", self.h, self.why)
        }
    }
}

/// Beyond this many times its bounding-box diagonal, h is refused: every sample weighs about
/// alike, and the "surface" is one blob fitted to the whole cloud.
const MAX_H_OVER_DIAGONAL: f64 = 10.0;

/// Points at which the kernel's reach is counted, by brute force, for the warnings.
const SUPPORT_PROBES: usize = 32;

/// At most this many points are counted around each probe (every k-th point of a larger
/// cloud, the count scaled up): a fraction to a few tenths of a percent, in milliseconds on a
/// million points.
const SUPPORT_SAMPLE: usize = 1 << 16;

/// Samples per evaluation beyond which a run is called slow: the default h gives a few
/// hundred within the default cutoff (about 35 times fewer).
const SLOW_SUPPORT: f64 = 10_000.0;

/// Refuses an h far beyond the size of the cloud and returns warnings, each starting with
/// `file`, when the kernel's weight spans most of the cloud, or when its support holds so many
/// samples that the run will be slow. The binary prints them on stderr even with --quiet (the
/// results would look fine; see [`print_warning`]). At h = 1000 on the 0.25 m bunny every point
/// came out "ok", with k ≈ 1e-6, after a run 300 times longer than usual.
pub fn check_scale(
    points: &[Point],
    scale: &Scale,
    cutoff: Cutoff,
    file: &str,
) -> Result<Vec<String>> {
    let h = scale.h;
    let Some(first) = points.first() else {
        return Ok(Vec::new());
    };
    let (lo, hi) = points
        .iter()
        .fold((first.coords, first.coords), |(lo, hi), p| {
            (lo.inf(&p.coords), hi.sup(&p.coords))
        });
    let diagonal = (hi - lo).norm();
    if !(diagonal > 0.0) {
        return Ok(Vec::new());
    }
    if h > MAX_H_OVER_DIAGONAL * diagonal {
        bail!(
            "{file}: h = {h} is {:.0} times the diagonal {diagonal:.6} of the cloud's bounding box: \
             every point would weigh alike and the curvature would be that of one blob, not of the \
             surface; choose h well below the size of the cloud (`mlscurv info` suggests one)",
            h / diagonal
        );
    }
    // The weight is 1.2e-4 at 3h: what lies within 3h is what shapes the surface. The cutoff
    // (5h by default) only bounds the work, and on a small cloud holds most of it harmlessly.
    let weighty = 3.0 * h;
    let support = match cutoff {
        Cutoff::Radius(c) => Some(c * h),
        Cutoff::None => None,
    };
    let n = points.len();
    let probes = n.min(SUPPORT_PROBES);
    let step = n / probes;
    let stride = n.div_ceil(SUPPORT_SAMPLE);
    let sampled = n.div_ceil(stride);
    let (mut within_weighty, mut within_support) = (0usize, 0usize);
    for i in 0..probes {
        let q = points[i * step];
        for p in points.iter().step_by(stride) {
            let d2 = (p - q).norm_squared();
            within_weighty += usize::from(d2 <= weighty * weighty);
            within_support += usize::from(support.is_none_or(|r| d2 <= r * r));
        }
    }
    let fraction = within_weighty as f64 / (probes * sampled) as f64;
    let per_point = within_support as f64 / probes as f64 * (n as f64 / sampled as f64);
    let mut warnings = Vec::new();
    if h > diagonal {
        warnings.push(format!(
            "h = {h} exceeds the cloud's extent (bounding-box diagonal {diagonal:.6})"
        ));
    } else if fraction > 0.5 {
        warnings.push(format!(
            "h = {h}: the kernel's weight (within 3h = {weighty:.6}) spans on average {:.0}% of \
             the {n} points",
            100.0 * fraction
        ));
    }
    if let Some(w) = warnings.first_mut() {
        w.push_str(
            "; the curvature will be that of an overall smoothed shape, not of local detail",
        );
        // With the default factor, h is what `info` would suggest: the cloud is then too
        // small for local detail, and saying "choose another h" would be no help.
        match scale.factor {
            None => w.push_str("; `mlscurv info` suggests an h"),
            Some(f) if f > mls_core::normals::DEFAULT_H_FACTOR => {
                w.push_str(&format!(
                    "; a smaller --h-factor than {f} gives a smaller h"
                ));
            }
            Some(_) => w.push_str("; the cloud has too few points for a local fit"),
        }
    }
    if per_point > SLOW_SUPPORT {
        warnings.push(format!(
            "h = {h}: the kernel's support ({}) holds about {per_point:.0} of the {n} points at \
             each evaluation; expect a long run",
            match support {
                Some(r) => format!("cutoff {r:.6}"),
                None => "no cutoff".to_owned(),
            }
        ));
    }
    Ok(warnings
        .into_iter()
        .map(|w| format!("{file}: {w}"))
        .collect())
}

/// Prints a warning of [`check_scale`] on stderr, as the binary does even with `--quiet`.
pub fn print_warning(warning: String) {
    eprintln!("mlscurv: warning: {warning}");
}

pub fn choose_h(
    points: &[Point],
    h: Option<f64>,
    factor: f64,
    par: Parallelism,
    file: &str,
) -> Result<Scale> {
    if let Some(h) = h {
        return Ok(Scale {
            h,
            why: "given with --h".into(),
            spacing: None,
            factor: None,
        });
    }
    let stats = spacing_statistics(points, DEFAULT_SPACING_NEIGHBOURS, par)
        .with_context(|| format!("{file}: cannot measure the point spacing"))?;
    let h = suggest_h(&stats, factor)
        .with_context(|| format!("{file}: cannot derive h from the spacing"))?;
    Ok(Scale {
        h,
        why: format!(
            "{factor} × median local spacing {:.6} over {} neighbours",
            stats.spacing, stats.k
        ),
        spacing: Some(stats),
        factor: Some(factor),
    })
}

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
    let scale = t.time("spacing", || {
        choose_h(points, h, mls_core::normals::DEFAULT_H_FACTOR, par, file)
    })?;
    for w in check_scale(points, &scale, cutoff, file)? {
        warn(w);
    }
    let normals: Vec<Vector> = normals.iter().map(|n| Vector::from(*n)).collect();
    let surface = t.time("index", || {
        MlsSurface::new(
            points,
            &normals,
            MlsConfig {
                cutoff,
                ..MlsConfig::new(scale.h)
            },
        )
        .with_context(|| file.to_owned())
    })?;
    Ok((scale, surface))
}

/// Oriented normals, one per point (`None` where none could be had), and their source.
#[derive(Debug)]
pub struct Normals {
    pub normals: Vec<Option<Vector>>,
    pub source: String,
    /// Whether they are the file's (measured data) rather than estimated from the points.
    pub from_file: bool,
}

/// The scanner position of each point of an E57 input whose scans all have a pose, for the
/// default orientation ([`normals`]); `None` for other inputs.
pub fn scan_viewpoints(cloud: &PointCloud) -> Option<Vec<Point>> {
    let viewpoints = cloud.scans.as_ref()?.viewpoints()?;
    Some(viewpoints.into_iter().map(Point::from).collect())
}

/// Normals from `file_normals` (the file's, consumed here so that they are not held beside
/// the converted ones) or estimated from `points`, as `mode` says, and oriented as
/// `orientation` says; without one (the default), towards `viewpoints` (one per point: each
/// point's own scanner, [`scan_viewpoints`]) if given, else outward.
#[allow(clippy::too_many_arguments)]
pub fn normals(
    file_normals: Option<Vec<[f64; 3]>>,
    points: &[Point],
    mode: NormalsMode,
    orientation: Option<Orientation>,
    viewpoints: Option<&[Point]>,
    h: f64,
    par: Parallelism,
    file: &str,
) -> Result<Normals> {
    let from_file = match (mode, file_normals) {
        (NormalsMode::File, None) => {
            bail!("{file}: --normals file given but the file has no normals (nx, ny, nz)")
        }
        (NormalsMode::File | NormalsMode::Auto, Some(n)) => Some(n),
        _ => None,
    };
    if let Some(file_normals) = from_file {
        let normals: Vec<Option<Vector>> = file_normals
            .into_iter()
            .map(|n| {
                mls_core::UnitNormal::new(Vector::from(n))
                    .ok()
                    .map(|u| u.into_inner())
            })
            .collect();
        let bad = normals.iter().filter(|n| n.is_none()).count();
        let source = if bad == 0 {
            "from the file".to_string()
        } else {
            format!("from the file ({bad} zero normals left out of the surface)")
        };
        return Ok(Normals {
            normals,
            source,
            from_file: true,
        });
    }
    // Per-scan viewpoints: estimated unoriented, then oriented by the per-point vote.
    let per_scan = match (orientation, viewpoints) {
        (None, Some(v)) => Some(v),
        _ => None,
    };
    let orientation = orientation.unwrap_or_default();
    let config = NormalsConfig {
        k: DEFAULT_NEIGHBOURS,
        h: Some(h),
        orientation: if per_scan.is_some() {
            Orientation::None
        } else {
            orientation
        },
        ..NormalsConfig::default()
    };
    let mut est = estimate_normals(points, &config, par)
        .with_context(|| format!("{file}: normal estimation"))?;
    if let Some(viewpoints) = per_scan {
        est.report =
            orient_normals_towards(points, &est.graph, &mut est.estimates, viewpoints, par)
                .with_context(|| format!("{file}: normal orientation"))?;
    }
    let orient = match orientation {
        _ if per_scan.is_some() => "oriented towards each scan's scanner position (E57 pose) by \
            minimum spanning tree and a vote per smooth patch"
            .to_string(),
        Orientation::Outward => "oriented outward by minimum spanning tree".to_string(),
        Orientation::Viewpoint(v) => format!(
            "oriented towards the viewpoint ({}, {}, {}) by minimum spanning tree and a vote per smooth patch",
            v.x, v.y, v.z
        ),
        Orientation::Up => {
            "oriented up (+z) by minimum spanning tree and a vote per smooth patch".to_string()
        }
        Orientation::None => "not oriented (--orient none)".to_string(),
    };
    let r = &est.report;
    let mut checks = Vec::new();
    if let Some(f) = r.facing {
        let towards = match orientation {
            _ if per_scan.is_some() => "face their scanner",
            Orientation::Up => "point up",
            _ => "face the viewpoint",
        };
        if let Some(share) = f.share() {
            checks.push(format!("{:.2}% of normals {towards}", 100.0 * share));
        }
        if let Some(share) = f.decisive_share() {
            checks.push(format!(
                "{:.2}% of the {} within 60° of the line of sight",
                100.0 * share,
                f.decisive
            ));
        }
    }
    if let Some(c) = r.consistency {
        checks.push(format!("{:.2}% of neighbour pairs agree", 100.0 * c));
    }
    let pieces = if r.patches > r.components {
        format!("{} component(s) in {} patches", r.components, r.patches)
    } else {
        format!("{} component(s)", r.components)
    };
    let checks = if checks.is_empty() {
        String::new()
    } else {
        format!(", {}", checks.join(", "))
    };
    let source = format!(
        "estimated (weighted covariance, {} neighbours), {orient}: {pieces}{checks}; {} failed",
        DEFAULT_NEIGHBOURS,
        est.failed()
    );
    Ok(Normals {
        normals: est.normals().into_iter().map(Result::ok).collect(),
        source,
        from_file: false,
    })
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

/// Builds one fixed-scale surface in `frame`.
pub fn fixed_surface(
    points: &[Point],
    normals: &[Vector],
    h: f64,
    cutoff: Cutoff,
    frame: Frame,
) -> Result<MlsSurface, ConfigError> {
    MlsSurface::with_frame(
        points,
        normals,
        MlsConfig {
            cutoff,
            ..MlsConfig::new(h)
        },
        frame,
    )
}

/// Reads the input, then builds the surface as [`build_surface`] does, timing each stage and
/// printing the warnings on stderr.
pub fn prepare<S>(
    input: &Path,
    format: Option<Format>,
    columns: Option<&mls_io::ColumnNames>,
    s: &SurfaceOptions,
    t: &mut Timings,
    build: impl FnOnce(&[Point], &[Vector], f64, Cutoff, Frame) -> Result<S, ConfigError>,
) -> Result<Prepared<S>> {
    let cloud = t.time("read", || read(input, format, columns))?;
    let viewpoints = scan_viewpoints(&cloud);
    let PointCloud {
        points,
        normals: file_normals,
        attributes,
        las,
        scans: _,
    } = cloud;
    // `[f64; 3]` and `Point` have the same layout: the conversion reuses the buffer.
    let points: Vec<Point> = points.into_iter().map(Point::from).collect();
    let built = build_surface(
        &points,
        file_normals,
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
        carried: Carried::new(attributes, las, true),
    })
}

/// Chooses h, checks it against the cloud (passing its warnings to `warn` at once), gets
/// oriented normals (`file_normals`, or estimated, as `s.normals` says) and builds the surface
/// with `build` (points, normals, h, cutoff), timing each stage. `viewpoints`, one per point,
/// are the default orientation's ([`normals`]). `file` names the cloud in
/// messages; `points` must be finite (the readers refuse other values) and at least
/// [`MIN_POINTS`] ([`check_count`]).
#[allow(clippy::too_many_arguments)]
pub fn build_surface<S>(
    points: &[Point],
    file_normals: Option<Vec<[f64; 3]>>,
    viewpoints: Option<&[Point]>,
    file: &str,
    s: &SurfaceOptions,
    t: &mut Timings,
    mut warn: impl FnMut(String),
    build: impl FnOnce(&[Point], &[Vector], f64, Cutoff, Frame) -> Result<S, ConfigError>,
) -> Result<Built<S>> {
    let par = Parallelism::Rayon;
    let scale = t.time("spacing", || choose_h(points, s.h, s.h_factor, par, file))?;
    for w in check_scale(points, &scale, s.cutoff, file)? {
        warn(w);
    }
    let Normals {
        normals,
        source,
        from_file,
    } = t.time("normals", || {
        normals(
            file_normals,
            points,
            s.normals,
            s.orient,
            viewpoints,
            scale.h,
            par,
            file,
        )
    })?;
    let surface = t.time("index", || {
        surface(points, normals, scale.h, s.cutoff, file, build)
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
/// points lack a normal.
pub fn surface<S>(
    points: &[Point],
    normals: Vec<Option<Vector>>,
    h: f64,
    cutoff: Cutoff,
    file: &str,
    build: impl FnOnce(&[Point], &[Vector], f64, Cutoff, Frame) -> Result<S, ConfigError>,
) -> Result<S> {
    surface_in(points, normals, h, cutoff, Frame::of(points), file, build)
}

/// [`surface`] in a given frame: a tile's, the whole cloud's.
pub fn surface_in<S>(
    points: &[Point],
    normals: Vec<Option<Vector>>,
    h: f64,
    cutoff: Cutoff,
    frame: Frame,
    file: &str,
    build: impl FnOnce(&[Point], &[Vector], f64, Cutoff, Frame) -> Result<S, ConfigError>,
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
    build(p, &n, h, cutoff, frame).with_context(|| file.to_owned())
}

/// Runs `f` on a rayon pool with the requested number of threads (all cores by default).
pub fn with_threads<T: Send>(
    threads: Option<u16>,
    f: impl FnOnce() -> Result<T> + Send,
) -> Result<T> {
    match threads {
        None => f(),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(usize::from(n))
            .build()
            .context("cannot start the worker threads")?
            .install(f),
    }
}

/// Counts of each status, in code order.
pub fn status_counts(codes: &[i32]) -> String {
    let ok = codes.iter().filter(|&&c| c == 0).count();
    let mut parts = vec![format!("ok {ok}")];
    for s in PointStatus::ALL {
        let n = codes.iter().filter(|&&c| c == i32::from(s.code())).count();
        if n > 0 {
            parts.push(format!("{} {n}", s.name()));
        }
    }
    parts.join(", ")
}

/// A few percentiles of the finite values.
pub fn percentiles(values: &[f64]) -> String {
    let mut v: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if v.is_empty() {
        return "no values".into();
    }
    v.sort_unstable_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    format!(
        "p1 {:+.4e}  p5 {:+.4e}  p25 {:+.4e}  p50 {:+.4e}  p75 {:+.4e}  p95 {:+.4e}  p99 {:+.4e}",
        q(0.01),
        q(0.05),
        q(0.25),
        q(0.5),
        q(0.75),
        q(0.95),
        q(0.99)
    )
}
