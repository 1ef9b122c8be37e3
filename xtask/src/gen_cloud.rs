//! `gen-cloud`: a large realistic airborne-LiDAR test cloud (mls-shapes' [`Scene`]) written as
//! LAS 1.4 or LAZ chunk by chunk, so that runs of 10^8 points are reproducible from a seed
//! and the generator's memory does not grow with the count.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use las::point::Format;
use las::{
    Builder, GpsTimeType, PointData, PointDataBuilder, Transform, Vector, Version, Vlr, Writer,
};
use mls_shapes::{Scene, SceneConfig, ScenePoint};
use rayon::prelude::*;

/// Points generated and encoded per step: the unit of memory.
const CHUNK_POINTS: usize = 1 << 16;

/// Coordinate scale: millimetres, as survey deliveries use.
const SCALE: f64 = 0.001;

/// Bytes of a point format 6 record.
const FORMAT6_BYTES: usize = 30;

/// Extra Bytes VLR (LAS 1.4 R15, section 2.5.7): LASF_Spec record 4, 192 bytes a descriptor.
const EXTRA_BYTES_USER_ID: &str = "LASF_Spec";
const EXTRA_BYTES_RECORD_ID: u16 = 4;
const DESCRIPTOR_BYTES: usize = 192;
/// Data type 10 of the descriptor: `double`.
const TYPE_F64: u8 = 10;
const NORMAL_NAMES: [&str; 3] = ["nx", "ny", "nz"];

/// Options of `gen-cloud`.
#[derive(Debug)]
pub(crate) struct Options {
    points: u64,
    output: PathBuf,
    seed: u64,
    noise: f64,
    normals: bool,
    /// Rows (along `y`) and columns (along `x`) of tiles.
    tiles: (u32, u32),
}

/// The arguments of `cargo xtask gen-cloud`.
#[derive(Clone, Debug, clap::Parser)]
#[command(name = "gen-cloud")]
pub(crate) struct Args {
    /// Number of points (underscores allowed: 100_000_000).
    #[arg(long, value_parser = parse_count)]
    points: u64,
    /// Output file, .las or .laz, relative to the directory the task was run from.
    #[arg(short = 'o', long, value_name = "OUT.las|OUT.laz")]
    output: PathBuf,
    /// Seed of the scene.
    #[arg(long, default_value_t = SceneConfig::default().seed)]
    seed: u64,
    /// Standard deviation of the range noise, metres.
    #[arg(long, value_name = "SIGMA", default_value_t = SceneConfig::default().range_noise)]
    noise: f64,
    /// Add the true normals as f64 extra bytes nx ny nz.
    #[arg(long)]
    normals: bool,
    /// Rows (along y) by columns (along x) of tiles, written as OUT_r{i}_c{j}.laz.
    #[arg(long, value_name = "RxC", value_parser = parse_tiles, default_value = "1x1")]
    tiles: (u32, u32),
}

impl Args {
    /// The options, with a relative output taken relative to `invoked_from`, the directory
    /// `cargo xtask` was run from (the xtask itself runs at the project root).
    pub(crate) fn options(self, invoked_from: &Path) -> Options {
        Options {
            points: self.points,
            output: invoked_from.join(self.output),
            seed: self.seed,
            noise: self.noise,
            normals: self.normals,
            tiles: self.tiles,
        }
    }
}

impl Options {
    /// Parses `gen-cloud`'s arguments (without the task's name).
    pub(crate) fn parse(args: &[String], invoked_from: &Path) -> Result<Self> {
        use clap::Parser as _;
        let args = Args::try_parse_from(
            std::iter::once("gen-cloud").chain(args.iter().map(String::as_str)),
        )
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().trim_end()))?;
        Ok(args.options(invoked_from))
    }
}

/// A point count, with `_` separators allowed.
fn parse_count(text: &str) -> Result<u64> {
    text.replace('_', "")
        .parse()
        .with_context(|| format!("gen-cloud: --points {text}"))
}

/// `RxC`, both at least 1.
fn parse_tiles(text: &str) -> Result<(u32, u32)> {
    let parsed = text
        .split_once(['x', 'X'])
        .and_then(|(r, c)| Some((r.parse::<u32>().ok()?, c.parse::<u32>().ok()?)));
    match parsed {
        Some((r, c)) if r >= 1 && c >= 1 && u64::from(r) * u64::from(c) <= 10_000 => Ok((r, c)),
        _ => bail!("gen-cloud: --tiles {text}: expected RxC with R, C ≥ 1 and at most 10000 tiles"),
    }
}

/// One output file: its writer and the buffer its share of a chunk is encoded into.
struct Tile {
    path: PathBuf,
    writer: Writer<BufWriter<File>>,
    transforms: Vector<Transform>,
    data: PointData,
    points: u64,
}

