//! The end-to-end rows of `cargo xtask validate`: `mlscurv curvature` through its library entry
//! (`mls_pipeline::curvature`, the call the binary and the Python package make: the surface,
//! the jet's configuration, the evaluation; the tiled run through
//! `mls_pipeline::tiled::curvature` on a LAS file) on generated clouds and the
//! bundled bunny, for the combinations users reach, against an independent pipeline assembled
//! from the witnesses of mls-ad: its own h (`mls_ad::spacing_witness` with the documented
//! rule), its own normals (the file's as they are; or `mls_ad::normal_witness` oriented by the
//! shape's outside, by `up` on a sheet, or on the bunny as the command's after
//! `mls_ad::pair_agreement` has recounted their consistency), the documented role of file
//! normals (slopes in the jet; estimated ones give the frame only), then the witness's
//! curvature at a sample of the same points.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use mls_ad::documented as doc;
use mls_core::{NormalData, Point, PointStatus, Sample, Vector};
use mls_pipeline::evaluate::CurvatureColumns;
use mls_pipeline::pipeline::{self, Timings};
use mls_pipeline::{At, CurvatureOptions, CurvatureRun, Method, NormalsMode, SurfaceOptions};
use mls_shapes::{Ellipsoid, HeightField, HeightFieldConfig, Sphere, Torus, random_area_uniform};
use nalgebra::Vector3;
use rand::seq::index::sample;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::validate::{Q, SPACING_THRESHOLD, THRESHOLD, Tally};

/// The quantities of the row, each against its witness (the report's rows, in this order).
const QUANTITIES: [(Q, &str, f64); 7] = [
    (Q::E2eH, "h", SPACING_THRESHOLD),
    (Q::E2eOrientation, "orientation", 0.0),
    (
        Q::E2eJet,
        "jet k1, k2 (foot with --at projected)",
        THRESHOLD,
    ),
    (
        Q::E2ePaper,
        "paper n, k1, k2 (projected: stationary)",
        THRESHOLD,
    ),
    (Q::E2eAdaptive, "adaptive h, k1, k2", THRESHOLD),
    (Q::E2eTiled, "tiled k1, k2, n (tiles, h)", THRESHOLD),
    (Q::E2eStatus, "status", 0.0),
];

/// How the witness orients its own normals.
#[derive(Clone, Copy, Debug)]
enum Rule {
    /// The file's normals, as they are.
    File,
    /// Outward: towards the truth direction given per point (a closed shape's `∇f`).
    Outward,
    /// Up (+z): a sheet seen from above (the default rule's choice there, and a tiled run's).
    Up,
    /// The command's own signs, taken once the recount of their neighbour pairs found them
    /// consistent (the bunny: no truth to orient by).
    Command,
}

/// A cloud as the command reads it, with what the witness knows about it.
struct Cloud {
    name: String,
    points: Vec<Point>,
    file_normals: Option<Vec<[f64; 3]>>,
    /// Outward direction per point where the geometry decides it (closed shapes), else empty.
    truth: Vec<Vector>,
    rule: Rule,
}

/// One run of the command and its result.
struct Run {
    h: f64,
    source: String,
    from_file: bool,
    out: CurvatureColumns,
}

/// The command's options with every default but `method`, `at` and `adaptive`.
fn default_options(method: Method, at: At, adaptive: bool) -> Result<CurvatureOptions> {
    Ok(CurvatureOptions {
        surface: SurfaceOptions {
            h: None,
            h_factor: mls_core::normals::DEFAULT_H_FACTOR,
            cutoff: mls_pipeline::parse_cutoff(mls_pipeline::DEFAULT_CUTOFF)
                .map_err(anyhow::Error::msg)?,
            normals: NormalsMode::Auto,
            orient: None,
        },
        method,
        at,
        adaptive,
    })
}

/// `mlscurv curvature` on `points` with the default options but `method`, `at` and
/// `adaptive`: the binary's and the Python package's calls.
fn command(cloud: &Cloud, method: Method, at: At, adaptive: bool) -> Result<Run> {
    let options = default_options(method, at, adaptive)?;
    let run = mls_pipeline::curvature(
        mls_pipeline::Cloud {
            points: &cloud.points,
            normals: cloud.file_normals.clone(),
            viewpoints: None,
            name: &cloud.name,
        },
        &options,
        &mut Timings::default(),
        |_| {},
    )?;
    let CurvatureRun {
        columns: out,
        scale,
        normals_source,
        normals_from_file,
        ..
    } = run;
    Ok(Run {
        h: scale.h,
        source: normals_source,
        from_file: normals_from_file,
        out,
    })
}

