//! Integration tests of the `mlscurv` binary: each runs it in a temporary directory and
//! checks its output against analytic truth or an independent computation.

mod adaptive;
mod atomic;
mod bad_input;
mod chunks;
mod columns;
mod common;
mod curvature_bunny;
mod eval;
mod info;
mod normals;
mod project;
mod sphere;
