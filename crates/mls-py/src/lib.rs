//! `mlscurv` for Python: the Python module built from this crate by maturin
//! (`pip install ./crates/mls-py`).
//!
//! Every function runs the steps of the `mlscurv` command of the same name through
//! [`mls_cli`]'s library (the same h, normals, surface and chunked evaluation), so that the
//! numbers are the command's bit for bit and the errors carry its messages; the array named
//! `points` (or `normals`) stands where the command names the file. This crate only converts:
//! numpy arrays in (a float64 C-contiguous (N, 3) array is borrowed, not copied), numpy arrays
//! out, errors to exceptions, the command's warnings to Python warnings. The GIL is released
//! while the Rust code runs.
//!
//! Architecture invariant: no geometry and no pipeline step is written here; a step missing
//! from `mls_cli` is added there, for the binary and this module alike.

use std::borrow::Cow;
use std::ffi::CString;
use std::path::PathBuf;

use mls_cli::evaluate::{self, CurvatureColumns};
use mls_cli::pipeline::{self, Built, Scale, Timings};
use mls_cli::{At, CurvatureOptions, Format, Method, NormalsMode, SurfaceOptions};
use mls_core::normals::{DEFAULT_H_FACTOR, Orientation};
use mls_core::{Cutoff, Parallelism, Point, PointStatus};
use mls_io::{AttributeData, Column, ColumnNames, ReadError, ReadOptions, WriteError};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{
    PyAttributeError, PyFileNotFoundError, PyIsADirectoryError, PyKeyError, PyOSError,
    PyPermissionError, PyTypeError, PyUserWarning, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PySlice, PyTuple};

/// How the point array is named in messages, where the command names its input file.
const POINTS: &str = "points";
/// How the normal array is named in messages.
const NORMALS: &str = "normals";

// ---------------------------------------------------------------------------------------------
// Input arrays.

/// `obj` as a float64 C-contiguous (N, 3) array: `obj` itself if it is one (no copy), else a
/// converted copy. Integer and floating-point dtypes are converted; other dtypes, and other
/// shapes, are refused with a message naming `what`.
fn coordinates<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyArray2<f64>>> {
    if let Ok(array) = obj.cast::<PyArray2<f64>>()
        && array.shape()[1] == 3
        && array.is_c_contiguous()
    {
        return Ok(array.clone());
    }
    let py = obj.py();
    let np = py.import("numpy")?;
    let array = np.call_method1("asarray", (obj,)).map_err(|e| {
        PyTypeError::new_err(format!(
            "{what}: expected an array of shape (N, 3), got {} ({e})",
            type_name(obj)
        ))
    })?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(PyTypeError::new_err(format!(
            "{what}: dtype {} is not a real number type; expected coordinates of shape (N, 3), \
             float64 preferably (other real types are converted)",
            dtype.str()?
        )));
    }
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape.len() != 2 || shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{what}: expected an array of shape (N, 3), got shape {}",
            shape_text(&shape)
        )));
    }
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", np.getattr("float64")?)?;
    let converted = np.call_method("ascontiguousarray", (array,), Some(&kwargs))?;
    Ok(converted.cast_into::<PyArray2<f64>>()?)
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type()
        .name()
        .map_or_else(|_| "an object".to_owned(), |n| n.to_string())
}

/// A shape as Python prints it: `(5,)`, `(5, 2)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The rows of a float64 C-contiguous (N, 3) array as points: borrowed when the buffer is
/// aligned (always, for arrays numpy allocated), else copied.
fn as_points(flat: &[f64]) -> Cow<'_, [Point]> {
    match bytemuck::try_cast_slice::<f64, Point>(flat) {
        Ok(points) => Cow::Borrowed(points),
        Err(_) => Cow::Owned(
            flat.chunks_exact(3)
                .map(|c| Point::new(c[0], c[1], c[2]))
                .collect(),
        ),
    }
}

/// Refuses a non-finite value, as the file readers do; `row` names a row in the message
/// (`point`, `normal`).
fn check_finite(flat: &[f64], what: &str, row: &str) -> PyResult<()> {
    match flat
        .chunks_exact(3)
        .position(|c| !c.iter().all(|v| v.is_finite()))
    {
        None => Ok(()),
        Some(i) => {
            let c = &flat[3 * i..3 * i + 3];
            Err(PyValueError::new_err(format!(
                "{what}: {row} {i} is not finite: ({}, {}, {})",
                c[0], c[1], c[2]
            )))
        }
    }
}

/// The normals given beside `n` points, as the pipeline takes a file's normals (owned, as
/// stored: zero normals are left out of the surface).
fn file_normals(normals: Option<&Bound<'_, PyAny>>, n: usize) -> PyResult<Option<Vec<[f64; 3]>>> {
    let Some(normals) = normals else {
        return Ok(None);
    };
    let array = coordinates(normals, NORMALS)?;
    let readonly = array.readonly();
    let flat = readonly.as_slice().map_err(to_value_error)?;
    if flat.len() / 3 != n {
        return Err(PyValueError::new_err(format!(
            "{NORMALS}: {} rows for {n} points; expected one normal per point",
            flat.len() / 3
        )));
    }
    check_finite(flat, NORMALS, "normal")?;
    Ok(Some(
        flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    ))
}

fn to_value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

// ---------------------------------------------------------------------------------------------
// Options, checked with the command line's parsers and messages.

/// The `cutoff` argument: a factor, or `None`/`"none"` for the untruncated kernel.
#[derive(Debug, FromPyObject)]
enum CutoffArg {
    Factor(f64),
    Text(String),
}

