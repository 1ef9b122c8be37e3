//! XYZ/TXT/PTS and CSV files with known contents.

use mls_io::{
    Attribute, AttributeData, ColumnNames, FileFormat, ReadError, ReadOptions, ReadOutcome,
    read_csv, read_csv_with, read_point_cloud_as_with, read_point_cloud_from_with,
    read_point_cloud_with, read_xyz, read_xyz_with,
};

#[test]
fn xyz_points_with_comments_tabs_and_crlf() {
    let text = "# exported\r\n\r\n1 2 3\r\n  # indented comment\n4\t5   6\n-1e-3 +2.5 0\n";
    let cloud = read_xyz(text.as_bytes(), "a.xyz").unwrap();
    assert_eq!(
        cloud.points,
        [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [-1e-3, 2.5, 0.0]]
    );
    assert_eq!(cloud.normals, None);
}

#[test]
fn xyz_points_with_normals() {
    let text = "1 2 3 0 0 1\n4 5 6 0.6 0.8 0\n";
    let cloud = read_xyz(text.as_bytes(), "a.txt").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0], [0.6, 0.8, 0.0]]));
}

#[test]
fn pts_point_count_line_is_skipped_once() {
    let cloud = read_xyz("2\n1 2 3\n4 5 6\n".as_bytes(), "a.pts").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    // Only the first data row may be a count: a second one is a short row.
    assert!(read_xyz("2\n3\n1 2 3\n".as_bytes(), "a.pts").is_err());
}

/// A count line that states another number of rows than follow (a truncated file, or a
/// header with no rows) is an error naming the line, in headerless text as in CSV.
#[test]
fn a_count_line_must_match_the_rows() {
    for (text, read, found) in [
        ("5\n", 0, "a.pts"),
        ("3\n1 2 3\n4 5 6\n", 2, "a.pts"),
        ("//X Y Z\n3\n1 2 3\n", 1, "a.asc"),
    ] {
        let err = read_xyz(text.as_bytes(), found).unwrap_err();
        assert!(
            matches!(err, ReadError::CountMismatch { found: f, .. } if f == read),
            "{text:?}: {err:?}"
        );
        assert!(
            err.to_string().starts_with(&format!("{found}: line ")),
            "{err}"
        );
    }
    let err = read_csv("x,y,z\n2\n1,2,3\n".as_bytes(), "a.csv").unwrap_err();
    assert!(
        matches!(
            err,
            ReadError::CountMismatch {
                line: 2,
                stated: 2,
                found: 1,
                ..
            }
        ),
        "{err:?}"
    );
}

/// ESRI's `.asc` grids share CloudCompare's extension: a raster is refused as one, by its
/// first keyword (any case), not read as a short row.
#[test]
fn an_esri_ascii_grid_is_refused_as_a_raster() {
    let grid = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n";
    for text in [grid.to_owned(), format!("# dem\n{}", grid.to_uppercase())] {
        let err = read_xyz(text.as_bytes(), "dem.asc").unwrap_err();
        assert!(matches!(err, ReadError::RasterGrid { .. }), "{err:?}");
        let message = err.to_string();
        let line = if text.starts_with('#') { 2 } else { 1 };
        assert!(
            message.starts_with(&format!("dem.asc: line {line}: ")),
            "{message}"
        );
        assert!(message.contains("ESRI ASCII grid"), "{message}");
    }
    let cloud = read_xyz("1 2 3\n".as_bytes(), "a.asc").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0]]);
    assert_eq!(FileFormat::from_extension("ASC"), Some(FileFormat::Xyz));
}

#[test]
fn empty_text_files_are_empty_clouds() {
    assert!(read_xyz("".as_bytes(), "a.xyz").unwrap().is_empty());
    assert!(
        read_xyz("# nothing\n\n".as_bytes(), "a.xyz")
            .unwrap()
            .is_empty()
    );
    let cloud = read_csv("x,y,z,nx,ny,nz\n".as_bytes(), "a.csv").unwrap();
    assert!(cloud.is_empty());
    assert_eq!(cloud.normals, Some(vec![]));
}

#[test]
fn csv_header_is_flexible_and_extra_columns_are_ignored() {
    let text = "\u{feff}id, \"Z\" ,label,X,y\n\
                7,3,\"a, \"\"quoted\"\" label\",1,2\n\
                \n\
                8, -6.5 ,plain,4,5\n";
    let cloud = read_csv(text.as_bytes(), "a.csv").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, -6.5]]);
    assert_eq!(cloud.normals, None);
}

