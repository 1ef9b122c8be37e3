//! An h on the scale of the whole cloud: `--h 1000` on the 0.25 m bunny used to run 300 times
//! longer and report every point "ok" with k ≈ 1e-6. Far beyond the cloud (over 10 times its
//! bounding-box diagonal) h is refused; beyond the cloud, when the kernel's weight (3h) spans
//! most of it, or when its support holds so many points that the run will be slow, there is a
//! warning on stderr, also with `--quiet`.

use std::path::Path;

use crate::common::{
    Run, assert_one_line_error, bunny_path, listing, mlscurv, run, run_ok, write_unit_sphere,
};

/// Points of the unit sphere (bounding-box diagonal 2√3 ≈ 3.46).
const N: usize = 500;

fn curvature(input: &Path, out: &Path, extra: &[&str]) -> Run {
    run(mlscurv()
        .arg("curvature")
        .arg(input)
        .arg("-o")
        .arg(out)
        .args(extra))
}

fn warnings(r: &Run) -> Vec<&str> {
    r.stderr
        .lines()
        .filter(|l| l.starts_with("mlscurv: warning:"))
        .collect()
}

#[test]
fn h_far_beyond_the_bunny_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.ply");
    let r = curvature(&bunny_path(), &out, &["--h", "1000"]);
    assert_one_line_error(
        &r,
        &bunny_path().display().to_string(),
        &["h = 1000", "bounding box", "mlscurv info"],
    );
    assert!(listing(dir.path()).is_empty());
    // The same from --h-factor, and in the other commands that build a surface.
    let r = curvature(&bunny_path(), &out, &["--h-factor", "1e6"]);
    assert_one_line_error(&r, &bunny_path().display().to_string(), &["bounding box"]);
    let r = run(mlscurv()
        .arg("project")
        .arg(bunny_path())
        .arg("-o")
        .arg(&out)
        .args(["--h", "1000"]));
    assert_one_line_error(&r, &bunny_path().display().to_string(), &["bounding box"]);
}

#[test]
fn eval_refuses_h_far_beyond_the_cloud() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, N);
    let r = run(mlscurv()
        .arg("eval")
        .arg("--cloud")
        .arg(&input)
        .arg("--queries")
        .arg(&input)
        .args(["--h", "100"]));
    assert_one_line_error(&r, &input.display().to_string(), &["bounding box"]);
}

#[test]
fn h_beyond_the_cloud_or_a_kernel_holding_most_of_it_is_warned_about_even_when_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, N);
    let out = dir.path().join("out.csv");
    // h = 5 exceeds the diagonal 3.46; h = 1 does not, but 3h spans the sphere.
    for (h, says) in [
        ("5", "exceeds the cloud's extent"),
        ("1", "spans on average 100% of the 500 points"),
    ] {
        for quiet in [false, true] {
            let mut extra = vec!["--h", h];
            if quiet {
                extra.push("--quiet");
            }
            let r = curvature(&input, &out, &extra);
            assert!(r.success, "{}", r.stderr);
            let w = warnings(&r);
            assert_eq!(w.len(), 1, "h = {h}, quiet {quiet}:\n{}", r.stderr);
            assert!(w[0].contains(says), "{}", w[0]);
            assert!(w[0].contains("overall smoothed shape"), "{}", w[0]);
            assert!(w[0].ends_with("`mlscurv info` suggests an h"), "{}", w[0]);
            assert!(w[0].contains("in.xyz"), "{}", w[0]);
            assert_eq!(r.stderr.contains("points read"), !quiet, "{}", r.stderr);
        }
    }
}

/// The default h on a small cloud: its cutoff (5h) holds most of the 500 points, which costs
/// nothing and changes nothing (the weight there is below 1e-10), so there is no warning.
#[test]
fn default_h_on_a_small_cloud_gives_no_warning() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, N);
    let r = curvature(&input, &dir.path().join("out.csv"), &["--quiet"]);
    assert!(r.success, "{}", r.stderr);
    assert_eq!(r.stderr, "");
}

/// The advice follows where h came from: on a cloud too small for a local fit the default h
/// already is the suggested one, and a large --h-factor is named.
#[test]
fn the_advice_follows_where_h_came_from() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("five.xyz");
    std::fs::write(&input, "0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 2 0\n").unwrap();
    let out = dir.path().join("out.csv");
    // The paper's surface, which has a result on five points (the jet has none, an error).
    for (extra, advice) in [
        (
            &["-q", "--method", "paper"][..],
            "the cloud has too few points for a local fit",
        ),
        (
            &["-q", "--method", "paper", "--h-factor", "3"][..],
            "a smaller --h-factor than 3 gives a smaller h",
        ),
    ] {
        let r = curvature(&input, &out, extra);
        assert!(r.success, "{}", r.stderr);
        let w = warnings(&r);
        assert_eq!(w.len(), 1, "{extra:?}: {}", r.stderr);
        assert!(w[0].contains("exceeds the cloud's extent"), "{}", w[0]);
        assert!(w[0].ends_with(advice), "{}", w[0]);
    }
}

/// Without a cutoff every evaluation visits every sample: on 12,000 points that is slow enough to
/// say so. Through `eval` with no queries, so that the test itself is not slow.
#[test]
fn a_support_holding_many_points_is_warned_about_as_slow() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, 12_000);
    let queries = dir.path().join("none.xyz");
    std::fs::write(&queries, "").unwrap();
    for (cutoff, slow) in [("none", true), ("5", false)] {
        let r = run_ok(
            mlscurv()
                .arg("eval")
                .arg("--cloud")
                .arg(&input)
                .arg("--queries")
                .arg(&queries)
                .args(["--cutoff", cutoff, "--quiet"]),
        );
        let w = warnings(&r);
        assert_eq!(
            w.len(),
            usize::from(slow),
            "--cutoff {cutoff}:\n{}",
            r.stderr
        );
        if slow {
            assert!(
                w[0].contains("holds about 12000 of the 12000 points") && w[0].contains("long run"),
                "{}",
                w[0]
            );
        }
        assert_eq!(r.stdout.lines().count(), 1, "the header only");
    }
}

#[test]
fn default_h_on_the_bunny_gives_no_warning() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let r = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(bunny_path())
            .arg("-o")
            .arg(&out),
    );
    assert!(warnings(&r).is_empty(), "{}", r.stderr);
}

/// The other end: an h well below the spacing leaves each point a sample or two of weight,
/// and says so; at the spacing itself (about 12 within 2h) it does not.
#[test]
fn an_h_below_the_spacing_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    let n = 20_000;
    write_unit_sphere(&input, n);
    let spacing = (4.0 * std::f64::consts::PI / n as f64).sqrt();
    let out = dir.path().join("out.csv");
    for (factor, warned) in [(0.4, true), (1.0, false), (2.0, false)] {
        let h = format!("{}", factor * spacing);
        let r = curvature(&input, &out, &["-q", "--method", "paper", "--h", &h]);
        assert!(r.success, "{}", r.stderr);
        let w = warnings(&r);
        assert_eq!(w.len(), usize::from(warned), "h = {factor} s: {}", r.stderr);
        if warned {
            assert!(w[0].contains("other samples within 2h"), "{}", w[0]);
            assert!(w[0].contains("too few for a fit"), "{}", w[0]);
        }
    }
}
