//! Input attributes carried through `curvature`, `normals` and `project` (issue 14): PLY
//! colour and intensity, text columns that are not normals, LAS dimensions, scale and offset.

use std::fmt::Write as _;
use std::path::Path;

use las::point::{Classification, Format};
use las::{Builder, Color, Point, Reader, Transform, Vector, Version, Writer};
use mls_io::{AttributeData, PointCloud};

use crate::common::{JET_HEADER, Table, median, mlscurv, run_ok};

/// Points on the unit sphere used here: few, so each run is quick.
const N: usize = 2_000;

fn unit_sphere() -> Vec<[f64; 3]> {
    mls_shapes::points(&mls_shapes::fibonacci_sphere(N, 1.0))
}

/// Colour of point `i`, as a 0-255 triple.
fn rgb(i: usize) -> [u8; 3] {
    [(i % 256) as u8, (i * 7 % 256) as u8, (255 - i % 256) as u8]
}

/// An intensity for point `i` that only a bit-exact copy reproduces.
fn intensity(i: usize) -> f32 {
    (i as f32 + 0.1).sqrt() * 1.000_000_1
}

/// A binary PLY of the sphere written by hand: float x y z, uchar red green blue, float
/// intensity, and `extra` float properties set to 0.5.
fn write_coloured_ply(path: &Path, extra: &[&str]) {
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {N}\nproperty float x\n\
         property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nproperty float intensity\n"
    );
    for name in extra {
        let _ = writeln!(header, "property float {name}");
    }
    header.push_str("end_header\n");
    let mut bytes = header.into_bytes();
    for (i, p) in unit_sphere().iter().enumerate() {
        for c in p {
            bytes.extend_from_slice(&(*c as f32).to_le_bytes());
        }
        bytes.extend_from_slice(&rgb(i));
        bytes.extend_from_slice(&intensity(i).to_le_bytes());
        for _ in extra {
            bytes.extend_from_slice(&0.5f32.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// The attribute `name` of a cloud.
fn attribute<'c>(cloud: &'c PointCloud, name: &str) -> &'c AttributeData {
    &cloud
        .attributes
        .iter()
        .find(|a| a.name == name)
        .unwrap_or_else(|| panic!("no attribute {name}"))
        .data
}

fn f64_column(cloud: &PointCloud, name: &str) -> Vec<f64> {
    match attribute(cloud, name) {
        AttributeData::F64(v) => v.clone(),
        other => panic!("{name} is not float64: {other:?}"),
    }
}

#[test]
fn ply_colour_and_intensity_survive_curvature_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("coloured.ply");
    let output = dir.path().join("out.ply");
    write_coloured_ply(&input, &[]);
    let run = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .arg("--quiet"),
    );
    assert!(run.stderr.is_empty(), "{}", run.stderr);
    let bytes = std::fs::read(&output).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(1200)]).into_owned();
    // After the geometry, before the computed columns, in input order and type.
    assert!(
        header.contains(
            "property double nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
             property float intensity\nproperty double scalar_k1\n"
        ),
        "{header}"
    );
    let out = mls_io::read_ply(&bytes[..], "out.ply").unwrap();
    let colours: Vec<AttributeData> = ["red", "green", "blue"]
        .iter()
        .map(|n| attribute(&out, n).clone())
        .collect();
    for (k, colour) in colours.iter().enumerate() {
        assert_eq!(
            *colour,
            AttributeData::U8((0..N).map(|i| rgb(i)[k]).collect()),
            "channel {k}"
        );
    }
    let AttributeData::F32(got) = attribute(&out, "intensity") else {
        panic!("intensity is not float32");
    };
    let got: Vec<u32> = got.iter().map(|v| v.to_bits()).collect();
    let expected: Vec<u32> = (0..N).map(|i| intensity(i).to_bits()).collect();
    assert_eq!(got, expected);
    // The curvature columns are those of the unit sphere.
    for name in ["k1", "k2", "mean"] {
        let m = median(&f64_column(&out, name));
        assert!((m - 1.0).abs() < 2e-3, "median {name} {m}");
    }
    let AttributeData::I32(status) = attribute(&out, "status") else {
        panic!("status is not int32");
    };
    assert!(status.iter().all(|&s| s == 0));
}

