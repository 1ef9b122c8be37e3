//! `curvature in.las -o out.laz` end to end: a sphere written with the `las` crate, the
//! output read back with it.

use las::point::Format;
use las::{Builder, Point, Reader, Transform, Vector, Version, Writer};

use crate::common::{median, mlscurv, run_ok};

/// Radius of the sphere, and its centre far from the origin as in georeferenced data.
const R: f64 = 2.0;
const CENTRE: [f64; 3] = [350_000.0, 5_600_000.0, 120.0];
const N: usize = 2_000;

/// The names of the Extra Bytes VLR's descriptors.
fn extra_names(reader: &Reader) -> Vec<String> {
    let vlr = reader
        .header()
        .all_vlrs()
        .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
        .expect("no Extra Bytes VLR");
    vlr.data
        .chunks(192)
        .map(|d| {
            let name = &d[4..36];
            let end = name.iter().position(|&b| b == 0).unwrap_or(32);
            String::from_utf8(name[..end].to_vec()).unwrap()
        })
        .collect()
}

#[test]
fn curvature_of_a_las_sphere_written_as_laz() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.las");
    let output = dir.path().join("out.laz");

    // A micrometre grid, as a fine terrestrial scan would use.
    let mut builder = Builder::from(Version::new(1, 2));
    builder.point_format = Format::new(1).unwrap();
    let t = |offset| Transform {
        scale: 1e-6,
        offset,
    };
    builder.transforms = Vector {
        x: t(CENTRE[0]),
        y: t(CENTRE[1]),
        z: t(CENTRE[2]),
    };
    let file = std::io::BufWriter::new(std::fs::File::create(&input).unwrap());
    let mut writer = Writer::new(file, builder.into_header().unwrap()).unwrap();
    let sphere = mls_shapes::fibonacci_sphere(N, R);
    for [x, y, z] in mls_shapes::points(&sphere) {
        writer
            .write_point(Point {
                x: CENTRE[0] + x,
                y: CENTRE[1] + y,
                z: CENTRE[2] + z,
                gps_time: Some(0.0),
                ..Point::default()
            })
            .unwrap();
    }
    writer.close().unwrap();
    drop(writer);

    let run = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .arg("--quiet"),
    );
    assert!(run.stderr.is_empty(), "{}", run.stderr);

    let mut reader = Reader::from_path(&output).unwrap();
    assert!(reader.header().point_format().is_compressed);
    assert_eq!(reader.header().number_of_points(), N as u64);
    let names = extra_names(&reader);
    let expected = "nx ny nz k1 k2 mean gauss d1x d1y d1z d2x d2y d2z k1_sd k2_sd status";
    assert_eq!(names.join(" "), expected);
    let k1_at = 8 * names.iter().position(|n| n == "k1").unwrap();
    let status_at = 8 * names.iter().position(|n| n == "status").unwrap();
    let points: Vec<Point> = reader
        .read_all()
        .unwrap()
        .points()
        .map(Result::unwrap)
        .collect();
    assert_eq!(points.len(), N);
    let mut k1 = Vec::with_capacity(N);
    for p in &points {
        let e = &p.extra_bytes;
        k1.push(f64::from_le_bytes(e[k1_at..k1_at + 8].try_into().unwrap()));
        assert_eq!(
            i32::from_le_bytes(e[status_at..status_at + 4].try_into().unwrap()),
            0
        );
        let r = ((p.x - CENTRE[0]).powi(2) + (p.y - CENTRE[1]).powi(2) + (p.z - CENTRE[2]).powi(2))
            .sqrt();
        assert!((r - R).abs() < 1e-5, "point off the sphere: r = {r}");
    }
    let relative = (median(&k1) * R - 1.0).abs();
    eprintln!("LAS sphere: median k1 × R − 1 = {relative:e}");
    assert!(
        relative < 1e-3,
        "median k1 {} vs 1/R {}",
        median(&k1),
        1.0 / R
    );
}

/// The header of `mlscurv curvature`'s LAS output, read back from its bytes: point format 6,
/// legacy point counts 0 (LAS 1.4 R15), the 64-bit count, and with `SOURCE_DATE_EPOCH` that
/// instant's creation date (1700000000 s is 2023-11-14, day 318; `date -u -d @1700000000`).
#[test]
fn las_output_header_is_las_1_4_and_dated_by_source_date_epoch() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    crate::common::write_unit_sphere(&input, 2_000);
    let output = dir.path().join("out.las");
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .env("SOURCE_DATE_EPOCH", "1700000000")
            .arg("--quiet"),
    );
    let bytes = std::fs::read(&output).unwrap();
    let u16_at = |at: usize| u16::from_le_bytes(bytes[at..at + 2].try_into().unwrap());
    assert_eq!(bytes[104], 6, "point format");
    assert_eq!(&bytes[107..131], &[0u8; 24], "legacy point counts");
    assert_eq!(
        u64::from_le_bytes(bytes[247..255].try_into().unwrap()),
        2_000
    );
    assert_eq!((u16_at(92), u16_at(90)), (2023, 318), "year, day of year");
    // A value that is not a number of seconds is refused, naming it.
    let r = crate::common::run(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .env("SOURCE_DATE_EPOCH", "yesterday")
            .args(["--quiet", "--force"]),
    );
    assert!(!r.success);
    assert!(
        r.stderr.contains("SOURCE_DATE_EPOCH=`yesterday`"),
        "{}",
        r.stderr
    );
}