fn cutoff(arg: Option<CutoffArg>) -> PyResult<Cutoff> {
    let text = match arg {
        None => "none".to_owned(),
        Some(CutoffArg::Factor(c)) => c.to_string(),
        Some(CutoffArg::Text(s)) => s,
    };
    mls_cli::parse_cutoff(&text).map_err(|e| PyValueError::new_err(format!("cutoff: {e}")))
}

/// `h` and `h_factor`, which exclude each other as `--h` and `--h-factor` do.
fn scale_options(h: Option<f64>, h_factor: Option<f64>) -> PyResult<(Option<f64>, f64)> {
    let check = |name: &str, v: f64| {
        mls_cli::positive_finite(&v.to_string())
            .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
    };
    match (h, h_factor) {
        (Some(_), Some(_)) => Err(PyValueError::new_err(
            "h and h_factor cannot both be given: h is the scale, h_factor derives it from the \
             point spacing",
        )),
        (Some(h), None) => Ok((Some(check("h", h)?), DEFAULT_H_FACTOR)),
        (None, f) => Ok((None, check("h_factor", f.unwrap_or(DEFAULT_H_FACTOR))?)),
    }
}

fn orient(s: &str) -> PyResult<Orientation> {
    mls_cli::parse_orient(s).map_err(|e| PyValueError::new_err(format!("orient: {e}")))
}

fn threads(n: Option<usize>) -> PyResult<Option<u16>> {
    n.map(|n| {
        u16::try_from(n).ok().filter(|&n| n >= 1).ok_or_else(|| {
            PyValueError::new_err(format!("threads: must be between 1 and 65535, got {n}"))
        })
    })
    .transpose()
}

fn method(s: &str) -> PyResult<Method> {
    match s {
        "jet" => Ok(Method::Jet),
        "paper" => Ok(Method::Paper),
        _ => Err(PyValueError::new_err(format!(
            "method: expected \"jet\" or \"paper\", got {s:?}"
        ))),
    }
}

fn at(s: &str) -> PyResult<At> {
    match s {
        "input" => Ok(At::Input),
        "projected" => Ok(At::Projected),
        _ => Err(PyValueError::new_err(format!(
            "at: expected \"input\" or \"projected\", got {s:?}"
        ))),
    }
}

fn format(s: Option<&str>) -> PyResult<Option<Format>> {
    s.map(|s| match s.to_ascii_lowercase().as_str() {
        "ply" => Ok(Format::Ply),
        "xyz" => Ok(Format::Xyz),
        "csv" => Ok(Format::Csv),
        "las" => Ok(Format::Las),
        "laz" => Ok(Format::Laz),
        _ => Err(PyValueError::new_err(format!(
            "format: expected \"ply\", \"xyz\", \"csv\", \"las\" or \"laz\", got {s:?}"
        ))),
    })
    .transpose()
}

// ---------------------------------------------------------------------------------------------
// Running the pipeline.

/// The command's error, with its one-line message (`mlscurv: error: …` without the prefix).
fn pipeline_error(e: anyhow::Error) -> PyErr {
    PyValueError::new_err(format!("{e:#}"))
}

/// What every result carries besides its arrays.
#[derive(Debug)]
struct Summary {
    scale: Scale,
    normals_source: String,
    timings: Timings,
    warnings: Vec<String>,
}

/// Issues the command's warnings (printed by `mlscurv` on stderr) as Python `UserWarning`s.
fn warn(py: Python<'_>, warnings: &[String]) -> PyResult<()> {
    let category = py.get_type::<PyUserWarning>();
    for w in warnings {
        let message = CString::new(w.as_str()).map_err(to_value_error)?;
        PyErr::warn(py, category.as_any(), &message, 1)?;
    }
    Ok(())
}

/// The checked input of `curvature` and `project`: the point array (the caller's, or a
/// converted copy) and the normals.
struct Input<'py> {
    array: Bound<'py, PyArray2<f64>>,
    normals: Option<Vec<[f64; 3]>>,
}

impl<'py> Input<'py> {
    fn new(points: &Bound<'py, PyAny>, normals: Option<&Bound<'py, PyAny>>) -> PyResult<Self> {
        let array = coordinates(points, POINTS)?;
        let n = array.shape()[0];
        {
            let readonly = array.readonly();
            let flat = readonly.as_slice().map_err(to_value_error)?;
            check_finite(flat, POINTS, "point")?;
        }
        pipeline::check_count(n, POINTS).map_err(pipeline_error)?;
        let normals = file_normals(normals, n)?;
        Ok(Self { array, normals })
    }
}

// ---------------------------------------------------------------------------------------------
// Results.

/// Where a column of the written table lives among a result's arrays: the array's attribute
/// name and, for a component of an (N, 3) array, the component.
fn column_source(column: &str) -> (&str, Option<usize>) {
    let vector = |prefix: &'static str, axis: char| {
        let i = match axis {
            'x' => 0,
            'y' => 1,
            _ => 2,
        };
        (prefix, Some(i))
    };
    match column {
        "x" | "y" | "z" => vector("points", column.chars().next().unwrap_or('x')),
        "nx" | "ny" | "nz" => vector("normals", column.chars().nth(1).unwrap_or('x')),
        "d1x" | "d1y" | "d1z" => vector("d1", column.chars().nth(2).unwrap_or('x')),
        "d2x" | "d2y" | "d2z" => vector("d2", column.chars().nth(2).unwrap_or('x')),
        other => (other, None),
    }
}

