//! `cargo xtask clients`: mlscurv's files opened by the programs people open them with, and
//! theirs by mlscurv (issue 38). On a quarter of the bundled bunny it writes `curvature`
//! output as PLY, CSV, LAS and XYZ into `target/clients/`, then
//!
//! - CloudCompare's command line (headless, `QT_QPA_PLATFORM=offscreen`) opens the PLY, CSV
//!   and LAS and exports each as ASCII (`;`-separated, with a header and a point count) and
//!   the PLY again as binary PLY; mlscurv's reader reads those exports, and every field must
//!   be there under its name with our values to float32 precision (CloudCompare's scalar
//!   type), normals to its quantised precision;
//! - pymeshlab opens the PLY: its vertex quality must be our mean curvature, and its own PLY
//!   must read back with `quality`;
//! - laspy (with lazrs) reads the LAS: every field an extra dimension of its name and our
//!   value; it writes a LAZ that mlscurv's reader must read back the same;
//! - numpy: `genfromtxt(names=True)` names the CSV's columns as ours, `loadtxt` reads the XYZ.
//!
//! A program that is not installed is skipped with a message (`.ci/run` installs them); a
//! field that does not arrive fails the task, naming the program, file, field and row.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use mls_io::{PlyFormat, PointCloud, ReadOptions};

use crate::bench::{build_mlscurv, target_dir};

/// The Python side: pymeshlab and laspy.
const SCRIPT: &str = include_str!("clients.py");

/// Exit status of the script when a module is missing.
const MISSING: i32 = 3;

/// The longest a program may take on one file before it is killed and the check fails.
const TIMEOUT: Duration = Duration::from_secs(300);

/// float32 (CloudCompare's scalar type, MeshLab's quality) against our float64: half an ulp
/// relative, with 1e-12 absolute for CloudCompare's 12 decimals.
const F32: Tolerance = Tolerance::new(6.0e-8, 1e-12);

/// Exact: a float64 that went through a file and back.
const EXACT: Tolerance = Tolerance::new(0.0, 0.0);

/// CloudCompare stores normals quantised (its `ccNormalCompressor`, a few thousand
/// directions): each component to about 1e-3. It has no missing normal: a failed point's
/// NaN normal comes back as some unit vector, so only our finite normals are compared.
const CC_NORMALS: Tolerance = Tolerance {
    relative: 0.0,
    absolute: 5e-3,
    nan_is_any: true,
};

#[derive(Clone, Copy, Debug)]
struct Tolerance {
    relative: f64,
    absolute: f64,
    /// Whether our NaN may come back as any value.
    nan_is_any: bool,
}

impl Tolerance {
    const fn new(relative: f64, absolute: f64) -> Self {
        Self {
            relative,
            absolute,
            nan_is_any: false,
        }
    }

    fn admits(self, ours: f64, theirs: f64) -> bool {
        (ours.is_nan() && (theirs.is_nan() || self.nan_is_any))
            || (ours - theirs).abs() <= self.relative * ours.abs() + self.absolute
    }
}

/// Our values by name: `x y z`, then every column of the output after them.
struct Table {
    columns: Vec<(String, Vec<f64>)>,
}

impl Table {
    /// Every column of a file, read by mlscurv's reader with normals as plain columns.
    fn read(path: &Path) -> Result<Self> {
        let cloud = mls_io::read_point_cloud_normals_as_attributes(path, &ReadOptions::default())
            .with_context(|| format!("mlscurv's reader on {}", path.display()))?;
        Ok(Self::of(&cloud))
    }

    fn of(cloud: &PointCloud) -> Self {
        let mut columns: Vec<(String, Vec<f64>)> = ["x", "y", "z"]
            .iter()
            .enumerate()
            .map(|(k, n)| ((*n).to_owned(), cloud.points.iter().map(|p| p[k]).collect()))
            .collect();
        if let Some(normals) = &cloud.normals {
            for (k, n) in ["nx", "ny", "nz"].iter().enumerate() {
                columns.push(((*n).to_owned(), normals.iter().map(|v| v[k]).collect()));
            }
        }
        for a in &cloud.attributes {
            let values = (0..a.data.len())
                .map(|i| a.data.f64_at(i).unwrap_or(f64::NAN))
                .collect();
            columns.push((a.name.clone(), values));
        }
        Self { columns }
    }

