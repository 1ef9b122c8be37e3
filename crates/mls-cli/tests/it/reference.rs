//! Outputs against references made before a change: the redesign of issue 13 (one cloud, one
//! index) must leave every number where it was, to 1e-12 relative.
//!
//! Each case runs `curvature` through every stage (spacing and h, normal estimation and
//! orientation where the file has none, the surface, the evaluation) and compares h and, at
//! every 97th point, the normal, k1 and k2 with `tests/data/reference/<case>.txt`. The files
//! were written by main at the commit that added this test; a deliberate change of results
//! rewrites them with `MLSCURV_BLESS=1 cargo test -p mls-cli --test it reference` and says
//! why in its commit.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use mls_shapes::{Torus, grid, normals, points, random_area_uniform, surface_points};

use crate::common::{Table, bunny_path, mlscurv, run_ok, write_xyz};

/// Rows compared: every `STRIDE`-th point (a prime, so a grid's rows are all visited).
const STRIDE: usize = 97;

/// Relative tolerance of h, of each normal component and of each curvature (relative to its
/// own value, with a floor of 1e-6 of the largest |k| so that a k near zero is not asked for
/// digits it never had).
const TOLERANCE: f64 = 1e-12;

fn reference_path(case: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/reference")
        .join(format!("{case}.txt"))
}

/// Runs `curvature` on `input` with `args`, returns h as the summary prints it (4 digits; the
/// curvatures check it fully) and the table.
fn curvature(input: &Path, args: &[&str]) -> (f64, Table) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let r = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(input)
            .arg("-o")
            .arg(&out)
            .args(args),
    );
    let h = r
        .stderr
        .lines()
        .chain(r.stdout.lines())
        .find_map(|l| {
            let rest = l.trim().strip_prefix("h ")?;
            rest.split_whitespace().next()?.parse::<f64>().ok()
        })
        .unwrap_or_else(|| panic!("no h line in the summary:\n{}{}", r.stdout, r.stderr));
    let table = Table::parse_csv(&std::fs::read_to_string(&out).unwrap());
    (h, table)
}

const COLUMNS: [&str; 5] = ["nx", "ny", "nz", "k1", "k2"];

/// The compared rows: `index nx ny nz k1 k2`, with h first.
fn extract(h: f64, table: &Table) -> (f64, Vec<(usize, [f64; 5])>) {
    let cols = COLUMNS.map(|c| table.col(c));
    let rows = (0..table.rows.len())
        .step_by(STRIDE)
        .map(|i| (i, cols.map(|c| table.rows[i][c])))
        .collect();
    (h, rows)
}

fn write_reference(path: &Path, h: f64, rows: &[(usize, [f64; 5])]) {
    let mut text =
        String::from("# index nx ny nz k1 k2 (see crates/mls-cli/tests/it/reference.rs)\n");
    let _ = writeln!(text, "h {h:e}");
    for (i, v) in rows {
        let _ = write!(text, "{i}");
        for x in v {
            let _ = write!(text, " {x:e}");
        }
        text.push('\n');
    }
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

fn read_reference(path: &Path) -> (f64, Vec<(usize, [f64; 5])>) {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e} (MLSCURV_BLESS=1 writes it)", path.display()));
    let mut h = f64::NAN;
    let mut rows = Vec::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let mut fields = line.split_whitespace();
        let first = fields.next().unwrap();
        if first == "h" {
            h = fields.next().unwrap().parse().unwrap();
            continue;
        }
        let values: Vec<f64> = fields.map(|f| f.parse().unwrap()).collect();
        rows.push((first.parse().unwrap(), values.try_into().unwrap()));
    }
    (h, rows)
}

/// Compares a run with its reference (or writes the reference under `MLSCURV_BLESS`).
fn check(case: &str, input: &Path, args: &[&str]) {
    let (h, table) = curvature(input, args);
    let (h, rows) = extract(h, &table);
    let path = reference_path(case);
    if std::env::var_os("MLSCURV_BLESS").is_some() {
        write_reference(&path, h, &rows);
        return;
    }
    let (h_ref, rows_ref) = read_reference(&path);
    assert!(
        (h - h_ref).abs() <= TOLERANCE * h_ref,
        "{case}: h {h:e}, reference {h_ref:e}"
    );
    assert_eq!(rows.len(), rows_ref.len(), "{case}: rows compared");
    let k_scale = rows_ref
        .iter()
        .flat_map(|(_, v)| [v[3].abs(), v[4].abs()])
        .fold(0.0f64, f64::max);
    let mut worst = [0.0f64; 5];
    for ((i, v), (i_ref, v_ref)) in rows.iter().zip(&rows_ref) {
        assert_eq!(i, i_ref);
        for c in 0..5 {
            let scale = if c < 3 {
                1.0
            } else {
                v_ref[c].abs().max(1e-6 * k_scale)
            };
            let d = (v[c] - v_ref[c]).abs() / scale;
            // NaN (a failed point) must stay NaN.
            let d = if v[c].is_nan() && v_ref[c].is_nan() {
                0.0
            } else {
                d
            };
            worst[c] = if d.is_nan() {
                f64::INFINITY
            } else {
                worst[c].max(d)
            };
        }
    }
    for (c, w) in COLUMNS.iter().zip(worst) {
        assert!(
            w <= TOLERANCE,
            "{case}: {c} differs from the reference by {w:e} (relative; tolerance {TOLERANCE:e})"
        );
    }
}

#[test]
fn bunny_paper_method_with_estimated_normals_is_unchanged() {
    check("bunny-paper", &bunny_path(), &["--method", "paper"]);
}

#[test]
fn bunny_default_method_with_estimated_normals_is_unchanged() {
    check("bunny-jet", &bunny_path(), &[]);
}

/// Random area-uniform torus with exact normals from the file, and the same points without
/// normals (estimated and oriented).
#[test]
fn random_torus_paper_method_is_unchanged() {
    let torus = Torus::new(6.0, 2.0);
    let s = surface_points(&random_area_uniform(&torus, 20_000, 7));
    let dir = tempfile::tempdir().unwrap();
    let (with, without) = (dir.path().join("n.xyz"), dir.path().join("p.xyz"));
    write_xyz(&with, &points(&s), Some(&normals(&s)));
    write_xyz(&without, &points(&s), None);
    check("torus-random-paper", &with, &["--method", "paper"]);
    check(
        "torus-random-paper-estimated",
        &without,
        &["--method", "paper"],
    );
}

/// The paper's regular torus grid without normals: equidistant neighbours everywhere, so
/// the neighbour graph's choice among ties enters the normals.
#[test]
fn grid_torus_paper_method_with_estimated_normals_is_unchanged() {
    let torus = Torus::new(1.0, 0.2);
    let s = surface_points(&grid(&torus, 200, 50));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.xyz");
    write_xyz(&path, &points(&s), None);
    check("torus-grid-paper-estimated", &path, &["--method", "paper"]);
}
