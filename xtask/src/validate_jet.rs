//! The jet rows of `cargo xtask validate`: `MlsSurface::jet_stream` (the CLI's path, in chunks
//! of a random size, bitwise `jet_at_points`) against `mls_ad::jet_witness`, on the case's clean
//! patch (with slopes or heights only) and on a noisy patch of its own with heights only, where
//! the degree-2 candidates (`JetConfig::quadratic`) are sought and most often chosen, and with
//! stray samples (outliers) that their robust fit weighs out or flags (`PointStatus::Outlier`).

use mls_ad::JetRefusal;
use mls_core::{
    JetConfig, JetPoint, MlsConfig, MlsSurface, NormalData, NormalsConfig, Parallelism, Point,
    PointStatus, Sample, Vector, estimate_normals,
};
use mls_shapes::{HeightField, HeightFieldConfig, ParametricSurface, Sphere, Torus, derivatives};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::validate::{Q, SD_THRESHOLD, THRESHOLD, Tally};
use crate::validate_shapes as cases;
use crate::validate_sweep::streamed;

/// Queries of the noisy heights-only cloud of each case.
const NOISY_QUERIES: usize = 12;
/// Stray samples of the noisy cloud: a fraction of all, moved along the normal by 3–10
/// spacings either way, and as many near the centre (each one a query).
const STRAY_FRACTION: f64 = 0.01;
const STRAY_QUERIES: usize = 2;

/// The jet estimator through the whole-cloud entry point against its witness, which filters
/// its support from every sample of the patch by brute force.
pub(crate) fn compare_jets(
    tally: &mut Tally,
    seed: u64,
    patch: &cases::Patch,
    surface: &MlsSurface,
    queries: &[Point],
    rng: &mut ChaCha8Rng,
) {
    let normals = if rng.random_bool(0.5) {
        NormalData::Slopes
    } else {
        NormalData::Ignore
    };
    // Production with the defaults (as the command: `mls_pipeline::evaluate::jet_config`), the
    // witness with the documented values.
    let config = JetConfig {
        normals,
        ..JetConfig::default()
    };
    let documented = mls_ad::documented::jet_config(normals);
    let samples = samples_of(&patch.points, &patch.normals);
    // The CLI's path: the stream in chunks of a random size, then against the witness.
    let results = streamed(
        tally,
        seed,
        rng,
        queries.len(),
        ("jet_stream", "jet_at_points"),
        |par, chunk, sink| surface.jet_stream(queries, &config, par, chunk, sink),
        |par| surface.jet_at_points(queries, &config, par),
    );
    let setting = match config.normals {
        NormalData::Slopes => "clean patch, slopes",
        NormalData::Ignore => "clean patch, heights only",
    };
    let compared = Compared {
        setting,
        config: &documented,
        samples: &samples,
        h: patch.h,
        kinds: Vec::new(),
    };
    compared.record(tally, seed, queries, results);
    compare_noisy_heights(tally, seed, rng);
}

/// The witness's cloud: each point with its unit normal.
fn samples_of(points: &[Point], normals: &[Vector]) -> Vec<Sample> {
    points
        .iter()
        .zip(normals)
        .map(|(p, n)| Sample {
            point: *p,
            normal: n.normalize(),
        })
        .collect()
}

