"""Tour: the Van der Pol limit cycle and its phase portrait."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

import mechpy as mp
from mechpy._timing import median_time
from mechpy.benches.phase import _starts, _vdp
from mechpy.tours import line

TITLE = "Phase space: Van der Pol limit cycle, pendulum fixed points, chaos"
ORDER = 30


def run(out: Path) -> None:
    vdp = mp.scenes.VanDerPol(1.0)
    ref = 6.6632868593231301897
    T, A = mp.phase.limit_cycle(vdp, [0.5, 0.0], tol=1e-10)
    Ts, _ = _scipy_cycle()
    t_mp = median_time(lambda: mp.phase.limit_cycle(vdp, [0.5, 0.0], tol=1e-10), repeat=3)
    t_sp = median_time(_scipy_cycle, repeat=3)
    line("Van der Pol mu=1 period", f"{T:.12f}", ref=f"{ref:.10f}", err=abs(T - ref),
         t_mp=t_mp, t_ref=t_sp)
    line("  same with solve_ivp DOP853 + events", f"{Ts:.12f}", err=abs(Ts - ref))
    line("Van der Pol mu=1 amplitude", f"{A:.8f}", ref="2.00861986", err=abs(A - 2.00861986))
    fps = mp.phase.fixed_points(mp.scenes.Pendulum(), [(-7, 7), (-3, 3)])
    line("pendulum fixed points", ", ".join(f"{p.x[0]:+.4f} {p.kind}" for p in fps))
    X, Y = np.meshgrid(np.linspace(-3, 3, 200), np.linspace(-3, 3, 200))
    t_mp = median_time(lambda: mp.phase.vector_field(vdp, X, Y))
    t_np = median_time(lambda: [_vdp(0.0, np.array([x, y])) for x, y in
                                zip(X.ravel()[:4000], Y.ravel()[:4000])]) * 10
    line("200x200 Van der Pol field", "C", t_mp=t_mp, t_ref=t_np, ref_name="Python loop")
    k, sub = 2500, 5
    y0s, te = _starts(k), np.linspace(0.0, 20.0, 201)
    t_mp = median_time(lambda: mp.solve_many(vdp, (0, 20), y0s, t_eval=te, rtol=1e-8,
                                             atol=1e-10), repeat=3)
    idx = np.linspace(0, k - 1, sub).astype(int)
    t_sp = median_time(lambda: [solve_ivp(_vdp, (0, 20), y0s[i], method="DOP853", rtol=1e-8,
                                          atol=1e-10, t_eval=te) for i in idx],
                       repeat=1, warmup=0) * (k / sub)
    line(f"{k} Van der Pol trajectories (201 samples)", "solve_many", t_mp=t_mp, t_ref=t_sp,
         ref_name=f"solve_ivp loop ({sub} timed, scaled)")
    sc = mp.scenes.Pendulum(g=1, length=1, damping=0.5, drive_amplitude=1.5,
                            drive_frequency=2 / 3)
    lam = mp.phase.lyapunov(sc, [0.2, 0.0], 200.0, transient=50.0, method="neighbours")
    line("driven pendulum Lyapunov exponent (A=1.5)", f"{lam:.3f} > 0: chaos")
    t_mp = median_time(lambda: mp.solve(sc, (0, 200), [0.2, 0.0], rtol=1e-10), repeat=3)
    t_sp = median_time(lambda: solve_ivp(lambda t, y: [y[1], -np.sin(y[0]) - 0.5 * y[1]
                                                       + 1.5 * np.cos(2 / 3 * t)],
                                         (0, 200), [0.2, 0.0], method="DOP853", rtol=1e-10),
                       repeat=3)
    line("driven pendulum, t = 200", "dop853", t_mp=t_mp, t_ref=t_sp)
    try:
        import time
        t0 = time.perf_counter()
        w = mp.live.phase_portrait(vdp, (-4, 4), (-6, 6), params={"mu": (0.0, 4.0)})
        page = w.save(out / "vanderpol_live.html")
        dt = time.perf_counter() - t0
        cyc = w.spec["overlays"]["sets"][0]
        line("live phase portrait (10^4 particles, GPU)",
             f"{page} ({page.stat().st_size / 1e6:.2f} MB, {dt:.1f} s)",
             ref="cycle amplitude 2.0086198609", err=abs(cyc["amplitude"] - 2.0086198609))
        line("  open it in a browser", "drag, scroll, click; the mu slider works offline")
    except ImportError as e:  # pragma: no cover - the live extra is missing
        line("live phase portrait", f"not written: {e}")
    try:
        import matplotlib
        matplotlib.use("Agg")
        ax = mp.plot.phase_portrait(vdp, (-3, 3), (-3, 3), trajectories=[(0.5, 0.0)])
        ax.figure.savefig(out / "vanderpol_portrait.png", dpi=100)
    except ImportError:  # pragma: no cover
        pass
    # the tangent flow: the cycle's Floquet multipliers by shooting with the exact monodromy
    Tf, mult = mp.phase.floquet(vdp, [2.0, 0.0])
    line("Van der Pol Floquet multipliers", f"1 and {mult[1].real:.6e} (T = {Tf:.12f})",
         ref=f"T {ref:.10f}", err=abs(Tf - ref))


def _scipy_cycle(t_end=60.0):
    """The mu = 1 period and amplitude from solve_ivp: successive maxima of x."""
    def xdot(t, y):
        return y[1]
    xdot.direction = -1
    s = solve_ivp(_vdp, (0, t_end), [0.5, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                  events=xdot)
    return float(np.diff(s.t_events[0][-2:])[0]), float(s.y_events[0][-1][0])
