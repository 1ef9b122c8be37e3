//! Seeded noise on positions and normals.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

use crate::math::{Vector, tangent_basis};

/// Adds isotropic Gaussian noise of standard deviation `sigma` (per coordinate) to each point,
/// reproducibly from `seed` (ChaCha8). Works for `[f64; 3]`, `Point` and `Vector`.
#[must_use]
pub fn add_position_noise<P>(points: &[P], sigma: f64, seed: u64) -> Vec<P>
where
    P: Copy + Into<[f64; 3]> + From<[f64; 3]>,
{
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    points
        .iter()
        .map(|&p| {
            let mut p: [f64; 3] = p.into();
            for c in &mut p {
                let g: f64 = rng.sample(StandardNormal);
                *c += sigma * g;
            }
            P::from(p)
        })
        .collect()
}

/// Rotates each normal by an angle drawn uniformly from `[0, max_angle]` (radians) about an
/// axis drawn uniformly from the directions perpendicular to it, reproducibly from `seed`
/// (ChaCha8). Lengths are preserved, so unit normals stay unit.
///
/// The rotated vector is `n cos α + |n| t sin α` with `t` a uniformly random unit tangent,
/// so the angle to the original is exactly `α` (for `α <= π`). Note that a uniform angle is
/// not uniform over the spherical cap: small deviations are over-represented.
#[must_use]
pub fn perturb_normals<V>(normals: &[V], max_angle: f64, seed: u64) -> Vec<V>
where
    V: Copy + Into<[f64; 3]> + From<[f64; 3]>,
{
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    normals
        .iter()
        .map(|&n| {
            let n = Vector::from(n.into());
            // Draw both numbers even for a zero vector so the stream stays aligned with the
            // input index.
            let alpha = max_angle * rng.random::<f64>();
            let psi = std::f64::consts::TAU * rng.random::<f64>();
            let len = n.norm();
            if len == 0.0 || !len.is_finite() {
                return V::from(n.into());
            }
            let (t1, t2) = tangent_basis(&(n / len));
            let t = t1 * psi.cos() + t2 * psi.sin();
            V::from((n * alpha.cos() + t * (len * alpha.sin())).into())
        })
        .collect()
}
