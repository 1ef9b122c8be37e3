//! Writing a table as LAS 1.4 or LAZ: raw point records encoded here and handed to the `las`
//! writer in chunks.

use std::fs::File;
use std::io::{self, BufWriter, Cursor, Seek, Write};

use las::point::Format;
use las::{Builder, PointDataBuilder, Transform, Vector, Version, Vlr, Writer};
use rayon::prelude::*;

use super::LasTemplate;
use super::dims::{self, Field};
use super::extra::{self, Descriptor, MAX_NAME_BYTES};
use crate::attributes::{AttributeData, Le, Scalar, scatter_le};
use crate::error::WriteError;
use crate::write::{Column, ColumnData, validate};

/// Records encoded per task: big enough to amortise a task, small enough to share a batch
/// evenly between threads.
const RECORDS_PER_TASK: usize = 4096;

/// The plan of a LAS file for a table: the coordinate columns, the columns that go into
/// standard fields, the extra-bytes columns and the header.
/// Columns are named by their index in the table, so that a plan made from one chunk of a
/// table serves the next ([`LasSink`]).
#[derive(Debug)]
struct Plan {
    xyz: [usize; 3],
    standard: Vec<(Field, usize)>,
    /// The fields without a column, written with their defaults.
    defaults: Vec<Field>,
    extra: Vec<usize>,
    transforms: Vector<Transform>,
    format: Format,
    /// The table's column names and types, which every chunk must repeat.
    schema: Vec<(String, crate::AttributeType)>,
}

/// Checks the table and chooses the header for it.
fn plan(
    file: &str,
    columns: &[Column<'_>],
    compressed: bool,
    template: Option<&LasTemplate>,
) -> Result<(Plan, Builder, usize), WriteError> {
    let rows = validate(file, columns)?;
    let find = |name: &'static str| {
        columns
            .iter()
            .position(|c| c.name == name)
            .ok_or_else(|| WriteError::MissingCoordinate {
                file: file.to_owned(),
                field: name,
            })
    };
    let xyz = [find("x")?, find("y")?, find("z")?];
    let number = template.map_or(6, |t| t.point_format);
    // A column named as a standard field of the format, of the field's type (and, for a bit
    // field, with every value within its bits), goes into that field: a LAS input's dimensions
    // go back where they came from. Anything else is extra bytes.
    let mut standard = Vec::new();
    let mut defaults = Vec::new();
    for f in dims::fields(number) {
        let column = columns.iter().position(|c| {
            c.name == f.name && matches!(c.data, ColumnData::Attribute(d) if fits(d, &f))
        });
        match column {
            Some(c) => standard.push((f, c)),
            None => defaults.push(f),
        }
    }
    let extra: Vec<usize> = (0..columns.len())
        .filter(|&i| !matches!(columns[i].name, "x" | "y" | "z"))
        .filter(|i| !standard.iter().any(|(_, s)| s == i))
        .collect();
    for column in extra.iter().map(|&i| &columns[i]) {
        if column.name.len() > MAX_NAME_BYTES {
            return Err(WriteError::InvalidColumnName {
                file: file.to_owned(),
                name: column.name.to_owned(),
                reason: "longer than 32 characters, the limit of a LAS extra-bytes name",
            });
        }
    }
    let transforms = match template {
        Some(t) => {
            let transform = |i: usize| Transform {
                scale: t.scale[i],
                offset: t.offset[i],
            };
            Vector {
                x: transform(0),
                y: transform(1),
                z: transform(2),
            }
        }
        None => fitted_transforms(file, &xyz.map(|i| &columns[i]), rows)?,
    };
    let mut builder = Builder::from(Version::new(1, 4));
    let mut format = Format::new(number).map_err(|e| las_error(file, &e))?;
    let extra_len: usize = extra
        .iter()
        .map(|&i| extra::column_type(&columns[i].data).size())
        .sum();
    format.extra_bytes = u16::try_from(extra_len)
        .ok()
        .filter(|&n| usize::from(n) + usize::from(format.len()) <= usize::from(u16::MAX))
        .ok_or_else(|| WriteError::Las {
            file: file.to_owned(),
            message: format!("{} columns do not fit in a LAS point record", columns.len()),
        })?;
    format.is_compressed = compressed;
    builder.point_format = format;
    builder.transforms = transforms;
    "mls-curvature".clone_into(&mut builder.generating_software);
    if let Some(t) = template {
        builder.gps_time_type = t.gps_time_type;
        builder.file_source_id = t.file_source_id;
        builder.has_wkt_crs = t.has_wkt_crs;
        builder.vlrs.extend(t.vlrs.iter().cloned());
        builder.evlrs.extend(t.evlrs.iter().cloned());
    }
    if !extra.is_empty() {
        builder.vlrs.push(Vlr {
            user_id: extra::USER_ID.to_owned(),
            record_id: extra::RECORD_ID,
            description: "Extra Bytes".to_owned(),
            data: extra
                .iter()
                .flat_map(|&i| descriptor(&columns[i], template))
                .collect(),
        });
    }
    Ok((
        Plan {
            xyz,
            standard,
            defaults,
            extra,
            transforms,
            format,
            schema: schema(columns),
        },
        builder,
        rows,
    ))
}

