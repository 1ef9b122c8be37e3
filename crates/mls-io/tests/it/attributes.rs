//! Attributes carried from input to output: PLY properties of every scalar type, text
//! columns, LAS standard dimensions and extra bytes, each read in its type and written back
//! bit for bit.

use std::fmt::Write as _;

use las::point::{Classification, Format, ScanDirection};
use las::{Builder, Color, Point, Reader, Transform, Vector, Version, Vlr, Writer};
use mls_io::{
    Attribute, AttributeData, Axis, Column, FileFormat, PlyFormat, PointCloud, WriteOptions,
    read_csv_with, read_ply, read_point_cloud_from_with, write_ply_to, write_point_cloud,
    write_point_cloud_as_with,
};

use crate::{Body, assert_message};

/// The attributes of the PLY fixtures: every scalar type PLY has.
fn expected_ply_attributes() -> Vec<Attribute> {
    let a = |name: &str, data| Attribute {
        name: name.to_owned(),
        data,
    };
    vec![
        a("red", AttributeData::U8(vec![255, 0, 17])),
        a("green", AttributeData::U8(vec![1, 128, 34])),
        a("blue", AttributeData::U8(vec![2, 200, 51])),
        a(
            "intensity",
            AttributeData::F32(vec![0.1, -2.5e-8, f32::MAX]),
        ),
        a("class", AttributeData::I8(vec![-128, 0, 127])),
        a("label", AttributeData::I16(vec![-32768, 7, 32767])),
        a("count", AttributeData::U16(vec![0, 65535, 9])),
        a("id", AttributeData::I32(vec![i32::MIN, 0, i32::MAX])),
        a("tag", AttributeData::U32(vec![u32::MAX, 1, 2])),
        a("time", AttributeData::F64(vec![1e300, -0.0, 123.456])),
    ]
}

const PROPERTIES: &str = "property float x\nproperty float y\nproperty float z\n\
    property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float intensity\n\
    property char class\nproperty short label\nproperty ushort count\nproperty int id\n\
    property uint tag\nproperty double time\n";

/// The fixture in `encoding` (`ascii`, `binary_little_endian`, `binary_big_endian`), with a
/// list property before the scalars if `list`.
fn ply_fixture(encoding: &str, list: bool) -> Vec<u8> {
    let attributes = expected_ply_attributes();
    let list_line = if list {
        "property list uchar int faces\n"
    } else {
        ""
    };
    let mut bytes = format!(
        "ply\nformat {encoding} 1.0\nelement vertex 3\n{list_line}{PROPERTIES}end_header\n"
    )
    .into_bytes();
    for row in 0..3 {
        let point = [row as f32, 2.0 * row as f32, -1.5];
        if encoding == "ascii" {
            let mut line = String::new();
            if list {
                line.push_str("2 4 5 ");
            }
            let _ = write!(line, "{} {} {}", point[0], point[1], point[2]);
            for a in &attributes {
                let v = match &a.data {
                    AttributeData::U8(v) => v[row].to_string(),
                    AttributeData::I8(v) => v[row].to_string(),
                    AttributeData::I16(v) => v[row].to_string(),
                    AttributeData::U16(v) => v[row].to_string(),
                    AttributeData::I32(v) => v[row].to_string(),
                    AttributeData::U32(v) => v[row].to_string(),
                    AttributeData::F32(v) => format!("{:?}", v[row]),
                    AttributeData::F64(v) => format!("{:?}", v[row]),
                    other => panic!("no such PLY type: {other:?}"),
                };
                line.push(' ');
                line.push_str(&v);
            }
            line.push('\n');
            bytes.extend_from_slice(line.as_bytes());
            continue;
        }
        let mut body = Body {
            big: encoding == "binary_big_endian",
            ..Body::default()
        };
        if list {
            body.u8(2).i32(4).i32(5);
        }
        body.f32(point[0]).f32(point[1]).f32(point[2]);
        for a in &attributes {
            match &a.data {
                AttributeData::U8(v) => body.u8(v[row]),
                AttributeData::I8(v) => body.i8(v[row]),
                AttributeData::I16(v) => body.i16(v[row]),
                AttributeData::U16(v) => body.u16(v[row]),
                AttributeData::I32(v) => body.i32(v[row]),
                AttributeData::U32(v) => body.u32(v[row]),
                AttributeData::F32(v) => body.f32(v[row]),
                AttributeData::F64(v) => body.f64(v[row]),
                other => panic!("no such PLY type: {other:?}"),
            };
        }
        bytes.extend_from_slice(&body.bytes);
    }
    bytes
}

