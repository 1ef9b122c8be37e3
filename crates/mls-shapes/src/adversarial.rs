//! Adversarial point clouds: the degenerate and hostile inputs users feed a curvature tool
//! every day (duplicated scans, flat walls, scan lines, outliers, sheets closer than the
//! kernel, wrongly oriented normals, NaN, georeferenced coordinates), each reproducible from
//! a seed, with what is expected of a robust implementation.
//!
//! [`AdversarialCloud::from_seed`] picks the class from the seed, so a sweep over consecutive
//! seeds covers every class evenly and a failure is replayed from its seed alone.
//!
//! ```
//! use mls_shapes::adversarial::{AdversarialClass, AdversarialCloud, Expectation};
//!
//! let cloud = AdversarialCloud::generate(AdversarialClass::Coplanar, 7);
//! assert_eq!(cloud.points.len(), cloud.normals.len());
//! assert!(matches!(cloud.expectation, Expectation::Flat));
//! // The same seed gives the same cloud.
//! assert_eq!(cloud, AdversarialCloud::generate(AdversarialClass::Coplanar, 7));
//! ```
//!
//! This module knows nothing of the MLS surface: it states expectations in terms of the
//! input (which point is not finite, which probe has no sample within the cutoff, which cloud
//! is a similarity image of which), and the caller checks them against `mls-core`.

use std::f64::consts::{PI, TAU};

use nalgebra::{Rotation3, Unit};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::math::{Point, Vector};
use crate::sampling::{fibonacci_sphere, grid, random};
use crate::shapes::{Cylinder, HeightField, HeightFieldConfig, Torus};
use crate::surface_point::SurfacePoint;

/// The kinds of adversarial cloud.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AdversarialClass {
    /// A smooth patch whose points are repeated exactly: every point the same number of times
    /// (the surface is unchanged, [`Expectation::Matches`]), a random number of times, with
    /// near-duplicates 10⁻⁹ spacings apart, or every point a copy of one.
    Duplicates,
    /// Every point on one plane (random orientation and offset, grid or random sampling) with
    /// the plane's normal, consistently signed: curvature 0 ([`Expectation::Flat`]).
    Coplanar,
    /// Points on one line: a normal cannot be estimated anywhere. Given normals are one
    /// constant perpendicular (the surface is then a plane, [`Expectation::Flat`]) or random
    /// perpendiculars.
    Collinear,
    /// A patch plus points farther than twice the cutoff from every other point, and probes
    /// in the empty space between ([`ProbeKind::Alone`], [`ProbeKind::Void`]); or only
    /// scattered points.
    Isolated,
    /// Two parallel sheets, mirror images of each other, closer than 2h, with opposite
    /// normals (facing away or towards each other); probes on the mid-plane, where the
    /// normals cancel exactly ([`ProbeKind::Cancelling`]).
    OppositeSheets,
    /// A closed rectangular plate thinner than h, sampled on all six faces, normals outward.
    ThinPlate,
    /// A smooth patch given normals that are not consistently oriented: random signs, a
    /// random fraction flipped, or random directions.
    UnorientedNormals,
    /// A smooth patch with NaN or infinite coordinates in one to three points: construction
    /// must fail with a typed error naming the first ([`Expectation::NonFinitePoint`]).
    NonFinite,
    /// A smooth patch with a zero, NaN, infinite or subnormal normal: construction must fail
    /// naming it ([`Expectation::BadNormal`]); or with finite normals of huge or tiny length,
    /// which must be accepted.
    BadNormals,
    /// A smooth patch translated by about 10⁶ in every coordinate ([`Expectation::Matches`]).
    Offset,
    /// A smooth patch scaled by 10⁻⁶, h likewise ([`Expectation::Matches`]).
    ScaledDown,
    /// A smooth patch scaled by 10⁶, h likewise ([`Expectation::Matches`]).
    ScaledUp,
    /// A smooth patch with h far from the spacing: 10⁻³ spacings (every sample alone in its
    /// support) or 10³ times the extent (every sample in every support).
    MismatchedScale,
    /// Two to five random points.
    Tiny,
    /// A single point.
    SinglePoint,
    /// No points at all.
    Empty,
}

