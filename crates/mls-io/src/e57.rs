//! E57 (ASTM E2807) input through the `e57` crate.
//!
//! Every scan (`data3D` child) is read, in file order, and the scans are concatenated: each
//! point in world (file) coordinates, its scan's pose (rotation, then translation) applied by
//! the crate, spherical coordinates converted to Cartesian where a scan has no Cartesian ones.
//! Points whose coordinates are invalid (`cartesianInvalidState` 1, a direction only, or 2, and
//! no valid spherical coordinates) are skipped. Carried as attributes: `scan` (the scan's index,
//! `uint32`), `intensity` and `red`, `green`, `blue` when a scan has them, raw (not scaled to
//! 0–1 by the file's limits) in `uint8` or `uint16` when every scan stores them as integers in
//! that range, else `float32`; a point whose value is missing or marked invalid gets 0 (NaN for
//! `float32`). The E57 normals extension, row and column indices, return indices and time
//! stamps are not read. Each scan's pose translation, the scanner's position, is kept in
//! [`Scans`] for orientation towards it.

use std::io::{Read, Seek};

use e57::{CartesianCoordinate, E57Reader, RecordDataType, RecordName};

use crate::attributes::{Attribute, AttributeData, AttributeType, Scalar};
use crate::{MAX_PREALLOCATED, PointCloud, ReadError, ReadOutcome, Scans};

/// The number of points in every scan of an E57 file, from its XML section.
pub(crate) fn record_count<R: Read + Seek>(reader: R, file: &str) -> Result<u64, ReadError> {
    let e57 = E57Reader::new(reader).map_err(|e| ReadError::E57 {
        file: file.to_owned(),
        message: format!("not a readable E57 file: {e}"),
    })?;
    Ok(e57.pointclouds().iter().map(|pc| pc.records).sum())
}

/// Reads every scan of an E57 file from `reader`; `file` names it in errors.
pub(crate) fn read<R: Read + Seek>(reader: R, file: &str) -> Result<ReadOutcome, ReadError> {
    crate::one_batch(|sink| read_batches(reader, file, u64::MAX, sink))
}

/// One batch of points on its way to a [`PointCloud`].
struct Batch {
    points: Vec<[f64; 3]>,
    scan_of_point: Vec<u32>,
    intensity: Option<AttributeData>,
    colour: [Option<AttributeData>; 3],
}

impl Batch {
    fn new(
        capacity: usize,
        intensity: Option<AttributeType>,
        colour: Option<AttributeType>,
    ) -> Self {
        let column =
            |ty: Option<AttributeType>| ty.map(|ty| AttributeData::with_capacity(ty, capacity));
        Self {
            points: Vec::with_capacity(capacity),
            scan_of_point: Vec::with_capacity(capacity),
            intensity: column(intensity),
            colour: [column(colour), column(colour), column(colour)],
        }
    }

    fn finish(self, origins: &[Option<[f64; 3]>]) -> PointCloud {
        let mut attributes = vec![Attribute {
            name: "scan".into(),
            data: AttributeData::U32(self.scan_of_point.clone()),
        }];
        if let Some(data) = self.intensity {
            attributes.push(Attribute {
                name: "intensity".into(),
                data,
            });
        }
        for (name, data) in ["red", "green", "blue"].into_iter().zip(self.colour) {
            if let Some(data) = data {
                attributes.push(Attribute {
                    name: name.into(),
                    data,
                });
            }
        }
        PointCloud {
            points: self.points,
            normals: None,
            attributes,
            las: None,
            scans: Some(Scans {
                origins: origins.to_vec(),
                scan_of_point: self.scan_of_point,
            }),
        }
    }
}

