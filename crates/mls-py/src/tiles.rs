//! The private pieces of `mlscurv.dask`: the tile plan, the reach, the capacity of a memory
//! budget and one tile's curvature, each a thin call into `mls_core::tiling` or
//! `mls_pipeline::tiled`, so that the Dask graph and the binary's out-of-core run cut a cloud by
//! the same rules (written once, in Rust).

use mls_core::normals::DEFAULT_H_FACTOR;
use mls_core::tiling::{self, Grid, TilePlan};
use mls_core::{Frame, Point, Vector};
use mls_pipeline::tiled::{self, TileResult};
use mls_pipeline::{At, CurvatureOptions, Method, NormalsMode, SurfaceOptions, pipeline};
use numpy::{IntoPyArray, PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::result::{Table, vectors};
use crate::{
    CutoffArg, POINTS, Summary, as_points, check_finite_from, coordinates, file_normals,
    pipeline_error, to_value_error,
};

/// The rows of `obj` as owned points, after the module's shape, dtype and finiteness checks
/// (row numbers in messages counted from `first`).
fn points_of(obj: &Bound<'_, PyAny>, first: usize) -> PyResult<Vec<Point>> {
    let array = coordinates(obj, POINTS)?;
    let readonly = array.readonly();
    let flat = readonly.as_slice().map_err(to_value_error)?;
    check_finite_from(flat, POINTS, "point", first)?;
    Ok(as_points(flat).into_owned())
}

fn vector(v: [f64; 3]) -> Vector {
    Vector::new(v[0], v[1], v[2])
}

fn tiling_error(e: tiling::TilingError) -> PyErr {
    PyValueError::new_err(format!("{POINTS}: {e}"))
}

/// Checks one chunk of a cloud (rows `first..`) as `curvature` checks a whole one, with its
/// normals if given, and returns its bounding box `(lo, hi)`, or None for an empty chunk.
#[pyfunction]
#[pyo3(signature = (points, normals, first))]
pub(crate) fn _check_chunk(
    points: &Bound<'_, PyAny>,
    normals: Option<&Bound<'_, PyAny>>,
    first: usize,
) -> PyResult<Option<([f64; 3], [f64; 3])>> {
    let points = points_of(points, first)?;
    if let Some(normals) = normals {
        let array = coordinates(normals, crate::NORMALS)?;
        let readonly = array.readonly();
        let flat = readonly.as_slice().map_err(to_value_error)?;
        if flat.len() / 3 != points.len() {
            return Err(PyValueError::new_err(format!(
                "{}: {} rows for {} points; expected one normal per point",
                crate::NORMALS,
                flat.len() / 3,
                points.len()
            )));
        }
        check_finite_from(flat, crate::NORMALS, "normal", first)?;
    }
    let Some(p0) = points.first() else {
        return Ok(None);
    };
    let (lo, hi) = points.iter().fold((p0.coords, p0.coords), |(lo, hi), p| {
        (lo.inf(&p.coords), hi.sup(&p.coords))
    });
    Ok(Some((lo.into(), hi.into())))
}

/// Refuses a cloud of fewer points than a neighbourhood needs, with `curvature`'s message.
#[pyfunction]
pub(crate) fn _check_count(n: usize) -> PyResult<()> {
    pipeline::check_count(n, POINTS).map_err(pipeline_error)
}

/// How far from a point the samples deciding its result lie ([`tiling::reach`]), for `h`,
/// the `cutoff`, the `method` and whether the normals are estimated.
#[pyfunction]
#[pyo3(signature = (h, cutoff, method, estimated_normals))]
pub(crate) fn _reach(
    h: f64,
    cutoff: Option<CutoffArg>,
    method: &str,
    estimated_normals: bool,
) -> PyResult<f64> {
    let h = mls_pipeline::positive_finite(&h.to_string())
        .map_err(|e| PyValueError::new_err(format!("h: {e}")))?;
    let cutoff = crate::cutoff(cutoff)?;
    let jet = (crate::method(method)? == Method::Jet)
        .then(|| mls_pipeline::evaluate::jet_config(!estimated_normals));
    tiling::reach(h, cutoff, jet.as_ref(), estimated_normals).ok_or_else(|| {
        PyValueError::new_err(
            "cutoff: a tiled run needs a kernel cutoff (cutoff=None reaches every point)",
        )
    })
}

/// Refuses an `orient` that `curvature` refuses, before any work is sent to a cluster.
#[pyfunction]
pub(crate) fn _check_orient(orient: &str) -> PyResult<()> {
    crate::orient(orient).map(|_| ())
}

/// The points a tile may load under a memory budget of `budget` bytes, as the binary's
/// `--memory` gives them; `given` is the `memory` argument as the caller wrote it, for the
/// error when the budget is too small.
#[pyfunction]
pub(crate) fn _capacity(budget: u64, given: &str) -> PyResult<u64> {
    tiled::tile_capacity(budget, given).map_err(PyValueError::new_err)
}

/// A memory size as the binary's `--memory` reads it (`300MiB`, `2G`, bytes).
#[pyfunction]
pub(crate) fn _parse_size(text: &str) -> PyResult<u64> {
    tiled::parse_size(text).map_err(|e| PyValueError::new_err(format!("memory: {e}")))
}

/// The counting grid over a bounding box: `counts(points)` are its points per cell, to be
/// summed over the chunks of a cloud before a plan is made.
#[pyclass(module = "mlscurv._mlscurv", name = "_Grid", frozen)]
#[derive(Debug)]
pub(crate) struct PyGrid {
    grid: Grid,
    lo: [f64; 3],
    hi: [f64; 3],
    max_cells: usize,
}

#[pymethods]
impl PyGrid {
    #[new]
    fn new(lo: [f64; 3], hi: [f64; 3], max_cells: usize) -> PyResult<Self> {
        let grid = Grid::new(vector(lo), vector(hi), max_cells).map_err(tiling_error)?;
        Ok(Self {
            grid,
            lo,
            hi,
            max_cells,
        })
    }

    /// Rebuilt from its inputs when unpickled: a grid is a few numbers.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let me = slf.get();
        (
            py.get_type::<Self>(),
            (me.lo, me.hi, me.max_cells).into_pyobject(py)?,
        )
            .into_pyobject(py)
    }

    /// Number of cells.
    fn __len__(&self) -> usize {
        self.grid.len()
    }

    /// Points per cell (uint64, one per cell) of `points`, an (n, 3) array.
    fn counts<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<u64>>> {
        let points = points_of(points, 0)?;
        let counts = py.detach(|| {
            let mut counts = vec![0u64; self.grid.len()];
            for p in &points {
                counts[self.grid.index_of(p)] += 1;
            }
            counts
        });
        Ok(counts.into_pyarray(py))
    }
}