impl AdversarialClass {
    /// Every class, in a fixed order ([`AdversarialCloud::from_seed`] indexes it by seed).
    pub const ALL: [AdversarialClass; 16] = [
        Self::Duplicates,
        Self::Coplanar,
        Self::Collinear,
        Self::Isolated,
        Self::OppositeSheets,
        Self::ThinPlate,
        Self::UnorientedNormals,
        Self::NonFinite,
        Self::BadNormals,
        Self::Offset,
        Self::ScaledDown,
        Self::ScaledUp,
        Self::MismatchedScale,
        Self::Tiny,
        Self::SinglePoint,
        Self::Empty,
    ];

    /// A short machine-friendly name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Duplicates => "duplicates",
            Self::Coplanar => "coplanar",
            Self::Collinear => "collinear",
            Self::Isolated => "isolated",
            Self::OppositeSheets => "opposite_sheets",
            Self::ThinPlate => "thin_plate",
            Self::UnorientedNormals => "unoriented_normals",
            Self::NonFinite => "non_finite",
            Self::BadNormals => "bad_normals",
            Self::Offset => "offset_1e6",
            Self::ScaledDown => "scaled_1e-6",
            Self::ScaledUp => "scaled_1e6",
            Self::MismatchedScale => "mismatched_h",
            Self::Tiny => "tiny",
            Self::SinglePoint => "single_point",
            Self::Empty => "empty",
        }
    }
}

impl std::fmt::Display for AdversarialClass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What a robust implementation must do with a cloud, beyond never panicking and never
/// returning a NaN or infinity without a failure status (which holds for every cloud).
#[derive(Clone, Debug, PartialEq)]
pub enum Expectation {
    /// Nothing beyond the universal properties.
    Robust,
    /// The points are coplanar and the normals are the plane's, consistently signed: the MLS
    /// surface is that plane, so every curvature that is computed is zero up to rounding.
    Flat,
    /// `points[index]` is the first point with a NaN or infinite coordinate: building a
    /// surface or estimating normals must fail with a typed error naming it.
    NonFinitePoint {
        /// Index of the first non-finite point.
        index: usize,
    },
    /// `normals[index]` is the first normal that is zero, NaN, infinite or too short to
    /// normalise: building a surface must fail with a typed error naming it.
    BadNormal {
        /// Index of the first bad normal.
        index: usize,
    },
    /// The cloud defines the same MLS surface as `base` mapped by `x ↦ scale·x + offset` (and
    /// its `h` is `scale` times the base's): curvature at the image `scale·q + offset` of a
    /// point `q` of the base is the base's divided by `scale`, and the normal is the same.
    Matches {
        /// The cloud it is an image of.
        base: Box<AdversarialCloud>,
        /// The similarity factor `s`.
        scale: f64,
        /// The translation `t`.
        offset: Vector,
    },
}

/// What is known about the surface near a probe point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ProbeKind {
    /// No sample lies within twice the cutoff radius of the probe.
    Void,
    /// The probe is a sample with no other sample within twice the cutoff radius.
    Alone,
    /// The probe lies on the mirror plane of two sheets with opposite normals, within the
    /// support of both: the weighted normals cancel exactly (up to rounding).
    Cancelling,
}

/// A query point with what is known about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// Where to evaluate.
    pub point: Point,
    /// What is known there.
    pub kind: ProbeKind,
}

/// One adversarial cloud with the parameters to build its surface and what to expect.
#[derive(Clone, Debug, PartialEq)]
pub struct AdversarialCloud {
    /// The class.
    pub class: AdversarialClass,
    /// The seed it was generated from.
    pub seed: u64,
    /// A few words on the variant within the class, for reports.
    pub variant: &'static str,
    /// The points (possibly non-finite, duplicated, empty).
    pub points: Vec<Point>,
    /// One normal per point, as a caller would pass it (possibly unnormalised, zero,
    /// non-finite, or inconsistently oriented).
    pub normals: Vec<Vector>,
    /// The Gaussian scale to build the surface with (finite and positive).
    pub h: f64,
    /// The kernel cutoff factor (support radius `cutoff · h`), or `None` for the untruncated
    /// kernel. Always finite and at least 2 where probes of kind [`ProbeKind::Void`] or
    /// [`ProbeKind::Alone`] are given.
    pub cutoff: Option<f64>,
    /// Extra query points beyond the cloud's own points.
    pub probes: Vec<Probe>,
    /// What to expect.
    pub expectation: Expectation,
}