    fn get(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    fn names(&self) -> Vec<&str> {
        self.columns.iter().map(|(n, _)| n.as_str()).collect()
    }
}

/// The fields a check compares and how.
struct Expect<'a> {
    ours: &'a Table,
    /// The names compared, each with its tolerance.
    fields: Vec<(&'a str, Tolerance)>,
}

impl Expect<'_> {
    /// Compares `theirs` with ours on every field; the error names the first field missing or
    /// the first row that differs. Returns the largest relative difference seen in the fields
    /// that are not geometry (coordinates and normals have tolerances of their own).
    fn check(&self, theirs: &Table) -> Result<f64, String> {
        let mut worst = 0.0f64;
        for &(name, tolerance) in &self.fields {
            let ours = self
                .ours
                .get(name)
                .ok_or_else(|| format!("we have no `{name}`"))?;
            let Some(values) = theirs.get(name) else {
                return Err(format!(
                    "field `{name}` missing; it has {}",
                    theirs.names().join(" ")
                ));
            };
            if values.len() != ours.len() {
                return Err(format!(
                    "field `{name}`: {} values, ours {}",
                    values.len(),
                    ours.len()
                ));
            }
            for (row, (&o, &t)) in ours.iter().zip(values).enumerate() {
                if !tolerance.admits(o, t) {
                    return Err(format!(
                        "field `{name}` row {}: {t:e}, ours {o:e} (tolerance {:e} relative + \
                         {:e})",
                        row + 1,
                        tolerance.relative,
                        tolerance.absolute
                    ));
                }
                if o.is_finite() && o != 0.0 && !GEOMETRY.contains(&name) {
                    worst = worst.max((t - o).abs() / o.abs());
                }
            }
        }
        Ok(worst)
    }
}

const GEOMETRY: [&str; 6] = ["x", "y", "z", "nx", "ny", "nz"];

/// One line of the table.
struct Row {
    program: &'static str,
    what: String,
    outcome: Outcome,
}

enum Outcome {
    Ok(String),
    Failed(String),
    Skipped(String),
}

