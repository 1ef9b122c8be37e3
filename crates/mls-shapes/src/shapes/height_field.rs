//! Random smooth height fields for randomized differential tests.

use std::f64::consts::{PI, TAU};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::math::Scalar;
use crate::parametric::{ParamInterval, ParametricSurface};

/// One Gaussian bump `amplitude · exp(−|p − center|² / (2 width²))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bump {
    /// Centre `(x, y)`.
    pub center: [f64; 2],
    /// Standard deviation of the Gaussian.
    pub width: f64,
    /// Peak height (negative for a dip).
    pub amplitude: f64,
}

/// One plane wave `amplitude · sin(k · p + phase)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wave {
    /// Wave vector `k = (kx, ky)`.
    pub wavevector: [f64; 2],
    /// Phase offset.
    pub phase: f64,
    /// Peak height.
    pub amplitude: f64,
}

/// How [`HeightField::random`] draws its terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightFieldConfig {
    /// Half the side of the square domain `[−half_width, half_width]²`.
    pub half_width: f64,
    /// Number of Gaussian bumps.
    pub bumps: usize,
    /// Number of plane waves.
    pub waves: usize,
    /// Bump heights are drawn from `[−amplitude, amplitude]`, wave heights from half that.
    pub amplitude: f64,
}

impl Default for HeightFieldConfig {
    /// The unit square `[−1, 1]²`, four bumps and two waves of height up to 0.1: curvatures of
    /// order one, so absolute and relative tolerances mean about the same.
    fn default() -> Self {
        Self {
            half_width: 1.0,
            bumps: 4,
            waves: 2,
            amplitude: 0.1,
        }
    }
}

/// A smooth height field `z = f(x, y)`, a sum of Gaussian bumps and plane waves, over
/// `[−half_width, half_width]²`, with the normal on the `+z` side. Its geometry comes from
/// automatic differentiation.
///
/// Parameters: `u = x`, `v = y`, both closed.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightField {
    /// Half the side of the square domain.
    pub half_width: f64,
    /// Gaussian bumps.
    pub bumps: Vec<Bump>,
    /// Plane waves.
    pub waves: Vec<Wave>,
}

impl HeightField {
    /// A random height field, reproducible from `seed`.
    ///
    /// Bump centres are uniform over the domain and widths uniform in
    /// `[0.25, 0.6] · half_width`, so every bump spans several samples of a moderate grid;
    /// wave numbers are uniform in `[0.5, 1.5] · π / half_width` in a uniform direction, so
    /// there are at most a couple of oscillations across the domain.
    #[must_use]
    pub fn random(config: &HeightFieldConfig, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let w = config.half_width;
        let amp = config.amplitude;
        let bumps = (0..config.bumps)
            .map(|_| Bump {
                center: [rng.random_range(-w..w), rng.random_range(-w..w)],
                width: rng.random_range(0.25..0.6) * w,
                amplitude: rng.random_range(-amp..amp),
            })
            .collect();
        let waves = (0..config.waves)
            .map(|_| {
                let k = rng.random_range(0.5..1.5) * PI / w;
                let dir: f64 = rng.random_range(0.0..TAU);
                Wave {
                    wavevector: [k * dir.cos(), k * dir.sin()],
                    phase: rng.random_range(0.0..TAU),
                    amplitude: rng.random_range(-0.5 * amp..0.5 * amp),
                }
            })
            .collect();
        Self {
            half_width: w,
            bumps,
            waves,
        }
    }

    /// The height `f(x, y)`.
    #[must_use]
    pub fn height<D: Scalar>(&self, x: D, y: D) -> D {
        let bumps = self.bumps.iter().map(|b| {
            let (dx, dy) = (x - b.center[0], y - b.center[1]);
            (-(dx * dx + dy * dy) * (0.5 / (b.width * b.width))).exp() * b.amplitude
        });
        let waves = self
            .waves
            .iter()
            .map(|w| (x * w.wavevector[0] + y * w.wavevector[1] + w.phase).sin() * w.amplitude);
        bumps.chain(waves).fold(D::from(0.0), |acc, t| acc + t)
    }
}

impl ParametricSurface for HeightField {
    fn domain(&self) -> [ParamInterval; 2] {
        let w = self.half_width;
        [ParamInterval::closed(-w, w), ParamInterval::closed(-w, w)]
    }

    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        [u, v, self.height(u, v)]
    }
}
