//! Files written by CloudCompare 2.11.3 (`tests/data/cloudcompare/`, see the README there):
//! its ASCII export with each separator, a header of names with spaces and parentheses and a
//! point-count line, and its PLY export; and what is refused in such files.

use std::path::{Path, PathBuf};

use mls_io::{
    AttributeData, FileFormat, PointCloud, ReadOptions, read_csv, read_point_cloud,
    read_point_cloud_from_with, read_xyz,
};

use crate::assert_message;

fn sample(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/cloudcompare")
        .join(name)
}

/// The scalar fields of the samples, as the readers name them: CloudCompare's `Mean
/// curvature (0.8)` (`Mean_curvature_(0.8)` in its space-separated export).
const FIELDS: [&str; 2] = ["Mean_curvature__0.8_", "Gaussian_curvature__0.8_"];

fn column<'a>(cloud: &'a PointCloud, name: &str) -> &'a [f64] {
    let a = cloud
        .attributes
        .iter()
        .find(|a| a.name == name)
        .unwrap_or_else(|| panic!("no attribute {name}"));
    match &a.data {
        AttributeData::F64(v) => v,
        other => panic!("{name}: {other:?}"),
    }
}

#[test]
fn ascii_exports_with_every_separator_read_alike() {
    let mut clouds = Vec::new();
    for sep in ["space", "semicolon", "comma", "tab"] {
        let cloud = read_point_cloud(&sample(&format!("cc-sphere-{sep}.asc")))
            .unwrap_or_else(|e| panic!("{sep}: {e}"));
        assert_eq!(cloud.len(), 12, "{sep}: the count line is not a point");
        let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, FIELDS, "{sep}");
        // The first row, as written.
        assert_eq!(
            cloud.points[0],
            [-0.021784000099, -0.239510998130, 0.970649003983],
            "{sep}"
        );
        assert_eq!(
            cloud.normals.as_ref().unwrap()[0],
            [-0.022853, -0.239358, 0.970662],
            "{sep}"
        );
        assert_eq!(column(&cloud, FIELDS[0])[0], 0.977369725704, "{sep}");
        assert_eq!(column(&cloud, FIELDS[1])[0], 0.954469919205, "{sep}");
        clouds.push(cloud);
    }
    for cloud in &clouds[1..] {
        assert_eq!(cloud, &clouds[0]);
    }
    // The semicolon export read as CSV: the same cloud.
    let text = std::fs::read_to_string(sample("cc-sphere-semicolon.asc")).unwrap();
    assert_eq!(read_csv(text.as_bytes(), "cc.csv").unwrap(), clouds[0]);
}

#[test]
fn ply_export_has_the_same_fields() {
    let ply = read_point_cloud(&sample("cc-sphere.ply")).unwrap();
    let ascii = read_point_cloud(&sample("cc-sphere-comma.asc")).unwrap();
    let names: Vec<&str> = ply.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, FIELDS);
    // CloudCompare's ASCII PLY has 6 significant digits, its ASCII export 12 decimals.
    let close = |p: f64, a: f64| (p - a).abs() <= 5e-6 * a.abs().max(1e-3);
    for (p, a) in ply.points.iter().zip(&ascii.points) {
        for k in 0..3 {
            assert!(close(p[k], a[k]), "{p:?} {a:?}");
        }
    }
    for name in FIELDS {
        let AttributeData::F32(p) = &ply.attributes.iter().find(|a| a.name == name).unwrap().data
        else {
            panic!("{name} is not float32 in the PLY");
        };
        for (p, a) in p.iter().zip(column(&ascii, name)) {
            assert!(close(f64::from(*p), *a), "{name}: {p} {a}");
        }
    }
}

#[test]
fn names_with_spaces_need_a_separator_other_than_space() {
    // Tab-separated names keep their spaces until made writable.
    let text = "//X\tY\tZ\tmean curvature (0.4)\n1\t2\t3\t0.5\n";
    let cloud = read_xyz(text.as_bytes(), "tab.txt").unwrap();
    assert_eq!(cloud.attributes[0].name, "mean_curvature__0.4_");
    // Separated by spaces, such a name is four columns for a row of one.
    let text = "//X Y Z mean curvature (0.4)\n1 2 3 0.5\n";
    let err = read_xyz(text.as_bytes(), "space.txt").unwrap_err();
    assert_message(&err, "space.txt", &["line 2", "4 columns", "`//` line 1"]);
}

#[test]
fn bad_headers_are_refused_naming_file_line_and_column() {
    let cases: [(&str, &[&str]); 4] = [
        ("//X;Y;Nx;Ny;Nz;k\n1;2;3;4;5;6\n", &["line 1", "no `z`"]),
        ("//X Y Z X\n1 2 3 4\n", &["line 1", "`x` named twice"]),
        ("//X Y Z Nx Ny\n1 2 3 0 0\n", &["line 1", "some of nx"]),
        ("//X,Y,Z,k1\n1\n1,2,3,oops\n", &["line 3", "column 4"]),
    ];
    for (text, parts) in cases {
        let outcome = read_point_cloud_from_with(
            text.as_bytes(),
            "cc.asc",
            FileFormat::Xyz,
            &ReadOptions::default(),
        );
        match outcome {
            Err(err) => {
                assert_message(&err, "cc.asc", parts);
            }
            // A column of text is dropped with a note, not an error.
            Ok(read) => {
                assert!(
                    read.notes
                        .iter()
                        .any(|n| n.starts_with("cc.asc") && parts.iter().all(|p| n.contains(p))),
                    "{text:?}: {:?}",
                    read.notes
                );
            }
        }
    }
}
