"""mp.solve_many in SIMD lanes (csrc/ode/lanes.c) against the scalar path.

Each lane repeats the scalar driver's decisions; fused multiply-adds and
libmvec's sin/cos round differently, so samples agree to round-off amplified
by the flow, and statuses, messages (the times in them to that rounding, with
their sign) and evaluation counts agree.
"""
import re
import sys

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

S = mp.scenes
LANES = 8   # MP_LANES in csrc/ode/lanes.h: trajectories in one lane group

# one instance of every scene (the walk below checks none is missing), a start,
# and the relative spread of the ensemble's starts around it
CASES = {
    "Pendulum": (S.Pendulum(), [1.0, 0.0], 1e-2),
    "Pendulum driven": (S.Pendulum(damping=0.1, drive_amplitude=0.5, drive_frequency=1.2),
                        [1.0, 0.0], 1e-2),
    "VanDerPol": (S.VanDerPol(mu=1.0), [2.0, 0.0], 1e-2),
    "Duffing": (S.Duffing(alpha=-1.0, beta=1.0, delta=0.2, gamma=0.3, omega=1.2), [1.0, 0.0],
                1e-2),
    "Kepler": (S.Kepler(), [1.0, 0.0, 0.0, 1.1], 1e-2),
    # Arenstorf's orbit: a spread of 1e-2 sends starts into the primaries, where
    # round-off grows to the method's error on either path
    "RestrictedThreeBody": (S.RestrictedThreeBody(), [0.994, 0.0, 0.0, -2.00158510637908],
                            1e-6),
    "Foucault": (S.Foucault(latitude=45.0, length=10.0), [0.1, 0.0, 0.0, 0.0], 1e-2),
    "RigidBody": (S.RigidBody(), [1.0, 0.1, 0.2], 1e-2),
    "HeavyTop": (S.HeavyTop(I1=1.0, I3=0.5, mass=1.0), [0.0, 0.5, 0.0, 0.0, 0.0, 10.0], 1e-2),
    "SpringChain": (S.SpringChain(masses=[1.0, 1.0, 1.0]), [0.1, 0.0, -0.1, 0.0, 0.0, 0.0],
                    1e-2),
    "Rocket": (S.Rocket(exhaust_speed=2000.0, burn_rate=10.0, m0=1000.0, m_dry=200.0),
               [0.0, 0.0, 1000.0], 1e-2),
}
METHODS = {"dop853": {}, "dopri5": {}, "rk4": {"h": 1e-3}}


def _compiled_pendulum():
    x, v = mp.coordinates("x v")
    return mp.equations([v, -sp.sin(x)], [x, v])


def _both(system, t_span, y0s, **kw):
    a = mp.solve_many(system, t_span, y0s, lanes=True, **kw)
    b = mp.solve_many(system, t_span, y0s, lanes=False, **kw)
    assert a.lanes and not b.lanes
    return a, b


def _starts(y0, spread, k):
    return np.asarray(y0, float) * (1 + spread * np.linspace(-1, 1, k))[:, None]


def _rel_diff(a, b, rows=slice(None)):
    ya, yb = a.y[rows], b.y[rows]
    scale = np.maximum(np.max(np.abs(yb), axis=(0, 2)), 1e-300)
    return float(np.max(np.abs(ya - yb) / scale[None, :, None]))


_TIME = re.compile(r"t = ([-+0-9.e]+)")


def _same_messages(a, b, rtol=3e-5):
    """Messages of the lanes (a) and of the scalar path (b): the same text, and
    the times in them (where a failure happened) the same to rounding amplified
    by the flow: relative rtol, the same sign (a backward solve fails at t < 0).
    The step sizes follow error estimates that are differences of nearly equal
    stages, so the rounding of the lanes' sin/cos moves a time after a few steps
    (measured 5.6e-10 after 5 steps of a pendulum, 3.7e-6 after 188 steps of one
    started near the separatrix; a step is ~1e-2 of these spans, a sign flips it)."""
    assert len(a) == len(b)
    for ma, mb in zip(a, b):
        assert _TIME.sub("t = ?", ma) == _TIME.sub("t = ?", mb), (ma, mb)
        ta = [float(x) for x in _TIME.findall(ma)]
        tb = [float(x) for x in _TIME.findall(mb)]
        for x, y in zip(ta, tb):
            assert np.sign(x) == np.sign(y) and abs(x - y) <= rtol * max(abs(y), 1e-300), \
                (ma, mb)


def _message_times(messages):
    """The time in each message (NaN where it names none)."""
    return np.array([float(m[0]) if (m := _TIME.findall(msg)) else np.nan
                     for msg in messages])


def _same_fields(a, b, rel=3e-12, rtol_t=3e-5):
    """Every field of the lanes' result (a) against the scalar path's (b)."""
    assert a.lanes and not b.lanes
    assert np.array_equal(a.t, b.t)
    assert np.array_equal(a.status, b.status) and np.array_equal(a.success, b.success)
    assert np.array_equal(a.nfev, b.nfev)
    _same_messages(a.message, b.message, rtol_t)
    assert np.array_equal(np.isnan(a.y), np.isnan(b.y))
    ok = ~np.isnan(b.y)
    if ok.any():
        scale = np.maximum(np.max(np.abs(np.where(ok, b.y, 0.0)), axis=(0, 2)), 1e-300)
        assert np.max((np.abs(a.y - b.y) / scale[None, :, None])[ok]) < rel


