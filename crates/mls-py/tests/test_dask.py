"""`mlscurv.dask` on a LocalCluster of two worker processes: the tiled graph gives the single
call's numbers bit for bit (given normals and h), close ones with estimated normals, and the
single call's errors."""

import ast
import doctest
import pickle
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest

dask = pytest.importorskip("dask")
da = pytest.importorskip("dask.array")
distributed = pytest.importorskip("distributed")

import mlscurv  # noqa: E402
import mlscurv.dask  # noqa: E402

SEED = 7
H = 0.8
# 64 MiB is the fixed part of a budget and 400 bytes a loaded point: about 5,200 points a
# tile, so that 60,000 points with their halos need more than 8 tiles.
SMALL = "66MiB"
CHUNK = 7_500


def terrain(n: int, side: float, seed: int):
    """Rolling terrain far from the origin, uniformly at random (so in no spatial order),
    with its exact unit normals."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(0, side, size=(2, n))
    z = 2 * np.sin(x / 7) + 1.5 * np.cos(y / 5) + 0.05 * x
    fx, fy = 2 / 7 * np.cos(x / 7) + 0.05, -1.5 / 5 * np.sin(y / 5)
    norm = np.sqrt(fx * fx + fy * fy + 1)
    points = np.column_stack([x + 420_000.0, y + 5_100_000.0, z + 300.0])
    return points, np.column_stack([-fx / norm, -fy / norm, 1 / norm])


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def cloud():
    return terrain(60_000, 150.0, SEED)


def assert_same(lazy: dict, whole, bitwise: bool = True):
    (got,) = dask.compute(lazy)
    assert set(got) == {"points"} | {k for k in dir(whole) if not k.startswith("_")} - {
        "scale", "scale_source", "normals_source", "timings", "warnings", "keys", "to_dict",
    }
    for name, value in got.items():
        expected = getattr(whole, name)
        assert value.dtype == expected.dtype and value.shape == expected.shape, name
        assert np.array_equal(value, expected, equal_nan=True), name


def test_plan_has_many_tiles_and_complete_halos(cloud):
    """The plan the graph uses: at least 8 tiles here; every tile loads every point within the
    reach of its own points (checked by brute force on a subset), and it survives pickling."""
    points, normals = cloud
    dp = da.from_array(points, chunks=CHUNK)
    capacity = mlscurv.dask._capacity(SMALL)
    plan, *_ = mlscurv.dask._plan(
        dp, None, h=H, cutoff=5.0, method="jet", capacity=capacity,
        max_cells=mlscurv.dask.MAX_CELLS,
    )
    assert len(plan) >= 8
    again = pickle.loads(pickle.dumps(plan))
    assert np.array_equal(again.tile_of(points), plan.tile_of(points))

    sample = points[:6_000]
    own = plan.tile_of(sample)
    rows, tiles = plan.loads(sample)
    assert np.all(np.isin(own, np.arange(len(plan))))
    # The graph's edges from the grid's cells: a superset of the tiles the points need.
    cells = np.flatnonzero(mlscurv._mlscurv._Grid(
        points.min(0).tolist(), points.max(0).tolist(), mlscurv.dask.MAX_CELLS
    ).counts(sample))
    own_tiles, near_tiles = plan.tiles_of_cells(cells)
    assert set(own.tolist()) == set(own_tiles.tolist())
    assert set(tiles.tolist()) <= set(near_tiles.tolist())
    # Its own tile loads each point.
    assert {(r, own[r]) for r in range(len(sample))} <= set(zip(rows.tolist(), tiles.tolist()))
    for t in range(len(plan)):
        core = sample[own == t]
        outside = sample[~np.isin(np.arange(len(sample)), rows[tiles == t])]
        if len(core) == 0 or len(outside) == 0:
            continue
        d2 = ((outside[:, None, :] - core[None, :, :]) ** 2).sum(-1).min(axis=1)
        assert np.sqrt(d2.min()) > plan.reach, t


@pytest.mark.parametrize(
    "method, rows",
    [("jet", (CHUNK,) * 8), ("paper", (20_000, 1, 14_999, 25_000))],
)
def test_equals_the_single_call_bitwise(client, cloud, method, rows):
    """Eight equal chunks, or uneven ones with a chunk of one point: the single call's bits."""
    points, normals = cloud
    lazy = mlscurv.dask.curvature(
        da.from_array(points, chunks=(rows, 3)),
        da.from_array(normals, chunks=(rows, 3)),
        h=H,
        method=method,
        memory=SMALL,
    )
    assert lazy["k1"].chunks == (rows,)
    assert_same(lazy, mlscurv.curvature(points, normals, h=H, method=method))


