//! Spatial tiles with halos, for clouds evaluated a part at a time (out of core, or on
//! several machines).
//!
//! A result at a point depends only on the samples within its *reach* ([`reach`]): the
//! kernel's support, the jet's largest radius, plus the neighbourhoods of those samples'
//! normals when they are estimated. A tile is a box of the cloud; it is evaluated at its own
//! points (its *core*) from a surface built over the core and its *halo*, every point within
//! the reach of the box. Built in the whole cloud's [`Frame`](crate::surface::Frame), that
//! surface gives each core point bitwise its result in one whole run.
//!
//! The plan is made from counts alone, so that it can be built in one streaming pass over a
//! file of any size: a [`Grid`] of cells over the bounding box counts the points per cell, and
//! [`TilePlan::new`] halves the box along its longest side at the count's median plane until
//! every tile with its halo holds at most a given number of points. A point belongs to the
//! tile of its cell ([`TilePlan::tile_of`]), and to the halo of every other tile whose box
//! lies within the reach ([`TilePlan::tiles_near`]).

use crate::jet::JetConfig;
use crate::kernel::Cutoff;
use crate::math::{Point, Vector};

/// The reach of the normal estimation's neighbourhood, in units of h: its 16 nearest
/// neighbours lie within about 1.1 h at the default scale (`h` = 2 × spacing; the 16th
/// neighbour of a uniform sample is at `√(16/π)` spacings), and within 3 h on scan lines up to
/// 7 times denser along than across.
pub const NORMALS_REACH: f64 = 3.0;

/// How far from a point the samples that decide its result can lie: the jet's largest radius
/// (`jet`), or the kernel's support (`cutoff`, for the paper's surface), plus
/// [`NORMALS_REACH`] × h when the normals are estimated from the points. `None` for an
/// untruncated kernel, which reaches everywhere.
pub fn reach(
    h: f64,
    cutoff: Cutoff,
    jet: Option<&JetConfig>,
    estimated_normals: bool,
) -> Option<f64> {
    let evaluation = match (jet, cutoff) {
        (Some(jet), _) => jet.reach_radius() * h,
        (None, Cutoff::Radius(c)) => c * h,
        (None, Cutoff::None) => return None,
    };
    let normals = if estimated_normals {
        NORMALS_REACH * h
    } else {
        0.0
    };
    // A point is given to the tile of its cell, and the cells are rounded boxes: a margin of a
    // millionth keeps a sample at exactly the reach inside the halo.
    Some((evaluation + normals) * (1.0 + 1e-6))
}

/// Why a plan cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TilingError {
    /// The box is empty or not finite.
    #[error("the bounding box {lo:?} to {hi:?} is not a finite box")]
    BadBox { lo: [f64; 3], hi: [f64; 3] },
    /// A single cell with its halo holds more points than a tile may.
    #[error(
        "{points} points lie within the reach {reach} of one cell of side {cell}, more than the \
         {capacity} a tile may hold: the memory budget is too small for the neighbourhoods"
    )]
    TooDense {
        points: u64,
        capacity: u64,
        cell: f64,
        reach: f64,
    },
}

/// A regular grid of cubic cells over a bounding box, for counting points.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    lo: Vector,
    cell: f64,
    dims: [usize; 3],
}

impl Grid {
    /// Cubic cells over the box `lo`..`hi`, at most about `max_cells` of them (at least one
    /// per axis).
    pub fn new(lo: Vector, hi: Vector, max_cells: usize) -> Result<Self, TilingError> {
        let extent = hi - lo;
        if !(extent.iter().all(|e| e.is_finite() && *e >= 0.0) && lo.iter().all(|c| c.is_finite()))
        {
            return Err(TilingError::BadBox {
                lo: lo.into(),
                hi: hi.into(),
            });
        }
        let max_cells = max_cells.max(1) as f64;
        // Cells of side `c` over the box: ∏ ⌈e_i / c⌉ ≤ max_cells. Start from the volume (or
        // the area of a flat box) and grow c until the count fits.
        let positive: Vec<f64> = extent.iter().copied().filter(|&e| e > 0.0).collect();
        let mut cell = if positive.is_empty() {
            1.0
        } else {
            let d = positive.len() as f64;
            positive.iter().product::<f64>().powf(1.0 / d) / max_cells.powf(1.0 / d)
        };
        let dims = |c: f64| extent.map(|e| ((e / c).ceil() as usize).max(1));
        while dims(cell).iter().map(|&d| d as f64).product::<f64>() > max_cells {
            cell *= 1.01;
        }
        Ok(Self {
            lo,
            cell,
            dims: dims(cell).into(),
        })
    }

