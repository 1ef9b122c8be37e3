//! A streaming PLY reader: the header is parsed into element layouts, then only the `vertex`
//! element is decoded, with a per-property plan computed once.
//!
//! The maintained PLY crates were measured and not used: `ply-rs-bw` stores each vertex as a
//! map of properties by default (1.06 s and 800 MB for a million vertices), and its typed
//! interface, though fast, reports neither byte offsets nor property names in its errors and
//! can panic on some inputs. Reading only x, y, z and nx, ny, nz needs little code.

use std::collections::HashSet;
use std::io::{self, BufRead, Read};

use crate::error::{ReadError, quoted};
use crate::lines::{Lines, parse_finite, strip_line_ending};
use crate::{CloudBuilder, PointCloud, SLOT_NAMES};

/// Longest header line accepted. It bounds what a binary file without line breaks, passed off
/// as PLY, makes the reader buffer before it gives up.
const MAX_HEADER_LINE: u64 = 64 * 1024;

/// How the body is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

/// A PLY scalar type, under either its classic or its sized name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    /// The size in bytes in a binary body.
    const fn size(self) -> u64 {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    /// The sized name, used in error messages whatever name the header used.
    const fn name(self) -> &'static str {
        match self {
            Self::I8 => "int8",
            Self::U8 => "uint8",
            Self::I16 => "int16",
            Self::U16 => "uint16",
            Self::I32 => "int32",
            Self::U32 => "uint32",
            Self::F32 => "float32",
            Self::F64 => "float64",
        }
    }

    const fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    /// Decodes the value at the start of `bytes`; every type converts to `f64` exactly.
    /// `None` only if `bytes` is shorter than the type, which the callers rule out.
    fn decode(self, bytes: &[u8], encoding: Encoding) -> Option<f64> {
        fn array<const N: usize>(bytes: &[u8]) -> Option<[u8; N]> {
            bytes.get(..N)?.try_into().ok()
        }
        let big = encoding == Encoding::BigEndian;
        // One macro arm per type keeps the byte order choice in one place.
        macro_rules! decode {
            ($t:ty) => {{
                let raw = array(bytes)?;
                f64::from(if big {
                    <$t>::from_be_bytes(raw)
                } else {
                    <$t>::from_le_bytes(raw)
                })
            }};
        }
        Some(match self {
            Self::I8 => decode!(i8),
            Self::U8 => decode!(u8),
            Self::I16 => decode!(i16),
            Self::U16 => decode!(u16),
            Self::I32 => decode!(i32),
            Self::U32 => decode!(u32),
            Self::F32 => decode!(f32),
            Self::F64 => decode!(f64),
        })
    }
}

/// The type of one property.
#[derive(Clone, Copy, Debug)]
enum PropertyKind {
    Scalar(ScalarType),
    /// A length of type `count`, then that many values of type `item`.
    List {
        count: ScalarType,
        item: ScalarType,
    },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: PropertyKind,
    /// The header line that declares it.
    line: usize,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// The header line that declares it.
    line: usize,
}

impl Element {
    /// The record size in a binary body, if no property is a list.
    fn fixed_size(&self) -> Option<u64> {
        self.properties
            .iter()
            .map(|p| match p.kind {
                PropertyKind::Scalar(t) => Some(t.size()),
                PropertyKind::List { .. } => None,
            })
            .sum()
    }

    /// In a fixed-size record, the property holding byte `at` and the offset where it starts.
    fn property_at(&self, at: u64) -> Option<(&Property, u64)> {
        let mut start = 0;
        for property in &self.properties {
            let size = match property.kind {
                PropertyKind::Scalar(t) => t.size(),
                PropertyKind::List { .. } => return None,
            };
            if at < start + size {
                return Some((property, start));
            }
            start += size;
        }
        None
    }
}

/// Names a value for an error message, e.g. `vertex 17 property y (float32)`.
fn describe(element: &Element, index: u64, property: &Property, what: &str) -> String {
    format!(
        "{} {index} property {} ({what})",
        element.name, property.name
    )
}

