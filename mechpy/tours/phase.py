"""Tour: the Van der Pol limit cycle and its phase portrait."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

import mechpy as mp
from mechpy._timing import median_time
from mechpy.tours import line

TITLE = "Phase space: Van der Pol limit cycle, pendulum fixed points, chaos"
ORDER = 30


def run(out: Path) -> None:
    vdp = mp.scenes.VanDerPol(1.0)
    T, A = mp.phase.limit_cycle(vdp, [0.5, 0.0], tol=1e-10)
    ref = 6.6632868593231301897
    line("Van der Pol mu=1 period", f"{T:.12f}", ref=f"{ref:.10f}", err=abs(T - ref))
    line("Van der Pol mu=1 amplitude", f"{A:.8f}", ref="2.00861986", err=abs(A - 2.00861986))
    fps = mp.phase.fixed_points(mp.scenes.Pendulum(), [(-7, 7), (-3, 3)])
    line("pendulum fixed points", ", ".join(f"{p.x[0]:+.4f} {p.kind}" for p in fps))
    X, Y = np.meshgrid(np.linspace(-3, 3, 200), np.linspace(-3, 3, 200))
    t_mp = median_time(lambda: mp.phase.vector_field(vdp, X, Y))
    t_np = median_time(lambda: [vdp_py(0.0, np.array([x, y])) for x, y in
                                zip(X.ravel()[:4000], Y.ravel()[:4000])]) * 10
    line("200x200 Van der Pol field", "C", t_mp=t_mp, t_ref=t_np, ref_name="Python loop")
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
        import matplotlib
        matplotlib.use("Agg")
        ax = mp.plot.phase_portrait(vdp, (-3, 3), (-3, 3), trajectories=[(0.5, 0.0)])
        ax.figure.savefig(out / "vanderpol_portrait.png", dpi=100)
    except ImportError:  # pragma: no cover
        pass


def vdp_py(t, y, mu=1.0):
    return [y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]]
