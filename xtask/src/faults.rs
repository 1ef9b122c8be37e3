//! Fault injection: does `validate` catch the misreadings a careful reader of the paper could
//! make? Each fault is a source patch applied to a copy of the workspace (production code has
//! no switch for it); the copy then runs `validate --quick --differential-only`, which must
//! fail.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use anyhow::{Context, Result, bail};

#[derive(Debug)]
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
        file: "crates/mls-core/src/kernels/field.rs",
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
        name: "F7 β's 3aB² by (1 + 1e-9)",
        description: "near threshold: β = 1 − 3aB² with 3(1 + 1e-9) (∇g and H move by about 1e-9 relative)",
        file: "crates/mls-core/src/kernels/field.rs",
        original: "let beta = 1.0 - 3.0 * a * b2;",
        replacement: "let beta = 1.0 - 3.0 * (1.0 + 1e-9) * a * b2;",
    },
    Fault {
        name: "G1 gradient threshold 1e-12 → 0.6",
        description: "MIN_GRADIENT_RATIO raised until 16 % of evaluations are skipped as GradientVanishes (issue 12's audit)",
        file: "crates/mls-core/src/field.rs",
        original: "pub const MIN_GRADIENT_RATIO: f64 = 1e-12;",
        replacement: "pub const MIN_GRADIENT_RATIO: f64 = 0.6;",
    },
    Fault {
        name: "X1 exp's P1 by (1 + 1e-9)",
        description: "near threshold: the first coefficient of the kernels' exp polynomial off by 1e-9 relative",
        file: "crates/mls-core/src/kernels/exp.rs",
        original: "const P1: f64 = 1.666_666_666_666_660_2e-1;",
        replacement: "const P1: f64 = 1.666_666_666_666_660_2e-1 * (1.0 + 1e-9);",
    },
    Fault {
        name: "X2 exp's ln 2 split without its low part",
        description: "r = x − k ln2_hi, dropping the k ln2_lo correction (weights off by up to 1e-7 relative)",
        file: "crates/mls-core/src/kernels/exp.rs",
        original: "let lo = kf * LN2_LO;",
        replacement: "let lo = kf * 0.0 * LN2_LO;",
    },
    Fault {
        name: "S1 search radius × 0.64",
        description: "the k-d tree query radius 0.64 × cutoff·h (issue 12's audit)",
        file: "crates/mls-core/src/surface.rs",
        original: "let (mut lo, mut hi) = (u32::MAX, 0);\n        self.tree\n            .query(&x.coords.into())\n            .within::<SquaredEuclidean<f64>>(radius * radius)",
        replacement: "let (mut lo, mut hi) = (u32::MAX, 0);\n        self.tree\n            .query(&x.coords.into())\n            .within::<SquaredEuclidean<f64>>((0.64 * radius) * (0.64 * radius))",
    },
    Fault {
        name: "S2 cluster reach = radius",
        description: "a cluster's shared search reaches the support radius from its centre, not radius + spread (issue 12's audit)",
        file: "crates/mls-core/src/surface/evaluator.rs",
        original: "(radius + spread) * (1.0 + 1e-9)",
        replacement: "(radius + 0.0 * spread) * (1.0 + 1e-9)",
    },
    Fault {
        name: "C1 mean of the shape operator by (1 + 1e-9)",
        description: "near threshold: mean = (S11 + S22)/2 · (1 + 1e-9), so k1, k2 and mean move by 1e-9 · mean",
        file: "crates/mls-core/src/curvature.rs",
        original: "let mean = 0.5 * (a + c);",
        replacement: "let mean = 0.5 * (1.0 + 1e-9) * (a + c);",
    },
    Fault {
        name: "C2 principal angle halved twice",
        description: "φ = ½ atan2(2 S12, S11 − S22) written ½ atan2(S12, S11 − S22)",
        file: "crates/mls-core/src/curvature.rs",
        original: "let angle = 0.5 * b.atan2(0.5 * (a - c));",
        replacement: "let angle = 0.5 * b.atan2(a - c);",
    },
    Fault {
        name: "P1 e″'s 10aB² by (1 + 1e-9)",
        description: "near threshold: e″ = Σθ(2 − 10aB² + 4a²B⁴) with 10(1 + 1e-9)",
        file: "crates/mls-core/src/kernels/line.rs",
        original: "theta[l] * (2.0 - 10.0 * ab2[l]",
        replacement: "theta[l] * (2.0 - 10.0 * (1.0 + 1e-9) * ab2[l]",
    },
    Fault {
        name: "P2 projection walks uphill",
        description: "the line search heads along +e′ (towards the energy maxima, the spurious sheets)",
        file: "crates/mls-core/src/projection.rs",
        original: "-e1.signum()\n    } else if",
        replacement: "e1.signum()\n    } else if",
    },
    Fault {
        name: "P3 e′ cubic term 3aB³",
        description: "e′ = Σ 2θ(B − aB³) misread as Σ 2θ(B − 3aB³) (d/dB of B³ taken twice)",
        file: "crates/mls-core/src/kernels/line.rs",
        original: "2.0 * theta[l] * bb[l] * (1.0 - ab2[l])",
        replacement: "2.0 * theta[l] * bb[l] * (1.0 - 3.0 * ab2[l])",
    },
    Fault {
        name: "P4 series' e″ β² term by (1 + 1e-9)",
        description: "near threshold: in the series near t = 0, q₂ = −10 + 24τ² with 10(1 + 1e-9)",
        file: "crates/mls-core/src/projection.rs",
        original: "-10.0 + 24.0 * t2,",
        replacement: "-10.0 * (1.0 + 1e-9) + 24.0 * t2,",
    },
    Fault {
        name: "P5 series' moments along the wrong axis",
        description: "β = d·n with n's y and z swapped in the moments of the series",
        file: "crates/mls-core/src/kernels/line.rs",
        original: "x[l] * n.x + y[l] * n.y + z[l] * n.z",
        replacement: "x[l] * n.x + y[l] * n.z + z[l] * n.y",
    },
    Fault {
        name: "SH1 shrinkage δ by (1 + 1e-9)",
        description: "near threshold: δ = (k1 + k2)h²/4 · (1 + 1e-9) in the shrinkage correction",
        file: "crates/mls-core/src/adaptive.rs",
        original: "let delta = 0.5 * curvature.mean * h * h;",
        replacement: "let delta = 0.5 * (1.0 + 1e-9) * curvature.mean * h * h;",
    },
    Fault {
        name: "SH2 shrinkage inverted the wrong way",
        description: "k/(1 − kδ) (the parallel surface's curvature) applied instead of its inverse k/(1 + kδ)",
        file: "crates/mls-core/src/adaptive.rs",
        original: "let k1 = curvature.k1 / (1.0 + curvature.k1 * delta);",
        replacement: "let k1 = curvature.k1 / (1.0 - curvature.k1 * delta);",
    },
    Fault {
        name: "A1 predicted scatter with √Σw",
        description: "the adaptive scatter C σ/(h² √(2Σw)) written C σ/(h² √Σw)",
        file: "crates/mls-core/src/adaptive.rs",
        original: "unit_scatter: 1.0 / (h * h * (2.0 * weight_sum).sqrt()),",
        replacement: "unit_scatter: 1.0 / (h * h * weight_sum.sqrt()),",
    },
    Fault {
        name: "A2 Richardson bias over h_b² + h_a²",
        description: "the h² bias c h_a² = h_a² (k_b − k_a)/(h_b² − h_a²) with h_b² + h_a² in the denominator",
        file: "crates/mls-core/src/adaptive.rs",
        original: "let bias = |a: f64, b: f64| ha2 * (b - a) / (hb2 - ha2);",
        replacement: "let bias = |a: f64, b: f64| ha2 * (b - a) / (hb2 + ha2);",
    },
    Fault {
        name: "A3 noise dof without the leverage",
        description: "σ² = RSS/Σw instead of RSS/(Σw − Σ w h_ii): the fitted terms' degrees of freedom not removed",
        file: "crates/mls-core/src/adaptive.rs",
        original: "let dof = sw - leverage;",
        replacement: "let dof = sw;",
    },
    Fault {
        name: "NE1 centroid not normalised",
        description: "the printed c = Σθq (erratum E2) instead of Σθq/Σθ (issue 12's audit)",
        file: "crates/mls-core/src/normals/estimate.rs",
        original: "let c = moment / wsum;",
        replacement: "let c = moment;",
    },
    Fault {
        name: "NE2 neighbourhood without the point",
        description: "the covariance of the k neighbours alone, the point itself left out",
        file: "crates/mls-core/src/normals/estimate.rs",
        original: "normal_from_neighbourhood(p, iter::once(p).chain(others), h, tolerance)",
        replacement: "normal_from_neighbourhood(p, others.chain(iter::empty()), h, tolerance)",
    },
    Fault {
        name: "NE3 covariance weights exp(−d²/h)",
        description: "θ = exp(−|q − p|²/h) for exp(−|q − p|²/h²) in the covariance",
        file: "crates/mls-core/src/normals/estimate.rs",
        original: "let inv_h2 = 1.0 / (h * h);\n    // `f64::max`",
        replacement: "let inv_h2 = 1.0 / h;\n    // `f64::max`",
    },
    Fault {
        name: "J1 slope sign",
        description: "the jet's slope data from a normal ν taken as +ν_u/ν_w instead of −ν_u/ν_w",
        file: "crates/mls-core/src/jet/fit.rs",
        original: "[-a / c, -b / c]",
        replacement: "[a / c, -b / c]",
    },
    Fault {
        name: "J2 mixed term of the jet's Hessian",
        description: "H = −(2a20 t1t1ᵀ + a11(t1t2ᵀ + t2t1ᵀ) + 2a02 t2t2ᵀ) with 2a11 for a11",
        file: "crates/mls-core/src/jet/mod.rs",
        original: "(t1 * t2.transpose() + t2 * t1.transpose()) * a[A11]",
        replacement: "(t1 * t2.transpose() + t2 * t1.transpose()) * (2.0 * a[A11])",
    },
    Fault {
        name: "J3 predicted sd's mixed term",
        description: "δk = −2(c² δa20 + cs δa11 + s² δa02)/|∇F| with 2cs for cs",
        file: "crates/mls-core/src/jet/mod.rs",
        original: "Vector::new(cs * cs, cs * sn, sn * sn)",
        replacement: "Vector::new(cs * cs, 2.0 * cs * sn, sn * sn)",
    },
    Fault {
        name: "J4 slope degrees of freedom",
        description: "the slopes' share of the hat matrix's trace counted without the weight λ",
        file: "crates/mls-core/src/jet/fit.rs",
        original: "weight_s - lambda * trace_product(&inv, &sp2)",
        replacement: "weight_s - trace_product(&inv, &sp2)",
    },
    Fault {
        name: "J5 trusted fits",
        description: "a fit enters the ladder's stopping rules from 2 equations per coefficient, not 3",
        file: "crates/mls-core/src/jet/mod.rs",
        original: "pub const TRUSTED_EQUATIONS_PER_COEFFICIENT: f64 = 3.0;",
        replacement: "pub const TRUSTED_EQUATIONS_PER_COEFFICIENT: f64 = 2.0;",
    },
    Fault {
        name: "ST1 stream drops the last partial chunk",
        description: "the chunk loop stops at the last whole chunk, so the queries after it (in the spatial order) get no result",
        file: "crates/mls-core/src/stream.rs",
        original: "for start in (0..queries.len()).step_by(chunk) {",
        replacement: "for start in (0..queries.len() / chunk * chunk).step_by(chunk) {",
    },
    Fault {
        name: "ST2 each chunk one query short",
        description: "off by one between chunks: a chunk ends one before the next begins, so one query per chunk boundary is skipped",
        file: "crates/mls-core/src/stream.rs",
        original: "let end = (start + chunk).min(queries.len());",
        replacement: "let end = (start + chunk).min(queries.len()).max(start + 1) - 1;",
    },
    Fault {
        name: "ST3 results under the wrong queries' indices",
        description: "a chunk evaluates the queries at its positions in input order but reports them under the indices of the spatial order",
        file: "crates/mls-core/src/stream.rs",
        original: "batch.extend(indices.iter().map(|&i| queries[i]));",
        replacement: "batch.extend(queries[start..end].iter().copied());",
    },
    Fault {
        name: "SP1 local spacing by (1 + 1e-9)",
        description: "near threshold: s(p) = √(mean d²)/ρ_k · (1 + 1e-9), so the suggested h moves by 1e-9 relative",
        file: "crates/mls-core/src/normals/spacing.rs",
        original: "mean_d2.sqrt() / rho",
        replacement: "mean_d2.sqrt() * (1.0 + 1e-9) / rho",
    },
    Fault {
        name: "SP2 k-nearest query without the point itself",
        description: "off by one in k: the k-d tree asked for k hits, one of them the point, so k − 1 neighbours against the grid's ρ_k",
        file: "crates/mls-core/src/normals/spacing.rs",
        original: "NonZeroUsize::new(k + 1)",
        replacement: "NonZeroUsize::new(k)",
    },
    Fault {
        name: "SP3 spacing as the mean",
        description: "the spacing taken as the mean of the local spacings instead of their median",
        file: "crates/mls-core/src/normals/spacing.rs",
        original: "spacing: local_spacing.median,",
        replacement: "spacing: local_spacing.mean,",
    },
];

