//! Bad input: a non-zero exit, one line on stderr naming the file and the place, no panic,
//! and nothing left in the directory.

use std::collections::BTreeSet;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

use tempfile::TempDir;

use crate::common::{Run, bunny_path, listing, mlscurv, run, write_xyz};

/// Points of the small valid cloud used where the input must get past reading.
const SMALL_N: usize = 500;

/// A temporary directory and what it held before the run.
struct Scene {
    dir: TempDir,
    before: BTreeSet<OsString>,
}

impl Scene {
    /// A directory holding the given files.
    fn with_files(files: &[(&str, &[u8])]) -> Self {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in files {
            std::fs::write(dir.path().join(name), bytes).unwrap();
        }
        let before = listing(dir.path());
        Self { dir, before }
    }

    /// A directory holding one text file.
    fn with(name: &str, text: &str) -> Self {
        Self::with_files(&[(name, text.as_bytes())])
    }

    /// A directory holding a small valid sphere as `name` (3 or 6 columns).
    fn with_small_sphere(name: &str, with_normals: bool) -> Self {
        let s = mls_shapes::fibonacci_sphere(SMALL_N, 1.0);
        let dir = tempfile::tempdir().unwrap();
        let normals = mls_shapes::normals(&s);
        write_xyz(
            &dir.path().join(name),
            &mls_shapes::points(&s),
            with_normals.then_some(&normals[..]),
        );
        let before = listing(dir.path());
        Self { dir, before }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Runs `curvature <input> -o out.csv` with extra arguments.
    fn curvature(&self, input: &str, extra: &[&str]) -> Run {
        run(mlscurv()
            .arg("curvature")
            .arg(self.path(input))
            .arg("-o")
            .arg(self.path("out.csv"))
            .args(extra))
    }

    /// Asserts the directory holds what it held before the run: no output, no temporary file.
    fn assert_untouched(&self) {
        assert_eq!(
            listing(self.dir.path()),
            self.before,
            "the directory changed"
        );
    }

    /// Asserts the run failed with a one-line `mlscurv: error:` message naming `file` and
    /// containing each of `details`, and left the directory untouched.
    fn assert_error(&self, r: &Run, file: &Path, details: &[&str]) {
        assert_error_message(r, file, details);
        self.assert_untouched();
    }

    /// Asserts a command-line usage error (from clap, several lines) that mentions `option`.
    fn assert_usage_error(&self, r: &Run, option: &str) {
        assert!(!r.success, "expected failure, got success: {}", r.stderr);
        // Every clap error ends in "try '--help'"; the option must be named elsewhere.
        assert!(
            r.stderr.replace("--help", "").contains(option),
            "stderr does not mention {option}:\n{}",
            r.stderr
        );
        assert!(!r.stderr.contains("panicked"), "panic:\n{}", r.stderr);
        self.assert_untouched();
    }
}

fn assert_error_message(r: &Run, file: &Path, details: &[&str]) {
    let e = &r.stderr;
    assert!(!r.success, "expected failure, got success: {e}");
    assert!(!e.contains("panicked"), "panic:\n{e}");
    assert!(e.starts_with("mlscurv: error:"), "stderr: {e}");
    assert!(
        e.ends_with('\n') && e.matches('\n').count() == 1,
        "stderr is not one line: {e:?}"
    );
    let name = file.display().to_string();
    assert!(e.contains(&name), "stderr does not name {name}: {e}");
    for d in details {
        assert!(e.contains(d), "stderr does not say {d:?}: {e}");
    }
    assert_eq!(r.stdout, "", "stdout");
}

/// Three points each a row of `x y z`, then `bad` as the third row.
fn xyz_with_third_row(bad: &str) -> String {
    format!("0 0 0\n1 0 0\n{bad}\n0 0 1\n1 1 1\n")
}

#[test]
fn missing_input_file_is_named() {
    let s = Scene::with_files(&[]);
    s.assert_error(
        &s.curvature("missing.ply", &[]),
        &s.path("missing.ply"),
        &[],
    );
}

#[test]
fn missing_input_is_a_one_line_error_for_every_command() {
    let s = Scene::with_files(&[]);
    let (missing, out) = (s.path("missing.xyz"), s.path("out.ply"));
    let commands: [Vec<OsString>; 5] = [
        vec![
            "curvature".into(),
            missing.clone().into(),
            "-o".into(),
            out.clone().into(),
        ],
        vec![
            "normals".into(),
            missing.clone().into(),
            "-o".into(),
            out.clone().into(),
        ],
        vec![
            "project".into(),
            missing.clone().into(),
            "-o".into(),
            out.clone().into(),
        ],
        vec!["info".into(), missing.clone().into()],
        vec![
            "eval".into(),
            "--cloud".into(),
            missing.clone().into(),
            "--queries".into(),
            missing.clone().into(),
        ],
    ];
    for args in commands {
        let r = run(mlscurv().args(&args));
        assert_error_message(&r, &missing, &[]);
        s.assert_untouched();
    }
}

#[test]
fn unknown_extension_is_named() {
    let s = Scene::with("in.obj", "v 0 0 0\n");
    s.assert_error(&s.curvature("in.obj", &[]), &s.path("in.obj"), &[".obj"]);
}

#[test]
fn ply_with_bad_magic_is_reported_at_header_line_1() {
    let text = "plx\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n\
                property double z\nend_header\n0 0 0\n";
    let s = Scene::with("in.ply", text);
    s.assert_error(&s.curvature("in.ply", &[]), &s.path("in.ply"), &["line 1"]);
}

#[test]
fn ply_without_end_header_is_reported_at_a_header_line() {
    let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n\
                property double z\n";
    let s = Scene::with("in.ply", text);
    s.assert_error(&s.curvature("in.ply", &[]), &s.path("in.ply"), &["line"]);
}

#[test]
fn truncated_binary_ply_is_reported_at_a_byte_offset() {
    let bunny = std::fs::read(bunny_path()).unwrap();
    const END: &[u8] = b"end_header\n";
    let body = bunny.windows(END.len()).position(|w| w == END).unwrap() + END.len();
    // Cut in the middle of a vertex (12 bytes each: three floats).
    let cut = &bunny[..body + 12 * 1000 + 5];
    let s = Scene::with_files(&[("in.ply", cut)]);
    s.assert_error(&s.curvature("in.ply", &[]), &s.path("in.ply"), &["byte"]);
}

#[test]
fn xyz_short_row_is_reported_at_its_line() {
    let s = Scene::with("in.xyz", &xyz_with_third_row("1 2"));
    s.assert_error(&s.curvature("in.xyz", &[]), &s.path("in.xyz"), &["line 3"]);
}

#[test]
fn xyz_non_numeric_value_is_reported_at_its_line_and_quoted() {
    let s = Scene::with("in.xyz", &xyz_with_third_row("1 2 abc"));
    s.assert_error(
        &s.curvature("in.xyz", &[]),
        &s.path("in.xyz"),
        &["line 3", "abc"],
    );
}

#[test]
fn nan_coordinate_is_reported_at_its_line() {
    let s = Scene::with("in.xyz", &xyz_with_third_row("1 NaN 2"));
    s.assert_error(&s.curvature("in.xyz", &[]), &s.path("in.xyz"), &["line 3"]);
}

#[test]
fn infinite_coordinate_is_reported_at_its_line() {
    let s = Scene::with("in.xyz", &xyz_with_third_row("1 2 inf"));
    s.assert_error(&s.curvature("in.xyz", &[]), &s.path("in.xyz"), &["line 3"]);
}

#[test]
fn nan_coordinate_in_csv_is_reported_at_its_line() {
    let s = Scene::with("in.csv", "x,y,z\n0,0,0\n1,0,0\n0,NaN,1\n1,1,1\n");
    s.assert_error(&s.curvature("in.csv", &[]), &s.path("in.csv"), &["line 4"]);
}

#[test]
fn normals_file_without_normals_in_the_file_is_refused() {
    let s = Scene::with_small_sphere("in.xyz", false);
    s.assert_error(
        &s.curvature("in.xyz", &["--normals", "file"]),
        &s.path("in.xyz"),
        &["normals"],
    );
}

#[test]
fn three_points_are_too_few_for_a_neighbourhood() {
    let s = Scene::with("in.xyz", "0 0 0\n1 0 0\n0 1 0\n");
    s.assert_error(&s.curvature("in.xyz", &[]), &s.path("in.xyz"), &["3 point"]);
}

#[test]
fn non_positive_or_nan_h_is_a_usage_error_naming_the_option() {
    let s = Scene::with_small_sphere("in.xyz", true);
    for args in [
        &["--h", "0"][..],
        &["--h", "nan"],
        &["--h=0"],
        &["--h=-1"],
        &["--h=nan"],
    ] {
        s.assert_usage_error(&s.curvature("in.xyz", args), "--h");
    }
}

#[test]
fn cutoff_below_two_h_is_a_usage_error_naming_the_option() {
    let s = Scene::with_small_sphere("in.xyz", true);
    for args in [&["--cutoff", "1"][..], &["--cutoff=-1"]] {
        s.assert_usage_error(&s.curvature("in.xyz", args), "--cutoff");
    }
}

/// clap takes a value that looks like a negative number for an unknown flag unless the
/// argument allows it, so `--h -1` fails with "unexpected argument '-1' found" and a tip to
/// write `-- -1`, and never says which option is wrong.
#[test]
fn negative_h_or_cutoff_as_a_separate_argument_is_a_usage_error_naming_the_option() {
    let s = Scene::with_small_sphere("in.xyz", true);
    s.assert_usage_error(&s.curvature("in.xyz", &["--h", "-1"]), "--h");
    s.assert_usage_error(&s.curvature("in.xyz", &["--cutoff", "-1"]), "--cutoff");
}

#[test]
fn output_equal_to_input_is_refused_and_the_input_is_unchanged() {
    let mut s = Scene::with_small_sphere("in.xyz", true);
    let input = s.path("in.xyz");
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&input, s.path("link.xyz")).unwrap();
        s.before = listing(s.dir.path());
    }
    let original = std::fs::read(&input).unwrap();
    let dir_name = s.dir.path().file_name().unwrap();
    // The same file by the same path, through `.`, through `..` and through a link.
    let mut spellings = vec![
        input.clone(),
        s.dir.path().join(".").join("in.xyz"),
        s.dir.path().join("..").join(dir_name).join("in.xyz"),
    ];
    if cfg!(unix) {
        spellings.push(s.path("link.xyz"));
    }
    for command in ["curvature", "normals", "project", "eval"] {
        for out in &spellings {
            let mut cmd = mlscurv();
            if command == "eval" {
                cmd.arg("eval")
                    .arg("--cloud")
                    .arg(&input)
                    .arg("--queries")
                    .arg(&input);
            } else {
                cmd.arg(command).arg(&input);
            }
            let r = run(cmd.arg("-o").arg(out));
            assert_error_message(&r, out, &[]);
            s.assert_untouched();
            let now = std::fs::read(&input).unwrap();
            assert!(
                now == original,
                "{command} -o {} changed the input",
                out.display()
            );
        }
    }
}