/// The witness's side of a cloud: h, the samples with the witness's normals (points without
/// one left out, as the command leaves them out of its surface) and the normals' role.
struct Witness {
    h: f64,
    samples: Vec<Sample>,
    role: NormalData,
}

/// h by the documented rule: `H_FACTOR` × the median local spacing over `SPACING_NEIGHBOURS`.
fn witness_h(points: &[Point]) -> Option<f64> {
    mls_ad::spacing_witness(points, doc::SPACING_NEIGHBOURS, doc::H_FACTOR).map(|w| w.h)
}

/// The witness's unoriented normal at each point marked `needed` (`None` elsewhere and where
/// the neighbourhood is degenerate): `mls_ad::normal_witness` on the 16k nearest points (its
/// neighbourhood and both wider retries lie among them), found by computing every distance.
fn witness_normals(points: &[Point], needed: &[bool], h: f64) -> Vec<Option<Vector>> {
    let k = doc::NORMAL_NEIGHBOURS;
    (0..points.len())
        .into_par_iter()
        .map(|i| {
            if !needed[i] {
                return None;
            }
            let p = points[i];
            let order =
                |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            let mut near: Vec<(f64, usize)> = (0..points.len())
                .filter(|&j| j != i)
                .map(|j| ((points[j] - p).norm_squared(), j))
                .collect();
            let m = 16 * k;
            if m < near.len() {
                near.select_nth_unstable_by(m, order);
                near.truncate(m);
            }
            // In the cloud's order, so that ties fall as they would among all points.
            near.sort_by_key(|n| n.1);
            let local: Vec<Point> = std::iter::once(p)
                .chain(near.iter().map(|&(_, j)| points[j]))
                .collect();
            mls_ad::normal_witness(0, &local, k, h, doc::DEGENERACY_TOLERANCE).map(|w| w.normal)
        })
        .collect()
}

/// The witness's pipeline over `cloud`, for queries at `queries` reaching `reach` (in h) of
/// them; `command_normals` are the command's own oriented normals (estimated clouds), for
/// [`Rule::Command`].
fn witness(
    cloud: &Cloud,
    h: f64,
    queries: &[usize],
    reach: f64,
    command_normals: Option<&[Option<Vector>]>,
) -> Witness {
    let points = &cloud.points;
    if let (Rule::File, Some(file)) = (cloud.rule, &cloud.file_normals) {
        let samples = points
            .iter()
            .zip(file)
            .filter_map(|(p, n)| {
                let n = Vector::from(*n);
                (n.norm() > 0.0).then(|| Sample {
                    point: *p,
                    normal: n.normalize(),
                })
            })
            .collect();
        return Witness {
            h,
            samples,
            role: doc::JET_NORMALS,
        };
    }
    // Normals only where a support can reach (a few thousand points stay whole).
    let r2 = (reach * h).powi(2);
    let needed: Vec<bool> = if points.len() <= 5_000 {
        vec![true; points.len()]
    } else {
        points
            .iter()
            .map(|p| {
                queries
                    .iter()
                    .any(|&q| (points[q] - p).norm_squared() <= r2)
            })
            .collect()
    };
    let normals = witness_normals(points, &needed, h);
    let samples = points
        .iter()
        .enumerate()
        .zip(normals)
        .filter_map(|((i, p), n)| {
            let n = n?;
            let towards = match cloud.rule {
                Rule::Outward => cloud.truth[i],
                Rule::Up => Vector::z(),
                Rule::Command => command_normals.and_then(|c| c[i])?,
                // A cloud written with normals that read back without them: no witness
                // normal, so no sample, and the status row fails.
                Rule::File => return None,
            };
            let n = if n.dot(&towards) < 0.0 { -n } else { n };
            Some(Sample {
                point: *p,
                normal: n,
            })
        })
        .collect();
    Witness {
        h,
        samples,
        role: doc::ESTIMATED_NORMALS,
    }
}

/// One row of the command's output, whichever way it was read.
#[derive(Clone, Copy, Debug)]
struct Output {
    status: i32,
    normal: Vector3<f64>,
    k: [f64; 2],
    /// The point evaluated at (the projection with `--at projected`).
    at: Vector3<f64>,
    /// The adaptive scale chosen.
    h: f64,
}

fn output(out: &CurvatureColumns, points: &[Point], i: usize) -> Output {
    Output {
        status: out.status[i],
        normal: Vector3::from(out.normal[i]),
        k: [out.k1[i], out.k2[i]],
        at: out
            .projected
            .as_ref()
            .map_or(points[i].coords, |p| Vector3::from(p[i])),
        h: out.h.get(i).copied().unwrap_or(f64::NAN),
    }
}

