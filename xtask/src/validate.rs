//! `cargo xtask validate`: the closed form of mls-core against the hyper-dual witness of mls-ad
//! on seeded random clouds, and the curvature of analytic shapes against their exact values.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Result, bail};

use crate::validate_shapes as cases;
use crate::validate_sweep::{QUERIES_PER_CASE, one_case};

/// Differences above this fail the run.
pub(crate) const THRESHOLD: f64 = 1e-10;
/// The jet's predicted error goes through M⁻¹ twice and through residuals, so two correct
/// routes agree less closely than on k; it is also divided by the rounding factor of the fit's
/// conditioning (see `NORMALISATION_NOTE`). Measured worst: 1.2e-7 (full run).
pub(crate) const SD_THRESHOLD: f64 = 1e-5;
/// Production measures distances between points centred on their bounding box, the witness
/// between the raw points: each coordinate then differs by a rounding of at most ε·|x| ≈ 6e-16
/// (|x| < 3 in the sweep), about 1e-13 of the smallest spacing (0.005); the sums, square roots
/// and the median's interpolation add a few ε. Anything above 1e-12 relative is a fault.
pub(crate) const SPACING_THRESHOLD: f64 = 1e-12;
/// Default base seed; every case derives its own seed from it and prints it when it is worst.
const DEFAULT_SEED: u64 = 0x4d4c_5321;

/// Options of `cargo xtask validate`.
#[derive(Clone, Debug, clap::Args)]
pub(crate) struct Options {
    /// A small run for CI (under 30 s).
    #[arg(long)]
    pub quick: bool,
    /// Base seed; every case derives its own from it (decimal or 0x hexadecimal).
    #[arg(long, default_value_t = DEFAULT_SEED, value_parser = crate::parse_u64)]
    pub seed: u64,
    /// Evaluations of the differential sweep (default: the run's own count).
    #[arg(long)]
    pub evals: Option<usize>,
    /// The differential sweep only: no analytic shapes, no robustness sweep.
    #[arg(long)]
    pub differential_only: bool,
    /// Run only the case with this seed (as printed in the report).
    #[arg(long, value_parser = crate::parse_u64)]
    pub replay: Option<u64>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            quick: false,
            seed: DEFAULT_SEED,
            evals: None,
            differential_only: false,
            replay: None,
        }
    }
}

/// The rows of the report: one per quantity compared with its witness.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Q {
    N,
    J,
    D2N,
    G,
    GradG,
    H,
    Gauss,
    Mean,
    K1,
    K2,
    Directions,
    Eq5,
    Status,
    LineFirst,
    LineSecond,
    Stationarity,
    Shrinkage,
    NormalDirection,
    NormalVariation,
    NormalStatus,
    ExpWeight,
    ExpAny,
    AdaptiveChoice,
    AdaptiveK,
    AdaptiveNoise,
    AdaptiveScatter,
    JetK1,
    JetK2,
    JetError,
    JetChoice,
    StreamBitwise,
    SpacingH,
    Defaults,
    OrientOutward,
    OrientSheet,
    PairAgreement,
    PerQuery,
    E2eH,
    E2eOrientation,
    E2eJet,
    E2ePaper,
    E2eAdaptive,
    E2eTiled,
    E2eStatus,
}

/// A row: its name, the threshold above which the run fails, the production entry point and
/// the witness.
struct Row {
    name: &'static str,
    threshold: f64,
    entry: &'static str,
}

