//! `mlscurv curvature` on a LAS/LAZ cloud larger than memory: tiles with halos on disk.
//!
//! Four streaming passes over the input, and the tiles one at a time in between:
//! 1. *scan*: the exact bounding box (the whole cloud's [`Frame`]) and the points per cell of
//!    a grid ([`mls_core::tiling`]);
//! 2. *spacing* (without `--h`): h from the points of a few tiles spread over the cloud;
//! 3. *tiles*: each point is appended to the file of every tile that loads it (its own, and
//!    those whose box lies within the reach, [`tiling::reach`]);
//! 4. per tile: normals, the surface in the whole cloud's frame, the curvature at its own
//!    points, appended to the tile's result file (the tile's input file is then removed);
//! 5. *write*: the input is read again, and each point's attributes are written with the
//!    next result of its tile, in input order.
//!
//! With the file's normals and a given h the results are bitwise those of one in-memory run:
//! a result depends only on the samples within the reach, all of them in the tile, and the
//! surface sums them in the same order ([`mls_core::Frame`]). Estimated normals are estimated
//! and oriented per tile; their agreement in the overlaps is measured and reported.
//!
//! Temporary files live in one directory (in the output's directory unless `--temp-dir`),
//! removed on success, on error and on Ctrl-C; the free space is checked first.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};
use mls_core::normals::{DEFAULT_SPACING_NEIGHBOURS, Orientation, spacing_statistics, suggest_h};
use mls_core::tiling::{self, Grid, TilePlan};
use mls_core::{Frame, Parallelism, Point, PointStatus, Vector};
use mls_io::{Column, FileFormat, LasReader};

use crate::evaluate::{self, CurvatureColumns};
use crate::pipeline::{self, Scale, Timings};
use crate::{At, CurvatureOptions, Method, NormalsMode};

/// Memory per loaded point while a tile is evaluated: the points, normals, surface and k-d
/// tree, the neighbour graph of estimated normals, the results of its own points. Measured as
/// peak resident memory over points loaded (docs/benchmarks.md, "Out of core"): about 350
/// bytes with estimated normals, the heaviest case, on tiles of 0.27M and 2M points.
pub const BYTES_PER_POINT: u64 = 400;

/// Memory besides the tile: the program, the grid of counts, the reader's and writer's
/// chunks, the buffers of the tile files (measured: about 25 MB in all).
pub const FIXED_BYTES: u64 = 64 << 20;

/// Cells of the counting grid: 8 MB of counts, and boxes of about 100 points on 100M.
const GRID_CELLS: usize = 1 << 20;

/// Points read per chunk.
const CHUNK: u64 = 1 << 16;

/// The spacing is measured on up to [`SPACING_TILES`] tiles of this many points spread over
/// the cloud: the same sample whatever the budget, once it holds them.
const SPACING_TILE: u64 = 1 << 18;

/// See [`SPACING_TILE`].
const SPACING_TILES: u64 = 8;

/// Bytes of a result record: 16 `f64` (normal, k1, k2, mean, gauss, d1, d2, k1_sd, k2_sd),
/// the status and the estimated normal's code.
const RESULT_BYTES: usize = 16 * 8 + 4 + 1;

/// The directories to remove on Ctrl-C, and the outputs whose temporary files to remove.
static CLEANUP: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// What a tiled run is asked to do.
#[derive(Debug)]
pub struct TiledRun<'a> {
    pub input: &'a Path,
    pub output: &'a Path,
    pub format: FileFormat,
    pub options: &'a CurvatureOptions,
    /// Memory budget in bytes.
    pub budget: u64,
    /// Where the temporary tiles go; default the output's directory.
    pub temp_dir: Option<&'a Path>,
    /// Whether the input's attributes are carried.
    pub keep_attributes: bool,
}

