//! The jet at one query ([`Evaluator::jet_at`]): the degree-4 ladder of scales, the lead
//! scale, the least-error choice and, for heights only, the degree-2 candidates
//! ([`crate::jet`] holds the fits and the rules; this drives them over the evaluator's
//! neighbour search and buffers).

use super::Evaluator;
use crate::field::Sample;
use crate::jet::{self, JetConfig, JetPoint, NormalData};
use crate::math::{Point, UnitNormal, Vector};
use crate::status::PointStatus;

impl Evaluator<'_> {
    /// Curvature of a weighted polynomial jet at the world-space point `x`, with the scale
    /// chosen per point from the ladder of [`JetConfig`] (see [`crate::jet`]).
    pub fn jet_at(&mut self, x: &Point, config: &JetConfig) -> Result<JetPoint, PointStatus> {
        if !x.iter().all(|c| c.is_finite()) {
            return Err(PointStatus::InvalidQuery);
        }
        let local = x - self.surface.index.origin;
        let h = self.surface.kernel.h();
        let mut frame = None;
        let mut best: Option<JetPoint> = None;
        let mut fallback: Option<JetPoint> = None;
        self.ladder.clear();
        let mut agree_last = true;
        // Full-degree fits with too few equations to trust their own noise estimate: candidates
        // for the choice at the front of the ladder, outside its stopping rules.
        let mut early = 0;
        let mut failure = PointStatus::NoNeighbours;
        let (mut lo, mut hi) = ([f64::NEG_INFINITY; 2], [f64::INFINITY; 2]);
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
                failure = if inside == 0 {
                    PointStatus::NoNeighbours
                } else {
                    PointStatus::TooFewNeighbours
                };
                continue;
            }
            let frame = *frame.get_or_insert_with(|| {
                // The frame normal: the input normals averaged with the jet's weights. Across
                // a thin part the far sheet's normals are opposed and may turn that average
                // away from the query's own sheet; past 60° from the nearest sample's normal
                // (where the fit would refuse that sample's slope) only the normals facing the
                // nearest's way are averaged. Elsewhere, on folds sampled more coarsely than
                // they bend, the whole average is the better frame (docs/derivation.md).
                let inv_r2 = 1.0 / (radius * radius);
                let weighted = |s: &Sample, d2: f64| {
                    let t = (1.0 - d2 * inv_r2).max(0.0);
                    s.normal * (t * t * t)
                };
                // One pass for the average and the nearest sample (the first of equals).
                let mut sum = Vector::zeros();
                let (mut nearest, mut own) = (f64::INFINITY, Vector::zeros());
                for s in &self.support {
                    let d2 = (s.point - local).norm_squared();
                    if d2 < nearest {
                        (nearest, own) = (d2, s.normal);
                    }
                    sum += weighted(s, d2);
                }
                let sum = if sum.dot(&own) > 0.5 * sum.norm() * own.norm() {
                    sum
                } else {
                    self.support
                        .iter()
                        .filter(|s| s.normal.dot(&own) > 0.0)
                        .map(|s| weighted(s, (s.point - local).norm_squared()))
                        .sum()
                };
                UnitNormal::new(sum)
                    .ok()
                    .map(|n| jet::frame(&n.into_inner()))
            });
            let Some(frame) = frame else {
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
                self.handed_slope_weight(),
                &mut self.jet_scratch,
            ) else {
                if best.is_some() {
                    break;
                }
                failure = PointStatus::TooFewNeighbours;
                continue;
            };
            let Ok(p) = jet::jet_curvature(x, &frame, &fit) else {
                failure = PointStatus::GradientVanishes;
                break;
            };
            // Fits of a lower degree have a bias of another order: the ladder proper starts at
            // the first scale that determines the full degree, and a lower-degree fit is kept
            // only for a point where no scale does (sparse or boundary neighbourhoods).
            if best.is_none() && fit.degree < config.degree.clamp(2, 4) {
                fallback = fallback.or(Some(p));
                continue;
            }
            if best.is_none() && !jet::trusted(&fit) {
                self.ladder.push(p);
                early += 1;
                continue;
            }
            let k = [p.curvature.k1, p.curvature.k2];
            let mut agree = true;
            for i in 0..2 {
                lo[i] = lo[i].max(k[i] - config.confidence * p.sd[i]);
                hi[i] = hi[i].min(k[i] + config.confidence * p.sd[i]);
                agree &= lo[i] <= hi[i];
            }
            self.ladder.push(p);
            agree_last = agree;
            if !agree {
                break;
            }
            best = Some(p);
            if jet::past_optimum(&self.ladder[early..]) {
                break;
            }
        }
        let mut accepted = if best.is_some() {
            self.ladder.len() - usize::from(!agree_last)
        } else {
            early
        };
        // The ladder's choice with its estimated squared error; a lower-degree fallback (no
        // scale determined the full degree) has none, and any degree-2 candidate replaces it.
        let ladder = if accepted == 0 {
            fallback.map(|p| (f64::INFINITY, p)).ok_or(failure)
        } else {
            // The lead scale, from the support already gathered (it holds every smaller one),
            // in one round with the slopes weighted as the ladder's first fit found.
            if let (Some(lead), Some(Some(frame))) = (config.lead_radius(), frame) {
                let lead = jet::fit(
                    &self.support,
                    &local,
                    &frame,
                    lead * h,
                    config,
                    self.handed_slope_weight(),
                    &mut self.jet_scratch,
                )
                .filter(|f| f.degree == config.degree.clamp(2, 4) && jet::trusted(f));
                if let Some(Ok(p)) = lead.map(|f| jet::jet_curvature(x, &frame, &f)) {
                    self.ladder.insert(0, p);
                    accepted += 1;
                }
            }
            Ok(jet::choose_scale_with_mse(&self.ladder, accepted))
        };
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
        let wide = self.wide_frame(local, radii[last], frame);
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

    /// The frame of the estimated normals averaged over the support gathered, with the jet's
    /// weights at `radius`; across a thin part (the average over 60° from the ladder's normal)
    /// only those facing the ladder's frame; that frame where they cancel.
    fn wide_frame(
        &self,
        local: &Point,
        radius: f64,
        ladder: &(Vector, Vector, Vector),
    ) -> (Vector, Vector, Vector) {
        let inv_r2 = 1.0 / (radius * radius);
        let weighted = |s: &Sample| {
            let t = (1.0 - (s.point - local).norm_squared() * inv_r2).max(0.0);
            s.normal * (t * t * t)
        };
        let sum: Vector = self.support.iter().map(weighted).sum();
        let own = ladder.2;
        let sum = if sum.dot(&own) > 0.5 * sum.norm() {
            sum
        } else {
            self.support
                .iter()
                .filter(|s| s.normal.dot(&own) > 0.0)
                .map(weighted)
                .sum()
        };
        UnitNormal::new(sum).map_or(*ladder, |n| jet::frame(&n.into_inner()))
    }

    /// The λ the ladder's first fit found, for the fits after it; none where that fit had no
    /// slope to weigh (λ = 0), so that a later scale with slopes weighs its own.
    fn handed_slope_weight(&self) -> Option<f64> {
        self.ladder
            .first()
            .map(|p| p.fit.slope_weight)
            .filter(|&l| l > 0.0)
    }
}
