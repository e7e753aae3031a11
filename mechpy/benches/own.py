"""Bench: the user's own system, compiled from its Lagrangian.

* The pendulum from L = l^2 theta'^2 / 2 + g l cos(theta) (per unit mass)
  beside the hand-written C scene ``mp.scenes.Pendulum``, same method (dop853)
  and tolerances: the cost of generated code (goal: within 1.25x).
* The double pendulum: the compiled scene beside what a SymPy user writes
  today (the Euler-Lagrange equations with SymPy, ``sympy.solve`` for the
  accelerations, ``lambdify`` to NumPy, ``solve_ivp``), time against the
  final-time error over an rtol sweep (goal: >= 100x at equal error).
* The n-link pendulum on a cart (n = 5, 10) beside PyDy on its own model,
  built with ``sympy.physics.mechanics.KanesMethod`` (derivation, code
  generation, compilation and integration timed apart; both errors against a
  tight reference).
* Ensembles (``solve_many``, 1 thread, dop853 at rtol 1e-8): compiled double
  pendulums in SIMD lanes (the generated lane right-hand side) against the
  scalar path and a Python loop of ``solve_ivp`` on the lambdified equations
  (goals: >= 2x, >= 100x as for one solve); the compiled pendulum against ``Pendulum``, both
  in lanes (goal: within 1.25x).
* Building: the double pendulum's first build in an empty cache folder
  (derive, print C, compile; goal < 2 s) and its build from the cache in a new
  process (goal < 50 ms).

Rows carry ``path`` ("lagrangian" for the compiled scene, "scene" for the
hand-written one, "sympy" for lambdify + ``solve_ivp``, "pydy", "build-*",
"own-ensemble-*" and "*-pendulum-lanes" for the ensembles)
and :func:`targets` turns them into the report's overhead-budget lines.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

TITLE = "Your own system, compiled: Lagrangian scenes beside SymPy + solve_ivp and PyDy"
ORDER = 90

G = 9.81
DP_PARAMS = {"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": G}
DP_Y0 = np.array([1.0, 0.5, 0.0, 0.0])   # at rest; angles from the downward vertical
DP_T = 10.0


# --------------------------------------------------------------------------- systems

def pendulum_lagrangian():
    """L = l^2 theta'^2 / 2 + g l cos(theta) (per unit mass); returns (L, q)."""
    import sympy as sp

    import mechpy as mp
    (th,) = mp.coordinates("theta")
    g, l = sp.symbols("g l")
    return l ** 2 * th.diff() ** 2 / 2 + g * l * sp.cos(th), [th]


