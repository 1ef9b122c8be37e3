//! `mlscurv curvature` on a cloud larger than memory: tiles with halos on disk.
//!
//! The input is read in batches ([`mls_io::PointStream`]: LAS/LAZ, PLY, XYZ/CSV, E57), in
//! four streaming passes, and the tiles one at a time in between (a file that is not LAS is
//! read once more first, for its box and, for text, what its columns are):
//! 1. *scan*: the exact bounding box (the whole cloud's [`Frame`]) and the points per cell of
//!    a grid ([`mls_core::tiling`]);
//! 2. *spacing* (without `--h`): h from the points of a few tiles spread over the cloud;
//! 3. *tiles*: each point is appended to the file of every tile that loads it (its own, and
//!    those whose box lies within the reach, [`tiling::reach`]);
//! 4. per tile: normals, the surface in the whole cloud's frame, the curvature at its own
//!    points, appended to the tile's result file (the tile's input file is then removed);
//! 5. *write*: the input is read again, and each point's attributes are written with the
//!    next result of its tile, in input order, in any output format but E57
//!    ([`mls_io::write_point_cloud_chunks`]): the file an in-memory run writes.
//!
//! With the file's normals and a given h the results are bitwise those of one in-memory run:
//! a result depends only on the samples within the reach, all of them in the tile, and the
//! surface sums them in the same order ([`mls_core::Frame`]). Estimated normals are estimated
//! and oriented per tile; their agreement in the overlaps is measured and reported.
//!
//! Temporary files live in one directory (in the output's directory unless `--temp-dir`),
//! removed on success, on error and on Ctrl-C; the free space is checked first.

mod files;
mod tile;

use std::path::Path;

use anyhow::{Context, Result, bail};
use mls_core::normals::{DEFAULT_SPACING_NEIGHBOURS, Orientation, suggest_h};
use mls_core::tiling::{self, Grid, TilePlan};
use mls_core::{Frame, IndexedCloud, Parallelism, Point, Vector};
use mls_io::{FileFormat, PointStream};

use files::{TileWriters, Workspace};
pub use files::{available_memory, parse_size};
use tile::{RESULT_BYTES, evaluate_tile, write_output};
pub use tile::{TileResult, signs_agree, tile_curvature};

use crate::evaluate;
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

/// The spacing is measured on up to [`SPACING_TILES`] tiles of this many points spread over
/// the cloud: the same sample whatever the budget, once it holds them.
const SPACING_TILE: u64 = 1 << 18;

/// See [`SPACING_TILE`].
const SPACING_TILES: u64 = 8;

/// What a tiled run is asked to do.
#[derive(Debug)]
pub struct TiledRun<'a> {
    pub input: &'a Path,
    /// The input's format.
    pub input_format: FileFormat,
    /// The names of a text input's columns (`--columns`).
    pub columns: Option<&'a mls_io::ColumnNames>,
    pub output: &'a Path,
    pub format: FileFormat,
    /// PLY output in ASCII rather than binary.
    pub ascii: bool,
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

/// Points per batch of the write stage, which runs when no tile is loaded: as many as the
/// tiles' share of the budget holds, at most the reader's own batch. A point of a batch costs
/// its results as columns and as output records (twice [`RESULT_BYTES`]) and its input record
/// three times: read, decoded into attributes, written again. Measured as the slope of peak
/// resident memory over the batch size: about 500 bytes a point with 54-byte records (2M
/// points, `--memory 100MiB`, batches of 25,000 to 100,000 points).
fn write_batch(budget: u64, record_in: u64) -> u64 {
    let per_point = 2 * RESULT_BYTES as u64 + 24 + 3 * record_in;
    (budget.saturating_sub(FIXED_BYTES) / per_point).max(1 << 10)
}

/// The least share of overlap points whose estimated normals have the same sign in both
/// tiles before a warning. Airborne terrain measures 99.9–100 % (`tiled` tests); a closed
/// cylinder, which `up` cannot orient, 56.6 %.
pub const MIN_OVERLAP_AGREEMENT: f64 = 0.99;

/// The directory of `output`.
fn output_dir(output: &Path) -> std::path::PathBuf {
    output
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf()
}

/// The directory in which the tiles' temporary directory is made: `--temp-dir`, else the
/// output's.
fn temp_parent(run: &TiledRun<'_>) -> std::path::PathBuf {
    run.temp_dir
        .map_or_else(|| output_dir(run.output), Path::to_path_buf)
}