fn code(s: PointStatus) -> i32 {
    i32::from(s.code())
}

/// The paper's curvature at the query (or, `projected`, at the command's projection, which
/// must be stationary): n, k1, k2 against `mls_ad::classify` and `witness_curvature` on the
/// brute-force support of the documented cutoff. `Err` for a status the witness disagrees
/// with.
fn paper(x: &Vector3<f64>, o: &Output, w: &Witness, projected: bool) -> Result<f64, ()> {
    let a = 1.0 / (w.h * w.h);
    let radius = doc::CUTOFF * w.h;
    let verdict = |at: &Vector3<f64>| {
        let support = mls_ad::support(at, &w.samples, Some(radius));
        mls_ad::classify(at, &support, a, doc::MIN_NEIGHBOURS)
    };
    if o.status != 0 {
        // A failed point keeps its input position: the witness's verdict there.
        return match verdict(x) {
            Err(s) if code(s) == o.status => Ok(0.0),
            _ => Err(()),
        };
    }
    let Ok(v) = verdict(&o.at) else {
        return Err(());
    };
    let c = mls_ad::witness_curvature(&v.gradient, &v.hessian);
    let kappa = v.hessian.norm() / v.gradient.norm();
    let mut worst = (o.normal - v.gradient.normalize())
        .norm()
        .max((o.k[0] - c.k1).abs() / kappa)
        .max((o.k[1] - c.k2).abs() / kappa);
    if projected {
        // As the stationarity row: the support of the projection's last line search.
        let support = mls_ad::support(&o.at, &w.samples, Some(radius + 1.5 * w.h));
        let s = mls_ad::stationarity(&o.at, &support, a);
        worst = worst.max(if s.second < -1e-10 * s.second_scale {
            1.0
        } else {
            s.first.abs() / (s.second_scale * w.h)
        });
    }
    Ok(worst)
}

/// The jet at the query: k1, k2 (and, `projected`, the foot the command reports as the
/// point evaluated at) against `mls_ad::jet_candidates` with the documented configuration and
/// the documented role of the normals, scaled as the jet rows scale them. A candidate whose
/// estimated error ties the least within 1e-4 is a choice rounding may make: the tied
/// candidate nearest the command's k1, k2 is compared.
fn jet(x: &Vector3<f64>, o: &Output, w: &Witness, projected: bool) -> Result<f64, ()> {
    let config = doc::jet_config(w.role);
    let measure = |j: &mls_ad::JetWitness| {
        let kappa = j.k1.abs().max(j.k2.abs()).max(1.0 / w.h);
        let rounding = (1e3 * f64::EPSILON * j.condition / THRESHOLD).max(1.0);
        let mut d = (o.k[0] - j.k1).abs().max((o.k[1] - j.k2).abs()) / kappa;
        if projected {
            d = d.max((o.at - j.foot).norm() / w.h);
        }
        d / rounding
    };
    // Heights only: a query the anchors share gets their blend (the witness's samples reach
    // 12 h, the blend's anchors and their supports 11.5 h).
    if let Some(blend) = mls_ad::ShareWitness::new(&w.samples, w.h, &config).shared(x) {
        return if o.status == 0 {
            Ok(measure(&blend))
        } else {
            Err(())
        };
    }
    let candidates = mls_ad::jet_candidates(x, &w.samples, w.h, &config);
    match (o.status, candidates) {
        (0, Ok(c)) => {
            let least = c.iter().map(|(m, _)| *m).fold(f64::INFINITY, f64::min);
            Ok(c.iter()
                .filter(|(m, _)| *m <= least * (1.0 + 1e-4))
                .map(|(_, j)| measure(j))
                .fold(f64::INFINITY, f64::min))
        }
        (s, Err(mls_ad::JetRefusal::Outlier)) if s == code(PointStatus::Outlier) => Ok(0.0),
        (s, Err(mls_ad::JetRefusal::NoFit)) if s != 0 && s != code(PointStatus::Outlier) => Ok(0.0),
        _ => Err(()),
    }
}