def double_pendulum_lagrangian(q=None):
    """The planar double pendulum (point masses m1, m2 on massless rods l1, l2,
    angles from the downward vertical); returns (L, q).

    L = (m1 + m2) l1^2 th1'^2 / 2 + m2 l2^2 th2'^2 / 2
        + m2 l1 l2 th1' th2' cos(th1 - th2) + (m1 + m2) g l1 cos th1 + m2 g l2 cos th2
    """
    import sympy as sp

    import mechpy as mp
    th1, th2 = q if q is not None else mp.coordinates("theta1 theta2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
    w1, w2 = th1.diff(), th2.diff()
    L = ((m1 + m2) * l1 ** 2 * w1 ** 2 / 2 + m2 * l2 ** 2 * w2 ** 2 / 2
         + m2 * l1 * l2 * w1 * w2 * sp.cos(th1 - th2)
         + (m1 + m2) * g * l1 * sp.cos(th1) + m2 * g * l2 * sp.cos(th2))
    return L, [th1, th2]


def double_pendulum_sympy(params=DP_PARAMS):
    """What a SymPy user writes today: Euler-Lagrange equations, solved for the
    accelerations, lambdified to NumPy; returns ``f(t, y)`` for ``solve_ivp``."""
    import sympy as sp
    t = sp.symbols("t")
    th1, th2 = sp.Function("theta1")(t), sp.Function("theta2")(t)
    L, _ = double_pendulum_lagrangian([th1, th2])
    eqs = [sp.diff(L.diff(q.diff(t)), t) - L.diff(q) for q in (th1, th2)]
    acc = sp.solve(eqs, [th1.diff(t, 2), th2.diff(t, 2)], dict=True)[0]
    x1, x2, v1, v2 = sp.symbols("x1 x2 v1 v2")
    sub = {th1.diff(t): v1, th2.diff(t): v2}
    a = [acc[q.diff(t, 2)].subs(sub).subs({th1: x1, th2: x2}) for q in (th1, th2)]
    a = [e.subs({sp.Symbol(k): v for k, v in params.items()}) for e in a]
    f = sp.lambdify((x1, x2, v1, v2), [v1, v2, a[0], a[1]], "numpy")
    return lambda t, y: f(y[0], y[1], y[2], y[3])


def cart_pendulum_lagrangian(n):
    """The n-link pendulum on a cart as a Lagrangian, the system of
    :func:`cart_pendulum_pydy` written by hand: a cart of mass m0 at x = q0
    sliding along the ground, n massless links of lengths l0..l(n-1) with point
    masses m1..mn at their ends, absolute angles q1..qn from the ground line,
    gravity along -y.  Returns (L, q, param symbols)."""
    import sympy as sp

    import mechpy as mp
    q = mp.coordinates(" ".join(f"q{i}" for i in range(n + 1)))
    m = sp.symbols(f"m0:{n + 1}")
    ln = sp.symbols(f"l0:{n}")
    g, t = sp.symbols("g t")
    T = m[0] * q[0].diff(t) ** 2 / 2
    V = 0
    x, y = q[0], sp.Integer(0)
    for i in range(n):
        x = x + ln[i] * sp.cos(q[i + 1])
        y = y + ln[i] * sp.sin(q[i + 1])
        T += m[i + 1] * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2
        V += m[i + 1] * g * y
    return T - V, q


def cart_pendulum_pydy(n):
    """The n-link pendulum on a cart by Kane's method, as PyDy builds it.

    Transcribed from PyDy's model ``pydy.models.n_link_pendulum_on_cart``
    (PyDy 0.9, BSD licence) without its input force, which itself follows
    J. K. Moore's example "Swinging N-link pendulum on a cart" (2013) for
    ``sympy.physics.mechanics``: a particle per link end and one for the cart,
    frames B_i rotated by q_(i+1) about I.z, u = q'.  Returns the KanesMethod,
    the coordinates, the speeds and the constants (g, m0..mn, l0..l(n-1)).
    """
    import sympy as sp
    import sympy.physics.mechanics as me
    q = me.dynamicsymbols(f"q:{n + 1}")
    u = me.dynamicsymbols(f"u:{n + 1}")
    m = sp.symbols(f"m:{n + 1}")
    ln = sp.symbols(f"l:{n}")
    g, t = sp.symbols("g t")
    I = me.ReferenceFrame("I")
    O = me.Point("O")
    O.set_vel(I, 0)
    P0 = me.Point("P0")
    P0.set_pos(O, q[0] * I.x)
    P0.set_vel(I, u[0] * I.x)
    points, particles = [P0], [me.Particle("Pa0", P0, m[0])]
    forces = [(P0, -m[0] * g * I.y)]
    kindiffs = [q[0].diff(t) - u[0]]
    for i in range(n):
        Bi = I.orientnew(f"B{i}", "Axis", [q[i + 1], I.z])
        Bi.set_ang_vel(I, u[i + 1] * I.z)
        Pi = points[-1].locatenew(f"P{i + 1}", ln[i] * Bi.x)
        Pi.v2pt_theory(points[-1], I, Bi)
        points.append(Pi)
        particles.append(me.Particle(f"Pa{i + 1}", Pi, m[i + 1]))
        forces.append((Pi, -m[i + 1] * g * I.y))
        kindiffs.append(q[i + 1].diff(t) - u[i + 1])
    kane = me.KanesMethod(I, q_ind=q, u_ind=u, kd_eqs=kindiffs)
    kane.kanes_equations(particles, forces)
    return kane, q, u, [g, *m, *ln]


def cart_pendulum_values(n):
    """The classic example's numbers (links of 1/n m, bobs and cart of 0.01/n
    kg) and a start with the chain hanging, every link turned 0.3 rad from the
    downward vertical (q = -pi/2 + 0.3), at rest.

    The classic start (every link pointing up, speeds 1e-3) is chaotic at
    once: two DOP853 solutions at rtol 1e-12 and 1e-13 differ by 2e-4 (n = 5)
    and 11 (n = 10) at t = 2, so a final-time error measures nothing there;
    from this start they agree to 2e-12 (n = 5) and 9e-12 (n = 10) at t = 10.
    """
    vals = {"g": G, "m0": 0.01 / n}
    vals.update({f"m{i + 1}": 0.01 / n for i in range(n)})
    vals.update({f"l{i}": 1.0 / n for i in range(n)})
    y0 = np.concatenate([[0.0], np.full(n, -np.pi / 2 + 0.3), np.zeros(n + 1)])
    return vals, y0


# --------------------------------------------------------------------------- helpers

def _err(y, ref):
    return float(np.max(np.abs(np.asarray(y) - ref)))


def _paired_times(fns, repeat=41):
    """Median wall time of each of ``fns``, called in alternation (after one
    warm-up each), so that a change in the machine's load falls on all alike."""
    for f in fns:
        f()
    times = [[] for _ in fns]
    for _ in range(repeat):
        for f, ts in zip(fns, times):
            t0 = time.perf_counter()
            f()
            ts.append(time.perf_counter() - t0)
    return [float(np.median(ts)) for ts in times]


def _pydy_generator():
    """PyDy's Cython generator with its code generation and compilation timed
    apart (``timings``), or None when Cython is missing."""
    try:
        from pydy.codegen.cython_code import CythonMatrixGenerator
        from pydy.codegen.ode_function_generators import CythonODEFunctionGenerator
        import Cython  # noqa: F401
    except ImportError:
        return None

    class Timed(CythonODEFunctionGenerator):
        timings: dict = {}

        def _cythonize(self, outputs, inputs):
            t0 = time.perf_counter()
            g = CythonMatrixGenerator(inputs, outputs, prefix=self._options["prefix"],
                                      cse=self._options["cse"])   # CSE and C printing
            t1 = time.perf_counter()
            f = g.compile(tmp_dir=self._options["tmp_dir"])          # Cython, cc, import
            Timed.timings.update(codegen=t1 - t0, compile=time.perf_counter() - t1)
            return f
    return Timed


class _Stages:
    """Times the stages of ``mp.lagrangian`` (derivation, C printing, compiling
    and loading) by wrapping the functions it calls, within a ``with`` block
    that points ``MECHPY_CACHE_DIR`` at a new empty folder (``cache``, removed
    on exit), so that a first build compiles.  ``seconds`` maps "derive",
    "codegen", "compile" to the time spent in each (a stage whose function is
    not found is absent) and "total" to the block's time."""

    def __init__(self):
        self.seconds = {}
        self._saved = []

    def _wrap(self, mod, name, stage):
        fn = getattr(mod, name, None)
        if fn is None:
            return

        def timed(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.seconds[stage] = self.seconds.get(stage, 0.0) + time.perf_counter() - t0
        self._saved.append((mod, name, fn))
        setattr(mod, name, timed)

    def __enter__(self):
        from mechpy.symbolic import build, codegen, derive
        self._dir = tempfile.TemporaryDirectory(prefix="mechpy-cache-")
        self.cache = self._dir.name
        self._old = os.environ.get("MECHPY_CACHE_DIR")
        os.environ["MECHPY_CACHE_DIR"] = self.cache
        self._wrap(derive, "lagrangian_ir", "derive")
        self._wrap(codegen, "c_source", "codegen")
        self._wrap(build, "build", "compile")
        self._t0 = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.seconds["total"] = time.perf_counter() - self._t0
        for mod, name, fn in reversed(self._saved):
            setattr(mod, name, fn)
        if self._old is None:
            del os.environ["MECHPY_CACHE_DIR"]
        else:
            os.environ["MECHPY_CACHE_DIR"] = self._old
        self._dir.cleanup()
        return False


def cache_build_time(cache: str, setup: str, call: str) -> float:
    """Seconds taken by ``call`` (an ``mp.lagrangian(...)``) in a new process
    whose cache folder already holds the system; the imports and ``setup``
    (writing L) are not counted.  Bytecode caching is left on (as in an
    installed package), so that from the second process on the modules that
    ``call`` imports load from their ``.pyc``."""
    prog = ("import time, json, mechpy as mp\n"
            "from mechpy.benches.own import *\n"
            f"{setup}\n"
            f"t0 = time.perf_counter(); {call}\n"
            "print(json.dumps(time.perf_counter() - t0))\n")
    env = dict(os.environ, MECHPY_CACHE_DIR=cache)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    out = subprocess.run([sys.executable, "-c", prog], env=env, capture_output=True,
                         text=True, check=True)
    return float(json.loads(out.stdout.strip().splitlines()[-1]))


# --------------------------------------------------------------------------- sections

def _pendulum_rows(rtols):
    from scipy.special import ellipj, ellipk

    import mechpy as mp
    theta0, T = 2.5, 10.0
    k = np.sin(theta0 / 2)
    sn, cn, _, _ = ellipj(ellipk(k * k) - np.sqrt(G) * T, k * k)
    ref = np.array([2 * np.arcsin(k * sn), -2 * k * np.sqrt(G) * cn])
    L, q = pendulum_lagrangian()
    own = mp.lagrangian(L, q, params={"g": G, "l": 1.0})
    hand = mp.scenes.Pendulum(g=G, length=1.0)
    y0 = np.array([theta0, 0.0])
    problem = "pendulum theta0=2.5, t=10: compiled Lagrangian vs Pendulum (exact elliptic)"
    rows = []
    for rtol in rtols:
        fns = [lambda sc=sc: mp.solve(sc, (0, T), y0, rtol=rtol, atol=rtol * 1e-3)
               for sc in (own, hand)]
        times = _paired_times(fns, repeat=41)
        for (impl, path), fn, t in zip((("mechpy dop853 (compiled Lagrangian)", "lagrangian"),
                                        ("mechpy dop853 (Pendulum, hand-written C)", "scene")),
                                       fns, times):
            s = fn()
            rows.append(dict(problem=problem, impl=impl, path=path, method="dop853", rtol=rtol,
                             error=_err(s.y[:, -1], ref), nfev=int(s.nfev), time=t,
                             note="timed in alternation with the other row"))
    return rows


def _double_pendulum_rows(rtols):
    from scipy.integrate import solve_ivp

    import mechpy as mp
    from mechpy._timing import median_time
    L, q = double_pendulum_lagrangian()
    own = mp.lagrangian(L, q, params=DP_PARAMS)
    ref = mp.solve(own, (0, DP_T), DP_Y0, rtol=1e-14, atol=1e-16).y[:, -1]
    check = mp.solve(own, (0, DP_T), DP_Y0, method="gsl:rk8pd", rtol=1e-14,
                     atol=1e-16).y[:, -1]
    assert _err(ref, check) < 1e-10, "reference solutions disagree"
    f = double_pendulum_sympy()
    # the lambdified equations describe the same system: one tight solve of them
    tight = solve_ivp(f, (0, DP_T), DP_Y0, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
    note = f"reference: dop853 at 1e-14 (rk8pd {_err(ref, check):.0e}, lambdified DOP853 " \
           f"at 1e-12 {_err(ref, tight):.0e})"
    problem = "double pendulum (1, 0.5) rad, t=10: compiled Lagrangian vs SymPy lambdify"
    rows = []
    for rtol in rtols:
        atol = rtol * 1e-3
        cases = [("mechpy dop853 (compiled Lagrangian)", "lagrangian", "dop853",
                  lambda: mp.solve(own, (0, DP_T), DP_Y0, rtol=rtol, atol=atol)),
                 ("mechpy dopri5 (compiled Lagrangian)", "lagrangian", "dopri5",
                  lambda: mp.solve(own, (0, DP_T), DP_Y0, method="dopri5", rtol=rtol,
                                   atol=atol)),
                 ("lambdify + solve_ivp DOP853", "sympy", "dop853",
                  lambda: solve_ivp(f, (0, DP_T), DP_Y0, method="DOP853", rtol=rtol, atol=atol)),
                 ("lambdify + solve_ivp RK45", "sympy", "dopri5",
                  lambda: solve_ivp(f, (0, DP_T), DP_Y0, method="RK45", rtol=rtol, atol=atol)),
                 ("lambdify + solve_ivp LSODA", "sympy", "lsoda",
                  lambda: solve_ivp(f, (0, DP_T), DP_Y0, method="LSODA", rtol=rtol, atol=atol))]
        for impl, path, method, fn in cases:
            if rtol < 1e-8 and path == "sympy" and method == "dopri5":
                continue  # a 5th-order method below 1e-8 takes seconds in Python
            s = fn()
            rows.append(dict(problem=problem, impl=impl, path=path, method=method, rtol=rtol,
                             error=_err(s.y[:, -1], ref), nfev=int(s.nfev), note=note,
                             time=median_time(fn, repeat=7 if path == "lagrangian" else 3,
                                              budget=1.0)))
    return rows


def _ensemble_rows(quick):
    """Ensembles of compiled systems, 1 thread, dop853 at rtol 1e-8: the double
    pendulum in SIMD lanes (its generated lane rhs), on the scalar path, and a
    Python loop of ``solve_ivp`` on the lambdified equations (a subset, scaled);
    the compiled pendulum beside the C scene ``Pendulum``, both in lanes."""
    from scipy.integrate import solve_ivp

    import mechpy as mp
    from mechpy._timing import median_time
    k = 1000 if quick else 4000
    rtol, atol = 1e-8, 1e-10
    te = np.linspace(0, DP_T, 11)
    L, q = double_pendulum_lagrangian()
    own = mp.lagrangian(L, q, params=DP_PARAMS)
    y0s = np.column_stack([np.linspace(-1.5, 1.5, k), np.linspace(1.0, -1.0, k),
                           np.zeros(k), np.zeros(k)])
    ref = mp.solve_many(own, (0, DP_T), y0s, t_eval=te, rtol=1e-13, atol=1e-15,
                        lanes=False).y[:, :, -1]
    problem = (f"{k} double pendulums, t=10, rtol=1e-8, dop853, 1 thread: compiled "
               "Lagrangian in lanes vs scalar vs SymPy lambdify + solve_ivp")
    rows = []
    for lanes, tag in ((True, "lanes"), (False, "scalar")):
        def fn(lanes=lanes):
            return mp.solve_many(own, (0, DP_T), y0s, t_eval=te, rtol=rtol, atol=atol,
                                 threads=1, lanes=lanes)
        rows.append(dict(problem=problem, impl=f"mechpy solve_many, {tag} (compiled Lagrangian)",
                         path=f"own-ensemble-{tag}", method="dop853", rtol=rtol,
                         time=median_time(fn, repeat=5),
                         error=_err(fn().y[:, :, -1], ref)))
    f = double_pendulum_sympy()
    sub = 10 if quick else 40
    idx = np.linspace(0, k - 1, sub).astype(int)

    def loop():
        return [solve_ivp(f, (0, DP_T), y0s[i], method="DOP853", rtol=rtol, atol=atol,
                          t_eval=te).y[:, -1] for i in idx]
    t0 = time.perf_counter()
    ends = loop()
    rows.append(dict(problem=problem, impl="Python loop of lambdify + solve_ivp DOP853",
                     path="own-ensemble-loop", method="dop853", rtol=rtol,
                     time=(time.perf_counter() - t0) * k / sub, error=_err(ends, ref[idx]),
                     note=f"{sub} trajectories timed, scaled to {k}"))

    Lp, qp = pendulum_lagrangian()
    pend = mp.lagrangian(Lp, qp, params={"g": G, "l": 1.0})
    hand = mp.scenes.Pendulum(g=G, length=1.0)
    y0p = np.column_stack([np.linspace(0.1, 3.0, k), np.zeros(k)])
    problem = f"{k} pendulums, t=10, rtol=1e-8, dop853, 1 thread, in lanes: compiled vs C scene"
    refp = mp.solve_many(hand, (0, DP_T), y0p, t_eval=te, rtol=1e-13, atol=1e-15,
                         lanes=False).y[:, :, -1]
    fns = [lambda sc=sc: mp.solve_many(sc, (0, DP_T), y0p, t_eval=te, rtol=rtol, atol=atol,
                                       threads=1, lanes=True) for sc in (pend, hand)]
    times = _paired_times(fns, repeat=9 if quick else 21)
    for (impl, path), fn, t in zip((("mechpy solve_many, lanes (compiled Lagrangian)",
                                     "own-pendulum-lanes"),
                                    ("mechpy solve_many, lanes (Pendulum, hand-written C)",
                                     "scene-pendulum-lanes")), fns, times):
        rows.append(dict(problem=problem, impl=impl, path=path, method="dop853", rtol=rtol,
                         time=t, error=_err(fn().y[:, :, -1], refp),
                         note="timed in alternation with the other row"))
    return rows


def _build_rows():
    """First build of the double pendulum in an empty cache folder, in this
    process, by stage; the build from the cache in a new process and again in
    this one; SymPy's derivation and lambdify beside them."""
    import mechpy as mp
    rows = []
    problem = "double pendulum: building the system"
    L, q = double_pendulum_lagrangian()
    st = _Stages()
    with st:
        t0 = time.perf_counter()
        mp.lagrangian(L, q, params=DP_PARAMS)
        t1 = time.perf_counter()
        first = dict(st.seconds)
        mp.lagrangian(L, q, params=DP_PARAMS)
        first_total, again = t1 - t0, time.perf_counter() - t1
        cached = min(cache_build_time(st.cache, "L, q = double_pendulum_lagrangian()",
                                       "mp.lagrangian(L, q, params=DP_PARAMS)")
                     for _ in range(3))
    stages = ", ".join(f"{k} {first[k]:.3f} s" for k in ("derive", "codegen", "compile")
                       if k in first)
    rows.append(dict(problem=problem, impl="mp.lagrangian, first build (empty cache folder)",
                     path="build-first", time=first_total,
                     error=float("nan"), note=stages))
    rows.append(dict(problem=problem, impl="mp.lagrangian from the cache (new process)",
                     path="build-cache", time=cached, error=float("nan"),
                     note="best of 3 processes; imports and writing L not counted"))
    rows.append(dict(problem=problem, impl="mp.lagrangian again in the same process",
                     path="build-again", time=again, error=float("nan")))
    t0 = time.perf_counter()
    double_pendulum_sympy()
    rows.append(dict(problem=problem, impl="SymPy: Euler-Lagrange, solve, lambdify",
                     path="build-sympy", time=time.perf_counter() - t0, error=float("nan")))
    return rows


def _cart_rows(n, rtols, T):
    """PyDy (Kane's method, Cython or lambdify backend, odeint as
    ``System.integrate`` runs it) beside mp.lagrangian on the n-link pendulum
    on a cart; each stage timed once, integration as a median."""
    from scipy.integrate import odeint, solve_ivp

    import mechpy as mp
    from mechpy._timing import median_time
    problem = f"{n}-link pendulum on a cart, t={T:g}: mechpy vs PyDy"
    vals, y0 = cart_pendulum_values(n)
    rows = []

    def stage(impl, path, seconds, note=""):
        rows.append(dict(problem=problem, impl=impl, path=path, time=seconds,
                         error=float("nan"), note=note))

    # mechpy: derivation, C printing and compilation inside mp.lagrangian, in
    # an empty cache folder
    L, q = cart_pendulum_lagrangian(n)
    st = _Stages()
    with st:
        own = mp.lagrangian(L, q, params=vals)
    sec = st.seconds
    for k, label in (("derive", "derivation (Euler-Lagrange blocks)"),
                     ("codegen", "code generation (CSE, C printing)"),
                     ("compile", "compilation (cc, load)")):
        if k in sec:
            stage(f"mechpy: {label}", "mechpy-stage", sec[k])
    stage("mechpy: mp.lagrangian in all", "mechpy-stage", sec["total"], note="first build")

    # PyDy: Kane's method, then its code generation and compilation
    from pydy.codegen.ode_function_generators import generate_ode_function
    t0 = time.perf_counter()
    kane, qs, us, consts = cart_pendulum_pydy(n)
    stage("PyDy: KanesMethod (derivation)", "pydy-stage", time.perf_counter() - t0)
    Timed = _pydy_generator()
    backend = "cython"
    t0 = time.perf_counter()
    try:
        if Timed is None:
            raise ImportError("Cython is not installed")
        rhs = generate_ode_function(kane.forcing_full, qs, us, consts,
                                    mass_matrix=kane.mass_matrix_full, generator=Timed)
        tg = dict(Timed.timings)
    except Exception as exc:  # no Cython or no compiler: PyDy's default backend
        backend = f"lambdify ({type(exc).__name__})"
        t0 = time.perf_counter()
        rhs = generate_ode_function(kane.forcing_full, qs, us, consts,
                                    mass_matrix=kane.mass_matrix_full)
        tg = dict(codegen=time.perf_counter() - t0, compile=0.0)
    total = time.perf_counter() - t0
    stage(f"PyDy: code generation ({backend})", "pydy-stage", tg["codegen"],
          note="CSE and C printing" if backend == "cython" else "lambdify")
    stage(f"PyDy: compilation ({backend})", "pydy-stage", tg["compile"],
          note=("Cython + cc; " if backend == "cython" else "nothing to compile; ")
          + f"generate_ode_function in all {total:.2f} s")
    p = np.array([vals[str(c)] for c in consts])

    # the reference: mechpy dop853 at 1e-13, checked against PyDy's own equations
    ref = mp.solve(own, (0, T), y0, rtol=1e-13, atol=1e-15).y[:, -1]
    chk = solve_ivp(lambda t, x: rhs(x, t, p), (0, T), y0, method="DOP853", rtol=1e-12,
                    atol=1e-14).y[:, -1]
    note = f"reference: mechpy dop853 at 1e-13; PyDy's equations by DOP853 at 1e-12 " \
           f"differ by {_err(ref, chk):.0e}"
    for rtol in rtols:
        atol = rtol * 1e-3
        f_mp = lambda: mp.solve(own, (0, T), y0, rtol=rtol, atol=atol)  # noqa: E731
        f_py = lambda: odeint(rhs, y0, [0.0, T], args=(p,), rtol=rtol, atol=atol,  # noqa: E731
                              mxstep=10**7)
        s = f_mp()
        rows.append(dict(problem=problem, impl="mechpy dop853 (compiled Lagrangian)",
                         path="lagrangian", method="dop853", rtol=rtol,
                         error=_err(s.y[:, -1], ref), nfev=int(s.nfev), note=note,
                         time=median_time(f_mp, repeat=5, budget=1.0)))
        rows.append(dict(problem=problem, impl=f"PyDy {backend} + odeint", path="pydy",
                         method="lsoda", rtol=rtol, error=_err(f_py()[-1], ref), note=note,
                         time=median_time(f_py, repeat=3, budget=2.0)))
    return rows


def run(quick: bool) -> list[dict]:
    rtols = [1e-4, 1e-7, 1e-10] if quick else [1e-3, 1e-5, 1e-7, 1e-9, 1e-11, 1e-13]
    rows = _pendulum_rows(rtols)
    rows += _double_pendulum_rows(rtols)
    rows += _ensemble_rows(quick)
    rows += _build_rows()
    try:
        import pydy  # noqa: F401
    except ImportError:
        print("  PyDy is not installed (pip install pydy cython): no n-link pendulum rows")
        return rows
    for n in ((5,) if quick else (5, 10)):
        rows += _cart_rows(n, [1e-6, 1e-9] if quick else [1e-5, 1e-7, 1e-9, 1e-11],
                           T=5.0 if quick else 10.0)
    return rows


# --------------------------------------------------------------------------- targets

def _ok(r):
    e = r.get("error")
    return isinstance(e, float) and e > 0 and not math.isnan(e)


def targets(rows) -> list[dict]:
    """This section's overhead-budget lines, computed from its rows.

    * compiled Lagrangian pendulum against ``Pendulum``, same method and rtol:
      time ratio (worst = largest), goal <= 1.25x;
    * compiled scene against lambdify + ``solve_ivp`` and against PyDy at equal
      error: for each of their runs the fastest compiled-scene run of the same
      problem with no larger error (ratio of their time to ours);
    * the ensembles: lanes against the scalar path and against the Python loop
      (time ratios), the compiled pendulum against ``Pendulum`` in lanes;
    * first build and build from the cache (seconds).
    """
    out = []
    problems = list(dict.fromkeys(r["problem"] for r in rows))
    for p in problems:
        pr = [r for r in rows if r["problem"] == p]
        own = [r for r in pr if r.get("path") == "lagrangian"]
        hand = {(r["method"], r["rtol"]): r["time"] for r in pr if r.get("path") == "scene"}
        rs = sorted(r["time"] / hand[(r["method"], r["rtol"])] for r in own
                    if (r["method"], r["rtol"]) in hand)
        if rs:
            out.append(dict(target="compiled Lagrangian / hand-written scene, same method "
                            "and rtol (time ratio)", problem=p, goal="<= 1.25x",
                            worst=rs[-1], median=rs[len(rs) // 2], n=len(rs)))
        for theirs, label, goal in (("sympy", "compiled Lagrangian vs SymPy lambdify + "
                                     "solve_ivp at equal error", ">= 100x"),
                                    ("pydy", "compiled Lagrangian vs PyDy + odeint at equal "
                                     "error", "(none)")):
            pairs = []
            for q in (r for r in pr if r.get("path") == theirs and _ok(r)):
                fit = [r["time"] for r in own if _ok(r) and r["error"] <= q["error"]]
                if fit:
                    pairs.append(q["time"] / min(fit))
            pairs.sort()
            if pairs:
                out.append(dict(target=label, problem=p, goal=goal, worst=pairs[0],
                                median=pairs[len(pairs) // 2], n=len(pairs)))
    by = {r.get("path"): r for r in rows if r.get("path")}
    for a, b, label, goal in (
            ("own-ensemble-scalar", "own-ensemble-lanes",
             "compiled ensemble in lanes vs one solve per trajectory, 1 thread", ">= 2x"),
            ("own-ensemble-loop", "own-ensemble-lanes",
             "compiled ensemble vs a Python loop of lambdify + solve_ivp", ">= 100x"),
            ("own-pendulum-lanes", "scene-pendulum-lanes",
             "compiled pendulum / hand-written scene, ensemble in lanes (time ratio)",
             "<= 1.25x")):
        if a in by and b in by:
            v = by[a]["time"] / by[b]["time"]
            out.append(dict(target=label, problem=by[b]["problem"], goal=goal, worst=v,
                            median=v, n=1))
    for path, label, goal in (("build-first", "first build, empty cache (seconds)", "< 2 s"),
                              ("build-cache", "build from the cache, new process (seconds)",
                               "< 0.05 s")):
        for r in rows:
            if r.get("path") == path:
                out.append(dict(target=label, problem=r["problem"], goal=goal, worst=r["time"],
                                median=r["time"], n=1, unit=" s"))
    return out
