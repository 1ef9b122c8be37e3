//! Point-cloud readers and writers for mls-curvature: PLY (ASCII and binary, either byte
//! order), XYZ/TXT/PTS (whitespace, comma or semicolon separated), CSV with a header, LAS/LAZ (through the
//! `las` crate; computed columns as LAS extra bytes on output), and E57 input (through the
//! `e57` crate: every scan in world coordinates, with each scan's scanner position in
//! [`Scans`]).
//!
//! Readers return a [`PointCloud`] of points, when the file has all of `nx`, `ny`, `nz`,
//! normals exactly as stored (not normalised: the caller validates them), and every other
//! per-point value as an [`Attribute`] in its stored type (PLY properties, text columns, LAS
//! dimensions and extra bytes). A headerless text file has no names, so its columns 4–6 are
//! taken as normals only when they are unit vectors on every row ([`read_xyz_with`]);
//! [`ColumnNames`] (`--columns`) names the columns instead, and the `_with` readers return
//! notes on the columns dropped or not taken as normals. Every coordinate and normal
//! component must be finite. Errors ([`ReadError`]) are one line starting with the file
//! name and say where: the line and field for text, the byte offset and property for binary
//! PLY. An empty cloud is not an error; the caller decides.
//!
//! Writers take a table of named [`Column`]s (floats as `f64`, integers such as a status code
//! as `i32`, attributes in their own types) and write it atomically as PLY, CSV, XYZ or LAS/LAZ; floats round-trip exactly in
//! every format (LAS coordinates excepted: they are stored on the header's grid).
//!
//! ```
//! use mls_io::{PlyFormat, PointCloud, read_ply, write_ply_to};
//!
//! let cloud = PointCloud {
//!     points: vec![[0.0, 1.0, 2.5]],
//!     normals: Some(vec![[0.0, 0.0, 1.0]]),
//!     ..PointCloud::default()
//! };
//! let mut bytes = Vec::new();
//! write_ply_to(&mut bytes, "memory", &cloud.columns(), PlyFormat::BinaryLittleEndian)?;
//! assert_eq!(read_ply(&bytes[..], "memory")?, cloud);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Architecture invariant: this crate does no geometry; it only moves numbers between files
//! and memory.

#![warn(missing_docs)]

mod attributes;
mod columns;
mod e57;
mod error;
mod las;
mod lines;
mod ply;
mod stream;
mod text;
mod write;

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

pub use attributes::{Attribute, AttributeData, AttributeType, rename_clashes};
pub use columns::{ColumnNames, ReadOptions, UNIT_TOLERANCE};
pub use error::{ReadError, WriteError};
pub use las::{LasReader, LasSink, LasTemplate, creation_date as las_creation_date};
pub use stream::PointStream;
pub use text::{read_csv, read_csv_with, read_xyz, read_xyz_with};
pub use write::{
    Axis, ChunkSink, Column, ColumnData, PlyFormat, WriteOptions, check_writable, write_csv,
    write_csv_to, write_las, write_las_chunks, write_ply, write_ply_to, write_point_cloud,
    write_point_cloud_as, write_point_cloud_as_with, write_point_cloud_chunks,
    write_point_cloud_to, write_point_cloud_to_with, write_xyz, write_xyz_to,
};

/// The fields the readers look for, in the order of the slots of a row.
const SLOT_NAMES: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];

/// The slot name a field name stands for, where writers differ: PCL writes normals as
/// `normal_x`, `normal_y`, `normal_z` (its PLY and PCD writers), PDAL as `NormalX`, `NormalY`,
/// `NormalZ` (its dimension names, lowercased here by the text and LAS readers), most others as
/// `nx` …. Lowercase names.
pub(crate) fn slot_alias(name: &str) -> &str {
    match name {
        "normal_x" | "normalx" => "nx",
        "normal_y" | "normaly" => "ny",
        "normal_z" | "normalz" => "nz",
        other => other,
    }
}