/// What the summary reports.
#[derive(Debug)]
pub struct TiledSummary {
    pub points: u64,
    pub scale: Scale,
    pub normals_source: String,
    pub tiles: usize,
    /// Most points loaded by one tile (core and halo).
    pub largest_tile: u64,
    /// Points loaded in all, over the points: the halos' cost.
    pub load_factor: f64,
    pub reach: f64,
    /// Status counts, as the summary words them.
    pub status: String,
    /// Every k-th point's k1 and predicted error, for the percentiles.
    pub k1: Vec<f64>,
    pub k2: Vec<f64>,
    pub mean: Vec<f64>,
    pub gauss: Vec<f64>,
    pub k1_sd: Vec<f64>,
    /// Overlap points whose estimated normal's sign agrees between two tiles, and those
    /// compared.
    pub agreement: Option<(u64, u64)>,
}

/// The budget in bytes from the machine's available memory (Linux: `MemAvailable`), leaving a
/// fifth to the rest of the system; `None` where it cannot be read.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Whether a run over `points` points fits in `budget` bytes without tiles.
pub fn fits_in_memory(points: u64, budget: u64) -> bool {
    points.saturating_mul(BYTES_PER_POINT) <= budget.saturating_sub(FIXED_BYTES)
}

/// Parses a memory size: a number with an optional unit `B`, `K`/`KB`/`KiB`, `M`/`MiB`,
/// `G`/`GiB`, `T`/`TiB` (powers of 1024 for all), case-insensitive.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a size such as 2GiB, 512M or 1500000000"))?;
    let shift = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        other => {
            return Err(format!(
                "unknown unit `{other}` in `{text}` (use K, M, G or T)"
            ));
        }
    };
    let bytes = value * (1u64 << shift) as f64;
    if !(bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("`{text}` is not a positive size"));
    }
    Ok(bytes as u64)
}

/// Removes the registered temporary directories and output files and exits with 130, as a
/// shell reports an interrupted command.
fn on_interrupt() {
    if let Ok(paths) = CLEANUP.lock() {
        for path in paths.iter() {
            if path.is_dir() {
                let _ = std::fs::remove_dir_all(path);
            } else if let (Some(dir), Some(name)) = (path.parent(), path.file_name()) {
                // The atomic writer's temporary file: `.NAME.XXXXXX.tmp` beside the output.
                let prefix = format!(".{}.", name.to_string_lossy());
                let dir = if dir.as_os_str().is_empty() {
                    Path::new(".")
                } else {
                    dir
                };
                for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
                    let n = entry.file_name().to_string_lossy().into_owned();
                    if n.starts_with(&prefix) && n.ends_with(".tmp") {
                        let _ = std::fs::remove_file(entry.path());
                    }
                }
            }
        }
    }
    eprintln!("mlscurv: interrupted; temporary files removed");
    std::process::exit(130);
}

/// The temporary directory of a run, removed when dropped and on Ctrl-C.
struct Workspace {
    dir: tempfile::TempDir,
}

impl Workspace {
    fn new(parent: &Path, output: &Path) -> Result<Self> {
        let dir = tempfile::Builder::new()
            .prefix(".mlscurv-tiles-")
            .tempdir_in(parent)
            .with_context(|| {
                format!("{}: cannot create a temporary directory", parent.display())
            })?;
        if let Ok(mut paths) = CLEANUP.lock() {
            paths.push(dir.path().to_path_buf());
            paths.push(output.to_path_buf());
        }
        // Once per process; a second run in the same process keeps the first handler.
        let _ = ctrlc::set_handler(on_interrupt);
        Ok(Self { dir })
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }
}

impl Drop for Workspace {
    fn drop(&mut self) {
        if let Ok(mut paths) = CLEANUP.lock() {
            paths.clear();
        }
    }
}

fn open_reader(input: &Path) -> Result<LasReader> {
    Ok(LasReader::open(input)?)
}

