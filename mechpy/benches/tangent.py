"""Bench: the tangent flow (fits, sensitivities, Lyapunov spectra) beside SciPy.

* Fit: the damping and length of a pendulum from 101 noisy samples of theta on [0, 10]
  (noise 0.01 rad, start damping 0.1, length 2.0; truth 0.3, 1.2).  ``mp.fit`` (the
  exact Jacobian from the compiled sensitivities) against
  ``scipy.optimize.least_squares`` over ``solve_ivp`` (DOP853) with 2-point differences,
  same tolerances, same data; error = the larger |estimate - truth| / stderr (the two
  optimisers reach the same minimum; the figure says how well).
* Sensitivities: the 7 columns of the driven damped pendulum (5 parameters, 2 initial
  states) at 11 times on [0, 10]: ``mp.sensitivity`` against central differences of
  ``mp.solve`` (15 solves); error against ``mp.sensitivity`` at rtol 1e-13 (which the
  tests check against differences of tight solves and, for a linear system, expm).
* Lyapunov spectrum of Lorenz (10, 28, 8/3) over t = 10^4 (quick 10^3), dt = 1:
  ``mp.phase.lyapunov_spectrum`` against the same algorithm in NumPy/SciPy (the 12
  variational equations in Python through ``solve_ivp`` DOP853, QR each dt; timed over a
  tenth of the span and scaled); error = |sum + 41/3| (the trace) and
  |lambda_1 - 0.9056| (published).
"""
import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Tangent flow: fit, sensitivities, Lyapunov spectrum"
ORDER = 31

_RTOL, _ATOL = 1e-10, 1e-12


def _pendulum(t, y, g, L, b, A, w):
    return np.array([y[1], -g / L * np.sin(y[0]) - b * y[1] + A * np.cos(w * t)])


def _fit_rows():
    from scipy.integrate import solve_ivp
    from scipy.optimize import least_squares
    sc = mp.scenes.Pendulum(damping=0.3, length=1.2)
    t = np.linspace(0, 10, 101)
    clean = mp.solve(sc, (0, 10), [1.0, 0.0], t_eval=t, rtol=1e-12, atol=1e-14).y[:1]
    data = clean + 0.01 * np.random.default_rng(1).normal(size=clean.shape)
    name = "fit damping, length of a pendulum: 101 samples, rtol 1e-10"

    def ours():
        return mp.fit(mp.scenes.Pendulum(), t, data, {"damping": 0.1, "length": 2.0},
                      y0=[1.0, 0.0], observe=0, rtol=_RTOL, atol=_ATOL)
    r = ours()
    se = np.array([r.stderr["damping"], r.stderr["length"]])
    est = np.array([r.params["damping"], r.params["length"]])
    err = float(np.max(np.abs(est - [0.3, 1.2]) / se))
    rows = [dict(problem=name, impl="mechpy fit (exact Jacobian, compiled sensitivities)",
                 time=median_time(ours, repeat=3), error=err, nfev=r.nfev,
                 note=f"{r.nfev} solves: each gives the residuals and the Jacobian "
                      f"({r.njev} Jacobians used)")]

    def res(x):
        s = solve_ivp(_pendulum, (0, 10), [1.0, 0.0], method="DOP853", t_eval=t,
                      rtol=_RTOL, atol=_ATOL, args=(9.81, x[1], x[0], 0.0, 0.0))
        return s.y[0] - data[0]

    def theirs():
        return least_squares(res, [0.1, 2.0], jac="2-point", bounds=([0, 1e-12], np.inf),
                             x_scale="jac")
    q = theirs()
    err_sp = float(np.max(np.abs(q.x - [0.3, 1.2]) / se))
    rows.append(dict(problem=name, impl="scipy least_squares over solve_ivp, 2-point jac",
                     time=median_time(theirs, repeat=1), error=err_sp,
                     nfev=q.nfev + 2 * q.njev,
                     note=f"|x - mechpy's| = {np.abs(q.x - est).max():.1e}; "
                          f"{q.nfev} + 2 x {q.njev} solves"))
    return rows


