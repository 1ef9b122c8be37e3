//! The terrain: a seeded sum of plane waves, and the ray's hit with it.

use std::f64::consts::TAU;

use super::SALT_TERRAIN;
use super::draws::{Draws, hash3};
use crate::math::{Point, Vector};

/// Plane waves of the terrain: amplitude (m) and wavelength (m). The steepest possible slope,
/// `2π Σ A/λ ≈ 0.18`, keeps the ground gentle and every ray's terrain hit unique.
const TERRAIN_WAVES: [(f64, f64); 4] = [(6.0, 900.0), (2.5, 350.0), (1.0, 130.0), (0.3, 45.0)];

/// The ground: $h(x, y) = h_0 + \sum_i A_i \sin(k_i \cdot (x, y) + \varphi_i)$, in local
/// coordinates.
#[derive(Clone, Debug)]
pub(super) struct Terrain {
    level: f64,
    /// Amplitude, wave vector x and y, phase.
    waves: [[f64; 4]; 4],
    amplitude: f64,
}

impl Terrain {
    pub(super) fn new(seed: u64, level: f64) -> Self {
        let mut draws = Draws::new(hash3(seed, SALT_TERRAIN, 0));
        let waves = TERRAIN_WAVES.map(|(a, wavelength)| {
            let angle = TAU * draws.unit();
            let k = TAU / wavelength;
            [a, k * angle.cos(), k * angle.sin(), TAU * draws.unit()]
        });
        Self {
            level,
            waves,
            amplitude: TERRAIN_WAVES.iter().map(|w| w.0).sum(),
        }
    }

    pub(super) fn min(&self) -> f64 {
        self.level - self.amplitude
    }

    pub(super) fn max(&self) -> f64 {
        self.level + self.amplitude
    }

    /// Height and gradient at `(x, y)`.
    pub(super) fn at(&self, x: f64, y: f64) -> (f64, f64, f64) {
        let mut h = self.level;
        let (mut gx, mut gy) = (0.0, 0.0);
        for [a, kx, ky, phase] in self.waves {
            let (s, c) = (kx * x + ky * y + phase).sin_cos();
            h += a * s;
            gx += a * kx * c;
            gy += a * ky * c;
        }
        (h, gx, gy)
    }

    /// The ray parameter of the terrain hit in `[lo, hi]` and the gradient there, by Newton
    /// steps kept inside a bracket (bisection when a step leaves it): `f(t) = z(t) − h(t)`
    /// is strictly decreasing for rays steeper than the steepest slope, so the root is
    /// unique, and the fixed sequence of steps makes the result deterministic.
    pub(super) fn intersect(
        &self,
        origin: &Point,
        d: &Vector,
        lo: f64,
        hi: f64,
    ) -> (f64, f64, f64) {
        let (mut lo, mut hi) = (lo, hi);
        let mut t = 0.5 * (lo + hi);
        for _ in 0..60 {
            let p = origin + d * t;
            let (h, gx, gy) = self.at(p.x, p.y);
            let f = p.z - h;
            if f.abs() < 1e-10 {
                break;
            }
            if f > 0.0 {
                lo = t;
            } else {
                hi = t;
            }
            let slope = d.z - gx * d.x - gy * d.y;
            let step = t - f / slope;
            t = if step > lo && step < hi {
                step
            } else {
                0.5 * (lo + hi)
            };
        }
        // The gradient where the search stopped, which the last step may have moved.
        let p = origin + d * t;
        let (_, gx, gy) = self.at(p.x, p.y);
        (t, gx, gy)
    }
}
