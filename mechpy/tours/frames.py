"""Tour: the Foucault pendulum and the Coriolis deflection."""
from __future__ import annotations

from pathlib import Path

import numpy as np

import mechpy as mp
from mechpy._timing import median_time
from mechpy.tours import line

TITLE = "Rotating frames: Foucault pendulum at Paris, eastward deflection"
ORDER = 35


def run(out: Path) -> None:
    lat = 48.857
    T = mp.frames.foucault_period(lat)
    line("Foucault period at Paris (h)", f"{T / 3600:.3f}", ref="31.78")
    sc = mp.scenes.Foucault(lat, 67.0)
    T0 = 2 * np.pi * np.sqrt(67.0 / 9.81)
    t_end = 6 * 3600.0
    te = np.linspace(t_end - 2 * T0, t_end, 400)

    def sim():
        return mp.solve(sc, (0, t_end), [1.0, 0, 0, 0], rtol=1e-11, atol=1e-12, t_eval=te)
    s = sim()
    x, y = s.y[0], s.y[1]
    angle = 0.5 * np.arctan2(2 * np.mean(x * y), np.mean(x * x) - np.mean(y * y))
    expect = -sc.precession_rate * (t_end - T0)
    line("plane of swing after 6 h (rad, clockwise <0)", f"{angle:.6f}", ref=f"{expect:.6f}",
         err=abs(angle - expect) / abs(expect), t_mp=median_time(sim, repeat=3))

    # the precession period: the plane of swing in windows of two swings over 33 h, fitted
    centres = np.linspace(T0, 33 * 3600.0, 60)
    tw = (centres[:, None] + np.linspace(-T0, T0, 80)[None, :]).ravel()

    def long_run():
        return mp.solve(sc, (0, tw[-1]), [1.0, 0, 0, 0], rtol=1e-11, atol=1e-12, t_eval=tw)
    s = long_run()
    x, y = s.y[0].reshape(60, 80), s.y[1].reshape(60, 80)
    plane = np.unwrap(np.arctan2(2 * (x * y).mean(1), (x * x).mean(1) - (y * y).mean(1))) / 2
    rate = np.polyfit(centres, plane, 1)[0]
    T_meas = 2 * np.pi / abs(rate)
    line("precession period over 33 h (h)", f"{T_meas / 3600:.5f} "
         f"{'clockwise' if rate < 0 else 'anticlockwise'}", ref=f"{T / 3600:.5f}",
         err=abs(T_meas - T) / T, t_mp=median_time(long_run, repeat=3))
    land, _ = mp.frames.drop(100.0, lat)
    d = mp.frames.eastward_deflection(100.0, lat)
    line("100 m drop eastward deflection (mm)", f"{land[0] * 1e3:.5f}", ref=f"{d * 1e3:.5f}",
         err=abs(land[0] - d) / d)