/// Reads every scan of an E57 file as [`read`] does, handing the points to `sink` in clouds
/// of at most `max` points, in file order, each with every scan's origin and its own points'
/// scans in [`PointCloud::scans`] (an empty cloud for a file without valid points); returns
/// the notes (none).
pub(crate) fn read_batches<R: Read + Seek, E: From<ReadError>>(
    reader: R,
    file: &str,
    max: u64,
    sink: &mut dyn FnMut(PointCloud) -> Result<(), E>,
) -> Result<Vec<String>, E> {
    let error = |message: String| ReadError::E57 {
        file: file.to_owned(),
        message,
    };
    let mut e57 =
        E57Reader::new(reader).map_err(|e| error(format!("not a readable E57 file: {e}")))?;
    let scans = e57.pointclouds();
    if scans.is_empty() {
        return Err(error("an E57 file without scans (its data3D list is empty)".into()).into());
    }
    for (s, pc) in scans.iter().enumerate() {
        if !pc.has_cartesian() && !pc.has_spherical() {
            return Err(error(format!(
                "E57 scan {s}{}: no Cartesian or spherical coordinates",
                scan_name(pc)
            ))
            .into());
        }
    }
    let max = max.max(1);
    let capacity = scans
        .iter()
        .map(|pc| pc.records)
        .sum::<u64>()
        .min(MAX_PREALLOCATED)
        .min(max) as usize;
    let intensity_type = value_type(&scans, &[RecordName::Intensity]);
    let colour_type = value_type(
        &scans,
        &[
            RecordName::ColorRed,
            RecordName::ColorGreen,
            RecordName::ColorBlue,
        ],
    );
    let origins: Vec<Option<[f64; 3]>> = scans
        .iter()
        .map(|pc| {
            pc.transform
                .as_ref()
                .map(|t| [t.translation.x, t.translation.y, t.translation.z])
        })
        .collect();
    let fresh = || Batch::new(capacity, intensity_type, colour_type);
    let mut batch = fresh();
    let mut handed = false;
    for (s, pc) in scans.iter().enumerate() {
        let name = scan_name(pc);
        let index = u32::try_from(s).map_err(|_| error("more than 2^32 scans".into()))?;
        let mut it = e57
            .pointcloud_simple(pc)
            .map_err(|e| error(format!("E57 scan {s}{name}: {e}")))?;
        it.spherical_to_cartesian(true);
        it.apply_pose(true);
        it.intensity_to_color(false);
        it.normalize_intensity(false);
        it.normalize_color(false);
        for (i, p) in it.enumerate() {
            let p = p.map_err(|e| error(format!("E57 scan {s}{name}, point {i}: {e}")))?;
            let CartesianCoordinate::Valid { x, y, z } = p.cartesian else {
                continue;
            };
            if ![x, y, z].iter().all(|c| c.is_finite()) {
                return Err(error(format!(
                    "E57 scan {s}{name}, point {i}: coordinate ({x}, {y}, {z}) is not finite"
                ))
                .into());
            }
            batch.points.push([x, y, z]);
            batch.scan_of_point.push(index);
            if let Some(column) = &mut batch.intensity {
                push(column, p.intensity);
            }
            let rgb = p.color.map(|c| [c.red, c.green, c.blue]);
            for (k, column) in batch.colour.iter_mut().enumerate() {
                if let Some(column) = column {
                    push(column, rgb.map(|c| c[k]));
                }
            }
            if batch.points.len() as u64 >= max {
                let full = std::mem::replace(&mut batch, fresh());
                handed = true;
                sink(full.finish(&origins))?;
            }
        }
    }
    if !handed || !batch.points.is_empty() {
        sink(batch.finish(&origins))?;
    }
    Ok(Vec::new())
}

/// ` ("name")` for a scan with a name, for messages.
fn scan_name(pc: &e57::PointCloud) -> String {
    pc.name
        .as_deref()
        .map(|n| format!(" ({})", crate::error::quoted(n)))
        .unwrap_or_default()
}

/// The attribute type for the records `names` over every scan that has them: `uint8` or
/// `uint16` when each is an integer record whose range fits, else `float32`; `None` when no
/// scan has them all.
fn value_type(scans: &[e57::PointCloud], names: &[RecordName]) -> Option<AttributeType> {
    let mut max = Some(0_i64);
    let mut found = false;
    for pc in scans {
        let records: Vec<_> = names
            .iter()
            .map(|n| pc.prototype.iter().find(|r| &r.name == n))
            .collect();
        if records.iter().any(Option::is_none) {
            continue;
        }
        found = true;
        for r in records.into_iter().flatten() {
            max = match (max, &r.data_type) {
                (Some(m), RecordDataType::Integer { min, max }) if *min >= 0 => Some(m.max(*max)),
                _ => None,
            };
        }
    }
    found.then(|| match max {
        Some(m) if m <= i64::from(u8::MAX) => AttributeType::U8,
        Some(m) if m <= i64::from(u16::MAX) => AttributeType::U16,
        _ => AttributeType::F32,
    })
}

/// Appends a value read as `f32` to a column of [`value_type`]'s type: rounded for integers
/// (their raw values are integers already), 0 or NaN when missing.
fn push(column: &mut AttributeData, value: Option<f32>) {
    let scalar = match column.ty() {
        AttributeType::U8 => Scalar::U8(value.map_or(0, |v| v.round() as u8)),
        AttributeType::U16 => Scalar::U16(value.map_or(0, |v| v.round() as u16)),
        _ => Scalar::F32(value.unwrap_or(f32::NAN)),
    };
    column.push(scalar);
}
