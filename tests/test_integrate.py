"""mp.solve against closed forms, SciPy's solve_ivp and odeint, and bad input."""
import ctypes
import math
import pickle
import shutil
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import odeint, solve_ivp

import mechpy as mp
from ref_ode import VDP_PERIOD_MU1, pendulum_exact, pendulum_period, pendulum_rhs, vdp_rhs

ADAPTIVE = ["dop853", "dopri5", "radau", "auto", "gsl:rkf45", "gsl:rk8pd", "gsl:msadams",
            "gsl:rkck", "gsl:msbdf", "gsl:bsimp", "gsl:rk4imp"]
THETA0 = 2.5  # a large amplitude: far from the small-angle regime


# ---- accuracy against the exact large-amplitude pendulum ---------------------

@pytest.mark.parametrize("method", ADAPTIVE)
def test_pendulum_against_exact_solution(method):
    p = mp.scenes.Pendulum()
    sol = mp.solve(p, (0, 10), [THETA0, 0.0], method=method, rtol=1e-10, atol=1e-12)
    assert sol.success and sol.status == 0 and sol.t[-1] == 10.0
    exact = pendulum_exact(THETA0, sol.t)
    err = np.max(np.abs(sol.y - exact))
    # ten seconds, ~4 periods: each method's own bound, about 5x its measured error
    assert err < PENDULUM_BOUND[method], err


# max |y - exact| at rtol 1e-10, atol 1e-12 over 0..10 s (measured on x86-64 beside each)
PENDULUM_BOUND = {
    "dop853": 3e-8,        # 6.8e-9
    "dopri5": 8e-8,        # 1.7e-8
    "radau": 2e-10,        # 2.6e-11
    "auto": 3e-8,          # 6.8e-9 (non-stiff: the dop853 path)
    "gsl:rkf45": 3e-7,     # 6.2e-8
    "gsl:rk8pd": 1.5e-8,   # 2.9e-9
    "gsl:msadams": 1.5e-6,  # 3.2e-7
    "gsl:rkck": 5e-7,      # 1.0e-7
    "gsl:msbdf": 1e-5,     # 2.4e-6 (variable-order BDF accumulates on an oscillation)
    "gsl:bsimp": 2.5e-7,   # 4.7e-8
    "gsl:rk4imp": 2e-7,    # 3.6e-8
}


@pytest.mark.parametrize("method,scipy_method", [("dop853", "DOP853"), ("dopri5", "RK45")])
def test_agrees_with_solve_ivp_same_method(method, scipy_method):
    t = np.linspace(0, 10, 101)
    ours = mp.solve(mp.scenes.Pendulum(), (0, 10), [THETA0, 0.0], method=method, rtol=1e-9,
                    atol=1e-12, t_eval=t)
    ref = solve_ivp(pendulum_rhs, (0, 10), [THETA0, 0.0], method=scipy_method, rtol=1e-9,
                    atol=1e-12, t_eval=t)
    exact = pendulum_exact(THETA0, t)
    e_ours = np.max(np.abs(ours.y - exact))
    e_ref = np.max(np.abs(ref.y - exact))
    # both claim ~1e-9 local accuracy; they agree within the error both make
    assert np.max(np.abs(ours.y - ref.y)) <= 2 * max(e_ours, e_ref) + 1e-12
    assert e_ours < 3 * e_ref + 1e-9
    # same method, same controller family: comparable work
    assert ours.nfev < 1.5 * ref.nfev


@pytest.mark.parametrize("method,scipy_method", [("dop853", "DOP853"), ("dopri5", "RK45")])
def test_first_step_is_solve_ivps(method, scipy_method):
    # the automatic first step is Hairer's estimate (Solving ODEs I, II.4), SciPy's
    # select_initial_step: the same step to round-off, forward and backward, from rest
    # and where one component is near zero, at loose and tight tolerances, relative and
    # absolute (where the second-derivative probe, not 100 times the trial step, sets it)
    def f(t, y):
        return [y[1], -np.sin(y[0]) - 0.1 * y[1] + 0.3 * np.cos(t)]
    for span in [(0.0, 10.0), (2.0, -8.0), (0.0, 0.01)]:
        for y0 in ([1.0, 0.0], [0.3, 2.0], [1e-3, 4.0], [0.0, 0.0]):
            for rtol, atol in [(1e-3, 1e-5), (1e-6, 1e-8), (1e-10, 1e-12), (1e-6, 1e-2),
                               (1e-3, 1e-1)]:
                kw = dict(rtol=rtol, atol=atol)
                ours = mp.solve(f, span, y0, method=method, **kw)
                ref = solve_ivp(f, span, y0, method=scipy_method, **kw)
                h, h_ref = ours.t[1] - ours.t[0], ref.t[1] - ref.t[0]
                assert abs(h - h_ref) <= 4e-15 * abs(h_ref), (span, y0, rtol, atol, h, h_ref)


def test_agrees_with_odeint_python_rhs():
    t = np.linspace(0, 20, 201)
    ours = mp.solve(vdp_rhs, (0, 20), [2.0, 0.0], rtol=1e-11, atol=1e-12, t_eval=t)
    ref = odeint(vdp_rhs, [2.0, 0.0], t, rtol=1e-12, atol=1e-12, tfirst=True)
    assert np.max(np.abs(ours.y - ref.T)) < 1e-9  # measured 1.7e-10


def test_python_callable_matches_scene():
    t = np.linspace(0, 5, 11)
    a = mp.solve(mp.scenes.Pendulum(length=2.0), (0, 5), [1.0, 0.3], t_eval=t, rtol=1e-12)
    b = mp.solve(pendulum_rhs, (0, 5), [1.0, 0.3], t_eval=t, rtol=1e-12, args=(9.81, 2.0))
    assert np.array_equal(a.y, b.y)  # same arithmetic, same steps
    assert a.nfev == b.nfev


def test_fixed_step_rk4_converges_at_fourth_order():
    p = mp.scenes.Pendulum()
    exact = pendulum_exact(THETA0, [2.0])[:, 0]
    errs = []
    for h in (0.008, 0.004, 0.002):
        s = mp.solve(p, (0, 2), [THETA0, 0.0], method="rk4", h=h)
        assert s.t[-1] == 2.0
        errs.append(np.max(np.abs(s.y[:, -1] - exact)))
    rates = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(np.abs(rates - 4) < 0.3), rates


def test_small_angle_pendulum_is_harmonic():
    a = 1e-5
    t = np.linspace(0, 7, 50)
    s = mp.solve(mp.scenes.Pendulum(length=0.5), (0, 7), [a, 0.0], t_eval=t, rtol=1e-12,
                 atol=1e-16)
    w = np.sqrt(9.81 / 0.5)
    # sin(theta) ~ theta - theta^3/6: relative deviation ~ a^2/16 over these few periods
    assert np.max(np.abs(s.y[0] - a * np.cos(w * t))) < 1e-13


