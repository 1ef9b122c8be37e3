//! LAS and LAZ: tables written by mls-io and read back with the `las` crate itself, clouds
//! written by the `las` crate and read by mls-io, and bad files.

use std::path::Path;

use las::point::Format;
use las::{Builder, Point, Reader, Transform, Vector, Version, Writer};
use mls_io::{
    Axis, Column, FileFormat, PlyFormat, ReadError, read_point_cloud, read_point_cloud_as,
    read_point_cloud_from, write_point_cloud, write_point_cloud_to,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{assert_message, seeds};

const ROWS: usize = 257;

/// A generated table: points in a box far from the origin (as georeferenced data is), two
/// float columns with values of every magnitude, and an integer status.
struct Table {
    points: Vec<[f64; 3]>,
    k1: Vec<f64>,
    k1_sd: Vec<f64>,
    status: Vec<i32>,
}

impl Table {
    fn new() -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seeds::LAS);
        let points = (0..ROWS)
            .map(|_| {
                [
                    500_000.0 + rng.random_range(0.0..300.0),
                    4_000_000.0 + rng.random_range(0.0..200.0),
                    rng.random_range(-20.0..80.0),
                ]
            })
            .collect();
        let k1 = (0..ROWS)
            .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-300..300)))
            .collect();
        let k1_sd = (0..ROWS).map(|_| rng.random::<f64>()).collect();
        let status = (0..ROWS).map(|_| rng.random_range(-5..5)).collect();
        Self {
            points,
            k1,
            k1_sd,
            status,
        }
    }

    fn columns(&self) -> Vec<Column<'_>> {
        self.rows(0..ROWS)
    }

    /// The columns of rows `r`.
    fn rows(&self, r: std::ops::Range<usize>) -> Vec<Column<'_>> {
        vec![
            Column::component("x", &self.points[r.clone()], Axis::X),
            Column::component("y", &self.points[r.clone()], Axis::Y),
            Column::component("z", &self.points[r.clone()], Axis::Z),
            Column::f64("k1", &self.k1[r.clone()]),
            Column::f64("k1_sd", &self.k1_sd[r.clone()]),
            Column::i32("status", &self.status[r]),
        ]
    }
}

/// The descriptions of the Extra Bytes VLR's descriptors (the last 32 bytes of each).
fn extra_bytes_descriptions(reader: &Reader) -> Vec<String> {
    let vlr = reader
        .header()
        .all_vlrs()
        .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
        .expect("no Extra Bytes VLR");
    vlr.data
        .chunks(192)
        .map(|d| {
            let text = &d[160..192];
            let end = text.iter().position(|&b| b == 0).unwrap_or(32);
            String::from_utf8(text[..end].to_vec()).unwrap()
        })
        .collect()
}

