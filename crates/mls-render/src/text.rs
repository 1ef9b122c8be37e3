//! Text: the compiled-in font, and the plotters backend that draws text with it.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, ScaleFont};
use anyhow::{Result, anyhow, ensure};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind};

use crate::FONT;

/// The font: Ubuntu Light, from `epaint_default_fonts`.
pub(crate) const FONT_BYTES: &[u8] = epaint_default_fonts::UBUNTU_LIGHT;

/// Registers the compiled-in font with plotters, once: plotters measures text with it when it
/// lays out a chart.
pub(crate) fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    ensure!(ok, "the compiled-in font does not parse");
    Ok(())
}

/// The bitmap backend with our own text drawing.
///
/// plotters 0.3.7 draws `ab_glyph` text without each glyph's side bearing, which spaces the
/// letters unevenly ("ag ainst"); this draws every glyph at its pen position plus its bearing.
/// Everything else goes to the bitmap backend.
pub(crate) struct Backend<'a> {
    pub(crate) inner: BitMapBackend<'a>,
    pub(crate) font: FontRef<'static>,
}

type BackendResult<E> = Result<(), DrawingErrorKind<E>>;

impl Backend<'_> {
    /// Width and height of `text` at `size` pixels: the advances with kerning, and the line
    /// height.
    fn text_extent(&self, text: &str, size: f64) -> (f32, f32) {
        let font = self.font.as_scaled(size as f32);
        let mut width = 0.0;
        let mut previous = None;
        for c in text.chars() {
            let id = font.glyph_id(c);
            if let Some(p) = previous {
                width += font.kern(p, id);
            }
            width += font.h_advance(id);
            previous = Some(id);
        }
        (width, font.ascent() - font.descent())
    }
}

impl DrawingBackend for Backend<'_> {
    type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }

    fn ensure_prepared(&mut self) -> BackendResult<Self::ErrorType> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> BackendResult<Self::ErrorType> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        at: BackendCoord,
        colour: BackendColor,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_pixel(at, colour)
    }

    fn draw_line<S: plotters_backend::BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_line(from, to, style)
    }

    fn draw_rect<S: plotters_backend::BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_path(path, style)
    }

    fn draw_circle<S: plotters_backend::BackendStyle>(
        &mut self,
        centre: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.draw_circle(centre, radius, style, fill)
    }

    fn fill_polygon<S: plotters_backend::BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vertices: I,
        style: &S,
    ) -> BackendResult<Self::ErrorType> {
        self.inner.fill_polygon(vertices, style)
    }

    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> BackendResult<Self::ErrorType> {
        let colour = style.color();
        let (width, height) = self.text_extent(text, style.size());
        let dx = match style.anchor().h_pos {
            HPos::Left => 0.0,
            HPos::Center => -width / 2.0,
            HPos::Right => -width,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0.0,
            VPos::Center => -height / 2.0,
            VPos::Bottom => -height,
        };
        let font = self.font.as_scaled(style.size() as f32);
        let transform = style.transform();
        let mut pen = dx;
        let mut previous = None;
        let mut coverage = Vec::new();
        for c in text.chars() {
            let id = font.glyph_id(c);
            if let Some(p) = previous {
                pen += font.kern(p, id);
            }
            let glyph =
                id.with_scale_and_position(font.scale(), ab_glyph::point(pen, dy + font.ascent()));
            if let Some(outline) = font.outline_glyph(glyph) {
                let corner = outline.px_bounds().min;
                outline.draw(|x, y, c| {
                    coverage.push((corner.x as i32 + x as i32, corner.y as i32 + y as i32, c));
                });
            }
            pen += font.h_advance(id);
            previous = Some(id);
        }
        for (x, y, c) in coverage {
            let (x, y) = transform.transform(x, y);
            // A little more than the coverage, as the light font fades at small sizes.
            let alpha = colour.alpha * f64::from(c.clamp(0.0, 1.0).powf(0.75));
            self.inner.draw_pixel(
                (pos.0 + x, pos.1 + y),
                BackendColor {
                    alpha,
                    rgb: colour.rgb,
                },
            )?;
        }
        Ok(())
    }

    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        let (width, height) = self.text_extent(text, style.size());
        Ok((width.ceil() as u32, height.ceil() as u32))
    }
}

/// Plotters errors borrow the backend, so they become messages here.
pub(crate) fn plotting_error(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("plotting: {e}")
}
