"""The examples in the public docstrings run and print what they say.

Every module of the public face is walked; each docstring with ``>>>``
examples is one test.  An example that needs an optional package (SciPy,
matplotlib) is skipped when that package is missing.  As in NumPy's own
docstrings, the examples take ``import numpy as np`` and ``import mechpy as mp``
as done; matplotlib draws with the Agg backend.

Every public function and class (``mechpy.__all__`` and each public module's
``__all__``) has an Examples section: ``test_every_entry_point_has_examples``.
"""
import doctest
import importlib
import inspect
import pkgutil
import re

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
            # (the docstring is part of the key: the scenes' docstrings are assembled at
            # import, so their line is unknown and would make them all look the same)
            key = (test.filename, test.lineno, test.docstring)
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


def _public_entry_points():
    """(dotted name, object) of every function and class in ``mechpy.__all__`` and in
    the ``__all__`` of each public module.  Not entry points: the modules themselves,
    constants (numbers, tuples, dicts) and the exception classes of
    :mod:`mechpy.errors`, whose docstrings are the C status table's messages (the
    module's docstring shows when each is raised)."""
    seen = set()
    # the public modules are those mechpy.__all__ lists; the defining modules come
    # first, so that a re-exported name is named where it lives
    modnames = [f"mechpy.{n}" for n in mechpy.__all__
                if inspect.ismodule(getattr(mechpy, n))] + ["mechpy"]
    for modname in modnames:
        module = importlib.import_module(modname)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if inspect.ismodule(obj) or not callable(obj):
                continue
            if inspect.isclass(obj) and issubclass(obj, mechpy.MechpyError):
                continue
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            yield f"{modname}.{name}", obj


_ENTRY_POINTS = list(_public_entry_points())


def test_entry_points_are_found():
    names = {n for n, _ in _ENTRY_POINTS}
    assert {"mechpy.integrate.solve", "mechpy.integrate.solve_many", "mechpy.symbolic.lagrangian",
            "mechpy.plot.animate", "mechpy.scenes.Pendulum", "mechpy.phase.limit_cycle"} <= names
    assert len(names) >= 100


@pytest.mark.parametrize("name,obj", _ENTRY_POINTS, ids=[n for n, _ in _ENTRY_POINTS])
def test_every_entry_point_has_examples(name, obj):
    """Each public function and class shows its use in a numpydoc Examples section
    with ``>>>`` lines (run by test_docstring_examples): a new public name without
    one fails here."""
    doc = inspect.getdoc(obj) or ""
    section = re.search(r"^Examples\n-{8,}\n(.*?)(?=^\w[\w ]*\n-{3,}$|\Z)", doc,
                        flags=re.M | re.S)
    assert section, f"{name} has no Examples section in its docstring"
    assert ">>> " in section.group(1), f"{name}: its Examples section has no >>> example"


@pytest.mark.parametrize("test", _TESTS, ids=[t.name for t in _TESTS])
def test_docstring_examples(test):
    source = "\n".join(ex.source for ex in test.examples)
    if "scipy" in source:
        pytest.importorskip("scipy")
    if "matplotlib" in source or "mp.plot" in source:
        pytest.importorskip("matplotlib").use("Agg")
    globs = {"np": np, "mp": mechpy}
    globs.update(test.globs)
    test.globs = globs
    report = []
    runner = doctest.DocTestRunner(optionflags=_FLAGS)
    runner.run(test, out=report.append)
    if runner.failures:
        pytest.fail("".join(report), pytrace=False)


def _source_root():
    """The source tree with docs/ (tests/test_docs_math.py's source_root); the test is
    skipped where there is none."""
    from test_docs_math import source_root

    root = source_root()
    if root is None:
        pytest.skip("no docs/ beside or above the tests")
    return root


def _conf_value(name):
    """A top-level constant of docs/conf.py (read, not imported: Sphinx need not be installed)."""
    import ast

    root = _source_root()
    tree = ast.parse((root / "docs" / "conf.py").read_text())
    for node in tree.body:
        if (isinstance(node, ast.Assign) and len(node.targets) == 1
                and getattr(node.targets[0], "id", None) == name):
            return ast.literal_eval(node.value)
    raise AssertionError(f"docs/conf.py does not set {name}")


def test_a_stalled_notebook_cell_fails_the_docs_build_fast():
    """A cold build once waited 626 s on a widget cell of phase_portraits (nbclient's
    wait for the reply of a cell whose Output widget it answers on the same shell
    channel; the notebook runs in about 20 s).  Each cell's time is bounded well below
    nbclient's 600 s, above the slowest notebook's whole run (under 60 s:
    tests/test_notebooks.py), and a timeout fails the build."""
    timeout = _conf_value("nb_execution_timeout")
    assert isinstance(timeout, int) and 60 <= timeout <= 180, timeout
    assert _conf_value("nb_execution_raise_on_error") is True


