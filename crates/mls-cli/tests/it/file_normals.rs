//! Normals read from a file are used as they are; when their signs are not consistent the
//! commands say so (the curvature near a flipped normal is wrong in sign and size).

use crate::common::{mlscurv, printed_agreement, run_ok, sphere, write_xyz};

const WARNING: &str = "the file's normals are not consistently oriented";

#[test]
fn flipped_file_normals_are_warned_about_and_consistent_ones_are_not() {
    let dir = tempfile::tempdir().unwrap();
    let (points, normals) = sphere();
    let good = dir.path().join("good.xyz");
    write_xyz(&good, &points, Some(&normals));
    // Every 25th normal of the lattice flipped: 4 % of the points, isolated from each other,
    // so a fraction 2 f (1 − f) = 7.7 % of neighbour pairs disagree.
    let flipped: Vec<[f64; 3]> = normals
        .iter()
        .enumerate()
        .map(|(i, n)| if i % 25 == 0 { n.map(|c| -c) } else { *n })
        .collect();
    let bad = dir.path().join("bad.xyz");
    write_xyz(&bad, &points, Some(&flipped));
    let queries = dir.path().join("q.xyz");
    write_xyz(&queries, &points[..10], None);

    for method in ["jet", "paper"] {
        let out = dir.path().join("out.csv");
        let r = run_ok(
            mlscurv()
                .args(["curvature", "--method", method, "-q", "-o"])
                .arg(&out)
                .arg(&good),
        );
        assert!(!r.stderr.contains(WARNING), "{method}: {}", r.stderr);
        let r = run_ok(
            mlscurv()
                .args(["curvature", "--method", method, "-q", "-o"])
                .arg(&out)
                .arg(&bad),
        );
        assert!(r.stderr.contains(WARNING), "{method}: {}", r.stderr);
        assert!(r.stderr.contains("bad.xyz") && r.stderr.contains("--normals estimate"));
        let agree = printed_agreement(&r.stderr);
        let expected = 100.0 * (1.0 - 2.0 * 0.04 * 0.96);
        assert!(
            (agree - expected).abs() < 1.0,
            "{agree}% against {expected}%"
        );
        // A warning, not a refusal: the output is written.
        assert!(out.exists());
        // Estimated normals replace the file's, and nothing is said.
        let r = run_ok(
            mlscurv()
                .args([
                    "curvature",
                    "--method",
                    method,
                    "--normals",
                    "estimate",
                    "-q",
                    "-o",
                ])
                .arg(&out)
                .arg(&bad),
        );
        assert!(!r.stderr.contains(WARNING), "{}", r.stderr);
    }

    // `eval` builds its surface from the file's normals too.
    let r = run_ok(
        mlscurv()
            .args(["eval", "--cloud"])
            .arg(&bad)
            .arg("--queries")
            .arg(&queries),
    );
    assert!(r.stderr.contains(WARNING), "{}", r.stderr);
    let r = run_ok(
        mlscurv()
            .args(["eval", "--cloud"])
            .arg(&good)
            .arg("--queries")
            .arg(&queries),
    );
    assert!(!r.stderr.contains(WARNING), "{}", r.stderr);
}