/// Reads every point of `input` in chunks, calling `f` with each chunk's first index and
/// cloud.
fn for_each_chunk(
    input: &Path,
    with_attributes: bool,
    mut f: impl FnMut(u64, &mls_io::PointCloud) -> Result<()>,
) -> Result<()> {
    let mut reader = open_reader(input)?;
    let mut first = 0u64;
    loop {
        let mut chunk = reader.empty_cloud(CHUNK as usize);
        if !with_attributes {
            // Nothing to decode them into: they are skipped.
            chunk.attributes.clear();
        }
        let n = reader.read_into(&mut chunk, CHUNK)?;
        if n == 0 {
            return Ok(());
        }
        f(first, &chunk)?;
        first += n as u64;
    }
}

/// The code of an estimated normal's sign for the overlap check: its largest component's
/// axis and sign (0 for none). Two estimates of one normal from overlapping neighbourhoods are
/// nearly parallel, so they share the axis unless it is a near tie, when they are not
/// compared.
fn sign_code(n: Option<&Vector>) -> u8 {
    let Some(n) = n else { return 0 };
    let axis = n.iamax();
    1 + 2 * axis as u8 + u8::from(n[axis] < 0.0)
}

/// Runs `mlscurv curvature` tile by tile.
pub fn curvature(run: &TiledRun<'_>, t: &mut Timings) -> Result<TiledSummary> {
    let options = run.options;
    let name = pipeline::input_name(run.input);
    if options.adaptive {
        bail!("{name}: --adaptive is not available for a tiled (out-of-core) run");
    }
    if options.at == At::Projected {
        bail!("{name}: --at projected is not available for a tiled (out-of-core) run");
    }
    let s = &options.surface;
    let jet = (options.method == Method::Jet).then(|| evaluate::jet_config(false));
    let reader = open_reader(run.input)?;
    let n = reader.len();
    pipeline::check_count(usize::try_from(n).unwrap_or(usize::MAX), &name)?;
    let from_file = match (s.normals, reader.has_normals()) {
        (NormalsMode::File, false) => {
            bail!("{name}: --normals file given but the file has no normals (nx, ny, nz)")
        }
        (NormalsMode::File | NormalsMode::Auto, true) => true,
        _ => false,
    };
    let jet = jet.map(|_| evaluate::jet_config(from_file));
    for note in reader.notes() {
        eprintln!("mlscurv: note: {note}");
    }
    let (header_lo, header_hi) = reader.header_bounds();
    let template = reader.template().clone();
    drop(reader);
    let capacity = run.budget.saturating_sub(FIXED_BYTES) / BYTES_PER_POINT;
    if capacity < 1000 {
        bail!(
            "--memory {}: too small; a tiled run needs at least {} MiB",
            run.budget,
            (FIXED_BYTES + 1000 * BYTES_PER_POINT) >> 20
        );
    }

    // 1. The box and the counts.
    let grid = Grid::new(Vector::from(header_lo), Vector::from(header_hi), GRID_CELLS)
        .with_context(|| format!("{name}: the header's bounding box"))?;
    let mut counts = vec![0u64; grid.len()];
    let (mut lo, mut hi) = (
        Vector::repeat(f64::INFINITY),
        Vector::repeat(f64::NEG_INFINITY),
    );
    t.time("scan", || {
        for_each_chunk(run.input, false, |_, chunk| {
            for p in &chunk.points {
                let p = Point::from(*p);
                counts[grid.index_of(&p)] += 1;
                lo = lo.inf(&p.coords);
                hi = hi.sup(&p.coords);
            }
            Ok(())
        })
    })?;
    let frame = Frame::of_box(lo, hi);

    // 2. h.
    let scale = match s.h {
        Some(h) => Scale {
            h,
            why: "given with --h".into(),
            spacing: None,
            factor: None,
        },
        None => t.time("spacing", || {
            sampled_scale(run.input, &grid, &counts, capacity, s.h_factor, &name)
        })?,
    };
    let h = scale.h;
    let reach = tiling::reach(h, s.cutoff, jet.as_ref(), !from_file).with_context(|| {
        format!("{name}: a tiled run needs a kernel cutoff (--cutoff none reaches every point)")
    })?;
    let plan = TilePlan::new(grid, &counts, reach, capacity)
        .with_context(|| format!("{name}: --memory {} MiB", run.budget >> 20))?;
    drop(counts);
    let tiles = plan.tiles().len();

    // Disk: the tile files (points with their halos), the results, and the output.
    let parent = run.temp_dir.map_or_else(
        || {
            run.output
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."))
                .to_path_buf()
        },
        Path::to_path_buf,
    );
    let record = if from_file { 56 } else { 32 };
    let loaded: u64 = plan.tiles().iter().map(|t| t.loaded).sum();
    let needed = loaded * record + n * (RESULT_BYTES as u64 + 1) + n * 200;
    let free = fs4::available_space(&parent)
        .with_context(|| format!("{}: cannot measure the free disk space", parent.display()))?;
    if free < needed {
        bail!(
            "{}: {:.1} GB free, but a tiled run of {n} points needs about {:.1} GB for its \
             temporary tiles and the output; free some space or choose --temp-dir",
            parent.display(),
            free as f64 / 1e9,
            needed as f64 / 1e9
        );
    }
    let work = Workspace::new(&parent, run.output)?;

    // 3. The tile files, in input order.
    t.time("tiles", || -> Result<()> {
        let mut files: Vec<BufWriter<File>> = (0..tiles)
            .map(|i| {
                let path = work.path(&format!("tile{i}.pts"));
                File::create(&path)
                    .map(|f| BufWriter::with_capacity(1 << 16, f))
                    .with_context(|| path.display().to_string())
            })
            .collect::<Result<_>>()?;
        for_each_chunk(run.input, false, |first, chunk| {
            for (k, p) in chunk.points.iter().enumerate() {
                let mut bytes = [0u8; 56];
                bytes[..8].copy_from_slice(&(first + k as u64).to_le_bytes());
                for (i, c) in p.iter().enumerate() {
                    bytes[8 + 8 * i..16 + 8 * i].copy_from_slice(&c.to_le_bytes());
                }
                if let (true, Some(normals)) = (from_file, &chunk.normals) {
                    for (i, c) in normals[k].iter().enumerate() {
                        bytes[32 + 8 * i..40 + 8 * i].copy_from_slice(&c.to_le_bytes());
                    }
                }
                let mut error = None;
                plan.tiles_near(&Point::from(*p), |tile| {
                    if let Err(e) = files[tile].write_all(&bytes[..record as usize]) {
                        error = Some(e);
                    }
                });
                if let Some(e) = error {
                    return Err(e).context(work.dir.path().display().to_string());
                }
            }
            Ok(())
        })?;
        for f in &mut files {
            f.flush().context(work.dir.path().display().to_string())?;
        }
        Ok(())
    })?;

    // 4. Each tile.
    let orientation = s.orient.unwrap_or(Orientation::Up);
    let mut normals_source = String::new();
    let bar = crate::progress::Bar::new(n as usize, "curvature", t.show());
    let mut done = 0usize;
    t.measure("curvature", || -> Result<()> {
        for tile in 0..tiles {
            let source = evaluate_tile(
                &work,
                tile,
                &plan,
                from_file,
                record as usize,
                &scale,
                orientation,
                s.orient.is_none(),
                frame,
                options,
                jet.as_ref(),
                &name,
            )?;
            if normals_source.is_empty() {
                normals_source = source;
            }
            done += plan.tiles()[tile].points as usize;
            bar.set(done);
        }
        Ok(())
    })?;
    drop(bar);

    // 5. The output, in input order.
    let mut summary = TiledSummary {
        points: n,
        scale,
        normals_source,
        tiles,
        largest_tile: plan.tiles().iter().map(|t| t.loaded).max().unwrap_or(0),
        load_factor: loaded as f64 / n as f64,
        reach,
        status: String::new(),
        k1: Vec::new(),
        k2: Vec::new(),
        mean: Vec::new(),
        gauss: Vec::new(),
        k1_sd: Vec::new(),
        agreement: (!from_file).then_some((0, 0)),
    };
    t.time("write", || {
        write_output(run, &work, &plan, &template, &mut summary)
    })?;
    drop(work);
    Ok(summary)
}

