//! Standard streams and named formats: `-` as input (format from --input-format, else
//! recognised from the data) and as output (CSV unless --output-format); a file with another
//! extension read with --input-format; a directory as input named as one; XYZ output naming its
//! columns in a `#` line.

use std::fs;
use std::path::Path;
use std::process::Stdio;

use crate::common::{
    CURVATURE_HEADER, Run, assert_one_line_error, bunny_path, mlscurv, run, run_ok,
    write_unit_sphere,
};

/// Points of the unit sphere the runs read.
const N: usize = 500;

/// Runs `mlscurv args…` with the file `stdin` on standard input.
fn run_with_stdin(args: &[&str], stdin: &Path) -> Run {
    run(mlscurv()
        .args(args)
        .stdin(Stdio::from(fs::File::open(stdin).unwrap())))
}

/// `curvature <input> -o <out> --quiet`, and the output's bytes.
fn curvature_file(input: &Path, out: &Path, extra: &[&str]) -> Vec<u8> {
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(input)
            .arg("-o")
            .arg(out)
            .arg("--quiet")
            .args(extra),
    );
    fs::read(out).unwrap()
}

#[test]
fn standard_input_in_every_format_gives_what_the_file_gives() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = dir.path().join("in.xyz");
    write_unit_sphere(&xyz, N);
    // The same cloud as CSV and binary PLY, written by mlscurv itself.
    let (csv, ply) = (dir.path().join("in.csv"), dir.path().join("in.ply"));
    for out in [&csv, &ply] {
        run_ok(
            mlscurv()
                .arg("normals")
                .arg(&xyz)
                .arg("-o")
                .arg(out)
                .arg("--quiet"),
        );
    }
    for input in [&xyz, &csv, &ply] {
        let expected = curvature_file(input, &dir.path().join("expected.csv"), &[]);
        // Recognised from the data, and named.
        let format = input.extension().unwrap().to_str().unwrap();
        for extra in [&[][..], &["--input-format", format][..]] {
            let out = dir.path().join("from-stdin.csv");
            let mut args = vec!["curvature", "-", "-o", out.to_str().unwrap(), "--quiet"];
            args.extend(extra);
            let r = run_with_stdin(&args, input);
            assert!(r.success, "{input:?} {extra:?}: {}", r.stderr);
            assert!(
                fs::read(&out).unwrap() == expected,
                "{input:?} {extra:?}: stdin differs from the file"
            );
        }
    }
}

#[test]
fn standard_output_gets_csv_by_default_and_the_named_format_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, N);
    let csv = curvature_file(&input, &dir.path().join("out.csv"), &[]);
    let r = run_ok(mlscurv().arg("curvature").arg(&input).args(["-o", "-"]));
    assert_eq!(r.stdout.as_bytes(), csv);
    // The summary goes to stderr and names the destination.
    assert!(
        r.stderr.contains("wrote           <stdout>"),
        "{}",
        r.stderr
    );
    let xyz = curvature_file(&input, &dir.path().join("out.xyz"), &[]);
    let r = run_ok(mlscurv().arg("curvature").arg(&input).args([
        "-o",
        "-",
        "--output-format",
        "xyz",
        "--quiet",
    ]));
    assert_eq!(r.stdout.as_bytes(), xyz);
    assert_eq!(r.stderr, "");
}

#[test]
fn stdin_to_stdout_through_a_pipe() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, N);
    let expected = curvature_file(&input, &dir.path().join("out.csv"), &[]);
    let r = run_with_stdin(&["curvature", "-", "-o", "-", "-q"], &input);
    assert!(r.success, "{}", r.stderr);
    assert_eq!(r.stdout.as_bytes(), expected);
}

#[test]
fn empty_standard_input_is_an_error_naming_it() {
    let r = run(mlscurv()
        .args(["curvature", "-", "-o", "-"])
        .stdin(Stdio::null()));
    assert_one_line_error(&r, "<stdin>", &["0 point(s)"]);
}

