"""Progress of long work (issue: mp.lagrangian 2 s, mp.mechanics of the bicycle 10-22 s
said nothing): silent for the first second, then the stages named, on a terminal a line
each (no tqdm) or a tqdm bar; MECHPY_PROGRESS=0 keeps it silent."""
import sys
import time

import pytest

from mechpy import _progress


def _run(monkeypatch, capsys, waits, tqdm=False):
    if not tqdm:
        monkeypatch.setitem(sys.modules, "tqdm.auto", None)   # import fails: lines
    with _progress.Stages("mp.lagrangian", ("deriving", "printing C", "compiling"),
                          after=0.2) as bar:
        for name, wait in zip(("deriving", "printing C", "compiling"), waits):
            bar.stage(name)
            time.sleep(wait)
    return capsys.readouterr().err


def test_short_work_says_nothing(monkeypatch, capsys):
    assert _run(monkeypatch, capsys, (0.0, 0.0, 0.0)) == ""


def test_long_work_names_its_stages_past_the_first_interval(monkeypatch, capsys):
    err = _run(monkeypatch, capsys, (0.35, 0.0, 0.05))
    lines = err.strip().splitlines()
    # the first stage named once the interval passed inside it, then each next one
    assert [ln.split(" (")[0] for ln in lines] == [
        "mp.lagrangian: deriving", "mp.lagrangian: printing C", "mp.lagrangian: compiling",
        "mp.lagrangian: done"]
    assert float(lines[0].split("(")[1].split(" s")[0]) >= 0.2


def test_a_bar_with_tqdm(monkeypatch, capsys):
    pytest.importorskip("tqdm")
    err = _run(monkeypatch, capsys, (0.35, 0.0, 0.0), tqdm=True)
    assert "mp.lagrangian: deriving" in err       # tqdm writes its bar to stderr


def test_silent_when_asked(monkeypatch, capsys):
    monkeypatch.setenv("MECHPY_PROGRESS", "0")
    assert _run(monkeypatch, capsys, (0.35, 0.0, 0.0)) == ""


def test_a_lagrangian_names_its_stages(monkeypatch, capsys):
    """mp.lagrangian through the same stages (the interval set to 0: shown at once; a
    new parameter name, so that nothing comes from the cache)."""
    import sympy as sp

    import mechpy as mp
    monkeypatch.setattr(_progress, "AFTER", 0.0)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    th, = mp.coordinates("theta")
    k = sp.Symbol(f"k{time.time_ns()}")
    mp.lagrangian(th.diff() ** 2 / 2 - k * th ** 2 / 2, [th], params={k.name: 4.0})
    err = capsys.readouterr().err
    for stage in ("deriving the equations", "printing C", "compiling", "done"):
        assert f"mp.lagrangian: {stage}" in err


def test_a_portraits_overlays_name_their_values(monkeypatch, capsys):
    """A saved portrait precomputes its overlays over each slider (4 s for a few
    sliders): the values named as they are computed."""
    import mechpy as mp
    monkeypatch.setattr(_progress, "AFTER", 0.0)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    p = mp.live.phase_portrait(mp.scenes.VanDerPol(1.0), (-3, 3), (-3, 3),
                               params={"mu": (0.5, 2.0)}, overlay_grid=3)
    p.precompute()
    err = capsys.readouterr().err
    for v in ("0.5", "1.25", "2"):
        assert f"phase_portrait: overlays at mu = {v}" in err


def test_a_kane_model_names_its_stages(monkeypatch, capsys):
    """mp.mechanics (the bicycle builds for 10-22 s) through its stages."""
    import sympy as sp
    from sympy.physics import mechanics as me

    import mechpy as mp
    monkeypatch.setattr(_progress, "AFTER", 0.0)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    q, u = me.dynamicsymbols("q u")
    c = sp.Symbol(f"c{time.time_ns()}")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x)
    kane = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff() - u])
    kane.kanes_equations([me.Particle("p", P, 1.0)], [(P, -c * q * N.x)])
    mp.mechanics(kane, {c.name: 4.0})
    err = capsys.readouterr().err
    for stage in ("reading the model", "deriving the equations", "printing C", "compiling",
                  "done"):
        assert f"mp.mechanics: {stage}" in err
