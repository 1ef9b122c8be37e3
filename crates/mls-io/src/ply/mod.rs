//! A streaming PLY reader: the header is parsed into element layouts, then only the `vertex`
//! element is decoded, with a per-property plan computed once.
//!
//! The maintained PLY crates were measured and not used: `ply-rs-bw` stores each vertex as a
//! map of properties by default (1.06 s and 800 MB for a million vertices), and its typed
//! interface, though fast, reports neither byte offsets nor property names in its errors and
//! can panic on some inputs. Reading the vertex properties, each in its own type, needs little
//! code.

mod binary;
mod header;

use std::collections::HashSet;
use std::io::BufRead;

use crate::attributes::{Attribute, AttributeData, usable_name};
use crate::error::{ReadError, quoted};
use crate::lines::{Lines, parse_finite};
use crate::{CloudBuilder, PointCloud, ReadOutcome, SLOT_NAMES};
use binary::BinaryBody;
use header::{Element, Encoding, Header, Property, PropertyKind, no_vertex_element, parse_header};

/// Where a vertex property's values go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    /// A slot of [`SLOT_NAMES`].
    Slot(usize),
    /// An attribute, by index in the cloud's attributes.
    Attribute(usize),
    /// Nowhere: a list property.
    Skip,
}

/// Reads a PLY stream; `size_hint` is the total file size when known, to bound preallocation;
/// `slots` are the leading [`SLOT_NAMES`] read as geometry (the rest become attributes).
pub(crate) fn read(
    reader: impl BufRead,
    file: &str,
    size_hint: Option<u64>,
    slots: &[&str],
) -> Result<ReadOutcome, ReadError> {
    crate::one_batch(|sink| read_batches(reader, file, size_hint, slots, u64::MAX, sink))
}

/// Reads a PLY stream as [`read`] does, handing the vertices to `sink` in clouds of at most
/// `max` points, in file order (an empty one for a file without vertices); returns the notes.
pub(crate) fn read_batches<E: From<ReadError>>(
    mut reader: impl BufRead,
    file: &str,
    size_hint: Option<u64>,
    slots: &[&str],
    max: u64,
    sink: &mut dyn FnMut(PointCloud) -> Result<(), E>,
) -> Result<Vec<String>, E> {
    let header = parse_header(&mut reader, file)?;
    let (vertex_index, targets, notes) = vertex_layout(&header, file, slots)?;
    let has_normals = targets.contains(&Target::Slot(3));
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
                return Err(no_vertex_element(file, &header).into());
            };
            // An ASCII vertex takes at least two bytes per property (a digit and a separator).
            let min_record = 2 * vertex.properties.len() as u64;
            let capacity = capacity(vertex.count.min(max), min_record, remaining);
            let fresh = batch_builder(vertex, &targets, has_normals, capacity);
            let mut batches = crate::Batches::new(max, fresh, sink);
            read_ascii_vertices(&mut lines, file, vertex, &targets, &mut batches)?;
            batches.finish()?;
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
                return Err(no_vertex_element(file, &header).into());
            };
            let capacity = capacity(vertex.count.min(max), body.min_record(vertex), remaining);
            let fresh = batch_builder(vertex, &targets, has_normals, capacity);
            let mut batches = crate::Batches::new(max, fresh, sink);
            body.read_vertices(vertex, &targets, &mut batches)?;
            batches.finish()?;
        }
    }
    Ok(notes)
}

/// A new, empty batch of vertices with room for `capacity`.
fn batch_builder<'a>(
    vertex: &'a Element,
    targets: &'a [Target],
    has_normals: bool,
    capacity: usize,
) -> Box<dyn Fn() -> CloudBuilder + 'a> {
    Box::new(move || {
        let mut cloud = CloudBuilder::new(has_normals, capacity);
        cloud.attributes = attribute_columns(vertex, targets, capacity);
        cloud
    })
}

/// The number of vertices a PLY header declares, read from the header alone.
pub(crate) fn vertex_count(mut reader: impl BufRead, file: &str) -> Result<u64, ReadError> {
    let header = parse_header(&mut reader, file)?;
    header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map(|e| e.count)
        .ok_or_else(|| no_vertex_element(file, &header))
}