pub(crate) fn run(options: &Options) -> Result<()> {
    let start = Instant::now();
    let config = SceneConfig {
        seed: options.seed,
        range_noise: options.noise,
        ..SceneConfig::default()
    };
    let scene = Scene::new(config, options.points).context("gen-cloud")?;
    let compressed = match options
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("laz") => true,
        Some("las") => false,
        _ => bail!(
            "gen-cloud: {} must end in .las or .laz",
            options.output.display()
        ),
    };
    if let Some(dir) = options
        .output
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
    {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let area = scene.area();
    let (rows, cols) = options.tiles;
    let tile_w = (area.max.x - area.min.x) / f64::from(cols);
    let tile_h = (area.max.y - area.min.y) / f64::from(rows);
    let mut tiles = Vec::with_capacity((rows * cols) as usize);
    for r in 0..rows {
        for c in 0..cols {
            let path = if (rows, cols) == (1, 1) {
                options.output.clone()
            } else {
                tile_path(&options.output, r, c)
            };
            // One offset for every tile, the area's minimum: a point's stored coordinates are
            // then the same in a tile as in the whole cloud's file, so runs over the tiles and
            // over the whole file see the same points (bit for bit).
            let min = [area.min.x, area.min.y, area.min.z];
            let opened = open(&path, min, compressed, options.normals);
            match opened {
                Ok(tile) => tiles.push(tile),
                Err(e) => {
                    abandon(tiles);
                    return Err(e);
                }
            }
        }
    }
    let tile_of = |p: &ScenePoint| {
        // Points a little outside the area (range noise) go to the nearest tile.
        let c = ((p.position.x - area.min.x) / tile_w).floor().max(0.0) as usize;
        let r = ((p.position.y - area.min.y) / tile_h).floor().max(0.0) as usize;
        r.min(rows as usize - 1) * cols as usize + c.min(cols as usize - 1)
    };
    if let Err(e) = write(&scene, &mut tiles, options.normals, tile_of) {
        abandon(tiles);
        return Err(e);
    }
    let mut files = Vec::with_capacity(tiles.len());
    let mut open_tiles = tiles.into_iter();
    while let Some(mut tile) = open_tiles.next() {
        if let Err(e) = tile.writer.close() {
            let message = format!("cannot finish {}", tile.path.display());
            abandon(std::iter::once(tile).chain(open_tiles).collect());
            return Err(e).context(message);
        }
        files.push((tile.path, tile.points));
    }
    let seconds = start.elapsed().as_secs_f64();
    let named = match files.as_slice() {
        [(path, _)] => path.display().to_string(),
        _ => format!(
            "{} files {}_r*_c* ({} to {} points each)",
            files.len(),
            options.output.with_extension("").display(),
            files.iter().map(|f| f.1).min().unwrap_or(0),
            files.iter().map(|f| f.1).max().unwrap_or(0),
        ),
    };
    println!(
        "gen-cloud: {} points ({} strip(s), seed {}, noise {} m{}), area {:.1} m × {:.1} m at ({:.1}, {:.1}), {named}, {seconds:.2} s ({:.0} points/s)",
        scene.len(),
        scene.strips(),
        options.seed,
        options.noise,
        if options.normals { ", normals" } else { "" },
        area.max.x - area.min.x,
        area.max.y - area.min.y,
        area.min.x,
        area.min.y,
        scene.len() as f64 / seconds,
    );
    Ok(())
}

/// `out_r{i}_c{j}.laz` beside `out.laz`.
fn tile_path(output: &Path, r: u32, c: u32) -> PathBuf {
    let stem = output
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let ext = output
        .extension()
        .map_or_else(String::new, |e| e.to_string_lossy().into_owned());
    output.with_file_name(format!("{stem}_r{r}_c{c}.{ext}"))
}

