"""The site loads nothing from other hosts: it reads offline, and no reader's visit is
reported to a CDN (``tests/test_docs_site.py`` counts a built page's requests in Chromium).

What asked other hosts, and what this build does instead:

* matplotlib's JSHTML animations (``Animation.to_jshtml``, in the notebooks' outputs) carry
  ``<link rel="stylesheet" href="https://maxcdn.bootstrapcdn.com/font-awesome/4.4.0/...">``
  for their buttons' icons: :func:`drop_remote_stylesheets` removes such links from the raw
  HTML of cell outputs, and ``_static/mechpy.css`` gives the buttons characters instead;
* myst-nb's ipywidgets scripts (require.js and the widgets' HTML manager, from cdnjs and
  jsDelivr) on every page with widget state: ``nb_ipywidgets_js = {}`` in ``conf.py`` (the
  widget views are not shown on the site: ``nb_mime_priority_overrides`` drops them for
  the live views' own pages, which run without a kernel);
* MathJax: Debian's copy is served from the site (``conf.py``) when the machine has it.
"""
import re

from docutils import nodes

#: a stylesheet link to another host (http, https or protocol-relative)
REMOTE_STYLESHEET = re.compile(
    r"""<link\b(?=[^>]*\brel\s*=\s*["']?stylesheet)(?=[^>]*\bhref\s*=\s*["']?(?:https?:)?//)"""
    r"""[^>]*>\s*""", re.I)


def without_remote_stylesheets(html: str) -> str:
    """``html`` less its ``<link rel="stylesheet">`` elements that point at other hosts."""
    return REMOTE_STYLESHEET.sub("", html)


def drop_remote_stylesheets(app, doctree, docname):
    for node in list(doctree.findall(nodes.raw)):
        if "html" not in node.get("format", "").split():
            continue
        text = node.astext()
        new = without_remote_stylesheets(text)
        if new != text:
            node.replace_self(nodes.raw(new, new, format=node["format"]))


def setup(app):
    app.connect("doctree-resolved", drop_remote_stylesheets)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
