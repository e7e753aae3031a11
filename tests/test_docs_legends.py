"""The plots on the site have legends a reader can read: a legend's text is at least as
large as the axis labels' and the legend lies inside its figure (an animation's frames are
drawn at a fixed size, with nothing to widen them).  The site's plots are drawn by
``mechpy.plot`` (the notebooks' animations and portraits, the bench's work-precision
figures) and by the notebooks' own code: both are checked here, the first by drawing, the
second by reading every ``legend(...)`` call of the notebooks and the docs' code cells."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

import mechpy as mp

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.font_manager as fm  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

from test_docs_math import source_root  # noqa: E402


def _check_legends(fig):
    """Every legend of ``fig``: text not smaller than its axes' x label, inside the figure."""
    fig.canvas.draw()
    found = 0
    whole = fig.bbox
    for ax in fig.axes:
        leg = ax.get_legend()
        if leg is None:
            continue
        found += 1
        label = ax.xaxis.label.get_fontsize()
        sizes = [t.get_fontsize() for t in leg.get_texts()]
        if leg.get_title().get_text():
            sizes.append(leg.get_title().get_fontsize())
        assert min(sizes) >= label, (
            f"{ax.get_title()!r}: legend text {min(sizes)} pt, axis labels {label} pt")
        box = leg.get_window_extent()
        assert (box.x0 >= whole.x0 - 1 and box.y0 >= whole.y0 - 1 and box.x1 <= whole.x1 + 1
                and box.y1 <= whole.y1 + 1), f"{ax.get_title()!r}: legend {box} outside {whole}"
    return found


def _frame(anim, k=1):
    anim._init_draw()
    anim._draw_frame(k)
    return anim._fig


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def test_animation_legends():
    top = mp.scenes.HeavyTop(0.5, 0.2, 1.0, 9.81, 0.1)
    sol = mp.solve(top, (0, 2), [0.0, 0.8, 0.0, -1.0, 0.0, 15.0], rtol=1e-9)
    assert _check_legends(_frame(mp.plot.animate(top, sol, frames=3))) == 1
    body = mp.scenes.RigidBody([1.0, 2.0, 3.0], orientation=True)
    sol = mp.solve(body, (0, 5), body.initial_state([0.02, 1.0, 0.01]), rtol=1e-9)
    assert _check_legends(_frame(mp.plot.animate(body, sol, frames=3))) == 1
    chain = mp.scenes.SpringChain([1.0, 1.0, 1.0, 1.0], 1.0, ends="fixed")
    y0 = np.zeros(8)
    y0[0] = 0.3
    sol = mp.solve(chain, (0, 10), y0, rtol=1e-9)
    assert _check_legends(_frame(mp.plot.animate(chain, sol, frames=3))) == 1


def test_figure_legends():
    ax = mp.plot.phase_portrait(mp.scenes.VanDerPol(mu=1.0), (-3, 3), (-4, 4), grid=21,
                                trajectories=[[2.0, 0.0]], t_max=5)
    assert _check_legends(ax.figure) == 1
    rows = [dict(problem="p", impl=impl, time=t, error=e)
            for impl, k in (("mechpy dop853", 1.0), ("scipy DOP853", 10.0), ("other", 3.0))
            for t, e in ((1e-3 * k, 1e-6), (2e-3 * k, 1e-9))]
    assert _check_legends(mp.plot.work_precision(rows).figure) == 1
    m = mp.modes.normal_modes(*mp.modes.chain(4))
    assert _check_legends(mp.plot.modes(m).figure) == 1


def test_the_check_sees_a_small_legend():
    fig, ax = plt.subplots()
    ax.plot([0, 1], label="a line")
    ax.set_xlabel("x (m)")
    ax.legend(fontsize=7)
    with pytest.raises(AssertionError, match="legend text"):
        _check_legends(fig)


#: a legend(...) call's explicit font size (fontsize= or title_fontsize=, a number or a name)
LEGEND_SIZE = re.compile(r"legend\((?:[^()]|\([^()]*\))*?\b(?:title_)?fontsize\s*=\s*"
                         r"""(?P<size>[\d.]+|["'][a-z-]+["'])""")


def _code_sources():
    root = source_root()
    if root is None:
        pytest.skip("no docs/ beside or above the tests")
    out = []
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        for i, cell in enumerate(json.loads(path.read_text())["cells"]):
            if cell["cell_type"] == "code":
                src = cell["source"]
                out.append((f"{path.name} cell {i}", "".join(src) if isinstance(src, list) else src))
    for path in sorted((root / "docs").rglob("*.md")):
        if "_build" not in path.parts:
            out.append((str(path.relative_to(root)), path.read_text()))
    return out


def test_notebook_legends_are_not_smaller_than_axis_labels():
    label = fm.FontProperties(size=matplotlib.rcParams["axes.labelsize"]).get_size_in_points()
    small = []
    for name, src in _code_sources():
        for m in LEGEND_SIZE.finditer(src):
            size = m.group("size").strip("'\"")
            pts = fm.FontProperties(size=float(size) if size[0].isdigit() else size)
            if pts.get_size_in_points() < label:
                small.append(f"{name}: {m.group(0)}")
    assert not small, f"legends smaller than the axis labels ({label} pt): {small}"


def test_the_source_check_sees_a_small_legend():
    src = 'ax.legend(handles=h, loc="best", bbox_to_anchor=(1.0, 0.5), fontsize=8)'
    assert LEGEND_SIZE.search(src).group("size") == "8"
    assert LEGEND_SIZE.search('ax.legend(fontsize="small")').group("size") == '"small"'
