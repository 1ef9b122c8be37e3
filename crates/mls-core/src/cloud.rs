//! One cloud, checked and indexed once: its points in the Morton order of a [`Frame`], relative
//! to the frame's origin, with one k-d tree. The spacing is measured on it and the MLS surface
//! is built from it ([`crate::MlsSurface::from_cloud`]), so a command sorts the points and builds
//! a tree once, not once per stage.

use kiddo::ImmutableKdTree;

use crate::error::{InputError, check_points};
use crate::frame::{Frame, morton_key};
use crate::math::Point;
use crate::normals::{NormalsError, SpacingStats, spacing_of_local, spacing_on_tree};
use crate::par::Parallelism;

/// A checked cloud in storage order with its k-d tree, over the points it borrows.
///
/// Storage order is the Morton order of the frame's cube, points with one key in input order:
/// the order [`crate::MlsSurface::with_frame`] stores its samples in, so a surface built from
/// the cloud is bitwise the one built from the points. The coordinates relative to the frame
/// are recomputed from the points when needed, not stored: 28 bytes a point fewer while the
/// normals are estimated.
#[derive(Debug)]
pub struct IndexedCloud<'a> {
    pub(crate) points: &'a [Point],
    pub(crate) frame: Frame,
    /// The input index of each stored point.
    pub(crate) order: Vec<u32>,
    /// Over the points relative to `frame.origin` in storage order: an item is a storage index.
    pub(crate) tree: ImmutableKdTree<f64, 3>,
}

impl<'a> IndexedCloud<'a> {
    /// Indexes `points` in their own frame ([`Frame::of`]).
    ///
    /// # Errors
    /// A non-finite coordinate, or more points than the tree's `u32` items can name.
    pub fn new(points: &'a [Point], par: Parallelism) -> Result<Self, InputError> {
        Self::with_frame(points, Frame::of(points), par)
    }

    /// Indexes `points` in `frame`: a part of a larger cloud indexed in the whole cloud's frame
    /// stores its points in the whole cloud's relative order (see [`Frame`]).
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn with_frame(
        points: &'a [Point],
        frame: Frame,
        par: Parallelism,
    ) -> Result<Self, InputError> {
        check_points(points)?;
        let mut keyed: Vec<(u64, u32)> = par.map(points.len(), 4096, |i| {
            (
                morton_key(&(points[i] - frame.origin), frame.half_extent),
                i as u32,
            )
        });
        // By key, then input index: a stable sort by key.
        par.sort_unstable(&mut keyed);
        let order: Vec<u32> = keyed.into_iter().map(|(_, i)| i).collect();
        let local: Vec<[f64; 3]> = par.map(order.len(), 4096, |s| {
            (points[order[s] as usize] - frame.origin).coords.into()
        });
        let tree = ImmutableKdTree::new_from_slice(&local)
            .map_err(|_| InputError::TooManyPoints(points.len()))?;
        Ok(Self {
            points,
            frame,
            order,
            tree,
        })
    }

    /// Stored point `s` relative to the frame's origin: the coordinates the tree holds.
    pub(crate) fn local(&self, s: usize) -> [f64; 3] {
        (self.points[self.order[s] as usize] - self.frame.origin)
            .coords
            .into()
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// Whether the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// The frame the points are stored in.
    pub fn frame(&self) -> Frame {
        self.frame
    }

    /// [`crate::normals::spacing_statistics`] of the cloud, bitwise: measured on the cloud's
    /// own tree when no two points coincide, otherwise (exact duplicates, which the statistics
    /// leave out) on a tree of the distinct positions, as that function does.
    ///
    /// # Errors
    /// As [`crate::normals::spacing_statistics`].
    pub fn spacing_statistics(
        &self,
        k: usize,
        par: Parallelism,
    ) -> Result<SpacingStats, NormalsError> {
        if k == 0 {
            return Err(InputError::InvalidNeighbourCount { min: 1, got: 0 }.into());
        }
        let n = self.len();
        if n >= 2 {
            let k_eff = k.min(n - 1);
            if let Some(stats) = spacing_on_tree(&self.tree, n, |s| self.local(s), k_eff, par, true)
            {
                return Ok(stats);
            }
        }
        spacing_of_local((0..n).map(|s| self.local(s)).collect(), k, par)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vector;

    /// Storage order is a Morton order of the points' own neighbourhoods: consecutive stored
    /// points are a few spacings apart, where consecutive points of a Fibonacci spiral (and
    /// of an order computed in the wrong frame, whose keys all clamp to one face of the cube)
    /// are across the sphere.
    #[test]
    fn storage_order_keeps_neighbours_together_far_from_the_origin() {
        let n = 4_000;
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let offset = Vector::new(1.0e3, -2.0e3, 5.0e2);
        let points: Vec<Point> = (0..n)
            .map(|i| {
                let z = 1.0 - (2 * i + 1) as f64 / n as f64;
                let r = (1.0 - z * z).sqrt();
                let t = golden * i as f64;
                Point::new(r * t.cos(), r * t.sin(), z) + offset
            })
            .collect();
        let spacing = (4.0 * std::f64::consts::PI / n as f64).sqrt();
        let cloud = IndexedCloud::new(&points, Parallelism::Sequential).unwrap();
        let mean_step = |order: &[u32]| {
            let steps = order
                .windows(2)
                .map(|w| (points[w[1] as usize] - points[w[0] as usize]).norm());
            steps.sum::<f64>() / (order.len() - 1) as f64
        };
        let input: Vec<u32> = (0..n as u32).collect();
        assert!(mean_step(&input) > 10.0 * spacing);
        let stored = mean_step(&cloud.order);
        assert!(
            stored < 3.0 * spacing,
            "mean step {stored}, spacing {spacing}"
        );
        assert_eq!((cloud.len(), cloud.is_empty()), (n, false));
        let empty = IndexedCloud::new(&[], Parallelism::Sequential).unwrap();
        assert_eq!((empty.len(), empty.is_empty()), (0, true));
        // The tree holds the stored points relative to the origin.
        let s = 1234;
        let local = cloud.local(s);
        let p = points[cloud.order[s] as usize];
        assert!((Point::from(local) + cloud.frame().origin - p).norm() < 1e-9);
    }
}
