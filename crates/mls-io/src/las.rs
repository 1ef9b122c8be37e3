//! LAS and LAZ (ASPRS LAS 1.0–1.4, LASzip-compressed or not) through the `las` crate.
//!
//! Reading keeps the points only, as `f64` world coordinates (the crate applies the header's
//! scale and offset); LAS has no normals. Writing puts `x y z` in the point records (LAS 1.4,
//! point format 6) and every other column in LAS 1.4 "extra bytes" with its name: `f64` for
//! float columns, `i32` for integer ones, described by an Extra Bytes VLR so that PDAL,
//! laspy and CloudCompare show them as dimensions / scalar fields.
//!
//! The coordinate scale is the power of ten `10^(floor(log10 E) - 7)`, where `E` is the
//! largest extent of the bounding box, and the offset is the box's minimum: every coordinate
//! is then stored within half a scale step, between 5e-9 and 5e-8 of `E`, far below the 1e-6
//! relative resolution the curvature needs, and the stored integers stay below 10^8, well
//! inside the `i32` range. A decimal scale is what LiDAR tools expect to display.

use std::fs::File;
use std::io::{self, BufWriter, Cursor, Read, Seek, Write};

use las::point::Format;
use las::{Builder, Point, Reader, Transform, Vector, Version, Vlr, Writer};

use crate::error::{ReadError, WriteError};
use crate::write::{Column, ColumnData, validate};
use crate::{MAX_PREALLOCATED, PointCloud};

/// Points read per call to the `las` reader: bounded, so a header that claims too many points
/// costs no memory until they arrive.
const CHUNK_POINTS: u64 = 1 << 16;

/// The longest name an extra-bytes descriptor holds.
const MAX_NAME_BYTES: usize = 32;

/// Extra Bytes VLR: LASF_Spec record 4, one 192-byte descriptor per attribute.
const EXTRA_BYTES_USER_ID: &str = "LASF_Spec";
const EXTRA_BYTES_RECORD_ID: u16 = 4;
const DESCRIPTOR_BYTES: usize = 192;
/// The data types of the LAS 1.4 extra-bytes descriptor.
const TYPE_I32: u8 = 6;
const TYPE_F64: u8 = 10;

/// Reads a LAS or LAZ file (the header says which) from `read`; `name` is the display name.
pub(crate) fn read<R>(read: R, name: &str) -> Result<PointCloud, ReadError>
where
    R: Read + Seek + Send + Sync + 'static,
{
    let error = |message: String| ReadError::Las {
        file: name.to_owned(),
        message,
    };
    let mut reader = Reader::new(read).map_err(|e| error(header_message(&e)))?;
    let expected = reader.header().number_of_points();
    let normal_offsets = normal_extra_bytes(reader.header());
    let mut normals = normal_offsets.map(|_| Vec::with_capacity(0));
    let capacity = usize::try_from(expected.min(MAX_PREALLOCATED)).unwrap_or(0);
    let mut points = Vec::with_capacity(capacity);
    let mut done: u64 = 0;
    while done < expected {
        let data = reader
            .read_points(CHUNK_POINTS.min(expected - done))
            .map_err(|e| {
                error(if ends_early(&e) {
                    format!(
                        "truncated: the header says {expected} points but the data ends \
                         within points {done}..{}",
                        done + CHUNK_POINTS.min(expected - done)
                    )
                } else {
                    format!("point data from point {done}: {e}")
                })
            })?;
        if data.is_empty() {
            return Err(error(format!(
                "truncated: the header says {expected} points but only {done} could be read"
            )));
        }
        for (index, ((x, y), z)) in data.x().zip(data.y()).zip(data.z()).enumerate() {
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                return Err(error(format!(
                    "point {}: coordinate ({x}, {y}, {z}) is not finite (check the header's \
                     scale and offset)",
                    done + index as u64
                )));
            }
            points.push([x, y, z]);
        }
        // Extra bytes close each record (`Format::len` counts them).
        let format = data.format();
        let base = format
            .len()
            .checked_sub(format.extra_bytes)
            .map(usize::from);
        if let (Some(offsets), Some(normals), Some(base)) = (normal_offsets, normals.as_mut(), base)
        {
            let record = data.record_len();
            for raw in data.raw_bytes().chunks_exact(record) {
                normals.push(offsets.map(|o| {
                    let at = base + o;
                    raw.get(at..at + 8)
                        .and_then(|b| b.try_into().ok())
                        .map_or(f64::NAN, f64::from_le_bytes)
                }));
            }
        }
        done += data.len() as u64;
    }
    Ok(PointCloud { points, normals })
}

