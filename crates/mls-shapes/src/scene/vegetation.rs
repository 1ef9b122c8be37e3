//! Vegetation: trees with a trunk and an ellipsoidal crown that scatters the returns.

use super::draws::Draws;
use super::terrain::Terrain;
use super::{CELL_SIZE, Hit, Ray, SurfaceClass};
use crate::math::{Point, Vector};

/// Probability that a ray meets a crown but passes through its gaps.
const CROWN_GAP: f64 = 0.35;

/// A tree: a vertical trunk under an ellipsoidal crown. Rays that meet the crown either pass
/// through its gaps or return from some depth inside it, which scatters the returns as
/// foliage does.
#[derive(Clone, Debug)]
pub(super) struct Tree {
    centre: Point,
    /// Horizontal and vertical semi-axes of the crown.
    radius: f64,
    half_height: f64,
    trunk_radius: f64,
    ground: f64,
    reflectance: f64,
}

impl Tree {
    pub(super) fn new(draws: &mut Draws, terrain: &Terrain, x0: f64, y0: f64) -> Self {
        let radius = draws.range(1.5, 4.0);
        let half_height = draws.range(2.0, 6.0);
        let trunk = draws.range(2.0, 8.0);
        let x = x0 + draws.range(radius + 1.0, CELL_SIZE - radius - 1.0);
        let y = y0 + draws.range(radius + 1.0, CELL_SIZE - radius - 1.0);
        let ground = terrain.at(x, y).0;
        Self {
            centre: Point::new(x, y, ground + trunk + half_height),
            radius,
            half_height,
            trunk_radius: draws.range(0.1, 0.3),
            ground: ground - 0.5,
            reflectance: draws.range(0.35, 0.6),
        }
    }

    pub(super) fn intersect(&self, ray: &Ray, key: u64, best: &mut Hit) {
        let d = ray.direction;
        let scale = Vector::new(self.radius, self.radius, self.half_height);
        let q = (ray.origin - self.centre).component_div(&scale);
        let e = d.component_div(&scale);
        if let Some((t_in, t_out)) = quadratic(e.norm_squared(), q.dot(&e), q.norm_squared() - 1.0)
        {
            let mut draws = Draws::new(key);
            if draws.unit() >= CROWN_GAP {
                // Returns cluster near the crown's surface.
                let depth = draws.unit();
                let t = t_in + depth * depth * 0.6 * (t_out - t_in);
                let r = ray.origin + d * t - self.centre;
                let g = Vector::new(
                    r.x / (self.radius * self.radius),
                    r.y / (self.radius * self.radius),
                    r.z / (self.half_height * self.half_height),
                );
                let n = g.try_normalize(1e-12).unwrap_or(-d);
                let n = if n.dot(&d) > 0.0 { -n } else { n };
                best.offer(t, n, SurfaceClass::Vegetation, self.reflectance);
            }
        }
        // The trunk: |(x, y) − centre| = trunk radius between the ground and the crown.
        let (px, py) = (ray.origin.x - self.centre.x, ray.origin.y - self.centre.y);
        let r2 = self.trunk_radius * self.trunk_radius;
        let a = d.x * d.x + d.y * d.y;
        if a > 0.0
            && let Some((t, _)) = quadratic(a, px * d.x + py * d.y, px * px + py * py - r2)
        {
            let z = ray.origin.z + d.z * t;
            if z >= self.ground && z <= self.centre.z {
                let h = ray.origin + d * t - self.centre;
                let n = Vector::new(h.x, h.y, 0.0).normalize();
                best.offer(t, n, SurfaceClass::Vegetation, 0.3);
            }
        }
    }
}

/// The roots `t1 ≤ t2` of `a t² + 2 b t + c = 0` (a > 0), if real.
fn quadratic(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - a * c;
    if !(disc > 0.0) {
        return None;
    }
    let root = disc.sqrt();
    Some(((-b - root) / a, (-b + root) / a))
}
