//! E57 input: two scans written with the `e57` crate's writer, each from its own pose, read
//! back in world coordinates with their attributes and scanner positions.

use std::path::Path;

use e57::{E57Writer, Quaternion, Record, RecordValue, Transform, Translation};
use mls_io::{AttributeData, FileFormat, PointCloud, ReadError, read_point_cloud};

use crate::assert_message;

/// One scan to write: points in the scanner's frame, its pose, and per-point values.
pub(crate) struct Scan {
    /// `w, x, y, z` of a unit quaternion.
    rotation: [f64; 4],
    translation: [f64; 3],
    /// Local coordinates, and whether each is marked invalid (`cartesianInvalidState` 2).
    points: Vec<([f64; 3], bool)>,
    intensity: Vec<u16>,
    colour: Option<Vec<[u8; 3]>>,
}

/// Writes `scans` as an E57 file.
pub(crate) fn write_e57(path: &Path, scans: &[Scan]) {
    let mut writer = E57Writer::from_file(path, "file-guid").unwrap();
    for (s, scan) in scans.iter().enumerate() {
        let mut prototype = vec![
            Record::CARTESIAN_X_F64,
            Record::CARTESIAN_Y_F64,
            Record::CARTESIAN_Z_F64,
            Record::CARTESIAN_INVALID_STATE,
            Record::INTENSITY_U16,
        ];
        if scan.colour.is_some() {
            prototype.extend([
                Record::COLOR_RED_U8,
                Record::COLOR_GREEN_U8,
                Record::COLOR_BLUE_U8,
            ]);
        }
        let mut pc = writer
            .add_pointcloud(&format!("scan-guid-{s}"), prototype)
            .unwrap();
        let [w, x, y, z] = scan.rotation;
        let [tx, ty, tz] = scan.translation;
        pc.set_transform(Some(Transform {
            rotation: Quaternion { w, x, y, z },
            translation: Translation {
                x: tx,
                y: ty,
                z: tz,
            },
        }));
        for (i, &(p, invalid)) in scan.points.iter().enumerate() {
            let mut values = vec![
                RecordValue::Double(p[0]),
                RecordValue::Double(p[1]),
                RecordValue::Double(p[2]),
                RecordValue::Integer(if invalid { 2 } else { 0 }),
                RecordValue::Integer(i64::from(scan.intensity[i])),
            ];
            if let Some(colour) = &scan.colour {
                values.extend(colour[i].map(|c| RecordValue::Integer(i64::from(c))));
            }
            pc.add_point(values).unwrap();
        }
        pc.finalize().unwrap();
    }
    writer.finalize().unwrap();
}

/// `q p q*` for a unit quaternion `q = (w, u)`: `p + 2w (u × p) + 2 u × (u × p)`, written
/// out here rather than taken from the crate's rotation matrix.
fn rotate([w, x, y, z]: [f64; 4], p: [f64; 3]) -> [f64; 3] {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let u = [x, y, z];
    let c = cross(u, p);
    let cc = cross(u, c);
    [0, 1, 2].map(|k| p[k] + 2.0 * w * c[k] + 2.0 * cc[k])
}

fn unit_quaternion(q: [f64; 4]) -> [f64; 4] {
    let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / n)
}

pub(crate) fn two_scans() -> Vec<Scan> {
    let grid = |offset: f64, invalid_every: usize| -> Vec<([f64; 3], bool)> {
        (0..30)
            .map(|i| {
                let (a, b) = ((i % 6) as f64, (i / 6) as f64);
                (
                    [a * 0.1 + offset, b * 0.1, 5.0 - 0.01 * a],
                    i % invalid_every == 3,
                )
            })
            .collect()
    };
    vec![
        Scan {
            rotation: unit_quaternion([0.9, 0.1, -0.2, 0.3]),
            translation: [100.25, -20.5, 3.125],
            points: grid(0.0, 7),
            intensity: (0..30).map(|i| 1000 + 37 * i).collect(),
            colour: Some(
                (0..30)
                    .map(|i| [i as u8, 2 * i as u8, 255 - i as u8])
                    .collect(),
            ),
        },
        Scan {
            rotation: unit_quaternion([0.2, -0.7, 0.1, 0.4]),
            translation: [-7.0, 1234.5, -0.75],
            points: grid(0.05, 1000),
            intensity: (0..30).map(|i| 60000 - 11 * i).collect(),
            colour: None,
        },
    ]
}

