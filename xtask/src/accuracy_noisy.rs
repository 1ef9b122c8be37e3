//! `cargo xtask accuracy-noisy`: the clouds LiDAR, photogrammetry and structured-light users
//! have (noisy positions, no normals, outliers, noise along the line of sight), with the
//! estimators a user would tune against ours (issue 37).

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::Result;
use mls_core::{AdaptiveConfig, AdaptiveSurface, JetConfig, Location, NormalData, Parallelism};
use mls_core::{Point, Vector};
use mls_shapes::{Ellipsoid, Torus};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::accuracy::{
    Cloud, Stats, calibration, default_h, estimated_normals, reference_jets_of_degree, stats,
};

/// A noisy cloud: the scored points' truth at the nearest point of the shape; outliers have
/// NaN truth in `cloud` and their own nearest-point truth here.
pub(crate) struct NoisyCloud {
    pub cloud: Cloud,
    /// The shape's unit normal at each point's nearest point (outliers included).
    pub normal_truth: Vec<Vector>,
    pub outliers: Vec<usize>,
    pub outlier_truth: Vec<[f64; 2]>,
}

/// Mean spacing of `n` points spread evenly over `area`.
fn spacing(area: f64, n: usize) -> f64 {
    (area / n as f64).sqrt()
}

fn torus_truth(torus: &Torus, points: &[Point]) -> Vec<[f64; 2]> {
    points
        .iter()
        .map(|p| {
            let s = torus.closest_point(p);
            [s.k1, s.k2]
        })
        .collect()
}

fn torus_normals(torus: &Torus, points: &[Point]) -> Vec<Vector> {
    points
        .iter()
        .map(|p| torus.closest_point(p).normal)
        .collect()
}

/// The median and 95th percentile of the angle (degrees, sign aside) between `normals` and
/// `truth`, over the points not in `skip`.
fn angle_percentiles(normals: &[Vector], truth: &[Vector], skip: &[usize]) -> (f64, f64) {
    let mut a: Vec<f64> = normals
        .iter()
        .zip(truth)
        .enumerate()
        .filter(|(i, _)| skip.binary_search(i).is_err())
        .filter(|(_, (n, _))| n.iter().all(|c| c.is_finite()))
        .map(|(_, (n, t))| n.dot(t).abs().min(1.0).acos().to_degrees())
        .collect();
    a.sort_unstable_by(f64::total_cmp);
    let at = |q: f64| {
        a.get(((a.len() as f64 - 1.0) * q).round() as usize)
            .copied()
    };
    (at(0.5).unwrap_or(f64::NAN), at(0.95).unwrap_or(f64::NAN))
}

