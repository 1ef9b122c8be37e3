//! Shared helpers: running the binary, fixture files, parsing its output, small statistics.

use std::collections::BTreeSet;
use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use nalgebra::Vector3;

/// The columns `curvature` writes, in order.
pub const CURVATURE_HEADER: &str = "x,y,z,nx,ny,nz,k1,k2,mean,gauss,d1x,d1y,d1z,d2x,d2y,d2z,status";
/// The columns of `mlscurv curvature` with the default jet method.
pub const JET_HEADER: &str =
    "x,y,z,nx,ny,nz,k1,k2,mean,gauss,d1x,d1y,d1z,d2x,d2y,d2z,k1_sd,k2_sd,status";

/// The columns `eval` writes, in order.
pub const EVAL_HEADER: &str =
    "x,y,z,g,gx,gy,gz,hxx,hxy,hxz,hyy,hyz,hzz,nx,ny,nz,k1,k2,mean,gauss,status";

/// Points in the Stanford bunny file.
pub const BUNNY_POINTS: usize = 35_947;

/// Radius of the generated test sphere.
pub const SPHERE_R: f64 = 0.5;

/// Points on the generated test sphere (Fibonacci lattice).
pub const SPHERE_N: usize = 20_000;

/// The Stanford bunny scan (binary PLY, metres, no normals).
pub fn bunny_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/bunny-stanford.ply")
}

/// A command running the `mlscurv` binary.
pub fn mlscurv() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mlscurv"))
}

/// What a run of the binary produced.
#[derive(Debug)]
pub struct Run {
    pub success: bool,
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

/// Runs the command to completion and captures its output.
pub fn run(cmd: &mut Command) -> Run {
    let out = cmd.output().expect("cannot start mlscurv");
    Run {
        success: out.status.success(),
        code: out.status.code(),
        stdout: String::from_utf8(out.stdout).expect("stdout is not UTF-8"),
        stderr: String::from_utf8(out.stderr).expect("stderr is not UTF-8"),
    }
}

/// Runs the command and panics with its stderr unless it succeeds.
pub fn run_ok(cmd: &mut Command) -> Run {
    let r = run(cmd);
    assert!(
        r.success,
        "mlscurv failed ({:?}): {cmd:?}\n{}",
        r.code, r.stderr
    );
    r
}

/// The names of every entry in `dir`, hidden ones included.
pub fn listing(dir: &Path) -> BTreeSet<OsString> {
    std::fs::read_dir(dir)
        .expect("cannot list the directory")
        .map(|e| e.expect("cannot read a directory entry").file_name())
        .collect()
}

/// Writes points (and normals) as whitespace-separated XYZ, 3 or 6 columns, with Rust's
/// shortest round-trip float formatting (independent of mls-io's writers).
pub fn write_xyz(path: &Path, points: &[[f64; 3]], normals: Option<&[[f64; 3]]>) {
    let mut text = String::with_capacity(points.len() * 120);
    for (i, p) in points.iter().enumerate() {
        let _ = write!(text, "{} {} {}", p[0], p[1], p[2]);
        if let Some(n) = normals {
            let _ = write!(text, " {} {} {}", n[i][0], n[i][1], n[i][2]);
        }
        text.push('\n');
    }
    std::fs::write(path, text).expect("cannot write the XYZ fixture");
}

/// Writes a Fibonacci sphere of radius 1 with `n` points and exact outward normals as XYZ.
pub fn write_unit_sphere(path: &Path, n: usize) {
    let s = mls_shapes::fibonacci_sphere(n, 1.0);
    write_xyz(
        path,
        &mls_shapes::points(&s),
        Some(&mls_shapes::normals(&s)),
    );
}

/// Asserts that a failed run printed one `mlscurv: error:` line naming `name` and containing
/// each of `details`, nothing on stdout, and did not panic.
#[track_caller]
pub fn assert_one_line_error(r: &Run, name: &str, details: &[&str]) {
    let e = &r.stderr;
    assert!(!r.success, "expected failure, got success: {e}");
    assert!(!e.contains("panicked"), "panic:\n{e}");
    assert!(e.starts_with("mlscurv: error:"), "stderr: {e}");
    assert_eq!(e.matches('\n').count(), 1, "stderr is not one line: {e:?}");
    assert!(e.contains(name), "stderr does not name {name}: {e}");
    for d in details {
        assert!(e.contains(d), "stderr does not say {d:?}: {e}");
    }
    assert_eq!(r.stdout, "", "stdout");
}

/// The Fibonacci sphere of radius [`SPHERE_R`] with [`SPHERE_N`] points: positions and exact
/// outward normals.
pub fn sphere() -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let s = mls_shapes::fibonacci_sphere(SPHERE_N, SPHERE_R);
    (mls_shapes::points(&s), mls_shapes::normals(&s))
}

/// The sphere's mean point spacing, `sqrt(area / n)`.
pub fn sphere_spacing() -> f64 {
    (4.0 * std::f64::consts::PI * SPHERE_R * SPHERE_R / SPHERE_N as f64).sqrt()
}

