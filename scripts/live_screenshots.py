"""Screenshots of the live views for the docs (docs/images/live-*.png).

Run from a clone after set-up: ``.venv/bin/python scripts/live_screenshots.py
[name ...]`` (the names: only those, e.g. ``live-bicycle``).  Each page is
saved, opened in headless Chromium (software WebGL2), played for two seconds
(a 3D view: shown at a frame) and photographed.
"""
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import sympy as sp

import mechpy as mp
from mechpy.live import _browser

OUT = Path(__file__).resolve().parent.parent / "docs" / "images"


def views():
    yield "live-vanderpol", mp.live.phase_portrait(
        mp.scenes.VanDerPol(mu=1.0), (-4, 4), (-6, 6), params={"mu": (0.0, 4.0)})
    yield "live-pendulum", mp.live.phase_portrait(
        mp.scenes.Pendulum(g=1.0, damping=0.15), (-2 * np.pi, 2 * np.pi), (-3, 3),
        params={"g": (0.2, 4.0), "damping": (0.0, 1.0)})
    th1, th2 = mp.coordinates("th1 th2")
    w1, w2 = th1.diff(), th2.diff()
    L = w1**2 + w2**2 / 2 + w1 * w2 * sp.cos(th1 - th2) + 2 * sp.cos(th1) + sp.cos(th2)
    yield "live-double-pendulum", mp.live.phase_portrait(
        mp.lagrangian(L, [th1, th2]), (-3, 3), (-3, 3), particles=20_000,
        hidden=[(0, 0), (0, 0), (-0.5, 0.5), (-0.5, 0.5)], overlays=False)


def motion():
    body = mp.scenes.RigidBody([1.0, 2.0, 3.0], orientation=True)
    w0 = [0.02, 1.0, 0.01]
    T = mp.rigid.flip_period(body.moments, w0)
    sol = mp.solve(body, (0, 2 * T), body.initial_state(w0), dense_output=True, rtol=1e-11,
                   atol=1e-12)
    yield "live-rigid", mp.live.animate(body, sol, duration=12), 0.3
    top = mp.scenes.HeavyTop(I1=0.5, I3=0.2, mass=1.0, g=9.81, l=0.1)
    sol = mp.solve(top, (0, 4), [0.0, 0.8, 0.0, 0.0, 0.0, 15.0], rtol=1e-10, dense_output=True)
    yield "live-top", mp.live.animate(top, sol), 0.9
    fou = mp.scenes.Foucault(latitude=48.85, length=67.0, omega=7.2921159e-5 * 400)
    sol = mp.solve(fou, (0, 600), [1.0, 0.0, 0.0, 0.0], rtol=1e-10, dense_output=True)
    yield "live-foucault", mp.live.animate(fou, sol, duration=20), 0.95
    yield from own_systems()


def own_systems():
    """The pages of docs/guide/live.md's own systems and of the notebooks, with plots."""
    from mechpy.symbolic.models import rolling_disc, whipple_bicycle, whipple_state
    kane, p = whipple_bicycle()
    bike = mp.mechanics(kane, p)
    sol = mp.solve(bike, (0, 5), bike.project(whipple_state(4.6, roll_rate=0.5)),
                   dense_output=True, rtol=1e-10)
    yield "live-bicycle", mp.live.animate(
        bike, sol, fps=20, shapes={"R": dict(kind="torus", size=p["rR"]),
                                   "F": dict(kind="torus", size=p["rF"])},
        plots=["q2", "q5"]), 0.1
    kane, p = rolling_disc()
    disc = mp.mechanics(kane, p)
    y0 = disc.project([0.0, 0.2, 0.0, 0.0, 0.0, 0.3, 0.0, 4.0, 0.0, 0.0])
    sol = mp.solve(disc, (0, 5), y0, dense_output=True, rtol=1e-10, atol=1e-12)
    yield "live-rolling-disc", mp.live.animate(
        disc, sol, fps=20, shapes={"disc": dict(kind="cylinder", size=(0.5, 0.02))},
        plots=["q2", "energy"]), 0.05
    sys.path.insert(0, str(OUT.parent.parent / "tests"))
    from test_live_bodies import _triple_pendulum      # the tests' and the guide's (l 0.7 m)
    triple, points = _triple_pendulum()
    sol = mp.solve(triple, (0, 10), [1.2, 0.4, -0.3, 0, 0, 0], dense_output=True, rtol=1e-10)
    a, c = sp.symbols("a c")
    yield "live-triple-pendulum", mp.live.animate(
        triple, sol, points=points, links=[("O", "bob1"), ("bob1", "bob2"), ("bob2", "bob3")],
        plots=["energy", "a", sp.sin(a - c)]), 0.03
    # the notebook's double pendulum (unit masses and rods), its Lagrangian from its points
    th1, th2 = mp.coordinates("theta1 theta2")
    l1, l2, g = sp.symbols("l1 l2 g")
    bob1 = (l1 * sp.sin(th1), -l1 * sp.cos(th1), 0)
    bob2 = (bob1[0] + l2 * sp.sin(th2), bob1[1] - l2 * sp.cos(th2), 0)
    t = sp.Symbol("t")
    L = sum((b[0].diff(t) ** 2 + b[1].diff(t) ** 2) / 2 - g * b[1] for b in (bob1, bob2))
    double = mp.lagrangian(L, [th1, th2], params=dict(l1=1.0, l2=1.0, g=9.81))
    sol = mp.solve(double, (0, 8), [2.0, 2.5, 0.0, 0.0], dense_output=True, rtol=1e-10)
    yield "live-own-double-pendulum", mp.live.animate(
        double, sol, points={"bob 1": bob1, "bob 2": bob2},
        links=[("O", "bob 1"), ("bob 1", "bob 2")],
        plots=["energy", "theta1", sp.sin(th1 - th2)]), 0.06


def main():
    why = _browser.available()
    if why:
        sys.exit(why)
    only = set(sys.argv[1:])
    tmp = Path(tempfile.mkdtemp())
    d = _browser.browser()
    try:
        for name, w in views() if not only else ():
            _browser.open_page(d, w.save(tmp / f"{name}.html"))
            time.sleep(2.5)
            el = d.find_element("css selector", ".mechpy-live")
            el.screenshot(str(OUT / f"{name}.png"))
            print("wrote", OUT / f"{name}.png")
        d.set_window_size(1000, 1200)          # a 3D view with plots is taller than 800 px
        for name, w, frac in motion():
            if only and name not in only:
                continue
            _browser.open_page(d, w.save(tmp / f"{name}.html"))
            n = d.execute_script("return window.mechpyLive.frames()")
            d.execute_script(f"window.mechpyLive.frame({int(frac * (n - 1))})")
            time.sleep(1.0)
            d.find_element("css selector", ".mechpy-live").screenshot(str(OUT / f"{name}.png"))
            print("wrote", OUT / f"{name}.png")
    finally:
        d.quit()


if __name__ == "__main__":
    main()