pub(crate) fn run() -> Result<()> {
    let dir = target_dir().join("clients");
    if dir.exists() {
        std::fs::remove_dir_all(&dir).with_context(|| format!("cannot clear {}", dir.display()))?;
    }
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let exe = build_mlscurv()?;

    // A quarter of the bunny (every 4th point): a real scan, and a few seconds per output.
    let bunny = mls_io::read_point_cloud(Path::new("tests/data/bunny-stanford.ply"))?;
    let points: Vec<[f64; 3]> = bunny.points.iter().step_by(4).copied().collect();
    let input = dir.join("bunny-quarter.ply");
    mls_io::write_ply(
        &input,
        &PointCloud {
            points,
            ..PointCloud::default()
        }
        .columns(),
        PlyFormat::BinaryLittleEndian,
    )?;
    let ours = |ext: &str| dir.join(format!("ours.{ext}"));
    for ext in ["ply", "csv", "las", "xyz"] {
        crate::run_checked(
            Command::new(&exe)
                .arg("curvature")
                .arg(&input)
                .arg("-o")
                .arg(ours(ext))
                .arg("--quiet"),
        )?;
    }
    let table = Table::read(&ours("ply"))?;
    // `quality` repeats `mean` for MeshLab; every other column is a field to check.
    let fields: Vec<&str> = table
        .names()
        .into_iter()
        .filter(|n| !["x", "y", "z", "quality"].contains(n))
        .collect();
    // The columns the README documents for the default method, so that a column our own
    // writer lost cannot pass unnoticed.
    let documented = "nx ny nz k1 k2 mean gauss d1x d1y d1z d2x d2y d2z k1_sd k2_sd status";
    if fields.join(" ") != documented {
        bail!(
            "{}: columns {}, but the README documents {documented}",
            ours("ply").display(),
            fields.join(" ")
        );
    }
    println!(
        "clients: {} points, fields {}",
        table.get("x").map_or(0, <[f64]>::len),
        fields.join(" ")
    );
    let with = |tolerance: Tolerance, normals: Tolerance| Expect {
        ours: &table,
        fields: ["x", "y", "z"]
            .into_iter()
            .map(|n| (n, tolerance))
            .chain(fields.iter().map(|&n| {
                let t = if ["nx", "ny", "nz"].contains(&n) {
                    normals
                } else {
                    tolerance
                };
                (n, t)
            }))
            .collect(),
    };

    let mut rows = Vec::new();
    cloudcompare(&dir, &ours, &with(F32, CC_NORMALS), &mut rows);
    let python = python();
    meshlab(&python, &dir, &ours("ply"), &table, &mut rows);
    // LAS coordinates are on the header's grid: within 5e-8 of the extent (README).
    let grid = Tolerance::new(0.0, 1e-7 * extent(&table));
    let mut las = with(EXACT, EXACT);
    for f in &mut las.fields {
        if ["x", "y", "z"].contains(&f.0) {
            f.1 = grid;
        }
    }
    laspy(&python, &dir, &ours("las"), &las, &mut rows);
    numpy(&python, &dir, &ours, &with(EXACT, EXACT), &mut rows);

    print_table(&rows);
    let failed: Vec<&Row> = rows
        .iter()
        .filter(|r| matches!(r.outcome, Outcome::Failed(_)))
        .collect();
    if !failed.is_empty() {
        let mut message = format!("{} of {} checks failed:", failed.len(), rows.len());
        for r in failed {
            if let Outcome::Failed(why) = &r.outcome {
                let _ = write!(message, "\n  {} {}: {why}", r.program, r.what);
            }
        }
        bail!("{message}");
    }
    Ok(())
}

/// The bounding box's largest extent.
fn extent(table: &Table) -> f64 {
    ["x", "y", "z"]
        .iter()
        .filter_map(|n| table.get(n))
        .map(|v| {
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                    (lo.min(x), hi.max(x))
                });
            hi - lo
        })
        .fold(0.0, f64::max)
}

/// The program on `PATH`, if there.
fn on_path(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// Runs `cmd` to completion within [`TIMEOUT`]; returns its status and its output (stdout
/// then stderr), which is kept in `target/clients/log-N.txt`. (Through a file, not a pipe:
/// CloudCompare writes much, and a full pipe would stall it.)
fn run_captured(cmd: &mut Command) -> Result<(std::process::ExitStatus, String)> {
    static RUNS: AtomicUsize = AtomicUsize::new(0);
    let n = RUNS.fetch_add(1, Ordering::Relaxed);
    let log = target_dir().join("clients").join(format!("log-{n}.txt"));
    let out =
        std::fs::File::create(&log).with_context(|| format!("cannot create {}", log.display()))?;
    let err = out.try_clone()?;
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(err)
        .spawn()
        .with_context(|| format!("cannot run {cmd:?}"))?;
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            bail!("{cmd:?} did not finish in {} s; killed", TIMEOUT.as_secs());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    Ok((status, std::fs::read_to_string(&log).unwrap_or_default()))
}

/// The last lines of a program's output, for a message.
fn tail(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| !l.contains("Plugin") && !l.trim().is_empty())
        .collect();
    lines[lines.len().saturating_sub(4)..].join(" | ")
}