#[test]
fn csv_with_normals() {
    let text = "nz,ny,nx,z,y,x\n1,0,0,3,2,1\n";
    let cloud = read_csv(text.as_bytes(), "a.csv").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0]]));
}

#[test]
fn csv_as_cloudcompare_and_spreadsheets_write_it() {
    // CloudCompare's header is a comment; PCL names normals normal_x ….
    let text = "//X,Y,Z,Nx,Ny,Nz\n1,2,3,0,0,1\n";
    let cloud = read_csv(text.as_bytes(), "cc.csv").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0]]));
    let text = "x;y;z;normal_x;normal_y;normal_z;intensity\n1;2;3;0;1;0;7\n4;5;6;1;0;0;8\n";
    let cloud = read_csv(text.as_bytes(), "semi.csv").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]));
    assert_eq!(cloud.attributes.len(), 1);
    // PDAL's `writers.text` names dimensions as PDAL does: `NormalX` ….
    let text = "\"X\",\"Y\",\"Z\",\"NormalX\",\"NormalY\",\"NormalZ\"\n1,2,3,0,0,1\n";
    let cloud = read_csv(text.as_bytes(), "pdal.csv").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0]]));
    assert!(cloud.attributes.is_empty());
    // A decimal comma with semicolons is not a number: said, not misread.
    let err = read_csv("x;y;z\n1,5;2;3\n".as_bytes(), "comma.csv").unwrap_err();
    let message = err.to_string();
    assert!(
        message.contains("comma.csv: line 2") && message.contains("\"1,5\""),
        "{message}"
    );
    // With commas in the header, semicolons are part of the fields.
    assert!(read_csv("x,y,z\n1;2;3\n".as_bytes(), "mixed.csv").is_err());
}

#[test]
fn xyz_column_names_from_a_cloudcompare_header() {
    let text = "//X Y Z Nx Ny Nz\n1 2 3 0 0 1\n4 5 6 0 0 -1\n";
    let cloud = read_xyz(text.as_bytes(), "cc.txt").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]));
    // Named colour columns are attributes, never normals, whatever their values.
    let cloud = read_xyz("//X Y Z R G B\n1 2 3 1 0 0\n".as_bytes(), "rgb.txt").unwrap();
    assert_eq!(cloud.normals, None);
    let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["R", "G", "B"]);
    // --columns overrides the file's names; a later `//` line is a comment.
    let outcome = read_with(
        "//X Y Z Nx Ny Nz\n1 2 3 0 0 1\n// end\n",
        Some("x,y,z,a,b,c"),
    )
    .unwrap();
    assert_eq!(outcome.cloud.normals, None);
    assert_eq!(outcome.cloud.points, [[1.0, 2.0, 3.0]]);
    // Names that do not match the rows are an error that says where they came from.
    let err = read_xyz("//X Y Z Scalar field\n1 2 3 4\n".as_bytes(), "sf.txt").unwrap_err();
    assert_eq!(
        err.to_string(),
        "sf.txt: line 2: 4 columns, but the `//` line 1 names x,y,z,Scalar,field"
    );
    let err = read_xyz("//X Y W\n1 2 3\n".as_bytes(), "w.txt").unwrap_err();
    assert!(
        err.to_string()
            .starts_with("w.txt: header line 1: column names after `//`"),
        "{err}"
    );
}

#[test]
fn xyz_column_names_from_a_first_row_of_names() {
    // Other tools write the names as a plain first row: no token is a number, so it is no point.
    let text = "X Y Z Nx Ny Nz intensity\n1 2 3 0 0 1 7\n4 5 6 0 0 -1 8\n";
    let cloud = read_xyz(text.as_bytes(), "named.xyz").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]));
    let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["intensity"]);
    // Colour stays colour; --columns overrides the row's names.
    let cloud = read_xyz("x y z r g b\n1 2 3 1 0 0\n".as_bytes(), "rgb.xyz").unwrap();
    assert_eq!(cloud.normals, None);
    let outcome = read_with("x y z nx ny nz\n1 2 3 0 0 1\n", Some("x,y,z,a,b,c")).unwrap();
    assert_eq!(outcome.cloud.normals, None);
    assert_eq!(outcome.cloud.points, [[1.0, 2.0, 3.0]]);
    // Names without x, y and z are an error at that row; a row with a number is data, and a
    // later row of names is not a number.
    let err = read_xyz("a b c\n1 2 3\n".as_bytes(), "abc.xyz").unwrap_err();
    assert!(
        err.to_string()
            .starts_with("abc.xyz: header line 1: the first row names the columns"),
        "{err}"
    );
    let err = read_xyz("x 2 3\n".as_bytes(), "x.xyz").unwrap_err();
    assert!(err.to_string().contains("not a number"), "{err}");
    let err = read_xyz("1 2 3\nx y z\n".as_bytes(), "late.xyz").unwrap_err();
    assert!(err.to_string().starts_with("late.xyz: line 2"), "{err}");
}