/// The most points a reader reserves room for before reading them. A header may claim any
/// count; memory beyond this grows only as points actually arrive.
const MAX_PREALLOCATED: u64 = 1 << 20;

/// Points, normals if the file has them, and the file's other per-point attributes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    /// The points, in file order.
    pub points: Vec<[f64; 3]>,
    /// One normal per point, as stored in the file (not normalised, possibly zero), if the
    /// file has `nx`, `ny` and `nz`.
    pub normals: Option<Vec<[f64; 3]>>,
    /// Every other per-point value of the file, in file order, each with one value per point:
    /// PLY vertex properties, text columns, LAS dimensions and extra bytes.
    pub attributes: Vec<Attribute>,
    /// The layout of a LAS/LAZ input, for LAS output that keeps it.
    pub las: Option<LasTemplate>,
    /// The scans of an E57 input: where each was taken from and which points it gave.
    pub scans: Option<Scans>,
}

/// The scans a cloud was concatenated from (an E57 file's `data3D` list), for orienting each
/// point's normal towards its own scanner.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scans {
    /// Per scan, in file order: the scanner's position in world coordinates (the translation
    /// of the scan's pose, the image of its local origin), `None` for a scan without a pose,
    /// whose local origin may not be where it was scanned from (an export of registered
    /// data).
    pub origins: Vec<Option<[f64; 3]>>,
    /// Per point: the index of its scan in [`origins`](Self::origins).
    pub scan_of_point: Vec<u32>,
}

impl Scans {
    /// Per point, the position of its scanner, when every scan has a pose; `None` otherwise.
    pub fn viewpoints(&self) -> Option<Vec<[f64; 3]>> {
        let origins: Option<Vec<[f64; 3]>> = self.origins.iter().copied().collect();
        let origins = origins?;
        self.scan_of_point
            .iter()
            .map(|&s| origins.get(s as usize).copied())
            .collect()
    }
}

impl PointCloud {
    /// The number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Columns `x y z`, `nx ny nz` if there are normals, then the attributes, borrowing the
    /// data, for the writers.
    pub fn columns(&self) -> Vec<Column<'_>> {
        let mut columns = vec![
            Column::component("x", &self.points, Axis::X),
            Column::component("y", &self.points, Axis::Y),
            Column::component("z", &self.points, Axis::Z),
        ];
        if let Some(normals) = &self.normals {
            columns.extend([
                Column::component("nx", normals, Axis::X),
                Column::component("ny", normals, Axis::Y),
                Column::component("nz", normals, Axis::Z),
            ]);
        }
        columns.extend(self.attributes.iter().map(Column::attribute));
        columns
    }
}

/// A cloud and what the reader noticed on the way: one line per note, starting with the file
/// name, about columns it ignored or did not take as normals. Not errors: the cloud is
/// usable, but a caller should show them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReadOutcome {
    /// The cloud read.
    pub cloud: PointCloud,
    /// The notes, in the order found.
    pub notes: Vec<String>,
}

/// A file format, as named by a file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileFormat {
    /// `.ply`: PLY, ASCII or binary.
    Ply,
    /// `.xyz`, `.txt`, `.pts`, `.asc` (CloudCompare's ASCII cloud): columns separated by
    /// whitespace (or commas or semicolons, as the first row has them), `#` comment lines (the
    /// writers put the column names in one).
    Xyz,
    /// `.csv`: comma-separated columns with a header row.
    Csv,
    /// `.las`: ASPRS LAS. Read as LAS or LAZ, whichever the header says.
    Las,
    /// `.laz`: LASzip-compressed LAS. Read as LAS or LAZ, whichever the header says.
    Laz,
    /// `.e57`: ASTM E2807 E57, every scan (input only).
    E57,
}