impl AdversarialCloud {
    /// The cloud of seed `seed`: its class is `AdversarialClass::ALL[seed % 16]`.
    #[must_use]
    pub fn from_seed(seed: u64) -> Self {
        let classes = AdversarialClass::ALL;
        let class = classes[(seed % classes.len() as u64) as usize];
        Self::generate(class, seed)
    }

    /// A cloud of the given class, reproducible from `seed` (ChaCha8).
    #[must_use]
    pub fn generate(class: AdversarialClass, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xad7e_5a41_c10d_0000);
        let mut cloud = match class {
            AdversarialClass::Duplicates => duplicates(&mut rng, seed),
            AdversarialClass::Coplanar => coplanar(&mut rng),
            AdversarialClass::Collinear => collinear(&mut rng),
            AdversarialClass::Isolated => isolated(&mut rng),
            AdversarialClass::OppositeSheets => opposite_sheets(&mut rng),
            AdversarialClass::ThinPlate => thin_plate(&mut rng),
            AdversarialClass::UnorientedNormals => unoriented(&mut rng),
            AdversarialClass::NonFinite => non_finite(&mut rng),
            AdversarialClass::BadNormals => bad_normals(&mut rng),
            AdversarialClass::Offset
            | AdversarialClass::ScaledDown
            | AdversarialClass::ScaledUp => similar(&mut rng, seed, class),
            AdversarialClass::MismatchedScale => mismatched_scale(&mut rng),
            AdversarialClass::Tiny => tiny(&mut rng),
            AdversarialClass::SinglePoint => single_point(&mut rng),
            AdversarialClass::Empty => Draft::new("no points", Vec::new(), 1.0),
        };
        // Untruncated kernels are exact but cost O(n) per query; keep them to small clouds and
        // to clouds whose probes do not rely on a finite support.
        if cloud.cutoff_free && cloud.points.len() <= 600 && rng.random_bool(0.1) {
            cloud.cutoff = None;
        }
        Self {
            class,
            seed,
            variant: cloud.variant,
            points: cloud.points.iter().map(|s| s.0).collect(),
            normals: cloud.points.iter().map(|s| s.1).collect(),
            h: cloud.h,
            cutoff: cloud.cutoff,
            probes: cloud.probes,
            expectation: cloud.expectation,
        }
    }

    /// The support radius `cutoff · h`, if the kernel is truncated.
    #[must_use]
    pub fn support_radius(&self) -> Option<f64> {
        self.cutoff.map(|c| c * self.h)
    }
}

/// A cloud under construction: points with normals, and the rest of [`AdversarialCloud`].
#[derive(Debug)]
struct Draft {
    variant: &'static str,
    points: Vec<(Point, Vector)>,
    h: f64,
    cutoff: Option<f64>,
    /// Whether the untruncated kernel may be chosen instead of `cutoff`.
    cutoff_free: bool,
    probes: Vec<Probe>,
    expectation: Expectation,
}

impl Draft {
    fn new(variant: &'static str, points: Vec<(Point, Vector)>, h: f64) -> Self {
        Self {
            variant,
            points,
            h,
            cutoff: Some(5.0),
            cutoff_free: true,
            probes: Vec::new(),
            expectation: Expectation::Robust,
        }
    }
}

/// A smooth oriented patch: samples with exact normals and their typical spacing.
#[derive(Debug)]
struct Patch {
    points: Vec<(Point, Vector)>,
    spacing: f64,
}

/// A random rotation (uniform axis, uniform angle) and a translation of at most `shift`.
fn random_motion(rng: &mut ChaCha8Rng, shift: f64) -> (Rotation3<f64>, Vector) {
    let axis = Unit::new_normalize(random_unit(rng));
    let rotation = Rotation3::from_axis_angle(&axis, rng.random_range(0.0..TAU));
    let t = Vector::new(
        rng.random_range(-shift..=shift),
        rng.random_range(-shift..=shift),
        rng.random_range(-shift..=shift),
    );
    (rotation, t)
}

