//! Encoding a table's rows: binary PLY, and text for ASCII PLY, CSV and XYZ.

use std::fmt::Write as _;
use std::io::Write;
use std::slice;

use super::{Axis, Column, PlyFormat, io_error};
use crate::attributes::{AttributeData, Scalar};
use crate::error::WriteError;

/// Walks one column row by row, so rows can be written without indexing.
#[derive(Debug)]
pub(crate) enum Cursor<'a> {
    F64(slice::Iter<'a, f64>),
    I32(slice::Iter<'a, i32>),
    Component(slice::Iter<'a, [f64; 3]>, Axis),
    Attribute(&'a AttributeData, usize),
}

impl Iterator for Cursor<'_> {
    type Item = Scalar;

    fn next(&mut self) -> Option<Scalar> {
        match self {
            Self::F64(iter) => iter.next().map(|&v| Scalar::F64(v)),
            Self::I32(iter) => iter.next().map(|&v| Scalar::I32(v)),
            Self::Component(iter, axis) => iter.next().map(|v| Scalar::F64(axis.of(v))),
            Self::Attribute(data, next) => {
                let value = data.get(*next)?;
                *next += 1;
                Some(value)
            }
        }
    }
}

pub(super) fn write_ply_rows(
    out: &mut impl Write,
    file: &str,
    columns: &[Column<'_>],
    rows: usize,
    format: PlyFormat,
) -> Result<(), WriteError> {
    write_ply_header(out, file, columns, rows as u64, format)?;
    write_ply_body(out, file, columns, rows, format)
}

/// The PLY header of a table of `rows` rows.
pub(super) fn write_ply_header(
    out: &mut impl Write,
    file: &str,
    columns: &[Column<'_>],
    rows: u64,
    format: PlyFormat,
) -> Result<(), WriteError> {
    let mut header = String::from("ply\n");
    header.push_str(match format {
        PlyFormat::BinaryLittleEndian => "format binary_little_endian 1.0\n",
        PlyFormat::Ascii => "format ascii 1.0\n",
    });
    header.push_str("comment written by mls-io\n");
    // Writing to a String cannot fail.
    let _ = writeln!(header, "element vertex {rows}");
    for column in columns {
        let _ = writeln!(
            header,
            "property {} {}",
            column.data.ply_type(),
            super::ply_property_name(column.name)
        );
    }
    header.push_str("end_header\n");
    out.write_all(header.as_bytes()).map_err(io_error(file))
}

/// The PLY rows of a table, after its header.
pub(super) fn write_ply_body(
    out: &mut impl Write,
    file: &str,
    columns: &[Column<'_>],
    rows: usize,
    format: PlyFormat,
) -> Result<(), WriteError> {
    match format {
        PlyFormat::BinaryLittleEndian => write_binary_rows(out, file, columns, rows),
        PlyFormat::Ascii => write_text_rows(out, file, columns, rows, ' ', TextHeader::None),
    }
}

fn write_binary_rows(
    out: &mut impl Write,
    file: &str,
    columns: &[Column<'_>],
    rows: usize,
) -> Result<(), WriteError> {
    let mut cursors: Vec<Cursor<'_>> = columns.iter().map(|c| c.data.cursor()).collect();
    let mut row = Vec::with_capacity(8 * columns.len());
    for _ in 0..rows {
        row.clear();
        for value in cursors.iter_mut().filter_map(Iterator::next) {
            value.push_ply(&mut row);
        }
        out.write_all(&row).map_err(io_error(file))?;
    }
    Ok(())
}

/// What comes before the rows of a text table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TextHeader {
    /// Nothing (the body of an ASCII PLY, whose header names the properties).
    None,
    /// A row of the names after `//` (CSV): CloudCompare takes the names of its scalar
    /// fields only from a first line starting with `//` (it reads any other first line as
    /// a row of values, reports it corrupted and names the fields `Scalar field #N`).
    Names,
    /// A `#` comment line of the names (XYZ), which readers of such files skip.
    Comment,
}

/// Writes the rows as text, after the names as `header` says.
pub(super) fn write_text_rows(
    out: &mut impl Write,
    file: &str,
    columns: &[Column<'_>],
    rows: usize,
    separator: char,
    header: TextHeader,
) -> Result<(), WriteError> {
    let names: Vec<&str> = columns.iter().map(|c| c.name).collect();
    let line = match header {
        TextHeader::None => None,
        TextHeader::Names => Some(format!("//{}\n", names.join(&separator.to_string()))),
        TextHeader::Comment => Some(format!("# {}\n", names.join(&separator.to_string()))),
    };
    if let Some(line) = line {
        out.write_all(line.as_bytes()).map_err(io_error(file))?;
    }
    let mut cursors: Vec<Cursor<'_>> = columns.iter().map(|c| c.data.cursor()).collect();
    let mut row = String::with_capacity(24 * columns.len());
    for _ in 0..rows {
        row.clear();
        for (index, value) in cursors.iter_mut().filter_map(Iterator::next).enumerate() {
            if index > 0 {
                row.push(separator);
            }
            // Floats as the shortest decimal that parses back to the same value, switching
            // to exponent form for very large or small magnitudes.
            value.push_text(&mut row);
        }
        row.push('\n');
        out.write_all(row.as_bytes()).map_err(io_error(file))?;
    }
    Ok(())
}