#[test]
fn an_earlier_ply_output_is_read_by_its_column_names_and_quality_is_renamed() {
    // As mlscurv writes a curvature PLY: `scalar_k1`, and `quality` repeating `mean`.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("earlier.ply");
    write_coloured_ply(&input, &["scalar_k1", "quality"]);
    let csv = dir.path().join("out.csv");
    let run = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&csv)
            .arg("--quiet"),
    );
    assert_eq!(
        run.stderr,
        format!(
            "mlscurv: note: {}: the output has columns of these names of its own, so the \
             input's attributes are written as: `k1` as `k1_in`, `quality` as `quality_in`\n",
            input.display()
        )
    );
    let table = Table::parse_csv(&std::fs::read_to_string(&csv).unwrap());
    let expected = JET_HEADER.replace("nz,k1,", "nz,red,green,blue,intensity,k1_in,quality_in,k1,");
    assert_eq!(table.header.join(","), expected);
    assert!(table.column("quality_in").iter().all(|&v| v == 0.5));
    // As PLY: each under `scalar_`, and this run's mean as `quality`.
    let ply = dir.path().join("out.ply");
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&ply)
            .args(["--quiet", "--ascii"]),
    );
    let text = std::fs::read_to_string(&ply).unwrap();
    assert!(
        text.contains(
            "property float intensity\nproperty float scalar_k1_in\n\
             property float scalar_quality_in\nproperty double scalar_k1\n"
        ),
        "{text:.900}"
    );
    assert!(text.contains("property int scalar_status\nproperty double quality\nend_header\n"));
    let table = Table::parse_ascii_ply(&text);
    assert_eq!(table.header.join(","), expected);
}

#[test]
fn clashing_names_are_renamed_with_a_note_and_no_attributes_drops_them() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("k.ply");
    let output = dir.path().join("out.csv");
    write_coloured_ply(&input, &["k1", "k1_in"]);
    let run = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .arg("--quiet"),
    );
    assert_eq!(
        run.stderr,
        format!(
            "mlscurv: note: {}: the output has columns of these names of its own, so the \
             input's attributes are written as: `k1` as `k1_in2`\n",
            input.display()
        )
    );
    let table = Table::parse_csv(&std::fs::read_to_string(&output).unwrap());
    let expected = JET_HEADER.replace("nz,k1,", "nz,red,green,blue,intensity,k1_in2,k1_in,k1,");
    assert_eq!(table.header.join(","), expected);
    assert!(table.column("k1_in2").iter().all(|&v| v == 0.5));
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .args(["--quiet", "--no-attributes"]),
    );
    let table = Table::parse_csv(&std::fs::read_to_string(&output).unwrap());
    assert_eq!(table.header.join(","), JET_HEADER);
    // `project` carries them too.
    run_ok(
        mlscurv()
            .arg("project")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .arg("--quiet"),
    );
    let table = Table::parse_csv(&std::fs::read_to_string(&output).unwrap());
    assert_eq!(
        table.header.join(","),
        "x,y,z,nx,ny,nz,red,green,blue,intensity,k1,k1_in,status"
    );
    // A float32 written as text is its shortest decimal, which parses back to the same bits.
    let got: Vec<u32> = table
        .column("intensity")
        .iter()
        .map(|&v| (v as f32).to_bits())
        .collect();
    let want: Vec<u32> = (0..N).map(|i| intensity(i).to_bits()).collect();
    assert_eq!(got, want);
}

#[test]
fn text_colour_columns_are_carried_not_taken_as_normals() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("rgb.txt");
    let mut text = String::new();
    for (i, p) in unit_sphere().iter().enumerate() {
        let [r, g, b] = rgb(i);
        let _ = writeln!(text, "{} {} {} {r} {g} {b}", p[0], p[1], p[2]);
    }
    std::fs::write(&input, text).unwrap();
    for (columns, names) in [
        (None, ["col4", "col5", "col6"]),
        (Some("x,y,z,r,g,b"), ["r", "g", "b"]),
    ] {
        let output = dir.path().join("out.csv");
        let mut cmd = mlscurv();
        cmd.arg("curvature").arg(&input).arg("-o").arg(&output);
        if let Some(c) = columns {
            cmd.args(["--columns", c]);
        }
        let run = run_ok(&mut cmd);
        assert!(
            run.stderr.contains("normals         estimated"),
            "{}",
            run.stderr
        );
        if columns.is_none() {
            assert!(
                run.stderr
                    .contains("they are carried as attributes col4 col5 col6"),
                "{}",
                run.stderr
            );
        }
        let table = Table::parse_csv(&std::fs::read_to_string(&output).unwrap());
        let expected = JET_HEADER.replace("nz,k1,", &format!("nz,{},k1,", names.join(",")));
        assert_eq!(table.header.join(","), expected);
        for (k, name) in names.iter().enumerate() {
            let got = table.column(name);
            let want: Vec<f64> = (0..N).map(|i| f64::from(rgb(i)[k])).collect();
            assert_eq!(got, want, "{name}");
        }
        let m = median(&table.column("mean"));
        assert!((m - 1.0).abs() < 2e-3, "median mean {m}");
    }
    // `normals` to XYZ keeps the normals in columns 4-6, where a reader looks for them, and
    // the colour after them as integers.
    let output = dir.path().join("normals.xyz");
    run_ok(
        mlscurv()
            .arg("normals")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .args(["--columns", "x,y,z,r,g,b", "--quiet"]),
    );
    let written = std::fs::read_to_string(&output).unwrap();
    let mut lines = written.lines();
    assert_eq!(lines.next(), Some("# x y z nx ny nz r g b"));
    let first: Vec<&str> = lines.next().unwrap().split(' ').collect();
    assert_eq!(first[6..], ["0", "0", "255"]);
}

