//! E57 input: a sphere scanned from two poses, each scan stored in its scanner's frame.
//! `curvature` reads it in world coordinates, orients the estimated normals towards each
//! point's own scanner by default, and finds k1 = k2 = 1/R.

use std::path::Path;

use e57::{E57Writer, Quaternion, Record, RecordValue, Transform, Translation};
use nalgebra::Vector3;

use crate::common::{Table, assert_one_line_error, mlscurv, run, run_ok};

/// Radius and centre of the scanned sphere.
const R: f64 = 1.0;
const CENTRE: [f64; 3] = [10.0, -3.0, 2.0];

/// Fibonacci-lattice points on the whole sphere, of which each scan keeps those it sees.
const LATTICE: usize = 4000;

/// A scan: its pose (`w, x, y, z` unit quaternion, translation = the scanner's position).
pub(crate) struct Pose {
    rotation: [f64; 4],
    origin: [f64; 3],
}

pub(crate) fn poses() -> [Pose; 2] {
    let unit = |q: [f64; 4]| {
        let n = q.iter().map(|c| c * c).sum::<f64>().sqrt();
        q.map(|c| c / n)
    };
    [
        Pose {
            rotation: unit([0.8, 0.3, -0.1, 0.5]),
            origin: [CENTRE[0] + 3.0, CENTRE[1] + 1.0, CENTRE[2]],
        },
        Pose {
            rotation: unit([0.1, 0.6, 0.7, -0.2]),
            origin: [CENTRE[0] - 1.0, CENTRE[1] - 3.0, CENTRE[2] + 1.0],
        },
    ]
}

/// `q p q*` for a unit quaternion `q = (w, u)`.
fn rotate([w, x, y, z]: [f64; 4], p: Vector3<f64>) -> Vector3<f64> {
    let u = Vector3::new(x, y, z);
    let c = u.cross(&p);
    p + 2.0 * w * c + 2.0 * u.cross(&c)
}

/// The sphere's lattice points in world coordinates, with the scan that sees each (the first
/// that does; points neither scanner sees are left out).
pub(crate) fn scanned_points(poses: &[Pose]) -> Vec<(Vector3<f64>, usize)> {
    let centre = Vector3::from(CENTRE);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..LATTICE)
        .filter_map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / LATTICE as f64;
            let r = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            let n = Vector3::new(r * t.cos(), r * t.sin(), z);
            let p = centre + R * n;
            let scan = poses
                .iter()
                .position(|s| n.dot(&(Vector3::from(s.origin) - p)) > 0.0)?;
            Some((p, scan))
        })
        .collect()
}

/// Writes the scans, each point in its scanner's frame (`R^T (p − t)`) with an intensity.
pub(crate) fn write_scans(path: &Path, poses: &[Pose], points: &[(Vector3<f64>, usize)]) {
    let mut writer = E57Writer::from_file(path, "sphere-file").unwrap();
    for (s, pose) in poses.iter().enumerate() {
        let prototype = vec![
            Record::CARTESIAN_X_F64,
            Record::CARTESIAN_Y_F64,
            Record::CARTESIAN_Z_F64,
            Record::INTENSITY_U16,
        ];
        let mut pc = writer
            .add_pointcloud(&format!("sphere-scan-{s}"), prototype)
            .unwrap();
        let [w, x, y, z] = pose.rotation;
        let [tx, ty, tz] = pose.origin;
        pc.set_transform(Some(Transform {
            rotation: Quaternion { w, x, y, z },
            translation: Translation {
                x: tx,
                y: ty,
                z: tz,
            },
        }));
        let inverse = [w, -x, -y, -z];
        for (i, (p, _)) in points.iter().enumerate().filter(|(_, (_, k))| *k == s) {
            let local = rotate(inverse, p - Vector3::from(pose.origin));
            pc.add_point(vec![
                RecordValue::Double(local.x),
                RecordValue::Double(local.y),
                RecordValue::Double(local.z),
                RecordValue::Integer((i % 4096) as i64),
            ])
            .unwrap();
        }
        pc.finalize().unwrap();
    }
    writer.finalize().unwrap();
}