impl FileFormat {
    /// The format for an extension (without the dot, case-insensitive), if supported.
    pub fn from_extension(extension: &str) -> Option<Self> {
        match extension.to_ascii_lowercase().as_str() {
            "ply" => Some(Self::Ply),
            "xyz" | "txt" | "pts" | "asc" => Some(Self::Xyz),
            "csv" => Some(Self::Csv),
            "las" => Some(Self::Las),
            "laz" => Some(Self::Laz),
            "e57" => Some(Self::E57),
            _ => None,
        }
    }

    /// The format for a path's extension, if it has a supported one.
    pub fn from_path(path: &Path) -> Option<Self> {
        detect_format(path).ok()
    }
}

/// The format for a path, or the unsupported extension (`None` if there is none).
fn detect_format(path: &Path) -> Result<FileFormat, Option<String>> {
    let extension = path.extension().ok_or(None)?.to_string_lossy();
    FileFormat::from_extension(&extension).ok_or_else(|| Some(extension.into_owned()))
}

/// Reads a point cloud, choosing the reader by the file's extension (case-insensitive):
/// `.ply` ([`read_ply`]), `.xyz`, `.txt`, `.pts`, `.asc` ([`read_xyz`]), `.csv` ([`read_csv`]), or
/// `.las`, `.laz` ([`ReadError::Las`] names what is wrong), or `.e57` ([`ReadError::E57`]).
/// The readers' notes are dropped; [`read_point_cloud_with`] returns them.
///
/// # Errors
/// [`ReadError::IsADirectory`], [`ReadError::NoExtension`] or [`ReadError::UnknownExtension`]
/// before the file is opened, [`ReadError::Io`] if it cannot be opened or read, and those of
/// the reader.
pub fn read_point_cloud(path: &Path) -> Result<PointCloud, ReadError> {
    read_point_cloud_with(path, &ReadOptions::default()).map(|r| r.cloud)
}

/// Reads a point cloud as [`read_point_cloud`] does, with options, and returns the readers'
/// notes beside it ([`read_xyz_with`], [`read_csv_with`]).
///
/// # Errors
/// Those of [`read_point_cloud`], and [`ReadError::ColumnsForPly`] when column names are
/// given for a PLY file.
pub fn read_point_cloud_with(path: &Path, options: &ReadOptions) -> Result<ReadOutcome, ReadError> {
    let file = path.display().to_string();
    // Checked first: a directory usually has no extension, and "no file extension" would send
    // the user looking for the wrong mistake (on Linux a directory even opens, and only the
    // first read fails).
    if path.is_dir() {
        return Err(ReadError::IsADirectory { file });
    }
    let format = match detect_format(path) {
        Ok(format) => format,
        Err(None) => return Err(ReadError::NoExtension { file }),
        Err(Some(extension)) => return Err(ReadError::UnknownExtension { file, extension }),
    };
    read_point_cloud_as_with(path, format, options)
}

/// Reads a point cloud in the given format, whatever the file's extension. The readers'
/// notes are dropped; [`read_point_cloud_as_with`] returns them.
///
/// # Errors
/// [`ReadError::IsADirectory`], [`ReadError::Io`] if the file cannot be opened or read, and
/// those of the reader.
pub fn read_point_cloud_as(path: &Path, format: FileFormat) -> Result<PointCloud, ReadError> {
    read_point_cloud_as_with(path, format, &ReadOptions::default()).map(|r| r.cloud)
}

/// Reads a point cloud in the given format, whatever the file's extension, with options, and
/// returns the readers' notes beside it.
///
/// # Errors
/// Those of [`read_point_cloud_as`], and [`ReadError::ColumnsForPly`] when column names are
/// given for PLY.
pub fn read_point_cloud_as_with(
    path: &Path,
    format: FileFormat,
    options: &ReadOptions,
) -> Result<ReadOutcome, ReadError> {
    let file = path.display().to_string();
    if path.is_dir() {
        return Err(ReadError::IsADirectory { file });
    }
    if matches!(
        format,
        FileFormat::Ply | FileFormat::Las | FileFormat::Laz | FileFormat::E57
    ) && options.columns.is_some()
    {
        return Err(ReadError::ColumnsForPly { file });
    }
    let opened = File::open(path).map_err(|error| ReadError::Io {
        file: file.clone(),
        error,
    })?;
    let size = opened.metadata().ok().map(|m| m.len());
    let reader = BufReader::with_capacity(1 << 20, opened);
    match format {
        FileFormat::Ply => ply::read(reader, &file, size, &SLOT_NAMES),
        FileFormat::Xyz => read_xyz_with(reader, &file, options),
        FileFormat::Csv => read_csv_with(reader, &file, options),
        FileFormat::Las | FileFormat::Laz => las::read(reader, &file),
        FileFormat::E57 => e57::read(reader, &file),
    }
}

