//! `eval`'s options: `--queries` (was `--at`, which clashed with `curvature --at`; still
//! accepted), `--threads`, `--quiet`, queries on standard input, output format by extension;
//! and the summaries of every command read without nested parentheses.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::common::{EVAL_HEADER, Table, bunny_path, mlscurv, run_ok, write_unit_sphere};

/// A unit sphere with normals as the cloud, and a few queries inside, on and outside it.
fn inputs(dir: &Path) -> (PathBuf, PathBuf) {
    let cloud = dir.join("cloud.xyz");
    write_unit_sphere(&cloud, 2_000);
    let queries = dir.join("queries.xyz");
    fs::write(&queries, "0 0 0.95\n0 0 1\n0.6 0 0.8\n0 1.05 0\n").unwrap();
    (cloud, queries)
}

fn eval(cloud: &Path) -> Command {
    let mut cmd = mlscurv();
    cmd.arg("eval").arg("--cloud").arg(cloud);
    cmd
}

#[test]
fn queries_option_and_the_old_at_spelling_give_the_same_table() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, queries) = inputs(dir.path());
    let new = run_ok(eval(&cloud).arg("--queries").arg(&queries).arg("-q")).stdout;
    let old = run_ok(eval(&cloud).arg("--at").arg(&queries).arg("-q")).stdout;
    assert_eq!(new, old);
    let t = Table::parse_csv(&new);
    assert_eq!(t.header.join(","), EVAL_HEADER);
    assert_eq!(t.rows.len(), 4);
    assert!(t.column("status").iter().all(|&s| s == 0.0), "{new}");
}

#[test]
fn quiet_silences_the_summary_which_otherwise_goes_to_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, queries) = inputs(dir.path());
    let quiet = run_ok(eval(&cloud).arg("--queries").arg(&queries).arg("--quiet"));
    assert_eq!(quiet.stderr, "");
    let loud = run_ok(eval(&cloud).arg("--queries").arg(&queries));
    assert_eq!(loud.stdout, quiet.stdout, "the table does not change");
    for line in [
        "mlscurv eval: ",
        "  queries         4 from ",
        "  h               ",
        "  status          ok 4",
        "  wrote           <stdout>",
    ] {
        assert!(
            loud.stderr.contains(line),
            "no {line:?} in\n{}",
            loud.stderr
        );
    }
    // Four queries give no rate: it would measure the fixed costs (reading, the index), not
    // the throughput.
    let times = loud
        .stderr
        .lines()
        .find(|l| l.trim_start().starts_with("time (s)"))
        .unwrap_or_else(|| panic!("no time line in\n{}", loud.stderr));
    assert!(times.contains("; total "), "{times}");
    assert!(!times.contains("/s"), "{times}");
}

/// Enough queries (here 1000 copies of the four) and the summary gives their rate, in
/// queries per second.
#[test]
fn the_summary_gives_a_rate_of_queries_when_there_are_enough() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, queries) = inputs(dir.path());
    let many = fs::read_to_string(&queries).unwrap().repeat(250);
    fs::write(&queries, many).unwrap();
    let r = run_ok(eval(&cloud).arg("--queries").arg(&queries));
    let times = r
        .stderr
        .lines()
        .find(|l| l.trim_start().starts_with("time (s)"))
        .unwrap_or_else(|| panic!("no time line in\n{}", r.stderr));
    let rate: f64 = times
        .rsplit_once(" (")
        .and_then(|(_, r)| r.strip_suffix(" queries/s)"))
        .unwrap_or_else(|| panic!("no rate in {times}"))
        .parse()
        .unwrap();
    let total: f64 = times
        .split("; total ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    // The printed rate is the queries over the printed total (each rounded).
    assert!(
        (rate * total - 1000.0).abs() <= 1000.0 * 0.01 + rate * 0.0005,
        "{times}"
    );
}

