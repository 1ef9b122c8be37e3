//! The readers on the fuzz seed corpus (crates/mls-io/fuzz/seeds), every truncation and many
//! byte edits of it: the properties the cargo-fuzz targets check, on every `cargo test`
//! without a fuzzer. See docs/robustness.md.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use mls_io::{
    PlyFormat, PointCloud, ReadError, ReadOptions, read_csv, read_ply, read_xyz, read_xyz_with,
    write_csv_to, write_ply_to, write_xyz_to,
};

fn seeds(format: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../crates/mls-io/fuzz/seeds")
        .join(format);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.unwrap().path())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no seeds in {}", dir.display());
    files
        .into_iter()
        .map(|path| {
            let bytes = std::fs::read(&path).unwrap();
            (path, bytes)
        })
        .collect()
}

/// What the fuzz targets assert: an `Ok` cloud is finite, has one normal per point and
/// survives a write and re-read (an XYZ file unless a column was dropped); an error is one
/// line starting with the display name.
fn check(format: &str, bytes: &[u8], what: &str) {
    let name = format!("seed.{format}");
    let started = Instant::now();
    let read = |b: &[u8]| -> Result<PointCloud, ReadError> {
        match format {
            "ply" => read_ply(b, &name),
            "xyz" => read_xyz(b, &name),
            _ => read_csv(b, &name),
        }
    };
    // A headerless file's attributes are named by position: a column dropped for holding text
    // shifts the names of those after it in the file written back.
    let dropped = format == "xyz"
        && read_xyz_with(bytes, &name, &ReadOptions::default())
            .is_ok_and(|r| r.notes.iter().any(|n| n.contains("is not carried")));
    match read(bytes) {
        Ok(cloud) => {
            assert!(
                cloud.points.iter().flatten().all(|c| c.is_finite()),
                "{what}"
            );
            if let Some(normals) = &cloud.normals {
                assert_eq!(normals.len(), cloud.len(), "{what}");
                assert!(normals.iter().flatten().all(|c| c.is_finite()), "{what}");
            }
            if (cloud.is_empty() && format == "xyz") || dropped {
                return;
            }
            let mut out = Vec::new();
            match format {
                "ply" => write_ply_to(&mut out, &name, &cloud.columns(), PlyFormat::Ascii),
                "xyz" => write_xyz_to(&mut out, &name, &cloud.columns()),
                _ => write_csv_to(&mut out, &name, &cloud.columns()),
            }
            .unwrap();
            assert_eq!(read(&out).unwrap(), cloud, "{what}: round trip");
        }
        Err(err) => {
            let message = err.to_string();
            assert!(!message.contains('\n'), "{what}: {message:?}");
            assert!(message.starts_with(&name), "{what}: {message:?}");
        }
    }
    // Even a header claiming 10¹² vertices fails as soon as the input ends.
    assert!(started.elapsed() < Duration::from_secs(2), "{what}: slow");
}

#[test]
fn seeds_their_truncations_and_byte_edits_read_or_fail_cleanly() {
    for format in ["ply", "xyz", "csv"] {
        for (path, bytes) in seeds(format) {
            let what = path.display().to_string();
            check(format, &bytes, &what);
            for cut in 0..bytes.len() {
                check(format, &bytes[..cut], &format!("{what} cut at {cut}"));
            }
            for at in 0..bytes.len() {
                for byte in [b'\n', b' ', b'0', b'-', b',', b'"', 0x00, 0xff] {
                    let mut edited = bytes.clone();
                    edited[at] = byte;
                    check(format, &edited, &format!("{what} byte {at} = {byte:#x}"));
                }
            }
        }
    }
}

#[test]
fn seeds_claiming_a_trillion_vertices_fail_with_a_located_error() {
    for (path, bytes) in seeds("ply") {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if !name.starts_with("huge_count") {
            continue;
        }
        let message = read_ply(&bytes[..], &name).unwrap_err().to_string();
        let located = message.contains("byte") || message.contains("line");
        assert!(located && message.contains("vertex"), "{name}: {message}");
    }
}

/// A header with very many properties parses in linear time. Found by fuzzing-adjacent
/// testing: the duplicate-name check used to scan every earlier property (O(n²): 41 s for
/// 2·10⁵ properties); it now uses a set.
#[test]
fn a_header_with_many_properties_is_parsed_in_linear_time() {
    let n = 200_000;
    let mut header = String::from(
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
         property float z\n",
    );
    for i in 0..n {
        header.push_str(&format!("property uchar p{i}\n"));
    }
    header.push_str("end_header\n");
    let started = Instant::now();
    let err = read_ply(header.as_bytes(), "wide.ply").unwrap_err();
    let seconds = started.elapsed().as_secs_f64();
    assert!(err.to_string().contains("vertex 0"), "{err}");
    assert!(
        seconds < 2.0,
        "{n} properties ({} bytes) took {seconds:.1} s",
        header.len()
    );
}
