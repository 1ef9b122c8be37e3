//! Typed errors of the library. Per-point failures are not errors: see [`crate::PointStatus`].

/// Invalid parameters or input data when building a surface.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// `h` must be finite and within `[Kernel::MIN_H, Kernel::MAX_H]` = [1e-150, 1e150].
    #[error("Gaussian scale h must be finite and within [1e-150, 1e150], got {0}")]
    InvalidScale(f64),
    /// The cutoff factor must be finite and at least `Cutoff::MIN_FACTOR`.
    #[error("cutoff factor must be finite and at least {min}, got {0}", min = crate::Cutoff::MIN_FACTOR)]
    InvalidCutoff(f64),
    /// Points and normals must pair up one to one.
    #[error("{points} points but {normals} normals")]
    LengthMismatch {
        /// Number of points.
        points: usize,
        /// Number of normals.
        normals: usize,
    },
    /// A point has a NaN or infinite coordinate.
    #[error("point {index} has a non-finite coordinate")]
    NonFinitePoint {
        /// Index of the offending point.
        index: usize,
    },
    /// A normal is zero, NaN or infinite.
    #[error("normal {index}: {source}")]
    BadNormal {
        /// Index of the offending normal.
        index: usize,
        /// What is wrong with it.
        source: crate::math::NormalError,
    },
    /// The cloud is larger than the spatial index supports.
    #[error("too many points for the spatial index: {0} (at most {max})", max = u32::MAX)]
    TooManyPoints(usize),
    /// A neighbourhood size of zero was asked for.
    #[error("neighbourhood size k must be at least {min}, got {got}")]
    InvalidNeighbourCount {
        /// The smallest accepted value.
        min: usize,
        /// The value given.
        got: usize,
    },
}
