"""Bench: the hard cases (stiff, long, near a separatrix), mechpy beside SciPy.

Each row gives the error against the published reference and the work
(nfev, njev, nlu) at the same tolerance, mechpy's best method beside SciPy's."""
import numpy as np

import mechpy as mp
from mechpy._timing import median_time
from mechpy.benches import problems

TITLE = "Hard cases: stiff, long, near a separatrix"
ORDER = 20

# the stiff Van der Pol (scaled form) and Robertson with their published end values
VDP = problems.VDP_SCALED
ROBER = problems.ROBER


def _row(problem, impl, fn, err_of, rtol, repeat=3, path=None, method=None):
    s = fn()
    t = median_time(fn, repeat=repeat, budget=2.0)
    return dict(problem=problem, impl=impl, path=path, method=method, rtol=rtol,
                error=float(err_of(s)), time=t,
                nfev=int(getattr(s, "nfev", 0)), njev=int(getattr(s, "njev", 0)),
                nlu=int(getattr(s, "nlu", 0)))


def run(quick: bool):
    from scipy.integrate import solve_ivp
    rows = []
    rtols = [1e-6, 1e-8] if quick else [1e-4, 1e-6, 1e-8, 1e-10]
    # stiff Van der Pol, eps = 1e-6 (atol = rtol)
    p = "stiff Van der Pol eps=1e-6, t=2 (IVP test set)"
    err = lambda s: np.max(np.abs(s.y[:, -1] - np.array(VDP.ref)))  # noqa: E731
    for rtol in rtols:
        for m in ["radau", "auto", "gsl:bsimp"]:
            rows.append(_row(p, f"mechpy {m} (Python rhs + jac)", lambda m=m: mp.solve(
                VDP.f, VDP.t_span, VDP.y0, method=m, rtol=rtol, atol=rtol, jac=VDP.jac),
                err, rtol, path="python", method=m))
        for m in ["Radau", "BDF", "LSODA"]:
            rows.append(_row(p, f"scipy {m} (Python rhs + jac)", lambda m=m: solve_ivp(
                VDP.f, VDP.t_span, VDP.y0, method=m, rtol=rtol, atol=rtol, jac=VDP.jac),
                err, rtol, repeat=1, path="scipy", method=m.lower()))
    # Robertson
    p = "Robertson to t=1e11 (IVP test set), relative error"
    ref = np.array(ROBER.ref)
    err = lambda s: np.max(np.abs(s.y[:, -1] - ref) / ref)  # noqa: E731
    for rtol in rtols:
        for m in ["radau", "auto", "gsl:bsimp"]:
            rows.append(_row(p, f"mechpy {m} (Python rhs + jac)", lambda m=m: mp.solve(
                ROBER.f, ROBER.t_span, ROBER.y0, method=m, rtol=rtol, atol=ROBER.atol,
                jac=ROBER.jac), err, rtol, path="python", method=m))
        for m in ["Radau", "BDF", "LSODA"]:
            rows.append(_row(p, f"scipy {m} (Python rhs + jac)", lambda m=m: solve_ivp(
                ROBER.f, ROBER.t_span, ROBER.y0, method=m, rtol=rtol, atol=ROBER.atol,
                jac=ROBER.jac), err, rtol, repeat=1, path="scipy", method=m.lower()))
    # Kepler: energy error over many orbits
    k = mp.scenes.Kepler()
    y0 = k.initial_state(0.6)
    periods = 100 if quick else 1000
    T = periods * 2 * np.pi
    p = f"Kepler e=0.6, {periods} orbits: max energy error"
    te = np.linspace(0, T, 20 * periods + 1)
    err = lambda s: np.max(np.abs(k.energy(s.y) - k.energy(y0)))  # noqa: E731
    rows.append(_row(p, "mechpy yoshida4 h=T/150 (C scene)", lambda: mp.solve(
        k, (0, T), y0, method="yoshida4", h=2 * np.pi / 150, t_eval=te), err, None))
    rows.append(_row(p, "mechpy yoshida6 h=T/100 (C scene)", lambda: mp.solve(
        k, (0, T), y0, method="yoshida6", h=2 * np.pi / 100, t_eval=te), err, None))
    rows.append(_row(p, "mechpy dop853 rtol=1e-10 (C scene)", lambda: mp.solve(
        k, (0, T), y0, rtol=1e-10, atol=1e-12, t_eval=te), err, 1e-10))

    def kep(t, y):
        r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
        return [y[2], y[3], -y[0] / r3, -y[1] / r3]
    rows.append(_row(p, "scipy DOP853 rtol=1e-10", lambda: solve_ivp(
        kep, (0, T), y0, method="DOP853", rtol=1e-10, atol=1e-12, t_eval=te), err, 1e-10,
        repeat=1))
    return rows