#[test]
fn ply_properties_are_read_in_their_types_and_written_back_bit_for_bit() {
    for encoding in ["ascii", "binary_little_endian", "binary_big_endian"] {
        for list in [false, true] {
            let bytes = ply_fixture(encoding, list);
            let read = read_point_cloud_from_with(
                &bytes[..],
                "f.ply",
                FileFormat::Ply,
                &Default::default(),
            )
            .unwrap();
            let cloud = read.cloud;
            assert_eq!(cloud.points[2], [2.0, 4.0, -1.5]);
            assert_eq!(cloud.attributes, expected_ply_attributes(), "{encoding}");
            if list {
                assert_eq!(
                    read.notes,
                    ["f.ply: vertex property faces is a list; it is not carried to the output"]
                );
            } else {
                assert!(read.notes.is_empty());
            }
            for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
                let mut written = Vec::new();
                write_ply_to(&mut written, "out.ply", &cloud.columns(), format).unwrap();
                let text = String::from_utf8_lossy(&written);
                assert!(
                    text.contains(
                        "property uchar red\nproperty uchar green\nproperty uchar blue\n\
                         property float intensity\nproperty char scalar_class\nproperty short scalar_label\n"
                    ),
                    "{text}"
                );
                let back = read_ply(&written[..], "out.ply").unwrap();
                assert_eq!(back, cloud, "{encoding} {format:?}");
                // Bit for bit, -0.0 and all.
                let AttributeData::F64(time) = &back.attributes[9].data else {
                    panic!("time is not float64");
                };
                assert_eq!(time[1].to_bits(), (-0.0f64).to_bits());
            }
        }
    }
}

#[test]
fn bad_ply_attribute_values_name_file_line_and_property() {
    let text = format!(
        "ply\nformat ascii 1.0\nelement vertex 2\n{PROPERTIES}end_header\n\
         0 0 0 1 2 3 0.5 1 2 3 4 5 6\n0 0 0 300 2 3 0.5 1 2 3 4 5 6\n"
    );
    let err = read_ply(text.as_bytes(), "bad.ply").unwrap_err();
    assert_message(
        &err,
        "bad.ply",
        &[
            "line 19",
            "vertex 1 property red",
            "\"300\" is not a uint8 value",
        ],
    );
    let text = format!(
        "ply\nformat ascii 1.0\nelement vertex 1\n{PROPERTIES}end_header\n\
         0 0 0 1 2 3 0.5 1 2 3 4 -5 6\n"
    );
    let err = read_ply(text.as_bytes(), "bad.ply").unwrap_err();
    assert_message(
        &err,
        "bad.ply",
        &[
            "line 18",
            "vertex 0 property tag",
            "\"-5\" is not a uint32 value",
        ],
    );
}

#[test]
fn csv_columns_beyond_the_geometry_are_attributes_under_their_header_names() {
    let csv = "X,Y,Z,Intensity,label,bad name,Intensity,t\n\
               1,2,3,7,roof,0.5,1,1e3\n4,5,6,9,wall,-1,2,2\n";
    let read = read_csv_with(csv.as_bytes(), "a.csv", &Default::default()).unwrap();
    let names: Vec<&str> = read
        .cloud
        .attributes
        .iter()
        .map(|a| a.name.as_str())
        .collect();
    // A name the writers cannot write is mended, a repeated one numbered; text is dropped
    // with a note.
    assert_eq!(names, ["Intensity", "bad_name", "Intensity_2", "t"]);
    assert_eq!(
        read.cloud.attributes[0].data,
        AttributeData::I32(vec![7, 9])
    );
    assert_eq!(
        read.cloud.attributes[1].data,
        AttributeData::F64(vec![0.5, -1.0])
    );
    assert_eq!(
        read.cloud.attributes[3].data,
        AttributeData::F64(vec![1e3, 2.0])
    );
    assert_eq!(
        read.notes,
        [
            "a.csv: column 5 (label) is not carried to the output: line 2 holds \"roof\", not a \
          number"
        ]
    );
}