def test_damped_small_angle_pendulum_closed_form():
    a, b = 1e-6, 0.3
    t = np.linspace(0, 10, 60)
    s = mp.solve(mp.scenes.Pendulum(damping=b), (0, 10), [a, 0.0], t_eval=t, rtol=1e-12,
                 atol=1e-18)
    w0 = np.sqrt(9.81)
    wd = np.sqrt(w0 ** 2 - b ** 2 / 4)
    x = a * np.exp(-b * t / 2) * (np.cos(wd * t) + b / (2 * wd) * np.sin(wd * t))
    assert np.max(np.abs(s.y[0] - x)) < 1e-15


def test_driven_pendulum_matches_solve_ivp():
    p = mp.scenes.Pendulum(damping=0.5, drive_amplitude=1.2, drive_frequency=2 / 3)
    t = np.linspace(0, 30, 31)
    ours = mp.solve(p, (0, 30), [0.2, 0.0], t_eval=t, rtol=1e-11, atol=1e-12)
    ref = solve_ivp(pendulum_rhs, (0, 30), [0.2, 0.0], method="DOP853", t_eval=t, rtol=1e-11,
                    atol=1e-12, args=(9.81, 1.0, 0.5, 1.2, 2 / 3))
    assert np.max(np.abs(ours.y - ref.y)) < 1e-7


# ---- events, dense output ----------------------------------------------------

def test_large_amplitude_period_from_events():
    def upward(t, y):
        return y[0]
    upward.direction = 1
    s = mp.solve(mp.scenes.Pendulum(), (0, 20), [THETA0, 0.0], events=upward, rtol=1e-12,
                 atol=1e-14)
    te = s.t_events[0]
    assert len(te) >= 3
    T = pendulum_period(THETA0)
    assert np.max(np.abs(np.diff(te) - T)) < 1e-10
    assert abs(mp.scenes.Pendulum().period(THETA0) - T) < 1e-13 * T
    # y_events holds the state there: theta = 0, theta_dot > 0
    assert np.all(np.abs(s.y_events[0][:, 0]) < 1e-12) and np.all(s.y_events[0][:, 1] > 0)


def test_terminal_event_time_to_round_off():
    def bottom(t, y):
        return y[0]
    bottom.terminal = True
    s = mp.solve(mp.scenes.Pendulum(), (0, 10), [THETA0, 0.0], events=[bottom], rtol=1e-12,
                 atol=1e-14, dense_output=True)
    quarter = pendulum_period(THETA0) / 4
    assert s.status == 1 and s.success
    assert abs(s.t_events[0][0] - quarter) < 1e-12
    assert s.t[-1] == s.t_events[0][0]
    assert abs(s.y[0, -1]) < 1e-12


def test_terminal_count_and_several_events():
    def zero(t, y):
        return y[0]

    def still(t, y):
        return y[1]
    zero.terminal = 3
    s = mp.solve(mp.scenes.Pendulum(), (0, 100), [1.0, 0.0], events=[zero, still], rtol=1e-11)
    T = pendulum_period(1.0)
    assert s.status == 1
    assert len(s.t_events[0]) == 3
    np.testing.assert_allclose(s.t_events[0], [T / 4, 3 * T / 4, 5 * T / 4], rtol=1e-9)
    # turning points at 0 (released at rest: theta_dot = 0 at t0, reported as
    # SciPy's solve_ivp reports it), T/2 and T before the third zero
    assert s.t_events[1][0] == 0.0
    np.testing.assert_allclose(s.t_events[1][1:], [T / 2, T], rtol=1e-9)


