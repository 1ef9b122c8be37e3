//! Small seeded clouds with exact normals, written out here so the core's tests stand alone.

use mls_core::{Point, Vector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Near-uniform (Fibonacci) points on a sphere of radius `r` with outward normals.
pub fn fibonacci_sphere(n: usize, r: f64) -> (Vec<Point>, Vec<Vector>) {
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    let normals: Vec<Vector> = (0..n)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / n as f64;
            let rho = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            Vector::new(rho * phi.cos(), rho * phi.sin(), z)
        })
        .collect();
    (
        normals.iter().map(|n| Point::from(n * r)).collect(),
        normals,
    )
}

/// A jittered grid on the wavy height field `z = A sin(x/L) cos(y/L)` over `[-w, w]²` with
/// exact upward normals, optionally tilted at random by up to `tilt` radians.
pub fn wavy_patch(seed: u64, spacing: f64, w: f64, tilt: f64) -> (Vec<Point>, Vec<Vector>) {
    let (amp, len) = (0.1, 0.4);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = (2.0 * w / spacing).round() as i64;
    let mut pts = Vec::new();
    let mut nrm = Vec::new();
    for i in -n / 2..=n / 2 {
        for j in -n / 2..=n / 2 {
            let x = i as f64 * spacing + rng.random_range(-0.3..0.3) * spacing;
            let y = j as f64 * spacing + rng.random_range(-0.3..0.3) * spacing;
            let z = amp * (x / len).sin() * (y / len).cos();
            let zx = amp / len * (x / len).cos() * (y / len).cos();
            let zy = -amp / len * (x / len).sin() * (y / len).sin();
            let normal = Vector::new(-zx, -zy, 1.0).normalize();
            let jitter = Vector::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let axis = normal.cross(&jitter);
            let tilted = if axis.norm() > 1e-12 && tilt > 0.0 {
                nalgebra::Rotation3::new(axis.normalize() * rng.random_range(0.0..tilt)) * normal
            } else {
                normal
            };
            pts.push(Point::new(x, y, z));
            nrm.push(tilted);
        }
    }
    (pts, nrm)
}