def _sens_rows():
    sc = mp.scenes.Pendulum(damping=0.3, length=1.2, drive_amplitude=0.5, drive_frequency=1.1)
    names = ("g", "length", "damping", "drive_amplitude", "drive_frequency")
    y0 = np.array([1.0, 0.2])
    te = np.linspace(0, 10, 11)
    ref = mp.sensitivity(sc, (0, 10), y0, params=names, t_eval=te, rtol=1e-13, atol=1e-15).S
    scale = np.abs(ref).max()
    name = "sensitivities of a driven pendulum: 7 columns at 11 times, rtol 1e-10"

    def ours():
        return mp.sensitivity(sc, (0, 10), y0, params=names, t_eval=te, rtol=_RTOL, atol=_ATOL)
    rows = [dict(problem=name, impl="mechpy sensitivity (compiled variational equations)",
                 time=median_time(ours), error=float(np.abs(ours().S - ref).max() / scale),
                 rtol=_RTOL, note="error relative to max |S|")]
    scenes = [(sc.replace(**{nm: sc.params[nm] + s * 1e-4 * max(1, abs(sc.params[nm]))}), y0)
              for nm in names for s in (1, -1)]
    scenes += [(sc, y0 + s * 1e-4 * e) for e in np.eye(2) for s in (1, -1)]

    def fd():
        ys = [mp.solve(c, (0, 10), yy, t_eval=te, rtol=_RTOL, atol=_ATOL).y for c, yy in scenes]
        S = np.empty_like(ref)
        for j in range(7):
            h = (1e-4 * max(1, abs(sc.params[names[j]]))) if j < 5 else 1e-4
            S[:, j] = (ys[2 * j] - ys[2 * j + 1]) / (2 * h)
        return S
    rows.append(dict(problem=name, impl="central differences of mp.solve (14 solves)",
                     time=median_time(fd), error=float(np.abs(fd() - ref).max() / scale),
                     rtol=_RTOL, note="step 1e-4 max(1, |p|)"))
    return rows


def _lorenz_numpy(y0, T, dt):
    """Benettin's QR on the Lorenz tangent flow, in NumPy/SciPy."""
    from scipy.integrate import solve_ivp
    s_, r_, b_ = 10.0, 28.0, 8 / 3

    def f(t, z):
        x, y, w = z[:3]
        P = z[3:].reshape(3, 3)
        J = np.array([[-s_, s_, 0], [r_ - w, -1, -x], [y, x, -b_]])
        return np.concatenate([[s_ * (y - x), x * (r_ - w) - y, x * y - b_ * w],
                               (J @ P).ravel()])
    y, Q, sums = np.asarray(y0, float), np.eye(3), np.zeros(3)
    m = int(round(T / dt))
    for i in range(m):
        z = solve_ivp(f, (i * dt, (i + 1) * dt), np.concatenate([y, Q.ravel()]),
                      method="DOP853", rtol=_RTOL, atol=_ATOL).y[:, -1]
        y = z[:3]
        Q, R = np.linalg.qr(z[3:].reshape(3, 3))
        d = np.diag(R)
        sums += np.log(np.abs(d))
        Q = Q * np.sign(d)
    return np.sort(sums / (m * dt))[::-1]


def _lyap_rows(quick):
    import sympy as sp
    x, y, z = sp.symbols("x y z")
    s, r, b = sp.symbols("sigma rho beta")
    lor = mp.equations([s * (y - x), x * (r - z) - y, x * y - b * z], [x, y, z],
                       params={"sigma": 10.0, "rho": 28.0, "beta": 8 / 3})
    T = 1e3 if quick else 1e4
    y0 = [0.906, 0.0, -14.57]
    name = f"Lorenz Lyapunov spectrum, t = {T:g}, dt = 1, rtol 1e-10"

    def err(lam):
        return float(max(abs(lam.sum() + 41 / 3), abs(lam[0] - 0.9056)))
    lam = mp.phase.lyapunov_spectrum(lor, y0, T)
    rows = [dict(problem=name, impl="mechpy phase.lyapunov_spectrum (compiled tangent flow)",
                 time=median_time(lambda: mp.phase.lyapunov_spectrum(lor, y0, T), repeat=1),
                 error=err(lam), rtol=_RTOL,
                 note=f"spectrum {np.array2string(lam, precision=4)}; "
                      f"|sum + 41/3| = {abs(lam.sum() + 41 / 3):.1e}")]
    import time
    t0 = time.perf_counter()
    lam_np = _lorenz_numpy(y0, T / 10, 1.0)
    t_np = (time.perf_counter() - t0) * 10
    rows.append(dict(problem=name, impl="NumPy/SciPy: solve_ivp DOP853 + QR per dt",
                     time=t_np, error=err(lam_np), rtol=_RTOL,
                     note=f"timed over t = {T / 10:g}, scaled x10 (its error at that t)"))
    return rows


def run(quick: bool):
    return _fit_rows() + _sens_rows() + _lyap_rows(quick)
