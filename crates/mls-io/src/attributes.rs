//! Per-point attributes carried from input to output: colour, intensity, classification and
//! anything else a file holds beside the coordinates and normals, each in the type the file
//! stores it in.
//!
//! Here the types and names ([`AttributeType`], [`Attribute`], the renaming of clashes);
//! `attributes/data.rs` holds the columns of values ([`AttributeData`]), `attributes/scalar.rs`
//! one value and its byte encodings, `attributes/text_column.rs` a text column whose type is
//! found from its values.

mod data;
mod scalar;
mod text_column;

use std::collections::HashSet;

pub use data::AttributeData;
pub(crate) use scalar::{Le, Scalar, scatter_le};
pub(crate) use text_column::{TextColumn, TextColumnType};

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
}