/// h from the spacing of up to [`SPACING_TILES`] tiles of [`SPACING_TILE`] points spread
/// over the cloud (all of a cloud that small: then h is the in-memory run's), fewer if the
/// budget's `capacity` holds fewer.
fn sampled_scale(
    input: &Path,
    grid: &Grid,
    counts: &[u64],
    capacity: u64,
    factor: f64,
    name: &str,
) -> Result<Scale> {
    let size = SPACING_TILE.min(capacity);
    let plan = TilePlan::new(grid.clone(), counts, 0.0, size)
        .with_context(|| format!("{name}: planning the spacing sample"))?;
    let tiles = plan.tiles();
    // Every k-th tile (the plan's order follows space), as many as the budget holds.
    let take = (capacity / size)
        .clamp(1, SPACING_TILES)
        .min(tiles.len() as u64) as usize;
    let chosen: Vec<bool> = (0..tiles.len())
        .map(|i| (i * take) / tiles.len() != ((i + 1) * take) / tiles.len())
        .collect();
    let mut points = Vec::new();
    for_each_chunk(input, false, |_, chunk| {
        for p in &chunk.points {
            let p = Point::from(*p);
            if chosen[plan.tile_of(&p)] {
                points.push(p);
            }
        }
        Ok(())
    })?;
    let par = Parallelism::Rayon;
    let stats = spacing_statistics(&points, DEFAULT_SPACING_NEIGHBOURS, par)
        .with_context(|| format!("{name}: cannot measure the point spacing"))?;
    let h = suggest_h(&stats, factor)
        .with_context(|| format!("{name}: cannot derive h from the spacing"))?;
    Ok(Scale {
        h,
        why: format!(
            "{factor} × median local spacing {:.6} over {} neighbours, of {} points in {take} \
             of {} tiles",
            stats.spacing,
            stats.k,
            points.len(),
            tiles.len()
        ),
        spacing: Some(stats),
        factor: Some(factor),
    })
}