/// Heights only on a noisy cloud, where the degree-2 candidates (`JetConfig::quadratic`) are
/// sought (the ladder's choice is not resolved, `jet::resolved`) and win at most queries: a
/// patch of a sphere (radius 0.3–2), a torus (tube 0.15–0.5) or a random height field (bumps up
/// to 0.1–0.4 high, strong cubic terms: there the ladder wins over the degree-2 candidates at
/// some queries), sampled within 10h of a random interior point (every degree-2 support, up to
/// 8.5h, inside it) at 1.5–3 spacings per h, h 1–8 % of the radius (sphere, tube) or 0.01–0.06
/// (height field); Gaussian position noise of 1e-4 to 0.3 spacings per coordinate
/// (log-uniform: at the low end the ladder's choice is resolved and no degree-2 candidate is
/// sought); the normals (the frame only) exact, tilted by up to 0.1 rad or estimated
/// (`estimate_normals`, sign as it orients them). Stray samples ([`STRAY_FRACTION`] of all, and
/// [`STRAY_QUERIES`] more among those within h of the centre) moved 3–10 spacings along the
/// normal, either way: the degree-2 candidates' robust weights drop them from the other
/// queries' fits, and a query beyond the robust cutoff is an outlier on both sides. Queries
/// near the centre: those stray samples, then samples (their noise off the surface) or surface
/// points, half of those off it by up to h/2.
fn compare_noisy_heights(tally: &mut Tally, seed: u64, rng: &mut ChaCha8Rng) {
    // h as a fraction of the smallest radius of curvature (of the sphere, of the torus's
    // tube), or on the height field (curvatures of order 1, bumps 0.25–0.6 wide) in absolute
    // terms.
    let (setting, (points, normals, h, near, strays)) = match rng.random_range(0..3) {
        0 => {
            let radius = rng.random_range(0.3..2.0);
            let h = rng.random_range(0.01..0.08) * radius;
            let patch = noisy_patch(&Sphere::centered(radius), h, rng);
            ("noisy sphere patch, heights only", patch)
        }
        1 => {
            let minor = rng.random_range(0.15..0.5);
            let h = rng.random_range(0.01..0.08) * minor;
            let patch = noisy_patch(&Torus { major: 1.0, minor }, h, rng);
            ("noisy torus patch, heights only", patch)
        }
        _ => {
            let config = HeightFieldConfig {
                amplitude: rng.random_range(0.1..0.4),
                ..HeightFieldConfig::default()
            };
            let field = HeightField::random(&config, rng.random());
            let h = rng.random_range(0.01..0.06);
            let patch = noisy_patch(&field, h, rng);
            ("noisy height-field patch, heights only", patch)
        }
    };
    let Ok(surface) = MlsSurface::new(&points, &normals, MlsConfig::new(h)) else {
        tally.record(Q::Status, 1.0, seed);
        return;
    };
    let (queries, kinds): (Vec<Point>, Vec<&'static str>) = strays
        .iter()
        .map(|&i| (points[i], "stray sample"))
        .chain((0..NOISY_QUERIES).map(|_| {
            if rng.random_bool(0.5) {
                // A sample near the centre (its own noise off the surface).
                let i = near.0[rng.random_range(0..near.0.len())];
                (points[i], "sample")
            } else {
                let (p, n) = near.1[rng.random_range(0..near.1.len())];
                if rng.random_bool(0.5) {
                    (p, "surface point")
                } else {
                    let off = 0.5 * rng.random_range(-1.0..1.0) * h;
                    (p + n * off, "surface point moved up to h/2 off")
                }
            }
        }))
        .unzip();
    let config = JetConfig {
        normals: NormalData::Ignore,
        ..JetConfig::default()
    };
    let results = streamed(
        tally,
        seed,
        rng,
        queries.len(),
        ("jet_stream", "jet_at_points"),
        |par, chunk, sink| surface.jet_stream(&queries, &config, par, chunk, sink),
        |par| surface.jet_at_points(&queries, &config, par),
    );
    let samples = samples_of(&points, &normals);
    let documented = mls_ad::documented::jet_config(NormalData::Ignore);
    let compared = Compared {
        setting,
        config: &documented,
        samples: &samples,
        h,
        kinds,
    };
    compared.record(tally, seed, &queries, results);
}

/// A noisy cloud of `s` around a random interior point: points, normals, h, near the centre
/// (within h) the indices of the samples and the surface points with their normals, and the
/// indices of the stray samples near the centre (the queries among them).
#[allow(clippy::type_complexity)]
fn noisy_patch<S: ParametricSurface>(
    s: &S,
    h: f64,
    rng: &mut ChaCha8Rng,
) -> (
    Vec<Point>,
    Vec<Vector>,
    f64,
    (Vec<usize>, Vec<(Point, Vector)>),
    Vec<usize>,
) {
    let [du, dv] = s.domain();
    let (u0, v0) = (
        du.lerp(rng.random_range(0.3..0.7)),
        dv.lerp(rng.random_range(0.3..0.7)),
    );
    let at = s.at(u0, v0);
    let centre = at.point;
    let spacing = h / rng.random_range(1.5..3.0);
    let radius = 10.0 * h;
    let d = derivatives(s, u0, v0);
    let (su, sv) = (d.du.norm(), d.dv.norm());
    let (hu, hv) = (1.5 * radius / su, 1.5 * radius / sv);
    let count = ((2.0 * hu * su) * (2.0 * hv * sv) / (spacing * spacing)).ceil() as usize;
    let (mut points, mut exact) = (Vec::new(), Vec::new());
    let mut on_surface = Vec::new();
    for _ in 0..count {
        let sp = s.at(
            du.normalize(u0 + rng.random_range(-hu..hu)),
            dv.normalize(v0 + rng.random_range(-hv..hv)),
        );
        let dist = (sp.point - centre).norm();
        if dist > radius {
            continue;
        }
        if dist < h {
            on_surface.push((sp.point, sp.normal));
        }
        points.push(sp.point);
        exact.push(sp.normal);
    }
    if on_surface.is_empty() {
        on_surface.push((centre, at.normal));
    }
    let mut points = mls_shapes::add_position_noise(
        &points,
        10f64.powf(rng.random_range(-4.0..-0.5)) * spacing,
        rng.random(),
    );
    // Stray samples: a fraction of all, anywhere, and a few within h of the centre (queries).
    let within: Vec<usize> = (0..points.len())
        .filter(|&i| (points[i] - centre).norm() < h)
        .collect();
    let strays: Vec<usize> = within
        .iter()
        .step_by((within.len() / STRAY_QUERIES).max(1))
        .take(STRAY_QUERIES)
        .copied()
        .collect();
    let mut moved = vec![false; points.len()];
    for i in 0..points.len() {
        if strays.contains(&i) || rng.random_bool(STRAY_FRACTION) {
            let side = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            points[i] += exact[i] * (side * rng.random_range(3.0..10.0) * spacing);
            moved[i] = true;
        }
    }
    let normals = match rng.random_range(0..3) {
        0 => exact,
        1 => mls_shapes::perturb_normals(&exact, 0.1, rng.random()),
        _ => {
            let config = NormalsConfig {
                h: Some(h),
                ..NormalsConfig::default()
            };
            match estimate_normals(&points, &config, Parallelism::Sequential) {
                Ok(est) => est
                    .estimates
                    .iter()
                    .zip(&exact)
                    .map(|(e, v)| e.as_ref().map_or(*v, |e| e.normal.into_inner()))
                    .collect(),
                Err(_) => exact,
            }
        }
    };
    let samples: Vec<usize> = within.into_iter().filter(|&i| !moved[i]).collect();
    let samples = if samples.is_empty() { vec![0] } else { samples };
    (points, normals, h, (samples, on_surface), strays)
}

/// What the jet results of one cloud are compared with.
struct Compared<'a> {
    /// The cloud and normal data, for the report's count of chosen degrees.
    setting: &'static str,
    /// The witness's configuration: the documented defaults (`mls_ad::documented`).
    config: &'a JetConfig,
    samples: &'a [Sample],
    h: f64,
    /// What each query is (noisy cloud: a stray sample, a sample, a surface point, or one
    /// moved off the surface), for the report; empty for the clean patch.
    kinds: Vec<&'static str>,
}

