//! Tiled (out-of-core) runs of PLY, XYZ, CSV and E57 inputs against in-memory runs of the
//! same cloud, to every output format: bitwise with the file's normals and a given h, close
//! with estimated normals, and a clear error for a bad input.

use std::fmt::Write as _;
use std::path::Path;

use e57::{E57Writer, Quaternion, Record, RecordValue, Transform, Translation};
use mls_io::{Attribute, AttributeData, Axis, Column, FileFormat, PlyFormat};

use crate::common::{assert_one_line_error, listing, mlscurv, run};
use crate::tiled::{SMALL_BUDGET, assert_same_bytes, curvature, terrain, tiles};

/// Points of the bitwise tests: with [`SIDE`] and `--h 1.1`, more than 16 tiles at
/// [`SMALL_BUDGET`] (as the LAS test, `tiled.rs`).
const N: usize = 60_000;
const SIDE: f64 = 150.0;
const SEED: u64 = 7;

/// The terrain of `tiled.rs` as PLY (`format`): coordinates and normals as `double`, its
/// intensity as `ushort` and a `float` reflectance.
fn write_ply_terrain(path: &Path, format: PlyFormat) {
    let (points, normals, intensity) = terrain(N, SIDE, SEED, usize::MAX);
    let reflectance: Vec<f32> = intensity.iter().map(|&i| f32::from(i) / 4096.0).collect();
    let attributes = [
        Attribute {
            name: "intensity".into(),
            data: AttributeData::U16(intensity),
        },
        Attribute {
            name: "reflectance".into(),
            data: AttributeData::F32(reflectance),
        },
    ];
    let mut columns = vec![
        Column::component("x", &points, Axis::X),
        Column::component("y", &points, Axis::Y),
        Column::component("z", &points, Axis::Z),
        Column::component("nx", &normals, Axis::X),
        Column::component("ny", &normals, Axis::Y),
        Column::component("nz", &normals, Axis::Z),
    ];
    columns.extend(attributes.iter().map(Column::attribute));
    mls_io::write_point_cloud_as(path, FileFormat::Ply, &columns, format).unwrap();
}

/// The terrain as headerless text: `x y z nx ny nz` (read as normals because they are unit
/// vectors on every row), an integer column that turns to floats two thirds of the way down,
/// and a column that holds a word on one row (dropped, with a note). As CSV when `csv`, with
/// a header row naming them.
fn write_text_terrain(path: &Path, csv: bool) {
    let (points, normals, intensity) = terrain(N, SIDE, SEED, usize::MAX);
    let sep = if csv { "," } else { " " };
    let mut text = String::new();
    if csv {
        text.push_str("x,y,z,nx,ny,nz,intensity,flag\n");
    }
    for (i, ((p, n), c)) in points.iter().zip(&normals).zip(&intensity).enumerate() {
        let value = if i < 2 * N / 3 {
            format!("{c}")
        } else {
            format!("{}", f64::from(*c) + 0.25)
        };
        let flag = if i == N / 2 {
            "n/a".to_owned()
        } else {
            format!("{}", i % 3)
        };
        let row = [
            p[0].to_string(),
            p[1].to_string(),
            p[2].to_string(),
            n[0].to_string(),
            n[1].to_string(),
            n[2].to_string(),
            value,
            flag,
        ];
        let _ = writeln!(text, "{}", row.join(sep));
    }
    std::fs::write(path, text).unwrap();
}

/// No temporary file or directory is left in `dir`.
#[track_caller]
fn assert_nothing_left(dir: &Path) {
    let left: Vec<_> = listing(dir)
        .into_iter()
        .filter(|n| n.to_string_lossy().starts_with('.'))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

/// Runs `input` in memory and tiled with `options`, to an output named `output` (whose
/// extension gives the format), and checks the files are the same bytes.
#[track_caller]
fn assert_tiled_is_whole(input: &Path, output: &str, options: &[&str]) -> String {
    let dir = input.parent().unwrap();
    let whole = dir.join(format!("whole-{output}"));
    let tiled = dir.join(format!("tiled-{output}"));
    curvature(input, &whole, options);
    let r = curvature(
        input,
        &tiled,
        &[options, &["--memory", SMALL_BUDGET]].concat(),
    );
    assert!(tiles(&r.stderr) >= 16, "{}", r.stderr);
    assert_same_bytes(&whole, &tiled);
    assert_nothing_left(dir);
    r.stderr
}

/// Binary PLY in, with the file's normals and a given h: PLY out with the jet, LAS and LAZ
/// out (the layout fitted to the box, as in memory) with the paper's surface, each the
/// in-memory run's file byte for byte.
#[test]
fn tiled_binary_ply_runs_equal_the_in_memory_run_bitwise() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    write_ply_terrain(&input, PlyFormat::BinaryLittleEndian);
    assert_tiled_is_whole(&input, "out.ply", &["--h", "1.1"]);
    let paper = ["--h", "1.1", "--method", "paper"];
    assert_tiled_is_whole(&input, "out.las", &paper);
    assert_tiled_is_whole(&input, "out.laz", &paper);
    // Without attributes, and ASCII PLY out.
    assert_tiled_is_whole(
        &input,
        "bare.ply",
        &[&paper[..], &["--no-attributes", "--ascii"]].concat(),
    );
}

