//! Reading LAS and LAZ: coordinates, every standard dimension of the point format and the
//! extra bytes, as attributes, and the header's layout as a [`LasTemplate`].

use std::collections::HashSet;
use std::io::{self, Cursor, Read, Seek};

use las::Reader;

use super::dims::{self, Field};
use super::extra::{self, ExtraField};
use super::{LasTemplate, extra::Descriptor};
use crate::attributes::{Attribute, AttributeData, usable_name};
use crate::error::{ReadError, quoted};
use crate::{MAX_PREALLOCATED, PointCloud, ReadOutcome};

/// Points read per call to the `las` reader: bounded, so a header that claims too many points
/// costs no memory until they arrive.
const CHUNK_POINTS: u64 = 1 << 16;

/// Where each attribute comes from in a record.
#[derive(Debug)]
enum Source {
    Standard(Field),
    /// Byte offset of the value within the record.
    Extra(usize),
}

/// Reads a LAS or LAZ file (the header says which) from `read`; `name` is the display name.
pub(crate) fn read<R>(read: R, name: &str) -> Result<ReadOutcome, ReadError>
where
    R: Read + Seek + Send + Sync + 'static,
{
    let error = |message: String| ReadError::Las {
        file: name.to_owned(),
        message,
    };
    let mut reader = Reader::new(read).map_err(|e| error(header_message(&e)))?;
    let header = reader.header();
    let expected = header.number_of_points();
    let format = *header.point_format();
    let number = format
        .to_u8()
        .map_err(|e| error(format!("LAS header: {e}")))?;
    let extra_len = usize::from(format.extra_bytes);
    // Extra bytes close each record (`Format::len` counts them).
    let base = usize::from(format.len()) - extra_len;
    let mut notes = Vec::new();
    if format.has_waveform {
        notes.push(format!(
            "{name}: point format {number}: the waveform packet fields are not carried to the \
             output (point format {})",
            dims::without_waveform(number)
        ));
    }
    let extras = extra::parse(header).map_err(|m| error(format!("Extra Bytes VLR: {m}")))?;
    let normal_offsets = normal_offsets(&extras);
    let capacity = usize::try_from(expected.min(MAX_PREALLOCATED)).unwrap_or(0);
    let mut sources = Vec::new();
    let mut attributes = Vec::new();
    let mut descriptors: Vec<(String, Descriptor)> = Vec::new();
    for f in dims::fields(number) {
        sources.push(Source::Standard(f));
        attributes.push(Attribute {
            name: f.name.to_owned(),
            data: AttributeData::with_capacity(f.ty, capacity),
        });
    }
    let mut taken: HashSet<String> = attributes.iter().map(|a| a.name.clone()).collect();
    let mut described = 0;
    for e in &extras {
        let end = e.offset + e.size;
        described = described.max(end);
        if normal_offsets.is_some() && matches!(e.name.as_str(), "nx" | "ny" | "nz") {
            continue;
        }
        let Some(ty) = e.ty else {
            notes.push(format!(
                "{name}: extra bytes {}: data type {} (not a single number) is not carried",
                quoted(&e.name),
                e.code
            ));
            continue;
        };
        if end > extra_len {
            return Err(error(format!(
                "extra bytes {} ({}) end at byte {end} of the extra bytes, but each point \
                 has only {extra_len}",
                quoted(&e.name),
                ty.name()
            )));
        }
        // A name such as "Echo Width" becomes one every writer can write, and one that a
        // standard dimension already has gets a number; the descriptor keeps the original.
        let usable = usable_name(&e.name, "extra", &mut taken);
        sources.push(Source::Extra(base + e.offset));
        descriptors.push((usable.clone(), e.descriptor));
        attributes.push(Attribute {
            name: usable,
            data: AttributeData::with_capacity(ty, capacity),
        });
    }
    if described < extra_len {
        notes.push(format!(
            "{name}: {} extra bytes per point without a descriptor are not carried",
            extra_len - described
        ));
    }
    let template = LasTemplate::from_header(header, number, descriptors);

    let mut points = Vec::with_capacity(capacity);
    let mut normals = normal_offsets.map(|_| Vec::with_capacity(capacity));
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
        let record = data.record_len();
        for raw in data.raw_bytes().chunks_exact(record) {
            if let (Some(offsets), Some(normals)) = (normal_offsets, normals.as_mut()) {
                normals.push(offsets.map(|o| {
                    let at = base + o;
                    raw.get(at..at + 8)
                        .and_then(|b| b.try_into().ok())
                        .map_or(f64::NAN, f64::from_le_bytes)
                }));
            }
            for (source, attribute) in sources.iter().zip(&mut attributes) {
                // Both arms are within the record: the layout is the las crate's, and the
                // extra bytes were checked against it above.
                match source {
                    Source::Standard(f) => {
                        if let Some(value) = dims::decode(raw, f) {
                            attribute.data.push(value);
                        }
                    }
                    Source::Extra(at) => {
                        attribute
                            .data
                            .push_bytes(raw.get(*at..).unwrap_or_default(), false);
                    }
                }
            }
        }
        done += data.len() as u64;
    }
    Ok(ReadOutcome {
        cloud: PointCloud {
            points,
            normals,
            attributes,
            las: Some(template),
            scans: None,
        },
        notes,
    })
}

/// Offsets within each point's extra bytes of `f64` attributes named `nx`, `ny`, `nz` (as
/// `mlscurv` writes them), when the Extra Bytes VLR declares all three.
fn normal_offsets(extras: &[ExtraField]) -> Option<[usize; 3]> {
    let find = |n: &str| {
        extras
            .iter()
            .find(|e| e.name == n && e.ty == Some(crate::AttributeType::F64))
            .map(|e| e.offset)
    };
    Some([find("nx")?, find("ny")?, find("nz")?])
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
pub(crate) fn read_stream(mut reader: impl Read, name: &str) -> Result<ReadOutcome, ReadError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|error| ReadError::Io {
            file: name.to_owned(),
            error,
        })?;
    read(Cursor::new(bytes), name)
}