/// The result of `curvature`, `normals` or `project`: named numpy arrays with the columns,
/// status codes and conventions of the `mlscurv` command's output file.
///
/// Attributes hold whole arrays: ``points``, ``normals``, ``d1``, ``d2`` of shape (N, 3);
/// ``k1``, ``k2``, ``mean``, ``gauss``, ``k1_sd``, ``k2_sd``, ``h``, ``noise`` of shape (N,)
/// (those the command writes); ``status`` of dtype int32 (0 = ok, see ``mlscurv.STATUS``).
/// Indexing by a column name of the file (``result["nx"]``, ``result["k1"]``) gives that
/// column; ``keys()`` lists them in the file's order, so ``dict(result)`` and
/// ``pandas.DataFrame(dict(result))`` give the command's table, and ``mlscurv.write(path,
/// result)`` writes the command's file.
///
/// Also: ``scale`` (the h used), ``scale_source`` (how h was chosen), ``normals_source`` (where
/// the normals came from), ``timings`` (seconds per stage), ``warnings`` (those also issued as
/// ``UserWarning``), as in the command's summary.
#[pyclass(module = "mlscurv", name = "Result", frozen)]
#[derive(Debug)]
struct Table {
    /// Arrays by attribute name, in the order the columns first use them.
    arrays: Vec<(String, Py<PyAny>)>,
    /// The column names, in the file's order.
    columns: Vec<String>,
    #[pyo3(get)]
    scale: f64,
    #[pyo3(get)]
    scale_source: String,
    #[pyo3(get)]
    normals_source: String,
    timings: Vec<(String, f64)>,
    #[pyo3(get)]
    warnings: Vec<String>,
    /// `curvature`, `normals` or `project`.
    kind: &'static str,
}

impl Table {
    fn new(
        kind: &'static str,
        columns: Vec<String>,
        arrays: Vec<(&str, Py<PyAny>)>,
        summary: Summary,
    ) -> Self {
        Self {
            arrays: arrays
                .into_iter()
                .map(|(name, a)| (name.to_owned(), a))
                .collect(),
            columns,
            scale: summary.scale.h,
            scale_source: summary.scale.why,
            normals_source: summary.normals_source,
            timings: summary
                .timings
                .0
                .into_iter()
                .map(|(s, t)| (s.to_owned(), t))
                .collect(),
            warnings: summary.warnings,
            kind,
        }
    }

    fn array<'py>(&self, py: Python<'py>, name: &str) -> Option<Bound<'py, PyAny>> {
        self.arrays
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, a)| a.bind(py).clone())
    }

    fn column<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        if !self.columns.iter().any(|c| c == name) {
            return Err(PyKeyError::new_err(format!(
                "{name:?} is not a column; the columns are {}",
                self.columns.join(" ")
            )));
        }
        let (array, component) = column_source(name);
        let array = self
            .array(py, array)
            .ok_or_else(|| PyKeyError::new_err(name.to_owned()))?;
        match component {
            None => Ok(array),
            // A view: no copy.
            Some(i) => array.get_item((PySlice::full(py), i)),
        }
    }
}

#[pymethods]
impl Table {
    /// The column names of the command's output file, in its order.
    fn keys(&self) -> Vec<String> {
        self.columns.clone()
    }

    fn __getitem__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        self.column(py, name)
    }

    fn __contains__(&self, name: &str) -> bool {
        self.columns.iter().any(|c| c == name)
    }

    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        PyList::new(py, &self.columns)?
            .try_iter()
            .map(Bound::into_any)
    }

    fn __getattr__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        self.array(py, name).ok_or_else(|| {
            PyAttributeError::new_err(format!(
                "'Result' object has no attribute '{name}' (the arrays of this {} result: {})",
                self.kind,
                self.arrays
                    .iter()
                    .map(|(n, _)| n.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
    }

    fn __dir__(&self) -> Vec<String> {
        let mut names: Vec<String> = self.arrays.iter().map(|(n, _)| n.clone()).collect();
        names.extend(
            [
                "scale",
                "scale_source",
                "normals_source",
                "timings",
                "warnings",
                "keys",
                "to_dict",
            ]
            .map(str::to_owned),
        );
        names
    }

    /// The columns as a dict of one-dimensional arrays (views of the result's arrays), in the
    /// file's order.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for c in &self.columns {
            dict.set_item(c, self.column(py, c)?)?;
        }
        Ok(dict)
    }

    /// Seconds per stage, as in the command's summary (`spacing`, `normals`, `index`,
    /// `curvature`, …).
    #[getter]
    fn timings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (stage, t) in &self.timings {
            dict.set_item(stage, t)?;
        }
        Ok(dict)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let n = self
            .array(py, "status")
            .and_then(|s| s.len().ok())
            .unwrap_or(0);
        format!(
            "<mlscurv.Result of {}: {n} points, h = {}, columns {}>",
            self.kind,
            self.scale,
            self.columns.join(" ")
        )
    }
}

fn vectors(py: Python<'_>, v: Vec<[f64; 3]>) -> PyResult<Py<PyAny>> {
    let n = v.len();
    Ok(PyArray1::from_vec(py, v.into_flattened())
        .reshape([n, 3])?
        .into_any()
        .unbind())
}

fn scalars<T: numpy::Element>(py: Python<'_>, v: Vec<T>) -> Py<PyAny> {
    PyArray1::from_vec(py, v).into_any().unbind()
}

// ---------------------------------------------------------------------------------------------
// The functions.