/// Every fault, or those whose name starts with one of `only`; a prefix that names no fault is
/// an error (a typo, not a run with nothing to catch).
fn select(only: &[String]) -> Result<Vec<&'static Fault>> {
    if let Some(unknown) = only
        .iter()
        .find(|o| !FAULTS.iter().any(|f| f.name.starts_with(o.as_str())))
    {
        bail!(
            "no fault's name starts with `{unknown}` (the names start with {})",
            FAULTS
                .iter()
                .filter_map(|f| f.name.split_whitespace().next())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(FAULTS
        .iter()
        .filter(|f| only.is_empty() || only.iter().any(|o| f.name.starts_with(o.as_str())))
        .collect())
}

/// Runs every fault, or those whose name starts with one of `only`.
pub(crate) fn run(only: &[String]) -> Result<()> {
    let work = Path::new("target/faults/work");
    let mut report = String::from(
        "# Fault injection\n\nEach fault is a source patch on a copy of the workspace; `cargo xtask validate --quick \
         --differential-only` then runs on the copy. Caught means it reported `validation failed`.\n\n| fault | misreading | result |\n| --- | --- | --- |\n",
    );
    let selected = select(only)?;
    let mut missed = 0;
    let mut count = 0;
    for fault in selected {
        count += 1;
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
        if !caught {
            // A crash or a pass: the end of its output says which.
            for line in stderr
                .lines()
                .rev()
                .take(3)
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
            {
                eprintln!("   {line}");
            }
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
    writeln!(report, "\n{} of {count} caught.", count - missed)?;
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

#[cfg(test)]
mod tests {
    use super::{FAULTS, select};

    #[test]
    fn prefixes_select_faults_and_a_typo_is_an_error() {
        let names = |only: &[&str]| -> Vec<&str> {
            let only: Vec<String> = only.iter().map(|s| s.to_string()).collect();
            select(&only).unwrap().iter().map(|f| f.name).collect()
        };
        assert_eq!(names(&[]).len(), FAULTS.len());
        let ne = names(&["NE"]);
        assert_eq!(ne.len(), 3);
        assert!(ne.iter().all(|n| n.starts_with("NE")));
        assert_eq!(names(&["G1", "S1"]).len(), 2);
        let err = select(&["G1".into(), "NOPE".into()])
            .unwrap_err()
            .to_string();
        assert!(err.contains("`NOPE`"), "{err}");
    }

    /// Every fault's text is in its file exactly once, so that `cargo xtask faults` can apply
    /// it: a refactor that rewrites the patched lines fails here, in `cargo test`, rather than
    /// in the half-hour fault run.
    #[test]
    fn every_fault_applies() {
        let root = crate::project_root();
        for f in FAULTS {
            let source = std::fs::read_to_string(root.join(f.file)).expect(f.file);
            assert_eq!(
                source.matches(f.original).count(),
                1,
                "fault `{}`: its text is not in {} exactly once",
                f.name,
                f.file
            );
        }
    }
}
