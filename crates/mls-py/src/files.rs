//! `read` and `write`: files in every format of the command, with its messages and Python's
//! exception types.

use std::path::PathBuf;

use mls_io::{AttributeData, Axis, Column, ColumnNames, ReadError, ReadOptions, WriteError};
use mls_pipeline::pipeline;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{
    PyFileNotFoundError, PyIsADirectoryError, PyOSError, PyPermissionError, PyTypeError,
    PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PySlice, PyTuple};

use crate::result::{Table, scalars, vectors};
use crate::{coordinates, shape_text, to_value_error, warn};

/// The error of a reader or writer as the matching Python exception: `OSError` subclasses for
/// the operating system's errors, `ValueError` for the contents.
pub(crate) fn file_error(e: anyhow::Error) -> PyErr {
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
pub(crate) fn python_words(message: &str) -> String {
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
pub(crate) fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
    format: Option<&str>,
    columns: Option<&Bound<'py, PyAny>>,
    attributes: bool,
) -> PyResult<Bound<'py, PyTuple>> {
    let format = crate::format(format)?;
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
            Some(f) => mls_io::read_point_cloud_as_with(&path, f, &options),
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
pub(crate) fn attribute_array(py: Python<'_>, data: AttributeData) -> Py<PyAny> {
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
pub(crate) enum Owned {
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
pub(crate) fn vector_names(key: &str) -> [String; 3] {
    match key {
        "points" => ["x", "y", "z"].map(str::to_owned),
        "normals" => ["nx", "ny", "nz"].map(str::to_owned),
        _ => ["x", "y", "z"].map(|a| format!("{key}{a}")),
    }
}

/// The values of a one-dimensional array, converted by numpy to `dtype` (the name of `T`)
/// rather than element by element.
pub(crate) fn values<T: numpy::Element>(array: &Bound<'_, PyAny>, dtype: &str) -> PyResult<Vec<T>> {
    let py = array.py();
    let kwargs = PyDict::new(py);
    kwargs.set_item("dtype", dtype)?;
    kwargs.set_item("requirements", "CA")?;
    let contiguous = py
        .import("numpy")?
        .call_method("require", (array,), Some(&kwargs))?;
    contiguous
        .cast_into::<PyArray1<T>>()?
        .to_vec()
        .map_err(to_value_error)
}

/// Appends the columns of `value` (one-dimensional, or (N, 3) with [`vector_names`]) under
/// `key`: integers as int32, real numbers as float64.
pub(crate) fn owned_columns(
    key: &str,
    value: &Bound<'_, PyAny>,
    out: &mut Vec<Owned>,
) -> PyResult<()> {
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
/// ``ascii``; columns other than ``x y z nx ny nz`` and colour as ``scalar_<name>``, and
/// ``mean`` repeated as ``quality``, for CloudCompare and MeshLab), CSV (its header after
/// ``//``, CloudCompare's form), XYZ/TXT/PTS or LAS/LAZ (coordinates on a fine grid, other
/// columns as extra bytes), by the extension unless ``format`` names it. The file is written atomically; an
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
/// //x,y,z,label
/// >>> mlscurv.read(path)[0].tolist() == p.tolist()
/// True
#[pyfunction]
#[pyo3(signature = (path, data, *, format=None, ascii=false, force=false))]
pub(crate) fn write(
    py: Python<'_>,
    path: PathBuf,
    data: &Bound<'_, PyAny>,
    format: Option<&str>,
    ascii: bool,
    force: bool,
) -> PyResult<()> {
    let format = crate::format(format)?;
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

/// Checks, before any work, that `output` can be written as [`_write_like`] will write it
/// for `input` (a known extension, not the input, a directory that exists and that this
/// user can create a file in): `mlscurv.dask.curvature_files` runs it on the workers first.
#[pyfunction]
#[pyo3(signature = (input, output, *, force=false))]
pub(crate) fn _check_output(
    py: Python<'_>,
    input: PathBuf,
    output: PathBuf,
    force: bool,
) -> PyResult<()> {
    py.detach(|| pipeline::check_output(&[input.as_path()], &output, None, force, false, None))
        .map(drop)
        .map_err(file_error)
}

/// Writes the points of `input` with `data` (a mapping of a result's columns but the
/// coordinates, one row per point of `input`) to `output` as `mlscurv curvature input -o
/// output` writes its result: with the input's attributes
/// after the coordinates and normals (renamed where a result column has the name) and, for a
/// LAS input, its layout. The writer of `mlscurv.dask.curvature_files`.
#[pyfunction]
#[pyo3(signature = (input, output, data, *, force=false))]
pub(crate) fn _write_like(
    py: Python<'_>,
    input: PathBuf,
    output: PathBuf,
    data: &Bound<'_, pyo3::types::PyMapping>,
    force: bool,
) -> PyResult<()> {
    let mut owned = Vec::new();
    for item in data.items()?.iter() {
        let (key, value): (String, Bound<'_, PyAny>) = item.extract()?;
        owned_columns(&key, &value, &mut owned)?;
    }
    py.detach(|| -> anyhow::Result<()> {
        // Any count, none too: an empty tile of a survey grid gets its empty output.
        let cloud = pipeline::read_any(&input, None, None)?;
        let n = cloud.points.len();
        if let Some(c) = owned.iter().find(|c| c.len() != n) {
            anyhow::bail!(
                "column {:?}: {} rows for the {n} points of {}",
                c.name(),
                c.len(),
                input.display()
            );
        }
        let mut carried = pipeline::Carried::new(cloud.attributes, cloud.las, true);
        let out = pipeline::check_output(&[input.as_path()], &output, None, force, false, None)?;
        carried.check(out.format(), &input)?;
        let mut columns: Vec<Column<'_>> = [Axis::X, Axis::Y, Axis::Z]
            .into_iter()
            .zip(["x", "y", "z"])
            .map(|(axis, name)| Column::component(name, &cloud.points, axis))
            .collect();
        columns.extend(owned.iter().map(Owned::column));
        carried.rename_clashes(&columns, &input);
        let columns = carried.insert(columns, 6);
        out.write(&columns, false, carried.las.as_ref())
    })
    .map_err(file_error)
}