/// The noisy clouds of issue 37, for one seed.
pub(crate) fn noisy_clouds(seed: u64) -> Vec<NoisyCloud> {
    let torus = Torus::new(6.0, 2.0);
    let area = 4.0 * std::f64::consts::PI.powi(2) * 6.0 * 2.0;
    let n = 40_000;
    let s = spacing(area, n);
    let clean = mls_shapes::surface_points(&mls_shapes::random_area_uniform(&torus, n, seed));
    let clean_points: Vec<Point> = clean.iter().map(|p| p.point).collect();
    let mut out = Vec::new();
    let plain = |name: String,
                 points: Vec<Point>,
                 truth: Vec<[f64; 2]>,
                 normals: Vec<Vector>,
                 normal_truth: Vec<Vector>| NoisyCloud {
        cloud: Cloud {
            name,
            points,
            exact_normals: normals,
            truth,
        },
        normal_truth,
        outliers: Vec::new(),
        outlier_truth: Vec::new(),
    };
    let normals: Vec<Vector> = clean.iter().map(|p| p.normal).collect();
    for f in [0.05, 0.2] {
        let points = mls_shapes::add_position_noise(&clean_points, f * s, seed ^ 0x5eed);
        let truth = torus_truth(&torus, &points);
        let normal_truth = torus_normals(&torus, &points);
        out.push(plain(
            format!("torus 6/2, random 40k, noise {f} spacing"),
            points,
            truth,
            normals.clone(),
            normal_truth,
        ));
    }
    // 1 % outliers, each moved 3 to 10 spacings along its normal (either way), on the cloud
    // with noise 0.05 spacing.
    {
        let mut points = mls_shapes::add_position_noise(&clean_points, 0.05 * s, seed ^ 0x5eed);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x71e5);
        let mut outliers = Vec::new();
        for (i, p) in points.iter_mut().enumerate() {
            if rng.random::<f64>() < 0.01 {
                let d = rng.random_range(3.0..10.0) * s;
                let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                *p += normals[i] * (sign * d);
                outliers.push(i);
            }
        }
        let mut truth = torus_truth(&torus, &points);
        let outlier_truth = outliers.iter().map(|&i| truth[i]).collect();
        for &i in &outliers {
            truth[i] = [f64::NAN; 2];
        }
        let normal_truth = torus_normals(&torus, &points);
        out.push(NoisyCloud {
            normal_truth,
            cloud: Cloud {
                name: "torus 6/2, random 40k, noise 0.05 + 1 % outliers".into(),
                points,
                exact_normals: normals.clone(),
                truth,
            },
            outliers,
            outlier_truth,
        });
    }
    // An airborne scanner's view: top-down scan lines over the upper half, noise along the
    // line of sight (z) only.
    {
        let scan = torus.top_down_scan(0.06, 0.25);
        let s = (0.06f64 * 0.25).sqrt();
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x11e5);
        let points: Vec<Point> = scan
            .iter()
            .map(|p| {
                let g: f64 = rng.sample(StandardNormal);
                p.point + Vector::z() * (0.2 * s * g)
            })
            .collect();
        let truth = torus_truth(&torus, &points);
        let normal_truth = torus_normals(&torus, &points);
        out.push(plain(
            "torus 6/2, top-down scanlines, z noise 0.2 spacing".into(),
            points,
            truth,
            scan.iter().map(|p| p.normal).collect(),
            normal_truth,
        ));
    }
    {
        let e = Ellipsoid::new(3.0, 2.0, 1.0);
        let samples = mls_shapes::random_area_uniform(&e, 20_000, seed);
        // The ellipsoid's area (Knud Thomsen's formula, within 1.1 %).
        let p = 1.6075;
        let (a, b, c) = (3.0f64, 2.0f64, 1.0f64);
        let area = 4.0
            * std::f64::consts::PI
            * (((a * b).powf(p) + (a * c).powf(p) + (b * c).powf(p)) / 3.0).powf(1.0 / p);
        let s = spacing(area, samples.len());
        let clean: Vec<Point> = samples.iter().map(|x| x.surface.point).collect();
        let points = mls_shapes::add_position_noise(&clean, 0.1 * s, seed ^ 0xe11);
        let (truth, normal_truth) = points
            .iter()
            .zip(&samples)
            .map(|(p, x)| {
                let f = mls_shapes::closest_point_newton(&e, p, x.uv);
                ([f.surface.k1, f.surface.k2], f.surface.normal)
            })
            .unzip();
        out.push(plain(
            "ellipsoid 3/2/1, random 20k, noise 0.1 spacing".into(),
            points,
            truth,
            samples.iter().map(|x| x.surface.normal).collect(),
            normal_truth,
        ));
    }
    out
}

/// One estimate: `(k1, k2)` and the predicted error where the method gives one.
pub(crate) struct Run {
    pub k: Vec<[f64; 2]>,
    /// The estimator's own unit normals, where it reports them.
    pub normals: Option<Vec<Vector>>,
    pub sd: Option<Vec<[f64; 2]>>,
    pub seconds: f64,
}

/// The jet on estimated normals, as the command runs it.
pub(crate) fn run_jet(
    points: &[Point],
    normals: &[Vector],
    h: f64,
    config: &JetConfig,
) -> Result<Run> {
    run_jet_diag(points, normals, h, config, None)
}

