//! Writers: a table of named columns to PLY (binary little-endian or ASCII), CSV, XYZ, or
//! LAS/LAZ (in `las/`); the PLY and text rows are encoded in `rows.rs`.
//!
//! Files are written atomically: into a temporary file in the destination's directory, which
//! is flushed, synced and then renamed over the destination. On any error the temporary file
//! is removed and the destination is untouched.

mod rows;

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use rows::{Cursor, TextHeader, write_ply_body, write_ply_header, write_ply_rows, write_text_rows};

use crate::attributes::{Attribute, AttributeData};
use crate::error::WriteError;
use crate::las::LasTemplate;
use crate::{FileFormat, detect_format};

/// Size of the output buffer: large enough that a million rows take few system calls.
const BUFFER_BYTES: usize = 1 << 20;

/// A component of a 3-vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// The first component.
    X,
    /// The second component.
    Y,
    /// The third component.
    Z,
}

impl Axis {
    pub(crate) fn of(self, v: &[f64; 3]) -> f64 {
        let [x, y, z] = *v;
        match self {
            Self::X => x,
            Self::Y => y,
            Self::Z => z,
        }
    }
}

/// The values of one column, borrowed from the caller.
#[derive(Clone, Copy, Debug)]
pub enum ColumnData<'a> {
    /// Floating-point values: PLY `double`, text with enough digits to round-trip exactly.
    F64(&'a [f64]),
    /// Integer values, such as a status code: PLY `int`.
    I32(&'a [i32]),
    /// One component of a slice of 3-vectors, e.g. the `y` coordinates of
    /// [`PointCloud::points`](crate::PointCloud::points), written as `F64` without copying
    /// them into a column first.
    Component {
        /// The vectors.
        vectors: &'a [[f64; 3]],
        /// The component to write.
        axis: Axis,
    },
    /// An attribute carried from the input, written in its own type: in PLY as a property of
    /// that type (64-bit integers as `double`), in LAS as extra bytes of that type or as the
    /// standard field it came from ([`WriteOptions::las`]).
    Attribute(&'a AttributeData),
}

impl ColumnData<'_> {
    /// The number of values (rows).
    pub fn len(&self) -> usize {
        match self {
            Self::F64(data) => data.len(),
            Self::I32(data) => data.len(),
            Self::Component { vectors, .. } => vectors.len(),
            Self::Attribute(data) => data.len(),
        }
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(crate) fn cursor(&self) -> Cursor<'_> {
        match *self {
            Self::F64(data) => Cursor::F64(data.iter()),
            Self::I32(data) => Cursor::I32(data.iter()),
            Self::Component { vectors, axis } => Cursor::Component(vectors.iter(), axis),
            Self::Attribute(data) => Cursor::Attribute(data, 0),
        }
    }

    /// The PLY property type written for the column.
    pub(crate) fn ply_type(&self) -> &'static str {
        match self {
            Self::I32(_) => "int",
            Self::F64(_) | Self::Component { .. } => "double",
            Self::Attribute(data) => data.ty().ply_name(),
        }
    }
}

/// A named column of a table to write.
#[derive(Clone, Copy, Debug)]
pub struct Column<'a> {
    /// The header (CSV) name, and the PLY property's after `scalar_` unless it is a standard
    /// one ([`write_ply`]): ASCII letters, digits, `_`, `-` or `.`.
    pub name: &'a str,
    /// The values, one per row.
    pub data: ColumnData<'a>,
}

impl<'a> Column<'a> {
    /// A floating-point column.
    pub fn f64(name: &'a str, data: &'a [f64]) -> Self {
        Self {
            name,
            data: ColumnData::F64(data),
        }
    }

    /// An integer column.
    pub fn i32(name: &'a str, data: &'a [i32]) -> Self {
        Self {
            name,
            data: ColumnData::I32(data),
        }
    }

    /// A column of an attribute's values, under its name.
    pub fn attribute(attribute: &'a Attribute) -> Self {
        Self {
            name: &attribute.name,
            data: ColumnData::Attribute(&attribute.data),
        }
    }