def test_several_crossings_in_one_step_are_found():
    # a huge max step on a smooth problem: steps span several zeros of sin(5 t)
    def g(t, y):
        return np.sin(5 * t)
    s = mp.solve(lambda t, y: [0.0], (0, 10), [0.0], events=g, first_step=2.0, max_step=2.0)
    expected = np.arange(0, 16) * np.pi / 5   # g(0) = 0: an event at t0, as in SciPy
    assert s.nsteps == 5  # three zeros in each step
    np.testing.assert_allclose(s.t_events[0], expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("method", ["dop853", "dopri5", "gsl:rk8pd", "rk4"])
def test_dense_output_matches_t_eval_and_exact(method):
    t = np.linspace(0, 6, 37)
    kw = dict(h=1e-3) if method == "rk4" else dict(rtol=1e-10, atol=1e-12)
    s = mp.solve(mp.scenes.Pendulum(), (0, 6), [THETA0, 0.0], method=method, t_eval=t,
                 dense_output=True, **kw)
    np.testing.assert_allclose(s.sol(t), s.y, rtol=0, atol=1e-14)
    assert s.sol(3.0).shape == (2,)
    tt = np.linspace(0, 6, 1001)
    err = np.max(np.abs(s.sol(tt) - pendulum_exact(THETA0, tt)))
    # the interpolants' orders: 7 (dop853), 4 (dopri5), cubic Hermite (GSL rows, rk4)
    assert err < {"dop853": 1e-8, "dopri5": 1e-7, "gsl:rk8pd": 1e-3, "rk4": 1e-7}[method], err


def test_t_eval_is_not_forced_onto_steps():
    few = mp.solve(mp.scenes.Pendulum(), (0, 10), [1.0, 0.0])
    many = mp.solve(mp.scenes.Pendulum(), (0, 10), [1.0, 0.0], t_eval=np.linspace(0, 10, 5000))
    assert many.nsteps == few.nsteps
    assert many.y.shape == (2, 5000)


def test_energy_of_undamped_pendulum_conserved():
    p = mp.scenes.Pendulum(length=1.3)
    s = mp.solve(p, (0, 50), [THETA0, 0.0], rtol=1e-12, atol=1e-14)
    E = p.energy(s.y)
    assert E.shape == s.t.shape
    assert abs(E[0] - 9.81 * 1.3 * (1 - np.cos(THETA0))) < 1e-12
    assert np.max(np.abs(E - E[0])) / E[0] < 1e-9


def test_van_der_pol_limit_cycle_period():
    def up(t, y):
        return y[0]
    up.direction = 1
    s = mp.solve(mp.scenes.VanDerPol(mu=1.0), (0, 80), [2.0, 0.0], events=up, rtol=1e-12,
                 atol=1e-12)
    periods = np.diff(s.t_events[0])
    assert abs(periods[-1] - VDP_PERIOD_MU1) < 5e-13  # measured 4.9e-14
    amp = np.max(np.abs(s.y[0][s.t > 40]))
    assert abs(amp - 2.0086) < 1e-3


# ---- scenes -------------------------------------------------------------------

def test_scene_rhs_jacobian_energy_vectorised(rng):
    p = mp.scenes.Pendulum(g=9.7, length=0.8, damping=0.2, drive_amplitude=0.5,
                           drive_frequency=1.1)
    Y = rng.normal(size=(2, 5, 3))
    f = p.rhs(0.7, Y)
    assert f.shape == Y.shape
    ref = pendulum_rhs(0.7, Y, 9.7, 0.8, 0.2, 0.5, 1.1)
    np.testing.assert_allclose(f, ref, rtol=1e-15)
    J = p.jacobian(0.7, Y[:, 0, 0])
    eps = 1e-7
    for j in range(2):
        d = np.zeros(2)
        d[j] = eps
        fd = (p.rhs(0.7, Y[:, 0, 0] + d) - p.rhs(0.7, Y[:, 0, 0] - d)) / (2 * eps)
        np.testing.assert_allclose(J[:, j], fd, rtol=1e-7, atol=1e-8)
    v = mp.scenes.VanDerPol(mu=3.0)
    np.testing.assert_allclose(v.rhs(0, Y), vdp_rhs(0, Y, 3.0), rtol=1e-15)
    assert v.energy(Y).shape == (5, 3)


def test_scene_params_replace_pickle():
    p = mp.scenes.Pendulum(length=2.0)
    assert p.params == dict(g=9.81, length=2.0, damping=0.0, drive_amplitude=0.0,
                            drive_frequency=0.0)
    q = p.replace(damping=0.1)
    assert q.params["damping"] == 0.1 and p.params["damping"] == 0.0
    r = pickle.loads(pickle.dumps(q))
    assert r == q and r.dim == 2
    d = mp.scenes.Duffing(alpha=-1.0, beta=1.0, delta=0.3, gamma=0.5, omega=1.2)
    assert pickle.loads(pickle.dumps(d)) == d


def test_methods_table():
    table = {m["name"]: m for m in mp.methods()}
    for name in ["rk4", "dopri5", "dop853", "gsl:rkf45", "gsl:rk8pd", "gsl:msadams"]:
        assert name in table
    assert table["rk4"]["adaptive"] is False
    assert table["dop853"]["order"] == 8 and table["dop853"]["dense_output"] == 7
    assert table["gsl:msbdf"]["needs_jacobian"] and table["gsl:msbdf"]["implicit"]
    assert set(table["dopri5"]) == {"name", "order", "adaptive", "implicit", "symplectic",
                                    "needs_jacobian", "dense_output", "lanes", "rigid",
                                    "compensated", "scalar_rtol"}


@pytest.mark.parametrize("row", [m for m in mp.methods() if m["adaptive"] and not m["rigid"]],
                         ids=lambda m: m["name"])
def test_scalar_rtol_is_what_the_row_takes(row):
    """A row's scalar_rtol decides whether one rtol per component is taken:
    the solve refuses differing rtols exactly for those rows, and runs them
    (to the looser tolerance's accuracy, against exp(-t)) for the others."""
    def decay(t, y):
        return -y
    kw = dict(rtol=[1e-6, 1e-9], atol=1e-12)
    if row["scalar_rtol"]:
        with pytest.raises(ValueError, match="takes one rtol"):
            mp.solve(decay, (0, 1), [1.0, 2.0], method=row["name"], **kw)
        assert mp.solve(decay, (0, 1), [1.0, 2.0], method=row["name"],
                        rtol=[1e-6, 1e-6], atol=1e-12).success
        return
    s = mp.solve(decay, (0, 1), [1.0, 2.0], method=row["name"], **kw)
    assert s.success
    err = np.max(np.abs(s.y[:, -1] - np.array([1.0, 2.0]) * np.exp(-1.0)))
    assert err < 2e-9, err   # 1.7e-10 measured (dopri5)


def test_user_jacobian_is_used():
    calls = []

    def jac(t, y, mu):
        calls.append(t)
        return np.array([[0.0, 1.0], [-2 * mu * y[0] * y[1] - 1, mu * (1 - y[0] ** 2)]])
    s = mp.solve(vdp_rhs, (0, 5), [2.0, 0.0], method="gsl:bsimp", args=(2.0,), jac=jac,
                 rtol=1e-10)
    ref = solve_ivp(vdp_rhs, (0, 5), [2.0, 0.0], method="DOP853", args=(2.0,), rtol=1e-12,
                    atol=1e-12)
    assert calls and s.njev == len(calls)
    assert np.max(np.abs(s.y[:, -1] - ref.y[:, -1])) < 1e-7


# ---- C callbacks --------------------------------------------------------------

CB = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.POINTER(ctypes.c_double),
                      ctypes.POINTER(ctypes.c_double), ctypes.c_void_p)


def _ctypes_pendulum():
    @CB
    def f(t, y, dydt, ud):
        dydt[0] = y[1]
        dydt[1] = -9.81 * np.sin(y[0])
    return f


def test_ctypes_callback():
    f = _ctypes_pendulum()
    t = np.linspace(0, 3, 7)
    s = mp.solve(f, (0, 3), [THETA0, 0.0], t_eval=t, rtol=1e-11)
    ref = mp.solve(mp.scenes.Pendulum(), (0, 3), [THETA0, 0.0], t_eval=t, rtol=1e-11)
    np.testing.assert_allclose(s.y, ref.y, rtol=0, atol=1e-13)


@pytest.mark.parametrize("method, kw, bound", [("yoshida4", dict(h=1e-3), 1e-10),
                                               ("dop853", dict(rtol=1e-11, atol=1e-12), 2e-10)])
def test_second_order_c_callback(method, kw, bound):
    # SecondOrder with a ctypes acceleration q_i'' = -w_i^2 q_i (w = 1, 2): the state
    # (q, v) is cos(w t), -w sin(w t) (measured 1.8e-11 and 3.2e-11); every field equal
    # to the Python accel's solve
    @CB
    def acc(t, q, a, ud):
        a[0] = -q[0]
        a[1] = -4.0 * q[1]

    t = np.linspace(0, 5, 11)
    s = mp.solve(mp.SecondOrder(acc), (0, 5), [1.0, 1.0, 0.0, 0.0], t_eval=t, method=method,
                 **kw)
    py = mp.solve(mp.SecondOrder(lambda t, q: [-q[0], -4.0 * q[1]]), (0, 5),
                  [1.0, 1.0, 0.0, 0.0], t_eval=t, method=method, **kw)
    exact = np.array([np.cos(t), np.cos(2 * t), -np.sin(t), -2 * np.sin(2 * t)])
    assert s.success and np.array_equal(s.t, t)
    assert np.abs(s.y - exact).max() < bound
    for k in ("t", "y", "status", "nfev", "nsteps", "nreject"):
        assert np.array_equal(s[k], py[k]), k


