"""The Python side of `cargo xtask clients` (xtask/src/clients.rs): opens mlscurv's files with
pymeshlab and laspy and writes what they found as plain text for the xtask to compare, and
writes files of their own for mlscurv's reader.

Usage: clients.py meshlab OURS.PLY OUT_DIR | clients.py laspy OURS.LAS OUT_DIR

Exit status 3 with one line on stderr when the module is not installed (the xtask then skips
that program); any other failure is a traceback and status 1.
"""

import sys
from pathlib import Path

MISSING = 3


def need(module):
    try:
        return __import__(module)
    except ImportError as e:
        print(f"{module} is not installed ({e})", file=sys.stderr)
        sys.exit(MISSING)


def meshlab(ours, out):
    pymeshlab = need("pymeshlab")
    np = need("numpy")
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(ours))
    m = ms.current_mesh()
    # What MeshLab took from the file: the vertices, and its per-vertex quality if any.
    np.savetxt(out / "meshlab-vertices.txt", m.vertex_matrix(), fmt="%.17g")
    if m.has_vertex_scalar():
        np.savetxt(out / "meshlab-quality.txt", m.vertex_scalar_array(), fmt="%.17g")
    # MeshLab's own PLY, for mlscurv's reader.
    ms.save_current_mesh(str(out / "meshlab.ply"), binary=True, save_vertex_quality=True)


def laspy_check(ours, out):
    laspy = need("laspy")
    np = need("numpy")
    # LAZ needs a backend: lazrs.
    if not laspy.LazBackend.Lazrs.is_available():
        print("lazrs (laspy's LAZ backend) is not installed", file=sys.stderr)
        sys.exit(MISSING)
    las = laspy.read(str(ours))
    names = list(las.point_format.extra_dimension_names)
    # What laspy read, as CSV with a header row: x, y, z and every extra dimension.
    columns = [np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)]
    columns += [np.asarray(las[n], dtype=np.float64) for n in names]
    np.savetxt(
        out / "laspy-read.csv",
        np.column_stack(columns),
        delimiter=",",
        header=",".join(["x", "y", "z"] + names),
        comments="",
        fmt="%.17g",
    )
    # A LAZ written by laspy: the same points and extra dimensions, each in its own type.
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.offsets = las.header.offsets
    header.scales = las.header.scales
    header.add_extra_dims(
        [laspy.ExtraBytesParams(name=n, type=las[n].dtype) for n in names]
    )
    written = laspy.LasData(header)
    written.x = las.x
    written.y = las.y
    written.z = las.z
    for n in names:
        written[n] = las[n]
    written.write(str(out / "laspy.laz"), laz_backend=laspy.LazBackend.Lazrs)


def main():
    mode, ours, out = sys.argv[1], Path(sys.argv[2]), Path(sys.argv[3])
    {"meshlab": meshlab, "laspy": laspy_check}[mode](ours, out)


if __name__ == "__main__":
    main()