/// Principal curvatures k1 ≥ k2, their directions, mean and Gaussian curvature at every point,
/// as ``mlscurv curvature`` computes them (the same numbers, bit for bit).
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     The cloud. A float64 C-contiguous array is used as it is, without a copy; other real
///     dtypes and layouts are converted. At least 4 points, all finite.
/// normals : array_like, shape (N, 3), optional
///     Measured normals (as a file's ``nx ny nz``): zero ones are left out of the surface. When
///     absent, normals are estimated (weighted covariance, 16 neighbours) and oriented as
///     ``orient`` says. Normals that were themselves estimated from the points are better left
///     out: the jet fits given normals as data.
/// h : float, optional
///     Gaussian scale, in the units of the points. Default: ``h_factor`` × the median local
///     spacing.
/// h_factor : float, optional
///     h as a multiple of the median local spacing (default 2); not with ``h``.
/// cutoff : float or "none" or None
///     Kernel truncated at ``cutoff`` · h (at least 2; default 5), or untruncated.
/// method : "jet" or "paper"
///     ``"jet"`` (default): weighted degree-4 fits with the support chosen per point and a
///     predicted error (``k1_sd``, ``k2_sd``). ``"paper"``: the Amenta–Kil MLS surface in closed
///     form (Yang & Qian 2007).
/// at : "input" or "projected"
///     Evaluate at the input points (default) or at their projections onto the surface.
/// orient : str
///     Orientation of estimated normals: ``"mst"`` (outward; default), ``"up"``,
///     ``"viewpoint:X,Y,Z"`` or ``"none"``.
/// adaptive : bool
///     A scale per point, from h up to 4 h (adds ``h`` and ``noise``); ``method="paper"`` only.
/// threads : int, optional
///     Worker threads (default: all cores).
///
/// Returns
/// -------
/// Result
///     ``points`` (the input array itself with ``at="input"``, the projections with
///     ``"projected"``), ``normals``, ``k1``, ``k2``, ``mean``, ``gauss``, ``d1``, ``d2``,
///     ``k1_sd`` and ``k2_sd`` (jet), ``h`` and ``noise`` (adaptive), ``status`` (int32; 0 =
///     ok, else NaN numbers, see ``mlscurv.STATUS``). Positive curvature bends away from the
///     normal: a sphere with outward normals has k1 = k2 = 1/R.
///
/// Raises
/// ------
/// ValueError
///     Wrong shape, a non-finite value, fewer than 4 points, a bad option, or an h the
///     command refuses; with the command's message.
/// TypeError
///     An array of a dtype that is not a real number.
///
/// Examples
/// --------
/// >>> import numpy as np, mlscurv
/// >>> rng = np.random.default_rng(1)
/// >>> p = rng.normal(size=(4000, 3))
/// >>> p /= np.linalg.norm(p, axis=1, keepdims=True)   # the unit sphere
/// >>> r = mlscurv.curvature(p)
/// >>> bool(np.all(r.status == 0)), round(float(np.median(r.mean)), 2)
/// (True, 1.0)
/// >>> r.keys()[:10]
/// ['x', 'y', 'z', 'nx', 'ny', 'nz', 'k1', 'k2', 'mean', 'gauss']
/// >>> r.points is p        # float64 C-contiguous input is not copied
/// True
#[pyfunction]
#[pyo3(signature = (
    points, normals=None, *, h=None, h_factor=None, cutoff=Some(CutoffArg::Factor(5.0)),
    method="jet", at="input", orient="mst", adaptive=false, threads=None
))]
#[pyo3(
    text_signature = "(points, normals=None, *, h=None, h_factor=2.0, cutoff=5.0, method='jet', at='input', orient='mst', adaptive=False, threads=None)"
)]
#[allow(clippy::too_many_arguments)]
fn curvature<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    h: Option<f64>,
    h_factor: Option<f64>,
    cutoff: Option<CutoffArg>,
    method: &str,
    at: &str,
    orient: &str,
    adaptive: bool,
    threads: Option<usize>,
) -> PyResult<Table> {
    let (h, h_factor) = scale_options(h, h_factor)?;
    let options = CurvatureOptions {
        surface: SurfaceOptions {
            h,
            h_factor,
            cutoff: self::cutoff(cutoff)?,
            normals: NormalsMode::Auto,
            orient: self::orient(orient)?,
        },
        method: self::method(method)?,
        at: self::at(at)?,
        adaptive,
    };
    let threads = self::threads(threads)?;
    if options.adaptive && options.method == Method::Jet {
        return Err(PyValueError::new_err(mls_cli::ADAPTIVE_NEEDS_PAPER));
    }
    let Input { array, normals } = Input::new(points, normals)?;
    let readonly = array.readonly();
    let points = as_points(readonly.as_slice().map_err(to_value_error)?);
    let points: &[Point] = &points;
    let (out, summary) = py
        .detach(|| {
            pipeline::with_threads(threads, || {
                let mut t = Timings::default();
                let mut warnings = Vec::new();
                let Built {
                    scale,
                    normals_source,
                    normals_from_file,
                    surface,
                } = pipeline::build_surface(
                    points,
                    normals,
                    POINTS,
                    &options.surface,
                    &mut t,
                    |w| warnings.push(w),
                    evaluate::curvature_surface(options.adaptive),
                )?;
                let jet = evaluate::jet_config(normals_from_file);
                let out = t.time(evaluate::curvature_label(options.at), || {
                    evaluate::curvature(points, &surface, &options, &jet, false)
                });
                let summary = Summary {
                    scale,
                    normals_source,
                    timings: t,
                    warnings,
                };
                Ok((out, summary))
            })
        })
        .map_err(pipeline_error)?;
    drop(readonly);
    warn(py, &summary.warnings)?;
    let columns: Vec<String> = out.columns(&[]).iter().map(|c| c.name.to_owned()).collect();
    let CurvatureColumns {
        normal,
        k1,
        k2,
        mean,
        gauss,
        d1,
        d2,
        status,
        h,
        noise,
        k1_sd,
        k2_sd,
        projected,
        adaptive,
        jet,
    } = out;
    let positions = match projected {
        Some(p) => vectors(py, p)?,
        None => array.into_any().unbind(),
    };
    let mut arrays = vec![
        ("points", positions),
        ("normals", vectors(py, normal)?),
        ("k1", scalars(py, k1)),
        ("k2", scalars(py, k2)),
        ("mean", scalars(py, mean)),
        ("gauss", scalars(py, gauss)),
        ("d1", vectors(py, d1)?),
        ("d2", vectors(py, d2)?),
    ];
    if adaptive {
        arrays.push(("h", scalars(py, h)));
        arrays.push(("noise", scalars(py, noise)));
    }
    if jet {
        arrays.push(("k1_sd", scalars(py, k1_sd)));
        arrays.push(("k2_sd", scalars(py, k2_sd)));
    }
    arrays.push(("status", scalars(py, status)));
    Ok(Table::new("curvature", columns, arrays, summary))
}

