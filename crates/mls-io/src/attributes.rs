//! Per-point attributes carried from input to output: colour, intensity, classification and
//! anything else a file holds beside the coordinates and normals, each in the type the file
//! stores it in.

use std::collections::HashSet;
use std::fmt::Write as _;

/// The type of an attribute's values: the integer and float types that PLY, LAS extra bytes
/// and the LAS point formats use. Integers stay integers and floats keep their width, so an
/// attribute is written back exactly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AttributeType {
    /// Signed 8-bit integer (PLY `char`, LAS extra-bytes type 2).
    I8,
    /// Unsigned 8-bit integer (PLY `uchar`, LAS type 1).
    U8,
    /// Signed 16-bit integer (PLY `short`, LAS type 4).
    I16,
    /// Unsigned 16-bit integer (PLY `ushort`, LAS type 3).
    U16,
    /// Signed 32-bit integer (PLY `int`, LAS type 6).
    I32,
    /// Unsigned 32-bit integer (PLY `uint`, LAS type 5).
    U32,
    /// Signed 64-bit integer (LAS type 8; PLY has none: written there as `double`).
    I64,
    /// Unsigned 64-bit integer (LAS type 7; PLY has none: written there as `double`).
    U64,
    /// 32-bit float (PLY `float`, LAS type 9).
    F32,
    /// 64-bit float (PLY `double`, LAS type 10).
    F64,
}

impl AttributeType {
    /// The size of one value in bytes.
    pub const fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// The sized name, as in PLY's `uint8` … `float64`, for messages.
    pub const fn name(self) -> &'static str {
        match self {
            Self::I8 => "int8",
            Self::U8 => "uint8",
            Self::I16 => "int16",
            Self::U16 => "uint16",
            Self::I32 => "int32",
            Self::U32 => "uint32",
            Self::I64 => "int64",
            Self::U64 => "uint64",
            Self::F32 => "float32",
            Self::F64 => "float64",
        }
    }

    /// The PLY property type written for it (classic names, as the rest of the header).
    pub(crate) const fn ply_name(self) -> &'static str {
        match self {
            Self::I8 => "char",
            Self::U8 => "uchar",
            Self::I16 => "short",
            Self::U16 => "ushort",
            Self::I32 => "int",
            Self::U32 => "uint",
            Self::F32 => "float",
            Self::I64 | Self::U64 | Self::F64 => "double",
        }
    }

    /// The data type of a LAS 1.4 extra-bytes descriptor (R15, table 24).
    pub(crate) const fn las_code(self) -> u8 {
        match self {
            Self::U8 => 1,
            Self::I8 => 2,
            Self::U16 => 3,
            Self::I16 => 4,
            Self::U32 => 5,
            Self::I32 => 6,
            Self::U64 => 7,
            Self::I64 => 8,
            Self::F32 => 9,
            Self::F64 => 10,
        }
    }

    /// The type for a LAS extra-bytes data type, if it is a single scalar (1–10).
    pub(crate) const fn from_las_code(code: u8) -> Option<Self> {
        Some(match code {
            1 => Self::U8,
            2 => Self::I8,
            3 => Self::U16,
            4 => Self::I16,
            5 => Self::U32,
            6 => Self::I32,
            7 => Self::U64,
            8 => Self::I64,
            9 => Self::F32,
            10 => Self::F64,
            _ => return None,
        })
    }
}

/// One attribute's values, one per point, in file order.
///
/// Equality compares values as data: floats bit for bit (so `-0.0` differs from `0.0`), except
/// that any NaN equals any NaN (text keeps neither a NaN's sign nor its payload).
#[derive(Clone, Debug)]
#[allow(missing_docs)]
pub enum AttributeData {
    I8(Vec<i8>),
    U8(Vec<u8>),
    I16(Vec<i16>),
    U16(Vec<u16>),
    I32(Vec<i32>),
    U32(Vec<u32>),
    I64(Vec<i64>),
    U64(Vec<u64>),
    F32(Vec<f32>),
    F64(Vec<f64>),
}

