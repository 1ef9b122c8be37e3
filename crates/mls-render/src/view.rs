//! Views: the camera a [`View`] describes, and the fit of a projected cloud into a rectangle.

use anyhow::Result;

use crate::splat::{Rect, SPLAT_RADIUS};

/// A fixed orthographic camera: the direction it looks from, as angles around the `up` axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Angle of the camera around the up axis, from the axis after it towards the one after
    /// that (for z up: from +x towards +y; for y up: from +z towards +x; for x up: from +y
    /// towards +z).
    pub azimuth_deg: f64,
    /// Angle of the camera above the plane across the up axis.
    pub elevation_deg: f64,
    /// The world axis drawn pointing up the picture (as nearly as the view allows).
    pub up: Up,
}

/// A coordinate axis that a [`View`] keeps upright.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Up {
    /// +x up.
    X,
    /// +y up, as in many scans (the Stanford bunny).
    Y,
    /// +z up, as in LiDAR and the paper's figures.
    #[default]
    Z,
}

impl Up {
    /// A world vector in the frame whose third axis is the up axis: a cyclic permutation of
    /// the coordinates, so that the frame stays right-handed.
    fn to_local(self, [x, y, z]: [f64; 3]) -> [f64; 3] {
        match self {
            Self::X => [y, z, x],
            Self::Y => [z, x, y],
            Self::Z => [x, y, z],
        }
    }

    /// The inverse of [`Self::to_local`].
    pub(crate) fn to_world(self, [a, b, c]: [f64; 3]) -> [f64; 3] {
        match self {
            Self::X => [c, a, b],
            Self::Y => [b, c, a],
            Self::Z => [a, b, c],
        }
    }
}

impl View {
    /// A three-quarter view from above that shows a sphere or a torus well.
    pub const THREE_QUARTER: View = View {
        azimuth_deg: -60.0,
        elevation_deg: 30.0,
        up: Up::Z,
    };

