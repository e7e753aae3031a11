"""Sphinx configuration of the mechpy documentation.

Build with ``bash scripts/dev.sh docs`` (warnings are errors); the site is
written to ``docs/_build/html``.  The notebooks are read from ``notebooks/``
(``docs/notebooks`` is a link to it) and executed at build time, with a cache.
"""
import os
import sys
from pathlib import Path

import mechpy

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "_ext"))

project = "mechpy"
author = "the mechpy developers"
copyright = "2026, the mechpy developers"
version = release = mechpy.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_nb",
    "sphinx_copybutton",
    "notebook_time",          # docs/_ext: a notebook that ran too long fails the build
    "offline_html",           # docs/_ext: no stylesheet from another host in cell outputs
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "_*.md", "**.ipynb_checkpoints", "Thumbs.db", ".DS_Store"]
templates_path = ["_templates"]

# ---- API reference: one page per public module, one per object -------------
autosummary_generate = True
autosummary_ignore_module_all = False     # each module's __all__ is its public list
autosummary_imported_members = True       # names re-exported through __all__
autodoc_typehints = "none"                # numpydoc's Parameters section says it
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# ---- notebooks: executed at build time, cached ------------------------------
nb_execution_mode = "cache"
nb_execution_cache_path = str(HERE / "_build" / ".jupyter_cache")
# A cell's own limit, in seconds: the notebooks run top to bottom in under a minute
# (tests/test_notebooks.py; docs/course.md lists their times), so a cell still busy
# after 120 s is stalled, not slow: nbclient stops it with CellTimeoutError naming
# the notebook and the cell, and the build fails (nb_execution_raise_on_error),
# instead of waiting 600 s per stalled cell.  A wait for a reply nbclient missed
# ends at this limit too (docs/_ext/notebook_time.py).
nb_execution_timeout = 120
# ...and a notebook executed by the build that took longer than this fails it, named
# (docs/_ext/notebook_time.py: a widget cell's stall ends at the cell limit without an error)
mechpy_notebook_max_seconds = 90
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True
os.environ.pop("MPLBACKEND", None)   # the kernels draw inline figures
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
# the notebooks hold widgets and animations as HTML; mime types Sphinx cannot show
# otherwise are dropped quietly rather than warned about (the build uses -W)
nb_mime_priority_overrides = [("html", "application/vnd.jupyter.widget-view+json", None)]
suppress_warnings = ["mystnb.unknown_mime_type"]
# ...and so the ipywidgets scripts myst-nb adds to a page with widget state (require.js and
# the widgets' HTML manager, from CDNs) would render nothing: none, the site asks no other
# host (docs/_ext/offline_html.py)
nb_ipywidgets_js = {}

# ---- math: a local MathJax when the machine has one ---------------------------
# Debian's libjs-mathjax (MathJax 2, installed by `scripts/dev.sh docs`) is copied
# into the site, so that formulas render without a network; elsewhere Sphinx's
# default MathJax from its CDN is used.
MATHJAX_SRC = Path(os.environ.get("MECHPY_MATHJAX", "/usr/share/javascript/mathjax"))
_mathjax_static = []
if (MATHJAX_SRC / "MathJax.js").is_file():
    import shutil

    _dst = HERE / "_build" / "_mathjax" / "mathjax"
    if not (_dst / "MathJax.js").is_file():
        for part in ("MathJax.js", "config/TeX-AMS_CHTML.js", "extensions", "jax/element",
                     "jax/input/TeX", "jax/output/CommonHTML", "fonts/HTML-CSS/TeX/woff"):
            src, dst = MATHJAX_SRC / part, _dst / part
            dst.parent.mkdir(parents=True, exist_ok=True)
            if src.is_dir():
                shutil.copytree(src, dst, dirs_exist_ok=True)
            elif src.is_file():
                shutil.copyfile(src, dst)
    _mathjax_static = [str(_dst.parent)]
    mathjax_path = "mathjax/MathJax.js?config=TeX-AMS_CHTML"
    # myst-nb marks notebook cells tex2jax_ignore; the math inside them is
    # marked "math" and processed all the same (as Sphinx asks of MathJax 3)
    mathjax2_config = {"tex2jax": {"processClass": "math|output_area",
                                   "ignoreClass": "tex2jax_ignore|mathjax_ignore|document"},
                       "messageStyle": "none"}

# ---- links -------------------------------------------------------------------
intersphinx_mapping = {}   # offline build: no inventories are fetched

# ---- HTML --------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"mechpy {release}"
html_static_path = ["_static"] + _mathjax_static
html_css_files = ["mechpy.css"]
html_theme_options = {
    "navbar_align": "left",
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"index": [], "conventions": []}
