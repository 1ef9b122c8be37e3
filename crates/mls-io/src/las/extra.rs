//! LAS 1.4 extra bytes: the Extra Bytes VLR's descriptors, read from an input and written
//! for an output's extra columns.

use crate::attributes::AttributeType;
use crate::write::{Column, ColumnData};

/// Extra Bytes VLR: LASF_Spec record 4, one 192-byte descriptor per attribute.
pub(crate) const USER_ID: &str = "LASF_Spec";
pub(crate) const RECORD_ID: u16 = 4;
pub(crate) const DESCRIPTOR_BYTES: usize = 192;

/// The longest name a descriptor holds.
pub(crate) const MAX_NAME_BYTES: usize = 32;

/// One 192-byte descriptor, as stored.
pub(crate) type Descriptor = [u8; DESCRIPTOR_BYTES];

/// The data types of the LAS 1.4 extra-bytes descriptor used for table columns.
const TYPE_I32: u8 = 6;
const TYPE_F64: u8 = 10;

/// One attribute of an input's extra bytes.
#[derive(Debug)]
pub(crate) struct ExtraField {
    pub(crate) name: String,
    /// The type, if a scalar of data type 1–10; `None` for what is not carried.
    pub(crate) ty: Option<AttributeType>,
    /// The data type code, for a message about what is not carried.
    pub(crate) code: u8,
    /// Offset within the extra bytes.
    pub(crate) offset: usize,
    /// Size in bytes.
    pub(crate) size: usize,
    pub(crate) descriptor: Descriptor,
}

/// The extra-bytes attributes an input's Extra Bytes VLR declares, in order, with their
/// offsets; `Err` names the descriptor that cannot be laid out (an unknown data type, whose
/// size, and so the offsets of all the later ones, is unknown).
pub(crate) fn parse(header: &las::Header) -> Result<Vec<ExtraField>, String> {
    let Some(vlr) = header
        .all_vlrs()
        .find(|v| v.user_id == USER_ID && v.record_id == RECORD_ID)
    else {
        return Ok(Vec::new());
    };
    let mut offset = 0;
    let mut fields = Vec::new();
    for (index, d) in vlr.data.chunks_exact(DESCRIPTOR_BYTES).enumerate() {
        let code = d[2];
        let name = &d[4..36];
        let name = &name[..name.iter().position(|&b| b == 0).unwrap_or(MAX_NAME_BYTES)];
        let name = String::from_utf8_lossy(name).into_owned();
        // Type 0 keeps its size in the options byte; 11–30 are the deprecated arrays of
        // two or three values of types 1–10.
        let size = match code {
            0 => usize::from(d[3]),
            1..=10 => AttributeType::from_las_code(code).map_or(0, AttributeType::size),
            11..=30 => {
                let base = (code - 1) % 10 + 1;
                let count = usize::from((code - 1) / 10 + 1);
                count * AttributeType::from_las_code(base).map_or(0, AttributeType::size)
            }
            _ => {
                return Err(format!(
                    "extra-bytes descriptor {index} ({}) has the unknown data type {code}",
                    crate::error::quoted(&name)
                ));
            }
        };
        fields.push(ExtraField {
            name,
            ty: AttributeType::from_las_code(code),
            code,
            offset,
            size,
            descriptor: d.try_into().unwrap_or([0; DESCRIPTOR_BYTES]),
        });
        offset += size;
    }
    Ok(fields)
}

/// The description written for a column `mlscurv` produces (at most 32 bytes, shown by PDAL,
/// laspy and CloudCompare beside the name); other columns get none.
pub(crate) fn description(name: &str) -> &'static str {
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

/// The type a column is written as in extra bytes.
pub(crate) fn column_type(data: &ColumnData<'_>) -> AttributeType {
    match data {
        ColumnData::I32(_) => AttributeType::I32,
        ColumnData::F64(_) | ColumnData::Component { .. } => AttributeType::F64,
        ColumnData::Attribute(data) => data.ty(),
    }
}

/// One 192-byte descriptor (LAS 1.4 R15, table 24) for a column: no options (no no-data,
/// min, max, scale or offset), the name and, for `mlscurv`'s columns, a description.
pub(crate) fn descriptor(column: &Column<'_>) -> Descriptor {
    let mut d = [0u8; DESCRIPTOR_BYTES];
    // Bytes 0–1 reserved; 2 data type; 3 options; 4–35 name; then unused, no_data, min,
    // max, scale, offset (4 + 5 × 24 bytes) and a 32-byte description.
    d[2] = match column.data {
        ColumnData::I32(_) => TYPE_I32,
        ColumnData::F64(_) | ColumnData::Component { .. } => TYPE_F64,
        ColumnData::Attribute(data) => data.ty().las_code(),
    };
    let name = column.name.as_bytes();
    let name = &name[..name.len().min(MAX_NAME_BYTES)];
    d[4..4 + name.len()].copy_from_slice(name);
    let text = description(column.name).as_bytes();
    d[DESCRIPTOR_BYTES - 32..DESCRIPTOR_BYTES - 32 + text.len()].copy_from_slice(text);
    d
}

#[cfg(test)]
mod tests {
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