#[test]
fn curvature_columns_carry_descriptions() {
    let table = Table::new();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("described.las");
    mls_io::write_point_cloud(
        &path,
        &table.columns(),
        mls_io::PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    let reader = Reader::from_path(&path).unwrap();
    assert_eq!(
        extra_bytes_descriptions(&reader),
        [
            "larger principal curvature",
            "predicted error of k1",
            "0 ok; codes: mlscurv --help"
        ]
    );
}

/// The names and data types of the Extra Bytes VLR's descriptors.
fn extra_bytes_schema(reader: &Reader) -> Vec<(String, u8)> {
    let vlr = reader
        .header()
        .all_vlrs()
        .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
        .expect("no Extra Bytes VLR");
    assert_eq!(vlr.data.len() % 192, 0);
    vlr.data
        .chunks(192)
        .map(|d| {
            let name = &d[4..36];
            let end = name.iter().position(|&b| b == 0).unwrap_or(32);
            (String::from_utf8(name[..end].to_vec()).unwrap(), d[2])
        })
        .collect()
}

fn check_written(path: &Path, table: &Table, compressed: bool) {
    let mut reader = Reader::from_path(path).unwrap();
    let header = reader.header().clone();
    assert_eq!(header.number_of_points(), ROWS as u64);
    assert_eq!(header.version(), Version::new(1, 4));
    assert_eq!(header.point_format().is_compressed, compressed);
    assert_eq!(header.point_format().extra_bytes, 8 + 8 + 4);
    assert_eq!(
        extra_bytes_schema(&reader),
        [
            ("k1".to_owned(), 10),
            ("k1_sd".to_owned(), 10),
            ("status".to_owned(), 6)
        ]
    );
    // The documented grid: a power of ten between 1e-8 and 1e-7 of the largest extent (300).
    let scale = header.transforms().x.scale;
    assert!((1e-6..=1e-5).contains(&scale), "scale {scale}");
    assert_eq!(scale, 1e-5);
    let points: Vec<Point> = reader
        .read_all()
        .unwrap()
        .points()
        .map(Result::unwrap)
        .collect();
    assert_eq!(points.len(), ROWS);
    for (i, p) in points.iter().enumerate() {
        let [x, y, z] = table.points[i];
        for (got, want) in [(p.x, x), (p.y, y), (p.z, z)] {
            // Half a step, and the rounding of offset + scale × n in f64.
            assert!(
                (got - want).abs() <= 0.5 * scale * (1.0 + 1e-6),
                "row {i}: {got} vs {want}"
            );
        }
        let e = &p.extra_bytes;
        assert_eq!(e.len(), 20);
        let k1 = f64::from_le_bytes(e[0..8].try_into().unwrap());
        let k1_sd = f64::from_le_bytes(e[8..16].try_into().unwrap());
        let status = i32::from_le_bytes(e[16..20].try_into().unwrap());
        assert_eq!(k1.to_bits(), table.k1[i].to_bits(), "row {i} k1");
        assert_eq!(k1_sd.to_bits(), table.k1_sd[i].to_bits(), "row {i} k1_sd");
        assert_eq!(status, table.status[i], "row {i} status");
    }
}

#[test]
fn las_and_laz_round_trip_through_the_las_crate() {
    let dir = tempfile::tempdir().unwrap();
    let table = Table::new();
    for (name, compressed) in [("out.las", false), ("out.LAZ", true)] {
        let path = dir.path().join(name);
        write_point_cloud(&path, &table.columns(), PlyFormat::default()).unwrap();
        check_written(&path, &table, compressed);
        // And mls-io reads its own output back: the points on the grid, no normals.
        let cloud = read_point_cloud(&path).unwrap();
        assert_eq!(cloud.len(), ROWS);
        assert!(cloud.normals.is_none());
        for (got, want) in cloud.points.iter().zip(&table.points) {
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() <= 0.51e-5, "{got:?} vs {want:?}");
            }
        }
    }
    // Only the two outputs: the temporary files are gone.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn las_and_laz_to_a_stream_read_back() {
    let table = Table::new();
    for format in [FileFormat::Las, FileFormat::Laz] {
        let mut bytes = Vec::new();
        write_point_cloud_to(
            &mut bytes,
            "-",
            format,
            &table.columns(),
            PlyFormat::default(),
        )
        .unwrap();
        assert!(bytes.starts_with(b"LASF"));
        let cloud = read_point_cloud_from(&bytes[..], "-", format).unwrap();
        assert_eq!(cloud.len(), ROWS);
        for (got, want) in cloud.points.iter().zip(&table.points) {
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() <= 0.51e-5, "{got:?} vs {want:?}");
            }
        }
    }
}

/// A LAS file written by the `las` crate alone, in a pre-1.4 point format with colour.
fn write_with_las_crate(path: &Path, points: &[[f64; 3]], compressed: bool) {
    let mut builder = Builder::from(Version::new(1, 2));
    let mut format = Format::new(3).unwrap();
    format.is_compressed = compressed;
    builder.point_format = format;
    let t = Transform {
        scale: 0.001,
        offset: 100.0,
    };
    builder.transforms = Vector { x: t, y: t, z: t };
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut writer = Writer::new(file, builder.into_header().unwrap()).unwrap();
    for &[x, y, z] in points {
        writer
            .write_point(Point {
                x,
                y,
                z,
                gps_time: Some(1.0),
                color: Some(las::Color::new(1, 2, 3)),
                ..Point::default()
            })
            .unwrap();
    }
    writer.close().unwrap();
}