#[test]
fn other_extensions_are_read_with_input_format_and_refused_without() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = dir.path().join("in.xyz");
    write_unit_sphere(&xyz, N);
    let asc = dir.path().join("scan.asc");
    fs::copy(&xyz, &asc).unwrap();
    let expected = curvature_file(&xyz, &dir.path().join("a.csv"), &[]);
    let got = curvature_file(&asc, &dir.path().join("b.csv"), &["--input-format", "xyz"]);
    assert!(got == expected);
    let r = run(mlscurv()
        .arg("curvature")
        .arg(&asc)
        .arg("-o")
        .arg(dir.path().join("c.csv")));
    assert_one_line_error(
        &r,
        &asc.display().to_string(),
        &["\".asc\"", "--input-format"],
    );
    let r = run_ok(
        mlscurv()
            .arg("info")
            .arg(&asc)
            .args(["--input-format", "xyz"]),
    );
    assert!(r.stdout.contains("points          500"), "{}", r.stdout);
}

#[test]
fn a_directory_as_input_is_named_as_a_directory_by_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("in.xyz");
    write_unit_sphere(&good, N);
    for name in ["scans", "scans.ply"] {
        let scans = dir.path().join(name);
        fs::create_dir(&scans).unwrap();
        let out = dir.path().join("out.csv");
        for args in [
            vec!["curvature".into(), scans.clone(), "-o".into(), out.clone()],
            vec!["normals".into(), scans.clone(), "-o".into(), out.clone()],
            vec!["project".into(), scans.clone(), "-o".into(), out.clone()],
            vec!["info".into(), scans.clone()],
            vec![
                "eval".into(),
                "--cloud".into(),
                scans.clone(),
                "--queries".into(),
                good.clone(),
            ],
            vec![
                "eval".into(),
                "--cloud".into(),
                good.clone(),
                "--queries".into(),
                scans.clone(),
            ],
        ] {
            let r = run(mlscurv().args(&args));
            assert_one_line_error(&r, &scans.display().to_string(), &["is a directory"]);
            assert!(!out.exists());
        }
    }
}

#[test]
fn xyz_output_names_its_columns_and_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, N);
    let text = String::from_utf8(curvature_file(&input, &dir.path().join("k.xyz"), &[])).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        format!("# {}", CURVATURE_HEADER.replace(',', " "))
    );
    assert_eq!(lines.count(), N);
    // The normals command's XYZ (6 columns) reads back, header and all.
    let normals = dir.path().join("n.xyz");
    let text = String::from_utf8(normals_file(&input, &normals)).unwrap();
    assert!(text.starts_with("# x y z nx ny nz\n"), "{text:.60}");
    let r = run_ok(mlscurv().arg("info").arg(&normals));
    assert!(r.stdout.contains("points          500"), "{}", r.stdout);
    assert!(r.stdout.contains("normals         present"), "{}", r.stdout);
}

fn normals_file(input: &Path, out: &Path) -> Vec<u8> {
    run_ok(
        mlscurv()
            .arg("normals")
            .arg(input)
            .arg("-o")
            .arg(out)
            .arg("--quiet"),
    );
    fs::read(out).unwrap()
}

/// `info x.ply | head -1` and `curvature … -o - | head -1`: the reader leaves early; mlscurv
/// must stop quietly and successfully, not panic (as `info` did) or report a broken pipe.
#[test]
fn a_reader_that_leaves_early_is_not_an_error() {
    for args in [
        vec!["info".to_owned(), bunny_path().display().to_string()],
        vec![
            "curvature".to_owned(),
            bunny_path().display().to_string(),
            "-o".to_owned(),
            "-".to_owned(),
            "-q".to_owned(),
        ],
    ] {
        let mut child = mlscurv()
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Hang up at once: both read the bunny first, so they write into a closed pipe.
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert!(out.status.success(), "{args:?}: {stderr}");
        assert_eq!(stderr, "", "{args:?}");
    }
}
