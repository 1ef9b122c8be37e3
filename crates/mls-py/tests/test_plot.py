"""mlscurv.plot draws a result with matplotlib (skipped where matplotlib is not installed)."""

import numpy as np
import pytest

import mlscurv

plt = pytest.importorskip("matplotlib.pyplot")
import matplotlib  # noqa: E402

matplotlib.use("Agg")
from mlscurv.plot import plot  # noqa: E402


def sphere(n=2000):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    t = np.pi * (1 + 5**0.5) * i
    r = np.sqrt(1 - z * z)
    p = np.c_[r * np.cos(t), r * np.sin(t), z]
    return p, p.copy()


def test_plot_colours_by_the_column_with_a_symmetric_robust_range(tmp_path):
    points, normals = sphere()
    r = mlscurv.curvature(points, normals)
    ax = plot(r, "mean", view="z")
    art = [c for c in ax.collections if c.get_array() is not None][-1]
    lo, hi = art.get_clim()
    # A unit sphere: every mean curvature 1, so the limit is |1| and the range symmetric.
    assert lo == -hi and abs(hi - 1) < 1e-3, (lo, hi)
    np.testing.assert_allclose(np.sort(art.get_array()), np.sort(np.asarray(r["mean"])))
    ax.figure.savefig(tmp_path / "mean.png")
    assert (tmp_path / "mean.png").stat().st_size > 1000
    plt.close(ax.figure)


def test_plot_refuses_an_unknown_column_or_view():
    points, normals = sphere()
    r = mlscurv.curvature(points, normals)
    with pytest.raises(KeyError, match="not a column"):
        plot(r, "curvedness")
    with pytest.raises(ValueError, match="view must be"):
        plot(r, "mean", view="w")
