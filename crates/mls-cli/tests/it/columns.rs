//! Text columns that are not normals, `--columns`, and `--orient up` (issue 14).

use std::fmt::Write as _;
use std::path::Path;

use crate::common::{SPHERE_N, SPHERE_R, Table, median, mlscurv, run, run_ok, sphere};

/// Writes the sphere with extra columns around x y z: `before` and `after` give each row's
/// extra values as text.
fn write_columns(
    path: &Path,
    points: &[[f64; 3]],
    before: impl Fn(usize) -> String,
    after: impl Fn(usize) -> String,
) {
    let mut text = String::new();
    for (i, p) in points.iter().enumerate() {
        let _ = writeln!(text, "{}{} {} {}{}", before(i), p[0], p[1], p[2], after(i));
    }
    std::fs::write(path, text).unwrap();
}

/// Median mean curvature of `curvature` on `input`, and its stderr.
fn median_mean(input: &Path, args: &[&str]) -> (f64, String) {
    let out = input.with_extension("out.csv");
    let r = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(input)
            .arg("-o")
            .arg(&out)
            .args(args),
    );
    let table = Table::parse_csv(&std::fs::read_to_string(&out).unwrap());
    assert_eq!(table.rows.len(), SPHERE_N);
    let mean: Vec<f64> = table
        .column("mean")
        .into_iter()
        .filter(|v| v.is_finite())
        .collect();
    (median(&mean), r.stderr)
}

#[test]
fn rgb_columns_are_not_normals_and_curvature_is_right() {
    let (points, _) = sphere();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("rgb.txt");
    // CloudCompare's ASCII export with colour: 0-255 integers after x y z.
    write_columns(
        &input,
        &points,
        |_| String::new(),
        |i| format!(" {} {} {}", i % 256, (3 * i) % 256, 200),
    );
    let info = run_ok(mlscurv().arg("info").arg(&input));
    assert!(
        info.stdout.contains("normals         absent"),
        "{}",
        info.stdout
    );
    assert!(
        info.stderr
            .contains("rgb.txt: columns 4-6 are not read as normals"),
        "{}",
        info.stderr
    );
    // Estimated outward normals: the sphere's 1/R, as from a three-column file.
    let (mean, stderr) = median_mean(&input, &[]);
    assert!((mean - 1.0 / SPHERE_R).abs() < 1e-3, "median mean {mean}");
    assert!(stderr.contains("normals         estimated"), "{stderr}");
    assert!(stderr.contains("mlscurv: note: "), "{stderr}");
}

#[test]
fn named_columns_read_normals_anywhere_and_skip_the_rest() {
    let (points, normals) = sphere();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("named.xyz");
    // intensity x y z r g b nx ny nz: normals after colour, where no rule would look.
    write_columns(
        &input,
        &points,
        |i| format!("{} ", i % 7),
        |i| {
            let n = normals[i];
            format!(" 12 34 56 {} {} {}", n[0], n[1], n[2])
        },
    );
    let columns = "intensity,x,y,z,r,g,b,nx,ny,nz";
    let info = run_ok(
        mlscurv()
            .arg("info")
            .arg(&input)
            .args(["--columns", columns]),
    );
    assert!(
        info.stdout
            .contains("normals         present, 0 zero or invalid; consistently oriented"),
        "{}",
        info.stdout
    );
    assert!(info.stderr.is_empty(), "{}", info.stderr);
    // The MLS surface of exact normals on the sphere gives 1/R to 1e-6 (the jet, fitting the
    // samples' slopes as well, is off by about 2e-6).
    let (mean, stderr) = median_mean(
        &input,
        &[
            "--columns",
            columns,
            "--normals",
            "file",
            "--method",
            "paper",
        ],
    );
    assert!((mean - 1.0 / SPHERE_R).abs() < 1e-6, "median mean {mean}");
    assert!(stderr.contains("normals         from the file"), "{stderr}");
    // Without the names the file is ten columns: x y z would be taken from columns 1-3.
    // A wrong count is an error naming the file, the line and the names.
    let r = run(mlscurv()
        .arg("info")
        .arg(&input)
        .args(["--columns", "x,y,z,nx,ny,nz"]));
    assert!(!r.success);
    assert!(
        r.stderr
            .contains("named.xyz: line 1: 10 columns, but --columns names x,y,z,nx,ny,nz"),
        "{}",
        r.stderr
    );
}

#[test]
fn orient_up_and_its_check_in_the_summary() {
    // A wavy sheet z = 0.05 sin(4x) cos(3y) on a 60 × 60 grid, seen from above.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("sheet.xyz");
    let mut text = String::new();
    for i in 0..60 {
        for j in 0..60 {
            let (x, y) = (i as f64 / 30.0 - 1.0, j as f64 / 30.0 - 1.0);
            let z = 0.05 * (4.0 * x).sin() * (3.0 * y).cos();
            let _ = writeln!(text, "{x} {y} {z}");
        }
    }
    std::fs::write(&input, text).unwrap();
    for (orient, says) in [
        ("up", "oriented up (+z)"),
        (
            "viewpoint:0,0,1000",
            "oriented towards the viewpoint (0, 0, 1000)",
        ),
        (
            "viewpoint:0,0,-5",
            "oriented towards the viewpoint (0, 0, -5)",
        ),
    ] {
        let out = dir.path().join("normals.csv");
        let r = run_ok(
            mlscurv()
                .arg("normals")
                .arg(&input)
                .arg("-o")
                .arg(&out)
                .args(["--orient", orient]),
        );
        assert!(r.stderr.contains(says), "{}", r.stderr);
        let table = Table::parse_csv(&std::fs::read_to_string(&out).unwrap());
        let nz = table.column("nz");
        let below = orient.ends_with("-5");
        assert!(
            nz.iter().all(|&z| if below { z < -0.8 } else { z > 0.8 }),
            "{orient}"
        );
        let share = if orient == "up" {
            "100.00% of normals point up"
        } else {
            "100.00% of normals face the viewpoint"
        };
        assert!(r.stderr.contains(share), "{}", r.stderr);
        assert!(
            r.stderr
                .contains("100.00% of the 3600 within 60° of the line of sight"),
            "{}",
            r.stderr
        );
    }
}