#[test]
fn output_into_a_nonexistent_directory_is_reported_and_creates_nothing() {
    let s = Scene::with_small_sphere("in.xyz", true);
    let out = s.path("no-such-dir").join("out.csv");
    let r = run(mlscurv()
        .arg("curvature")
        .arg(s.path("in.xyz"))
        .arg("-o")
        .arg(&out)
        .arg("--quiet"));
    s.assert_error(&r, &out, &[]);
}

/// mls-io's `Io` errors state the OS error in their message and do not also chain it as a
/// `source()`, which `mlscurv`'s `{:#}` would print a second time.
#[test]
fn io_errors_state_the_operating_system_reason_once() {
    let s = Scene::with_files(&[]);
    let r = s.curvature("missing.ply", &[]);
    assert_error_message(&r, &s.path("missing.ply"), &[]);
    assert_eq!(r.stderr.matches("os error").count(), 1, "{}", r.stderr);
}

/// Writing into a missing directory reports the OS error once, naming the destination, not the
/// temporary file (".out.csv.XXXXXX.tmp") that the atomic writer tried to create.
#[test]
fn output_directory_error_names_the_output_and_no_temporary_file() {
    let s = Scene::with_small_sphere("in.xyz", true);
    let out = s.path("no-such-dir").join("out.csv");
    let r = run(mlscurv()
        .arg("curvature")
        .arg(s.path("in.xyz"))
        .arg("-o")
        .arg(&out)
        .arg("--quiet"));
    s.assert_error(&r, &out, &[]);
    // The test directory itself is named ".tmpXXXX": look for the writer's temporary name.
    assert!(!r.stderr.contains(".out.csv."), "{}", r.stderr);
    assert_eq!(r.stderr.matches("os error").count(), 1, "{}", r.stderr);
}