/// CloudCompare's ASCII export offers commas and semicolons as separators: the first row of
/// values (or of names) says which, and every row is read with it. Decimal commas and a
/// whitespace-separated row with commas in a text column are not taken for it.
#[test]
fn xyz_columns_separated_by_commas_or_semicolons() {
    let text = "//X,Y,Z,Nx,Ny,Nz\n1,2,3,0,0,1\n4.5, 5 ,6,0,0,-1\n";
    let cloud = read_xyz(text.as_bytes(), "cc.txt").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.5, 5.0, 6.0]]);
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]));
    let cloud = read_xyz("x;y;z;intensity\n1;2;3;7\n".as_bytes(), "semi.txt").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0]]);
    let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["intensity"]);
    let cloud = read_xyz("1, 2, 3\n4, 5, 6\n".as_bytes(), "spaced.xyz").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    // Every row takes the first row's separator: a later whitespace row has one column.
    let err = read_xyz("1,2,3\n4 5 6\n".as_bytes(), "mixed.xyz").unwrap_err();
    assert!(
        err.to_string().starts_with("mixed.xyz: line 2: 1 columns"),
        "{err}"
    );
    // Commas in a text column of a whitespace-separated row are that column's.
    let cloud = read_xyz("1 2 3 a,b,c\n4 5 6 d,e,f\n".as_bytes(), "tags.xyz").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    // Decimal commas are refused, saying so.
    let err = read_xyz("0,5 1,5 2,5\n".as_bytes(), "dec.txt").unwrap_err();
    assert_eq!(
        err.to_string(),
        "dec.txt: line 1, column 1 (x): not a number: \"0,5\" (a decimal comma? numbers are \
         read with a decimal point: 1.5, not 1,5)"
    );
}

