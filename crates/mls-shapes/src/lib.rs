//! Analytic test surfaces with exact normals and exact principal curvatures and directions,
//! samplers and noise: the shared ground truth for the tests, benches and xtask of
//! mls-curvature. Unpublished; deliberately independent of `mls-core`, so it can judge it.
//!
//! # Conventions
//!
//! * Normals are unit and outward: away from the enclosed volume for closed shapes, the `+z`
//!   side for height-field-like surfaces ([`Saddle`], [`HeightField`], the B-spline patches).
//! * Principal curvatures are the eigenvalues of the Weingarten map `W = dN` (not `−dN`):
//!   positive where the surface bends away from the normal. A sphere of radius `R` has
//!   `k1 = k2 = 1/R`; a cylinder `1/R` and `0`. Always `k1 >= k2`,
//!   `mean = (k1 + k2)/2`, `gauss = k1 k2`.
//! * Principal directions `d1`, `d2` are unit, tangent and right-handed with the normal:
//!   `d1 × d2 = normal`. Their signs are arbitrary.
//!
//! # Example
//!
//! ```
//! use mls_shapes::{ParametricSurface, Torus, differential_geometry, grid};
//!
//! let torus = Torus::new(2.0, 0.5);
//! // Closed form and automatic differentiation agree.
//! let closed = torus.at(0.3, 0.0);
//! let ad = differential_geometry(&torus, 0.3, 0.0);
//! assert!((closed.k1 - 2.0).abs() < 1e-12 && (ad.k1 - 2.0).abs() < 1e-12);
//! assert!((ad.k2 - 1.0 / 2.5).abs() < 1e-12); // outer equator: cos φ / (R + r cos φ)
//! // Both torus parameters are periodic, so the grid has no duplicated seam.
//! assert_eq!(grid(&torus, 16, 8).len(), 128);
//! ```
#![warn(missing_docs)]

pub mod adversarial;
mod math;
mod noise;
mod parametric;
mod sampling;
pub mod scene;
pub mod shapes;
mod surface_point;

pub use adversarial::{AdversarialClass, AdversarialCloud};
pub use math::{Matrix3, Point, Scalar, Vector, tangent_basis};
pub use noise::{add_position_noise, perturb_normals};
pub use parametric::{
    IntervalKind, Orientation, ParamInterval, ParametricSurface, Projection, SurfaceDerivatives,
    closest_point_newton, closest_point_search, derivatives, differential_geometry, position,
};
pub use sampling::{
    Sample, fibonacci_sphere, grid, jittered_grid, normals, points, random, random_area_uniform,
    surface_points,
};
pub use scene::{Area, Scan, Scene, SceneConfig, SceneError, ScenePoint, SurfaceClass};
pub use shapes::{
    BSplineBasis, BSplineSurface, Bump, Cylinder, Ellipsoid, HeightField, HeightFieldConfig,
    Saddle, Sphere, Torus, Wave,
};
pub use surface_point::SurfacePoint;