/// Radius and centre of the LAS sphere, far from the origin as georeferenced data is.
const R: f64 = 2.0;
const CENTRE: [f64; 3] = [350_000.0, 5_600_000.0, 120.0];

fn read_las(path: &Path) -> (las::Header, Vec<Point>) {
    let mut reader = Reader::from_path(path).unwrap();
    let points = reader
        .read_all()
        .unwrap()
        .points()
        .map(Result::unwrap)
        .collect();
    (reader.header().clone(), points)
}

#[test]
fn las_dimensions_scale_and_offset_survive_curvature() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scan.las");
    let output = dir.path().join("out.laz");
    let mut builder = Builder::from(Version::new(1, 2));
    builder.point_format = Format::new(3).unwrap();
    let t = |offset| Transform {
        scale: 1e-5,
        offset,
    };
    builder.transforms = Vector {
        x: t(CENTRE[0] - 10.0),
        y: t(CENTRE[1] + 3.0),
        z: t(100.0),
    };
    let mut writer = Writer::new(
        std::io::BufWriter::new(std::fs::File::create(&input).unwrap()),
        builder.into_header().unwrap(),
    )
    .unwrap();
    let sphere = mls_shapes::points(&mls_shapes::fibonacci_sphere(N, R));
    for (i, p) in sphere.iter().enumerate() {
        writer
            .write_point(Point {
                x: CENTRE[0] + p[0],
                y: CENTRE[1] + p[1],
                z: CENTRE[2] + p[2],
                intensity: (i * 31 % 65536) as u16,
                return_number: (i % 2 + 1) as u8,
                number_of_returns: 2,
                classification: Classification::new([2, 5, 6][i % 3]).unwrap(),
                user_data: (i % 200) as u8,
                point_source_id: 7,
                gps_time: Some(3.0e5 + i as f64 * 1e-4),
                color: Some(Color {
                    red: (i * 257 % 65536) as u16,
                    green: 1000,
                    blue: 65535 - i as u16,
                }),
                ..Point::default()
            })
            .unwrap();
    }
    writer.close().unwrap();
    drop(writer);

    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .arg("--quiet"),
    );
    let (in_header, in_points) = read_las(&input);
    let (header, points) = read_las(&output);
    assert_eq!(header.point_format().to_u8().unwrap(), 3);
    assert!(header.point_format().is_compressed);
    assert_eq!(header.transforms(), in_header.transforms());
    assert_eq!(points.len(), N);
    let record = usize::from(header.point_format().extra_bytes);
    assert_eq!(record, 8 * 15 + 4, "nx .. k2_sd as f64, status as i32");
    let k1_at = 8 * 3;
    let mut k1 = Vec::with_capacity(N);
    for (got, want) in points.iter().zip(&in_points) {
        // Every dimension as it was, coordinates on the same grid steps.
        let mut got = got.clone();
        k1.push(f64::from_le_bytes(
            got.extra_bytes[k1_at..k1_at + 8].try_into().unwrap(),
        ));
        got.extra_bytes.clear();
        assert_eq!(&got, want);
    }
    let m = median(&k1);
    assert!((m * R - 1.0).abs() < 1e-3, "median k1 {m}");

    // Without attributes: the layout of a cloud of points only, as before.
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .args(["--quiet", "--no-attributes"]),
    );
    let (header, points) = read_las(&output);
    assert_eq!(header.point_format().to_u8().unwrap(), 6);
    assert_eq!(points[1].intensity, 0);
}

#[test]
fn an_attribute_name_too_long_for_las_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("long.csv");
    let name = "reflectance_after_atmospheric_correction";
    let mut text = format!("x,y,z,{name}\n");
    for (i, p) in unit_sphere().iter().enumerate() {
        let _ = writeln!(text, "{},{},{},{i}", p[0], p[1], p[2]);
    }
    std::fs::write(&input, text).unwrap();
    let output = dir.path().join("out.las");
    let r = crate::common::run(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output),
    );
    crate::common::assert_one_line_error(
        &r,
        "long.csv",
        &[
            &format!("attribute `{name}` has a name of 40 bytes"),
            "--no-attributes",
        ],
    );
    assert!(!output.exists());
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .args(["--quiet", "--no-attributes"]),
    );
}
