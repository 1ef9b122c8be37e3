//! The PLY header: element layouts, property types and their decoding.

use std::collections::HashSet;
use std::io::{self, BufRead, Read};

use crate::attributes::AttributeType;
use crate::error::{ReadError, quoted};
use crate::lines::strip_line_ending;

/// Longest header line accepted. It bounds what a binary file without line breaks, passed off
/// as PLY, makes the reader buffer before it gives up.
const MAX_HEADER_LINE: u64 = 64 * 1024;

/// How the body is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

/// A PLY scalar type, under either its classic or its sized name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ScalarType {
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
    pub(super) fn from_name(name: &str) -> Option<Self> {
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
    pub(super) const fn size(self) -> u64 {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    /// The sized name, used in error messages whatever name the header used.
    pub(super) const fn name(self) -> &'static str {
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

    /// The attribute type holding its values exactly.
    pub(super) const fn attribute_type(self) -> AttributeType {
        match self {
            Self::I8 => AttributeType::I8,
            Self::U8 => AttributeType::U8,
            Self::I16 => AttributeType::I16,
            Self::U16 => AttributeType::U16,
            Self::I32 => AttributeType::I32,
            Self::U32 => AttributeType::U32,
            Self::F32 => AttributeType::F32,
            Self::F64 => AttributeType::F64,
        }
    }

    /// Whether an ASCII body's value `v` is one of this type's values: within the range of
    /// float32 for `float`, a whole number within range for the integers. A `float` written
    /// with more digits than float32 keeps them (sloppy writers are common and the digits are
    /// the writer's intent); a value the type cannot hold at all is a broken file.
    pub(super) fn holds(self, v: f64) -> bool {
        let whole_within = |lo: f64, hi: f64| v.fract() == 0.0 && (lo..=hi).contains(&v);
        match self {
            Self::I8 => whole_within(i8::MIN.into(), i8::MAX.into()),
            Self::U8 => whole_within(0.0, u8::MAX.into()),
            Self::I16 => whole_within(i16::MIN.into(), i16::MAX.into()),
            Self::U16 => whole_within(0.0, u16::MAX.into()),
            Self::I32 => whole_within(i32::MIN.into(), i32::MAX.into()),
            Self::U32 => whole_within(0.0, u32::MAX.into()),
            Self::F32 => v.abs() <= f64::from(f32::MAX),
            Self::F64 => true,
        }
    }

    pub(super) const fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    /// Decodes the value at the start of `bytes`; every type converts to `f64` exactly.
    /// `None` only if `bytes` is shorter than the type, which the callers rule out.
    pub(super) fn decode(self, bytes: &[u8], encoding: Encoding) -> Option<f64> {
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
pub(super) enum PropertyKind {
    Scalar(ScalarType),
    /// A length of type `count`, then that many values of type `item`.
    List {
        count: ScalarType,
        item: ScalarType,
    },
}

#[derive(Debug)]
pub(super) struct Property {
    pub(super) name: String,
    pub(super) kind: PropertyKind,
    /// The header line that declares it.
    pub(super) line: usize,
}

#[derive(Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) properties: Vec<Property>,
    /// The header line that declares it.
    pub(super) line: usize,
}

impl Element {
    /// The record size in a binary body, if no property is a list.
    pub(super) fn fixed_size(&self) -> Option<u64> {
        self.properties
            .iter()
            .map(|p| match p.kind {
                PropertyKind::Scalar(t) => Some(t.size()),
                PropertyKind::List { .. } => None,
            })
            .sum()
    }

    /// In a fixed-size record, the property holding byte `at` and the offset where it starts.
    pub(super) fn property_at(&self, at: u64) -> Option<(&Property, u64)> {
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
pub(super) fn describe(element: &Element, index: u64, property: &Property, what: &str) -> String {
    format!(
        "{} {index} property {} ({what})",
        element.name, property.name
    )
}

#[derive(Debug)]
pub(super) struct Header {
    pub(super) encoding: Encoding,
    pub(super) elements: Vec<Element>,
    /// Number of lines, so the ASCII body can go on counting.
    pub(super) lines: usize,
    /// Length in bytes, where the binary body starts.
    pub(super) bytes: u64,
}

pub(super) fn io_error(file: &str) -> impl FnOnce(io::Error) -> ReadError + '_ {
    move |error| ReadError::Io {
        file: file.to_owned(),
        error,
    }
}

pub(super) fn no_vertex_element(file: &str, header: &Header) -> ReadError {
    ReadError::Header {
        file: file.to_owned(),
        line: header.lines,
        message: "no \"vertex\" element".to_owned(),
    }
}

pub(super) fn parse_header(reader: &mut impl BufRead, file: &str) -> Result<Header, ReadError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    pub(super) fn decodes_every_type_in_both_byte_orders() {
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
    pub(super) fn property_at_finds_the_cut() {
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
