//! The README's shell examples, run as written: every `mlscurv` line of its `sh` blocks, in
//! a temporary directory holding the repository's `tests/` and an empty `docs/`, with small
//! stand-ins for the files the examples only name (`big.laz`, `scan.ply`, `site.e57`) and a
//! temporary directory for `/scratch`. The blocks' `cargo` and `pip` lines are what CI runs
//! itself (`cargo xtask ci`, `.ci/python`).

use std::path::Path;

use super::common::{bunny_path, mlscurv, run_ok};
use super::e57::{poses, scanned_points, write_scans};

/// The `mlscurv` command lines of the README's `sh` blocks, comments removed.
fn readme_commands() -> Vec<String> {
    let readme = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md");
    let text = std::fs::read_to_string(readme).unwrap();
    let mut inside = false;
    let mut commands = Vec::new();
    for line in text.lines() {
        if line.starts_with("```") {
            inside = line == "```sh";
            continue;
        }
        let command = line.split(" #").next().unwrap_or("").trim();
        if inside && command.starts_with("mlscurv ") {
            commands.push(command.to_owned());
        }
    }
    commands
}

#[test]
fn the_readme_shell_examples_run_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    std::os::unix::fs::symlink(root.join("tests"), dir.path().join("tests")).unwrap();
    std::fs::create_dir(dir.path().join("docs")).unwrap();
    let scratch = tempfile::tempdir().unwrap();
    // Stand-ins: an airborne LiDAR tile as LAZ, a scan as PLY, two posed scans as E57.
    let lidar = root.join("tests/data/lidar-buildings-b9.xyz");
    run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&lidar)
            .args(["-o", "big.laz", "--method", "paper", "-q"])
            .current_dir(dir.path()),
    );
    std::fs::copy(bunny_path(), dir.path().join("scan.ply")).unwrap();
    let poses = poses();
    write_scans(
        &dir.path().join("site.e57"),
        &poses,
        &scanned_points(&poses),
    );
    let commands = readme_commands();
    assert!(commands.len() >= 5, "{commands:?}");
    for command in &commands {
        let command = command.replace("/scratch", &scratch.path().to_string_lossy());
        let args: Vec<&str> = command.split_whitespace().skip(1).collect();
        run_ok(mlscurv().args(&args).current_dir(dir.path()));
        let output = args
            .iter()
            .position(|a| *a == "-o")
            .and_then(|i| args.get(i + 1))
            .expect("every example writes a file");
        assert!(dir.path().join(output).is_file(), "{command}: no {output}");
    }
}
