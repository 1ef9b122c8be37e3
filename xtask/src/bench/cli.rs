//! The whole command: `mlscurv` built in release, run on generated files with its peak
//! memory, and a flat `perf` profile when perf is installed.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use mls_bench::Cloud;
use mls_io::{PlyFormat, PointCloud, write_ply};

#[derive(Debug)]
pub(super) struct CliRun {
    pub(super) label: &'static str,
    pub(super) points: usize,
    /// Peak resident set size in bytes, or why it is unknown.
    pub(super) peak_rss: Result<u64, String>,
    pub(super) wall_seconds: f64,
    /// mlscurv's own per-stage times line.
    pub(super) stage_times: String,
    /// How the peak was read.
    pub(super) method: &'static str,
}

#[derive(Debug)]
pub(super) struct Cli {
    pub(super) runs: Vec<CliRun>,
    /// Why the command could not be measured at all.
    pub(super) error: Option<String>,
    /// A flat profile of each run (label, report), when asked for.
    pub(super) profiles: Vec<(&'static str, String)>,
}

pub(super) fn cli_measurements(
    exe: Result<PathBuf>,
    cloud: &Cloud,
    work: &Path,
    profile: bool,
) -> Cli {
    match exe.and_then(|exe| cli_measurements_inner(&exe, cloud, work, profile)) {
        Ok(cli) => cli,
        Err(e) => Cli {
            runs: Vec::new(),
            error: Some(format!("{e:#}")),
            profiles: Vec::new(),
        },
    }
}

pub(super) fn cli_measurements_inner(
    exe: &Path,
    cloud: &Cloud,
    work: &Path,
    profile: bool,
) -> Result<Cli> {
    let points: Vec<[f64; 3]> = cloud.points.iter().map(|p| p.coords.into()).collect();
    let with = PointCloud {
        points: points.clone(),
        normals: Some(cloud.normals.iter().map(|&v| v.into()).collect()),
        ..PointCloud::default()
    };
    let without = PointCloud {
        points,
        normals: None,
        ..PointCloud::default()
    };
    let mut runs = Vec::new();
    let mut profiles = Vec::new();
    let out = work.join("cli-output.ply");
    for (label, pc) in [
        ("points only: normals estimated and oriented", &without),
        ("points and normals: file normals", &with),
    ] {
        let input = work.join("cli-input.ply");
        write_ply(&input, &pc.columns(), PlyFormat::BinaryLittleEndian)?;
        let mut run = run_with_peak(exe, &input, &out)?;
        run.label = label;
        run.points = pc.len();
        runs.push(run);
        if profile {
            profiles.push((label, perf_profile(exe, &input, work)));
        }
        let _ = std::fs::remove_file(&input);
        let _ = std::fs::remove_file(&out);
    }
    Ok(Cli {
        runs,
        error: None,
        profiles,
    })
}

/// Builds the release `mlscurv` and returns its path (from cargo's JSON messages).
pub(crate) fn build_mlscurv() -> Result<PathBuf> {
    let output = crate::cargo()
        .args([
            "build",
            "--release",
            "-p",
            "mls-cli",
            "--bin",
            "mlscurv",
            "--message-format=json-render-diagnostics",
        ])
        .stderr(Stdio::inherit())
        .output()
        .context("cannot run cargo build")?;
    if !output.status.success() {
        bail!("cargo build --release -p mls-cli failed");
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    stdout
        .lines()
        .filter(|l| l.contains("\"reason\":\"compiler-artifact\""))
        .filter_map(|l| json_string_field(l, "executable"))
        .find(|p| p.ends_with("mlscurv") || p.ends_with("mlscurv.exe"))
        .map(PathBuf::from)
        .context("cargo did not report the mlscurv executable")
}

/// The string value of `"key":"…"` in one line of cargo's JSON (paths need no unescaping on
/// the platforms this runs on, apart from `\\`).
pub(super) fn json_string_field(line: &str, key: &str) -> Option<String> {
    let start = line.find(&format!("\"{key}\":\""))? + key.len() + 4;
    let rest = &line[start..];
    let end = rest.find('"')?;
    Some(rest[..end].replace("\\\\", "\\"))
}

/// Runs `mlscurv curvature IN -o OUT` and reads its peak RSS: from `/usr/bin/time -v` when
/// installed (exact: the kernel's rusage of the child), else by polling VmHWM in
/// `/proc/<pid>/status` (the high-water mark, so only growth in the last few milliseconds
/// before exit could be missed).
pub(super) fn run_with_peak(exe: &Path, input: &Path, output: &Path) -> Result<CliRun> {
    // Issue 5's targets are the MLS surface's (`--method paper`); the jet, the default since
    // issue 11, is timed in docs/accuracy.md.
    let args = [
        "curvature".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        output.as_os_str(),
        "--method".as_ref(),
        "paper".as_ref(),
    ];
    let time = Path::new("/usr/bin/time");
    let t = Instant::now();
    let (stderr, peak_rss, method) = if time.exists() {
        let out = Command::new(time)
            .arg("-v")
            .arg(exe)
            .args(args)
            .output()
            .context("cannot run /usr/bin/time")?;
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        if !out.status.success() {
            bail!("mlscurv failed ({}):\n{stderr}", out.status);
        }
        let kb = stderr
            .lines()
            .find_map(|l| l.trim().strip_prefix("Maximum resident set size (kbytes):"))
            .and_then(|v| v.trim().parse::<u64>().ok());
        let peak = kb
            .map(|kb| kb * 1024)
            .ok_or_else(|| "no peak in /usr/bin/time's output".to_owned());
        (stderr, peak, "/usr/bin/time -v (maximum resident set size)")
    } else {
        let mut child = Command::new(exe)
            .args(args)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .context("cannot run mlscurv")?;
        let status_path = format!("/proc/{}/status", child.id());
        let mut stderr_pipe = child.stderr.take().context("no stderr pipe")?;
        let reader = std::thread::spawn(move || {
            let mut s = String::new();
            let _ = std::io::Read::read_to_string(&mut stderr_pipe, &mut s);
            s
        });
        let mut peak = 0;
        let status = loop {
            if let Ok(text) = std::fs::read_to_string(&status_path)
                && let Some(kb) = text
                    .lines()
                    .find_map(|l| l.strip_prefix("VmHWM:"))
                    .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            {
                peak = peak.max(kb * 1024);
            }
            if let Some(status) = child.try_wait()? {
                break status;
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        let stderr = reader.join().unwrap_or_default();
        if !status.success() {
            bail!("mlscurv failed ({status}):\n{stderr}");
        }
        let peak = if peak > 0 {
            Ok(peak)
        } else {
            Err("VmHWM not readable".to_owned())
        };
        (stderr, peak, "VmHWM polled from /proc every 5 ms")
    };
    let wall_seconds = t.elapsed().as_secs_f64();
    let stage_times = stderr
        .lines()
        .find_map(|l| l.trim().strip_prefix("time (s)"))
        .map(|s| s.trim().to_owned())
        .unwrap_or_default();
    Ok(CliRun {
        label: "",
        points: 0,
        peak_rss,
        wall_seconds,
        stage_times,
        method,
    })
}

/// A flat profile (self time by symbol) of `mlscurv curvature INPUT`, by `perf record` with
/// the software cpu-clock event (hardware counters are often unavailable in virtual
/// machines). Returns the report's top lines, or why there is none.
pub(super) fn perf_profile(exe: &Path, input: &Path, work: &Path) -> String {
    let run = || -> Result<String> {
        let output = work.join("perf-output.ply");
        let data = work.join("perf.data");
        let status = Command::new("perf")
            .args(["record", "-e", "cpu-clock", "-F", "999", "-o"])
            .arg(&data)
            .arg("--")
            .arg(exe)
            .arg("curvature")
            .args(["--method", "paper"])
            .arg(input)
            .arg("-o")
            .arg(&output)
            .arg("--quiet")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .context("perf is not installed")?;
        let _ = std::fs::remove_file(&output);
        if !status.success() {
            bail!("perf record failed ({status})");
        }
        let report = Command::new("perf")
            .args([
                "report",
                "--stdio",
                "--no-children",
                "--sort",
                "symbol",
                "--percent-limit",
                "1",
                "-i",
            ])
            .arg(&data)
            .stderr(Stdio::null())
            .output()
            .context("perf report failed")?;
        let _ = std::fs::remove_file(&data);
        let text = String::from_utf8_lossy(&report.stdout);
        let lines: Vec<String> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| shorten_symbol(l.trim()))
            .collect();
        if lines.is_empty() {
            bail!("perf report was empty");
        }
        Ok(lines.join("\n"))
    };
    run().unwrap_or_else(|e| format!("(no profile: {e:#})"))
}

/// One line of `perf report`: the percentage, `[.]` or `[k]` and the symbol, with the empty
/// trailing columns and the padding removed, cut to fit a page.
pub(super) fn shorten_symbol(line: &str) -> String {
    let mut words: Vec<&str> = line.split_whitespace().collect();
    while words.last() == Some(&"-") {
        words.pop();
    }
    let line = words.join(" ");
    match line.char_indices().nth(140) {
        Some((i, _)) => format!("{}…", &line[..i]),
        None => line,
    }
}

// ---------------------------------------------------------------------------------------
// Environment