/// Creates a tile's file with the LAS 1.4 point format 6 header, offset at `min` (the whole
/// area's, for every tile).
fn open(path: &Path, min: [f64; 3], compressed: bool, normals: bool) -> Result<Tile> {
    let mut builder = Builder::from(Version::new(1, 4));
    let mut format = Format::new(6).context("point format 6")?;
    format.is_compressed = compressed;
    if normals {
        format.extra_bytes = (3 * size_of::<f64>()) as u16;
        builder.vlrs.push(Vlr {
            user_id: EXTRA_BYTES_USER_ID.to_owned(),
            record_id: EXTRA_BYTES_RECORD_ID,
            description: "Extra Bytes".to_owned(),
            data: NORMAL_NAMES
                .iter()
                .flat_map(|name| descriptor(name, "unit surface normal"))
                .collect(),
        });
    }
    builder.point_format = format;
    let transform = |offset: f64| Transform {
        scale: SCALE,
        offset,
    };
    let transforms = Vector {
        x: transform(min[0]),
        y: transform(min[1]),
        z: transform(min[2]),
    };
    builder.transforms = transforms;
    // The scene's times are adjusted standard GPS time.
    builder.gps_time_type = GpsTimeType::Standard;
    "mls-curvature gen-cloud".clone_into(&mut builder.generating_software);
    let header = builder
        .into_header()
        .with_context(|| format!("header of {}", path.display()))?;
    let file = File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let writer = Writer::new(BufWriter::new(file), header)
        .with_context(|| format!("cannot start {}", path.display()))?;
    let data = PointDataBuilder::new().for_header(writer.header()).build();
    Ok(Tile {
        path: path.to_owned(),
        writer,
        transforms,
        data,
        points: 0,
    })
}

/// An Extra Bytes descriptor (LAS 1.4 R15, table 24) of one `double` without options:
/// reserved (2 bytes), data type, options, name (32), unused (4), then no-data, min, max,
/// scale and offset (each 8 bytes of value and 16 deprecated), and a description (32).
fn descriptor(name: &str, description: &str) -> [u8; DESCRIPTOR_BYTES] {
    let mut d = [0u8; DESCRIPTOR_BYTES];
    d[2] = TYPE_F64;
    d[4..4 + name.len()].copy_from_slice(name.as_bytes());
    let at = DESCRIPTOR_BYTES - 32;
    d[at..at + description.len()].copy_from_slice(description.as_bytes());
    d
}

/// Generates the points chunk by chunk (each chunk in parallel: every point is a pure
/// function of its index) and hands each tile its share.
fn write(
    scene: &Scene,
    tiles: &mut [Tile],
    normals: bool,
    tile_of: impl Fn(&ScenePoint) -> usize,
) -> Result<()> {
    let record = FORMAT6_BYTES + if normals { 24 } else { 0 };
    let mut chunk = Vec::with_capacity(CHUNK_POINTS);
    // The chunk's points grouped by tile (a counting sort): tile t has
    // order[starts[t]..starts[t + 1]].
    let mut tile_of_point = Vec::with_capacity(CHUNK_POINTS);
    let mut order = vec![0; CHUNK_POINTS];
    let mut starts = vec![0; tiles.len() + 1];
    let mut first = 0;
    while first < scene.len() {
        let end = scene.len().min(first + CHUNK_POINTS as u64);
        // A chunk's length fits in usize; rayon splits only usize ranges evenly.
        (0..(end - first) as usize)
            .into_par_iter()
            .map(|k| scene.point(first + k as u64))
            .collect_into_vec(&mut chunk);
        tile_of_point.clear();
        tile_of_point.extend(chunk.iter().map(&tile_of));
        starts.fill(0);
        for &t in &tile_of_point {
            starts[t + 1] += 1;
        }
        for t in 0..tiles.len() {
            starts[t + 1] += starts[t];
        }
        let mut next = starts.clone();
        for (i, &t) in tile_of_point.iter().enumerate() {
            order[next[t]] = i;
            next[t] += 1;
        }
        for (t, tile) in tiles.iter_mut().enumerate() {
            let mine = &order[starts[t]..starts[t + 1]];
            if mine.is_empty() {
                continue;
            }
            let bytes = tile.data.resize_for(mine.len());
            for (&i, out) in mine.iter().zip(bytes.chunks_exact_mut(record)) {
                encode(out, &chunk[i], &tile.transforms, normals)?;
            }
            tile.writer
                .write_points(&tile.data)
                .with_context(|| format!("cannot write {}", tile.path.display()))?;
            tile.points += mine.len() as u64;
        }
        first = end;
    }
    Ok(())
}

/// Encodes one point as a format 6 record (with `f64` normals as extra bytes).
fn encode(record: &mut [u8], p: &ScenePoint, t: &Vector<Transform>, normals: bool) -> Result<()> {
    let xyz = [
        t.x.inverse(p.position.x)?,
        t.y.inverse(p.position.y)?,
        t.z.inverse(p.position.z)?,
    ];
    for (i, v) in xyz.iter().enumerate() {
        record[4 * i..4 * i + 4].copy_from_slice(&v.to_le_bytes());
    }
    record[12..14].copy_from_slice(&p.intensity.to_le_bytes());
    // Return number 1 of 1.
    record[14] = (p.return_number & 0xF) | (1 << 4);
    // Scan direction positive (+x), edge of flight line on the last point of a line.
    record[15] = (1 << 6) | (u8::from(p.edge_of_line) << 7);
    record[16] = p.class.code();
    record[17] = 0;
    let angle = (p.scan_angle_deg / 0.006).round() as i16;
    record[18..20].copy_from_slice(&angle.to_le_bytes());
    record[20..22].copy_from_slice(&p.strip.to_le_bytes());
    record[22..30].copy_from_slice(&p.gps_time.to_le_bytes());
    if normals {
        for (i, v) in p.normal.iter().enumerate() {
            let at = FORMAT6_BYTES + 8 * i;
            record[at..at + 8].copy_from_slice(&v.to_le_bytes());
        }
    }
    Ok(())
}