/// Estimated and oriented normals, as ``mlscurv normals`` computes them.
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     The cloud (at least 4 finite points; float64 C-contiguous input is not copied).
/// h, h_factor : float, optional
///     The scale that weighs the neighbours, as for ``curvature``.
/// orient : str
///     ``"mst"`` (outward, by minimum spanning tree; default), ``"up"`` (+z, airborne scans),
///     ``"viewpoint:X,Y,Z"`` (towards a scanner) or ``"none"``.
/// threads : int, optional
///     Worker threads (default: all cores).
///
/// Returns
/// -------
/// Result
///     ``points`` (the input array), ``normals`` (unit; 0 0 0 where none could be estimated)
///     and ``status`` (0, or 7 = normal_estimation_failed).
///
/// Examples
/// --------
/// >>> import numpy as np, mlscurv
/// >>> g = np.stack(np.meshgrid(np.arange(20.0), np.arange(20.0)), -1).reshape(-1, 2)
/// >>> plane = np.column_stack([g, np.zeros(len(g))])
/// >>> r = mlscurv.normals(plane, orient="up")
/// >>> r.normals[0].tolist(), r.keys()
/// ([0.0, 0.0, 1.0], ['x', 'y', 'z', 'nx', 'ny', 'nz', 'status'])
#[pyfunction]
#[pyo3(signature = (points, *, h=None, h_factor=None, orient="mst", threads=None))]
#[pyo3(text_signature = "(points, *, h=None, h_factor=2.0, orient='mst', threads=None)")]
fn normals<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    h: Option<f64>,
    h_factor: Option<f64>,
    orient: &str,
    threads: Option<usize>,
) -> PyResult<Table> {
    let (h, h_factor) = scale_options(h, h_factor)?;
    let orient = self::orient(orient)?;
    let threads = self::threads(threads)?;
    let Input { array, .. } = Input::new(points, None)?;
    let readonly = array.readonly();
    let points = as_points(readonly.as_slice().map_err(to_value_error)?);
    let points: &[Point] = &points;
    let ((normal, status), summary) = py
        .detach(|| {
            pipeline::with_threads(threads, || {
                let mut t = Timings::default();
                let par = Parallelism::Rayon;
                let scale = t.time("spacing", || {
                    pipeline::choose_h(points, h, h_factor, par, POINTS)
                })?;
                let est = t.time("normals", || {
                    pipeline::normals(
                        None,
                        points,
                        NormalsMode::Estimate,
                        orient,
                        scale.h,
                        par,
                        POINTS,
                    )
                })?;
                let summary = Summary {
                    scale,
                    normals_source: est.source,
                    timings: t,
                    warnings: Vec::new(),
                };
                Ok((evaluate::normals_columns(&est.normals), summary))
            })
        })
        .map_err(pipeline_error)?;
    drop(readonly);
    let arrays = vec![
        ("points", array.into_any().unbind()),
        ("normals", vectors(py, normal)?),
        ("status", scalars(py, status)),
    ];
    Ok(Table::new("normals", names(&XYZ_N_STATUS), arrays, summary))
}

/// The columns of `mlscurv normals` and `mlscurv project`.
const XYZ_N_STATUS: [&str; 7] = ["x", "y", "z", "nx", "ny", "nz", "status"];

fn names(names: &[&str]) -> Vec<String> {
    names.iter().map(|&n| n.to_owned()).collect()
}