    /// A floating-point column holding one component of `vectors`.
    pub fn component(name: &'a str, vectors: &'a [[f64; 3]], axis: Axis) -> Self {
        Self {
            name,
            data: ColumnData::Component { vectors, axis },
        }
    }
}

/// The encoding of a PLY file to write.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PlyFormat {
    /// `binary_little_endian`: compact, exact and fast; the default.
    #[default]
    BinaryLittleEndian,
    /// `ascii`: readable, still exact (shortest round-trip decimal form).
    Ascii,
}

/// How to write a table, beyond its format.
#[derive(Clone, Copy, Debug, Default)]
pub struct WriteOptions<'a> {
    /// The encoding of PLY output.
    pub ply_format: PlyFormat,
    /// For PLY output, the column also written as the vertex property `quality`, after the
    /// others: MeshLab reads no other per-vertex value of a PLY file (its importer maps
    /// `quality` to the vertex quality and ignores every property it does not know). Not
    /// written when no column has this name or one is named `quality` already. Ignored for
    /// other formats.
    pub ply_quality: Option<&'a str>,
    /// For LAS/LAZ output, the layout of the LAS input the table came from
    /// ([`PointCloud::las`](crate::PointCloud::las)): its point format (without waveform
    /// data), scale and offset, GPS time type, coordinate-system records, and the standard
    /// fields and extra-bytes descriptors of its dimensions, so that columns named as its
    /// dimensions go back where they came from. Ignored for other formats.
    pub las: Option<&'a LasTemplate>,
}