def test_files_equal_the_single_call_on_their_concatenation(client, cloud, tmp_path):
    """Four LAS tiles (strips of the terrain) with normals and an intensity, and an empty one
    among them (a survey grid's tile with no points): each output file holds the single
    call's numbers on the concatenated cloud, and the intensity; the empty one is empty."""
    points, normals = cloud
    rng = np.random.default_rng(SEED)
    intensity = rng.integers(0, 4096, size=len(points)).astype(np.uint16)
    strip = np.minimum((points[:, 0] - points[:, 0].min()) // 37.5, 3).astype(int)
    paths = []
    # Strip 99 has no points.
    for i, s in enumerate([0, 1, 99, 2, 3]):
        path = tmp_path / f"t{i}.las"
        take = strip == s
        mlscurv.write(
            path, {"points": points[take], "normals": normals[take], "intensity": intensity[take]}
        )
        paths.append(path)
    out = tmp_path / "out"
    out.mkdir()
    written = mlscurv.dask.curvature_files(paths, out, h=H, method="paper", memory=SMALL)
    assert written == [str(out / p.name) for p in paths]

    read = [mlscurv.read(p, attributes=True) for p in paths]
    whole = mlscurv.curvature(
        np.concatenate([r[0] for r in read]), np.concatenate([r[1] for r in read]), h=H,
        method="paper",
    )
    first = 0
    for (p, n, attrs), w in zip(read, written):
        got_p, got_n, got = mlscurv.read(w, attributes=True)
        rows = slice(first, first + len(p))
        first += len(p)
        assert np.array_equal(got_p, p)
        assert np.array_equal(got_n, whole.normals[rows], equal_nan=True)
        for name in ("k1", "k2", "mean", "gauss", "status"):
            assert np.array_equal(got[name], whole[name][rows], equal_nan=True), name
        assert np.array_equal(got["d1x"], whole["d1x"][rows], equal_nan=True)
        assert np.array_equal(got["intensity"], attrs["intensity"])
    assert first == len(points)


def test_files_outputs_that_cannot_be_written_are_refused_before_any_work(client, cloud, tmp_path):
    """An output in a directory that cannot exist (its parent is a regular file) is refused
    before the inputs are read: the second input is missing, and reading it would fail
    first otherwise."""
    points, normals = cloud
    good = tmp_path / "t0.las"
    mlscurv.write(good, {"points": points[:1000], "normals": normals[:1000]})
    blocker = tmp_path / "file"
    blocker.write_text("")
    outs = [blocker / "a.las", blocker / "b.las"]
    with pytest.raises((ValueError, OSError)) as error:
        mlscurv.dask.curvature_files(
            [good, tmp_path / "missing.las"], outs, h=H, memory=SMALL
        )
    message = str(error.value)
    # The workers check the outputs in parallel: either may be the one reported.
    assert any(message.startswith(f"{o}: ") for o in outs), message
    assert "is not a directory" in message, message
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "t0.las"]


def test_estimated_normals_are_close(client, cloud):
    """Normals estimated per tile from the points within its halo: nearly every k1 is the
    single call's to 1e-9."""
    points, _ = cloud
    lazy = mlscurv.dask.curvature(
        da.from_array(points, chunks=CHUNK), h=H, orient="up", memory=SMALL
    )
    (k1,) = dask.compute(lazy["k1"])
    whole = mlscurv.curvature(points, h=H, orient="up")
    close = np.isclose(k1, whole.k1, rtol=1e-9, atol=0, equal_nan=True)
    assert close.mean() >= 0.99, close.mean()


def random_sphere(n: int, radius: float, seed: int):
    """Points uniformly at random on a sphere about the origin."""
    v = np.random.default_rng(seed).normal(size=(n, 3))
    return radius * v / np.linalg.norm(v, axis=1)[:, None]


def test_tiles_that_disagree_on_the_estimated_normals_signs_are_reported(client, tmp_path):
    """Each tile orients its own estimated normals. On terrain every overlap agrees; a closed
    sphere in tiles, each oriented up, disagrees in a seventh of its overlaps (the binary's
    tiled run warns below 99 %), and half its k1 are negative: `overlap_agreement` says so and
    `curvature_files` warns, naming the file. A viewpoint inside orients every tile one way."""
    points, _ = terrain(60_000, 150.0, SEED)
    flat = mlscurv.dask.curvature(
        da.from_array(points, chunks=CHUNK), h=H, method="paper", memory=SMALL
    )
    (share,) = dask.compute(flat["overlap_agreement"])
    assert share >= mlscurv.dask.MIN_OVERLAP_AGREEMENT, share

    sphere = random_sphere(30_000, 10.0, SEED)
    shares = {}
    for orient in ["up", "viewpoint:0,0,0"]:
        lazy = mlscurv.dask.curvature(
            da.from_array(sphere, chunks=CHUNK), h=0.4, method="paper", orient=orient,
            memory=SMALL,
        )
        shares[orient], k1 = dask.compute(lazy["overlap_agreement"], lazy["k1"])
        if orient == "up":
            assert 0.2 < np.mean(k1 < 0) < 0.8
    assert shares["up"] < 0.95, shares
    assert shares["viewpoint:0,0,0"] >= mlscurv.dask.MIN_OVERLAP_AGREEMENT, shares

    for cloud_points, warned in [(sphere, True), (points, False)]:
        path = tmp_path / ("sphere.ply" if warned else "terrain.ply")
        mlscurv.write(path, {"points": cloud_points})
        out = tmp_path / f"out-{path.name}"
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            mlscurv.dask.curvature_files(
                [path], [out], h=0.4 if warned else H, method="paper", memory=SMALL
            )
        said = [str(w.message) for w in caught if "differ between tiles" in str(w.message)]
        assert bool(said) == warned, said
        assert all(w.startswith(f"{path}: ") for w in said), said


