//! The scan pattern: the ray of each point and its first hit with the terrain and the cells
//! it crosses.

use super::buildings::Building;
use super::draws::{Draws, hash3};
use super::terrain::Terrain;
use super::vegetation::Tree;
use super::{CELL_SIZE, Hit, OBJECT_CEILING, Ray, SALT_CELL, SALT_CROWN, Scene, SurfaceClass};
use crate::math::{Point, Vector};

impl Scene {
    pub(super) fn world_offset(&self) -> Vector {
        let [x0, y0] = self.config.origin;
        Vector::new(x0, y0, 0.0)
    }

    /// The ray of point `index` in local coordinates (origin at the area's corner).
    pub(super) fn ray(&self, index: u64) -> Ray {
        let c = &self.config;
        let per_strip = self.per_line * self.lines;
        let strip = index / per_strip;
        let line = (index % per_strip) / self.per_line;
        let k = index % self.per_line;
        // Odd strips fly back, so their lines run from the far end.
        let along = if strip.is_multiple_of(2) {
            line as f64 + 0.5
        } else {
            self.lines as f64 - line as f64 - 0.5
        };
        let y = along * c.line_spacing;
        let centre = strip as f64 * self.strip_spacing + 0.5 * self.swath;
        let across = (k as f64 + 0.5) * c.point_pitch - 0.5 * self.swath;
        let origin = Point::new(centre, y, self.terrain.min() + c.flying_height);
        let direction = Vector::new(across, 0.0, -c.flying_height).normalize();
        let line_period = c.line_spacing / c.speed;
        // A turn of two minutes between strips.
        let strip_period = self.lines as f64 * line_period + 120.0;
        let time = c.start_time
            + strip as f64 * strip_period
            + line as f64 * line_period
            + k as f64 * line_period / self.per_line as f64;
        Ray {
            origin,
            direction,
            time,
            strip: u16::try_from(strip).unwrap_or(u16::MAX),
            scan_angle_deg: across.atan2(c.flying_height).to_degrees(),
            edge: k + 1 == self.per_line,
        }
    }

    /// The first hit of `ray` (local coordinates) with the scene.
    pub(super) fn cast(&self, ray: &Ray, index: u64) -> Hit {
        let d = ray.direction;
        // Only the part of the ray below the object ceiling can hit anything.
        let t_top = (ray.origin.z - (self.terrain.max() + OBJECT_CEILING)) / -d.z;
        let t_bottom = (ray.origin.z - self.terrain.min()) / -d.z;
        let (t, gx, gy) = self.terrain.intersect(&ray.origin, &d, t_top, t_bottom);
        let mut best = Hit {
            t,
            normal: Vector::new(-gx, -gy, 1.0).normalize(),
            class: SurfaceClass::Ground,
            reflectance: 0.3,
        };
        let a = ray.origin + d * t_top;
        let b = ray.origin + d * t_bottom;
        let cells = |u: f64, v: f64| {
            let lo = (u.min(v) / CELL_SIZE).floor() as i64;
            let hi = (u.max(v) / CELL_SIZE).floor() as i64;
            lo..=hi
        };
        for i in cells(a.x, b.x) {
            for j in cells(a.y, b.y) {
                let key = hash3(self.config.seed, SALT_CROWN, index);
                intersect_cell(self.config.seed, &self.terrain, (i, j), ray, key, &mut best);
            }
        }
        best
    }
}

/// Draws what stands in cell `(i, j)` (one building, a copse of trees, or nothing) from a
/// hash of the seed and the indices, and offers its hits along `ray` to `best`. Drawing the
/// content per ray costs a few hashes and no allocation, and no scene is ever stored.
fn intersect_cell(
    seed: u64,
    terrain: &Terrain,
    (i, j): (i64, i64),
    ray: &Ray,
    key: u64,
    best: &mut Hit,
) {
    let mut draws = Draws::new(hash3(hash3(seed, SALT_CELL, i as u64), SALT_CELL, j as u64));
    let x0 = i as f64 * CELL_SIZE;
    let y0 = j as f64 * CELL_SIZE;
    let kind = draws.unit();
    if kind < 0.35 {
        Building::new(&mut draws, terrain, x0, y0).intersect(ray, best);
    } else if kind < 0.8 {
        // A copse of 3 to 14 trees.
        let count = 3 + (draws.unit() * 12.0) as u64;
        for n in 0..count {
            let tree = Tree::new(&mut draws, terrain, x0, y0);
            tree.intersect(ray, hash3(key, SALT_CROWN, n), best);
        }
    }
}
