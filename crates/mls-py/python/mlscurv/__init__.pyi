"""Type stub of the ``mlscurv`` package: the native module ``mlscurv._mlscurv``
(crates/mls-py/src/lib.rs) it re-exports. ``mlscurv.dask`` is Python, typed in its source."""

import os
from typing import (
    Any,
    Dict,
    Iterator,
    Literal,
    Mapping,
    Optional,
    Sequence,
    Tuple,
    Union,
    overload,
)

import numpy as np
import numpy.typing as npt

__version__: str

STATUS: dict[int, str]
"""Codes of the ``status`` column: 0 ``ok``, 1 ``no_neighbours``, 2 ``too_few_neighbours``,
3 ``normal_undefined``, 4 ``gradient_vanishes``, 5 ``projection_failed``, 6 ``invalid_query``,
7 ``normal_estimation_failed``, 8 ``outlier`` (the jet without normals: a stray sample)."""

Float64Array = npt.NDArray[np.float64]
Int32Array = npt.NDArray[np.int32]
Cutoff = Union[float, Literal["none"], None]
Format = Literal["ply", "xyz", "csv", "las", "laz"]
PathLike = Union[str, "os.PathLike[str]"]

class Result:
    """Named numpy arrays with the columns, status codes and conventions of the ``mlscurv``
    command's output file. Which arrays a result has depends on the function and its options:
    an absent one raises ``AttributeError``."""

    points: Float64Array
    """(N, 3): the points evaluated at (the input array itself where it was not moved)."""
    normals: Float64Array
    """(N, 3) unit normals."""
    k1: Float64Array
    """(N,) the larger principal curvature (curvature only)."""
    k2: Float64Array
    """(N,) the smaller principal curvature (curvature only)."""
    mean: Float64Array
    """(N,) (k1 + k2) / 2 (curvature only)."""
    gauss: Float64Array
    """(N,) k1 · k2 (curvature only)."""
    d1: Float64Array
    """(N, 3) unit principal direction of k1 (curvature only)."""
    d2: Float64Array
    """(N, 3) unit principal direction of k2 (curvature only)."""
    k1_sd: Float64Array
    """(N,) predicted error of k1 (curvature with method="jet")."""
    k2_sd: Float64Array
    """(N,) predicted error of k2 (curvature with method="jet")."""
    h: Float64Array
    """(N,) the scale chosen per point (curvature with adaptive=True)."""
    noise: Float64Array
    """(N,) the estimated position noise (curvature with adaptive=True)."""
    status: Int32Array
    """(N,) 0 = ok; else the point's numbers are NaN (see ``STATUS``)."""

    @property
    def scale(self) -> float:
        """The h used (the smallest, with adaptive=True)."""
    @property
    def scale_source(self) -> str:
        """How h was chosen, as in the command's summary."""
    @property
    def normals_source(self) -> str:
        """Where the normals came from, as in the command's summary."""
    @property
    def timings(self) -> dict[str, float]:
        """Seconds per stage (spacing, normals, index, curvature, ...)."""
    @property
    def warnings(self) -> list[str]:
        """The command's warnings for this run (also issued as UserWarning)."""
    def keys(self) -> list[str]:
        """The column names of the command's output file, in its order."""
    def to_dict(self) -> dict[str, npt.NDArray[np.generic]]:
        """The columns as one-dimensional arrays (views), in the file's order."""
    def __getitem__(self, column: str) -> npt.NDArray[np.generic]: ...
    def __contains__(self, column: object) -> bool: ...
    def __iter__(self) -> Iterator[str]: ...

def curvature(
    points: npt.ArrayLike,
    normals: Optional[npt.ArrayLike] = None,
    *,
    h: Optional[float] = None,
    h_factor: Optional[float] = None,
    cutoff: Cutoff = 5.0,
    method: Literal["jet", "paper"] = "jet",
    at: Literal["input", "projected"] = "input",
    orient: Optional[str] = None,
    adaptive: bool = False,
    threads: Optional[int] = None,
) -> Result:
    """Principal curvatures, directions, mean and Gaussian curvature at every point, as
    ``mlscurv curvature`` computes them (see ``help(mlscurv.curvature)`` for the parameters)."""

def normals(
    points: npt.ArrayLike,
    *,
    h: Optional[float] = None,
    h_factor: Optional[float] = None,
    orient: Optional[str] = None,
    threads: Optional[int] = None,
) -> Result:
    """Estimated and oriented normals, as ``mlscurv normals`` computes them."""

def project(
    points: npt.ArrayLike,
    normals: Optional[npt.ArrayLike] = None,
    *,
    h: Optional[float] = None,
    h_factor: Optional[float] = None,
    cutoff: Cutoff = 5.0,
    orient: Optional[str] = None,
    threads: Optional[int] = None,
) -> Result:
    """The points projected onto the MLS surface, with its normals, as ``mlscurv project``."""

def eval(
    points: npt.ArrayLike,
    normals: npt.ArrayLike,
    queries: npt.ArrayLike,
    *,
    h: Optional[float] = None,
    cutoff: Cutoff = 5.0,
    threads: Optional[int] = None,
) -> Result:
    """g, ∇g, H, the normal field and the curvature of the MLS surface of an oriented cloud at
    query points, as ``mlscurv eval`` (columns ``x y z g gx gy gz hxx hxy hxz hyy hyz hzz nx ny
    nz k1 k2 mean gauss status``)."""

@overload
def read(
    path: PathLike,
    *,
    format: Optional[Format] = None,
    columns: Union[str, Sequence[str], None] = None,
    attributes: Literal[False] = False,
) -> Tuple[Float64Array, Optional[Float64Array]]:
    """(points, normals) of a PLY, XYZ/TXT/PTS, CSV or LAS/LAZ file; normals is None when the
    file has none."""

@overload
def read(
    path: PathLike,
    *,
    format: Optional[Format] = None,
    columns: Union[str, Sequence[str], None] = None,
    attributes: Literal[True],
) -> Tuple[Float64Array, Optional[Float64Array], Dict[str, npt.NDArray[Any]]]:
    """(points, normals, attributes): attributes maps the file's other per-point values (PLY
    properties, text columns, LAS dimensions) to arrays of their stored types."""

def write(
    path: PathLike,
    data: Union[Result, Mapping[str, npt.ArrayLike], npt.ArrayLike],
    *,
    format: Optional[Format] = None,
    ascii: bool = False,
    force: bool = False,
) -> None:
    """Writes a Result, a mapping of columns or an (N, 3) array of points as the command
    writes its output (PLY, CSV, XYZ, LAS/LAZ)."""
