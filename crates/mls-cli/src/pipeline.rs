//! Shared steps: read and check the input, choose h, get oriented normals, build the surface.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use mls_core::normals::{
    DEFAULT_NEIGHBOURS, DEFAULT_SPACING_NEIGHBOURS, NormalsConfig, Orientation, SpacingStats,
    estimate_normals, spacing_statistics, suggest_h,
};
use mls_core::{
    AdaptiveSurface, ConfigError, Cutoff, MlsConfig, MlsSurface, Parallelism, Point, PointStatus,
    Vector,
};
use mls_io::PointCloud;

use crate::{NormalsMode, SurfaceArgs};

/// The smallest cloud a neighbourhood can be built from: a covariance normal needs 3 points
/// besides the centre, the MLS evaluation at least 3 samples.
pub const MIN_POINTS: usize = 4;

/// Wall-clock time of the named stages, for the summary.
#[derive(Debug, Default)]
pub struct Timings(pub Vec<(&'static str, f64)>);

impl Timings {
    pub fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let out = f();
        self.0.push((stage, t.elapsed().as_secs_f64()));
        out
    }
}

/// Reads a cloud (with the column names of `--columns`, if given) and prints the reader's
/// notes on stderr, even with `--quiet`: they say how the columns were understood.
pub fn read_noted(path: &Path, columns: Option<&mls_io::ColumnNames>) -> Result<PointCloud> {
    let options = mls_io::ReadOptions {
        columns: columns.cloned(),
    };
    let mls_io::ReadOutcome { cloud, notes } = mls_io::read_point_cloud_with(path, &options)?;
    for note in notes {
        eprintln!("mlscurv: note: {note}");
    }
    Ok(cloud)
}

/// Reads a cloud as [`read_noted`] does and checks it has enough points.
pub fn read(path: &Path, columns: Option<&mls_io::ColumnNames>) -> Result<PointCloud> {
    let cloud = read_noted(path, columns)?;
    if cloud.points.len() < MIN_POINTS {
        bail!(
            "{}: {} point(s); at least {MIN_POINTS} are needed to build a neighbourhood",
            path.display(),
            cloud.points.len()
        );
    }
    Ok(cloud)
}

/// Refuses to overwrite the input with the output.
pub fn check_output(input: &Path, output: &Path) -> Result<()> {
    if mls_io::same_file(input, output) {
        bail!(
            "{}: output path is the input file; refusing to overwrite it",
            output.display()
        );
    }
    Ok(())
}

pub fn to_points(cloud: &PointCloud) -> Vec<Point> {
    cloud.points.iter().map(|p| Point::from(*p)).collect()
}

/// The chosen h and a sentence on why.
pub struct Scale {
    pub h: f64,
    pub why: String,
    pub spacing: Option<SpacingStats>,
}

pub fn choose_h(
    points: &[Point],
    h: Option<f64>,
    factor: f64,
    par: Parallelism,
    file: &Path,
) -> Result<Scale> {
    if let Some(h) = h {
        return Ok(Scale {
            h,
            why: "given with --h".into(),
            spacing: None,
        });
    }
    let stats = spacing_statistics(points, DEFAULT_SPACING_NEIGHBOURS, par)
        .with_context(|| format!("{}: cannot measure the point spacing", file.display()))?;
    let h = suggest_h(&stats, factor)
        .with_context(|| format!("{}: cannot derive h from the spacing", file.display()))?;
    Ok(Scale {
        h,
        why: format!(
            "{factor} × median local spacing {:.6} (over {} neighbours; use --h or --h-factor to change)",
            stats.spacing, stats.k
        ),
        spacing: Some(stats),
    })
}

/// Oriented normals, one per point (`None` where none could be had), and their source.
pub struct Normals {
    pub normals: Vec<Option<Vector>>,
    pub source: String,
    /// Whether they are the file's (measured data) rather than estimated from the points.
    pub from_file: bool,
}

/// Normals from `file_normals` (the file's, consumed here so that they are not held beside
/// the converted ones) or estimated from `points`, as `mode` says.
pub fn normals(
    file_normals: Option<Vec<[f64; 3]>>,
    points: &[Point],
    mode: NormalsMode,
    orientation: Orientation,
    h: f64,
    par: Parallelism,
    file: &Path,
) -> Result<Normals> {
    let from_file = match (mode, file_normals) {
        (NormalsMode::File, None) => {
            bail!(
                "{}: --normals file given but the file has no normals (nx, ny, nz)",
                file.display()
            )
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
    let config = NormalsConfig {
        k: DEFAULT_NEIGHBOURS,
        h: Some(h),
        orientation,
        ..NormalsConfig::default()
    };
    let est = estimate_normals(points, &config, par)
        .with_context(|| format!("{}: normal estimation", file.display()))?;
    let orient = match orientation {
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

/// Everything a command needs before evaluating: the points, h, where the normals came from,
/// and the surface. The file's normals and the oriented normals are not kept: the surface holds
/// its own copy, and a cloud's worth of memory counts at a million points.
pub struct Prepared<S = MlsSurface> {
    /// The input points, in file order.
    pub points: Vec<Point>,
    pub scale: Scale,
    /// Where the normals came from, for the summary.
    pub normals_source: String,
    /// Whether the normals are the file's.
    pub normals_from_file: bool,
    pub surface: S,
}

/// The surface `mlscurv curvature` evaluates: one scale, or a per-point scale (`--adaptive`).
pub enum Surface {
    Fixed(MlsSurface),
    Adaptive(AdaptiveSurface),
}

/// Builds one fixed-scale surface.
pub fn fixed_surface(
    points: &[Point],
    normals: &[Vector],
    h: f64,
    cutoff: Cutoff,
) -> Result<MlsSurface, ConfigError> {
    MlsSurface::new(
        points,
        normals,
        MlsConfig {
            cutoff,
            ..MlsConfig::new(h)
        },
    )
}

/// Reads the input, chooses h, gets oriented normals and builds the surface with `build`
/// (points, normals, h, cutoff), timing each stage.
pub fn prepare<S>(
    input: &Path,
    s: &SurfaceArgs,
    t: &mut Timings,
    build: impl FnOnce(&[Point], &[Vector], f64, Cutoff) -> Result<S, ConfigError>,
) -> Result<Prepared<S>> {
    let par = Parallelism::Rayon;
    let PointCloud {
        points,
        normals: file_normals,
    } = t.time("read", || read(input, s.columns.as_ref()))?;
    // `[f64; 3]` and `Point` have the same layout: the conversion reuses the buffer.
    let points: Vec<Point> = points.into_iter().map(Point::from).collect();
    let scale = t.time("spacing", || {
        choose_h(&points, s.scale.h, s.scale.h_factor, par, input)
    })?;
    let Normals {
        normals,
        source,
        from_file,
    } = t.time("normals", || {
        normals(
            file_normals,
            &points,
            s.normals,
            s.orient,
            scale.h,
            par,
            input,
        )
    })?;
    let surface = t.time("index", || {
        surface(&points, normals, scale.h, s.cutoff, input, build)
    })?;
    Ok(Prepared {
        points,
        scale,
        normals_source: source,
        normals_from_file: from_file,
        surface,
    })
}

/// Builds the surface from the points that have normals, consuming the normals.
pub fn surface<S>(
    points: &[Point],
    normals: Vec<Option<Vector>>,
    h: f64,
    cutoff: Cutoff,
    file: &Path,
    build: impl FnOnce(&[Point], &[Vector], f64, Cutoff) -> Result<S, ConfigError>,
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
            "{}: only {} point(s) have a normal; at least {MIN_POINTS} are needed",
            file.display(),
            p.len()
        );
    }
    build(p, &n, h, cutoff).with_context(|| format!("{}", file.display()))
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
