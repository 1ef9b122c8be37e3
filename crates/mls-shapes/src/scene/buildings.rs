//! Buildings: rotated boxes with flat or gable roofs.

use std::f64::consts::TAU;

use super::draws::Draws;
use super::terrain::Terrain;
use super::{CELL_SIZE, Hit, Ray, SurfaceClass};
use crate::math::Vector;

/// A box building, possibly rotated about `z`, with a flat or a gable roof: the convex
/// solid `|u| ≤ hx`, `|v| ≤ hy`, `base ≤ z ≤ eave + rise (1 − |v|/hy)` in its frame `(u, v)`.
#[derive(Clone, Debug)]
pub(super) struct Building {
    centre: [f64; 2],
    /// Cosine and sine of the rotation of the frame.
    rotation: (f64, f64),
    half: [f64; 2],
    base: f64,
    eave: f64,
    /// Height of the ridge above the eaves; 0 for a flat roof.
    rise: f64,
    reflectance: f64,
}

impl Building {
    pub(super) fn new(draws: &mut Draws, terrain: &Terrain, x0: f64, y0: f64) -> Self {
        let hx = draws.range(5.0, 16.0);
        let hy = draws.range(4.0, hx.min(10.0));
        // Half the buildings are aligned with the axes, as in planned districts.
        let angle = if draws.unit() < 0.5 {
            0.0
        } else {
            draws.range(0.0, TAU / 4.0)
        };
        let margin = hx.hypot(hy) + 1.0;
        let centre = [
            x0 + draws.range(margin, CELL_SIZE - margin),
            y0 + draws.range(margin, CELL_SIZE - margin),
        ];
        let ground = terrain.at(centre[0], centre[1]).0;
        // The walls start below the lowest ground of the footprint (slopes are below 0.18).
        let base = ground - 0.2 * margin - 1.0;
        let (eave, rise) = if draws.unit() < 0.5 {
            (ground + draws.range(5.0, 30.0), 0.0)
        } else {
            let eave = ground + draws.range(4.0, 20.0);
            (eave, draws.range(2.0, 0.8 * hy))
        };
        Self {
            centre,
            rotation: (angle.cos(), angle.sin()),
            half: [hx, hy],
            base,
            eave,
            rise,
            reflectance: draws.range(0.1, 0.4),
        }
    }

    /// Clips the ray against the bounding planes `n · q ≤ c` of the solid (Cyrus–Beck) in the
    /// building's frame; the entry plane gives the normal.
    pub(super) fn intersect(&self, ray: &Ray, best: &mut Hit) {
        let (c, s) = self.rotation;
        let to_local = |v: Vector| Vector::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z);
        let p = to_local(Vector::new(
            ray.origin.x - self.centre[0],
            ray.origin.y - self.centre[1],
            ray.origin.z,
        ));
        let d = to_local(ray.direction);
        let [hx, hy] = self.half;
        let top = self.eave + self.rise;
        let slope = self.rise / hy;
        let planes = [
            (Vector::new(1.0, 0.0, 0.0), hx),
            (Vector::new(-1.0, 0.0, 0.0), hx),
            (Vector::new(0.0, 1.0, 0.0), hy),
            (Vector::new(0.0, -1.0, 0.0), hy),
            (Vector::new(0.0, 0.0, -1.0), -self.base),
            // z ≤ top − slope |v| as two planes; the same plane twice for a flat roof.
            (Vector::new(0.0, slope, 1.0), top),
            (Vector::new(0.0, -slope, 1.0), top),
        ];
        let mut t_in = f64::NEG_INFINITY;
        let mut t_out = f64::INFINITY;
        let mut normal = Vector::z();
        for (n, limit) in planes {
            let denom = n.dot(&d);
            let num = limit - n.dot(&p);
            if denom.abs() < 1e-15 {
                if num < 0.0 {
                    return;
                }
            } else if denom < 0.0 {
                let t = num / denom;
                if t > t_in {
                    t_in = t;
                    normal = n;
                }
            } else {
                t_out = t_out.min(num / denom);
            }
        }
        if t_in > t_out || !t_in.is_finite() {
            return;
        }
        let n = normal.normalize();
        let world = Vector::new(c * n.x - s * n.y, s * n.x + c * n.y, n.z);
        best.offer(t_in, world, SurfaceClass::Building, self.reflectance);
    }
}