#[test]
fn threads_option_gives_the_same_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, queries) = inputs(dir.path());
    let all = run_ok(eval(&cloud).arg("--queries").arg(&queries).arg("-q")).stdout;
    let one = run_ok(
        eval(&cloud)
            .arg("--queries")
            .arg(&queries)
            .args(["--threads", "1", "-q"]),
    )
    .stdout;
    let (a, b) = (Table::parse_csv(&all), Table::parse_csv(&one));
    for (ra, rb) in a.rows.iter().zip(&b.rows) {
        for (x, y) in ra.iter().zip(rb) {
            assert!((x - y).abs() <= 1e-12 * x.abs().max(1.0), "{x} vs {y}");
        }
    }
    let r = crate::common::run(
        eval(&cloud)
            .arg("--queries")
            .arg(&queries)
            .args(["--threads", "0"]),
    );
    assert!(!r.success && r.stderr.contains("--threads"), "{}", r.stderr);
}

#[test]
fn queries_from_standard_input() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, queries) = inputs(dir.path());
    let from_file = run_ok(eval(&cloud).arg("--queries").arg(&queries).arg("-q")).stdout;
    let out = eval(&cloud)
        .args(["--queries", "-", "-q"])
        .stdin(Stdio::from(fs::File::open(&queries).unwrap()))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(String::from_utf8(out.stdout).unwrap(), from_file);
}

/// `eval -o out.ply` wrote CSV into the .ply file; it now writes what the extension says.
#[test]
fn output_file_format_follows_its_extension() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, queries) = inputs(dir.path());
    let csv = run_ok(eval(&cloud).arg("--queries").arg(&queries).arg("-q")).stdout;
    let ply = dir.path().join("out.ply");
    run_ok(
        eval(&cloud)
            .arg("--queries")
            .arg(&queries)
            .arg("-o")
            .arg(&ply)
            .arg("-q"),
    );
    let bytes = fs::read(&ply).unwrap();
    assert!(bytes.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    let xyz = dir.path().join("out.xyz");
    run_ok(
        eval(&cloud)
            .arg("--queries")
            .arg(&queries)
            .arg("-o")
            .arg(&xyz)
            .arg("-q"),
    );
    // The same numbers, space-separated after a `#` line of the names.
    let text = fs::read_to_string(&xyz).unwrap();
    let csv = csv.strip_prefix("//").expect("CSV header after `//`");
    let expected = format!("# {}", csv.replace(',', " "));
    assert_eq!(text, expected);
}

/// How deep the parentheses of a line nest.
fn paren_depth(line: &str) -> usize {
    let (mut depth, mut max) = (0usize, 0usize);
    for c in line.chars() {
        match c {
            '(' => {
                depth += 1;
                max = max.max(depth);
            }
            ')' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    max
}

/// The h line used to read "0.002406 = 2 × median local spacing 0.001203 (over 12 neighbours;
/// use --h or --h-factor to change)", and `info` wrapped it in another pair.
#[test]
fn summaries_have_no_nested_parentheses_and_say_how_to_change_h() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.ply");
    let bunny = bunny_path();
    let mut texts = Vec::new();
    for command in ["curvature", "normals", "project"] {
        let r = run_ok(mlscurv().arg(command).arg(&bunny).arg("-o").arg(&out));
        let h = r
            .stderr
            .lines()
            .find(|l| l.starts_with("  h "))
            .unwrap()
            .to_owned();
        assert!(
            h.contains("= 2 × median local spacing")
                && h.ends_with("; --h or --h-factor to change"),
            "{command}: {h}"
        );
        texts.push(r.stderr);
    }
    let r = run_ok(
        mlscurv()
            .arg("curvature")
            .arg(&bunny)
            .arg("-o")
            .arg(&out)
            .args(["--h", "0.003"]),
    );
    assert!(
        r.stderr
            .contains("  h               0.003000, given with --h\n"),
        "{}",
        r.stderr
    );
    texts.push(r.stderr);
    let r = run_ok(mlscurv().arg("info").arg(&bunny));
    assert!(
        r.stdout.contains(
            "suggested h     0.002406 = 2 × median local spacing 0.001203 over 12 neighbours\n"
        ),
        "{}",
        r.stdout
    );
    texts.push(r.stdout);
    for line in texts.iter().flat_map(|t| t.lines()) {
        assert!(paren_depth(line) <= 1, "nested parentheses: {line}");
    }
}