#[derive(Debug)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Number of lines, so the ASCII body can go on counting.
    lines: usize,
    /// Length in bytes, where the binary body starts.
    bytes: u64,
}

/// Reads a PLY stream; `size_hint` is the total file size when known, to bound preallocation.
pub(crate) fn read(
    mut reader: impl BufRead,
    file: &str,
    size_hint: Option<u64>,
) -> Result<PointCloud, ReadError> {
    let header = parse_header(&mut reader, file)?;
    let (vertex_index, targets) = vertex_layout(&header, file)?;
    let has_normals = targets.iter().flatten().any(|&slot| slot >= 3);
    let remaining = size_hint.map(|size| size.saturating_sub(header.bytes));
    let mut elements = header.elements.iter();
    // The elements before the vertex element are skipped; those after it are never read, as
    // nothing in them is needed.
    let before = elements.by_ref().take(vertex_index);
    match header.encoding {
        Encoding::Ascii => {
            let mut lines = Lines::new(reader, header.lines);
            for element in before {
                skip_ascii_element(&mut lines, file, element)?;
            }
            let Some(vertex) = elements.next() else {
                return Err(no_vertex_element(file, &header));
            };
            read_ascii_vertices(&mut lines, file, vertex, &targets, has_normals, remaining)
        }
        Encoding::LittleEndian | Encoding::BigEndian => {
            let mut body = BinaryBody {
                reader,
                file,
                offset: header.bytes,
                encoding: header.encoding,
            };
            for element in before {
                body.skip_element(element)?;
            }
            let Some(vertex) = elements.next() else {
                return Err(no_vertex_element(file, &header));
            };
            body.read_vertices(vertex, &targets, has_normals, remaining)
        }
    }
}

fn io_error(file: &str) -> impl FnOnce(io::Error) -> ReadError + '_ {
    move |error| ReadError::Io {
        file: file.to_owned(),
        error,
    }
}

fn no_vertex_element(file: &str, header: &Header) -> ReadError {
    ReadError::Header {
        file: file.to_owned(),
        line: header.lines,
        message: "no \"vertex\" element".to_owned(),
    }
}

