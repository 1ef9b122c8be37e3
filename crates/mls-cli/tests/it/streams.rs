//! Standard streams and named formats: `-` as input (format from --input-format, else
//! recognised from the data) and as output (CSV unless --output-format); a file with another
//! extension read with --input-format; a directory as input named as one; XYZ output naming its
//! columns in a `#` line.

use std::fs;
use std::path::Path;
use std::process::Stdio;

use crate::common::{
    JET_HEADER, Run, assert_one_line_error, bunny_path, mlscurv, run, run_ok, write_unit_sphere,
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
    // And as headerless comma-separated rows (an XYZ file, not a CSV one: no header).
    let commas = dir.path().join("in-commas.xyz");
    let text = fs::read_to_string(&xyz).unwrap();
    let rows: Vec<String> = text
        .lines()
        .map(|l| l.split_ascii_whitespace().collect::<Vec<_>>().join(","))
        .collect();
    fs::write(&commas, rows.join("\n") + "\n").unwrap();
    let whitespace = curvature_file(&xyz, &dir.path().join("whitespace.csv"), &[]);
    assert!(curvature_file(&commas, &dir.path().join("commas.csv"), &[]) == whitespace);
    for input in [&xyz, &csv, &ply, &commas] {
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
    let other = dir.path().join("scan.dat");
    fs::copy(&xyz, &other).unwrap();
    let expected = curvature_file(&xyz, &dir.path().join("a.csv"), &[]);
    let got = curvature_file(
        &other,
        &dir.path().join("b.csv"),
        &["--input-format", "xyz"],
    );
    assert!(got == expected);
    let r = run(mlscurv()
        .arg("curvature")
        .arg(&other)
        .arg("-o")
        .arg(dir.path().join("c.csv")));
    assert_one_line_error(
        &r,
        &other.display().to_string(),
        &["\".dat\"", "--input-format"],
    );
    let r = run_ok(
        mlscurv()
            .arg("info")
            .arg(&other)
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
        format!("# {}", JET_HEADER.replace(',', " "))
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

/// `--columns` names the columns of standard input as of a file; for PLY (named or
/// recognised) it is refused, as for a PLY file.
#[test]
fn columns_apply_to_standard_input() {
    let dir = tempfile::tempdir().unwrap();
    let sphere = dir.path().join("sphere.xyz");
    write_unit_sphere(&sphere, N);
    // intensity x y z nx ny nz: without the names, columns 4-6 (z nx ny) are not unit vectors.
    let named = dir.path().join("named.txt");
    let text: String = fs::read_to_string(&sphere)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, line)| format!("{} {line}\n", i % 7))
        .collect();
    fs::write(&named, text).unwrap();
    let columns = ["--columns", "intensity,x,y,z,nx,ny,nz"];
    let from_file = run_ok(mlscurv().arg("info").arg(&named).args(columns));
    let mut args = vec!["info", "-"];
    args.extend(columns);
    let from_stdin = run_with_stdin(&args, &named);
    assert!(from_stdin.success, "{}", from_stdin.stderr);
    assert!(
        from_stdin.stdout.contains("normals         present"),
        "{}",
        from_stdin.stdout
    );
    assert_eq!(
        from_stdin
            .stdout
            .replace("<stdin>", &named.display().to_string()),
        from_file.stdout
    );
    assert_eq!(from_stdin.stderr, "");
    // Without the names, standard input gets the file's note, naming <stdin>.
    let r = run_with_stdin(&["info", "-"], &named);
    assert!(r.success, "{}", r.stderr);
    assert!(
        r.stderr.contains("mlscurv: note: <stdin>: "),
        "{}",
        r.stderr
    );
    // Curvature from standard input with the names equals curvature from the file.
    let out = dir.path().join("k.csv");
    let expected = curvature_file(&named, &out, &["--columns", "intensity,x,y,z,nx,ny,nz"]);
    let mut args = vec!["curvature", "-", "-o", "-", "-q"];
    args.extend(columns);
    let r = run_with_stdin(&args, &named);
    assert!(r.success, "{}", r.stderr);
    assert!(
        r.stdout.as_bytes() == expected,
        "stdin differs from the file"
    );
    // PLY on standard input names its own properties.
    let ply = dir.path().join("in.ply");
    run_ok(
        mlscurv()
            .arg("normals")
            .arg(&sphere)
            .arg("-o")
            .arg(&ply)
            .arg("--quiet"),
    );
    for extra in [&[][..], &["--input-format", "ply"][..]] {
        let mut args = vec!["info", "-", "--columns", "x,y,z"];
        args.extend(extra);
        let r = run_with_stdin(&args, &ply);
        assert_one_line_error(&r, "<stdin>", &["--columns applies to text files"]);
    }
}