/// A unit vector uniform on the sphere.
fn random_unit(rng: &mut ChaCha8Rng) -> Vector {
    let z: f64 = rng.random_range(-1.0..=1.0);
    let phi: f64 = rng.random_range(0.0..TAU);
    let r = ((1.0 - z) * (1.0 + z)).sqrt();
    Vector::new(r * phi.cos(), r * phi.sin(), z)
}

fn from_samples(samples: &[SurfacePoint]) -> Vec<(Point, Vector)> {
    samples.iter().map(|s| (s.point, s.normal)).collect()
}

/// One of four smooth shapes, sampled with 60 to 400 points and moved rigidly.
fn smooth_patch(rng: &mut ChaCha8Rng) -> Patch {
    let (points, spacing) = match rng.random_range(0..4) {
        0 => {
            let n = rng.random_range(60..=400);
            let r = rng.random_range(0.3..3.0);
            let spacing = r * (4.0 * PI / n as f64).sqrt();
            (from_samples(&fibonacci_sphere(n, r)), spacing)
        }
        1 => {
            let m = rng.random_range(8..=20);
            let field = HeightField::random(&HeightFieldConfig::default(), rng.random());
            let samples: Vec<SurfacePoint> = grid(&field, m, m).iter().map(|s| s.surface).collect();
            (from_samples(&samples), 2.0 / (m - 1) as f64)
        }
        2 => {
            let torus = Torus::new(1.0, rng.random_range(0.25..0.5));
            let (nu, nv) = (rng.random_range(20..=40), rng.random_range(8..=14));
            let samples: Vec<SurfacePoint> =
                grid(&torus, nu, nv).iter().map(|s| s.surface).collect();
            let area = 4.0 * PI * PI * torus.major * torus.minor;
            (from_samples(&samples), (area / (nu * nv) as f64).sqrt())
        }
        _ => {
            // Random parameters are not uniform in area: clumps and holes, like a real scan.
            let n = rng.random_range(100..=400);
            let cylinder = Cylinder::new(rng.random_range(0.3..1.0), 2.0);
            let samples: Vec<SurfacePoint> = random(&cylinder, n, rng.random())
                .iter()
                .map(|s| s.surface)
                .collect();
            let area = TAU * cylinder.radius * cylinder.height;
            (from_samples(&samples), (area / n as f64).sqrt())
        }
    };
    let (rotation, t) = random_motion(rng, 2.0);
    Patch {
        points: points
            .into_iter()
            .map(|(p, n)| (rotation * p + t, rotation * n))
            .collect(),
        spacing,
    }
}

/// A Gaussian scale between 1.2 and 3 spacings, where the MLS surface is well defined.
fn usual_h(rng: &mut ChaCha8Rng, spacing: f64) -> f64 {
    rng.random_range(1.2..3.0) * spacing
}

/// A kernel cutoff factor: mostly the default 5, sometimes the minimum 2 or 3.
fn usual_cutoff(rng: &mut ChaCha8Rng) -> f64 {
    match rng.random_range(0..10) {
        0 => 2.0,
        1 | 2 => 3.0,
        _ => 5.0,
    }
}

fn smooth_draft(rng: &mut ChaCha8Rng, variant: &'static str) -> Draft {
    let patch = smooth_patch(rng);
    let h = usual_h(rng, patch.spacing);
    let mut draft = Draft::new(variant, patch.points, h);
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}

