"""Python call overhead against the command's curvature stage (issue 15's target: at most 5 %
on the 1M sphere).

    python crates/mls-py/bench/overhead.py [N] [--cli target/release/mlscurv] [--method paper]

Times `mlscurv.curvature` on N random points of the unit sphere (default 1,000,000): the whole
call against the sum of the stages it reports (the command's stages: spacing, normals, index,
curvature), so that the difference is what Python adds (checking and converting the input,
building the output arrays). With --cli, the command runs on the same points (binary PLY) and
its summary's stages are printed beside.
"""

import argparse
import re
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import mlscurv


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("n", nargs="?", type=int, default=1_000_000)
    ap.add_argument("--cli", type=Path)
    ap.add_argument("--method", default="paper", choices=["jet", "paper"])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    rng = np.random.default_rng(42)
    points = rng.normal(size=(args.n, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)

    best = None
    for _ in range(args.repeat):
        start = time.perf_counter()
        r = mlscurv.curvature(points, method=args.method)
        wall = time.perf_counter() - start
        if best is None or wall < best[0]:
            best = (wall, r.timings)
    wall, stages = best
    inside = sum(stages.values())
    print(f"{args.n} points, method {args.method}, best of {args.repeat}")
    print("python stages (s): " + ", ".join(f"{k} {v:.3f}" for k, v in stages.items()))
    print(f"python call {wall:.3f} s; stages {inside:.3f} s; overhead {wall - inside:.3f} s "
          f"= {100 * (wall - inside) / stages['curvature']:.1f} % of the curvature stage")

    if args.cli:
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "sphere.ply"
            mlscurv.write(path, points)
            done = subprocess.run(
                [str(args.cli), "curvature", str(path), "-o", str(Path(d) / "out.ply"),
                 "--method", args.method],
                capture_output=True, text=True, check=True,
            )
        line = next(l for l in done.stderr.splitlines() if "time (s)" in l)
        print("command:", re.sub(r"\s+", " ", line.strip()))
        cli = dict(re.findall(r"(\w+) ([0-9.]+)", line.split("total")[0]))
        compute = sum(float(cli[k]) for k in ("spacing", "normals", "index", "curvature"))
        print(f"command stages without read/write {compute:.3f} s; python call / that = "
              f"{wall / compute:.3f}")


if __name__ == "__main__":
    main()
