//! The one integration-test binary of mls-shapes (one binary keeps link time down).

mod bspline;
mod closest;
mod curvature;
mod frames;
mod sampling;

use mls_shapes::{SurfacePoint, Vector};

/// Seeds, named so that a failure can be replayed.
pub mod seeds {
    /// Random parameters for the frame and differential checks.
    pub const PARAMS: u64 = 0x5eed_0001;
    /// Random height fields.
    pub const HEIGHT_FIELD: u64 = 0x5eed_0002;
    /// Position noise.
    pub const POSITION_NOISE: u64 = 0x5eed_0003;
    /// Normal perturbation.
    pub const NORMAL_NOISE: u64 = 0x5eed_0004;
}

/// `|a · b|`: 1 when two unit directions agree up to sign.
pub fn alignment(a: &Vector, b: &Vector) -> f64 {
    a.dot(b).abs()
}

/// Checks the frame invariants every [`SurfacePoint`] promises: unit normal and directions,
/// orthogonal and tangent directions, `d1 × d2 = normal`, `k1 >= k2`, all finite.
pub fn assert_frame(s: &SurfacePoint, tol: f64, context: &str) {
    let finite = [s.k1, s.k2].iter().all(|k| k.is_finite())
        && s.point
            .iter()
            .chain(s.normal.iter())
            .chain(s.d1.iter())
            .chain(s.d2.iter())
            .all(|c| c.is_finite());
    assert!(finite, "{context}: non-finite {s:?}");
    assert!(
        (s.normal.norm() - 1.0).abs() < tol,
        "{context}: |n| = {}",
        s.normal.norm()
    );
    assert!(
        (s.d1.norm() - 1.0).abs() < tol,
        "{context}: |d1| = {}",
        s.d1.norm()
    );
    assert!(
        (s.d2.norm() - 1.0).abs() < tol,
        "{context}: |d2| = {}",
        s.d2.norm()
    );
    assert!(
        s.d1.dot(&s.d2).abs() < tol,
        "{context}: d1·d2 = {}",
        s.d1.dot(&s.d2)
    );
    assert!(
        s.d1.dot(&s.normal).abs() < tol,
        "{context}: d1·n = {}",
        s.d1.dot(&s.normal)
    );
    assert!(
        s.d2.dot(&s.normal).abs() < tol,
        "{context}: d2·n = {}",
        s.d2.dot(&s.normal)
    );
    let handed = (s.d1.cross(&s.d2) - s.normal).norm();
    assert!(handed < tol, "{context}: |d1 × d2 − n| = {handed}");
    assert!(s.k1 >= s.k2, "{context}: k1 = {} < k2 = {}", s.k1, s.k2);
}
