//! Atomic output: a failed write leaves no file behind and the destination untouched.

use std::fs;
use std::path::Path;

use mls_io::{Column, PlyFormat, WriteError, same_file, write_csv, write_ply, write_point_cloud};

use crate::assert_message;

const XS: [f64; 3] = [1.0, 2.0, 3.0];

fn columns() -> Vec<Column<'static>> {
    vec![
        Column::f64("x", &XS),
        Column::f64("y", &XS),
        Column::f64("z", &XS),
    ]
}

/// The names in a directory, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn nonexistent_directory_is_an_error_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("missing").join("out.ply");
    let err = write_ply(&path, &columns(), PlyFormat::BinaryLittleEndian).unwrap_err();
    assert!(matches!(err, WriteError::Io { .. }), "{err:?}");
    assert_message(&err, &path.display().to_string(), &[]);
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn path_without_file_name_is_rejected() {
    let err = write_csv(Path::new("/"), &columns()).unwrap_err();
    assert!(matches!(err, WriteError::NotAFilePath { .. }), "{err:?}");
}

#[test]
fn failed_validation_creates_nothing_and_keeps_the_destination() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.csv");
    fs::write(&path, "old contents").unwrap();
    let short = [1.0];
    let bad = [Column::f64("x", &XS), Column::f64("y", &short)];
    assert!(write_csv(&path, &bad).is_err());
    assert_eq!(fs::read_to_string(&path).unwrap(), "old contents");
    assert_eq!(listing(dir.path()), ["out.csv"]);
}

/// The rename fails after the data is written (the destination is a directory): the
/// temporary file must be gone and the destination as it was.
#[test]
fn failure_after_writing_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("taken.ply");
    fs::create_dir(&path).unwrap();
    fs::write(path.join("inside"), "keep").unwrap();
    let err = write_point_cloud(&path, &columns(), PlyFormat::Ascii).unwrap_err();
    assert!(matches!(err, WriteError::Io { .. }), "{err:?}");
    assert_message(&err, &path.display().to_string(), &[]);
    assert_eq!(listing(dir.path()), ["taken.ply"]);
    assert_eq!(listing(&path), ["inside"]);
}

#[test]
fn successful_write_replaces_an_existing_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.csv");
    fs::write(
        &path,
        "old contents that are longer than the new ones, to be sure",
    )
    .unwrap();
    write_csv(&path, &columns()).unwrap();
    assert_eq!(
        fs::read_to_string(&path).unwrap(),
        "//x,y,z\n1.0,1.0,1.0\n2.0,2.0,2.0\n3.0,3.0,3.0\n"
    );
    assert_eq!(listing(dir.path()), ["out.csv"]);
}

#[test]
fn relative_path_in_current_directory_works() {
    // A bare file name has an empty parent, which must mean the current directory. The
    // name is unique to this test, which is the only one writing into the working directory.
    let name = format!("mls-io-test-{}.xyz", std::process::id());
    let path = Path::new(&name);
    let result = write_point_cloud(path, &columns(), PlyFormat::default());
    let contents = fs::read_to_string(path);
    let _ = fs::remove_file(path);
    result.unwrap();
    assert_eq!(
        contents.unwrap(),
        "# x y z\n1.0 1.0 1.0\n2.0 2.0 2.0\n3.0 3.0 3.0\n"
    );
}

#[cfg(unix)]
#[test]
fn output_gets_the_usual_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    // A file created directly gets 0666 less the umask; the written file must match it
    // rather than the 0600 of temporary files.
    let reference = dir.path().join("reference");
    fs::File::create(&reference).unwrap();
    let path = dir.path().join("out.ply");
    write_ply(&path, &columns(), PlyFormat::BinaryLittleEndian).unwrap();
    let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode(&path), mode(&reference));
}

/// Replacing a file keeps its mode, whatever it is: read-only stays read-only (the caller
/// decides whether to overwrite such a file at all), executable or group-writable stays so.
#[cfg(unix)]
#[test]
fn replaced_file_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode() & 0o777;
    for (name, before) in [("ro.csv", 0o444), ("rw.ply", 0o664), ("odd.xyz", 0o640)] {
        let path = dir.path().join(name);
        fs::write(&path, "old").unwrap();
        fs::set_permissions(&path, fs::Permissions::from_mode(before)).unwrap();
        write_point_cloud(&path, &columns(), PlyFormat::Ascii).unwrap();
        assert_ne!(fs::read(&path).unwrap(), b"old", "{name} was not replaced");
        assert_eq!(mode(&path), before, "{name}");
    }
}

/// Writing through a symbolic link replaces the file it points to and keeps the link.
#[cfg(unix)]
#[test]
fn symbolic_link_is_kept_and_its_target_replaced() {
    let dir = tempfile::tempdir().unwrap();
    fs::create_dir(dir.path().join("data")).unwrap();
    let target = dir.path().join("data").join("real.csv");
    fs::write(&target, "old").unwrap();
    let link = dir.path().join("link.csv");
    // A relative link, resolved against the link's directory.
    std::os::unix::fs::symlink(Path::new("data").join("real.csv"), &link).unwrap();
    write_csv(&link, &columns()).unwrap();
    assert!(
        fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(
        fs::read_to_string(&target)
            .unwrap()
            .starts_with("//x,y,z\n")
    );
    assert_eq!(listing(dir.path()), ["data", "link.csv"]);
    assert_eq!(listing(&dir.path().join("data")), ["real.csv"]);
}

#[test]
fn directory_as_input_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["scans", "scans.ply"] {
        let path = dir.path().join(name);
        fs::create_dir(&path).unwrap();
        let err = mls_io::read_point_cloud(&path).unwrap_err();
        assert!(
            matches!(err, mls_io::ReadError::IsADirectory { .. }),
            "{err:?}"
        );
        assert_message(&err, &path.display().to_string(), &["is a directory"]);
    }
}

#[test]
fn same_file_sees_through_spellings() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.ply");
    fs::write(&input, "ply").unwrap();
    fs::create_dir(dir.path().join("sub")).unwrap();
    let respelled = dir.path().join("sub").join("..").join("in.ply");
    assert!(same_file(&input, &input));
    assert!(same_file(&input, &respelled));
    assert!(!same_file(&input, &dir.path().join("out.ply")));
    // An output that does not exist yet, spelled two ways.
    let out = dir.path().join("out.ply");
    assert!(same_file(
        &out,
        &dir.path().join("sub").join("..").join("out.ply")
    ));
    #[cfg(unix)]
    {
        let link = dir.path().join("link.ply");
        std::os::unix::fs::symlink(&input, &link).unwrap();
        assert!(same_file(&input, &link));
        let hard = dir.path().join("hard.ply");
        fs::hard_link(&input, &hard).unwrap();
        assert!(same_file(&input, &hard));
    }
}