fn cloudcompare(
    dir: &Path,
    ours: &dyn Fn(&str) -> PathBuf,
    expect: &Expect<'_>,
    rows: &mut Vec<Row>,
) {
    const PROGRAM: &str = "CloudCompare";
    let Some(exe) = on_path("CloudCompare") else {
        rows.push(Row {
            program: PROGRAM,
            what: "all".to_owned(),
            outcome: Outcome::Skipped(
                "CloudCompare is not on PATH (Debian: apt-get install cloudcompare)".to_owned(),
            ),
        });
        return;
    };
    // Each file CloudCompare opens, with what it writes back: ASCII (`;`: names may hold
    // spaces), and binary PLY from the PLY.
    let runs: [(&str, &str, &[&str]); 4] = [
        (
            "ply",
            "asc",
            &[
                "-C_EXPORT_FMT",
                "ASC",
                "-SEP",
                "SEMICOLON",
                "-ADD_HEADER",
                "-ADD_PTS_COUNT",
            ],
        ),
        (
            "ply",
            "ply",
            &["-C_EXPORT_FMT", "PLY", "-PLY_EXPORT_FMT", "BINARY_LE"],
        ),
        (
            "csv",
            "asc",
            &["-C_EXPORT_FMT", "ASC", "-SEP", "SEMICOLON", "-ADD_HEADER"],
        ),
        (
            "las",
            "asc",
            &["-C_EXPORT_FMT", "ASC", "-SEP", "SEMICOLON", "-ADD_HEADER"],
        ),
    ];
    for (from, to, export) in runs {
        let input = ours(from);
        let output = dir.join(format!("cloudcompare-from-{from}.{to}"));
        let what = format!(
            "ours.{from} -> {}",
            output.file_name().unwrap_or_default().to_string_lossy()
        );
        let mut cmd = Command::new(&exe);
        if std::env::var_os("QT_QPA_PLATFORM").is_none() {
            cmd.env("QT_QPA_PLATFORM", "offscreen");
        }
        cmd.args(["-SILENT", "-AUTO_SAVE", "OFF", "-O"])
            .arg(&input)
            .args(export)
            .args(["-SAVE_CLOUDS", "FILE"])
            .arg(&output);
        let outcome = match run_captured(&mut cmd) {
            Err(e) => Outcome::Failed(format!("{e:#}")),
            Ok((_, log)) if log.contains("unhandled file extension") => Outcome::Skipped(format!(
                "this CloudCompare has no .{from} reader (Debian's is built without PDAL): {}",
                tail(&log)
            )),
            Ok((status, log)) if !status.success() || !output.exists() => Outcome::Failed(format!(
                "CloudCompare failed ({status}), no {}: {}",
                output.display(),
                tail(&log)
            )),
            Ok(_) => compare(&output, expect),
        };
        rows.push(Row {
            program: PROGRAM,
            what,
            outcome,
        });
    }
}

/// Reads `theirs` with mlscurv's reader and compares it with ours.
fn compare(theirs: &Path, expect: &Expect<'_>) -> Outcome {
    match Table::read(theirs) {
        Err(e) => Outcome::Failed(format!("{e:#}")),
        Ok(table) => match expect.check(&table) {
            Ok(worst) => Outcome::Ok(format!(
                "{} fields named and equal (largest relative difference of a curvature field \
                 {worst:.1e})",
                expect.fields.len()
            )),
            Err(why) => Outcome::Failed(format!("{}: {why}", theirs.display())),
        },
    }
}

/// The Python that has pymeshlab and laspy: `$MLSCURV_CLIENTS_PYTHON`, else the virtual
/// environment `.ci/clients` makes, else `python3`.
fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("MLSCURV_CLIENTS_PYTHON") {
        return p.into();
    }
    let venv = target_dir().join("clients-venv/bin/python");
    if venv.is_file() {
        return venv;
    }
    "python3".into()
}

