//! The image in memory that a figure is drawn into, and its output as a PNG.

use std::io::BufWriter;
use std::path::Path;

use ab_glyph::FontRef;
use anyhow::{Context, Result, ensure};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::colour::percentile;
use crate::splat::{Rect, Splats};
use crate::text::{Backend, FONT_BYTES, plotting_error, register_font};
use crate::view::{Camera, Fit};
use crate::{BACKGROUND, ColourScale, NO_VALUE, Rgb, View};

/// An RGB image in memory, 8 bits a channel, rows from the top: the splats are drawn into it
/// directly, text through plotters.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    /// `3 × width × height` bytes.
    rgb: Vec<u8>,
}

impl Image {
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colour at column `x` and row `y` (from the top), if inside.
    pub fn pixel(&self, x: u32, y: u32) -> Option<Rgb> {
        (x < self.width && y < self.height).then(|| {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
        })
    }

    pub(crate) fn new((width, height): (u32, u32)) -> Result<Self> {
        ensure!(width > 0 && height > 0, "empty image size {width}×{height}");
        let pixels = width as usize * height as usize;
        Ok(Self {
            width,
            height,
            rgb: BACKGROUND.repeat(pixels),
        })
    }

    pub(crate) fn drawing_area(&mut self) -> Result<DrawingArea<Backend<'_>, Shift>> {
        register_font()?;
        let inner = BitMapBackend::with_buffer_and_format(&mut self.rgb, (self.width, self.height))
            .map_err(plotting_error)?;
        let font =
            FontRef::try_from_slice(FONT_BYTES).context("the compiled-in font does not parse")?;
        Ok(Backend { inner, font }.into_drawing_area())
    }

    fn set(&mut self, x: i64, y: i64, colour: Rgb) {
        if (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&y) {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&colour);
        }
    }

    /// Draws the cloud into `rect`, scaled to fit, each point a disc of its colour.
    pub(crate) fn splat(
        &mut self,
        rect: Rect,
        cloud: &Splats<'_>,
        colours: &[Option<Rgb>],
        view: View,
    ) {
        let camera = Camera::new(view);
        let projected: Vec<Option<[f64; 3]>> = cloud
            .cloud
            .points
            .iter()
            .map(|p| p.iter().all(|c| c.is_finite()).then(|| camera.project(p)))
            .collect();
        let Some(fit) = Fit::new(rect, &projected, percentile(&cloud.reach, 0.5)) else {
            return;
        };
        let (w, h) = (rect.w as usize, rect.h as usize);
        let mut depth = vec![f64::NEG_INFINITY; w * h];
        for (i, q) in projected.iter().enumerate() {
            let Some(q) = q else { continue };
            let (cx, cy) = fit.pixel(q);
            let radius = fit.radius(cloud.reach[i]);
            let reach = radius.ceil() as i64;
            let shade = cloud
                .cloud
                .normals
                .map_or(1.0, |normals| camera.shade(&normals[i]));
            let base = colours[i].unwrap_or(NO_VALUE);
            let lit: Rgb = std::array::from_fn(|c| (f64::from(base[c]) * shade).round() as u8);
            let (px, py) = (cx.floor() as i64, cy.floor() as i64);
            for y in (py - reach).max(0)..=(py + reach).min(rect.h - 1) {
                for x in (px - reach).max(0)..=(px + reach).min(rect.w - 1) {
                    let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
                    let d2 = dx * dx + dy * dy;
                    if d2 > radius * radius {
                        continue;
                    }
                    // A sphere rather than a flat disc, so that overlapping neighbours meet
                    // along a line between them instead of one covering the other.
                    let z = q[2] + (radius * radius - d2).sqrt() / fit.scale;
                    let k = y as usize * w + x as usize;
                    if z > depth[k] {
                        depth[k] = z;
                        // Hatch the points without a value, so that grey cannot pass for a value.
                        let hatch = colours[i].is_none() && (rect.x + x + rect.y + y) % 6 < 2;
                        let colour = if hatch { lit.map(|c| c / 2 + 20) } else { lit };
                        self.set(rect.x + x, rect.y + y, colour);
                    }
                }
            }
        }
    }

    /// Fills `rect` with the colour map from `scale.min` (left) to `scale.max` (right).
    pub(crate) fn colour_bar(&mut self, rect: Rect, scale: &ColourScale) {
        for x in 0..rect.w {
            let value = scale.min + (scale.max - scale.min) * (x as f64 + 0.5) / rect.w as f64;
            let colour = scale.colour(value).unwrap_or(NO_VALUE);
            for y in 0..rect.h {
                self.set(rect.x + x, rect.y + y, colour);
            }
        }
    }

    /// Fills the "no value" swatch right of the bar.
    pub(crate) fn no_value_swatch(&mut self, bar: Rect) {
        let swatch = Rect {
            x: bar.x + bar.w + 14,
            y: bar.y,
            w: 14,
            h: bar.h,
        };
        self.fill(swatch, NO_VALUE, true);
    }

    /// Fills `rect` with `colour`, hatched as the points without a value are if `hatch`.
    pub(crate) fn fill(&mut self, rect: Rect, colour: Rgb, hatch: bool) {
        for y in rect.y..rect.y + rect.h {
            for x in rect.x..rect.x + rect.w {
                let dark = hatch && (x + y) % 6 < 2;
                self.set(
                    x,
                    y,
                    if dark {
                        colour.map(|c| c / 2 + 20)
                    } else {
                        colour
                    },
                );
            }
        }
    }

    /// Writes the image as a PNG, atomically: into a temporary file beside `path`, then
    /// renamed over it, so that `path` holds the whole picture or what it held before. A file
    /// that is replaced keeps its permissions; a new one gets those of any new file (0666 less
    /// the umask).
    ///
    /// # Errors
    /// Any I/O error, in a message naming `path`.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let context = || format!("cannot write {}", path.display());
        let dir = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        let mut builder = tempfile::Builder::new();
        // Readable by all like any other output file, not private as temporary files are.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let mut file = builder
            .prefix(".figure-")
            .suffix(".png.tmp")
            .tempfile_in(dir)
            .with_context(context)?;
        if let Ok(existing) = std::fs::metadata(path)
            && existing.is_file()
        {
            file.as_file()
                .set_permissions(existing.permissions())
                .with_context(context)?;
        }
        {
            let mut encoder =
                png::Encoder::new(BufWriter::new(file.as_file_mut()), self.width, self.height);
            encoder.set_color(png::ColorType::Rgb);
            encoder.set_depth(png::BitDepth::Eight);
            encoder.set_compression(png::Compression::High);
            let mut writer = encoder.write_header().with_context(context)?;
            writer.write_image_data(&self.rgb).with_context(context)?;
            writer.finish().with_context(context)?;
        }
        file.as_file().sync_all().with_context(context)?;
        file.persist(path).with_context(context)?;
        Ok(())
    }
}
