//! Outputs are written atomically: after a successful run the directory holds the input and
//! the output, and no temporary file.

use std::collections::BTreeSet;
use std::ffi::OsString;

use crate::common::{listing, mlscurv, run_ok, write_xyz};

/// Points of the small sphere the runs read.
const SMALL_N: usize = 2_000;

#[test]
fn successful_runs_leave_exactly_the_input_and_the_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    let s = mls_shapes::fibonacci_sphere(SMALL_N, 1.0);
    write_xyz(
        &input,
        &mls_shapes::points(&s),
        Some(&mls_shapes::normals(&s)),
    );
    let runs: [(&str, &str, &[&str]); 7] = [
        ("curvature", "out.csv", &[]),
        ("curvature", "out.ply", &[]),
        ("curvature", "out.ply", &["--ascii"]),
        ("curvature", "out.xyz", &[]),
        ("normals", "out.ply", &[]),
        ("project", "out.ply", &[]),
        ("eval", "out.csv", &[]),
    ];
    for (command, output, extra) in runs {
        let out = dir.path().join(output);
        // Run twice: the second run replaces an existing output.
        for _ in 0..2 {
            let mut cmd = mlscurv();
            if command == "eval" {
                cmd.arg("eval")
                    .arg("--cloud")
                    .arg(&input)
                    .arg("--queries")
                    .arg(&input)
                    .arg("-o")
                    .arg(&out);
            } else {
                cmd.arg(command)
                    .arg(&input)
                    .arg("-o")
                    .arg(&out)
                    .arg("--quiet")
                    .args(extra);
            }
            run_ok(&mut cmd);
            let expected: BTreeSet<OsString> =
                ["in.xyz", output].into_iter().map(OsString::from).collect();
            assert_eq!(
                listing(dir.path()),
                expected,
                "after {command} -o {output} {extra:?}"
            );
        }
        std::fs::remove_file(&out).unwrap();
    }
}