fn duplicates(rng: &mut ChaCha8Rng, seed: u64) -> Draft {
    match rng.random_range(0..4) {
        0 => {
            // Each point k times: Σ w v and Σ w both scale by k, so the surface is unchanged.
            let base = AdversarialCloud {
                class: AdversarialClass::Duplicates,
                seed,
                variant: "the patch the duplicates repeat",
                ..from_draft(smooth_draft(rng, ""))
            };
            let k = rng.random_range(2..=4);
            let points = base
                .points
                .iter()
                .zip(&base.normals)
                .flat_map(|(p, n)| std::iter::repeat_n((*p, *n), k))
                .collect();
            let mut draft = Draft::new("every point repeated 2-4 times", points, base.h);
            draft.cutoff = base.cutoff;
            draft.cutoff_free = false;
            draft.expectation = Expectation::Matches {
                base: Box::new(base),
                scale: 1.0,
                offset: Vector::zeros(),
            };
            draft
        }
        1 => {
            let mut draft = smooth_draft(rng, "random points repeated up to 5 times");
            let mut points = Vec::new();
            for &s in &draft.points {
                let k = if rng.random_bool(0.3) {
                    rng.random_range(2..=5)
                } else {
                    1
                };
                points.extend(std::iter::repeat_n(s, k));
            }
            draft.points = points;
            draft
        }
        2 => {
            let mut draft = smooth_draft(rng, "near-duplicates 1e-9 spacings apart");
            let eps = 1e-9 * draft.h;
            let twins: Vec<(Point, Vector)> = draft
                .points
                .iter()
                .map(|&(p, n)| (p + random_unit(rng) * eps, n))
                .collect();
            draft.points.extend(twins);
            draft
        }
        _ => {
            let p = Point::from(random_unit(rng) * rng.random_range(0.0..10.0));
            let n = random_unit(rng);
            let count = rng.random_range(2..=50);
            Draft::new(
                "every point a copy of one",
                vec![(p, n); count],
                rng.random_range(0.01..1.0),
            )
        }
    }
}

fn coplanar(rng: &mut ChaCha8Rng) -> Draft {
    let spacing = rng.random_range(0.01..0.2);
    let m = rng.random_range(6..=20);
    let mut local: Vec<[f64; 2]> = Vec::new();
    let variant = if rng.random_bool(0.5) {
        for i in 0..m {
            for j in 0..m {
                local.push([i as f64 * spacing, j as f64 * spacing]);
            }
        }
        "square grid"
    } else {
        let side = spacing * m as f64;
        for _ in 0..m * m {
            local.push([rng.random_range(0.0..side), rng.random_range(0.0..side)]);
        }
        "uniform random"
    };
    let (rotation, t) = random_motion(rng, 5.0);
    let normal = rotation * Vector::z();
    let points = local
        .iter()
        .map(|&[x, y]| (rotation * Point::new(x, y, 0.0) + t, normal))
        .collect();
    let mut draft = Draft::new(variant, points, usual_h(rng, spacing));
    draft.cutoff = Some(usual_cutoff(rng));
    draft.expectation = Expectation::Flat;
    draft
}

fn collinear(rng: &mut ChaCha8Rng) -> Draft {
    let spacing = rng.random_range(0.01..0.2);
    let count = rng.random_range(3..=200);
    let dir = random_unit(rng);
    let start = Point::from(random_unit(rng) * rng.random_range(0.0..5.0));
    let perpendicular = dir.cross(&random_unit(rng)).normalize();
    let constant = rng.random_bool(0.5);
    let points = (0..count)
        .map(|i| {
            let p = start + dir * (i as f64 * spacing);
            let n = if constant {
                perpendicular
            } else {
                dir.cross(&random_unit(rng)).normalize()
            };
            (p, n)
        })
        .collect();
    let mut draft = Draft::new(
        if constant {
            "one perpendicular normal"
        } else {
            "random perpendicular normals"
        },
        points,
        usual_h(rng, spacing),
    );
    draft.cutoff = Some(usual_cutoff(rng));
    if constant {
        draft.expectation = Expectation::Flat;
    }
    draft
}

fn isolated(rng: &mut ChaCha8Rng) -> Draft {
    let scattered = rng.random_bool(0.25);
    let mut draft = if scattered {
        Draft::new(
            "only scattered points",
            Vec::new(),
            rng.random_range(0.01..1.0),
        )
    } else {
        smooth_draft(rng, "patch with outliers")
    };
    let cutoff = usual_cutoff(rng);
    draft.cutoff = Some(cutoff);
    draft.cutoff_free = false;
    let radius = cutoff * draft.h;
    // Outliers on a lattice of pitch 3 radii far from the patch: every one is more than
    // twice the support radius from every other point, and so is the centre of every lattice
    // cell (a void probe).
    let far = draft
        .points
        .iter()
        .map(|(p, _)| p.coords.amax())
        .fold(0.0, f64::max)
        + 4.0 * radius;
    let pitch = 3.0 * radius;
    let count = rng.random_range(1..=12);
    let corner = Vector::repeat(far);
    for k in 0..count {
        let cell = Vector::new((k % 3) as f64, ((k / 3) % 2) as f64, (k / 6) as f64);
        let p = Point::from(corner + cell * pitch);
        draft.points.push((p, random_unit(rng)));
        draft.probes.push(Probe {
            point: p,
            kind: ProbeKind::Alone,
        });
        draft.probes.push(Probe {
            point: p + Vector::repeat(0.5 * pitch),
            kind: ProbeKind::Void,
        });
    }
    draft
}

