//! Written tables read back exactly, checked by the readers and by decoding the files
//! independently.

use mls_io::{
    Column, ColumnNames, PlyFormat, PointCloud, ReadOptions, WriteError, read_csv,
    read_point_cloud, read_point_cloud_with, read_xyz_with, write_csv_to, write_ply_to,
    write_point_cloud, write_xyz_to,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{assert_message, seeds};

/// The curvature output columns after the points and normals.
const EXTRA: [&str; 10] = [
    "k1", "k2", "mean", "gauss", "d1x", "d1y", "d1z", "d2x", "d2y", "d2z",
];

/// Values that stress exact decimal round trips, then random bit patterns (finite ones only
/// in the coordinates, which the readers check).
fn hard_values(rng: &mut ChaCha8Rng, n: usize, finite: bool) -> Vec<f64> {
    let mut values = vec![
        0.0,
        -0.0,
        0.1,
        1.0 / 3.0,
        -std::f64::consts::PI,
        1e-300,
        5e-324,
        f64::MIN_POSITIVE,
        f64::MAX,
        -f64::MAX,
        123_456_789.123_456_79,
        1e16,
        1e22,
    ];
    while values.len() < n {
        let v = f64::from_bits(rng.random());
        if v.is_finite() || !finite {
            values.push(v);
        }
    }
    values.truncate(n);
    values
}

struct Table {
    cloud: PointCloud,
    extra: Vec<Vec<f64>>,
    status: Vec<i32>,
}

impl Table {
    fn new(n: usize) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seeds::ROUND_TRIP);
        let mut vectors = || {
            let [a, b, c] = [0, 1, 2].map(|_| hard_values(&mut rng, n, true));
            (0..n)
                .map(|i| [a[i], b[(i + 1) % n], c[(i + 2) % n]])
                .collect::<Vec<_>>()
        };
        let cloud = PointCloud {
            points: vectors(),
            normals: Some(vectors()),
            ..PointCloud::default()
        };
        let mut extra: Vec<Vec<f64>> = EXTRA
            .iter()
            .map(|_| hard_values(&mut rng, n, false))
            .collect();
        // Failed points carry NaN curvature; the writers must pass it through.
        if let Some(k1) = extra.first_mut() {
            k1[1] = f64::NAN;
            k1[2] = f64::INFINITY;
        }
        let status = (0..n)
            .map(|i| [0, 3, i32::MAX, i32::MIN, -1][i % 5])
            .collect();
        Self {
            cloud,
            extra,
            status,
        }
    }

    fn columns(&self) -> Vec<Column<'_>> {
        let mut columns = self.cloud.columns();
        columns.extend(
            EXTRA
                .iter()
                .zip(&self.extra)
                .map(|(name, data)| Column::f64(name, data)),
        );
        columns.push(Column::i32("status", &self.status));
        columns
    }

    /// Row `i` as (float cells, status).
    fn row(&self, i: usize) -> (Vec<f64>, i32) {
        let [x, y, z] = self.cloud.points[i];
        let [nx, ny, nz] = self.cloud.normals.as_ref().unwrap()[i];
        let mut cells = vec![x, y, z, nx, ny, nz];
        cells.extend(self.extra.iter().map(|c| c[i]));
        (cells, self.status[i])
    }
}

/// Compares bit for bit, except that text keeps only that a value is NaN, not its payload.
fn assert_same_bits(a: &[f64], b: &[f64], context: &str) {
    assert_eq!(a.len(), b.len(), "{context}");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert_eq!(
            x.to_bits(),
            y.to_bits(),
            "{context}, cell {i}: {x:?} vs {y:?}"
        );
    }
}

fn assert_same_text_values(read: &[f64], written: &[f64], context: &str) {
    assert_eq!(read.len(), written.len(), "{context}");
    for (i, (x, y)) in read.iter().zip(written).enumerate() {
        if !(x.is_nan() && y.is_nan()) {
            assert_eq!(
                x.to_bits(),
                y.to_bits(),
                "{context}, cell {i}: {x:?} vs {y:?}"
            );
        }
    }
}

