//! The totals of a run, per adversarial class and per status, and the Markdown report made
//! of them (printed, and written to `target/robustness/report.md`).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use mls_shapes::adversarial::AdversarialClass;

use super::{FLAT_TOLERANCE, OFFSET_TOLERANCE, Options, Outcome, SIMILAR_TOLERANCE};

/// Totals per class.
#[derive(Debug, Default)]
struct ClassTotals {
    clouds: u64,
    failed: u64,
    construction_errors: BTreeMap<&'static str, u64>,
    curvature: [u64; 8],
    projection: [u64; 8],
    pipeline: [u64; 8],
    normals: [u64; 2],
    flat: Option<f64>,
    matched: Option<[f64; 2]>,
    variants: BTreeMap<&'static str, u64>,
}

#[derive(Debug, Default)]
pub(super) struct Summary {
    classes: BTreeMap<AdversarialClass, ClassTotals>,
    pub(super) failures: usize,
    /// The first failures, with their seeds.
    first_failures: Vec<String>,
}

impl Summary {
    pub(super) fn of(outcomes: &[Outcome]) -> Self {
        let mut s = Self::default();
        for o in outcomes {
            if !o.failures.is_empty() {
                s.failures += 1;
                if s.first_failures.len() < 20 {
                    let class = o.class.map_or("?", AdversarialClass::name);
                    s.first_failures.push(format!(
                        "seed {:#x} ({class}, {}): {}",
                        o.seed,
                        o.variant,
                        o.failures[..o.failures.len().min(3)].join("; ")
                    ));
                }
            }
            let Some(class) = o.class else { continue };
            let t = s.classes.entry(class).or_default();
            t.clouds += 1;
            t.failed += u64::from(!o.failures.is_empty());
            if let Some(e) = o.construction_error {
                *t.construction_errors.entry(e).or_default() += 1;
            }
            *t.variants.entry(o.variant).or_default() += 1;
            for (sum, add) in [
                (&mut t.curvature, &o.curvature),
                (&mut t.projection, &o.projection),
                (&mut t.pipeline, &o.pipeline),
            ] {
                for (a, b) in sum.iter_mut().zip(add) {
                    *a += b;
                }
            }
            t.normals[0] += o.normals[0];
            t.normals[1] += o.normals[1];
            if let Some(v) = o.flat {
                t.flat = Some(t.flat.map_or(v, |w| w.max(v)));
            }
            if let Some([c, p]) = o.matched {
                t.matched = Some(t.matched.map_or([c, p], |[wc, wp]| [wc.max(c), wp.max(p)]));
            }
        }
        s
    }

    pub(super) fn render(&self, clouds: usize, options: &Options, seconds: f64) -> String {
        let mut md = String::new();
        let (first, last) = (options.seed, options.seed.wrapping_add(clouds as u64) - 1);
        let _ = writeln!(
            md,
            "# Adversarial clouds\n\n{clouds} clouds (seeds {first:#x}..={last:#x}) in \
             {seconds:.1} s; {} failed.\n",
            self.failures
        );
        let _ = writeln!(
            md,
            "Statuses are counted per query: `ok`, then codes 1–7 (no_neighbours, \
             too_few_neighbours, normal_undefined, gradient_vanishes, projection_failed, \
             invalid_query, normal_estimation_failed); code 8 (outlier) is the jet's without \
             file normals, which these checks do not run.\n"
        );
        md.push_str(
            "| class | clouds | failed | construction error | curvature ok/1/2/3/4/5/6 | \
             projection ok/1/2/3/4/5/6 | normals ok/failed | pipeline ok/1/2/3/4 | worst |\n\
             | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
        );
        let statuses = |c: &[u64; 8], n: usize| {
            c[..n]
                .iter()
                .map(u64::to_string)
                .collect::<Vec<_>>()
                .join("/")
        };
        for (class, t) in &self.classes {
            let errors = if t.construction_errors.is_empty() {
                "—".to_owned()
            } else {
                t.construction_errors
                    .iter()
                    .map(|(e, n)| format!("{e} × {n}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let worst = match (t.flat, t.matched) {
                (Some(f), _) => format!("\\|k\\|·h ≤ {f:.1e}"),
                (_, Some([c, p])) => format!("Δ ≤ {c:.1e} / {p:.1e}"),
                _ => "—".to_owned(),
            };
            let _ = writeln!(
                md,
                "| {class} | {} | {} | {errors} | {} | {} | {}/{} | {} | {worst} |",
                t.clouds,
                t.failed,
                statuses(&t.curvature, 7),
                statuses(&t.projection, 7),
                t.normals[0],
                t.normals[1],
                statuses(&t.pipeline, 5),
            );
        }
        md.push_str("\nVariants: ");
        let variants: Vec<String> = self
            .classes
            .iter()
            .map(|(class, t)| {
                let v: Vec<String> = t
                    .variants
                    .iter()
                    .map(|(name, n)| format!("{name} × {n}"))
                    .collect();
                format!("{class}: {}", v.join(", "))
            })
            .collect();
        md.push_str(&variants.join("; "));
        md.push('\n');
        let totals = self.classes.values().fold([0u64; 3], |acc, t| {
            [
                acc[0] + t.curvature.iter().sum::<u64>(),
                acc[1] + t.projection.iter().sum::<u64>(),
                acc[2] + t.pipeline.iter().sum::<u64>(),
            ]
        });
        let _ = writeln!(
            md,
            "\nEvaluations: {} curvature, {} projection, {} pipeline. Tolerances: flat \
             {FLAT_TOLERANCE:e}, offset {OFFSET_TOLERANCE:?}, scale and duplicates \
             {SIMILAR_TOLERANCE:?} (at the points, after projection).",
            totals[0], totals[1], totals[2]
        );
        if !self.first_failures.is_empty() {
            md.push_str("\n## Failures\n\n");
            for f in &self.first_failures {
                let _ = writeln!(md, "- {f}");
            }
        }
        md
    }
}