/// [`run_jet`]; with `JET_DIAG` set, also the chosen degrees and supports, the 12 worst
/// points, the make-up of the predicted error by decile (against `truth`) and the unscored
/// points (NaN truth: outliers) that kept a value.
pub(crate) fn run_jet_diag(
    points: &[Point],
    normals: &[Vector],
    h: f64,
    config: &JetConfig,
    truth: Option<&[[f64; 2]]>,
) -> Result<Run> {
    let t = Instant::now();
    let s = mls_core::MlsSurface::new(points, normals, mls_core::MlsConfig::new(h))?;
    let r = s.jet_at_points(points, config, Parallelism::Rayon);
    if std::env::var_os("JET_DIAG").is_some() {
        let mut hist = std::collections::BTreeMap::new();
        for p in r.iter().flatten() {
            *hist
                .entry((p.fit.degree, (p.fit.radius / h * 100.0).round() as i64))
                .or_insert(0usize) += 1;
        }
        eprintln!("chosen (degree, 100 ρ/h): {hist:?}");
        if let Some(truth) = truth {
            let mut rows: Vec<DiagRow> = r
                .iter()
                .zip(truth)
                .filter_map(|(r, t)| {
                    r.as_ref().ok().filter(|_| t[0].is_finite()).map(|p| {
                        (
                            p.sd[0],
                            p.bias[0],
                            (p.curvature.k1 - t[0]).powi(2),
                            p.fit.noise,
                        )
                    })
                })
                .collect();
            rows.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut worst: Vec<(f64, usize)> = r
                .iter()
                .zip(truth)
                .enumerate()
                .filter(|(_, (_, t))| t[0].is_finite())
                .filter_map(|(i, (r, t))| {
                    r.as_ref().ok().map(|p| ((p.curvature.k1 - t[0]).abs(), i))
                })
                .collect();
            worst.sort_by(|a, b| b.0.total_cmp(&a.0));
            for &(e, i) in worst.iter().take(12) {
                let Ok(p) = r[i].as_ref() else { continue };
                eprintln!(
                    "worst: err {e:.3} at {:.2?} truth {:.3?} k {:.3} {:.3} deg {} ρ/h {:.2} n·z {:.2}",
                    points[i].coords.as_slice(),
                    truth[i],
                    p.curvature.k1,
                    p.curvature.k2,
                    p.fit.degree,
                    p.fit.radius / h,
                    normals[i].z
                );
            }
            let n = rows.len();
            for d in 0..10 {
                let part = &rows[d * n / 10..(d + 1) * n / 10];
                let m = |f: &dyn Fn(&DiagRow) -> f64| {
                    part.iter().map(f).sum::<f64>() / part.len() as f64
                };
                eprintln!(
                    "decile {d}: sd {:.2e} bias {:.2e} rms err {:.2e} noise {:.2e}",
                    m(&|r| r.0),
                    m(&|r| r.1),
                    m(&|r| r.2).sqrt(),
                    m(&|r| r.3)
                );
            }
            // The unscored points (outliers) that kept a value, and the fit that gave it.
            for (i, (r, t)) in r.iter().zip(truth).enumerate() {
                if let (Ok(p), false) = (r, t[0].is_finite()) {
                    eprintln!(
                        "unscored {i}: deg {} ρ/h {:.2} a00/h {:.3} noise/h {:.4} k1 {:.3} sd {:.4} n·z {:.2}",
                        p.fit.degree,
                        p.fit.radius / h,
                        p.fit.coefficients[0] / h,
                        p.fit.noise / h,
                        p.curvature.k1,
                        p.sd[0],
                        normals[i].z
                    );
                }
            }
        }
    }
    let nan = [f64::NAN; 2];
    Ok(Run {
        k: r.iter()
            .map(|r| r.map_or(nan, |p| [p.curvature.k1, p.curvature.k2]))
            .collect(),
        sd: Some(
            r.iter()
                .map(|r| r.map_or(nan, |p| p.predicted_error()))
                .collect(),
        ),
        normals: Some(
            r.iter()
                .map(|r| r.map_or(Vector::repeat(f64::NAN), |p| p.curvature.normal))
                .collect(),
        ),
        seconds: t.elapsed().as_secs_f64(),
    })
}

