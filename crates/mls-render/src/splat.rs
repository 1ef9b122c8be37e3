//! The splat renderer and the panel layout: the discs of each point, the bands for titles and
//! legends, and the legends' text.

use std::num::NonZeroUsize;

use anyhow::{Context, Result, anyhow, ensure};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rayon::prelude::*;

use crate::colour::percentile;
use crate::text::{Backend, plotting_error};
use crate::{
    Category, Cloud, ColourScale, FONT, Grid, INK, Image, LABEL_SIZE, NO_VALUE, PANEL_TITLE_SIZE,
    Rgb, TICK_SIZE, TITLE_SIZE, View,
};

/// A cloud with the world-space size of each point's disc, shared by all panels of a figure.
pub(crate) struct Splats<'a> {
    pub(crate) cloud: Cloud<'a>,
    /// Distance from each point to its [`SPLAT_NEIGHBOURS`]-th nearest neighbour, kept within
    /// a factor 2 of the median; NaN for points with a non-finite coordinate, and all NaN when
    /// the cloud has no extent.
    pub(crate) reach: Vec<f64>,
}

/// Neighbours per point for the disc size: the 4th neighbour lies one pitch away on square
/// and hexagonal grids, and a little further where random sampling left a gap.
const SPLAT_NEIGHBOURS: usize = 4;

impl<'a> Splats<'a> {
    pub(crate) fn new(cloud: Cloud<'a>) -> Result<Self> {
        let Cloud { points, normals } = cloud;
        let finite: Vec<usize> = (0..points.len())
            .filter(|&i| points[i].iter().all(|c| c.is_finite()))
            .collect();
        ensure!(
            !finite.is_empty(),
            "no points with finite coordinates to draw"
        );
        if let Some(n) = normals {
            ensure!(
                n.len() == points.len(),
                "{} normals for {} points",
                n.len(),
                points.len()
            );
        }
        let coords: Vec<[f64; 3]> = finite.iter().map(|&i| points[i]).collect();
        let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&coords)
            .map_err(|_| anyhow!("too many points ({}) for the k-d tree", coords.len()))?;
        // The point itself comes first, at distance 0.
        let wanted = NonZeroUsize::new(SPLAT_NEIGHBOURS + 1).context("neighbour count")?;
        // The queries dominate the time for a large cloud (a million points), and each is
        // independent: in parallel.
        let kth: Vec<f64> = coords
            .par_iter()
            .map(|p| {
                let hits = tree
                    .query(p)
                    .nearest_n::<SquaredEuclidean<f64>>(wanted)
                    .execute();
                hits.iter().map(|h| h.distance).fold(0.0, f64::max).sqrt()
            })
            .collect();
        let median = percentile(&kth, 0.5).unwrap_or(0.0);
        let mut reach = vec![f64::NAN; points.len()];
        if median > 0.0 {
            // Bounded so that a lone outlier does not become a blot, nor a duplicate vanish.
            for (&i, &d) in finite.iter().zip(&kth) {
                reach[i] = d.clamp(0.5 * median, 2.0 * median);
            }
        }
        Ok(Self { cloud, reach })
    }
}

/// A panel with borrowed data.
pub(crate) struct PanelRef<'a> {
    pub(crate) title: &'a str,
    pub(crate) values: &'a [f64],
    pub(crate) legend: LegendRef<'a>,
}

/// A [`Legend`](crate::Legend) borrowed.
#[derive(Clone, Copy)]
pub(crate) enum LegendRef<'a> {
    Bar(&'a ColourScale),
    Categories(&'a [Category]),
}

impl LegendRef<'_> {
    /// The colour of `value`; None for NaN, and for a value of no category.
    fn colour(self, value: f64) -> Option<Rgb> {
        match self {
            Self::Bar(scale) => scale.colour(value),
            Self::Categories(categories) => categories
                .iter()
                .find(|c| c.value == value)
                .map(|c| c.colour),
        }
    }
}