def test_numba_cfunc_callback():
    # a numba cfunc is taken by its address (as the C core's callback) in solve,
    # solve_many and SecondOrder: the pendulum's motion equals the scene's
    numba = pytest.importorskip("numba")
    from numba import types
    sig = types.void(types.double, types.CPointer(types.double), types.CPointer(types.double),
                     types.voidptr)

    @numba.cfunc(sig)
    def f(t, y, dydt, ud):
        dydt[0] = y[1]
        dydt[1] = -9.81 * np.sin(y[0])

    @numba.cfunc(sig)
    def acc(t, q, a, ud):
        a[0] = -9.81 * np.sin(q[0])

    t = np.linspace(0, 3, 7)
    ref = mp.solve(mp.scenes.Pendulum(), (0, 3), [THETA0, 0.0], t_eval=t, rtol=1e-11)
    for system in (f, mp.SecondOrder(acc)):
        s = mp.solve(system, (0, 3), [THETA0, 0.0], t_eval=t, rtol=1e-11)
        np.testing.assert_allclose(s.y, ref.y, rtol=0, atol=1e-13)
        e = mp.solve_many(system, (0, 3), [[THETA0, 0.0], [1.0, 0.0]], t_eval=t, rtol=1e-11)
        np.testing.assert_allclose(e.y[0], ref.y, rtol=0, atol=1e-13)


def test_low_level_callable_with_user_data():
    from scipy import LowLevelCallable

    @CB
    def f(t, y, dydt, ud):
        g = ctypes.cast(ud, ctypes.POINTER(ctypes.c_double))[0]
        dydt[0] = y[1]
        dydt[1] = -g * np.sin(y[0])
    g = ctypes.c_double(4.0)
    llc = LowLevelCallable(f, ctypes.cast(ctypes.pointer(g), ctypes.c_void_p),
                           "void (double, double *, double *, void *)")
    s = mp.solve(llc, (0, 2), [1.0, 0.0], rtol=1e-11)
    ref = mp.solve(mp.scenes.Pendulum(g=4.0), (0, 2), [1.0, 0.0], rtol=1e-11)
    np.testing.assert_allclose(s.y[:, -1], ref.y[:, -1], atol=1e-12)


def test_low_level_callable_with_a_wrong_signature():
    # only void (double, double const *, double *, void *) is called: a callable with
    # fewer or more arguments, or another return type, is refused before any call
    from scipy import LowLevelCallable
    dp, d = ctypes.POINTER(ctypes.c_double), ctypes.c_double
    calls = []
    for ret, args in [(None, (d, dp)), (None, (d, dp, dp)),
                      (None, (d, dp, dp, ctypes.c_void_p, ctypes.c_int)),
                      (ctypes.c_int, (d, dp, dp, ctypes.c_void_p))]:
        fn = ctypes.CFUNCTYPE(ret, *args)(lambda *a: calls.append(a))
        llc = LowLevelCallable(fn)
        with pytest.raises(TypeError, match="signature .* does not match"):
            mp.solve(llc, (0, 1), [1.0])
        with pytest.raises(TypeError, match="signature .* does not match"):
            mp.solve(mp.SecondOrder(llc), (0, 1), [1.0, 0.0])
    assert not calls


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_compiled_c_callback(tmp_path):
    src = tmp_path / "vdp.c"
    src.write_text(
        "void vdp(double t, const double *y, double *f, void *ud) {\n"
        "  double mu = *(const double *)ud; (void)t;\n"
        "  f[0] = y[1]; f[1] = mu * (1 - y[0] * y[0]) * y[1] - y[0]; }\n")
    lib = tmp_path / "libvdp.so"
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", str(src), "-o", str(lib)], check=True)
    so = ctypes.CDLL(str(lib))
    fn = CB(("vdp", so))
    from scipy import LowLevelCallable
    mu = ctypes.c_double(1.0)
    llc = LowLevelCallable(fn, ctypes.cast(ctypes.pointer(mu), ctypes.c_void_p))
    s = mp.solve(llc, (0, 20), [2.0, 0.0], rtol=1e-11, atol=1e-12)
    ref = mp.solve(mp.scenes.VanDerPol(1.0), (0, 20), [2.0, 0.0], rtol=1e-11, atol=1e-12)
    assert np.array_equal(s.y[:, -1], ref.y[:, -1])


# ---- budgets and failures -------------------------------------------------------

def test_step_budget_ends_with_failed_status():
    s = mp.solve(mp.scenes.VanDerPol(mu=1000.0), (0, 3000), [2.0, 0.0], max_steps=200)
    assert s.status == -1 and not s.success
    assert "max_steps=200" in s.message
    assert s.nsteps + s.nreject <= 200


# ---- bad input --------------------------------------------------------------------

P = mp.scenes.Pendulum()


@pytest.mark.parametrize("y0", [[np.nan, 0.0], [np.inf, 0.0], [0.0, -np.inf]])
def test_non_finite_y0(y0):
    with pytest.raises(ValueError, match="y0"):
        mp.solve(P, (0, 1), y0)


@pytest.mark.parametrize("y0", [[[1.0, 0.0]], [1.0, 0.0, 0.0], [], 1.0])
def test_wrong_shapes(y0):
    with pytest.raises(ValueError, match="y0"):
        mp.solve(P, (0, 1), y0)


def test_wrong_dtypes():
    with pytest.raises(TypeError, match="y0"):
        mp.solve(P, (0, 1), ["a", "b"])
    with pytest.raises(TypeError, match="y0"):
        mp.solve(P, (0, 1), [1 + 1j, 0])
    with pytest.raises(TypeError, match="system"):
        mp.solve(42, (0, 1), [1.0, 0.0])


@pytest.mark.parametrize("rtol", [0.0, -1e-6, np.nan])
def test_bad_rtol(rtol):
    with pytest.raises(ValueError, match="rtol"):
        mp.solve(P, (0, 1), [1.0, 0.0], rtol=rtol)


@pytest.mark.parametrize("span", [(0.0,), (0, np.inf), "ab"])  # (1, 0): backwards
def test_bad_t_span(span):
    with pytest.raises(ValueError, match="t_span"):
        mp.solve(P, span, [1.0, 0.0])


def test_zero_span_returns_y0_as_scipy():
    # t0 == tf: y0 at t = [t0, t0], no step, as solve_ivp (it raised ValueError);
    # solve_many has nothing to integrate and says so
    s = mp.solve(P, (1.0, 1.0), [1.0, 0.0])
    assert s.t.tolist() == [1.0, 1.0] and s.y.tolist() == [[1.0, 1.0], [0.0, 0.0]]
    assert s.status == 0 and s.nsteps == 0
    with pytest.raises(ValueError, match="t_span"):
        mp.solve_many(P, (1.0, 1.0), [[1.0, 0.0]])


