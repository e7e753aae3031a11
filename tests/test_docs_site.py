"""The docs site for a newcomer: the landing page names every guide page and runs a live
portrait, the site asks no other host for anything (counted in headless Chromium, as the
live pages' tests count theirs), the doctrees stay out of the published folder.

The whole site is built by ``bash scripts/dev.sh docs`` (not part of the suite: minutes);
``test_a_subset_of_the_site_builds_offline_and_as_math`` builds three of its pages with the
docs' own configuration where the docs extra is installed, and the checks of the built
site run on ``docs/_build/html`` when it is there."""
from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys

import pytest

from live_browser import driver, network_requests, wait_for  # noqa: F401
from test_docs_math import raw_tex_in_html, source_root

ROOT = source_root()
pytestmark = pytest.mark.skipif(ROOT is None, reason="no docs/ beside or above the tests")
DOCS = ROOT / "docs" if ROOT else None
HTML = DOCS / "_build" / "html" if ROOT else None


def _toctree(path):
    """The entries of the toctrees of a MyST page."""
    text = path.read_text()
    out = []
    for block in re.findall(r"```\{toctree\}\n(.*?)```", text, flags=re.S):
        out += [ln.strip() for ln in block.splitlines()
                if ln.strip() and not ln.strip().startswith(":")]
    return out


def test_the_landing_page_names_every_guide_page():
    guide = _toctree(DOCS / "guide" / "index.md")
    assert len(guide) >= 17
    index = (DOCS / "index.md").read_text()
    missing = [g for g in guide if f"(guide/{g}.md)" not in index]
    assert not missing, f"docs/index.md does not link these guide pages: {missing}"
    entries = _toctree(DOCS / "index.md")
    for page in ("quickstart", "install", "guide/index", "development/index"):
        assert page in entries, f"{page} is not in the landing page's toctree"
    # the development notes sit in their own part, not among the user's pages
    dev = _toctree(DOCS / "development" / "index.md")
    assert {"../benchmarks", "../reliability", "performance"} <= set(dev)


def test_the_landing_page_opens_on_a_live_portrait():
    text = (DOCS / "index.md").read_text()
    first_section = text.split("\n## ", 1)[0]
    cell = re.search(r"```\{code-cell\}[^\n]*\n(.*?)```", first_section, flags=re.S)
    assert cell and "mp.live.phase_portrait(" in cell.group(1)


def test_guide_pages_carry_no_development_notes():
    """Instruction counts, goals and machine loads are the development notes' (docs/development)."""
    notes = re.compile(r"valgrind|instructions (?:a|an|per) |goal of|load average")
    found = [f"{p.name}: {m.group(0)}" for p in sorted((DOCS / "guide").glob("*.md"))
             for m in notes.finditer(p.read_text())]
    assert not found, found


def test_the_doctrees_stay_out_of_the_published_folder():
    line = next(ln for ln in (ROOT / "scripts" / "dev.sh").read_text().splitlines()
                if "-m sphinx" in ln and not ln.lstrip().startswith("#"))
    args = line.split()
    out, doctrees = args[-2 if args[-1] == '"$@"' else -1], args[args.index("-d") + 1]
    assert out == "docs/_build/html"
    assert not doctrees.startswith(out), (doctrees, out)


def test_remote_stylesheets_are_dropped_from_cell_outputs():
    """matplotlib's JSHTML animation asks Font Awesome from a CDN: the docs build drops
    that link (docs/_ext/offline_html.py), and keeps the rest of the output."""
    pytest.importorskip("docutils")
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation

    spec = importlib.util.spec_from_file_location("offline_html",
                                                  DOCS / "_ext" / "offline_html.py")
    ext = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ext)
    fig, ax = plt.subplots(figsize=(1, 1), dpi=20)
    (ln,) = ax.plot([0, 1])
    html = FuncAnimation(fig, lambda k: (ln,), frames=2).to_jshtml()
    plt.close(fig)
    assert re.search(r"https?://", html)                 # what matplotlib writes today
    kept = ext.without_remote_stylesheets(html)
    assert not re.search(r"<link[^>]*https?://", kept)
    assert kept.count("<script") == html.count("<script") and "anim-buttons" in kept
    local = '<link rel="stylesheet" href="_static/x.css">'
    assert ext.without_remote_stylesheets(local) == local


