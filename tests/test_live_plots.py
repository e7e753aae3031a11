"""plots=[...] beside the motion in mp.live.animate (mp.plot.animate's are in
tests/test_plot.py) and the 3D view's camera framing what is drawn: the
series read back from the page (window.mechpyLive.plot) against the solution
evaluated independently, the cursor at the shown frame, screenshots of the
canvas (what is drawn fits it and fills it), the size of a bicycle's page,
bad input."""
from __future__ import annotations

import io
import os

import numpy as np
import pytest
import sympy as sp

import mechpy as mp
from mechpy import _series

pytest.importorskip("anywidget")
from live_browser import driver, open_page  # noqa: E402,F401
from test_live_bodies import _triple_pendulum  # noqa: E402
from test_live_motion import _page  # noqa: E402

LINKS = [("O", "bob1"), ("bob1", "bob2"), ("bob2", "bob3")]


def _energy_by_hand(Y, l=0.7, g=9.81):
    """T + V of the triple pendulum (unit masses, rods l) from its angles and
    rates, NumPy: every bob's velocity the sum of l (cos, sin) q' above it."""
    a, ad = Y[:3], Y[3:]
    vx = np.cumsum(l * np.cos(a) * ad, axis=0)
    vy = np.cumsum(l * np.sin(a) * ad, axis=0)
    y = np.cumsum(-l * np.cos(a), axis=0)
    return 0.5 * (vx ** 2 + vy ** 2).sum(axis=0) + g * y.sum(axis=0)


def _cursors(driver):
    """Per panel: (data-left, data-width, data-t0, data-t1, cursor's x, its time)."""
    return driver.execute_script("""
        return [...document.querySelectorAll('.mechpy-plot')].map((p) => {
          const c = p.querySelector('.mechpy-cursor');
          return [+p.dataset.left, +p.dataset.width, +p.dataset.t0, +p.dataset.t1,
                  parseFloat(c.style.left) + 1, +c.dataset.t];
        });""")


def _drawn_box(driver):
    """(x0, y0, x1, y1, width, height) of what the 3D canvas shows that is not its
    white background, the legend and clock hidden (a screenshot of the canvas)."""
    from PIL import Image
    from selenium.webdriver.common.by import By
    driver.execute_script("""
        const c = document.querySelector('.mechpy-animate canvas');
        for (const d of c.parentElement.querySelectorAll('div')) d.style.visibility = 'hidden';""")
    canvas = driver.find_element(By.CSS_SELECTOR, ".mechpy-animate canvas")
    img = np.asarray(Image.open(io.BytesIO(canvas.screenshot_as_png)).convert("RGB"))
    ink = np.argwhere((img < 235).any(axis=2))
    assert ink.size, "nothing drawn"
    (y0, x0), (y1, x1) = ink.min(axis=0), ink.max(axis=0)
    return x0, y0, x1, y1, img.shape[1], img.shape[0]


def _framed(driver, frames, least=0.5):
    """At each frame: the drawing stays off the canvas's edges; over them it
    spans ``least`` of the canvas's width or height."""
    boxes = []
    for i in frames:
        driver.execute_script(f"window.mechpyLive.frame({i})")
        x0, y0, x1, y1, W, H = _drawn_box(driver)
        assert x0 > 0 and y0 > 0 and x1 < W - 1 and y1 < H - 1, (i, x0, y0, x1, y1, W, H)
        boxes.append((x0, y0, x1, y1))
    b = np.array(boxes)
    span = max((b[:, 2].max() - b[:, 0].min()) / W, (b[:, 3].max() - b[:, 1].min()) / H)
    assert span >= least, span
    return span


