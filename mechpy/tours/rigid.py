"""Tour section: the tennis-racket flip against the exact elliptic solution,
and the heavy top between its nutation bounds."""
from __future__ import annotations

from pathlib import Path

import numpy as np

TITLE = "Rigid bodies: the intermediate-axis flip and the heavy top"
ORDER = 70


def run(out: Path) -> None:
    from scipy.integrate import solve_ivp

    from .. import rigid, solve
    from .._timing import median_time
    from ..scenes import HeavyTop, RigidBody
    from . import line

    I = np.array([1.0, 2.0, 3.0])
    w0 = np.array([0.02, 1.0, 0.01])
    T = rigid.flip_period(I, w0)
    t = np.linspace(0, 2 * T, 2001)
    ex = rigid.free_rotation(I, w0, t)
    body = RigidBody(I)
    f_mp = lambda: solve(body, (0, 2 * T), w0, rtol=1e-11, atol=1e-13, t_eval=t)  # noqa: E731
    eul = lambda s, w: [(I[1] - I[2]) / I[0] * w[1] * w[2], (I[2] - I[0]) / I[1] * w[2] * w[0],  # noqa: E731
                        (I[0] - I[1]) / I[2] * w[0] * w[1]]
    f_sp = lambda: solve_ivp(eul, (0, 2 * T), w0, method="DOP853", rtol=1e-11,  # noqa: E731
                             atol=1e-13, t_eval=t)
    e_mp = np.abs(f_mp().y.T - ex).max()
    e_sp = np.abs(f_sp().y.T - ex).max()
    line("flip period T (s)", f"{T:.6f}")
    line("omega(t) over 2T vs exact, max error", f"{e_mp:.2e}", err=e_sp, ref_name="SciPy",
         t_mp=median_time(f_mp, repeat=3), t_ref=median_time(f_sp, repeat=3))
    s = solve(body, (0, 1e4), w0, method="rigid:split", h=0.01, t_eval=np.linspace(0, 1e4, 11))
    L = np.linalg.norm(I[:, None] * s.y, axis=0)
    line("rigid:split, 10^6 steps: |L| relative drift", f"{np.abs(L / L[0] - 1).max():.1e}")
    top = HeavyTop(0.5, 0.2, 1.0, 9.81, 0.1)
    y0 = [0.0, 0.5, 0.0, 0.8, 0.3, 40.0]
    lo, hi = rigid.nutation_bounds(0.5, 0.2, 1.0, 9.81, 0.1, 0.5, 0.3, 0.8, 40.0)
    r = solve(top, (0, 6), y0, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 6, 6001))
    line("heavy top theta range (rad)", f"[{r.y[1].min():.6f}, {r.y[1].max():.6f}]",
         ref=f"[{lo:.6f}, {hi:.6f}]", err=max(abs(r.y[1].min() - lo), abs(r.y[1].max() - hi)),
         ref_name="bounds")
