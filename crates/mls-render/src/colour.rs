//! Colour maps and legends: how the values of a panel become colours.

use anyhow::{Result, ensure};

use crate::Rgb;

/// How values map to colours.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScaleKind {
    /// Blue, white, red; white at 0 when `min < 0 < max`, else at the middle of the range.
    /// For signed quantities: errors, curvature of either sign.
    Diverging,
    /// Viridis, dark blue to yellow. For quantities of one sign or without a natural zero.
    Sequential,
}

/// The value range of a colour map and its legend label. Values outside the range take the
/// colour of the nearer end.
#[derive(Clone, Debug, PartialEq)]
pub struct ColourScale {
    pub min: f64,
    pub max: f64,
    /// Shown under the colour bar, e.g. "k1 error".
    pub label: String,
    pub kind: ScaleKind,
}

impl ColourScale {
    /// A sequential scale over the 2nd..98th percentile of the finite values, so that a few
    /// outliers do not wash out the map. Falls back to [0, 1] without finite values.
    pub fn robust_sequential(values: &[f64], label: &str) -> Self {
        let (min, max) = match (percentile(values, 0.02), percentile(values, 0.98)) {
            (Some(lo), Some(hi)) if hi > lo => (lo, hi),
            // Constant data: a unit-wide range around it, so the map shows its middle colour.
            (Some(v), Some(_)) => (v - 0.5, v + 0.5),
            _ => (0.0, 1.0),
        };
        Self {
            min,
            max,
            label: label.to_owned(),
            kind: ScaleKind::Sequential,
        }
    }

    /// A diverging scale symmetric around 0, out to the 98th percentile of `|value|`: for
    /// errors and signed curvature. Falls back to [-1, 1] when every finite value is 0 or
    /// there is none.
    pub fn robust_symmetric(values: &[f64], label: &str) -> Self {
        let magnitudes: Vec<f64> = values.iter().map(|v| v.abs()).collect();
        let bound = percentile(&magnitudes, 0.98)
            .filter(|&b| b > 0.0)
            .unwrap_or(1.0);
        Self {
            min: -bound,
            max: bound,
            label: label.to_owned(),
            kind: ScaleKind::Diverging,
        }
    }

    pub(crate) fn check(&self) -> Result<()> {
        ensure!(
            self.min.is_finite() && self.max.is_finite() && self.min < self.max,
            "colour scale `{}` needs finite min < max, got [{}, {}]",
            self.label,
            self.min,
            self.max
        );
        Ok(())
    }

    /// The position of `value` along the colour map, in [0, 1].
    fn position(&self, value: f64) -> f64 {
        let t = match self.kind {
            ScaleKind::Diverging if self.min < 0.0 && 0.0 < self.max => {
                // Each side of zero has its own rate, so that zero is white.
                if value < 0.0 {
                    0.5 - 0.5 * value / self.min
                } else {
                    0.5 + 0.5 * value / self.max
                }
            }
            _ => (value - self.min) / (self.max - self.min),
        };
        t.clamp(0.0, 1.0)
    }

    /// The colour of `value`; NaN has none.
    pub(crate) fn colour(&self, value: f64) -> Option<Rgb> {
        if value.is_nan() {
            return None;
        }
        let stops = match self.kind {
            ScaleKind::Diverging => &RDBU[..],
            ScaleKind::Sequential => &VIRIDIS[..],
        };
        Some(interpolate(stops, self.position(value)))
    }
}

/// ColorBrewer RdBu (9 classes), reversed so that low is blue.
pub(crate) const RDBU: [Rgb; 9] = [
    [0x21, 0x66, 0xac],
    [0x43, 0x93, 0xc3],
    [0x92, 0xc5, 0xde],
    [0xd1, 0xe5, 0xf0],
    [0xf7, 0xf7, 0xf7],
    [0xfd, 0xdb, 0xc7],
    [0xf4, 0xa5, 0x82],
    [0xd6, 0x60, 0x4d],
    [0xb2, 0x18, 0x2b],
];

/// Viridis at nine evenly spaced positions.
const VIRIDIS: [Rgb; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2d, 0x7b],
    [0x3b, 0x52, 0x8b],
    [0x2c, 0x72, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x28, 0xae, 0x80],
    [0x5e, 0xc9, 0x62],
    [0xad, 0xdc, 0x30],
    [0xfd, 0xe7, 0x25],
];

/// Piecewise-linear interpolation between evenly spaced colour stops, `t` in [0, 1].
fn interpolate(stops: &[Rgb], t: f64) -> Rgb {
    let x = t * (stops.len() - 1) as f64;
    let i = (x.floor() as usize).min(stops.len() - 2);
    let f = x - i as f64;
    let (a, b) = (stops[i], stops[i + 1]);
    std::array::from_fn(|c| (f64::from(a[c]) * (1.0 - f) + f64::from(b[c]) * f).round() as u8)
}

/// The `p`-quantile (0..=1) of the finite values, or None when there are none.
pub(crate) fn percentile(values: &[f64], p: f64) -> Option<f64> {
    let mut finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    finite.sort_unstable_by(f64::total_cmp);
    let x = p.clamp(0.0, 1.0) * (finite.len() - 1) as f64;
    let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
    Some(finite[lo] + (finite[hi] - finite[lo]) * (x - lo as f64))
}

/// How the values of a panel become colours, and what is drawn under the render to say so.
#[derive(Clone, Debug, PartialEq)]
pub enum Legend {
    /// A colour map, with a colour bar.
    Bar(ColourScale),
    /// A few distinct values, each with its own colour and a labelled swatch (for codes such
    /// as a status).
    Categories(Vec<Category>),
}

impl From<ColourScale> for Legend {
    fn from(scale: ColourScale) -> Self {
        Self::Bar(scale)
    }
}

/// One value of a categorical panel: points with exactly this value take this colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Category {
    pub value: f64,
    /// Shown beside the swatch.
    pub label: String,
    pub colour: Rgb,
}
