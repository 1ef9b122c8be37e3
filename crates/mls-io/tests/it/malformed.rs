//! Every class of malformed input gives an error naming the file and where.

use std::path::Path;
use std::time::Instant;

use mls_io::{ReadError, read_csv, read_ply, read_point_cloud, read_xyz};

use crate::{Body, assert_message, ply};

const XYZ_FLOAT: &str = "property float x\nproperty float y\nproperty float z\n";

fn ply_err(bytes: &[u8]) -> ReadError {
    read_ply(bytes, "bad.ply").unwrap_err()
}

#[test]
fn missing_file() {
    let path = Path::new("/nonexistent-dir/cloud.ply");
    let err = read_point_cloud(path).unwrap_err();
    assert!(matches!(err, ReadError::Io { .. }), "{err:?}");
    assert_message(&err, "/nonexistent-dir/cloud.ply", &["No such file"]);
}

#[test]
fn unknown_or_missing_extension() {
    let err = read_point_cloud(Path::new("scan.obj")).unwrap_err();
    assert!(matches!(err, ReadError::UnknownExtension { .. }), "{err:?}");
    assert_message(&err, "scan.obj", &["\".obj\"", ".ply"]);
    let err = read_point_cloud(Path::new("scan")).unwrap_err();
    assert!(matches!(err, ReadError::NoExtension { .. }), "{err:?}");
    assert_message(&err, "scan", &["no file extension"]);
}

#[test]
fn extension_is_case_insensitive() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("UPPER.XYZ");
    std::fs::write(&path, "1 2 3\n").unwrap();
    assert_eq!(read_point_cloud(&path).unwrap().points, [[1.0, 2.0, 3.0]]);
}

#[test]
fn header_errors_name_the_line() {
    let cases: [(&str, &[&str]); 13] = [
        ("", &["header line 1", "empty file"]),
        (
            "plx\nformat ascii 1.0\n",
            &["header line 1", "bad magic", "\"plx\""],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n",
            &["header line 5", "missing end_header"],
        ),
        (
            "ply\nformat binary_middle_endian 1.0\nend_header\n",
            &["header line 2", "unknown format"],
        ),
        (
            "ply\nformat ascii\nend_header\n",
            &["header line 2", "expected \"format"],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
            &["header line 4", "unknown property type \"float128\""],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\nend_header\n",
            &["header line 4", "not an integer"],
        ),
        (
            "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
            &["header line 3", "before any element"],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n",
            &["header line 3", "element count"],
        ),
        (
            "ply\nformat ascii 1.0\nelements vertex 1\nend_header\n",
            &["header line 3", "unknown keyword"],
        ),
        (
            "ply\nelement vertex 0\nend_header\n",
            &["header line 3", "no format line"],
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\nend_header\n",
            &["header line 5", "duplicate property \"x\""],
        ),
        (
            "ply\nformat ascii 1.0\nelement face 0\nend_header\n",
            &["header line 4", "no \"vertex\" element"],
        ),
    ];
    for (text, parts) in cases {
        let err = ply_err(text.as_bytes());
        assert!(matches!(err, ReadError::Header { .. }), "{text:?}: {err:?}");
        assert_message(&err, "bad.ply", parts);
    }
}

#[test]
fn binary_garbage_without_line_breaks() {
    let mut bytes = b"ply\n".to_vec();
    bytes.extend(std::iter::repeat_n(b'a', 200_000));
    assert_message(
        &ply_err(&bytes),
        "bad.ply",
        &["header line 2", "longer than"],
    );
}

#[test]
fn vertex_element_without_x() {
    let text =
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\nend_header\n";
    let err = ply_err(text.as_bytes());
    assert!(
        matches!(err, ReadError::MissingField { field: "x", .. }),
        "{err:?}"
    );
    assert_message(&err, "bad.ply", &["line 3", "\"x\""]);
}

#[test]
fn coordinate_declared_as_list() {
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property list uchar float z\nend_header\n";
    assert_message(
        &ply_err(text.as_bytes()),
        "bad.ply",
        &["header line 6", "z is a list"],
    );
}

#[test]
fn partial_normals_name_the_missing_component() {
    let text = format!(
        "ply\nformat ascii 1.0\nelement vertex 1\n{XYZ_FLOAT}property float nx\nproperty float ny\nend_header\n"
    );
    let err = ply_err(text.as_bytes());
    assert!(matches!(err, ReadError::PartialNormals { .. }), "{err:?}");
    assert_message(&err, "bad.ply", &["line 3", "nz is missing"]);

    let err = read_csv("x,y,z,nx\n1,2,3,4\n".as_bytes(), "bad.csv").unwrap_err();
    assert_message(&err, "bad.csv", &["line 1", "ny and nz are missing"]);
}