/// The number of points a file in `format` holds, without reading them: the count its header
/// declares (PLY, LAS/LAZ, E57: every scan's records), or for a text format (XYZ, CSV) the
/// number of lines that are neither blank nor `#` comments, an upper bound (a CSV header row
/// counts), found by one pass over the bytes in constant memory.
///
/// # Errors
/// [`ReadError::IsADirectory`], [`ReadError::Io`] if the file cannot be opened or read, and
/// those of the format's header.
pub fn point_count(path: &Path, format: FileFormat) -> Result<u64, ReadError> {
    let file = path.display().to_string();
    if path.is_dir() {
        return Err(ReadError::IsADirectory { file });
    }
    let opened = File::open(path).map_err(|error| ReadError::Io {
        file: file.clone(),
        error,
    })?;
    let mut reader = BufReader::with_capacity(1 << 20, opened);
    match format {
        FileFormat::Ply => ply::vertex_count(reader, &file),
        FileFormat::Las | FileFormat::Laz => Ok(LasReader::open(path)?.len()),
        FileFormat::E57 => e57::record_count(reader, &file),
        FileFormat::Xyz | FileFormat::Csv => {
            let mut count = 0;
            let mut line = Vec::new();
            loop {
                line.clear();
                let read = reader
                    .read_until(b'\n', &mut line)
                    .map_err(|error| ReadError::Io {
                        file: file.clone(),
                        error,
                    })?;
                if read == 0 {
                    return Ok(count);
                }
                let text = line.trim_ascii_start();
                if !text.is_empty() && !text.starts_with(b"#") {
                    count += 1;
                }
            }
        }
    }
}

/// Reads every column of a file as [`read_point_cloud`] does, except that only `x`, `y`, `z`
/// are geometry: `nx`, `ny`, `nz` are read as attributes like any other column, NaN allowed,
/// and [`PointCloud::normals`] is `None` (LAS/LAZ excepted, whose normals, from extra bytes,
/// are never checked). For the output of a computation, whose failed points have NaN
/// normals, when no normals are needed as such (a picture of a result). `options` name the
/// columns of a text file, as for [`read_point_cloud_with`].
///
/// # Errors
/// Those of [`read_point_cloud_with`].
pub fn read_point_cloud_normals_as_attributes(
    path: &Path,
    options: &ReadOptions,
) -> Result<PointCloud, ReadError> {
    let file = path.display().to_string();
    if path.is_dir() {
        return Err(ReadError::IsADirectory { file });
    }
    let format = match detect_format(path) {
        Ok(format) => format,
        Err(None) => return Err(ReadError::NoExtension { file }),
        Err(Some(extension)) => return Err(ReadError::UnknownExtension { file, extension }),
    };
    let opened = File::open(path).map_err(|error| ReadError::Io {
        file: file.clone(),
        error,
    })?;
    let size = opened.metadata().ok().map(|m| m.len());
    let reader = BufReader::with_capacity(1 << 20, opened);
    let points = &SLOT_NAMES[..3];
    let outcome = match format {
        FileFormat::Ply if options.columns.is_some() => Err(ReadError::ColumnsForPly { file }),
        FileFormat::Ply => ply::read(reader, &file, size, points),
        FileFormat::Xyz => text::read_xyz_slots(reader, &file, options, points),
        FileFormat::Csv => text::read_csv_slots(reader, &file, options, points),
        FileFormat::Las | FileFormat::Laz => las::read(reader, &file),
        FileFormat::E57 if options.columns.is_some() => Err(ReadError::ColumnsForPly { file }),
        FileFormat::E57 => e57::read(reader, &file),
    };
    outcome.map(|r| r.cloud)
}

