//! Fault injection: does `validate` catch the misreadings a careful reader of the paper could
//! make? Each fault is a source patch applied to a copy of the workspace (production code has
//! no switch for it); the copy then runs `validate --quick --differential-only`, which must
//! fail.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use anyhow::{Context, Result, bail};

struct Fault {
    name: &'static str,
    description: &'static str,
    file: &'static str,
    original: &'static str,
    replacement: &'static str,
}

const FAULTS: &[Fault] = &[
    Fault {
        name: "F1 J transposed",
        description: "∂B/∂x = n + J d instead of n + Jᵀ d (∇ᵀ(n) read as ∇(n))",
        file: "crates/mls-core/src/field.rs",
        original: "let jt = field.jacobian.transpose();",
        replacement: "let jt = field.jacobian;",
    },
    Fault {
        name: "F2 ∂²n contracted over a derivative index",
        description: "∇ᵀ(∇n)·d read as rows (N_k d)ᵀ instead of Σ_a d_a N_a",
        file: "crates/mls-core/src/field.rs",
        original: "+ field.second[0] * sum_beta_d.x\n        + field.second[1] * sum_beta_d.y\n        + field.second[2] * sum_beta_d.z;",
        replacement: "+ Matrix::from_rows(&[(field.second[0] * sum_beta_d).transpose(), (field.second[1] * sum_beta_d).transpose(), (field.second[2] * sum_beta_d).transpose()]);",
    },
    Fault {
        name: "F3 ∂²n term dropped",
        description: "the Appendix's ∇ᵀ(∇n)·(x − q) term omitted",
        file: "crates/mls-core/src/field.rs",
        original: "+ field.second[0] * sum_beta_d.x\n        + field.second[1] * sum_beta_d.y\n        + field.second[2] * sum_beta_d.z;",
        replacement: ";",
    },
    Fault {
        name: "F4 sign of (6B²/h⁴ − 2/h²)",
        description: "the C·(∂B/∂x)ᵀ coefficient of Eq. 8, (6B²/h⁴ − 2/h²) = −2β/h², taken as +2β/h²",
        file: "crates/mls-core/src/field.rs",
        original: "(sum_beta_d * (-2.0 * a), beta.second.matrix() * (-2.0 * a))",
        replacement: "(sum_beta_d * (2.0 * a), beta.second.matrix() * (2.0 * a))",
    },
    Fault {
        name: "F5 coefficient 12 → 6",
        description: "−12/h² B D Dᵀ (Appendix) written −6/h² B D Dᵀ",
        file: "crates/mls-core/src/field.rs",
        original: "let c_bb = -6.0 * a * b;",
        replacement: "let c_bb = -3.0 * a * b;",
    },
    Fault {
        name: "F6 ∂²m curvature term 4/h⁴ → 2/h⁴",
        description: "∇∇θ = θ(4 d dᵀ/h⁴ − 2I/h²) written with 2 d dᵀ/h⁴",
        file: "crates/mls-core/src/field.rs",
        original: "s2[c].matrix() * (4.0 * a * a)",
        replacement: "s2[c].matrix() * (2.0 * a * a)",
    },
    Fault {
        name: "J1 slope sign",
        description: "the jet's slope data from a normal ν taken as +ν_u/ν_w instead of −ν_u/ν_w",
        file: "crates/mls-core/src/jet.rs",
        original: "[-a / c, -b / c]",
        replacement: "[a / c, -b / c]",
    },
    Fault {
        name: "J2 mixed term of the jet's Hessian",
        description: "H = −(2a20 t1t1ᵀ + a11(t1t2ᵀ + t2t1ᵀ) + 2a02 t2t2ᵀ) with 2a11 for a11",
        file: "crates/mls-core/src/jet.rs",
        original: "(t1 * t2.transpose() + t2 * t1.transpose()) * a[A11]",
        replacement: "(t1 * t2.transpose() + t2 * t1.transpose()) * (2.0 * a[A11])",
    },
    Fault {
        name: "J3 predicted sd's mixed term",
        description: "δk = −2(c² δa20 + cs δa11 + s² δa02)/|∇F| with 2cs for cs",
        file: "crates/mls-core/src/jet.rs",
        original: "Vector::new(cs * cs, cs * sn, sn * sn)",
        replacement: "Vector::new(cs * cs, 2.0 * cs * sn, sn * sn)",
    },
    Fault {
        name: "J4 slope degrees of freedom",
        description: "the slopes' share of the hat matrix's trace counted without the weight λ",
        file: "crates/mls-core/src/jet.rs",
        original: "weight_s - lambda * inv.dot(&sp2)",
        replacement: "weight_s - inv.dot(&sp2)",
    },
];