fn run_adaptive(points: &[Point], normals: &[Vector], h: f64) -> Result<Run> {
    let t = Instant::now();
    let s = AdaptiveSurface::new(points, normals, &AdaptiveConfig::new(h))?;
    let r = s.curvature_at_points(points, Location::Input, Parallelism::Rayon);
    let nan = [f64::NAN; 2];
    Ok(Run {
        k: r.iter()
            .map(|r| r.map_or(nan, |p| [p.curvature.k1, p.curvature.k2]))
            .collect(),
        sd: None,
        normals: None,
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// Predicted sd, bias, squared error and noise of one point (diagnostics).
type DiagRow = (f64, f64, f64, f64);

/// A row of the study.
pub(crate) struct Row {
    pub method: String,
    pub stats: Stats,
    pub calibration: Option<(f64, f64)>,
    pub seconds: f64,
}

fn row(method: String, cloud: &Cloud, run: &Run) -> Row {
    let calibration = run.sd.as_ref().map(|sd| {
        calibration(&run.k, &cloud.truth, sd)
            .into_iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(r), b.max(r)))
    });
    Row {
        method,
        stats: stats(cloud, &run.k),
        calibration,
        seconds: run.seconds,
    }
}

/// The peers a user would tune: degree-2 and degree-4 jets on 50, 100 and 200 neighbours
/// (CGAL's method), and the paper's surface with `--adaptive`.
pub(crate) fn peers(cloud: &Cloud, normals: &[Vector], h: f64) -> Result<Vec<Row>> {
    let mut rows = Vec::new();
    for degree in [2, 4] {
        for k in [50, 100, 200] {
            let t = Instant::now();
            let est = reference_jets_of_degree(&cloud.points, normals, k, degree);
            let run = Run {
                k: est,
                sd: None,
                normals: None,
                seconds: t.elapsed().as_secs_f64(),
            };
            rows.push(row(format!("CGAL-style jet d{degree} k{k}"), cloud, &run));
        }
    }
    rows.push(row(
        "paper --adaptive".into(),
        cloud,
        &run_adaptive(&cloud.points, normals, h)?,
    ));
    Ok(rows)
}

/// What the outliers get: the share with a value, and of those the share whose error exceeds
/// 3 predicted errors (a confident wrong value).
fn outlier_report(noisy: &NoisyCloud, run: &Run) -> String {
    if noisy.outliers.is_empty() {
        return String::new();
    }
    let (mut valued, mut confident_wrong) = (0, 0);
    for (&i, t) in noisy.outliers.iter().zip(&noisy.outlier_truth) {
        let k = run.k[i];
        if !k[0].is_finite() {
            continue;
        }
        valued += 1;
        if let Some(sd) = &run.sd
            && (k[0] - t[0]).abs() > 3.0 * sd[i][0]
        {
            confident_wrong += 1;
        }
    }
    format!(
        " | outliers {} valued {} confident-wrong {}",
        noisy.outliers.len(),
        valued,
        confident_wrong
    )
}

/// The prose after the tables.
const CONCLUSIONS: &str = include_str!("accuracy_noisy_conclusions.md");

/// The page's opening: what the rows are.
const INTRO: &str = "# Accuracy on noisy scans without normals\n\n\
Generated by `cargo xtask accuracy-noisy --peers --write` (issue 37), seed 1. Every cloud has \
noisy positions and no normals: normals are estimated and oriented as the command does, and \
the jet uses them for its frame only. Truth at the point of the shape nearest to each noisy \
sample; outliers are not scored (their own line says how many got a value and how many of those \
are wrong by more than 3 predicted errors). nRMS = RMS(k − k_true) / max|k_true|; calibration = \
observed / predicted RMS error of k1 per decile of the prediction (min–max); time on this \
2-core machine (the peers' k-d tree and fits included).\n\n\
Peers, as a user would tune them: **CGAL-style jet dD kK** = unweighted least-squares Monge \
fit of degree D on the K nearest neighbours in the PCA frame (CGAL's `Monge_via_jet_fitting`, \
written independently in the xtask); **paper --adaptive** = the Amenta–Kil surface with the \
scale chosen per point. **jet (default)** = `mlscurv curvature` without flags.\n\n";

/// `cargo xtask accuracy-noisy [CLOUD] [--peers] [--write]`: the noisy rows, our jet against
/// the tuned peers; with `--write` into docs/accuracy-noisy.md.
pub(crate) fn explore(only: Option<&String>, with_peers: bool, write: bool) -> Result<()> {
    let seed = 1;
    let mut md = String::from(INTRO);
    let mut summary = String::from(
        "| cloud | jet k1 nRMS | best peer | its k1 nRMS | jet / best |\n| --- | --- | --- | --- | --- |\n",
    );
    let mut clouds = noisy_clouds(seed);
    {
        let (name, sigma) = ("paper torus, σ = 1e-3", 1e-3);
        let paper = Torus::new(1.0, 0.2);
        let grid = mls_shapes::surface_points(&mls_shapes::grid(&paper, 500, 100));
        let clean: Vec<Point> = grid.iter().map(|p| p.point).collect();
        let points = mls_shapes::add_position_noise(&clean, sigma, seed);
        let truth = torus_truth(&paper, &points);
        let normal_truth = torus_normals(&paper, &points);
        clouds.push(NoisyCloud {
            normal_truth,
            cloud: Cloud {
                name: name.into(),
                points,
                exact_normals: grid.iter().map(|p| p.normal).collect(),
                truth,
            },
            outliers: Vec::new(),
            outlier_truth: Vec::new(),
        });
    }
    for noisy in &clouds {
        let cloud = &noisy.cloud;
        if let Some(o) = only
            && !cloud.name.contains(o.as_str())
        {
            continue;
        }
        let h = default_h(&cloud.points)?;
        let t = Instant::now();
        let normals = estimated_normals(&cloud.points, h)?;
        let normals_s = t.elapsed().as_secs_f64();
        let mut rows = if with_peers {
            peers(cloud, &normals, h)?
        } else {
            Vec::new()
        };
        let default = JetConfig {
            normals: NormalData::Ignore,
            ..JetConfig::default()
        };
        let run = run_jet_diag(&cloud.points, &normals, h, &default, Some(&cloud.truth))?;
        // The normals' error against the shape's, outliers aside: those estimated (the frame
        // and the orientation) and the jet's own (the output's nx, ny, nz).
        let (est_median, est_p95) =
            angle_percentiles(&normals, &noisy.normal_truth, &noisy.outliers);
        let (jet_median, jet_p95) = run.normals.as_ref().map_or((f64::NAN, f64::NAN), |n| {
            angle_percentiles(n, &noisy.normal_truth, &noisy.outliers)
        });
        let angles = format!(
            "normal error (median / 95th percentile, degrees): estimated {est_median:.2} / \
             {est_p95:.2}, the jet's output {jet_median:.2} / {jet_p95:.2}"
        );
        let extra = outlier_report(noisy, &run);
        let mut r = row("jet (default)".into(), cloud, &run);
        r.method += &extra;
        rows.push(r);
        // Studies: JET_CONFIGS="degree:radius:scales:confidence,..." (for exploration).
        if let Ok(list) = std::env::var("JET_CONFIGS") {
            for spec in list.split(',') {
                let f: Vec<f64> = spec
                    .split(':')
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect();
                let config = JetConfig {
                    degree: f[0] as usize,
                    radius: f[1],
                    scales: f[2] as usize,
                    confidence: f[3],
                    ..default
                };
                let run = run_jet(&cloud.points, &normals, h, &config)?;
                let extra = outlier_report(noisy, &run);
                let mut r = row(format!("jet {spec}"), cloud, &run);
                r.method += &extra;
                rows.push(r);
            }
        }
        writeln!(
            md,
            "## {}\n\n{} points, h = {h:.4}, normals estimated in {normals_s:.2} s; {angles}.\n\n\
             | method | k1 nRMS | k2 nRMS | k1 error μ ± σ | failed | calibration | time (s) |\n\
             | --- | --- | --- | --- | --- | --- | --- |",
            cloud.name,
            cloud.points.len()
        )?;
        println!(
            "## {} (h = {h:.4}, normals {normals_s:.2}s; {angles})",
            cloud.name
        );
        for r in &rows {
            let cal = r
                .calibration
                .map_or("—".into(), |(a, b)| format!("{a:.2}–{b:.2}"));
            println!(
                "{:<60} k1 nRMS {:.3e} k2 nRMS {:.3e} | k1 {:+.1e} ± {:.1e} | fail {} | cal {cal} | {:.2}s",
                r.method,
                r.stats.nrms[0],
                r.stats.nrms[1],
                r.stats.mean[0],
                r.stats.sd[0],
                r.stats.failed,
                r.seconds
            );
            writeln!(
                md,
                "| {} | {:.2e} | {:.2e} | {:+.1e} ± {:.1e} | {} | {cal} | {:.2} |",
                r.method,
                r.stats.nrms[0],
                r.stats.nrms[1],
                r.stats.mean[0],
                r.stats.sd[0],
                r.stats.failed,
                r.seconds
            )?;
        }
        md.push('\n');
        let ours = rows.iter().find(|r| r.method.starts_with("jet (default)"));
        let best = rows
            .iter()
            .filter(|r| !r.method.starts_with("jet"))
            .min_by(|a, b| a.stats.nrms[0].total_cmp(&b.stats.nrms[0]));
        if let (Some(o), Some(b)) = (ours, best) {
            writeln!(
                summary,
                "| {} | {:.2e} | {} | {:.2e} | {:.2} |",
                cloud.name,
                o.stats.nrms[0],
                b.method,
                b.stats.nrms[0],
                o.stats.nrms[0] / b.stats.nrms[0]
            )?;
        }
    }
    println!("{summary}");
    if write {
        let page = md.replacen("## ", &format!("## Summary\n\n{summary}\n## "), 1);
        std::fs::write("docs/accuracy-noisy.md", page + CONCLUSIONS)?;
    }
    Ok(())
}
