//! Degenerate geometry: duplicated points, coplanar and collinear clouds, two to five points,
//! one point.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::patch::{random_motion, random_unit, smooth_draft, usual_cutoff, usual_h};
use super::{AdversarialClass, AdversarialCloud, Draft, Expectation, from_draft};
use crate::math::{Point, Vector};

pub(super) fn duplicates(rng: &mut ChaCha8Rng, seed: u64) -> Draft {
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

pub(super) fn coplanar(rng: &mut ChaCha8Rng) -> Draft {
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

pub(super) fn collinear(rng: &mut ChaCha8Rng) -> Draft {
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

pub(super) fn tiny(rng: &mut ChaCha8Rng) -> Draft {
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

pub(super) fn single_point(rng: &mut ChaCha8Rng) -> Draft {
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