/// The adaptive scale at the query: the chosen h exactly, k1 and k2 by the witness's κ,
/// against `mls_ad::adaptive_witness` with the documented ladder from the witness's h.
fn adaptive_scale(x: &Vector3<f64>, o: &Output, w: &Witness) -> Result<Option<f64>, ()> {
    let ladder = mls_ad::Ladder {
        h_min: w.h,
        scales: doc::ADAPTIVE_SCALES,
        confidence: doc::ADAPTIVE_CONFIDENCE,
        min_h_factor: doc::ADAPTIVE_MIN_H_FACTOR,
        cutoff: doc::CUTOFF,
        // The measured noise gain, as the adaptive rows restate it.
        gain: 2.0,
    };
    let Some(a) = mls_ad::adaptive_witness(x, &w.samples, &ladder) else {
        // No comparison where the witness finds some scale degenerate.
        return Ok(None);
    };
    if o.status != 0 {
        return Err(());
    }
    // The same scale of the ladder: its h_min, the command's h and the witness's, differ by
    // the rounding the h row allows.
    if !((o.h - a.h).abs() <= SPACING_THRESHOLD * a.h) {
        return Ok(Some(1.0));
    }
    Ok(Some(
        (o.k[0] - a.k1).abs().max((o.k[1] - a.k2).abs()) / a.kappa,
    ))
}

/// The worst value per quantity of one run, and what it was.
struct Line {
    /// Seconds the run and its comparisons took.
    seconds: f64,
    cloud: String,
    run: String,
    h: (f64, f64),
    source: String,
    compared: usize,
    worst: Vec<(usize, f64)>,
}

impl Line {
    fn new(cloud: &Cloud, run: &str) -> Self {
        Self {
            seconds: 0.0,
            cloud: cloud.name.clone(),
            run: run.to_owned(),
            h: (f64::NAN, f64::NAN),
            source: String::new(),
            compared: 0,
            worst: Vec::new(),
        }
    }

    fn record(&mut self, tally: &mut Tally, q: usize, value: f64, seed: u64) {
        tally.record(QUANTITIES[q].0, value, seed);
        match self.worst.iter_mut().find(|(i, _)| *i == q) {
            Some((_, w)) if value.is_nan() || value > *w => {
                *w = if value.is_nan() { f64::INFINITY } else { value };
            }
            Some(_) => {}
            None => self
                .worst
                .push((q, if value.is_nan() { f64::INFINITY } else { value })),
        }
    }
}

const H: usize = 0;
const ORIENTATION: usize = 1;
const JET: usize = 2;
const PAPER: usize = 3;
const ADAPTIVE: usize = 4;
const TILED: usize = 5;
const STATUS: usize = 6;

/// Queries per run: `--quick` and full.
fn queries_per_run(quick: bool) -> usize {
    if quick { 6 } else { 24 }
}

/// The combinations users reach in memory: the default (jet at the input points), the jet at
/// the projections, the paper's surface at both, and its adaptive scale.
const COMBINATIONS: [(Method, At, bool, &str); 5] = [
    (Method::Jet, At::Input, false, "--method jet (default)"),
    (
        Method::Jet,
        At::Projected,
        false,
        "--method jet --at projected",
    ),
    (Method::Paper, At::Input, false, "--method paper"),
    (
        Method::Paper,
        At::Projected,
        false,
        "--method paper --at projected",
    ),
    (Method::Paper, At::Input, true, "--method paper --adaptive"),
];

/// The reach, in h, of the witness's supports around a query: the jet's largest (8.5 h; 11.5 h
/// with the anchors a heights-only query blends) and a projection's step, or the adaptive
/// ladder's 5 h at 4 h.
fn reach(adaptive: bool) -> f64 {
    if adaptive { 22.0 } else { 12.0 }
}

