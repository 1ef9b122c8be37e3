//! The Gaussian kernel θ (Eq. 3) and its support.

use crate::error::ConfigError;

/// Where the Gaussian weight is truncated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cutoff {
    /// Samples farther than `factor · h` from the evaluation point are ignored.
    ///
    /// The neglected tail of the weight is `exp(-factor²)`: 1.2e-4 at 3h, 1.1e-7 at 4h,
    /// 1.4e-11 at 5h. Measured change of k1, k2 relative to the untruncated kernel (test
    /// `cutoff_cost`): 8.3e-2 at 3h, 1.8e-4 at 4h, 2.4e-8 at 5h, 8.9e-13 at 6h.
    Radius(f64),
    /// Every sample contributes. Exact to the definition; for verification.
    None,
}

impl Cutoff {
    /// The default, `5h`: curvature then matches the untruncated surface to about 2e-8
    /// relative (measured, see `docs/derivation.md`).
    pub const DEFAULT: Cutoff = Cutoff::Radius(5.0);
    /// The smallest accepted factor: below 2h the truncated kernel no longer resembles a
    /// Gaussian and the surface develops visible steps.
    pub const MIN_FACTOR: f64 = 2.0;
}

impl Default for Cutoff {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The Gaussian scale `h` with its truncation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    h: f64,
    inv_h2: f64,
    cutoff: Cutoff,
}

impl Kernel {
    /// The smallest accepted h. Between `MIN_H` and `MAX_H`, h², 1/h² and squared support
    /// radii are normal doubles; outside, rescale the coordinates.
    pub const MIN_H: f64 = 1e-150;
    /// The largest accepted h (see [`Kernel::MIN_H`]).
    pub const MAX_H: f64 = 1e150;

    /// A kernel of scale `h`, checked: `h` must be within `[MIN_H, MAX_H]`, a cutoff factor
    /// finite and at least [`Cutoff::MIN_FACTOR`].
    pub fn new(h: f64, cutoff: Cutoff) -> Result<Self, ConfigError> {
        if !(h.is_finite() && (Self::MIN_H..=Self::MAX_H).contains(&h)) {
            return Err(ConfigError::InvalidScale(h));
        }
        if let Cutoff::Radius(c) = cutoff
            && !(c.is_finite() && c >= Cutoff::MIN_FACTOR)
        {
            return Err(ConfigError::InvalidCutoff(c));
        }
        let inv_h2 = 1.0 / (h * h);
        Ok(Self { h, inv_h2, cutoff })
    }

    /// The Gaussian scale `h`.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// `1 / h²`.
    pub fn inv_h2(&self) -> f64 {
        self.inv_h2
    }

    /// The truncation.
    pub fn cutoff(&self) -> Cutoff {
        self.cutoff
    }

    /// The support radius, or `None` for an untruncated kernel.
    pub fn support_radius(&self) -> Option<f64> {
        match self.cutoff {
            Cutoff::Radius(c) => Some(c * self.h),
            Cutoff::None => None,
        }
    }

    /// θ = exp(−|x − q|² / h²) (Eq. 3), given the squared distance.
    pub fn weight(&self, dist2: f64) -> f64 {
        (-dist2 * self.inv_h2).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_parameters() {
        for h in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e-200] {
            assert!(Kernel::new(h, Cutoff::DEFAULT).is_err(), "h = {h}");
        }
        for c in [1.0, f64::NAN, f64::INFINITY] {
            assert!(Kernel::new(1.0, Cutoff::Radius(c)).is_err(), "c = {c}");
        }
        let k = Kernel::new(0.5, Cutoff::Radius(4.0)).unwrap();
        assert_eq!(k.support_radius(), Some(2.0));
        assert_eq!(k.cutoff(), Cutoff::Radius(4.0));
        let untruncated = Kernel::new(0.5, Cutoff::None).unwrap();
        assert_eq!(untruncated.cutoff(), Cutoff::None);
        assert_eq!(untruncated.support_radius(), None);
        assert!((k.weight(0.25) - (-1.0f64).exp()).abs() < 1e-16);
    }
}
