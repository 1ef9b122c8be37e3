//! The default orientation of estimated normals: outward for a closed object, up for a sheet
//! seen from above (terrain and roofs), recognised by where the outward normals point.

use std::path::Path;

use mls_io::{Axis, Column, FileFormat};
use mls_shapes::{Scene, SceneConfig};

use crate::common::{Table, mlscurv, outward_fraction, run_ok, write_xyz};

/// An airborne scan of terrain, houses and trees (mls-shapes' scene), with the true normals
/// (up on ground and roofs, outward on walls).
fn scene(n: u64) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let scene = Scene::new(SceneConfig::default(), n).unwrap();
    (0..n)
        .map(|i| {
            let p = scene.point(i);
            let (q, n): ([f64; 3], [f64; 3]) = (p.position.coords.into(), p.normal.into());
            (q, n)
        })
        .unzip()
}

/// `mlscurv normals INPUT -o OUTPUT.csv` with `extra` arguments: the normals and stderr.
fn normals(input: &Path, output: &Path, extra: &[&str]) -> (Vec<[f64; 3]>, String) {
    let r = run_ok(
        mlscurv()
            .arg("normals")
            .arg(input)
            .arg("-o")
            .arg(output)
            .args(extra),
    );
    let table = Table::parse_csv(&std::fs::read_to_string(output).unwrap());
    (table.arrays(["nx", "ny", "nz"]), r.stderr)
}

/// The estimated normals within 60° of vertical, and those of them that point down (failed
/// estimates, written as 0 0 0, are not among them).
fn level_and_down(normals: &[[f64; 3]]) -> (usize, usize) {
    let level = normals.iter().filter(|n| n[2].abs() >= 0.5);
    let down = level.clone().filter(|n| n[2] < 0.0).count();
    (level.count(), down)
}

const CHOSEN: &str = "oriented up (+z) by minimum spanning tree and a vote per smooth patch \
                      (default for a sheet seen from above";

#[test]
fn an_airborne_scan_is_oriented_up_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let (points, truth) = scene(20_000);
    let las = dir.path().join("scan.las");
    let columns = [
        Column::component("x", &points, Axis::X),
        Column::component("y", &points, Axis::Y),
        Column::component("z", &points, Axis::Z),
    ];
    mls_io::write_point_cloud_as(&las, FileFormat::Las, &columns, mls_io::PlyFormat::Ascii)
        .unwrap();
    let (default, stderr) = normals(&las, &dir.path().join("default.csv"), &[]);
    assert!(stderr.contains(CHOSEN), "{stderr}");
    // Against the truth, where it is up or down.
    let (mut level, mut wrong) = (0, 0);
    for (t, e) in truth.iter().zip(&default) {
        if t[2].abs() >= 0.5 && e[2] != 0.0 {
            level += 1;
            wrong += usize::from(t[2] * e[2] < 0.0);
        }
    }
    assert!(level > 15_000, "{level} near-level normals");
    assert!(wrong * 1000 <= level, "{wrong} of {level} turned over");
    let (asked, stderr) = normals(&las, &dir.path().join("up.csv"), &["--orient", "up"]);
    assert!(!stderr.contains("default for a sheet"), "{stderr}");
    assert_eq!(default, asked);
}

#[test]
fn a_real_aerial_tile_is_oriented_up_where_outward_turns_roofs_over() {
    // A real aerial tile as text, so that no format says what it is.
    let dir = tempfile::tempdir().unwrap();
    let tile =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/lidar-buildings-b9.xyz");
    let (default, default_stderr) = normals(&tile, &dir.path().join("default.csv"), &[]);
    assert!(default_stderr.contains(CHOSEN), "{default_stderr}");
    let (level, down) = level_and_down(&default);
    assert!(
        level > 20_000 && down * 1000 < level,
        "{down} of {level} down"
    );
    // Asked for, outward leaves a share of roofs and ground facing down: the tree carries
    // the sign wrongly across creases. The default's choice is made on that result.
    let (outward, stderr) = normals(&tile, &dir.path().join("mst.csv"), &["--orient", "mst"]);
    assert!(stderr.contains("oriented outward"), "{stderr}");
    let (level, down) = level_and_down(&outward);
    assert!(
        down * 100 > level && down * 4 < level,
        "{down} of {level} down"
    );
    let share = format!(
        "outward left {:.1}% of the normals within 60° of vertical on one side",
        100.0 * (level - down) as f64 / level as f64
    );
    assert!(
        default_stderr.contains(&share),
        "{share:?} in\n{default_stderr}"
    );
}

#[test]
fn a_closed_object_stays_outward() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("sphere.xyz");
    let sphere = mls_shapes::fibonacci_sphere(5_000, 1.0);
    let points = mls_shapes::points(&sphere);
    write_xyz(&input, &points, None);
    let (n, stderr) = normals(&input, &dir.path().join("out.csv"), &[]);
    assert!(stderr.contains("oriented outward"), "{stderr}");
    let (level, down) = level_and_down(&n);
    assert!(
        (2 * down).abs_diff(level) * 50 < level,
        "{down} of {level} down"
    );
    let n: Vec<_> = n.into_iter().map(nalgebra::Vector3::from).collect();
    assert_eq!(outward_fraction(&points, &n), 1.0);
}