fn attribute<'a>(cloud: &'a PointCloud, name: &str) -> &'a AttributeData {
    &cloud
        .attributes
        .iter()
        .find(|a| a.name == name)
        .unwrap_or_else(|| panic!("no attribute {name}"))
        .data
}

#[test]
fn two_scans_read_back_in_world_coordinates_with_attributes_and_origins() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scans.e57");
    let scans = two_scans();
    write_e57(&path, &scans);
    assert_eq!(FileFormat::from_path(&path), Some(FileFormat::E57));
    let cloud = read_point_cloud(&path).unwrap();

    // The expected cloud, built independently: valid points only, each scan's pose applied.
    let mut expected = Vec::new();
    let (mut scan_index, mut intensity, mut red, mut green, mut blue) =
        (vec![], vec![], vec![], vec![], vec![]);
    for (s, scan) in scans.iter().enumerate() {
        for (i, &(p, invalid)) in scan.points.iter().enumerate() {
            if invalid {
                continue;
            }
            let r = rotate(scan.rotation, p);
            expected.push([0, 1, 2].map(|k| r[k] + scan.translation[k]));
            scan_index.push(s as u32);
            intensity.push(scan.intensity[i]);
            let c = scan.colour.as_ref().map_or([0; 3], |c| c[i]);
            red.push(c[0]);
            green.push(c[1]);
            blue.push(c[2]);
        }
    }
    // Scan 0 has 30 points of which 4 are invalid (i = 3, 10, 17, 24), scan 1 one (i = 3).
    assert_eq!(expected.len(), 55);
    assert_eq!(cloud.len(), expected.len());
    for (got, want) in cloud.points.iter().zip(&expected) {
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() <= 1e-9,
                "world coordinates {got:?}, expected {want:?}"
            );
        }
    }
    assert_eq!(cloud.normals, None);
    assert_eq!(
        attribute(&cloud, "scan"),
        &AttributeData::U32(scan_index.clone())
    );
    assert_eq!(
        attribute(&cloud, "intensity"),
        &AttributeData::U16(intensity)
    );
    assert_eq!(attribute(&cloud, "red"), &AttributeData::U8(red));
    assert_eq!(attribute(&cloud, "green"), &AttributeData::U8(green));
    assert_eq!(attribute(&cloud, "blue"), &AttributeData::U8(blue));

    let found = cloud.scans.as_ref().expect("E57 scans");
    let origins: Vec<_> = scans.iter().map(|s| Some(s.translation)).collect();
    assert_eq!(found.origins, origins);
    assert_eq!(found.scan_of_point, scan_index);
    let viewpoints = found.viewpoints().unwrap();
    for (v, s) in viewpoints.iter().zip(&scan_index) {
        assert_eq!(*v, scans[*s as usize].translation);
    }
}

#[test]
fn a_file_that_is_not_e57_is_one_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken.e57");
    std::fs::write(
        &path,
        b"ASTM-E57 but then nothing that makes sense\n".repeat(50),
    )
    .unwrap();
    let name = path.display().to_string();
    let err = read_point_cloud(&path).unwrap_err();
    assert!(matches!(err, ReadError::E57 { .. }), "{err:?}");
    assert_message(&err, &name, &["E57"]);
}

#[test]
fn a_truncated_e57_file_is_one_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.e57");
    write_e57(&path, &two_scans());
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let name = path.display().to_string();
    let err = read_point_cloud(&path).unwrap_err();
    assert!(matches!(err, ReadError::E57 { .. }), "{err:?}");
    assert_message(&err, &name, &["E57"]);
}

#[test]
fn a_corrupted_e57_body_is_an_error_not_wrong_points() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flipped.e57");
    write_e57(&path, &two_scans());
    let mut bytes = std::fs::read(&path).unwrap();
    // The binary sections start after the 48-byte header; every page carries a checksum.
    for b in &mut bytes[48..400] {
        *b ^= 0x5a;
    }
    std::fs::write(&path, &bytes).unwrap();
    let name = path.display().to_string();
    let err = read_point_cloud(&path).unwrap_err();
    assert_message(&err, &name, &["E57"]);
}
