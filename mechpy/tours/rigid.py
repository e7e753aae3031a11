"""Tour section: the tennis-racket flip against the exact elliptic solution,
the torque-free symmetric top's precession, the geometric method's |L|, and
the heavy top between its nutation bounds, each beside solve_ivp."""
from __future__ import annotations

from pathlib import Path

import numpy as np

TITLE = "Rigid bodies: the intermediate-axis flip and the tops"
ORDER = 70


def run(out: Path) -> None:
    from scipy.integrate import solve_ivp

    from .. import rigid, solve
    from .._timing import median_time
    from ..scenes import HeavyTop, RigidBody
    from . import line

    def euler(I):
        return lambda t, w: [(I[1] - I[2]) / I[0] * w[1] * w[2],
                             (I[2] - I[0]) / I[1] * w[2] * w[0],
                             (I[0] - I[1]) / I[2] * w[0] * w[1]]

    # the flip: near the intermediate axis omega_2 reverses every T/2
    I = np.array([1.0, 2.0, 3.0])
    w0 = np.array([0.02, 1.0, 0.01])
    T = rigid.flip_period(I, w0)
    t = np.linspace(0, 2 * T, 2001)
    ex = rigid.free_rotation(I, w0, t)
    body = RigidBody(I)
    f_mp = lambda: solve(body, (0, 2 * T), w0, rtol=1e-11, atol=1e-13, t_eval=t)  # noqa: E731
    f_sp = lambda: solve_ivp(euler(I), (0, 2 * T), w0, method="DOP853", rtol=1e-11,  # noqa: E731
                             atol=1e-13, t_eval=t)
    s = f_mp()
    e_mp = np.abs(s.y.T - ex).max()
    e_sp = np.abs(f_sp().y.T - ex).max()
    w2 = s.y[1]
    cross = t[:-1][np.sign(w2[:-1]) != np.sign(w2[1:])]
    line("tennis-racket flip: period T (flip_period)", f"{T:.6f} s",
         ref=f"flips every {np.diff(cross).mean():.4f} s simulated, T/2 = {T / 2:.4f}")
    line("omega(t) over 2T, max error vs exact", f"{e_mp:.2e}", ref=f"SciPy's {e_sp:.2e}",
         t_mp=median_time(f_mp, repeat=3), t_ref=median_time(f_sp, repeat=3))
    _live_flip(out, I, w0, T, line)

    # the torque-free symmetric top: (w1, w2) turns at Omega = w3 (I3 - I1) / I1
    Is = np.array([2.0, 2.0, 3.0])
    ws = np.array([0.4, 0.0, 1.7])
    Om = ws[2] * (Is[2] - Is[0]) / Is[0]
    ts = np.linspace(0, 20, 401)
    r = solve(RigidBody(Is), (0, 20), ws, rtol=1e-12, atol=1e-12, t_eval=ts)
    ang = np.unwrap(np.arctan2(r.y[1], r.y[0]))
    Om_fit = np.polyfit(ts, ang, 1)[0]
    line("symmetric top: body-frame precession rate", f"{Om_fit:.12f} rad/s",
         ref=f"w3 (I3 - I1)/I1 = {Om:.12f}", err=abs(Om_fit - Om))

    # the geometric method keeps |L| to round-off where RK4 drifts
    n, h = 10**6, 0.01
    te = np.linspace(0, n * h, 11)
    for m in ("rigid:split", "rk4"):
        g = lambda m=m: solve(body, (0, n * h), w0, method=m, h=h, t_eval=te)  # noqa: E731
        L = np.linalg.norm(I[:, None] * g().y, axis=0)
        line(f"{m}, 10^6 steps: |L| relative drift", f"{np.abs(L / L[0] - 1).max():.1e}",
             t_mp=median_time(g, repeat=1))

    # the heavy top between its nutation bounds
    I1, I3, M, gr, ll = 0.5, 0.2, 1.0, 9.81, 0.1
    top = HeavyTop(I1, I3, M, gr, ll)
    y0 = [0.0, 0.5, 0.0, 0.8, 0.3, 40.0]
    lo, hi = rigid.nutation_bounds(I1, I3, M, gr, ll, 0.5, 0.3, 0.8, 40.0)
    tt = np.linspace(0, 6, 6001)

    def top_py(t, y):  # the same equations as a SciPy user writes them
        s, c = np.sin(y[1]), np.cos(y[1])
        pd, td, w3 = y[3], y[4], y[5] + y[3] * c
        phdd = td * (I3 / I1 * w3 - 2.0 * pd * c) / s
        thdd = pd * pd * s * c - I3 / I1 * w3 * pd * s + M * gr * ll / I1 * s
        return [pd, td, y[5], phdd, thdd, -phdd * c + pd * td * s]

    f_mp = lambda: solve(top, (0, 6), y0, rtol=1e-10, atol=1e-12, t_eval=tt)  # noqa: E731
    f_sp = lambda: solve_ivp(top_py, (0, 6), y0, method="DOP853", rtol=1e-10,  # noqa: E731
                             atol=1e-12, t_eval=tt)
    r = f_mp()
    th = r.y[1]
    E = top.energy(r.y)
    line("heavy top theta range (rad)", f"[{th.min():.6f}, {th.max():.6f}]",
         ref=f"nutation_bounds [{lo:.6f}, {hi:.6f}]",
         err=max(abs(th.min() - lo), abs(th.max() - hi)),
         t_mp=median_time(f_mp, repeat=3), t_ref=median_time(f_sp, repeat=1))
    line("heavy top energy, p_phi, p_psi relative drift",
         f"{np.abs(E / E[0] - 1).max():.1e}, "
         f"{np.abs(top.p_phi(r.y) / top.p_phi(r.y)[0] - 1).max():.1e}, "
         f"{np.abs(top.p_psi(r.y) / top.p_psi(r.y)[0] - 1).max():.1e}")


def _live_flip(out: Path, I, w0, T, line) -> None:
    """The flip in 3D in the browser (mp.live.animate), saved as one offline page;
    the page's box turns over while the angular momentum stays put."""
    try:
        from .. import live, solve
        from ..scenes import RigidBody
        body = RigidBody(I, orientation=True)
        s = solve(body, (0, 2 * T), body.initial_state(w0), dense_output=True, rtol=1e-11,
                  atol=1e-13)
        w = live.animate(body, s, duration=12)
    except ImportError:  # pragma: no cover - the live extra is missing
        line("tennis-racket flip in 3D (mp.live.animate)", "skipped: needs anywidget")
        return
    path = w.save(out / "live_tennis_racket.html", title="mechpy: the tennis-racket flip")
    line("tennis-racket flip in 3D (mp.live.animate)",
         f"{w.times.size} frames, a {path.stat().st_size / 1e6:.2f} MB offline page: {path}")