fn parse_header(reader: &mut impl BufRead, file: &str) -> Result<Header, ReadError> {
    let error = |line: usize, message: String| ReadError::Header {
        file: file.to_owned(),
        line,
        message,
    };
    let mut buf = Vec::with_capacity(128);
    let mut line = 0;
    let mut bytes = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    // Names of the current element's properties, for the duplicate check.
    let mut property_names: HashSet<String> = HashSet::new();
    loop {
        buf.clear();
        let read = (&mut *reader)
            .take(MAX_HEADER_LINE)
            .read_until(b'\n', &mut buf)
            .map_err(io_error(file))?;
        if read == 0 {
            return Err(if line == 0 {
                error(1, "empty file; expected \"ply\"".to_owned())
            } else {
                error(line + 1, "missing end_header".to_owned())
            });
        }
        line += 1;
        bytes += read as u64;
        let text = strip_line_ending(&buf);
        if line == 1 {
            // Trailing blanks after the magic are harmless, so they are tolerated.
            if text.trim_ascii_end() == b"ply" {
                continue;
            }
            let found = String::from_utf8_lossy(text);
            return Err(error(
                1,
                format!("bad magic: expected \"ply\", found {}", quoted(&found)),
            ));
        }
        if buf.last() != Some(&b'\n') && read as u64 == MAX_HEADER_LINE {
            return Err(error(
                line,
                format!("line longer than {MAX_HEADER_LINE} bytes; missing end_header?"),
            ));
        }
        // Comments are free text, possibly in some legacy encoding: skip them before the
        // text check.
        let first_word = text
            .split(u8::is_ascii_whitespace)
            .find(|word| !word.is_empty());
        if matches!(first_word, Some(b"comment" | b"obj_info")) {
            continue;
        }
        let text = std::str::from_utf8(text)
            .map_err(|_| error(line, "not ASCII text; missing end_header?".to_owned()))?;
        let mut tokens = text.split_ascii_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        let rest: Vec<&str> = tokens.collect();
        match keyword {
            "format" => {
                if encoding.is_some() {
                    return Err(error(line, "second format line".to_owned()));
                }
                let [name, _version] = rest.as_slice() else {
                    return Err(error(
                        line,
                        "expected \"format <ascii|binary_little_endian|binary_big_endian> 1.0\""
                            .to_owned(),
                    ));
                };
                encoding = Some(match *name {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::LittleEndian,
                    "binary_big_endian" => Encoding::BigEndian,
                    other => {
                        return Err(error(line, format!("unknown format {}", quoted(other))));
                    }
                });
            }
            "element" => {
                let [name, count] = rest.as_slice() else {
                    return Err(error(
                        line,
                        "expected \"element <name> <count>\"".to_owned(),
                    ));
                };
                let count = count
                    .parse::<u64>()
                    .map_err(|_| error(line, format!("invalid element count {}", quoted(count))))?;
                if *name == "vertex" && elements.iter().any(|e| e.name == "vertex") {
                    return Err(error(line, "second \"vertex\" element".to_owned()));
                }
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    properties: Vec::new(),
                    line,
                });
                property_names.clear();
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(error(line, "property before any element".to_owned()));
                };
                let scalar = |name: &str| {
                    ScalarType::from_name(name).ok_or_else(|| {
                        error(line, format!("unknown property type {}", quoted(name)))
                    })
                };
                let (kind, name) = match rest.as_slice() {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if !count.is_integer() {
                            return Err(error(
                                line,
                                format!("list length type {} is not an integer", count.name()),
                            ));
                        }
                        let item = scalar(item)?;
                        (PropertyKind::List { count, item }, name)
                    }
                    [ty, name] => (PropertyKind::Scalar(scalar(ty)?), name),
                    _ => {
                        return Err(error(
                            line,
                            "expected \"property <type> <name>\" or \
                             \"property list <length type> <item type> <name>\""
                                .to_owned(),
                        ));
                    }
                };
                // A set, not a scan of the earlier properties: a header of 10⁵ properties must
                // not take quadratic time.
                if !property_names.insert((*name).to_owned()) {
                    return Err(error(
                        line,
                        format!(
                            "duplicate property {} in element {}",
                            quoted(name),
                            element.name
                        ),
                    ));
                }
                element.properties.push(Property {
                    name: (*name).to_owned(),
                    kind,
                    line,
                });
            }
            "end_header" => {
                let Some(encoding) = encoding else {
                    return Err(error(line, "no format line before end_header".to_owned()));
                };
                return Ok(Header {
                    encoding,
                    elements,
                    lines: line,
                    bytes,
                });
            }
            other => {
                return Err(error(line, format!("unknown keyword {}", quoted(other))));
            }
        }
    }
}

/// Finds the vertex element and maps each of its properties to a slot of [`SLOT_NAMES`] (or
/// `None` to skip it).
fn vertex_layout(header: &Header, file: &str) -> Result<(usize, Vec<Option<usize>>), ReadError> {
    let Some((index, vertex)) = header
        .elements
        .iter()
        .enumerate()
        .find(|(_, e)| e.name == "vertex")
    else {
        return Err(no_vertex_element(file, header));
    };
    let mut targets = Vec::with_capacity(vertex.properties.len());
    let mut present = [false; 6];
    for property in &vertex.properties {
        let slot = SLOT_NAMES.iter().position(|&n| n == property.name);
        if let (Some(slot), PropertyKind::List { .. }) = (slot, property.kind) {
            return Err(ReadError::Header {
                file: file.to_owned(),
                line: property.line,
                message: format!(
                    "vertex property {} is a list; coordinates and normals must be scalars",
                    SLOT_NAMES.get(slot).unwrap_or(&"?")
                ),
            });
        }
        if let Some(flag) = slot.and_then(|s| present.get_mut(s)) {
            *flag = true;
        }
        targets.push(slot);
    }
    let [x, y, z, nx, ny, nz] = present;
    for (found, field) in [(x, "x"), (y, "y"), (z, "z")] {
        if !found {
            return Err(ReadError::MissingField {
                file: file.to_owned(),
                line: vertex.line,
                field,
            });
        }
    }
    check_normals(file, vertex.line, [nx, ny, nz])?;
    Ok((index, targets))
}