fn opposite_sheets(rng: &mut ChaCha8Rng) -> Draft {
    let spacing = rng.random_range(0.01..0.2);
    let h = usual_h(rng, spacing);
    let gap = rng.random_range(0.05..2.0) * h;
    let m = rng.random_range(8..=20);
    let facing = rng.random_bool(0.5);
    let (rotation, t) = random_motion(rng, 5.0);
    let up = rotation * Vector::z();
    let sign = if facing { -1.0 } else { 1.0 };
    let mut points = Vec::new();
    for i in 0..m {
        for j in 0..m {
            let (x, y) = (i as f64 * spacing, j as f64 * spacing);
            points.push((rotation * Point::new(x, y, 0.5 * gap) + t, up * sign));
            points.push((rotation * Point::new(x, y, -0.5 * gap) + t, -up * sign));
        }
    }
    let mut draft = Draft::new(
        if facing {
            "normals facing each other"
        } else {
            "normals facing away"
        },
        points,
        h,
    );
    draft.cutoff = Some(usual_cutoff(rng));
    // Mid-plane probes away from the rim, where both sheets are within the support.
    let middle = (m - 1) as f64 * spacing * 0.5;
    for _ in 0..8 {
        let (x, y) = (
            middle + rng.random_range(-0.25..0.25) * middle,
            middle + rng.random_range(-0.25..0.25) * middle,
        );
        draft.probes.push(Probe {
            point: rotation * Point::new(x, y, 0.0) + t,
            kind: ProbeKind::Cancelling,
        });
    }
    draft
}

fn thin_plate(rng: &mut ChaCha8Rng) -> Draft {
    let spacing = rng.random_range(0.01..0.2);
    let h = usual_h(rng, spacing);
    let thickness = rng.random_range(0.05..1.0) * h;
    let (nx, ny) = (rng.random_range(6..=16), rng.random_range(6..=16));
    let (lx, ly) = ((nx - 1) as f64 * spacing, (ny - 1) as f64 * spacing);
    let rows = ((thickness / spacing).ceil() as usize).max(1) + 1;
    let mut points = Vec::new();
    // Top and bottom faces.
    for i in 0..nx {
        for j in 0..ny {
            let (x, y) = (i as f64 * spacing, j as f64 * spacing);
            points.push((Point::new(x, y, thickness), Vector::z()));
            points.push((Point::new(x, y, 0.0), -Vector::z()));
        }
    }
    // The four sides, with `rows` rows across the thickness, corners excluded.
    for r in 0..rows {
        let z = thickness * r as f64 / (rows - 1).max(1) as f64;
        for i in 1..nx - 1 {
            let x = i as f64 * spacing;
            points.push((Point::new(x, 0.0, z), -Vector::y()));
            points.push((Point::new(x, ly, z), Vector::y()));
        }
        for j in 1..ny - 1 {
            let y = j as f64 * spacing;
            points.push((Point::new(0.0, y, z), -Vector::x()));
            points.push((Point::new(lx, y, z), Vector::x()));
        }
    }
    let (rotation, t) = random_motion(rng, 5.0);
    let points = points
        .into_iter()
        .map(|(p, n)| (rotation * p + t, rotation * n))
        .collect();
    let mut draft = Draft::new("closed plate thinner than h", points, h);
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}

fn unoriented(rng: &mut ChaCha8Rng) -> Draft {
    let mut draft = smooth_draft(rng, "");
    let mode = rng.random_range(0..3);
    draft.variant = ["random signs", "10% flipped", "random directions"][mode];
    for (_, n) in &mut draft.points {
        *n = match mode {
            0 if rng.random_bool(0.5) => -*n,
            1 if rng.random_bool(0.1) => -*n,
            2 => random_unit(rng),
            _ => *n,
        };
    }
    draft
}