/// Offsets within each point's extra bytes of `f64` attributes named `nx`, `ny`, `nz` (as
/// `mlscurv` writes them), when the Extra Bytes VLR declares all three.
fn normal_extra_bytes(header: &las::Header) -> Option<[usize; 3]> {
    let vlr = header
        .all_vlrs()
        .find(|v| v.user_id == EXTRA_BYTES_USER_ID && v.record_id == EXTRA_BYTES_RECORD_ID)?;
    let mut offset = 0;
    let mut found = [None; 3];
    for d in vlr.data.chunks_exact(DESCRIPTOR_BYTES) {
        // Sizes of the LAS 1.4 data types 1–10; type 0 keeps its size in the options byte.
        let size = match d[2] {
            0 => usize::from(d[3]),
            1 | 2 => 1,
            3 | 4 => 2,
            5 | 6 | 9 => 4,
            7 | 8 | 10 => 8,
            _ => return None,
        };
        let name = &d[4..36];
        let name = &name[..name.iter().position(|&b| b == 0).unwrap_or(32)];
        if let Some(i) = [&b"nx"[..], b"ny", b"nz"].iter().position(|n| *n == name)
            && d[2] == TYPE_F64
        {
            found[i] = Some(offset);
        }
        offset += size;
    }
    match found {
        [Some(x), Some(y), Some(z)] => Some([x, y, z]),
        _ => None,
    }
}

/// The message for an error while reading the header.
fn header_message(error: &las::Error) -> String {
    match error {
        las::Error::InvalidFileSignature(signature) => format!(
            "not a LAS file: it starts with {:?}, not \"LASF\"",
            String::from_utf8_lossy(signature)
        ),
        e if ends_early(e) => {
            "truncated: the file ends within the LAS header, its VLRs or the LAZ chunk table"
                .to_owned()
        }
        other => format!("LAS header: {other}"),
    }
}

/// Whether the error is the end of the file where more data should be.
fn ends_early(error: &las::Error) -> bool {
    let io = match error {
        las::Error::Io(io) | las::Error::LasZipError(laz::LasZipError::IoError(io)) => io,
        _ => return false,
    };
    io.kind() == io::ErrorKind::UnexpectedEof
}

/// Reads a whole stream (such as standard input) into memory and reads LAS or LAZ from it:
/// the `las` reader needs to seek.
pub(crate) fn read_stream(mut reader: impl Read, name: &str) -> Result<PointCloud, ReadError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|error| ReadError::Io {
            file: name.to_owned(),
            error,
        })?;
    read(Cursor::new(bytes), name)
}

/// The plan of a LAS file for a table: the coordinate columns, the extra-bytes columns and
/// the header.
#[derive(Debug)]
struct Plan<'c, 'a> {
    xyz: [&'c Column<'a>; 3],
    extra: Vec<&'c Column<'a>>,
    builder: Builder,
}

