//! The frame a surface stores its samples in: an origin near them, and the Morton order of a
//! cube around it. Shared by every surface built over part of one cloud (see [`Frame`]).

use crate::math::{Point, Vector, bounding_box_centre};

/// The internal coordinate frame of a surface: the origin its samples are stored relative to,
/// and the half-width of the cube their Morton order is taken in.
///
/// Two surfaces built over different subsets of one cloud with the same frame store their
/// common samples in the same relative order and at the same internal coordinates, so each
/// support sums in the same order and a result is bitwise the same in both: this is what lets a
/// cloud be evaluated tile by tile ([`crate::tiling`]) with the numbers of one whole run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// Subtracted from every coordinate, so that coordinates far from zero (georeferenced
    /// scans) do not cost precision in `x − q`.
    pub origin: Vector,
    /// The Morton key's cube is `[−half_extent, half_extent]³` around `origin`.
    pub half_extent: f64,
}

impl Frame {
    /// The frame of a cloud: its bounding-box centre, and the half-extent of the box about it.
    pub fn of(points: &[Point]) -> Self {
        let origin = bounding_box_centre(points);
        let half_extent = points
            .iter()
            .fold(0.0f64, |m, p| m.max((p.coords - origin).amax()));
        Self {
            origin,
            half_extent,
        }
    }

    /// The frame of a cloud given by its bounding box (`lo`, `hi`: the coordinate-wise minimum
    /// and maximum): bitwise [`Frame::of`] of any cloud with that box.
    pub fn of_box(lo: Vector, hi: Vector) -> Self {
        let origin = (lo + hi) * 0.5;
        let half_extent = (lo - origin).amax().max((hi - origin).amax());
        Self {
            origin,
            half_extent,
        }
    }
}

/// The Morton (Z-order) key of a point in the cube `[−half_extent, half_extent]³`, 21 bits per
/// axis interleaved.
pub(crate) fn morton_key(p: &Point, half_extent: f64) -> u64 {
    const CELLS: f64 = ((1u64 << 21) - 1) as f64;
    let scale = if half_extent > 0.0 {
        0.5 / half_extent
    } else {
        0.0
    };
    let cell = |c: f64| (((c * scale + 0.5) * CELLS).clamp(0.0, CELLS)) as u64;
    // Spreads the low 21 bits of v to every third bit.
    let spread = |v: u64| {
        let mut v = v & 0x1f_ffff;
        v = (v | v << 32) & 0x1f_0000_0000_ffff;
        v = (v | v << 16) & 0x1f_0000_ff00_00ff;
        v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
        v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
        (v | v << 2) & 0x1249_2492_4924_9249
    };
    spread(cell(p.x)) | spread(cell(p.y)) << 1 | spread(cell(p.z)) << 2
}
