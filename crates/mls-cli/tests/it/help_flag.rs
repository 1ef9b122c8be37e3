//! `-h` is not help: `curvature -h 0.01 in.ply -o out.ply` used to print help and exit 0, which
//! a script read as success. It is now a usage error pointing to `--h` (the scale) and
//! `--help`; `--help` works on every command.

use crate::common::{listing, mlscurv, run, write_unit_sphere};

const COMMANDS: [&str; 5] = ["curvature", "eval", "normals", "project", "info"];

#[test]
fn short_h_with_a_scale_fails_and_points_to_double_dash_h_and_help() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.xyz");
    write_unit_sphere(&input, 500);
    let before = listing(dir.path());
    for short in ["-h", "-h0.01", "-h=0.01"] {
        let mut cmd = mlscurv();
        cmd.arg("curvature").arg(short);
        if short == "-h" {
            cmd.arg("0.01");
        }
        let r = run(cmd.arg(&input).arg("-o").arg(dir.path().join("out.ply")));
        assert_eq!(r.code, Some(2), "{short}: a usage error\n{}", r.stderr);
        assert_eq!(r.stdout, "", "{short}: no help on stdout");
        assert!(r.stderr.contains(&format!("`{short}` is not an option")));
        assert!(r.stderr.contains("`--h H`"), "{}", r.stderr);
        assert!(r.stderr.contains("`--help`"), "{}", r.stderr);
        assert!(!r.stderr.contains("panicked"));
        assert_eq!(listing(dir.path()), before, "{short}: no output file");
    }
}

#[test]
fn short_h_alone_fails_on_every_command_and_names_only_the_options_it_has() {
    for command in COMMANDS {
        let r = run(mlscurv().arg(command).arg("-h"));
        assert_eq!(r.code, Some(2), "{command} -h\n{}", r.stderr);
        assert!(
            r.stderr.contains(&format!("`mlscurv {command}`")),
            "{}",
            r.stderr
        );
        assert!(r.stderr.contains("`--help`"), "{}", r.stderr);
        // `info` has no scale option, so it must not suggest one.
        assert_eq!(
            r.stderr.contains("--h H"),
            command != "info",
            "{command}: {}",
            r.stderr
        );
    }
    let r = run(mlscurv().arg("-h"));
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("`--help`"), "{}", r.stderr);
}

/// Operands after `--` are not options, so a `-h` there is not refused as one (it then fails as
/// a missing file, which is what it is).
#[test]
fn short_h_after_double_dash_is_an_operand() {
    let dir = tempfile::tempdir().unwrap();
    let r = run(mlscurv().current_dir(dir.path()).args(["info", "--", "-h"]));
    assert!(!r.success);
    assert!(!r.stderr.contains("is not an option"), "{}", r.stderr);
    assert!(r.stderr.contains("-h"), "{}", r.stderr);
}

#[test]
fn long_help_works_on_every_command_and_lists_no_short_h() {
    for args in [vec!["--help"], vec!["help"]]
        .into_iter()
        .chain(COMMANDS.map(|c| vec![c, "--help"]))
    {
        let r = run(mlscurv().args(&args));
        assert_eq!(r.code, Some(0), "{args:?}: {}", r.stderr);
        assert!(
            r.stdout.contains("Usage: mlscurv"),
            "{args:?}: {}",
            r.stdout
        );
        assert!(r.stdout.contains("--help"), "{args:?}");
        assert!(
            !r.stdout.contains("-h,"),
            "{args:?} lists -h:\n{}",
            r.stdout
        );
    }
    let r = run(mlscurv().args(["curvature", "--help"]));
    for option in [
        "--h <H>",
        "--h-factor",
        "--force",
        "--input-format",
        "--output-format",
    ] {
        assert!(r.stdout.contains(option), "no {option}:\n{}", r.stdout);
    }
    let r = run(mlscurv().args(["eval", "--help"]));
    for option in ["--queries", "--threads", "--quiet", "--force"] {
        assert!(r.stdout.contains(option), "no {option}:\n{}", r.stdout);
    }
    // The deprecated `--at` of eval still parses but is not advertised.
    assert!(!r.stdout.contains("--at "), "{}", r.stdout);
}