    /// A view from a written description, keeping `up` upright:
    ///
    /// - `+x`, `-x`, `+y`, `-y`, `+z`, `-z`: from far out along that axis, looking back at the
    ///   cloud (`+z` with z up is from above). Looking along the up axis itself, the next axis
    ///   points right (x for z up).
    /// - `AZIMUTH,ELEVATION` in degrees, as in [`View`]; `-60,30` is [`View::THREE_QUARTER`].
    ///
    /// # Errors
    /// A message saying what is expected.
    pub fn parse(spec: &str, up: Up) -> Result<Self, String> {
        let spec = spec.trim();
        let axis = match spec {
            "+x" | "x" => Some([1.0, 0.0, 0.0]),
            "-x" => Some([-1.0, 0.0, 0.0]),
            "+y" | "y" => Some([0.0, 1.0, 0.0]),
            "-y" => Some([0.0, -1.0, 0.0]),
            "+z" | "z" => Some([0.0, 0.0, 1.0]),
            "-z" => Some([0.0, 0.0, -1.0]),
            _ => None,
        };
        if let Some(direction) = axis {
            let [a, b, c] = up.to_local(direction);
            let (azimuth_deg, elevation_deg) = if c == 0.0 {
                (b.atan2(a).to_degrees(), 0.0)
            } else {
                // Along the up axis: the azimuth that puts the next axis to the right.
                (-90.0, 90.0 * c)
            };
            return Ok(Self {
                azimuth_deg,
                elevation_deg,
                up,
            });
        }
        let expected = "expected +x, -x, +y, -y, +z, -z, or AZIMUTH,ELEVATION in degrees \
             (e.g. -60,30)";
        let numbers: Vec<Option<f64>> = spec
            .split(',')
            .map(|s| s.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect();
        match numbers[..] {
            [Some(azimuth_deg), Some(elevation_deg)] if elevation_deg.abs() <= 90.0 => Ok(Self {
                azimuth_deg,
                elevation_deg,
                up,
            }),
            [Some(_), Some(e)] => Err(format!(
                "view `{spec}`: the elevation must be within -90..90 degrees, got {e}"
            )),
            _ => Err(format!("view `{spec}`: {expected}")),
        }
    }
}

/// The orthonormal frame of a [`View`]: screen right, screen up, and towards the camera.
pub(crate) struct Camera {
    pub(crate) right: [f64; 3],
    pub(crate) up: [f64; 3],
    pub(crate) toward: [f64; 3],
    /// Direction towards the light: from the camera's upper left.
    light: [f64; 3],
}

pub(crate) fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Camera {
    pub(crate) fn new(view: View) -> Self {
        let (sa, ca) = view.azimuth_deg.to_radians().sin_cos();
        let (se, ce) = view.elevation_deg.to_radians().sin_cos();
        // In the frame whose third axis is up, then back in world coordinates.
        let right = view.up.to_world([-sa, ca, 0.0]);
        let up = view.up.to_world([-se * ca, -se * sa, ce]);
        let toward = view.up.to_world([ce * ca, ce * sa, se]);
        let l: [f64; 3] = std::array::from_fn(|i| toward[i] + 0.6 * up[i] - 0.4 * right[i]);
        let norm = dot(&l, &l).sqrt();
        Self {
            right,
            up,
            toward,
            light: l.map(|c| c / norm),
        }
    }

    /// Screen x, screen y and depth (larger is nearer the camera), in world units.
    pub(crate) fn project(&self, p: &[f64; 3]) -> [f64; 3] {
        [dot(p, &self.right), dot(p, &self.up), dot(p, &self.toward)]
    }

    /// Brightness factor from a normal of either sign; 1 when the normal is unusable.
    pub(crate) fn shade(&self, normal: &[f64; 3]) -> f64 {
        const AMBIENT: f64 = 0.4;
        let length = dot(normal, normal).sqrt();
        let lambert = dot(normal, &self.light).abs() / length;
        if lambert.is_finite() {
            AMBIENT + (1.0 - AMBIENT) * lambert.min(1.0)
        } else {
            1.0
        }
    }
}

/// Scale and offset that fit the projected cloud into a rectangle.
pub(crate) struct Fit {
    /// Pixels per world unit.
    pub(crate) scale: f64,
    centre: (f64, f64),
    half: (f64, f64),
    /// Largest disc radius in pixels.
    max_radius: f64,
}

impl Fit {
    /// `reach` is the typical disc size in world units, None when unknown.
    pub(crate) fn new(
        rect: Rect,
        projected: &[Option<[f64; 3]>],
        reach: Option<f64>,
    ) -> Option<Self> {
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for q in projected.iter().flatten() {
            for c in 0..2 {
                lo[c] = lo[c].min(q[c]);
                hi[c] = hi[c].max(q[c]);
            }
        }
        if !(lo[0] <= hi[0]) {
            return None;
        }
        const PAD: f64 = 8.0;
        let (w, h) = (rect.w as f64, rect.h as f64);
        let max_radius = w.min(h) / 4.0;
        let fit =
            |pad: f64| ((w - 2.0 * pad) / (hi[0] - lo[0])).min((h - 2.0 * pad) / (hi[1] - lo[1]));
        // The margin depends on the disc size and the disc size on the scale: one round of each.
        let scale = fit(PAD);
        let scale = match reach {
            Some(r) if scale.is_finite() => fit(PAD + (SPLAT_RADIUS * r * scale).min(max_radius)),
            Some(_) | None if scale.is_finite() => scale,
            // All points project to one place: no extent to fit, any scale does.
            _ => 1.0,
        };
        Some(Self {
            scale,
            centre: ((lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0),
            half: (w / 2.0, h / 2.0),
            max_radius,
        })
    }

    /// Disc radius in pixels for a point whose disc reaches `reach` world units (NaN: 3 px).
    pub(crate) fn radius(&self, reach: f64) -> f64 {
        let r = SPLAT_RADIUS * reach * self.scale;
        if r.is_finite() {
            r.clamp(1.0, self.max_radius)
        } else {
            3.0
        }
    }

    /// Position in the rectangle, in pixels (y down).
    pub(crate) fn pixel(&self, q: &[f64; 3]) -> (f64, f64) {
        (
            self.half.0 + (q[0] - self.centre.0) * self.scale,
            self.half.1 - (q[1] - self.centre.1) * self.scale,
        )
    }
}
