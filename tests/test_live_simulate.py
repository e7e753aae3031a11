"""mp.live.animate(..., params=, y0=): a page that integrates the system itself
(Dormand-Prince 5(4) with dense output, static/simulate.js), read back from the
page in headless Chromium against mp.solve (rtol 1e-10) and the drawings'
geometry computed here from mp.solve's states; its sliders (setParam) against
mp.solve at the new values; the step budget; what Python refuses."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

pytest.importorskip("anywidget")
from live_browser import driver, network_requests, open_page  # noqa: E402,F401
from test_live_motion import _page  # noqa: E402

SPAN = (0.0, 10.0)


def _reference(system, y0, rtol=1e-10, **changes):
    """mp.solve's state at the end of SPAN (DOP853, rtol 1e-10 and atol 1e-12;
    or ``rtol`` and atol 1e-3 of it), at the system's parameters with
    ``changes``."""
    s = system.replace(**changes) if changes else system
    return mp.solve(s, SPAN, s.initial_state(y0), rtol=rtol,
                    atol=1e-12 if rtol == 1e-10 else 1e-3 * rtol).y[:, -1]


def _bobs(theta, lengths):
    """The bobs of a planar chain of rods from the downward vertical (x right, y
    up): the running sums of l (sin, -cos), (bobs, 3)."""
    x = np.cumsum(np.asarray(lengths) * np.sin(theta))
    y = np.cumsum(-np.asarray(lengths) * np.cos(theta))
    return np.stack([x, y, np.zeros_like(x)], axis=-1)


def _agrees(pos, system, y0, lengths, truth=5e-10, **changes):
    """The page's bobs ``pos`` (bobs, 3) at the end of SPAN against mp.solve's
    state there: at rtol 1e-10 to 1e-7 (the contract: mp.solve's own error
    dominates), and at rtol 1e-13 to ``truth`` (the page's own error: measured 4.6e-11
    m at most, the pendulum; 4.6e-12 m the double pendulums)."""
    nq = len(lengths)
    got = [np.abs(pos - _bobs(_reference(system, y0, rtol=r, **changes)[:nq], lengths)).max()
           for r in (1e-10, 1e-13)]
    print(f"  {type(system).__name__} {changes}: page - mp.solve at rtol 1e-10: {got[0]:.2g}, "
          f"at 1e-13: {got[1]:.2g}")
    assert got[0] < 1e-7 and got[1] < truth


def _last(driver):
    """positions() at the last frame, (bodies, 3), and the page's time there."""
    t = driver.execute_script("const L = window.mechpyLive; return L.frame(L.frames() - 1)")
    pos = driver.execute_script("return window.mechpyLive.positions()")
    return t, np.array(pos).reshape(-1, 3)


def _set(driver, name, value):
    """setParam(name, value): the run's report."""
    return driver.execute_script(f"return window.mechpyLive.setParam({name!r}, {value!r})")