#[test]
fn mls_io_reads_las_and_laz_written_by_the_las_crate() {
    let dir = tempfile::tempdir().unwrap();
    let points: Vec<[f64; 3]> = (0..1000)
        .map(|i| {
            let i = f64::from(i);
            [100.0 + i * 0.001, 101.5 - i * 0.002, 99.0 + i * 0.003]
        })
        .collect();
    for (name, compressed) in [("in.las", false), ("in.laz", true)] {
        let path = dir.path().join(name);
        write_with_las_crate(&path, &points, compressed);
        let cloud = read_point_cloud(&path).unwrap();
        assert!(cloud.normals.is_none());
        assert_eq!(cloud.len(), points.len());
        for (got, want) in cloud.points.iter().zip(&points) {
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() < 1e-9, "{got:?} vs {want:?}");
            }
        }
        // The same through a stream (standard input), and whatever the extension.
        let bytes = std::fs::read(&path).unwrap();
        let streamed = read_point_cloud_from(&bytes[..], "-", FileFormat::Las).unwrap();
        assert_eq!(streamed, cloud);
        let renamed = dir.path().join(format!("{name}.bin"));
        std::fs::copy(&path, &renamed).unwrap();
        assert_eq!(
            read_point_cloud_as(&renamed, FileFormat::Las).unwrap(),
            cloud
        );
    }
}

#[test]
fn a_file_that_is_not_las_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fake.las");
    std::fs::write(&path, "x y z\n1 2 3\n").unwrap();
    let err = read_point_cloud(&path).unwrap_err();
    assert!(matches!(err, ReadError::Las { .. }), "{err:?}");
    assert_message(&err, &path.display().to_string(), &["not a LAS file"]);
    // A file shorter than the LAS header.
    std::fs::write(&path, b"LASF").unwrap();
    let err = read_point_cloud(&path).unwrap_err();
    assert_message(&err, &path.display().to_string(), &["truncated"]);
}

#[test]
fn truncated_point_data_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let points: Vec<[f64; 3]> = (0..500).map(|i| [f64::from(i), 0.0, 1.0]).collect();
    for (name, compressed) in [("cut.las", false), ("cut.laz", true)] {
        let path = dir.path().join(name);
        write_with_las_crate(&path, &points, compressed);
        let bytes = std::fs::read(&path).unwrap();
        let cut = bytes.len() * 2 / 3;
        std::fs::write(&path, &bytes[..cut]).unwrap();
        let err = read_point_cloud(&path).unwrap_err();
        assert!(matches!(err, ReadError::Las { .. }), "{err:?}");
        let message = assert_message(&err, &path.display().to_string(), &[]);
        assert!(message.contains("truncated"), "{message}");
        if !compressed {
            assert!(message.contains("500 points"), "{message}");
            assert!(
                message.contains(&format!("ends at byte {cut}")),
                "{message}"
            );
            // The first point cut short, from the header's offset and record length.
            let start = u32::from_le_bytes(bytes[96..100].try_into().unwrap()) as usize;
            let record = u16::from_le_bytes(bytes[105..107].try_into().unwrap()) as usize;
            let whole = (cut - start) / record;
            assert!(whole < 500, "{whole}");
            assert!(
                message.contains(&format!("within point {whole} ")),
                "{message}"
            );
        }
    }
}

/// Corrupt compressed data: an error or a wrong cloud, never a crash. (LASzip has no
/// checksums, so garbage may decode to points.)
#[test]
fn corrupt_laz_does_not_crash() {
    let dir = tempfile::tempdir().unwrap();
    let points: Vec<[f64; 3]> = (0..500).map(|i| [f64::from(i), 0.0, 1.0]).collect();
    let path = dir.path().join("bad.laz");
    write_with_las_crate(&path, &points, true);
    let mut bytes = std::fs::read(&path).unwrap();
    // In the compressed points: after the offset to the point data (header bytes 96..100)
    // and the 8-byte offset of the chunk table that starts them.
    let data = u32::from_le_bytes(bytes[96..100].try_into().unwrap()) as usize;
    let start = data + 8 + 16;
    for b in &mut bytes[start..start + 64] {
        *b = b.wrapping_mul(31).wrapping_add(7);
    }
    std::fs::write(&path, &bytes).unwrap();
    if let Err(err) = read_point_cloud(&path) {
        let message = assert_message(&err, &path.display().to_string(), &[]);
        eprintln!("{message}");
    }
}

