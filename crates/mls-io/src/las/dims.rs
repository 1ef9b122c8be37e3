//! The standard fields of the LAS point formats 0–10, decoded from and encoded into raw point
//! records, so that every dimension of an input goes back bit for bit.
//!
//! Names follow laspy (`intensity`, `return_number`, `classification`, `gps_time`, `red` …);
//! flags are one `uint8` attribute each (0 or 1). The scan angle keeps its stored form:
//! `scan_angle_rank` (`int8`, degrees) in formats 0–5, `scan_angle` (`int16`, units of
//! 0.006°) in formats 6–10. Waveform packets (formats 4, 5, 9, 10) are not carried: they
//! point into waveform data that the output does not hold.

use crate::attributes::{AttributeType, Scalar};

/// A standard field of a point record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Field {
    pub(crate) name: &'static str,
    pub(crate) ty: AttributeType,
    /// Byte offset in the record.
    pub(crate) at: usize,
    /// For a bit field: the shift and the mask (after the shift) within the byte at `at`.
    pub(crate) bits: Option<(u8, u8)>,
}

const fn field(name: &'static str, ty: AttributeType, at: usize) -> Field {
    Field {
        name,
        ty,
        at,
        bits: None,
    }
}

const fn bits(name: &'static str, at: usize, shift: u8, mask: u8) -> Field {
    Field {
        name,
        ty: AttributeType::U8,
        at,
        bits: Some((shift, mask)),
    }
}

/// The fields of point format `format` after x, y, z, in record order. Empty for a format
/// above 10.
pub(crate) fn fields(format: u8) -> Vec<Field> {
    use AttributeType::{F64, I8, I16, U8, U16};
    let rgb = |at: usize| {
        [
            field("red", U16, at),
            field("green", U16, at + 2),
            field("blue", U16, at + 4),
        ]
    };
    let mut f = Vec::with_capacity(20);
    match format {
        0..=5 => {
            f.extend([
                field("intensity", U16, 12),
                bits("return_number", 14, 0, 0b111),
                bits("number_of_returns", 14, 3, 0b111),
                bits("scan_direction_flag", 14, 6, 1),
                bits("edge_of_flight_line", 14, 7, 1),
                bits("classification", 15, 0, 0b1_1111),
                bits("synthetic", 15, 5, 1),
                bits("key_point", 15, 6, 1),
                bits("withheld", 15, 7, 1),
                field("scan_angle_rank", I8, 16),
                field("user_data", U8, 17),
                field("point_source_id", U16, 18),
            ]);
            if matches!(format, 1 | 3 | 4 | 5) {
                f.push(field("gps_time", F64, 20));
            }
            match format {
                2 => f.extend(rgb(20)),
                3 | 5 => f.extend(rgb(28)),
                _ => {}
            }
        }
        6..=10 => {
            f.extend([
                field("intensity", U16, 12),
                bits("return_number", 14, 0, 0b1111),
                bits("number_of_returns", 14, 4, 0b1111),
                bits("synthetic", 15, 0, 1),
                bits("key_point", 15, 1, 1),
                bits("withheld", 15, 2, 1),
                bits("overlap", 15, 3, 1),
                bits("scanner_channel", 15, 4, 0b11),
                bits("scan_direction_flag", 15, 6, 1),
                bits("edge_of_flight_line", 15, 7, 1),
                field("classification", U8, 16),
                field("user_data", U8, 17),
                field("scan_angle", I16, 18),
                field("point_source_id", U16, 20),
                field("gps_time", F64, 22),
            ]);
            if matches!(format, 7 | 8 | 10) {
                f.extend(rgb(30));
            }
            if matches!(format, 8 | 10) {
                f.push(field("nir", U16, 36));
            }
        }
        _ => {}
    }
    f
}

/// The format written for an input in `format`: the same, without waveform packets.
pub(crate) const fn without_waveform(format: u8) -> u8 {
    match format {
        4 => 1,
        5 => 3,
        9 => 6,
        10 => 8,
        other => other,
    }
}

/// Reads field `f` from a record (`None` if the record is too short, which the reader rules
/// out).
pub(crate) fn decode(record: &[u8], f: &Field) -> Option<Scalar> {
    let bytes = record.get(f.at..f.at + f.ty.size())?;
    if let Some((shift, mask)) = f.bits {
        return Some(Scalar::U8((bytes.first()? >> shift) & mask));
    }
    Some(match f.ty {
        AttributeType::U8 => Scalar::U8(*bytes.first()?),
        AttributeType::I8 => Scalar::I8(i8::from_le_bytes(bytes.try_into().ok()?)),
        AttributeType::U16 => Scalar::U16(u16::from_le_bytes(bytes.try_into().ok()?)),
        AttributeType::I16 => Scalar::I16(i16::from_le_bytes(bytes.try_into().ok()?)),
        AttributeType::F64 => Scalar::F64(f64::from_le_bytes(bytes.try_into().ok()?)),
        // No standard field has another type.
        _ => return None,
    })
}

/// Writes `value` into field `f` of a zeroed record; bits beyond a bit field's width are
/// dropped (values read from the same format always fit).
pub(crate) fn encode(record: &mut [u8], f: &Field, value: Scalar) {
    if let Some((shift, mask)) = f.bits {
        if let (Some(byte), Scalar::U8(v)) = (record.get_mut(f.at), value) {
            *byte |= (v & mask) << shift;
        }
        return;
    }
    let (bytes, len) = value.le_bytes();
    if let Some(dst) = record.get_mut(f.at..f.at + len) {
        dst.copy_from_slice(&bytes[..len]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fields end where the `las` crate says the record ends (before any waveform
    /// packet), and never overlap.
    #[test]
    fn layouts_match_the_las_crate() {
        for format in 0..=10u8 {
            let len = usize::from(las::point::Format::new(format).unwrap().len());
            let waveform = if matches!(format, 4 | 5 | 9 | 10) {
                29
            } else {
                0
            };
            let fields = fields(format);
            let end = fields.iter().map(|f| f.at + f.ty.size()).max().unwrap();
            assert_eq!(end, len - waveform, "format {format}");
            let mut bits_used = vec![0u8; len];
            for f in &fields {
                let mask = f.bits.map_or(0xFF, |(s, m)| m << s);
                for used in &mut bits_used[f.at..f.at + f.ty.size()] {
                    assert_eq!(*used & mask, 0, "format {format} {}", f.name);
                    *used |= mask;
                }
            }
        }
    }

    #[test]
    fn fields_round_trip() {
        let fields = fields(7);
        let mut record = vec![0u8; 36];
        let values: Vec<Scalar> = fields
            .iter()
            .enumerate()
            .map(|(i, f)| match (f.bits, f.ty) {
                (Some((_, mask)), _) => Scalar::U8(i as u8 & mask),
                (None, AttributeType::U16) => Scalar::U16(1000 + i as u16),
                (None, AttributeType::I16) => Scalar::I16(-7),
                (None, AttributeType::F64) => Scalar::F64(123.456),
                _ => Scalar::U8(200),
            })
            .collect();
        for (f, v) in fields.iter().zip(&values) {
            encode(&mut record, f, *v);
        }
        for (f, v) in fields.iter().zip(&values) {
            assert_eq!(decode(&record, f), Some(*v), "{}", f.name);
        }
    }
}
