//! `mlscurv.Result`: the named arrays of a function's result, with the command's columns.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyAttributeError, PyKeyError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PySlice};

use crate::Summary;

/// Where a column of the written table lives among a result's arrays: the array's attribute
/// name and, for a component of an (N, 3) array, the component.
pub(crate) fn column_source(column: &str) -> (&str, Option<usize>) {
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
pub(crate) struct Table {
    /// Arrays by attribute name, in the order the columns first use them.
    arrays: Vec<(String, Py<PyAny>)>,
    /// The column names, in the file's order.
    pub(crate) columns: Vec<String>,
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
    pub(crate) fn new(
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

    pub(crate) fn column<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
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

pub(crate) fn vectors(py: Python<'_>, v: Vec<[f64; 3]>) -> PyResult<Py<PyAny>> {
    let n = v.len();
    Ok(PyArray1::from_vec(py, v.into_flattened())
        .reshape([n, 3])?
        .into_any()
        .unbind())
}

pub(crate) fn scalars<T: numpy::Element>(py: Python<'_>, v: Vec<T>) -> Py<PyAny> {
    PyArray1::from_vec(py, v).into_any().unbind()
}