/// Checks the table and chooses the header for it.
fn plan<'c, 'a>(
    file: &str,
    columns: &'c [Column<'a>],
    compressed: bool,
) -> Result<(Plan<'c, 'a>, usize), WriteError> {
    let rows = validate(file, columns)?;
    let find = |name: &'static str| {
        columns
            .iter()
            .find(|c| c.name == name)
            .ok_or_else(|| WriteError::MissingCoordinate {
                file: file.to_owned(),
                field: name,
            })
    };
    let xyz = [find("x")?, find("y")?, find("z")?];
    let extra: Vec<&Column<'_>> = columns
        .iter()
        .filter(|c| !matches!(c.name, "x" | "y" | "z"))
        .collect();
    for column in &extra {
        if column.name.len() > MAX_NAME_BYTES {
            return Err(WriteError::InvalidColumnName {
                file: file.to_owned(),
                name: column.name.to_owned(),
                reason: "longer than 32 characters, the limit of a LAS extra-bytes name",
            });
        }
    }
    // The bounding box, which must be finite: a LAS coordinate is an integer step.
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for (axis, column) in xyz.iter().enumerate() {
        for (row, value) in f64_values(&column.data).enumerate() {
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
    let transforms = Vector {
        x: transform(0),
        y: transform(1),
        z: transform(2),
    };
    let mut builder = Builder::from(Version::new(1, 4));
    let mut format = Format::new(6).map_err(|e| las_error(file, &e))?;
    let extra_len: usize = extra.iter().map(|c| value_bytes(&c.data)).sum();
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
    if !extra.is_empty() {
        builder.vlrs.push(Vlr {
            user_id: EXTRA_BYTES_USER_ID.to_owned(),
            record_id: EXTRA_BYTES_RECORD_ID,
            description: "Extra Bytes".to_owned(),
            data: extra.iter().flat_map(|c| descriptor(c)).collect(),
        });
    }
    Ok((
        Plan {
            xyz,
            extra,
            builder,
        },
        rows,
    ))
}

/// The power of ten between 1e-8 and 1e-7 of `extent` (see the module documentation).
fn coordinate_scale(extent: f64) -> f64 {
    if extent > 0.0 && extent.is_finite() {
        10f64.powi(extent.log10().floor() as i32 - 7)
    } else {
        // One point, or all at the same place: every stored integer is 0 whatever the scale.
        1e-7
    }
}

/// The description written for a column `mlscurv` produces (at most 32 bytes, shown by PDAL,
/// laspy and CloudCompare beside the name); other columns get none.
fn description(name: &str) -> &'static str {
    match name {
        "nx" | "ny" | "nz" => "unit surface normal",
        "k1" => "larger principal curvature",
        "k2" => "smaller principal curvature",
        "mean" => "mean curvature (k1 + k2)/2",
        "gauss" => "Gaussian curvature k1 k2",
        "d1x" | "d1y" | "d1z" => "unit direction of k1",
        "d2x" | "d2y" | "d2z" => "unit direction of k2",
        "k1_sd" => "predicted error of k1",
        "k2_sd" => "predicted error of k2",
        "h" => "chosen Gaussian scale h",
        "noise" => "estimated position noise",
        "status" => "0 ok; codes: mlscurv --help",
        _ => "",
    }
}

/// One 192-byte extra-bytes descriptor (LAS 1.4 R15, table 24): no options (no no-data,
/// min, max, scale or offset), the name and, for `mlscurv`'s columns, a description.
fn descriptor(column: &Column<'_>) -> [u8; DESCRIPTOR_BYTES] {
    let mut d = [0u8; DESCRIPTOR_BYTES];
    // Bytes 0–1 reserved; 2 data type; 3 options; 4–35 name; then unused, no_data, min,
    // max, scale, offset (4 + 5 × 24 bytes) and a 32-byte description.
    d[2] = match column.data {
        ColumnData::I32(_) => TYPE_I32,
        ColumnData::F64(_) | ColumnData::Component { .. } => TYPE_F64,
    };
    let name = column.name.as_bytes();
    d[4..4 + name.len()].copy_from_slice(name);
    let text = description(column.name).as_bytes();
    d[DESCRIPTOR_BYTES - 32..DESCRIPTOR_BYTES - 32 + text.len()].copy_from_slice(text);
    d
}

fn value_bytes(data: &ColumnData<'_>) -> usize {
    match data {
        ColumnData::I32(_) => 4,
        ColumnData::F64(_) | ColumnData::Component { .. } => 8,
    }
}