/// Height of the figure title band; none when the title is empty.
pub(crate) const TITLE_BAND: u32 = 40;
/// Height of the panel title band; none when the panel title is empty.
pub(crate) const PANEL_TITLE_BAND: u32 = 30;
/// Height of the colour-bar band under each render.
pub(crate) const LEGEND_BAND: u32 = 78;
/// Width of one entry (swatch and label) of a legend of categories.
const CATEGORY_WIDTH: i64 = 200;
/// Height of one row of a legend of categories; three fit in the legend band.
const CATEGORY_ROW: i64 = 22;
/// Disc radius as a multiple of the distance to the [`SPLAT_NEIGHBOURS`]-th neighbour: enough
/// to close the diagonal gaps of a square grid (0.71) and most gaps of random sampling.
pub(crate) const SPLAT_RADIUS: f64 = 1.0;

pub(crate) fn render_panels(
    name: &str,
    title: &str,
    cloud: &Splats<'_>,
    panels: &[PanelRef<'_>],
    view: View,
    grid: Grid,
) -> Result<Image> {
    let context = || format!("cannot draw {name}");
    for panel in panels {
        ensure!(
            panel.values.len() == cloud.cloud.points.len(),
            "panel `{}`: {} values for {} points ({name})",
            panel.title,
            panel.values.len(),
            cloud.cloud.points.len(),
        );
        if let LegendRef::Bar(scale) = panel.legend {
            scale.check().with_context(context)?;
        }
    }
    let title_band = if title.is_empty() { 0 } else { TITLE_BAND };
    let columns = grid.columns.max(1);
    let rows = (panels.len() as u32).div_ceil(columns);
    let (panel_width, panel_height) = grid.panel;
    let size = (
        panel_width
            .checked_mul(columns)
            .context("figure too wide")?,
        panel_height
            .checked_mul(rows)
            .and_then(|h| h.checked_add(title_band))
            .context("figure too tall")?,
    );
    let mut canvas = Image::new(size)?;
    let mut layouts = Vec::with_capacity(panels.len());
    for (i, panel) in panels.iter().enumerate() {
        let (row, column) = (i as u32 / columns, i as u32 % columns);
        let x0 = column * panel_width;
        let top = title_band + row * panel_height;
        let colours: Vec<Option<Rgb>> = panel
            .values
            .iter()
            .map(|&v| panel.legend.colour(v))
            .collect();
        let has_none = colours.iter().any(Option::is_none);
        let entries = match panel.legend {
            LegendRef::Bar(_) => 0,
            LegendRef::Categories(c) => c.len() + usize::from(has_none),
        };
        let layout = PanelLayout::new(
            x0,
            top,
            panel_width,
            top + panel_height,
            panel.title,
            entries,
        )
        .with_context(|| format!("{name} is too small for its panels"))?;
        canvas.splat(layout.render, cloud, &colours, view);
        match panel.legend {
            LegendRef::Bar(scale) => {
                canvas.colour_bar(layout.bar, scale);
                if has_none {
                    canvas.no_value_swatch(layout.bar);
                }
            }
            LegendRef::Categories(categories) => {
                for (k, category) in categories.iter().enumerate() {
                    canvas.fill(layout.category_swatch(k), category.colour, false);
                }
                if has_none {
                    canvas.fill(layout.category_swatch(categories.len()), NO_VALUE, true);
                }
            }
        }
        layouts.push((layout, has_none));
    }
    {
        let root = canvas.drawing_area()?;
        if title_band > 0 {
            let style = text_style(TITLE_SIZE, HPos::Center, VPos::Center);
            root.draw_text(title, &style, (size.0 as i32 / 2, title_band as i32 / 2))
                .map_err(plotting_error)
                .with_context(context)?;
        }
        for (panel, (layout, has_none)) in panels.iter().zip(&layouts) {
            draw_panel_text(&root, panel, layout, *has_none).with_context(context)?;
        }
        root.present().map_err(plotting_error)?;
    }
    Ok(canvas)
}

/// A rectangle in pixels: left, top, width, height.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rect {
    pub(crate) x: i64,
    pub(crate) y: i64,
    pub(crate) w: i64,
    pub(crate) h: i64,
}

