"""Bench: the live phase portrait in headless Chromium (software WebGL2) beside
matplotlib's pre-rendered ``animate_field``.

Van der Pol (mu = 1) on (-4, 4) x (-6, 6), dt = 0.01.  For 10^3, 10^4 and
10^5 particles (quick: the first two): the frames per second while playing
(one RK4 step per particle per frame, trails faded and drawn), the particle
steps per second of the update alone (``step(200)`` timed to the read-back of
the states), and the error of the float32 states after 100 steps against a
float64 RK4 of the same dt from the same seeds (median and maximum relative,
over 1000 particles).  Then the saved page's size and load time, and
``mp.plot.animate_field`` rendering the same particle count into a JavaScript
animation (its time per frame and the size of the HTML).

The machine has no GPU: SwiftShader runs WebGL on the CPU.  A laptop GPU is
two to three orders of magnitude faster (fieldplay's mark: 10^6 particles at
60 fps); the page's work per particle is the same.
"""
from __future__ import annotations

import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import mechpy as mp

TITLE = "Live phase portrait in the browser (software WebGL2) beside pre-rendered frames"
ORDER = 95


def _vdp(t, y):
    return np.stack([y[:, 1], (1 - y[:, 0] ** 2) * y[:, 1] - y[:, 0]], axis=1)


def _rk4(y, h, n):
    for _ in range(n):
        k1 = _vdp(0, y)
        k2 = _vdp(0, y + h / 2 * k1)
        k3 = _vdp(0, y + h / 2 * k2)
        k4 = _vdp(0, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y


def run(quick: bool):
    from mechpy.live import _browser
    why = _browser.available()
    if why:
        return [dict(problem="live phase portrait", impl="mechpy.live", time=float("nan"),
                     error=float("nan"), note=f"not measured: {why}")]
    vdp = mp.scenes.VanDerPol(mu=1.0)
    rows = []
    tmp = Path(tempfile.mkdtemp(prefix="mechpy-bench-live-"))
    d = _browser.browser()
    try:
        for n in (1_000, 10_000) if quick else (1_000, 10_000, 100_000):
            w = mp.live.phase_portrait(vdp, (-4, 4), (-6, 6), particles=n, play=False,
                                       overlays=False)
            path = w.save(tmp / f"vdp{n}.html")
            t0 = time.perf_counter()
            _browser.open_page(d, path)
            t_load = time.perf_counter() - t0
            seeds = np.array(d.execute_script(
                "return Array.from(window.mechpyLive.seeds().subarray(0, 2000))")).reshape(-1, 2)
            d.execute_script("window.mechpyLive.step(100)")
            got = np.array(d.execute_script(
                "return Array.from(window.mechpyLive.particles().subarray(0, 2000))")).reshape(-1, 2)
            ref = _rk4(seeds.astype(float), 0.01, 100)
            rel = (np.abs(got - ref) / np.maximum(1.0, np.abs(ref))).max(axis=1)
            # the update alone: 200 steps, finished when the states are read back
            t_upd = d.execute_script("""
                const a = window.mechpyLive, t0 = performance.now();
                a.step(200); a.particles();
                return (performance.now() - t0) / 1000;""")
            d.execute_script("window.mechpyLive.play()")
            time.sleep(3.0)
            fps = float(d.execute_script("return window.mechpyLive.fps()"))
            d.execute_script("window.mechpyLive.pause()")
            name = f"Van der Pol, {n} particles, software WebGL2 (headless Chromium)"
            rows.append(dict(problem=name, impl="mechpy.live phase_portrait (RK4 in a shader)",
                             time=1.0 / fps if fps > 0 else float("nan"),
                             error=float(np.median(rel)), n=n,
                             note=(f"{fps:.1f} fps while playing; {n * 200 / t_upd:.3g} "
                                   f"particle steps/s in the update; max error after 100 "
                                   f"steps {rel.max():.1e} (float32 against float64 RK4); "
                                   f"page {path.stat().st_size / 1e6:.2f} MB, loads in "
                                   f"{t_load:.2f} s")))
            if n <= 10_000:
                frames = 10 if quick else 30
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", DeprecationWarning)
                    import matplotlib
                    matplotlib.use("Agg")
                    import matplotlib.pyplot as plt
                    t0 = time.perf_counter()
                    anim = mp.plot.animate_field(vdp, (-4, 4), (-6, 6), particles=n,
                                                 frames=frames, dt=0.01, trail=8)
                    html = anim.to_jshtml()
                    t_mpl = time.perf_counter() - t0
                    plt.close("all")
                rows.append(dict(problem=name, impl="mp.plot.animate_field (pre-rendered frames)",
                                 time=t_mpl / frames, error=float("nan"), n=n,
                                 note=(f"{frames} frames rendered in {t_mpl:.1f} s; HTML "
                                       f"{len(html) / 1e6:.1f} MB ({len(html) / frames / 1e3:.0f} "
                                       "kB a frame); no slider without a kernel")))
    finally:
        d.quit()
    return rows