fn non_finite(rng: &mut ChaCha8Rng) -> Draft {
    let mut draft = smooth_draft(rng, "NaN and infinite coordinates");
    let len = draft.points.len();
    let bad = rng.random_range(1..=3);
    let mut first = len;
    for _ in 0..bad {
        let index = rng.random_range(0..len);
        let value = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][rng.random_range(0..3)];
        draft.points[index].0[rng.random_range(0..3)] = value;
        first = first.min(index);
    }
    draft.expectation = Expectation::NonFinitePoint { index: first };
    draft
}

fn bad_normals(rng: &mut ChaCha8Rng) -> Draft {
    let mut draft = smooth_draft(rng, "");
    let len = draft.points.len();
    if rng.random_bool(0.25) {
        // Finite, non-zero normals of any length are valid input: the surface normalises them.
        // 1e±150, not more: normals of length 1e±200 are rejected (their squared length
        // leaves the double range), see docs/robustness.md.
        let exponent: i32 = if rng.random_bool(0.5) { 150 } else { -150 };
        let factor = 10f64.powi(exponent);
        for (_, n) in &mut draft.points {
            *n *= factor;
        }
        draft.variant = if exponent > 0 {
            "normals of length 1e150"
        } else {
            "normals of length 1e-150"
        };
        return draft;
    }
    let bad = rng.random_range(1..=3);
    let mut first = len;
    for _ in 0..bad {
        let index = rng.random_range(0..len);
        let normal = &mut draft.points[index].1;
        match rng.random_range(0..4) {
            0 => *normal = Vector::zeros(),
            1 => normal[rng.random_range(0..3)] = f64::NAN,
            2 => normal[rng.random_range(0..3)] = f64::INFINITY,
            // Subnormal: the length is below the smallest normal double.
            _ => *normal *= 1e-310,
        }
        first = first.min(index);
    }
    draft.variant = "zero, NaN, infinite or subnormal normals";
    draft.expectation = Expectation::BadNormal { index: first };
    draft
}

/// The base patch and its image under the similarity the class names (`Offset`,
/// `ScaledDown` or `ScaledUp`).
fn similar(rng: &mut ChaCha8Rng, seed: u64, class: AdversarialClass) -> Draft {
    let draft = smooth_draft(rng, "the patch before the similarity");
    let base = AdversarialCloud {
        class,
        seed,
        ..from_draft(draft)
    };
    let (scale, offset, variant) = match class {
        AdversarialClass::ScaledDown => (1e-6, Vector::zeros(), "scaled by 1e-6"),
        AdversarialClass::ScaledUp => (1e6, Vector::zeros(), "scaled by 1e6"),
        _ => {
            let mut offset = Vector::zeros();
            for c in offset.iter_mut() {
                let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                *c = sign * rng.random_range(0.5e6..2e6);
            }
            (1.0, offset, "translated by about 1e6")
        }
    };
    let points = base
        .points
        .iter()
        .zip(&base.normals)
        .map(|(p, n)| (Point::from(p.coords * scale + offset), *n))
        .collect();
    let mut draft = Draft::new(variant, points, base.h * scale);
    draft.cutoff = base.cutoff;
    draft.cutoff_free = false;
    draft.expectation = Expectation::Matches {
        base: Box::new(base),
        scale,
        offset,
    };
    draft
}

fn mismatched_scale(rng: &mut ChaCha8Rng) -> Draft {
    let patch = smooth_patch(rng);
    let tiny = rng.random_bool(0.5);
    let extent = patch
        .points
        .iter()
        .map(|(p, _)| p.coords.amax())
        .fold(0.0, f64::max);
    let (h, variant) = if tiny {
        (patch.spacing * 1e-3, "h = 1e-3 spacings")
    } else {
        (extent.max(patch.spacing) * 1e3, "h = 1e3 extents")
    };
    let mut draft = Draft::new(variant, patch.points, h);
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}

fn tiny(rng: &mut ChaCha8Rng) -> Draft {
    let count = rng.random_range(2..=5);
    let points = (0..count)
        .map(|_| {
            (
                Point::from(random_unit(rng) * rng.random_range(0.0..1.0)),
                random_unit(rng),
            )
        })
        .collect();
    let mut draft = Draft::new("2-5 random points", points, rng.random_range(0.05..2.0));
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}

