"""Formulas on the site are math, never raw TeX in the prose.

Sphinx's ``-W`` does not see it when MyST's ``$...$`` pairing goes wrong: a
``$$`` inside a paragraph (MyST reads display math only as a block of its
own) leaves the following ``$`` signs paired with the wrong partners, and the
page shows fragments such as ``and\\omega(t)hastheperiod`` with the prose set
as math; and a formula typed without ``$`` shows as typed (``t_{k+1}``).  Two checks:

* every Markdown source the site renders (``docs/**/*.md`` and the notebooks'
  Markdown cells) is parsed with the parser the docs use (MyST's, with
  ``docs/conf.py``'s extensions; markdown-it with MyST's dollarmath settings
  where myst-parser is not installed): no text token outside math or code may
  hold a ``$``, a TeX command such as ``\\omega`` or a braced sub- or superscript;
* when the site has been built (``bash scripts/dev.sh docs`` writes
  ``docs/_build/html``), the visible text of each page outside math, code and
  scripts holds no ``$`` and no TeX command either (a page older than its
  source is skipped: rebuild to check it).
"""
import ast
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest



def source_root():
    """The source tree holding docs/ and notebooks/: the folder above tests/, or, when the
    suite runs from a copy of tests/ inside the tree (``scripts/dev.sh``'s run against
    the sdist-installed copy, in build/sdist/run), the first folder above that holds
    docs/conf.py; None when there is none (the docs tests are then skipped)."""
    here = Path(__file__).resolve().parent.parent
    for folder in (here, *here.parents):
        if (folder / "docs" / "conf.py").is_file() and (folder / "notebooks").is_dir():
            return folder
    return None


ROOT = source_root() or Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
HTML = DOCS / "_build" / "html"
pytestmark = pytest.mark.skipif(source_root() is None,
                                reason="no docs/ beside or above the tests")

#: a TeX command (backslash and letters), a dollar sign, or a braced sub- or superscript
#: (``t_{k+1}``, ``e^{-x}``): math left in the prose
RAW_TEX = re.compile(r"\$|\\[A-Za-z]+|[_^]\{")


def _conf_extensions():
    """myst_enable_extensions as docs/conf.py sets it (read, not imported)."""
    tree = ast.parse((DOCS / "conf.py").read_text())
    for node in tree.body:
        if (isinstance(node, ast.Assign) and len(node.targets) == 1
                and getattr(node.targets[0], "id", None) == "myst_enable_extensions"):
            return set(ast.literal_eval(node.value))
    raise AssertionError("docs/conf.py does not set myst_enable_extensions")


def _parser():
    """The Markdown parser of the docs build."""
    exts = _conf_extensions()
    try:
        from markdown_it.renderer import RendererHTML
        from myst_parser.config.main import MdParserConfig
        from myst_parser.parsers.mdit import create_md_parser
    except ImportError:
        # the same dollarmath rules as MyST's defaults (allow_space, allow_digits,
        # no double-dollar math inside a paragraph)
        markdown_it = pytest.importorskip("markdown_it")
        dollarmath = pytest.importorskip("mdit_py_plugins.dollarmath")
        md = markdown_it.MarkdownIt("commonmark")
        if "dollarmath" in exts:
            md.use(dollarmath.dollarmath_plugin, allow_labels=True, allow_space=True,
                   allow_digits=True, double_inline=False)
        if "amsmath" in exts:
            from mdit_py_plugins.amsmath import amsmath_plugin
            md.use(amsmath_plugin)
        return md
    return create_md_parser(MdParserConfig(enable_extensions=exts), RendererHTML)


def _sources():
    """(name, markdown text) of every Markdown source the site renders."""
    out = []
    for path in sorted(DOCS.rglob("*.md")):
        rel = path.relative_to(DOCS)
        if rel.parts[0] in ("_build", "notebooks") or path.name.startswith("_"):
            continue
        out.append((str(rel), path.read_text()))
    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        nb = json.loads(path.read_text())
        for i, cell in enumerate(nb["cells"]):
            if cell["cell_type"] == "markdown":
                src = cell["source"]
                out.append((f"notebooks/{path.name} cell {i}",
                            "".join(src) if isinstance(src, list) else src))
    return out


def raw_tex_in_markdown(md, text):
    """The text fragments of ``text`` (prose, outside math and code) that hold TeX."""
    bad = []

    def walk(tokens):
        for tok in tokens:
            if tok.type == "text" and RAW_TEX.search(tok.content):
                bad.append(tok.content)
            if tok.children:
                walk(tok.children)

    walk(md.parse(text))
    return bad


SOURCES = _sources()


