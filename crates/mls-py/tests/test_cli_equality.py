"""The Python functions give the `mlscurv` command's output bit for bit: same columns in the
same order, same numbers, same status codes, and `mlscurv.write` writes the same file."""

import numpy as np
import pytest

import mlscurv
from conftest import BUNNY, read_ply_table, sphere, torus


def assert_same_table(result, path):
    """`result` holds exactly the columns of the PLY file at `path`, bit for bit."""
    table = read_ply_table(path)
    assert result.keys() == list(table)
    for name, column in table.items():
        mine = np.asarray(result[name])
        assert mine.dtype == column.dtype, name
        # Bitwise, NaN included: the failed points' NaNs must sit in the same places.
        assert mine.tobytes() == column.tobytes(), f"column {name} differs"


@pytest.fixture(scope="module")
def cloud_file(tmp_path_factory):
    """A noisy sphere of 3000 points, written as binary PLY (exact doubles)."""
    points = sphere(3000, seed=7, noise=0.002)
    path = tmp_path_factory.mktemp("cloud") / "sphere.ply"
    mlscurv.write(path, points)
    return points, path


@pytest.mark.parametrize("method", ["jet", "paper"])
@pytest.mark.parametrize("at", ["input", "projected"])
def test_curvature_equals_cli(cloud_file, run_cli, tmp_path, method, at):
    points, path = cloud_file
    out = tmp_path / "out.ply"
    run_cli("curvature", path, "-o", out, "--method", method, "--at", at, "--quiet")
    result = mlscurv.curvature(points, method=method, at=at)
    assert_same_table(result, out)
    assert result.points is points if at == "input" else result.points is not points


def test_curvature_with_normals_and_options_equals_cli(run_cli, tmp_path):
    points, normals = torus(4000, seed=3)
    path = tmp_path / "torus.ply"
    mlscurv.write(path, {"points": points, "normals": normals})
    out = tmp_path / "out.ply"
    run_cli("curvature", path, "-o", out, "--h", 0.06, "--cutoff", 4, "--threads", 1, "--quiet")
    result = mlscurv.curvature(points, normals, h=0.06, cutoff=4, threads=1)
    assert_same_table(result, out)
    assert result.normals_source == "from the file"
    # Both signs of curvature, with k1 >= k2 and the sign convention of the command.
    ok = result.status == 0
    assert ok.all()
    assert (result.k1[ok] >= result.k2[ok]).all()
    assert (result.gauss < 0).any() and (result.gauss > 0).any()


def test_adaptive_and_no_cutoff_equal_cli(run_cli, tmp_path):
    points = sphere(1500, seed=11, noise=0.003)
    path = tmp_path / "in.ply"
    mlscurv.write(path, points)
    out = tmp_path / "out.ply"
    run_cli(
        "curvature", path, "-o", out, "--method", "paper", "--adaptive", "--h-factor", 2.5,
        "--cutoff", "none", "--orient", "viewpoint:0,0,0", "--quiet",
    )
    result = mlscurv.curvature(
        points, method="paper", adaptive=True, h_factor=2.5, cutoff=None, orient="viewpoint:0,0,0"
    )
    assert_same_table(result, out)
    assert {"h", "noise"} <= set(result.keys())


def test_bunny_equals_cli(run_cli, tmp_path):
    """The README's main command on the bundled scan, and the same from Python."""
    out = tmp_path / "bunny-curvature.ply"
    run_cli("curvature", BUNNY, "-o", out, "--quiet")
    points, normals = mlscurv.read(BUNNY)
    assert normals is None and points.shape == (35947, 3)
    result = mlscurv.curvature(points)
    assert_same_table(result, out)
    assert result.scale_source.startswith("2 × median local spacing")
    # `mlscurv.write` of the result writes the command's file, byte for byte.
    mine = tmp_path / "mine.ply"
    mlscurv.write(mine, result)
    assert mine.read_bytes() == out.read_bytes()


def test_normals_equal_cli(cloud_file, run_cli, tmp_path):
    points, path = cloud_file
    out = tmp_path / "normals.ply"
    run_cli("normals", path, "-o", out, "--quiet")
    result = mlscurv.normals(points)
    assert_same_table(result, out)
    assert result.points is points


def test_default_orientation_of_a_sheet_equals_cli(run_cli, tmp_path):
    """A height field seen from above: by default both orient it up, not outward."""
    g = np.stack(np.meshgrid(np.arange(40.0), np.arange(40.0)), -1).reshape(-1, 2)
    z = 2.0 * np.sin(g[:, 0] / 6.0) * np.cos(g[:, 1] / 9.0)
    points = np.column_stack([g, z])
    path = tmp_path / "sheet.ply"
    mlscurv.write(path, points)
    out = tmp_path / "normals.ply"
    run_cli("normals", path, "-o", out, "--quiet")
    result = mlscurv.normals(points)
    assert_same_table(result, out)
    assert (result.normals[:, 2] > 0).all()


def test_project_equals_cli(cloud_file, run_cli, tmp_path):
    points, path = cloud_file
    out = tmp_path / "projected.ply"
    run_cli("project", path, "-o", out, "--h-factor", 3, "--quiet")
    result = mlscurv.project(points, h_factor=3)
    assert_same_table(result, out)


def test_csv_output_equals_cli(cloud_file, run_cli, tmp_path):
    """The text writer too: the command's CSV and `mlscurv.write`'s are the same bytes."""
    points, path = cloud_file
    out = tmp_path / "out.csv"
    run_cli("curvature", path, "-o", out, "--method", "paper", "--quiet")
    mine = tmp_path / "mine.csv"
    mlscurv.write(mine, mlscurv.curvature(points, method="paper"))
    assert mine.read_bytes() == out.read_bytes()


def test_eval_equals_cli(run_cli, tmp_path):
    """``eval`` at points on and off the surface (and one far away, which fails): the
    command's table, bit for bit."""
    points = sphere(3000, seed=5)
    cloud = tmp_path / "cloud.ply"
    queries = np.vstack([points[:50] * 1.01, points[50:100] * 0.97, [[40.0, 0.0, 0.0]]])
    qfile = tmp_path / "queries.ply"
    mlscurv.write(cloud, {"points": points, "normals": points})
    mlscurv.write(qfile, queries)
    out = tmp_path / "eval.ply"
    run_cli("eval", "--cloud", cloud, "--queries", qfile, "-o", out, "--h", 0.12, "--quiet")
    result = mlscurv.eval(points, points, queries, h=0.12)
    assert result.keys() == list(read_ply_table(out).keys())
    assert_same_table(result, out)
    assert result.status[-1] != 0 and np.isnan(result.k1[-1])
