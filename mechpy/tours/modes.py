"""Tour: normal modes of a 1000-mass chain, its exact and its integrated motion
(SpringChain) beside SciPy, and the FPUT recurrence."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from . import line
from .._timing import median_time

TITLE = "Normal modes: coupled oscillators and a 1000-mass chain"
ORDER = 60


def run(out: Path) -> None:
    import scipy.linalg as sl
    from scipy.integrate import odeint

    from ..modes import chain, linear_triatomic, normal_modes

    # the two-mass system of the course notes
    kappa, k12, m = 1.0, 0.1, 1.0
    K = np.array([[kappa + k12, -k12], [-k12, kappa + k12]])
    two = normal_modes(K, m * np.eye(2))
    ref = np.array([np.sqrt(kappa / m), np.sqrt((kappa + 2 * k12) / m)])
    line("two masses: omega (rad/s)", np.array2string(two.omega, precision=6),
         ref="sqrt(k/M), sqrt((k+2k12)/M)", err=float(np.max(np.abs(two.omega - ref))))

    # a 1000-mass fixed chain: all modes
    N = 1000
    K, M = chain(N, mass=m, spring=kappa)
    exact = 2 * np.sqrt(kappa / m) * np.sin(np.arange(1, N + 1) * np.pi / (2 * (N + 1)))
    res = {}
    t_mp = median_time(lambda: res.__setitem__("mp", normal_modes(K, M)), repeat=3)
    t_sp = median_time(lambda: res.__setitem__("sp", sl.eigh(K, M)), repeat=1, warmup=0)
    modes = res["mp"]
    line(f"chain N={N}: omega_1 .. omega_N (rad/s)",
         f"{modes.omega[0]:.8f} .. {modes.omega[-1]:.8f}", ref="2 sqrt(k/m) sin(j pi/2(N+1))",
         err=float(np.max(np.abs(modes.omega - exact))), t_mp=t_mp, t_ref=t_sp,
         ref_name="scipy eigh(K, M)")

    # its exact motion from a plucked start, beside odeint
    x = np.arange(N)
    q0 = np.exp(-0.5 * ((x - N / 3) / 10.0) ** 2)
    v0 = np.zeros(N)
    t = np.linspace(0.0, 50.0, 51)

    def rhs(y, _t):
        q = y[:N]
        qp = np.concatenate([[0.0], q, [0.0]])
        return np.concatenate([y[N:], kappa / m * (qp[2:] - 2 * q + qp[:-2])])

    q_ex = modes.evolve(q0, v0, t)
    t_ev = median_time(lambda: modes.evolve(q0, v0, t), repeat=3)
    ode = {}
    t_ode = median_time(lambda: ode.__setitem__(
        "y", odeint(rhs, np.concatenate([q0, v0]), t, rtol=1e-10, atol=1e-12)),
        repeat=1, warmup=0)
    err = float(np.max(np.abs(q_ex - ode["y"][:, :N])))
    E = modes.energy(*modes.evolve(q0, v0, t, velocities=True))
    drift = float(np.max(np.abs(E.sum(axis=1) - E[0].sum())) / E[0].sum())
    line(f"chain N={N}: exact q(t), 51 times to t=50", f"max|q| {np.max(np.abs(q_ex)):.6f}",
         ref="odeint rtol 1e-10", err=err, t_mp=t_ev, t_ref=t_ode, ref_name="odeint")
    line("  energy drift of the exact motion", f"{drift:.1e}")

    # the same chain integrated in time (SpringChain, a C scene) beside the exact motion
    from scipy.integrate import solve_ivp

    from ..integrate import solve
    from ..scenes import SpringChain

    sc = SpringChain.uniform(N, mass=m, spring=kappa)
    y0 = sc.initial_state(q0, v0)

    def rhs_ivp(_t, y):
        r = np.diff(np.concatenate([[0.0], y[:N], [0.0]]))   # spring extensions
        return np.concatenate([y[N:], kappa / m * np.diff(r)])

    runs = {}
    t_int = median_time(lambda: runs.__setitem__("mp", solve(
        sc, (0.0, 50.0), y0, rtol=1e-10, atol=1e-12, t_eval=t)), repeat=3)
    t_ivp = median_time(lambda: runs.__setitem__("sp", solve_ivp(
        rhs_ivp, (0.0, 50.0), y0, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=t)),
        repeat=1, warmup=0)
    err_mp = float(np.max(np.abs(runs["mp"].y[:N].T - q_ex)))
    err_sp = float(np.max(np.abs(runs["sp"].y[:N].T - q_ex)))
    line(f"SpringChain N={N}: dop853 rtol 1e-10 to t=50", f"solve_ivp err {err_sp:.1e}",
         ref="exact modes", err=err_mp, t_mp=t_int, t_ref=t_ivp, ref_name="solve_ivp DOP853")
    t_sy = median_time(lambda: runs.__setitem__("sy", solve(
        sc, (0.0, 50.0), y0, method="yoshida4", h=0.05, t_eval=t)), repeat=3)
    line("  symplectic yoshida4, h=0.05", "",
         ref="exact modes", err=float(np.max(np.abs(runs["sy"].y[:N].T - q_ex))), t_mp=t_sy)

    # FPUT: the alpha chain of Fermi, Pasta, Ulam and Tsingou shares mode 1's energy
    # among the modes and gives it back (the recurrence, ~160 periods of mode 1)
    nf = 32
    fput = SpringChain.uniform(nf, alpha=0.25)
    w1 = fput.modes().omega[0]
    tf = np.linspace(0.0, 180 * 2 * np.pi / w1, 3601)
    yf0 = fput.initial_state(np.sin(np.pi * np.arange(1, nf + 1) / (nf + 1)))
    t_f = median_time(lambda: runs.__setitem__("fput", solve(
        fput, (0.0, tf[-1]), yf0, method="yoshida4", h=0.1, t_eval=tf)), repeat=1)
    Ef = fput.mode_energies(runs["fput"].y)
    frac = Ef[0] / Ef.sum(axis=0)
    late = tf * w1 / (2 * np.pi) > 100
    k = int(np.argmax(np.where(late, frac, 0.0)))
    line("FPUT alpha=1/4, N=32: mode-1 energy share",
         f"min {frac.min():.2f}, back to {frac[k]:.3f} after {tf[k] * w1 / (2 * np.pi):.0f} "
         "periods", ref="FPUT 1955: near-return after ~160 periods",
         t_mp=t_f)

    # CO2: 5 zero modes, 4 vibrations
    co2 = linear_triatomic()
    line("CO2 (harmonic model): wavenumbers (cm^-1)",
         np.array2string(co2.wavenumbers, precision=1), ref="667, 667, 1335, 2555 (model)")
    line("  zero modes (3 translations + 2 rotations)", len(co2.zero))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for j in (0, 1, 2, 9):
        ax.plot(x, modes.vectors[:, j], label=f"mode {j + 1}")
    ax.set_xlabel("mass index")
    ax.set_ylabel("v (M-normalised)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "modes_chain.png", dpi=100)
    plt.close(fig)