fn assert_same_cloud(read: &PointCloud, written: &PointCloud) {
    let flat = |v: &[[f64; 3]]| v.iter().flatten().copied().collect::<Vec<_>>();
    assert_same_bits(&flat(&read.points), &flat(&written.points), "points");
    assert_same_bits(
        &flat(read.normals.as_deref().unwrap()),
        &flat(written.normals.as_deref().unwrap()),
        "normals",
    );
}

/// The body of a PLY file, after `end_header\n`.
fn ply_body(bytes: &[u8]) -> &[u8] {
    let marker = b"end_header\n";
    let at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .unwrap();
    &bytes[at + marker.len()..]
}

#[test]
fn binary_ply_round_trip() {
    let table = Table::new(200);
    let mut bytes = Vec::new();
    write_ply_to(
        &mut bytes,
        "t.ply",
        &table.columns(),
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    let header =
        String::from_utf8_lossy(&bytes[..bytes.len() - ply_body(&bytes).len()]).into_owned();
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"));
    assert!(header.contains("\nelement vertex 200\nproperty double x\n"));
    assert!(
        header.ends_with("property double scalar_d2z\nproperty int scalar_status\nend_header\n")
    );
    assert_same_cloud(
        &mls_io::read_ply(&bytes[..], "t.ply").unwrap(),
        &table.cloud,
    );

    // Decoded by hand: 16 doubles and one int per row, little-endian, in input order.
    let body = ply_body(&bytes);
    assert_eq!(body.len(), 200 * (16 * 8 + 4));
    for (i, row) in body.chunks(16 * 8 + 4).enumerate() {
        let cells: Vec<f64> = row[..128]
            .chunks(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let status = i32::from_le_bytes(row[128..].try_into().unwrap());
        let (expected, expected_status) = table.row(i);
        assert_same_bits(&cells, &expected, &format!("row {i}"));
        assert_eq!(status, expected_status);
    }
}

/// Splits text rows into cells; the readers cover x..nz, this covers every column.
fn check_text_rows(text: &str, table: &Table, separator: char, header: bool) {
    let mut lines = text.lines();
    if header {
        let names: Vec<String> = table.columns().iter().map(|c| c.name.to_owned()).collect();
        assert_eq!(lines.next().unwrap(), format!("//{}", names.join(",")));
    }
    let mut count = 0;
    for (i, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(separator).collect();
        assert_eq!(cells.len(), 17, "row {i}: {line}");
        let floats: Vec<f64> = cells[..16].iter().map(|c| c.parse().unwrap()).collect();
        let (expected, status) = table.row(i);
        assert_same_text_values(&floats, &expected, &format!("row {i}"));
        assert_eq!(
            cells[16],
            status.to_string(),
            "row {i}: status is an integer"
        );
        count += 1;
    }
    assert_eq!(count, table.cloud.len());
}

#[test]
fn ascii_ply_round_trip() {
    let table = Table::new(200);
    let mut bytes = Vec::new();
    write_ply_to(&mut bytes, "t.ply", &table.columns(), PlyFormat::Ascii).unwrap();
    assert!(bytes.starts_with(b"ply\nformat ascii 1.0\n"));
    assert_same_cloud(
        &mls_io::read_ply(&bytes[..], "t.ply").unwrap(),
        &table.cloud,
    );
    check_text_rows(
        std::str::from_utf8(ply_body(&bytes)).unwrap(),
        &table,
        ' ',
        false,
    );
}

#[test]
fn csv_round_trip() {
    let table = Table::new(200);
    let mut bytes = Vec::new();
    write_csv_to(&mut bytes, "t.csv", &table.columns()).unwrap();
    assert_same_cloud(&read_csv(&bytes[..], "t.csv").unwrap(), &table.cloud);
    check_text_rows(std::str::from_utf8(&bytes).unwrap(), &table, ',', true);
}

/// Names for `x y z nx ny nz`, so that non-unit normals are read as normals.
fn named() -> ReadOptions {
    ReadOptions {
        columns: Some(ColumnNames::parse("x,y,z,nx,ny,nz").unwrap()),
    }
}

#[test]
fn xyz_round_trip() {
    let table = Table::new(200);
    let mut bytes = Vec::new();
    write_xyz_to(&mut bytes, "t.xyz", &table.cloud.columns()).unwrap();
    // The table's "normals" are hard values, not unit vectors: the `#` line naming every
    // column makes them normals all the same (named columns are taken as given), as
    // `--columns` does; without it they would not be.
    let read = read_xyz_with(&bytes[..], "t.xyz", &ReadOptions::default()).unwrap();
    assert!(read.notes.is_empty(), "{:?}", read.notes);
    assert_same_cloud(&read.cloud, &table.cloud);
    assert_same_cloud(
        &read_xyz_with(&bytes[..], "t.xyz", &named()).unwrap().cloud,
        &table.cloud,
    );
    let text = std::str::from_utf8(&bytes).unwrap();
    let rows = text.split_once('\n').unwrap().1;
    let read = read_xyz_with(rows.as_bytes(), "t.xyz", &ReadOptions::default()).unwrap();
    assert_eq!(read.cloud.normals, None);
    assert_eq!(read.notes.len(), 1, "{:?}", read.notes);
    let mut bytes = Vec::new();
    write_xyz_to(&mut bytes, "t.xyz", &table.columns()).unwrap();
    // The first line names the columns as a comment, which XYZ readers skip.
    let text = std::str::from_utf8(&bytes).unwrap();
    let (first, rows) = text.split_once('\n').unwrap();
    let names: Vec<&str> = table.columns().iter().map(|c| c.name).collect();
    assert_eq!(first, format!("# {}", names.join(" ")));
    check_text_rows(rows, &table, ' ', false);
}

#[test]
fn files_round_trip_through_every_extension() {
    let table = Table::new(50);
    let dir = tempfile::tempdir().unwrap();
    for (name, format) in [
        ("a.ply", PlyFormat::BinaryLittleEndian),
        ("b.PLY", PlyFormat::Ascii),
        ("c.csv", PlyFormat::default()),
        ("d.xyz", PlyFormat::default()),
        ("e.txt", PlyFormat::default()),
        ("f.pts", PlyFormat::default()),
        ("g.ASC", PlyFormat::default()),
    ] {
        let path = dir.path().join(name);
        // Text formats without a header are written with x y z nx ny nz only, to be read back
        // with those names (the table's normals are not unit vectors, and the names in the XYZ
        // writer's `#` line are not read back).
        let columns = if name.ends_with("ply") || name.ends_with("csv") {
            table.columns()
        } else {
            table.cloud.columns()
        };
        write_point_cloud(&path, &columns, format).unwrap();
        let read = if name.ends_with("ply") || name.ends_with("PLY") || name.ends_with("csv") {
            read_point_cloud(&path).unwrap()
        } else {
            read_point_cloud_with(&path, &named()).unwrap().cloud
        };
        assert_same_cloud(&read, &table.cloud);
    }
    let ascii = std::fs::read(dir.path().join("b.PLY")).unwrap();
    assert!(ascii.starts_with(b"ply\nformat ascii 1.0\n"));
}

#[test]
fn points_without_normals_round_trip() {
    let cloud = PointCloud {
        points: vec![[1.0, 2.0, 3.0]],
        normals: None,
        ..PointCloud::default()
    };
    let mut bytes = Vec::new();
    write_ply_to(
        &mut bytes,
        "p.ply",
        &cloud.columns(),
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    assert_eq!(mls_io::read_ply(&bytes[..], "p.ply").unwrap(), cloud);
    // No rows at all is a valid, empty file.
    let empty = PointCloud::default();
    let mut bytes = Vec::new();
    write_csv_to(&mut bytes, "e.csv", &empty.columns()).unwrap();
    assert_eq!(bytes, b"//x,y,z\n");
    assert_eq!(read_csv(&bytes[..], "e.csv").unwrap(), empty);
}

#[test]
fn invalid_tables_are_rejected_before_writing() {
    let a = [1.0, 2.0];
    let b = [1.0];
    let s = [0, 1];
    let mut sink = Vec::new();
    let cases: [(Vec<Column<'_>>, &[&str]); 5] = [
        (vec![], &["no columns"]),
        (
            vec![Column::f64("x", &a), Column::f64("y", &b)],
            &["\"y\" has 1 rows", "\"x\" has 2"],
        ),
        (
            vec![Column::f64("x", &a), Column::i32("x", &s)],
            &["duplicate column name \"x\""],
        ),
        (
            vec![Column::f64("my x", &a)],
            &["invalid column name \"my x\""],
        ),
        (
            vec![Column::f64("", &a)],
            &["invalid column name \"\"", "empty"],
        ),
    ];
    for (columns, parts) in cases {
        let err = write_csv_to(&mut sink, "t.csv", &columns).unwrap_err();
        assert_message(&err, "t.csv", parts);
    }
    assert!(sink.is_empty());
    let err = write_point_cloud(
        "out.obj".as_ref(),
        &[Column::f64("x", &a)],
        PlyFormat::Ascii,
    )
    .unwrap_err();
    assert!(
        matches!(err, WriteError::UnknownExtension { .. }),
        "{err:?}"
    );
    assert_message(&err, "out.obj", &["\".obj\""]);
}

/// A result table with a failed point (NaN normal, as `curvature` writes it) reads back in
/// every text and PLY format with the normals as attributes, NaN kept, while the usual reader
/// refuses the NaN normal.
#[test]
fn normals_as_attributes_reads_nan_normals_of_failed_points() {
    let dir = tempfile::tempdir().unwrap();
    let points = vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]];
    let normals = vec![[0.0, 0.0, 1.0], [f64::NAN; 3]];
    let mean = vec![0.5, f64::NAN];
    let status = vec![0, 5];
    let columns = vec![
        Column::component("x", &points, mls_io::Axis::X),
        Column::component("y", &points, mls_io::Axis::Y),
        Column::component("z", &points, mls_io::Axis::Z),
        Column::component("nx", &normals, mls_io::Axis::X),
        Column::component("ny", &normals, mls_io::Axis::Y),
        Column::component("nz", &normals, mls_io::Axis::Z),
        Column::f64("mean", &mean),
        Column::i32("status", &status),
    ];
    // An XYZ file has its names in a comment only: they are given.
    let named = ReadOptions {
        columns: Some(ColumnNames::parse("x,y,z,nx,ny,nz,mean,status").unwrap()),
    };
    for (file, options) in [
        ("r.ply", ReadOptions::default()),
        ("r.csv", ReadOptions::default()),
        ("r.xyz", named),
    ] {
        let path = dir.path().join(file);
        write_point_cloud(&path, &columns, PlyFormat::BinaryLittleEndian).unwrap();
        // A headerless XYZ file already takes `NaN NaN NaN` for a missing normal.
        if file != "r.xyz" {
            assert!(read_point_cloud(&path).is_err(), "{file}: NaN refused");
        }
        let cloud = mls_io::read_point_cloud_normals_as_attributes(&path, &options).unwrap();
        assert_eq!(cloud.points, points, "{file}");
        assert_eq!(cloud.normals, None, "{file}");
        let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["nx", "ny", "nz", "mean", "status"], "{file}");
        let value = |name: &str, i: usize| {
            let a = cloud.attributes.iter().find(|a| a.name == name).unwrap();
            a.data.f64_at(i).unwrap()
        };
        assert_eq!((value("nz", 0), value("mean", 0)), (1.0, 0.5), "{file}");
        assert!(
            value("nx", 1).is_nan() && value("mean", 1).is_nan(),
            "{file}"
        );
        assert_eq!(value("status", 1), 5.0, "{file}");
    }
}
