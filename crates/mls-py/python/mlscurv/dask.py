"""Curvature of clouds larger than one machine, as a Dask graph of spatial tiles with halos.

The cloud is cut as the ``mlscurv`` binary's out-of-core run cuts it (``--memory``): the
bounding box and the points per cell of a grid give a plan of tiles, each holding with its
halo (every point within the reach of its box) at most the points a memory budget allows; each
tile's surface is built in the whole cloud's frame, so that its own points get bitwise the
numbers of one run over the whole cloud. The plan, the halo rule and the tile's computation are
the package's Rust code (``mlscurv._mlscurv._Plan``, ``_tile_curvature``); this module only
wires them into a graph:

1. *plan* (computed when ``curvature`` is called): each chunk is checked and its bounding box
   taken; each chunk counts its points per grid cell; the counts are summed and the plan made.
2. *split*: each chunk gives every tile that loads some of its points those points (their rows,
   coordinates and normals), in input order.
3. *tiles*: one task per tile gathers its parts from the chunks and computes the curvature at
   its own points.
4. *scatter*: each chunk of the result takes its points' rows back from the tiles.
5. *overlaps* (estimated normals): each tile's halo points' normal signs are compared with
   those their own tiles gave them, as the binary's tiled run compares them.

It runs on whatever cluster the ``distributed.Client`` in use reaches: a ``LocalCluster``,
dask-jobqueue's ``SLURMCluster``, dask-kubernetes' ``KubeCluster``; there is no scheduler here.
"""

from __future__ import annotations

import os
import warnings
from typing import Dict, List, Optional, Sequence, Union

import numpy as np

import dask
import dask.array as da
from dask import delayed

from . import _mlscurv

# Cells of the counting grid: 512 KiB of counts per chunk, and a plan a few hundred kilobytes
# when pickled to the workers.
MAX_CELLS = 1 << 16

# The arrays of a result of shape (N, 3); the others are of shape (N,).
_VECTORS = ("normals", "d1", "d2")

# Below this share of agreeing signs in the tiles' overlaps the estimated normals are not
# oriented one way across tiles: the binary's tiled run's threshold (0.99).
MIN_OVERLAP_AGREEMENT = _mlscurv._MIN_OVERLAP_AGREEMENT


def _columns(method: str) -> List[str]:
    """The arrays a tile's result has besides ``points``, in the command's column order."""
    names = ["normals", "k1", "k2", "mean", "gauss", "d1", "d2"]
    if method == "jet":
        names += ["k1_sd", "k2_sd"]
    return names + ["status"]


def _shape_text(shape) -> str:
    return "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _as_cloud(array, what: str, chunks=None):
    """``array`` as a float64 Dask array of shape (N, 3) whose chunks are whole rows, refused
    with ``mlscurv.curvature``'s message when it has another shape."""
    if not isinstance(array, da.Array):
        array = da.asarray(array) if chunks is None else da.from_array(np.asarray(array), chunks=chunks)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(
            f"{what}: expected an array of shape (N, 3), got shape {_shape_text(array.shape)}"
        )
    if array.dtype.kind not in "fiu":
        raise TypeError(
            f"{what}: dtype {array.dtype} is not a real number type; expected coordinates of "
            "shape (N, 3), float64 preferably (other real types are converted)"
        )
    if any(np.isnan(c) for c in array.chunks[0]):
        array = array.compute_chunk_sizes()
    return array.astype(np.float64).rechunk({1: 3})


def _tree_sum(parts):
    """The sum of delayed arrays, added pairwise so that no task receives them all."""
    parts = list(parts)
    while len(parts) > 1:
        parts = [
            delayed(np.add)(parts[i], parts[i + 1]) if i + 1 < len(parts) else parts[i]
            for i in range(0, len(parts), 2)
        ]
    return parts[0]


def _budget(memory) -> int:
    return _mlscurv._parse_size(memory) if isinstance(memory, str) else int(memory)


def _capacity(memory) -> int:
    """The points a tile may load under ``memory``, which an error names as it was given
    (``memory='64MiB'``, ``memory=67108864``)."""
    return _mlscurv._capacity(_budget(memory), f"memory={memory!r}")


def _split(plan, points, normals, first):
    """The points of one chunk (rows ``first..``) that each tile loads: ``{tile: (rows,
    points, normals or None)}``, rows in input order."""
    rows, tiles = plan.loads(points)
    order = np.argsort(tiles, kind="stable")
    rows, tiles = rows[order], tiles[order]
    bounds = np.flatnonzero(np.diff(tiles)) + 1
    parts = {}
    for r in np.split(np.arange(len(tiles)), bounds):
        if len(r) == 0:
            continue
        own = rows[r]
        parts[int(tiles[r[0]])] = (
            own + first,
            points[own],
            None if normals is None else normals[own],
        )
    return parts