/// Accepts all three normal components or none; otherwise names the missing ones.
pub(crate) fn check_normals(file: &str, line: usize, present: [bool; 3]) -> Result<(), ReadError> {
    let count = present.iter().filter(|&&p| p).count();
    if count == 0 || count == 3 {
        return Ok(());
    }
    let missing: Vec<&str> = present
        .iter()
        .zip(["nx", "ny", "nz"])
        .filter(|&(&p, _)| !p)
        .map(|(_, name)| name)
        .collect();
    let missing = match missing.as_slice() {
        [one] => format!("{one} is"),
        [a, b] => format!("{a} and {b} are"),
        _ => "some are".to_owned(),
    };
    Err(ReadError::PartialNormals {
        file: file.to_owned(),
        line,
        missing,
    })
}

/// How many points to reserve room for: never more than the remaining bytes could hold (when
/// the size is known) nor [`crate::MAX_PREALLOCATED`], so a header claiming 10^12 vertices
/// costs nothing before the body runs out.
fn capacity(count: u64, min_record_bytes: u64, remaining: Option<u64>) -> usize {
    let by_size = remaining.map_or(u64::MAX, |r| r / min_record_bytes.max(1));
    let capped = count.min(by_size).min(crate::MAX_PREALLOCATED);
    usize::try_from(capped).unwrap_or(0)
}

fn skip_ascii_element<R: BufRead>(
    lines: &mut Lines<R>,
    file: &str,
    element: &Element,
) -> Result<(), ReadError> {
    // One instance per line, so skipping needs no parsing.
    for index in 0..element.count {
        if lines.next_line(file)?.is_none() {
            return Err(ascii_eof(lines, file, element, index));
        }
    }
    Ok(())
}

fn ascii_eof<R: BufRead>(lines: &Lines<R>, file: &str, element: &Element, index: u64) -> ReadError {
    ReadError::Ascii {
        file: file.to_owned(),
        line: lines.line() + 1,
        field: format!("{} {index}", element.name),
        message: format!(
            "unexpected end of file; the header declares {} {} elements",
            element.count, element.name
        ),
    }
}

fn read_ascii_vertices<R: BufRead>(
    lines: &mut Lines<R>,
    file: &str,
    vertex: &Element,
    targets: &[Option<usize>],
    has_normals: bool,
    remaining: Option<u64>,
) -> Result<PointCloud, ReadError> {
    // An ASCII vertex takes at least two bytes per property (a digit and a separator).
    let min_record = 2 * vertex.properties.len() as u64;
    let mut cloud = CloudBuilder::new(has_normals, capacity(vertex.count, min_record, remaining));
    for index in 0..vertex.count {
        let Some((line, text)) = lines.next_line(file)? else {
            return Err(ascii_eof(lines, file, vertex, index));
        };
        let error = |property: &Property, message: String| ReadError::Ascii {
            file: file.to_owned(),
            line,
            field: format!("vertex {index} property {}", property.name),
            message,
        };
        let mut tokens = text.split_ascii_whitespace();
        let mut values = [0.0; 6];
        for (property, target) in vertex.properties.iter().zip(targets) {
            let Some(token) = tokens.next() else {
                return Err(error(property, "missing value (row too short)".to_owned()));
            };
            match property.kind {
                PropertyKind::Scalar(_) => {
                    if let Some(value) = target.and_then(|slot| values.get_mut(slot)) {
                        *value = parse_finite(token).map_err(|m| error(property, m))?;
                    }
                }
                PropertyKind::List { .. } => {
                    let length = token.parse::<u64>().map_err(|_| {
                        error(property, format!("invalid list length {}", quoted(token)))
                    })?;
                    for item in 0..length {
                        if tokens.next().is_none() {
                            return Err(error(
                                property,
                                format!("list of {length} values ends after {item}"),
                            ));
                        }
                    }
                }
            }
        }
        if let Some(extra) = tokens.next() {
            return Err(ReadError::Ascii {
                file: file.to_owned(),
                line,
                field: format!("vertex {index}"),
                message: format!(
                    "unexpected extra value {}; the header declares {} properties",
                    quoted(extra),
                    vertex.properties.len()
                ),
            });
        }
        cloud.push(values);
    }
    Ok(cloud.finish())
}

