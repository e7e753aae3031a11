"""CONTRIBUTING.md's recipes "A new scene" and "A new drawing", walked: the C
file of the recipe compiles against the row of today, every scene has the row
line, the meson line and the class line the recipe names, the recipe's class
line makes a scene, and a drawing made as the recipe says is drawn by both
painters."""
from __future__ import annotations

import gc
import inspect
import os
import pathlib
import re
import subprocess

import numpy as np
import pytest

import mechpy as mp
from mechpy import _core, _motion

# the checkout (dev.sh names it in MECHPY_SOURCE_DIR when the suite runs from a copy of
# tests/ beside an installed mechpy): the recipes name its files
ROOT = pathlib.Path(os.environ.get("MECHPY_SOURCE_DIR") or pathlib.Path(__file__).parents[1])


def _section(title: str) -> str:
    text = (ROOT / "CONTRIBUTING.md").read_text()
    start = text.index(f"## {title}")
    end = text.find("\n## ", start + 3)
    return text[start:end if end > 0 else None]


def _blocks(section: str, lang: str) -> list:
    return re.findall(rf"```{lang}\n(.*?)```", section, flags=re.S)


SCENE = _section("A new scene")
DRAWING = _section("A new drawing")


def test_the_new_scene_c_file_compiles_against_the_row():
    """The recipe's C file, as written, against csrc/models/models.h: -Wall
    -Wextra clean (a row field the recipe names that the struct lacks, or a
    changed function type, fails here)."""
    from mechpy.symbolic.build import compiler, have_compiler
    if not have_compiler():
        pytest.skip("no C compiler")
    (src,) = _blocks(SCENE, "c")
    # the project's flags (meson.build: c11, warning_level=2, -fopenmp-simd)
    cmd = compiler() + ["-std=c11", "-fopenmp-simd", "-fsyntax-only", "-Wall", "-Wextra", "-Werror",
                        "-I", str(ROOT / "csrc"), "-x", "c", "-"]
    r = subprocess.run(cmd, input=src, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert re.search(r"const mp_model mp_model_(\w+) = \{", src)


def test_every_scene_has_the_lines_the_recipe_names():
    """The row line in csrc/models/list.h, the meson line, the class line:
    the form the recipe gives is the form of every scene there is."""
    (c_src,) = _blocks(SCENE, "c")
    sym = re.search(r"mp_model mp_model_(\w+)", c_src)[1]
    assert f"`MP_MODEL({sym})` in `csrc/models/list.h`" in SCENE
    assert f"`'models/{sym}.c',` in `c_sources` of `csrc/meson.build`" in SCENE
    listed = re.findall(r"^MP_MODEL\((\w+)\)$", (ROOT / "csrc/models/list.h").read_text(),
                        flags=re.M)
    rows = {}
    for path in (ROOT / "csrc/models").glob("*.c"):
        for s, name in re.findall(r'const mp_model mp_model_(\w+) = \{\s*\.name = "(\w+)"',
                                  path.read_text()):
            rows[s] = name
    assert [rows[s] for s in listed] == list(_core.scene_rows())   # one line a row, in order
    meson = (ROOT / "csrc/meson.build").read_text()
    for path in (ROOT / "csrc/models").glob("*.c"):
        assert f"  'models/{path.name}',\n" in meson
    scenes_py = (ROOT / "mechpy/scenes.py").read_text()
    (py_src,) = _blocks(SCENE, "python")
    head = py_src.splitlines()[0]
    assert re.fullmatch(r'class (\w+)\(Scene, row="\1"\):', head)
    for row in _core.scene_rows():
        if row != "RigidBodyOriented":           # a RigidBody with orientation=True
            assert f'class {row}(Scene, row="{row}"):' in scenes_py
            assert row in mp.scenes.__all__


def test_the_class_line_makes_a_scene():
    """The recipe's class, on an existing row (the Van der Pol oscillator's):
    its signature, defaults, documented parameters and state names come from
    the row; it is a scene mp.solve takes.  (Made and dropped here: the other
    tests list the scene classes.)"""
    (py_src,) = _blocks(SCENE, "python")
    ns = {"Scene": mp.scenes.Scene}
    exec(py_src.replace('row="Oscillator"', 'row="VanDerPol"'), ns)
    cls = ns.pop("Oscillator")
    try:
        assert list(inspect.signature(cls).parameters) == ["mu"]
        s = cls(mu=0.5)
        assert s.states == ["x", "x'"] and s.coordinates == ["x"] and s.speeds == ["x'"]
        assert "Parameters from the scene's C row: ``mu`` (default 1.0, >= 0)" in cls.__doc__
        assert "Its states, by name" in cls.__doc__
        sol = mp.solve(s, (0, 1), {"x": 1.0, "x'": 0.0}, rtol=1e-10)
        ref = mp.solve(mp.scenes.VanDerPol(0.5), (0, 1), [1.0, 0.0], rtol=1e-10)
        np.testing.assert_array_equal(sol.y, ref.y)
    finally:
        del cls, s
        gc.collect()
    assert all(c.__name__ != "Oscillator" for c in mp.scenes.Scene.__subclasses__())


# ------------------------------------------------------------------ a new drawing

def _dot_plot(ax, system, t, y, trail, lengths):
    """The recipe's matplotlib painter: a dot at (theta, 0)."""
    ax.set_xlim(-np.pi, np.pi)
    (dot,) = ax.plot([], [], "o", gid="dot")

    def update(k):
        dot.set_data(y[:1, k], [0.0])
        return (dot,)
    return update


def _dot_live(system, times, Y):
    """The recipe's three.js painter: a body at (theta, 0, 0)."""
    P = np.stack([Y[0], np.zeros_like(Y[0]), np.zeros_like(Y[0])], axis=-1)[:, None, :]
    return dict(P=P, bodies=[{"name": "dot", "color": "#1f77b4", "radius": 0.1,
                              "shape": "sphere", "local": None}],
                rods=[], lines=[], trail=[0], up=[0, 1, 0], center=[0.0, 0.0, 0.0],
                extent=4.0, camera=[0.0, 0.0, 1.0], title="a dot at theta")


def test_a_drawing_made_as_the_recipe_says_is_drawn_by_both_painters(monkeypatch):
    pytest.importorskip("matplotlib")
    pytest.importorskip("anywidget")
    (entry_src,) = _blocks(DRAWING, "python")
    entry = eval(entry_src.strip().rstrip(","), {"Drawing": _motion.Drawing})
    assert entry.name == "dot"
    assert entry.plot.startswith("mechpy.plot:") and entry.live.startswith("mechpy.live.motion:")
    entry = entry._replace(plot=f"{__name__}:_dot_plot", live=f"{__name__}:_dot_live",
                           rows=("Pendulum",))
    monkeypatch.setitem(_motion.DRAWINGS, "dot", entry)
    p = mp.scenes.Pendulum()
    sol = mp.solve(p, (0, 1), [1.0, 0.0], t_eval=np.linspace(0, 1, 5), dense_output=True)
    anim = mp.plot.animate(p, sol, kind="dot")
    anim._func(4)
    (dot,) = [a for a in anim._fig.axes[0].lines if a.get_gid() == "dot"]
    assert dot.get_data()[0][0] == sol.y[0, -1]
    w = mp.live.animate(p, sol, kind="dot", fps=4, duration=1.0)
    assert w.kind == "dot" and w.bodies == ["dot"]
    assert w.spec["legend"] == [["#1f77b4", "dot"]]
    with pytest.raises(TypeError, match="kind='dot' draws a mp.scenes.Pendulum"):
        mp.live.animate(mp.scenes.VanDerPol(), sol, kind="dot")
    import matplotlib.pyplot as plt
    plt.close("all")


def test_every_drawing_follows_the_painters_contract():
    """Each entry's painters take what the recipe says; the rows it names are
    rows, and each such row names it back."""
    pytest.importorskip("matplotlib")
    pytest.importorskip("anywidget")
    for d in _motion.DRAWINGS.values():
        assert list(inspect.signature(d.painter("plot")).parameters) == [
            "ax", "system", "t", "y", "trail", "lengths"]
        live = list(inspect.signature(d.painter("live")).parameters)
        assert live[:3] == ["system", "times", "Y"] and live[3:] == list(d.options)
        for row in d.rows:
            assert _core.scene_info(row)["drawing"] == d.name