impl Compared<'_> {
    /// Each result against the witness at its query.
    fn record(
        &self,
        tally: &mut Tally,
        seed: u64,
        queries: &[Point],
        results: Vec<Result<JetPoint, PointStatus>>,
    ) {
        // Heights only with the degree-2 candidates: a query the anchors share gets their
        // blend, witnessed by `mls_ad::ShareWitness` from the witness's own anchor jets.
        let mut share = (self.config.normals == NormalData::Ignore
            && self.config.quadratic
            && self.config.share)
            .then(|| mls_ad::ShareWitness::new(self.samples, self.h, self.config));
        for (i, (x, r)) in queries.iter().zip(results).enumerate() {
            let kind = self
                .kinds
                .get(i)
                .copied()
                .unwrap_or("sample or surface point");
            match share.as_mut().and_then(|s| s.shared(&x.coords)) {
                Some(w) => {
                    let chosen = format!("degree 2 blended, ρ = {:.1}h", w.radius / self.h);
                    self.compare(tally, seed, r, Ok(w), Some(chosen), kind);
                }
                None => self.record_one(tally, seed, x, r, kind),
            }
        }
    }

    fn record_one(
        &self,
        tally: &mut Tally,
        seed: u64,
        x: &Point,
        r: Result<JetPoint, PointStatus>,
        kind: &'static str,
    ) {
        let candidates = mls_ad::jet_candidates(&x.coords, self.samples, self.h, self.config);
        // The witness's choice; a production choice of another candidate (degree and support)
        // whose estimated error ties the least within 1e-4 (the two routes' error estimates
        // agree to ~1e-5) is a tie broken by rounding, not a wrong formula: compare against
        // that candidate.
        let witness = candidates.as_ref().map_err(|e| *e).and_then(|c| {
            let least = c.iter().map(|(m, _)| *m).fold(f64::INFINITY, f64::min);
            let chosen = c.iter().find(|(m, _)| *m == least).map(|(_, w)| *w);
            match &r {
                Ok(j) => c
                    .iter()
                    .find(|(m, w)| {
                        (w.degree, w.radius) == (j.fit.degree, j.fit.radius)
                            && *m <= least * (1.0 + 1e-4)
                    })
                    .map(|(_, w)| *w)
                    .or(chosen)
                    .ok_or(JetRefusal::NoFit),
                Err(_) => chosen.ok_or(JetRefusal::NoFit),
            }
        });
        // With heights only, whether degree-2 candidates were sought and lost (the witness has
        // some beside the ladder's) or not (the ladder's choice resolved, or no high terms).
        let sought = candidates
            .as_ref()
            .is_ok_and(|c| c.len() > 1 && c.iter().any(|(_, w)| w.degree == 2));
        let stray = kind == "stray sample";
        let query = if stray { ", stray sample" } else { "" };
        let chosen = r.as_ref().ok().map(|j| match (j.fit.degree, sought) {
            (2, _) if self.config.normals == NormalData::Ignore => {
                format!("degree 2, ρ = {:.1}h{query}", j.fit.radius / self.h)
            }
            (d, true) => format!("degree {d}, over degree-2 candidates{query}"),
            (d, false) => format!("degree {d}{query}"),
        });
        self.compare(tally, seed, r, witness, chosen, kind);
    }

    /// One production result against its witness; `chosen` names the choice for the report.
    fn compare(
        &self,
        tally: &mut Tally,
        seed: u64,
        r: Result<JetPoint, PointStatus>,
        witness: Result<mls_ad::JetWitness, JetRefusal>,
        chosen: Option<String>,
        kind: &'static str,
    ) {
        let h = self.h;
        match (r, witness) {
            (Ok(j), Ok(w)) => {
                let kappa = w.k1.abs().max(w.k2.abs()).max(1.0 / h);
                // A least-squares solution carries rounding of about cond(M)·ε whatever the
                // route; differences are measured against that bound where it exceeds the
                // threshold (reported at the threshold's scale).
                let rounding = (1e3 * f64::EPSILON * w.condition / THRESHOLD).max(1.0);
                let k = [(j.curvature.k1 - w.k1), (j.curvature.k2 - w.k2)]
                    .map(|d| d.abs() / kappa / rounding);
                tally.record(Q::JetK1, k[0], seed);
                tally.record(Q::JetK2, k[1], seed);
                let pe = j.predicted_error();
                let we = [w.sd[0].hypot(w.bias[0]), w.sd[1].hypot(w.bias[1])];
                let sd = (pe[0] - we[0]).abs().max((pe[1] - we[1]).abs());
                let sd_scale = (w.sd[0].hypot(w.bias[0]))
                    .max(w.sd[1].hypot(w.bias[1]))
                    // Within 1000× of the rounding floor (1e-8/ρ) a predicted error is made of
                    // residuals at rounding level and carries their rounding.
                    .max(1e3 * mls_core::jet::SD_FLOOR / w.radius);
                let sd_rounding = (1e3 * f64::EPSILON * w.condition / SD_THRESHOLD).max(1.0);
                let error = sd / sd_scale / sd_rounding;
                tally.record(Q::JetError, error, seed);
                if let Some(chosen) = chosen {
                    tally.jet_choice(self.setting, chosen, k[0].max(k[1]), error);
                }
                let same = j.fit.degree == w.degree && j.fit.radius == w.radius;
                tally.record(Q::JetChoice, if same { 0.0 } else { 1.0 }, seed);
                tally.evals += 1;
            }
            // Both find the query an outlier: the same status, compared.
            (Err(PointStatus::Outlier), Err(JetRefusal::Outlier)) => {
                tally.jet_choice(
                    self.setting,
                    format!("outlier (status 8), {kind}"),
                    0.0,
                    0.0,
                );
                tally.record(Q::JetChoice, 0.0, seed);
                tally.evals += 1;
            }
            // Both find the point degenerate: nothing to compare.
            (Err(s), Err(JetRefusal::NoFit)) if s != PointStatus::Outlier => tally.skipped += 1,
            // One side failed where the other did not: as wrong as a different number.
            _ => tally.record(Q::JetChoice, 1.0, seed),
        }
    }
}
