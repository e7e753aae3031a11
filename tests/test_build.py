"""The package as built and installed: the import guard, the installed files."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import mechpy

PKG = Path(mechpy.__file__).resolve().parent


def _copy_sources(dest):
    """The package's Python sources without any built C core, into dest/mechpy."""
    shutil.copytree(PKG, dest / "mechpy",
                    ignore=shutil.ignore_patterns("*.so", "*.pyd", "__pycache__"))


def _import_in(folder):
    # -S: no site-packages, so no installed (or editable) mechpy can be found; -E: no
    # PYTHONPATH; the copy in folder is the one imported
    return subprocess.run([sys.executable, "-S", "-E", "-c",
                           "import sys; sys.path.insert(0, sys.argv[1]); import mechpy",
                           str(folder)], capture_output=True, text=True, timeout=60)


def test_import_from_unbuilt_source_tree_says_so(tmp_path):
    _copy_sources(tmp_path)
    (tmp_path / "meson.build").write_text("project('mechpy', 'c')\n")  # a source tree
    r = _import_in(tmp_path)
    assert r.returncode != 0
    assert "ImportError: you are importing mechpy from its source tree" in r.stderr, r.stderr
    assert "partially initialized" not in r.stderr


def test_import_without_core_elsewhere_names_the_core(tmp_path):
    _copy_sources(tmp_path)  # an installed copy that lost its C core: no meson.build beside
    r = _import_in(tmp_path)
    assert r.returncode != 0
    assert "ImportError: mechpy's C core mechpy._core could not be loaded" in r.stderr, r.stderr


def test_package_is_typed_and_whole():
    assert (PKG / "py.typed").is_file()
    import mechpy.benches
    import mechpy.symbolic
    import mechpy.tours
    import mechpy.variational  # noqa: F401
    for sub in (mechpy.benches, mechpy.symbolic, mechpy.tours, mechpy.variational):
        assert Path(sub.__file__).resolve().is_relative_to(PKG)


def _distribution():
    from importlib import metadata
    dist = metadata.distribution("mechpy-classical")   # the import name is mechpy
    url = dist.read_text("direct_url.json") or "{}"
    import json
    return dist, json.loads(url).get("dir_info", {}).get("editable", False)


def test_installed_files_are_the_package_only():
    """The wheel holds mechpy/ and its metadata: no tests, no test-only reference code."""
    dist, editable = _distribution()
    if editable:
        pytest.skip("editable install: the wheel's files are checked on the sdist-installed copy")
    files = [str(f) for f in dist.files]
    tops = {f.split("/")[0] for f in files}
    assert tops <= {"mechpy", f"mechpy_classical-{dist.version}.dist-info"}, sorted(tops)
    assert not [f for f in files if "/tests/" in f or Path(f).name.startswith(("ref_", "test_"))]
    assert "mechpy/py.typed" in files
    for lic in ("LICENSE", "NOTICE", "LICENSES/GSL-COPYING"):
        assert any(f.endswith(f".dist-info/licenses/{lic}") for f in files), (lic, files)
    meta = dist.metadata
    # what the package contains (NOTICE; tests/test_release.py reads the wheel's): mechpy's
    # code, GSL linked into _core, three.js in the live pages
    assert meta["License-Expression"] == "BSD-3-Clause AND GPL-3.0-or-later AND MIT"
    assert "Typing :: Typed" in meta.get_all("Classifier")
    assert not meta.get_all("Project-URL")  # no invented addresses


def test_installed_copy_is_the_one_imported():
    """Under dev.sh's sdist pass, the suite imports the installed copy, not the source tree."""
    if not os.environ.get("MECHPY_INSTALLED_COPY"):
        pytest.skip("not the sdist-installed run of scripts/dev.sh")
    dist, editable = _distribution()
    assert not editable
    assert PKG == Path(dist.locate_file("mechpy")).resolve()
    assert not (PKG.parent / "meson.build").exists()


@pytest.mark.parametrize("argv", [["--help"], ["tour", "--help"], ["bench", "--help"]])
def test_command_line_runs_from_the_package(argv, tmp_path):
    # from an empty folder: the package that is imported, not a source tree beside it
    r = subprocess.run([sys.executable, "-m", "mechpy", *argv], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "usage: python -m mechpy" in r.stdout


def test_bench_targets_read_every_sections_rows():
    # the report's targets see all sections' rows at once: a row without a path,
    # with path None (hard_cases', longrun's) or without an error must not stop any
    # section's targets (a whole bench run lost its report to one such row)
    from mechpy import bench
    from mechpy.benches import entries
    rows = [dict(problem="p", impl="a", time=1.0, error=float("nan")),
            dict(problem="p", impl="b", time=1.0, error=1e-6, rtol=1e-6, path=None),
            dict(problem="q", impl="c", time=2.0, error=1e-6, rtol=1e-3, path="call-mechpy",
                 method="dop853", nfev=10)]
    for mod in entries():
        if hasattr(mod, "targets"):
            assert isinstance(mod.targets(rows), list), mod.__name__
    tg = bench.targets(rows)
    assert all({"target", "goal", "worst", "median"} <= set(t) for t in tg)
