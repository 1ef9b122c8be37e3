//! What every class builds on: smooth oriented patches, random motions and directions, and
//! the usual h and cutoff.

use std::f64::consts::{PI, TAU};

use nalgebra::{Rotation3, Unit};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::Draft;
use crate::math::{Point, Vector};
use crate::sampling::{fibonacci_sphere, grid, random};
use crate::shapes::{Cylinder, HeightField, HeightFieldConfig, Torus};
use crate::surface_point::SurfacePoint;

/// A smooth oriented patch: samples with exact normals and their typical spacing.
#[derive(Debug)]
pub(super) struct Patch {
    pub(super) points: Vec<(Point, Vector)>,
    pub(super) spacing: f64,
}

/// A random rotation (uniform axis, uniform angle) and a translation of at most `shift`.
pub(super) fn random_motion(rng: &mut ChaCha8Rng, shift: f64) -> (Rotation3<f64>, Vector) {
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
pub(super) fn random_unit(rng: &mut ChaCha8Rng) -> Vector {
    let z: f64 = rng.random_range(-1.0..=1.0);
    let phi: f64 = rng.random_range(0.0..TAU);
    let r = ((1.0 - z) * (1.0 + z)).sqrt();
    Vector::new(r * phi.cos(), r * phi.sin(), z)
}

fn from_samples(samples: &[SurfacePoint]) -> Vec<(Point, Vector)> {
    samples.iter().map(|s| (s.point, s.normal)).collect()
}

/// One of four smooth shapes, sampled with 60 to 400 points and moved rigidly.
pub(super) fn smooth_patch(rng: &mut ChaCha8Rng) -> Patch {
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
pub(super) fn usual_h(rng: &mut ChaCha8Rng, spacing: f64) -> f64 {
    rng.random_range(1.2..3.0) * spacing
}

/// A kernel cutoff factor: mostly the default 5, sometimes the minimum 2 or 3.
pub(super) fn usual_cutoff(rng: &mut ChaCha8Rng) -> f64 {
    match rng.random_range(0..10) {
        0 => 2.0,
        1 | 2 => 3.0,
        _ => 5.0,
    }
}

pub(super) fn smooth_draft(rng: &mut ChaCha8Rng, variant: &'static str) -> Draft {
    let patch = smooth_patch(rng);
    let h = usual_h(rng, patch.spacing);
    let mut draft = Draft::new(variant, patch.points, h);
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}