/// Writes `columns` to `path` in the format its extension names (case-insensitive): `.ply`
/// (in `ply_format`; [`write_ply`]), `.csv` ([`write_csv`]), `.xyz`, `.txt`, `.pts`, `.asc`
/// (space-separated after a `#` line of column names), or `.las`, `.laz` ([`write_las`]).
///
/// For points and normals only, pass [`PointCloud::columns`](crate::PointCloud::columns).
///
/// # Errors
/// [`WriteError::NoExtension`] or [`WriteError::UnknownExtension`], then those of
/// [`write_ply`], [`write_csv`] and [`write_xyz`].
pub fn write_point_cloud(
    path: &Path,
    columns: &[Column<'_>],
    ply_format: PlyFormat,
) -> Result<(), WriteError> {
    let file = path.display().to_string();
    match detect_format(path) {
        Ok(format) => write_point_cloud_as(path, format, columns, ply_format),
        Err(None) => Err(WriteError::NoExtension { file }),
        Err(Some(extension)) => Err(WriteError::UnknownExtension { file, extension }),
    }
}

/// Writes `columns` to `path` in the given format, whatever the extension, atomically.
///
/// # Errors
/// Those of [`write_ply`], [`write_csv`] and [`write_xyz`].
pub fn write_point_cloud_as(
    path: &Path,
    format: FileFormat,
    columns: &[Column<'_>],
    ply_format: PlyFormat,
) -> Result<(), WriteError> {
    let options = WriteOptions {
        ply_format,
        ..WriteOptions::default()
    };
    write_point_cloud_as_with(path, format, columns, &options)
}

/// Writes `columns` to `path` in the given format, atomically, as [`write_point_cloud_as`]
/// does, with options.
///
/// # Errors
/// Those of [`write_point_cloud_as`].
pub fn write_point_cloud_as_with(
    path: &Path,
    format: FileFormat,
    columns: &[Column<'_>],
    options: &WriteOptions<'_>,
) -> Result<(), WriteError> {
    match format {
        FileFormat::Ply => {
            let file = path.display().to_string();
            let rows = validate(&file, columns)?;
            let columns = with_quality(columns, options.ply_quality);
            write_atomically(path, |out| {
                write_ply_rows(out, &file, &columns, rows, options.ply_format)
            })
        }
        FileFormat::Csv => write_csv(path, columns),
        FileFormat::Xyz => write_xyz(path, columns),
        FileFormat::Las | FileFormat::Laz => {
            let file = path.display().to_string();
            validate(&file, columns)?;
            let compressed = format == FileFormat::Laz;
            write_atomically(path, |out| {
                crate::las::write_file(out, &file, columns, compressed, options.las)
            })
        }
        FileFormat::E57 => Err(WriteError::ReadOnlyFormat {
            file: path.display().to_string(),
            format: "E57",
        }),
    }
}

/// Writes `columns` in the given format to a stream, such as standard output; `name` is the
/// display name used in errors.
///
/// # Errors
/// Those of [`write_ply_to`], [`write_csv_to`] and [`write_xyz_to`].
pub fn write_point_cloud_to(
    writer: impl Write,
    name: &str,
    format: FileFormat,
    columns: &[Column<'_>],
    ply_format: PlyFormat,
) -> Result<(), WriteError> {
    let options = WriteOptions {
        ply_format,
        ..WriteOptions::default()
    };
    write_point_cloud_to_with(writer, name, format, columns, &options)
}

/// Writes `columns` in the given format to a stream, as [`write_point_cloud_to`] does, with
/// options.
///
/// # Errors
/// Those of [`write_point_cloud_to`].
pub fn write_point_cloud_to_with(
    writer: impl Write,
    name: &str,
    format: FileFormat,
    columns: &[Column<'_>],
    options: &WriteOptions<'_>,
) -> Result<(), WriteError> {
    match format {
        FileFormat::Ply => write_ply_to(
            writer,
            name,
            &with_quality(columns, options.ply_quality),
            options.ply_format,
        ),
        FileFormat::Csv => write_csv_to(writer, name, columns),
        FileFormat::Xyz => write_xyz_to(writer, name, columns),
        FileFormat::Las => crate::las::write_stream(writer, name, columns, false, options.las),
        FileFormat::Laz => crate::las::write_stream(writer, name, columns, true, options.las),
        FileFormat::E57 => Err(WriteError::ReadOnlyFormat {
            file: name.to_owned(),
            format: "E57",
        }),
    }
}

/// The columns, and `quality` as a copy of the column named `mirror` when there is one and
/// no column is named `quality` ([`WriteOptions::ply_quality`]).
fn with_quality<'a>(columns: &[Column<'a>], mirror: Option<&str>) -> Vec<Column<'a>> {
    let mut all = columns.to_vec();
    let source = mirror.and_then(|m| columns.iter().find(|c| c.name == m));
    if let Some(source) = source
        && !columns.iter().any(|c| c.name == QUALITY)
    {
        all.push(Column {
            name: QUALITY,
            data: source.data,
        });
    }
    all
}

/// MeshLab's per-vertex scalar: the one PLY vertex property it reads beside the geometry and
/// colour.
const QUALITY: &str = "quality";

/// Vertex property names written as they are; every other column `name` is written as the
/// property `scalar_name`. CloudCompare loads a vertex property as a scalar field only when
/// its name contains `scal` (its command line loads nothing else; its dialog preselects
/// nothing else), and takes `scalar_name` as the field `name` (`PlyFilter.cpp`); these are
/// the names other programs know by themselves: the geometry, colour (CloudCompare, MeshLab,
/// Open3D), MeshLab's `quality`, and `intensity` (PCL, and a scalar field in CloudCompare).
pub(crate) const PLY_PLAIN_NAMES: [&str; 12] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "red",
    "green",
    "blue",
    "alpha",
    QUALITY,
    "intensity",
];

/// The prefix of the PLY vertex property of a column not in [`PLY_PLAIN_NAMES`].
pub(crate) const PLY_SCALAR_PREFIX: &str = "scalar_";

/// The PLY vertex property name of column `name`.
pub(crate) fn ply_property_name(name: &str) -> std::borrow::Cow<'_, str> {
    if PLY_PLAIN_NAMES.contains(&name) {
        name.into()
    } else {
        format!("{PLY_SCALAR_PREFIX}{name}").into()
    }
}