def test_pendulum_page_simulates_and_its_sliders_rerun(driver, tmp_path):
    p = mp.scenes.Pendulum(length=1.5)
    y0 = [2.0, 0.0]
    sol = mp.solve(p, SPAN, y0, dense_output=True, rtol=1e-10, atol=1e-12)
    w = mp.live.animate(p, sol, fps=30, params={"length": (0.5, 3.0), "g": (1.0, 20.0)},
                        y0=y0)
    assert w.spec["pos"] is None and w.spec["sim"]["nc"] == 0      # the page makes the frames
    _page(driver, tmp_path, w, "pendulum_sim")
    rep = driver.execute_script("return window.mechpyLive.simulation()")
    assert rep["status"] == "done" and rep["t"] == 10.0
    assert driver.execute_script("return window.mechpyLive.params()")["length"] == 1.5
    t, pos = _last(driver)
    assert t == 10.0
    _agrees(pos, p, y0, [1.5])
    # frames along the way against mp.solve's dense output (rtol 1e-10)
    P = np.array(driver.execute_script("""
        const L = window.mechpyLive, out = [];
        for (let i = 0; i < L.frames(); i += 25) { L.frame(i); out.push(L.positions()); }
        return out;""")).reshape(-1, 3)
    th = sol.sol(w.times[::25])[0]
    assert np.abs(P - 1.5 * np.stack([np.sin(th), -np.cos(th), 0 * th], axis=-1)).max() < 1e-7
    # a slider: the length, then g; the places after it are mp.solve's at the new values
    assert _set(driver, "length", 2.25)["status"] == "done"
    _agrees(_last(driver)[1], p, y0, [2.25], length=2.25)
    assert _set(driver, "g", 3.7)["status"] == "done"
    _agrees(_last(driver)[1], p, y0, [2.25], length=2.25, g=3.7)
    slider = driver.execute_script(
        "return document.querySelector('input[aria-label=\"g\"]').value")
    assert float(slider) == 3.7                              # setParam moved the slider
    # a runaway (g = 1e9: 2.6e4 rad/s for 10 s) stops at the step budget, says so, and
    # the page lives on
    rep = _set(driver, "g", 1e9)
    assert rep["status"] == "budget" and rep["steps"] == w.spec["sim"]["max_steps"]
    assert rep["t"] < 10.0
    msg = driver.execute_script("return Array.from(document.querySelectorAll('div'))"
                                ".filter((e) => e.textContent.startsWith('simulation stopped'))"
                                ".map((e) => [e.textContent, getComputedStyle(e).display])")
    assert msg and "step budget" in msg[0][0] and msg[0][1] == "block"
    assert _set(driver, "g", 9.81)["status"] == "done"
    _agrees(_last(driver)[1], p, y0, [2.25], length=2.25)
    # parameters without a slider, through setParam: damping and a drive (the field's t)
    _set(driver, "damping", 0.3)
    _set(driver, "drive_frequency", 2.0)
    assert _set(driver, "drive_amplitude", 1.5)["status"] == "done"
    _agrees(_last(driver)[1], p, y0, [2.25], length=2.25, damping=0.3, drive_frequency=2.0,
            drive_amplitude=1.5)


def test_double_pendulum_through_the_mass_matrix(driver, tmp_path, double_pendulum):
    """The Lagrangian double pendulum (kind double_pendulum): M(q) q'' = F solved
    by the page's LU; the page's integration time over 10 s is measured."""
    dp = double_pendulum
    # a start whose neighbours stay close over 10 s (from 1.2, -0.4 they part: mp.solve at
    # rtol 1e-10 is itself 6.7e-7 rad from its rtol 1e-13 answer there)
    y0 = {"theta1": 0.6, "theta2": -0.3, "theta1'": 0.0, "theta2'": 0.5}
    sol = mp.solve(dp, SPAN, dp.initial_state(y0), dense_output=True)
    w = mp.live.animate(dp, sol, params={"l2": (0.2, 1.5), "g": (1.0, 20.0)}, y0=y0)
    assert w.kind == "double_pendulum" and w.spec["sim"]["nc"] == 2
    _page(driver, tmp_path, w, "double_sim")
    rep = driver.execute_script("return window.mechpyLive.simulation()")
    assert rep["status"] == "done"
    print(f"\n  double pendulum, 10 s in the page: {rep['ms']:.1f} ms, {rep['steps']} steps "
          f"({rep['rejected']} rejected), {rep['evals']} evaluations")
    _agrees(_last(driver)[1], dp, y0, [1.0, 0.5])
    _set(driver, "l2", 0.8)
    _agrees(_last(driver)[1], dp, y0, [1.0, 0.8], l2=0.8)


