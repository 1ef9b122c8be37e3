//! One cloud, checked and indexed once: its points in the Morton order of a [`Frame`], relative
//! to the frame's origin, with one k-d tree. The spacing is measured on it and the MLS surface
//! is built from it ([`crate::MlsSurface::from_cloud`]), so a command sorts the points and builds
//! a tree once, not once per stage.

use kiddo::ImmutableKdTree;

use crate::error::{InputError, check_points};
use crate::frame::{Frame, morton_key};
use crate::math::Point;
use crate::normals::{NormalsError, SpacingStats, spacing_of_local};
use crate::par::Parallelism;

/// A checked cloud in storage order with its k-d tree.
///
/// Storage order is the Morton order of the frame's cube, points with one key in input order:
/// the order [`crate::MlsSurface::with_frame`] stores its samples in, so a surface built from
/// the cloud is bitwise the one built from the points.
#[derive(Debug)]
pub struct IndexedCloud {
    pub(crate) frame: Frame,
    /// The input index of each stored point.
    pub(crate) order: Vec<u32>,
    /// The points relative to `frame.origin`, in storage order.
    pub(crate) local: Vec<[f64; 3]>,
    /// Over `local`: an item is a storage index.
    pub(crate) tree: ImmutableKdTree<f64, 3>,
}

impl IndexedCloud {
    /// Indexes `points` in their own frame ([`Frame::of`]).
    ///
    /// # Errors
    /// A non-finite coordinate, or more points than the tree's `u32` items can name.
    pub fn new(points: &[Point], par: Parallelism) -> Result<Self, InputError> {
        Self::with_frame(points, Frame::of(points), par)
    }

    /// Indexes `points` in `frame`: a part of a larger cloud indexed in the whole cloud's frame
    /// stores its points in the whole cloud's relative order (see [`Frame`]).
    ///
    /// # Errors
    /// As [`Self::new`].
    pub fn with_frame(
        points: &[Point],
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
            frame,
            order,
            local,
            tree,
        })
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
            if let Some(stats) =
                crate::normals::spacing_on_tree(&self.tree, &self.local, k_eff, par, true)
            {
                return Ok(stats);
            }
        }
        spacing_of_local(self.local.clone(), k, par)
    }
}