/// Writes `columns` as the `vertex` element of a PLY file, atomically: float columns as
/// `double`, integer columns as `int`, rows in input order. A column is the property of its
/// name if that is a standard one (`x y z nx ny nz red green blue alpha quality
/// intensity`), else `scalar_` and its name (`k1` is `scalar_k1`), which CloudCompare loads
/// as the scalar field `k1` and [`read_ply`](crate::read_ply) reads as `k1` again.
///
/// # Errors
/// [`WriteError::NoColumns`], [`WriteError::InvalidColumnName`],
/// [`WriteError::DuplicateColumn`] or [`WriteError::LengthMismatch`] before anything is
/// written; [`WriteError::NotAFilePath`] or [`WriteError::Io`] (for instance, a missing or
/// read-only directory), after which no file is left behind.
pub fn write_ply(path: &Path, columns: &[Column<'_>], format: PlyFormat) -> Result<(), WriteError> {
    let file = path.display().to_string();
    let rows = validate(&file, columns)?;
    write_atomically(path, |out| {
        write_ply_rows(out, &file, columns, rows, format)
    })
}

/// Writes `columns` as CSV, atomically: a header row of the names after `//`
/// (`//x,y,z,k1,...`, CloudCompare's form, which [`read_csv`](crate::read_csv) reads too),
/// then one row per point, floats in the shortest form that parses back to the same `f64`.
///
/// # Errors
/// As for [`write_ply`].
pub fn write_csv(path: &Path, columns: &[Column<'_>]) -> Result<(), WriteError> {
    let file = path.display().to_string();
    let rows = validate(&file, columns)?;
    write_atomically(path, |out| {
        write_text_rows(out, &file, columns, rows, ',', TextHeader::Names)
    })
}

/// Writes `columns` space-separated, atomically, after one comment line naming them
/// (`# x y z nx ny nz`) so that the file says what its columns are. [`read_xyz`](crate::read_xyz)
/// skips that line and reads the result back when the columns are `x y z` or
/// `x y z nx ny nz`.
///
/// # Errors
/// As for [`write_ply`].
pub fn write_xyz(path: &Path, columns: &[Column<'_>]) -> Result<(), WriteError> {
    let file = path.display().to_string();
    let rows = validate(&file, columns)?;
    write_atomically(path, |out| {
        write_text_rows(out, &file, columns, rows, ' ', TextHeader::Comment)
    })
}

/// Writes `columns` as LAS 1.4 (point format 6), or LAZ if `compressed`, atomically: the
/// columns `x`, `y`, `z` as the point coordinates, on a decimal grid of 1e-8 to 1e-7 of the
/// bounding box's largest extent with the offset at its minimum; an attribute column with the
/// name and type of a point format 6 dimension (`intensity` `uint16` …; a flag only if every
/// value fits its bits) in that field; every other column, in order, as a named LAS
/// extra-bytes attribute (`double` for float columns, `long` (i32) for integer ones, an
/// attribute's own type for attribute columns), which PDAL, laspy and CloudCompare show as
/// dimensions. To keep a LAS input's layout, use [`write_point_cloud_as_with`] with its
/// [`LasTemplate`].
///
/// # Errors
/// Those of [`write_ply`], [`WriteError::MissingCoordinate`] without an `x`, `y` or `z` column,
/// [`WriteError::NonFiniteCoordinate`], [`WriteError::InvalidColumnName`] for a name over 32
/// characters, and [`WriteError::Las`].
pub fn write_las(path: &Path, columns: &[Column<'_>], compressed: bool) -> Result<(), WriteError> {
    let file = path.display().to_string();
    validate(&file, columns)?;
    write_atomically(path, |out| {
        crate::las::write_file(out, &file, columns, compressed, None)
    })
}

/// Writes a PLY file to a stream; `name` is the display name used in errors.
///
/// # Errors
/// As for [`write_ply`], with [`WriteError::Io`] for a failing stream.
pub fn write_ply_to(
    writer: impl Write,
    name: &str,
    columns: &[Column<'_>],
    format: PlyFormat,
) -> Result<(), WriteError> {
    let rows = validate(name, columns)?;
    let mut out = BufWriter::with_capacity(BUFFER_BYTES, writer);
    write_ply_rows(&mut out, name, columns, rows, format)?;
    out.flush().map_err(io_error(name))
}

/// Writes CSV to a stream; `name` is the display name used in errors.
///
/// # Errors
/// As for [`write_ply_to`].
pub fn write_csv_to(
    writer: impl Write,
    name: &str,
    columns: &[Column<'_>],
) -> Result<(), WriteError> {
    let rows = validate(name, columns)?;
    let mut out = BufWriter::with_capacity(BUFFER_BYTES, writer);
    write_text_rows(&mut out, name, columns, rows, ',', TextHeader::Names)?;
    out.flush().map_err(io_error(name))
}

/// Writes space-separated values to a stream after a `#` line naming the columns, as
/// [`write_xyz`] does; `name` is the display name used in errors.
///
/// # Errors
/// As for [`write_ply_to`].
pub fn write_xyz_to(
    writer: impl Write,
    name: &str,
    columns: &[Column<'_>],
) -> Result<(), WriteError> {
    let rows = validate(name, columns)?;
    let mut out = BufWriter::with_capacity(BUFFER_BYTES, writer);
    write_text_rows(&mut out, name, columns, rows, ' ', TextHeader::Comment)?;
    out.flush().map_err(io_error(name))
}

pub(crate) fn io_error(file: &str) -> impl FnOnce(std::io::Error) -> WriteError + '_ {
    move |error| WriteError::Io {
        file: file.to_owned(),
        error,
    }
}

/// Checks the columns before anything is written; returns the number of rows.
pub(crate) fn validate(file: &str, columns: &[Column<'_>]) -> Result<usize, WriteError> {
    let Some(first) = columns.first() else {
        return Err(WriteError::NoColumns {
            file: file.to_owned(),
        });
    };
    for (index, column) in columns.iter().enumerate() {
        let reason = if column.name.is_empty() {
            Some("empty")
        } else if !column
            .name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'.'))
        {
            // Whitespace would split a PLY property line, commas and quotes a CSV header.
            Some("only ASCII letters, digits, '_', '-' and '.' are allowed")
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(WriteError::InvalidColumnName {
                file: file.to_owned(),
                name: column.name.to_owned(),
                reason,
            });
        }
        if columns.iter().take(index).any(|c| c.name == column.name) {
            return Err(WriteError::DuplicateColumn {
                file: file.to_owned(),
                name: column.name.to_owned(),
            });
        }
        if column.data.len() != first.data.len() {
            return Err(WriteError::LengthMismatch {
                file: file.to_owned(),
                first: first.name.to_owned(),
                expected: first.data.len(),
                column: column.name.to_owned(),
                len: column.data.len(),
            });
        }
    }
    Ok(first.data.len())
}

/// Writes LAS (LAZ if `compressed`) to `path` a chunk at a time, atomically: `body` hands
/// the chunks, each a table of the same columns, to [`LasSink::write`](crate::LasSink::write);
/// the file is renamed over `path` only when `body` succeeds and the file is complete. The
/// layout is `template`'s, as [`WriteOptions::las`] gives it to [`write_las`]'s whole tables.
///
/// # Errors
/// `body`'s, and those of [`write_las`]; on any error no file is left behind.
pub fn write_las_chunks<E: From<WriteError>>(
    path: &Path,
    compressed: bool,
    template: &LasTemplate,
    body: impl FnOnce(&mut crate::LasSink) -> Result<(), E>,
) -> Result<(), E> {
    let file = path.display().to_string();
    write_atomically(path, |out| {
        crate::las::write_file_chunks(out, &file, compressed, template, body)
    })
}

/// Writes a table of `rows` rows to `path` in `format` a chunk at a time, atomically: `body`
/// hands the chunks, each a table of the same columns, to [`ChunkSink::write`]; the file is
/// renamed over `path` only when `body` succeeds and exactly `rows` rows were written. The
/// file is the one [`write_point_cloud_as_with`] writes for the whole table, byte for byte,
/// given the same `options`; for LAS/LAZ, `options.las` must be given, the layout of a LAS
/// input or [`LasTemplate::fitted`] to the table's bounding box (as a whole table without a
/// template is written).
///
/// # Errors
/// `body`'s; those of [`write_point_cloud_as_with`]; [`WriteError::RowCount`] when the
/// rows written are not `rows`; [`WriteError::Las`] for LAS without a layout or with chunks
/// whose columns differ; [`WriteError::ReadOnlyFormat`] for E57. On any error no file is left
/// behind.
pub fn write_point_cloud_chunks<E: From<WriteError>>(
    path: &Path,
    format: FileFormat,
    options: &WriteOptions<'_>,
    rows: u64,
    body: impl FnOnce(&mut ChunkSink<'_>) -> Result<(), E>,
) -> Result<(), E> {
    let file = path.display().to_string();
    match format {
        FileFormat::E57 => Err(WriteError::ReadOnlyFormat {
            file,
            format: "E57",
        }
        .into()),
        FileFormat::Las | FileFormat::Laz => {
            let Some(template) = options.las else {
                return Err(WriteError::Las {
                    file,
                    message: "a LAS file written in chunks needs its layout (a template)"
                        .to_owned(),
                }
                .into());
            };
            write_las_chunks(path, format == FileFormat::Laz, template, |sink| {
                let mut chunks = ChunkSink {
                    kind: SinkKind::Las(sink),
                    file: file.clone(),
                    declared: rows,
                    written: 0,
                };
                body(&mut chunks)?;
                chunks.finish().map_err(E::from)
            })
        }
        FileFormat::Ply | FileFormat::Csv | FileFormat::Xyz => write_atomically(path, |out| {
            let mut chunks = ChunkSink {
                kind: SinkKind::Rows {
                    out,
                    format,
                    ply_format: options.ply_format,
                    quality: options.ply_quality.map(str::to_owned),
                },
                file: file.clone(),
                declared: rows,
                written: 0,
            };
            body(&mut chunks)?;
            chunks.finish().map_err(E::from)
        }),
    }
}

/// Where [`write_point_cloud_chunks`] writes the chunks.
pub struct ChunkSink<'a> {
    kind: SinkKind<'a>,
    file: String,
    declared: u64,
    written: u64,
}

enum SinkKind<'a> {
    Las(&'a mut crate::LasSink),
    Rows {
        out: &'a mut dyn Write,
        format: FileFormat,
        ply_format: PlyFormat,
        quality: Option<String>,
    },
}

impl std::fmt::Debug for ChunkSink<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ChunkSink")
            .field("file", &self.file)
            .field("declared", &self.declared)
            .field("written", &self.written)
            .finish_non_exhaustive()
    }
}

impl ChunkSink<'_> {
    /// Appends the rows of `columns`, the same columns (names and types) in every chunk; the
    /// header is written with the first.
    ///
    /// # Errors
    /// Those of the format's writer for a whole table, and [`WriteError::RowCount`] for
    /// more rows than declared.
    pub fn write(&mut self, columns: &[Column<'_>]) -> Result<(), WriteError> {
        let file = self.file.as_str();
        let rows = validate(file, columns)?;
        let first = self.written == 0;
        if self.written + rows as u64 > self.declared {
            return Err(self.row_count(self.written + rows as u64));
        }
        match &mut self.kind {
            SinkKind::Las(sink) => sink.write(columns)?,
            SinkKind::Rows {
                out,
                format,
                ply_format,
                quality,
            } => match format {
                FileFormat::Ply => {
                    let columns = with_quality(columns, quality.as_deref());
                    if first {
                        write_ply_header(out, file, &columns, self.declared, *ply_format)?;
                    }
                    write_ply_body(out, file, &columns, rows, *ply_format)?;
                }
                _ => {
                    let (separator, header) = if *format == FileFormat::Csv {
                        (',', TextHeader::Names)
                    } else {
                        (' ', TextHeader::Comment)
                    };
                    let header = if first { header } else { TextHeader::None };
                    write_text_rows(out, file, columns, rows, separator, header)?;
                }
            },
        }
        self.written += rows as u64;
        Ok(())
    }

    /// Checks that every declared row was written.
    fn finish(&self) -> Result<(), WriteError> {
        if self.written != self.declared {
            return Err(self.row_count(self.written));
        }
        Ok(())
    }

    fn row_count(&self, written: u64) -> WriteError {
        WriteError::RowCount {
            file: self.file.clone(),
            declared: self.declared,
            written,
        }
    }
}

/// Writes through a temporary file in the destination's directory, renamed over the
/// destination only once everything is written and synced.
fn write_atomically<E: From<WriteError>>(
    path: &Path,
    body: impl FnOnce(&mut BufWriter<&File>) -> Result<(), E>,
) -> Result<(), E> {
    let file = path.display().to_string();
    let io_error = |file: &String| {
        let file = file.clone();
        move |error| E::from(WriteError::Io { file, error })
    };
    let (resolved, temp) = temp_beside(path)?;
    let path = resolved.as_path();
    // A file that is replaced keeps its permissions (a read-only file stays read-only, a
    // group-writable one group-writable); a new one gets 0666 less the umask (`temp_beside`).
    if let Ok(existing) = std::fs::metadata(path)
        && existing.is_file()
    {
        temp.as_file()
            .set_permissions(existing.permissions())
            .map_err(io_error(&file))?;
    }
    {
        let mut out = BufWriter::with_capacity(BUFFER_BYTES, temp.as_file());
        body(&mut out)?;
        out.flush().map_err(io_error(&file))?;
    }
    temp.as_file().sync_all().map_err(io_error(&file))?;
    temp.persist(path).map_err(|err| WriteError::Io {
        file: file.clone(),
        error: err.error,
    })?;
    Ok(())
}

/// The destination with its symbolic links followed ([`resolve_links`]) and a new temporary
/// file beside it, in its directory (for the rename to be atomic, on the same file system),
/// named `.NAME.XXXXXX.tmp`.
fn temp_beside(path: &Path) -> Result<(PathBuf, tempfile::NamedTempFile), WriteError> {
    let file = path.display().to_string();
    let io_error = |error| WriteError::Io {
        file: file.clone(),
        error,
    };
    // Through a symbolic link, the file it points to is replaced and the link kept, as
    // writing into the link would do.
    let resolved = resolve_links(path).map_err(io_error)?;
    let Some(file_name) = resolved.file_name() else {
        return Err(WriteError::NotAFilePath { file });
    };
    let dir = match resolved.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let prefix = format!(".{}.", file_name.to_string_lossy());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        // The default 0600 of temporary files would otherwise become the output's mode; 0666
        // less the umask is what creating the file directly gives.
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    // tempfile's errors name the temporary path, which means nothing to the user: report a
    // missing directory with the OS's own words, anything else naming the destination and the
    // directory, with the OS's words for the cause (tempfile writes them before " at path
    // …"; else the error's kind).
    std::fs::metadata(dir).map_err(io_error)?;
    let temp = builder.tempfile_in(dir).map_err(|e| {
        let text = e.to_string();
        let cause = text
            .rsplit_once(" at path ")
            .map_or_else(|| e.kind().to_string(), |(cause, _)| cause.to_owned());
        io_error(io::Error::new(
            e.kind(),
            format!("cannot create a file in {}: {cause}", dir.display()),
        ))
    })?;
    Ok((resolved, temp))
}

/// Checks that `path` can be written as the writers write it: the file a symbolic link
/// points to, replaced through a temporary file created in its directory (here created and
/// removed again). For the check of an output before a long computation.
///
/// # Errors
/// [`WriteError::Io`] naming `path` when its directory is missing, not a directory or does
/// not let this user create a file; [`WriteError::NotAFilePath`] for a path without a file
/// name.
pub fn check_writable(path: &Path) -> Result<(), WriteError> {
    temp_beside(path).map(drop)
}

/// The path with every symbolic link of its last component followed (a dangling link gives
/// the path it points to, which is then created). Stops after 40 links, as the kernel does,
/// and leaves the rest to the rename's error.
fn resolve_links(path: &Path) -> io::Result<PathBuf> {
    let mut path = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&path) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let target = std::fs::read_link(&path)?;
                path = match path.parent() {
                    Some(parent) if target.is_relative() => parent.join(target),
                    _ => target,
                };
            }
            _ => break,
        }
    }
    Ok(path)
}
