//! `eval`: the implicit function g, its gradient and Hessian at query points around the
//! sphere.

use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::common::{EVAL_HEADER, SPHERE_R, Table, listing, mlscurv, run_ok, sphere, write_xyz};

/// Query directions, none near the Fibonacci lattice's poles.
const DIRECTIONS: [[f64; 3]; 5] = [
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 1.0, 1.0],
    [-0.3, 0.5, 0.2],
    [0.6, -0.8, 0.1],
];

/// Radial offset of the inside and outside queries, as a fraction of R: 0.005, a fifth of h.
/// Amenta and Kil's g = n(x) · ∇e(x, n(x)) behaves like 2 Σ θ_i d_i (1 − d_i²/h²) in the
/// signed distances d_i to the samples, so it has further zero crossings about h from the
/// surface (measured: g < 0 at 1.05 R, g > 0 at 0.9 R); the sign test must stay well
/// inside that band.
const OFFSET: f64 = 0.01;

/// Distance of the far query, in units of R.
const FAR: f64 = 100.0;

/// Largest angle (rad) between ∇g and the radius at a point on the sphere.
const MAX_GRADIENT_ANGLE: f64 = 1e-3;

/// The kinds of query, in the order they are written for each direction.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    On,
    Inside,
    Outside,
}

const KINDS: [(Kind, f64); 3] = [
    (Kind::On, 1.0),
    (Kind::Inside, 1.0 - OFFSET),
    (Kind::Outside, 1.0 + OFFSET),
];

fn unit(d: [f64; 3]) -> Vector3<f64> {
    Vector3::from(d).normalize()
}

/// The queries: for each direction on, inside and outside the sphere, then one far away.
fn queries() -> Vec<(Option<Kind>, [f64; 3])> {
    let mut q: Vec<(Option<Kind>, [f64; 3])> = DIRECTIONS
        .iter()
        .flat_map(|&d| KINDS.map(|(kind, s)| (Some(kind), (unit(d) * (s * SPHERE_R)).into())))
        .collect();
    q.push((None, (unit(DIRECTIONS[2]) * (FAR * SPHERE_R)).into()));
    q
}

/// Writes the sphere cloud (6 columns) and the queries (3 columns) into `dir`.
fn write_inputs(dir: &Path) -> (PathBuf, PathBuf) {
    let (p, n) = sphere();
    let cloud = dir.join("cloud.xyz");
    write_xyz(&cloud, &p, Some(&n));
    let at = dir.join("queries.xyz");
    let q: Vec<[f64; 3]> = queries().into_iter().map(|(_, p)| p).collect();
    write_xyz(&at, &q, None);
    (cloud, at)
}

/// Runs `eval` to stdout and returns its output.
fn eval_stdout(args: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, at) = write_inputs(dir.path());
    run_ok(
        mlscurv()
            .arg("eval")
            .arg("--cloud")
            .arg(&cloud)
            .arg("--queries")
            .arg(&at)
            .args(args),
    )
    .stdout
}

/// `eval` with the default cutoff, to stdout.
static EVAL: LazyLock<String> = LazyLock::new(|| eval_stdout(&[]));

/// `eval --cutoff none`, to stdout.
static EVAL_NO_CUTOFF: LazyLock<String> = LazyLock::new(|| eval_stdout(&["--cutoff", "none"]));

/// The rows of the queries of one kind, with their directions.
fn rows_of(kind: Kind) -> Vec<(usize, Vector3<f64>)> {
    queries()
        .iter()
        .enumerate()
        .filter(|(_, (k, _))| *k == Some(kind))
        .map(|(i, (_, p))| (i, Vector3::from(*p).normalize()))
        .collect()
}

fn far_row() -> usize {
    queries().len() - 1
}

#[test]
fn eval_prints_the_documented_header_and_one_row_per_query_to_stdout() {
    assert_eq!(EVAL.lines().next(), Some(&*format!("//{EVAL_HEADER}")));
    let t = Table::parse_csv(&EVAL);
    let q: Vec<[f64; 3]> = queries().into_iter().map(|(_, p)| p).collect();
    assert_eq!(t.arrays(["x", "y", "z"]), q);
}

#[test]
fn eval_gradient_is_radial_and_outward_on_the_sphere() {
    let t = Table::parse_csv(&EVAL);
    let (grad, status) = (t.vectors(["gx", "gy", "gz"]), t.column("status"));
    for (i, d) in rows_of(Kind::On) {
        assert_eq!(status[i], 0.0, "row {i}");
        // atan2 keeps its digits for tiny angles, unlike acos of the cosine.
        let angle = grad[i].cross(&d).norm().atan2(grad[i].dot(&d));
        eprintln!("eval: angle(∇g, radius) = {angle:e} at row {i}");
        assert!(
            angle < MAX_GRADIENT_ANGLE,
            "row {i}: ∇g {:?} is {angle} rad off the radius",
            grad[i]
        );
    }
}

#[test]
fn eval_g_changes_sign_from_inside_to_outside_along_a_radius() {
    for text in [&*EVAL, &*EVAL_NO_CUTOFF] {
        let t = Table::parse_csv(text);
        let (g, status) = (t.column("g"), t.column("status"));
        let (inside, outside) = (rows_of(Kind::Inside), rows_of(Kind::Outside));
        for ((i, _), (o, _)) in inside.into_iter().zip(outside) {
            assert_eq!((status[i], status[o]), (0.0, 0.0), "rows {i}, {o}");
            assert!(
                g[i] < 0.0 && g[o] > 0.0,
                "g inside {} and outside {} (rows {i}, {o})",
                g[i],
                g[o]
            );
        }
    }
}

