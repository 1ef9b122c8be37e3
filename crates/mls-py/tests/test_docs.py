"""The examples in the docstrings run and give what they show."""

import doctest
import os
import subprocess
import sys

import mlscurv
from conftest import REPO, readme_example


def test_docstring_examples(monkeypatch):
    monkeypatch.chdir(REPO)
    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for name in ("curvature", "eval", "normals", "project", "read", "write"):
        tests = finder.find(getattr(mlscurv, name), name, globs={})
        assert any(t.examples for t in tests), name
        for test in tests:
            runner.run(test)
    assert runner.failures == 0, f"{runner.failures} docstring example(s) failed"


def test_every_function_has_a_docstring_and_signature():
    for name in ("curvature", "eval", "normals", "project", "read", "write"):
        f = getattr(mlscurv, name)
        assert "Examples" in f.__doc__, name
        assert f.__text_signature__, name
    assert mlscurv.__doc__ and mlscurv.Result.__doc__


def test_stub_is_installed():
    """maturin puts mlscurv.pyi and py.typed beside the module."""
    here = os.path.dirname(mlscurv.__file__)
    assert os.path.isfile(os.path.join(here, "__init__.pyi")) or os.path.isfile(
        os.path.join(here, "mlscurv.pyi")
    ), os.listdir(here)


def test_readme_python_example_runs_as_written(tmp_path):
    """The README's first Python example, taken verbatim from README.md and run as a script
    where the bundled scan is at the path it names: it prints what the README shows after it
    and writes the command's output file, byte for byte."""
    code, shown = readme_example("pip install ./crates/mls-py")
    (tmp_path / "tests").symlink_to(REPO / "tests")
    script = tmp_path / "example.py"
    script.write_text(code, encoding="utf-8")
    done = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == shown
    assert (tmp_path / "bunny-curvature.ply").stat().st_size > 0
