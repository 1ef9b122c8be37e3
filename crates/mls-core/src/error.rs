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
    /// A normal is zero, NaN or infinite.
    #[error("normal {index}: {source}")]
    BadNormal {
        /// Index of the offending normal.
        index: usize,
        /// What is wrong with it.
        source: crate::math::NormalError,
    },
    /// The points themselves are unusable.
    #[error(transparent)]
    Input(#[from] InputError),
}

/// What is wrong with a cloud's points, or with a neighbourhood size, whichever computation
/// was asked for: surface construction ([`ConfigError::Input`]) and normal estimation
/// ([`crate::normals::NormalsError::Input`]) check their input with the same
/// [`check_points`] and report it alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum InputError {
    /// A point has a NaN or infinite coordinate; neither the k-d tree nor any sum can use it.
    #[error("point {index} has a non-finite coordinate")]
    NonFinitePoint {
        /// Index of the first offending point.
        index: usize,
    },
    /// A point has a coordinate beyond ±[`MAX_COORDINATE`]: squared distances between such
    /// points overflow to infinity, and no spacing or weight can be formed from them.
    #[error(
        "point {index} has a coordinate beyond ±1e153, where squared distances between points overflow"
    )]
    CoordinateTooLarge {
        /// Index of the first offending point.
        index: usize,
    },
    /// The cloud is larger than the k-d tree (u32 item indices) supports.
    #[error("too many points for the spatial index: {0} (at most {max})", max = u32::MAX)]
    TooManyPoints(usize),
    /// A neighbourhood size below the minimum was asked for.
    #[error("neighbourhood size k must be at least {min}, got {got}")]
    InvalidNeighbourCount {
        /// The smallest accepted value.
        min: usize,
        /// The value given.
        got: usize,
    },
}

/// The largest coordinate magnitude accepted: the difference of two such coordinates, squared
/// and summed over three axes (1.2e307), stays below `f64::MAX` (1.8e308). Far beyond any
/// scan, and above the largest h (1e150), so every accepted h has clouds it can serve.
pub const MAX_COORDINATE: f64 = 1e153;

/// Checks a cloud for the spatial index: at most `u32::MAX` points, every coordinate finite
/// and within ±[`MAX_COORDINATE`] (the first offending point is named).
///
/// # Errors
/// [`InputError::TooManyPoints`], [`InputError::NonFinitePoint`] or
/// [`InputError::CoordinateTooLarge`].
pub fn check_points(points: &[crate::Point]) -> Result<(), InputError> {
    if points.len() > u32::MAX as usize {
        return Err(InputError::TooManyPoints(points.len()));
    }
    match points
        .iter()
        .position(|p| !p.iter().all(|c| c.abs() <= MAX_COORDINATE))
    {
        Some(index) if points[index].iter().all(|c| c.is_finite()) => {
            Err(InputError::CoordinateTooLarge { index })
        }
        Some(index) => Err(InputError::NonFinitePoint { index }),
        None => Ok(()),
    }
}
