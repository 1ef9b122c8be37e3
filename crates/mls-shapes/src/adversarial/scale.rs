//! Scale and position: similarity images of a patch (offset by 10⁶, scaled by 10^±6), and h
//! far from the spacing.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::patch::{smooth_draft, smooth_patch, usual_cutoff};
use super::{AdversarialClass, AdversarialCloud, Draft, Expectation, from_draft};
use crate::math::{Point, Vector};

/// The base patch and its image under the similarity the class names (`Offset`,
/// `ScaledDown` or `ScaledUp`).
pub(super) fn similar(rng: &mut ChaCha8Rng, seed: u64, class: AdversarialClass) -> Draft {
    let draft = smooth_draft(rng, "the patch before the similarity");
    let base = AdversarialCloud {
        class,
        seed,
        ..from_draft(draft)
    };
    let (scale, offset, variant) = match class {
        AdversarialClass::ScaledDown => (1e-6, Vector::zeros(), "scaled by 1e-6"),
        AdversarialClass::ScaledUp => (1e6, Vector::zeros(), "scaled by 1e6"),
        _ => {
            let mut offset = Vector::zeros();
            for c in offset.iter_mut() {
                let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
                *c = sign * rng.random_range(0.5e6..2e6);
            }
            (1.0, offset, "translated by about 1e6")
        }
    };
    let points = base
        .points
        .iter()
        .zip(&base.normals)
        .map(|(p, n)| (Point::from(p.coords * scale + offset), *n))
        .collect();
    let mut draft = Draft::new(variant, points, base.h * scale);
    draft.cutoff = base.cutoff;
    draft.cutoff_free = false;
    draft.expectation = Expectation::Matches {
        base: Box::new(base),
        scale,
        offset,
    };
    draft
}

pub(super) fn mismatched_scale(rng: &mut ChaCha8Rng) -> Draft {
    let patch = smooth_patch(rng);
    let tiny = rng.random_bool(0.5);
    let extent = patch
        .points
        .iter()
        .map(|(p, _)| p.coords.amax())
        .fold(0.0, f64::max);
    let (h, variant) = if tiny {
        (patch.spacing * 1e-3, "h = 1e-3 spacings")
    } else {
        (extent.max(patch.spacing) * 1e3, "h = 1e3 extents")
    };
    let mut draft = Draft::new(variant, patch.points, h);
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}