/// Tiles over a cloud's box, each holding with its halo at most `capacity` points
/// ([`TilePlan::new`] on the grid `_Grid(lo, hi, max_cells)` with the summed `counts`).
/// Pickled as its inputs, and made again when unpickled: the plan is a deterministic function
/// of them.
#[pyclass(module = "mlscurv._mlscurv", name = "_Plan", frozen)]
#[derive(Debug)]
pub(crate) struct PyPlan {
    plan: TilePlan,
    lo: [f64; 3],
    hi: [f64; 3],
    counts: Vec<u64>,
    capacity: u64,
    max_cells: usize,
}

#[pymethods]
impl PyPlan {
    #[new]
    fn new(
        lo: [f64; 3],
        hi: [f64; 3],
        counts: &Bound<'_, PyAny>,
        reach: f64,
        capacity: u64,
        max_cells: usize,
    ) -> PyResult<Self> {
        let grid = Grid::new(vector(lo), vector(hi), max_cells).map_err(tiling_error)?;
        let counts: Vec<u64> = crate::files::values(counts, "uint64")?;
        if counts.len() != grid.len() {
            return Err(PyValueError::new_err(format!(
                "counts: {} values for a grid of {} cells",
                counts.len(),
                grid.len()
            )));
        }
        let plan = TilePlan::new(grid, &counts, reach, capacity).map_err(tiling_error)?;
        Ok(Self {
            plan,
            lo,
            hi,
            counts,
            capacity,
            max_cells,
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let me = slf.get();
        let counts = PyArray1::from_slice(py, &me.counts);
        (
            py.get_type::<Self>(),
            (
                me.lo,
                me.hi,
                counts,
                me.plan.reach(),
                me.capacity,
                me.max_cells,
            )
                .into_pyobject(py)?,
        )
            .into_pyobject(py)
    }

    /// Number of tiles.
    fn __len__(&self) -> usize {
        self.plan.tiles().len()
    }

    /// The halo width.
    #[getter]
    fn reach(&self) -> f64 {
        self.plan.reach()
    }

    /// Points per tile (its core), and points it loads (core and halo, an upper bound by
    /// whole cells).
    fn sizes(&self) -> (Vec<u64>, Vec<u64>) {
        self.plan
            .tiles()
            .iter()
            .map(|t| (t.points, t.loaded))
            .unzip()
    }

    /// For occupied cells (linear indices, as `_Grid.counts` numbers them): the tiles whose
    /// cores hold them, and the tiles that may load a point of them (every tile whose box of
    /// cells lies within the reach of the cell's box: a superset of [`TilePlan::tiles_near`]
    /// of its points). Each a sorted int64 array without repeats; the graph's edges from a
    /// chunk to the tiles, known before any point is split.
    fn tiles_of_cells<'py>(
        &self,
        py: Python<'py>,
        cells: &Bound<'py, PyAny>,
    ) -> PyResult<Pairs<'py>> {
        let cells: Vec<i64> = crate::files::values(cells, "int64")?;
        let grid = self.plan.grid();
        let [nx, ny, nz] = grid.dims();
        if let Some(c) = cells.iter().find(|&&c| c < 0 || c as usize >= grid.len()) {
            return Err(PyValueError::new_err(format!(
                "cells: {c} is not a cell of a grid of {} cells",
                grid.len()
            )));
        }
        let (own, near) = py.detach(|| {
            let (mut own, mut near) = (vec![false; self.plan.tiles().len()], Vec::new());
            near.resize(own.len(), false);
            let cell = grid.cell();
            let lo = vector(self.lo);
            for &c in &cells {
                let c = c as usize;
                let at = [c % nx, (c / nx) % ny, c / (nx * ny)];
                debug_assert!(at[2] < nz);
                // The cell's centre lies in the cell, whatever the rounding at its faces.
                let centre = Point::from(lo + Vector::from(at.map(|a| (a as f64 + 0.5) * cell)));
                own[self.plan.tile_of(&centre)] = true;
                for (t, tile) in self.plan.tiles().iter().enumerate() {
                    // Whole cells between the cell and the tile's box, per axis: the boxes are
                    // at least that far apart.
                    let gap: f64 = (0..3)
                        .map(|i| {
                            let cells = tile.start[i]
                                .saturating_sub(at[i] + 1)
                                .max(at[i].saturating_sub(tile.end[i]));
                            (cells as f64 * cell).powi(2)
                        })
                        .sum();
                    if gap <= self.plan.reach() * self.plan.reach() {
                        near[t] = true;
                    }
                }
            }
            let list = |flags: Vec<bool>| -> Vec<i64> {
                (0..flags.len() as i64)
                    .filter(|&t| flags[t as usize])
                    .collect()
            };
            (list(own), list(near))
        });
        Ok((own.into_pyarray(py), near.into_pyarray(py)))
    }