/// Runs the script in `mode`; `Err` is the row's outcome (skipped or failed).
fn script(python: &Path, dir: &Path, mode: &str, file: &Path) -> Result<(), Outcome> {
    let path = dir.join("clients.py");
    std::fs::write(&path, SCRIPT).map_err(|e| Outcome::Failed(format!("{e}")))?;
    let mut cmd = Command::new(python);
    cmd.arg(&path).arg(mode).arg(file).arg(dir);
    match run_captured(&mut cmd) {
        Err(e) if format!("{e:#}").contains("cannot run") => Err(Outcome::Skipped(format!(
            "cannot run Python {}: {} (set MLSCURV_CLIENTS_PYTHON, or run .ci/clients)",
            python.display(),
            e.root_cause()
        ))),
        Err(e) => Err(Outcome::Failed(format!("{e:#}"))),
        Ok((status, log)) if status.code() == Some(MISSING) => Err(Outcome::Skipped(format!(
            "{} (pip install laspy lazrs pymeshlab; {})",
            log.trim(),
            python.display()
        ))),
        Ok((status, log)) if !status.success() => Err(Outcome::Failed(format!(
            "{} {mode} failed ({status}): {}",
            path.display(),
            tail(&log)
        ))),
        Ok(_) => Ok(()),
    }
}

/// Numbers of a whitespace-separated text file, one row a line.
fn numbers(path: &Path) -> Result<Vec<Vec<f64>>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    text.lines()
        .map(|l| {
            l.split_whitespace()
                .map(|t| {
                    t.parse::<f64>()
                        .map_err(|_| format!("{}: not a number: {t}", path.display()))
                })
                .collect()
        })
        .collect()
}

fn meshlab(python: &Path, dir: &Path, ply: &Path, ours: &Table, rows: &mut Vec<Row>) {
    const PROGRAM: &str = "pymeshlab";
    if let Err(outcome) = script(python, dir, "meshlab", ply) {
        rows.push(Row {
            program: PROGRAM,
            what: "ours.ply".to_owned(),
            outcome,
        });
        return;
    }
    // MeshLab keeps one scalar per vertex, its quality: our mean curvature.
    let outcome = (|| {
        let vertices = numbers(&dir.join("meshlab-vertices.txt"))?;
        let quality = dir.join("meshlab-quality.txt");
        if !quality.exists() {
            return Err("MeshLab found no vertex quality in ours.ply".to_owned());
        }
        let quality: Vec<f64> = numbers(&quality)?.into_iter().flatten().collect();
        let mut theirs = Table {
            columns: vec![("mean".to_owned(), quality)],
        };
        for (k, n) in ["x", "y", "z"].iter().enumerate() {
            let v = vertices
                .iter()
                .map(|r| r.get(k).copied().unwrap_or(f64::NAN));
            theirs.columns.push(((*n).to_owned(), v.collect()));
        }
        let expect = Expect {
            ours,
            fields: vec![("x", F32), ("y", F32), ("z", F32), ("mean", F32)],
        };
        expect.check(&theirs).map(|worst| {
            format!("vertex quality is mean (largest relative difference {worst:.1e})")
        })
    })();
    rows.push(Row {
        program: PROGRAM,
        what: "ours.ply (quality)".to_owned(),
        outcome: outcome.map_or_else(Outcome::Failed, Outcome::Ok),
    });
    // MeshLab's own PLY, read back: `quality` is the mean curvature.
    let theirs = dir.join("meshlab.ply");
    let outcome = match Table::read(&theirs) {
        Err(e) => Outcome::Failed(format!("{e:#}")),
        Ok(mut table) => {
            for (name, _) in &mut table.columns {
                if name == "quality" {
                    "mean".clone_into(name);
                }
            }
            let expect = Expect {
                ours,
                fields: vec![("x", F32), ("y", F32), ("z", F32), ("mean", F32)],
            };
            match expect.check(&table) {
                Ok(worst) => Outcome::Ok(format!(
                    "mlscurv reads its quality as mean (largest relative difference {worst:.1e})"
                )),
                Err(why) => Outcome::Failed(format!("{}: {why}", theirs.display())),
            }
        }
    };
    rows.push(Row {
        program: PROGRAM,
        what: "meshlab.ply -> mlscurv".to_owned(),
        outcome,
    });
}