/// A table of numbers with named columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub header: Vec<String>,
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// Parses CSV with a header row after `//`, as mlscurv writes it (every value a number,
    /// `NaN` allowed).
    pub fn parse_csv(text: &str) -> Self {
        let mut lines = text.lines();
        let first = lines.next().expect("CSV has no header");
        let header: Vec<String> = first
            .strip_prefix("//")
            .unwrap_or_else(|| panic!("CSV header without `//`: {first:?}"))
            .split(',')
            .map(str::to_owned)
            .collect();
        let rows = lines
            .enumerate()
            .map(|(i, line)| parse_row(line, ',', i + 2, header.len()))
            .collect();
        Self { header, rows }
    }

    /// Parses an ASCII PLY whose first element is `vertex` (independent of mls-io's reader),
    /// naming the columns as mlscurv does: property `scalar_k1` is column `k1`, and a
    /// `quality` property, which must repeat `mean`, is left out.
    pub fn parse_ascii_ply(text: &str) -> Self {
        let mut table = Self::parse_ascii_ply_properties(text);
        for name in &mut table.header {
            if let Some(bare) = name.strip_prefix("scalar_") {
                *name = bare.to_owned();
            }
        }
        if let Some(q) = table.header.iter().position(|h| h == "quality") {
            let mean = table.col("mean");
            for row in &mut table.rows {
                let quality = row.remove(q);
                assert!(
                    quality.to_bits() == row[mean - usize::from(mean > q)].to_bits(),
                    "quality {quality} is not mean"
                );
            }
            table.header.remove(q);
        }
        table
    }

    /// Parses an ASCII PLY whose first element is `vertex`, each column named as its
    /// property.
    pub fn parse_ascii_ply_properties(text: &str) -> Self {
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("ply"));
        assert_eq!(lines.next(), Some("format ascii 1.0"));
        let mut header = Vec::new();
        let mut count = None;
        for line in lines.by_ref() {
            let words: Vec<&str> = line.split_whitespace().collect();
            match words[..] {
                ["end_header"] => break,
                ["element", "vertex", n] => count = Some(n.parse::<usize>().expect("vertex count")),
                ["element", ..] => panic!("unexpected element: {line}"),
                ["property", _ty, name] => header.push(name.to_owned()),
                _ => {}
            }
        }
        let rows: Vec<Vec<f64>> = lines
            .enumerate()
            .map(|(i, line)| parse_row(line, ' ', i + 1, header.len()))
            .collect();
        assert_eq!(Some(rows.len()), count, "vertex count in the header");
        Self { header, rows }
    }

    /// The index of a column; panics if absent.
    pub fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }

    /// One column's values.
    pub fn column(&self, name: &str) -> Vec<f64> {
        let c = self.col(name);
        self.rows.iter().map(|r| r[c]).collect()
    }

    /// Three columns as vectors, e.g. `["nx", "ny", "nz"]`.
    pub fn vectors(&self, names: [&str; 3]) -> Vec<Vector3<f64>> {
        let c = names.map(|n| self.col(n));
        self.rows
            .iter()
            .map(|r| Vector3::new(r[c[0]], r[c[1]], r[c[2]]))
            .collect()
    }

    /// Three columns as arrays, e.g. `["x", "y", "z"]`.
    pub fn arrays(&self, names: [&str; 3]) -> Vec<[f64; 3]> {
        self.vectors(names).into_iter().map(Into::into).collect()
    }
}

fn parse_row(line: &str, separator: char, line_no: usize, width: usize) -> Vec<f64> {
    let row: Vec<f64> = if separator == ' ' {
        line.split_whitespace()
            .map(|v| parse_value(v, line_no))
            .collect()
    } else {
        line.split(separator)
            .map(|v| parse_value(v, line_no))
            .collect()
    };
    assert_eq!(row.len(), width, "line {line_no}: {line}");
    row
}

fn parse_value(v: &str, line_no: usize) -> f64 {
    v.parse()
        .unwrap_or_else(|_| panic!("line {line_no}: {v:?} is not a number"))
}

/// The median of the values (which must not be empty or contain NaN).
pub fn median(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_unstable_by(f64::total_cmp);
    let n = v.len();
    assert!(n > 0, "median of nothing");
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

pub fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// Population standard deviation.
pub fn std_dev(values: &[f64]) -> f64 {
    let m = mean(values);
    (values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / values.len() as f64).sqrt()
}

/// The largest absolute value.
pub fn max_abs(values: impl IntoIterator<Item = f64>) -> f64 {
    values.into_iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// The fraction of normals that point away from the centroid of the points,
/// `n · (p − centroid) > 0`.
pub fn outward_fraction(points: &[[f64; 3]], normals: &[Vector3<f64>]) -> f64 {
    let c = points
        .iter()
        .fold(Vector3::zeros(), |s, p| s + Vector3::from(*p))
        / points.len() as f64;
    let out = points
        .iter()
        .zip(normals)
        .filter(|(p, n)| n.dot(&(Vector3::from(**p) - c)) > 0.0)
        .count();
    out as f64 / points.len() as f64
}

/// The share of neighbour pairs that agree, as the warning prints it ("only 92.3% of").
pub fn printed_agreement(stderr: &str) -> f64 {
    let after = stderr
        .split("only ")
        .nth(1)
        .expect("no share in the warning");
    after.split('%').next().unwrap().parse().unwrap()
}
