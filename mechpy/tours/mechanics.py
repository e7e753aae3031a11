"""Tour section: a model as SymPy's mechanics writes it, the Carvallo-Whipple
bicycle (Kane's method, a holonomic and three nonholonomic constraints),
compiled by ``mp.mechanics``: its build time, the benchmark's eigenvalues and
self-stability speeds (Meijaard et al. 2007), and a nonlinear run that stays
on its constraints, timed beside lambdify + solve_ivp."""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

TITLE = "Models as mechanics writes them: the Whipple bicycle by Kane's method"
ORDER = 91


def run(out: Path) -> None:
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    import mechpy as mp
    from mechpy._timing import median_time
    from mechpy.benches.mechanics import _EmptyCache, _lambdified
    from mechpy.symbolic.models import whipple_bicycle, whipple_state

    from . import line

    t0 = time.perf_counter()
    kane, params = whipple_bicycle()
    t1 = time.perf_counter()
    with _EmptyCache():
        bike = mp.mechanics(kane, params)
    t2 = time.perf_counter()
    line("bicycle: mp.mechanics, first build", f"{t2 - t1:.1f} s",
         ref=f"SymPy's kanes_equations {t1 - t0:.1f} s")
    ls = [1, 2, 3, 5]

    def eig(v):
        return np.linalg.eigvals(bike.linearize(whipple_state(v))[0][np.ix_(ls, ls)])
    ev = np.sort_complex(eig(5.0))
    want = np.sort_complex(np.array([-14.07838969279822, -0.32286642900409,
                                     -0.77534188219585 - 4.46486771378823j,
                                     -0.77534188219585 + 4.46486771378823j]))
    line("eigenvalues at 5 m/s (weave)", f"{ev[1].real:.6f} +- {abs(ev[1].imag):.6f}i",
         ref="Meijaard et al. 2007, Table 2", err=float(np.abs(ev - want).max()))
    weave = brentq(lambda v: eig(v).real.max(), 4, 5, xtol=1e-12)
    capsize = brentq(lambda v: eig(v).real.max(), 5.5, 7, xtol=1e-12)
    line("weave and capsize speeds (m/s)", f"{weave:.8f}, {capsize:.8f}",
         ref="4.29238254, 6.02426202",
         err=max(abs(weave - 4.29238253634111), abs(capsize - 6.02426201538837)))
    y0 = bike.project(np.array(whipple_state(4.6, roll=0.1, steer=0.05, roll_rate=0.3)))
    s = mp.solve(bike, (0, 10), y0)
    res = np.abs(bike.constraint_residual(s.y)).max()
    line("nonlinear run, 10 s at 4.6 m/s: residuals", f"{res:.1e}",
         ref=f"energy drift {np.ptp(bike.energy(s.y)):.1e} J")
    f = _lambdified(kane, params)
    ref = mp.solve(bike, (0, 5), y0, rtol=1e-13, atol=1e-14).y[:, -1]
    f_mp = lambda: mp.solve(bike, (0, 5), y0, rtol=1e-9, atol=1e-11)  # noqa: E731
    f_sp = lambda: solve_ivp(f, (0, 5), y0, method="DOP853", rtol=1e-9, atol=1e-11)  # noqa: E731
    line("dop853 rtol 1e-9: error at t = 5", f"{np.abs(f_mp().y[:, -1] - ref).max():.1e}",
         ref=f"lambdify + solve_ivp {np.abs(f_sp().y[:, -1] - ref).max():.1e}",
         t_mp=median_time(f_mp, repeat=5), t_ref=median_time(f_sp, repeat=3),
         ref_name="lambdify + solve_ivp")
    _live_bicycle(out, bike, params, y0, line)


def _live_bicycle(out: Path, bike, params, y0, line) -> None:
    """The bicycle in 3D as a page that simulates (mp.live.animate with params=
    and y0=): the page integrates the printed model itself, so its sliders for
    g and the rear frame's mass re-run the ride offline, with the roll and the
    steer plotted under it."""
    import time

    try:
        from .. import live
    except ImportError:  # pragma: no cover - the live extra is missing
        line("bicycle in 3D, simulated in the page", "skipped: needs anywidget")
        return
    t0 = time.perf_counter()
    w = live.animate(bike, None, t=(0, 10), y0=y0, params={"g": (1.0, 20.0),
                                                             "mB": (40.0, 140.0)},
                     shapes={"R": dict(kind="torus", size=params["rR"]),
                             "F": dict(kind="torus", size=params["rF"])},
                     plots=["q2", "q5"])
    path = w.save(out / "live_bicycle.html", title="mechpy: the Whipple bicycle, simulated")
    line("bicycle in 3D, simulated in the page",
         f"{w.times.size} frames, sliders g and mB, a {path.stat().st_size / 1e6:.2f} MB "
         f"offline page ({time.perf_counter() - t0:.1f} s): {path}")