/// Runs every combination on `cloud` and compares a sample of its points with the witness.
fn check_cloud(
    tally: &mut Tally,
    lines: &mut Vec<Line>,
    cloud: &Cloud,
    combinations: &[(Method, At, bool, &str)],
    seed: u64,
    quick: bool,
) -> Result<()> {
    let start = std::time::Instant::now();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = cloud.points.len();
    let wh = witness_h(&cloud.points).context("no spacing for the witness")?;
    // The command's own oriented normals, as `build_surface` gets them (the same call, the
    // same index and h): for the orientation's checks and the bunny's signs.
    let index = pipeline::index(
        &cloud.points,
        mls_core::Frame::of(&cloud.points),
        &cloud.name,
    )?;
    let scale = pipeline::choose_h_on(
        &index,
        None,
        mls_core::normals::DEFAULT_H_FACTOR,
        mls_core::Parallelism::Rayon,
        &cloud.name,
    )?;
    let command_normals = match cloud.file_normals {
        Some(_) => None,
        None => Some(pipeline::normals(
            None,
            &cloud.points,
            Some(&index),
            NormalsMode::Auto,
            None,
            None,
            scale.h,
            mls_core::Parallelism::Rayon,
            &cloud.name,
        )?),
    };
    drop(index);
    let mut orientation = Line::new(cloud, "normals (`--normals auto`, default `--orient`)");
    orientation.h = (scale.h, wh);
    if let Some(cn) = &command_normals {
        check_orientation(
            tally,
            &mut orientation,
            cloud,
            &cn.normals,
            &cn.source,
            seed,
        );
    }
    orientation.seconds = start.elapsed().as_secs_f64();
    lines.push(orientation);
    for &(method, at, adaptive, label) in combinations {
        let start = std::time::Instant::now();
        let run = command(cloud, method, at, adaptive)?;
        let mut line = Line::new(cloud, label);
        line.h = (run.h, wh);
        line.source = if command_normals.is_some() {
            "estimated, as above".into()
        } else {
            run.source.clone()
        };
        line.record(tally, H, (run.h - wh).abs() / wh, seed);
        // `--normals auto`: the file's normals where it has them (README.md, `--normals`).
        line.record(
            tally,
            STATUS,
            f64::from(run.from_file != cloud.file_normals.is_some()),
            seed,
        );
        let queries = sample(&mut rng, n, queries_per_run(quick).min(n)).into_vec();
        let w = witness(
            cloud,
            wh,
            &queries,
            reach(adaptive),
            command_normals.as_ref().map(|c| c.normals.as_slice()),
        );
        // The role the command chose, against the documented one (file normals as slopes).
        let results: Vec<(usize, Result<Option<f64>, ()>)> = queries
            .par_iter()
            .map(|&i| {
                let x = cloud.points[i].coords;
                let o = output(&run.out, &cloud.points, i);
                let projected = at == At::Projected;
                let r = match (method, adaptive) {
                    (Method::Jet, _) => jet(&x, &o, &w, projected).map(Some),
                    (Method::Paper, false) => paper(&x, &o, &w, projected).map(Some),
                    (Method::Paper, true) => adaptive_scale(&x, &o, &w),
                };
                (i, r)
            })
            .collect();
        let quantity = match (method, adaptive) {
            (Method::Jet, _) => JET,
            (Method::Paper, false) => PAPER,
            (Method::Paper, true) => ADAPTIVE,
        };
        for (_, r) in results {
            match r {
                Ok(Some(v)) => {
                    line.record(tally, quantity, v, seed);
                    line.record(tally, STATUS, 0.0, seed);
                    line.compared += 1;
                    tally.evals += 1;
                }
                Ok(None) => tally.skipped += 1,
                Err(()) => line.record(tally, STATUS, 1.0, seed),
            }
        }
        tally.entry(format!("`mlscurv curvature` {label} (end to end)"), n);
        line.seconds = start.elapsed().as_secs_f64();
        lines.push(line);
    }
    Ok(())
}

/// The command's oriented normals against the witness's own orientation: on closed shapes
/// the share of normals within 60° of the outward direction or its opposite that face in, on
/// sheets the share facing down; everywhere 1 when the recount of agreeing neighbour pairs
/// (`mls_ad::pair_agreement`) is below the documented 99 % or differs from the summary's.
fn check_orientation(
    tally: &mut Tally,
    line: &mut Line,
    cloud: &Cloud,
    normals: &[Option<Vector>],
    source: &str,
    seed: u64,
) {
    let (mut decisive, mut wrong) = (0usize, 0usize);
    for (i, n) in normals.iter().enumerate() {
        let towards = match cloud.rule {
            Rule::Outward => cloud.truth[i],
            Rule::Up => Vector::z(),
            Rule::Command | Rule::File => continue,
        };
        let (Some(n), Some(t)) = (n, towards.try_normalize(0.0)) else {
            continue;
        };
        let cosine = n.normalize().dot(&t);
        if cosine.abs() >= 0.5 {
            decisive += 1;
            wrong += usize::from(cosine < 0.0);
        }
    }
    if decisive > 0 {
        line.record(tally, ORIENTATION, wrong as f64 / decisive as f64, seed);
    }
    let recount = mls_ad::pair_agreement(&cloud.points, normals, doc::NORMAL_NEIGHBOURS);
    let share = recount.share().unwrap_or(0.0);
    let printed = crate::validate_orient::printed_agreement(source);
    let expected = format!("{:.2}", 100.0 * share);
    line.record(
        tally,
        ORIENTATION,
        f64::from(share < doc::MIN_CONSISTENCY || printed != Some(expected.as_str())),
        seed,
    );
    line.source = format!(
        "{source}; recount {expected}% of {} pairs{}",
        recount.compared,
        if decisive > 0 {
            format!(", {wrong} of {decisive} decisive normals facing the wrong way")
        } else {
            String::new()
        }
    );
    line.compared += 1;
}