def test_cases_cover_every_scene():
    # the C scenes (a row of the scene table); compiled scenes are cased apart
    classes = {c.__name__ for c in S.Scene.__subclasses__() if getattr(c, "_model", None)}
    assert classes <= {type(s).__name__ for s, _, _ in CASES.values()}


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("name", sorted(CASES) + ["compiled"])
def test_lanes_agree_with_scalar_path(name, method):
    if name == "compiled":
        system, y0, spread = _compiled_pendulum(), [1.0, 0.0], 1e-2
    else:
        system, y0, spread = CASES[name]
    te = np.linspace(0, 2, 5)
    if name == "Rocket":   # burn-out is a switch the engine crosses as an event: scalar path
        y0s = _starts(y0, spread, 37)
        with pytest.raises(ValueError, match="switch"):
            mp.solve_many(system, (0, 2), y0s, t_eval=te, method=method, lanes=True,
                          **METHODS[method])
        e = mp.solve_many(system, (0, 2), y0s, t_eval=te, method=method, **METHODS[method])
        assert not e.lanes
        return
    a, b = _both(system, (0, 2), _starts(y0, spread, 37), t_eval=te, method=method,
                 **METHODS[method])
    # measured: at most 2.5e-13 (Pendulum, dopri5); 0 for most rk4 cases
    assert _rel_diff(a, b) < 3e-12
    assert np.array_equal(a.status, b.status) and a.success.all()
    assert np.array_equal(a.nfev, b.nfev)
    assert np.array_equal(a.t, b.t)


def test_backward_and_params_in_lanes():
    p = S.Pendulum()
    k = 21
    y0s = _starts([1.0, 0.3], 0.2, k)
    params = {"length": np.linspace(0.5, 2.0, k), "drive_amplitude": np.linspace(0, 1, k),
              "drive_frequency": np.full(k, 1.3)}
    te = np.linspace(3, -3, 7)
    a, b = _both(p, (3, -3), y0s, t_eval=te, params=params)
    assert _rel_diff(a, b) < 3e-12   # measured 3e-14
    assert np.array_equal(a.nfev, b.nfev)
    for i in (0, 10, 20):   # each lane's own parameters
        row = {n: float(v[i]) for n, v in params.items()}
        s = mp.solve(p.replace(**row), (3, -3), y0s[i], t_eval=te)
        assert np.max(np.abs(s.y - a.y[i])) < 1e-10   # measured 1e-14


def test_thread_count_does_not_change_lanes():
    y0s = _starts([1.0, 0.0], 0.5, 53)
    te = np.linspace(0, 5, 6)
    a = mp.solve_many(S.Pendulum(), (0, 5), y0s, t_eval=te, threads=1, lanes=True)
    b = mp.solve_many(S.Pendulum(), (0, 5), y0s, t_eval=te, threads=2, lanes=True)
    assert np.array_equal(a.y, b.y) and np.array_equal(a.nfev, b.nfev)


# ---- statuses: failures in the middle of a lane group, refill --------------------

@pytest.mark.parametrize("k", [1, LANES - 1, LANES + 1, 37])
def test_step_budget_per_lane(k):
    """Starts of growing amplitude need more steps: a budget between them fails
    some lanes early, their slots take the next trajectories."""
    y0s = np.column_stack([np.linspace(0.1, 3.1, k)[::-1], np.zeros(k)])
    te = np.linspace(0, 20, 9)
    full = mp.solve_many(S.Pendulum(), (0, 20), y0s, t_eval=te, lanes=False)
    budget = int(np.median(full.nfev) / 12) if k > 1 else 5
    kw = dict(t_eval=te, max_steps=budget, errors="status")
    a, b = _both(S.Pendulum(), (0, 20), y0s, **kw)
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    if k >= LANES:
        assert 0 < np.sum(a.status == -1) < k   # some ran out, some finished
    _same_messages(a.message, b.message)
    assert np.array_equal(np.isnan(a.y), np.isnan(b.y))   # samples past a failure are NaN
    ok = ~np.isnan(b.y)
    assert np.max(np.abs(a.y[ok] - b.y[ok]), initial=0.0) < 1e-10   # measured 2e-13