/// Where the parts of one panel go.
struct PanelLayout {
    /// Centre of the panel title, when there is one.
    title_at: Option<(i32, i32)>,
    render: Rect,
    bar: Rect,
    /// Top left of the first entry of a legend of categories, and entries per row.
    categories: ((i64, i64), i64),
}

impl PanelLayout {
    /// The layout of a panel whose legend is a colour bar (`categories` 0) or that many
    /// categories.
    fn new(
        x0: u32,
        top: u32,
        width: u32,
        bottom: u32,
        title: &str,
        categories: usize,
    ) -> Result<Self> {
        let title_band = if title.is_empty() {
            0
        } else {
            PANEL_TITLE_BAND
        };
        let render_top = top + title_band;
        let legend_top = bottom
            .checked_sub(LEGEND_BAND)
            .filter(|&t| t >= render_top + 50 && width >= 120)
            .context("a panel needs at least 120 px width and 50 px for the render")?;
        let (x0, width) = (i64::from(x0), i64::from(width));
        // The bar spans 70 % of the panel width, and leaves room for the "no value" swatch
        // and its label after it.
        const SWATCH: i64 = 80;
        let bar_width = (width * 7 / 10).min(width - SWATCH - 50);
        let per_row = ((width - 20) / CATEGORY_WIDTH).max(1);
        let entries = categories as i64;
        let rows = (entries + per_row - 1) / per_row;
        ensure!(
            (rows * CATEGORY_ROW + 8) <= i64::from(LEGEND_BAND),
            "{categories} categories need {rows} rows of {per_row} in the legend, which holds 3; \
             make the panel wider"
        );
        let used = per_row.min(entries.max(1));
        Ok(Self {
            title_at: (title_band > 0)
                .then(|| ((x0 + width / 2) as i32, (top + title_band / 2) as i32)),
            render: Rect {
                x: x0,
                y: i64::from(render_top),
                w: width,
                h: i64::from(legend_top - render_top),
            },
            bar: Rect {
                x: x0 + (width - bar_width - SWATCH) / 2,
                y: i64::from(legend_top) + 8,
                w: bar_width,
                h: 14,
            },
            categories: (
                (
                    x0 + (width - used * CATEGORY_WIDTH) / 2 + 10,
                    i64::from(legend_top) + 8,
                ),
                per_row,
            ),
        })
    }

    /// The swatch of entry `k` of a legend of categories.
    fn category_swatch(&self, k: usize) -> Rect {
        let ((x0, y0), per_row) = self.categories;
        let k = k as i64;
        Rect {
            x: x0 + (k % per_row) * CATEGORY_WIDTH,
            y: y0 + (k / per_row) * CATEGORY_ROW,
            w: 14,
            h: 14,
        }
    }
}

fn text_style(size: f64, h: HPos, v: VPos) -> TextStyle<'static> {
    (FONT, size).into_font().color(&INK).pos(Pos::new(h, v))
}