def test_triple_pendulum_plots_energy_angle_and_an_expression(driver, tmp_path):
    scene, points = _triple_pendulum()
    sol = mp.solve(scene, (0, 3), [1.2, 0.4, -0.3, 0.0, 0.0, 0.0], dense_output=True,
                   rtol=1e-10)
    a, c, bd, l = sp.Symbol("a"), sp.Symbol("c"), sp.Symbol("b'"), sp.Symbol("l")
    expr = sp.sin(a - c) + l * bd
    w = mp.live.animate(scene, sol, fps=20, points=points, links=LINKS,
                        plots=["energy", "a", expr])
    _page(driver, tmp_path, w, "triple-plots")
    Y = sol.sol(w.times)                       # the frames' states, from the dense output
    got = {nm: driver.execute_script(f"return window.mechpyLive.plot({nm!r})")
           for nm in ("energy", "a", str(expr))}
    for nm, g in got.items():
        assert np.array_equal(g["t"], w.times), nm
    E = np.array(got["energy"]["y"])
    # the compiled Jacobi integral at each frame's state, and T + V by hand: measured
    # 0 and 5.3e-16 relative
    ref = scene.energy(Y)
    assert np.abs(E - ref).max() <= 1e-12 * np.abs(ref).max()
    assert np.abs(E - _energy_by_hand(Y)).max() <= 1e-12 * np.abs(ref).max()
    assert np.array_equal(got["a"]["y"], Y[0])
    f = sp.lambdify([a, c, bd, l], expr, "numpy")
    np.testing.assert_allclose(got[str(expr)]["y"], f(Y[0], Y[2], Y[4], 0.7), rtol=1e-14,
                               atol=1e-15)
    with pytest.raises(Exception, match="no plot named b"):
        driver.execute_script("return window.mechpyLive.plot('b')")
    # the cursor of each panel at the shown frame's time, on the panel's time axis
    n = w.times.size
    for i in (0, 17, n - 1):
        driver.execute_script(f"window.mechpyLive.frame({i})")
        cur = _cursors(driver)
        assert len(cur) == 3
        for left, width, t0, t1, x, t in cur:
            assert t == w.times[i] and (t0, t1) == (w.times[0], w.times[-1])
            assert abs(x - (left + (t - t0) / (t1 - t0) * width)) < 0.01
    # it follows the time slider and play
    driver.execute_script("""
        const s = document.querySelector('input[aria-label="frame"]');
        s.value = '40'; s.dispatchEvent(new Event('input'));""")
    assert {c[5] for c in _cursors(driver)} == {w.times[40]}
    driver.execute_script("window.mechpyLive.play()")
    driver.execute_script("return new Promise((r) => setTimeout(r, 400))")
    t_now = driver.execute_script("window.mechpyLive.pause(); return window.mechpyLive.time()")
    assert {c[5] for c in _cursors(driver)} == {t_now} and t_now != w.times[40]
    # the camera frames the pendulum and its trails (canvas screenshots): measured 77 %
    # of the height
    _framed(driver, (0, n // 2, n - 1))


def test_points_are_drawn_with_y_up(driver, tmp_path):
    """A drawing from points= shows y up: the triple pendulum hanging at rest is
    a vertical line on the screen (its top and bottom rows of ink one above
    the other), whatever the camera's distance."""
    scene, points = _triple_pendulum()
    w = mp.live.animate(scene, np.zeros((6, 2)), t=[0.0, 1.0], points=points, links=LINKS)
    _page(driver, tmp_path, w, "triple-at-rest")
    from PIL import Image
    from selenium.webdriver.common.by import By
    _drawn_box(driver)                                 # hides the legend and the clock
    canvas = driver.find_element(By.CSS_SELECTOR, ".mechpy-animate canvas")
    img = np.asarray(Image.open(io.BytesIO(canvas.screenshot_as_png)).convert("RGB"))
    ink = np.argwhere((img < 235).any(axis=2))
    top, bottom = ink[:, 0].min(), ink[:, 0].max()
    height = bottom - top
    x_of = lambda rows: ink[np.isin(ink[:, 0], rows), 1].mean()    # noqa: E731
    x_top = x_of(np.arange(top, top + height // 10))
    x_bottom = x_of(np.arange(bottom - height // 10, bottom + 1))
    # measured: 0.003 px apart over a height of 538 px (a roll of 1 degree puts them 9 px
    # apart; the up of (0.1, 1, 0), 49 px)
    assert height > 200 and abs(x_top - x_bottom) < 2.0, (height, x_top, x_bottom)


def test_chain_of_40_masses_fills_the_view(driver, tmp_path):
    chain = mp.scenes.SpringChain(np.ones(40), 1.0)
    y0 = np.zeros(80)
    y0[:40] = 0.3 * np.sin(np.pi * np.arange(1, 41) / 41)
    sol = mp.solve(chain, (0, 10), y0, dense_output=True)
    w = mp.live.animate(chain, sol, fps=10)
    _page(driver, tmp_path, w, "chain40")
    # measured: 92 % of the width (57 %, 9 px high, before the camera framed what is drawn)
    assert _framed(driver, (0, 50, 100), least=0.8) > 0.8


def test_bicycle_page_of_10_s_is_small_and_framed(driver, tmp_path):
    from mechpy.symbolic.models import whipple_bicycle, whipple_state
    kane, p = whipple_bicycle()
    bike = mp.mechanics(kane, p)
    sol = mp.solve(bike, (0, 10), bike.project(whipple_state(4.6, roll_rate=0.5)),
                   dense_output=True, rtol=1e-10)
    w = mp.live.animate(bike, sol, fps=30, shapes={"R": dict(kind="torus", size=p["rR"]),
                                                   "F": dict(kind="torus", size=p["rF"])},
                        plots=["energy"])
    assert w.times.size == 301
    path = _page(driver, tmp_path, w, "bicycle")
    size = os.path.getsize(path)
    # measured 1.00 MB: three.js and the page's code 0.84 MB, 301 frames of 4 places
    # and 4 rotations 0.16 MB, the series 3 kB (base64 of float64)
    assert size < 2_000_000
    _framed(driver, (0, 150, 300))        # measured: 79 % of the width


def test_series_and_their_expressions_agree():
    """_series.expressions (what a page that integrates prints) evaluated at
    the states equals _series.series; coordinates as functions of t work."""
    scene, _ = _triple_pendulum()
    sol = mp.solve(scene, (0, 1), [1.2, 0.4, -0.3, 0.5, 0.0, 0.0], dense_output=True,
                   rtol=1e-10)
    times = np.linspace(0, 1, 11)
    Y = sol.sol(times)
    t = sp.Symbol("t")
    q = sp.Function("a")(t)
    plots = ["energy", "c'", q.diff(t) * sp.cos(q) + t * sp.Symbol("g")]
    got = _series.series(scene, plots, times, Y)
    assert [g[0] for g in got] == ["energy", "c'", str(plots[2])]
    np.testing.assert_array_equal(got[1][1], Y[5])
    np.testing.assert_allclose(got[2][1], Y[3] * np.cos(Y[0]) + 9.81 * times, rtol=1e-15)
    ys = sp.symbols("y0:6")
    for (label, values), (label2, e) in zip(got, _series.expressions(scene, plots)):
        assert label == label2 and e.free_symbols <= set(ys) | set(sp.symbols("t l g"))
        f = sp.lambdify([t, *ys, sp.Symbol("l"), sp.Symbol("g")], e, "numpy")
        v = np.broadcast_to(f(times, *Y, 0.7, 9.81), times.shape)
        # the symbolic energy against the compiled one: measured 5e-16 relative
        np.testing.assert_allclose(v, values, rtol=1e-13, atol=0)
    assert _series.expressions(mp.scenes.Pendulum(), ["energy"]) == [("energy", None)]
    # a mechanics model's T + V, symbolic against compiled: measured 2.2e-16 relative
    from mechpy.symbolic.models import rolling_disc
    kane, params = rolling_disc()
    disc = mp.mechanics(kane, params)
    Y = np.array([disc.project([0.0, 0.2 * k, 0.0, 0.0, 0.0, 0.3, 0.1 * k, 4.0, 0.0, 0.0])
                  for k in range(5)]).T
    ((_, e),) = _series.expressions(disc, ["energy"])
    ys = sp.symbols(f"y0:{disc.dim}")
    f = sp.lambdify([*ys, *map(sp.Symbol, params)], e, "numpy")
    np.testing.assert_allclose(f(*Y, *params.values()), disc.energy(Y), rtol=1e-14)


def test_bad_plots_are_named():
    scene, points = _triple_pendulum()
    sol = mp.solve(scene, (0, 0.5), [0.1, 0.0, 0.0, 0.0, 0.0, 0.0], dense_output=True)
    kw = dict(points=points, links=LINKS, fps=10)
    with pytest.raises(ValueError, match=r"'d' is neither a state of the system \(\['a',"):
        mp.live.animate(scene, sol, plots=["d"], **kw)
    with pytest.raises(ValueError, match=r"plots\['a \+ k'\] depends on k, which is neither a "
                                         "state"):
        mp.live.animate(scene, sol, plots=[sp.Symbol("a") + sp.Symbol("k")], **kw)
    with pytest.raises(ValueError, match=r"series 'log\(a - 1\)' is not finite at t = 0"):
        mp.live.animate(scene, sol, plots=[sp.log(sp.Symbol("a") - 1)], **kw)
    with pytest.raises(TypeError, match="3 is not a state's name"):
        mp.live.animate(scene, sol, plots=[3], **kw)
    with pytest.raises(TypeError, match="plots must be a list"):
        mp.live.animate(scene, sol, plots="energy", **kw)
    with pytest.raises(ValueError, match=r"plots names \['a'\] more than once"):
        mp.live.animate(scene, sol, plots=["a", "a"], **kw)
    # a page that simulates computes its series: a built-in scene's energy (C only) it cannot
    pend = mp.scenes.Pendulum()
    with pytest.raises(ValueError, match=r"cannot recompute the series \['energy'\]: a "
                                         "built-in scene's energy is computed in C only"):
        mp.live.animate(pend, mp.solve(pend, (0, 1), [0.5, 0.0]), plots=["theta", "energy"],
                        params={"g": (1.0, 20.0)})
    x, v = sp.symbols("x v")
    osc = mp.equations([v, -x], [x, v])
    with pytest.raises(ValueError, match=r"'energy' asked of CompiledScene\(equations.*which "
                                         "has no"):
        mp.live.animate(osc, mp.solve(osc, (0, 1), [1.0, 0.0]), points={"m": (x, 0, 0)},
                        plots=["energy"])
    with pytest.raises(ValueError, match="'energy' asked of CompiledScene"):
        _series.expressions(osc, ["energy"])
