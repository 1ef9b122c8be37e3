//! Line charts: series with markers on linear or logarithmic axes, with a legend.

use std::path::Path;

use anyhow::{Context, Result, ensure};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters_backend::{BackendCoord, DrawingErrorKind};

use crate::text::{Backend, plotting_error};
use crate::{FONT, INK, Image, LABEL_SIZE, TICK_SIZE, TITLE_SIZE};

/// One named series of a line chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// An axis of a line chart.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub label: String,
    /// Logarithmic; points at or below 0 are then left out.
    pub log: bool,
}

impl Axis {
    pub fn linear(label: &str) -> Self {
        Self {
            label: label.to_owned(),
            log: false,
        }
    }

    pub fn log(label: &str) -> Self {
        Self {
            label: label.to_owned(),
            log: true,
        }
    }
}

/// A line chart of several series with markers, axis labels and a legend: for instance error
/// against sampling density. Points that cannot be drawn (NaN, or not positive on a log axis)
/// are left out.
pub fn line_chart_png(
    path: &Path,
    title: &str,
    x_axis: &Axis,
    y_axis: &Axis,
    series: &[Series],
    size: (u32, u32),
) -> Result<()> {
    let (log_x, log_y) = (x_axis.log, y_axis.log);
    let (x_label, y_label) = (x_axis.label.as_str(), y_axis.label.as_str());
    let drawable = |v: f64, log: bool| v.is_finite() && (!log || v > 0.0);
    let series: Vec<Series> = series
        .iter()
        .map(|s| Series {
            name: s.name.clone(),
            points: s
                .points
                .iter()
                .copied()
                .filter(|&(x, y)| drawable(x, log_x) && drawable(y, log_y))
                .collect(),
        })
        .collect();
    let all = || series.iter().flat_map(|s| s.points.iter().copied());
    ensure!(
        all().next().is_some(),
        "no drawable points for the chart {}",
        path.display()
    );
    let x = axis_range(all().map(|p| p.0), log_x);
    let y = axis_range(all().map(|p| p.1), log_y);

    let mut canvas = Image::new(size)?;
    {
        let root = canvas.drawing_area()?;
        let labels = (title, x_label, y_label);
        let result = match (log_x, log_y) {
            (false, false) => draw_chart(&root, labels, &series, x.0..x.1, y.0..y.1),
            (true, false) => draw_chart(&root, labels, &series, (x.0..x.1).log_scale(), y.0..y.1),
            (false, true) => draw_chart(&root, labels, &series, x.0..x.1, (y.0..y.1).log_scale()),
            (true, true) => draw_chart(
                &root,
                labels,
                &series,
                (x.0..x.1).log_scale(),
                (y.0..y.1).log_scale(),
            ),
        };
        result.with_context(|| format!("cannot draw the chart {}", path.display()))?;
        root.present().map_err(plotting_error)?;
    }
    canvas.write_png(path)
}

/// The data range with a margin: 5 % of the span on a linear axis, a factor 1.25 on a log one.
fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if log {
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo / 2.0, hi * 2.0)
        };
        (lo / 1.25, hi * 1.25)
    } else {
        let pad = if hi > lo {
            0.05 * (hi - lo)
        } else {
            1.0_f64.max(lo.abs())
        };
        (lo - pad, hi + pad)
    }
}

/// Okabe–Ito colours, distinguishable with the common colour-vision deficiencies.
const SERIES_COLOURS: [RGBColor; 7] = [
    RGBColor(0x00, 0x72, 0xb2),
    RGBColor(0xd5, 0x5e, 0x00),
    RGBColor(0x00, 0x9e, 0x73),
    RGBColor(0xcc, 0x79, 0xa7),
    RGBColor(0xe6, 0x9f, 0x00),
    RGBColor(0x56, 0xb4, 0xe9),
    RGBColor(0x00, 0x00, 0x00),
];

fn draw_chart<X, Y>(
    root: &DrawingArea<Backend<'_>, Shift>,
    (title, x_label, y_label): (&str, &str, &str),
    series: &[Series],
    x_range: X,
    y_range: Y,
) -> Result<()>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, TITLE_SIZE).into_font().color(&INK))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(x_range, y_range)
        .map_err(plotting_error)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .axis_desc_style((FONT, LABEL_SIZE).into_font().color(&INK))
        .label_style((FONT, TICK_SIZE).into_font().color(&INK))
        .x_label_formatter(&|v| format_number(*v))
        .y_label_formatter(&|v| format_number(*v))
        .light_line_style(RGBColor(240, 240, 240))
        .bold_line_style(RGBColor(210, 210, 210))
        .draw()
        .map_err(plotting_error)?;
    for (i, s) in series.iter().enumerate() {
        let colour = SERIES_COLOURS[i % SERIES_COLOURS.len()];
        let line = colour.stroke_width(2);
        chart
            .draw_series(LineSeries::new(s.points.iter().copied(), line))
            .map_err(plotting_error)?
            .label(s.name.as_str())
            .legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(-12, 0), (12, 0)], line)
                    + Marker {
                        at: (0, 0),
                        series: i,
                        colour,
                    }
            });
        chart
            .draw_series(s.points.iter().map(|&at| Marker {
                at,
                series: i,
                colour,
            }))
            .map_err(plotting_error)?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, LABEL_SIZE).into_font().color(&INK))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(plotting_error)?;
    Ok(())
}

/// The marker of a series at one point: circle, triangle, square, cross, then again.
///
/// Our own element rather than plotters' `DynElement`, which only works with a `'static`
/// backend, and a bitmap backend over a buffer is not.
struct Marker<C> {
    at: C,
    series: usize,
    colour: RGBColor,
}

impl<'a, C: 'a> PointCollection<'a, C> for &'a Marker<C> {
    type Point = &'a C;
    type IntoIter = std::iter::Once<&'a C>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.at)
    }
}

impl<C, DB: DrawingBackend> Drawable<DB> for Marker<C> {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut points: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some((x, y)) = points.next() else {
            return Ok(());
        };
        let fill = self.colour.filled();
        match self.series % 4 {
            0 => backend.draw_circle((x, y), 4, &fill, true),
            1 => backend.fill_polygon([(x, y - 6), (x - 6, y + 4), (x + 6, y + 4)], &fill),
            2 => backend.draw_rect((x - 4, y - 4), (x + 4, y + 4), &fill, true),
            _ => {
                let stroke = self.colour.stroke_width(2);
                backend.draw_line((x - 5, y - 5), (x + 5, y + 5), &stroke)?;
                backend.draw_line((x - 5, y + 5), (x + 5, y - 5), &stroke)
            }
        }
    }
}

/// A tick label: plain with few digits, or in `1e-5` form for very small or large numbers.
fn format_number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".to_owned()
    } else if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.1e}");
        s.replace(".0e", "e")
    } else {
        let s = format!("{v:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    }
}
