//! A deterministic airborne-LiDAR scene: terrain, buildings and trees, sampled by a simulated
//! scanner in parallel flight strips, so that large realistic test clouds (10^8 points and
//! more) can be regenerated from a seed instead of being stored.
//!
//! The scene is never held in memory. The terrain is a sum of a few plane waves; the area is
//! cut into square cells of [`CELL_SIZE`] metres, and what stands in a cell (one building,
//! a copse of trees, or nothing) is drawn from a hash of the seed and the cell's indices, with
//! every object kept inside its cell. A ray therefore only has to look at the cells its
//! last few tens of metres cross, and each point is a pure function of its index
//! ([`Scene::point`]): chunking cannot change the output and memory stays O(chunk).
//!
//! # Scan pattern
//!
//! Strip `s` is flown along `+y` (even strips) or `−y` (odd strips) at
//! [`flying_height`](SceneConfig::flying_height) above the lowest terrain. Each scan line
//! runs across track (`+x`) through `n` nominal ground points at pitch `a` on the plane of the
//! lowest terrain, `n a` being the swath of the maximum scan angle; lines are `b` apart.
//! A point is the first hit of the ray from the sensor through its nominal ground point
//! with the terrain, a building or a tree crown, moved along the ray by Gaussian range noise.
//! Because the rays are up to [`max_scan_angle_deg`](SceneConfig::max_scan_angle_deg) off
//! nadir, walls facing `±x` receive returns.
//!
//! Points are numbered strip by strip, line by line, across each line; the requested count
//! fixes the layout (a near-square area) and truncates the last strip.

mod buildings;
mod draws;
mod scan;
mod terrain;
mod vegetation;

use crate::math::{Point, Vector};

use draws::{Draws, hash3};
use terrain::Terrain;

/// Side of the square cells that hold at most one building or a small group of trees (m).
pub const CELL_SIZE: f64 = 60.0;

/// Highest point of any object above the terrain under it (m): 30 m eaves, 8 m of gable,
/// 20 m trees, with a margin.
const OBJECT_CEILING: f64 = 40.0;

/// Salts that keep the hash streams of different purposes apart.
const SALT_TERRAIN: u64 = 1;
const SALT_CELL: u64 = 2;
const SALT_POINT: u64 = 3;
const SALT_CROWN: u64 = 4;

/// The parameters of a scene and its scan. Lengths in metres, angles in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneConfig {
    /// Seed of the terrain, the objects and the noise.
    pub seed: u64,
    /// Distance `a` between neighbouring points of a scan line on the ground.
    pub point_pitch: f64,
    /// Distance `b` between neighbouring scan lines.
    pub line_spacing: f64,
    /// Height of the sensor above the lowest terrain.
    pub flying_height: f64,
    /// Largest scan angle off nadir, either side.
    pub max_scan_angle_deg: f64,
    /// Fraction of a swath that the next strip covers again, in `[0, 0.9]`.
    pub strip_overlap: f64,
    /// Standard deviation of the range noise along each ray; 0 gives points exactly on the
    /// surfaces.
    pub range_noise: f64,
    /// World coordinates of the area's south-west corner (projected, e.g. UTM), so that the
    /// large coordinates of real data are exercised.
    pub origin: [f64; 2],
    /// Mean terrain height.
    pub ground_level: f64,
    /// Aircraft speed (m/s), which spaces the GPS times.
    pub speed: f64,
    /// GPS time of the first point (adjusted standard GPS time, s).
    pub start_time: f64,
}

impl Default for SceneConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            point_pitch: 0.5,
            line_spacing: 0.7,
            flying_height: 600.0,
            max_scan_angle_deg: 15.0,
            strip_overlap: 0.2,
            range_noise: 0.02,
            origin: [500_000.0, 5_000_000.0],
            ground_level: 200.0,
            speed: 60.0,
            start_time: 4.0e8,
        }
    }
}