/// A float column's values (integer columns as floats, for completeness).
fn f64_values<'d>(data: &'d ColumnData<'_>) -> Box<dyn Iterator<Item = f64> + 'd> {
    match *data {
        ColumnData::F64(values) => Box::new(values.iter().copied()),
        ColumnData::I32(values) => Box::new(values.iter().map(|&v| f64::from(v))),
        ColumnData::Component { vectors, axis } => {
            Box::new(vectors.iter().map(move |v| axis.of(v)))
        }
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
) -> Result<W, WriteError>
where
    W: Write + Seek + Send + Sync + 'static,
{
    let (plan, rows) = plan(file, columns, compressed)?;
    let header = plan
        .builder
        .into_header()
        .map_err(|e| las_error(file, &e))?;
    let mut writer = Writer::new(write, header).map_err(|e| las_error(file, &e))?;
    let written =
        write_points(&mut writer, &plan.xyz, &plan.extra, rows).and_then(|()| writer.close());
    match written {
        Ok(()) => writer.into_inner().map_err(|e| las_error(file, &e)),
        Err(e) => {
            // The `las` writer closes itself when dropped and panics if that fails, which it
            // may after a failed write: leak it instead, on this error path only.
            std::mem::forget(writer);
            Err(las_error(file, &e))
        }
    }
}

fn write_points<W>(
    writer: &mut Writer<W>,
    xyz: &[&Column<'_>; 3],
    extra: &[&Column<'_>],
    rows: usize,
) -> las::Result<()>
where
    W: Write + Seek + Send + Sync + 'static,
{
    let [xs, ys, zs] = xyz.map(|c| f64_values(&c.data));
    let mut extra_values: Vec<Box<dyn Iterator<Item = [u8; 8]> + '_>> = extra
        .iter()
        .map(|c| -> Box<dyn Iterator<Item = [u8; 8]> + '_> {
            match c.data {
                ColumnData::I32(values) => Box::new(values.iter().map(|v| {
                    let mut b = [0u8; 8];
                    b[..4].copy_from_slice(&v.to_le_bytes());
                    b
                })),
                _ => Box::new(f64_values(&c.data).map(f64::to_le_bytes)),
            }
        })
        .collect();
    let widths: Vec<usize> = extra.iter().map(|c| value_bytes(&c.data)).collect();
    let record: usize = widths.iter().sum();
    for ((x, y), z) in xs.zip(ys).zip(zs).take(rows) {
        let mut extra_bytes = Vec::with_capacity(record);
        for (values, &width) in extra_values.iter_mut().zip(&widths) {
            let bytes = values.next().unwrap_or_default();
            extra_bytes.extend_from_slice(&bytes[..width]);
        }
        // The writer stores the nearest step of the header's grid.
        writer.write_point(Point {
            x,
            y,
            z,
            return_number: 1,
            number_of_returns: 1,
            gps_time: Some(0.0),
            extra_bytes,
            ..Point::default()
        })?;
    }
    Ok(())
}

/// Writes the table as LAS (or LAZ if `compressed`) into an already open file, through a
/// handle of its own (the `las` writer owns its stream).
pub(crate) fn write_file(
    out: &mut BufWriter<&File>,
    file: &str,
    columns: &[Column<'_>],
    compressed: bool,
) -> Result<(), WriteError> {
    let io_error = |error| WriteError::Io {
        file: file.to_owned(),
        error,
    };
    out.flush().map_err(io_error)?;
    let handle = out.get_ref().try_clone().map_err(io_error)?;
    let mut inner = write_to(BufWriter::new(handle), file, columns, compressed)?;
    inner.flush().map_err(io_error)
}

/// Writes the table as LAS or LAZ to a stream that cannot seek (standard output), through
/// memory.
pub(crate) fn write_stream(
    mut out: impl Write,
    file: &str,
    columns: &[Column<'_>],
    compressed: bool,
) -> Result<(), WriteError> {
    let bytes = write_to(Cursor::new(Vec::new()), file, columns, compressed)?.into_inner();
    out.write_all(&bytes)
        .and_then(|()| out.flush())
        .map_err(|error| WriteError::Io {
            file: file.to_owned(),
            error,
        })
}

#[cfg(test)]
mod description_tests {
    /// Every description fits the descriptor's 32 bytes.
    #[test]
    fn descriptions_fit() {
        for name in [
            "nx", "k1", "k2", "mean", "gauss", "d1x", "d2z", "k1_sd", "k2_sd", "h", "noise",
            "status", "other",
        ] {
            assert!(super::description(name).len() <= 32, "{name}");
        }
    }
}