/// The principal curvatures of the level set of g from its printed gradient and Hessian:
/// the eigenvalues of `P H P / |∇g|` on the tangent plane (`P = I − n nᵀ`, `n = ∇g/|∇g|`),
/// largest first.
fn level_set_curvatures(grad: Vector3<f64>, hessian: Matrix3<f64>) -> (f64, f64) {
    let n = grad.normalize();
    let p = Matrix3::identity() - n * n.transpose();
    let eig = SymmetricEigen::new(p * hessian * p / grad.norm());
    // Drop the eigenvalue whose eigenvector is the normal (it is zero).
    let normal = (0..3).max_by(|&a, &b| {
        let (da, db) = (
            eig.eigenvectors.column(a).dot(&n).abs(),
            eig.eigenvectors.column(b).dot(&n).abs(),
        );
        da.total_cmp(&db)
    });
    let mut k: Vec<f64> = (0..3)
        .filter(|&j| Some(j) != normal)
        .map(|j| eig.eigenvalues[j])
        .collect();
    k.sort_unstable_by(|a, b| b.total_cmp(a));
    (k[0], k[1])
}

#[test]
fn eval_hessian_is_finite_and_gives_the_printed_curvatures() {
    for text in [&*EVAL, &*EVAL_NO_CUTOFF] {
        let t = Table::parse_csv(text);
        let grad = t.vectors(["gx", "gy", "gz"]);
        let (hxx, hxy, hxz, hyy, hyz, hzz) = (
            t.column("hxx"),
            t.column("hxy"),
            t.column("hxz"),
            t.column("hyy"),
            t.column("hyz"),
            t.column("hzz"),
        );
        let (k1, k2, status) = (t.column("k1"), t.column("k2"), t.column("status"));
        for kind in [Kind::On, Kind::Inside, Kind::Outside] {
            for (i, _) in rows_of(kind) {
                assert_eq!(status[i], 0.0, "row {i}");
                let h = [hxx[i], hxy[i], hxz[i], hyy[i], hyz[i], hzz[i]];
                assert!(h.iter().all(|v| v.is_finite()), "row {i}: Hessian {h:?}");
                #[rustfmt::skip]
                let hessian = Matrix3::new(
                    hxx[i], hxy[i], hxz[i],
                    hxy[i], hyy[i], hyz[i],
                    hxz[i], hyz[i], hzz[i],
                );
                let (a, b) = level_set_curvatures(grad[i], hessian);
                let scale = k1[i].abs().max(k2[i].abs());
                assert!(
                    (a - k1[i]).abs() < 1e-6 * scale && (b - k2[i]).abs() < 1e-6 * scale,
                    "row {i}: from H and ∇g ({a}, {b}), printed ({}, {})",
                    k1[i],
                    k2[i]
                );
                if kind == Kind::On {
                    // The level set through a point of the sphere is the sphere.
                    for k in [k1[i], k2[i]] {
                        assert!(
                            (k * SPHERE_R - 1.0).abs() < 1e-3,
                            "row {i}: k = {k}, 1/R = {}",
                            1.0 / SPHERE_R
                        );
                    }
                }
            }
        }
    }
}

/// A status-0 row has finite curvatures, any other row NaN ones.
fn assert_status_matches_numbers(t: &Table, i: usize) {
    let status = t.column("status")[i];
    let k = [
        t.column("k1")[i],
        t.column("k2")[i],
        t.column("mean")[i],
        t.column("gauss")[i],
    ];
    if status == 0.0 {
        assert!(
            k.iter().all(|v| v.is_finite()),
            "row {i}: status 0 with {k:?}"
        );
    } else {
        assert!(
            k.iter().all(|v| v.is_nan()),
            "row {i}: status {status} with {k:?}"
        );
    }
}

#[test]
fn eval_far_query_without_cutoff_gives_finite_curvature_or_no_neighbours() {
    let t = Table::parse_csv(&EVAL_NO_CUTOFF);
    let i = far_row();
    let status = t.column("status")[i];
    eprintln!(
        "eval --cutoff none: far query status {status}, k1 {}",
        t.column("k1")[i]
    );
    assert!(status == 0.0 || status == 1.0, "status {status}");
    assert_status_matches_numbers(&t, i);
}

#[test]
fn eval_far_query_with_cutoff_has_no_neighbours_and_nan_numbers() {
    let t = Table::parse_csv(&EVAL);
    let i = far_row();
    assert_eq!(t.column("status")[i], 1.0);
    assert_status_matches_numbers(&t, i);
    for name in ["g", "gx", "hxx", "nx"] {
        assert!(t.column(name)[i].is_nan(), "{name} = {}", t.column(name)[i]);
    }
}

#[test]
fn eval_output_file_equals_stdout() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, at) = write_inputs(dir.path());
    let out = dir.path().join("out.csv");
    let r = run_ok(
        mlscurv()
            .arg("eval")
            .arg("--cloud")
            .arg(&cloud)
            .arg("--queries")
            .arg(&at)
            .arg("-o")
            .arg(&out),
    );
    assert_eq!(r.stdout, "", "nothing on stdout with -o");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), *EVAL);
    let names: Vec<_> = listing(dir.path()).into_iter().collect();
    assert_eq!(names, ["cloud.xyz", "out.csv", "queries.xyz"]);
}