#[test]
fn ply_property_names_the_writers_cannot_write_are_mended() {
    // `scalar_Intensity` is CloudCompare's scalar field `Intensity`; `scalar/Intensity` is
    // not of that form and only loses its slash.
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property float z\nproperty float scalar/Intensity\nproperty uchar scalar_Intensity\n\
                property uchar scalar_(0.4)\nend_header\n1 2 3 0.5 7 9\n";
    let cloud = read_ply(text.as_bytes(), "cc.ply").unwrap();
    let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["scalar_Intensity", "Intensity", "_0.4_"]);
    let mut csv = Vec::new();
    mls_io::write_csv_to(&mut csv, "o.csv", &cloud.columns()).unwrap();
    assert_eq!(
        String::from_utf8(csv).unwrap(),
        "//x,y,z,scalar_Intensity,Intensity,_0.4_\n1.0,2.0,3.0,0.5,7,9\n"
    );
}

#[test]
fn ply_scalar_prefix_is_written_and_read_back() {
    let cloud = PointCloud {
        points: vec![[1.0, 2.0, 3.0]],
        normals: Some(vec![[0.0, 0.0, 1.0]]),
        attributes: vec![
            Attribute {
                name: "red".to_owned(),
                data: AttributeData::U8(vec![200]),
            },
            Attribute {
                name: "k1".to_owned(),
                data: AttributeData::F64(vec![-0.25]),
            },
            Attribute {
                name: "mean".to_owned(),
                data: AttributeData::F64(vec![1.5]),
            },
        ],
        ..PointCloud::default()
    };
    let options = WriteOptions {
        ply_format: PlyFormat::Ascii,
        ply_quality: Some("mean"),
        ..WriteOptions::default()
    };
    let mut bytes = Vec::new();
    mls_io::write_point_cloud_to_with(
        &mut bytes,
        "o.ply",
        FileFormat::Ply,
        &cloud.columns(),
        &options,
    )
    .unwrap();
    let text = String::from_utf8(bytes.clone()).unwrap();
    assert!(
        text.contains(
            "property double nz\nproperty uchar red\nproperty double scalar_k1\n\
             property double scalar_mean\nproperty double quality\nend_header\n\
             1.0 2.0 3.0 0.0 0.0 1.0 200 -0.25 1.5 1.5\n"
        ),
        "{text}"
    );
    // Read back under the columns' names; the copy is an attribute `quality`.
    let back = read_ply(&bytes[..], "o.ply").unwrap();
    let names: Vec<&str> = back.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["red", "k1", "mean", "quality"]);
    assert_eq!(back.attributes[..3], cloud.attributes[..]);
    // The older unprefixed names read the same; a file with both keeps the prefix.
    let old = "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n\
               property double z\nproperty double k1\nproperty double scalar_k1\n\
               property double scalar_x\nend_header\n1 2 3 4 5 6\n";
    let back = read_ply(old.as_bytes(), "old.ply").unwrap();
    let names: Vec<&str> = back.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["k1", "scalar_k1", "scalar_x"]);
    // An existing `quality` column is not doubled.
    let mut with_quality = cloud.clone();
    with_quality.attributes.push(Attribute {
        name: "quality".to_owned(),
        data: AttributeData::F32(vec![0.5]),
    });
    let mut bytes = Vec::new();
    mls_io::write_point_cloud_to_with(
        &mut bytes,
        "o.ply",
        FileFormat::Ply,
        &with_quality.columns(),
        &options,
    )
    .unwrap();
    let back = read_ply(&bytes[..], "o.ply").unwrap();
    assert_eq!(back.attributes, with_quality.attributes);
}