/// ASCII PLY in, CSV out.
#[test]
fn tiled_ascii_ply_runs_equal_the_in_memory_run_bitwise() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    write_ply_terrain(&input, PlyFormat::Ascii);
    assert_tiled_is_whole(&input, "out.csv", &["--h", "1.1", "--method", "paper"]);
}

/// Headerless XYZ in, whose normals and column types are known only after every row: XYZ
/// out with the jet and CSV out with the paper's surface, bitwise, with the same notes.
#[test]
fn tiled_xyz_runs_equal_the_in_memory_run_bitwise() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.xyz");
    write_text_terrain(&input, false);
    let stderr = assert_tiled_is_whole(&input, "out.xyz", &["--h", "1.1"]);
    assert!(
        stderr.contains("column 8 (col8) is not carried to the output: line 30001 holds"),
        "{stderr}"
    );
    assert_tiled_is_whole(&input, "out.csv", &["--h", "1.1", "--method", "paper"]);
    // The columns as read: normals, `col7` as floats (the integers before line 40001 too).
    let out = mls_io::read_point_cloud(&dir.path().join("tiled-out.csv")).unwrap();
    let col7 = out.attributes.iter().find(|a| a.name == "col7").unwrap();
    assert!(matches!(col7.data, AttributeData::F64(_)));
    assert!(out.attributes.iter().all(|a| a.name != "col8"));
}

/// CSV in, PLY out.
#[test]
fn tiled_csv_runs_equal_the_in_memory_run_bitwise() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.csv");
    write_text_terrain(&input, true);
    assert_tiled_is_whole(&input, "out.ply", &["--h", "1.1", "--method", "paper"]);
}

/// Estimated normals in a tiled PLY run: the overlaps agree, and the curvature is the
/// in-memory run's (oriented up too) where the neighbourhoods are whole.
#[test]
fn tiled_ply_with_estimated_normals_agrees_with_the_in_memory_run() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.ply");
    write_ply_terrain(&input, PlyFormat::BinaryLittleEndian);
    let options = ["--normals", "estimate", "--orient", "up", "--h", "1.1"];
    let (whole, tiled) = (dir.path().join("whole.ply"), dir.path().join("tiled.ply"));
    curvature(&input, &whole, &options);
    let r = curvature(
        &input,
        &tiled,
        &[&options[..], &["--memory", SMALL_BUDGET]].concat(),
    );
    assert!(tiles(&r.stderr) >= 16, "{}", r.stderr);
    assert_close_k1(&whole, &tiled, 0.99);
}

/// The share of points whose k1 agrees to 1e-9 between two outputs is at least `share`.
#[track_caller]
fn assert_close_k1(a: &Path, b: &Path, share: f64) {
    let k1 = |path: &Path| -> Vec<f64> {
        let cloud = mls_io::read_point_cloud(path).unwrap();
        let a = cloud.attributes.iter().find(|a| a.name == "k1").unwrap();
        (0..a.data.len())
            .map(|i| a.data.f64_at(i).unwrap())
            .collect()
    };
    let (a, b) = (k1(a), k1(b));
    assert_eq!(a.len(), b.len());
    let close = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| (*x - *y).abs() <= 1e-9 * (1.0 + x.abs()))
        .count();
    assert!(
        close as f64 >= share * a.len() as f64,
        "{close} of {} agree",
        a.len()
    );
}