def test_bad_options():
    with pytest.raises(ValueError, match="unknown method"):
        mp.solve(P, (0, 1), [1.0, 0.0], method="euler")
    with pytest.raises(ValueError, match="give h"):
        mp.solve(P, (0, 1), [1.0, 0.0], method="rk4")
    with pytest.raises(ValueError, match="h"):
        mp.solve(P, (0, 1), [1.0, 0.0], method="rk4", h=-0.1)
    with pytest.raises(ValueError, match="atol"):
        mp.solve(P, (0, 1), [1.0, 0.0], atol=-1.0)
    with pytest.raises(ValueError, match="atol"):
        mp.solve(P, (0, 1), [1.0, 0.0], atol=[1e-6, 1e-6, 1e-6])
    with pytest.raises(ValueError, match="t_eval"):
        mp.solve(P, (0, 1), [1.0, 0.0], t_eval=[0.5, 2.0])
    with pytest.raises(ValueError, match="t_eval"):
        mp.solve(P, (0, 1), [1.0, 0.0], t_eval=[0.5, 0.2])
    with pytest.raises(ValueError, match="max_steps"):
        mp.solve(P, (0, 1), [1.0, 0.0], max_steps=0)
    with pytest.raises(ValueError, match="length"):
        mp.scenes.Pendulum(length=-1.0)
    with pytest.raises(TypeError, match="mass"):
        mp.scenes.Pendulum().replace(mass=2.0)


def test_callback_exception_propagates_with_traceback():
    class Boom(RuntimeError):
        pass

    def f(t, y):
        if t > 0.5:
            raise Boom("raised inside the right-hand side")
        return [y[1], -y[0]]
    with pytest.raises(Boom, match="inside the right-hand side") as info:
        mp.solve(f, (0, 1), [1.0, 0.0])
    assert any(tb.name == "f" for tb in info.traceback)


def test_callback_wrong_return_shape():
    with pytest.raises(ValueError, match="fun returned shape"):
        mp.solve(lambda t, y: [1.0, 2.0, 3.0], (0, 1), [1.0, 0.0])
    with pytest.raises(TypeError, match="fun must return real numbers"):
        mp.solve(lambda t, y: ["x", "y"], (0, 1), [1.0, 0.0])


def test_callback_non_finite_result():
    def f(t, y):
        return [np.nan if t > 0.3 else 1.0, 0.0]
    with pytest.raises(mp.NonFiniteError, match="near t"):
        mp.solve(f, (0, 1), [1.0, 0.0])


def test_event_that_raises():
    def ev(t, y):
        raise KeyError("event")
    with pytest.raises(KeyError):
        mp.solve(P, (0, 1), [1.0, 0.0], events=ev)


def test_crash_free_in_subprocess():
    """A batch of hostile calls in a child process: it must exit normally."""
    code = r"""
import numpy as np, mechpy as mp
P = mp.scenes.Pendulum()
bad = [dict(y0=[np.nan, 0]), dict(y0=np.zeros((2, 2))), dict(y0=[1.0, 0], rtol=-1),
       dict(y0=[1.0, 0], t_eval=[np.nan])]
for kw in bad:
    y0 = kw.pop("y0")
    try:
        mp.solve(P, (0, 1), y0, **kw)
    except (ValueError, TypeError):
        pass
for f in (lambda t, y: None, lambda t, y: object(), lambda t, y: np.ones((2, 2)),
          lambda t, y: 1 / 0):
    try:
        mp.solve(f, (0, 1), [1.0, 0.0])
    except Exception:
        pass
print("ok")
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr


# ---- fixed-step methods against a plain loop, bit for bit ----------------------
#
# The driver runs rk4 and the splitting methods in unchecked blocks of steps and
# replays a block checked when a value is not finite.  These plain loops do the
# same arithmetic in the same order (the driver's step sequence: steps of h, the
# last one cut to end at tf; every evaluation checked), so that states, times,
# counts and the place of the first non-finite value must agree exactly.

YOSHIDA = {"verlet": [1.0],
           "yoshida4": [1.3512071919596576340476878089715, -1.7024143839193152680953756179429,
                        1.3512071919596576340476878089715]}
# the compositions whose updates are compensated sums (Kahan): s += inc kept as
# s + lo, the low-order part lo carried from step to step
COMPENSATED = {"yoshida4", "yoshida6"}


def _sum_add(s, lo, inc):
    """(s, lo) after s += inc, compensated: the sum is s + lo to about twice
    the working precision (Kahan 1965, lo = -c)."""
    y = inc + lo
    t = s + y
    return t, y - (t - s)


def _sin(x):
    return math.sin(x) if math.isfinite(x) else math.nan  # C's sin(inf) is NaN


def _pendulum_c(g=9.81, length=1.0, drive=0.0):
    """The Pendulum scene's right-hand side as its C row computes it."""
    if drive:
        return lambda t, y: [y[1], -(g / length) * _sin(y[0]) - 0.0 * y[1] + drive * math.cos(0.0 * t)]
    return lambda t, y: [y[1], -(g / length) * _sin(y[0])]


class _Failed(Exception):
    pass


def _fixed_step_reference(method, f, tf, y0, h):
    """(times, states, nfev, failure) of the fixed-step driver's loop from t = 0;
    failure = (component, t of the failing step) of the first non-finite value."""
    count = [0]

    def rhs(t, y):
        count[0] += 1
        d = f(t, y)
        bad = [i for i, v in enumerate(d) if not math.isfinite(v)]
        if bad:
            raise _Failed(bad[0])
        return d

    def rk4(t, h, y, k1):
        k2 = rhs(t + 0.5 * h, [y[i] + 0.5 * h * k1[i] for i in range(2)])
        k3 = rhs(t + 0.5 * h, [y[i] + 0.5 * h * k2[i] for i in range(2)])
        k4 = rhs(t + h, [y[i] + h * k3[i] for i in range(2)])
        yn = [y[i] + (h / 6.0) * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]) for i in range(2)]
        return yn, rhs(t + h, yn)

    lo = [0.0, 0.0]    # the compensated rows' low-order parts of (q, v)

    def add(s, i, inc):
        if method not in COMPENSATED:
            return s + inc
        s, lo[i] = _sum_add(s, lo[i], inc)
        return s

    def compose(t, h, y, fy):
        q, v, a = y[0], y[1], fy[1]
        for c in YOSHIDA[method]:
            hc = c * h
            v = add(v, 1, 0.5 * hc * a)
            q = add(q, 0, hc * v)
            a = rhs(t + hc, [q, v])[1]
            v = add(v, 1, 0.5 * hc * a)
            t += hc
        return [q, v], [v, a]

    t, y, i = 0.0, list(y0), 0
    ts, ys = [t], [y]
    try:
        fy = rhs(t, y)
        while t < tf:
            hh, last = h, False
            if t + hh * (1.0 + 1e-9) >= tf:
                hh = tf - t
                while t + hh > tf:
                    hh = math.nextafter(hh, 0.0)
                last = True
            y, fy = (rk4 if method == "rk4" else compose)(t, hh, y, fy)
            i += 1
            t = tf if last else i * h   # times counted, not summed
            ts.append(t)
            ys.append(y)
    except _Failed as e:
        return np.array(ts), np.array(ys).T, count[0], (e.args[0], t)
    return np.array(ts), np.array(ys).T, count[0], None


