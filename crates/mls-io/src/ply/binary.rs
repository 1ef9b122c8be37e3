//! The binary PLY body.

use std::io::{self, BufRead, Read};

use super::Target;
use super::header::{Element, Encoding, Property, PropertyKind, ScalarType, describe, io_error};
use crate::Batches;
use crate::error::ReadError;

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
pub(super) struct BinaryBody<'a, R> {
    pub(super) reader: R,
    pub(super) file: &'a str,
    pub(super) offset: u64,
    pub(super) encoding: Encoding,
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

    /// Reads the bytes of one scalar into the start of an 8-byte buffer, or reports it as
    /// truncated.
    fn read_raw(
        &mut self,
        ty: ScalarType,
        field: impl FnOnce() -> String,
    ) -> Result<[u8; 8], ReadError> {
        let mut buf = [0; 8];
        let bytes = buf.get_mut(..ty.size() as usize).unwrap_or_default();
        let read = read_full(&mut self.reader, bytes).map_err(io_error(self.file))?;
        if read < bytes.len() {
            return Err(self.truncated(self.offset, field()));
        }
        self.offset = self.offset.saturating_add(ty.size());
        Ok(buf)
    }

    /// Reads one scalar, or reports it as truncated.
    fn read_scalar(
        &mut self,
        ty: ScalarType,
        field: impl FnOnce() -> String,
    ) -> Result<f64, ReadError> {
        let raw = self.read_raw(ty, field)?;
        // The buffer holds 8 bytes, enough for any type.
        Ok(ty.decode(&raw, self.encoding).unwrap_or(f64::NAN))
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

    pub(super) fn skip_element(&mut self, element: &Element) -> Result<(), ReadError> {
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

    /// The fewest bytes a vertex can take (a list property at least its length).
    pub(super) fn min_record(&self, vertex: &Element) -> u64 {
        vertex
            .properties
            .iter()
            .map(|p| match p.kind {
                PropertyKind::Scalar(ty) => ty.size(),
                PropertyKind::List { count, .. } => count.size(),
            })
            .sum()
    }

    pub(super) fn read_vertices<E: From<ReadError>>(
        &mut self,
        vertex: &Element,
        targets: &[Target],
        batches: &mut Batches<'_, E>,
    ) -> Result<(), E> {
        match vertex.fixed_size() {
            Some(size) => self.read_fixed_vertices(vertex, size, targets, batches),
            None => self.read_variable_vertices(vertex, targets, batches),
        }
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
    fn read_fixed_vertices<E: From<ReadError>>(
        &mut self,
        vertex: &Element,
        size: u64,
        targets: &[Target],
        batches: &mut Batches<'_, E>,
    ) -> Result<(), E> {
        // (offset in record, type, slot, property) for the coordinates and normals, and
        // (offset in record, attribute) for the attributes.
        let mut plan = Vec::with_capacity(6);
        let mut attributes = Vec::with_capacity(batches.cloud().attributes.len());
        let mut at = 0;
        for (property, target) in vertex.properties.iter().zip(targets) {
            if let PropertyKind::Scalar(ty) = property.kind {
                match *target {
                    Target::Slot(slot) => plan.push((at, ty, slot, property)),
                    Target::Attribute(i) => attributes.push((usize::try_from(at).ok(), i)),
                    Target::Skip => {}
                }
                at += ty.size();
            }
        }
        let big_endian = self.encoding == Encoding::BigEndian;
        let mut record = vec![0; usize::try_from(size).unwrap_or(0)];
        for index in 0..vertex.count {
            let read = read_full(&mut self.reader, &mut record).map_err(io_error(self.file))?;
            if read < record.len() {
                return Err(self
                    .truncated_record(vertex, index, size, read as u64)
                    .into());
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
                    return Err(self.truncated(offset, field()).into());
                };
                if !value.is_finite() {
                    return Err(self.non_finite(offset, field(), value).into());
                }
                if let Some(dst) = values.get_mut(slot) {
                    *dst = value;
                }
            }
            let cloud = batches.cloud();
            for &(at, i) in &attributes {
                let bytes = at.and_then(|at| record.get(at..)).unwrap_or_default();
                if let Some(a) = cloud.attributes.get_mut(i) {
                    // The record holds every property whole: this cannot come up short.
                    a.data.push_bytes(bytes, big_endian);
                }
            }
            self.offset = self.offset.saturating_add(size);
            batches.push(values)?;
        }
        Ok(())
    }

    /// The general path for vertices with list properties: one property at a time.
    fn read_variable_vertices<E: From<ReadError>>(
        &mut self,
        vertex: &Element,
        targets: &[Target],
        batches: &mut Batches<'_, E>,
    ) -> Result<(), E> {
        let big_endian = self.encoding == Encoding::BigEndian;
        for index in 0..vertex.count {
            let mut values = [0.0; 6];
            for (property, target) in vertex.properties.iter().zip(targets) {
                match property.kind {
                    PropertyKind::Scalar(ty) => {
                        let field = || describe(vertex, index, property, ty.name());
                        let offset = self.offset;
                        let raw = self.read_raw(ty, field)?;
                        match *target {
                            Target::Slot(slot) => {
                                let value = ty.decode(&raw, self.encoding).unwrap_or(f64::NAN);
                                if !value.is_finite() {
                                    return Err(self.non_finite(offset, field(), value).into());
                                }
                                if let Some(dst) = values.get_mut(slot) {
                                    *dst = value;
                                }
                            }
                            Target::Attribute(i) => {
                                if let Some(a) = batches.cloud().attributes.get_mut(i) {
                                    a.data.push_bytes(&raw, big_endian);
                                }
                            }
                            Target::Skip => {}
                        }
                    }
                    PropertyKind::List { count, item } => {
                        self.skip_list(vertex, index, property, count, item)?;
                    }
                }
            }
            batches.push(values)?;
        }
        Ok(())
    }
}
