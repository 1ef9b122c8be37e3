//! `mlscurv` for Python: the Python module built from this crate by maturin
//! (`pip install ./crates/mls-py`).
//!
//! Every function runs the steps of the `mlscurv` command of the same name through
//! [`mls_pipeline`] (the same h, normals, surface and streamed evaluation), so that the
//! numbers are the command's bit for bit and the errors carry its messages; the array named
//! `points` (or `normals`) stands where the command names the file. This crate only converts:
//! numpy arrays in (a float64 C-contiguous (N, 3) array is borrowed, not copied), numpy arrays
//! out, errors to exceptions, the command's warnings to Python warnings. The GIL is released
//! while the Rust code runs.
//!
//! `functions` holds `curvature`, `normals` and `project`, `files` holds `read` and `write`,
//! `result` the `Result` class; this file checks and converts the arguments and builds the
//! module.
//!
//! Architecture invariant: no geometry and no pipeline step is written here; a step missing
//! from `mls_pipeline` is added there, for the binary and this module alike.

mod files;
mod functions;
mod result;
mod tiles;

use std::borrow::Cow;
use std::ffi::CString;

use mls_core::normals::{DEFAULT_H_FACTOR, Orientation};
use mls_core::{Cutoff, Point, PointStatus};
use mls_io::FileFormat;
use mls_pipeline::pipeline::{self, Scale, Timings};
use mls_pipeline::{At, Method};
use numpy::{PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

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
        && array.getattr("flags")?.getattr("aligned")?.is_truthy()?
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
    // Aligned as well as contiguous: an array that Dask's workers unpickled can start at any
    // byte, and numpy's `ascontiguousarray` would leave it so.
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", np.getattr("float64")?)?;
    kwargs.set_item("requirements", "CA")?;
    let converted = np.call_method("require", (array,), Some(&kwargs))?;
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
    check_finite_from(flat, what, row, 0)
}

/// [`check_finite`] of rows numbered from `first`: a chunk of a larger array, named in the
/// message by its row in the whole.
fn check_finite_from(flat: &[f64], what: &str, row: &str, first: usize) -> PyResult<()> {
    match flat
        .chunks_exact(3)
        .position(|c| !c.iter().all(|v| v.is_finite()))
    {
        None => Ok(()),
        Some(i) => {
            let c = &flat[3 * i..3 * i + 3];
            Err(PyValueError::new_err(format!(
                "{what}: {row} {} is not finite: ({}, {}, {})",
                first + i,
                c[0],
                c[1],
                c[2]
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
    mls_pipeline::parse_cutoff(&text).map_err(|e| PyValueError::new_err(format!("cutoff: {e}")))
}

/// `h` and `h_factor`, which exclude each other as `--h` and `--h-factor` do.
fn scale_options(h: Option<f64>, h_factor: Option<f64>) -> PyResult<(Option<f64>, f64)> {
    let check = |name: &str, v: f64| {
        mls_pipeline::positive_finite(&v.to_string())
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
    mls_pipeline::parse_orient(s).map_err(|e| PyValueError::new_err(format!("orient: {e}")))
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

fn format(s: Option<&str>) -> PyResult<Option<FileFormat>> {
    s.map(|s| match s.to_ascii_lowercase().as_str() {
        "ply" => Ok(FileFormat::Ply),
        "xyz" => Ok(FileFormat::Xyz),
        "csv" => Ok(FileFormat::Csv),
        "las" => Ok(FileFormat::Las),
        "laz" => Ok(FileFormat::Laz),
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
fn _mlscurv(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(functions::curvature, m)?)?;
    m.add_function(wrap_pyfunction!(functions::normals, m)?)?;
    m.add_function(wrap_pyfunction!(functions::project, m)?)?;
    m.add_function(wrap_pyfunction!(functions::eval, m)?)?;
    m.add_function(wrap_pyfunction!(files::read, m)?)?;
    m.add_function(wrap_pyfunction!(files::write, m)?)?;
    m.add_class::<result::Table>()?;
    // The private pieces of `mlscurv.dask`.
    m.add_function(wrap_pyfunction!(tiles::_check_chunk, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::_check_count, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::_reach, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::_capacity, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::_check_orient, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::_parse_size, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::_tile_curvature, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::_overlap_counts, m)?)?;
    m.add_function(wrap_pyfunction!(files::_write_like, m)?)?;
    m.add_function(wrap_pyfunction!(files::_check_output, m)?)?;
    m.add_class::<tiles::PyGrid>()?;
    m.add_class::<tiles::PyPlan>()?;
    m.add("STATUS", status_names(m.py())?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "_MIN_OVERLAP_AGREEMENT",
        mls_pipeline::tiled::MIN_OVERLAP_AGREEMENT,
    )?;
    Ok(())
}
