//! One tile's evaluation, and the output written from every tile's results in input order.

use std::fs::File;
use std::io::{BufWriter, Read, Write};

use anyhow::{Context, Result};
use mls_core::normals::Orientation;
use mls_core::tiling::TilePlan;
use mls_core::{Frame, Parallelism, Point, PointStatus, Vector};
use mls_io::{Column, PlyFormat, PointStream};

use super::files::{TileReaders, Workspace};
use super::{TiledRun, TiledSummary};
use crate::evaluate::{self, CurvatureColumns};
use crate::pipeline::{self, Scale};
use crate::{CurvatureOptions, Method, NormalsMode};

/// Bytes of a result record: 16 `f64` (normal, k1, k2, mean, gauss, d1, d2, k1_sd, k2_sd),
/// the status and the estimated normal's code.
pub(super) const RESULT_BYTES: usize = 16 * 8 + 4 + 1;

/// The code of an estimated normal's sign for the overlap check: its largest component's
/// axis and sign (0 for none). Two estimates of one normal from overlapping neighbourhoods are
/// nearly parallel, so they share the axis unless it is a near tie, when they are not
/// compared.
fn sign_code(n: Option<&Vector>) -> u8 {
    let Some(n) = n else { return 0 };
    let axis = n.iamax();
    1 + 2 * axis as u8 + u8::from(n[axis] < 0.0)
}

/// Whether two tiles' sign codes of one point's normal are compared (both defined, on the same
/// axis) and, if so, whether they agree: the overlap check of a tiled run.
pub fn signs_agree(mine: u8, theirs: u8) -> Option<bool> {
    (mine != 0 && theirs != 0 && (mine - 1) / 2 == (theirs - 1) / 2).then_some(mine == theirs)
}

/// The results of one tile's own points.
#[derive(Debug)]
pub struct TileResult {
    /// The curvature columns of the tile's own points, in their order.
    pub columns: CurvatureColumns,
    /// The sign code of every loaded point's estimated normal (see `sign_code`), for the
    /// overlap check.
    pub codes: Vec<u8>,
    /// Where the normals came from, for the summary.
    pub source: String,
    /// With the file's normals, the share of sampled neighbour pairs over the tile whose
    /// normals agree in sign ([`pipeline::file_normals_agreement`]).
    pub agreement: Option<f64>,
}

/// The curvature at the tile's own points (`core`) of the surface of all its `points` (its
/// own and its halo), built in the whole cloud's `frame` with scale `h`: the step of a tiled
/// run that needs no file, shared by the binary's out-of-core path and the Python package's
/// Dask runner. `file_normals`, if given, are the points' normals; otherwise normals are
/// estimated and oriented by `orientation` over the tile.
///
/// With the file's normals, every own point's results are bitwise those of one run over the
/// whole cloud, provided the tile holds every point within [`mls_core::tiling::reach`] of
/// its own points.
#[allow(clippy::too_many_arguments)]
pub fn tile_curvature(
    points: &[Point],
    file_normals: Option<Vec<[f64; 3]>>,
    core: &[bool],
    h: f64,
    orientation: Orientation,
    frame: Frame,
    options: &CurvatureOptions,
    name: &str,
) -> Result<TileResult> {
    let orient = Orient::Rule(orientation);
    tile_curvature_oriented(points, file_normals, core, h, &orient, frame, options, name)
}

/// How a tile's estimated normals are oriented.
#[derive(Debug)]
pub(super) enum Orient {
    /// By a rule (`--orient`, or `up`).
    Rule(Orientation),
    /// Each towards its point's own scanner (E57 scans with poses, in memory the default).
    Towards(Vec<Point>),
}

/// [`tile_curvature`], with estimated normals oriented as `orient` says.
#[allow(clippy::too_many_arguments)]
pub(super) fn tile_curvature_oriented(
    points: &[Point],
    file_normals: Option<Vec<[f64; 3]>>,
    core: &[bool],
    h: f64,
    orient: &Orient,
    frame: Frame,
    options: &CurvatureOptions,
    name: &str,
) -> Result<TileResult> {
    let from_file = file_normals.is_some();
    let (orientation, viewpoints) = match orient {
        Orient::Rule(o) => (Some(*o), None),
        Orient::Towards(v) => (None, Some(&v[..])),
    };
    let s = &options.surface;
    let normals = pipeline::normals(
        file_normals,
        points,
        None,
        if from_file {
            NormalsMode::File
        } else {
            NormalsMode::Estimate
        },
        orientation,
        viewpoints,
        h,
        Parallelism::Rayon,
        name,
    )?;
    let codes: Vec<u8> = normals
        .normals
        .iter()
        .map(|n| sign_code(n.as_ref()))
        .collect();
    let queries: Vec<Point> = points
        .iter()
        .zip(core)
        .filter_map(|(p, &c)| c.then_some(*p))
        .collect();
    let build = evaluate::curvature_surface(false);
    let (surface, agreement) = if from_file {
        // One index, in the whole cloud's frame, for the check and the surface.
        let cloud = pipeline::index(points, frame, name)?;
        let agreement = pipeline::file_normals_agreement(&cloud, |i| normals.normals[i]);
        let surface = pipeline::surface(cloud, points, normals.normals, h, s.cutoff, name, build)?;
        (surface, agreement)
    } else {
        let surface =
            pipeline::surface_in(points, normals.normals, h, s.cutoff, frame, name, build)?;
        (surface, None)
    };
    let (columns, _) = crate::curvature_on(
        &queries,
        &surface,
        from_file,
        options,
        &crate::progress::NoProgress,
    );
    Ok(TileResult {
        columns,
        codes,
        source: normals.source,
        agreement,
    })
}