/// Why a [`Scene`] cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// A parameter of [`SceneConfig`] is out of its range (or not finite).
    #[error("scene parameter {name} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// The field's name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The range it must lie in.
        reason: &'static str,
    },
    /// Zero points were requested: the layout of an empty scan is undefined.
    #[error("a scene needs at least one point")]
    NoPoints,
    /// The points need more strips than a LAS point source id (`u16`) can number.
    #[error("{points} points need {strips} flight strips, more than 65536")]
    TooManyStrips {
        /// Points requested.
        points: u64,
        /// Strips they need.
        strips: u64,
    },
}

/// ASPRS classification of a point's surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SurfaceClass {
    /// Bare terrain (ASPRS 2).
    Ground,
    /// Tree crowns and trunks (ASPRS 5, high vegetation).
    Vegetation,
    /// Roofs and walls (ASPRS 6).
    Building,
}

impl SurfaceClass {
    /// The ASPRS LAS classification code.
    #[must_use]
    pub fn code(self) -> u8 {
        match self {
            Self::Ground => 2,
            Self::Vegetation => 5,
            Self::Building => 6,
        }
    }
}

/// One simulated return.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScenePoint {
    /// Position in world coordinates, range noise included.
    pub position: Point,
    /// Unit normal of the surface at the noise-free hit, on the sensor's side: up on ground
    /// and roofs, outward on walls.
    pub normal: Vector,
    /// What was hit.
    pub class: SurfaceClass,
    /// Return strength: reflectance of the surface times the cosine of the incidence angle,
    /// scaled to 16 bits.
    pub intensity: u16,
    /// Always 1: the scanner records first returns only.
    pub return_number: u8,
    /// GPS time (s), increasing along each line, line by line and strip by strip.
    pub gps_time: f64,
    /// Index of the flight strip (the LAS point source id).
    pub strip: u16,
    /// Signed across-track scan angle (degrees, positive towards `+x`).
    pub scan_angle_deg: f64,
    /// Whether this is the last point of its scan line (the LAS edge-of-flight-line flag).
    pub edge_of_line: bool,
}

/// The horizontal extent of a scene in world coordinates, and bounds of its heights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Area {
    /// South-west corner: smallest `x`, `y`, and a height below every surface.
    pub min: Point,
    /// North-east corner: largest `x`, `y`, and a height above every surface.
    pub max: Point,
}

/// A scene with a fixed number of points laid out in strips: see the [module
/// documentation](self).
#[derive(Clone, Debug)]
pub struct Scene {
    config: SceneConfig,
    points: u64,
    terrain: Terrain,
    /// Points per scan line.
    per_line: u64,
    /// Scan lines per full strip.
    lines: u64,
    strips: u64,
    /// Width covered by a line on the lowest terrain.
    swath: f64,
    /// Distance between the centre lines of neighbouring strips.
    strip_spacing: f64,
}

impl Scene {
    /// A scene of exactly `points` points.
    ///
    /// # Errors
    ///
    /// [`SceneError`] if a parameter is out of range, `points` is 0 or the layout needs more
    /// strips than a `u16` numbers.
    pub fn new(config: SceneConfig, points: u64) -> Result<Self, SceneError> {
        validate(&config)?;
        if points == 0 {
            return Err(SceneError::NoPoints);
        }
        let reach = config.flying_height * config.max_scan_angle_deg.to_radians().tan();
        // At least one point per line; the swath is a whole number of pitches.
        let per_line = ((2.0 * reach / config.point_pitch).floor() as u64).max(1);
        let swath = per_line as f64 * config.point_pitch;
        let strip_spacing = swath * (1.0 - config.strip_overlap);
        // A near-square area: strips × spacing ≈ lines × line spacing.
        let total_lines = points.div_ceil(per_line);
        let square = (points as f64 * strip_spacing / (per_line as f64 * config.line_spacing))
            .sqrt()
            .round() as u64;
        let lines = square.clamp(1, total_lines);
        let strips = total_lines.div_ceil(lines);
        if strips > u64::from(u16::MAX) + 1 {
            return Err(SceneError::TooManyStrips { points, strips });
        }
        Ok(Self {
            terrain: Terrain::new(config.seed, config.ground_level),
            config,
            points,
            per_line,
            lines,
            strips,
            swath,
            strip_spacing,
        })
    }

