"""The package as built and installed: the import guard, the installed files."""
import shutil
import subprocess
import sys
from pathlib import Path

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
