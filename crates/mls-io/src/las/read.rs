//! Reading LAS and LAZ: coordinates, every standard dimension of the point format and the
//! extra bytes, as attributes, and the header's layout as a [`LasTemplate`].

use std::collections::HashSet;
use std::io::{self, Cursor, Read, Seek};

use las::Reader;
use rayon::prelude::*;

use super::dims::{self, Field};
use super::extra::{self, ExtraField};
use super::{LasTemplate, extra::Descriptor};
use crate::attributes::{Attribute, AttributeData, Scalar, usable_name};
use crate::error::{ReadError, quoted};
use crate::{MAX_PREALLOCATED, PointCloud, ReadOutcome};

/// Where each attribute comes from in a record.
#[derive(Debug)]
enum Source {
    Standard(Field),
    /// Byte offset of the value within the record.
    Extra(usize),
}

/// A LAS or LAZ file (the header says which) read chunk by chunk: the header and its
/// layout at [`LasReader::open`], then the points in file order, a bounded number at a time,
/// so that a file larger than memory can be streamed.
pub struct LasReader {
    reader: Reader,
    name: String,
    expected: u64,
    done: u64,
    /// Length of the record without its extra bytes.
    base: usize,
    /// Length of the whole record.
    record_len: usize,
    normal_offsets: Option<[usize; 3]>,
    sources: Vec<Source>,
    /// Name and type of each attribute, in the order of `sources`.
    columns: Vec<(String, crate::AttributeType)>,
    template: LasTemplate,
    notes: Vec<String>,
    bounds: ([f64; 3], [f64; 3]),
    batch: u64,
    /// Where the point records start and where the stream ends (bytes from the header's
    /// start), and whether they are compressed: for the message about a truncated file.
    point_data: (u64, Option<u64>, bool),
}

impl std::fmt::Debug for LasReader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LasReader")
            .field("name", &self.name)
            .field("expected", &self.expected)
            .field("done", &self.done)
            .finish_non_exhaustive()
    }
}

/// The offset of the point records (from the header's raw field) and the length of the
/// stream, both from the stream's current position, which is restored.
fn measure<R: Read + Seek>(read: &mut R) -> io::Result<(u64, Option<u64>)> {
    let start = read.stream_position()?;
    let offset = las::raw::Header::read_from(&mut *read)
        .map(|h| u64::from(h.offset_to_point_data))
        .unwrap_or(0);
    let end = read.seek(io::SeekFrom::End(0))?;
    read.seek(io::SeekFrom::Start(start))?;
    Ok((offset, Some(end - start)))
}