def _part(parts, tile):
    return parts.get(tile)


def _tile(plan, tile, options, *parts):
    """The curvature at the own points of ``tile``, from its parts gathered from the chunks
    (in chunk order, so the points stay in input order): ``(rows, {name: array})``."""
    parts = [p for p in parts if p is not None]
    rows = np.concatenate([p[0] for p in parts])
    points = np.concatenate([p[1] for p in parts])
    normals = None if parts[0][2] is None else np.concatenate([p[2] for p in parts])
    core = plan.tile_of(points) == tile
    result, codes = _mlscurv._tile_curvature(
        points, normals, core, name=f"points (tile {tile})", **options
    )
    names = _columns(options["method"])
    # The sign codes of the estimated normals: the own points' and the halo's, by row.
    signs = None if codes is None else (codes[core], rows[~core], codes[~core])
    return rows[core], {n: getattr(result, n) for n in names}, signs


def _own_signs(result):
    """A tile's own rows and their sign codes (small: what the overlap check moves)."""
    rows, _, signs = result
    return rows, signs[0]


def _overlap(result, *owners):
    """``[agree, compared]`` over the halo points of one tile's result, each against the sign
    code its own tile gave it, by the binary's rule (``_overlap_counts``). ``owners`` are
    ``_own_signs`` of every tile that can own a point of this halo."""
    _, halo_rows, halo_codes = result[2]
    rows = np.concatenate([o[0] for o in owners]) if owners else np.empty(0, np.int64)
    codes = np.concatenate([o[1] for o in owners]) if owners else np.empty(0, np.uint8)
    order = np.argsort(rows, kind="stable")
    rows, codes = rows[order], codes[order]
    at = np.minimum(np.searchsorted(rows, halo_rows), max(len(rows) - 1, 0))
    found = (rows[at] == halo_rows) if len(rows) else np.zeros(len(halo_rows), bool)
    agree, compared = _mlscurv._overlap_counts(codes[at[found]], halo_codes[found])
    return np.array([agree, compared], np.int64)


def _share(pair):
    agree, compared = (int(v) for v in pair)
    return np.float64(agree / compared) if compared else np.float64(np.nan)


def _rows_in(result, first, end):
    """The rows of a tile's result that fall in the chunk of rows ``first..end``."""
    rows, arrays, _ = result
    take = (rows >= first) & (rows < end)
    if not take.any():
        return None
    return rows[take] - first, {n: a[take] for n, a in arrays.items()}


def _assemble(n, names, *pieces):
    """One chunk of the result from its rows' pieces, every row given by exactly one tile."""
    out = {
        k: np.empty((n, 3) if k in _VECTORS else (n,), np.int32 if k == "status" else np.float64)
        for k in names
    }
    for piece in pieces:
        if piece is not None:
            rows, arrays = piece
            for k, a in arrays.items():
                out[k][rows] = a
    return out


def _check(points, normals, first):
    return _mlscurv._check_chunk(points, normals, first)


def _plan(points, normals, *, h, cutoff, method, capacity, max_cells):
    """Step 1: checks every chunk, takes the box, counts per cell and makes the plan."""
    offsets = np.concatenate([[0], np.cumsum(points.chunks[0])]).astype(int)
    p_blocks = points.to_delayed().ravel()
    n_blocks = [None] * len(p_blocks) if normals is None else normals.to_delayed().ravel()
    boxes = dask.compute(
        *[delayed(_check)(p, q, int(o)) for p, q, o in zip(p_blocks, n_blocks, offsets)]
    )
    _mlscurv._check_count(int(offsets[-1]))
    boxes = [b for b in boxes if b is not None]
    lo = np.min([b[0] for b in boxes], axis=0).tolist()
    hi = np.max([b[1] for b in boxes], axis=0).tolist()
    grid = _mlscurv._Grid(lo, hi, max_cells)
    counts = [delayed(_counts)(grid, p) for p in p_blocks]
    total, occupied = dask.compute(_tree_sum(counts), [delayed(_occupied)(c) for c in counts])
    reach = _mlscurv._reach(h, cutoff, method, normals is None)
    plan = _mlscurv._Plan(lo, hi, total, reach, capacity, max_cells)
    # Which tiles each chunk feeds and takes results from: the graph's only edges, so that it
    # grows with the halos' overlaps, not with chunks × tiles.
    cells = [np.flatnonzero(np.unpackbits(o, count=len(grid))) for o in occupied]
    incidence = [plan.tiles_of_cells(c) for c in cells]
    return plan, lo, hi, offsets, p_blocks, n_blocks, incidence