/// Reads a point cloud in the given format from a stream, such as standard input; `name` is
/// the display name used in errors.
///
/// # Errors
/// Those of [`read_ply`], [`read_xyz`] or [`read_csv`].
pub fn read_point_cloud_from(
    reader: impl BufRead,
    name: &str,
    format: FileFormat,
) -> Result<PointCloud, ReadError> {
    read_point_cloud_from_with(reader, name, format, &ReadOptions::default()).map(|r| r.cloud)
}

/// Reads a point cloud in the given format from a stream, as [`read_point_cloud_from`] does,
/// with options, and returns the readers' notes beside it.
///
/// # Errors
/// Those of [`read_point_cloud_from`], and [`ReadError::ColumnsForPly`] when column names are
/// given for PLY.
pub fn read_point_cloud_from_with(
    reader: impl BufRead,
    name: &str,
    format: FileFormat,
    options: &ReadOptions,
) -> Result<ReadOutcome, ReadError> {
    match format {
        FileFormat::Ply | FileFormat::Las | FileFormat::Laz | FileFormat::E57
            if options.columns.is_some() =>
        {
            Err(ReadError::ColumnsForPly {
                file: name.to_owned(),
            })
        }
        FileFormat::Ply => ply::read(reader, name, None, &SLOT_NAMES),
        FileFormat::Xyz => read_xyz_with(reader, name, options),
        FileFormat::Csv => read_csv_with(reader, name, options),
        FileFormat::Las | FileFormat::Laz => las::read_stream(reader, name),
        FileFormat::E57 => {
            // The E57 reader seeks (the XML section is at the end): the stream is read whole.
            let mut reader = reader;
            let mut bytes = Vec::new();
            std::io::Read::read_to_end(&mut reader, &mut bytes).map_err(|error| ReadError::Io {
                file: name.to_owned(),
                error,
            })?;
            e57::read(std::io::Cursor::new(bytes), name)
        }
    }
}

/// Reads a PLY file (`ascii`, `binary_little_endian` or `binary_big_endian`) from a stream;
/// `name` is the display name used in errors.
///
/// The `vertex` element must have scalar properties `x`, `y`, `z` and may have `nx`, `ny`,
/// `nz` (all three or none), of any PLY scalar type (`char`/`int8` … `double`/`float64`).
/// Other vertex properties, including lists, and other elements before the vertex element
/// are skipped; elements after it are not read at all. Comments and `obj_info` lines are
/// ignored. In an ASCII body each element instance is one line; blank lines are ignored.
///
/// # Errors
/// [`ReadError::Header`] (naming the header line), [`ReadError::MissingField`],
/// [`ReadError::PartialNormals`]; for an ASCII body [`ReadError::Ascii`] (naming the line
/// and the property); for a binary body [`ReadError::Truncated`] and [`ReadError::Binary`]
/// (naming the byte offset, element index and property); and [`ReadError::Io`].
pub fn read_ply(reader: impl BufRead, name: &str) -> Result<PointCloud, ReadError> {
    ply::read(reader, name, None, &SLOT_NAMES).map(|r| r.cloud)
}

/// Returns whether `a` and `b` name the same file, so a caller can refuse to overwrite its
/// input. Paths that exist are compared by identity (device and inode on Unix, canonical path
/// elsewhere), so links and `..` are seen through; a path that does not exist yet is compared
/// by its canonical directory and file name, and failing that, literally.
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (a.metadata(), b.metadata()) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    match (canonical(a), canonical(b)) {
        (Some(ca), Some(cb)) => ca == cb,
        _ => a == b,
    }
}