    /// The tile whose core holds each point (int64, one per row of `points`).
    fn tile_of<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let points = points_of(points, 0)?;
        let tiles: Vec<i64> =
            py.detach(|| points.iter().map(|p| self.plan.tile_of(p) as i64).collect());
        Ok(tiles.into_pyarray(py))
    }

    /// Every (row, tile) pair where the tile loads the row's point (its own tile, and every
    /// tile whose box lies within the reach), as two int64 arrays, by row and then tile number.
    fn loads<'py>(&self, py: Python<'py>, points: &Bound<'py, PyAny>) -> PyResult<Pairs<'py>> {
        let points = points_of(points, 0)?;
        let (rows, tiles) = py.detach(|| {
            let (mut rows, mut tiles) = (Vec::new(), Vec::new());
            let mut near = Vec::new();
            for (i, p) in points.iter().enumerate() {
                near.clear();
                self.plan.tiles_near(p, |t| near.push(t as i64));
                near.sort_unstable();
                rows.extend(std::iter::repeat_n(i as i64, near.len()));
                tiles.extend_from_slice(&near);
            }
            (rows, tiles)
        });
        Ok((rows.into_pyarray(py), tiles.into_pyarray(py)))
    }
}

/// Rows and tiles of [`PyPlan::loads`].
type Pairs<'py> = (Bound<'py, PyArray1<i64>>, Bound<'py, PyArray1<i64>>);

