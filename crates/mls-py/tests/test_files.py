"""`read` and `write`: every format of the command, the command's messages, Python's
exception types for the operating system's errors."""

import os
import stat
import warnings

import numpy as np
import pytest

import mlscurv
from conftest import BUNNY, torus


@pytest.fixture(scope="module")
def cloud():
    return torus(500, seed=4)


@pytest.mark.parametrize("ext", ["ply", "csv", "xyz", "txt", "pts", "asc"])
def test_round_trip_is_exact(tmp_path, cloud, ext):
    points, normals = cloud
    path = tmp_path / f"cloud.{ext}"
    mlscurv.write(path, {"points": points, "normals": normals})
    p, n = mlscurv.read(path)
    assert p.tobytes() == points.tobytes() and n.tobytes() == normals.tobytes()


@pytest.mark.parametrize("ext", ["las", "laz"])
def test_las_round_trip_on_its_grid(tmp_path, cloud, ext):
    points, normals = cloud
    path = tmp_path / f"cloud.{ext}"
    mlscurv.write(path, {"points": points, "normals": normals})
    p, n = mlscurv.read(path)
    # LAS stores coordinates on a grid of about 1e-8 of the extent; nx ny nz as f64 extra bytes.
    assert np.abs(p - points).max() < 1e-7
    assert n.tobytes() == normals.tobytes()


def test_ascii_ply_and_format_argument(tmp_path, cloud):
    points, _ = cloud
    path = tmp_path / "cloud.dat"
    mlscurv.write(path, points, format="ply", ascii=True)
    assert path.read_bytes().startswith(b"ply\nformat ascii 1.0\n")
    with pytest.raises(ValueError, match=r"unknown extension.*format=\"ply\""):
        mlscurv.read(path)
    assert mlscurv.read(path, format="ply")[0].tobytes() == points.tobytes()


def test_result_columns_and_types(tmp_path, cloud):
    points, normals = cloud
    result = mlscurv.curvature(points, normals, method="paper")
    path = tmp_path / "k.csv"
    mlscurv.write(path, result)
    # The header follows CloudCompare's form, `//x,y,z,...`.
    header = path.read_text().splitlines()[0].removeprefix("//").split(",")
    assert header == result.keys()
    # Read back: positions and normals (the reader takes nx ny nz), the rest are its notes.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p, n = mlscurv.read(path)
    assert p.tobytes() == points.tobytes()
    assert n.tobytes() == np.ascontiguousarray(result.normals).tobytes()


def test_columns_argument_names_text_columns(tmp_path, cloud):
    points, normals = cloud
    path = tmp_path / "cloud.xyz"
    # Normals scaled: not unit, so a headerless reader would not take them as normals.
    np.savetxt(path, np.column_stack([points, 2 * normals, np.ones(len(points))]))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        p, n = mlscurv.read(path)
    assert n is None and caught, "the reader's note says why columns 4-6 are not normals"
    p, n = mlscurv.read(path, columns=["x", "y", "z", "nx", "ny", "nz", "intensity"])
    assert np.allclose(n, 2 * normals)
    with pytest.raises(ValueError, match="^columns: "):
        mlscurv.read(path, columns="x,y")


def test_attributes_in_their_stored_types(tmp_path, cloud):
    points, _ = cloud
    path = tmp_path / "cloud.csv"
    label = np.arange(len(points)) % 7
    weight = np.linspace(0.0, 1.0, len(points))
    mlscurv.write(path, {"points": points, "label": label, "weight": weight})
    p, n, attributes = mlscurv.read(path, attributes=True)
    assert p.tobytes() == points.tobytes() and n is None
    assert list(attributes) == ["label", "weight"]
    assert attributes["label"].dtype.kind == "i" and attributes["label"].tolist() == label.tolist()
    assert attributes["weight"].dtype == np.float64
    assert attributes["weight"].tobytes() == weight.tobytes()
    assert len(mlscurv.read(path)) == 2


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothing.ply"):
        mlscurv.read(tmp_path / "nothing.ply")
    with pytest.raises(IsADirectoryError):
        mlscurv.read(tmp_path)
    with pytest.raises(ValueError, match="no file extension"):
        mlscurv.read(tmp_path / "noext")


def test_bad_contents_message_names_the_place(tmp_path):
    path = tmp_path / "bad.xyz"
    path.write_text("0 0 0\n1 1 nan\n")
    with pytest.raises(ValueError, match=r"bad.xyz: line 2"):
        mlscurv.read(path)


def test_write_refusals_use_python_words(tmp_path, cloud):
    points, _ = cloud
    with pytest.raises(ValueError, match=r'unknown extension "\.foo".*format="ply"'):
        mlscurv.write(tmp_path / "x.foo", points)
    with pytest.raises(ValueError, match='format="csv" disagrees'):
        mlscurv.write(tmp_path / "x.ply", points, format="csv")
    with pytest.raises(ValueError, match="directory"):
        mlscurv.write(tmp_path / "missing" / "x.ply", points)
    path = tmp_path / "ro.ply"
    mlscurv.write(path, points)
    os.chmod(path, stat.S_IRUSR)
    if os.access(path, os.W_OK):
        pytest.skip("running as a user who may write read-only files")
    with pytest.raises(ValueError, match="read-only.*pass force=True"):
        mlscurv.write(path, points[:10])
    mlscurv.write(path, points[:10], force=True)
    assert mlscurv.read(path)[0].shape == (10, 3)


def test_write_checks_columns(tmp_path, cloud):
    points, _ = cloud
    with pytest.raises(ValueError, match='column "k": 3 rows, but column "x" has 500'):
        mlscurv.write(tmp_path / "x.csv", {"points": points, "k": np.zeros(3)})
    with pytest.raises(ValueError, match=r'column "m": expected shape \(N,\) or \(N, 3\)'):
        mlscurv.write(tmp_path / "x.csv", {"m": np.zeros((500, 2))})
    with pytest.raises(ValueError, match="does not fit in a 32-bit integer"):
        mlscurv.write(tmp_path / "x.csv", {"points": points, "id": np.full(500, 2**40)})
    with pytest.raises(ValueError, match="standard output"):
        mlscurv.write("-", points)


def test_bunny_reads_as_the_command_reads_it():
    points, normals = mlscurv.read(str(BUNNY))
    assert points.dtype == np.float64 and points.flags.c_contiguous and normals is None
    assert points.shape == (35947, 3)