def _graph(points, normals, *, h, cutoff, method, orient, memory, max_cells, threads):
    """Steps 1 to 5: the plan, per chunk of ``points`` a delayed dict of its result's
    arrays, and with estimated normals the delayed ``[agree, compared]`` of the overlaps
    (None with given normals)."""
    options = dict(h=h, cutoff=cutoff, method=method, orient=orient, threads=threads)
    capacity = _capacity(memory)
    _mlscurv._reach(h, cutoff, method, normals is None)  # the options' errors before any work
    _mlscurv._check_orient(orient)
    plan, lo, hi, offsets, p_blocks, n_blocks, incidence = _plan(
        points, normals, h=h, cutoff=cutoff, method=method, capacity=capacity,
        max_cells=max_cells,
    )
    options.update(lo=lo, hi=hi)
    plan_d = delayed(plan, traverse=False)
    splits = [
        delayed(_split)(plan_d, p, q, int(o)) for p, q, o in zip(p_blocks, n_blocks, offsets)
    ]
    feeds = [set(near.tolist()) for _, near in incidence]
    tiles = {
        t: delayed(_tile)(
            plan_d, t, options, *[delayed(_part)(s, t) for s, f in zip(splits, feeds) if t in f]
        )
        for t in sorted(set().union(*(own.tolist() for own, _ in incidence)))
    }
    names = _columns(method)
    chunks = [
        delayed(_assemble)(
            int(offsets[c + 1] - offsets[c]),
            names,
            *[
                delayed(_rows_in)(tiles[t], int(offsets[c]), int(offsets[c + 1]))
                for t in own.tolist()
            ],
        )
        for c, (own, _) in enumerate(incidence)
    ]
    overlap = None
    if normals is None:
        # The points tile t loads come from the chunks that feed it, and each is owned by one
        # of those chunks' own tiles.
        owners = {t: set() for t in tiles}
        for own, near in incidence:
            for t in near.tolist():
                if t in owners:
                    owners[t].update(own.tolist())
        signs = {t: delayed(_own_signs)(r) for t, r in tiles.items()}
        overlap = _tree_sum(
            delayed(_overlap)(r, *[signs[u] for u in sorted(owners[t]) if u != t])
            for t, r in tiles.items()
        )
    return plan, chunks, offsets, names, overlap


