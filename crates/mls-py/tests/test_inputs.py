"""Arrays in: what is used without a copy, what is converted, what is refused and with which
message (the command's, with `points` where it names the file)."""

import threading
import time
import warnings

import numpy as np
import pytest

import mlscurv
from conftest import CliError, sphere


@pytest.fixture(scope="module")
def points():
    return sphere(2000, seed=5)


@pytest.fixture(scope="module")
def reference(points):
    return mlscurv.curvature(points, method="paper")


def same(a, b):
    return a.keys() == b.keys() and all(
        np.asarray(a[k]).tobytes() == np.asarray(b[k]).tobytes() for k in a.keys()
    )


def test_float64_c_contiguous_is_not_copied(points, reference):
    assert reference.points is points
    assert np.shares_memory(reference["x"], points)


@pytest.mark.parametrize(
    "convert",
    [
        lambda p: p.astype(np.float32).astype(np.float64),  # reference for float32, below
        lambda p: np.asfortranarray(p),
        lambda p: np.repeat(p, 2, axis=0)[::2],  # a strided view
        lambda p: p.tolist(),
    ],
    ids=["float32-roundtrip", "fortran", "strided", "list"],
)
def test_other_layouts_give_the_same_numbers(points, reference, convert):
    converted = convert(points)
    result = mlscurv.curvature(converted, method="paper")
    if isinstance(converted, np.ndarray) and converted.dtype == np.float64 and converted.flags.c_contiguous:
        assert same(result, mlscurv.curvature(converted, method="paper"))
    else:
        assert same(result, reference)


def test_float32_and_integers_are_converted(points):
    p32 = points.astype(np.float32)
    assert same(
        mlscurv.curvature(p32, method="paper"),
        mlscurv.curvature(p32.astype(np.float64), method="paper"),
    )
    grid = np.stack(np.meshgrid(np.arange(30), np.arange(30), [0]), -1).reshape(-1, 3)
    assert grid.dtype.kind == "i"
    result = mlscurv.normals(grid, orient="up")
    assert result.points.dtype == np.float64
    assert np.array_equal(result.normals[result.status == 0], np.tile([0.0, 0.0, 1.0], (900, 1)))


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.zeros((10, 2)), "points: expected an array of shape (N, 3), got shape (10, 2)"),
        (np.zeros(9), "points: expected an array of shape (N, 3), got shape (9,)"),
        (np.zeros((2, 5, 3)), "points: expected an array of shape (N, 3), got shape (2, 5, 3)"),
    ],
)
def test_wrong_shape(bad, message):
    with pytest.raises(ValueError) as e:
        mlscurv.curvature(bad)
    assert str(e.value) == message


@pytest.mark.parametrize("dtype", [np.complex128, np.bool_, object])
def test_wrong_dtype(points, dtype):
    with pytest.raises(TypeError, match=r"points: dtype .* is not a real number type"):
        mlscurv.curvature(points.astype(dtype))


def test_strings_are_refused():
    with pytest.raises(TypeError, match="not a real number type"):
        mlscurv.curvature([["a", "b", "c"]] * 5)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite(points, value):
    bad = points.copy()
    bad[17, 1] = value
    with pytest.raises(ValueError, match=rf"(?i)^points: point 17 is not finite: \(.*{value}.*\)$"):
        mlscurv.curvature(bad)
    normals = points.copy()
    normals[3, 2] = value
    with pytest.raises(ValueError, match=r"^normals: normal 3 is not finite"):
        mlscurv.curvature(points, normals)


def test_too_few_points_message_is_the_commands(run_cli, tmp_path):
    three = np.eye(3)
    path = tmp_path / "three.ply"
    mlscurv.write(path, three)
    with pytest.raises(CliError) as cli:
        run_cli("curvature", path, "-o", tmp_path / "out.ply")
    with pytest.raises(ValueError) as py:
        mlscurv.curvature(three)
    assert str(py.value) == str(cli.value).replace(str(path), "points")
    assert str(py.value) == "points: 3 point(s); at least 4 are needed to build a neighbourhood"
    for f in (mlscurv.normals, mlscurv.project):
        with pytest.raises(ValueError, match="at least 4 are needed"):
            f(three)


def test_huge_h_message_is_the_commands(points, run_cli, tmp_path):
    path = tmp_path / "in.ply"
    mlscurv.write(path, points)
    with pytest.raises(CliError) as cli:
        run_cli("curvature", path, "-o", tmp_path / "out.ply", "--h", 1000)
    with pytest.raises(ValueError) as py:
        mlscurv.curvature(points, h=1000)
    assert str(py.value) == str(cli.value).replace(str(path), "points")
    assert "times the diagonal" in str(py.value)


