//! Closed-form curvature of the Amenta–Kil MLS point-set surface, after Yang & Qian,
//! *Direct Computing of Surface Curvatures for Point-Set Surfaces* (2007).
//!
//! From points `q_i` with oriented unit normals `v_i` and one Gaussian scale `h`, the normal
//! field n(x) (Eq. 2) and the energy e (Eq. 4) define the MLS surface as the zero set of g
//! (Eq. 5, 7). This crate evaluates g, its gradient and Hessian in closed form ([`field`]),
//! turns them into curvature ([`curvature()`]), projects points onto the surface
//! ([`projection`]), and does both over whole clouds ([`MlsSurface`]), at once or chunk by
//! chunk ([`stream`]).
//!
//! **Sign convention.** Curvature is positive where the surface bends away from the oriented
//! normal: a unit sphere with outward normals has `k1 = k2 = mean = gauss = 1`;
//! `mean = (k1 + k2)/2`, `k1 ≥ k2`. Flipping every normal flips `k1`, `k2` and `mean`, not
//! `gauss`.
//!
//! Architecture invariant: this crate does no I/O and holds no generic dual-number code.

pub mod adaptive;
pub mod cloud;
pub mod curvature;
pub mod error;
pub mod field;
mod frame;
pub mod jet;
pub mod kernel;
pub mod kernels;
pub mod math;
pub mod normals;
pub mod par;
pub mod projection;
pub mod status;
pub mod stream;
pub mod surface;
pub mod tiling;

pub use adaptive::{
    AdaptiveConfig, AdaptivePoint, AdaptiveResult, AdaptiveSurface, Location, adaptive_curvature,
    correct_shrinkage,
};
pub use cloud::IndexedCloud;
pub use curvature::{Curvature, curvature};
pub use error::{ConfigError, InputError, check_points};
pub use field::{Implicit, NormalField, Sample};
pub use jet::{JetConfig, JetFit, JetPoint, NormalData};
pub use kernel::{Cutoff, Kernel};
pub use math::{Matrix, Point, UnitNormal, Vector};
pub use normals::{
    EstimatedNormals, NormalsConfig, NormalsError, Orientation, estimate_normals,
    orientation_consistency,
};
pub use projection::{LineDerivatives, ProjectionConfig};
pub use status::PointStatus;
pub use stream::DEFAULT_CHUNK;
pub use surface::{
    Evaluator, Frame, MlsConfig, MlsSurface, Parallelism, PointResult, SurfacePoint,
};

/// The README's Rust example, compiled and run as a doctest so that it cannot drift.
#[doc = include_str!("../../../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