def _double_with_points():
    t = sp.Symbol("t")
    a, b = mp.coordinates("a b")
    l, m, g = sp.symbols("l m g", positive=True)
    x1, y1 = l * sp.sin(a), -l * sp.cos(a)
    x2, y2 = x1 + l * sp.sin(b), y1 - l * sp.cos(b)
    T = m * (x1.diff(t) ** 2 + y1.diff(t) ** 2 + x2.diff(t) ** 2 + y2.diff(t) ** 2) / 2
    V = m * g * (y1 + y2)
    scene = mp.lagrangian(T - V, [a, b], params=dict(l=0.7, m=1.3, g=9.81))
    return scene, {"bob1": (x1, y1, 0), "bob2": (x2, y2, 0)}


def test_lagrangian_points_simulated_without_a_solution(driver, tmp_path):
    """A double pendulum of mp.lagrangian drawn from points= (kind "bodies"),
    given no solution: sol=None with t=(t0, t1); its plots (the energy, a
    state, an expression) computed by the page at its own frames, before and
    after a slider's change, against mp.solve's states run through the
    scene's own energy and NumPy."""
    scene, points = _double_with_points()
    a, b = mp.coordinates("a b")
    y0 = [0.7, -0.5, 0.3, -0.2]
    w = mp.live.animate(scene, None, t=SPAN, points=points, links=[("O", "bob1"),
                        ("bob1", "bob2")], params={"l": (0.3, 1.2)}, y0=y0,
                        plots=["energy", "a", sp.sin(a - b) * sp.Symbol("l")])
    assert w.kind == "bodies" and w.spec["sim"]["nc"] == 2 and w.times[-1] == 10.0
    assert all(p["y"] is None for p in w.spec["plots"])        # the page computes them
    _page(driver, tmp_path, w, "points_sim")
    _agrees(_last(driver)[1], scene, y0, [0.7, 0.7])
    _plots_agree(driver, scene, y0, w.times)
    _set(driver, "l", 1.1)
    _agrees(_last(driver)[1], scene, y0, [1.1, 1.1], l=1.1)
    _plots_agree(driver, scene, y0, w.times, l=1.1)


def _plots_agree(driver, scene, y0, times, **changes):
    """The page's series against mp.solve (rtol 1e-13) at the frames' times: the
    energy (scene.energy, which the page's run conserves: its drift is the page's
    own error), the state a, and l sin(a - b), at the run's parameters."""
    s = scene.replace(**changes) if changes else scene
    ref = mp.solve(s, SPAN, s.initial_state(y0), rtol=1e-13, atol=1e-14, t_eval=times).y
    got = {nm: np.array(driver.execute_script(f"return window.mechpyLive.plot({nm!r}).y"))
           for nm in ("energy", "a", "l*sin(a(t) - b(t))")}
    E = s.energy(ref)
    err = {"energy": np.abs(got["energy"] - E).max() / np.abs(E).max(),
           "a": np.abs(got["a"] - ref[0]).max(),
           "expr": np.abs(got["l*sin(a(t) - b(t))"] - s.params["l"] * np.sin(ref[0] - ref[1])).max()}
    print(f"  plots {changes}: {err}")
    # measured 3.8e-12 (relative), 1.0e-12 and 2.6e-12
    assert err["energy"] < 1e-11 and err["a"] < 1e-11 and err["expr"] < 1e-11