/// Generated cloud `shape` (0: a sphere with its exact normals as file normals, 1: an
/// ellipsoid, 2: a noisy torus, 3: a noisy height field, the last three without normals):
/// 1,500–2,500 random area-uniform points (twice as many on the torus) with Gaussian position
/// noise in spacings, and the outward direction at each point (the sheet's: up).
fn generated(shape: usize, rng: &mut ChaCha8Rng) -> Cloud {
    let n = rng.random_range(1_500..2_500);
    let seed = rng.random();
    let centre = Vector::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let mut axes = Vector::new(1.0, 1.0, 1.0);
    let (name, samples, area, noise, file, rule) = match shape {
        0 => {
            let r = rng.random_range(0.5..2.0);
            (
                format!("sphere R = {r:.2}, file normals"),
                random_area_uniform(&Sphere::centered(r), n, seed),
                4.0 * std::f64::consts::PI * r * r,
                rng.random_range(0.0..0.1),
                true,
                Rule::File,
            )
        }
        1 => {
            let (a, b, c) = (
                rng.random_range(0.6..1.4),
                rng.random_range(0.6..1.4),
                rng.random_range(0.5..1.0),
            );
            axes = Vector::new(a, b, c);
            let p = 1.6075;
            let area = 4.0
                * std::f64::consts::PI
                * (((a * b).powf(p) + (a * c).powf(p) + (b * c).powf(p)) / 3.0).powf(1.0 / p);
            (
                format!("ellipsoid {a:.2} × {b:.2} × {c:.2}, no normals"),
                random_area_uniform(&Ellipsoid::new(a, b, c), n, seed),
                area,
                rng.random_range(0.0..0.1),
                false,
                Rule::Outward,
            )
        }
        2 => {
            let minor = rng.random_range(0.3..0.5);
            (
                format!("noisy torus R = 1, r = {minor:.2}, no normals"),
                random_area_uniform(&Torus { major: 1.0, minor }, 2 * n, seed),
                4.0 * std::f64::consts::PI.powi(2) * minor,
                0.3,
                false,
                Rule::Outward,
            )
        }
        _ => {
            let config = HeightFieldConfig {
                amplitude: rng.random_range(0.05..0.2),
                ..HeightFieldConfig::default()
            };
            let w = config.half_width;
            (
                "noisy height field, no normals".to_string(),
                random_area_uniform(&HeightField::random(&config, rng.random()), n, seed),
                4.0 * w * w,
                0.3,
                false,
                Rule::Up,
            )
        }
    };
    let spacing = (area / samples.len() as f64).sqrt();
    let exact: Vec<[f64; 3]> = samples
        .iter()
        .map(|s| (s.surface.point + centre).coords.into())
        .collect();
    let noisy = mls_shapes::add_position_noise(&exact, noise * spacing, rng.random());
    let points: Vec<Point> = noisy.iter().map(|p| Point::from(*p)).collect();
    let truth = points
        .iter()
        .map(|x| {
            let d = x.coords - centre;
            match shape {
                0 | 1 => d.component_div(&axes.component_mul(&axes)),
                2 => d - Vector::new(d.x, d.y, 0.0).normalize(),
                _ => Vector::z(),
            }
        })
        .collect();
    let file_normals = file.then(|| samples.iter().map(|s| s.surface.normal.into()).collect());
    Cloud {
        name: format!("{name}, {} points, noise {noise:.2} spacing", points.len()),
        points,
        file_normals,
        truth,
        rule,
    }
}

/// The bundled bunny (`tests/data/bunny-stanford.ply`, 35,947 points, no normals).
fn bunny() -> Result<Cloud> {
    let path = Path::new("tests/data/bunny-stanford.ply");
    let c = mls_io::read_point_cloud(path).with_context(|| path.display().to_string())?;
    Ok(Cloud {
        name: "bunny (tests/data/bunny-stanford.ply), no normals".into(),
        points: c.points.iter().map(|p| Point::from(*p)).collect(),
        file_normals: c.normals,
        truth: Vec::new(),
        rule: Rule::Command,
    })
}

