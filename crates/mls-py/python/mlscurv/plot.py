"""A quick look at a result with matplotlib: the points seen along one axis, coloured by a
column on a diverging map centred on 0 with robust limits, as ``mlscurv render`` colours them."""

import numpy as np

_AXES = {"x": 0, "y": 1, "z": 2}


def plot(result, field="mean", *, view="z", ax=None, size=1.0, limit=None):
    """Draws ``result[field]`` at the points, seen along ``view`` (``"x"``, ``"y"`` or ``"z"``,
    nearest points on top), on ``ax`` (a new figure's if None), and returns the axes.

    Curvatures get a blue-white-red map centred on 0 whose limit is the 98th percentile of
    ``|value|`` (``limit`` overrides it), so that a few extreme points do not wash the rest
    out; ``k1_sd`` and ``k2_sd`` a sequential map from 0. Points whose ``status`` is not ok are
    grey. Needs matplotlib (``pip install matplotlib``).

    Examples
    --------
    >>> import mlscurv, mlscurv.plot
    >>> points, _ = mlscurv.read("tests/data/bunny-stanford.ply")
    >>> r = mlscurv.curvature(points)
    >>> ax = mlscurv.plot.plot(r, "mean", view="z")
    >>> ax.figure.savefig("bunny-mean-matplotlib.png", dpi=150)
    """
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:
        raise ImportError("mlscurv.plot needs matplotlib: pip install matplotlib") from e
    if view not in _AXES:
        raise ValueError(f"view must be 'x', 'y' or 'z', not {view!r}")
    if field not in result:
        raise KeyError(f"{field!r} is not a column; the columns are {' '.join(result.keys())}")
    points = np.asarray(result.points)
    values = np.asarray(result[field], dtype=float)
    if "status" in result and field != "status":
        values = np.where(np.asarray(result["status"]) == 0, values, np.nan)
    depth = _AXES[view]
    u, v = [a for a in range(3) if a != depth]
    # Nearest last, so that it is drawn on top (looking down the view axis from +∞).
    order = np.argsort(points[:, depth], kind="stable")
    points, values = points[order], values[order]
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 5))
    bad = ~np.isfinite(values)
    if bad.any():
        ax.scatter(points[bad, u], points[bad, v], s=size, c="0.7", linewidths=0, label="no value")
    finite = values[~bad]
    if field in ("k1_sd", "k2_sd"):
        top = limit if limit is not None else (np.percentile(finite, 98) if finite.size else 1.0)
        cmap, vmin, vmax = "viridis", 0.0, top
    else:
        top = limit if limit is not None else (np.percentile(np.abs(finite), 98) if finite.size else 1.0)
        top = top if top > 0 else 1.0
        cmap, vmin, vmax = "RdBu_r", -top, top
    art = ax.scatter(
        points[~bad, u], points[~bad, v], s=size, c=finite, cmap=cmap, vmin=vmin, vmax=vmax,
        linewidths=0,
    )
    ax.figure.colorbar(art, ax=ax, label=field)
    ax.set_aspect("equal")
    ax.set_xlabel("xyz"[u])
    ax.set_ylabel("xyz"[v])
    ax.set_title(f"{field}, {len(values)} points, seen along {view}")
    return ax