@pytest.mark.parametrize("method", ["rk4", "verlet", "yoshida4"])
def test_fixed_step_equals_plain_loop_bit_for_bit(method):
    # 1234 steps: blocks of up to 255 between the interrupt polls, and a cut last step
    tf, h, y0 = 12.345, 0.01, [2.5, 0.0]
    ts, ys, nfev, failure = _fixed_step_reference(method, _pendulum_c(), tf, y0, h)
    assert failure is None and len(ts) == 1236
    s = mp.solve(mp.scenes.Pendulum(), (0, tf), y0, method=method, h=h)
    assert s.nsteps == len(ts) - 1 and s.nfev == nfev
    assert np.array_equal(s.t, ts) and np.array_equal(s.y, ys)
    # output at step ends only: the blocks stop at each t_eval point
    pick = [0, 1, 254, 255, 256, 600, 1234, 1235]
    s = mp.solve(mp.scenes.Pendulum(), (0, tf), y0, method=method, h=h, t_eval=ts[pick])
    assert s.nsteps == len(ts) - 1 and s.nfev == nfev
    assert np.array_equal(s.t, ts[pick]) and np.array_equal(s.y, ys[:, pick])


# Kepler e = 0.6 (a = mu = 1) from pericentre over 1000 orbits: the relative
# energy error at the orbits' ends.  A symplectic method's energy error
# oscillates along an orbit with its truncation error (yoshida6, h = T/400: 4e-9
# near pericentre) and comes back at the same phase: what is left at the ends
# is what the run accumulated, round-off (the same steps in 80-bit arithmetic:
# 3.1e-16 for yoshida6, 6.5e-16 for yoshida4).  Plain updates of the state
# leave 2.6e-13 (yoshida6) and 3.9e-13 (yoshida4) there; compensated ones:
@pytest.mark.parametrize("method, n, bound", [
    ("yoshida6", 400, 5e-14),    # measured 9.8e-15 (4.0e-15 at the last end)
    ("yoshida4", 2000, 3e-14),   # measured 4.0e-15 (1.3e-15 at the last end)
])
def test_compensated_compositions_keep_kepler_energy_to_round_off(method, n, bound):
    k = mp.scenes.Kepler()
    y0 = k.initial_state(0.6)
    e0 = k.energy(y0)
    assert e0 == -0.5
    te = 2 * np.pi * np.arange(1, 1001)
    s = mp.solve(k, (0, te[-1]), y0, method=method, h=2 * np.pi / n, t_eval=te)
    assert s.success and s.nfev == 1 + n * 1000 * {"yoshida6": 7, "yoshida4": 3}[method]
    err = np.abs(k.energy(s.y) - e0) / abs(e0)
    assert err.max() < bound
    # the same steps checked one by one (dense output keeps the driver out of
    # the fast blocks; the low-order part then goes through the driver's
    # swaps): the same states, bit for bit
    few = te[:20]
    fast = mp.solve(k, (0, few[-1]), y0, method=method, h=2 * np.pi / n, t_eval=few)
    checked = mp.solve(k, (0, few[-1]), y0, method=method, h=2 * np.pi / n, t_eval=few,
                       dense_output=True)
    assert fast.nfev == checked.nfev and np.array_equal(checked.y, fast.y)


def test_compensated_compositions_in_solve_many_equal_solve():
    # solve_many runs the compositions one trajectory at a time (no lane
    # kernel): each trajectory's states and counts are its solve's, bit for bit,
    # on 1 and 2 threads, with per-trajectory parameters
    k = mp.scenes.Kepler()
    y0s = np.array([k.initial_state(e) for e in (0.0, 0.3, 0.6, 0.9)])
    mus = np.array([1.0, 0.5, 2.0, 1.0])
    te = np.linspace(0, 40 * np.pi, 41)
    for method in ("yoshida4", "yoshida6"):
        for threads in (1, 2):
            ens = mp.solve_many(k, (0, te[-1]), y0s, params={"mu": mus}, method=method,
                                h=2 * np.pi / 300, t_eval=te, threads=threads)
            assert ens.success.all()
            for i in range(len(y0s)):
                one = mp.solve(k.replace(mu=mus[i]), (0, te[-1]), y0s[i], method=method,
                               h=2 * np.pi / 300, t_eval=te)
                assert np.array_equal(ens.y[i], one.y) and ens.nfev[i] == one.nfev


@pytest.mark.parametrize("method", ["rk4", "verlet", "yoshida4"])
@pytest.mark.parametrize("t_eval", [None, [0.0, 1000.0]])
def test_fixed_step_non_finite_found_where_the_plain_loop_finds_it(method, t_eval):
    # a drive of 1e303 overflows theta after ~600 steps of h = 1, in the middle of
    # an unchecked block: the block is replayed checked and the solve stops at
    # the first non-finite evaluation, with the counts of a checked run
    A, tf = 1e303, 2000.0
    ts, ys, nfev, failure = _fixed_step_reference(method, _pendulum_c(drive=A), tf,
                                                  [0.0, 0.0], 1.0)
    assert failure is not None and 300 < len(ts) < 1000
    index, t_fail = failure
    s = mp.solve(mp.scenes.Pendulum(drive_amplitude=A), (0, tf), [0.0, 0.0], method=method,
                 h=1.0, t_eval=t_eval, errors="status")
    assert s.status == -2 and s.nfev == nfev and s.nsteps == len(ts) - 1
    assert f"dydt[{index}] = NaN or inf near t = {t_fail:.17g})" in s.message
    if t_eval is None:
        assert np.array_equal(s.t, ts) and np.array_equal(s.y, ys)
    else:
        assert np.array_equal(s.t, [0.0]) and np.array_equal(s.y, [[0.0], [0.0]])
    with pytest.raises(mp.NonFiniteError, match=f"near t = {t_fail:.17g}"):
        mp.solve(mp.scenes.Pendulum(drive_amplitude=A), (0, tf), [0.0, 0.0], method=method,
                 h=1.0)