impl LasReader {
    /// Reads the header of a LAS or LAZ file at `path`.
    ///
    /// # Errors
    /// [`ReadError::Io`] if it cannot be opened, [`ReadError::Las`] for a header that is not
    /// LAS or that describes its points inconsistently.
    pub fn open(path: &std::path::Path) -> Result<Self, ReadError> {
        let name = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|error| ReadError::Io {
            file: name.clone(),
            error,
        })?;
        Self::new(io::BufReader::new(file), &name)
    }

    /// Reads the header from `read`; `name` is the display name.
    pub(crate) fn new<R>(read: R, name: &str) -> Result<Self, ReadError>
    where
        R: Read + Seek + Send + Sync + 'static,
    {
        let error = |message: String| ReadError::Las {
            file: name.to_owned(),
            message,
        };
        // Where the points start and the stream ends, measured before the `las` reader takes
        // the stream; a header it cannot read gives its own error below.
        let mut read = read;
        let point_data = measure(&mut read).unwrap_or((0, None));
        let reader = Reader::new(read).map_err(|e| error(header_message(&e)))?;
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
                "{name}: point format {number}: the waveform packet fields are not carried to \
                 the output (point format {})",
                dims::without_waveform(number)
            ));
        }
        let extras = extra::parse(header).map_err(|m| error(format!("Extra Bytes VLR: {m}")))?;
        let normal_offsets = normal_offsets(&extras);
        let mut sources = Vec::new();
        let mut columns = Vec::new();
        let mut descriptors: Vec<(String, Descriptor)> = Vec::new();
        for f in dims::fields(number) {
            sources.push(Source::Standard(f));
            columns.push((f.name.to_owned(), f.ty));
        }
        let mut taken: HashSet<String> = columns.iter().map(|(n, _)| n.clone()).collect();
        let mut described = 0;
        for e in &extras {
            let end = e.offset + e.size;
            described = described.max(end);
            if normal_offsets.is_some_and(|o| o.contains(&e.offset)) {
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
            columns.push((usable, ty));
        }
        if described < extra_len {
            notes.push(format!(
                "{name}: {} extra bytes per point without a descriptor are not carried",
                extra_len - described
            ));
        }
        let template = LasTemplate::from_header(header, number, descriptors);
        let b = header.bounds();
        let bounds = ([b.min.x, b.min.y, b.min.z], [b.max.x, b.max.y, b.max.z]);
        let chunk = header
            .laz_vlr()
            .ok()
            .filter(|v| !v.uses_variable_size_chunks())
            .map(|v| v.chunk_size());
        Ok(Self {
            reader,
            name: name.to_owned(),
            expected,
            done: 0,
            base,
            record_len: usize::from(format.len()),
            normal_offsets,
            sources,
            columns,
            template,
            notes,
            bounds,
            batch: super::batch_points(chunk) as u64,
            point_data: (point_data.0, point_data.1, format.is_compressed),
        })
    }

    /// The number of points the header announces.
    pub fn len(&self) -> u64 {
        self.expected
    }

    /// Whether the header announces no points.
    pub fn is_empty(&self) -> bool {
        self.expected == 0
    }

    /// The bounding box the header records (minimum, maximum); writers keep it loosely, so a
    /// caller that needs it exact measures the points.
    pub fn header_bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.bounds
    }

    /// Points per [`Self::read_into`] call that keeps every thread of the LAZ codec busy, a
    /// few hundred thousand.
    pub fn batch_len(&self) -> u64 {
        self.batch
    }

    /// Bytes of one point record, extra bytes included.
    pub fn record_len(&self) -> usize {
        self.record_len
    }

    /// Whether the points have normals (`f64` extra bytes `nx`, `ny`, `nz`).
    pub fn has_normals(&self) -> bool {
        self.normal_offsets.is_some()
    }

    /// The layout of the file, for LAS output that keeps it.
    pub fn template(&self) -> &LasTemplate {
        &self.template
    }

    /// What the reader noticed in the header (dimensions it does not carry).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// A cloud with no points and this file's attribute columns, to read into.
    pub fn empty_cloud(&self, capacity: usize) -> PointCloud {
        PointCloud {
            points: Vec::with_capacity(capacity),
            normals: self.normal_offsets.map(|_| Vec::with_capacity(capacity)),
            attributes: self
                .columns
                .iter()
                .map(|(name, ty)| Attribute {
                    name: name.clone(),
                    data: AttributeData::with_capacity(*ty, capacity),
                })
                .collect(),
            las: None,
            scans: None,
        }
    }

    /// Reads the next `max` points at most (fewer at the end of the file) and appends them to
    /// `cloud`, which must come from [`Self::empty_cloud`]. Returns how many were read: 0 once
    /// every point is read.
    ///
    /// # Errors
    /// [`ReadError::Las`] for a truncated file, undecodable point data or a coordinate that is
    /// not finite, naming the point.
    pub fn read_into(&mut self, cloud: &mut PointCloud, max: u64) -> Result<usize, ReadError> {
        let (expected, done) = (self.expected, self.done);
        if done >= expected || max == 0 {
            return Ok(0);
        }
        let error = |message: String| ReadError::Las {
            file: self.name.clone(),
            message,
        };
        let want = max.min(expected - done);
        let (start, end, compressed) = self.point_data;
        let record = self.record_len as u64;
        let data = self.reader.read_points(want).map_err(|e| {
            error(if ends_early(&e) {
                match end {
                    // Uncompressed: the last whole record says where.
                    Some(end) if !compressed && record > 0 => {
                        let whole = end.saturating_sub(start) / record;
                        format!(
                            "truncated: the header says {expected} points but the file ends at \
                             byte {end}, within point {whole} (the point records start at byte \
                             {start}, {record} bytes each; points 0..{whole} are whole)"
                        )
                    }
                    Some(end) => format!(
                        "truncated: the header says {expected} points but the compressed data \
                         ends at byte {end} of the file, within points {done}..{} (points \
                         0..{done} were read)",
                        done + want
                    ),
                    None => format!(
                        "truncated: the header says {expected} points but the data ends within \
                         points {done}..{} (points 0..{done} were read)",
                        done + want
                    ),
                }
            } else {
                format!("point data from point {done}: {e}")
            })
        })?;
        if data.is_empty() {
            return Err(error(format!(
                "truncated: the header says {expected} points but only {done} could be read"
            )));
        }
        // Column by column, each on its own thread: the codec's threads are idle meanwhile.
        let raw = data.raw_bytes();
        let record = data.record_len();
        let base = self.base;
        let points = || {
            for (index, ((x, y), z)) in data.x().zip(data.y()).zip(data.z()).enumerate() {
                if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                    return Err(error(format!(
                        "point {}: coordinate ({x}, {y}, {z}) is not finite (check the header's \
                         scale and offset)",
                        done + index as u64
                    )));
                }
                cloud.points.push([x, y, z]);
            }
            Ok(())
        };
        let normals = || {
            if let (Some(offsets), Some(normals)) = (self.normal_offsets, cloud.normals.as_mut()) {
                normals.extend(raw.chunks_exact(record).map(|raw| {
                    offsets.map(|o| {
                        let at = base + o;
                        raw.get(at..at + 8)
                            .and_then(|b| b.try_into().ok())
                            .map_or(f64::NAN, f64::from_le_bytes)
                    })
                }));
            }
        };
        let attributes = || {
            self.sources
                .par_iter()
                .zip(cloud.attributes.par_iter_mut())
                .for_each(|(source, attribute)| {
                    // Within the record: the layout is the las crate's, and the extra bytes
                    // were checked against it when the header was read.
                    let data = &mut attribute.data;
                    match (source, data) {
                        (Source::Standard(f), AttributeData::U8(v)) if f.bits.is_some() => {
                            v.extend(raw.chunks_exact(record).filter_map(|r| {
                                match dims::decode(r, f) {
                                    Some(Scalar::U8(b)) => Some(b),
                                    _ => None,
                                }
                            }));
                        }
                        (Source::Standard(f), data) => {
                            data.extend_le(raw, record, f.at);
                        }
                        (Source::Extra(at), data) => {
                            data.extend_le(raw, record, *at);
                        }
                    }
                });
        };
        let (points, ((), ())) = rayon::join(points, || rayon::join(normals, attributes));
        points?;
        self.done += data.len() as u64;
        Ok(data.len())
    }
}