/// A LAS point of format `format` with every field set from `i`.
fn las_point(format: u8, i: usize) -> Point {
    let extended = format >= 6;
    Point {
        x: 1000.0 + 0.001 * i as f64,
        y: 2000.0 + 0.002 * (i % 97) as f64,
        z: 0.5 * (i % 13) as f64,
        intensity: (i * 257 % 65536) as u16,
        return_number: (i % 3 + 1) as u8,
        number_of_returns: 3,
        scan_direction: if i.is_multiple_of(2) {
            ScanDirection::LeftToRight
        } else {
            ScanDirection::RightToLeft
        },
        is_edge_of_flight_line: i.is_multiple_of(5),
        classification: Classification::new((i % 10) as u8).unwrap(),
        is_synthetic: i.is_multiple_of(7),
        is_key_point: i.is_multiple_of(11),
        is_withheld: i.is_multiple_of(13),
        is_overlap: extended && i.is_multiple_of(17),
        scanner_channel: if extended { (i % 4) as u8 } else { 0 },
        scan_angle: if extended { -12.0 } else { 12.0 },
        user_data: (i % 256) as u8,
        point_source_id: (i * 31 % 65536) as u16,
        gps_time: Some(1.0e8 + i as f64 / 3.0),
        color: matches!(format, 2 | 3 | 7 | 8).then(|| Color {
            red: (i * 3 % 65536) as u16,
            green: (i * 5 % 65536) as u16,
            blue: 65535,
        }),
        nir: (format == 8).then_some(4242),
        waveform: None,
        // One `u16` extra-bytes attribute, `amplitude`.
        extra_bytes: ((i * 7) as u16).to_le_bytes().to_vec(),
    }
}

/// A LAS file of `format` with 300 such points, a millimetre grid, an `amplitude` extra
/// bytes attribute with a description, and a coordinate-system record.
fn las_fixture(format: u8) -> Vec<u8> {
    let mut builder = Builder::from(Version::new(1, 4));
    builder.point_format = Format::new(format).unwrap();
    builder.point_format.extra_bytes = 2;
    let t = |offset| Transform {
        scale: 0.001,
        offset,
    };
    builder.transforms = Vector {
        x: t(1000.0),
        y: t(2000.0),
        z: t(0.0),
    };
    let mut descriptor = [0u8; 192];
    descriptor[2] = 3; // u16
    descriptor[4..13].copy_from_slice(b"amplitude");
    descriptor[160..176].copy_from_slice(b"echo amplitude d");
    builder.vlrs.push(Vlr {
        user_id: "LASF_Spec".to_owned(),
        record_id: 4,
        description: "Extra Bytes".to_owned(),
        data: descriptor.to_vec(),
    });
    builder.vlrs.push(Vlr {
        user_id: "LASF_Projection".to_owned(),
        record_id: 2112,
        description: "WKT".to_owned(),
        data: b"PROJCS[\"test\"]\0".to_vec(),
    });
    let mut writer = Writer::new(
        std::io::Cursor::new(Vec::new()),
        builder.into_header().unwrap(),
    )
    .unwrap();
    for i in 0..300 {
        writer.write_point(las_point(format, i)).unwrap();
    }
    writer.into_inner().unwrap().into_inner()
}

fn las_points(bytes: &[u8]) -> (las::Header, Vec<Point>) {
    let mut reader = Reader::new(std::io::Cursor::new(bytes.to_vec())).unwrap();
    let points = reader
        .read_all()
        .unwrap()
        .points()
        .map(Result::unwrap)
        .collect();
    (reader.header().clone(), points)
}