/// Drops writers after a failure without closing them: the `las` writer closes itself when
/// dropped and panics if that fails, which it may after a failed write.
fn abandon(tiles: Vec<Tile>) {
    for tile in tiles {
        std::mem::forget(tile.writer);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SEED: u64 = 14;

    fn options(dir: &Path, name: &str, points: u64, tiles: (u32, u32)) -> Options {
        Options {
            points,
            output: dir.join(name),
            seed: SEED,
            noise: 0.02,
            normals: true,
            tiles,
        }
    }

    /// The generator's files read back through mls-io with the scene's points, normals and
    /// classes.
    #[test]
    fn gen_cloud_reads_back_through_mls_io() -> Result<()> {
        let dir = tempfile::tempdir()?;
        let scene = Scene::new(
            SceneConfig {
                seed: SEED,
                ..SceneConfig::default()
            },
            5000,
        )?;
        for name in ["cloud.laz", "cloud.las"] {
            run(&options(dir.path(), name, 5000, (1, 1)))?;
            let cloud = mls_io::read_point_cloud(&dir.path().join(name))?;
            assert_eq!(cloud.len(), 5000, "{name}");
            let normals = cloud.normals.as_ref().context("no normals read")?;
            let class = cloud
                .attributes
                .iter()
                .find(|a| a.name == "classification")
                .context("no classification")?;
            let mls_io::AttributeData::U8(class) = &class.data else {
                bail!("classification is not u8");
            };
            for (i, p) in scene.scan().enumerate() {
                let q = cloud.points[i];
                let stored = (0..3)
                    .map(|k| (q[k] - p.position[k]).abs())
                    .fold(0.0, f64::max);
                assert!(
                    stored <= 0.5 * SCALE + 1e-9,
                    "{name} point {i}: off by {stored}"
                );
                assert_eq!(
                    normals[i],
                    [p.normal.x, p.normal.y, p.normal.z],
                    "{name} {i}"
                );
                assert_eq!(class[i], p.class.code(), "{name} {i}");
            }
        }
        Ok(())
    }

    /// Tiles split the points by position and together hold all of them once.
    #[test]
    fn gen_cloud_tiles_partition_the_points() -> Result<()> {
        let dir = tempfile::tempdir()?;
        run(&options(dir.path(), "t.laz", 20_000, (2, 3)))?;
        let mut total = 0;
        let mut boxes = Vec::new();
        for r in 0..2 {
            for c in 0..3 {
                let path = dir.path().join(format!("t_r{r}_c{c}.laz"));
                let cloud = mls_io::read_point_cloud(&path)?;
                total += cloud.len();
                let min_x = cloud.points.iter().map(|p| p[0]).fold(f64::MAX, f64::min);
                let max_x = cloud.points.iter().map(|p| p[0]).fold(f64::MIN, f64::max);
                boxes.push((r, c, min_x, max_x));
            }
        }
        assert_eq!(total, 20_000);
        // Columns are ordered along x.
        for &(r, c, _, max_x) in &boxes {
            for &(r2, c2, min_x2, _) in &boxes {
                if r == r2 && c2 == c + 1 {
                    assert!(max_x <= min_x2 + 1e-3, "{r} {c}");
                }
            }
        }
        Ok(())
    }

    #[test]
    fn gen_cloud_rejects_bad_arguments() {
        let here = Path::new("/tmp");
        let args = |a: &[&str]| a.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
        assert!(Options::parse(&args(&["--points", "10"]), here).is_err());
        assert!(Options::parse(&args(&["-o", "x.laz"]), here).is_err());
        assert!(Options::parse(&args(&["--points", "1_000", "-o", "x.laz"]), here).is_ok());
        for tiles in ["0x2", "3", "2x", "axb"] {
            assert!(parse_tiles(tiles).is_err(), "{tiles}");
        }
        assert_eq!(parse_tiles("2x3").ok(), Some((2, 3)));
        let bad_ext = options(here, "x.txt", 10, (1, 1));
        assert!(run(&bad_ext).is_err());
    }
}