# every right-hand side with fixed-step blocks of its own (ode/fixed.h: the
# scene's rhs inlined) and some without (the generic block, f behind its
# pointer); y0 and whether the symplectic methods apply
_S = mp.scenes
FIXED_BLOCK_CASES = {
    "Pendulum": (_S.Pendulum(), [2.5, 0.0], True),
    "Pendulum damped": (_S.Pendulum(damping=0.3), [2.5, 0.0], False),
    "Pendulum driven": (_S.Pendulum(drive_amplitude=0.5, drive_frequency=1.2), [2.5, 0.0], True),
    "Duffing": (_S.Duffing(alpha=-1.0, beta=1.0), [1.0, 0.0], True),
    "Duffing driven": (_S.Duffing(alpha=-1.0, beta=1.0, gamma=0.3, omega=1.2), [1.0, 0.0], True),
    "VanDerPol": (_S.VanDerPol(mu=2.0), [2.0, 0.0], False),
    "Kepler": (_S.Kepler(), [1.0, 0.0, 0.0, 1.1], True),
    # generic blocks
    "SpringChain": (_S.SpringChain(masses=[1.0, 2.0, 1.0], alpha=0.25), [0.1, 0.0, -0.1, 0, 0, 0],
                    True),
    "Foucault": (_S.Foucault(latitude=45.0, length=10.0), [0.1, 0.0, 0.0, 0.0], False),
}


@pytest.mark.parametrize("name, method", [
    (name, m) for name, (_, _, separable) in sorted(FIXED_BLOCK_CASES.items())
    for m in (["rk4", "verlet", "yoshida4", "yoshida6"] if separable else ["rk4"])])
def test_fixed_step_blocks_equal_the_checked_loop(name, method):
    # the fast blocks (a scene's own, or the generic one) against the checked
    # loop every step of which is a method row's step (dense output keeps the
    # driver out of the blocks): the same states and counts, bit for bit
    scene, y0, _ = FIXED_BLOCK_CASES[name]
    fast = mp.solve(scene, (0, 12.345), y0, method=method, h=0.01)
    checked = mp.solve(scene, (0, 12.345), y0, method=method, h=0.01, dense_output=True)
    assert fast.nsteps == checked.nsteps == 1235 and fast.nfev == checked.nfev
    assert np.array_equal(fast.t, checked.t) and np.array_equal(fast.y, checked.y)


def test_scalar_atol_is_the_same_as_n_copies():
    # solve hands a scalar atol to the C core, which spreads it over the states
    p = mp.scenes.Kepler()
    y0 = p.initial_state(0.6)
    a = mp.solve(p, (0, 20), y0, rtol=1e-7, atol=1e-9)
    b = mp.solve(p, (0, 20), y0, rtol=1e-7, atol=np.full(4, 1e-9))
    c = mp.solve(p, (0, 20), y0, rtol=1e-7, atol=[1e-9])
    assert a.nfev == b.nfev == c.nfev and np.array_equal(a.y, b.y) and np.array_equal(a.y, c.y)


@pytest.mark.parametrize("method, order", [("verlet", 2), ("yoshida4", 4), ("yoshida6", 6)])
def test_splitting_methods_on_several_coordinates(method, order):
    # a chain of three unequal masses (nq = 3, each velocity kicked by its own
    # acceleration): the fixed-step splitting methods converge to the exact motion
    # from the normal modes at their order, halving h divides the error by 2^order
    ch = mp.scenes.SpringChain([1.0, 2.0, 0.5], [1.0, 3.0, 0.7, 2.0])
    y0 = np.array([0.3, -0.2, 0.1, 0.0, 0.25, -0.4])
    md = ch.modes()
    te = np.array([0.0, 2.5, 5.0])
    q, v = md.evolve(y0[:3], y0[3:], te, velocities=True)
    exact = np.concatenate([q.T, v.T])   # evolve gives (m, n)
    errs = []
    for h in (0.05, 0.025):
        s = mp.solve(ch, (0, 5), y0, method=method, h=h, t_eval=te)
        errs.append(np.max(np.abs(s.y - exact)))
    # measured at h = 0.05: 6.2e-3, 1.4e-4, 1.2e-7; rates 2.00, 4.00, 6.00
    assert errs[0] < {2: 2e-2, 4: 5e-4, 6: 5e-7}[order], errs
    rate = np.log2(errs[0] / errs[1])
    assert abs(rate - order) < 0.1, (errs, rate)


# ---- args as SciPy takes them (issue 51, item 17) ---------------------------

def test_args_none_is_no_arguments_and_a_non_iterable_is_refused_as_scipy_does():
    # solve_ivp: args=None means no extra arguments, an iterable is unpacked, and a
    # value that cannot be unpacked is a TypeError (not wrapped into a 1-tuple)
    def decay(t, y):
        return -y

    def rate(t, y, a):
        return -a * y

    s = mp.solve(decay, (0, 1), [1.0], args=None, rtol=1e-10, atol=1e-12)
    assert abs(s.y[0, -1] - np.exp(-1.0)) < 1e-9
    e = mp.solve_many(decay, (0, 1), [[1.0], [2.0]], args=None, rtol=1e-10, atol=1e-12)
    assert np.allclose(e.y[:, 0, -1], [np.exp(-1.0), 2 * np.exp(-1.0)], rtol=1e-8, atol=0)
    with pytest.raises(TypeError, match="cannot be unpacked"):
        solve_ivp(rate, (0, 1), [1.0], args=2.0)
    with pytest.raises(TypeError, match=r"args must be a tuple.*args=\(2\.0,\)"):
        mp.solve(rate, (0, 1), [1.0], args=2.0)
    with pytest.raises(TypeError, match=r"args must be a tuple.*args=\(2\.0,\)"):
        mp.solve_many(rate, (0, 1), [[1.0]], args=2.0)
    # a list is unpacked, as by SciPy: y' = -2 y
    ref = solve_ivp(rate, (0, 1), [1.0], args=[2.0], rtol=1e-10, atol=1e-12).y[0, -1]
    got = mp.solve(rate, (0, 1), [1.0], args=[2.0], rtol=1e-10, atol=1e-12).y[0, -1]
    assert abs(got - np.exp(-2.0)) < 1e-9 and abs(ref - np.exp(-2.0)) < 1e-8