/// Whether a run over `points` points fits in `budget` bytes without tiles.
pub fn fits_in_memory(points: u64, budget: u64) -> bool {
    in_memory_bytes(points) <= budget
}

/// The memory a run over `points` points is planned to need without tiles: what a tile of
/// that many points is planned to need ([`BYTES_PER_POINT`] and [`FIXED_BYTES`]). (An
/// in-memory run measures less: 235–247 bytes a point on a million points,
/// docs/benchmarks.md.)
pub fn in_memory_bytes(points: u64) -> u64 {
    points
        .saturating_mul(BYTES_PER_POINT)
        .saturating_add(FIXED_BYTES)
}

/// The least budget a tiled run takes: room for tiles of 1000 points.
pub const MIN_BUDGET: u64 = FIXED_BYTES + 1000 * BYTES_PER_POINT;

/// The points a tile may load under a budget of `budget` bytes; `given` is the budget as the
/// user wrote it (`--memory 64 MiB`, `memory='64MiB'`), for the error when it is below
/// [`MIN_BUDGET`].
pub fn tile_capacity(budget: u64, given: &str) -> Result<u64, String> {
    if budget < MIN_BUDGET {
        return Err(format!(
            "{given}: too small; a tiled run needs at least {} MiB",
            // Rounded up: the least whole number of MiB that is enough.
            MIN_BUDGET.div_ceil(1 << 20)
        ));
    }
    Ok((budget - FIXED_BYTES) / BYTES_PER_POINT)
}

