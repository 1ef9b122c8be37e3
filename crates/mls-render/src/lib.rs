//! Pictures of values on point clouds: each point a shaded splat coloured by its value, with a
//! colour bar (a diverging or sequential map with robust limits) or a legend of categories,
//! several panels to a figure; and line charts. Used by `cargo xtask paper` for the paper's
//! figures and by `mlscurv render`.
//!
//! The splat renderer is our own (an orthographic z-buffer of screen-space discs) and writes
//! straight into an RGB buffer; plotters then draws the text, tick marks and line charts into
//! the same buffer, and the `png` crate encodes it, atomically. Text uses Ubuntu Light,
//! compiled in from `epaint_default_fonts` and drawn with `ab_glyph`, so that building and
//! running this needs no system font library.
//!
//! ```
//! use mls_render::{Cloud, ColourScale, Panel, View, render};
//!
//! let points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
//! let values = vec![-1.0, 0.5, 1.0, f64::NAN];
//! let panel = Panel {
//!     title: String::new(),
//!     legend: ColourScale::robust_symmetric(&values, "mean curvature").into(),
//!     values,
//! };
//! let cloud = Cloud { points: &points, normals: None };
//! let image = render("Four points", cloud, &[panel], View::THREE_QUARTER, (300, 260), 1)?;
//! assert_eq!((image.width(), image.height()), (300, 300));
//! # Ok::<(), anyhow::Error>(())
//! ```
//!
//! Errors are `anyhow` errors with a message naming the file or panel: every caller (the xtask
//! and the CLI) only shows them.
//!
//! Set `FIGURES_TEST_DIR` when running the tests to keep their figures and look at them.

mod chart;
mod colour;
mod image;
mod splat;
#[cfg(test)]
mod tests;
mod text;
mod view;

pub use chart::{Axis, Series, line_chart_png};
pub use colour::{Category, ColourScale, Legend, ScaleKind};
pub use image::Image;
pub use view::{Up, View};

use std::path::Path;

use anyhow::{Context, Result, ensure};
use plotters::prelude::*;

use splat::{LegendRef, PanelRef, Splats, TITLE_BAND, render_panels};

/// The family name under which the compiled-in font is registered with plotters.
const FONT: &str = "sans-serif";
const TITLE_SIZE: f64 = 22.0;
const PANEL_TITLE_SIZE: f64 = 18.0;
const LABEL_SIZE: f64 = 15.0;
const TICK_SIZE: f64 = 13.0;

/// A colour, red, green and blue.
pub type Rgb = [u8; 3];
const BACKGROUND: Rgb = [255, 255, 255];
const INK: RGBColor = RGBColor(30, 30, 30);
/// Colour of points without a value (NaN), drawn hatched so that it cannot pass for a value.
pub const NO_VALUE: Rgb = [170, 170, 170];

/// A cloud to draw: positions, and normals (of either sign) for shading.
#[derive(Clone, Copy, Debug)]
pub struct Cloud<'a> {
    pub points: &'a [[f64; 3]],
    /// One per point; None draws flat colours.
    pub normals: Option<&'a [[f64; 3]]>,
}

/// One render of a figure with several: its title, one value per point, and how values
/// become colours.
#[derive(Clone, Debug, PartialEq)]
pub struct Panel {
    /// Shown above the render; none when empty.
    pub title: String,
    /// One per point of the cloud; NaN is "no value", drawn hatched grey.
    pub values: Vec<f64>,
    pub legend: Legend,
}

/// Renders a cloud coloured by `values` (NaN: hatched grey, "no value") with a title and a
/// colour bar, into a PNG of `size` pixels.
///
/// Orthographic projection along `view`, z-buffered discs sized from each point's distance to
/// its neighbours so that a sampled surface looks closed, and Lambert shading from the normals
/// when given, so that the shape reads at a glance.
pub fn splat_png(
    path: &Path,
    title: &str,
    cloud: Cloud<'_>,
    values: &[f64],
    scale: &ColourScale,
    view: View,
    size: (u32, u32),
) -> Result<()> {
    let panel = PanelRef {
        title: "",
        values,
        legend: LegendRef::Bar(scale),
    };
    let name = path.display().to_string();
    let splats = Splats::new(cloud).with_context(|| format!("cannot draw {name}"))?;
    let band = if title.is_empty() { 0 } else { TITLE_BAND };
    let grid = Grid {
        columns: 1,
        panel: (size.0, size.1.saturating_sub(band)),
    };
    render_panels(&name, title, &splats, &[panel], view, grid)?.write_png(path)
}

/// Several renders of one cloud side by side in one PNG, sharing the view: for instance k1, k2
/// and their errors. Each panel gets its own title and colour bar; `panel_size` is the size of
/// one panel; panels fill rows of `columns` (so that a figure shown at page width keeps them
/// large enough to read), and the figure's title band is added above.
pub fn splat_panels_png(
    path: &Path,
    title: &str,
    cloud: Cloud<'_>,
    panels: &[Panel],
    view: View,
    panel_size: (u32, u32),
    columns: usize,
) -> Result<()> {
    let name = path.display().to_string();
    render_named(&name, title, cloud, panels, view, panel_size, columns)?.write_png(path)
}

/// The figure of [`splat_panels_png`] as an image in memory, for a caller that checks it or
/// writes it itself ([`Image::write_png`]). A figure of one panel of `(w, h)` with a title is
/// `(w, h + 40)` pixels.
///
/// # Errors
/// No panels, no point with finite coordinates, values not one per point, a colour scale
/// without a finite range, or panels too small for their legends.
pub fn render(
    title: &str,
    cloud: Cloud<'_>,
    panels: &[Panel],
    view: View,
    panel_size: (u32, u32),
    columns: usize,
) -> Result<Image> {
    render_named(
        "the figure",
        title,
        cloud,
        panels,
        view,
        panel_size,
        columns,
    )
}

/// [`render`], with `name` in the error messages.
fn render_named(
    name: &str,
    title: &str,
    cloud: Cloud<'_>,
    panels: &[Panel],
    view: View,
    panel_size: (u32, u32),
    columns: usize,
) -> Result<Image> {
    ensure!(!panels.is_empty(), "no panels to draw in {name}");
    let splats = Splats::new(cloud).with_context(|| format!("cannot draw {name}"))?;
    let panels: Vec<PanelRef<'_>> = panels
        .iter()
        .map(|p| PanelRef {
            title: &p.title,
            values: &p.values,
            legend: match &p.legend {
                Legend::Bar(scale) => LegendRef::Bar(scale),
                Legend::Categories(categories) => LegendRef::Categories(categories),
            },
        })
        .collect();
    let grid = Grid {
        columns: panels.len().min(columns.max(1)) as u32,
        panel: panel_size,
    };
    render_panels(name, title, &splats, &panels, view, grid)
}

/// Panels laid out in rows of `columns`, each `panel` pixels, under the figure's title band.
#[derive(Clone, Copy, Debug)]
struct Grid {
    columns: u32,
    panel: (u32, u32),
}