fn single_point(rng: &mut ChaCha8Rng) -> Draft {
    let magnitude = [1.0, 1e6, 1e-6][rng.random_range(0..3)];
    let p = Point::from(random_unit(rng) * magnitude);
    let mut draft = Draft::new(
        "one point",
        vec![(p, random_unit(rng))],
        magnitude * rng.random_range(0.01..1.0),
    );
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}

/// The cloud of a draft, with placeholder class and seed for the caller to set.
fn from_draft(draft: Draft) -> AdversarialCloud {
    AdversarialCloud {
        class: AdversarialClass::Empty,
        seed: 0,
        variant: draft.variant,
        points: draft.points.iter().map(|s| s.0).collect(),
        normals: draft.points.iter().map(|s| s.1).collect(),
        h: draft.h,
        cutoff: draft.cutoff,
        probes: draft.probes,
        expectation: draft.expectation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_class_is_reproducible_and_well_formed() {
        for seed in 0..(4 * AdversarialClass::ALL.len() as u64) {
            let cloud = AdversarialCloud::from_seed(seed);
            // Debug output, not `==`: NaN coordinates are equal to themselves there.
            let again = AdversarialCloud::from_seed(seed);
            assert_eq!(format!("{cloud:?}"), format!("{again:?}"), "seed {seed}");
            assert_eq!(cloud.points.len(), cloud.normals.len(), "seed {seed}");
            assert!(cloud.h.is_finite() && cloud.h > 0.0, "seed {seed}");
            if let Some(c) = cloud.cutoff {
                assert!(c >= 2.0, "seed {seed}");
            }
            let needs_support = cloud
                .probes
                .iter()
                .any(|p| matches!(p.kind, ProbeKind::Void | ProbeKind::Alone));
            assert!(!needs_support || cloud.cutoff.is_some(), "seed {seed}");
        }
    }

    #[test]
    fn probes_are_as_described() {
        for seed in 0..40 {
            let cloud = AdversarialCloud::generate(AdversarialClass::Isolated, seed);
            let radius = cloud.support_radius().unwrap();
            for probe in &cloud.probes {
                let near = cloud
                    .points
                    .iter()
                    .filter(|p| (*p - probe.point).norm() <= 2.0 * radius)
                    .count();
                let expected = match probe.kind {
                    ProbeKind::Void => 0,
                    _ => 1,
                };
                assert_eq!(near, expected, "seed {seed}: {probe:?}");
            }
        }
    }

    #[test]
    fn non_finite_and_bad_normal_indices_are_the_first() {
        for seed in 0..40 {
            let cloud = AdversarialCloud::generate(AdversarialClass::NonFinite, seed);
            let Expectation::NonFinitePoint { index } = cloud.expectation else {
                panic!("seed {seed}: {:?}", cloud.expectation);
            };
            let first = cloud
                .points
                .iter()
                .position(|p| !p.iter().all(|c| c.is_finite()));
            assert_eq!(first, Some(index), "seed {seed}");
            let cloud = AdversarialCloud::generate(AdversarialClass::BadNormals, seed);
            if let Expectation::BadNormal { index } = cloud.expectation {
                let first = cloud.normals.iter().position(|n| {
                    !n.iter().all(|c| c.is_finite()) || n.norm() <= f64::MIN_POSITIVE
                });
                assert_eq!(first, Some(index), "seed {seed}");
            }
        }
    }

    #[test]
    fn matches_are_images_of_their_base() {
        for class in [
            AdversarialClass::Offset,
            AdversarialClass::ScaledDown,
            AdversarialClass::ScaledUp,
        ] {
            for seed in 0..10 {
                let cloud = AdversarialCloud::generate(class, seed);
                let Expectation::Matches {
                    base,
                    scale,
                    offset,
                } = &cloud.expectation
                else {
                    panic!("{class} seed {seed}");
                };
                assert_eq!(cloud.points.len(), base.points.len());
                assert_eq!(cloud.h, base.h * scale);
                for (p, q) in cloud.points.iter().zip(&base.points) {
                    assert_eq!(p.coords, q.coords * *scale + offset);
                }
            }
        }
    }
}