    /// The configuration.
    #[must_use]
    pub fn config(&self) -> &SceneConfig {
        &self.config
    }

    /// The number of points.
    #[must_use]
    pub fn len(&self) -> u64 {
        self.points
    }

    /// Always false: a scene has at least one point.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.points == 0
    }

    /// The number of flight strips (the last one possibly shorter).
    #[must_use]
    pub fn strips(&self) -> u64 {
        self.strips
    }

    /// Points per scan line and scan lines per full strip.
    #[must_use]
    pub fn line_layout(&self) -> (u64, u64) {
        (self.per_line, self.lines)
    }

    /// The area the nominal ground points cover, with height bounds of every surface.
    /// Range noise can move a point a few σ past it.
    #[must_use]
    pub fn area(&self) -> Area {
        let [x0, y0] = self.config.origin;
        let width = (self.strips - 1) as f64 * self.strip_spacing + self.swath;
        let length = self.lines as f64 * self.config.line_spacing;
        Area {
            min: Point::new(x0, y0, self.terrain.min()),
            max: Point::new(x0 + width, y0 + length, self.terrain.max() + OBJECT_CEILING),
        }
    }

    /// Terrain height at world position `(x, y)`, buildings and trees left out.
    #[must_use]
    pub fn ground_height(&self, x: f64, y: f64) -> f64 {
        let [x0, y0] = self.config.origin;
        self.terrain.at(x - x0, y - y0).0
    }

    /// Upward unit normal of the terrain at world position `(x, y)`.
    #[must_use]
    pub fn ground_normal(&self, x: f64, y: f64) -> Vector {
        let [x0, y0] = self.config.origin;
        let (_, gx, gy) = self.terrain.at(x - x0, y - y0);
        Vector::new(-gx, -gy, 1.0).normalize()
    }

    /// The sensor's position when it measured point `index`, in world coordinates (the
    /// viewpoint for orienting normals).
    #[must_use]
    pub fn sensor_position(&self, index: u64) -> Point {
        let ray = self.ray(index);
        ray.origin + self.world_offset()
    }

    /// Point `index` (`0 ≤ index < len()`), a pure function of the seed, the layout and
    /// the index. An index past the end continues the scan pattern.
    #[must_use]
    pub fn point(&self, index: u64) -> ScenePoint {
        let ray = self.ray(index);
        let hit = self.cast(&ray, index);
        let mut draws = Draws::new(hash3(self.config.seed, SALT_POINT, index));
        let noise = self.config.range_noise * draws.normal();
        let position = ray.origin + ray.direction * (hit.t + noise) + self.world_offset();
        let cos_incidence = hit.normal.dot(&ray.direction).abs();
        let jitter = 0.9 + 0.2 * draws.unit();
        let intensity = (hit.reflectance * cos_incidence * jitter * f64::from(u16::MAX))
            .round()
            .clamp(0.0, f64::from(u16::MAX)) as u16;
        ScenePoint {
            position,
            normal: hit.normal,
            class: hit.class,
            intensity,
            return_number: 1,
            gps_time: ray.time,
            strip: ray.strip,
            scan_angle_deg: ray.scan_angle_deg,
            edge_of_line: ray.edge,
        }
    }

    /// A cursor over all points in order.
    #[must_use]
    pub fn scan(&self) -> Scan<'_> {
        self.scan_from(0)
    }

    /// A cursor over the points from `index` on.
    #[must_use]
    pub fn scan_from(&self, index: u64) -> Scan<'_> {
        Scan {
            scene: self,
            next: index.min(self.points),
        }
    }
}

