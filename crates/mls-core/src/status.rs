//! Per-point outcome: a failure at one point is data, not an abort.

/// Why no curvature could be computed at a point. The numeric codes are stable: they are
/// written to output files (0 is reserved for success).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum PointStatus {
    /// No sample lies within the kernel support of the point.
    NoNeighbours = 1,
    /// Fewer samples than the configured minimum lie within the support.
    TooFewNeighbours = 2,
    /// The weighted normal sum (Eq. 2) nearly cancels: n(x) is undefined, typically between
    /// two sheets with opposite normals or where the input normals are not consistently
    /// oriented.
    NormalUndefined = 3,
    /// |∇g| ≈ 0: the level set through the point has no defined normal.
    GradientVanishes = 4,
    /// The Amenta–Kil projection found no energy minimum along the normal line, or did not
    /// converge within its iteration budget.
    ProjectionFailed = 5,
    /// The query point itself has a NaN or infinite coordinate.
    InvalidQuery = 6,
    /// The input normal of this point could not be estimated (degenerate neighbourhood:
    /// too few or collinear neighbours).
    NormalEstimationFailed = 7,
    /// The point lies farther from the surface fitted to its neighbours than their residuals
    /// allow (beyond Tukey's cutoff, 4.685 robust standard deviations): a stray sample, not a
    /// sample of the surface (the jet without file normals).
    Outlier = 8,
}

impl PointStatus {
    /// Every status, for documentation and summaries.
    pub const ALL: [PointStatus; 8] = [
        Self::NoNeighbours,
        Self::TooFewNeighbours,
        Self::NormalUndefined,
        Self::GradientVanishes,
        Self::ProjectionFailed,
        Self::InvalidQuery,
        Self::NormalEstimationFailed,
        Self::Outlier,
    ];

    /// The stable numeric code written to files (never 0).
    pub fn code(self) -> u8 {
        self as u8
    }

    /// A short machine-friendly name.
    pub fn name(self) -> &'static str {
        match self {
            Self::NoNeighbours => "no_neighbours",
            Self::TooFewNeighbours => "too_few_neighbours",
            Self::NormalUndefined => "normal_undefined",
            Self::GradientVanishes => "gradient_vanishes",
            Self::ProjectionFailed => "projection_failed",
            Self::InvalidQuery => "invalid_query",
            Self::NormalEstimationFailed => "normal_estimation_failed",
            Self::Outlier => "outlier",
        }
    }

    /// A one-line description for users.
    pub fn description(self) -> &'static str {
        match self {
            Self::NoNeighbours => "no sample within the kernel support (isolated point)",
            Self::TooFewNeighbours => "fewer samples within the support than the minimum",
            Self::NormalUndefined => "weighted normals cancel: normal field undefined",
            Self::GradientVanishes => "gradient of g vanishes: level set has no normal",
            Self::ProjectionFailed => "MLS projection found no energy minimum or did not converge",
            Self::InvalidQuery => "query point has a non-finite coordinate",
            Self::NormalEstimationFailed => {
                "normal could not be estimated (degenerate neighbourhood)"
            }
            Self::Outlier => "far off the surface fitted to its neighbours (a stray sample)",
        }
    }
}

impl std::fmt::Display for PointStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Codes and names are written to output files: they are a file format, pinned here.
    /// Descriptions are for people: present and different for each status.
    #[test]
    fn codes_and_names_are_the_file_format() {
        assert_eq!(
            PointStatus::ALL.map(PointStatus::code),
            [1, 2, 3, 4, 5, 6, 7, 8]
        );
        assert_eq!(
            PointStatus::ALL.map(PointStatus::name),
            [
                "no_neighbours",
                "too_few_neighbours",
                "normal_undefined",
                "gradient_vanishes",
                "projection_failed",
                "invalid_query",
                "normal_estimation_failed",
                "outlier",
            ]
        );
        for s in PointStatus::ALL {
            assert_eq!(s.to_string(), s.name());
            assert!(s.description().len() > 20, "{s}: {}", s.description());
        }
        let mut descriptions = PointStatus::ALL.map(PointStatus::description).to_vec();
        descriptions.sort_unstable();
        descriptions.dedup();
        assert_eq!(descriptions.len(), PointStatus::ALL.len());
    }
}