    /// Side of a cell.
    pub fn cell(&self) -> f64 {
        self.cell
    }

    /// Cells per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// Whether the grid has no cells (never: every axis has at least one).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The cell of `p`, per axis; points outside the box go to the nearest cell.
    pub fn cell_of(&self, p: &Point) -> [usize; 3] {
        std::array::from_fn(|i| {
            let c = ((p[i] - self.lo[i]) / self.cell).floor();
            if c > 0.0 {
                (c as usize).min(self.dims[i] - 1)
            } else {
                0
            }
        })
    }

    /// The linear index of a cell (x fastest).
    pub fn index(&self, c: [usize; 3]) -> usize {
        c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])
    }

    /// The linear index of the cell of `p`.
    pub fn index_of(&self, p: &Point) -> usize {
        self.index(self.cell_of(p))
    }

    /// The world box of cells `a..b` per axis; the outermost cells extend to infinity, as
    /// [`Self::cell_of`] puts every point outside the grid into them.
    fn world_box(&self, a: [usize; 3], b: [usize; 3]) -> ([f64; 3], [f64; 3]) {
        let lo = std::array::from_fn(|i| {
            if a[i] == 0 {
                f64::NEG_INFINITY
            } else {
                self.lo[i] + a[i] as f64 * self.cell
            }
        });
        let hi = std::array::from_fn(|i| {
            if b[i] == self.dims[i] {
                f64::INFINITY
            } else {
                self.lo[i] + b[i] as f64 * self.cell
            }
        });
        (lo, hi)
    }
}

/// Counts of points per cell, summed over boxes of cells in constant time.
#[derive(Clone, Debug)]
struct BoxSums {
    dims: [usize; 3],
    /// `sums[(x, y, z)]` = points in cells `< x, < y, < z`, on a grid one larger per axis.
    sums: Vec<u64>,
}

impl BoxSums {
    fn new(grid: &Grid, counts: &[u64]) -> Self {
        let [nx, ny, nz] = grid.dims;
        let (sx, sy) = (nx + 1, ny + 1);
        let mut sums = vec![0u64; sx * sy * (nz + 1)];
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let at = |x: usize, y: usize, z: usize| x + sx * (y + sy * z);
                    let v = counts[grid.index([x, y, z])]
                        + sums[at(x, y + 1, z + 1)]
                        + sums[at(x + 1, y, z + 1)]
                        + sums[at(x + 1, y + 1, z)]
                        + sums[at(x, y, z)]
                        - sums[at(x, y, z + 1)]
                        - sums[at(x, y + 1, z)]
                        - sums[at(x + 1, y, z)];
                    sums[at(x + 1, y + 1, z + 1)] = v;
                }
            }
        }
        Self {
            dims: grid.dims,
            sums,
        }
    }

    /// Points in cells `a..b` per axis (clamped to the grid).
    fn count(&self, a: [usize; 3], b: [usize; 3]) -> u64 {
        let b: [usize; 3] = std::array::from_fn(|i| b[i].min(self.dims[i]));
        let a: [usize; 3] = std::array::from_fn(|i| a[i].min(b[i]));
        let (sx, sy) = (self.dims[0] + 1, self.dims[1] + 1);
        let at = |x: usize, y: usize, z: usize| self.sums[x + sx * (y + sy * z)];
        // Inclusion–exclusion over the eight corners, in an order that never goes negative.
        (at(b[0], b[1], b[2]) + at(a[0], a[1], b[2]) + at(a[0], b[1], a[2]) + at(b[0], a[1], a[2]))
            - (at(a[0], b[1], b[2])
                + at(b[0], a[1], b[2])
                + at(b[0], b[1], a[2])
                + at(a[0], a[1], a[2]))
    }
}

/// One tile: a box of cells, the points in it, and the points it loads (with its halo; an
/// upper bound from whole cells).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tile {
    /// First cell per axis.
    pub start: [usize; 3],
    /// One past the last cell per axis.
    pub end: [usize; 3],
    /// Points whose cell is in the tile (its core).
    pub points: u64,
    /// Points in the cells within the reach of the tile, core included: at least the points
    /// the tile loads.
    pub loaded: u64,
}

#[derive(Clone, Copy, Debug)]
enum Node {
    Leaf(usize),
    Split {
        axis: usize,
        /// Cells `< at` go left.
        at: usize,
        left: usize,
        right: usize,
    },
}

/// Tiles covering a grid, each holding with its halo at most a given number of points.
#[derive(Clone, Debug)]
pub struct TilePlan {
    grid: Grid,
    reach: f64,
    tiles: Vec<Tile>,
    nodes: Vec<Node>,
}