@pytest.mark.parametrize("k", [1, LANES - 1, LANES + 1, 37])
def test_singular_heavy_top_in_a_lane_group(k):
    """theta = 0 is singular for the top's Euler angles: those lanes fail at
    once (SingularityError's status) while their neighbours run to the end."""
    top = S.HeavyTop(I1=1.0, I3=0.5, mass=1.0)
    y0s = _starts([0.0, 0.5, 0.0, 0.0, 0.0, 10.0], 0.1, k)
    y0s[k // 2, 1] = 0.0
    if k > 3:
        y0s[3, 1] = 0.0
    te = np.linspace(0, 1, 3)
    a, b = _both(top, (0, 1), y0s, t_eval=te, errors="status")
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    bad = y0s[:, 1] == 0.0
    assert (a.status[bad] == -3).all() and (a.status[~bad] == 0).all()
    _same_messages(a.message, b.message)
    assert np.isnan(a.y[bad]).all()
    if (~bad).any():
        assert _rel_diff(a, b, ~bad) < 3e-12   # measured 4e-14
    first = min(k // 2, 3) if k > 3 else k // 2
    with pytest.raises(mp.SingularityError, match=rf"trajectory {first}:"):
        mp.solve_many(top, (0, 1), y0s, t_eval=te, lanes=True)


@pytest.mark.parametrize("method, kw", [("dopri5", {}), ("rk4", {"h": 1e8}), ("dop853", {})])
def test_an_overflowing_state_fails_a_lane_as_it_fails_a_lone_solve(method, kw):
    """x' = 1e300 is finite everywhere, and x = 1e300 t overflows at t = 1.8e8
    (dop853: its error estimate overflows first): each lane stops where and as
    the lone solve stops, naming the same cause."""
    x, v = mp.coordinates("x v")
    s = mp.equations([sp.Float(1e300) + 0 * v, 0 * x], [x, v])
    lone = mp.solve(s, (0, 1e10), [0.0, 0.0], method=method, errors="status", **kw)
    assert lone.status == -2 and "right-hand side gave" not in lone.message
    a, b = _both(s, (0, 1e10), np.zeros((3, 2)), method=method, errors="status", **kw)
    assert list(a.status) == list(b.status) == [-2] * 3
    _same_messages(a.message, b.message)
    assert all(m == lone.message for m in b.message)


def test_blow_up_of_compiled_equations():
    """y' = y^2 from y0 > 0 leaves every float at t = 1/y0: the lanes that
    start above 2/3 fail within (0, 1.5) as the scalar path fails them."""
    (y,) = mp.coordinates("y")
    s = mp.equations([y ** 2], [y])
    y0s = np.linspace(-1.0, 1.0, 36)[:, None]
    te = np.linspace(0, 1.5, 4)
    a, b = _both(s, (0, 1.5), y0s, t_eval=te, errors="status")
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    blows = y0s[:, 0] > 1 / 1.5
    assert (a.status[blows] < 0).all() and (a.status[~blows] == 0).all()
    _same_messages(a.message, b.message)
    assert np.array_equal(np.isnan(a.y), np.isnan(b.y))
    with np.errstate(divide="ignore"):
        exact = (y0s / (1 - y0s * te[None, :]))[:, None, :]
    ok = ~np.isnan(b.y) & np.isfinite(exact)
    rel = np.abs(a.y[ok] - exact[ok]) / np.maximum(np.abs(exact[ok]), 1.0)
    assert np.max(rel) < 1e-6   # measured 8e-8 (the samples nearest the pole)


def test_t_eval_samples_at_the_same_times():
    te = np.array([0.0, 0.013, 0.5, 1.25, 3.0 - 1e-12, 3.0])
    y0s = _starts([1.0, 0.0], 0.5, 11)
    a, b = _both(S.Duffing(alpha=1.0, beta=0.5), (0, 3), y0s, t_eval=te)
    assert np.array_equal(a.t, te)
    assert np.array_equal(a.y[:, :, 0], y0s)   # the start is copied, not computed
    assert _rel_diff(a, b) < 3e-12   # measured 2e-15


# ---- the forced scalar path and the choice ------------------------------------------

def test_forced_scalar_path_is_bit_identical_to_solve(monkeypatch):
    y0s = _starts([1.0, 0.2], 0.5, 10)
    te = np.linspace(0, 4, 9)
    off = mp.solve_many(S.Pendulum(), (0, 4), y0s, t_eval=te, lanes=False)
    monkeypatch.setenv("MECHPY_LANES", "0")
    env = mp.solve_many(S.Pendulum(), (0, 4), y0s, t_eval=te)
    assert not off.lanes and not env.lanes
    for i in (0, 5, 9):
        s = mp.solve(S.Pendulum(), (0, 4), y0s[i], t_eval=te)
        assert np.array_equal(off.y[i], s.y) and np.array_equal(env.y[i], s.y)
        assert off.nfev[i] == s.nfev
    monkeypatch.delenv("MECHPY_LANES")
    assert mp.solve_many(S.Pendulum(), (0, 4), y0s, t_eval=te).lanes


def test_what_lanes_cannot_do_takes_the_scalar_path():
    y0s = _starts([1.0, 0.0], 0.1, 5)
    assert not mp.solve_many(S.Pendulum(), (0, 1), y0s, method="radau").lanes
    assert not mp.solve_many(lambda t, y: [y[1], -y[0]], (0, 1), y0s).lanes
    with pytest.raises(ValueError, match="lanes=True needs"):
        mp.solve_many(S.Pendulum(), (0, 1), y0s, method="radau", lanes=True)
    with pytest.raises(ValueError, match="lanes=True needs"):
        mp.solve_many(lambda t, y: [y[1], -y[0]], (0, 1), y0s, lanes=True)
    with pytest.raises(TypeError, match="lanes must be"):
        mp.solve_many(S.Pendulum(), (0, 1), y0s, lanes="yes")


def test_empty_ensemble_in_lanes():
    e = mp.solve_many(S.Pendulum(), (0, 1), np.zeros((0, 2)), lanes=True)
    assert e.y.shape == (0, 2, 1)


# ---- compiled systems: the generated lane right-hand side (mp_gen_lanes) -----------

T = sp.Symbol("t")


def _double_pendulum():
    th1, th2 = mp.coordinates("theta1 theta2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
    K = (m1 * (x1.diff(T) ** 2 + y1.diff(T) ** 2) + m2 * (x2.diff(T) ** 2 + y2.diff(T) ** 2)) / 2
    return mp.lagrangian(K - g * (m1 * y1 + m2 * y2), [th1, th2],
                         params=dict(m1=1.3, m2=0.7, l1=1.1, l2=0.8, g=9.81))


def _cartesian_pendulum():
    """A pendulum in (x, y) on the circle x^2 + y^2 = l^2 (a multiplier: NA = 3)."""
    x, y = mp.coordinates("x y")
    m, g, l = sp.symbols("m g l")
    L = m / 2 * (x.diff(T) ** 2 + y.diff(T) ** 2) - m * g * y
    return mp.lagrangian(L, [x, y], params=dict(m=0.8, g=9.81, l=1.0),
                         constraints=[x ** 2 + y ** 2 - l ** 2])


def _lagrangian_pendulum():
    """One coordinate, NA = 1: the solve is one division."""
    (th,) = mp.coordinates("theta")
    m, l, g = sp.symbols("m l g")
    return mp.lagrangian(m * l ** 2 / 2 * th.diff(T) ** 2 + m * g * l * sp.cos(th), [th],
                         params=dict(m=1.0, l=1.0, g=9.81))


def _lorenz():
    x, y, z = mp.coordinates("x y z")
    s, r, b = sp.symbols("sigma rho beta")
    return mp.equations([s * (y - x), x * (r - z) - y, x * y - b * z], [x, y, z],
                        params=dict(sigma=10.0, rho=28.0, beta=8 / 3))


def _van_der_pol():
    x, v = mp.coordinates("x v")
    mu = sp.Symbol("mu")
    return mp.equations([v, mu * (1 - x ** 2) * v - x], [x, v], params=dict(mu=1.0))


def _decay():
    """One state."""
    (y,) = mp.coordinates("y")
    a = sp.Symbol("a")
    return mp.equations([-a * y], [y], params=dict(a=0.7))


def _elementary():
    """Every function the lane rhs calls through a vector variant (libmvec),
    and sqrt, powers: a wrong declaration gives wrong values here."""
    x, v = mp.coordinates("x v")
    c = sp.Symbol("c")
    f1 = (sp.sin(x) + sp.cos(v) + sp.tan(x / 3) + sp.exp(-x ** 2) + sp.log(2 + v ** 2)
          + (1 + x ** 2) ** c + sp.asin(x / 4) + sp.acos(v / 5) + sp.atan(x)
          + sp.atan2(v, 1 + x ** 2))
    f2 = (sp.sinh(x / 3) + sp.cosh(v / 4) + sp.tanh(x) + sp.asinh(v) + sp.acosh(2 + x ** 2)
          + sp.atanh(v / 6) + sp.sqrt(1 + v ** 2) - c * (2 + x ** 2) ** sp.Rational(5, 2))
    return mp.equations([f1, f2], [x, v], params=dict(c=1.5))


# name: (system, a start, a spread of starts, per-lane parameter rows relative spread)
COMPILED = {
    "double pendulum": (_double_pendulum, [1.0, -0.5, 0.0, 0.3], 0.3),
    "constrained pendulum": (_cartesian_pendulum,
                             [np.sin(1.0), -np.cos(1.0), np.cos(1.0) * 0.5,
                              np.sin(1.0) * 0.5], None),
    "lagrangian pendulum": (_lagrangian_pendulum, [1.0, 0.2], 0.3),
    "lorenz": (_lorenz, [1.0, 1.0, 20.0], 0.1),
    "van der pol": (_van_der_pol, [2.0, 0.0], 0.5),
    "decay": (_decay, [1.0], 0.5),
    "elementary": (_elementary, [0.3, 0.2], 0.1),
}
_MADE = {}


def _compiled(name):
    if name not in _MADE:
        _MADE[name] = COMPILED[name][0]()
    return _MADE[name]


def _lane_call(s, t, Y, P):
    """mp_gen_lanes on LANES states Y (LANES, n) with parameter rows P
    (LANES, np) -> f (LANES, n), status (LANES,)."""
    import ctypes
    dp = ctypes.POINTER(ctypes.c_double)
    fn = ctypes.CFUNCTYPE(None, dp, dp, dp, dp, ctypes.POINTER(ctypes.c_int))(s._addr_lanes)
    tl = np.ascontiguousarray(np.broadcast_to(t, (LANES,)), dtype=float)
    y = np.ascontiguousarray(Y.T)
    p = np.ascontiguousarray(P.T) if P.size else np.zeros(1)
    f = np.full_like(y, np.nan)
    st = np.full(LANES, -99, dtype=np.intc)
    fn(tl.ctypes.data_as(dp), y.ctypes.data_as(dp), f.ctypes.data_as(dp), p.ctypes.data_as(dp),
       st.ctypes.data_as(ctypes.POINTER(ctypes.c_int)))
    return f.T, st


def _scalar_call(s, t, y, p):
    """mp_gen_rhs at one state -> (f, status)."""
    import ctypes
    dp = ctypes.POINTER(ctypes.c_double)
    fn = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, dp, dp, ctypes.c_void_p)(
        s._addr["rhs"])
    y = np.ascontiguousarray(y, dtype=float)
    p = np.ascontiguousarray(p, dtype=float)
    f = np.full_like(y, np.nan)
    rc = fn(float(t), y.ctypes.data_as(dp), f.ctypes.data_as(dp), p.ctypes.data if p.size else None)
    return f, rc


def _gcc_on_glibc_x86_64():
    import platform
    import subprocess

    from mechpy.symbolic import build
    if platform.machine() != "x86_64" or platform.libc_ver()[0] != "glibc":
        return False
    out = subprocess.run(build.compiler() + ["--version"], capture_output=True, text=True)
    return "Free Software Foundation" in out.stdout


@pytest.mark.skipif(not _gcc_on_glibc_x86_64(), reason="libmvec's variants: GCC, glibc, x86-64")
def test_lane_rhs_is_vectorised():
    """The double pendulum's library calls libmvec's 4-wide AVX2 sin (its
    AVX2+FMA clone) and 2-wide SSE sin (the portable one): the loop over the
    lanes was vectorised."""
    s = _compiled("double pendulum")
    with open(s._path, "rb") as f:
        data = f.read()
    assert b"_ZGVdN4v_sin" in data and b"_ZGVbN2v_sin" in data


def test_compiled_systems_export_a_lane_rhs():
    s = _compiled("lorenz")
    assert hasattr(s._lib, "mp_gen_lanes") and s._addr_lanes
    assert f"#define MP_LANES {mp._core.LANES}" in s.c_source
    assert mp._core.LANES == LANES
    e = mp.solve_many(s, (0, 1), _starts([1.0, 1.0, 20.0], 0.1, 9), t_eval=[0, 1])
    assert e.lanes


@pytest.mark.parametrize("name", sorted(COMPILED))
def test_lane_rhs_equals_eight_scalar_calls(name, rng):
    s = _compiled(name)
    y0 = np.asarray(COMPILED[name][1])
    Y = y0 * (1 + 0.2 * rng.uniform(-1, 1, (LANES, y0.size)))
    if name == "constrained pendulum":   # the rhs holds off the constraint too
        Y = y0 + 0.1 * rng.uniform(-1, 1, (LANES, y0.size))
    P = s._vector() * (1 + 0.3 * rng.uniform(-1, 1, (LANES, s._vector().size)))
    t = rng.uniform(0, 2, LANES)
    f, st = _lane_call(s, t, Y, P)
    assert (st == 0).all()
    worst = 0.0
    for l in range(LANES):
        g, rc = _scalar_call(s, t[l], Y[l], P[l])
        assert rc == 0
        worst = max(worst, np.max(np.abs(f[l] - g)) / np.max(np.abs(g)))
    # measured: at most 7e-16 (vector sin/cos/... and fused multiply-adds
    # against the scalar functions)
    assert worst < 5e-15


def _lane_params(s, k, spread):
    """Parameter rows of k trajectories around the scene's, as a dict."""
    names = list(s.params)
    vec = s._vector()
    rows = vec * (1 + spread * np.linspace(-1, 1, k)[:, None] * np.linspace(1, 0.5, vec.size))
    return {n: rows[:, j] for j, n in enumerate(names)}


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("name", sorted(set(COMPILED) - {"elementary"}))
def test_compiled_lanes_agree_with_scalar_path(name, method):
    s = _compiled(name)
    _, y0, spread = COMPILED[name]
    k = 21
    y0s = (_starts(y0, 0.2, k) if name != "constrained pendulum"
           else np.array([[np.sin(a), -np.cos(a), np.cos(a) * 0.5, np.sin(a) * 0.5]
                          for a in np.linspace(0.5, 1.5, k)]))
    params = _lane_params(s, k, spread) if spread else None
    te = np.linspace(0, 1, 5)
    a, b = _both(s, (0, 1), y0s, t_eval=te, method=method, params=params, **METHODS[method])
    # measured: at most 1.3e-12 (double pendulum, dopri5), mostly below 1e-14
    assert _rel_diff(a, b) < 1e-11
    assert np.array_equal(a.status, b.status) and a.success.all()
    assert np.array_equal(a.nfev, b.nfev)
    if params is not None:   # each lane ran with its own parameters
        for i in (0, k // 2, k - 1):
            one = s.replace(**{n: float(v[i]) for n, v in params.items()})
            sol = mp.solve(one, (0, 1), y0s[i], t_eval=te, method=method, **METHODS[method])
            # measured: at most 3.2e-13 (double pendulum, dopri5)
            assert np.max(np.abs(sol.y - a.y[i])) < 3e-12 * np.max(np.abs(sol.y))


def test_chaotic_rows_in_lanes_are_another_rounding_of_the_same_solve():
    """What the docs state for chaotic trajectories: a lane's evaluations agree with
    the scalar ones to round-off (test_lane_rhs_equals_eight_scalar_calls), which
    the flow amplifies: the paths agree before the chaos grows, keep the same energy
    error after it, and their nfev (which may differ where a step is accepted on
    one path and rejected on the other) stay within a few percent."""
    s = _compiled("double pendulum")
    rng = np.random.default_rng(0)
    k = 64
    y0s = np.column_stack([rng.uniform(1.5, 3.0, k), rng.uniform(-3, 3, k), np.zeros(k),
                           np.zeros(k)])
    te = np.array([0.0, 1.0, 20.0])
    a, b = _both(s, (0, 20), y0s, t_eval=te)
    assert (a.status == 0).all() and (b.status == 0).all()
    # t = 1: measured 2.7e-12
    assert np.abs(a.y[:, :, 1] - b.y[:, :, 1]).max() < 3e-11
    # t = 20: the same energy error on both paths (measured 3.39e-6 on each), though
    # the states are up to 1.06 apart
    E0 = s.energy(y0s.T)
    for e in (a, b):
        assert np.abs(s.energy(e.y[:, :, -1].T) - E0).max() < 3e-5
    # measured: 10 rows of 64 differ, by at most 0.76% (6.7% over 333 rows)
    assert np.max(np.abs(a.nfev - b.nfev) / b.nfev) < 0.05


def _degenerate():
    """M = [[1, 1], [1, 1 + exp(-q1)]], positive definite, with q1 = q1(0) + v t,
    q2 = q2(0) while q2' = 0: the pivot exp(-q1) falls below the solver's
    NA eps max|A| once q1 > 35.1, and the solve reports a singular matrix (at
    the first stage that reaches it: q1 <= 2 v on the span [0, 2])."""
    q1, q2 = mp.coordinates("q1 q2")
    d1, d2 = q1.diff(T), q2.diff(T)
    return mp.lagrangian((d1 ** 2 + 2 * d1 * d2 + (1 + sp.exp(-q1)) * d2 ** 2) / 2, [q1, q2])


@pytest.mark.parametrize("k", [1, LANES - 1, LANES + 1, 37])
def test_singular_mass_matrix_in_a_compiled_lane(k):
    s = _degenerate()
    v = np.linspace(5.0, 50.0, k)
    y0s = np.column_stack([np.zeros(k), np.zeros(k), v, np.zeros(k)])
    te = np.linspace(0, 2, 5)
    a, b = _both(s, (0, 2), y0s, t_eval=te, errors="status")
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    bad = v * 2 > 35.1
    assert (a.status[bad] == -3).all() and (a.status[~bad] == 0).all()
    _same_messages(a.message, b.message)
    assert np.array_equal(np.isnan(a.y), np.isnan(b.y))
    # until the failure q1 = v t exactly as far as rounding goes
    ok = ~np.isnan(a.y[:, 0, :])
    exact = v[:, None] * te[None, :]
    # measured 2.2e-15
    assert np.max(np.abs(a.y[:, 0, :][ok] - exact[ok])) < 3e-14 * np.max(exact)
    if bad.any():
        with pytest.raises(mp.SingularityError):
            mp.solve_many(s, (0, 2), y0s, t_eval=te, lanes=True)


@pytest.mark.parametrize("method", sorted(METHODS))
def test_vanishing_mass_of_one_coordinate_in_lanes(method):
    """L = exp(-c t) q'^2 / 2 at rest: q stays put, b = 0, and the 1 x 1 mass
    matrix exp(-c t) turns subnormal (its inverse inf, q'' = 0 inf = NaN) past
    c t = 708.4 and exactly 0 (singular) past 745.1.  Which of the two a lane
    meets first depends on where its steps land: both paths meet the same."""
    (q,) = mp.coordinates("q")
    c = sp.Symbol("c")
    s = mp.lagrangian(sp.exp(-c * T) * q.diff(T) ** 2 / 2, [q], params=dict(c=1.0))
    k = 37
    cs = np.linspace(0.1, 2.0, k)
    y0s = np.column_stack([np.linspace(-1, 1, k), np.zeros(k)])
    te = np.linspace(0, 1000, 3)
    kw = dict(h=0.5) if method == "rk4" else {}
    a, b = _both(s, (0, 1000), y0s, t_eval=te, errors="status", params={"c": cs},
                 method=method, **kw)
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    _same_messages(a.message, b.message)
    fine = cs * 1000 < 708
    assert (a.status[fine] == 0).all() and (a.status[~fine] < 0).all()
    # NonFiniteError, SingularityError: both in one lane group but for rk4's steps
    assert set(a.status[~fine]) == ({-2} if method == "rk4" else {-2, -3})
    assert np.array_equal(a.y[fine], np.repeat(y0s[fine, :, None], 3, axis=2))


def test_blow_up_of_a_compiled_lagrangian():
    """L = q'^2 / 2 + q^4 / 4: q'' = q^3, and from q(0) = a, q'(0) = a^2 / sqrt(2)
    q = a / (1 - a t / sqrt(2)) leaves every float at t = sqrt(2) / a; the
    lanes that start above a = 0.943 fail within (0, 1.5) as the scalar path
    fails them."""
    (q,) = mp.coordinates("q")
    s = mp.lagrangian(q.diff(T) ** 2 / 2 + q ** 4 / 4, [q])
    a = np.linspace(0.5, 4.0, 19)
    y0s = np.column_stack([a, a ** 2 / np.sqrt(2)])
    te = np.linspace(0, 1.5, 4)
    r, b = _both(s, (0, 1.5), y0s, t_eval=te, errors="status")
    assert np.array_equal(r.status, b.status) and np.array_equal(r.nfev, b.nfev)
    blows = a * 1.5 > np.sqrt(2)
    assert (r.status[blows] < 0).all() and (r.status[~blows] == 0).all()
    _same_messages(r.message, b.message)
    assert np.array_equal(np.isnan(r.y), np.isnan(b.y))
    with np.errstate(divide="ignore"):
        exact = a[:, None] / (1 - a[:, None] * te[None, :] / np.sqrt(2))
    ok = ~np.isnan(r.y[:, 0, :]) & np.isfinite(exact)
    rel = np.abs(r.y[:, 0, :][ok] - exact[ok]) / np.maximum(np.abs(exact[ok]), 1.0)
    assert np.max(rel) < 1e-7   # measured 7.9e-9 (the samples nearest the pole)


def test_compiled_lanes_refill_across_groups():
    """53 trajectories of very different lengths in one thread's lane group:
    each slot takes the next trajectory as its own ends."""
    s = _compiled("double pendulum")
    k = 53
    y0s = _starts([1.0, -0.5, 0.0, 0.3], 0.5, k)
    te = np.linspace(0, 3, 4)
    params = {"l1": np.geomspace(0.05, 5.0, k)}   # short ones take many more steps
    params = {n: np.full(k, v) for n, v in s.params.items()} | params
    a, b = _both(s, (0, 3), y0s, t_eval=te, params=params)
    assert np.ptp(a.nfev) > 100
    assert np.array_equal(a.nfev, b.nfev)
    assert _rel_diff(a, b) < 3e-11   # measured 3.6e-12
    two = mp.solve_many(s, (0, 3), y0s, t_eval=te, params=params, threads=2, lanes=True)
    assert np.array_equal(two.y, a.y) and np.array_equal(two.nfev, a.nfev)


def test_no_lane_rhs_for_a_huge_system(monkeypatch, tmp_path):
    """Above codegen.LANE_MAX the library has no mp_gen_lanes; ensembles run
    in lanes through the generic wrapper, as before."""
    from mechpy.symbolic import codegen
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(codegen, "LANE_MAX", 10)
    s = _lorenz()
    assert "mp_gen_lanes" not in s.c_source.split("*/", 1)[1]
    assert s._addr_lanes is None and not hasattr(s._lib, "mp_gen_lanes")
    y0s = _starts([1.0, 1.0, 20.0], 0.1, 11)
    a, b = _both(s, (0, 1), y0s, t_eval=[0.0, 1.0])
    assert np.array_equal(a.nfev, b.nfev)
    assert _rel_diff(a, b) < 3e-13   # measured 2.3e-14 (the lane driver's own rounding)


# ---- every field against the scalar path: backward spans, starts from rest, ----------
# ---- budgets, stiffness hints, the progress line ---------------------------------------

def test_backward_blow_up_fails_at_the_pole_in_lanes():
    """y' = y^2 backwards from y0 < 0: y = y0 / (1 - y0 t) leaves every float at
    t = 1/y0 < 0.  The lanes that start below -2/3 fail there, at a negative
    time (the message's time as the scalar path's), the others reach -1.5."""
    (y,) = mp.coordinates("y")
    s = mp.equations([y ** 2], [y])
    y0s = np.linspace(-1.0, 1.0, 36)[:, None]
    te = np.linspace(0, -1.5, 4)
    a, b = _both(s, (0, -1.5), y0s, t_eval=te, errors="status")
    _same_fields(a, b, rel=1e-6)   # measured 9.4e-8, on the samples nearest the pole
    blows = y0s[:, 0] < -1 / 1.5
    assert (a.status[blows] == -1).all() and (a.status[~blows] == 0).all()
    tf = _message_times(a.message)[blows]
    # the step size falls below round-off just past the pole: measured 1.2e-9
    assert np.all(np.abs(tf - 1 / y0s[blows, 0]) < 1e-8)
    with np.errstate(divide="ignore"):
        exact = (y0s / (1 - y0s * te[None, :]))[:, None, :]
    ok = ~np.isnan(a.y) & np.isfinite(exact)
    rel = np.abs(a.y[ok] - exact[ok]) / np.maximum(np.abs(exact[ok]), 1.0)
    assert np.max(rel) < 1e-6   # measured 8e-8 (the samples nearest the pole)


@pytest.mark.parametrize("method", sorted(METHODS))
def test_backward_step_budget_per_lane(method):
    """A backward solve that runs out of steps: the same lanes fail, with the
    same negative time in their messages, and the samples before it agree."""
    k = 21
    y0s = np.column_stack([np.linspace(0.1, 3.1, k)[::-1], np.zeros(k)])
    te = np.linspace(0, -20, 9)
    kw = METHODS[method]
    full = mp.solve_many(S.Pendulum(), (0, -20), y0s, t_eval=te, lanes=False, method=method,
                         **kw)
    # evaluations per step: 12 and 6 (FSAL); rk4 gets half its 4 x 20000 steps
    budget = int(np.median(full.nfev) / {"dop853": 12, "dopri5": 6, "rk4": 8}[method])
    a, b = _both(S.Pendulum(), (0, -20), y0s, t_eval=te, max_steps=budget, errors="status",
                 method=method, **kw)
    _same_fields(a, b, rel=1e-10)   # measured 2e-13
    tf = _message_times(a.message)[a.status == -1]
    if method == "rk4":   # fixed steps of h: every lane stops after the same budget
        assert (a.status == -1).all()
        assert np.allclose(tf, -budget * kw["h"], rtol=1e-12, atol=0)
    else:
        assert 0 < np.sum(a.status == -1) < k
        assert np.all((tf < 0) & (tf > -20))
    # a failed lane's samples up to its failure time are the full solve's
    for i in np.flatnonzero(a.status == -1):
        got = te >= _message_times(a.message)[i]   # the time reached, the budget spent
        assert np.all(np.isfinite(a.y[i][:, got])) and np.all(np.isnan(a.y[i][:, ~got]))
        assert np.array_equal(b.y[i][:, got], full.y[i][:, got])
        assert np.max(np.abs(a.y[i][:, got] - full.y[i][:, got])) < 3e-9   # measured 4.3e-10


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("t_span", [(0, 3), (0, -3)])
def test_starts_from_rest(method, t_span):
    """At rest: on the equilibrium f(y0) = 0 (the first-step guess has no
    derivative to go by) and at rest away from it, in both directions, for
    scenes and a compiled system.  Every field as on the scalar path, and the
    equilibrium stays put exactly."""
    te = np.linspace(*t_span, 4)
    k = 11
    amp = np.linspace(-1.0, 1.0, k)   # amp[5] == 0: the equilibrium
    for system, y0s in [
            (S.Pendulum(), np.column_stack([amp, np.zeros(k)])),
            (S.Duffing(alpha=1.0, beta=0.5), np.column_stack([amp, np.zeros(k)])),
            (S.SpringChain(masses=[1.0, 2.0]), np.column_stack([amp, -amp, np.zeros((k, 2))])),
            (_compiled_pendulum(), np.column_stack([amp, np.zeros(k)]))]:
        a, b = _both(system, t_span, y0s, t_eval=te, method=method, **METHODS[method])
        _same_fields(a, b)   # measured 3e-15
        assert a.success.all()
        assert np.all(a.y[5] == 0.0)


def test_stiffness_hint_in_lanes():
    """Van der Pol at mu = 1000 under dop853 with a step budget: the message says
    the problem appears stiff (Hairer's test) in the stiff lanes only, at the same
    time as on the scalar path; mu = 1 lanes in the same group run out without it."""
    k = 9
    mu = np.r_[[1.0] * 4, [1000.0] * 5]
    y0s = np.tile([2.0, 0.0], (k, 1))
    a, b = _both(S.VanDerPol(mu=1.0), (0, 3000), y0s, params={"mu": mu}, max_steps=3000,
                 errors="status")
    _same_fields(a, b)   # measured: the failure times 1.1e-9 apart (relative)
    assert (a.status == -1).all()
    hint = np.array(["appears stiff" in m for m in a.message])
    assert np.array_equal(hint, mu > 100)
    # the non-stiff lanes run out far later in t: mu = 1 has period ~6.7, mu = 1000 ~1614
    # with a boundary layer of width ~1/mu where the explicit steps pile up
    tf = _message_times(a.message)
    assert np.all(tf[mu == 1.0] > 100) and np.all(tf[mu > 100] < 100)


def _progress_counts(err):
    lines = re.findall(r"solve_many: (\d+)/(\d+) trajectories", err)
    return [int(d) for d, _ in lines], {int(t) for _, t in lines}


@pytest.mark.parametrize("k", [1, LANES + 3, 50, 250])
def test_progress_line_in_lanes(k, monkeypatch, capfd):
    """Without tqdm, progress=True writes a stderr line as trajectories finish, at
    most once per percent and always at the end: in lanes as on the scalar path
    (one thread: every report comes from the calling thread)."""
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)    # the import fails
    y0s = np.column_stack([np.linspace(0.1, 3.0, k), np.zeros(k)])
    got = {}
    for lanes in (True, False):
        capfd.readouterr()
        e = mp.solve_many(S.Pendulum(), (0, 2), y0s, progress=True, threads=1, lanes=lanes)
        assert e.success.all() and e.lanes == lanes
        err = capfd.readouterr().err
        done, totals = _progress_counts(err)
        assert totals == {k} and err.endswith(f"solve_many: {k}/{k} trajectories\n")
        assert done == sorted(set(done)) and done[-1] == k
        # one report per percent step: every count up to 100 trajectories, else
        # exactly the counts that start a new percent (and the last)
        pct = [d for d in range(1, k + 1) if d == k or d * 100 // k != (d - 1) * 100 // k]
        assert done == pct
        got[lanes] = e
    assert np.array_equal(got[True].nfev, got[False].nfev)


def test_progress_callback_in_lanes(monkeypatch):
    """With tqdm, the bar gets the counts of the C side in lanes, rising to k."""
    import types
    reports = []

    class Bar:
        def __init__(self, total, **kw):
            self.total, self.n = total, 0

        def update(self, d):
            reports.append(d)
            self.n += d

        def close(self):
            pass

    fake = types.ModuleType("tqdm.auto")
    fake.tqdm = Bar
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", fake)
    k = 40
    y0s = np.column_stack([np.linspace(0.1, 3.0, k), np.zeros(k)])
    e = mp.solve_many(S.Pendulum(), (0, 2), y0s, progress=True, threads=1, lanes=True)
    assert e.lanes and e.success.all()
    # one update per finished trajectory from the lanes (k <= 100); the final
    # report(k, k) of solve_many then adds nothing
    assert reports[:k] == [1] * k and sum(reports) == k


@pytest.mark.parametrize("method", sorted(METHODS))
def test_samples_between_steps_in_lanes(method):
    """t_eval points inside the steps (rk4's steps of 0.01 end at multiples of it;
    the samples fall at odd thousandths): each method's interpolant in the lanes as on
    the scalar path, and near the exact motion of the harmonic chain."""
    ch = S.SpringChain(masses=[1.0, 2.0, 0.5])
    k = 11
    y0s = _starts([0.3, -0.2, 0.1, 0.0, 0.25, -0.4], 0.3, k)
    te = np.array([0.0, 0.0037, 0.5013, 1.2345, 2.9999])
    kw = dict(h=0.01) if method == "rk4" else {}
    a, b = _both(ch, (0, 3), y0s, t_eval=te, method=method, **kw)
    _same_fields(a, b)   # measured 3.7e-15 (0 for rk4)
    md = ch.modes()
    for i in range(k):
        q, v = md.evolve(y0s[i, :3], y0s[i, 3:], te, velocities=True)
        # measured 6.8e-9 (rk4's Hermite interpolant at h = 0.01), 5.1e-9 and 5.5e-9
        # (dop853, dopri5 at rtol 1e-8)
        assert np.max(np.abs(a.y[i] - np.concatenate([q.T, v.T]))) < 5e-8


@pytest.mark.parametrize("method", ["dopri5", "dop853"])
def test_span_of_a_few_ulps_in_lanes(method):
    """A span of 1 to 16 ulps of t0 (the step floor is 16 ulps): the one step lands on
    tf in the lanes as on the scalar path, every field; the pendulum at rest moves
    by g sin(theta) dt^2 / 2, below round-off."""
    y0s = _starts([1.0, 0.0], 0.3, 5)
    for t0 in (1.0, 1e6):
        for k in (1, 16):
            tf = t0
            for _ in range(k):
                tf = np.nextafter(tf, np.inf)
            a, b = _both(S.Pendulum(), (t0, tf), y0s, method=method)
            _same_fields(a, b)
            assert a.success.all() and a.t[-1] == tf
            assert np.abs(a.y[:, 0, -1] - y0s[:, 0]).max() <= 1e-15
