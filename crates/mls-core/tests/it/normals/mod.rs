//! Normal estimation, spacing and orientation against analytic shapes and brute force.

mod degenerate;
mod estimation;
mod forest;
mod graph;
mod orientation;
mod spacing;

use std::f64::consts::{PI, TAU};

use mls_core::normals::{NormalEstimate, NormalsConfig, Orientation};
use mls_core::{Parallelism, Point, PointStatus, Vector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Seed of the random sign flips applied before orientation.
const FLIP_SEED: u64 = 0x5EED_F11B;
/// Seed of the in-plane jitter of the plane samples.
const JITTER_SEED: u64 = 0x5EED_0717;
/// Seed of the random clouds compared with brute force.
const CLOUD_SEED: u64 = 0x5EED_C10D;

const SEQ: Parallelism = Parallelism::Sequential;
const PAR: Parallelism = Parallelism::Rayon;

// ---------------------------------------------------------------------------------------------
// Shapes.

/// `n` points on a sphere by the golden-angle spiral: nearly uniform, area `4πR²/n` each.
fn fibonacci_sphere(n: usize, centre: Point, radius: f64) -> Vec<Point> {
    let golden = PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            centre + Vector::new(r * phi.cos(), r * phi.sin(), z) * radius
        })
        .collect()
}

/// An `nx × ny` square grid of the given pitch in the plane z = 0, centred on the origin.
fn square_grid(nx: usize, ny: usize, pitch: f64) -> Vec<Point> {
    let (cx, cy) = ((nx - 1) as f64 / 2.0, (ny - 1) as f64 / 2.0);
    (0..nx)
        .flat_map(|i| {
            (0..ny).map(move |j| Point::new((i as f64 - cx) * pitch, (j as f64 - cy) * pitch, 0.0))
        })
        .collect()
}

/// A torus about the z axis with tube centre radius `big` and tube radius `small`, sampled on
/// a `nu × nv` parameter grid. Returns the points and their tube centres.
fn torus(nu: usize, nv: usize, big: f64, small: f64) -> (Vec<Point>, Vec<Point>) {
    (0..nu)
        .flat_map(|i| (0..nv).map(move |j| (i, j)))
        .map(|(i, j)| {
            let (u, v) = (TAU * i as f64 / nu as f64, TAU * j as f64 / nv as f64);
            let axis = Vector::new(u.cos(), u.sin(), 0.0);
            let centre = Point::from(axis * big);
            let p = centre + (axis * v.cos() + Vector::z() * v.sin()) * small;
            (p, centre)
        })
        .unzip()
}

/// Angle between two vectors in degrees; atan2 keeps small angles accurate, unlike acos.
fn angle_deg(a: &Vector, b: &Vector) -> f64 {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

/// Angle between the lines spanned by `a` and `b` (sign ignored), in degrees.
fn line_angle_deg(a: &Vector, b: &Vector) -> f64 {
    let d = angle_deg(a, b);
    d.min(180.0 - d)
}

fn unwrap_normals(est: &[Result<NormalEstimate, PointStatus>]) -> Vec<Vector> {
    est.iter()
        .enumerate()
        .map(|(i, e)| match e {
            Ok(e) => e.normal.into_inner(),
            Err(s) => panic!("normal {i} failed: {s}"),
        })
        .collect()
}

/// Flips about half of the normals, chosen by `seed`; returns how many were flipped.
fn flip_randomly(est: &mut [Result<NormalEstimate, PointStatus>], seed: u64) -> usize {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut count = 0;
    for e in est.iter_mut().flatten() {
        if rng.random_bool(0.5) {
            e.normal = -e.normal;
            count += 1;
        }
    }
    count
}

/// Configuration that leaves the signs as estimated.
fn unoriented(k: usize) -> NormalsConfig {
    NormalsConfig {
        k,
        orientation: Orientation::None,
        ..NormalsConfig::default()
    }
}

/// An estimate with the unit normal `v` and a flat neighbourhood (full confidence).
fn flat_estimate(v: Vector) -> Result<NormalEstimate, PointStatus> {
    Ok(NormalEstimate {
        normal: mls_core::UnitNormal::new(v).unwrap(),
        variation: 0.0,
    })
}
