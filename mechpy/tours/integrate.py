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


def _brusselator(N):
    """Hairer & Wanner's 1-D Brusselator with N grid points, the states (u_1,
    v_1, u_2, ...): f and its Jacobian's pattern (band 2 + 2)."""
    c = (N + 1) ** 2 / 50.0

    def f(t, y):
        u, v = y[0::2], y[1::2]
        up, vp = np.concatenate(([1.0], u, [1.0])), np.concatenate(([3.0], v, [3.0]))
        out = np.empty_like(y)
        out[0::2] = 1 + u * u * v - 4 * u + c * (up[:-2] - 2 * u + up[2:])
        out[1::2] = 3 * u - u * u * v + c * (vp[:-2] - 2 * v + vp[2:])
        return out
    i = np.arange(2 * N)
    pattern = np.abs(i[:, None] - i[None, :]) <= 2
    x = np.arange(1, N + 1) / (N + 1)
    y0 = np.empty(2 * N)
    y0[0::2], y0[1::2] = 1 + np.sin(2 * np.pi * x), 3.0
    return f, pattern, y0


def _stiff_banded():
    """radau's band LU on a large stiff system, beside SciPy's Radau given the
    same pattern (both finite-difference Jacobians, Python right-hand sides)."""
    from scipy.integrate import solve_ivp
    f, pattern, y0 = _brusselator(50)
    ref = solve_ivp(f, (0, 10), y0, method="Radau", rtol=1e-11, atol=1e-12,
                    jac_sparsity=pattern).y[:, -1]

    def ours():
        return mp.solve(f, (0, 10), y0, method="radau", rtol=1e-6, atol=1e-8,
                        jac_sparsity=pattern)

    def theirs():
        return solve_ivp(f, (0, 10), y0, method="Radau", rtol=1e-6, atol=1e-8,
                         jac_sparsity=pattern)
    s, r = ours(), theirs()
    e_mp = np.max(np.abs(s.y[:, -1] - ref)) / np.max(np.abs(ref))
    e_sp = np.max(np.abs(r.y[:, -1] - ref)) / np.max(np.abs(ref))
    line("Brusselator, 100 states, band 2+2, rtol 1e-6",
         f"radau err {e_mp:.1e} nfev {s.nfev} nlu {s.nlu}",
         t_mp=median_time(ours), t_ref=median_time(theirs, repeat=3),
         ref_name=f"solve_ivp Radau (err {e_sp:.1e}, nfev {r.nfev})")


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

    _stiff_banded()

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