/// The names and stored types of a table's columns.
fn schema(columns: &[Column<'_>]) -> Vec<(String, crate::AttributeType)> {
    columns
        .iter()
        .map(|c| (c.name.to_owned(), extra::column_type(&c.data)))
        .collect()
}

/// Whether every value of `data` can be stored in field `f` as it is.
fn fits(data: &AttributeData, f: &Field) -> bool {
    match (f.bits, data) {
        (None, data) => data.ty() == f.ty,
        (Some((_, mask)), AttributeData::U8(values)) => values.iter().all(|&v| v <= mask),
        (Some(_), _) => false,
    }
}

/// The input's descriptor for a column it carried, if the name and type still agree, else a
/// new one.
fn descriptor(column: &Column<'_>, template: Option<&LasTemplate>) -> Descriptor {
    let ty = extra::column_type(&column.data);
    template
        .and_then(|t| t.descriptors.iter().find(|(name, _)| name == column.name))
        .filter(|(_, d)| d[2] == ty.las_code())
        .map_or_else(|| extra::descriptor(column), |(_, d)| *d)
}

/// The transforms for a table without a template: the bounding box's minimum as offset, and
/// the scale of [`coordinate_scale`].
fn fitted_transforms(
    file: &str,
    xyz: &[&Column<'_>; 3],
    rows: usize,
) -> Result<Vector<Transform>, WriteError> {
    // The bounding box, which must be finite: a LAS coordinate is an integer step.
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for (axis, column) in xyz.iter().enumerate() {
        for row in 0..rows {
            let value = f64_at(&column.data, row);
            if !value.is_finite() {
                return Err(WriteError::NonFiniteCoordinate {
                    file: file.to_owned(),
                    column: column.name.to_owned(),
                    row,
                });
            }
            min[axis] = min[axis].min(value);
            max[axis] = max[axis].max(value);
        }
    }
    if rows == 0 {
        min = [0.0; 3];
        max = [0.0; 3];
    }
    let extent = (0..3).map(|i| max[i] - min[i]).fold(0.0, f64::max);
    let scale = coordinate_scale(extent);
    let transform = |axis: usize| Transform {
        scale,
        offset: min[axis],
    };
    Ok(Vector {
        x: transform(0),
        y: transform(1),
        z: transform(2),
    })
}

/// The power of ten between 1e-8 and 1e-7 of `extent` (see the module documentation).
pub(super) fn coordinate_scale(extent: f64) -> f64 {
    if extent > 0.0 && extent.is_finite() {
        10f64.powi(extent.log10().floor() as i32 - 7)
    } else {
        // One point, or all at the same place: every stored integer is 0 whatever the scale.
        1e-7
    }
}

/// Value `row` of a column, as a float (NaN past the end, which `validate` rules out).
fn f64_at(data: &ColumnData<'_>, row: usize) -> f64 {
    column_value(data, row).map_or(f64::NAN, Scalar::to_f64)
}

/// Value `row` of a column.
fn column_value(data: &ColumnData<'_>, row: usize) -> Option<Scalar> {
    Some(match *data {
        ColumnData::F64(values) => Scalar::F64(*values.get(row)?),
        ColumnData::I32(values) => Scalar::I32(*values.get(row)?),
        ColumnData::Component { vectors, axis } => Scalar::F64(axis.of(vectors.get(row)?)),
        ColumnData::Attribute(values) => values.get(row)?,
    })
}

/// Writes rows `first..` of a column, little-endian in its type, at byte `at` of the
/// successive `record`-byte records of `block`.
fn scatter(data: &ColumnData<'_>, first: usize, block: &mut [u8], record: usize, at: usize) {
    match *data {
        ColumnData::F64(values) => {
            scatter_le(values.get(first..).unwrap_or_default(), block, record, at)
        }
        ColumnData::I32(values) => {
            scatter_le(values.get(first..).unwrap_or_default(), block, record, at)
        }
        ColumnData::Component { vectors, axis } => {
            if at + f64::N <= record {
                let vectors = vectors.get(first..).unwrap_or_default();
                for (r, v) in block.chunks_exact_mut(record).zip(vectors) {
                    axis.of(v).write(&mut r[at..]);
                }
            }
        }
        ColumnData::Attribute(values) => values.scatter_le(first, block, record, at),
    }
}

fn las_error(file: &str, error: &las::Error) -> WriteError {
    match error {
        las::Error::Io(io) => WriteError::Io {
            file: file.to_owned(),
            error: io::Error::new(io.kind(), io.to_string()),
        },
        other => WriteError::Las {
            file: file.to_owned(),
            message: other.to_string(),
        },
    }
}

/// Writes the table as LAS or LAZ to `write`, which must be positioned where the file
/// starts.
fn write_to<W>(
    write: W,
    file: &str,
    columns: &[Column<'_>],
    compressed: bool,
    template: Option<&LasTemplate>,
) -> Result<W, WriteError>
where
    W: Write + Seek + Send + Sync + 'static,
{
    let (plan, builder, rows) = plan(file, columns, compressed, template)?;
    let header = builder.into_header().map_err(|e| las_error(file, &e))?;
    let mut writer = Writer::new(write, header).map_err(|e| las_error(file, &e))?;
    let written = write_points(&mut writer, &plan, columns, rows)
        .and_then(|bounds| writer.close().map(|()| bounds));
    match written {
        Ok(bounds) => {
            let mut inner = writer.into_inner().map_err(|e| las_error(file, &e))?;
            complete_header(&mut inner, file, &plan, bounds)?;
            Ok(inner)
        }
        Err(e) => {
            // The `las` writer closes itself when dropped and panics if that fails, which it
            // may after a failed write: leak it instead, on this error path only.
            std::mem::forget(writer);
            Err(las_error(file, &e))
        }
    }
}

/// The least and greatest stored (integer) coordinates of the records written, per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
struct StoredBounds {
    min: [i32; 3],
    max: [i32; 3],
}

impl StoredBounds {
    fn of(xyz: [i32; 3]) -> Self {
        Self { min: xyz, max: xyz }
    }

    fn with(self, xyz: [i32; 3]) -> Self {
        Self {
            min: std::array::from_fn(|i| self.min[i].min(xyz[i])),
            max: std::array::from_fn(|i| self.max[i].max(xyz[i])),
        }
    }

    fn union(a: Option<Self>, b: Option<Self>) -> Option<Self> {
        match (a, b) {
            (Some(a), Some(b)) => Some(a.with(b.min).with(b.max)),
            (a, b) => a.or(b),
        }
    }
}

/// Byte offsets in a LAS 1.4 header (LAS 1.4 R15, table 3).
mod header_at {
    /// File creation day of year, then year (`u16` each).
    pub const CREATION_DATE: u64 = 90;
    /// Legacy number of point records (`u32`), then the legacy numbers of points by return
    /// (5 × `u32`).
    pub const LEGACY_COUNTS: u64 = 107;
    /// Max X, min X, max Y, min Y, max Z, min Z (`f64` each).
    pub const BOUNDS: u64 = 179;
}

/// Completes the header the `las` crate wrote where LAS 1.4 R15 asks for other values than it
/// writes, at the header of `stream`, which starts at the stream's current position (where
/// [`Writer::into_inner`] leaves it), and returns there:
/// - for point formats 6 to 10 the legacy point counts must be 0 (the 64-bit counts, which
///   the crate writes, carry the numbers);
/// - the bounds must be those of the coordinates as stored: the crate rounds the largest
///   world coordinate up to the grid again and can land one step above it;
/// - the creation date, which the crate leaves 0, is today's (UTC) or, when the
///   `SOURCE_DATE_EPOCH` environment variable is set (reproducible output), that instant's.
fn complete_header<W: Write + Seek>(
    stream: &mut W,
    file: &str,
    plan: &Plan,
    bounds: Option<StoredBounds>,
) -> Result<(), WriteError> {
    let (day, year) = creation_date().map_err(|message| WriteError::Las {
        file: file.to_owned(),
        message,
    })?;
    let io_error = |error| WriteError::Io {
        file: file.to_owned(),
        error,
    };
    let start = stream.stream_position().map_err(io_error)?;
    let mut put = |at: u64, bytes: &[u8]| -> io::Result<()> {
        stream.seek(io::SeekFrom::Start(start + at))?;
        stream.write_all(bytes)
    };
    let mut date = [0u8; 4];
    date[..2].copy_from_slice(&day.to_le_bytes());
    date[2..].copy_from_slice(&year.to_le_bytes());
    put(header_at::CREATION_DATE, &date).map_err(io_error)?;
    if plan.format.is_extended {
        put(header_at::LEGACY_COUNTS, &[0u8; 24]).map_err(io_error)?;
    }
    if let Some(b) = bounds {
        let t = [plan.transforms.x, plan.transforms.y, plan.transforms.z];
        let mut bytes = Vec::with_capacity(48);
        for ((t, max), min) in t.iter().zip(b.max).zip(b.min) {
            // As a reader computes a coordinate from its stored integer.
            bytes.extend_from_slice(&t.direct(max).to_le_bytes());
            bytes.extend_from_slice(&t.direct(min).to_le_bytes());
        }
        put(header_at::BOUNDS, &bytes).map_err(io_error)?;
    }
    stream
        .seek(io::SeekFrom::Start(start))
        .map(drop)
        .map_err(io_error)
}

/// The LAS header's creation date as (day of year, year), UTC: `SOURCE_DATE_EPOCH`'s
/// instant when that is set (for reproducible output), else now.
///
/// # Errors
/// `SOURCE_DATE_EPOCH` is set but not a whole number of seconds: the message says so.
pub fn creation_date() -> Result<(u16, u16), String> {
    let seconds = match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(text) => text.trim().parse::<i64>().map_err(|_| {
            format!(
                "SOURCE_DATE_EPOCH=`{text}` is not a whole number of seconds since 1970-01-01 \
                 (it sets the LAS header's creation date)"
            )
        })?,
        Err(_) => std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs() as i64),
    };
    let (year, day) = year_and_day(seconds.div_euclid(86_400));
    // Years outside a u16 (before 1 or after 65535) are 0: unknown, as LAS allows.
    Ok(u16::try_from(year).map_or((0, 0), |y| (day, y)))
}

/// The year and the day of the year (1 for 1 January) of day `days` after 1970-01-01, in the
/// proleptic Gregorian calendar (H. Hinnant's `civil_from_days`).
fn year_and_day(days: i64) -> (i64, u16) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    // Day of the year counted from 1 March, in [0, 365].
    let from_march = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let leap = |y: i64| (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    // March to December follow January and February of the same year, from 1 March of the
    // civil year `yoe + era * 400`, which ends in February of the next.
    let march_year = yoe + era * 400;
    if from_march < 306 {
        let before_march = if leap(march_year) { 60 } else { 59 };
        (march_year, (from_march + before_march + 1) as u16)
    } else {
        (march_year + 1, (from_march - 306 + 1) as u16)
    }
}

/// Encodes the rows as raw point records, chunk by chunk.
fn write_points<W>(
    writer: &mut Writer<W>,
    plan: &Plan,
    columns: &[Column<'_>],
    rows: usize,
) -> las::Result<Option<StoredBounds>>
where
    W: Write + Seek + Send + Sync + 'static,
{
    let format = plan.format;
    let record_len = usize::from(format.len());
    let base = record_len - usize::from(format.extra_bytes);
    let transforms = [plan.transforms.x, plan.transforms.y, plan.transforms.z];
    let chunk = writer
        .header()
        .laz_vlr()
        .ok()
        .filter(|v| !v.uses_variable_size_chunks())
        .map(|v| v.chunk_size());
    let batch = super::batch_points(chunk);
    // The extra-bytes columns and their sizes, in record order.
    let extra: Vec<(&ColumnData<'_>, usize)> = plan
        .extra
        .iter()
        .map(|&i| {
            (
                &columns[i].data,
                extra::column_type(&columns[i].data).size(),
            )
        })
        .collect();
    // Rows `first..` into the records of `block`, column by column; the block's bounds.
    let encode = |first: usize, block: &mut [u8]| -> las::Result<Option<StoredBounds>> {
        let mut bounds: Option<StoredBounds> = None;
        for (row, record) in (first..).zip(block.chunks_exact_mut(record_len)) {
            let mut xyz = [0i32; 3];
            for (((&column, transform), at), stored) in plan
                .xyz
                .iter()
                .zip(&transforms)
                .zip([0, 4, 8])
                .zip(&mut xyz)
            {
                // The nearest step of the header's grid.
                *stored = transform.inverse(f64_at(&columns[column].data, row))?;
                record[at..at + 4].copy_from_slice(&stored.to_le_bytes());
            }
            bounds = Some(bounds.map_or(StoredBounds::of(xyz), |b| b.with(xyz)));
            for f in &plan.defaults {
                // One return of one, as a single-return scanner would record.
                if matches!(f.name, "return_number" | "number_of_returns") {
                    dims::encode(record, f, Scalar::U8(1));
                }
            }
        }
        for &(ref f, column) in &plan.standard {
            let data = &columns[column].data;
            if f.bits.is_some() {
                for (row, record) in (first..).zip(block.chunks_exact_mut(record_len)) {
                    if let Some(v) = column_value(data, row) {
                        dims::encode(record, f, v);
                    }
                }
            } else {
                // The plan put here only columns of the field's type.
                scatter(data, first, block, record_len, f.at);
            }
        }
        let mut at = base;
        for &(data, size) in &extra {
            scatter(data, first, block, record_len, at);
            at += size;
        }
        Ok(bounds)
    };
    let mut bounds: Option<StoredBounds> = None;
    let mut start = 0;
    while start < rows {
        let end = rows.min(start + batch);
        let mut bytes = vec![0u8; (end - start) * record_len];
        // Encoded on every thread: the codec's threads would otherwise wait for this one. The
        // first error in row order is the one reported, whatever the threads.
        let encoded: Vec<las::Result<Option<StoredBounds>>> = bytes
            .par_chunks_mut(RECORDS_PER_TASK * record_len)
            .enumerate()
            .map(|(task, block)| encode(start + task * RECORDS_PER_TASK, block))
            .collect();
        for block in encoded {
            bounds = StoredBounds::union(bounds, block?);
        }
        let data = PointDataBuilder::new()
            .for_header(writer.header())
            .build_from_bytes(bytes)?;
        writer.write_points(&data)?;
        start = end;
    }
    Ok(bounds)
}

/// A LAS or LAZ file written a chunk of rows at a time ([`crate::write_las_chunks`]), for
/// tables larger than memory. Every chunk has the same columns, named and typed alike; the
/// layout (point format, scale, offset, extra bytes) is the template's, with the extra-bytes
/// attributes chosen from the first chunk as [`crate::write_las`] chooses them for a whole
/// table.
pub struct LasSink {
    file: String,
    compressed: bool,
    template: LasTemplate,
    handle: Option<File>,
    writer: Option<(Writer<BufWriter<File>>, Plan)>,
    rows: u64,
    /// The stored coordinates' bounds over the chunks written.
    bounds: Option<StoredBounds>,
}

impl std::fmt::Debug for LasSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LasSink")
            .field("file", &self.file)
            .field("rows", &self.rows)
            .finish_non_exhaustive()
    }
}

impl LasSink {
    /// Appends the rows of `columns`.
    ///
    /// # Errors
    /// Those of [`crate::write_las`] for the first chunk; [`WriteError::Las`] when a later
    /// chunk's columns differ from the first's, or the `las` writer fails.
    pub fn write(&mut self, columns: &[Column<'_>]) -> Result<(), WriteError> {
        let file = self.file.clone();
        if self.writer.is_none() {
            let (plan, builder, _) = plan(&file, columns, self.compressed, Some(&self.template))?;
            let header = builder.into_header().map_err(|e| las_error(&file, &e))?;
            let handle = self.handle.take().ok_or_else(|| WriteError::Las {
                file: file.clone(),
                message: "the output was closed after an error".to_owned(),
            })?;
            let writer =
                Writer::new(BufWriter::new(handle), header).map_err(|e| las_error(&file, &e))?;
            self.writer = Some((writer, plan));
        }
        let rows = validate(&file, columns)?;
        let Some((writer, plan)) = self.writer.as_mut() else {
            unreachable!("set above");
        };
        if plan.schema != schema(columns) {
            return Err(WriteError::Las {
                file,
                message: "a chunk's columns differ from the first chunk's".to_owned(),
            });
        }
        match write_points(writer, plan, columns, rows) {
            Ok(bounds) => self.bounds = StoredBounds::union(self.bounds, bounds),
            Err(e) => {
                // See `write_to`: a failed `las` writer panics when dropped.
                if let Some(w) = self.writer.take() {
                    std::mem::forget(w);
                }
                return Err(las_error(&file, &e));
            }
        }
        self.rows += rows as u64;
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Completes the file: header counts and bounds, LAZ chunk table.
    fn finish(mut self) -> Result<(), WriteError> {
        let file = self.file.clone();
        let Some((mut writer, plan)) = self.writer.take() else {
            return Err(WriteError::NoColumns { file });
        };
        if let Err(e) = writer.close() {
            std::mem::forget(writer);
            return Err(las_error(&file, &e));
        }
        let mut inner = writer.into_inner().map_err(|e| las_error(&file, &e))?;
        complete_header(&mut inner, &file, &plan, self.bounds)?;
        inner
            .flush()
            .map_err(|error| WriteError::Io { file, error })
    }
}

/// Runs `body` with a [`LasSink`] on an already open file and completes the file.
pub(crate) fn write_file_chunks<E: From<WriteError>>(
    out: &mut BufWriter<&File>,
    file: &str,
    compressed: bool,
    template: &LasTemplate,
    body: impl FnOnce(&mut LasSink) -> Result<(), E>,
) -> Result<(), E> {
    let io_error = |error| WriteError::Io {
        file: file.to_owned(),
        error,
    };
    out.flush().map_err(io_error)?;
    let handle = out.get_ref().try_clone().map_err(io_error)?;
    let mut sink = LasSink {
        file: file.to_owned(),
        compressed,
        template: template.clone(),
        handle: Some(handle),
        writer: None,
        rows: 0,
        bounds: None,
    };
    let result = body(&mut sink);
    if result.is_err() {
        // Nothing more is written; the caller removes the file.
        if let Some(w) = sink.writer.take() {
            std::mem::forget(w);
        }
        return result;
    }
    sink.finish().map_err(E::from)
}

/// Writes the table as LAS (or LAZ if `compressed`) into an already open file, through a
/// handle of its own (the `las` writer owns its stream).
pub(crate) fn write_file(
    out: &mut BufWriter<&File>,
    file: &str,
    columns: &[Column<'_>],
    compressed: bool,
    template: Option<&LasTemplate>,
) -> Result<(), WriteError> {
    let io_error = |error| WriteError::Io {
        file: file.to_owned(),
        error,
    };
    out.flush().map_err(io_error)?;
    let handle = out.get_ref().try_clone().map_err(io_error)?;
    let mut inner = write_to(BufWriter::new(handle), file, columns, compressed, template)?;
    inner.flush().map_err(io_error)
}

/// Writes the table as LAS or LAZ to a stream that cannot seek (standard output), through
/// memory.
pub(crate) fn write_stream(
    mut out: impl Write,
    file: &str,
    columns: &[Column<'_>],
    compressed: bool,
    template: Option<&LasTemplate>,
) -> Result<(), WriteError> {
    let bytes =
        write_to(Cursor::new(Vec::new()), file, columns, compressed, template)?.into_inner();
    out.write_all(&bytes)
        .and_then(|()| out.flush())
        .map_err(|error| WriteError::Io {
            file: file.to_owned(),
            error,
        })
}

#[cfg(test)]
mod tests {
    use super::year_and_day;

    /// Against dates that `date -u -d DATE +%j` gives, and against counting the days year by
    /// year from 1970 over two centuries.
    #[test]
    fn year_and_day_is_the_calendars() {
        assert_eq!(year_and_day(0), (1970, 1));
        assert_eq!(year_and_day(-1), (1969, 365));
        assert_eq!(year_and_day(11_017), (2000, 61)); // 2000-03-01
        assert_eq!(year_and_day(20_088), (2024, 366)); // 2024-12-31
        assert_eq!(year_and_day(20_794), (2026, 341)); // 2026-12-07
        assert_eq!(year_and_day(47_540), (2100, 59)); // 2100-02-28
        let mut days = 0;
        for year in 1970..2170 {
            let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
            let length = if leap { 366 } else { 365 };
            for day in 1..=length {
                assert_eq!(year_and_day(days), (year, day), "day {days}");
                days += 1;
            }
        }
    }
}