#[test]
fn las_dimensions_and_extra_bytes_go_back_where_they_came_from() {
    for (format, names) in [
        (
            3,
            "intensity return_number number_of_returns scan_direction_flag edge_of_flight_line \
             classification synthetic key_point withheld scan_angle_rank user_data \
             point_source_id gps_time red green blue amplitude",
        ),
        (
            8,
            "intensity return_number number_of_returns synthetic key_point withheld overlap \
             scanner_channel scan_direction_flag edge_of_flight_line classification user_data \
             scan_angle point_source_id gps_time red green blue nir amplitude",
        ),
    ] {
        let input = las_fixture(format);
        let read =
            read_point_cloud_from_with(&input[..], "in.las", FileFormat::Las, &Default::default())
                .unwrap();
        assert!(read.notes.is_empty(), "{:?}", read.notes);
        let cloud = read.cloud;
        let found: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(found.join(" "), names);
        let attribute = |name: &str| {
            &cloud
                .attributes
                .iter()
                .find(|a| a.name == name)
                .unwrap()
                .data
        };
        let (_, expected) = las_points(&input);
        assert_eq!(
            *attribute("intensity"),
            AttributeData::U16(expected.iter().map(|p| p.intensity).collect())
        );
        assert_eq!(
            *attribute("gps_time"),
            AttributeData::F64(expected.iter().map(|p| p.gps_time.unwrap()).collect())
        );
        assert_eq!(
            *attribute("amplitude"),
            AttributeData::U16((0..300).map(|i| (i * 7) as u16).collect())
        );
        let template = cloud.las.as_ref().unwrap();
        assert_eq!(template.point_format, format);
        assert_eq!(template.scale, [0.001; 3]);
        assert_eq!(template.offset, [1000.0, 2000.0, 0.0]);

        // Written back as LAS and LAZ with the template: the same points, field for field.
        for compressed in [false, true] {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join(if compressed { "o.laz" } else { "o.las" });
            let format_out = if compressed {
                FileFormat::Laz
            } else {
                FileFormat::Las
            };
            let options = WriteOptions {
                las: Some(template),
                ..WriteOptions::default()
            };
            write_point_cloud_as_with(&path, format_out, &cloud.columns(), &options).unwrap();
            let (header, points) = las_points(&std::fs::read(&path).unwrap());
            assert_eq!(points, expected, "format {format}, compressed {compressed}");
            assert_eq!(header.point_format().to_u8().unwrap(), format);
            assert_eq!(header.transforms().x.scale, 0.001);
            assert_eq!(header.transforms().y.offset, 2000.0);
            let extra = header
                .all_vlrs()
                .find(|v| v.user_id == "LASF_Spec" && v.record_id == 4)
                .unwrap();
            assert_eq!(&extra.data[160..176], b"echo amplitude d");
            assert!(
                header
                    .all_vlrs()
                    .any(|v| v.user_id == "LASF_Projection" && v.data.starts_with(b"PROJCS"))
            );
        }

        // As PLY: every dimension a property of its type.
        let mut ply = Vec::new();
        write_ply_to(&mut ply, "o.ply", &cloud.columns(), PlyFormat::Ascii).unwrap();
        let text = String::from_utf8_lossy(&ply);
        assert!(text.contains("property ushort intensity\n"), "{text}");
        assert!(text.contains("property double scalar_gps_time\n"), "{text}");
        let back = read_ply(&ply[..], "o.ply").unwrap();
        assert_eq!(back.attributes, cloud.attributes);
    }
}

#[test]
fn attributes_of_a_ply_become_typed_las_extra_bytes() {
    let bytes = ply_fixture("binary_little_endian", false);
    let cloud = read_ply(&bytes[..], "f.ply").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("o.las");
    write_point_cloud(&path, &cloud.columns(), PlyFormat::default()).unwrap();
    let back = mls_io::read_point_cloud(&path).unwrap();
    // Point format 6's own dimensions first, then the PLY's attributes as they were; the
    // float `intensity` is not the 16-bit LAS intensity, so it is extra bytes of that name,
    // read back beside the standard one as `intensity_2`.
    let mut carried: Vec<Attribute> = back.attributes[15..].to_vec();
    assert_eq!(carried[3].name, "intensity_2");
    carried[3].name = "intensity".to_owned();
    assert_eq!(carried, expected_ply_attributes());
    assert_eq!(back.attributes[0].name, "intensity");
    assert_eq!(back.attributes[0].data, AttributeData::U16(vec![0; 3]));
}

#[test]
fn attributes_named_and_typed_as_las_fields_go_into_them() {
    let points = [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]];
    let intensity = Attribute {
        name: "intensity".to_owned(),
        data: AttributeData::U16(vec![7, 65535]),
    };
    let classification = Attribute {
        name: "classification".to_owned(),
        data: AttributeData::U8(vec![2, 200]),
    };
    // 20 does not fit the 4 bits of a return number: extra bytes, not the field.
    let return_number = Attribute {
        name: "return_number".to_owned(),
        data: AttributeData::U8(vec![1, 20]),
    };
    let columns = [
        Column::component("x", &points, Axis::X),
        Column::component("y", &points, Axis::Y),
        Column::component("z", &points, Axis::Z),
        Column::attribute(&intensity),
        Column::attribute(&classification),
        Column::attribute(&return_number),
    ];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.las");
    write_point_cloud(&path, &columns, PlyFormat::default()).unwrap();
    let (header, read) = las_points(&std::fs::read(&path).unwrap());
    assert_eq!(header.point_format().extra_bytes, 1);
    assert_eq!(read[1].intensity, 65535);
    assert_eq!(u8::from(read[1].classification), 200);
    assert_eq!(read[1].return_number, 1);
    assert_eq!(read[1].extra_bytes, [20]);
}

