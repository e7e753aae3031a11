"""Tour: the brachistochrone, the catenary and least-action paths (one and more coordinates),
beside closed forms."""
from pathlib import Path

import numpy as np

import mechpy as mp
from mechpy._timing import median_time
from mechpy.tours import line

TITLE = "Lagrangian mechanics: brachistochrone, catenary, least action"
ORDER = 80


def run(out: Path) -> None:
    from scipy.integrate import solve_bvp

    V = mp.variational
    r = V.brachistochrone(2.0, 1.0, n=400)
    line("brachistochrone to (2, 1), n = 400", f"{r.time:.10f} s",
         ref=f"{r.time_exact:.10f} s (cycloid)", err=abs(r.time - r.time_exact))
    line("  straight line / cycloid", f"{r.time_line:.5f} s / {r.time_exact:.5f} s")
    errs = [abs(V.brachistochrone(2.0, 1.0, n=n).time - r.time_exact) for n in (50, 100, 200)]
    line("  convergence order (n = 50, 100, 200)",
         " ".join(f"{o:.2f}" for o in np.log2(np.array(errs[:-1]) / errs[1:])))
    t_mp = median_time(lambda: V.brachistochrone(2.0, 1.0, n=400))
    line("  Newton, tridiagonal Hessian", f"{r.iterations} iterations", t_mp=t_mp)

    c = V.catenary(0.0, 2.0, 3.0, n=400)
    line("catenary, span 2 m, length 3 m, n = 400",
         f"max |y - cosh| {np.max(np.abs(c.y - c.y_exact)):.1e} m",
         ref=f"lambda = -c = {c.multiplier_exact:.6f}", err=abs(c.multiplier - c.multiplier_exact))

    p = mp.scenes.Pendulum()
    qa, qb, T = 0.2, -0.5, 1.0
    sp = V.stationary_path(p, qa, qb, T, n=400)

    def f(t, y):
        return np.vstack([y[1], -9.81 * np.sin(y[0])])

    def bc(ya, yb):
        return np.array([ya[0] - qa, yb[0] - qb])
    tt = np.linspace(0, T, 11)
    guess = np.vstack([qa + (qb - qa) * tt / T, np.zeros_like(tt)])
    bvp = solve_bvp(f, bc, tt, guess, tol=1e-10)
    err = np.max(np.abs(sp.q - bvp.sol(sp.t)[0]))
    t_mp = median_time(lambda: V.stationary_path(p, qa, qb, T, n=400))
    t_sp = median_time(lambda: solve_bvp(f, bc, tt, guess, tol=1e-10), repeat=3)
    line("pendulum least-action path, n = 400", f"err {err:.1e} rad", t_mp=t_mp, t_ref=t_sp,
         ref_name="solve_bvp (tol 1e-10)")

    vi = V.variational_integrate(p, (0, 1000), 2.0, 0.0, 0.05)
    rk = mp.solve(p, (0, 1000), [2.0, 0.0], method="rk4", h=0.05)
    dv = np.abs(vi.energy - vi.energy[0])
    dr = np.abs(p.energy(rk.y) - p.energy(rk.y[:, 0]))
    k = len(dv) // 10
    line("energy error, h = 0.05: first / last 100 s",
         f"variational {dv[:k].max():.1e} / {dv[-k:].max():.1e} J/kg",
         ref=f"rk4 {dr[:k].max():.1e} / {dr[-k:].max():.1e} J/kg (drifts)")
    # two coordinates: the double pendulum's least-action path (its Lagrangian
    # as a Python callable, derivatives by finite differences) and solve_bvp
    from mechpy.benches.variational import _dp_bvp, _dp_lagrangian
    qa2, qb2, T2 = np.array([0.4, -0.3]), np.array([-0.2, 0.5]), 0.8
    f2, bc2, tt2, guess2 = _dp_bvp(qa2, qb2, T2)
    dp = V.stationary_path(_dp_lagrangian, qa2, qb2, T2, n=400)
    bvp2 = solve_bvp(f2, bc2, tt2, guess2, tol=1e-12, max_nodes=200000)
    line("double pendulum action path, d = 2, n = 400",
         f"err {np.max(np.abs(dp.q - bvp2.sol(dp.t)[:2])):.1e} rad",
         t_mp=median_time(lambda: V.stationary_path(_dp_lagrangian, qa2, qb2, T2, n=400),
                          repeat=3),
         t_ref=median_time(lambda: solve_bvp(f2, bc2, tt2, guess2, tol=1e-6), repeat=3),
         ref_name="solve_bvp (tol 1e-6)")
    top = mp.scenes.HeavyTop(I1=0.5, I3=0.2, mass=1.0, l=0.3)
    vt = V.variational_integrate(top, (0, 20), [0.0, 0.6, 0.0], [1.0, 0.0, 20.0], 1e-3)
    kept = max(np.ptp(vt.p[0]) / abs(vt.p[0, 0]), np.ptp(vt.p[2]) / abs(vt.p[2, 0]))
    line("heavy top, d = 3, variational, 2e4 steps", f"p_phi, p_psi kept to {kept:.0e}",
         ref=f"energy to {np.ptp(vt.energy) / abs(vt.energy[0]):.0e} (relative)")

    s = mp.solve(p, (0, 3), [2.5, 0.0], t_eval=np.linspace(0, 3, 301))
    Tn = V.pendulum_tension(p, s.y)
    line("string tension by a Lagrange multiplier", f"min {Tn.min():.3f} max {Tn.max():.3f} N/kg",
         err=np.max(np.abs(Tn - (9.81 * np.cos(s.y[0]) + s.y[1] ** 2))))

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(r.x_cycloid, r.y_cycloid, "k-", lw=3, alpha=0.3, label="cycloid")
    ax.plot(r.x, r.y, "r--", label=f"numerical, T = {r.time:.6f} s")
    ax.plot([0, 2], [0, 1], "b:", label=f"line, T = {r.time_line:.5f} s")
    ax.invert_yaxis()
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y (down) [m]")
    ax.legend()
    fig.tight_layout()
    path = out / "brachistochrone.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    line("figure written", str(path))