/// Points of a [`Scene`] in order, from an index on: an iterator, and [`fill`](Self::fill)
/// for chunks.
#[derive(Clone, Debug)]
pub struct Scan<'s> {
    scene: &'s Scene,
    next: u64,
}

impl Scan<'_> {
    /// Index of the next point.
    #[must_use]
    pub fn position(&self) -> u64 {
        self.next
    }

    /// Clears `out` and fills it with up to `count` next points; returns how many (0 at the
    /// end). `out` keeps its allocation, so a loop of `fill` calls uses O(count) memory.
    pub fn fill(&mut self, out: &mut Vec<ScenePoint>, count: usize) -> usize {
        out.clear();
        let end = self
            .scene
            .points
            .min(self.next.saturating_add(count as u64));
        out.extend((self.next..end).map(|i| self.scene.point(i)));
        self.next = end;
        out.len()
    }
}

impl Iterator for Scan<'_> {
    type Item = ScenePoint;

    fn next(&mut self) -> Option<ScenePoint> {
        (self.next < self.scene.points).then(|| {
            self.next += 1;
            self.scene.point(self.next - 1)
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = usize::try_from(self.scene.points - self.next).unwrap_or(usize::MAX);
        (left, Some(left))
    }
}

fn validate(c: &SceneConfig) -> Result<(), SceneError> {
    let check = |name, value: f64, ok: bool, reason| {
        if value.is_finite() && ok {
            Ok(())
        } else {
            Err(SceneError::InvalidParameter {
                name,
                value,
                reason,
            })
        }
    };
    check(
        "point_pitch",
        c.point_pitch,
        c.point_pitch > 0.0,
        "must be > 0",
    )?;
    check(
        "line_spacing",
        c.line_spacing,
        c.line_spacing > 0.0,
        "must be > 0",
    )?;
    check(
        "flying_height",
        c.flying_height,
        c.flying_height >= 100.0,
        "must be ≥ 100 m, above the highest object",
    )?;
    check(
        "max_scan_angle_deg",
        c.max_scan_angle_deg,
        c.max_scan_angle_deg > 0.0 && c.max_scan_angle_deg <= 45.0,
        "must be in (0, 45]",
    )?;
    check(
        "strip_overlap",
        c.strip_overlap,
        (0.0..=0.9).contains(&c.strip_overlap),
        "must be in [0, 0.9]",
    )?;
    check(
        "range_noise",
        c.range_noise,
        c.range_noise >= 0.0,
        "must be ≥ 0",
    )?;
    check("origin x", c.origin[0], true, "must be finite")?;
    check("origin y", c.origin[1], true, "must be finite")?;
    check("ground_level", c.ground_level, true, "must be finite")?;
    check("speed", c.speed, c.speed > 0.0, "must be > 0")?;
    check("start_time", c.start_time, true, "must be finite")
}

/// A scanner ray in local coordinates, with what the record needs of its timing.
#[derive(Clone, Copy, Debug)]
struct Ray {
    origin: Point,
    /// Unit direction, downwards.
    direction: Vector,
    time: f64,
    strip: u16,
    scan_angle_deg: f64,
    edge: bool,
}

/// The nearest hit so far along a ray.
#[derive(Clone, Copy, Debug)]
struct Hit {
    t: f64,
    /// Unit, facing the sensor.
    normal: Vector,
    class: SurfaceClass,
    reflectance: f64,
}

impl Hit {
    /// Replaces the hit if `t` is nearer.
    fn offer(&mut self, t: f64, normal: Vector, class: SurfaceClass, reflectance: f64) {
        if t >= 0.0 && t < self.t {
            *self = Self {
                t,
                normal,
                class,
                reflectance,
            };
        }
    }
}

#[cfg(test)]
mod tests;
