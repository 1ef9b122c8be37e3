//! One cloud, checked and indexed once: its points in the Morton order of a [`Frame`], relative
//! to the frame's origin, with one k-d tree. The spacing is measured on it and the MLS surface
//! is built from it ([`crate::MlsSurface::from_cloud`]), so a command sorts the points and builds
//! a tree once, not once per stage.

use kiddo::ImmutableKdTree;

use crate::error::{InputError, check_points};
use crate::frame::{Frame, morton_key};
use crate::math::Point;
use crate::normals::{
    NormalsError, SPACING_SAMPLE, SpacingStats, spacing_of_local, spacing_on_tree, stride,
};
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
        self.spacing_sampled(k, None, par)
    }

    /// The spacing statistics measured at [`SPACING_SAMPLE`] positions spread evenly over the
    /// cloud (every `⌈n / SPACING_SAMPLE⌉`-th in storage order, a Morton order), against all
    /// the cloud's points: the spacing h is derived from, at a fraction of the cost of
    /// [`Self::spacing_statistics`] on a large cloud, and bitwise that on a cloud of at most
    /// [`SPACING_SAMPLE`] points. `measured` says how many positions were measured.
    ///
    /// A measured point that coincides with another sends the measurement, as in
    /// [`Self::spacing_statistics`], to a tree of the distinct positions, sampled the same way;
    /// when no measured point has a duplicate, `duplicates` is 0 even if some point elsewhere
    /// has one (too few to move the median).
    ///
    /// # Errors
    /// As [`crate::normals::spacing_statistics`].
    pub fn spacing(&self, k: usize, par: Parallelism) -> Result<SpacingStats, NormalsError> {
        self.spacing_sampled(k, Some(SPACING_SAMPLE), par)
    }

    /// The statistics at every `⌈n / sample⌉`-th stored point, or at every point.
    pub(crate) fn spacing_sampled(
        &self,
        k: usize,
        sample: Option<usize>,
        par: Parallelism,
    ) -> Result<SpacingStats, NormalsError> {
        if k == 0 {
            return Err(InputError::InvalidNeighbourCount { min: 1, got: 0 }.into());
        }
        let n = self.len();
        // Exact duplicates share a Morton key, so most sit next to each other in storage
        // order: finding one there goes straight to the distinct positions. (Among tens of
        // thousands of copies of one point, each neighbour query of the tree path took
        // 100 µs before it could report them.)
        let adjacent_copies = (1..n).any(|s| self.local(s) == self.local(s - 1));
        if n >= 2 && !adjacent_copies {
            let k_eff = k.min(n - 1);
            let stride = sample.map_or(1, |m| stride(n, m));
            let local = |s| self.local(s);
            if let Some(stats) = spacing_on_tree(&self.tree, n, local, k_eff, stride, par, true) {
                return Ok(stats);
            }
        }
        spacing_of_local((0..n).map(|s| self.local(s)).collect(), k, sample, par)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vector;

    /// A sample is every stride-th stored point: the statistics equal a brute force over
    /// exactly those points, each against all the others.
    #[test]
    fn a_sampled_spacing_measures_every_stride_th_stored_point() {
        use crate::normals::square_grid_rms_distance;
        let n = 3_001;
        let points: Vec<Point> = (0..n)
            .map(|i| {
                let t = i as f64;
                // An irregular patch: a quasi-random pattern on a paraboloid.
                let (u, v) = ((t * 0.618_034).fract(), (t * 0.754_878).fract() * 1.3);
                Point::new(u, v, 0.2 * (u * u - v * v))
            })
            .collect();
        let cloud = IndexedCloud::new(&points, Parallelism::Sequential).unwrap();
        let k = 12;
        let stats = cloud
            .spacing_sampled(k, Some(100), Parallelism::Sequential)
            .unwrap();
        // ⌈3001/100⌉ = 31: stored points 0, 31, …, 2976.
        assert_eq!(stats.measured, 97);
        let rho = square_grid_rms_distance(k);
        let mut local: Vec<f64> = (0..n)
            .step_by(31)
            .map(|s| {
                let p = points[cloud.order[s] as usize];
                let mut d2: Vec<f64> = (0..n)
                    .filter(|&j| j != cloud.order[s] as usize)
                    .map(|j| (points[j] - p).norm_squared())
                    .collect();
                d2.sort_by(f64::total_cmp);
                (d2[..k].iter().sum::<f64>() / k as f64).sqrt() / rho
            })
            .collect();
        local.sort_by(f64::total_cmp);
        let median = local[local.len() / 2];
        assert!((stats.spacing / median - 1.0).abs() < 1e-12);
        assert!((stats.local_spacing.min / local[0] - 1.0).abs() < 1e-12);
        assert!((stats.local_spacing.max / local[96] - 1.0).abs() < 1e-12);
        // The whole cloud when the sample would hold it all.
        assert_eq!(
            cloud
                .spacing_sampled(k, Some(n), Parallelism::Sequential)
                .unwrap(),
            cloud
                .spacing_statistics(k, Parallelism::Sequential)
                .unwrap()
        );
    }

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