/// The points projected onto the MLS surface (denoised), with its normals, as ``mlscurv
/// project`` computes them.
///
/// Parameters are those of ``curvature`` (without ``method``, ``at`` and ``adaptive``).
///
/// Returns
/// -------
/// Result
///     ``points`` (the projections; a point that failed keeps its position), ``normals`` (NaN
///     where it failed) and ``status``.
///
/// Examples
/// --------
/// >>> import numpy as np, mlscurv
/// >>> rng = np.random.default_rng(2)
/// >>> p = rng.normal(size=(3000, 3))
/// >>> p /= np.linalg.norm(p, axis=1, keepdims=True)
/// >>> noisy = p * (1 + 0.002 * rng.normal(size=(3000, 1)))
/// >>> r = mlscurv.project(noisy)
/// >>> radius = lambda q: np.linalg.norm(q, axis=1)
/// >>> bool(np.all(r.status == 0)), round(float(radius(noisy).std()), 4), round(float(radius(r.points).std()), 4)
/// (True, 0.002, 0.0011)
/// >>> round(float(np.median(radius(r.points))), 3)    # the MLS surface lies inside: about h²/2
/// 0.994
#[pyfunction]
#[pyo3(signature = (
    points, normals=None, *, h=None, h_factor=None, cutoff=Some(CutoffArg::Factor(5.0)),
    orient="mst", threads=None
))]
#[pyo3(
    text_signature = "(points, normals=None, *, h=None, h_factor=2.0, cutoff=5.0, orient='mst', threads=None)"
)]
#[allow(clippy::too_many_arguments)]
fn project<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    h: Option<f64>,
    h_factor: Option<f64>,
    cutoff: Option<CutoffArg>,
    orient: &str,
    threads: Option<usize>,
) -> PyResult<Table> {
    let (h, h_factor) = scale_options(h, h_factor)?;
    let options = SurfaceOptions {
        h,
        h_factor,
        cutoff: self::cutoff(cutoff)?,
        normals: NormalsMode::Auto,
        orient: self::orient(orient)?,
    };
    let threads = self::threads(threads)?;
    let Input { array, normals } = Input::new(points, normals)?;
    let readonly = array.readonly();
    let points = as_points(readonly.as_slice().map_err(to_value_error)?);
    let points: &[Point] = &points;
    let (out, summary) = py
        .detach(|| {
            pipeline::with_threads(threads, || {
                let mut t = Timings::default();
                let mut warnings = Vec::new();
                let built = pipeline::build_surface(
                    points,
                    normals,
                    POINTS,
                    &options,
                    &mut t,
                    |w| warnings.push(w),
                    pipeline::fixed_surface,
                )?;
                let out = t.time("projection", || {
                    evaluate::projection(points, &built.surface, false)
                });
                let summary = Summary {
                    scale: built.scale,
                    normals_source: built.normals_source,
                    timings: t,
                    warnings,
                };
                Ok((out, summary))
            })
        })
        .map_err(pipeline_error)?;
    drop(readonly);
    warn(py, &summary.warnings)?;
    let arrays = vec![
        ("points", vectors(py, out.points)?),
        ("normals", vectors(py, out.normal)?),
        ("status", scalars(py, out.status)),
    ];
    Ok(Table::new("project", names(&XYZ_N_STATUS), arrays, summary))
}

// ---------------------------------------------------------------------------------------------
// Files.

/// The error of a reader or writer as the matching Python exception: `OSError` subclasses for
/// the operating system's errors, `ValueError` for the contents.
fn file_error(e: anyhow::Error) -> PyErr {
    let message = python_words(&format!("{e:#}"));
    let io = e
        .downcast_ref::<ReadError>()
        .and_then(|r| match r {
            ReadError::Io { error, .. } => Some(error.kind()),
            _ => None,
        })
        .or_else(|| {
            e.downcast_ref::<WriteError>().and_then(|w| match w {
                WriteError::Io { error, .. } => Some(error.kind()),
                _ => None,
            })
        });
    match io {
        Some(std::io::ErrorKind::NotFound) => PyFileNotFoundError::new_err(message),
        Some(std::io::ErrorKind::PermissionDenied) => PyPermissionError::new_err(message),
        Some(std::io::ErrorKind::IsADirectory) => PyIsADirectoryError::new_err(message),
        Some(_) => PyOSError::new_err(message),
        None if e
            .downcast_ref::<ReadError>()
            .is_some_and(|r| matches!(r, ReadError::IsADirectory { .. })) =>
        {
            PyIsADirectoryError::new_err(message)
        }
        None => PyValueError::new_err(message),
    }
}

/// The command line's options in a message, as this module's arguments: `--output-format csv`
/// becomes `format="csv"`, `add --force` becomes `pass force=True`.
fn python_words(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(i) = rest.find("--output-format ") {
        out.push_str(&rest[..i]);
        rest = &rest[i + "--output-format ".len()..];
        let end = rest.find([' ', ';', ',']).unwrap_or(rest.len());
        let names: Vec<String> = rest[..end].split('|').map(|n| format!("\"{n}\"")).collect();
        out.push_str("format=");
        out.push_str(&names.join("|"));
        rest = &rest[end..];
    }
    out.push_str(rest);
    out.replace("add --force", "pass force=True")
}

