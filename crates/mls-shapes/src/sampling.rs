//! Samplers: parameter grids, seeded random parameters, and the Fibonacci sphere.

use std::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::Open01;

use crate::parametric::ParametricSurface;
use crate::shapes::Sphere;
use crate::surface_point::SurfacePoint;

/// One sample of a parametric surface: where it was taken and what is there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Parameters `(u, v)`.
    pub uv: [f64; 2],
    /// Grid indices `(i, j)` along u and v for [`grid`]; `(k, 0)` for the k-th sample of
    /// [`random`].
    pub ij: [usize; 2],
    /// The sample with its exact geometry.
    pub surface: SurfacePoint,
}

/// `nu × nv` samples on a grid uniform in the parameter domain, in row-major order (sample
/// `(i, j)` at index `i * nv + j`, `i` along u).
///
/// Grid values follow each parameter's [`IntervalKind`](crate::IntervalKind): closed
/// intervals include both ends, periodic ones exclude the end (no duplicated seam), intervals
/// with degenerate ends use cell midpoints (no sample on a pole). Pick interior samples by
/// `ij`, for example `margin <= i && i < nu - margin`.
#[must_use]
pub fn grid<S: ParametricSurface + ?Sized>(surface: &S, nu: usize, nv: usize) -> Vec<Sample> {
    let [du, dv] = surface.domain();
    let mut out = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let u = du.grid_value(i, nu);
        for j in 0..nv {
            let v = dv.grid_value(j, nv);
            out.push(Sample {
                uv: [u, v],
                ij: [i, j],
                surface: surface.at(u, v),
            });
        }
    }
    out
}

/// `n` samples with parameters drawn uniformly from the parameter domain (not uniform in
/// area), reproducible from `seed` (ChaCha8).
///
/// Draws from the open interval so that no sample lands exactly on a singular end (a pole).
#[must_use]
pub fn random<S: ParametricSurface + ?Sized>(surface: &S, n: usize, seed: u64) -> Vec<Sample> {
    let [du, dv] = surface.domain();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|k| {
            let u = du.lerp(rng.sample(Open01));
            let v = dv.lerp(rng.sample(Open01));
            Sample {
                uv: [u, v],
                ij: [k, 0],
                surface: surface.at(u, v),
            }
        })
        .collect()
}

/// `n` samples uniform in area (not in the parameters), reproducible from `seed` (ChaCha8):
/// parameters drawn uniformly, kept with probability `|r_u × r_v| / bound` (rejection), where
/// `bound` is 1.25 × the largest area element on a 128 × 128 parameter grid.
///
/// # Panics
/// If a drawn sample's area element exceeds the bound (a shape whose area element peaks
/// between grid nodes by more than 25 %).
#[must_use]
pub fn random_area_uniform<S: ParametricSurface + ?Sized>(
    surface: &S,
    n: usize,
    seed: u64,
) -> Vec<Sample> {
    let [du, dv] = surface.domain();
    let area = |u: f64, v: f64| crate::parametric::derivatives(surface, u, v).area_element();
    let bound = 1.25
        * (0..128)
            .flat_map(|i| (0..128).map(move |j| (i, j)))
            .map(|(i, j)| area(du.grid_value(i, 128), dv.grid_value(j, 128)))
            .filter(|a| a.is_finite())
            .fold(0.0f64, f64::max);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let u = du.lerp(rng.sample(Open01));
        let v = dv.lerp(rng.sample(Open01));
        let a = area(u, v);
        assert!(
            a <= bound,
            "area element {a} above the rejection bound {bound}"
        );
        if rng.random::<f64>() * bound < a {
            out.push(Sample {
                uv: [u, v],
                ij: [out.len(), 0],
                surface: surface.at(u, v),
            });
        }
    }
    out
}

/// The `nu × nv` grid of [`grid`] with each parameter moved by a uniform random fraction in
/// `[−jitter, jitter]` of its cell, reproducible from `seed` (ChaCha8). Closed intervals keep
/// their samples inside the domain (clamped).
#[must_use]
pub fn jittered_grid<S: ParametricSurface + ?Sized>(
    surface: &S,
    nu: usize,
    nv: usize,
    jitter: f64,
    seed: u64,
) -> Vec<Sample> {
    let [du, dv] = surface.domain();
    let (cu, cv) = (du.len() / nu as f64, dv.len() / nv as f64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut shift = |cell: f64| cell * jitter * (2.0 * rng.random::<f64>() - 1.0);
    let mut out = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let u = du.normalize(du.grid_value(i, nu) + shift(cu));
            let v = dv.normalize(dv.grid_value(j, nv) + shift(cv));
            out.push(Sample {
                uv: [u, v],
                ij: [i, j],
                surface: surface.at(u, v),
            });
        }
    }
    out
}

/// `n` near-uniform points on the sphere of the given radius centred on the origin (the
/// Fibonacci lattice: heights `z_i = 1 − (2i + 1)/n`, azimuths stepping by the golden angle
/// `π (3 − √5)`), with outward normals and `k1 = k2 = 1/radius`.
#[must_use]
pub fn fibonacci_sphere(n: usize, radius: f64) -> Vec<SurfacePoint> {
    let sphere = Sphere::centered(radius);
    let golden_angle = PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            // sqrt((1 − z)(1 + z)) keeps its digits near the poles, unlike sqrt(1 − z²).
            let theta = ((1.0 - z) * (1.0 + z)).sqrt().atan2(z);
            let phi = (i as f64 * golden_angle).rem_euclid(2.0 * PI);
            sphere.at(theta, phi)
        })
        .collect()
}

/// The surface points of `samples`, dropping their parameters.
#[must_use]
pub fn surface_points(samples: &[Sample]) -> Vec<SurfacePoint> {
    samples.iter().map(|s| s.surface).collect()
}

/// Positions as plain arrays, the form a k-d tree takes.
#[must_use]
pub fn points(samples: &[SurfacePoint]) -> Vec<[f64; 3]> {
    samples.iter().map(|s| s.point.into()).collect()
}

/// Normals as plain arrays.
#[must_use]
pub fn normals(samples: &[SurfacePoint]) -> Vec<[f64; 3]> {
    samples.iter().map(|s| s.normal.into()).collect()
}