/// The streams the CLI runs; their results are bitwise one unchunked call's (stream row).
const CURV: &str = "`curvature_stream`, `projection_stream` / `mls_ad::witness`";
const ROWS: [Row; 44] = [
    row("n", THRESHOLD, CURV),
    row("J", THRESHOLD, CURV),
    row("∂²n", THRESHOLD, CURV),
    row("g", THRESHOLD, CURV),
    row("∇g", THRESHOLD, CURV),
    row("H", THRESHOLD, CURV),
    row("gauss", THRESHOLD, CURV),
    row("mean", THRESHOLD, CURV),
    row("k1", THRESHOLD, CURV),
    row("k2", THRESHOLD, CURV),
    row("directions", THRESHOLD, CURV),
    row("Eq.5 = Eq.7", THRESHOLD, CURV),
    row(
        "status (skip agreed by the witness)",
        0.0,
        "`curvature_stream`, `projection_stream` / `mls_ad::classify`",
    ),
    row(
        "projection e′",
        THRESHOLD,
        "`projection::line_derivatives` / `mls_ad::line_witness`",
    ),
    row(
        "projection e″",
        THRESHOLD,
        "`projection::line_derivatives` / `mls_ad::line_witness`",
    ),
    row(
        "projected point stationary",
        THRESHOLD,
        "`project_points` / `mls_ad::stationarity`",
    ),
    row(
        "shrinkage correction",
        THRESHOLD,
        "`correct_shrinkage` / δ = (k1 + k2)h²/4, k/(1 + kδ)",
    ),
    row(
        "estimated normal",
        THRESHOLD,
        "`estimate_normals` / `mls_ad::normal_witness`",
    ),
    row(
        "estimated normal's variation",
        THRESHOLD,
        "`estimate_normals` / `mls_ad::normal_witness`",
    ),
    row(
        "normal estimation status",
        0.0,
        "`estimate_normals` / `mls_ad::normal_witness`",
    ),
    row(
        "exp_weight (ulps)",
        1.0,
        "`kernels::exp_weight` / `f64::exp`",
    ),
    row("exp_any (ulps)", 1.0, "`kernels::exp_any` / `f64::exp`"),
    row(
        "adaptive scale and extrapolation choice",
        0.0,
        "`AdaptiveSurface::curvature_stream` / `mls_ad::adaptive_witness`",
    ),
    row(
        "adaptive k1, k2, mean, gauss",
        THRESHOLD,
        "`AdaptiveSurface::curvature_stream` / `mls_ad::adaptive_witness`",
    ),
    row(
        "adaptive noise σ (as σ²·dof / Σwr²)",
        THRESHOLD,
        "`AdaptiveSurface::curvature_stream` / `mls_ad::adaptive_witness`",
    ),
    row(
        "adaptive predicted scatter",
        THRESHOLD,
        "`AdaptiveSurface::curvature_stream` / `mls_ad::adaptive_witness`",
    ),
    row("jet k1", THRESHOLD, "`jet_stream` / `mls_ad::jet_witness`"),
    row("jet k2", THRESHOLD, "`jet_stream` / `mls_ad::jet_witness`"),
    row(
        "jet predicted error",
        SD_THRESHOLD,
        "`jet_stream` / `mls_ad::jet_witness`",
    ),
    row(
        "jet support and degree",
        0.0,
        "`jet_stream` / `mls_ad::jet_witness`",
    ),
    row(
        "streamed = unchunked (bitwise)",
        0.0,
        "`curvature_stream`, `projection_stream`, `jet_stream`, the adaptive `curvature_stream` in chunks of 1, 7, all queries or the default / `curvature_at_points`, `project_points`, `jet_at_points`, `adaptive_curvature`",
    ),
    row(
        "suggested h",
        SPACING_THRESHOLD,
        "`spacing_statistics`, `suggest_h` / `mls_ad::spacing_witness`",
    ),
    row(
        "documented defaults",
        0.0,
        "`JetConfig::default()`, `NormalsConfig::default()`, `MlsConfig::new`, `AdaptiveConfig::new`, the jet's and normals' constants / `mls_ad::documented` (README.md, docs/)",
    ),
    row(
        "oriented normals outward (sphere, ellipsoid, torus, box; share facing in)",
        0.0,
        "`mls_pipeline::pipeline::normals` (estimated, default orientation) / n·∇f > 0, f the shape's implicit function (the box: its face's normal, 3 spacings from the edges)",
    ),
    row(
        "oriented normals up or towards the viewpoint (height fields; share facing away)",
        0.0,
        "`mls_pipeline::pipeline::normals` (default: up for a sheet seen from above; `--orient viewpoint`) / the height field's upper side",
    ),
    row(
        "neighbour pairs that agree, as the summary prints it",
        0.0,
        "`mls_pipeline::pipeline::normals`'s summary / `mls_ad::pair_agreement` (16 nearest by brute force, the 60° and 15° rules)",
    ),
    row(
        "n, g, k1, k2 at queries spread wider than the support (per query)",
        THRESHOLD,
        "`Evaluator::curvature_at` (support from `samples_within`) / `mls_ad::witness`, `mls_ad::classify`",
    ),
    row(
        "end to end: h",
        SPACING_THRESHOLD,
        "`mlscurv curvature`'s library entry (`pipeline::build_surface`, in memory) / `mls_ad::spacing_witness` with the documented rule (`mls_ad::documented`)",
    ),
    row(
        "end to end: orientation (share facing the wrong way; 1 where the pairs agree below 99 % or not as printed)",
        0.0,
        "`mlscurv curvature`'s normals (`pipeline::normals`, `--normals auto`, default `--orient`) / the shape's outside or up, `mls_ad::pair_agreement`",
    ),
    row(
        "end to end: jet k1, k2 (and the foot with --at projected)",
        THRESHOLD,
        "`mlscurv curvature` `--method jet` (default), `--at input`, `projected` / `mls_ad::jet_candidates` on the witnesses' h and normals, file normals as slopes, estimated ones as frame",
    ),
    row(
        "end to end: paper n, k1, k2 (and stationary with --at projected)",
        THRESHOLD,
        "`mlscurv curvature --method paper`, `--at input`, `projected` / `mls_ad::classify`, `witness_curvature`, `stationarity` on the witnesses' h and normals",
    ),
    row(
        "end to end: adaptive h, k1, k2",
        THRESHOLD,
        "`mlscurv curvature --method paper --adaptive` / `mls_ad::adaptive_witness` from the witness's h",
    ),
    row(
        "end to end: tiled k1, k2, n (1 for a single tile or h beyond 5 % of the rule's)",
        THRESHOLD,
        "`mls_pipeline::tiled::curvature` (`--memory 66MiB` on a LAS file) / `mls_ad::jet_candidates`, `mls_ad::classify`",
    ),
    row(
        "end to end: status (1 where the witness's differs)",
        0.0,
        "`mlscurv curvature`, every run above / the witnesses' verdicts",
    ),
];

