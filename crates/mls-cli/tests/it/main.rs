//! Integration tests of the `mlscurv` binary: each runs it in a temporary directory and
//! checks its output against analytic truth or an independent computation.

mod adaptive;
mod atomic;
mod attributes;
mod bad_input;
mod chunks;
mod columns;
mod common;
mod curvature_bunny;
mod e57;
mod eval;
mod eval_options;
mod file_normals;
mod help_flag;
mod info;
mod large_h;
mod las;
mod normals;
mod orient_default;
mod overwrite;
mod project;
mod readme;
mod reference;
mod render;
mod sphere;
mod streams;
mod tiled;
mod tiled_formats;
mod up_front;