def test_the_docs_extra_caps_the_notebook_execution_chain():
    """The packages that execute the notebooks at build time are capped below their
    next release series, so that a new one cannot change how a widget cell ends
    without a change here."""
    text = (_source_root() / "pyproject.toml").read_text()
    block = re.search(r"^docs = \[(.*?)^\]", text, flags=re.M | re.S).group(1)
    reqs = dict(re.findall(r'"([A-Za-z0-9_.\-]+)(?:\[[^\]]*\])?([^"]*)"', block))
    for name in ("sphinx", "myst-nb", "myst-parser", "jupyter-cache", "nbclient", "ipykernel",
                 "ipywidgets"):
        assert name in reqs, f"{name} is not in the docs extra"
        assert "<" in reqs[name], f"the docs extra does not cap {name}: {reqs[name]!r}"


@pytest.mark.parametrize("name,obj", _ENTRY_POINTS, ids=[n for n, _ in _ENTRY_POINTS])
def test_docstring_renders_without_docutils_warnings(name, obj):
    """What ``bash scripts/dev.sh docs`` (``-W``) would stop on, per docstring and in
    a fraction of a second: numpydoc's reStructuredText of the docstring parsed by
    docutils, Sphinx's roles and directives standing in as literals (needs the docs
    extra)."""
    pytest.importorskip("numpydoc")
    import io

    import docutils.core
    from docutils import nodes
    from docutils.parsers.rst import Directive, directives, roles
    from numpydoc.docscrape_sphinx import get_doc_object

    def role(name, rawtext, text, lineno, inliner, options=None, content=None):
        return [nodes.literal(rawtext, text)], []

    class AnyOptions(dict):
        def __getitem__(self, key):
            return directives.unchanged

        def __contains__(self, key):
            return True

    class Quiet(Directive):
        has_content = True
        optional_arguments = 10
        final_argument_whitespace = True
        option_spec = AnyOptions()

        def run(self):
            return []

    for r in ("func", "class", "meth", "mod", "data", "attr", "math", "exc", "obj", "ref", "doc"):
        roles.register_local_role(r, role)
    for d in ("math", "autosummary", "plot", "rubric", "versionadded", "seealso", "only",
              "index"):
        directives.register_directive(d, Quiet)
    rst = str(get_doc_object(obj, config={"show_class_members": False}))
    err = io.StringIO()
    docutils.core.publish_doctree(rst, settings_overrides={"warning_stream": err,
                                                           "report_level": 2, "halt_level": 5})
    assert not err.getvalue().strip(), f"{name}: {err.getvalue()}"


def test_a_notebook_that_ran_too_long_fails_the_docs_build():
    """A widget cell's stall can end at the cell limit without an error (the reply was
    there, nbclient had missed it): docs/_ext/notebook_time.py turns a notebook run
    longer than mechpy_notebook_max_seconds into a warning, an error under -W; a
    notebook taken from the execution cache is not checked again."""
    pytest.importorskip("sphinx")
    import importlib.util
    import time
    from types import SimpleNamespace

    path = _source_root() / "docs" / "_ext" / "notebook_time.py"
    spec = importlib.util.spec_from_file_location("notebook_time", path)
    ext = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ext)
    assert 60 <= _conf_value("mechpy_notebook_max_seconds") < _conf_value("nb_execution_timeout")

    warned = []
    ext.logger = SimpleNamespace(warning=lambda msg, **kw: warned.append(msg))
    ext._BUILD_START[0] = time.time() - 1000.0

    def app(runtime, mtime):
        env = SimpleNamespace(docname="notebooks/phase_portraits", nb_metadata={
            "notebooks/phase_portraits": {"exec_data": {"runtime": runtime, "mtime": mtime}}})
        return SimpleNamespace(env=env, config=SimpleNamespace(mechpy_notebook_max_seconds=90))

    now = time.time()
    ext.check_notebook_time(app(18.0, now), None)               # the notebook's own time
    assert warned == []
    ext.check_notebook_time(app(626.0, now), None)              # the stalled cold build
    assert len(warned) == 1 and "notebooks/phase_portraits" in warned[0] and "626 s" in warned[0]
    ext.check_notebook_time(app(626.0, now - 2000.0), None)     # from the cache: not again
    assert len(warned) == 1