def test_sources_are_found():
    names = [n for n, _ in SOURCES]
    assert any(n.startswith("guide/") for n in names)
    assert any(n.startswith("notebooks/rigid_body.ipynb") for n in names)


def test_the_check_sees_display_math_inside_a_paragraph():
    # the defect of the rigid-body page: $$...$$ in the middle of a paragraph, then
    # inline math on the next line; and the same formula written as a block of its own
    md = _parser()
    broken = ("the intermediate one,\n$$\\omega_a = A\\,\\mathrm{cn}(u, k)$$\n"
              "and $\\omega(t)$ has the period $T = 4K(k)/\\lambda$.")
    fixed = ("the intermediate one,\n\n$$\\omega_a = A\\,\\mathrm{cn}(u, k)$$\n\n"
             "and $\\omega(t)$ has the period $T = 4K(k)/\\lambda$.")
    assert raw_tex_in_markdown(md, broken)
    assert raw_tex_in_markdown(md, fixed) == []


@pytest.mark.parametrize("name,text", SOURCES, ids=[n for n, _ in SOURCES])
def test_markdown_math_parses_as_math(name, text):
    bad = raw_tex_in_markdown(_parser(), text)
    assert not bad, (f"{name}: TeX outside math (write it as $...$; a $$ display inside a "
                     f"paragraph needs a blank line before and after it): {bad[:3]}")


class _VisibleText(HTMLParser):
    """The text a reader sees as prose: outside math, code, scripts and styles."""

    SKIP_TAGS = {"script", "style", "pre", "code", "kbd", "samp", "tt", "textarea", "math",
                 "svg"}
    VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta",
            "source", "track", "wbr"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack = []          # (tag, skipped)
        self.chunks = []

    def _skipping(self):
        return any(skip for _, skip in self.stack)

    def handle_starttag(self, tag, attrs):
        if tag in self.VOID:
            return
        classes = (dict(attrs).get("class") or "").split()
        skip = (tag in self.SKIP_TAGS or "math" in classes
                or any(c.startswith("highlight") for c in classes)
                or "output" in classes)           # a notebook's printed output is code
        self.stack.append((tag, skip))

    def handle_endtag(self, tag):
        for i in range(len(self.stack) - 1, -1, -1):
            if self.stack[i][0] == tag:
                del self.stack[i:]
                return

    def handle_data(self, data):
        if not self._skipping():
            self.chunks.append(data)


def raw_tex_in_html(html):
    parser = _VisibleText()
    parser.feed(html)
    text = " ".join(parser.chunks)
    return [text[max(0, m.start() - 30):m.end() + 30].replace("\n", " ")
            for m in RAW_TEX.finditer(text)]


def _html_pages():
    """(page, source) for the built pages of the Markdown sources and notebooks."""
    if not (HTML / "index.html").is_file():
        return []
    pages = []
    for page in sorted(HTML.rglob("*.html")):
        rel = page.relative_to(HTML).with_suffix("")
        if rel.parts[0] in ("_static", "_modules", "_sources", "genindex", "search"):
            continue
        src = None
        for cand in (DOCS / rel.with_suffix(".md"), DOCS / rel.with_suffix(".rst"),
                     ROOT / rel.with_suffix(".ipynb")):
            if cand.is_file():
                src = cand
        pages.append((page, src))
    return pages


PAGES = _html_pages()


def test_the_html_check_sees_raw_tex():
    broken = ('<p>the intermediate one, <span class="math notranslate nohighlight">'
              '\\(\\omega_a = A\\)</span> and\\omega(t)hastheperiod</p>')
    fixed = ('<p>and <span class="math notranslate nohighlight">\\(\\omega(t)\\)</span> has '
             'the period <code>$HOME</code></p><script>var a = "\\\\alpha $";</script>'
             '<div class="math notranslate nohighlight">\\[T = 4K(k)/\\lambda\\]</div>')
    assert raw_tex_in_html(broken)
    assert raw_tex_in_html(fixed) == []


@pytest.mark.skipif(not PAGES, reason="the site is not built (bash scripts/dev.sh docs)")
@pytest.mark.parametrize("page,src", PAGES,
                         ids=[str(p.relative_to(HTML)) for p, _ in PAGES] or None)
def test_built_pages_show_no_raw_tex(page, src):
    if src is not None and src.stat().st_mtime > page.stat().st_mtime:
        pytest.skip(f"{page.relative_to(HTML)} is older than {src.name}: rebuild the site")
    bad = raw_tex_in_html(page.read_text(errors="replace"))
    assert not bad, f"{page.relative_to(HTML)}: TeX outside math: {bad[:3]}"