#[test]
fn an_extra_bytes_descriptor_beyond_the_record_is_an_error_naming_it() {
    let mut builder = Builder::from(Version::new(1, 4));
    builder.point_format = Format::new(6).unwrap();
    builder.point_format.extra_bytes = 2;
    let mut descriptor = [0u8; 192];
    descriptor[2] = 10; // f64: 8 bytes, but the records have 2
    descriptor[4..9].copy_from_slice(b"width");
    builder.vlrs.push(Vlr {
        user_id: "LASF_Spec".to_owned(),
        record_id: 4,
        description: "Extra Bytes".to_owned(),
        data: descriptor.to_vec(),
    });
    let mut writer = Writer::new(
        std::io::Cursor::new(Vec::new()),
        builder.into_header().unwrap(),
    )
    .unwrap();
    writer
        .write_point(Point {
            gps_time: Some(0.0),
            extra_bytes: vec![0, 0],
            ..Point::default()
        })
        .unwrap();
    let bytes = writer.into_inner().unwrap().into_inner();
    let err = read_point_cloud_from_with(&bytes[..], "w.las", FileFormat::Las, &Default::default())
        .unwrap_err();
    assert_message(
        &err,
        "w.las",
        &["extra bytes \"width\" (float64)", "each point has only 2"],
    );
}

/// A text token for an attribute cell: integers of every size, floats, NaN, or a word.
fn token() -> impl proptest::strategy::Strategy<Value = String> {
    use proptest::prelude::*;
    prop_oneof![
        any::<i32>().prop_map(|v| v.to_string()),
        any::<i64>().prop_map(|v| v.to_string()),
        any::<f64>().prop_map(|v| format!("{v:?}")),
        Just("nan".to_owned()),
        Just("-0.0".to_owned()),
        Just("roof".to_owned()),
    ]
}

proptest::proptest! {
    /// What the fuzz targets assert: a text file read, written and read again gives the same
    /// cloud (for XYZ, unless a column was dropped, which shifts the positions that name the
    /// others).
    #[test]
    fn text_attributes_survive_a_write_and_a_read(
        rows in proptest::collection::vec(proptest::collection::vec(token(), 1..5), 1..6),
        width in 1usize..5,
    ) {
        let mut xyz = String::new();
        let mut csv = String::from("x,y,z");
        for c in 0..width {
            csv.push_str(&format!(",a{c}"));
        }
        csv.push('\n');
        for (r, row) in rows.iter().enumerate() {
            let cells: Vec<&str> = (0..width).map(|c| row[c % row.len()].as_str()).collect();
            xyz.push_str(&format!("{r} 1 2 {}\n", cells.join(" ")));
            csv.push_str(&format!("{r},1,2,{}\n", cells.join(",")));
        }
        let read = mls_io::read_xyz_with(xyz.as_bytes(), "p.xyz", &Default::default()).unwrap();
        if !read.notes.iter().any(|n| n.contains("is not carried")) {
            let mut bytes = Vec::new();
            mls_io::write_xyz_to(&mut bytes, "p.xyz", &read.cloud.columns()).unwrap();
            proptest::prop_assert_eq!(mls_io::read_xyz(&bytes[..], "p.xyz").unwrap(), read.cloud);
        }
        let read = read_csv_with(csv.as_bytes(), "p.csv", &Default::default()).unwrap();
        let mut bytes = Vec::new();
        mls_io::write_csv_to(&mut bytes, "p.csv", &read.cloud.columns()).unwrap();
        proptest::prop_assert_eq!(mls_io::read_csv(&bytes[..], "p.csv").unwrap(), read.cloud);
    }
}