/// 20 vertices of x y z nx ny nz float32, cut inside vertex 17.
#[test]
fn truncated_binary_body_names_offset_vertex_and_property() {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex 20\n{XYZ_FLOAT}\
         property float nx\nproperty float ny\nproperty float nz\nend_header\n"
    );
    let mut body = Body::default();
    for i in 0..17 {
        for k in 0..6 {
            body.f32((i * 6 + k) as f32);
        }
    }
    body.f32(1.0).u8(0).u8(0);
    let bytes = ply(&header, &body.bytes);
    let expected = header.len() + 17 * 24 + 4;
    let err = ply_err(&bytes);
    assert!(matches!(err, ReadError::Truncated { .. }), "{err:?}");
    let message = assert_message(&err, "bad.ply", &[]);
    assert_eq!(
        message,
        format!(
            "bad.ply: truncated binary body at byte {expected}: expected vertex 17 property y (float32)"
        )
    );
}

#[test]
fn truncated_element_before_vertices() {
    let header = format!(
        "ply\nformat binary_big_endian 1.0\nelement pad 4\nproperty double a\nproperty short b\n\
         element vertex 1\n{XYZ_FLOAT}end_header\n"
    );
    // Two whole records of 10 bytes, then 9 bytes of the third: its b is cut.
    let bytes = ply(&header, &[0; 29]);
    let offset = header.len() + 28;
    assert_message(
        &ply_err(&bytes),
        "bad.ply",
        &[
            &format!("at byte {offset}"),
            "expected pad 2 property b (int16)",
        ],
    );
}

#[test]
fn truncated_list_and_negative_list_length() {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex 1\n{XYZ_FLOAT}\
         property list char int idx\nend_header\n"
    );
    let mut body = Body::default();
    body.f32(1.0).f32(2.0).f32(3.0).i8(3).i32(1);
    let err = ply_err(&ply(&header, &body.bytes));
    let offset = header.len() + 13;
    assert_message(
        &err,
        "bad.ply",
        &[
            &format!("at byte {offset}"),
            "vertex 0 property idx (list of 3 int32)",
        ],
    );

    let mut body = Body::default();
    body.f32(1.0).f32(2.0).f32(3.0).i8(-1);
    let err = ply_err(&ply(&header, &body.bytes));
    assert!(matches!(err, ReadError::Binary { .. }), "{err:?}");
    let offset = header.len() + 12;
    assert_message(
        &err,
        "bad.ply",
        &[
            "negative list length",
            &format!("at byte {offset}"),
            "vertex 0 property idx",
        ],
    );
}

#[test]
fn non_finite_binary_values_name_offset_and_property() {
    for (value, name) in [(f32::NAN, "NaN"), (f32::INFINITY, "inf")] {
        // Both the fixed-size and the list-bearing vertex paths.
        for extra in ["", "property list uchar uchar l\n"] {
            let header = format!(
                "ply\nformat binary_little_endian 1.0\nelement vertex 2\n{XYZ_FLOAT}{extra}end_header\n"
            );
            let mut body = Body::default();
            body.f32(0.0).f32(0.0).f32(0.0);
            if !extra.is_empty() {
                body.u8(0);
            }
            body.f32(0.0).f32(0.0).f32(value);
            if !extra.is_empty() {
                body.u8(0);
            }
            let offset = header.len() + if extra.is_empty() { 20 } else { 21 };
            let err = ply_err(&ply(&header, &body.bytes));
            assert!(matches!(err, ReadError::Binary { .. }), "{err:?}");
            assert_message(
                &err,
                "bad.ply",
                &[
                    &format!("non-finite value {name} at byte {offset}"),
                    "vertex 1 property z (float32)",
                ],
            );
        }
    }
}

#[test]
fn ascii_body_errors_name_line_and_property() {
    let header = format!("ply\nformat ascii 1.0\nelement vertex 3\n{XYZ_FLOAT}end_header\n");
    let cases: [(&str, &[&str]); 7] = [
        (
            "1 2 3\n4 5 1e39\n",
            &[
                "line 9",
                "vertex 1 property z",
                "\"1e39\" is not a value of the declared type float32",
            ],
        ),
        (
            "1 2 3\n4 5\n",
            &["line 9", "vertex 1 property z", "missing value"],
        ),
        (
            "1 2 3\n4 abc 6\n",
            &["line 9", "vertex 1 property y", "not a number: \"abc\""],
        ),
        (
            "1 2 3\n4 5 nan\n",
            &["line 9", "vertex 1 property z", "non-finite value \"nan\""],
        ),
        (
            "1 2 3\n-inf 5 6\n",
            &["line 9", "vertex 1 property x", "non-finite"],
        ),
        (
            "1 2 3\n4 5 6 7\n",
            &["line 9", "vertex 1", "unexpected extra value \"7\""],
        ),
        (
            "1 2 3\n4 5 6\n",
            &["line 10", "vertex 2", "unexpected end of file"],
        ),
    ];
    for (body, parts) in cases {
        let err = ply_err(ply(&header, body.as_bytes()).as_slice());
        assert!(matches!(err, ReadError::Ascii { .. }), "{body:?}: {err:?}");
        assert_message(&err, "bad.ply", parts);
    }
}