const fn row(name: &'static str, threshold: f64, entry: &'static str) -> Row {
    Row {
        name,
        threshold,
        entry,
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Worst {
    value: f64,
    seed: u64,
    evals: usize,
}

/// The jet results of one choice: how many, and their worst differences from the witness (as
/// in the jet rows).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct JetChoices {
    count: usize,
    k: f64,
    error: f64,
}

#[derive(Clone, Debug)]
pub(crate) struct Tally {
    worst: [Worst; ROWS.len()],
    pub evals: usize,
    /// Evaluations skipped with a status the witness agrees with.
    pub skipped: usize,
    /// Evaluations per production entry point and execution variant.
    pub entries: BTreeMap<String, usize>,
    /// The jet's choices (degree, and support of a degree-2 candidate) per kind of cloud and
    /// normal data.
    pub jet_choices: BTreeMap<(&'static str, String), JetChoices>,
}

// By hand: arrays implement `Default` only up to 32 elements.
impl Default for Tally {
    fn default() -> Self {
        Self {
            worst: [Worst::default(); ROWS.len()],
            evals: 0,
            skipped: 0,
            entries: BTreeMap::new(),
            jet_choices: BTreeMap::new(),
        }
    }
}

impl Tally {
    pub fn record(&mut self, q: Q, value: f64, seed: u64) {
        let w = &mut self.worst[q as usize];
        w.evals += 1;
        // NaN must count as a failure, never be skipped by a comparison.
        if value.is_nan() || value > w.value {
            w.value = if value.is_nan() { f64::INFINITY } else { value };
            w.seed = seed;
        }
    }

    pub fn entry(&mut self, name: String, count: usize) {
        *self.entries.entry(name).or_default() += count;
    }

    /// One jet result of `setting` with the choice `chosen`, and its differences from the
    /// witness (as in the jet rows).
    pub fn jet_choice(&mut self, setting: &'static str, chosen: String, k: f64, error: f64) {
        let c = self.jet_choices.entry((setting, chosen)).or_default();
        c.count += 1;
        c.k = c.k.max(k);
        c.error = c.error.max(error);
    }

    fn merge(mut self, other: Self) -> Self {
        for (a, b) in self.worst.iter_mut().zip(other.worst) {
            a.evals += b.evals;
            if b.value > a.value {
                a.value = b.value;
                a.seed = b.seed;
            }
        }
        self.evals += other.evals;
        self.skipped += other.skipped;
        for (k, v) in other.entries {
            *self.entries.entry(k).or_default() += v;
        }
        for (k, v) in other.jet_choices {
            let c = self.jet_choices.entry(k).or_default();
            c.count += v.count;
            c.k = c.k.max(v.k);
            c.error = c.error.max(v.error);
        }
        self
    }
}

pub(crate) fn run(o: &Options) -> Result<()> {
    let start = Instant::now();
    let target = o.evals.unwrap_or(if o.quick { 4_000 } else { 120_000 });
    let mut report = String::from("# Validation report\n\n");
    writeln!(
        report,
        "Generated by `cargo xtask validate{}` (base seed {:#x}).\n",
        if o.quick { " --quick" } else { "" },
        o.seed
    )?;

    let mut tally = match o.replay {
        Some(seed) => one_case(seed, QUERIES_PER_CASE),
        None => differential(o.seed, target),
    };
    crate::validate_formulas::exp_sweep(&mut tally, if o.quick { 200_000 } else { 2_000_000 });
    crate::validate_formulas::shrinkage_sweep(
        &mut tally,
        o.seed,
        if o.quick { 20_000 } else { 200_000 },
    );
    let (defaults_table, defaults_failed) = crate::validate_defaults::check(&mut tally);
    let orientation_table = if o.replay.is_none() {
        crate::validate_orient::check_orientation(
            &mut tally,
            o.seed,
            if o.quick { 18 } else { 60 },
        )?
    } else {
        String::new()
    };
    let (e2e_table, e2e_failed) = if o.replay.is_none() {
        crate::validate_e2e::check_end_to_end(&mut tally, o.seed, o.quick)?
    } else {
        (String::new(), Vec::new())
    };
    let elapsed = start.elapsed().as_secs_f64();
    writeln!(
        report,
        "## Production entry points against independent witnesses\n\n{} evaluations on {} cores in {elapsed:.1} s; \
         {} skipped with a status the witness also finds (any other skip fails the `status` row). \
         Kernels of this CPU: {}. Replay a case with `cargo xtask validate --replay <seed>`.\n",
        tally.evals,
        rayon::current_num_threads(),
        tally.skipped,
        mls_core::kernels::kernel_isa(),
    )?;
    report.push_str(
        "| quantity | worst relative difference | threshold | seed of worst case | comparisons | production / witness |\n\
         | --- | --- | --- | --- | --- | --- |\n",
    );
    let mut failed = Vec::new();
    let mut unreached = Vec::new();
    for (row, w) in ROWS.iter().zip(&tally.worst) {
        writeln!(
            report,
            "| {} | {:.2e} | {:e} | {:#x} | {} | {} |",
            row.name,
            w.value,
            row.threshold,
            w.seed,
            w.evals,
            row.entry.replace('|', "\\|")
        )?;
        // A row that compared nothing is a silent pass in a sweep; a replayed case need not
        // exercise every row (the adaptive rows run on some cases only).
        if !(w.value <= row.threshold) {
            failed.push(row.name.to_string());
        } else if w.evals == 0 && o.replay.is_none() {
            unreached.push(row.name);
        }
    }
    failed.extend(defaults_failed);
    report.push_str(&defaults_table);
    report.push_str(&orientation_table);
    failed.extend(e2e_failed);
    report.push_str(&e2e_table);
    if !unreached.is_empty() {
        failed.push(format!(
            "rows that compared nothing ({}; too few cases to reach them? --evals sets the sweep's size)",
            unreached.join("; ")
        ));
    }
    if let Some(seed) = o.replay {
        writeln!(
            report,
            "\nReplay of the case {seed:#x}: a row with 0 comparisons is not exercised by this case and is not checked."
        )?;
    }
    report.push_str("\nEvaluations per production entry point and execution path:\n\n| entry point | evaluations |\n| --- | --- |\n");
    for (entry, count) in &tally.entries {
        writeln!(report, "| {entry} | {count} |")?;
    }
    report.push_str(
        "\nThe jet's choices, per kind of cloud and normal data (heights only, degree 2 at a support \
         ρ of 3h to 8.5h is a degree-2 candidate of `JetConfig::quadratic`, or where no scale \
         determines degree 4 the ladder's own lower-degree fit; a stray sample is one moved \
         3–10 spacings along the normal, as a query; outlier (status 8) where both sides flag the \
         query, by kind of query, nothing to compare beyond the status):\n\n\
         | cloud, normal data | chosen | evaluations | worst jet k1, k2 | worst jet predicted error |\n\
         | --- | --- | --- | --- | --- |\n",
    );
    for ((setting, chosen), c) in &tally.jet_choices {
        writeln!(
            report,
            "| {setting} | {chosen} | {} | {:.2e} | {:.2e} |",
            c.count, c.k, c.error
        )?;
    }
    report.push_str(NORMALISATION_NOTE);

    if !o.differential_only {
        let analytic = cases::analytic_checks(o.quick)?;
        report.push_str(&analytic.markdown);
        failed.extend(analytic.failures);
    }
    std::fs::create_dir_all("target/validate")?;
    std::fs::write("target/validate/report.md", &report)?;
    println!("{report}");
    eprintln!(
        "report written to target/validate/report.md ({:.1} s)",
        start.elapsed().as_secs_f64()
    );
    if !failed.is_empty() {
        bail!("validation failed: {}", failed.join(", "));
    }
    if !o.differential_only && o.replay.is_none() {
        crate::robustness::run(&crate::robustness::Options {
            quick: o.quick,
            ..Default::default()
        })?;
    }
    Ok(())
}

const NORMALISATION_NOTE: &str = "
The curvature rows compare the production entry points `MlsSurface::curvature_stream` (the
CLI's stream over `curvature_at_points`, the clustered path; sequential and in rayon pools of
1–3 threads, with the AVX2 and the portable kernels) and `MlsSurface::projection_stream`
(over `project_points`, curvature at the projected point) with
the hyper-dual witness, whose support is a brute-force distance filter over every sample of
the cloud. The status row counts, as 1, every point where the production's status differs from
the witness's own verdict (`mls_ad::classify`: no or too few samples, |Σwv|/Σw < 1e-6,
|∇g| ≤ 1e-12·2Σw), and every projection that failed. The line rows compare e′(t), e″(t) on
random lines with hyper-dual derivatives of the energy, each scaled by the sum of its terms'
magnitudes; the stationarity row is |e′(0)|/(Σ|terms of e″|·h) at each projected point along
the witness's n (stopping rule: steps below 1e-12·h), or 1 where e″(0) < 0 (a maximum). The
shrinkage row scales the difference by max(|k − k_corrected|, 1e-5·max|k|): the correction's
own size, floored where it vanishes so that rounding of k (ε|k|) stays below 1e-10. The
normal rows compare `estimate_normals` (k = 16, h of the case) with a brute-force k-nearest
neighbourhood and a Jacobi eigen-solve: sin(angle)·(λ1 − λ0)/λ2 (the Davis–Kahan bound makes a
normal only as accurate as the eigengap allows) and the variation λ0/Σλ absolutely. The exp
rows are the worst distance in units in the last place over a dense sweep of arguments.

The jet rows compare `MlsSurface::jet_stream` (in chunks, bitwise `jet_at_points`) with `mls_ad::jet_witness` on the same queries
(heights only or with slopes, at random), and on a noisy patch of each case (a sphere, torus or
height field with Gaussian position noise of 1e-4 to 0.3 spacings, 1 % of its samples and 2 near
the centre moved 3–10 spacings along the normal) with heights only, where the degree-2
candidates are sought and mostly chosen, their robust weights drop the stray samples, and a
query beyond the robust cutoff is an outlier (the table of choices above; production's status 8
against the witness's outlier, any disagreement counts as 1 in the support-and-degree row). k1, k2 are scaled by κ = max(|k1|, |k2|, 1/h) and
divided by max(1, 1e3·ε·cond(M)/threshold), the rounding any least-squares route carries on a
fit whose normal matrix has condition number cond(M) (up to about 1e10 is admitted); the
predicted error is scaled by itself, at least 1e3 × its rounding floor 1e-8/ρ, and by the same
rounding factor. Where the two routes' least estimated errors tie within 1e-4, the production's
choice is compared with the witness's fit of that degree and scale; the support-and-degree row counts any
other difference in the chosen scale or degree, or a point only one side could fit, as 1.
The stream row runs the entry points the CLI runs, `curvature_stream` and `projection_stream`,
in chunks of 1, 7, all queries or `DEFAULT_CHUNK` (at random per case; the table below names
the chunk size each evaluation used); their results are what the rows above compare with the
witness, and the row counts, as 1, every case whose chunks do not tile the queries in order or
whose results are not bitwise those of one `curvature_at_points` or `project_points` call with
the same kernels and another thread count. The suggested-h row compares `spacing_statistics`
then `suggest_h` on 150–300 neighbouring points of the patch (2–12 in one case of ten), with a
few exact duplicates, k = 12 or random in 1–24, the factor 2 or random, with
`mls_ad::spacing_witness` (every distance sorted, no k-d tree; the grid calibration counted
shell by shell), relatively; a different k or count of distinct positions counts as 1.

Each difference is made dimensionless by the natural scale of its quantity at that point, taken
from the witness: n absolute; J by max(‖J‖, 1/h); ∂²n by max(Σ‖∂²n_a‖, 1/h²); g by ‖∇g‖·h;
∇g by ‖∇g‖; H by ‖H‖; k1, k2, mean by κ = ‖H‖/‖∇g‖ (the largest curvature the data can
express there) and gauss by κ²; directions by sin(angle)·(k1 − k2)/κ, the perturbation bound
that makes a direction meaningful only as far as the eigengap allows; Eq. 5 against Eq. 7 by
‖∇g‖·h. Norms are Frobenius.

";

/// Runs cases until `target` evaluations, each case seeded from the base seed, on one OS
/// thread per core. Not on rayon's pool: a case runs production entry points inside pools of
/// its own, and a rayon worker that blocks on another pool steals further cases while it
/// waits, nesting them on its stack until it overflows.
fn differential(base_seed: u64, target: usize) -> Tally {
    let cases = target.div_ceil(QUERIES_PER_CASE).max(1);
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut tally = Tally::default();
                    loop {
                        let c = next.fetch_add(1, Ordering::Relaxed);
                        if c >= cases {
                            return tally;
                        }
                        tally =
                            tally.merge(one_case(case_seed(base_seed, c as u64), QUERIES_PER_CASE));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .map(|w| w.join().expect("a validation worker panicked"))
            .fold(Tally::default(), Tally::merge)
    })
}

pub(crate) fn case_seed(base: u64, case: u64) -> u64 {
    // SplitMix64 step: distinct, well-mixed seeds per case.
    let mut z = base.wrapping_add(case.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
