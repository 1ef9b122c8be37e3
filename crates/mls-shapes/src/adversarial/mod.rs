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

mod degenerate;
mod invalid;
mod patch;
mod scale;
mod separation;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::math::{Point, Vector};

use degenerate::{collinear, coplanar, duplicates, single_point, tiny};
use invalid::{bad_normals, non_finite, unoriented};
use scale::{mismatched_scale, similar};
use separation::{isolated, opposite_sheets, thin_plate};

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
mod tests;
