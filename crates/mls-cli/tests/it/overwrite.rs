//! Existing outputs: a read-only file is refused unless `--force`, before any work is done;
//! a replaced file keeps its permissions; an output that cannot be written is reported before
//! the computation, not after it.

#![cfg(unix)]

use std::fs;
use std::os::unix::fs::PermissionsExt as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{assert_one_line_error, listing, mlscurv, run, run_ok, write_unit_sphere};

fn mode(path: &Path) -> u32 {
    fs::metadata(path).unwrap().permissions().mode() & 0o777
}

/// The four commands that write a file, with `input` and `-o out`.
fn writers(input: &Path, out: &Path) -> Vec<(&'static str, Command)> {
    ["curvature", "normals", "project", "eval"]
        .into_iter()
        .map(|name| {
            let mut cmd = mlscurv();
            if name == "eval" {
                cmd.arg("eval")
                    .arg("--cloud")
                    .arg(input)
                    .arg("--queries")
                    .arg(input);
            } else {
                cmd.arg(name).arg(input);
            }
            cmd.arg("-o").arg(out).arg("--quiet");
            (name, cmd)
        })
        .collect()
}

fn scene() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, 500);
    let out = dir.path().join("out.csv");
    (dir, input, out)
}

#[test]
fn read_only_output_is_refused_by_every_command_and_left_as_it_was() {
    let (dir, input, out) = scene();
    fs::write(&out, "keep me").unwrap();
    fs::set_permissions(&out, fs::Permissions::from_mode(0o444)).unwrap();
    let before = listing(dir.path());
    for (name, mut cmd) in writers(&input, &out) {
        let r = run(&mut cmd);
        assert_one_line_error(&r, &out.display().to_string(), &["read-only", "--force"]);
        assert_eq!(fs::read_to_string(&out).unwrap(), "keep me", "{name}");
        assert_eq!(mode(&out), 0o444, "{name}");
        assert_eq!(listing(dir.path()), before, "{name}: no temporary file");
    }
}

#[test]
fn force_replaces_a_read_only_output_and_keeps_it_read_only() {
    let (dir, input, out) = scene();
    for (name, mut cmd) in writers(&input, &out) {
        fs::write(&out, "old").unwrap();
        fs::set_permissions(&out, fs::Permissions::from_mode(0o444)).unwrap();
        run_ok(cmd.arg("--force"));
        let text = fs::read_to_string(&out).unwrap();
        assert!(text.starts_with("//x,y,z,"), "{name}: {text:.40}");
        assert_eq!(mode(&out), 0o444, "{name}");
        fs::remove_file(&out).unwrap();
    }
    assert_eq!(listing(dir.path()).len(), 1, "only the input is left");
}

#[test]
fn writable_output_is_replaced_and_keeps_its_mode() {
    let (_dir, input, out) = scene();
    for (name, mut cmd) in writers(&input, &out) {
        fs::write(&out, "old").unwrap();
        fs::set_permissions(&out, fs::Permissions::from_mode(0o640)).unwrap();
        run_ok(&mut cmd);
        assert_ne!(fs::read_to_string(&out).unwrap(), "old", "{name}");
        assert_eq!(mode(&out), 0o640, "{name}");
    }
}

/// A new output gets the mode a newly created file gets (0666 less the umask).
#[test]
fn new_output_gets_the_mode_of_a_new_file() {
    let (dir, input, out) = scene();
    let reference = dir.path().join("reference");
    fs::File::create(&reference).unwrap();
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .arg("-q"),
    );
    assert_eq!(mode(&out), mode(&reference));
}

/// A mistake in the output path is reported at once, not after the computation. The input does
/// not exist: the message must be about the output, so the output was checked first.
#[test]
fn bad_output_paths_fail_before_the_input_is_read() {
    let (dir, input, _) = scene();
    fs::create_dir(dir.path().join("taken")).unwrap();
    let missing_input = dir.path().join("missing-input.ply");
    let before = listing(dir.path());
    let cases: [(PathBuf, &[&str]); 4] = [
        (dir.path().join("out.dat"), &["\".dat\"", "--output-format"]),
        (
            dir.path().join("out"),
            &["no file extension", "--output-format"],
        ),
        (dir.path().join("taken"), &["is a directory"]),
        (dir.path().join("missing").join("out.csv"), &["os error"]),
    ];
    for (out, details) in cases {
        for command in ["curvature", "normals", "project"] {
            let r = run(mlscurv()
                .arg(command)
                .arg(&missing_input)
                .arg("-o")
                .arg(&out));
            assert_one_line_error(&r, &out.display().to_string(), details);
            assert!(!r.stderr.contains("missing-input"), "{}", r.stderr);
            assert_eq!(listing(dir.path()), before);
        }
    }
    // An extension and a contradicting --output-format.
    let out = dir.path().join("out.ply");
    let r = run(mlscurv()
        .arg("curvature")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--output-format", "csv"]));
    assert_one_line_error(
        &r,
        &out.display().to_string(),
        &["--output-format csv", "ply"],
    );
}