def curvature(
    points,
    normals=None,
    *,
    h: float,
    cutoff: Union[float, str, None] = 5.0,
    method: str = "jet",
    orient: str = "up",
    memory: Union[str, int] = "1GiB",
    max_cells: int = MAX_CELLS,
    threads: Optional[int] = None,
) -> Dict[str, "da.Array"]:
    """``mlscurv.curvature`` of a Dask array of points, tile by tile on a Dask cluster: the
    same numbers, bit for bit, for a given ``h`` and given normals.

    The cloud is planned into tiles as ``mlscurv curvature --memory`` plans them, each tile
    with its halo holding at most the points ``memory`` allows one task. Planning reads the
    chunks twice (the bounding box, then the points per cell) when this function is called;
    persist ``points`` first when its chunks are expensive to make. The rest is returned lazy.

    Parameters
    ----------
    points : dask.array.Array, shape (N, 3)
        The cloud, chunked by rows (columns are rechunked into one). A numpy array is wrapped.
    normals : dask.array.Array, shape (N, 3), optional
        Measured normals, chunked like ``points`` (rechunked if not). When absent, normals are
        estimated per tile, from the points within the halo, and oriented by ``orient``.
    h : float
        Gaussian scale, in the units of the points (required: the whole cloud's spacing is not
        measured here).
    cutoff : float or "none"
        Kernel truncated at ``cutoff`` · h (default 5); ``"none"`` reaches every point and
        cannot be tiled.
    method : "jet" or "paper"
        As for ``mlscurv.curvature``.
    orient : str
        Orientation of estimated normals, per tile: ``"up"`` (default, as the binary's tiled
        run), ``"viewpoint:X,Y,Z"``, ``"mst"`` (outward from each tile, rarely what a cloud
        cut in tiles needs) or ``"none"``. Each tile orients its own normals: for a closed
        object, not a sheet seen from above, pass ``normals`` or a viewpoint, and check
        ``overlap_agreement`` in the result.
    memory : str or int
        Memory one tile task may use (``"300MiB"``, ``"2GiB"``, bytes), as ``--memory``.
    max_cells : int
        Cells of the counting grid (the counts of each chunk are an array of this many).
    threads : int, optional
        Threads per tile task (default: all cores of its worker).

    Returns
    -------
    dict of dask.array.Array
        ``points`` (the input), ``normals``, ``k1``, ``k2``, ``mean``, ``gauss``, ``d1``,
        ``d2``, ``k1_sd`` and ``k2_sd`` (jet), ``status`` (int32), chunked like ``points``:
        the arrays of ``mlscurv.curvature``'s result. ``dask.compute(result)`` gives them.
        With estimated normals also ``overlap_agreement`` (0-d, float64): the share of the
        points two tiles load whose estimated normals' signs the two agree on (NaN with no
        such point). Below ``MIN_OVERLAP_AGREEMENT`` (0.99) the tiles are not oriented one
        way and the curvature's sign and size are wrong near the flips, which the binary's
        tiled run warns about (terrain measures 0.999 to 1).

    Raises
    ------
    ValueError
        Wrong shape, a non-finite value, fewer than 4 points, a bad option, or a budget too
        small for one cell's neighbourhood; with ``mlscurv.curvature``'s messages.

    Examples
    --------
    >>> import numpy as np, dask, dask.array as da, mlscurv, mlscurv.dask
    >>> from distributed import Client, LocalCluster
    >>> rng = np.random.default_rng(1)
    >>> xy = rng.uniform(0, 40, size=(20000, 2))
    >>> p = np.column_stack([xy, np.sin(xy[:, 0] / 5)])
    >>> with LocalCluster(n_workers=2, processes=True) as cluster, Client(cluster):
    ...     r = mlscurv.dask.curvature(da.from_array(p, chunks=5000), h=0.8, orient="up",
    ...                                memory="68MiB")
    ...     (k1,) = dask.compute(r["k1"])
    >>> one = mlscurv.curvature(p, h=0.8, orient="up")
    >>> float(np.mean(np.isclose(k1, one.k1, rtol=1e-9, equal_nan=True))) > 0.99
    True
    """
    points = _as_cloud(points, "points")
    if normals is not None:
        rows = np.shape(normals)[0] if np.ndim(normals) else 0
        if rows != points.shape[0]:
            raise ValueError(
                f"normals: {rows} rows for {points.shape[0]} points; expected one normal per "
                "point"
            )
        normals = _as_cloud(normals, "normals", chunks=points.chunks).rechunk(points.chunks)
    _, chunks, offsets, names, overlap = _graph(
        points, normals, h=h, cutoff=cutoff, method=method, orient=orient, memory=memory,
        max_cells=max_cells, threads=threads,
    )
    out = _result(points, chunks, offsets, names)
    if overlap is not None:
        out["overlap_agreement"] = da.from_delayed(
            delayed(_share)(overlap), shape=(), dtype=np.float64
        )
    return out


def _overlap_warning(share: float, name: str) -> Optional[str]:
    """The binary's warning about tiles that disagree on the normals' signs, or None."""
    if not share < MIN_OVERLAP_AGREEMENT:
        return None
    return (
        f"{name}: the estimated normals' signs differ between tiles at "
        f"{100 * (1 - share):.1f}% of the overlap points (at most "
        f"{100 * (1 - MIN_OVERLAP_AGREEMENT):.0f}% expected): the cloud is not oriented one "
        "way across tiles (each tile orients its own), so the sign and size of the curvature "
        "are wrong near the flips. Give orient=\"viewpoint:X,Y,Z\" for a scan from one "
        "position, normals, or a larger memory to use fewer tiles"
    )


def _result(points, chunks, offsets, names):
    out = {"points": points}
    for name in names:
        blocks = [
            da.from_delayed(
                delayed(lambda d, k=name: d[k])(c),
                shape=(int(offsets[i + 1] - offsets[i]),) + ((3,) if name in _VECTORS else ()),
                dtype=np.int32 if name == "status" else np.float64,
            )
            for i, c in enumerate(chunks)
        ]
        out[name] = da.concatenate(blocks, axis=0)
    return out


def _read(path):
    points, normals = _mlscurv.read(path)
    return points, normals


def _counts(grid, points):
    return grid.counts(points)


def _occupied(counts):
    """The cells a chunk has points in, a bit each."""
    return np.packbits(counts > 0)


def _check_output(path, out):
    _mlscurv._check_output(path, out)


def _write(path, out, chunk):
    # The writer reads the input again for its coordinates, attributes and LAS layout.
    _mlscurv._write_like(path, out, chunk)
    return out