#[test]
fn a_cloud_where_no_point_succeeds_is_an_error_and_writes_nothing() {
    // Four points: no support holds enough samples for the jet; with h a hundredth of their
    // spacing, none for the paper's surface or its projection either. A file of NaN rows with
    // exit status 0 would pass a script's check.
    let s = Scene::with(
        "four.xyz",
        "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n1 1 0 0 0 1\n",
    );
    let input = s.path("four.xyz");
    for (args, what) in [
        (&["curvature"][..], "curvature"),
        (
            &["curvature", "--method", "paper", "--h", "0.01"],
            "curvature",
        ),
        (&["project", "--h", "0.01"], "projection"),
    ] {
        let r = run(mlscurv()
            .args(&args[..1])
            .arg(&input)
            .arg("-o")
            .arg(s.path("out.csv"))
            .args(&args[1..]));
        assert!(!r.success, "{args:?} succeeded: {}", r.stderr);
        assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
        // After any warning, the error.
        let last = r.stderr.lines().last().unwrap_or_default();
        let want = format!("no {what} could be computed at any of its 4 points (ok 0, ");
        assert!(
            last.starts_with("mlscurv: error:")
                && last.contains(&input.display().to_string())
                && last.contains(&want)
                && last.contains("nothing written"),
            "{args:?}: {}",
            r.stderr
        );
        s.assert_untouched();
    }
}

#[test]
fn a_coordinate_whose_squared_distances_overflow_is_named() {
    let text = "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0.5 0.5 1e300\n2 2 0\n";
    let s = Scene::with("in.xyz", text);
    // Point 4 counted from 0: the fifth row.
    s.assert_error(
        &s.curvature("in.xyz", &[]),
        &s.path("in.xyz"),
        &["point 4", "beyond ±1e153", "overflow"],
    );
}
