//! XYZ/TXT/PTS and CSV files with known contents.

use mls_io::{read_csv, read_xyz};

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