/// Applies `$body` to the vector inside any variant, bound to `$v`.
macro_rules! each {
    ($data:expr, $v:ident => $body:expr) => {
        match $data {
            AttributeData::I8($v) => $body,
            AttributeData::U8($v) => $body,
            AttributeData::I16($v) => $body,
            AttributeData::U16($v) => $body,
            AttributeData::I32($v) => $body,
            AttributeData::U32($v) => $body,
            AttributeData::I64($v) => $body,
            AttributeData::U64($v) => $body,
            AttributeData::F32($v) => $body,
            AttributeData::F64($v) => $body,
        }
    };
}

/// A number stored little-endian in a fixed number of bytes (LAS records).
pub(crate) trait Le: Copy {
    const N: usize;
    /// From the first `N` bytes of `b`, which has at least `N`.
    fn read(b: &[u8]) -> Self;
    /// Into the first `N` bytes of `b`, which has at least `N`.
    fn write(self, b: &mut [u8]);
}

macro_rules! le {
    ($($t:ty),*) => {$(
        impl Le for $t {
            const N: usize = size_of::<$t>();
            fn read(b: &[u8]) -> Self {
                let mut a = [0; size_of::<$t>()];
                a.copy_from_slice(&b[..Self::N]);
                <$t>::from_le_bytes(a)
            }
            fn write(self, b: &mut [u8]) {
                b[..Self::N].copy_from_slice(&self.to_le_bytes());
            }
        }
    )*};
}
le!(i8, u8, i16, u16, i32, u32, i64, u64, f32, f64);

/// Appends the value at byte `at` of every `record`-byte record of `raw`; false (nothing
/// appended) if the value would not fit within a record.
fn extend_le<T: Le>(v: &mut Vec<T>, raw: &[u8], record: usize, at: usize) -> bool {
    if at + T::N > record {
        return false;
    }
    v.extend(raw.chunks_exact(record).map(|r| T::read(&r[at..])));
    true
}

/// Writes `values` at byte `at` of the successive `record`-byte records of `block`, as many
/// as both have; nothing if a value would not fit within a record.
pub(crate) fn scatter_le<T: Le>(values: &[T], block: &mut [u8], record: usize, at: usize) {
    if at + T::N > record {
        return;
    }
    for (r, &v) in block.chunks_exact_mut(record).zip(values) {
        v.write(&mut r[at..]);
    }
}

impl PartialEq for AttributeData {
    fn eq(&self, other: &Self) -> bool {
        fn floats<T: Copy>(a: &[T], b: &[T], same: impl Fn(T, T) -> bool) -> bool {
            a.len() == b.len() && a.iter().zip(b).all(|(&x, &y)| same(x, y))
        }
        match (self, other) {
            (Self::I8(a), Self::I8(b)) => a == b,
            (Self::U8(a), Self::U8(b)) => a == b,
            (Self::I16(a), Self::I16(b)) => a == b,
            (Self::U16(a), Self::U16(b)) => a == b,
            (Self::I32(a), Self::I32(b)) => a == b,
            (Self::U32(a), Self::U32(b)) => a == b,
            (Self::I64(a), Self::I64(b)) => a == b,
            (Self::U64(a), Self::U64(b)) => a == b,
            (Self::F32(a), Self::F32(b)) => floats(a, b, |x: f32, y: f32| {
                x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan())
            }),
            (Self::F64(a), Self::F64(b)) => floats(a, b, |x: f64, y: f64| {
                x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan())
            }),
            _ => false,
        }
    }
}

impl AttributeData {
    /// An empty column of type `ty` with room for `capacity` values.
    pub fn with_capacity(ty: AttributeType, capacity: usize) -> Self {
        match ty {
            AttributeType::I8 => Self::I8(Vec::with_capacity(capacity)),
            AttributeType::U8 => Self::U8(Vec::with_capacity(capacity)),
            AttributeType::I16 => Self::I16(Vec::with_capacity(capacity)),
            AttributeType::U16 => Self::U16(Vec::with_capacity(capacity)),
            AttributeType::I32 => Self::I32(Vec::with_capacity(capacity)),
            AttributeType::U32 => Self::U32(Vec::with_capacity(capacity)),
            AttributeType::I64 => Self::I64(Vec::with_capacity(capacity)),
            AttributeType::U64 => Self::U64(Vec::with_capacity(capacity)),
            AttributeType::F32 => Self::F32(Vec::with_capacity(capacity)),
            AttributeType::F64 => Self::F64(Vec::with_capacity(capacity)),
        }
    }

