//! `curvature`, `normals` and `project`: the commands' steps through `mls_pipeline` on arrays.

use mls_core::{Parallelism, Point};
use mls_pipeline::evaluate::{self, CurvatureColumns};
use mls_pipeline::pipeline::{self, Timings};
use mls_pipeline::progress::NoProgress;
use mls_pipeline::{Cloud, CurvatureOptions, CurvatureRun, Method, NormalsMode, SurfaceOptions};
use numpy::PyArrayMethods;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::result::{Table, scalars, vectors};
use crate::{
    CutoffArg, Input, POINTS, Summary, as_points, pipeline_error, scale_options, to_value_error,
    warn,
};

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
///     ``"jet"`` (default): weighted degree-4 fits, and without normals also degree-2 fits on
///     larger supports (noisy scans), the degree and support chosen per point, with a
///     predicted error (``k1_sd``, ``k2_sd``); without normals a stray point gets status 8
///     (outlier). ``"paper"``: the Amenta–Kil MLS surface in closed form (Yang & Qian 2007).
/// at : "input" or "projected"
///     Evaluate at the input points (default) or at their projections onto the surface.
/// orient : str, optional
///     Orientation of estimated normals: ``"mst"`` (outward), ``"up"``,
///     ``"viewpoint:X,Y,Z"`` or ``"none"``. Default: as ``mlscurv``, outward, or up for a
///     sheet seen from above (three quarters of the outward normals within 60° of vertical on
///     one side, as terrain and roofs; a closed object has half).
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
    method="jet", at="input", orient=None, adaptive=false, threads=None
))]
#[pyo3(
    text_signature = "(points, normals=None, *, h=None, h_factor=2.0, cutoff=5.0, method='jet', at='input', orient=None, adaptive=False, threads=None)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn curvature<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    h: Option<f64>,
    h_factor: Option<f64>,
    cutoff: Option<CutoffArg>,
    method: &str,
    at: &str,
    orient: Option<&str>,
    adaptive: bool,
    threads: Option<usize>,
) -> PyResult<Table> {
    let (h, h_factor) = scale_options(h, h_factor)?;
    let options = CurvatureOptions {
        surface: SurfaceOptions {
            h,
            h_factor,
            cutoff: crate::cutoff(cutoff)?,
            normals: NormalsMode::Auto,
            orient: orient.map(crate::orient).transpose()?,
        },
        method: crate::method(method)?,
        at: crate::at(at)?,
        adaptive,
    };
    let threads = crate::threads(threads)?;
    if options.adaptive && options.method == Method::Jet {
        return Err(PyValueError::new_err(mls_pipeline::ADAPTIVE_NEEDS_PAPER));
    }
    let Input { array, normals } = Input::new(points, normals)?;
    let readonly = array.readonly();
    let points = as_points(readonly.as_slice().map_err(to_value_error)?);
    let points: &[Point] = &points;
    let (mut out, summary) = py
        .detach(|| {
            pipeline::with_threads(threads, || {
                let mut t = Timings::default();
                let mut warnings = Vec::new();
                let CurvatureRun {
                    columns: out,
                    scale,
                    normals_source,
                    ..
                } = mls_pipeline::curvature(
                    Cloud {
                        points,
                        normals,
                        viewpoints: None,
                        name: POINTS,
                    },
                    &options,
                    &mut t,
                    |w| warnings.push(w),
                )?;
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
    let positions = out.projected.take().map(|p| vectors(py, p)).transpose()?;
    let positions = positions.unwrap_or_else(|| array.into_any().unbind());
    let arrays = curvature_arrays(py, out, positions)?;
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
/// orient : str, optional
///     ``"mst"`` (outward, by minimum spanning tree), ``"up"`` (+z, airborne scans),
///     ``"viewpoint:X,Y,Z"`` (towards a scanner) or ``"none"``. Default: as ``mlscurv``,
///     outward, or up for a sheet seen from above.
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
#[pyo3(signature = (points, *, h=None, h_factor=None, orient=None, threads=None))]
#[pyo3(text_signature = "(points, *, h=None, h_factor=2.0, orient=None, threads=None)")]
pub(crate) fn normals<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    h: Option<f64>,
    h_factor: Option<f64>,
    orient: Option<&str>,
    threads: Option<usize>,
) -> PyResult<Table> {
    let (h, h_factor) = scale_options(h, h_factor)?;
    let orient = orient.map(crate::orient).transpose()?;
    let threads = crate::threads(threads)?;
    let Input { array, .. } = Input::new(points, None)?;
    let readonly = array.readonly();
    let points = as_points(readonly.as_slice().map_err(to_value_error)?);
    let points: &[Point] = &points;
    let ((normal, status), summary) = py
        .detach(|| {
            pipeline::with_threads(threads, || {
                let mut t = Timings::default();
                let par = Parallelism::Rayon;
                let index = t.time("index", || {
                    pipeline::index(points, mls_core::Frame::of(points), POINTS)
                })?;
                let scale = t.time("spacing", || {
                    pipeline::choose_h_on(&index, h, h_factor, par, POINTS)
                })?;
                let est = t.time("normals", || {
                    pipeline::normals(
                        None,
                        points,
                        Some(&index),
                        NormalsMode::Estimate,
                        orient,
                        None,
                        scale.h,
                        par,
                        POINTS,
                    )
                })?;
                let summary = Summary {
                    scale,
                    normals_source: est.source,
                    timings: t,
                    warnings: est.warning.into_iter().collect(),
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
pub(crate) const XYZ_N_STATUS: [&str; 7] = ["x", "y", "z", "nx", "ny", "nz", "status"];

pub(crate) fn names(names: &[&str]) -> Vec<String> {
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
    orient=None, threads=None
))]
#[pyo3(
    text_signature = "(points, normals=None, *, h=None, h_factor=2.0, cutoff=5.0, orient=None, threads=None)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn project<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: Option<&Bound<'py, PyAny>>,
    h: Option<f64>,
    h_factor: Option<f64>,
    cutoff: Option<CutoffArg>,
    orient: Option<&str>,
    threads: Option<usize>,
) -> PyResult<Table> {
    let (h, h_factor) = scale_options(h, h_factor)?;
    let options = SurfaceOptions {
        h,
        h_factor,
        cutoff: crate::cutoff(cutoff)?,
        normals: NormalsMode::Auto,
        orient: orient.map(crate::orient).transpose()?,
    };
    let threads = crate::threads(threads)?;
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
                    None,
                    POINTS,
                    &options,
                    &mut t,
                    |w| warnings.push(w),
                    pipeline::fixed_surface,
                )?;
                let out = t.time("projection", || {
                    evaluate::projection(points, &built.surface, &NoProgress)
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

/// g, its gradient and Hessian, the normal field and the curvature of the MLS surface of an
/// oriented cloud at query points, as ``mlscurv eval`` computes them (the paper's closed form
/// at each query, which need not lie on the surface).
///
/// Parameters
/// ----------
/// points : array_like, shape (N, 3)
///     The cloud (at least 4 finite points).
/// normals : array_like, shape (N, 3)
///     Its oriented normals (non-zero; normalised here).
/// queries : array_like, shape (M, 3)
///     Where to evaluate (finite; any number).
/// h : float, optional
///     The scale (default: 2 × the median local spacing, as the command).
/// cutoff : float or "none"
///     The kernel's truncation in units of h (default 5).
/// threads : int, optional
///     Worker threads (default: all cores).
///
/// Returns
/// -------
/// Result
///     ``points`` (the queries), ``g``, ``gx`` … ``gz``, ``hxx`` … ``hzz``, ``normals`` (the
///     normal field n), ``k1``, ``k2``, ``mean``, ``gauss`` and ``status``: the command's columns
///     ``x y z g gx gy gz hxx hxy hxz hyy hyz hzz nx ny nz k1 k2 mean gauss status``.
///
/// Examples
/// --------
/// >>> import numpy as np, mlscurv
/// >>> i = np.arange(4000) + 0.5
/// >>> z = 1 - 2 * i / 4000; t = np.pi * (1 + 5 ** 0.5) * i; r = np.sqrt(1 - z * z)
/// >>> sphere = np.column_stack([r * np.cos(t), r * np.sin(t), z])
/// >>> e = mlscurv.eval(sphere, sphere, [[0.0, 0.0, 1.0], [0.0, 0.0, 1.02]])
/// >>> np.round(e.k1, 2).tolist(), e.status.tolist()
/// ([1.0, 0.99], [0, 0])
#[pyfunction]
#[pyo3(signature = (points, normals, queries, *, h=None, cutoff=Some(CutoffArg::Factor(5.0)), threads=None))]
#[pyo3(text_signature = "(points, normals, queries, *, h=None, cutoff=5.0, threads=None)")]
pub(crate) fn eval<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    normals: &Bound<'py, PyAny>,
    queries: &Bound<'py, PyAny>,
    h: Option<f64>,
    cutoff: Option<CutoffArg>,
    threads: Option<usize>,
) -> PyResult<Table> {
    let (h, _) = scale_options(h, None)?;
    let cutoff = crate::cutoff(cutoff)?;
    let threads = crate::threads(threads)?;
    let Input { array, normals } = Input::new(points, Some(normals))?;
    let normals = normals.unwrap_or_default();
    let queries = crate::coordinates(queries, "queries")?;
    let readonly = array.readonly();
    let points = as_points(readonly.as_slice().map_err(to_value_error)?);
    let points: &[Point] = &points;
    let q_readonly = queries.readonly();
    let q_flat = q_readonly.as_slice().map_err(to_value_error)?;
    crate::check_finite(q_flat, "queries", "query")?;
    let q = as_points(q_flat);
    let q: &[Point] = &q;
    let (table, summary) = py
        .detach(|| {
            pipeline::with_threads(threads, || {
                let mut t = Timings::default();
                let mut warnings = Vec::new();
                let (scale, surface) =
                    pipeline::eval_surface(points, &normals, h, cutoff, POINTS, &mut t, |w| {
                        warnings.push(w)
                    })?;
                let results = t.time("evaluation", || {
                    surface.curvature_at_points(q, Parallelism::Rayon)
                });
                let table = evaluate::EvalTable::new(&results, q);
                let summary = Summary {
                    scale,
                    normals_source: "given".to_owned(),
                    timings: t,
                    warnings,
                };
                Ok((table, summary))
            })
        })
        .map_err(pipeline_error)?;
    drop(readonly);
    drop(q_readonly);
    warn(py, &summary.warnings)?;
    let evaluate::EvalTable { values, status } = table;
    let mut values = values.into_iter();
    let mut take = |k: usize| -> Vec<Vec<f64>> { values.by_ref().take(k).collect() };
    let xyz = take(3);
    let scalars_before = take(10);
    let n = take(3);
    let curvature = take(4);
    let triple = |c: &[Vec<f64>]| -> Vec<[f64; 3]> {
        (0..c[0].len())
            .map(|i| [c[0][i], c[1][i], c[2][i]])
            .collect()
    };
    let mut arrays = vec![
        ("points", vectors(py, triple(&xyz))?),
        ("normals", vectors(py, triple(&n))?),
    ];
    for (name, v) in evaluate::EVAL_COLUMNS[3..13].iter().zip(scalars_before) {
        arrays.push((name, scalars(py, v)));
    }
    for (name, v) in evaluate::EVAL_COLUMNS[16..20].iter().zip(curvature) {
        arrays.push((name, scalars(py, v)));
    }
    arrays.push(("status", scalars(py, status)));
    Ok(Table::new(
        "eval",
        names(&evaluate::EVAL_COLUMNS),
        arrays,
        summary,
    ))
}

/// The arrays of a `curvature` result from the command's columns, the points evaluated at
/// given as `positions`.
pub(crate) fn curvature_arrays(
    py: Python<'_>,
    out: CurvatureColumns,
    positions: Py<PyAny>,
) -> PyResult<Vec<(&'static str, Py<PyAny>)>> {
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
        adaptive,
        jet,
        ..
    } = out;
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
    Ok(arrays)
}