#[test]
fn xyz_column_names_from_a_comment_that_names_every_column() {
    // As mlscurv writes XYZ: the names come back, so a result re-read keeps them.
    let text = "# made by mlscurv\n# x y z nx ny nz k1 status\n1 2 3 0 0 1 0.5 0\n";
    let cloud = read_xyz(text.as_bytes(), "out.xyz").unwrap();
    assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0]]));
    let names: Vec<&str> = cloud.attributes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["k1", "status"]);
    // Colour named as such is never taken for normals.
    let cloud = read_xyz("# X Y Z R G B\n1 2 3 1 0 0\n".as_bytes(), "rgb.xyz").unwrap();
    assert_eq!(cloud.normals, None);
    // A comment that is not one name per column, or lacks x y z, is only a comment.
    for comment in ["# x y z nx ny nz", "# a b c d e f", "# scan of: x y z"] {
        let text = format!("{comment}\n1 2 3 0 0 1\n");
        let cloud = read_xyz(text.as_bytes(), "c.xyz").unwrap();
        assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0]]), "{comment}");
        assert!(
            cloud.attributes.iter().all(|a| a.name.starts_with("col")),
            "{comment}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Which columns of a headerless file are normals (issue 14).

fn read_with(text: &str, columns: Option<&str>) -> Result<ReadOutcome, ReadError> {
    let options = ReadOptions {
        columns: columns.map(|c| ColumnNames::parse(c).unwrap()),
    };
    read_xyz_with(text.as_bytes(), "scan.txt", &options)
}

#[test]
fn rgb_as_0_to_255_integers_is_not_normals() {
    // CloudCompare's ASCII export with colour.
    let text = "0.5 1.5 2.5 255 128 0\n1.5 2.5 3.5 0 0 1\n2.5 3.5 4.5 12 200 37\n";
    let read = read_with(text, None).unwrap();
    assert_eq!(
        read.cloud.points,
        [[0.5, 1.5, 2.5], [1.5, 2.5, 3.5], [2.5, 3.5, 4.5]]
    );
    assert_eq!(read.cloud.normals, None);
    assert_eq!(read.notes.len(), 1, "{:?}", read.notes);
    let note = &read.notes[0];
    for part in [
        "scan.txt: columns 4-6 are not read as normals",
        "line 1: 255 128 0 has length 285.",
        "--columns",
    ] {
        assert!(note.contains(part), "{note}");
    }
}

#[test]
fn rgb_as_0_to_1_fractions_is_not_normals() {
    // Pure red and pure blue are unit vectors; grey on line 3 is not.
    let text = "0 0 0 1 0 0\n1 0 0 0 0 1\n0 1 0 0.5 0.5 0.5\n0 0 1 0.2 0.4 0.6\n";
    let read = read_with(text, None).unwrap();
    assert_eq!(read.cloud.len(), 4);
    assert_eq!(read.cloud.normals, None);
    assert!(
        read.notes[0].contains("line 3: 0.5 0.5 0.5 has length 0.866025"),
        "{:?}",
        read.notes
    );
}

#[test]
fn unit_columns_are_normals_within_the_tolerance() {
    // Three decimals (length 0.99937), a missing normal written as zeros and as NaN (the
    // curvature output of a failed point), and an exact unit vector.
    let text = "0 0 0 0.577 0.577 0.577\n1 0 0 0 0 0\n2 0 0 nan nan nan\n3 0 0 0.6 -0.8 0\n";
    let read = read_with(text, None).unwrap();
    assert_eq!(read.notes, Vec::<String>::new());
    assert_eq!(
        read.cloud.normals,
        Some(vec![
            [0.577, 0.577, 0.577],
            [0.0; 3],
            [0.0; 3],
            [0.6, -0.8, 0.0]
        ])
    );
    // Two decimals are outside 1e-3 (length 1.0046): not normals, and the note says so.
    let read = read_with("0 0 0 0.58 0.58 0.58\n", None).unwrap();
    assert_eq!(read.cloud.normals, None);
    assert!(
        read.notes[0].contains("length 1.004589"),
        "{:?}",
        read.notes
    );
    // All zeros is no normals.
    let read = read_with("0 0 0 0 0 0\n1 1 1 0 0 0\n", None).unwrap();
    assert_eq!(read.cloud.normals, None);
    assert!(
        read.notes[0].contains("0 0 0 on every row"),
        "{:?}",
        read.notes
    );
}

#[test]
fn four_and_seven_columns() {
    // x y z intensity: the fourth column is an attribute, unless it is not numbers.
    let read = read_with("1 2 3 17\n4 5 6 18\n", None).unwrap();
    assert_eq!(read.cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(read.cloud.normals, None);
    assert_eq!(
        read.cloud.attributes,
        [Attribute {
            name: "col4".to_owned(),
            data: AttributeData::I32(vec![17, 18]),
        }]
    );
    assert_eq!(
        read.notes,
        [
            "scan.txt: 4 columns; column 4 is carried as attribute col4 (name the columns with \
          --columns)"
        ]
    );
    let read = read_with("1 2 3 17\n4 5 6 roof\n", None).unwrap();
    assert!(read.cloud.attributes.is_empty());
    assert_eq!(
        read.notes[1],
        "scan.txt: column 4 (col4) is not carried to the output: line 2 holds \"roof\", not a \
         number"
    );
    // x y z nx ny nz intensity.
    let read = read_with("1 2 3 0 0 1 0.25\n4 5 6 1 0 0 0.5\n", None).unwrap();
    assert_eq!(
        read.cloud.normals,
        Some(vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    );
    assert_eq!(read.notes.len(), 1);
    assert!(read.notes[0].contains("7 columns; column 7 is carried as attribute col7"));
    assert_eq!(
        read.cloud.attributes,
        [Attribute {
            name: "col7".to_owned(),
            data: AttributeData::F64(vec![0.25, 0.5]),
        }]
    );
    // x y z r g b intensity: colour and intensity are attributes, not normals.
    let read = read_with("1 2 3 10 20 30 0.25\n", None).unwrap();
    assert_eq!(read.cloud.normals, None);
    assert_eq!(read.notes.len(), 2, "{:?}", read.notes);
    let names: Vec<&str> = read
        .cloud
        .attributes
        .iter()
        .map(|a| a.name.as_str())
        .collect();
    assert_eq!(names, ["col4", "col5", "col6", "col7"]);
    assert_eq!(read.cloud.attributes[1].data, AttributeData::I32(vec![20]));
    // Nine columns, colour then normals: 7-9 are not guessed at.
    let read = read_with("1 2 3 10 20 30 0 0 1\n", None).unwrap();
    assert_eq!(read.cloud.normals, None);
    assert!(
        read.notes[1].contains("columns 7-9 are carried as attributes col7-col9"),
        "{:?}",
        read.notes
    );
    // The old reader's entry point reads the same, without the notes.
    let cloud = read_xyz("1 2 3 10 20 30 0.25\n".as_bytes(), "a.xyz").unwrap();
    assert_eq!(cloud.points, [[1.0, 2.0, 3.0]]);
    assert_eq!(cloud.attributes.len(), 4);
}

#[test]
fn named_columns_override_the_rule() {
    // Colour then normals, named.
    let text = "1 2 3 10 20 30 0 0 1\n4 5 6 1 0 0 0 1 0\n";
    let read = read_with(text, Some("x,y,z,r,g,b,nx,ny,nz")).unwrap();
    assert_eq!(read.cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(
        read.cloud.normals,
        Some(vec![[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
    );
    assert!(read.notes.is_empty());
    // Unit vectors named as colours are not normals.
    let read = read_with("1 2 3 0 0 1\n", Some("x,y,z,r,g,b")).unwrap();
    assert_eq!(read.cloud.normals, None);
    assert!(read.notes.is_empty());
    // Any order; named normals are taken as they are, not checked for length.
    let read = read_with("9 1 2 3 0 0 2\n", Some("intensity,x,y,z,nx,ny,nz")).unwrap();
    assert_eq!(read.cloud.points, [[1.0, 2.0, 3.0]]);
    assert_eq!(read.cloud.normals, Some(vec![[0.0, 0.0, 2.0]]));
    // Errors name the file, the line and the field.
    let err = read_with("1 2 3 0 0 1\n4 5 6 0 x 1\n", Some("x,y,z,nx,ny,nz"))
        .unwrap_err()
        .to_string();
    assert_eq!(err, "scan.txt: line 2, column 5 (ny): not a number: \"x\"");
    let err = read_with("# head\n1 2 3 4 5 6\n", Some("x,y,z,nx,ny,nz,i"))
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "scan.txt: line 2: 6 columns, but --columns names x,y,z,nx,ny,nz,i"
    );
    // CSV: the names replace the header's.
    let options = ReadOptions {
        columns: Some(ColumnNames::parse("z,y,x,_").unwrap()),
    };
    let read = read_csv_with("a,b,c,d\n1,2,3,text\n".as_bytes(), "t.csv", &options).unwrap();
    assert_eq!(read.cloud.points, [[3.0, 2.0, 1.0]]);
    let err = read_csv_with("a,b\n1,2\n".as_bytes(), "t.csv", &options)
        .unwrap_err()
        .to_string();
    assert_eq!(err, "t.csv: line 1: 2 columns, but --columns names z,y,x,_");
}

#[test]
fn named_columns_are_refused_for_ply() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("a.ply");
    std::fs::write(
        &path,
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n",
    )
    .unwrap();
    let options = ReadOptions {
        columns: Some(ColumnNames::parse("x,y,z").unwrap()),
    };
    let err = read_point_cloud_with(&path, &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("a.ply: --columns applies to text files"),
        "{err}"
    );
    // Also when the format is named, for a file or a stream.
    let err = read_point_cloud_as_with(&path, FileFormat::Ply, &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("a.ply: --columns applies to text files"),
        "{err}"
    );
    let bytes = std::fs::read(&path).unwrap();
    let err = read_point_cloud_from_with(&bytes[..], "<stdin>", FileFormat::Ply, &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("<stdin>: --columns applies to text files"),
        "{err}"
    );
    assert_eq!(
        read_point_cloud_with(&path, &ReadOptions::default())
            .unwrap()
            .cloud
            .points,
        [[1.0, 2.0, 3.0]]
    );
}

#[test]
fn named_columns_apply_with_a_named_format_and_to_streams() {
    // Columns 4-6 are not unit vectors: without names they are skipped with a note.
    let text = "7 1 2 3 0 0 2\n8 4 5 6 0 2 0\n";
    let options = ReadOptions {
        columns: Some(ColumnNames::parse("i,x,y,z,nx,ny,nz").unwrap()),
    };
    let from_stream =
        read_point_cloud_from_with(text.as_bytes(), "<stdin>", FileFormat::Xyz, &options).unwrap();
    assert_eq!(from_stream.cloud.points, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    assert_eq!(
        from_stream.cloud.normals,
        Some(vec![[0.0, 0.0, 2.0], [0.0, 2.0, 0.0]])
    );
    assert!(from_stream.notes.is_empty(), "{:?}", from_stream.notes);
    let plain = read_point_cloud_from_with(
        text.as_bytes(),
        "<stdin>",
        FileFormat::Xyz,
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(plain.cloud.points, [[7.0, 1.0, 2.0], [8.0, 4.0, 5.0]]);
    assert_eq!(plain.cloud.normals, None);
    assert!(
        plain.notes.iter().any(|n| n.starts_with("<stdin>: ")),
        "{:?}",
        plain.notes
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scan.dat");
    std::fs::write(&path, text).unwrap();
    let from_file = read_point_cloud_as_with(&path, FileFormat::Xyz, &options).unwrap();
    assert_eq!(from_file, from_stream);
}