/// E57 in (two scans with poses, no normals): a tiled run to PLY estimates the normals per
/// tile, oriented towards each point's scanner as in memory, and agrees with the in-memory
/// run; every point in file order with its scan and intensity.
#[test]
fn tiled_e57_runs_agree_with_the_in_memory_run() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("terrain.e57");
    let (points, _, intensity) = terrain(N, SIDE, SEED, usize::MAX);
    let mut writer = E57Writer::from_file(&input, "terrain-file").unwrap();
    for (s, half) in points.chunks(N / 2).enumerate() {
        let prototype = vec![
            Record::CARTESIAN_X_F64,
            Record::CARTESIAN_Y_F64,
            Record::CARTESIAN_Z_F64,
            Record::INTENSITY_U16,
        ];
        let mut pc = writer
            .add_pointcloud(&format!("scan-{s}"), prototype)
            .unwrap();
        // Each scanner 60 m above the middle of its half, axes aligned with the world's; the
        // points in its frame.
        let t = half[0].map(|c| c.round()).map(|c| c + 60.0);
        pc.set_transform(Some(Transform {
            rotation: Quaternion {
                w: 1.0,
                x: 0.0,
                y: 0.0,
                z: 0.0,
            },
            translation: Translation {
                x: t[0],
                y: t[1],
                z: t[2],
            },
        }));
        for (k, p) in half.iter().enumerate() {
            pc.add_point(vec![
                RecordValue::Double(p[0] - t[0]),
                RecordValue::Double(p[1] - t[1]),
                RecordValue::Double(p[2] - t[2]),
                RecordValue::Integer(i64::from(intensity[s * N / 2 + k])),
            ])
            .unwrap();
        }
        pc.finalize().unwrap();
    }
    writer.finalize().unwrap();
    let options = ["--h", "1.1", "--method", "paper"];
    let (whole, tiled) = (dir.path().join("whole.ply"), dir.path().join("tiled.ply"));
    curvature(&input, &whole, &options);
    let r = curvature(
        &input,
        &tiled,
        &[&options[..], &["--memory", SMALL_BUDGET]].concat(),
    );
    assert!(tiles(&r.stderr) >= 16, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("oriented towards each scan's scanner position"),
        "{}",
        r.stderr
    );
    assert!(!r.stderr.contains("differ between tiles"), "{}", r.stderr);
    assert_close_k1(&whole, &tiled, 0.99);
    let (a, b) = (
        mls_io::read_point_cloud(&whole).unwrap(),
        mls_io::read_point_cloud(&tiled).unwrap(),
    );
    assert_eq!(a.points, b.points);
    let names = |c: &mls_io::PointCloud| -> Vec<String> {
        c.attributes.iter().map(|a| a.name.clone()).collect()
    };
    assert_eq!(names(&a), names(&b));
    for name in ["scan", "intensity"] {
        let get = |c: &mls_io::PointCloud| {
            c.attributes
                .iter()
                .find(|a| a.name == name)
                .unwrap()
                .data
                .clone()
        };
        assert_eq!(get(&a), get(&b), "{name}");
    }
    assert_nothing_left(dir.path());
}

/// A PLY cut short and an XYZ with a bad value, both too large for the budget: one-line
/// errors naming the file and where (byte offset and property; line and column), no output
/// and no temporary file left.
#[test]
fn a_bad_input_of_a_tiled_run_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("cut.ply");
    write_ply_terrain(&ply, PlyFormat::BinaryLittleEndian);
    let bytes = std::fs::read(&ply).unwrap();
    std::fs::write(&ply, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let xyz = dir.path().join("bad.xyz");
    write_text_terrain(&xyz, false);
    let text = std::fs::read_to_string(&xyz).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines[41_234] = "1 2 oops 0 0 1 3 4";
    std::fs::write(&xyz, lines.join("\n")).unwrap();
    let out = dir.path().join("out.ply");
    for (input, details) in [
        (&ply, &["truncated binary body at byte", "vertex 39998"][..]),
        (
            &xyz,
            &["line 41235", "column 3 (z)", "not a number: \"oops\""][..],
        ),
    ] {
        let r = run(mlscurv()
            .arg("curvature")
            .arg(input)
            .arg("-o")
            .arg(&out)
            .args(["--h", "1.1", "--quiet", "--memory", SMALL_BUDGET]));
        assert_one_line_error(&r, &input.display().to_string(), details);
        assert!(!out.exists());
        assert_nothing_left(dir.path());
    }
}

/// An attribute that LAS output cannot hold (a name over 32 bytes) is refused before any
/// work, as in memory.
#[test]
fn a_tiled_run_refuses_an_attribute_las_cannot_hold_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("long.ply");
    let (points, _, _) = terrain(20_000, 80.0, SEED, usize::MAX);
    let values: Vec<f64> = points.iter().map(|p| p[2]).collect();
    let name = "an_attribute_name_of_more_than_32_bytes";
    let columns = [
        Column::component("x", &points, Axis::X),
        Column::component("y", &points, Axis::Y),
        Column::component("z", &points, Axis::Z),
        Column::f64(name, &values),
    ];
    mls_io::write_point_cloud_as(&input, FileFormat::Ply, &columns, PlyFormat::default()).unwrap();
    let out = dir.path().join("out.las");
    let r = run(mlscurv()
        .arg("curvature")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--h", "1.1", "--quiet", "--memory", "65MiB"]));
    assert_one_line_error(
        &r,
        &input.display().to_string(),
        &[name, "a LAS extra-bytes name holds at most 32"],
    );
    assert!(!out.exists());
    assert_nothing_left(dir.path());
}