#[test]
fn curvature_of_two_scans_faces_each_scanner_and_is_one_over_r() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.e57");
    let poses = poses();
    let points = scanned_points(&poses);
    write_scans(&input, &poses, &points);
    // The file's points, in file order: scan 0's, then scan 1's.
    let ordered: Vec<&(Vector3<f64>, usize)> = (0..poses.len())
        .flat_map(|s| points.iter().filter(move |(_, k)| *k == s))
        .collect();

    let info = run_ok(mlscurv().arg("info").arg(&input));
    assert!(
        info.stdout
            .contains(&format!("points          {}", points.len())),
        "{}",
        info.stdout
    );
    assert!(
        info.stdout.contains("scans           2 (2 with a pose)"),
        "{}",
        info.stdout
    );

    let out = dir.path().join("out.ply");
    let r = run_ok(
        mlscurv()
            .args(["curvature", "--ascii", "-o"])
            .arg(&out)
            .arg(&input),
    );
    assert!(
        r.stderr.contains("each scan's scanner position"),
        "{}",
        r.stderr
    );
    let t = Table::parse_ascii_ply(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(t.rows.len(), points.len());
    let xyz = t.vectors(["x", "y", "z"]);
    let normals = t.vectors(["nx", "ny", "nz"]);
    let (scan, status) = (t.column("scan"), t.column("status"));
    let (k1, k2) = (t.column("k1"), t.column("k2"));
    assert!(t.header.iter().any(|h| h == "intensity"), "{:?}", t.header);

    let centre = Vector3::from(CENTRE);
    let mut interior = 0;
    let mut facing = 0;
    for i in 0..t.rows.len() {
        let (p, s) = *ordered[i];
        assert!((xyz[i] - p).amax() < 1e-9, "row {i}: {} vs {p}", xyz[i]);
        assert_eq!(scan[i], s as f64);
        let sight = Vector3::from(poses[s].origin) - xyz[i];
        facing += usize::from(normals[i].dot(&sight) > 0.0);
        // Outward everywhere, and so towards the scanner that saw the point.
        assert!(
            normals[i].dot(&(xyz[i] - centre)) > 0.0,
            "row {i}: normal {} points into the sphere",
            normals[i]
        );
        // Away from the edge of what the scanners saw, the curvature is that of the sphere.
        let outward = (p - centre) / R;
        if outward.dot(&sight.normalize()) > 0.3 {
            interior += 1;
            assert_eq!(status[i], 0.0, "row {i}");
            for k in [k1[i], k2[i]] {
                assert!(
                    (k - 1.0 / R).abs() < 1e-2,
                    "row {i}: k = {k}, expected {}",
                    1.0 / R
                );
            }
        }
    }
    assert!(interior > points.len() / 2, "{interior} interior points");
    // Every point was seen from its scanner, so the outward normal faces it; a normal
    // estimated at the silhouette may tilt past the line of sight.
    assert!(
        facing as f64 >= 0.99 * points.len() as f64,
        "{facing} of {} face their scanner",
        points.len()
    );

    // `--orient` overrides the default: `none` leaves the estimated signs as they came.
    let out_none = dir.path().join("none.csv");
    let r = run_ok(
        mlscurv()
            .args(["normals", "--orient", "none", "-o"])
            .arg(&out_none)
            .arg(&input),
    );
    assert!(
        !r.stderr.contains("each scan's scanner position"),
        "{}",
        r.stderr
    );
}

#[test]
fn a_corrupt_e57_file_is_one_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("corrupt.e57");
    std::fs::write(&input, b"ASTM-E57\0\0\0\0garbage".repeat(100)).unwrap();
    let name = input.display().to_string();
    let out = dir.path().join("out.csv");
    for args in [vec!["info"], vec!["curvature", "-o", out.to_str().unwrap()]] {
        let r = run(mlscurv().args(args).arg(&input));
        assert_one_line_error(&r, &name, &["E57"]);
    }
}

#[test]
fn e57_is_not_an_output_format() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    std::fs::write(&input, "0 0 0\n1 0 0\n0 1 0\n1 1 0.1\n").unwrap();
    let out = dir.path().join("out.e57");
    let r = run(mlscurv().arg("curvature").arg(&input).arg("-o").arg(&out));
    assert_one_line_error(&r, &out.display().to_string(), &["input format only"]);
}
