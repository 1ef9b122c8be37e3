//! One attribute's column of values, in the type the file stores it in, and the ways a reader
//! fills it: from little-endian records, from bytes in either order, from text.

use super::AttributeType;
use super::scalar::{Scalar, extend_le, scatter_le};

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
    /// integer in range for integer types; NaN and infinities are accepted for floats, but not
    /// a finite number that float32 rounds to infinity). The error is a phrase for a message.
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
            Self::F32(v) => {
                push!(v, f32);
                if v.last().is_some_and(|x| x.is_infinite())
                    && token.parse::<f64>().is_ok_and(f64::is_finite)
                {
                    v.pop();
                    return Err(format!(
                        "{} is beyond the range of {}",
                        crate::error::quoted(token),
                        ty.name()
                    ));
                }
            }
            Self::F64(v) => push!(v, f64),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn float_equality_is_bitwise_but_for_nan() {
        let a = AttributeData::F64(vec![f64::NAN, -0.0]);
        assert_eq!(a, AttributeData::F64(vec![-f64::NAN, -0.0]));
        assert_ne!(a, AttributeData::F64(vec![f64::NAN, 0.0]));
        assert_ne!(AttributeData::F32(vec![1.0]), AttributeData::F64(vec![1.0]));
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
        // A finite value beyond float32 is refused, not stored as infinity; "inf" is kept.
        assert!(
            f.push_text("1e39")
                .unwrap_err()
                .contains("\"1e39\" is beyond the range of float32")
        );
        f.push_text("-inf").unwrap();
        assert_eq!(f.f64_at(2), Some(f64::NEG_INFINITY));
        for code in 1..=10 {
            let ty = AttributeType::from_las_code(code).unwrap();
            assert_eq!(ty.las_code(), code);
        }
        let mut text = String::new();
        Scalar::F32(0.1).push_text(&mut text);
        assert_eq!(text, "0.1");
    }
}
