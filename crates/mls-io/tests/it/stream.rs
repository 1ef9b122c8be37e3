//! A file read in batches ([`PointStream`]) gives what a whole read gives: the same points,
//! normals and attributes in the same order, the same notes, its exact box, for every input
//! format and batch size.

use std::path::{Path, PathBuf};

use mls_io::{
    Axis, Column, FileFormat, PlyFormat, PointCloud, PointStream, ReadError, ReadOptions,
};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data")
        .join(name)
}

/// Reads `path` whole and in batches of each size, and compares them.
#[track_caller]
fn assert_batches_are_whole(path: &Path, format: FileFormat) {
    let options = ReadOptions::default();
    let whole = mls_io::read_point_cloud_as_with(path, format, &options).unwrap();
    let stream = PointStream::open(path, format, &options).unwrap();
    let cloud = &whole.cloud;
    assert_eq!(stream.len(), cloud.len() as u64, "{}", path.display());
    assert_eq!(stream.has_normals(), cloud.normals.is_some());
    assert_eq!(stream.notes(), &whole.notes[..]);
    if !matches!(format, FileFormat::Las | FileFormat::Laz) {
        let (lo, hi) = stream.bounds();
        for k in 0..3 {
            let min = cloud
                .points
                .iter()
                .map(|p| p[k])
                .fold(f64::INFINITY, f64::min);
            let max = cloud
                .points
                .iter()
                .map(|p| p[k])
                .fold(f64::NEG_INFINITY, f64::max);
            assert_eq!((lo[k], hi[k]), (min, max));
        }
    }
    for max in [7, 1000, u64::MAX] {
        let mut next = 0u64;
        stream
            .for_each_batch(true, max, |first, batch: PointCloud| {
                assert_eq!(first, next);
                assert!(!batch.is_empty() && batch.len() as u64 <= max);
                let at = first as usize..first as usize + batch.len();
                assert_eq!(batch.points, cloud.points[at.clone()]);
                assert_eq!(
                    batch.normals.as_deref(),
                    cloud.normals.as_ref().map(|n| &n[at.clone()])
                );
                let names = |c: &PointCloud| -> Vec<(String, mls_io::AttributeType)> {
                    c.attributes
                        .iter()
                        .map(|a| (a.name.clone(), a.data.ty()))
                        .collect()
                };
                assert_eq!(names(&batch), names(cloud));
                for (a, b) in batch.attributes.iter().zip(&cloud.attributes) {
                    for (k, i) in at.clone().enumerate() {
                        let (x, y) = (a.data.f64_at(k).unwrap(), b.data.f64_at(i).unwrap());
                        assert!(x.to_bits() == y.to_bits(), "{} row {i}: {x} {y}", a.name);
                    }
                }
                if let Some(scans) = &cloud.scans {
                    let mine = batch.scans.as_ref().unwrap();
                    assert_eq!(mine.origins, scans.origins);
                    assert_eq!(mine.scan_of_point, scans.scan_of_point[at]);
                }
                next += batch.len() as u64;
                Ok::<(), ReadError>(())
            })
            .unwrap();
        assert_eq!(next, stream.len());
    }
}

#[test]
fn batches_of_every_format_are_the_whole_read() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "bunny-stanford.ply",
        "lidar-buildings-b9.xyz",
        "cloudcompare/cc-sphere.ply",
        "cloudcompare/cc-sphere-comma.asc",
        "cloudcompare/cc-sphere-semicolon.asc",
        "cloudcompare/cc-sphere-tab.asc",
    ] {
        let path = data(name);
        let format = FileFormat::from_path(&path).unwrap();
        assert_batches_are_whole(&path, format);
    }
    // The bunny in every format written, binary and ASCII PLY, with its columns as
    // attributes of their types.
    let bunny = mls_io::read_point_cloud(&data("bunny-stanford.ply")).unwrap();
    let normals: Vec<[f64; 3]> = bunny.points.iter().map(|_| [0.0, 0.0, 1.0]).collect();
    let index: Vec<i32> = (0..bunny.len() as i32).map(|i| i * 1000).collect();
    let mut columns = bunny.columns();
    columns.extend([
        Column::component("nx", &normals, Axis::X),
        Column::component("ny", &normals, Axis::Y),
        Column::component("nz", &normals, Axis::Z),
        Column::i32("index", &index),
    ]);
    for (file, format) in [
        ("b.ply", FileFormat::Ply),
        ("b.csv", FileFormat::Csv),
        ("b.xyz", FileFormat::Xyz),
        ("b.las", FileFormat::Las),
        ("b.laz", FileFormat::Laz),
    ] {
        let path = dir.path().join(file);
        mls_io::write_point_cloud_as(&path, format, &columns, PlyFormat::BinaryLittleEndian)
            .unwrap();
        assert_batches_are_whole(&path, format);
    }
    let path = dir.path().join("a.ply");
    mls_io::write_point_cloud_as(&path, FileFormat::Ply, &columns, PlyFormat::Ascii).unwrap();
    assert_batches_are_whole(&path, FileFormat::Ply);
    let path = dir.path().join("scans.e57");
    crate::e57::write_e57(&path, &crate::e57::two_scans());
    assert_batches_are_whole(&path, FileFormat::E57);
}

/// A headerless text file whose columns 4–6 turn out not to be normals on its last row, and
/// whose integer column turns to floats: the batches, handed on before that row is read,
/// are already what the whole read makes of them.
#[test]
fn text_columns_are_typed_by_every_row_before_the_first_batch() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("late.xyz");
    let mut text = String::new();
    for i in 0..50 {
        let (n, c) = if i == 49 {
            ("0.5 0.5 0.5".to_owned(), "-0".to_owned())
        } else {
            ("0 0 1".to_owned(), format!("{i}"))
        };
        let c = if i == 30 { "2.5".to_owned() } else { c };
        text.push_str(&format!("{i} {} {} {n} {c}\n", i % 7, i % 3));
    }
    std::fs::write(&path, text).unwrap();
    assert_batches_are_whole(&path, FileFormat::Xyz);
    let stream = PointStream::open(&path, FileFormat::Xyz, &ReadOptions::default()).unwrap();
    assert!(!stream.has_normals());
    assert!(stream.notes()[0].contains("columns 4-6 are not read as normals"));
}

/// A file that changes between passes is an error, not a different cloud.
#[test]
fn a_file_changed_between_passes_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.xyz");
    std::fs::write(&path, "0 0 0\n1 0 0\n0 1 0\n").unwrap();
    let stream = PointStream::open(&path, FileFormat::Xyz, &ReadOptions::default()).unwrap();
    std::fs::write(&path, "0 0 0\n1 0 0\n").unwrap();
    let e = stream
        .for_each_batch(false, 10, |_, _| Ok::<(), ReadError>(()))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("c.xyz: the file changed while it was read: 3 points the first time, 2 now"),
        "{e}"
    );
}
