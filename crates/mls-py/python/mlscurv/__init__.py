# The package is the native module `mlscurv._mlscurv` (crates/mls-py/src), re-exported here so
# that `import mlscurv` gives its functions, and `mlscurv.dask` (dask.py), which runs them over
# a Dask cluster.
from . import _mlscurv
from ._mlscurv import STATUS, Result, __version__, curvature, eval, normals, project, read, write

__doc__ = _mlscurv.__doc__
__all__ = [
    "STATUS", "Result", "__version__", "curvature", "eval", "normals", "project", "read", "write",
]
