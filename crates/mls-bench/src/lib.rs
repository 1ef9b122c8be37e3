//! Fixtures shared by the criterion benches (`benches/`) and `cargo xtask bench`: generated
//! clouds with exact normals, the scale h that `mlscurv` would choose for them, and the MLS
//! surface built from both. Unpublished.
//!
//! Every benchmark uses the defaults of `mlscurv curvature`: `h = 2 ×` the median local
//! spacing ([`spacing`]), cutoff `5h`.

use mls_core::normals::{DEFAULT_H_FACTOR, DEFAULT_SPACING_NEIGHBOURS, spacing_statistics};
use mls_core::{Cutoff, MlsConfig, MlsSurface, Parallelism, Point, Vector};
use mls_shapes::{Torus, fibonacci_sphere, grid};

/// Major radius of the benchmark torus.
pub const TORUS_MAJOR: f64 = 1.0;
/// Minor (tube) radius of the benchmark torus.
pub const TORUS_MINOR: f64 = 0.3;

/// A generated point cloud with exact unit outward normals.
#[derive(Clone, Debug)]
pub struct Cloud {
    /// A short description, for reports ("sphere", "torus").
    pub name: &'static str,
    /// The points.
    pub points: Vec<Point>,
    /// One exact unit outward normal per point.
    pub normals: Vec<Vector>,
}

impl Cloud {
    /// `n` points on the unit sphere (Fibonacci lattice), in lattice order: by height from
    /// pole to pole, consecutive points a golden angle (137.5°) apart in azimuth, so index
    /// order is only coarsely local (within a band of height).
    pub fn sphere(n: usize) -> Self {
        let samples = fibonacci_sphere(n, 1.0);
        Self {
            name: "sphere",
            points: samples.iter().map(|s| s.point).collect(),
            normals: samples.iter().map(|s| s.normal).collect(),
        }
    }

    /// About `n` points on a parameter grid of the torus `R = 1`, `r = 0.3`, with the grid
    /// sides in the ratio `R : r` so that the spacing is the same in both directions on the
    /// core circle (it varies by ±30 % between the inner and outer equators, as on the
    /// paper's torus). The count is `nu · nv`, within 0.1 % of `n` for large `n`.
    pub fn torus(n: usize) -> Self {
        let torus = Torus::new(TORUS_MAJOR, TORUS_MINOR);
        let nv = ((n as f64 * TORUS_MINOR / TORUS_MAJOR).sqrt().round() as usize).max(3);
        let nu = n.div_ceil(nv).max(3);
        let samples = grid(&torus, nu, nv);
        Self {
            name: "torus",
            points: samples.iter().map(|s| s.surface.point).collect(),
            normals: samples.iter().map(|s| s.surface.normal).collect(),
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the cloud is empty.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The MLS surface of the cloud with its exact normals, at scale `h` and the given cutoff.
    ///
    /// # Panics
    /// If `h` or the cutoff is invalid; benchmarks use checked defaults.
    pub fn surface(&self, h: f64, cutoff: Cutoff) -> MlsSurface {
        let config = MlsConfig {
            cutoff,
            ..MlsConfig::new(h)
        };
        MlsSurface::new(&self.points, &self.normals, config)
            .expect("generated clouds have finite points and unit normals")
    }

    /// Query points off the surface: every `step`-th point moved along its normal by
    /// `offset`, alternately outwards and inwards, for the projection benchmarks.
    pub fn offset_queries(&self, step: usize, offset: f64) -> Vec<Point> {
        self.points
            .iter()
            .zip(&self.normals)
            .step_by(step.max(1))
            .enumerate()
            .map(|(i, (p, n))| {
                let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
                p + n * (sign * offset)
            })
            .collect()
    }
}

/// The median local spacing of `points`, as `mlscurv` measures it (RMS distance to 12
/// neighbours, calibrated to give the pitch of a grid).
///
/// # Panics
/// If the cloud has fewer than two distinct points.
pub fn spacing(points: &[Point]) -> f64 {
    spacing_statistics(points, DEFAULT_SPACING_NEIGHBOURS, Parallelism::Rayon)
        .expect("benchmark clouds have many distinct points")
        .spacing
}

/// The scale `mlscurv` chooses by default: `2 ×` [`spacing`].
pub fn default_h(points: &[Point]) -> f64 {
    DEFAULT_H_FACTOR * spacing(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torus_count_is_close_to_the_request() {
        for n in [1_000, 10_000, 100_000] {
            let len = Cloud::torus(n).len();
            assert!(len.abs_diff(n) * 100 <= n, "{n} -> {len}");
        }
    }

    #[test]
    fn default_h_is_twice_the_grid_pitch_on_a_sphere() {
        // On the Fibonacci sphere the pitch is about √(4π/n).
        let n = 20_000;
        let cloud = Cloud::sphere(n);
        let pitch = (4.0 * std::f64::consts::PI / n as f64).sqrt();
        let ratio = default_h(&cloud.points) / (2.0 * pitch);
        assert!((0.8..1.25).contains(&ratio), "{ratio}");
    }

    #[test]
    fn offset_queries_alternate_sides() {
        let cloud = Cloud::sphere(100);
        let q = cloud.offset_queries(10, 0.01);
        assert_eq!(q.len(), 10);
        assert!((q[0].coords.norm() - 1.01).abs() < 1e-12);
        assert!((q[1].coords.norm() - 0.99).abs() < 1e-12);
    }
}