/// Reads a point cloud file, as ``mlscurv`` reads its input: PLY (ASCII or binary), XYZ/TXT/PTS,
/// CSV with a header, LAS/LAZ; the format by the extension unless ``format`` names it.
///
/// Parameters
/// ----------
/// path : str or os.PathLike
/// format : "ply", "xyz", "csv", "las" or "laz", optional
/// columns : str or sequence of str, optional
///     Names of the columns of a text file, e.g. ``"x,y,z,nx,ny,nz,intensity"`` (the command's
///     ``--columns``; ``_`` skips a column).
/// attributes : bool
///     Also return the file's other per-point values, which the command carries to its output:
///     PLY properties, text columns, LAS dimensions and extra bytes.
///
/// Returns
/// -------
/// (points, normals) or (points, normals, attributes)
///     float64 arrays of shape (N, 3); ``normals`` is None when the file has none.
///     ``attributes`` (with ``attributes=True``) is a dict of one-dimensional arrays in the
///     file's order, each in its stored type (``uint16`` for a LAS intensity, ``uint8`` for a
///     PLY colour). The reader's notes (columns not taken as normals) are issued as
///     ``UserWarning``.
///
/// Raises
/// ------
/// FileNotFoundError, PermissionError, IsADirectoryError, OSError
///     The file cannot be opened or read.
/// ValueError
///     The contents are not a point cloud, with the line or byte offset and field.
///
/// Examples
/// --------
/// >>> import mlscurv
/// >>> points, normals = mlscurv.read("tests/data/bunny-stanford.ply")  # doctest: +SKIP
/// >>> points.shape, normals is None                                    # doctest: +SKIP
/// ((35947, 3), True)
#[pyfunction]
#[pyo3(signature = (path, *, format=None, columns=None, attributes=false))]
fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
    format: Option<&str>,
    columns: Option<&Bound<'py, PyAny>>,
    attributes: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let format = self::format(format)?;
    let columns = match columns {
        None => None,
        Some(c) => {
            let text: String = match c.extract::<String>() {
                Ok(s) => s,
                Err(_) => c.extract::<Vec<String>>()?.join(","),
            };
            Some(
                ColumnNames::parse(&text)
                    .map_err(|e| PyValueError::new_err(format!("columns: {e}")))?,
            )
        }
    };
    let options = ReadOptions { columns };
    let outcome = py
        .detach(|| match format {
            Some(f) => mls_io::read_point_cloud_as_with(&path, f.into(), &options),
            None => mls_io::read_point_cloud_with(&path, &options),
        })
        .map_err(|e| match e {
            ReadError::NoExtension { .. } | ReadError::UnknownExtension { .. } => {
                PyValueError::new_err(format!(
                    "{e}; or name the format with format=\"ply\"|\"xyz\"|\"csv\"|\"las\"|\"laz\""
                ))
            }
            e => file_error(e.into()),
        })?;
    warn(py, &outcome.notes)?;
    let points = vectors(py, outcome.cloud.points)?;
    let normals = match outcome.cloud.normals {
        Some(n) => vectors(py, n)?,
        None => py.None(),
    };
    if !attributes {
        return PyTuple::new(py, [points, normals]);
    }
    let dict = PyDict::new(py);
    for a in outcome.cloud.attributes {
        dict.set_item(a.name, attribute_array(py, a.data))?;
    }
    PyTuple::new(py, [points, normals, dict.into_any().unbind()])
}

/// An attribute's values as a numpy array of its stored type.
fn attribute_array(py: Python<'_>, data: AttributeData) -> Py<PyAny> {
    match data {
        AttributeData::I8(v) => scalars(py, v),
        AttributeData::U8(v) => scalars(py, v),
        AttributeData::I16(v) => scalars(py, v),
        AttributeData::U16(v) => scalars(py, v),
        AttributeData::I32(v) => scalars(py, v),
        AttributeData::U32(v) => scalars(py, v),
        AttributeData::I64(v) => scalars(py, v),
        AttributeData::U64(v) => scalars(py, v),
        AttributeData::F32(v) => scalars(py, v),
        AttributeData::F64(v) => scalars(py, v),
    }
}

/// A column to write, owned so that the writer can run without the GIL.
enum Owned {
    F64(String, Vec<f64>),
    I32(String, Vec<i32>),
}

impl Owned {
    fn column(&self) -> Column<'_> {
        match self {
            Self::F64(name, v) => Column::f64(name, v),
            Self::I32(name, v) => Column::i32(name, v),
        }
    }

    fn len(&self) -> usize {
        match self {
            Self::F64(_, v) => v.len(),
            Self::I32(_, v) => v.len(),
        }
    }

    fn name(&self) -> &str {
        match self {
            Self::F64(name, _) | Self::I32(name, _) => name,
        }
    }
}

/// The column names of an (N, 3) array under `key`: `points` gives `x y z`, `normals` gives
/// `nx ny nz`, any other `key` gives `keyx keyy keyz` (`d1` gives `d1x d1y d1z`).
fn vector_names(key: &str) -> [String; 3] {
    match key {
        "points" => ["x", "y", "z"].map(str::to_owned),
        "normals" => ["nx", "ny", "nz"].map(str::to_owned),
        _ => ["x", "y", "z"].map(|a| format!("{key}{a}")),
    }
}

/// The values of a one-dimensional array, converted by numpy to `dtype` (the name of `T`)
/// rather than element by element.
fn values<T: numpy::Element>(array: &Bound<'_, PyAny>, dtype: &str) -> PyResult<Vec<T>> {
    let py = array.py();
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", dtype)?;
    let contiguous =
        py.import("numpy")?
            .call_method("ascontiguousarray", (array,), Some(&kwargs))?;
    contiguous
        .cast_into::<PyArray1<T>>()?
        .to_vec()
        .map_err(to_value_error)
}