pub(crate) fn run() -> Result<()> {
    let work = Path::new("target/faults/work");
    let mut report = String::from(
        "# Fault injection\n\nEach fault is a source patch on a copy of the workspace; `cargo xtask validate --quick \
         --differential-only` then runs on the copy. Caught means it reported `validation failed`.\n\n| fault | misreading | result |\n| --- | --- | --- |\n",
    );
    let mut missed = 0;
    for fault in FAULTS {
        copy_workspace(work)?;
        let path = work.join(fault.file);
        let source =
            fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        if source.matches(fault.original).count() != 1 {
            bail!(
                "fault `{}`: the patched text no longer appears exactly once in {}",
                fault.name,
                fault.file
            );
        }
        fs::write(&path, source.replacen(fault.original, fault.replacement, 1))?;
        eprintln!("== {}: {}", fault.name, fault.description);
        let target = std::env::current_dir()?.join("target/faults/target");
        // A patch that no longer compiles is an error of this task, not a caught fault.
        let built = crate::cargo()
            .current_dir(work)
            .env("CARGO_TARGET_DIR", &target)
            .args(["build", "--release", "--quiet", "-p", "xtask"])
            .status()
            .context("building the patched workspace")?;
        if !built.success() {
            bail!(
                "fault `{}`: the patched workspace does not compile",
                fault.name
            );
        }
        let output = crate::cargo()
            .current_dir(work)
            .env("CARGO_TARGET_DIR", &target)
            .args([
                "run",
                "--release",
                "--quiet",
                "-p",
                "xtask",
                "--",
                "validate",
                "--quick",
                "--differential-only",
            ])
            .output()
            .context("running the patched validate")?;
        let stderr = String::from_utf8_lossy(&output.stderr);
        // Caught only when validation itself reports the failure (not any non-zero exit).
        let caught = !output.status.success() && stderr.contains("validation failed");
        if let Some(line) = stderr.lines().find(|l| l.contains("validation failed")) {
            eprintln!("   {line}");
        }
        missed += usize::from(!caught);
        eprintln!(
            "== {}: {}",
            fault.name,
            if caught { "caught" } else { "MISSED" }
        );
        writeln!(
            report,
            "| {} | {} | {} |",
            fault.name,
            fault.description,
            if caught { "caught" } else { "**missed**" }
        )?;
    }
    fs::create_dir_all("target/validate")?;
    fs::write("target/validate/faults.md", &report)?;
    println!("{report}");
    if missed > 0 {
        bail!("{missed} fault(s) not caught");
    }
    Ok(())
}

/// Copies the sources the build needs (not `target/`) into `dest`, replacing what was there.
fn copy_workspace(dest: &Path) -> Result<()> {
    if dest.exists() {
        fs::remove_dir_all(dest)?;
    }
    fs::create_dir_all(dest)?;
    for entry in [
        "Cargo.toml",
        "Cargo.lock",
        ".cargo",
        "crates",
        "xtask",
        "tests",
    ] {
        let src = Path::new(entry);
        if src.exists() {
            copy_recursively(src, &dest.join(entry))?;
        }
    }
    Ok(())
}

fn copy_recursively(src: &Path, dest: &Path) -> Result<()> {
    if src.is_dir() {
        fs::create_dir_all(dest)?;
        for entry in fs::read_dir(src)? {
            let entry = entry?;
            let name = entry.file_name();
            if name == "target" || name.to_string_lossy().starts_with("target-") {
                continue;
            }
            copy_recursively(&entry.path(), &dest.join(name))?;
        }
    } else {
        fs::copy(src, dest).with_context(|| format!("copying {}", src.display()))?;
    }
    Ok(())
}
