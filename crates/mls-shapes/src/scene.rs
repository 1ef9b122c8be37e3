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

use std::f64::consts::TAU;

use crate::math::{Point, Vector};

/// Side of the square cells that hold at most one building or a small group of trees (m).
pub const CELL_SIZE: f64 = 60.0;

/// Highest point of any object above the terrain under it (m): 30 m eaves, 8 m of gable,
/// 20 m trees, with a margin.
const OBJECT_CEILING: f64 = 40.0;

/// Plane waves of the terrain: amplitude (m) and wavelength (m). The steepest possible slope,
/// `2π Σ A/λ ≈ 0.18`, keeps the ground gentle and every ray's terrain hit unique.
const TERRAIN_WAVES: [(f64, f64); 4] = [(6.0, 900.0), (2.5, 350.0), (1.0, 130.0), (0.3, 45.0)];

/// Salts that keep the hash streams of different purposes apart.
const SALT_TERRAIN: u64 = 1;
const SALT_CELL: u64 = 2;
const SALT_POINT: u64 = 3;
const SALT_CROWN: u64 = 4;

/// Probability that a ray meets a crown but passes through its gaps.
const CROWN_GAP: f64 = 0.35;

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

    fn world_offset(&self) -> Vector {
        let [x0, y0] = self.config.origin;
        Vector::new(x0, y0, 0.0)
    }

    /// The ray of point `index` in local coordinates (origin at the area's corner).
    fn ray(&self, index: u64) -> Ray {
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
    fn cast(&self, ray: &Ray, index: u64) -> Hit {
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

/// The ground: $h(x, y) = h_0 + \sum_i A_i \sin(k_i \cdot (x, y) + \varphi_i)$, in local
/// coordinates.
#[derive(Clone, Debug)]
struct Terrain {
    level: f64,
    /// Amplitude, wave vector x and y, phase.
    waves: [[f64; 4]; 4],
    amplitude: f64,
}

impl Terrain {
    fn new(seed: u64, level: f64) -> Self {
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

    fn min(&self) -> f64 {
        self.level - self.amplitude
    }

    fn max(&self) -> f64 {
        self.level + self.amplitude
    }

    /// Height and gradient at `(x, y)`.
    fn at(&self, x: f64, y: f64) -> (f64, f64, f64) {
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
    fn intersect(&self, origin: &Point, d: &Vector, lo: f64, hi: f64) -> (f64, f64, f64) {
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

/// A box building, possibly rotated about `z`, with a flat or a gable roof: the convex
/// solid `|u| ≤ hx`, `|v| ≤ hy`, `base ≤ z ≤ eave + rise (1 − |v|/hy)` in its frame `(u, v)`.
#[derive(Clone, Debug)]
struct Building {
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
    fn new(draws: &mut Draws, terrain: &Terrain, x0: f64, y0: f64) -> Self {
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
    fn intersect(&self, ray: &Ray, best: &mut Hit) {
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

/// A tree: a vertical trunk under an ellipsoidal crown. Rays that meet the crown either pass
/// through its gaps or return from some depth inside it, which scatters the returns as
/// foliage does.
#[derive(Clone, Debug)]
struct Tree {
    centre: Point,
    /// Horizontal and vertical semi-axes of the crown.
    radius: f64,
    half_height: f64,
    trunk_radius: f64,
    ground: f64,
    reflectance: f64,
}

impl Tree {
    fn new(draws: &mut Draws, terrain: &Terrain, x0: f64, y0: f64) -> Self {
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

    fn intersect(&self, ray: &Ray, key: u64, best: &mut Hit) {
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

/// The SplitMix64 finaliser: a bijective, well-mixed hash of one word.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A hash of three words, for keys such as (seed, purpose, index).
fn hash3(a: u64, b: u64, c: u64) -> u64 {
    mix(mix(mix(a) ^ b) ^ c)
}

/// A SplitMix64 stream: cheap to start, so every point and cell can have its own without
/// a shared generator, which is what makes the output independent of chunking.
#[derive(Clone, Copy, Debug)]
struct Draws(u64);

impl Draws {
    fn new(key: u64) -> Self {
        Self(key)
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix(self.0)
    }

    /// Uniform in `[0, 1)`.
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Standard normal, by the Box–Muller transform.
    fn normal(&mut self) -> f64 {
        let u = 1.0 - self.unit();
        let v = self.unit();
        (-2.0 * u.ln()).sqrt() * (TAU * v).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SEED: u64 = 0x5EED_0014;

    fn scene(points: u64, noise: f64) -> Scene {
        let config = SceneConfig {
            seed: SEED,
            range_noise: noise,
            ..SceneConfig::default()
        };
        Scene::new(config, points).expect("valid config")
    }

    #[test]
    fn scene_is_deterministic() {
        let a: Vec<_> = scene(20_000, 0.02).scan().collect();
        let b: Vec<_> = scene(20_000, 0.02).scan().collect();
        assert_eq!(a, b);
        let other = Scene::new(
            SceneConfig {
                seed: SEED + 1,
                ..SceneConfig::default()
            },
            20_000,
        )
        .expect("valid config");
        assert_ne!(a, other.scan().collect::<Vec<_>>());
    }

    #[test]
    fn scene_chunking_does_not_change_points() {
        let s = scene(150_000, 0.02);
        let collect = |chunk: usize| {
            let mut scan = s.scan();
            let (mut all, mut buf) = (Vec::new(), Vec::new());
            while scan.fill(&mut buf, chunk) > 0 {
                all.extend_from_slice(&buf);
            }
            all
        };
        let small = collect(1000);
        assert_eq!(small.len(), 150_000);
        assert_eq!(small, collect(65_536));
        assert_eq!(small[77_777], s.point(77_777));
        assert_eq!(s.scan_from(149_990).count(), 10);
    }

    #[test]
    fn scene_counts_are_exact() {
        for n in [1, 2, 642, 643, 644, 999, 123_457] {
            let s = scene(n, 0.0);
            assert_eq!(s.len(), n);
            assert_eq!(s.scan().count() as u64, n, "{n}");
            assert_eq!(s.scan().size_hint(), (n as usize, Some(n as usize)));
        }
        // The layout of a large run, without generating it.
        for n in [100_000_000, 1_000_000_007] {
            let s = scene(n, 0.02);
            let (per_line, lines) = s.line_layout();
            let per_strip = per_line * lines;
            assert!(
                s.strips() * per_strip >= n && (s.strips() - 1) * per_strip < n,
                "{n}"
            );
            let area = s.area();
            let (w, l) = (area.max.x - area.min.x, area.max.y - area.min.y);
            assert!(
                w / l > 0.5 && w / l < 2.0,
                "{n}: {w} × {l} is not near square"
            );
        }
    }

    #[test]
    fn scene_normals_match_the_surfaces_hit() {
        let s = scene(200_000, 0.0);
        let area = s.area();
        let (mut walls, mut roofs, mut vegetation, mut ground) = (0, 0, 0, 0);
        let mut last_time = f64::NEG_INFINITY;
        for (i, p) in s.scan().enumerate() {
            let n = p.normal;
            assert!((n.norm() - 1.0).abs() < 1e-12, "point {i}: {n:?}");
            let to_sensor = s.sensor_position(i as u64) - p.position;
            assert!(
                n.dot(&to_sensor) > 0.0,
                "point {i} faces away from the sensor"
            );
            assert!(p.gps_time > last_time, "point {i}: time not increasing");
            last_time = p.gps_time;
            assert!(p.position.x >= area.min.x - 1e-6 && p.position.x <= area.max.x + 1e-6);
            assert!(p.position.y >= area.min.y - 1e-6 && p.position.y <= area.max.y + 1e-6);
            assert!(p.position.z >= area.min.z - 1e-6 && p.position.z <= area.max.z);
            assert_eq!(p.return_number, 1);
            match p.class {
                SurfaceClass::Ground => {
                    ground += 1;
                    let (x, y) = (p.position.x, p.position.y);
                    assert!(
                        (p.position.z - s.ground_height(x, y)).abs() < 1e-6,
                        "point {i}"
                    );
                    assert!((n - s.ground_normal(x, y)).norm() < 1e-9, "point {i}");
                    assert!(n.z > 0.9, "point {i}: {n:?}");
                }
                SurfaceClass::Building if n.z.abs() < 1e-12 => walls += 1,
                SurfaceClass::Building => {
                    roofs += 1;
                    assert!(n.z > 0.5, "point {i}: roof normal {n:?}");
                    assert!(p.position.z > s.ground_height(p.position.x, p.position.y) + 3.0);
                }
                SurfaceClass::Vegetation => vegetation += 1,
            }
        }
        assert!(ground > 100_000, "{ground} ground points");
        assert!(
            walls > 0 && roofs > 1000 && vegetation > 500,
            "{walls} {roofs} {vegetation}"
        );
    }

    #[test]
    fn scene_noise_moves_points_along_the_ray() {
        let exact = scene(5000, 0.0);
        let noisy = scene(5000, 0.05);
        let mut sum = 0.0;
        for i in 0..5000 {
            let (a, b) = (exact.point(i), noisy.point(i));
            let ray = (a.position - exact.sensor_position(i)).normalize();
            let offset = b.position - a.position;
            assert!(offset.cross(&ray).norm() < 1e-6, "point {i}");
            sum += offset.norm_squared();
            assert_eq!(a.normal, b.normal);
        }
        let sd = (sum / 5000.0).sqrt();
        assert!((sd - 0.05).abs() < 0.005, "range noise {sd}");
    }

    #[test]
    fn scene_rejects_bad_input() {
        assert_eq!(
            Scene::new(SceneConfig::default(), 0).err(),
            Some(SceneError::NoPoints)
        );
        for config in [
            SceneConfig {
                point_pitch: 0.0,
                ..SceneConfig::default()
            },
            SceneConfig {
                range_noise: f64::NAN,
                ..SceneConfig::default()
            },
            SceneConfig {
                max_scan_angle_deg: 80.0,
                ..SceneConfig::default()
            },
        ] {
            assert!(matches!(
                Scene::new(config, 10),
                Err(SceneError::InvalidParameter { .. })
            ));
        }
        let tiny = SceneConfig {
            point_pitch: 100.0,
            line_spacing: 1e-6,
            ..SceneConfig::default()
        };
        assert!(matches!(
            Scene::new(tiny, u64::MAX),
            Err(SceneError::TooManyStrips { .. })
        ));
    }
}
