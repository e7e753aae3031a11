"""Bench: models as SymPy's mechanics writes them, compiled by ``mp.mechanics``.

* Build time of the Carvallo-Whipple bicycle (Moore's formulation, Kane's
  method with a holonomic and three nonholonomic constraints) and of PyDy's
  n-link pendulum on a cart (n = 5, 10, 20): SymPy's ``kanes_equations``
  (the user's derivation, the same for every backend) apart from what
  ``mp.mechanics`` adds in an empty cache folder (blocks, derivatives, C,
  compilation), and beside PyDy's Cython backend (code generation and
  compilation) when PyDy and Cython are installed, else ``lambdify``.
  Goal: the bicycle builds in under 10 s.
* Integration at equal error: mechpy's dop853 on the compiled scene (at every
  decade of rtol from 10x the others' loosest to their tightest) against
  ``lambdify`` of SymPy's ``mass_matrix_full`` and ``forcing_full`` with
  ``numpy.linalg.solve`` in ``solve_ivp`` (DOP853), and PyDy + odeint when
  installed; errors at the final time against mechpy dop853 at rtol 1e-13.

Rows carry ``path``: "build-sympy", "build-mechpy", "build-pydy",
"build-lambdify" for the stages, "mechanics", "lambdify", "pydy" for the
integrations.
"""
from __future__ import annotations

import os
import shutil
import tempfile
import time

import numpy as np

TITLE = "Models as mechanics writes them: mp.mechanics beside lambdify + solve_ivp and PyDy"
ORDER = 91