/// Panel title, then the legend's text: the colour bar's frame, ticks, label and "no value"
/// swatch, or the categories' frames and labels.
fn draw_panel_text(
    root: &DrawingArea<Backend<'_>, Shift>,
    panel: &PanelRef<'_>,
    layout: &PanelLayout,
    has_nan: bool,
) -> Result<()> {
    if let Some(at) = layout.title_at {
        let style = text_style(PANEL_TITLE_SIZE, HPos::Center, VPos::Center);
        root.draw_text(panel.title, &style, at)
            .map_err(plotting_error)?;
    }
    let scale = match panel.legend {
        LegendRef::Bar(scale) => scale,
        LegendRef::Categories(categories) => {
            let labels = categories.iter().map(|c| c.label.as_str());
            let labels = labels.chain(has_nan.then_some("no value"));
            let style = text_style(TICK_SIZE, HPos::Left, VPos::Center);
            for (k, label) in labels.enumerate() {
                let swatch = layout.category_swatch(k);
                let (left, top) = (swatch.x as i32, swatch.y as i32);
                let (right, bottom) = ((swatch.x + swatch.w) as i32, (swatch.y + swatch.h) as i32);
                root.draw(&Rectangle::new([(left - 1, top - 1), (right, bottom)], INK))
                    .map_err(plotting_error)?;
                root.draw_text(label, &style, (right + 5, (top + bottom) / 2))
                    .map_err(plotting_error)?;
            }
            return Ok(());
        }
    };
    let bar = layout.bar;
    let (left, top, right, bottom) = (
        bar.x as i32,
        bar.y as i32,
        (bar.x + bar.w) as i32,
        (bar.y + bar.h) as i32,
    );
    root.draw(&Rectangle::new([(left - 1, top - 1), (right, bottom)], INK))
        .map_err(plotting_error)?;

    let ticks = Ticks::new(scale.min, scale.max);
    let tick_style = text_style(TICK_SIZE, HPos::Center, VPos::Top);
    for &value in &ticks.values {
        let x = left
            + ((value - scale.min) / (scale.max - scale.min) * f64::from(right - left)).round()
                as i32;
        root.draw(&PathElement::new(vec![(x, bottom), (x, bottom + 4)], INK))
            .map_err(plotting_error)?;
        root.draw_text(&ticks.label(value), &tick_style, (x, bottom + 7))
            .map_err(plotting_error)?;
    }
    let label = match ticks.exponent {
        0 => scale.label.clone(),
        e => format!("{} (×1e{e})", scale.label),
    };
    let label_style = text_style(LABEL_SIZE, HPos::Center, VPos::Top);
    root.draw_text(&label, &label_style, ((left + right) / 2, bottom + 27))
        .map_err(plotting_error)?;

    if has_nan {
        let x = right + 14;
        root.draw(&Rectangle::new([(x - 1, top - 1), (x + 14, bottom)], INK))
            .map_err(plotting_error)?;
        let style = text_style(TICK_SIZE, HPos::Left, VPos::Center);
        root.draw_text("no value", &style, (x + 19, (top + bottom) / 2))
            .map_err(plotting_error)?;
    }
    Ok(())
}

/// About five round tick values (1, 2 or 5 × 10^k apart) inside [min, max], labelled with a
/// common power of ten factored out when the numbers are very small or large.
pub(crate) struct Ticks {
    pub(crate) values: Vec<f64>,
    step: f64,
    /// The labels show `value / 10^exponent`.
    pub(crate) exponent: i32,
}

impl Ticks {
    pub(crate) fn new(min: f64, max: f64) -> Self {
        let raw = (max - min) / 5.0;
        let magnitude = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .into_iter()
            .map(|m| m * magnitude)
            // The tolerance keeps a span of exactly 5 steps (up to rounding) at 5 steps.
            .find(|&s| s >= raw * (1.0 - 1e-9))
            .unwrap_or(10.0 * magnitude);
        let first = (min / step).ceil() as i64;
        let last = (max / step).floor() as i64;
        let values = (first..=last).map(|k| k as f64 * step).collect();
        let largest = min.abs().max(max.abs());
        let exponent = if (1e-2..1e4).contains(&largest) {
            0
        } else {
            largest.log10().floor() as i32
        };
        Self {
            values,
            step,
            exponent,
        }
    }

    pub(crate) fn label(&self, value: f64) -> String {
        let scaled_step = self.step / 10f64.powi(self.exponent);
        let decimals = (-scaled_step.log10().floor()).max(0.0) as usize;
        let v = value / 10f64.powi(self.exponent);
        // Avoid "-0".
        let v = if v.abs() < scaled_step * 1e-6 { 0.0 } else { v };
        format!("{v:.decimals$}")
    }
}
