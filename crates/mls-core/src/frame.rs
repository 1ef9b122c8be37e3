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

#[cfg(test)]
mod tests {
    use super::*;

    /// The key interleaves the 21-bit cell indices x, y, z from the lowest bit up, over the
    /// cube `[−h, h]³`: its corners are the first and last cells.
    #[test]
    fn morton_key_interleaves_the_cells() {
        let h = 2.0;
        let cells = ((1u64 << 21) - 1) as f64;
        // The coordinate at the middle of cell `i` along an axis.
        let at = |i: f64| ((i + 0.5) / cells - 0.5) * 2.0 * h;
        let key = |x: f64, y: f64, z: f64| morton_key(&Point::new(at(x), at(y), at(z)), h);
        assert_eq!(key(0.0, 0.0, 0.0), 0);
        assert_eq!(key(1.0, 0.0, 0.0), 0b001);
        assert_eq!(key(0.0, 1.0, 0.0), 0b010);
        assert_eq!(key(0.0, 0.0, 1.0), 0b100);
        // Cell 0b101 along x: its bits 0 and 2 go to bits 0 and 6.
        assert_eq!(key(5.0, 0.0, 0.0), 0b100_0001);
        // y = 0b101 to bits 1 and 7, z = 0b011 to bits 2 and 5.
        assert_eq!(key(0.0, 5.0, 3.0), 1 << 1 | 1 << 7 | 1 << 2 | 1 << 5);
        let corner = Point::new(h, h, h);
        assert_eq!(morton_key(&corner, h), (1 << 63) - 1);
        assert_eq!(morton_key(&-corner, h), 0);
        // Outside the cube a coordinate is clamped to its face; a zero cube is one cell.
        assert_eq!(morton_key(&(corner * 3.0), h), (1 << 63) - 1);
        assert_eq!(
            morton_key(&corner, 0.0),
            key(cells / 2.0 - 0.5, cells / 2.0 - 0.5, cells / 2.0 - 0.5)
        );
    }

    #[test]
    fn a_frame_from_the_box_is_the_frame_of_the_points() {
        let points = [
            Point::new(500_000.0, -2.0, 7.0),
            Point::new(500_004.0, 6.0, 1.5),
            Point::new(500_001.0, 0.0, 3.0),
        ];
        let frame = Frame::of(&points);
        assert_eq!(frame.origin, Vector::new(500_002.0, 2.0, 4.25));
        assert_eq!(frame.half_extent, 4.0);
        let box_frame = Frame::of_box(
            Vector::new(500_000.0, -2.0, 1.5),
            Vector::new(500_004.0, 6.0, 7.0),
        );
        assert_eq!(box_frame, frame);
    }
}