/// `(agree, compared)` over pairs of sign codes that two tiles gave the same points (uint8
/// arrays of equal length; see `_tile_curvature`): [`tiled::signs_agree`], the tiled run's
/// overlap rule.
#[pyfunction]
pub(crate) fn _overlap_counts<'py>(
    mine: &Bound<'py, PyAny>,
    theirs: &Bound<'py, PyAny>,
) -> PyResult<(u64, u64)> {
    let mine: Vec<u8> = crate::files::values(mine, "uint8")?;
    let theirs: Vec<u8> = crate::files::values(theirs, "uint8")?;
    if mine.len() != theirs.len() {
        return Err(PyValueError::new_err(format!(
            "sign codes: {} against {}",
            mine.len(),
            theirs.len()
        )));
    }
    Ok(mine
        .iter()
        .zip(&theirs)
        .filter_map(|(&a, &b)| tiled::signs_agree(a, b))
        .fold((0, 0), |(agree, compared), same| {
            (agree + u64::from(same), compared + 1)
        }))
}

/// The curvature at a tile's own points (`core`, a bool per row) of the surface of all its
/// `points` (own and halo, in the cloud's order), built in the frame of the whole cloud's box
/// `lo`..`hi`: [`tiled::tile_curvature`], the step the binary's out-of-core run takes per
/// tile. Returns a `Result` of the own points, with the columns of `curvature`, and with
/// estimated normals the sign code of every point's normal (own and halo, a uint8 each: 0 for
/// none, else `1 + 2·axis + (component < 0)` of its largest component), which the caller
/// compares between the tiles that load a point, as the binary's tiled run does.
#[pyfunction]
#[pyo3(signature = (
    points, normals, core, *, h, lo, hi, cutoff=Some(CutoffArg::Factor(5.0)), method="jet",
    orient="up", name="points", threads=None
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn _tile_curvature<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    core: &Bound<'py, PyAny>,
    h: f64,
    lo: [f64; 3],
    hi: [f64; 3],
    cutoff: Option<CutoffArg>,
    method: &str,
    orient: &str,
    name: &str,
    threads: Option<usize>,
) -> PyResult<(Table, Option<Bound<'py, PyArray1<u8>>>)> {
    let orientation = crate::orient(orient)?;
    let options = CurvatureOptions {
        surface: SurfaceOptions {
            h: Some(h),
            h_factor: DEFAULT_H_FACTOR,
            cutoff: crate::cutoff(cutoff)?,
            normals: NormalsMode::Auto,
            orient: Some(orientation),
        },
        method: crate::method(method)?,
        at: At::Input,
        adaptive: false,
    };
    let threads = crate::threads(threads)?;
    let points = points_of(points, 0)?;
    let normals = file_normals(normals, points.len())?;
    let core: Vec<bool> = crate::files::values(core, "bool")?;
    if core.len() != points.len() {
        return Err(PyValueError::new_err(format!(
            "core: {} flags for {} points",
            core.len(),
            points.len()
        )));
    }
    let from_file = normals.is_some();
    let frame = Frame::of_box(vector(lo), vector(hi));
    let (result, timings) = py
        .detach(|| {
            pipeline::with_threads(threads, || {
                let mut t = pipeline::Timings::default();
                let result = t.time("curvature", || {
                    tiled::tile_curvature(
                        &points,
                        normals,
                        &core,
                        h,
                        orientation,
                        frame,
                        &options,
                        name,
                    )
                })?;
                Ok((result, t))
            })
        })
        .map_err(pipeline_error)?;
    let TileResult {
        columns: out,
        codes,
        source,
        agreement,
    } = result;
    let codes = (!from_file).then(|| codes.into_pyarray(py));
    // Judged per tile: each Dask task sees only its own.
    let warnings: Vec<String> = agreement
        .and_then(|a| pipeline::file_normals_warning(a, name))
        .into_iter()
        .collect();
    crate::warn(py, &warnings)?;
    let queries: Vec<[f64; 3]> = points
        .iter()
        .zip(&core)
        .filter_map(|(p, &c)| c.then_some(p.coords.into()))
        .collect();
    let columns: Vec<String> = out.columns(&[]).iter().map(|c| c.name.to_owned()).collect();
    let arrays = crate::functions::curvature_arrays(py, out, vectors(py, queries)?)?;
    let summary = Summary {
        scale: pipeline::Scale {
            h,
            why: "given".into(),
            spacing: None,
            factor: None,
        },
        normals_source: source,
        timings,
        warnings,
    };
    Ok((Table::new("curvature", columns, arrays, summary), codes))
}
