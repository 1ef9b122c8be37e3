//! mls-core integration tests: invariances, exact shapes, projection, whole-cloud evaluation.

mod adversarial;
mod clouds;
mod invariance;
mod normals;
mod projection;
mod surface;