/// The canonical form of a path, or of its directory joined with its file name when the file
/// does not exist.
fn canonical(path: &Path) -> Option<PathBuf> {
    if let Ok(path) = path.canonicalize() {
        return Some(path);
    }
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    Some(dir.canonicalize().ok()?.join(name))
}

/// Collects the values the readers find, row by row, into a [`PointCloud`].
#[derive(Debug)]
struct CloudBuilder {
    points: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
    attributes: Vec<Attribute>,
}

impl CloudBuilder {
    fn new(has_normals: bool, capacity: usize) -> Self {
        Self {
            points: Vec::with_capacity(capacity),
            normals: has_normals.then(|| Vec::with_capacity(capacity)),
            attributes: Vec::new(),
        }
    }

    /// Adds one row of values in the order of [`SLOT_NAMES`]; the row's attributes are
    /// pushed to [`Self::attributes`] by the reader.
    fn push(&mut self, [x, y, z, nx, ny, nz]: [f64; 6]) {
        self.points.push([x, y, z]);
        if let Some(normals) = &mut self.normals {
            normals.push([nx, ny, nz]);
        }
    }

    fn finish(self) -> PointCloud {
        PointCloud {
            points: self.points,
            normals: self.normals,
            attributes: self.attributes,
            las: None,
            scans: None,
        }
    }
}

/// Rows collected into clouds of at most `max` points, each handed to `sink` once full: a
/// reader streams a file larger than memory through it, and reads a whole file as one batch
/// of unbounded size. The last batch, possibly empty when it is the only one, is handed on at
/// [`Batches::finish`].
pub(crate) struct Batches<'s, E> {
    /// The batch being filled; a reader pushes a row's attributes into it, then calls
    /// [`Batches::push`] with the row's geometry.
    cloud: CloudBuilder,
    /// A new, empty batch with the reader's columns.
    fresh: Box<dyn Fn() -> CloudBuilder + 's>,
    max: u64,
    sink: &'s mut dyn FnMut(PointCloud) -> Result<(), E>,
    handed: bool,
}

impl<'s, E> Batches<'s, E> {
    pub(crate) fn new(
        max: u64,
        fresh: Box<dyn Fn() -> CloudBuilder + 's>,
        sink: &'s mut dyn FnMut(PointCloud) -> Result<(), E>,
    ) -> Self {
        Self {
            cloud: fresh(),
            fresh,
            max: max.max(1),
            sink,
            handed: false,
        }
    }

    /// The batch being filled, for the row's attributes.
    pub(crate) fn cloud(&mut self) -> &mut CloudBuilder {
        &mut self.cloud
    }

    /// Ends a row with its values in the order of [`SLOT_NAMES`]; hands the batch on when
    /// it is full.
    pub(crate) fn push(&mut self, values: [f64; 6]) -> Result<(), E> {
        self.cloud.push(values);
        if self.cloud.points.len() as u64 >= self.max {
            let full = std::mem::replace(&mut self.cloud, (self.fresh)());
            self.handed = true;
            (self.sink)(full.finish())?;
        }
        Ok(())
    }

    /// Hands on the last batch: the rows since the last full one, or an empty cloud if no
    /// batch was handed on before.
    pub(crate) fn finish(self) -> Result<(), E> {
        if !self.handed || !self.cloud.points.is_empty() {
            (self.sink)(self.cloud.finish())?;
        }
        Ok(())
    }
}

/// Reads a whole file through a batch reader `read` as one batch of unbounded size.
fn one_batch(
    read: impl FnOnce(
        &mut dyn FnMut(PointCloud) -> Result<(), ReadError>,
    ) -> Result<Vec<String>, ReadError>,
) -> Result<ReadOutcome, ReadError> {
    let mut whole = None;
    let notes = read(&mut |cloud| {
        whole = Some(cloud);
        Ok(())
    })?;
    Ok(ReadOutcome {
        cloud: whole.unwrap_or_default(),
        notes,
    })
}
