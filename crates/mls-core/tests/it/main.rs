//! mls-core integration tests: invariances, exact shapes, projection, whole-cloud evaluation.

mod adaptive;
mod adversarial;
mod buildings;
mod cloud;
mod clouds;
mod invariance;
mod jet;
mod normals;
mod projection;
mod stream;
mod surface;
