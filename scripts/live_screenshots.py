"""Screenshots of the live views for the docs (docs/images/live-*.png).

Run from a clone after set-up: ``.venv/bin/python scripts/live_screenshots.py``.
Each page is saved, opened in headless Chromium (software WebGL2), played for
two seconds and photographed.
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


def main():
    why = _browser.available()
    if why:
        sys.exit(why)
    tmp = Path(tempfile.mkdtemp())
    d = _browser.browser()
    try:
        for name, w in views():
            _browser.open_page(d, w.save(tmp / f"{name}.html"))
            time.sleep(2.5)
            el = d.find_element("css selector", ".mechpy-live")
            el.screenshot(str(OUT / f"{name}.png"))
            print("wrote", OUT / f"{name}.png")
        for name, w, frac in motion():
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
