//! The jet at one query ([`Evaluator::jet_at`]): the degree-4 ladder of scales, the lead
//! scale, the least-error choice and, for heights only, the degree-2 candidates
//! ([`crate::jet`] holds the fits and the rules; this drives them over the evaluator's
//! neighbour search and buffers).

use super::Evaluator;
use crate::jet::ladder::{self, Climb, Step};
use crate::jet::{self, JetConfig, JetPoint, NormalData};
use crate::math::{Point, Vector};
use crate::status::PointStatus;

impl Evaluator<'_> {
    /// Curvature of a weighted polynomial jet at the world-space point `x`, with the scale
    /// chosen per point from the ladder of [`JetConfig`] (see [`crate::jet`]).
    pub fn jet_at(&mut self, x: &Point, config: &JetConfig) -> Result<JetPoint, PointStatus> {
        if !x.iter().all(|c| c.is_finite()) {
            return Err(PointStatus::InvalidQuery);
        }
        self.jet_at_local(x, &(x - self.surface.index.origin), config)
    }

    /// [`Self::jet_at`] at `local`, in the internal frame (`x` only places the foot point).
    pub(crate) fn jet_at_local(
        &mut self,
        x: &Point,
        local: &Point,
        config: &JetConfig,
    ) -> Result<JetPoint, PointStatus> {
        let local = *local;
        let h = self.surface.kernel.h();
        let mut frame = None;
        let mut climb = Climb::new(std::mem::take(&mut self.ladder));
        let scales = config.scales.max(1);
        let radius_of = |j: usize| config.radius * h * std::f64::consts::SQRT_2.powi(j as i32);
        // The support is gathered for two scales at a time; the fit keeps its own radius.
        let mut gathered = 0.0;
        for j in 0..scales {
            let radius = radius_of(j);
            if radius > gathered {
                gathered = radius_of((j + 1).min(scales - 1));
                // In storage order, so that the fit's sums do not depend on the tree's shape
                // (a tile's tree differs from the whole cloud's; see [`Frame`]).
                self.support.clear();
                self.surface.index.samples_within_ordered(
                    &local,
                    gathered,
                    &mut self.hits,
                    &mut self.support,
                );
            }
            let r2 = radius * radius;
            let inside = self
                .support
                .iter()
                .filter(|s| (s.point - local).norm_squared() <= r2)
                .count();
            if inside < 6 {
                climb.too_few(inside);
                continue;
            }
            // The frame normal: the input normals averaged with the jet's weights. Across a
            // thin part the far sheet's normals are opposed and may turn that average away
            // from the query's own sheet; past 60° from the nearest sample's normal (where the
            // fit would refuse that sample's slope) only the normals facing the nearest's way
            // are averaged. Elsewhere, on folds sampled more coarsely than they bend, the
            // whole average is the better frame (docs/derivation.md).
            let frame = *frame.get_or_insert_with(|| {
                let own = ladder::nearest_normal(&self.support, &local);
                ladder::frame_of_normals(&self.support, &local, radius, &own)
            });
            let Some(frame) = frame else {
                self.ladder = climb.release();
                return Err(PointStatus::NormalUndefined);
            };
            // The ladder's first fit weighs the slopes in two rounds; the scales after it take
            // its λ in one (the sandwich covariance holds for any λ; docs/derivation.md).
            let Some(fit) = jet::fit(
                &self.support,
                &local,
                &frame,
                radius,
                config,
                climb.slope_weight(),
                &mut self.jet_scratch,
            ) else {
                match climb.no_fit() {
                    Step::Stop => break,
                    Step::Climb => continue,
                }
            };
            let Ok(p) = jet::jet_curvature(x, &frame, &fit) else {
                climb.no_curvature();
                break;
            };
            let full = fit.degree >= config.degree.clamp(2, 4);
            if climb.offer(p, &fit, full, config.confidence) == Step::Stop {
                break;
            }
        }
        // The lead scale, from the support already gathered (it holds every smaller one), in
        // one round with the slopes weighted as the ladder's first fit found.
        let lead = match (config.lead_radius(), frame) {
            (Some(lead), Some(Some(frame))) if climb.has_candidates() => jet::fit(
                &self.support,
                &local,
                &frame,
                lead * h,
                config,
                climb.slope_weight(),
                &mut self.jet_scratch,
            )
            .filter(|f| f.degree == config.degree.clamp(2, 4) && jet::trusted(f))
            .and_then(|f| jet::jet_curvature(x, &frame, &f).ok()),
            _ => None,
        };
        // The ladder's choice with its estimated squared error; a lower-degree fallback (no
        // scale determined the full degree) has none, and any degree-2 candidate replaces it.
        let (buffer, ladder) = climb.choose(lead);
        self.ladder = buffer;
        match frame {
            // The degree-2 candidates, also where the ladder stopped on its bias (under noise a
            // wild small-support fit can stop it there), but not where the ladder's predicted
            // error is already below what matters (clean and quantized data).
            Some(Some(frame))
                if config.quadratic
                    && config.normals == NormalData::Ignore
                    && !ladder
                        .as_ref()
                        .is_ok_and(|(m, p)| m.is_finite() && jet::resolved(p, h)) =>
            {
                let mse = ladder.as_ref().map_or(f64::INFINITY, |(m, _)| *m);
                match self.quadratic_at(x, &local, &frame, h)? {
                    Some((m, p)) if m < mse => Ok(p),
                    _ => ladder.map(|(_, p)| p),
                }
            }
            _ => ladder.map(|(_, p)| p),
        }
    }

    /// The degree-2 candidate of least estimated squared error at `x` (`local` in the
    /// internal frame), over the supports of [`jet::QUADRATIC_RADIUS`] and after, each with the
    /// leak of the cubic and quartic terms predicted from a degree-4 fit on the largest; `None`
    /// where none is determined, [`PointStatus::Outlier`] where the query lies beyond the
    /// robust cutoff of the largest support's plain fit.
    fn quadratic_at(
        &mut self,
        x: &Point,
        local: &Point,
        frame: &(Vector, Vector, Vector),
        h: f64,
    ) -> Result<Option<(f64, JetPoint)>, PointStatus> {
        // Arrays, not vectors: after warm-up no query allocates.
        let radii: [f64; jet::QUADRATIC_SCALES] = std::array::from_fn(|j| {
            jet::QUADRATIC_RADIUS * h * std::f64::consts::SQRT_2.powi(j as i32)
        });
        let Some(&top) = radii.last() else {
            return Ok(None);
        };
        self.support.clear();
        self.surface
            .index
            .samples_within_ordered(local, top, &mut self.hits, &mut self.support);
        // The largest support within the sample budget (the first in any case).
        let mut counts = [0usize; jet::QUADRATIC_SCALES];
        for s in &self.support {
            let d2 = (s.point - local).norm_squared();
            for (c, r) in counts.iter_mut().zip(&radii) {
                *c += usize::from(d2 <= r * r);
            }
        }
        let last = counts
            .iter()
            .rposition(|&c| c <= jet::QUADRATIC_MAX_SAMPLES)
            .unwrap_or(0);
        // The frame turned to the normal of the largest support's plain fit: the ladder's frame
        // comes from the estimated normals near the query, which heavy noise may tilt, and the
        // circles hold in the surface's own frame. A stray query off the surface has few near
        // samples, with normals its own offset spoiled, and may get a frame across the surface
        // (a height field seen edge-on, which no turn recovers): where the ladder's normal is
        // over 45° from the normals averaged over the whole support, or the fit in its frame
        // finds the surface steeper than 45°, the fit starts from that average instead.
        let wide =
            ladder::frame_of_normals(&self.support, local, radii[last], &frame.2).unwrap_or(*frame);
        let tilted_in = |this: &mut Self, frame: &(Vector, Vector, Vector)| {
            jet::quadratic(
                &this.support,
                local,
                frame,
                radii[last],
                None,
                &mut this.quadratic_scratch,
            )
            .filter(|t| t.fit.coefficients[1].hypot(t.fit.coefficients[2]) <= 1.0)
        };
        let near = frame.2.dot(&wide.2) >= std::f64::consts::FRAC_1_SQRT_2;
        let (frame, tilted) = match near.then(|| tilted_in(self, frame)).flatten() {
            Some(t) => (*frame, t),
            None => match tilted_in(self, &wide) {
                Some(t) => (wide, t),
                None => return Ok(None),
            },
        };
        let tilted = tilted.fit;
        let frame = &frame;
        let (t1, t2, n) = frame;
        let turned = n - t1 * tilted.coefficients[1] - t2 * tilted.coefficients[2];
        let frame = &jet::frame(&turned.normalize());
        // Robust weights from the largest support's plain fit: far samples (outliers) weigh
        // nothing in every fit after it, the query's own included.
        let Some(plain) = jet::quadratic(
            &self.support,
            local,
            frame,
            radii[last],
            None,
            &mut self.quadratic_scratch,
        ) else {
            return Ok(None);
        };
        let cut = jet::robust_weights(
            &self.support,
            local,
            frame,
            &plain,
            &mut self.robust,
            &mut self.quadratic_scratch,
        );
        // The query sits at the frame's origin: its residual is the fit's height there.
        if cut > 0.0 && !(plain.fit.coefficients[0].abs() < cut) {
            return Err(PointStatus::Outlier);
        }
        let robust = Some(&self.robust[..]);
        let mut fits: [Option<jet::QuadraticFit>; jet::QUADRATIC_SCALES] =
            [None; jet::QUADRATIC_SCALES];
        for (fit, &r) in fits.iter_mut().zip(&radii[..=last]) {
            *fit = jet::quadratic(
                &self.support,
                local,
                frame,
                r,
                robust,
                &mut self.quadratic_scratch,
            );
        }
        // The terms beside the circles of the largest support's own fit.
        let Some(top) = fits[last] else {
            return Ok(None);
        };
        let Some(high) = jet::high_terms(
            &self.support,
            local,
            frame,
            radii[last],
            &top.circles,
            robust,
            &mut self.quadratic_scratch,
        ) else {
            return Ok(None);
        };
        let mut best: Option<(f64, JetPoint)> = None;
        for jet::QuadraticFit {
            fit, sensitivity, ..
        } in fits.into_iter().flatten()
        {
            let leak = sensitivity.leak(&high);
            if let Some((m, p)) = jet::quadratic_candidate(x, frame, &fit, &leak)
                && best.as_ref().is_none_or(|(b, _)| m < *b)
            {
                best = Some((m, p));
            }
        }
        Ok(best)
    }
}