def test_large_h_warns_as_the_command_does(points, run_cli, tmp_path):
    path = tmp_path / "in.ply"
    mlscurv.write(path, points)
    stderr = run_cli("curvature", path, "-o", tmp_path / "out.ply", "--h", 3, "--method", "paper", "--quiet")
    expected = [
        line.removeprefix("mlscurv: warning: ").replace(str(path), "points")
        for line in stderr.splitlines()
        if line.startswith("mlscurv: warning: ")
    ]
    assert expected
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = mlscurv.curvature(points, h=3, method="paper")
    assert [str(w.message) for w in caught if w.category is UserWarning] == expected
    assert result.warnings == expected


def test_adaptive_needs_paper_message_is_the_commands(points, run_cli, tmp_path):
    path = tmp_path / "in.ply"
    mlscurv.write(path, points)
    with pytest.raises(CliError) as cli:
        run_cli("curvature", path, "-o", tmp_path / "out.ply", "--adaptive")
    with pytest.raises(ValueError) as py:
        mlscurv.curvature(points, adaptive=True)
    assert str(py.value) == str(cli.value)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"h": -1.0}, "h: must be finite and positive, got -1"),
        ({"h": float("nan")}, "h: must be finite and positive, got NaN"),
        ({"h_factor": 0.0}, "h_factor: must be finite and positive, got 0"),
        ({"h": 0.1, "h_factor": 3.0}, "h and h_factor cannot both be given"),
        ({"cutoff": 1.5}, "cutoff: must be at least 2 (in units of h) or `none`, got 1.5"),
        ({"cutoff": "far"}, "cutoff: `far` is not a number"),
        ({"method": "cgal"}, 'method: expected "jet" or "paper", got "cgal"'),
        ({"at": "surface"}, 'at: expected "input" or "projected", got "surface"'),
        ({"orient": "sideways"}, "orient: expected `mst`, `up`, `none` or `viewpoint:X,Y,Z`, got `sideways`"),
        ({"orient": "viewpoint:1,2"}, "orient: viewpoint needs three numbers X,Y,Z, got `1,2`"),
        ({"threads": 0}, "threads: must be between 1 and 65535, got 0"),
    ],
)
def test_bad_options(points, kwargs, message):
    with pytest.raises(ValueError) as e:
        mlscurv.curvature(points, **kwargs)
    assert str(e.value).startswith(message)


def test_orient_message_is_the_commands_parser(points, run_cli, tmp_path):
    path = tmp_path / "in.ply"
    mlscurv.write(path, points)
    with pytest.raises(CliError) as cli:
        run_cli("curvature", path, "-o", tmp_path / "out.ply", "--orient", "sideways")
    with pytest.raises(ValueError) as py:
        mlscurv.curvature(points, orient="sideways")
    assert str(py.value).removeprefix("orient: ") in str(cli.value)


def test_normals_must_match_points(points):
    with pytest.raises(ValueError, match=r"^normals: 1999 rows for 2000 points"):
        mlscurv.curvature(points, points[1:])
    with pytest.raises(ValueError, match=r"^normals: expected an array of shape \(N, 3\)"):
        mlscurv.curvature(points, points[:, :2])


def test_zero_normals_are_left_out(points):
    normals = points.copy()
    normals[:10] = 0.0
    result = mlscurv.curvature(points, normals)
    assert result.normals_source == "from the file (10 zero normals left out of the surface)"


def test_result_interface(reference, points):
    assert "k1" in reference and "k1_sd" not in reference
    assert list(reference) == reference.keys()
    d = reference.to_dict()
    assert list(d) == reference.keys()
    assert np.array_equal(d["ny"], reference.normals[:, 1])
    assert reference.status.dtype == np.int32
    assert set(mlscurv.STATUS) == set(range(9)) and mlscurv.STATUS[8] == "outlier"
    with pytest.raises(AttributeError, match="has no attribute 'k1_sd'"):
        reference.k1_sd
    with pytest.raises(KeyError):
        reference["points"]
    assert set(reference.timings) == {"spacing", "normals", "index", "curvature"}
    assert "2000 points" in repr(reference)


def test_gil_is_released_during_computation():
    """Another Python thread runs while curvature computes."""
    cloud = sphere(40000, seed=9)
    done = threading.Event()
    start = time.perf_counter()

    def work():
        mlscurv.curvature(cloud, method="paper", threads=1)
        done.set()

    worker = threading.Thread(target=work)
    worker.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    elapsed = time.perf_counter() - start
    # Holding the GIL, the worker would leave this loop a tick or two in the whole call.
    assert elapsed < 0.05 or ticks > 10 * 0.5 * elapsed, (ticks, elapsed)