#[test]
fn las_output_needs_finite_x_y_z() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.las");
    let xs = [1.0, 2.0];
    let err = write_point_cloud(
        &path,
        &[Column::f64("x", &xs), Column::f64("y", &xs)],
        PlyFormat::default(),
    )
    .unwrap_err();
    assert_message(&err, &path.display().to_string(), &["\"z\""]);
    let bad = [1.0, f64::NAN];
    let err = write_point_cloud(
        &path,
        &[
            Column::f64("x", &xs),
            Column::f64("y", &xs),
            Column::f64("z", &bad),
        ],
        PlyFormat::default(),
    )
    .unwrap_err();
    assert_message(&err, &path.display().to_string(), &["\"z\" row 1"]);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// Normals written as the `nx ny nz` extra bytes (what `mlscurv normals -o x.las` writes) are
/// read back as the cloud's normals, bit for bit.
#[test]
fn normals_written_as_extra_bytes_are_read_back() {
    let table = Table::new();
    let normals = radial_normals(&table.points);
    let mut columns = table.columns();
    columns.insert(3, Column::component("nx", &normals, Axis::X));
    columns.insert(4, Column::component("ny", &normals, Axis::Y));
    columns.insert(5, Column::component("nz", &normals, Axis::Z));
    let dir = tempfile::tempdir().unwrap();
    for name in ["normals.las", "normals.laz"] {
        let path = dir.path().join(name);
        mls_io::write_point_cloud(&path, &columns, mls_io::PlyFormat::BinaryLittleEndian).unwrap();
        let cloud = mls_io::read_point_cloud(&path).unwrap();
        assert_eq!(cloud.normals.as_deref(), Some(&normals[..]), "{name}");
    }
}

/// PDAL writes the normals of `filters.normal` as the extra bytes `NormalX`, `NormalY`,
/// `NormalZ` (with `extra_dims`): they are the cloud's normals too, and not also carried as
/// attributes; `nx ny nz` win when a file has both.
#[test]
fn pdal_normal_dimensions_are_normals() {
    let table = Table::new();
    let normals = radial_normals(&table.points);
    let flipped: Vec<[f64; 3]> = normals.iter().map(|n| n.map(|c| -c)).collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pdal.las");
    let mut columns = table.columns();
    let attributes_before = {
        mls_io::write_point_cloud(&path, &columns, mls_io::PlyFormat::BinaryLittleEndian).unwrap();
        mls_io::read_point_cloud(&path).unwrap().attributes.len()
    };
    columns.push(Column::component("NormalX", &normals, Axis::X));
    columns.push(Column::component("NormalY", &normals, Axis::Y));
    columns.push(Column::component("NormalZ", &normals, Axis::Z));
    mls_io::write_point_cloud(&path, &columns, mls_io::PlyFormat::BinaryLittleEndian).unwrap();
    let cloud = mls_io::read_point_cloud(&path).unwrap();
    assert_eq!(cloud.normals.as_deref(), Some(&normals[..]));
    assert_eq!(cloud.attributes.len(), attributes_before);
    // Both spellings: `nx ny nz` are the normals, the others stay attributes.
    columns.push(Column::component("nx", &flipped, Axis::X));
    columns.push(Column::component("ny", &flipped, Axis::Y));
    columns.push(Column::component("nz", &flipped, Axis::Z));
    mls_io::write_point_cloud(&path, &columns, mls_io::PlyFormat::BinaryLittleEndian).unwrap();
    let cloud = mls_io::read_point_cloud(&path).unwrap();
    assert_eq!(cloud.normals.as_deref(), Some(&flipped[..]));
    assert_eq!(cloud.attributes.len(), attributes_before + 3);
}

/// The unit vector from the origin to each point, as test normals.
fn radial_normals(points: &[[f64; 3]]) -> Vec<[f64; 3]> {
    points
        .iter()
        .map(|p| {
            let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            [p[0] / len, p[1] / len, p[2] / len]
        })
        .collect()
}