def test_given_normals_have_no_overlap_agreement(cloud):
    """With given normals no tile orients anything: the result has no `overlap_agreement`."""
    points, normals = cloud
    lazy = mlscurv.dask.curvature(
        da.from_array(points, chunks=CHUNK), da.from_array(normals, chunks=(CHUNK, 3)), h=H,
        memory=SMALL,
    )
    assert "overlap_agreement" not in lazy


def test_inconsistent_file_normals_are_warned_about(cloud):
    """Each tile judges the file normals' signs as the single call does: 4 % flipped is
    warned about (run in this process, where the warning can be caught), consistent ones are
    not."""
    points, normals = cloud
    flipped = normals.copy()
    flipped[::25] *= -1
    for given, warned in [(flipped, True), (normals, False)]:
        lazy = mlscurv.dask.curvature(
            da.from_array(points, chunks=CHUNK),
            da.from_array(given, chunks=(CHUNK, 3)),
            h=H,
            method="paper",
            memory=SMALL,
        )
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            dask.compute(lazy["k1"], scheduler="sync")
        said = [str(w.message) for w in caught if "not consistently oriented" in str(w.message)]
        assert bool(said) == warned, said
        assert all("(tile " in w for w in said), said


def message(call) -> str:
    with pytest.raises(ValueError) as e:
        call()
    return str(e.value)


def test_bad_input_raises_the_single_calls_errors(client, cloud):
    points, normals = cloud
    bad = points.copy()
    bad[23_456, 1] = np.nan
    expected = message(lambda: mlscurv.curvature(bad, h=H))
    assert "point 23456 is not finite" in expected
    got = message(lambda: mlscurv.dask.curvature(da.from_array(bad, chunks=CHUNK), h=H))
    assert got == expected

    flat = points[:, :2]
    expected = message(lambda: mlscurv.curvature(flat, h=H))
    got = message(lambda: mlscurv.dask.curvature(da.from_array(flat, chunks=CHUNK), h=H))
    assert got == expected

    short = normals[:100]
    expected = message(lambda: mlscurv.curvature(points, short, h=H))
    got = message(
        lambda: mlscurv.dask.curvature(da.from_array(points, chunks=CHUNK), short, h=H)
    )
    assert got == expected

    few = points[:3]
    assert message(lambda: mlscurv.dask.curvature(da.from_array(few), h=H)) == message(
        lambda: mlscurv.curvature(few, h=H)
    )
    for option in (dict(method="spline"), dict(orient="sideways"), dict(h=-1.0)):
        args = {"h": H, **option}
        assert message(
            lambda: mlscurv.dask.curvature(da.from_array(points, chunks=CHUNK), **args)
        ) == message(lambda: mlscurv.curvature(points, **args))
    # The paper's untruncated kernel reaches every point (the jet's radius bounds its reach).
    with pytest.raises(ValueError, match=re.escape("cutoff: a tiled run needs a kernel cutoff")):
        mlscurv.dask.curvature(
            da.from_array(points, chunks=CHUNK), h=H, cutoff="none", method="paper"
        )
    # The budget as given, and the least one rounded up (64 MiB and 400,000 bytes), as the
    # binary says it.
    for memory in ("64MiB", 64 << 20):
        with pytest.raises(ValueError) as error:
            mlscurv.dask.curvature(da.from_array(points, chunks=CHUNK), h=H, memory=memory)
        assert str(error.value) == (
            f"memory={memory!r}: too small; a tiled run needs at least 65 MiB"
        )


def test_docstring_example():
    """The example of `mlscurv.dask.curvature` (it starts its own cluster)."""
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    tests = doctest.DocTestFinder().find(mlscurv.dask.curvature, "curvature", globs={})
    assert any(t.examples for t in tests)
    with warnings.catch_warnings():
        # Its cluster's dashboard takes another port when the fixture's holds 8787.
        warnings.simplefilter("ignore", UserWarning)
        for test in tests:
            runner.run(test)
    assert runner.failures == 0


def test_readme_example_runs_as_written(tmp_path):
    """The README's Dask example, taken verbatim from README.md and run as a script (in a
    directory of its own, where it writes its survey tiles and their outputs): its worker
    processes import it, which the `__main__` guard allows. It prints what the README shows
    after it, and writes the files it names."""
    from conftest import readme_example

    code, shown = readme_example("### Python: Dask")
    script = tmp_path / "example.py"
    script.write_text(code, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == shown
    lines = done.stdout.splitlines()
    assert float(lines[0].rsplit(" ", 1)[1]) >= 0.99, lines[0]  # tiles that overlap
    for path in ast.literal_eval(lines[1]):
        points, _, columns = mlscurv.read(tmp_path / path, attributes=True)
        assert len(points) == 5_000 and "k1" in columns, path