/// A size in bytes for a message: in whole GiB or MiB when it is one (`64 MiB`), else in MiB
/// with one decimal (`445.5 MiB`), and below 1 MiB in whole KiB or bytes.
pub fn describe_size(bytes: u64) -> String {
    for (shift, unit) in [(30, "GiB"), (20, "MiB")] {
        if bytes >= 1 << shift && bytes.is_multiple_of(1 << shift) {
            return format!("{} {unit}", bytes >> shift);
        }
    }
    if bytes >= 1 << 20 {
        format!("{:.1} MiB", bytes as f64 / f64::from(1 << 20))
    } else if bytes >= 1 << 10 && bytes.is_multiple_of(1 << 10) {
        format!("{} KiB", bytes >> 10)
    } else {
        format!("{bytes} bytes")
    }
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
    // The tiles' directory, created (and removed) now rather than after the first passes
    // over the input: one this user cannot write to is refused before any work.
    drop(Workspace::probe(&temp_parent(run))?);
    let s = &options.surface;
    let jet = (options.method == Method::Jet).then(|| evaluate::jet_config(false));
    let options_in = mls_io::ReadOptions {
        columns: run.columns.cloned(),
    };
    let reader = PointStream::open(run.input, run.input_format, &options_in)?;
    let n = reader.len();
    if run.keep_attributes {
        // As in memory, before any work: an attribute the output cannot hold.
        let named = reader
            .attributes()
            .iter()
            .map(|(name, ty)| mls_io::Attribute {
                name: name.clone(),
                data: mls_io::AttributeData::with_capacity(*ty, 0),
            })
            .collect();
        pipeline::Carried::new(named, None, true).check(run.format, run.input)?;
    }
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
    let (header_lo, header_hi) = reader.bounds();
    let record_in = reader.record_len();
    let capacity = tile_capacity(
        run.budget,
        &format!("--memory {}", describe_size(run.budget)),
    )
    .map_err(anyhow::Error::msg)?;

    // 1. The box and the counts.
    let grid = Grid::new(Vector::from(header_lo), Vector::from(header_hi), GRID_CELLS)
        .with_context(|| format!("{name}: the header's bounding box"))?;
    let mut counts = vec![0u64; grid.len()];
    let (mut lo, mut hi) = (
        Vector::repeat(f64::INFINITY),
        Vector::repeat(f64::NEG_INFINITY),
    );
    t.time("scan", || {
        reader.for_each_batch::<anyhow::Error>(false, u64::MAX, |_, chunk| {
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
            sampled_scale(&reader, &grid, &counts, capacity, s.h_factor, &name)
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

    // Disk: the tile files (points with their halos, each removed once its tile is done),
    // the results, and the output, written last.
    let out_dir = output_dir(run.output);
    let parent = temp_parent(run);
    // Estimated normals of E57 scans that all have a pose are oriented towards each point's
    // own scanner, as in memory, unless --orient says otherwise: its position goes with the
    // point (where file normals would).
    let towards_scanners = !from_file && s.orient.is_none() && reader.scans_have_poses();
    let record = if from_file || towards_scanners {
        56
    } else {
        32
    };
    let loaded: u64 = plan.tiles().iter().map(|t| t.loaded).sum();
    let results = n * (RESULT_BYTES as u64 + u64::from(!from_file));
    let output = n * output_bytes(record_in, run.format, run.ascii);
    let free = |dir: &Path| {
        fs4::available_space(dir)
            .with_context(|| format!("{}: cannot measure the free disk space", dir.display()))
    };
    let short = |dir: &Path, needed: u64, what: &str| -> Result<()> {
        let free = free(dir)?;
        if free < needed {
            bail!(
                "{}: {:.1} GB free, but a tiled run of {n} points needs about {:.1} GB for {what}; \
                 free some space or choose --temp-dir",
                dir.display(),
                free as f64 / 1e9,
                needed as f64 / 1e9
            );
        }
        Ok(())
    };
    let temporary = loaded * record + results;
    if run.temp_dir.is_none() || same_file_system(&parent, &out_dir) {
        short(
            &parent,
            temporary.max(results + output),
            "its temporary tiles and the output",
        )?;
    } else {
        short(&parent, temporary, "its temporary tiles")?;
        short(&out_dir, output, "the output")?;
    }
    let work = Workspace::new(&parent, run.output)?;

    // 3. The tile files, in input order.
    t.time("tiles", || -> Result<()> {
        let mut files = TileWriters::create(
            (0..tiles)
                .map(|i| work.path(&format!("tile{i}.pts")))
                .collect(),
        )?;
        reader.for_each_batch::<anyhow::Error>(false, u64::MAX, |first, chunk| {
            let viewpoints = if towards_scanners {
                chunk.scans.as_ref().and_then(mls_io::Scans::viewpoints)
            } else {
                None
            };
            for (k, p) in chunk.points.iter().enumerate() {
                let mut bytes = [0u8; 56];
                bytes[..8].copy_from_slice(&(first + k as u64).to_le_bytes());
                for (i, c) in p.iter().enumerate() {
                    bytes[8 + 8 * i..16 + 8 * i].copy_from_slice(&c.to_le_bytes());
                }
                let extra = match (&chunk.normals, &viewpoints) {
                    (Some(normals), _) if from_file => Some(normals[k]),
                    (_, Some(viewpoints)) => Some(viewpoints[k]),
                    _ => None,
                };
                if let Some(extra) = extra {
                    for (i, c) in extra.iter().enumerate() {
                        bytes[32 + 8 * i..40 + 8 * i].copy_from_slice(&c.to_le_bytes());
                    }
                }
                let mut error = None;
                plan.tiles_near(&Point::from(*p), |tile| {
                    if let Err(e) = files.write(tile, &bytes[..record as usize]) {
                        error = error.take().or(Some(e));
                    }
                });
                if let Some(e) = error {
                    return Err(e);
                }
            }
            Ok(())
        })?;
        files.finish()
    })?;

    // 4. Each tile.
    let orientation = s.orient.unwrap_or(Orientation::Up);
    let mut normals_source = String::new();
    let bar = t.progress().bar(n as usize, "curvature");
    let mut done = 0usize;
    // The file normals' agreement, summed over tiles weighted by their own points.
    let mut agreement = (0.0, 0u64);
    t.measure("curvature", || -> Result<()> {
        for tile in 0..tiles {
            let (source, agree) = evaluate_tile(
                &work,
                tile,
                &plan,
                from_file,
                towards_scanners,
                record as usize,
                &scale,
                orientation,
                s.orient.is_none(),
                frame,
                options,
                &name,
            )?;
            if normals_source.is_empty() {
                normals_source = source;
            }
            let own = plan.tiles()[tile].points;
            if let Some(a) = agree {
                agreement.0 += a * own as f64;
                agreement.1 += own;
            }
            done += own as usize;
            bar.set(done);
        }
        Ok(())
    })?;
    drop(bar);
    if agreement.1 > 0 {
        let agree = agreement.0 / agreement.1 as f64;
        if let Some(w) = pipeline::file_normals_warning(agree, &name) {
            pipeline::print_warning(w);
        }
    }

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
    // The layout of LAS output: the LAS input's when its attributes are carried, else the
    // one a whole table gets from its box, as in memory.
    let template = match reader.las_template() {
        Some(t) if run.keep_attributes => t.clone(),
        _ => mls_io::LasTemplate::fitted(lo.into(), hi.into()),
    };
    t.time("write", || {
        let batch = write_batch(run.budget, record_in);
        write_output(run, &reader, &work, &plan, &template, batch, &mut summary)
    })?;
    drop(work);
    if let Some((agree, compared)) = summary.agreement
        && compared > 0
        && (agree as f64) < MIN_OVERLAP_AGREEMENT * compared as f64
    {
        pipeline::print_warning(format!(
            "{name}: the estimated normals' signs differ between tiles at {:.1}% of the \
             overlap points (at most {:.0}% expected): the cloud is not oriented one way \
             across tiles (a tiled run orients up: a sheet seen from above), so the sign and \
             size of the curvature are wrong near the flips. Give `--orient viewpoint:X,Y,Z` \
             for a scan from one position, or a larger `--memory` to run it whole",
            100.0 * (1.0 - agree as f64 / compared as f64),
            100.0 * (1.0 - MIN_OVERLAP_AGREEMENT)
        ));
    }
    Ok(summary)
}

/// Bytes a point of the output takes: the input's record (`record_in`), the computed columns as
/// `f64` extra bytes and the status; LAZ compresses, to about half of that on LiDAR clouds
/// (measured: 91 of 190 bytes); text (CSV, XYZ, ASCII PLY) writes an 8-byte float in up to
/// 24 characters with its separator, about 20 on curvature output: 2.5 times the binary size.
fn output_bytes(record_in: u64, format: FileFormat, ascii: bool) -> u64 {
    let record = record_in + 16 * 8 + 4;
    match format {
        FileFormat::Laz => record * 3 / 4,
        FileFormat::Csv | FileFormat::Xyz => record * 5 / 2,
        FileFormat::Ply if ascii => record * 5 / 2,
        _ => record,
    }
}

/// Whether two directories are on one file system (Unix: the same device); elsewhere, assumed.
fn same_file_system(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev(),
            _ => true,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (a, b);
        true
    }
}

/// h from the spacing of up to [`SPACING_TILES`] tiles of [`SPACING_TILE`] points spread
/// over the cloud (all of a cloud that small: then h is the in-memory run's), fewer if the
/// budget's `capacity` holds fewer.
fn sampled_scale(
    input: &PointStream,
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
    input.for_each_batch::<anyhow::Error>(false, u64::MAX, |_, chunk| {
        for p in &chunk.points {
            let p = Point::from(*p);
            if chosen[plan.tile_of(&p)] {
                points.push(p);
            }
        }
        Ok(())
    })?;
    let par = Parallelism::Rayon;
    // Indexed and sampled as an in-memory run is: when the tiles taken are the whole cloud,
    // the points are in file order, and h is the in-memory run's.
    let cloud = IndexedCloud::new(&points, par).with_context(|| name.to_owned())?;
    let stats = cloud
        .spacing(DEFAULT_SPACING_NEIGHBOURS, par)
        .with_context(|| format!("{name}: cannot measure the point spacing"))?;
    let h = suggest_h(&stats, factor)
        .with_context(|| format!("{name}: cannot derive h from the spacing"))?;
    Ok(Scale {
        h,
        why: format!(
            "{factor} × median local spacing {} over {} neighbours at {} of the {} points in \
             {take} of {} tiles",
            crate::pipeline::Length(stats.spacing),
            stats.k,
            stats.measured,
            points.len(),
            tiles.len()
        ),
        spacing: Some(stats),
        factor: Some(factor),
    })
}

#[cfg(test)]
mod tests {
    use super::describe_size;

    #[test]
    fn sizes_read_as_written_or_in_mib() {
        assert_eq!(describe_size(64 << 20), "64 MiB");
        assert_eq!(describe_size(2 << 30), "2 GiB");
        // A million points' estimate: 400,000,000 bytes and 64 MiB.
        assert_eq!(describe_size(400_000_000 + (64 << 20)), "445.5 MiB");
        assert_eq!(describe_size(3 << 10), "3 KiB");
        assert_eq!(describe_size(1000), "1000 bytes");
    }
}