# ---------------------------------------------------------------- built pages

def _external(driver, url):
    """The requests a page makes, in Chromium, to anything but its own files."""
    network_requests(driver)
    driver.get(url)
    wait_for(driver, "document.readyState === 'complete'", 60)
    driver.execute_script("window.scrollTo(0, document.body.scrollHeight)")
    # the live views in their frames: wait for each to run (a dead widget fails here)
    n = driver.execute_script("return document.querySelectorAll('iframe').length")
    for i in range(n):
        driver.switch_to.frame(driver.find_elements("tag name", "iframe")[i])
        wait_for(driver, "window.mechpyLive && window.mechpyLive.ready", 60)
        driver.switch_to.default_content()
    return [u for u in network_requests(driver) if not u.startswith("file:")]


def _local_mathjax():
    return (HTML / "_static" / "mathjax" / "MathJax.js").is_file()


BUILT = ["index.html", "quickstart.html", "guide/events.html", "guide/live.html",
         "notebooks/rigid_body.html", "notebooks/phase_portraits.html"]


@pytest.mark.skipif(not (HTML and (HTML / "index.html").is_file()),
                    reason="the site is not built (bash scripts/dev.sh docs)")
@pytest.mark.parametrize("page", BUILT)
def test_built_pages_ask_no_other_host(driver, page):
    if not _local_mathjax():
        pytest.skip("the site was built without a local MathJax (Debian's libjs-mathjax)")
    if not (HTML / page).is_file():
        pytest.skip(f"{page} is not built")
    assert _external(driver, f"file://{HTML / page}") == []


def test_a_subset_of_the_site_builds_offline_and_as_math(driver, tmp_path):
    """The landing page (a live widget: its widget state once brought myst-nb's require.js
    from a CDN), the events page (its figure computed at build time) and the phase page
    (formulas once shown as typed), built with docs/conf.py into a folder of their own:
    no raw TeX in their text, no request to another host, the widget running."""
    pytest.importorskip("myst_nb")
    pytest.importorskip("pydata_sphinx_theme")
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        f"__file__ = {str(DOCS / 'conf.py')!r}\n"
        "exec(compile(open(__file__).read(), __file__, 'exec'))\n")
    for d in ("images", "_static", "_templates", "_ext"):
        (src / d).symlink_to(DOCS / d)
    (src / "guide").mkdir()
    pages = ["index.md", "guide/events.md", "guide/phase.md"]
    for p in pages:
        shutil.copyfile(DOCS / p, src / p)
    out = tmp_path / "html"
    run = subprocess.run([sys.executable, "-m", "sphinx", "-q", "-b", "html", "-d",
                          str(tmp_path / "doctrees"), str(src), str(out)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    # links to the pages left out are the only warnings
    left = [ln for ln in run.stderr.splitlines() if "WARNING" in ln and not re.search(
        r"unknown document|nonexisting document|not found|included in any toctree"
        r"|IPKernelApp", ln)]
    assert not left, left
    for p in pages:
        html = (out / p).with_suffix(".html")
        assert raw_tex_in_html(html.read_text()) == [], p
    assert "widget-state+json" in (out / "index.html").read_text()
    if not (out / "_static" / "mathjax" / "MathJax.js").is_file():
        pytest.skip("no local MathJax (Debian's libjs-mathjax): the pages load it from its CDN")
    for p in ("index.html", "guide/events.html"):
        assert _external(driver, f"file://{out / p}") == [], p