    /// The type of the values.
    pub fn ty(&self) -> AttributeType {
        match self {
            Self::I8(_) => AttributeType::I8,
            Self::U8(_) => AttributeType::U8,
            Self::I16(_) => AttributeType::I16,
            Self::U16(_) => AttributeType::U16,
            Self::I32(_) => AttributeType::I32,
            Self::U32(_) => AttributeType::U32,
            Self::I64(_) => AttributeType::I64,
            Self::U64(_) => AttributeType::U64,
            Self::F32(_) => AttributeType::F32,
            Self::F64(_) => AttributeType::F64,
        }
    }

    /// The number of values.
    pub fn len(&self) -> usize {
        each!(self, v => v.len())
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` as an `f64` (exact except for 64-bit integers beyond 2^53), for checks and
    /// summaries.
    pub fn f64_at(&self, i: usize) -> Option<f64> {
        self.get(i).map(Scalar::to_f64)
    }

    /// Value `i`.
    pub(crate) fn get(&self, i: usize) -> Option<Scalar> {
        Some(match self {
            Self::I8(v) => Scalar::I8(*v.get(i)?),
            Self::U8(v) => Scalar::U8(*v.get(i)?),
            Self::I16(v) => Scalar::I16(*v.get(i)?),
            Self::U16(v) => Scalar::U16(*v.get(i)?),
            Self::I32(v) => Scalar::I32(*v.get(i)?),
            Self::U32(v) => Scalar::U32(*v.get(i)?),
            Self::I64(v) => Scalar::I64(*v.get(i)?),
            Self::U64(v) => Scalar::U64(*v.get(i)?),
            Self::F32(v) => Scalar::F32(*v.get(i)?),
            Self::F64(v) => Scalar::F64(*v.get(i)?),
        })
    }

    /// Appends the value stored little-endian at byte `at` of every `record`-byte record of
    /// `raw`, in this column's type: a whole chunk of LAS records at once. False (nothing
    /// appended) if it would not fit within a record.
    pub(crate) fn extend_le(&mut self, raw: &[u8], record: usize, at: usize) -> bool {
        each!(self, v => extend_le(v, raw, record, at))
    }

    /// Writes values `first..` little-endian at byte `at` of the successive `record`-byte
    /// records of `block`, as many as both have.
    pub(crate) fn scatter_le(&self, first: usize, block: &mut [u8], record: usize, at: usize) {
        each!(self, v => scatter_le(v.get(first..).unwrap_or_default(), block, record, at));
    }

    /// Appends a value of the column's type; false (and nothing appended) for another type.
    pub(crate) fn push(&mut self, value: Scalar) -> bool {
        match (self, value) {
            (Self::I8(v), Scalar::I8(x)) => v.push(x),
            (Self::U8(v), Scalar::U8(x)) => v.push(x),
            (Self::I16(v), Scalar::I16(x)) => v.push(x),
            (Self::U16(v), Scalar::U16(x)) => v.push(x),
            (Self::I32(v), Scalar::I32(x)) => v.push(x),
            (Self::U32(v), Scalar::U32(x)) => v.push(x),
            (Self::I64(v), Scalar::I64(x)) => v.push(x),
            (Self::U64(v), Scalar::U64(x)) => v.push(x),
            (Self::F32(v), Scalar::F32(x)) => v.push(x),
            (Self::F64(v), Scalar::F64(x)) => v.push(x),
            _ => return false,
        }
        true
    }

    /// Appends the value stored at the start of `bytes` in the given byte order; false (and
    /// nothing appended) if `bytes` is too short.
    pub(crate) fn push_bytes(&mut self, bytes: &[u8], big_endian: bool) -> bool {
        macro_rules! push {
            ($v:ident, $t:ty) => {{
                let Some(raw) = bytes.get(..size_of::<$t>()).and_then(|b| b.try_into().ok()) else {
                    return false;
                };
                $v.push(if big_endian {
                    <$t>::from_be_bytes(raw)
                } else {
                    <$t>::from_le_bytes(raw)
                });
            }};
        }
        match self {
            Self::I8(v) => push!(v, i8),
            Self::U8(v) => push!(v, u8),
            Self::I16(v) => push!(v, i16),
            Self::U16(v) => push!(v, u16),
            Self::I32(v) => push!(v, i32),
            Self::U32(v) => push!(v, u32),
            Self::I64(v) => push!(v, i64),
            Self::U64(v) => push!(v, u64),
            Self::F32(v) => push!(v, f32),
            Self::F64(v) => push!(v, f64),
        }
        true
    }

    /// Appends a value written as text, which must be a number of the column's type (an
    /// integer in range for integer types; NaN and infinities are accepted for floats). The
    /// error is a phrase for a message.
    pub(crate) fn push_text(&mut self, token: &str) -> Result<(), String> {
        let ty = self.ty();
        macro_rules! push {
            ($v:ident, $t:ty) => {
                $v.push(token.parse::<$t>().map_err(|_| {
                    format!(
                        "{} is not a {} value",
                        crate::error::quoted(token),
                        ty.name()
                    )
                })?)
            };
        }
        match self {
            Self::I8(v) => push!(v, i8),
            Self::U8(v) => push!(v, u8),
            Self::I16(v) => push!(v, i16),
            Self::U16(v) => push!(v, u16),
            Self::I32(v) => push!(v, i32),
            Self::U32(v) => push!(v, u32),
            Self::I64(v) => push!(v, i64),
            Self::U64(v) => push!(v, u64),
            Self::F32(v) => push!(v, f32),
            Self::F64(v) => push!(v, f64),
        }
        Ok(())
    }
}

/// One value of an attribute or of a table column.
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(missing_docs)]
pub(crate) enum Scalar {
    I8(i8),
    U8(u8),
    I16(i16),
    U16(u16),
    I32(i32),
    U32(u32),
    I64(i64),
    U64(u64),
    F32(f32),
    F64(f64),
}

impl Scalar {
    /// The value as an `f64`: exact but for 64-bit integers beyond 2^53.
    pub(crate) fn to_f64(self) -> f64 {
        match self {
            Self::I8(v) => f64::from(v),
            Self::U8(v) => f64::from(v),
            Self::I16(v) => f64::from(v),
            Self::U16(v) => f64::from(v),
            Self::I32(v) => f64::from(v),
            Self::U32(v) => f64::from(v),
            Self::I64(v) => v as f64,
            Self::U64(v) => v as f64,
            Self::F32(v) => f64::from(v),
            Self::F64(v) => v,
        }
    }

    /// Appends the value little-endian in its own type (LAS extra bytes and point fields).
    pub(crate) fn push_le(self, out: &mut Vec<u8>) {
        let (bytes, len) = self.le_bytes();
        out.extend_from_slice(&bytes[..len]);
    }

    /// The value little-endian in its own type, in the first `len` of eight bytes: no
    /// allocation, for the encoding of millions of records.
    pub(crate) fn le_bytes(self) -> ([u8; 8], usize) {
        fn padded<const N: usize>(b: [u8; N]) -> ([u8; 8], usize) {
            let mut out = [0; 8];
            out[..N].copy_from_slice(&b);
            (out, N)
        }
        match self {
            Self::I8(v) => padded(v.to_le_bytes()),
            Self::U8(v) => padded(v.to_le_bytes()),
            Self::I16(v) => padded(v.to_le_bytes()),
            Self::U16(v) => padded(v.to_le_bytes()),
            Self::I32(v) => padded(v.to_le_bytes()),
            Self::U32(v) => padded(v.to_le_bytes()),
            Self::I64(v) => padded(v.to_le_bytes()),
            Self::U64(v) => padded(v.to_le_bytes()),
            Self::F32(v) => padded(v.to_le_bytes()),
            Self::F64(v) => padded(v.to_le_bytes()),
        }
    }

    /// Appends the value little-endian as binary PLY stores it: 64-bit integers, which PLY
    /// lacks, as `double` (see [`AttributeType::ply_name`]).
    pub(crate) fn push_ply(self, out: &mut Vec<u8>) {
        match self {
            Self::I64(_) | Self::U64(_) => out.extend_from_slice(&self.to_f64().to_le_bytes()),
            other => other.push_le(out),
        }
    }

    /// Appends the value as text: integers as integers, floats in the shortest form that
    /// parses back to the same value of their type.
    pub(crate) fn push_text(self, out: &mut String) {
        // Writing to a String cannot fail.
        let _ = match self {
            Self::I8(v) => write!(out, "{v}"),
            Self::U8(v) => write!(out, "{v}"),
            Self::I16(v) => write!(out, "{v}"),
            Self::U16(v) => write!(out, "{v}"),
            Self::I32(v) => write!(out, "{v}"),
            Self::U32(v) => write!(out, "{v}"),
            Self::I64(v) => write!(out, "{v}"),
            Self::U64(v) => write!(out, "{v}"),
            Self::F32(v) => write!(out, "{v:?}"),
            Self::F64(v) => write!(out, "{v:?}"),
        };
    }
}

/// A named per-point attribute.
#[derive(Clone, Debug, PartialEq)]
pub struct Attribute {
    /// The name, as in the file (a PLY property, a CSV header, a `--columns` name, a LAS
    /// dimension such as `intensity`, or an extra-bytes name); `colN` for column `N` of a
    /// text file without names.
    pub name: String,
    /// The values, one per point.
    pub data: AttributeData,
}

/// `name` as an attribute name every writer can write, unique among `taken`, which it joins:
/// each character other than an ASCII letter, digit, `_`, `-` or `.` becomes `_` (an empty
/// name becomes `fallback`), and a name already taken gets `_2`, `_3` … appended. A set, not a
/// scan: a PLY header may declare 10⁵ properties.
pub(crate) fn usable_name(name: &str, fallback: &str, taken: &mut HashSet<String>) -> String {
    let base: String = if name.is_empty() {
        fallback.to_owned()
    } else {
        name.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                    c
                } else {
                    '_'
                }
            })
            .collect()
    };
    let usable = if taken.contains(&base) {
        (2..)
            .map(|k| format!("{base}_{k}"))
            .find(|n| !taken.contains(n))
            .unwrap_or(base)
    } else {
        base
    };
    taken.insert(usable.clone());
    usable
}

/// Renames attributes whose names are `reserved` (the columns an output computes, such as
/// `k1` or `status`) or taken by an earlier attribute: `name` becomes `name_in`, or
/// `name_in2`, `name_in3` … if that is taken too. Returns the renamings, `(old, new)`, in
/// order, for a note.
pub fn rename_clashes(attributes: &mut [Attribute], reserved: &[&str]) -> Vec<(String, String)> {
    let mut taken: HashSet<String> = reserved.iter().map(|&s| s.to_owned()).collect();
    // Names kept as they are claim their place first, so a renamed attribute cannot take the
    // name of a later one.
    let mut clashes = Vec::new();
    for (i, a) in attributes.iter().enumerate() {
        if !taken.insert(a.name.clone()) {
            clashes.push(i);
        }
    }
    let mut renamed = Vec::new();
    for i in clashes {
        let Some(a) = attributes.get_mut(i) else {
            continue;
        };
        let mut new = format!("{}_in", a.name);
        let mut n = 2;
        while taken.contains(&new) {
            new = format!("{}_in{n}", a.name);
            n += 1;
        }
        taken.insert(new.clone());
        renamed.push((std::mem::replace(&mut a.name, new.clone()), new));
    }
    renamed
}

/// A text column on its way to becoming an attribute: integers while every value is one,
/// floats from the first value that is not, and dropped at the first value that is not a
/// number at all.
#[derive(Debug)]
pub(crate) enum TextColumn {
    Integers(Vec<i64>),
    Floats(Vec<f64>),
    /// Not numbers: the line and the text of the first value that is not.
    Dropped(usize, String),
}

impl TextColumn {
    pub(crate) fn new() -> Self {
        Self::Integers(Vec::new())
    }

    pub(crate) fn push(&mut self, line: usize, token: &str) {
        match self {
            Self::Integers(values) => {
                if let Ok(v) = token.parse::<i64>() {
                    values.push(v);
                } else if let Ok(v) = token.parse::<f64>() {
                    // Integers beyond 2^53 round here; a column with a fraction somewhere is
                    // a float column.
                    let mut floats: Vec<f64> = values.iter().map(|&i| i as f64).collect();
                    floats.push(v);
                    *self = Self::Floats(floats);
                } else {
                    *self = Self::Dropped(line, token.to_owned());
                }
            }
            Self::Floats(values) => match token.parse::<f64>() {
                Ok(v) => values.push(v),
                Err(_) => *self = Self::Dropped(line, token.to_owned()),
            },
            Self::Dropped(..) => {}
        }
    }

    /// The values as an attribute column: `int32` if every value is an integer in its range,
    /// `int64` if every value is an integer, else `float64`; or where the column failed.
    pub(crate) fn finish(self) -> Result<AttributeData, (usize, String)> {
        match self {
            Self::Integers(values) => {
                let narrow: Result<Vec<i32>, _> =
                    values.iter().map(|&v| i32::try_from(v)).collect();
                Ok(match narrow {
                    Ok(narrow) => AttributeData::I32(narrow),
                    Err(_) => AttributeData::I64(values),
                })
            }
            Self::Floats(values) => Ok(AttributeData::F64(values)),
            Self::Dropped(line, token) => Err((line, token)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attribute(name: &str) -> Attribute {
        Attribute {
            name: name.to_owned(),
            data: AttributeData::U8(vec![1]),
        }
    }

    #[test]
    fn clashes_are_renamed_deterministically() {
        let mut a: Vec<Attribute> = ["k1", "red", "k1_in", "status", "red"]
            .iter()
            .map(|n| attribute(n))
            .collect();
        let renamed = rename_clashes(&mut a, &["k1", "status"]);
        let names: Vec<&str> = a.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["k1_in2", "red", "k1_in", "status_in", "red_in"]);
        assert_eq!(renamed.len(), 3);
        assert_eq!(renamed[0], ("k1".to_owned(), "k1_in2".to_owned()));
    }

    #[test]
    fn names_are_made_usable_and_unique() {
        let mut taken: HashSet<String> = ["a_b", "x", "x_2"].map(String::from).into();
        assert_eq!(usable_name("a/b", "col4", &mut taken), "a_b_2");
        assert_eq!(usable_name("a/b", "col4", &mut taken), "a_b_3");
        assert_eq!(usable_name("Echo Width", "c", &mut taken), "Echo_Width");
        assert_eq!(usable_name("", "col4", &mut taken), "col4");
        assert_eq!(usable_name("x", "c", &mut taken), "x_3");
        assert_eq!(usable_name("é", "c", &mut taken), "_");
    }

    #[test]
    fn float_equality_is_bitwise_but_for_nan() {
        let a = AttributeData::F64(vec![f64::NAN, -0.0]);
        assert_eq!(a, AttributeData::F64(vec![-f64::NAN, -0.0]));
        assert_ne!(a, AttributeData::F64(vec![f64::NAN, 0.0]));
        assert_ne!(AttributeData::F32(vec![1.0]), AttributeData::F64(vec![1.0]));
    }

    #[test]
    fn text_columns_keep_integers_integer() {
        let column = |tokens: &[&str]| {
            let mut c = TextColumn::new();
            for (i, t) in tokens.iter().enumerate() {
                c.push(i + 1, t);
            }
            c.finish()
        };
        assert_eq!(
            column(&["1", "-2", "255"]),
            Ok(AttributeData::I32(vec![1, -2, 255]))
        );
        assert_eq!(
            column(&["1", "9000000000"]),
            Ok(AttributeData::I64(vec![1, 9_000_000_000]))
        );
        assert_eq!(
            column(&["1", "0.5"]),
            Ok(AttributeData::F64(vec![1.0, 0.5]))
        );
        assert_eq!(column(&["1", "red", "2"]), Err((2, "red".to_owned())));
    }

    #[test]
    fn values_parse_and_decode_by_type() {
        let mut d = AttributeData::with_capacity(AttributeType::U8, 2);
        d.push_text("255").unwrap();
        assert!(
            d.push_text("256")
                .unwrap_err()
                .contains("not a uint8 value")
        );
        assert!(d.push_bytes(&[7], false));
        assert_eq!(d, AttributeData::U8(vec![255, 7]));
        let mut f = AttributeData::with_capacity(AttributeType::F32, 1);
        assert!(f.push_bytes(&1.5f32.to_be_bytes(), true));
        assert!(!f.push_bytes(&[0, 0], true));
        f.push_text("nan").unwrap();
        assert_eq!(f.f64_at(0), Some(1.5));
        assert!(f.f64_at(1).is_some_and(f64::is_nan));
        for code in 1..=10 {
            let ty = AttributeType::from_las_code(code).unwrap();
            assert_eq!(ty.las_code(), code);
        }
        let mut text = String::new();
        Scalar::F32(0.1).push_text(&mut text);
        assert_eq!(text, "0.1");
    }
}