/// Evaluates one tile: reads its points, gets their normals, builds the surface in the
/// whole cloud's frame, evaluates its own points and writes their results; returns the
/// normals' description.
#[allow(clippy::too_many_arguments)]
fn evaluate_tile(
    work: &Workspace,
    tile: usize,
    plan: &TilePlan,
    from_file: bool,
    record: usize,
    scale: &Scale,
    orientation: Orientation,
    default_orientation: bool,
    frame: Frame,
    options: &CurvatureOptions,
    jet: Option<&mls_core::JetConfig>,
    name: &str,
) -> Result<String> {
    let path = work.path(&format!("tile{tile}.pts"));
    let mut bytes = Vec::new();
    File::open(&path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .with_context(|| path.display().to_string())?;
    std::fs::remove_file(&path).with_context(|| path.display().to_string())?;
    let f64_at =
        |r: &[u8], at: usize| f64::from_le_bytes(r[at..at + 8].try_into().unwrap_or_default());
    let count = bytes.len() / record;
    let mut points = Vec::with_capacity(count);
    let mut file_normals = from_file.then(|| Vec::with_capacity(count));
    for r in bytes.chunks_exact(record) {
        points.push(Point::new(f64_at(r, 8), f64_at(r, 16), f64_at(r, 24)));
        if let Some(n) = &mut file_normals {
            n.push([f64_at(r, 32), f64_at(r, 40), f64_at(r, 48)]);
        }
    }
    drop(bytes);
    let core: Vec<bool> = points.iter().map(|p| plan.tile_of(p) == tile).collect();
    let tile_name = format!("{name} (tile {tile})");
    let s = &options.surface;
    let normals = pipeline::normals(
        file_normals,
        &points,
        if from_file {
            NormalsMode::File
        } else {
            NormalsMode::Estimate
        },
        Some(orientation),
        None,
        scale.h,
        Parallelism::Rayon,
        &tile_name,
    )?;
    let codes: Vec<u8> = normals
        .normals
        .iter()
        .map(|n| sign_code(n.as_ref()))
        .collect();
    let mut source = normals.source.clone();
    if !from_file && default_orientation {
        source.push_str(" (a tiled run orients up unless --orient says otherwise)");
    }
    // Each tile's numbers and checks are its own: the summary names the rule, per tile.
    let queries: Vec<Point> = points
        .iter()
        .zip(&core)
        .filter_map(|(p, &c)| c.then_some(*p))
        .collect();
    let surface = pipeline::surface_in(
        &points,
        normals.normals,
        scale.h,
        s.cutoff,
        frame,
        &tile_name,
        evaluate::curvature_surface(false),
    )?;
    let default_jet = mls_core::JetConfig::default();
    let out = evaluate::curvature(
        &queries,
        &surface,
        options,
        jet.unwrap_or(&default_jet),
        false,
    );
    drop(surface);
    let path = work.path(&format!("tile{tile}.out"));
    let mut w = BufWriter::with_capacity(
        1 << 16,
        File::create(&path).with_context(|| path.display().to_string())?,
    );
    let core_codes = codes
        .iter()
        .zip(&core)
        .filter_map(|(c, &k)| k.then_some(*c));
    for (i, code) in core_codes.enumerate() {
        let mut r = [0u8; RESULT_BYTES];
        let sd = |v: &Vec<f64>| v.get(i).copied().unwrap_or(f64::NAN);
        let values = [
            out.normal[i][0],
            out.normal[i][1],
            out.normal[i][2],
            out.k1[i],
            out.k2[i],
            out.mean[i],
            out.gauss[i],
            out.d1[i][0],
            out.d1[i][1],
            out.d1[i][2],
            out.d2[i][0],
            out.d2[i][1],
            out.d2[i][2],
            sd(&out.k1_sd),
            sd(&out.k2_sd),
            f64::NAN,
        ];
        for (j, v) in values.iter().enumerate() {
            r[8 * j..8 * j + 8].copy_from_slice(&v.to_le_bytes());
        }
        r[128..132].copy_from_slice(&out.status[i].to_le_bytes());
        r[132] = code;
        w.write_all(&r)
            .with_context(|| path.display().to_string())?;
    }
    w.flush().with_context(|| path.display().to_string())?;
    if !from_file {
        // The halo points' signs, in input order, for the overlap check.
        let path = work.path(&format!("tile{tile}.halo"));
        let halo: Vec<u8> = codes
            .iter()
            .zip(&core)
            .filter_map(|(c, &k)| (!k).then_some(*c))
            .collect();
        std::fs::write(&path, halo).with_context(|| path.display().to_string())?;
    }
    Ok(source)
}

/// Reads the input again and writes each point with its tile's next result.
fn write_output(
    run: &TiledRun<'_>,
    work: &Workspace,
    plan: &TilePlan,
    template: &mls_io::LasTemplate,
    summary: &mut TiledSummary,
) -> Result<()> {
    let tiles = plan.tiles().len();
    let open = |suffix: &str| -> Result<Vec<BufReader<File>>> {
        (0..tiles)
            .map(|i| {
                let path = work.path(&format!("tile{i}.{suffix}"));
                File::open(&path)
                    .map(|f| BufReader::with_capacity(1 << 16, f))
                    .with_context(|| path.display().to_string())
            })
            .collect()
    };
    let mut results = open("out")?;
    let mut halos = if summary.agreement.is_some() {
        Some(open("halo")?)
    } else {
        None
    };
    let jet = run.options.method == Method::Jet;
    let stride = (summary.points / 1_000_000).max(1);
    let mut counts = vec![0u64; PointStatus::ALL.len() + 1];
    let mut renamed: Option<Vec<String>> = None;
    let compressed = run.format == FileFormat::Laz;
    mls_io::write_las_chunks(run.output, compressed, template, |sink| -> Result<()> {
        for_each_chunk(run.input, run.keep_attributes, |first, chunk| {
            let m = chunk.points.len();
            let mut out = CurvatureColumns::with_capacity(m, run.options);
            for (k, p) in chunk.points.iter().enumerate() {
                let p = Point::from(*p);
                let own = plan.tile_of(&p);
                let mut r = [0u8; RESULT_BYTES];
                results[own]
                    .read_exact(&mut r)
                    .context("a tile's results end early")?;
                let v = |j: usize| {
                    f64::from_le_bytes(r[8 * j..8 * j + 8].try_into().unwrap_or_default())
                };
                out.normal.push([v(0), v(1), v(2)]);
                out.k1.push(v(3));
                out.k2.push(v(4));
                out.mean.push(v(5));
                out.gauss.push(v(6));
                out.d1.push([v(7), v(8), v(9)]);
                out.d2.push([v(10), v(11), v(12)]);
                if jet {
                    out.k1_sd.push(v(13));
                    out.k2_sd.push(v(14));
                }
                let status = i32::from_le_bytes(r[128..132].try_into().unwrap_or_default());
                out.status.push(status);
                let slot = if status == 0 {
                    0
                } else {
                    PointStatus::ALL
                        .iter()
                        .position(|s| i32::from(s.code()) == status)
                        .map_or(0, |i| i + 1)
                };
                counts[slot] += 1;
                if (first + k as u64).is_multiple_of(stride) {
                    summary.k1.push(v(3));
                    summary.k2.push(v(4));
                    summary.mean.push(v(5));
                    summary.gauss.push(v(6));
                    summary.k1_sd.push(v(13));
                }
                if let (Some(halos), Some((agree, compared))) =
                    (halos.as_mut(), summary.agreement.as_mut())
                {
                    let mine = r[132];
                    let mut error = None;
                    plan.tiles_near(&p, |t| {
                        if t == own {
                            return;
                        }
                        let mut b = [0u8];
                        if let Err(e) = halos[t].read_exact(&mut b) {
                            error = Some(e);
                        }
                        // Same axis: compare the signs.
                        if mine != 0 && b[0] != 0 && (mine - 1) / 2 == (b[0] - 1) / 2 {
                            *compared += 1;
                            *agree += u64::from(mine == b[0]);
                        }
                    });
                    if let Some(e) = error {
                        return Err(e).context("a tile's overlap signs end early");
                    }
                }
            }
            let positions = &chunk.points;
            let columns = out.columns(positions);
            let mut attributes = chunk.attributes.clone();
            if !run.keep_attributes {
                attributes.clear();
            }
            // The same names as an in-memory run gives them (`k1` → `k1_in`), noted once.
            let names = renamed.get_or_insert_with(|| {
                let mut carried = pipeline::Carried::new(attributes.clone(), None, true);
                carried.rename_clashes(&columns, run.input);
                carried.attributes.into_iter().map(|a| a.name).collect()
            });
            for (a, name) in attributes.iter_mut().zip(names.iter()) {
                a.name.clone_from(name);
            }
            let carried = pipeline::Carried::new(attributes, None, true);
            let columns: Vec<Column<'_>> = carried.insert(columns, 6);
            sink.write(&columns)?;
            Ok(())
        })
    })?;
    summary.status = status_text(&counts);
    Ok(())
}

/// The status counts (ok, then [`PointStatus::ALL`]) as [`pipeline::status_counts`] words them.
fn status_text(counts: &[u64]) -> String {
    let mut parts = vec![format!("ok {}", counts[0])];
    for (s, &c) in PointStatus::ALL.iter().zip(&counts[1..]) {
        if c > 0 {
            parts.push(format!("{} {c}", s.name()));
        }
    }
    parts.join(", ")
}
