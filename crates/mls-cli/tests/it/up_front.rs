//! What is decided before any work: whether `--memory` holds an input (else it is tiled; on
//! standard input, read whole, `--memory` is refused), and an output (or a tiled run's
//! temporary directory) that cannot be written, refused. Each
//! test gives an input whose reading would fail, so that an error naming the output, not the
//! input, shows that the output was checked first.

use std::path::Path;

use mls_io::{Axis, Column, PlyFormat};

use crate::common::{assert_one_line_error, listing, mlscurv, run, run_ok, write_unit_sphere};

/// A unit sphere with exact normals, `n` points, written by mls-io as binary PLY.
fn write_ply_sphere(path: &Path, n: usize) {
    let s = mls_shapes::fibonacci_sphere(n, 1.0);
    let (p, nrm) = (mls_shapes::points(&s), mls_shapes::normals(&s));
    let columns = [
        Column::component("x", &p, Axis::X),
        Column::component("y", &p, Axis::Y),
        Column::component("z", &p, Axis::Z),
        Column::component("nx", &nrm, Axis::X),
        Column::component("ny", &nrm, Axis::Y),
        Column::component("nz", &nrm, Axis::Z),
    ];
    mls_io::write_point_cloud(path, &columns, PlyFormat::default()).unwrap();
}

/// The estimate the refusal and the note quote, restated from crates/mls-cli/src/tiled/mod.rs
/// (400 bytes a point, 64 MiB besides).
fn estimate_mib(points: u64) -> f64 {
    (points * 400 + (64 << 20)) as f64 / f64::from(1 << 20)
}

#[test]
fn memory_is_checked_before_any_work_tiling_what_exceeds_it() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("sphere.ply");
    let xyz = dir.path().join("sphere.xyz");
    // 20,000 points: about 71.6 MiB by the estimate.
    write_ply_sphere(&ply, 20_000);
    write_unit_sphere(&xyz, 20_000);
    let need = format!("{:.1} MiB", estimate_mib(20_000));
    assert_eq!(need, "71.6 MiB");
    for input in [&ply, &xyz] {
        let output = dir.path().join("out.ply");
        let r = run_ok(
            mlscurv()
                .arg("curvature")
                .arg(input)
                .arg("-o")
                .arg(&output)
                .args(["--h", "0.05", "--memory", "70MiB"]),
        );
        assert!(
            r.stderr.contains(&format!(
                "{}: 20000 points need about 71.6 MiB, more than 70 MiB (--memory): evaluating \
                 in tiles",
                input.display()
            )),
            "{}",
            r.stderr
        );
        assert!(r.stderr.contains("  tiles           "), "{}", r.stderr);
        std::fs::remove_file(&output).unwrap();
        let r = run_ok(
            mlscurv()
                .arg("curvature")
                .arg(input)
                .arg("-o")
                .arg(&output)
                .args(["--h", "0.05", "--memory", "72MiB"]),
        );
        assert!(
            r.stderr.contains(&format!(
                "{}: 20000 points need about 71.6 MiB, within --memory 72 MiB: evaluating in memory",
                input.display()
            )),
            "{}",
            r.stderr
        );
        assert!(r.stderr.contains("  points read     20000"), "{}", r.stderr);
        std::fs::remove_file(&output).unwrap();
    }
    // A budget cannot be checked on standard input, whose size is unknown: refused.
    let r = run(mlscurv()
        .args(["curvature", "-", "--input-format", "ply", "-o"])
        .arg(dir.path().join("out.ply"))
        .args(["--memory", "1GiB"])
        .stdin(std::fs::File::open(&ply).unwrap()));
    assert_one_line_error(
        &r,
        "<stdin>",
        &["--memory 1 GiB: standard input is read whole"],
    );
}

/// A bad input (not PLY) beside outputs that cannot be written: the output's error comes
/// first, so it comes before the input is read.
#[cfg(target_os = "linux")]
#[test]
fn an_output_that_cannot_be_written_is_refused_before_the_input_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.ply");
    std::fs::write(&bad, "not a ply file\n").unwrap();
    // A symbolic link into a directory that does not exist (the link's own directory does),
    // and a directory nobody can create files in, root included.
    let link = dir.path().join("link.ply");
    std::os::unix::fs::symlink(dir.path().join("missing/out.ply"), &link).unwrap();
    let proc_out = Path::new("/proc/mlscurv-out.ply");
    for output in [link.as_path(), proc_out] {
        let name = output.display().to_string();
        let r = run(mlscurv().arg("curvature").arg(&bad).arg("-o").arg(output));
        assert_one_line_error(&r, &name, &[]);
        assert!(!r.stderr.contains("bad.ply"), "{}", r.stderr);
        let r = run(mlscurv()
            .args(["eval", "--cloud"])
            .arg(&bad)
            .arg("--queries")
            .arg(&bad)
            .arg("-o")
            .arg(output));
        assert_one_line_error(&r, &name, &[]);
        assert!(!r.stderr.contains("bad.ply"), "{}", r.stderr);
        for command in ["normals", "project"] {
            let r = run(mlscurv().arg(command).arg(&bad).arg("-o").arg(output));
            assert_one_line_error(&r, &name, &[]);
            assert!(!r.stderr.contains("bad.ply"), "{command}: {}", r.stderr);
        }
    }
    let r = run(mlscurv().arg("curvature").arg(&bad).arg("-o").arg(proc_out));
    // The operating system's words for the cause (`No such file or directory (os error 2)`).
    assert!(
        r.stderr.contains("cannot create a file in /proc: ") && r.stderr.contains("(os error "),
        "{}",
        r.stderr
    );
    let png = Path::new("/proc/mlscurv-out.png");
    let r = run(mlscurv().arg("render").arg(&bad).arg("-o").arg(png));
    assert_one_line_error(
        &r,
        "/proc/mlscurv-out.png",
        &["cannot create a file in /proc"],
    );
    // Nothing left behind: the link, the input, no temporary file.
    assert_eq!(listing(dir.path()).len(), 2, "{:?}", listing(dir.path()));
}
