"""The examples in the public docstrings run and print what they say.

Every module of the public face is walked; each docstring with ``>>>``
examples is one test.  An example that needs an optional package (SciPy,
matplotlib) is skipped when that package is missing.
"""
import doctest
import importlib
import pkgutil

import numpy as np
import pytest

import mechpy

#: modules whose names start with these are internal (no user-facing examples)
_PRIVATE = ("_", "benches", "tours", "bench", "__main__")


def _public_modules():
    names = ["mechpy"]
    for info in pkgutil.walk_packages(mechpy.__path__, "mechpy."):
        parts = info.name.split(".")[1:]
        if any(p.startswith(_PRIVATE) for p in parts):
            continue
        names.append(info.name)
    return sorted(names)


def _doctests():
    finder = doctest.DocTestFinder(exclude_empty=True)
    seen = set()
    for name in _public_modules():
        module = importlib.import_module(name)
        for test in finder.find(module, name):
            # re-exported objects are found again under their importer: keep the first
            key = (test.filename, test.lineno)
            if test.examples and key not in seen:
                seen.add(key)
                yield test


_TESTS = list(_doctests())
_FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def test_examples_are_collected():
    # the public modules carry examples: an import error or a renamed module
    # must not turn this file into a silent pass
    assert len(_TESTS) >= 10
    mods = {t.name.split(".")[1] for t in _TESTS if t.name.count(".") >= 1}
    assert {"rotation", "inertia", "modes", "scenes"} <= mods


@pytest.mark.parametrize("test", _TESTS, ids=[t.name for t in _TESTS])
def test_docstring_examples(test):
    source = "\n".join(ex.source for ex in test.examples)
    if "scipy" in source:
        pytest.importorskip("scipy")
    if "matplotlib" in source or "mp.plot" in source:
        pytest.importorskip("matplotlib")
    globs = {"np": np, "mp": mechpy}
    globs.update(test.globs)
    test.globs = globs
    report = []
    runner = doctest.DocTestRunner(optionflags=_FLAGS)
    runner.run(test, out=report.append)
    if runner.failures:
        pytest.fail("".join(report), pytrace=False)