/// Finds the vertex element and maps each of its properties to a slot of [`SLOT_NAMES`] or
/// to an attribute, in property order; list properties are skipped, with a note each.
fn vertex_layout(
    header: &Header,
    file: &str,
    slots: &[&str],
) -> Result<(usize, Vec<Target>, Vec<String>), ReadError> {
    let Some((index, vertex)) = header
        .elements
        .iter()
        .enumerate()
        .find(|(_, e)| e.name == "vertex")
    else {
        return Err(no_vertex_element(file, header));
    };
    let mut targets = Vec::with_capacity(vertex.properties.len());
    let mut notes = Vec::new();
    let mut attributes = 0;
    let mut present = [false; 6];
    // `normal_x` … (PCL's names) stand for `nx` … unless the file also has those. (A set: a
    // header may declare 10⁵ properties.)
    let declared: std::collections::HashSet<&str> =
        vertex.properties.iter().map(|p| p.name.as_str()).collect();
    for property in &vertex.properties {
        let alias = crate::slot_alias(&property.name);
        let name = if alias != property.name && declared.contains(alias) {
            &property.name
        } else {
            alias
        };
        let slot = slots.iter().position(|&n| n == name);
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
        targets.push(match (slot, property.kind) {
            (Some(slot), _) => Target::Slot(slot),
            (None, PropertyKind::Scalar(_)) => {
                attributes += 1;
                Target::Attribute(attributes - 1)
            }
            (None, PropertyKind::List { .. }) => {
                notes.push(format!(
                    "{file}: vertex property {} is a list; it is not carried to the output",
                    property.name
                ));
                Target::Skip
            }
        });
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
    Ok((index, targets, notes))
}

/// The empty attribute columns of the vertex element's scalar properties that are not
/// coordinates or normals, in property order, with room for `capacity` values; a name the
/// writers could not write (`scalar/Intensity`) gets `_` for each character they refuse.
/// A property `scalar_name` is the attribute `name` (CloudCompare's convention, which the
/// writer follows), unless the file has a property `name` too or `name` is a coordinate or
/// normal.
fn attribute_columns(vertex: &Element, targets: &[Target], capacity: usize) -> Vec<Attribute> {
    let declared: HashSet<&str> = vertex.properties.iter().map(|p| p.name.as_str()).collect();
    let mut attributes: Vec<Attribute> = Vec::new();
    let mut taken = HashSet::new();
    for (p, t) in vertex.properties.iter().zip(targets) {
        if let (Target::Attribute(_), PropertyKind::Scalar(ty)) = (t, p.kind) {
            let name = match p.name.strip_prefix(crate::write::PLY_SCALAR_PREFIX) {
                Some(bare)
                    if !bare.is_empty()
                        && !declared.contains(bare)
                        && !SLOT_NAMES.contains(&crate::slot_alias(bare)) =>
                {
                    bare
                }
                _ => &p.name,
            };
            attributes.push(Attribute {
                name: usable_name(name, "property", &mut taken),
                data: AttributeData::with_capacity(ty.attribute_type(), capacity),
            });
        }
    }
    attributes
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

fn read_ascii_vertices<R: BufRead, E: From<ReadError>>(
    lines: &mut Lines<R>,
    file: &str,
    vertex: &Element,
    targets: &[Target],
    batches: &mut crate::Batches<'_, E>,
) -> Result<(), E> {
    for index in 0..vertex.count {
        let cloud = batches.cloud();
        let Some((line, text)) = lines.next_line(file)? else {
            return Err(ascii_eof(lines, file, vertex, index).into());
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
                return Err(error(property, "missing value (row too short)".to_owned()).into());
            };
            match property.kind {
                PropertyKind::Scalar(ty) => match *target {
                    Target::Slot(slot) => {
                        if let Some(value) = values.get_mut(slot) {
                            let v = parse_finite(token).map_err(|m| error(property, m))?;
                            if !ty.holds(v) {
                                return Err(error(
                                    property,
                                    format!(
                                        "{} is not a value of the declared type {}",
                                        quoted(token),
                                        ty.name()
                                    ),
                                )
                                .into());
                            }
                            *value = v;
                        }
                    }
                    Target::Attribute(i) => {
                        if let Some(a) = cloud.attributes.get_mut(i) {
                            a.data.push_text(token).map_err(|m| error(property, m))?;
                        }
                    }
                    Target::Skip => {}
                },
                PropertyKind::List { .. } => {
                    let length = token.parse::<u64>().map_err(|_| {
                        error(property, format!("invalid list length {}", quoted(token)))
                    })?;
                    for item in 0..length {
                        if tokens.next().is_none() {
                            return Err(error(
                                property,
                                format!("list of {length} values ends after {item}"),
                            )
                            .into());
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
            }
            .into());
        }
        batches.push(values)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capacity_is_bounded() {
        assert_eq!(capacity(10, 24, None), 10);
        assert_eq!(capacity(u64::MAX, 24, None), 1 << 20);
        assert_eq!(capacity(1_000_000_000_000, 24, Some(240)), 10);
        assert_eq!(capacity(5, 0, Some(0)), 0);
    }
}
