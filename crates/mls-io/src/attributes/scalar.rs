//! One value of any attribute type ([`Scalar`]) and its encodings: little-endian as LAS
//! stores it, as binary PLY stores it, as text; and [`Le`], the little-endian reading and
//! writing of a whole column of LAS records at once.

use std::fmt::Write as _;

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
pub(super) fn extend_le<T: Le>(v: &mut Vec<T>, raw: &[u8], record: usize, at: usize) -> bool {
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
    /// lacks, as `double` (see [`AttributeType::ply_name`](super::AttributeType::ply_name)).
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