/// Evaluates one tile: reads its points, gets their normals, builds the surface in the
/// whole cloud's frame, evaluates its own points and writes their results; returns the
/// normals' description and, with the file's normals, their agreement over the tile
/// ([`TileResult::agreement`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn evaluate_tile(
    work: &Workspace,
    tile: usize,
    plan: &TilePlan,
    from_file: bool,
    towards_scanners: bool,
    record: usize,
    scale: &Scale,
    orientation: Orientation,
    default_orientation: bool,
    frame: Frame,
    options: &CurvatureOptions,
    name: &str,
) -> Result<(String, Option<f64>)> {
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
    let mut viewpoints = Vec::with_capacity(if towards_scanners { count } else { 0 });
    for r in bytes.chunks_exact(record) {
        points.push(Point::new(f64_at(r, 8), f64_at(r, 16), f64_at(r, 24)));
        if let Some(n) = &mut file_normals {
            n.push([f64_at(r, 32), f64_at(r, 40), f64_at(r, 48)]);
        } else if towards_scanners {
            viewpoints.push(Point::new(f64_at(r, 32), f64_at(r, 40), f64_at(r, 48)));
        }
    }
    let orient = if towards_scanners {
        Orient::Towards(viewpoints)
    } else {
        Orient::Rule(orientation)
    };
    drop(bytes);
    let core: Vec<bool> = points.iter().map(|p| plan.tile_of(p) == tile).collect();
    let tile_name = format!("{name} (tile {tile})");
    let TileResult {
        columns: out,
        codes,
        mut source,
        agreement,
    } = tile_curvature_oriented(
        &points,
        file_normals,
        &core,
        scale.h,
        &orient,
        frame,
        options,
        &tile_name,
    )?;
    if !from_file && default_orientation && !towards_scanners {
        source.push_str(" (a tiled run orients up unless --orient says otherwise)");
    }
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
    Ok((source, agreement))
}

/// Points sampled for the summary's percentiles (every k-th point): 5 MiB for its five columns.
const SUMMARY_SAMPLE: u64 = 1 << 17;

/// Reads the input again, `batch` points at a time, and writes each point with its tile's next
/// result.
pub(super) fn write_output(
    run: &TiledRun<'_>,
    input: &PointStream,
    work: &Workspace,
    plan: &TilePlan,
    template: &mls_io::LasTemplate,
    batch: u64,
    summary: &mut TiledSummary,
) -> Result<()> {
    let tiles = plan.tiles().len();
    let open = |suffix: &str| {
        TileReaders::new(
            (0..tiles)
                .map(|i| work.path(&format!("tile{i}.{suffix}")))
                .collect(),
        )
    };
    let mut results = open("out");
    let mut halos = summary.agreement.is_some().then(|| open("halo"));
    let jet = run.options.method == Method::Jet;
    let stride = summary.points.div_ceil(SUMMARY_SAMPLE).max(1);
    let mut counts = vec![0u64; PointStatus::ALL.len() + 1];
    let mut renamed: Option<Vec<String>> = None;
    // As an in-memory run writes ([`crate::pipeline::Output::write`]).
    let options = mls_io::WriteOptions {
        ply_format: if run.ascii {
            PlyFormat::Ascii
        } else {
            PlyFormat::BinaryLittleEndian
        },
        ply_quality: Some(crate::output::PLY_QUALITY),
        las: Some(template),
    };
    let rows = summary.points;
    mls_io::write_point_cloud_chunks(
        run.output,
        run.format,
        &options,
        rows,
        |sink| -> Result<()> {
            input.for_each_batch::<anyhow::Error>(run.keep_attributes, batch, |first, chunk| {
                let m = chunk.points.len();
                let mut out = CurvatureColumns::new(m, run.options);
                for (k, p) in chunk.points.iter().enumerate() {
                    let p = Point::from(*p);
                    let own = plan.tile_of(&p);
                    let mut r = [0u8; RESULT_BYTES];
                    results.read_exact(own, &mut r)?;
                    let v = |j: usize| {
                        f64::from_le_bytes(r[8 * j..8 * j + 8].try_into().unwrap_or_default())
                    };
                    out.normal[k] = [v(0), v(1), v(2)];
                    out.k1[k] = v(3);
                    out.k2[k] = v(4);
                    out.mean[k] = v(5);
                    out.gauss[k] = v(6);
                    out.d1[k] = [v(7), v(8), v(9)];
                    out.d2[k] = [v(10), v(11), v(12)];
                    if jet {
                        out.k1_sd[k] = v(13);
                        out.k2_sd[k] = v(14);
                    }
                    let status = i32::from_le_bytes(r[128..132].try_into().unwrap_or_default());
                    out.status[k] = status;
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
                            if let Err(e) = halos.read_exact(t, &mut b) {
                                error = error.take().or(Some(e));
                            }
                            if let Some(same) = signs_agree(mine, b[0]) {
                                *compared += 1;
                                *agree += u64::from(same);
                            }
                        });
                        if let Some(e) = error {
                            return Err(e);
                        }
                    }
                }
                let positions = &chunk.points;
                let columns = out.columns(positions);
                // Moved, not copied: the chunk is this call's (empty without attributes).
                let mut attributes = chunk.attributes;
                // The same names as an in-memory run gives them (`k1` → `k1_in`), noted once.
                let names = renamed.get_or_insert_with(|| {
                    let named = attributes
                        .iter()
                        .map(|a| mls_io::Attribute {
                            name: a.name.clone(),
                            data: mls_io::AttributeData::with_capacity(a.data.ty(), 0),
                        })
                        .collect();
                    let mut carried = pipeline::Carried::new(named, None, true);
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
        },
    )?;
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