/// Reads a LAS or LAZ file (the header says which) from `read`; `name` is the display name.
pub(crate) fn read<R>(read: R, name: &str) -> Result<ReadOutcome, ReadError>
where
    R: Read + Seek + Send + Sync + 'static,
{
    let mut reader = LasReader::new(read, name)?;
    let capacity = usize::try_from(reader.len().min(MAX_PREALLOCATED)).unwrap_or(0);
    let mut cloud = reader.empty_cloud(capacity);
    let batch = reader.batch_len();
    while reader.read_into(&mut cloud, batch)? > 0 {}
    cloud.las = Some(reader.template.clone());
    Ok(ReadOutcome {
        cloud,
        notes: std::mem::take(&mut reader.notes),
    })
}

/// Offsets within each point's extra bytes of `f64` attributes named `nx`, `ny`, `nz` (as
/// `mlscurv` writes them) or, when those are absent, by one of their aliases in any case
/// (`NormalX` …, as PDAL writes them with `extra_dims`), when the Extra Bytes VLR declares
/// all three.
fn normal_offsets(extras: &[ExtraField]) -> Option<[usize; 3]> {
    let f64s = || {
        extras
            .iter()
            .filter(|e| e.ty == Some(crate::AttributeType::F64))
    };
    let find = |n: &str| {
        f64s()
            .find(|e| e.name == n)
            .or_else(|| f64s().find(|e| crate::slot_alias(&e.name.to_ascii_lowercase()) == n))
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
