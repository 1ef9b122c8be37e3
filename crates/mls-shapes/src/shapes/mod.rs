//! The analytic test surfaces.

mod bspline;
mod cylinder;
mod ellipsoid;
mod height_field;
mod saddle;
mod sphere;
mod torus;

pub use bspline::{BSplineBasis, BSplineSurface};
pub use cylinder::Cylinder;
pub use ellipsoid::Ellipsoid;
pub use height_field::{Bump, HeightField, HeightFieldConfig, Wave};
pub use saddle::Saddle;
pub use sphere::Sphere;
pub use torus::Torus;