def curvature_files(
    paths: Sequence[Union[str, os.PathLike]],
    out: Union[str, os.PathLike, Sequence[Union[str, os.PathLike]]],
    *,
    h: float,
    cutoff: Union[float, str, None] = 5.0,
    method: str = "jet",
    orient: str = "up",
    memory: Union[str, int] = "1GiB",
    max_cells: int = MAX_CELLS,
    threads: Optional[int] = None,
    compute: bool = True,
):
    """``mlscurv curvature`` of a cloud given as several files (LAS/LAZ tiles, or any format
    ``mlscurv.read`` reads), one output file per input: the results of one run over their
    concatenation, each file written as the command writes its output (the input's attributes
    and LAS layout carried).

    Parameters
    ----------
    paths : sequence of paths
        The input files, read on the workers (each must be readable there). Their normals are
        used if every file has them, and estimated per tile if none has.
    out : directory, or sequence of paths
        Where the results go: a directory (each output named as its input), or one path per
        input. The output format is the extension's.
    h, cutoff, method, orient, memory, max_cells, threads
        As for :func:`curvature`.
    compute : bool
        Write the files now and return their paths (default), or return the delayed writes.
        Writing them now with estimated normals warns (``UserWarning``) when the tiles'
        overlaps disagree on the normals' signs, as ``mlscurv curvature --memory`` does.

    Examples
    --------
    >>> import mlscurv.dask                                                  # doctest: +SKIP
    >>> tiles = sorted(glob.glob("survey/*.laz"))                           # doctest: +SKIP
    >>> mlscurv.dask.curvature_files(tiles, "curvature/", h=0.5, memory="2GiB")  # doctest: +SKIP
    ['curvature/t_000.laz', ...]
    """
    paths = [os.fspath(p) for p in paths]
    if isinstance(out, (str, os.PathLike)):
        outs = [os.path.join(os.fspath(out), os.path.basename(p)) for p in paths]
    else:
        outs = [os.fspath(o) for o in out]
        if len(outs) != len(paths):
            raise ValueError(f"out: {len(outs)} paths for {len(paths)} inputs; give one per input")
    # The outputs checked where they will be written, before any work: a directory that is
    # missing or that the workers cannot write to is found now, not after the computation.
    dask.compute(
        *[delayed(_check_output, pure=False)(p, o) for p, o in zip(paths, outs)]
    )
    # Read once and kept in the workers' memory (the cluster's, not this machine's): the
    # plan's passes (check, counts, split) would otherwise each decompress every file again.
    reads = list(dask.persist(*[delayed(_read, pure=True)(p) for p in paths]))
    shapes = dask.compute(
        *[delayed(lambda r: (len(r[0]), r[1] is not None))(r) for r in reads]
    )
    # A file without points (an empty tile of a survey grid) is no chunk of the cloud: dask
    # drops empty blocks, which would shift every later file's rows onto the wrong file. It
    # gets an empty output.
    full = [i for i, (n, _) in enumerate(shapes) if n > 0]
    if not full:
        _mlscurv._check_count(0)
    with_normals = {shapes[i][1] for i in full}
    if len(with_normals) > 1:
        missing = [paths[i] for i in full if not shapes[i][1]]
        raise ValueError(
            f"{missing[0]}: the file has no normals (nx, ny, nz) but others have; give every "
            "file normals, or none"
        )
    points = da.concatenate(
        [
            da.from_delayed(delayed(lambda r: r[0])(reads[i]), shape=(shapes[i][0], 3), dtype=np.float64)
            for i in full
        ]
    )
    normals = None
    if with_normals == {True}:
        normals = da.concatenate(
            [
                da.from_delayed(
                    delayed(lambda r: r[1])(reads[i]), shape=(shapes[i][0], 3), dtype=np.float64
                )
                for i in full
            ]
        )
    _, chunks, offsets, names, overlap = _graph(
        points, normals, h=h, cutoff=cutoff, method=method, orient=orient, memory=memory,
        max_cells=max_cells, threads=threads,
    )
    chunk_of = dict(zip(full, chunks))
    empty = {
        k: np.empty((0, 3) if k in _VECTORS else (0,), np.int32 if k == "status" else np.float64)
        for k in names
    }
    writes = [
        delayed(_write)(p, o, chunk_of.get(i, empty))
        for i, (p, o) in enumerate(zip(paths, outs))
    ]
    if compute:
        if overlap is None:
            return list(dask.compute(*writes))
        *written, pair = dask.compute(*writes, overlap)
        name = paths[0] if len(paths) == 1 else f"{paths[0]} and {len(paths) - 1} more files"
        said = _overlap_warning(_share(pair), name)
        if said:
            warnings.warn(said, stacklevel=2)
        return written
    return writes