/// Reads `buf.len()` bytes unless the input ends first; returns how many were read, so a
/// truncation can be pinned to the property it cuts.
fn read_full(reader: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut filled = 0;
    while let Some(rest) = buf.get_mut(filled..) {
        if rest.is_empty() {
            break;
        }
        match reader.read(rest) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(err) if err.kind() == io::ErrorKind::Interrupted => {}
            Err(err) => return Err(err),
        }
    }
    Ok(filled)
}

/// The binary body, with the byte offset of the next unread byte for error messages.
struct BinaryBody<'a, R> {
    reader: R,
    file: &'a str,
    offset: u64,
    encoding: Encoding,
}

impl<R: BufRead> BinaryBody<'_, R> {
    fn truncated(&self, offset: u64, field: String) -> ReadError {
        ReadError::Truncated {
            file: self.file.to_owned(),
            offset,
            field,
        }
    }

    /// Skips `n` bytes; returns how many there were.
    fn skip(&mut self, n: u64) -> Result<u64, ReadError> {
        let skipped = io::copy(&mut (&mut self.reader).take(n), &mut io::sink())
            .map_err(io_error(self.file))?;
        Ok(skipped)
    }

    /// Skips `n` bytes that make up one value, or reports the value as truncated.
    fn skip_value(&mut self, n: u64, field: impl FnOnce() -> String) -> Result<(), ReadError> {
        if self.skip(n)? < n {
            return Err(self.truncated(self.offset, field()));
        }
        self.offset = self.offset.saturating_add(n);
        Ok(())
    }

    /// Reads one scalar, or reports it as truncated.
    fn read_scalar(
        &mut self,
        ty: ScalarType,
        field: impl FnOnce() -> String,
    ) -> Result<f64, ReadError> {
        let mut buf = [0; 8];
        let bytes = buf.get_mut(..ty.size() as usize).unwrap_or_default();
        let read = read_full(&mut self.reader, bytes).map_err(io_error(self.file))?;
        match ty.decode(bytes, self.encoding) {
            Some(value) if read == bytes.len() => {
                self.offset = self.offset.saturating_add(ty.size());
                Ok(value)
            }
            _ => Err(self.truncated(self.offset, field())),
        }
    }

    /// Reads a list length, which must not be negative.
    fn read_list_length(
        &mut self,
        element: &Element,
        index: u64,
        property: &Property,
        ty: ScalarType,
    ) -> Result<u64, ReadError> {
        let field = || {
            describe(
                element,
                index,
                property,
                &format!("list length, {}", ty.name()),
            )
        };
        let start = self.offset;
        let length = self.read_scalar(ty, field)?;
        if length < 0.0 {
            return Err(ReadError::Binary {
                file: self.file.to_owned(),
                offset: start,
                field: field(),
                message: format!("negative list length {length}"),
            });
        }
        // Integer types of at most 32 bits convert to f64 and back exactly.
        Ok(length as u64)
    }

    /// Skips one list property: its length, then its items.
    fn skip_list(
        &mut self,
        element: &Element,
        index: u64,
        property: &Property,
        count: ScalarType,
        item: ScalarType,
    ) -> Result<(), ReadError> {
        let length = self.read_list_length(element, index, property, count)?;
        self.skip_value(length.saturating_mul(item.size()), || {
            describe(
                element,
                index,
                property,
                &format!("list of {length} {}", item.name()),
            )
        })
    }

    fn skip_element(&mut self, element: &Element) -> Result<(), ReadError> {
        let Some(size) = element.fixed_size() else {
            for index in 0..element.count {
                for property in &element.properties {
                    match property.kind {
                        PropertyKind::Scalar(ty) => self.skip_value(ty.size(), || {
                            describe(element, index, property, ty.name())
                        })?,
                        PropertyKind::List { count, item } => {
                            self.skip_list(element, index, property, count, item)?;
                        }
                    }
                }
            }
            return Ok(());
        };
        // Fixed-size records are skipped in one go; a huge count simply runs out of input.
        let total = element.count.saturating_mul(size);
        let skipped = self.skip(total)?;
        if skipped < total {
            return Err(self.truncated_record(element, 0, size, skipped));
        }
        self.offset = self.offset.saturating_add(total);
        Ok(())
    }

    /// Names the value cut off after `available` bytes of a run of fixed-size records that
    /// starts at the current offset with record number `first`.
    fn truncated_record(
        &self,
        element: &Element,
        first: u64,
        size: u64,
        available: u64,
    ) -> ReadError {
        let whole = available / size.max(1);
        let within = available % size.max(1);
        let index = first.saturating_add(whole);
        let (field, start) = match element.property_at(within) {
            Some((property, start)) => {
                let ty = match property.kind {
                    PropertyKind::Scalar(ty) => ty.name(),
                    PropertyKind::List { .. } => "list",
                };
                (describe(element, index, property, ty), start)
            }
            None => (format!("{} {index}", element.name), 0),
        };
        let offset = self
            .offset
            .saturating_add(whole.saturating_mul(size))
            .saturating_add(start);
        self.truncated(offset, field)
    }

    fn read_vertices(
        &mut self,
        vertex: &Element,
        targets: &[Option<usize>],
        has_normals: bool,
        remaining: Option<u64>,
    ) -> Result<PointCloud, ReadError> {
        let min_record = vertex
            .properties
            .iter()
            .map(|p| match p.kind {
                PropertyKind::Scalar(ty) => ty.size(),
                PropertyKind::List { count, .. } => count.size(),
            })
            .sum();
        let mut cloud =
            CloudBuilder::new(has_normals, capacity(vertex.count, min_record, remaining));
        match vertex.fixed_size() {
            Some(size) => self.read_fixed_vertices(vertex, size, targets, &mut cloud)?,
            None => self.read_variable_vertices(vertex, targets, &mut cloud)?,
        }
        Ok(cloud.finish())
    }

    fn non_finite(&self, offset: u64, field: String, value: f64) -> ReadError {
        ReadError::Binary {
            file: self.file.to_owned(),
            offset,
            field,
            message: format!("non-finite value {value}"),
        }
    }

    /// The fast path: every vertex is a record of `size` bytes, read whole and decoded at
    /// offsets planned once.
    fn read_fixed_vertices(
        &mut self,
        vertex: &Element,
        size: u64,
        targets: &[Option<usize>],
        cloud: &mut CloudBuilder,
    ) -> Result<(), ReadError> {
        // (offset in record, type, slot, property) for each property that is kept.
        let mut plan = Vec::with_capacity(6);
        let mut at = 0;
        for (property, target) in vertex.properties.iter().zip(targets) {
            if let PropertyKind::Scalar(ty) = property.kind {
                if let Some(slot) = *target {
                    plan.push((at, ty, slot, property));
                }
                at += ty.size();
            }
        }
        let mut record = vec![0; usize::try_from(size).unwrap_or(0)];
        for index in 0..vertex.count {
            let read = read_full(&mut self.reader, &mut record).map_err(io_error(self.file))?;
            if read < record.len() {
                return Err(self.truncated_record(vertex, index, size, read as u64));
            }
            let mut values = [0.0; 6];
            for &(at, ty, slot, property) in &plan {
                let bytes = usize::try_from(at)
                    .ok()
                    .and_then(|at| record.get(at..))
                    .unwrap_or_default();
                let field = || describe(vertex, index, property, ty.name());
                let offset = self.offset.saturating_add(at);
                let Some(value) = ty.decode(bytes, self.encoding) else {
                    return Err(self.truncated(offset, field()));
                };
                if !value.is_finite() {
                    return Err(self.non_finite(offset, field(), value));
                }
                if let Some(dst) = values.get_mut(slot) {
                    *dst = value;
                }
            }
            cloud.push(values);
            self.offset = self.offset.saturating_add(size);
        }
        Ok(())
    }

    /// The general path for vertices with list properties: one property at a time.
    fn read_variable_vertices(
        &mut self,
        vertex: &Element,
        targets: &[Option<usize>],
        cloud: &mut CloudBuilder,
    ) -> Result<(), ReadError> {
        for index in 0..vertex.count {
            let mut values = [0.0; 6];
            for (property, target) in vertex.properties.iter().zip(targets) {
                match property.kind {
                    PropertyKind::Scalar(ty) => {
                        let field = || describe(vertex, index, property, ty.name());
                        let offset = self.offset;
                        let value = self.read_scalar(ty, field)?;
                        if let Some(dst) = target.and_then(|slot| values.get_mut(slot)) {
                            if !value.is_finite() {
                                return Err(self.non_finite(offset, field(), value));
                            }
                            *dst = value;
                        }
                    }
                    PropertyKind::List { count, item } => {
                        self.skip_list(vertex, index, property, count, item)?;
                    }
                }
            }
            cloud.push(values);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_every_type_in_both_byte_orders() {
        let cases: [(ScalarType, &[u8], f64); 8] = [
            (ScalarType::I8, &[0xFF], -1.0),
            (ScalarType::U8, &[0xFF], 255.0),
            (ScalarType::I16, &[0xFE, 0xFF], -257.0),
            (ScalarType::U16, &[0x01, 0x02], 258.0),
            (ScalarType::I32, &[0xFF, 0xFF, 0xFF, 0xFE], -2.0),
            (ScalarType::U32, &[0, 0, 1, 0], 256.0),
            (ScalarType::F32, &1.5f32.to_be_bytes(), 1.5),
            (ScalarType::F64, &(-0.25f64).to_be_bytes(), -0.25),
        ];
        for (ty, be, expected) in cases {
            assert_eq!(ty.decode(be, Encoding::BigEndian), Some(expected), "{ty:?}");
            let le: Vec<u8> = be.iter().rev().copied().collect();
            assert_eq!(
                ty.decode(&le, Encoding::LittleEndian),
                Some(expected),
                "{ty:?}"
            );
            assert_eq!(ty.size() as usize, be.len());
            assert_eq!(ScalarType::from_name(ty.name()), Some(ty));
        }
        assert_eq!(
            ScalarType::F64.decode(&[0; 7], Encoding::LittleEndian),
            None
        );
    }

    #[test]
    fn capacity_is_bounded() {
        assert_eq!(capacity(10, 24, None), 10);
        assert_eq!(capacity(u64::MAX, 24, None), 1 << 20);
        assert_eq!(capacity(1_000_000_000_000, 24, Some(240)), 10);
        assert_eq!(capacity(5, 0, Some(0)), 0);
    }

    #[test]
    fn property_at_finds_the_cut() {
        let element = Element {
            name: "vertex".to_owned(),
            count: 1,
            line: 3,
            properties: ["x", "y"]
                .iter()
                .map(|n| Property {
                    name: (*n).to_owned(),
                    kind: PropertyKind::Scalar(ScalarType::F32),
                    line: 4,
                })
                .collect(),
        };
        assert_eq!(element.fixed_size(), Some(8));
        assert_eq!(
            element.property_at(5).map(|(p, s)| (p.name.as_str(), s)),
            Some(("y", 4))
        );
        assert!(element.property_at(8).is_none());
    }
}