/// An ASCII value must be one its declared type can hold (a float32 beyond 3.4e38, a fraction
/// or a negative number for an unsigned byte), while a float32 written with more digits than
/// float32 has keeps them.
#[test]
fn ascii_values_must_fit_their_declared_type() {
    let header = |ty: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty {ty} x\nproperty float y\n\
             property float z\nend_header\n"
        )
    };
    for (ty, x, fits) in [
        ("float", "3.4e38", true),
        ("float", "-3.5e38", false),
        ("float", "0.1234567890123", true),
        ("double", "1e300", true),
        ("uchar", "255", true),
        ("uchar", "256", false),
        ("uchar", "-1", false),
        ("int", "2.5", false),
        ("short", "-32768", true),
    ] {
        let bytes = ply(&header(ty), format!("{x} 0 0\n").as_bytes());
        let got = read_ply(bytes.as_slice(), "bad.ply");
        match (fits, got) {
            (true, Ok(cloud)) => assert_eq!(cloud.points[0][0], x.parse::<f64>().unwrap()),
            (false, Err(err)) => {
                assert_message(
                    &err,
                    "bad.ply",
                    &["vertex 0 property x", "is not a value of the declared type"],
                );
            }
            (_, got) => panic!("{ty} {x}: {got:?}"),
        }
    }
}

#[test]
fn ascii_elements_before_vertices_must_be_complete() {
    let text = format!(
        "ply\nformat ascii 1.0\nelement cam 5\nproperty float a\nelement vertex 1\n{XYZ_FLOAT}end_header\n1\n2\n"
    );
    assert_message(
        &ply_err(text.as_bytes()),
        "bad.ply",
        &["line 12", "cam 2", "end of file"],
    );
}

/// A header claiming 10^12 vertices must fail fast on the short body, not allocate for them.
#[test]
fn huge_vertex_count_fails_quickly() {
    let start = Instant::now();
    for format in ["binary_little_endian", "binary_big_endian", "ascii"] {
        let header = format!(
            "ply\nformat {format} 1.0\nelement vertex 1000000000000\n{XYZ_FLOAT}end_header\n"
        );
        let body: &[u8] = if format == "ascii" {
            b"1 2 3\n"
        } else {
            &[0; 12]
        };
        let bytes = ply(&header, body);
        let err = ply_err(&bytes);
        assert_message(&err, "bad.ply", &["vertex 1"]);
        // Through a file, where the size bounds the preallocation instead.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("huge.ply");
        std::fs::write(&path, &bytes).unwrap();
        let err = read_point_cloud(&path).unwrap_err();
        assert_message(&err, &path.display().to_string(), &["vertex 1"]);
    }
    // Huge counts in skipped elements, fixed-size or not, fail as fast.
    for element in ["property double a", "property list uchar int a"] {
        let header = format!(
            "ply\nformat binary_little_endian 1.0\nelement junk 1000000000000\n{element}\n\
             element vertex 1\n{XYZ_FLOAT}end_header\n"
        );
        assert_message(&ply_err(&ply(&header, &[1; 64])), "bad.ply", &["junk"]);
    }
    // Generous, yet far below what allocating or looping over 10^12 entries would take.
    assert!(start.elapsed().as_secs() < 5, "took {:?}", start.elapsed());
}

#[test]
fn xyz_errors_name_line_and_column() {
    // Columns 4-6 that fail to parse are not normals (a note, not an error): see
    // `text::unit_columns_are_normals_within_the_tolerance` and, for named normals,
    // `text::named_columns_override_the_rule`.
    let cases: [(&str, &[&str]); 5] = [
        ("1 2 3\n4 5\n", &["line 2", "2 columns, expected 3"]),
        (
            "# c\n1 2\n",
            &["line 2", "2 column(s)", "expected at least 3 (x y z"],
        ),
        // Two values, comma-separated: still fewer than 3 columns.
        ("1,2\n", &["line 1", "1 column(s)"]),
        (
            "1 2 3\n4 x 6\n",
            &["line 2", "column 2 (y)", "not a number: \"x\""],
        ),
        (
            "1 2 3\n\n1e999 5 6\n",
            &["line 3", "column 1 (x)", "non-finite"],
        ),
    ];
    for (text, parts) in cases {
        let err = read_xyz(text.as_bytes(), "bad.xyz").unwrap_err();
        assert_message(&err, "bad.xyz", parts);
    }
}

#[test]
fn csv_errors_name_line_and_column() {
    let cases: [(&str, &[&str]); 7] = [
        ("", &["line 1", "empty file"]),
        ("x,y\n1,2\n", &["line 1", "no \"z\" field"]),
        ("x,y,z,X\n", &["line 1", "duplicate column \"x\""]),
        ("x,y,z\n1,2\n", &["line 2", "2 columns, expected 3"]),
        (
            "x,y,z\n1,2,3\n1,two,3\n",
            &["line 3", "column 2 (y)", "not a number: \"two\""],
        ),
        (
            "x,y,z\n1,2,inf\n",
            &["line 2", "column 3 (z)", "non-finite"],
        ),
        (
            "x,y,z,label\n1,2,3,\"open\n",
            &["line 2", "column 4", "unterminated"],
        ),
    ];
    for (text, parts) in cases {
        let err = read_csv(text.as_bytes(), "bad.csv").unwrap_err();
        assert_message(&err, "bad.csv", parts);
    }
}
