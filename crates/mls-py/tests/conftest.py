"""Fixtures: the repository, the `mlscurv` binary the results are compared with, and a reader
of the binary PLY files the binary writes (independent of the package's own reader)."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[3]
BUNNY = REPO / "tests" / "data" / "bunny-stanford.ply"


def readme_example(after: str) -> tuple[str, str]:
    """The first ```python block of README.md after the text `after`, and the ```text block
    after it (what the README shows the example printing)."""
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = readme[readme.index(after) :]
    start = section.index("```python\n") + len("```python\n")
    end = section.index("```", start)
    shown_at = section.index("```text\n", end) + len("```text\n")
    return section[start:end], section[shown_at : section.index("```", shown_at)]


def _target_dir() -> Path:
    try:
        meta = subprocess.run(
            ["cargo", "metadata", "--format-version", "1", "--no-deps"],
            cwd=REPO,
            capture_output=True,
            check=True,
            text=True,
        )
        return Path(json.loads(meta.stdout)["target_directory"])
    except (OSError, subprocess.CalledProcessError):
        return REPO / "target"


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `mlscurv` binary: $MLSCURV_BIN (set by .ci/python), else the newest one built in
    the workspace's target directory."""
    given = os.environ.get("MLSCURV_BIN")
    if given:
        path = Path(given)
        if not (path.is_file() and os.access(path, os.X_OK)):
            pytest.fail(f"MLSCURV_BIN={given} is not an executable file")
        return path
    target = _target_dir()
    found = [p for p in (target / "release" / "mlscurv", target / "debug" / "mlscurv") if p.is_file()]
    if not found:
        on_path = shutil.which("mlscurv")
        if on_path:
            return Path(on_path)
        pytest.skip("no mlscurv binary: run `cargo build -p mls-cli` or set MLSCURV_BIN")
    return max(found, key=lambda p: p.stat().st_mtime)


class CliError(Exception):
    """The binary exited with a failure; the message is its one line on stderr."""


@pytest.fixture(scope="session")
def run_cli(cli):
    """Runs `mlscurv ARGS...`; returns its stderr, or raises CliError with the error line
    (without the `mlscurv: error: ` prefix)."""

    def run(*args) -> str:
        done = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
        if done.returncode != 0:
            # The binary's own errors are one line; clap's usage errors start with `error: `.
            lines = done.stderr.splitlines()
            mine = [l for l in lines if l.startswith("mlscurv: error: ")]
            usage = [l for l in lines if l.startswith("error: ")]
            line = (mine or usage or lines or [""])[-1]
            raise CliError(line.removeprefix("mlscurv: error: ").removeprefix("error: "))
        return done.stderr

    return run


def read_ply_table(path) -> dict:
    """The columns of the vertex element of a binary little-endian PLY file whose first element
    is the vertices, by name, as numpy arrays. A property ``scalar_k1`` is the column ``k1``,
    as mlscurv writes and reads it; ``quality``, which repeats ``mean`` for MeshLab, must equal
    it and is left out."""
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    assert header[1] == "format binary_little_endian 1.0", header[1]
    types = {"double": "<f8", "float": "<f4", "int": "<i4"}
    fields, count, element = [], 0, None
    for words in map(str.split, header):
        if words[0] == "element":
            element = words[1]
            if element == "vertex":
                count = int(words[2])
        elif words[0] == "property" and element == "vertex":
            fields.append((words[2], types[words[1]]))
    table = np.frombuffer(data, dtype=np.dtype(fields), count=count, offset=end)
    columns = {
        name.removeprefix("scalar_"): np.ascontiguousarray(table[name]) for name, _ in fields
    }
    quality = columns.pop("quality", None)
    if quality is not None:
        assert quality.tobytes() == columns["mean"].tobytes(), "quality is not mean"
    return columns


def sphere(n: int, seed: int, noise: float = 0.0) -> np.ndarray:
    """n random points on the unit sphere, optionally moved radially by Gaussian noise."""
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    if noise:
        p *= 1.0 + noise * rng.normal(size=(n, 1))
    return p


def torus(n: int, seed: int, big: float = 1.0, small: float = 0.3):
    """n random points on a torus and their outward unit normals: both signs of curvature."""
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(0, 2 * np.pi, size=(2, n))
    normals = np.column_stack([np.cos(u) * np.cos(v), np.sin(u) * np.cos(v), np.sin(v)])
    centre = np.column_stack([big * np.cos(u), big * np.sin(u), np.zeros(n)])
    return centre + small * normals, normals