/// The days from 1970-01-01 to now (UTC), as (year, day of year), counted year by year: an
/// independent check of the header's date.
fn today() -> (u16, u16) {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs();
    let mut days = seconds / 86_400;
    let mut year = 1970;
    loop {
        let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
        let length = if leap { 366 } else { 365 };
        if days < length {
            return (year as u16, days as u16 + 1);
        }
        days -= length;
        year += 1;
    }
}

fn u16_at(bytes: &[u8], at: usize) -> u16 {
    u16::from_le_bytes(bytes[at..at + 2].try_into().unwrap())
}

fn f64_at(bytes: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap())
}

/// The header fields LAS 1.4 R15 fixes, read from the bytes: for point format 6 the legacy
/// point counts (offset 107, and the five by return after it) are 0 and the 64-bit count
/// (offset 247) holds the number; max and min X, Y, Z (offset 179) are those of the stored
/// coordinates, as a reader computes them; the creation date (offset 90) is today's.
#[track_caller]
fn check_header(bytes: &[u8], rows: usize, before: (u16, u16)) {
    assert_eq!(&bytes[..4], b"LASF");
    assert_eq!((bytes[24], bytes[25]), (1, 4), "version");
    assert_eq!(bytes[104] & 0x3f, 6, "point format");
    assert_eq!(&bytes[107..131], &[0u8; 24], "legacy point counts");
    assert_eq!(
        u64::from_le_bytes(bytes[247..255].try_into().unwrap()),
        rows as u64
    );
    // Every point is a first return of one.
    assert_eq!(
        u64::from_le_bytes(bytes[255..263].try_into().unwrap()),
        rows as u64
    );
    let points: Vec<Point> = Reader::new(std::io::Cursor::new(bytes.to_vec()))
        .unwrap()
        .read_all()
        .unwrap()
        .points()
        .map(Result::unwrap)
        .collect();
    assert_eq!(points.len(), rows);
    let axes: [fn(&Point) -> f64; 3] = [|p| p.x, |p| p.y, |p| p.z];
    for (axis, coordinate) in axes.iter().enumerate() {
        let max = points.iter().map(coordinate).fold(f64::MIN, f64::max);
        let min = points.iter().map(coordinate).fold(f64::MAX, f64::min);
        assert_eq!(f64_at(bytes, 179 + 16 * axis), max, "max of axis {axis}");
        assert_eq!(f64_at(bytes, 187 + 16 * axis), min, "min of axis {axis}");
    }
    let date = (u16_at(bytes, 92), u16_at(bytes, 90));
    // Written between `before` and now, which may straddle midnight.
    assert!(date == before || date == today(), "{date:?}");
}

#[test]
fn the_header_follows_las_1_4() {
    let dir = tempfile::tempdir().unwrap();
    let table = Table::new();
    let before = today();
    for (name, format) in [("h.las", FileFormat::Las), ("h.laz", FileFormat::Laz)] {
        // A file (written through a seekable handle) and a stream (through memory).
        let path = dir.path().join(name);
        write_point_cloud(&path, &table.columns(), PlyFormat::default()).unwrap();
        check_header(&std::fs::read(&path).unwrap(), ROWS, before);
        let mut bytes = Vec::new();
        write_point_cloud_to(
            &mut bytes,
            "-",
            format,
            &table.columns(),
            PlyFormat::default(),
        )
        .unwrap();
        check_header(&bytes, ROWS, before);
        // In chunks (a tiled run's output), with the first file's layout.
        let template = mls_io::LasReader::open(&path).unwrap().template().clone();
        let chunked = dir.path().join(format!("chunks-{name}"));
        mls_io::write_las_chunks::<mls_io::WriteError>(
            &chunked,
            format == FileFormat::Laz,
            &template,
            |sink| {
                for part in [0..100, 100..ROWS] {
                    sink.write(&table.rows(part))?;
                }
                Ok(())
            },
        )
        .unwrap();
        check_header(&std::fs::read(&chunked).unwrap(), ROWS, before);
    }
}