/// Appends the columns of `value` (one-dimensional, or (N, 3) with [`vector_names`]) under
/// `key`: integers as int32, real numbers as float64.
fn owned_columns(key: &str, value: &Bound<'_, PyAny>, out: &mut Vec<Owned>) -> PyResult<()> {
    let py = value.py();
    let np = py.import("numpy")?;
    let array = np.call_method1("asarray", (value,))?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    let integer = match kind.as_str() {
        "i" | "u" | "b" => true,
        "f" => false,
        _ => {
            return Err(PyTypeError::new_err(format!(
                "column {key:?}: dtype {} is not a number type",
                array.getattr("dtype")?.str()?
            )));
        }
    };
    match shape[..] {
        [_] => {
            let name = key.to_owned();
            out.push(if integer {
                let v: Vec<i64> = values(&array, "int64")?;
                let v = v
                    .into_iter()
                    .enumerate()
                    .map(|(i, x)| {
                        i32::try_from(x).map_err(|_| {
                            PyValueError::new_err(format!(
                                "column {key:?}: value {x} at row {i} does not fit in a 32-bit \
                                 integer"
                            ))
                        })
                    })
                    .collect::<PyResult<Vec<i32>>>()?;
                Owned::I32(name, v)
            } else {
                Owned::F64(name, values(&array, "float64")?)
            });
        }
        [_, 3] => {
            for (i, name) in vector_names(key).into_iter().enumerate() {
                let component = array.get_item((PySlice::full(py), i))?;
                out.push(Owned::F64(name, values(&component, "float64")?));
            }
        }
        _ => {
            return Err(PyValueError::new_err(format!(
                "column {key:?}: expected shape (N,) or (N, 3), got shape {}",
                shape_text(&shape)
            )));
        }
    }
    Ok(())
}

/// Writes a table, as ``mlscurv`` writes its output: PLY (binary little endian unless
/// ``ascii``), CSV, XYZ/TXT/PTS or LAS/LAZ (coordinates on a fine grid, other columns as extra
/// bytes), by the extension unless ``format`` names it. The file is written atomically; an
/// existing read-only file is replaced only with ``force``.
///
/// Parameters
/// ----------
/// path : str or os.PathLike
/// data : Result, mapping or array
///     A ``Result`` (its columns, as the command writes them); a mapping of names to arrays,
///     one-dimensional (a column: integers as int32, real numbers as float64) or of shape (N, 3)
///     (``points`` gives ``x y z``, ``normals`` gives ``nx ny nz``, ``key`` gives ``keyx keyy
///     keyz``); or an (N, 3) array of points.
/// format : "ply", "xyz", "csv", "las" or "laz", optional
/// ascii : bool
///     ASCII PLY.
/// force : bool
///     Replace a read-only file (it keeps its permissions).
///
/// Examples
/// --------
/// >>> import numpy as np, mlscurv, tempfile, os
/// >>> p = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]])
/// >>> path = os.path.join(tempfile.mkdtemp(), "cloud.csv")
/// >>> mlscurv.write(path, {"points": p, "label": np.array([1, 2, 3])})
/// >>> print(open(path).read().splitlines()[0])
/// x,y,z,label
/// >>> mlscurv.read(path)[0].tolist() == p.tolist()
/// True
#[pyfunction]
#[pyo3(signature = (path, data, *, format=None, ascii=false, force=false))]
fn write(
    py: Python<'_>,
    path: PathBuf,
    data: &Bound<'_, PyAny>,
    format: Option<&str>,
    ascii: bool,
    force: bool,
) -> PyResult<()> {
    let format = self::format(format)?;
    if path.as_os_str() == "-" {
        return Err(PyValueError::new_err(
            "write: \"-\" (standard output) is for the command line; give a file name",
        ));
    }
    let mut owned = Vec::new();
    if let Ok(table) = data.cast::<Table>() {
        let table = table.get();
        for c in &table.columns {
            owned_columns(c, &table.column(py, c)?, &mut owned)?;
        }
    } else if let Ok(mapping) = data.cast::<pyo3::types::PyMapping>() {
        for item in mapping.items()?.iter() {
            let (key, value): (String, Bound<'_, PyAny>) = item.extract()?;
            owned_columns(&key, &value, &mut owned)?;
        }
    } else {
        let array = coordinates(data, "data")?;
        owned_columns("points", array.as_any(), &mut owned)?;
    }
    let Some(first) = owned.first() else {
        return Err(PyValueError::new_err("data: no columns to write"));
    };
    if let Some(c) = owned.iter().find(|c| c.len() != first.len()) {
        return Err(PyValueError::new_err(format!(
            "column {:?}: {} rows, but column {:?} has {}; every column needs one value per point",
            c.name(),
            c.len(),
            first.name(),
            first.len()
        )));
    }
    py.detach(|| {
        let output = pipeline::check_output(&[], &path, format, force, ascii, None)?;
        let columns: Vec<Column<'_>> = owned.iter().map(Owned::column).collect();
        output.write(&columns, ascii, None)
    })
    .map_err(file_error)
}

/// The status codes of the ``status`` column and their names.
fn status_names(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item(0, "ok")?;
    for s in PointStatus::ALL {
        dict.set_item(s.code(), s.name())?;
    }
    Ok(dict)
}

/// Exact, signed surface curvature of point clouds: the ``mlscurv`` command's computations on
/// numpy arrays.
///
/// ``curvature(points)`` gives principal curvatures, directions, mean and Gaussian curvature at
/// every point; ``normals(points)`` estimates and orients normals; ``project(points)`` denoises
/// onto the MLS surface; ``read(path)`` and ``write(path, data)`` move clouds and results to and
/// from PLY, XYZ, CSV and LAS/LAZ files. The numbers are the command's, bit for bit.
///
/// ``STATUS`` maps the codes of the ``status`` column to their names (0 is ok; the numbers of a
/// point with another status are NaN).
///
/// Sign convention: curvature is positive where the surface bends away from the oriented
/// normal (a sphere with outward normals has k1 = k2 = mean = 1/R); mean = (k1 + k2)/2.
#[pymodule]
fn mlscurv(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(curvature, m)?)?;
    m.add_function(wrap_pyfunction!(normals, m)?)?;
    m.add_function(wrap_pyfunction!(project, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_class::<Table>()?;
    m.add("STATUS", status_names(m.py())?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