def test_what_the_page_cannot_simulate_is_named():
    pend = mp.scenes.Pendulum()
    sol = mp.solve(pend, (0, 1), [0.1, 0.0], dense_output=True)
    a = mp.live.animate
    with pytest.raises(ValueError, match=r"params: 'mass' is not a parameter"):
        a(pend, sol, params={"mass": (0, 1)})
    with pytest.raises(ValueError, match=r"must be an interval min < max holding the system's "
                                         r"value 9.81"):
        a(pend, sol, params={"g": (1, 5)})
    with pytest.raises(ValueError, match=r"params\['g'\] must be \(min, max\)"):
        a(pend, sol, params={"g": 3.0})
    with pytest.raises(TypeError, match="params must be a dict"):
        a(pend, sol, params=[("g", (1, 20))])
    with pytest.raises(ValueError, match="y0"):
        a(pend, sol, y0=[0.1, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"sol=None: t must be the span \(t0, t1\)"):
        a(pend, None, y0=[0.1, 0.0])
    with pytest.raises(ValueError, match="sol=None: the page simulates from y0"):
        a(pend, None, t=(0, 1), params={"g": (1, 20)})
    with pytest.raises(ValueError, match="must run forward"):
        a(pend, None, t=(1, 0), y0=[0.1, 0.0])
    back = mp.solve(pend, (1, 0), [0.1, 0.0], dense_output=True)
    with pytest.raises(ValueError, match="integrates forward in time"):
        a(pend, back, y0=[0.1, 0.0])
    body = mp.scenes.RigidBody(moments=(1.0, 2.0, 3.0))
    with pytest.raises(ValueError, match="cannot simulate kind='rigid'"):
        a(body, mp.solve(body, (0, 1), [0.1, 0.2, 1.0]), y0=[0.1, 0.2, 1.0])
    # a field the page cannot evaluate (log1p: C has it, the page's printer not), named
    from sympy.codegen.cfunctions import log1p
    x, v = sp.symbols("x v")
    osc = mp.equations([v, -log1p(x)], [x, v])
    with pytest.raises(ValueError, match="cannot simulate this system: the field holds log1p"):
        a(osc, mp.solve(osc, (0, 1), [0.1, 0.0]), points={"x": (x, 0, 0)}, y0=[0.1, 0.0])
    # constraints with multipliers
    q1, q2 = mp.coordinates("q1 q2")
    L = (q1.diff() ** 2 + q2.diff() ** 2) / 2
    con = mp.lagrangian(L, [q1, q2], constraints=[q1 - q2])
    with pytest.raises(ValueError, match="cannot simulate this system: a system with "
                                         "constraints"):
        a(con, mp.solve(con, (0, 1), [0.1, 0.1, 0.0, 0.0]), points={"p": (q1, q2, 0)},
          y0=[0.1, 0.1, 0.0, 0.0])
    # (a mechanics model: tests/test_live_simulate_bodies.py)
    # a solution with actions (events): the page has none
    hop = mp.solve(pend, (0, 2), [0.5, 0.0], dense_output=True,
                   events=[mp.events.impact("theta", wall=0.0, restitution=0.5)])
    assert np.any(np.diff(hop.t) == 0)
    with pytest.raises(ValueError, match="the page simulates without events"):
        a(pend, hop, params={"g": (1, 20)})


def test_pendulum_kinds_symbolic_geometry_is_the_painters(double_pendulum, rng):
    """The registry's symbolic bobs (what a simulating page prints) equal the
    NumPy painter's (mechpy._motion.pendulum_bobs), for both kinds and for
    lengths= given as numbers."""
    from mechpy import _motion
    for system, ls, given in ((mp.scenes.Pendulum(length=1.5), [1.5], None),
                              (double_pendulum, [1.0, 0.5], None),
                              (double_pendulum, [0.3, 0.9], [0.3, 0.9])):
        g = _motion.DRAWINGS[system.drawing].painter("geometry")(system, lengths=given)
        y = rng.uniform(-3, 3, (system.dim, 7))
        f = sp.lambdify([sp.symbols(f"y0:{system.dim}")] + [sp.Symbol(k) for k in system.params],
                        sp.Matrix(g))
        got = np.stack([np.array(f(y[:, k], *system.params.values()), dtype=float)
                        for k in range(y.shape[1])])                   # (m, bobs, 3)
        xs, ys = _motion.pendulum_bobs(y, np.array(ls))
        assert np.abs(got[..., 0] - xs.T).max() < 1e-15
        assert np.abs(got[..., 1] - ys.T).max() < 1e-15 and not got[..., 2].any()