/// A height field of `n` points, written as LAS with the exact normals (`file`) or without,
/// and read back as the command reads it (the coordinates quantised by the LAS scale).
fn sheet_las(n: usize, file: bool, rng_seed: u64, dir: &Path) -> Result<(Cloud, PathBuf)> {
    let mut rng = ChaCha8Rng::seed_from_u64(rng_seed);
    let config = HeightFieldConfig {
        amplitude: rng.random_range(0.05..0.2),
        ..HeightFieldConfig::default()
    };
    let field = HeightField::random(&config, rng.random());
    let samples = random_area_uniform(&field, n, rng.random());
    // Metres, far from the origin as a survey's coordinates are.
    let scale = 100.0;
    let origin = Vector::new(420_000.0, 5_100_000.0, 300.0);
    let points: Vec<[f64; 3]> = samples
        .iter()
        .map(|s| (s.surface.point.coords * scale + origin).into())
        .collect();
    let normals: Vec<[f64; 3]> = samples.iter().map(|s| s.surface.normal.into()).collect();
    let mut columns = vec![
        mls_io::Column::component("x", &points, mls_io::Axis::X),
        mls_io::Column::component("y", &points, mls_io::Axis::Y),
        mls_io::Column::component("z", &points, mls_io::Axis::Z),
    ];
    if file {
        columns.extend([
            mls_io::Column::component("nx", &normals, mls_io::Axis::X),
            mls_io::Column::component("ny", &normals, mls_io::Axis::Y),
            mls_io::Column::component("nz", &normals, mls_io::Axis::Z),
        ]);
    }
    let path = dir.join(if file {
        "sheet-normals.las"
    } else {
        "sheet.las"
    });
    mls_io::write_point_cloud_as(
        &path,
        mls_io::FileFormat::Las,
        &columns,
        mls_io::PlyFormat::Ascii,
    )?;
    let read = mls_io::read_point_cloud(&path)?;
    Ok((
        Cloud {
            name: format!(
                "height field, {n} points, LAS{}",
                if file {
                    ", file normals"
                } else {
                    ", no normals"
                }
            ),
            points: read.points.iter().map(|p| Point::from(*p)).collect(),
            file_normals: read.normals,
            truth: Vec::new(),
            rule: if file { Rule::File } else { Rule::Up },
        },
        path,
    ))
}

/// The tiled run (`mls_pipeline::tiled::curvature`, as `mlscurv curvature --memory 66MiB` on a
/// LAS file too large for that budget) against the witness at a sample of its points.
fn check_tiled(
    tally: &mut Tally,
    lines: &mut Vec<Line>,
    dir: &Path,
    method: Method,
    file: bool,
    seed: u64,
    quick: bool,
) -> Result<()> {
    let start = std::time::Instant::now();
    let (cloud, input) = sheet_las(20_000, file, seed, dir)?;
    let output_path = dir.join(if file {
        "tiled-normals-out.las"
    } else {
        "tiled-out.las"
    });
    let options = default_options(method, At::Input, false)?;
    let run = mls_pipeline::tiled::TiledRun {
        input: &input,
        input_format: mls_io::FileFormat::Las,
        columns: None,
        output: &output_path,
        format: mls_io::FileFormat::Las,
        ascii: false,
        options: &options,
        budget: TILED_BUDGET,
        temp_dir: Some(dir),
        keep_attributes: false,
    };
    let summary = mls_pipeline::tiled::curvature(&run, &mut Timings::default())?;
    let label = format!(
        "tiled, {} tiles within 66 MiB, {}",
        summary.tiles,
        match method {
            Method::Jet => "--method jet (default)",
            Method::Paper => "--method paper",
        }
    );
    let mut line = Line::new(&cloud, &label);
    let wh = witness_h(&cloud.points).context("no spacing for the witness")?;
    line.h = (summary.scale.h, wh);
    line.source = summary.normals_source.clone();
    // A tiled run measures the spacing on a sample of tiles, fewer points than the cloud's
    // under a small budget (README.md, "Larger than memory": h "differs more"), which the
    // witness cannot restate without the tile plan: it takes the run's h, and counts 1 where
    // it lies beyond 5 % of the documented rule's on the whole cloud (a changed factor, not a
    // sample's spread: 0.7 % here). At least two tiles, or the tiled path was not reached.
    let drift = (summary.scale.h - wh).abs() / wh;
    line.record(
        tally,
        TILED,
        f64::from(summary.tiles < 2 || !(drift <= TILED_H_DRIFT)),
        seed,
    );
    let wh = summary.scale.h;
    let result = mls_io::read_point_cloud(&output_path)?;
    let column = |name: &str| -> Result<Vec<f64>> {
        let a = result
            .attributes
            .iter()
            .find(|a| a.name == name)
            .with_context(|| format!("no column {name} in the tiled output"))?;
        Ok((0..a.data.len())
            .map(|i| a.data.f64_at(i).unwrap_or(f64::NAN))
            .collect())
    };
    let (k1, k2, status) = (column("k1")?, column("k2")?, column("status")?);
    let normal = result
        .normals
        .clone()
        .context("no normals in the tiled output")?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = cloud.points.len();
    let queries = sample(&mut rng, n, queries_per_run(quick).min(n)).into_vec();
    let w = witness(&cloud, wh, &queries, reach(false), None);
    let results: Vec<Result<f64, ()>> = queries
        .par_iter()
        .map(|&i| {
            let x = cloud.points[i].coords;
            let o = Output {
                status: status[i] as i32,
                normal: Vector3::from(normal[i]),
                k: [k1[i], k2[i]],
                at: x,
                h: f64::NAN,
            };
            match method {
                Method::Jet => jet(&x, &o, &w, false),
                Method::Paper => paper(&x, &o, &w, false),
            }
        })
        .collect();
    for r in results {
        match r {
            Ok(v) => {
                line.record(tally, TILED, v, seed);
                line.record(tally, STATUS, 0.0, seed);
                line.compared += 1;
                tally.evals += 1;
            }
            Err(()) => line.record(tally, STATUS, 1.0, seed),
        }
    }
    tally.entry(format!("`mlscurv curvature` {label} (end to end)"), n);
    line.seconds = start.elapsed().as_secs_f64();
    lines.push(line);
    Ok(())
}