# Every row of the method table against a reference (CONTRIBUTING's "new
# method" recipe: a new row adds its bound here): x'' = -x over [0, 10]
# against cos t, sin t (adaptive rows at rtol 1e-8, fixed-step rows at
# h = 0.01); a rigid-body splitting on a torque-free RigidBody against
# dop853 at rtol 1e-13.  Each bound is about 5x the error measured.
CROSS_CHECK = {"rk4": 3.5e-9, "dopri5": 5e-8, "dop853": 5.5e-8, "radau": 1.5e-8,
               "auto": 5.5e-8, "verlet": 2e-4, "yoshida4": 3e-8, "yoshida6": 2e-13,
               "gauss4": 6e-10, "gsl:rk2": 3.2e-8, "gsl:rk4": 4e-7, "gsl:rkf45": 7.5e-8,
               "gsl:rkck": 6e-8, "gsl:rk8pd": 1.8e-9, "gsl:msadams": 3e-6,
               "gsl:rk1imp": 1e-3, "gsl:rk2imp": 9e-6, "gsl:rk4imp": 2.8e-7,
               "gsl:bsimp": 1.8e-9, "gsl:msbdf": 7.5e-6, "rigid:split": 1e-4,
               "rigid:split4": 2.8e-9}


@pytest.mark.parametrize("row", mp.methods(), ids=lambda m: m["name"])
def test_every_method_row_against_a_reference(row):
    name = row["name"]
    assert name in CROSS_CHECK, f"method {name}: add its bound to CROSS_CHECK"
    t = np.linspace(0, 10, 11)
    kw = dict(rtol=1e-8, atol=1e-10) if row["adaptive"] else dict(h=0.01)
    if row["rigid"]:
        body = mp.scenes.RigidBody([1.0, 2.0, 3.0])
        w0 = [0.3, 1.0, 0.2]
        ref = mp.solve(body, (0, 10), w0, t_eval=t, rtol=1e-13, atol=1e-14).y
        s = mp.solve(body, (0, 10), w0, t_eval=t, method=name, **kw)
    else:
        ref = np.array([np.cos(t), -np.sin(t)])
        s = mp.solve(mp.SecondOrder(lambda t, q: -q), (0, 10), [1.0, 0.0], t_eval=t,
                     method=name, **kw)
    assert s.success, s.message
    err = np.max(np.abs(s.y - ref))
    assert err < CROSS_CHECK[name], err


def test_cross_check_names_only_rows():
    assert sorted(CROSS_CHECK) == sorted(m["name"] for m in mp.methods())


def test_core_calls_take_one_options_object():
    """_core.ode_solve and ode_solve_many share one calling convention,
    (method, system, y0, options), the options built by integrate._options
    alone: a missing, unknown or foreign key is a TypeError naming it, and the
    same options give the same solve as mp.solve."""
    from mechpy import _core
    from mechpy.integrate import _options
    P = mp.scenes.Pendulum()
    spec = ("scene", P._model, P._vector())
    y0 = np.array([1.0, 0.0])

    def opts(own, **change):
        o = _options(0.0, 1.0, 1e-8, 1e-10, None, 0.0, 0.0, np.inf, 10**7, None, None, None,
                     (), None, None, None, own)
        o.update(change)
        return o
    r = _core.ode_solve("dop853", spec, y0, opts({"dense": False}))
    s = mp.solve(P, (0, 1), y0)
    assert r[0] == 0 and np.array_equal(r[3].T, s.y) and r[4] == s.nfev
    bad = opts({"dense": False})
    del bad["atol"]
    with pytest.raises(TypeError, match="options lack atol"):
        _core.ode_solve("dop853", spec, y0, bad)
    with pytest.raises(TypeError, match="unknown option 'threads'"):
        _core.ode_solve("dop853", spec, y0, opts({"dense": False, "threads": 1}))
    with pytest.raises(TypeError, match="unknown option 'colour'"):
        _core.ode_solve("dop853", spec, y0, opts({"dense": False}, colour=1))
    with pytest.raises(TypeError, match="options lack dense"):
        _core.ode_solve("dop853", spec, y0, opts({}))
    with pytest.raises(TypeError, match="option args must be a tuple"):
        _core.ode_solve("dop853", spec, y0, opts({"dense": False}, args=[]))
    with pytest.raises(TypeError, match="options must be a dict"):
        _core.ode_solve("dop853", spec, y0, tuple(opts({"dense": False}).values()))
    with pytest.raises(TypeError, match="takes 4 arguments"):
        _core.ode_solve_many("dop853", spec, y0[None])
    with pytest.raises(TypeError, match="options lack params"):
        _core.ode_solve_many("dop853", spec, y0[None], opts({}, t_eval=np.array([1.0])))
    many = {"params": None, "threads": 1, "progress": False, "lanes": 0}
    e = _core.ode_solve_many("dop853", spec, y0[None], opts(many, t_eval=np.array([1.0])))
    assert np.array_equal(e["y"][0, :, -1], s.y[:, -1])
    with pytest.raises(ValueError, match="unknown system kind spline"):
        _core.ode_solve("dop853", ("spline",) + spec[1:], y0, opts({"dense": False}))


@pytest.mark.parametrize("errors", ["quiet", "Raise", "", None, 1, ("raise",)])
def test_errors_mode_outside_the_table_is_refused_before_any_solve(errors):
    """errors is one of "auto", "raise", "status": any other value, a string
    or not, is a ValueError naming the three, for solve and solve_many, and
    the right-hand side is never called."""
    calls = []

    def f(t, y):
        calls.append(t)
        return -y

    for call in (lambda: mp.solve(f, (0, 1), [1.0], errors=errors),
                 lambda: mp.solve_many(mp.scenes.Pendulum(), (0, 1), [[1.0, 0.0]],
                                       errors=errors)):
        with pytest.raises(ValueError, match=r"errors must be one of \('auto', 'raise', "
                                             r"'status'\)"):
            call()
    assert calls == []


@pytest.mark.parametrize("t_eval, error, match", [
    ([0.0, float("nan")], ValueError, "t_eval must be finite"),
    ((0.5, float("inf")), ValueError, "t_eval must be finite"),
    (np.array([0.0, np.nan]), ValueError, "t_eval must be finite"),
    ([[0.0, 0.5], [1.0, 1.5]], ValueError, r"t_eval must have 1 dimension\(s\)"),
    ([0.0, 0.5, [1.0]], ValueError, "t_eval"),
    (["a"] * 10, TypeError, "t_eval must be a real numeric array"),
    ([0.1 * k for k in range(12)] + [0.5], ValueError, "strictly increasing"),
    ([0.0, 0.5, 3.0], ValueError, "within t_span"),
])
def test_t_eval_of_every_form_gets_the_message_that_names_its_fault(t_eval, error, match):
    # a short list of floats is checked on a fast path of its own (integrate._t_eval):
    # it must say what the array path says
    with pytest.raises(error, match=match):
        mp.solve(mp.scenes.Pendulum(), (0, 2), [1.0, 0.0], t_eval=t_eval)