fn laspy(python: &Path, dir: &Path, las: &Path, expect: &Expect<'_>, rows: &mut Vec<Row>) {
    const PROGRAM: &str = "laspy+lazrs";
    if let Err(outcome) = script(python, dir, "laspy", las) {
        rows.push(Row {
            program: PROGRAM,
            what: "ours.las".to_owned(),
            outcome,
        });
        return;
    }
    rows.push(Row {
        program: PROGRAM,
        what: "ours.las (extra dimensions)".to_owned(),
        outcome: compare(&dir.join("laspy-read.csv"), expect),
    });
    rows.push(Row {
        program: PROGRAM,
        what: "laspy.laz -> mlscurv".to_owned(),
        outcome: compare(&dir.join("laspy.laz"), expect),
    });
}

fn numpy(
    python: &Path,
    dir: &Path,
    ours: &dyn Fn(&str) -> PathBuf,
    expect: &Expect<'_>,
    rows: &mut Vec<Row>,
) {
    const PROGRAM: &str = "numpy";
    // genfromtxt names the CSV's columns from its `//` header; loadtxt reads the XYZ, whose
    // `#` line it skips. Both written back as text with a header row of the names.
    let code = "import sys, numpy as np\n\
        csv, xyz, out = sys.argv[1:]\n\
        a = np.genfromtxt(csv, delimiter=',', names=True)\n\
        names = list(a.dtype.names)\n\
        np.savetxt(out + '/numpy-csv.csv', np.column_stack([a[n] for n in names]), \
        delimiter=',', header=','.join(names), comments='', fmt='%.17g')\n\
        b = np.loadtxt(xyz)\n\
        head = open(xyz).readline().lstrip('#').split()\n\
        np.savetxt(out + '/numpy-xyz.csv', b, delimiter=',', header=','.join(head), \
        comments='', fmt='%.17g')\n";
    let mut cmd = Command::new(python);
    cmd.arg("-c")
        .arg(code)
        .arg(ours("csv"))
        .arg(ours("xyz"))
        .arg(dir);
    match run_captured(&mut cmd) {
        Err(e) => rows.push(Row {
            program: PROGRAM,
            what: "ours.csv, ours.xyz".to_owned(),
            outcome: Outcome::Skipped(format!(
                "cannot run Python {}: {}",
                python.display(),
                e.root_cause()
            )),
        }),
        Ok((_, log)) if log.contains("No module named 'numpy'") => rows.push(Row {
            program: PROGRAM,
            what: "ours.csv, ours.xyz".to_owned(),
            outcome: Outcome::Skipped("numpy is not installed".to_owned()),
        }),
        Ok((status, log)) if !status.success() => rows.push(Row {
            program: PROGRAM,
            what: "ours.csv, ours.xyz".to_owned(),
            outcome: Outcome::Failed(format!("numpy failed ({status}): {}", tail(&log))),
        }),
        Ok(_) => {
            rows.push(Row {
                program: PROGRAM,
                what: "ours.csv (genfromtxt names=True)".to_owned(),
                outcome: compare(&dir.join("numpy-csv.csv"), expect),
            });
            rows.push(Row {
                program: PROGRAM,
                what: "ours.xyz (loadtxt)".to_owned(),
                outcome: compare(&dir.join("numpy-xyz.csv"), expect),
            });
        }
    }
}

fn print_table(rows: &[Row]) {
    let width = rows.iter().map(|r| r.what.len()).max().unwrap_or(0);
    println!();
    println!("{:<12}  {:<width$}  result", "program", "file");
    for r in rows {
        let (tag, text) = match &r.outcome {
            Outcome::Ok(t) => ("ok", t),
            Outcome::Failed(t) => ("FAILED", t),
            Outcome::Skipped(t) => ("skipped", t),
        };
        println!("{:<12}  {:<width$}  {tag}: {text}", r.program, r.what);
    }
    println!();
}
