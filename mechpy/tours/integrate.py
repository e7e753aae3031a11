"""Tour: the pendulum and the Van der Pol oscillator, beside SciPy."""
from pathlib import Path

import numpy as np

import mechpy as mp
from mechpy._timing import median_time
from mechpy.tours import line

TITLE = "Integrators: the pendulum and the Van der Pol oscillator"
ORDER = 10


def _pendulum_exact(theta0, t, g=9.81, length=1.0):
    from scipy.special import ellipj, ellipk
    k = np.sin(theta0 / 2)
    sn, cn, _, _ = ellipj(ellipk(k * k) - np.sqrt(g / length) * t, k * k)
    return np.array([2 * np.arcsin(k * sn), -2 * k * np.sqrt(g / length) * cn])


def run(out: Path) -> None:
    from scipy.integrate import solve_ivp

    p = mp.scenes.Pendulum()
    theta0, T = 2.5, 10.0

    def up(t, y):
        return y[0]
    up.direction = 1
    s = mp.solve(p, (0, 30), [theta0, 0.0], events=up, rtol=1e-12, atol=1e-14)
    period = np.diff(s.t_events[0]).mean()
    exact_period = p.period(theta0)
    line(f"pendulum period, theta0 = {theta0} rad", f"{period:.12f} s",
         ref=f"{exact_period:.12f} s (4 sqrt(L/g) K)", err=abs(period - exact_period))

    exact = _pendulum_exact(theta0, T)[:, None][:, 0]

    def f(t, y):
        return [y[1], -9.81 * np.sin(y[0])]
    ours = mp.solve(p, (0, T), [theta0, 0.0], rtol=1e-10, atol=1e-12)
    ref = solve_ivp(f, (0, T), [theta0, 0.0], method="DOP853", rtol=1e-10, atol=1e-12)
    t_mp = median_time(lambda: mp.solve(p, (0, T), [theta0, 0.0], rtol=1e-10, atol=1e-12))
    t_sp = median_time(lambda: solve_ivp(f, (0, T), [theta0, 0.0], method="DOP853", rtol=1e-10,
                                         atol=1e-12), repeat=3)
    e_mp = np.max(np.abs(ours.y[:, -1] - exact))
    e_sp = np.max(np.abs(ref.y[:, -1] - exact))
    line("pendulum y(10 s), dop853 C scene, rtol 1e-10", f"err {e_mp:.1e} nfev {ours.nfev}",
         t_mp=t_mp, t_ref=t_sp, ref_name=f"solve_ivp DOP853 (err {e_sp:.1e})")
    E = p.energy(ours.y)
    line("pendulum energy drift (J/kg)", f"{np.max(np.abs(E - E[0])):.1e}")

    v = mp.scenes.VanDerPol(mu=1.0)
    s = mp.solve(v, (0, 100), [2.0, 0.0], events=up, rtol=1e-12, atol=1e-12)
    per = np.diff(s.t_events[0])[-1]
    line("Van der Pol limit-cycle period, mu = 1", f"{per:.10f}", ref="6.6632868593",
         err=abs(per - 6.6632868593231301))

    def g(t, y):
        return [y[1], (1 - y[0] ** 2) * y[1] - y[0]]
    t_mp = median_time(lambda: mp.solve(v, (0, 100), [2.0, 0.0], rtol=1e-10, atol=1e-12))
    t_sp = median_time(lambda: solve_ivp(g, (0, 100), [2.0, 0.0], method="DOP853", rtol=1e-10,
                                         atol=1e-12), repeat=3)
    line("Van der Pol to t = 100, rtol 1e-10", "dop853 C scene", t_mp=t_mp, t_ref=t_sp,
         ref_name="solve_ivp DOP853")

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        line("phase portraits", "skipped (matplotlib not installed)")
        return
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    mp.plot.phase_portrait(p, (-2 * np.pi, 2 * np.pi), (-8, 8), ax=axes[0],
                           trajectories=[[1.0, 0.0], [2.5, 0.0], [-2 * np.pi, 6.5]], t_max=6,
                           labels=("theta [rad]", "theta_dot [rad/s]"))
    axes[0].set_title("pendulum")
    mp.plot.phase_portrait(v, (-3, 3), (-3, 3), ax=axes[1],
                           trajectories=[[0.1, 0.0], [3.0, 3.0]], t_max=30)
    axes[1].set_title("Van der Pol, mu = 1")
    fig.tight_layout()
    path = out / "phase_portraits.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    line("phase portraits written", str(path))