/// How far a tiled run's h may lie from the documented rule's on the whole cloud.
const TILED_H_DRIFT: f64 = 0.05;

/// The tiled runs' budget: 64 MiB fixed and about 5,200 loaded points per tile
/// (`crates/mls-cli/tests/it/tiled.rs`'s `SMALL_BUDGET`).
const TILED_BUDGET: u64 = 66 << 20;

/// Runs the end-to-end rows and returns the report's table and a failure message per run and
/// quantity above its threshold.
pub(crate) fn check_end_to_end(
    tally: &mut Tally,
    base_seed: u64,
    quick: bool,
) -> Result<(String, Vec<String>)> {
    let mut lines = Vec::new();
    let rounds = if quick { 1 } else { 3 };
    for round in 0..rounds {
        for shape in 0..4 {
            let seed = crate::validate::case_seed(
                base_seed ^ 0x0065_3265_2072_6f77,
                (4 * round + shape) as u64,
            );
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let cloud = generated(shape, &mut rng);
            check_cloud(tally, &mut lines, &cloud, &COMBINATIONS, seed, quick)
                .with_context(|| format!("end to end: {} (seed {seed:#x})", cloud.name))?;
        }
    }
    let bunny = bunny()?;
    let bunny_runs: &[(Method, At, bool, &str)] = if quick {
        &COMBINATIONS[..1]
    } else {
        &COMBINATIONS[..4]
    };
    check_cloud(tally, &mut lines, &bunny, bunny_runs, base_seed, quick)
        .context("end to end: the bunny")?;
    let dir = Path::new("target/validate/e2e");
    std::fs::create_dir_all(dir)?;
    for (method, file) in [(Method::Jet, true), (Method::Paper, false)] {
        check_tiled(tally, &mut lines, dir, method, file, base_seed, quick)
            .with_context(|| format!("end to end: tiled {method:?}"))?;
    }
    let mut table = String::from(
        "\nEnd to end (`mlscurv curvature` through its library entry against the witnesses' \
         pipeline, at a sample of each run's points; the worst value of each quantity):\n\n\
         | cloud | run | h (command / witness) | normals (the summary) | compared | worst | s |\n\
         | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let mut failures = Vec::new();
    for l in &lines {
        let worst: Vec<String> = l
            .worst
            .iter()
            .map(|&(q, v)| format!("{} {v:.2e}", QUANTITIES[q].1))
            .collect();
        writeln!(
            table,
            "| {} | {} | {:.6e} / {:.6e} | {} | {} | {} | {:.1} |",
            l.cloud,
            l.run,
            l.h.0,
            l.h.1,
            l.source.replace('|', "\\|"),
            l.compared,
            worst.join("; "),
            l.seconds
        )?;
        for &(q, v) in &l.worst {
            let (_, name, threshold) = QUANTITIES[q];
            if !(v <= threshold) {
                failures.push(format!(
                    "end to end: {name} broke on {}, {}: {v:.2e} against the witness (threshold {threshold:e})",
                    l.cloud, l.run
                ));
            }
        }
    }
    Ok((table, failures))
}