def _err(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


class _EmptyCache:
    """MECHPY_CACHE_DIR pointed at a new empty folder inside the block."""

    def __enter__(self):
        self.dir = tempfile.mkdtemp(prefix="mechpy-bench-")
        self.old = os.environ.get("MECHPY_CACHE_DIR")
        os.environ["MECHPY_CACHE_DIR"] = self.dir
        return self

    def __exit__(self, *exc):
        if self.old is None:
            os.environ.pop("MECHPY_CACHE_DIR", None)
        else:
            os.environ["MECHPY_CACHE_DIR"] = self.old
        shutil.rmtree(self.dir, ignore_errors=True)


def _timed_build(kane, params, specified=None):
    """mp.mechanics in an empty cache: (scene, total s, compile s)."""
    import mechpy as mp
    from mechpy.symbolic import build
    spent = {"compile": 0.0}
    orig = build._compile

    def timed(*a, **k):
        t0 = time.perf_counter()
        try:
            return orig(*a, **k)
        finally:
            spent["compile"] += time.perf_counter() - t0
    build._compile = timed
    try:
        with _EmptyCache():
            t0 = time.perf_counter()
            scene = mp.mechanics(kane, params, specified=specified)
            total = time.perf_counter() - t0
    finally:
        build._compile = orig
    return scene, total, spent["compile"]


def _lambdified(kane, params, inputs=()):
    """SymPy's full mass matrix and forcing lambdified: f(t, y) for solve_ivp."""
    import sympy as sp
    x = list(kane.q) + list(kane.u)
    exprs = kane.mass_matrix_full, kane.forcing_full
    free = exprs[0].free_symbols | exprs[1].free_symbols
    byname = {s.name: s for s in free}
    consts = [byname[k] for k in params if k in byname]
    vals = np.array([params[k] for k in params if k in byname])
    r = list(inputs)
    M = sp.lambdify([x, consts, r], exprs[0], "numpy", cse=True)
    F = sp.lambdify([x, consts, r], exprs[1], "numpy", cse=True)
    zero = [0.0] * len(r)

    def f(t, y):
        return np.linalg.solve(np.asarray(M(y, vals, zero), float),
                               np.asarray(F(y, vals, zero), float).ravel())
    return f


def _pydy(kane, params, inputs=()):
    """PyDy's generated rhs (Cython when it works, else its default), its
    backend, code generation + compilation time; None without PyDy."""
    try:
        from pydy.codegen.ode_function_generators import generate_ode_function
    except ImportError:
        return None
    free = kane.mass_matrix_full.free_symbols | kane.forcing_full.free_symbols
    byname = {s.name: s for s in free}
    consts = [byname[k] for k in params if k in byname]
    p = np.array([params[k] for k in params if k in byname])
    kw = dict(mass_matrix=kane.mass_matrix_full)
    if inputs:
        kw["specifieds"] = list(inputs)
    t0 = time.perf_counter()
    try:
        rhs = generate_ode_function(kane.forcing_full, list(kane.q), list(kane.u), consts,
                                    generator="cython", **kw)
        backend = "cython"
    except Exception as exc:   # no Cython or no compiler
        t0 = time.perf_counter()
        rhs = generate_ode_function(kane.forcing_full, list(kane.q), list(kane.u), consts,
                                    **kw)
        backend = f"lambdify ({type(exc).__name__})"
    gen = time.perf_counter() - t0
    if inputs:
        zero = np.zeros(len(inputs))
        return (lambda y, t: rhs(y, t, zero, p)), backend, gen
    return (lambda y, t: rhs(y, t, p)), backend, gen


def _own_rtols(rtols) -> list:
    """mechpy's rtols: every decade from 10x the loosest of ``rtols`` to the
    tightest.  dop853's error at a given rtol is far below odeint's (20-40x on
    the bicycle), so the run of equal error is often a decade looser than the
    others' rtol; with only their rtols, the equal-error ratio would be taken
    against a mechpy run up to 10x more accurate than needed."""
    hi = int(round(-np.log10(max(rtols)))) - 1
    lo = int(round(-np.log10(min(rtols))))
    return [10.0 ** -k for k in range(hi, lo + 1)]


def _problem_rows(problem, kane, params, y0, T, rtols, specified=None, inputs=(),
                  pydy=True, lambdify=True):
    import mechpy as mp
    from mechpy._timing import median_time
    from scipy.integrate import odeint, solve_ivp
    rows = []

    def stage(impl, path, seconds, note=""):
        rows.append(dict(problem=problem, impl=impl, path=path, time=seconds,
                         error=float("nan"), note=note))

    scene, total, comp = _timed_build(kane, params, specified)
    stage("mp.mechanics, first build (empty cache)", "build-mechpy", total,
          note=f"of which compilation {comp:.2f} s")
    fl = None
    if lambdify:
        t0 = time.perf_counter()
        fl = _lambdified(kane, params, inputs)
        stage("lambdify(mass_matrix_full, forcing_full)", "build-lambdify",
              time.perf_counter() - t0)
    py = _pydy(kane, params, inputs) if pydy else None
    if py is not None:
        stage(f"PyDy generate_ode_function ({py[1]})", "build-pydy", py[2])
    ref = mp.solve(scene, (0, T), y0, rtol=1e-13, atol=1e-14).y[:, -1]
    for rtol in _own_rtols(rtols):
        atol = rtol * 1e-2
        f_mp = lambda: mp.solve(scene, (0, T), y0, rtol=rtol, atol=atol)  # noqa: E731
        s = f_mp()
        rows.append(dict(problem=problem, impl="mechpy dop853 (mp.mechanics)",
                         path="mechanics", method="dop853", rtol=rtol,
                         error=_err(s.y[:, -1], ref), nfev=int(s.nfev),
                         time=median_time(f_mp, repeat=5, budget=1.0)))
    for rtol in rtols:
        atol = rtol * 1e-2
        if fl is not None:
            f_sp = lambda: solve_ivp(fl, (0, T), y0, method="DOP853", rtol=rtol,  # noqa: E731
                                     atol=atol)
            s2 = f_sp()
            rows.append(dict(problem=problem, impl="lambdify + np.linalg.solve + solve_ivp "
                             "DOP853", path="lambdify", method="DOP853", rtol=rtol,
                             error=_err(s2.y[:, -1], ref), nfev=int(s2.nfev),
                             time=median_time(f_sp, repeat=3, budget=2.0)))
        if py is not None:
            f_py = lambda: odeint(py[0], y0, [0.0, T], rtol=rtol, atol=atol,  # noqa: E731
                                  mxstep=10**7)
            rows.append(dict(problem=problem, impl=f"PyDy {py[1]} + odeint", path="pydy",
                             method="lsoda", rtol=rtol, error=_err(f_py()[-1], ref),
                             time=median_time(f_py, repeat=3, budget=2.0)))
    return rows


def run(quick: bool) -> list[dict]:
    from mechpy.symbolic.models import n_link_cart, whipple_bicycle, whipple_state
    rows = []
    rtols = [1e-6, 1e-9] if quick else [1e-5, 1e-7, 1e-9, 1e-11]
    try:
        import pydy  # noqa: F401
    except ImportError:
        print("  PyDy is not installed (pip install pydy cython): no PyDy rows")
    # the bicycle
    problem = "Whipple bicycle (Kane, 1 holonomic + 3 nonholonomic), 4.6 m/s, t=5"
    t0 = time.perf_counter()
    kane, params = whipple_bicycle()
    rows.append(dict(problem=problem, impl="SymPy kanes_equations (the model, any backend)",
                     path="build-sympy", time=time.perf_counter() - t0, error=float("nan")))
    import mechpy as mp
    with _EmptyCache():
        bike = mp.mechanics(kane, params)
        y0 = bike.project(np.array(whipple_state(4.6, roll=0.1, steer=0.05, roll_rate=0.3)))
    rows += _problem_rows(problem, kane, params, y0, 5.0, rtols)
    # the n-link pendulum on a cart, the force on the cart zero
    from sympy.physics.mechanics import dynamicsymbols
    for n in ((5, 10) if quick else (5, 10, 20)):
        problem = f"{n}-link pendulum on a cart (Kane), t=5"
        t0 = time.perf_counter()
        kane, params = n_link_cart(n)
        rows.append(dict(problem=problem, impl="SymPy kanes_equations", path="build-sympy",
                         time=time.perf_counter() - t0, error=float("nan")))
        y0 = np.zeros(2 * (n + 1))
        y0[1:n + 1] = np.linspace(0.1, 0.3, n)
        rows += _problem_rows(problem, kane, params, y0, 5.0, rtols[:1] if n == 20 else rtols,
                              specified={"F": 0.0}, inputs=(dynamicsymbols("F"),),
                              lambdify=n <= 10)
    return rows


def targets(rows) -> list[dict]:
    """The bicycle's build time (goal < 10 s) and, per problem, the speed-up
    at equal error against lambdify + solve_ivp and PyDy (their time over the
    fastest mechpy run with no larger error)."""
    out = []
    for r in rows:
        if r.get("path") == "build-mechpy" and r["problem"].startswith("Whipple"):
            out.append(dict(target="mp.mechanics: the bicycle's first build (s)",
                            problem=r["problem"], goal="< 10 s", worst=r["time"],
                            median=r["time"], n=1, unit=" s"))
    for p in dict.fromkeys(r["problem"] for r in rows):
        pr = [r for r in rows if r["problem"] == p]
        own = [r for r in pr if r.get("path") == "mechanics" and np.isfinite(r["error"])]
        for theirs, label in (("lambdify", "vs lambdify + solve_ivp"), ("pydy", "vs PyDy")):
            ratios = []
            for q in (r for r in pr if r.get("path") == theirs and np.isfinite(r["error"])):
                fit = [r["time"] for r in own if r["error"] <= q["error"]]
                if fit:
                    ratios.append(q["time"] / min(fit))
            if ratios:
                ratios.sort()
                out.append(dict(target=f"mp.mechanics {label} at equal error (time ratio)",
                                problem=p, goal=">= 50x" if theirs == "pydy" else "(none)",
                                worst=ratios[0], median=ratios[len(ratios) // 2],
                                n=len(ratios)))
    return out
