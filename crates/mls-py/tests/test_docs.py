"""The examples in the docstrings run and give what they show."""

import doctest
import os

import mlscurv
from conftest import REPO


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