impl TilePlan {
    /// Halves the grid's box, along the side with the most cells at the plane that splits its
    /// points most evenly, until every tile's points within `reach` (counted by whole cells)
    /// are at most `capacity`. `counts` are the points per cell ([`Grid::index`] order).
    ///
    /// Fails when one cell with its halo holds more than `capacity` points.
    pub fn new(grid: Grid, counts: &[u64], reach: f64, capacity: u64) -> Result<Self, TilingError> {
        assert_eq!(counts.len(), grid.len(), "one count per cell");
        let sums = BoxSums::new(&grid, counts);
        let halo = (reach / grid.cell).ceil() as usize;
        let mut plan = Self {
            grid,
            reach,
            tiles: Vec::new(),
            nodes: Vec::new(),
        };
        plan.split(&sums, [0; 3], plan.grid.dims, halo, capacity)?;
        Ok(plan)
    }

    fn split(
        &mut self,
        sums: &BoxSums,
        a: [usize; 3],
        b: [usize; 3],
        halo: usize,
        capacity: u64,
    ) -> Result<usize, TilingError> {
        let points = sums.count(a, b);
        let grown_a = a.map(|c| c.saturating_sub(halo));
        let loaded = sums.count(grown_a, b.map(|c| c + halo));
        let sizes: [usize; 3] = std::array::from_fn(|i| b[i] - a[i]);
        let axis = (0..3).max_by_key(|&i| (sizes[i], 2 - i)).unwrap_or(0);
        if loaded <= capacity || points == 0 {
            return Ok(self.leaf(Tile {
                start: a,
                end: b,
                points,
                loaded,
            }));
        }
        if sizes[axis] < 2 {
            return Err(TilingError::TooDense {
                points: loaded,
                capacity,
                cell: self.grid.cell,
                reach: self.reach,
            });
        }
        // The plane nearest the median of the points, keeping a cell on each side.
        let slab = |at: usize| {
            let mut hi = b;
            hi[axis] = at;
            sums.count(a, hi)
        };
        let (mut lo, mut hi) = (a[axis] + 1, b[axis] - 1);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if 2 * slab(mid) < points {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        let at = lo;
        let node = self.nodes.len();
        self.nodes.push(Node::Leaf(usize::MAX));
        let (mut left_end, mut right_start) = (b, a);
        left_end[axis] = at;
        right_start[axis] = at;
        let left = self.split(sums, a, left_end, halo, capacity)?;
        let right = self.split(sums, right_start, b, halo, capacity)?;
        self.nodes[node] = Node::Split {
            axis,
            at,
            left,
            right,
        };
        Ok(node)
    }

    fn leaf(&mut self, tile: Tile) -> usize {
        self.nodes.push(Node::Leaf(self.tiles.len()));
        self.tiles.push(tile);
        self.nodes.len() - 1
    }

    /// The tiles, in the order of [`Self::tile_of`]'s numbers.
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// The grid the plan was made on.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The halo width.
    pub fn reach(&self) -> f64 {
        self.reach
    }

    /// The tile whose core holds `p`.
    pub fn tile_of(&self, p: &Point) -> usize {
        let cell = self.grid.cell_of(p);
        let mut node = 0;
        loop {
            match self.nodes[node] {
                Node::Leaf(tile) => return tile,
                Node::Split {
                    axis,
                    at,
                    left,
                    right,
                } => node = if cell[axis] < at { left } else { right },
            }
        }
    }

    /// Calls `f` with every tile whose box lies within the reach of `p` (the tile of `p`
    /// included): the tiles that load `p`.
    pub fn tiles_near(&self, p: &Point, mut f: impl FnMut(usize)) {
        // Recursive rather than with a stack of its own: called for every point of a cloud,
        // twice, it must not allocate; the depth is that of the plan's tree.
        self.near(0, p, &mut f);
    }

    fn near(&self, node: usize, p: &Point, f: &mut impl FnMut(usize)) {
        match self.nodes[node] {
            Node::Leaf(tile) => {
                let t = &self.tiles[tile];
                let (lo, hi) = self.grid.world_box(t.start, t.end);
                let d2: f64 = (0..3)
                    .map(|i| (lo[i] - p[i]).max(p[i] - hi[i]).max(0.0).powi(2))
                    .sum();
                if d2 <= self.reach * self.reach {
                    f(tile);
                }
            }
            Node::Split {
                axis,
                at,
                left,
                right,
            } => {
                let plane = self.grid.lo[axis] + at as f64 * self.grid.cell;
                if p[axis] - self.reach < plane {
                    self.near(left, p, f);
                }
                if p[axis] + self.reach >= plane {
                    self.near(right, p, f);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;
