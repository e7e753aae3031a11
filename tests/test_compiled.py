"""A user's own system compiled to C: mp.coordinates, mp.lagrangian, mp.equations.

Checked against equations derived by hand (double and spherical pendulum,
written below in NumPy), SciPy's solve_ivp on them, the built-in scenes
(Pendulum, HeavyTop) rebuilt from their Lagrangians, closed forms (normal-mode
frequencies, string tension), conservation laws, and the cache's behaviour
across processes."""
import os
import pickle
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from sympy.codegen import cfunctions

import mechpy as mp

t = sp.Symbol("t")
G = 9.81


@pytest.fixture(scope="module", autouse=True)
def cache(tmp_path_factory):
    """A fresh cache folder for this module (the first build compiles)."""
    d = str(tmp_path_factory.mktemp("mechpy_cache"))
    old = os.environ.get("MECHPY_CACHE_DIR")
    os.environ["MECHPY_CACHE_DIR"] = d
    yield d
    if old is None:
        del os.environ["MECHPY_CACHE_DIR"]
    else:
        os.environ["MECHPY_CACHE_DIR"] = old


# ---- systems ----------------------------------------------------------------

def double_pendulum_L():
    th1, th2 = mp.coordinates("theta1 theta2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
    T = m1 / 2 * (x1.diff(t) ** 2 + y1.diff(t) ** 2) + m2 / 2 * (x2.diff(t) ** 2
                                                                 + y2.diff(t) ** 2)
    return T - (m1 * g * y1 + m2 * g * y2), [th1, th2]


DP = dict(m1=1.3, m2=0.7, l1=1.1, l2=0.8, g=G)


@pytest.fixture(scope="module")
def double_pendulum():
    L, q = double_pendulum_L()
    return mp.lagrangian(L, q, params=DP)


def dp_hand(t_, y, m1=1.3, m2=0.7, l1=1.1, l2=0.8, g=G):
    """The textbook double pendulum (angles from the downward vertical)."""
    a1, a2, w1, w2 = y
    d = a1 - a2
    M = np.array([[(m1 + m2) * l1, m2 * l2 * np.cos(d)], [l1 * np.cos(d), l2]])
    F = np.array([-m2 * l2 * w2 ** 2 * np.sin(d) - (m1 + m2) * g * np.sin(a1),
                  l1 * w1 ** 2 * np.sin(d) - g * np.sin(a2)])
    return np.concatenate([[w1, w2], np.linalg.solve(M, F)])


def spherical_L():
    th, ph = mp.coordinates("theta phi")
    m, l, g = sp.symbols("m l g")
    L = m * l ** 2 / 2 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) \
        + m * g * l * sp.cos(th)
    return L, [th, ph]


SP = dict(m=0.5, l=1.2, g=G)


@pytest.fixture(scope="module")
def spherical():
    L, q = spherical_L()
    return mp.lagrangian(L, q, params=SP)


def sp_hand(t_, y, l=1.2, g=G):
    """Spherical pendulum, theta from the downward vertical."""
    th, ph, thd, phd = y
    return np.array([thd, phd, np.sin(th) * np.cos(th) * phd ** 2 - g / l * np.sin(th),
                     -2.0 * thd * phd * np.cos(th) / np.sin(th)])


def pendulum_L():
    th, = mp.coordinates("theta")
    m, l, g = sp.symbols("m length g")
    return m * l ** 2 / 2 * th.diff(t) ** 2 + m * g * l * sp.cos(th), [th]


@pytest.fixture(scope="module")
def pendulum():
    L, q = pendulum_L()
    return mp.lagrangian(L, q, params=dict(m=1.0, length=1.0, g=G))


def cartesian_pendulum(**kw):
    x, y = mp.coordinates("x y")
    m, g, l = sp.symbols("m g l")
    L = m / 2 * (x.diff(t) ** 2 + y.diff(t) ** 2) - m * g * y
    return mp.lagrangian(L, [x, y], params=dict(m=0.8, g=G, l=1.0),
                         constraints=[x ** 2 + y ** 2 - l ** 2], **kw)


def cart_state(theta, omega, l=1.0):
    return np.array([l * np.sin(theta), -l * np.cos(theta), l * np.cos(theta) * omega,
                     l * np.sin(theta) * omega])


def fd_jacobian(f, y, h=1e-6):
    J = np.empty((y.size, y.size))
    for j in range(y.size):
        e = np.zeros(y.size)
        e[j] = h * max(1.0, abs(y[j]))
        J[:, j] = (f(y + e) - f(y - e)) / (2 * e[j])
    return J


# ---- against equations derived by hand ------------------------------------

def test_double_pendulum_rhs_against_hand_equations(double_pendulum, rng):
    s = double_pendulum
    assert s.dim == 4 and list(s.params) == list(DP)
    Y = rng.uniform(-3, 3, size=(4, 50))
    f = s.rhs(0.0, Y)
    ref = np.stack([dp_hand(0, y) for y in Y.T], axis=1)
    assert f.shape == (4, 50)
    assert np.abs(f - ref).max() < 3e-15 * np.abs(ref).max()   # measured 2.8e-16 relative
    y = Y[:, 0]
    assert s.rhs(0.0, y).shape == (4,)
    J = s.jacobian(0.0, Y[:, :3])
    assert J.shape == (4, 4, 3)
    for i in range(3):
        Jref = fd_jacobian(lambda v: dp_hand(0, v), Y[:, i])
        assert np.abs(J[:, :, i] - Jref).max() < 2e-9 * np.abs(Jref).max()  # measured 2.0e-10


def test_double_pendulum_trajectory_against_solve_ivp(double_pendulum):
    y0 = [1.2, -0.4, 0.3, 0.0]
    te = np.linspace(0, 5, 51)
    ours = mp.solve(double_pendulum, (0, 5), y0, rtol=1e-12, atol=1e-12, t_eval=te)
    ref = solve_ivp(dp_hand, (0, 5), y0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=te)
    assert np.abs(ours.y - ref.y).max() < 3e-12     # measured 3.0e-13
    # the Jacobi integral is the energy here, conserved
    E = double_pendulum.energy(ours.y)
    assert E.shape == (51,)
    assert np.abs(E - E[0]).max() < 3e-11 * abs(E[0])   # measured 2.5e-12 relative


def test_double_pendulum_normal_modes():
    L, q = double_pendulum_L()
    s = mp.lagrangian(L, q, params=dict(m1=1.0, m2=1.0, l1=0.5, l2=0.5, g=G))
    modes = s.small_oscillations([0.0, 0.0])
    ref = G / 0.5 * np.array([2 - np.sqrt(2), 2 + np.sqrt(2)])
    assert np.allclose(modes.omega ** 2, ref, rtol=1e-14, atol=0)   # measured 6.7e-16
    # the slow mode is in phase, amplitude ratio sqrt 2
    v = modes.vectors[:, 0]
    assert v[1] / v[0] == pytest.approx(np.sqrt(2), rel=1e-14)   # measured 2.2e-16
    with pytest.raises(ValueError, match="not an equilibrium"):
        s.small_oscillations([0.3, 0.0])


def test_spherical_pendulum(spherical, rng):
    s = spherical
    Y = np.vstack([rng.uniform(0.2, 2.9, 20), rng.uniform(-3, 3, 20), rng.uniform(-2, 2, 20),
                   rng.uniform(-2, 2, 20)])
    ref = np.stack([sp_hand(0, y) for y in Y.T], axis=1)
    assert np.abs(s.rhs(0.0, Y) - ref).max() < 3e-15 * np.abs(ref).max()   # measured 3.0e-16
    assert s.cyclic == ["phi"]
    y0 = [1.0, 0.0, 0.2, 1.5]
    te = np.linspace(0, 20, 201)
    sol = mp.solve(s, (0, 20), y0, rtol=1e-11, atol=1e-12, t_eval=te)
    ref = solve_ivp(sp_hand, (0, 20), y0, method="DOP853", rtol=1e-11, atol=1e-12, t_eval=te)
    assert np.abs(sol.y - ref.y).max() < 5e-12    # measured 5.1e-13
    p = s.momenta(sol.y)
    assert p.shape == (2, 201)
    m, l = SP["m"], SP["l"]
    # p_phi = m l^2 sin^2 theta phi_dot, conserved (phi is cyclic)
    assert np.allclose(p[1], m * l * l * np.sin(sol.y[0]) ** 2 * sol.y[3], rtol=1e-13)
    assert np.abs(p[1] - p[1, 0]).max() < 3e-10 * abs(p[1, 0])   # measured 2.7e-11
    E = s.energy(sol.y)
    assert np.abs(E - E[0]).max() < 7e-10 * abs(E[0])            # measured 6.8e-11


def test_lagrangian_c_for_the_variational_solvers(spherical):
    import ctypes
    addr, p = spherical._lagrangian_c
    assert isinstance(addr, int) and p.tolist() == list(SP.values())
    dp = ctypes.POINTER(ctypes.c_double)
    f = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_size_t, dp, dp, dp, dp, ctypes.c_void_p)(addr)
    m, l, g = SP["m"], SP["l"], SP["g"]

    def Lnum(q, qd):
        return m * l * l / 2 * (qd[0] ** 2 + np.sin(q[0]) ** 2 * qd[1] ** 2) \
            + m * g * l * np.cos(q[0])

    q = np.array([[0.7, 0.1], [1.3, -2.0]])
    qd = np.array([[0.4, -0.9], [1.1, 0.3]])
    tt = np.zeros(2)
    out = np.zeros((2, 1 + 4 + 12))
    assert f(2, tt.ctypes.data_as(dp), q.ctypes.data_as(dp), qd.ctypes.data_as(dp),
             out.ctypes.data_as(dp), p.ctypes.data) == 0
    h = 1e-5
    for i in range(2):
        assert out[i, 0] == pytest.approx(Lnum(q[i], qd[i]), rel=1e-15)   # measured 0
        for a in range(2):
            e = np.eye(2)[a] * h
            dq = (Lnum(q[i] + e, qd[i]) - Lnum(q[i] - e, qd[i])) / (2 * h)
            dv = (Lnum(q[i], qd[i] + e) - Lnum(q[i], qd[i] - e)) / (2 * h)
            assert out[i, 1 + a] == pytest.approx(dq, abs=1e-9)   # central differences: 1.1e-10
            assert out[i, 3 + a] == pytest.approx(dv, abs=1e-9)
        # d2L/dqd dqd = diag(m l^2, m l^2 sin^2 theta)
        Mref = np.diag([m * l * l, m * l * l * np.sin(q[i, 0]) ** 2])
        assert np.allclose(out[i, 13:17].reshape(2, 2), Mref, rtol=1e-14, atol=1e-15)
        # d2L/dq dqd: only [theta][phi_dot] = m l^2 2 sin cos phi_dot
        Bref = np.zeros((2, 2))
        Bref[0, 1] = m * l * l * 2 * np.sin(q[i, 0]) * np.cos(q[i, 0]) * qd[i, 1]
        assert np.allclose(out[i, 9:13].reshape(2, 2), Bref, rtol=1e-14, atol=1e-15)


def test_variational_tools_take_a_compiled_scene(double_pendulum):
    """stationary_path and variational_integrate run on the generated mp_gen_lagrangian:
    the discrete path of stationary action between the ends of a dop853 trajectory
    reproduces it, and the variational integrator follows mp.solve with second-order
    error and a bounded energy error."""
    y0 = [0.4, -0.3, 0.0, 0.5]
    T = 1.0
    ref = mp.solve(double_pendulum, (0, T), y0, rtol=1e-12, atol=1e-12, dense_output=True)
    path = mp.variational.stationary_path(double_pendulum, ref.y[:2, 0], ref.y[:2, -1], T,
                                          n=400)
    tt = np.linspace(0, T, path.q.shape[1])
    err = np.abs(path.q - ref.sol(tt)[:2]).max()
    assert err < 1e-4                                   # measured 1.5e-5 (second order)
    errs = []
    for h in (2e-3, 1e-3):
        vi = mp.variational.variational_integrate(double_pendulum, (0, T), y0[:2], y0[2:], h)
        errs.append(np.abs(vi.q[:, -1] - ref.y[:2, -1]).max())
    assert 3.5 < errs[0] / errs[1] < 4.5                # measured 4.0 (order 2)
    assert errs[1] < 3e-5                                # measured 3.9e-6
    E = double_pendulum.energy(np.concatenate([vi.q, vi.qdot]))
    assert np.abs(E - E[0]).max() < 4e-7 * abs(E[0])     # measured 3.9e-8


# ---- the built-in scenes rebuilt from their Lagrangians ----------------------

def test_pendulum_from_lagrangian_equals_builtin(pendulum):
    te = np.linspace(0, 10, 101)
    ref = mp.solve(mp.scenes.Pendulum(length=1.0), (0, 10), [2.5, 0.0], rtol=1e-10, t_eval=te)
    ours = mp.solve(pendulum, (0, 10), [2.5, 0.0], rtol=1e-10, t_eval=te)
    assert np.abs(ours.y - ref.y).max() < 1e-13    # measured 0: the same numbers
    assert pendulum.dim == 2 and pendulum._meta["nq"] == 1   # separable


@pytest.mark.parametrize("system, method", [
    ("pendulum", "rk4"), ("pendulum", "verlet"), ("pendulum", "yoshida4"),
    ("pendulum", "yoshida6"), ("double_pendulum", "rk4"), ("lotka_volterra", "rk4")])
def test_fixed_step_blocks_of_a_compiled_system(system, method, request, monkeypatch):
    # the generated library's own fixed-step blocks (the engine's templates
    # with mp_gen_rhs inlined, mp_gen_rk4 / mp_gen_compose) against the checked
    # loop, every step a method row's step (dense output keeps the driver out
    # of the blocks), and against the engine's generic blocks (the spec without
    # them): the same states and counts, bit for bit
    if system == "lotka_volterra":
        x, y = mp.coordinates("x y")
        s = mp.equations([1.1 * x - 0.4 * x * y, 0.1 * x * y - 0.4 * y], [x, y])
        y0 = [10.0, 5.0]
    else:
        s = request.getfixturevalue(system)
        y0 = [2.5, 0.0] if system == "pendulum" else [2.0, -1.0, 0.0, 0.5]
    # separable: the pendulum; not the double pendulum (its mass matrix varies)
    separable = s._meta["nq"] > 0
    assert separable == (system == "pendulum")
    fns = s._spec(method)[1]
    assert fns[4] is not None and (fns[5] is not None) == separable
    fast = mp.solve(s, (0, 12.345), y0, method=method, h=0.01)
    checked = mp.solve(s, (0, 12.345), y0, method=method, h=0.01, dense_output=True)
    assert fast.nsteps == checked.nsteps == 1235 and fast.nfev == checked.nfev
    assert np.array_equal(fast.t, checked.t) and np.array_equal(fast.y, checked.y)
    monkeypatch.setattr(s, "_addr_blocks", (None, None))
    generic = mp.solve(s, (0, 12.345), y0, method=method, h=0.01)
    assert generic.nfev == fast.nfev and np.array_equal(generic.y, fast.y)


#: A program around csrc/gen/*.h (the C every generated system shares, as
#: codegen pastes it: lanes.h, then lu.h, closed.h and lu_lanes.h): mp_lu and
#: mp_lu_solve on one NA x NA system, mp_lu_lanes on MP_LANES of them (lane l's
#: matrix is A + l I), and mp_closed_ok on A's determinant.
_SHARED_C_MAIN = r"""
#include <stdio.h>
int main(void)
{
    double A0[NA * NA] = {A_ENTRIES}, b0[NA] = {B_ENTRIES};
    double A[NA * NA], x[NA], dinv[NA];
    int piv[NA];
    for (int i = 0; i < NA * NA; i++) A[i] = A0[i];
    for (int i = 0; i < NA; i++) x[i] = b0[i];
    if (mp_lu(A, piv, dinv) != MP_OK) return 1;
    mp_lu_solve(A, piv, dinv, x);
    for (int i = 0; i < NA; i++) printf("%.17g\n", x[i]);
    double AL[NA * NA * MP_LANES], bl[NA * MP_LANES];
    int st[MP_LANES];
    for (int i = 0; i < NA; i++)
        for (int j = 0; j < NA; j++)
            for (int l = 0; l < MP_LANES; l++)
                AL[(i * NA + j) * MP_LANES + l] = A0[i * NA + j] + (i == j ? l : 0);
    for (int i = 0; i < NA; i++)
        for (int l = 0; l < MP_LANES; l++) bl[i * MP_LANES + l] = b0[i];
    mp_lu_lanes(AL, bl, st);
    for (int l = 0; l < MP_LANES; l++) {
        if (st[l] != MP_OK) return 2;
        for (int i = 0; i < NA; i++) printf("%.17g\n", bl[i * MP_LANES + l]);
    }
    printf("%d %d\n", mp_closed_ok(DET, ASUM, NA), mp_closed_normal(0.0));
    return 0;
}
"""


def test_shared_c_is_real_c_that_solves(tmp_path):
    """csrc/gen/*.h are the text codegen pastes into every generated system
    (mechpy.symbolic._ctext, embedded at build time), and compile as C with
    -Wall -Wextra -Werror: mp_lu/mp_lu_solve and the lane solver against
    numpy.linalg.solve, mp_closed_ok against the determinant's test."""
    from pathlib import Path

    from mechpy.symbolic import _ctext, build, codegen
    gen = Path(__file__).resolve().parents[1] / "csrc" / "gen"
    files = sorted(gen.glob("*.h"))
    assert [f.stem.upper() for f in files] == ["CLOSED", "LANES", "LU", "LU_LANES"]
    for f in files:
        assert getattr(_ctext, f.stem.upper()) == f.read_text(), f.name
        assert f.read_text() in codegen.RUNTIME + codegen.LANE_RUNTIME \
            + codegen.LANE_SOLVER + codegen.CLOSED, f.name
    if not build.have_compiler():
        pytest.skip("no C compiler")
    rng = np.random.default_rng(48)
    lanes = mp._core.LANES
    for na in (2, 5):
        A = rng.standard_normal((na, na)) + na * np.eye(na)
        b = rng.standard_normal(na)
        status = "\n".join(f"#define {k} {v}" for k, v in sorted(mp._core.STATUS.items()))
        c = lambda v: repr(float(v))  # noqa: E731
        main = (_SHARED_C_MAIN.replace("A_ENTRIES", ", ".join(map(c, A.ravel())))
                .replace("B_ENTRIES", ", ".join(map(c, b)))
                .replace("DET", c(np.linalg.det(A))).replace("ASUM", c(np.abs(A).sum())))
        src = tmp_path / f"shared{na}.c"
        src.write_text("#include <float.h>\n#include <math.h>\n#include <stddef.h>\n"
                       f"{status}\n#define NA {na}\n#define MP_LANES {lanes}\n"
                       + "".join((gen / f).read_text()
                                 for f in ("lanes.h", "lu.h", "closed.h", "lu_lanes.h"))
                       + main)
        exe = tmp_path / f"shared{na}"
        subprocess.run(build.compiler() + ["-std=c99", "-O2", "-fopenmp-simd", "-Wall",
                                           "-Wextra", "-Werror", str(src), "-o", str(exe),
                                           "-lm"], check=True, capture_output=True)
        out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
        lines = out.split()
        x = np.array(lines[:na], float)
        np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-13, atol=1e-14)
        xl = np.array(lines[na:na + na * lanes], float).reshape(lanes, na)
        for l in range(lanes):
            np.testing.assert_allclose(xl[l], np.linalg.solve(A + l * np.eye(na), b),
                                       rtol=1e-13, atol=1e-14)
        assert lines[-2:] == ["1", "0"]     # A's det is well away from 0; 0.0 is not normal


def test_generated_blocks_are_the_engines_template():
    # the text generated systems instantiate is csrc/ode/fixed.h as built
    from pathlib import Path
    header = Path(__file__).resolve().parents[1] / "csrc" / "ode" / "fixed.h"
    assert mp._core.FIXED_STEPS_C == header.read_text()
    assert "MP_ODE_BLOCK_FNS" in mp._core.FIXED_STEPS_C


def test_damped_pendulum_through_forces():
    L, q = pendulum_L()
    b = sp.Symbol("b")
    s = mp.lagrangian(L, q, params=dict(m=2.0, length=0.7, g=G, b=0.3),
                      forces=[-b * 2.0 * 0.7 ** 2 * q[0].diff(t)])
    assert s._meta["nq"] == 0      # a force: not separable
    te = np.linspace(0, 10, 101)
    ref = mp.solve(mp.scenes.Pendulum(length=0.7, damping=0.3), (0, 10), [1.0, 0.5],
                   rtol=1e-11, atol=1e-12, t_eval=te)
    ours = mp.solve(s, (0, 10), [1.0, 0.5], rtol=1e-11, atol=1e-12, t_eval=te)
    assert np.abs(ours.y - ref.y).max() < 3e-13    # measured 2.5e-14


def test_heavy_top_from_lagrangian_equals_builtin():
    ph, th, ps = mp.coordinates("phi theta psi")
    I1, I3, M, g, l = sp.symbols("I1 I3 mass g l")
    w3 = ps.diff(t) + ph.diff(t) * sp.cos(th)
    L = I1 / 2 * (th.diff(t) ** 2 + ph.diff(t) ** 2 * sp.sin(th) ** 2) + I3 / 2 * w3 ** 2 \
        - M * g * l * sp.cos(th)
    par = dict(I1=1.2, I3=0.6, mass=1.5, g=G, l=0.4)
    s = mp.lagrangian(L, [ph, th, ps], params=par)
    assert s.cyclic == ["phi", "psi"]
    top = mp.scenes.HeavyTop(**par)
    y0 = [0.0, 0.6, 0.0, 0.4, 0.0, 9.0]
    Y = np.array([y0, [0.3, 1.2, -0.5, -0.7, 0.8, 4.0]]).T
    assert np.allclose(s.rhs(0, Y), top.rhs(0, Y), rtol=1e-14, atol=1e-14)  # measured 8.9e-16
    assert np.allclose(s.jacobian(0, Y), top.jacobian(0, Y), rtol=1e-14, atol=1e-14)  # 8.9e-16
    te = np.linspace(0, 10, 101)
    for method in ("dop853", "radau"):
        a = mp.solve(s, (0, 10), y0, method=method, rtol=1e-10, t_eval=te)
        b = mp.solve(top, (0, 10), y0, method=method, rtol=1e-10, t_eval=te)
        assert np.abs(a.y - b.y).max() < 3e-12     # measured 2.8e-14 (dop853), 4.8e-13 (radau)
    E = s.energy(a.y)
    assert np.abs(E - top.energy(a.y)).max() < 5e-15 * abs(E[0])   # h is E; measured 4.6e-16
    p = s.momenta(a.y)
    assert np.allclose(p[0], top.p_phi(a.y), rtol=1e-13)
    assert np.allclose(p[2], top.p_psi(a.y), rtol=1e-13)


# ---- constraints -------------------------------------------------------------

def test_cartesian_pendulum_with_constraint():
    s = cartesian_pendulum()
    assert s._meta["k"] == 1 and s.dim == 4
    th0, w0 = 1.2, 0.3
    te = np.linspace(0, 10, 201)
    sol = mp.solve(s, (0, 10), cart_state(th0, w0), rtol=1e-11, atol=1e-12, t_eval=te)
    ref = mp.solve(mp.scenes.Pendulum(length=1.0), (0, 10), [th0, w0], rtol=1e-11,
                   atol=1e-12, t_eval=te)
    theta = np.arctan2(sol.y[0], -sol.y[1])
    assert np.abs(theta - ref.y[0]).max() < 3e-10      # measured 3.5e-11
    # the string tension m (g cos theta + l theta_dot^2), along -r
    f = s.constraint_forces(0.0, sol.y)
    assert f.shape == (2, 201)
    tension = 0.8 * (G * np.cos(ref.y[0]) + ref.y[1] ** 2)
    assert np.abs(np.hypot(f[0], f[1]) - tension).max() < 1e-9 * tension.max()  # measured 1.2e-10
    r = sol.y[:2]
    assert np.all(np.sum(f * r, axis=0) < 0)          # it pulls towards the pivot
    lam = s.multipliers(0.0, sol.y)
    assert lam.shape == (1, 201)
    assert np.allclose(f, 2 * r * lam, rtol=1e-13, atol=1e-13)   # C^T lambda, C = 2 (x, y)
    J = s.jacobian(0.3, sol.y[:, 50])
    Jref = fd_jacobian(lambda v: s.rhs(0.3, v), sol.y[:, 50])
    assert np.abs(J - Jref).max() < 5e-10 * np.abs(Jref).max()   # measured 5.0e-11


def test_double_pendulum_in_cartesian_coordinates_with_two_constraints():
    # two rods as two holonomic constraints (the only system here with k = 2:
    # each constraint's column of the (n + k) system is its own) against the
    # angles' equations of motion, solved by hand, in SciPy's DOP853
    x1, y1, x2, y2 = mp.coordinates("x1 y1 x2 y2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
    L = (m1 / 2 * (x1.diff(t) ** 2 + y1.diff(t) ** 2) + m2 / 2 * (x2.diff(t) ** 2
         + y2.diff(t) ** 2) - m1 * g * y1 - m2 * g * y2)
    P = dict(m1=1.0, m2=2.0, l1=1.0, l2=0.7, g=G)
    s = mp.lagrangian(L, [x1, y1, x2, y2], params=P,
                      constraints=[x1 ** 2 + y1 ** 2 - l1 ** 2,
                                   (x2 - x1) ** 2 + (y2 - y1) ** 2 - l2 ** 2])
    assert s._meta["k"] == 2 and s.dim == 8
    M1, M2, L1, L2 = P["m1"], P["m2"], P["l1"], P["l2"]

    def angles(_t, z):
        a, b, wa, wb = z
        c, d = np.cos(a - b), np.sin(a - b)
        A = [[(M1 + M2) * L1 ** 2, M2 * L1 * L2 * c], [M2 * L1 * L2 * c, M2 * L2 ** 2]]
        r = [-M2 * L1 * L2 * d * wb ** 2 - (M1 + M2) * G * L1 * np.sin(a),
             M2 * L1 * L2 * d * wa ** 2 - M2 * G * L2 * np.sin(b)]
        return np.r_[wa, wb, np.linalg.solve(A, r)]

    def cartesian(a, b, wa, wb):
        p1 = L1 * np.array([np.sin(a), -np.cos(a)])
        v1 = L1 * wa * np.array([np.cos(a), np.sin(a)])
        p2 = p1 + L2 * np.array([np.sin(b), -np.cos(b)])
        v2 = v1 + L2 * wb * np.array([np.cos(b), np.sin(b)])
        return np.r_[p1, p2, v1, v2]

    z0 = [0.5, -0.3, 0.2, 0.0]
    te = np.linspace(0, 3, 61)
    ref = solve_ivp(angles, (0, 3), z0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=te)
    sol = mp.solve(s, (0, 3), cartesian(*z0), rtol=1e-11, atol=1e-12, t_eval=te)
    want = np.array([cartesian(*z) for z in ref.y.T]).T
    assert np.abs(sol.y[:4] - want[:4]).max() < 4e-11   # positions, measured 3.8e-12
    assert np.abs(sol.y[4:] - want[4:]).max() < 4e-10   # velocities, measured 4.4e-11
    # the outer rod pulls mass 2 along the rod only
    f = s.constraint_forces(0.0, sol.y)
    rod = sol.y[2:4] - sol.y[0:2]
    cross = f[2] * rod[1] - f[3] * rod[0]
    assert np.abs(cross).max() < 5e-16 * np.abs(f[2:4]).max()   # measured 3.2e-17


def test_constraint_forces_and_multipliers_take_a_solutions_times():
    # a mass on a vertically driven constraint y = A sin(w t): lambda = m (g + y''),
    # y'' = -A w^2 sin(w t), a force along y only.  The natural call with a
    # solution's arrays raised "t must be a real scalar"; t broadcasts as y does
    x, y = mp.coordinates("x y")
    m, g, A, w = sp.symbols("m g A w", positive=True)
    L = m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2 - m * g * y
    s = mp.lagrangian(L, [x, y], params=dict(m=2.0, g=G, A=0.3, w=5.0),
                      constraints=[y - A * sp.sin(w * t)])
    te = np.linspace(0, 3, 61)
    sol = mp.solve(s, (0, 3), [0.0, 0.0, 0.5, 1.5], rtol=1e-11, atol=1e-12, t_eval=te)
    lam_ref = 2.0 * (G - 0.3 * 25.0 * np.sin(5.0 * te))
    lam = s.multipliers(sol.t, sol.y)
    assert lam.shape == (1, 61)
    assert np.abs(lam[0] - lam_ref).max() < 1e-9 * lam_ref.max()   # measured 4e-12 relative
    f = s.constraint_forces(sol.t, sol.y)
    assert f.shape == (2, 61) and np.all(f[0] == 0.0)
    np.testing.assert_array_equal(f[1], lam[0])                      # C = (0, 1)
    # column j at its own time: the same as the scalar call there
    assert s.multipliers(te[20], sol.y[:, 20])[0] == lam[0, 20]
    # a scalar state against several times; shapes that do not broadcast are named
    assert s.multipliers(te[:3], sol.y[:, 20]).shape == (1, 3)
    with pytest.raises(ValueError, match="t must be a scalar or broadcast"):
        s.multipliers(te[:3], sol.y)


def test_constraint_drift_over_a_long_run():
    s = cartesian_pendulum()
    sol = mp.solve(s, (0, 1000), cart_state(2.0, 0.0), rtol=1e-9, atol=1e-10,
                   t_eval=np.linspace(0, 1000, 2001))
    g = s.constraints(0.0, sol.y)[0]
    # Baumgarte (alpha = beta = 5/s) holds the drift at the integrator's local
    # error level: measured max |x^2 + y^2 - l^2| = 1.6e-9 over the first 100 s,
    # 1.2e-8 over 1000 s (~500 swings of 2 rad)
    assert np.abs(g).max() < 1e-7
    # without stabilisation the drift grows along the run: measured 1.0e-5
    # after 100 s, 1.0e-3 after 1000 s
    s0 = cartesian_pendulum(baumgarte=(0.0, 0.0))
    sol0 = mp.solve(s0, (0, 1000), cart_state(2.0, 0.0), rtol=1e-9, atol=1e-10,
                    t_eval=np.linspace(0, 1000, 2001))
    g0 = s0.constraints(0.0, sol0.y)[0]
    assert np.abs(g0).max() > 1e4 * np.abs(g).max()


def test_initial_state_must_satisfy_the_constraint():
    s = cartesian_pendulum()
    with pytest.raises(ValueError, match="violates constraint 0"):
        mp.solve(s, (0, 1), [1.0, -0.5, 0.0, 0.0])
    with pytest.raises(ValueError, match="violates constraint 0"):   # no step: checked too
        mp.solve(s, (1, 1), [1.0, -0.5, 0.0, 0.0])
    with pytest.raises(ValueError, match="rate of constraint 0"):
        mp.solve(s, (0, 1), [0.0, -1.0, 0.0, 1.0])
    good = cart_state(0.5, 0.2)
    with pytest.raises(ValueError, match=r"y0 \(row 1 of y0s\) violates constraint 0"):
        mp.solve_many(s, (0, 1), [good, [1.0, -0.5, 0.0, 0.0]])
    # the check uses each trajectory's parameters: here the length l
    with pytest.raises(ValueError, match=r"row 1 of y0s"):
        mp.solve_many(s, (0, 1), [good, good], params={"l": [1.0, 2.0]})
    ens = mp.solve_many(s, (0, 1), [good, 2 * good], params={"l": [1.0, 2.0]}, rtol=1e-10)
    assert ens.success.all()
    # the test is relative to the square of the state's size, max(1, max |y|)^2,
    # as x^2 + y^2 - l^2 grows: 1e-8 of it.  Pendulums of 100 m and 1 cm at rest,
    # x moved by d: g = 2 x d + d^2
    for length, limit in ((100.0, 1e-8 * (100.0 * np.cos(0.5)) ** 2), (0.01, 1e-8)):
        sized = s.replace(l=length)
        at = cart_state(0.5, 0.0, l=length)
        for factor, fails in ((0.5, False), (2.0, True)):
            y = at.copy()
            y[0] += factor * limit / (2 * at[0])
            if fails:
                with pytest.raises(ValueError, match="violates constraint 0"):
                    mp.solve(sized, (0, 1e-3), y)
            else:
                assert mp.solve(sized, (0, 1e-3), y).success
    one = mp.solve(s, (0, 1), cart_state(-0.3, 1.0), rtol=1e-10)
    ens = mp.solve_many(s, (0, 1), [good, cart_state(-0.3, 1.0)], rtol=1e-10, lanes=False)
    assert np.array_equal(ens.y[1, :, -1], one.y[:, -1])
    # in SIMD lanes the same steps (nfev equal), rounded apart: measured 4.4e-16
    ens = mp.solve_many(s, (0, 1), [good, cart_state(-0.3, 1.0)], rtol=1e-10, lanes=True)
    assert ens.nfev[1] == one.nfev
    assert np.abs(ens.y[1, :, -1] - one.y[:, -1]).max() < 5e-15


# ---- first-order systems -------------------------------------------------------

def test_equations_first_order_against_solve_ivp():
    x, y = mp.coordinates("x y")
    a, b, c, d = sp.symbols("a b c d")
    rhs = [a * x - b * x * y, d * x * y - c * y]
    H = d * x - c * sp.log(x) + b * y - a * sp.log(y)
    s = mp.equations(rhs, [x, y], params=dict(a=1.1, b=0.4, c=0.4, d=0.1), energy=H)
    assert s.dim == 2

    def lv(t_, v):
        return [1.1 * v[0] - 0.4 * v[0] * v[1], 0.1 * v[0] * v[1] - 0.4 * v[1]]

    te = np.linspace(0, 50, 101)
    sol = mp.solve(s, (0, 50), [10.0, 5.0], rtol=1e-11, atol=1e-12, t_eval=te)
    ref = solve_ivp(lv, (0, 50), [10.0, 5.0], method="DOP853", rtol=1e-11, atol=1e-12,
                    t_eval=te)
    assert np.abs(sol.y - ref.y).max() < 2e-12      # measured 2.2e-13 (populations ~ 10-30)
    E = s.energy(sol.y)
    assert np.abs(E - E[0]).max() < 1e-9           # measured 9.3e-11
    J = s.jacobian(0.0, [2.0, 3.0])
    assert np.allclose(J, [[1.1 - 0.4 * 3, -0.4 * 2], [0.1 * 3, 0.1 * 2 - 0.4]], rtol=1e-15)
    assert isinstance(s.equations[0], sp.Eq)
    with pytest.raises(AttributeError, match="mp.lagrangian"):
        s.momenta([1.0, 1.0])


#: Every form the generator prints or differentiates itself, one per state
#: (so that each is checked on its own): f(x) and the interval x is drawn from.
_a = sp.Symbol("a")
ELEMENTARY = [
    (lambda x: sp.sin(x), (-3, 3)), (lambda x: sp.cos(x), (-3, 3)),
    (lambda x: sp.tan(x), (-1.4, 1.4)), (lambda x: sp.exp(x), (-3, 3)),
    (lambda x: sp.exp(-_a * x), (-3, 3)), (lambda x: sp.log(x), (0.1, 5)),
    (lambda x: sp.sqrt(x), (0.1, 5)), (lambda x: x ** sp.Rational(-1, 2), (0.1, 5)),
    (lambda x: x ** sp.Rational(3, 2), (0.1, 5)), (lambda x: x ** sp.Rational(-3, 2), (0.1, 5)),
    (lambda x: x ** sp.Rational(1, 3), (0.1, 5)), (lambda x: x ** 2, (-3, 3)),
    (lambda x: x ** 3, (-3, 3)), (lambda x: x ** 4, (-3, 3)), (lambda x: x ** 5, (-3, 3)),
    (lambda x: x ** 7, (-3, 3)), (lambda x: 1 / x, (0.2, 3)), (lambda x: x ** -2, (0.2, 3)),
    (lambda x: x ** -3, (0.2, 3)), (lambda x: x ** -5, (0.2, 3)), (lambda x: _a ** x, (-3, 3)),
    (lambda x: x ** x, (0.2, 3)), (lambda x: sp.asin(x), (-0.9, 0.9)),
    (lambda x: sp.acos(x), (-0.9, 0.9)), (lambda x: sp.atan(x), (-3, 3)),
    (lambda x: sp.atan2(x, 0.7), (-3, 3)), (lambda x: sp.atan2(0.7, x), (-3, 3)),
    (lambda x: sp.sinh(x), (-3, 3)), (lambda x: sp.cosh(x), (-3, 3)),
    (lambda x: sp.tanh(x), (-3, 3)), (lambda x: sp.asinh(x), (-3, 3)),
    (lambda x: sp.acosh(x), (1.1, 5)), (lambda x: sp.atanh(x), (-0.9, 0.9)),
    (lambda x: sp.Float("1.23456789012345678") * x, (-3, 3)),
    (lambda x: 12345678901234567 * x, (-3, 3)), (lambda x: sp.Rational(2, 7) * x, (-3, 3)),
    (lambda x: sp.sin(x) * sp.cos(x) ** 3, (-3, 3)),
    (lambda x: sp.log(2 + x ** 2) / x ** 2, (0.2, 3)),
]


def test_elementary_functions_against_sympy(rng):
    # each elementary form on its own state: f(x_i) and d f/d x_i (the diagonal
    # of the Jacobian) against SymPy's diff evaluated with 30 digits, each
    # element to a few units in the last place, so that a wrong sign or a wrong
    # power in one rule shows (an O(1) error in one term is not hidden behind
    # the other terms of a sum)
    xs = mp.coordinates(" ".join(f"x{i}" for i in range(len(ELEMENTARY))))
    fs = [f(x) for (f, _), x in zip(ELEMENTARY, xs)]
    s = mp.equations(fs, xs, params=dict(a=1.7))
    X = sp.Symbol("X")
    worst_f = worst_j = 0.0
    for tv in (0.0, 0.7, 2.0):
        pt = np.array([rng.uniform(*dom) for _, dom in ELEMENTARY])
        got, J = s.rhs(tv, pt), s.jacobian(tv, pt)
        assert np.count_nonzero(J - np.diag(np.diag(J))) == 0
        for i, ((f, _), xv) in enumerate(zip(ELEMENTARY, pt)):
            e = f(X)
            vals = {X: sp.Float(xv, 30), _a: sp.Float(1.7, 30)}
            ref = float(e.evalf(30, subs=vals))
            dref = float(sp.diff(e, X).evalf(30, subs=vals))
            err_f = abs(got[i] - ref) / abs(ref)
            err_j = abs(J[i, i] - dref) / abs(dref)
            assert err_f < 1e-15, (e, xv, got[i], ref)      # measured 2.2e-16 at worst
            assert err_j < 2e-15, (e, xv, J[i, i], dref)    # measured 8.3e-16 at worst
            worst_f, worst_j = max(worst_f, err_f), max(worst_j, err_j)
    assert worst_f > 0 or worst_j > 0      # the points are not all exact


#: Sums and products the C printer rearranges, f(x, y) with parameters a, b: terms
#: that differ by a numeric or parameter factor (gathered into one coefficient),
#: quotients (negative powers moved to a denominator), rational powers of sums.
_b = sp.Symbol("b")
COMBINED = [
    lambda x, y: _a * sp.sin(x) + 2 * sp.sin(x) - _b * sp.sin(x),
    lambda x, y: 3 * x * y - _a * x * y + sp.Rational(1, 3) * x * y + y,
    lambda x, y: x / y ** 2 - _b * x / y ** 2,
    lambda x, y: x * y ** sp.Rational(-3, 2) + y ** sp.Rational(-1, 2),
    lambda x, y: (x ** 2 + y ** 2) ** sp.Rational(-1, 2) - (x ** 2 + y ** 2) ** sp.Rational(3, 2),
    lambda x, y: _a / (x * y) - x ** -4 * y ** 3,
    lambda x, y: sp.exp(-x) * sp.cos(y) - _a * sp.exp(-x) * sp.cos(y) + x ** 5 * y ** -5,
    lambda x, y: -x - y - _a * _b * x * y,
    lambda x, y: sp.atan2(y, x) - sp.atan2(x, y + 3),
    lambda x, y: sp.log(x * y) * sp.sqrt(x + y) - sp.acos(x / (y + 2)),
    # half-integer powers up to 7/2 are printed as products and one sqrt, 9/2 by pow()
    lambda x, y: (x * y ** sp.Rational(5, 2) - y ** sp.Rational(-5, 2)
                  + x ** sp.Rational(7, 2) * y ** sp.Rational(-7, 2) + x ** sp.Rational(9, 2)),
    # a reciprocal shared by several terms (a temporary that multiplies)
    lambda x, y: (x * (x + y) ** sp.Rational(-1, 2) + sp.sin(y) * (x + y) ** sp.Rational(-1, 2)
                  - x ** 2 * (x + y) ** sp.Rational(-3, 2) + y / (x + y)),
]


def test_sums_and_quotients_against_sympy_term_by_term(rng):
    # each form on its own pair of states (x_i, y_i), its row of f and its two
    # Jacobian entries against SymPy with 30 digits, element by element: a lost
    # sign, a coefficient gathered wrongly or a power printed as another shows as
    # an O(1) relative error in that element alone
    n = len(COMBINED)
    xs = mp.coordinates(" ".join(f"x{i}" for i in range(n)))
    ys = mp.coordinates(" ".join(f"y{i}" for i in range(n)))
    fs = [f(x, y) for f, x, y in zip(COMBINED, xs, ys)]
    s = mp.equations(fs + [sp.S.Zero] * n, list(xs) + list(ys), params=dict(a=1.7, b=0.45))
    X, Y = sp.symbols("X Y")
    worst = 0.0
    for tv in (0.0, 1.3):
        pt = np.concatenate([rng.uniform(0.3, 1.5, n), rng.uniform(0.4, 1.6, n)])
        got, J = s.rhs(tv, pt), s.jacobian(tv, pt)
        assert np.all(J[n:] == 0) and np.all(got[n:] == 0)
        for i, f in enumerate(COMBINED):
            e = f(X, Y)
            vals = {X: sp.Float(pt[i], 30), Y: sp.Float(pt[n + i], 30),
                    _a: sp.Float(1.7, 30), _b: sp.Float(0.45, 30)}
            ref = float(e.evalf(30, subs=vals))
            dx, dy = (float(sp.diff(e, v).evalf(30, subs=vals)) for v in (X, Y))
            for got_v, ref_v in [(got[i], ref), (J[i, i], dx), (J[i, n + i], dy)]:
                err = abs(got_v - ref_v) / max(abs(ref_v), 1e-300)
                # measured 3.8e-15 at worst (a sum that cancels), 3e-16 mostly
                assert err < 1e-14, (e, pt[i], pt[n + i], got_v, ref_v)
                worst = max(worst, err)
            others = np.delete(J[i], [i, n + i])
            assert np.all(others == 0)
    assert worst > 0


#: SymPy's named constants (NumberSymbol): printed as double literals.
CONSTANTS = [sp.pi, sp.E, sp.EulerGamma, sp.GoldenRatio, sp.Catalan, sp.TribonacciConstant]


def test_driven_pendulum_with_pi_compiles():
    # cos(2 pi t) drive: the build's -std=c99 declares no M_PI
    th, = mp.coordinates("theta")
    w = th.diff()
    L = w ** 2 / 2 + sp.cos(th) + sp.cos(2 * sp.pi * t) * th
    s = mp.lagrangian(L, [th])
    assert not re.search(r"\bM_[A-Z]", s.c_source) and repr(np.pi) in s.c_source
    for tv, y in [(0.0, [0.3, 0.1]), (0.3, [1.1, -0.4]), (1.7, [-2.0, 0.9])]:
        # theta'' = -sin(theta) + cos(2 pi t)
        assert s.rhs(tv, y)[1] == pytest.approx(-np.sin(y[0]) + np.cos(2 * np.pi * tv),
                                                rel=1e-15, abs=1e-16)


@pytest.mark.parametrize("c", CONSTANTS, ids=str)
def test_constants_against_the_numpy_backend(c, rng):
    th, = mp.coordinates("theta")
    w = th.diff()
    L = (1 + c * sp.sin(th) ** 2) * w ** 2 / 2 + c * sp.cos(th) + sp.cos(c * t) * th \
        - sp.sqrt(c) * th ** 2 / 2 + sp.exp(c) * th ** 4 / 100
    s, n = mp.lagrangian(L, [th]), mp.lagrangian(L, [th], backend="numpy")
    assert repr(float(c)) in s.c_source       # the double nearest to c, as a literal
    for tv in (0.0, 0.4, 1.3):
        y = rng.uniform(-2, 2, 2)
        # measured: rhs 3.9e-16, Jacobian within 1e-15, energy 3.2e-15 (relative)
        assert np.allclose(s.rhs(tv, y), n.rhs(tv, y), rtol=2e-15, atol=0)
        assert np.allclose(s.jacobian(tv, y), n.jacobian(tv, y), rtol=2e-15, atol=1e-15)
        assert s.energy(y, tv) == pytest.approx(n.energy(y, tv), rel=1e-14, abs=0)
    # a constant alone: its literal is the double nearest to it
    x, = mp.coordinates("x")
    e = mp.equations([c * x], [x])
    assert e.rhs(0.0, [1.0])[0] == float(sp.N(c, 40))


#: Special functions of C99's <math.h> (and SymPy's reciprocal ones), f(x, y).
SPECIAL = {
    "erf": lambda x, y: sp.erf(x * y),          # its derivative holds sqrt(pi)
    "erfc": lambda x, y: sp.erfc(x - y),
    "expm1": lambda x, y: cfunctions.expm1(x * y),
    "log1p": lambda x, y: cfunctions.log1p(x ** 2 + y),
    "exp2": lambda x, y: cfunctions.exp2(x * y),
    "log2": lambda x, y: cfunctions.log2(x ** 2 + 1),
    "log10": lambda x, y: cfunctions.log10(x ** 2 + y ** 2),
    "log(.., 10)": lambda x, y: sp.log(x ** 2 + 1, 10),
    "hypot": lambda x, y: cfunctions.hypot(x, y),
    "cot": lambda x, y: sp.cot(x + 2), "sec": lambda x, y: sp.sec(x * y),
    "csc": lambda x, y: sp.csc(x + 2), "coth": lambda x, y: sp.coth(x + 3),
    "sech": lambda x, y: sp.sech(x * y), "csch": lambda x, y: sp.csch(x + 3),
    "Piecewise": lambda x, y: sp.Piecewise((x ** 2 * y, x > 0.1), (x * y, True)),
}


@pytest.mark.parametrize("name", SPECIAL)
def test_special_functions_against_the_numpy_backend(name, rng):
    x, y = mp.coordinates("x y")
    f = SPECIAL[name](x, y)
    rhs = [y * f + sp.pi * x, -x * f]
    s, n = mp.equations(rhs, [x, y]), mp.equations(rhs, [x, y], backend="numpy")
    for tv in (0.0, 0.9):
        v = rng.uniform(-1.5, 1.5, 2)
        # measured: rhs 1.9e-16 (coth), Jacobian within 1e-15
        assert np.allclose(s.rhs(tv, v), n.rhs(tv, v), rtol=2e-15, atol=0)
        assert np.allclose(s.jacobian(tv, v), n.jacobian(tv, v), rtol=2e-15, atol=1e-15)


def test_cbrt_against_sympy():
    # (the NumPy backend has no Cbrt): against SymPy's evaluation, for x > 0
    # (SymPy's Cbrt is the principal root x**(1/3))
    x, = mp.coordinates("x")
    X = sp.Symbol("X")
    f = cfunctions.Cbrt(X)
    s = mp.equations([f.subs(X, x)], [x])
    for v in (0.3, 2.0, 5.0):
        vals = {X: sp.Float(v, 30)}
        assert s.rhs(0, [v])[0] == pytest.approx(float(sp.cbrt(X).evalf(30, subs=vals)),
                                                 rel=4e-16)
        assert s.jacobian(0, [v])[0, 0] == pytest.approx(
            float(sp.diff(f, X).evalf(30, subs=vals)), rel=4e-16)


def test_equations_with_time_and_radau():
    y, = mp.coordinates("y")
    k = sp.Symbol("k")
    s = mp.equations([-k * (y - sp.cos(t))], [y], params=dict(k=1e4))   # stiff
    sol = mp.solve(s, (0, 2), [0.0], method="radau", rtol=1e-8, atol=1e-10)
    ex = (1e8 * np.cos(2) + 1e4 * np.sin(2)) / (1e8 + 1)   # the slow manifold, t >> 1/k
    assert sol.y[0, -1] == pytest.approx(ex, abs=1.5e-8)    # measured 1.5e-9
    assert sol.nsteps < 200 and sol.njev >= 1


# ---- the engine: every method, ensembles -----------------------------------------

def test_every_method_runs(pendulum, double_pendulum):
    y0p = [1.0, 0.0]
    ref_p = mp.solve(pendulum, (0, 2), y0p, rtol=1e-13, atol=1e-13).y[:, -1]
    y0d = [0.5, 0.2, 0.0, 0.0]
    ref_d = mp.solve(double_pendulum, (0, 2), y0d, rtol=1e-13, atol=1e-13).y[:, -1]
    seen = []
    for m in mp.methods():
        name = m["name"]
        if m["rigid"]:
            with pytest.raises(ValueError):
                mp.solve(double_pendulum, (0, 2), y0d, method=name, h=1e-3)
            continue
        kw = {} if m["adaptive"] else {"h": 1e-3}
        kw["rtol"] = 1e-8
        systems = [(pendulum, y0p, ref_p)]
        if not (m["symplectic"] and not m["implicit"]):
            systems.append((double_pendulum, y0d, ref_d))
        else:
            with pytest.raises(ValueError, match="separable"):
                mp.solve(double_pendulum, (0, 2), y0d, method=name, **kw)
        for s, y0, ref in systems:
            sol = mp.solve(s, (0, 2), y0, method=name, **kw)
            assert sol.success, name
            # measured: 2.8e-4 worst (gsl:rk1imp, first order), 6.5e-6 next (verlet)
            assert np.abs(sol.y[:, -1] - ref).max() < 1e-3, name
        seen.append(name)
    assert {"verlet", "yoshida4", "yoshida6", "gauss4", "radau", "gsl:msbdf"} <= set(seen)


def test_solve_many_with_per_trajectory_params(double_pendulum):
    m1 = np.array([0.5, 1.0, 2.0])
    y0s = np.array([[1.0, 0.5, 0.0, 0.0]] * 3)
    te = np.linspace(0, 3, 7)
    # the scalar path: bit for bit (lanes against it: tests/test_lanes.py)
    ens = mp.solve_many(double_pendulum, (0, 3), y0s, params={"m1": m1}, t_eval=te,
                        rtol=1e-10, threads=2, lanes=False)
    assert ens.y.shape == (3, 4, 7) and ens.success.all()
    for i, v in enumerate(m1):
        one = mp.solve(double_pendulum.replace(m1=v), (0, 3), y0s[i], rtol=1e-10, t_eval=te)
        assert np.array_equal(ens.y[i], one.y)    # the same engine, bit for bit
        ref = solve_ivp(lambda tt, y: dp_hand(tt, y, m1=v), (0, 3), y0s[i], method="DOP853",
                        rtol=1e-12, atol=1e-12, t_eval=te)
        assert np.abs(one.y - ref.y).max() < 1.5e-8     # measured 1.4e-9
    with pytest.raises(ValueError, match="columns"):
        mp.solve_many(double_pendulum, (0, 1), y0s, params=np.ones((3, 2)))


def test_replace_shares_the_library(double_pendulum):
    s2 = double_pendulum.replace(g=1.62)
    assert s2._path == double_pendulum._path and not s2._compiled
    assert s2.params["g"] == 1.62 and double_pendulum.params["g"] == G
    y = np.array([0.4, 0.1, 0.0, 0.0])
    assert np.allclose(s2.rhs(0, y), dp_hand(0, y, g=1.62), rtol=1e-13)
    with pytest.raises(TypeError, match="unknown"):
        double_pendulum.replace(mass=1.0)


# ---- scale: the n-link pendulum on a cart ------------------------------------------

def test_pendulum_on_a_cart_scales_to_ten_coordinates():
    N = 10   # the cart and 9 links
    q = mp.coordinates("x " + " ".join(f"th{i}" for i in range(1, N)))
    g, Mc, m, l = sp.symbols("g M m l")
    T = Mc / 2 * q[0].diff(t) ** 2
    V = 0
    px, py = q[0], 0
    for i in range(1, N):
        px, py = px + l * sp.sin(q[i]), py - l * sp.cos(q[i])
        T += m / 2 * (px.diff(t) ** 2 + py.diff(t) ** 2)
        V += m * g * py
    s = mp.lagrangian(T - V, q, params=dict(g=G, M=2.0, m=0.5, l=0.3))
    assert s.dim == 20 and s.cyclic == ["x"]
    from mechpy.symbolic import build
    # the Jacobian and the lane rhs compiled beside the rest
    assert len(build.units(s.c_source)) == 3 and "mp_gen_lanes(" in build.units(s.c_source)[2]
    y0 = np.zeros(20)
    y0[1:N] = np.linspace(0.1, 0.5, N - 1)
    sol = mp.solve(s, (0, 5), y0, rtol=1e-10, atol=1e-12)
    E = s.energy(sol.y)
    assert abs(E[-1] - E[0]) < 1e-13 * abs(E[0])          # measured 5.1e-13 of 64 (8e-15)
    p = s.momenta(sol.y)
    assert abs(p[0, -1] - p[0, 0]) < 3e-14                # cart momentum, measured 2.4e-15
    J = s.jacobian(0.0, sol.y[:, -1])
    Jref = fd_jacobian(lambda v: s.rhs(0.0, v), sol.y[:, -1])
    assert np.abs(J - Jref).max() < 3e-10 * np.abs(Jref).max()   # measured 3.1e-11
    # an ensemble in lanes through the lane rhs of its own translation unit
    y0s = y0 * (1 + 0.1 * np.linspace(-1, 1, 11))[:, None]
    a = mp.solve_many(s, (0, 1), y0s, t_eval=[0.0, 1.0], lanes=True)
    b = mp.solve_many(s, (0, 1), y0s, t_eval=[0.0, 1.0], lanes=False)
    assert a.lanes and np.array_equal(a.nfev, b.nfev)
    assert np.abs(a.y - b.y).max() < 5e-13 * np.abs(b.y).max()   # measured 5.0e-14


# ---- the cache, processes, pickling ------------------------------------------------

def _run(code, env_extra, cwd):
    env = dict(os.environ, **env_extra)
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, env=env, cwd=cwd, timeout=300)


def test_second_build_loads_from_disk(tmp_path, monkeypatch):
    from mechpy.symbolic import build
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    L, q = pendulum_L()
    L = L + sp.Symbol("k") * q[0] ** 4        # a system no other test builds
    s = mp.lagrangian(L, q, params=dict(m=1.0, length=1.0, g=G, k=0.1))
    assert s._compiled
    sos = [f for f in os.listdir(tmp_path) if f.endswith(".so")]
    assert len(sos) == 1
    mtime = os.path.getmtime(tmp_path / sos[0])
    # a fresh process: the library and the derivation come from the folder
    code = f"""
        import sympy as sp, mechpy as mp
        from mechpy.symbolic import build
        def fail(*a):
            raise AssertionError("compiled again")
        build._compile = fail
        t = sp.Symbol("t")
        th, = mp.coordinates("theta")
        m, l, g, k = sp.symbols("m length g k")
        L = m * l**2 / 2 * th.diff(t)**2 + m * g * l * sp.cos(th) + k * th**4
        s = mp.lagrangian(L, [th], params=dict(m=1.0, length=1.0, g={G!r}, k=0.1))
        assert not s._compiled
        print(repr(float(s.rhs(0.0, [0.3, 0.0])[1])))
    """
    r = _run(code, {"MECHPY_CACHE_DIR": str(tmp_path)}, tmp_path)
    assert r.returncode == 0, r.stderr
    assert float(r.stdout) == s.rhs(0.0, [0.3, 0.0])[1]
    assert os.path.getmtime(tmp_path / sos[0]) == mtime
    # in this process: the library is loaded once
    monkeypatch.setattr(build, "_compile", None)
    s2 = mp.lagrangian(L, q, params=dict(m=2.0, length=1.0, g=G, k=0.1))
    assert not s2._compiled and s2._path == s._path


def test_the_cache_key_takes_every_input(tmp_path, monkeypatch):
    # systems that differ in one input each, built one after the other in one cache
    # folder: each behaves as its own input says (none is served another's library
    # or stored derivation), checked against the equations written by hand
    from mechpy import symbolic
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    th, = mp.coordinates("theta")
    w = th.diff(t)
    g_, l_, b_ = sp.symbols("g l b")
    P, Pb = dict(g=G, l=1.3), dict(g=G, l=1.3, b=0.2)
    y = np.array([0.7, -0.4])

    def acc(s):
        return s.rhs(0.0, y)[1]

    base = mp.lagrangian(l_ ** 2 / 2 * w ** 2 + g_ * l_ * sp.cos(th), [th], params=P)
    assert acc(base) == pytest.approx(-G / 1.3 * np.sin(0.7), rel=1e-15)
    # the Lagrangian
    s = mp.lagrangian(l_ ** 2 / 2 * w ** 2 + 2 * g_ * l_ * sp.cos(th), [th], params=P)
    assert acc(s) == pytest.approx(-2 * G / 1.3 * np.sin(0.7), rel=1e-15)
    # the parameters' order (the order of scene.params and of solve_many's rows)
    s = mp.lagrangian(l_ ** 2 / 2 * w ** 2 + g_ * l_ * sp.cos(th), [th],
                      params=dict(l=1.3, g=G))
    assert list(s.params) == ["l", "g"] and acc(s) == acc(base)
    assert s.replace(g=1.0).rhs(0.0, y)[1] == pytest.approx(-np.sin(0.7) / 1.3, rel=1e-15)
    # the forces
    L0 = l_ ** 2 / 2 * w ** 2 + g_ * l_ * sp.cos(th)
    d1 = mp.lagrangian(L0, [th], params=Pb, forces=[-b_ * w])
    d2 = mp.lagrangian(L0, [th], params=Pb, forces=[-2 * b_ * w])
    assert acc(d1) == pytest.approx(acc(base) + 0.2 * 0.4 / 1.3 ** 2, rel=1e-14)
    assert acc(d2) == pytest.approx(acc(base) + 2 * 0.2 * 0.4 / 1.3 ** 2, rel=1e-14)
    # the coordinates' order
    x, z = mp.coordinates("x z")
    Lxz = (x.diff(t) ** 2 + z.diff(t) ** 2) / 2 - (x ** 2 + 4 * z ** 2) / 2
    a, b = mp.lagrangian(Lxz, [x, z]), mp.lagrangian(Lxz, [z, x])
    v = np.array([0.3, 0.5, 0.0, 0.0])
    assert a.rhs(0.0, v)[2:].tolist() == [-0.3, -2.0] and b.rhs(0.0, v)[2:].tolist() == [-1.2, -0.5]
    # the constraints and Baumgarte's rates: a state off the constraint x^2 + z^2 = l^2,
    # moving along it, is pulled back by g'' + 2 alpha g' + beta^2 g = 0; on the z axis
    # (x = x' = 0) g' = 2 z z', g'' = 2 z'^2 + 2 z z'', so
    # z'' = -(2 z'^2 + 4 alpha z z' + beta^2 (z^2 - l^2)) / (2 z)
    L2 = (x.diff(t) ** 2 + z.diff(t) ** 2) / 2 - g_ * z
    zz, vz = -1.1, 0.3
    off = np.array([0.0, zz, 0.0, vz])
    for lv, (al, be) in [(1.0, (5.0, 5.0)), (1.0, (1.0, 2.0)), (1.05, (1.0, 2.0))]:
        c = mp.lagrangian(L2, [x, z], params=dict(g=G, l=lv),
                          constraints=[x ** 2 + z ** 2 - l_ ** 2], baumgarte=(al, be))
        zdd = -(2 * vz ** 2 + 4 * al * zz * vz + be ** 2 * (zz ** 2 - lv ** 2)) / (2 * zz)
        assert c.rhs(0.0, off)[3] == pytest.approx(zdd, rel=1e-13)
        assert c.rhs(0.0, off)[2] == 0.0
    # first-order equations: the right-hand side, the states' order and the energy
    e1 = mp.equations([z, -x], [x, z], energy=(x ** 2 + z ** 2) / 2)
    e2 = mp.equations([z, -x], [z, x], energy=(x ** 2 + z ** 2) / 2)
    e3 = mp.equations([z, -x], [x, z], energy=x ** 2 + z ** 2)
    e4 = mp.equations([z, -2 * x], [x, z], energy=(x ** 2 + z ** 2) / 2)
    u = np.array([0.3, 0.5])
    # (z, x) = (0.3, 0.5) for e2
    assert e1.rhs(0.0, u).tolist() == [0.5, -0.3] and e2.rhs(0.0, u).tolist() == [0.3, -0.5]
    assert e4.rhs(0.0, u).tolist() == [0.5, -0.6]
    assert e1.energy(u) == pytest.approx(0.17) and e3.energy(u) == pytest.approx(0.34)
    # the generator's code (its hash): a derivation stored by another generator is not
    # used, the system is derived again (the same source then loads the same library)
    from mechpy.symbolic import codegen
    derived = []
    real = codegen.c_source
    monkeypatch.setattr(codegen, "c_source", lambda *a: derived.append(1) or real(*a))
    same = mp.lagrangian(l_ ** 2 / 2 * w ** 2 + g_ * l_ * sp.cos(th), [th], params=P)
    assert not derived and same._path == base._path
    monkeypatch.setattr(symbolic, "_GEN_HASH", "another generator")
    again = mp.lagrangian(l_ ** 2 / 2 * w ** 2 + g_ * l_ * sp.cos(th), [th], params=P)
    assert derived == [1] and acc(again) == acc(base)


def test_the_library_key_takes_every_input(monkeypatch):
    from mechpy.symbolic import build
    src, cmd = "int f(void) { return 1; }\n", ["cc"]
    k = build._key(src, cmd)
    assert build._key(src, cmd) == k
    others = {build._key(src + " ", cmd), build._key(src, ["gcc"]), build._key(src, ["cc", "-m32"])}
    for name, value in [("FLAGS", build.FLAGS + ("-g",)), ("LIBS", ("-lm", "-lquadmath")),
                        ("ABI_VERSION", build.ABI_VERSION + 1)]:
        with monkeypatch.context() as m:
            m.setattr(build, name, value)
            others.add(build._key(src, cmd))
    assert len(others) == 6 and k not in others
    # a source past LARGE compiles with -O1: the flags it gets are part of its key
    big = "/*" + "x" * build.LARGE + "*/\n"
    kb = build._key(big, cmd)
    with monkeypatch.context() as m:
        m.setattr(build, "LARGE", 10 * build.LARGE)
        assert build._key(big, cmd) != kb


def test_two_processes_building_at_once(tmp_path):
    code = f"""
        import sympy as sp, mechpy as mp
        t = sp.Symbol("t")
        a, b = mp.coordinates("a b")
        k = sp.Symbol("kappa")
        L = (a.diff(t)**2 + b.diff(t)**2) / 2 - k * (a**2 + b**2 + a**2 * b**2) / 2
        s = mp.lagrangian(L, [a, b], params=dict(kappa=1.5))
        sol = mp.solve(s, (0, 5), [0.3, 0.1, 0.0, 0.2], rtol=1e-10)
        print(repr(sol.y[0, -1]))
    """
    env = dict(os.environ, MECHPY_CACHE_DIR=str(tmp_path))
    procs = [subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              cwd=tmp_path) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert all(p.returncode == 0 for p in procs), [e for _, e in outs]
    assert outs[0][0] == outs[1][0]
    files = os.listdir(tmp_path)
    assert len([f for f in files if f.endswith(".so")]) == 1
    assert not [f for f in files if f.startswith(".mp_")]    # no temporaries left


#: A system built in a child process (a damaged library must not be loaded by
#: the test process itself: truncating a mapped file can kill it): prints
#: whether it compiled and theta'' at (0.4, 0.1).
_CUBIC = """
    import sympy as sp, mechpy as mp
    t = sp.Symbol("t")
    th, = mp.coordinates("theta")
    L = th.diff(t)**2 / 2 + sp.cos(th) + sp.Symbol("kappa3") * th**3
    s = mp.lagrangian(L, [th], params=dict(kappa3=0.25))
    print(s._compiled, repr(float(s.rhs(0.0, [0.4, 0.1])[1])))
"""
_CUBIC_ACC = -np.sin(0.4) + 3 * 0.25 * 0.4 ** 2      # theta'' = -sin(theta) + 3 k theta^2


def _damage(path, how):
    data = path.read_bytes()
    if how == "truncate":
        path.write_bytes(data[:len(data) // 2])
    elif how == "flip":             # bytes of the code, the tables and the headers
        b = bytearray(data)
        for i in range(0, len(b), max(1, len(b) // 97)):
            b[i] ^= 0xFF
        path.write_bytes(bytes(b))
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "unrecorded":       # a library without its recorded sha256
        os.unlink(str(path)[:-3] + ".json")
    elif how == "other":            # another valid library in its place
        import shutil
        shutil.copy(mp._core.__file__, path)


@pytest.mark.parametrize("how", ["truncate", "flip", "empty", "unrecorded", "other"])
def test_a_damaged_cached_library_is_rebuilt(how, tmp_path):
    import hashlib
    import json
    env = {"MECHPY_CACHE_DIR": str(tmp_path)}
    r = _run(_CUBIC, env, tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split()[0] == "True"
    so, = tmp_path.glob("mp_*.so")
    _damage(so, how)
    # a fresh process: the damaged file is detected before it is loaded (no
    # SIGBUS or SIGSEGV, no OSError), compiled again and replaced
    r = _run(_CUBIC, env, tmp_path)
    assert r.returncode == 0, (r.returncode, r.stderr[-2000:])
    compiled, acc = r.stdout.split()
    assert compiled == "True"
    assert float(acc) == pytest.approx(_CUBIC_ACC, rel=1e-15, abs=1e-16)
    rec = json.loads((tmp_path / (so.name[:-3] + ".json")).read_text())
    assert rec["sha256"] == hashlib.sha256(so.read_bytes()).hexdigest()
    # and the repaired cache serves the next process without compiling
    r = _run(_CUBIC, env, tmp_path)
    assert r.returncode == 0 and r.stdout.split()[0] == "False", r.stderr


def test_a_compiler_that_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MECHPY_CC", "true")         # exits 0, writes no library
    x, = mp.coordinates("x")
    L = x.diff(t) ** 2 / 2 - sp.Symbol("c5") * x ** 5
    with pytest.raises(mp.CompileError, match="'true .*' exited 0 but wrote no library"):
        mp.lagrangian(L, [x], params=dict(c5=1.0))
    assert not list(tmp_path.glob("*.so"))           # nothing left to fail later
    monkeypatch.delenv("MECHPY_CC")
    s = mp.lagrangian(L, [x], params=dict(c5=1.0))
    assert s._compiled and s.rhs(0, [2.0, 0.0])[1] == -5 * 2.0 ** 4


def test_a_stored_description_that_is_not_one(tmp_path, monkeypatch):
    import json
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    x, = mp.coordinates("x")
    L = x.diff(t) ** 2 / 2 - sp.Symbol("c6") * x ** 6
    mp.lagrangian(L, [x], params=dict(c6=1.0))
    meta, = tmp_path.glob("sys_*.json")
    for junk in ("[]", "{}", '{"param_names": ["c6"]}', "not json", "null"):
        meta.write_text(junk)
        s = mp.lagrangian(L, [x], params=dict(c6=1.0))       # derived again
        assert s.rhs(0, [2.0, 0.0])[1] == -6 * 2.0 ** 5
        assert json.loads(meta.read_text())["param_names"] == ["c6"]     # and repaired


def test_a_cache_folder_that_is_a_file(tmp_path, monkeypatch):
    from mechpy.symbolic import build
    monkeypatch.setattr(build, "_PRIVATE", [], raising=False)         # this test's private folder
    bad = tmp_path / "not_a_folder"
    bad.write_text("")
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(bad))
    x, = mp.coordinates("x")
    L = x.diff(t) ** 2 / 2 - sp.Symbol("c7") * x ** 7
    with pytest.warns(RuntimeWarning, match=f"cache folder '{bad}' cannot be used.*"
                                            "MECHPY_CACHE_DIR"):
        s = mp.lagrangian(L, [x], params=dict(c7=1.0))
    assert s.rhs(0, [1.0, 0.0])[1] == -7.0
    assert os.path.dirname(s._path) == build._PRIVATE[0]
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")                   # warned once only
        s2 = mp.lagrangian(L + x ** 2, [x], params=dict(c7=1.0))
    assert s2.rhs(0, [1.0, 0.0])[1] == -5.0      # + 2x from the added x**2


def test_a_read_only_cache_folder(tmp_path, monkeypatch):
    import tempfile

    from mechpy.symbolic import build
    ro = tmp_path / "ro"
    ro.mkdir()
    r = _run(_CUBIC, {"MECHPY_CACHE_DIR": str(ro)}, tmp_path)    # built while writable
    assert r.returncode == 0, r.stderr
    ro.chmod(0o555)
    if os.geteuid() == 0:      # root writes anyway: the refusal a user would get
        real = tempfile.mkstemp

        def mkstemp(*a, dir=None, **kw):
            if dir is not None and os.path.samefile(dir, ro):
                raise PermissionError(13, "Permission denied", os.path.join(dir, ".mp_x"))
            return real(*a, dir=dir, **kw)
        monkeypatch.setattr(tempfile, "mkstemp", mkstemp)
    monkeypatch.setattr(build, "_PRIVATE", [], raising=False)
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(ro))
    try:
        # what it holds is loaded from it
        th, = mp.coordinates("theta")
        L = th.diff(t) ** 2 / 2 + sp.cos(th) + sp.Symbol("kappa3") * th ** 3
        s = mp.lagrangian(L, [th], params=dict(kappa3=0.25))
        assert not s._compiled and os.path.dirname(s._path) == str(ro)
        assert s.rhs(0.0, [0.4, 0.1])[1] == pytest.approx(_CUBIC_ACC, rel=1e-15, abs=1e-16)
        # a new system goes to a private folder, with a warning naming the cache
        with pytest.warns(RuntimeWarning, match=f"'{ro}' cannot be used .*Permission"):
            s2 = mp.lagrangian(L + th ** 4, [th], params=dict(kappa3=0.25))
        assert s2._compiled and os.path.dirname(s2._path) == build._PRIVATE[0]
        assert s2.rhs(0.0, [0.4, 0.1])[1] == pytest.approx(_CUBIC_ACC + 4 * 0.4 ** 3,
                                                          rel=1e-15, abs=1e-16)
        assert sorted(p.name[:3] for p in ro.iterdir()) == ["mp_", "mp_", "sys"]
    finally:
        ro.chmod(0o755)


def test_pickle_loads_in_a_fresh_process(double_pendulum, tmp_path):
    s = double_pendulum.replace(m2=1.1)
    blob = tmp_path / "scene.pkl"
    blob.write_bytes(pickle.dumps(s))
    assert pickle.loads(pickle.dumps(s)) == s
    y0 = [1.0, 0.5, 0.0, 0.0]
    ref = mp.solve(s, (0, 2), y0, rtol=1e-10).y[:, -1]
    code = f"""
        import pickle, sys, numpy as np, mechpy as mp
        s = pickle.loads(open({str(blob)!r}, "rb").read())
        assert "sympy" not in sys.modules, "loading needed SymPy"
        print(repr(s.params["m2"]))
        print(" ".join(repr(float(v)) for v in mp.solve(s, (0, 2), {y0!r}, rtol=1e-10).y[:, -1]))
    """
    # another cache folder: the receiving side compiles from the pickled source
    r = _run(code, {"MECHPY_CACHE_DIR": str(tmp_path / "other")}, tmp_path)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.split("\n")
    assert float(lines[0]) == 1.1
    assert np.array_equal(np.array(lines[1].split(), dtype=float), ref)


# ---- the NumPy backend -------------------------------------------------------------------

def test_numpy_backend_equals_c(double_pendulum, rng):
    L, q = double_pendulum_L()
    s = mp.lagrangian(L, q, params=DP, backend="numpy")
    Y = rng.uniform(-2, 2, size=(4, 5))
    assert np.allclose(s.rhs(0, Y), double_pendulum.rhs(0, Y), rtol=1e-13, atol=1e-13)
    assert np.allclose(s.jacobian(0, Y), double_pendulum.jacobian(0, Y), rtol=1e-12,
                       atol=1e-12)
    assert np.allclose(s.energy(Y), double_pendulum.energy(Y), rtol=1e-14)
    te = np.linspace(0, 2, 5)
    a = mp.solve(s, (0, 2), Y[:, 0], rtol=1e-10, t_eval=te)
    b = mp.solve(double_pendulum, (0, 2), Y[:, 0], rtol=1e-10, t_eval=te)
    assert np.abs(a.y - b.y).max() < 1e-12   # measured 7.9e-14 (states up to 7)
    ens = mp.solve_many(s, (0, 1), Y[:, :2].T, params={"m1": [1.0, 2.0]}, rtol=1e-10)
    ref = mp.solve_many(double_pendulum, (0, 1), Y[:, :2].T, params={"m1": [1.0, 2.0]},
                        rtol=1e-10)
    assert np.abs(ens.y - ref.y).max() < 1e-12   # round-off apart, as above
    assert pickle.loads(pickle.dumps(s)).rhs(0, Y).tolist() == s.rhs(0, Y).tolist()
    c = cartesian_pendulum(backend="numpy")
    y = cart_state(0.7, 0.4)
    assert np.allclose(c.constraint_forces(0, y), cartesian_pendulum().constraint_forces(0, y),
                       rtol=1e-13)


# ---- what the scene tells -------------------------------------------------------------------

def test_equations_and_source(double_pendulum):
    eqs = double_pendulum.equations
    assert len(eqs) == 2 and all(isinstance(e, sp.Eq) for e in eqs)
    # the equations hold for the hand-derived accelerations
    th1, th2 = mp.coordinates("theta1 theta2")
    y = np.array([0.4, -0.3, 0.2, 0.5])
    a = dp_hand(0, y)[2:]
    subs = {th1.diff(t, 2): a[0], th2.diff(t, 2): a[1]}
    subs.update({th1.diff(t): y[2], th2.diff(t): y[3]})
    subs.update({th1: y[0], th2: y[1]})
    subs.update({sp.Symbol(k): v for k, v in DP.items()})
    for e in eqs:
        assert float((e.lhs - e.rhs).subs(subs)) == pytest.approx(0.0, abs=1e-12)
    src = double_pendulum.c_source
    assert "int mp_gen_rhs(double t, const double *y, double *dydt, void *params)" in src
    assert "mp_gen_lagrangian(size_t m" in src and "mp_gen_dims[5]" in src
    assert f"#define MP_ESINGULAR {mp._core.STATUS['MP_ESINGULAR']}" in src


# ---- bad input ----------------------------------------------------------------------------------

def test_missing_parameter_is_named():
    L, q = double_pendulum_L()
    with pytest.raises(ValueError, match=r"\['l2', 'm2'\] have no value"):
        mp.lagrangian(L, q, params=dict(m1=1.0, l1=1.0, g=G))
    # a misspelt name leaves the symbol it was meant for without a value: the
    # message names both
    bad = {("M2" if k == "m2" else k): v for k, v in DP.items()}
    with pytest.raises(ValueError, match=r"\['m2'\] have no value.*\['M2'\], which no "
                                         r"expression of the system uses: misspelt\?"):
        mp.lagrangian(L, q, params=bad)
    # a name of a coordinate or the time is no parameter
    with pytest.raises(ValueError, match="'theta1' names a state"):
        mp.lagrangian(L, q, params=dict(DP, theta1=1.0))
    with pytest.raises(ValueError, match="'t' names the time"):
        mp.lagrangian(L, q, params=dict(DP, t=1.0))


def test_parameter_no_expression_uses_is_a_parameter():
    """A name no expression uses is a parameter all the same (an event's
    restitution may be its only reader): it keeps its place in scene.params
    and in solve_many's rows, and the motion is the one without it."""
    L, q = double_pendulum_L()
    s = mp.lagrangian(L, q, params=dict(DP, mass=3.0))
    assert list(s.params) == list(DP) + ["mass"] and s.params["mass"] == 3.0
    ref = mp.lagrangian(L, q, params=DP)
    y0 = [0.5, -0.3, 0.0, 0.2]
    a = mp.solve(s, (0, 1), y0, rtol=1e-10, atol=1e-12)
    b = mp.solve(ref, (0, 1), y0, rtol=1e-10, atol=1e-12)
    assert np.array_equal(a.y, b.y)


def test_coordinate_missing_from_L():
    a, b = mp.coordinates("a b")
    with pytest.raises(ValueError, match="coordinate b does not appear in L"):
        mp.lagrangian(a.diff(t) ** 2 / 2 - a ** 2 / 2, [a, b])
    with pytest.raises(TypeError, match="not a coordinate"):
        mp.lagrangian(a.diff(t) ** 2, [a, sp.Symbol("x") + 1])
    c, = mp.coordinates("c")
    with pytest.raises(ValueError, match="not coordinates"):
        mp.lagrangian(a.diff(t) ** 2 + c ** 2, [a])


def test_singular_mass_matrix_at_the_initial_state():
    x, = mp.coordinates("x")
    s = mp.lagrangian(x ** 2 * x.diff(t) ** 2 / 2 - x ** 2 / 2, [x])
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        mp.solve(s, (0, 1), [0.0, 1.0])
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        s.rhs(0, [0.0, 1.0])
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        mp.solve_many(s, (0, 1), [[1.0, 0.0], [0.0, 1.0]])
    # errors="status": a status, not an exception; one singular row leaves the
    # ensemble's other rows (in lanes and scalar), as HeavyTop's -3 does
    st = mp.solve(s, (0, 1), [0.0, 1.0], errors="status")
    assert st.status == -3 and "singular" in st.message
    for lanes in (None, False):
        ens = mp.solve_many(s, (0, 1), [[1.0, 0.0], [0.0, 1.0]], errors="status", lanes=lanes)
        assert ens.status.tolist() == [0, -3]
        # the regular row keeps its energy x^2 x'^2/2 + x^2/2 = 1/2 (measured 1.0e-8)
        x1, v1 = ens.y[0, :, -1]
        assert abs(x1 ** 2 * v1 ** 2 / 2 + x1 ** 2 / 2 - 0.5) < 1e-7
        with pytest.raises(mp.SingularityError, match="trajectory 1"):
            ens.raise_for_status()
    sn = mp.lagrangian(x ** 2 * x.diff(t) ** 2 / 2 - x ** 2 / 2, [x], backend="numpy")
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        mp.solve(sn, (0, 1), [0.0, 1.0])
    assert mp.solve(s, (0, 0.1), [1.0, 0.0]).success


def test_unprintable_expression_is_named():
    x, = mp.coordinates("x")
    with pytest.raises(ValueError, match=r"L contains besselj\(0, x\)"):
        mp.lagrangian(x.diff(t) ** 2 / 2 - sp.besselj(0, x), [x])
    # the NumPy backend: what lambdify evaluates runs (a Sum), the rest is named
    k = sp.Symbol("k", integer=True)
    s = mp.lagrangian(x.diff(t) ** 2 / 2 - sp.Sum(x ** k / k, (k, 1, 3)), [x],
                      backend="numpy")
    assert s.rhs(0, [0.5, 0.0])[1] == pytest.approx(-(1 + 0.5 + 0.25), rel=1e-15)
    s = mp.lagrangian(x.diff(t) ** 2 / 2 - sp.besselj(0, x), [x], backend="numpy")
    with pytest.raises(ValueError, match="uses besselj, which sympy.lambdify cannot"):
        s.rhs(0, [0.5, 0.0])


def _bad_systems():
    th, = mp.coordinates("theta")
    w = th.diff()
    k = sp.Symbol("k", integer=True)
    a, a_pos = sp.Symbol("a"), sp.Symbol("a", positive=True)
    return {
        "I": (w ** 2 / 2 + sp.I * th, r"L contains the imaginary unit I"),
        "Sum": (w ** 2 / 2 + sp.Sum(th ** k, (k, 1, 3)), r"L contains Sum\(theta\*\*k"),
        "1e400": (w ** 2 / 2 + sp.Integer(10) ** 400 * th ** 2,
                  r"L contains the number 1\.0+E\+400 .*beyond the range of double"),
        "oo": (w ** 2 / 2 + sp.oo * th, r"L contains oo, not a finite number"),
        "names": (w ** 2 / 2 + a * th ** 2 + a_pos * th,
                  r"two different symbols are named 'a' \(assumptions none and "
                  r"\{positive=True\}\)"),
        "gamma": (w ** 2 / 2 - sp.gamma(th + 3), r"gamma\(theta \+ 3\) \(in L\).*"
                                                  r"polygamma"),
        "reserved": (w ** 2 / 2 - sp.Symbol("mp_y0") * th, r"mp_y0, a name mechpy reserves"),
    }


@pytest.mark.parametrize("case", list(_bad_systems()))
def test_what_a_system_may_not_contain_is_named(case):
    # a ValueError naming the culprit, never the compiler's output or a SymPy
    # printer's internal message
    L, msg = _bad_systems()[case]
    th = mp.coordinates("theta")
    params = {"a": 1.0} if case == "names" else {"mp_y0": 1.0} if case == "reserved" else None
    with pytest.raises(ValueError, match=msg):
        mp.lagrangian(L, th, params=params)


def test_equations_refuse_relations_and_rough_functions():
    y, = mp.coordinates("y")
    with pytest.raises(ValueError, match=r"rhs\[0\] = Eq\(y\(t\), 1\) is an equation"):
        mp.equations([sp.Eq(y, 1)], [y])
    with pytest.raises(ValueError, match=r"gamma\(y\) \(in rhs\[0\]\).*needed by the "
                       r"Jacobian"):
        mp.equations([sp.gamma(y)], [y])
    with pytest.raises(ValueError, match=r"L = Eq\(y\(t\), 0\) is an equation"):
        mp.lagrangian(sp.Eq(y, 0), [y])


def test_wrong_number_of_forces():
    L, q = double_pendulum_L()
    with pytest.raises(ValueError, match="one entry per coordinate: got 1 for 2"):
        mp.lagrangian(L, q, params=DP, forces=[q[0].diff(t)])


def test_bad_constraints_and_equations():
    x, y = mp.coordinates("x y")
    L = (x.diff(t) ** 2 + y.diff(t) ** 2) / 2
    with pytest.raises(ValueError, match="holonomic"):
        mp.lagrangian(L, [x, y], constraints=[x.diff(t) - 1])
    with pytest.raises(ValueError, match="one expression per state"):
        mp.equations([x], [x, y])
    with pytest.raises(ValueError, match="backend"):
        mp.lagrangian(L, [x, y], backend="fortran")


def test_compile_failure_names_the_command(monkeypatch, tmp_path):
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("MECHPY_CC", "/nonexistent/cc")
    x, = mp.coordinates("x")
    with pytest.raises(mp.CompileError, match="/nonexistent/cc"):
        mp.lagrangian(x.diff(t) ** 2 / 2 - x ** 4, [x])
    monkeypatch.setenv("MECHPY_CC", "false")
    with pytest.raises(mp.CompileError, match="failed .exit 1. on 'false"):
        mp.lagrangian(x.diff(t) ** 2 / 2 - x ** 4, [x])
    assert isinstance(mp.CompileError("x"), RuntimeError)
    # without a compiler, the numpy backend
    s = mp.lagrangian(x.diff(t) ** 2 / 2 - x ** 4, [x], backend="numpy")
    assert s.rhs(0, [1.0, 0.0])[1] == -4.0


def test_translation_units_compile_link_and_clean_up(tmp_path):
    import ctypes

    from mechpy.symbolic import build
    shared = "int twice(int x);\n"
    good = shared + build.UNIT + "int quad(int x) { return twice(twice(x)); }\n" \
        + build.UNIT + "int twice(int x) { return 2 * x; }\n"
    assert len(build.units(good)) == 2
    so = str(tmp_path / "good.so")
    build._compile(good, build.compiler(), so, str(tmp_path))
    assert ctypes.CDLL(so).quad(5) == 20
    bad = good + build.UNIT + "int broken(int x) { return x +; }\n"
    with pytest.raises(mp.CompileError, match="failed"):
        build._compile(bad, build.compiler(), str(tmp_path / "bad.so"), str(tmp_path))
    assert sorted(os.listdir(tmp_path)) == ["good.so"]      # no temporaries left


def test_import_does_not_load_sympy():
    r = subprocess.run([sys.executable, "-c", "import sys, mechpy; "
                        "print('sympy' in sys.modules)"], capture_output=True, text=True)
    assert r.stdout.strip() == "False", r.stderr


def test_a_state_symbol_is_a_right_hand_side():
    """x' = v: a plain Symbol is an expression (SymPy counts Symbol among its
    Booleans), while an Eq or a condition is refused."""
    import sympy as sp
    x, v = sp.symbols("x v")
    osc = mp.equations([v, -x], [x, v])
    np.testing.assert_array_equal(osc.rhs(0.0, np.array([0.3, -0.7])), [-0.7, -0.3])
    with pytest.raises(ValueError, match="equation or a condition"):
        mp.equations([sp.Eq(v, 1), -x], [x, v])
    with pytest.raises(ValueError, match="equation or a condition"):
        mp.equations([x > 0, -x], [x, v])


def test_symbolic_field_of_a_compiled_lagrangian_is_its_rhs(double_pendulum, rng):
    # CompiledScene.symbolic(): the first-order field f(t, y) in SymPy, for a
    # Lagrangian of two coordinates (velocities y2, y3), equals the compiled rhs
    F = double_pendulum.symbolic()
    f = sp.lambdify([F.t, F.y], [e.subs(F.params) for e in F.f], "numpy")
    for _ in range(3):
        y = rng.uniform(-1.5, 1.5, 4)
        # measured 8.3e-15 (relative to max(1, |f|))
        np.testing.assert_allclose(f(0.3, y), double_pendulum.rhs(0.3, y), rtol=5e-14,
                                   atol=5e-14)


def test_a_library_is_loaded_once_per_process(tmp_path, monkeypatch):
    # build.py: a library this process has loaded is used again as it is (no second
    # read, hash or load of its file), so that a file changed on disk meanwhile does
    # not swap the code under a running system
    from mechpy.symbolic import build
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    x, = mp.coordinates("x")
    rhs = [-x * sp.Rational(7, 3)]         # a system no other test builds
    first = mp.equations(rhs, [x])
    assert first._compiled
    reads = []
    real = build._cached
    monkeypatch.setattr(build, "_cached", lambda path: reads.append(path) or real(path))
    again = mp.equations(rhs, [x])
    assert not again._compiled and again._path == first._path and reads == []
    assert again.rhs(0.0, [3.0])[0] == -7.0


# ---- the mass-matrix solve: closed form (NA <= 3) and LU ---------------------------

def _chain(n):
    """The planar n-link pendulum (point masses m_i on massless rods l_i, angles
    from the downward vertical), L = T - V with the full state-dependent mass
    matrix M_ij = (sum_{k >= max(i, j)} m_k) l_i l_j cos(q_i - q_j); returns
    (L, q, params)."""
    q = mp.coordinates(" ".join(f"a{i}" for i in range(n)))
    m = sp.symbols(f"m0:{n}")
    ln = sp.symbols(f"l0:{n}")
    g = sp.Symbol("g")
    T = sum(sum(m[k] for k in range(max(i, j), n)) * ln[i] * ln[j] * sp.cos(q[i] - q[j])
            * q[i].diff(t) * q[j].diff(t) for i in range(n) for j in range(n)) / 2
    V = -g * sum(sum(m[k] for k in range(i, n)) * ln[i] * sp.cos(q[i]) for i in range(n))
    vals = {"g": 9.81, **{f"m{i}": 1.0 + 0.3 * i for i in range(n)},
            **{f"l{i}": 1.0 - 0.05 * i for i in range(n)}}
    return T - V, q, vals


def _sympy_rhs(L, q, vals):
    """dy/dt from SymPy's own Euler-Lagrange equations (LagrangesMethod's mass
    matrix and forcing, lambdified; the accelerations by numpy.linalg.solve)."""
    from sympy.physics.mechanics import LagrangesMethod
    lm = LagrangesMethod(L, q)
    lm.form_lagranges_equations()
    n = len(q)
    x = sp.symbols(f"x0:{2 * n}")
    sub = {**{qi.diff(t): x[n + i] for i, qi in enumerate(q)},
           **{qi: x[i] for i, qi in enumerate(q)}}
    sub2 = {sp.Symbol(k): v for k, v in vals.items()}
    M = sp.lambdify(x, lm.mass_matrix.subs(sub).subs(sub2), "numpy")
    F = sp.lambdify(x, lm.forcing.subs(sub).subs(sub2), "numpy")

    def rhs(y):
        a = np.linalg.solve(np.array(M(*y), float), np.array(F(*y), float).ravel())
        return np.concatenate([y[n:], a])
    return rhs


def _spherical():
    th, ph = mp.coordinates("theta phi")
    m, l, g = sp.symbols("m l g")
    L = m * l ** 2 / 2 * (th.diff(t) ** 2 + sp.sin(th) ** 2 * ph.diff(t) ** 2) \
        + m * g * l * sp.cos(th)
    return L, [th, ph], {"m": 1.0, "l": 1.0, "g": 9.81}


def _heavy_top():
    ph, th, ps = mp.coordinates("phi theta psi")
    I1, I3, mgl = sp.symbols("I1 I3 mgl")
    w3 = ps.diff(t) + ph.diff(t) * sp.cos(th)
    L = I1 / 2 * (th.diff(t) ** 2 + ph.diff(t) ** 2 * sp.sin(th) ** 2) + I3 / 2 * w3 ** 2 \
        - mgl * sp.cos(th)
    return L, [ph, th, ps], {"I1": 1.0, "I3": 0.5, "mgl": 1.0}


def _uses_closed(s):
    return re.search(r"mp_closed_(ok|normal)\(mp_d0\b", s.c_source) is not None


# n >= 4 takes LU under either CLOSED_MAX, so chain10 with CLOSED_MAX = 0 repeats the
# C path of chain10 with 3; it is slow (SymPy's side) and left out under the sanitizers
@pytest.mark.parametrize("case,closed_max", [
    (c, m) if (c, m) != ("chain10", 0) else pytest.param(c, m, marks=pytest.mark.slow)
    for m in (3, 0)
    for c in ["chain1", "chain2", "chain3", "chain4", "chain10", "spherical", "top"]],
    ids=lambda v: str(v))
def test_generated_rhs_against_sympy(case, closed_max, monkeypatch, tmp_path):
    """The compiled rhs at random states equals SymPy's Euler-Lagrange equations
    solved by NumPy, on both solve paths: the closed form (n <= 3 with
    CLOSED_MAX = 3) and LU (n >= 4, or every n with CLOSED_MAX = 0)."""
    from mechpy.symbolic import codegen
    monkeypatch.setattr(codegen, "CLOSED_MAX", closed_max)
    # a cache of its own: the derivation cached with the other CLOSED_MAX is not taken
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    if case.startswith("chain"):
        L, q, vals = _chain(int(case[5:]))
    else:
        L, q, vals = _spherical() if case == "spherical" else _heavy_top()
    n = len(q)
    s = mp.lagrangian(L, q, params=vals)
    assert _uses_closed(s) == (n <= closed_max)
    ref = _sympy_rhs(L, q, vals)
    rng = np.random.default_rng(n + 10 * closed_max)
    worst = 0.0
    for _ in range(20 if n < 10 else 5):
        y = np.concatenate([rng.uniform(0.3, 2.8, n), rng.uniform(-2, 2, n)])
        want = ref(y)
        worst = max(worst, np.max(np.abs(s.rhs(0.0, y) - want)) / np.max(np.abs(want)))
    # measured: at most 2.6e-15 (n <= 4), 1.2e-13 (n = 10, ill-conditioned states)
    assert worst < 1e-12


def test_closed_solve_threshold_and_fallback():
    """n <= 3 coordinates + constraints solve in closed form, n >= 4 by LU; the
    closed form hands over to LU where det(A) overflows (entries of 1e200), and
    LU's statuses stand where the matrix is singular."""
    from mechpy.symbolic import codegen
    assert codegen.CLOSED_MAX == 3
    for n in (2, 3, 4):
        L, q, vals = _chain(n)
        assert _uses_closed(mp.lagrangian(L, q, params=vals)) == (n <= 3)
    # two coordinates and one constraint: NA = 3, closed
    x, y = mp.coordinates("x y")
    Lc = (x.diff(t) ** 2 + y.diff(t) ** 2) / 2 - 9.81 * y
    sc = mp.lagrangian(Lc, [x, y], constraints=[x ** 2 + y ** 2 - 1])
    assert _uses_closed(sc)
    # the bead on the circle at (1, 0) at rest: x'' = -lambda x ... gravity along
    # the tangent, so x'' = 0 and y'' = -9.81 exactly
    assert np.allclose(sc.rhs(0, [1.0, 0.0, 0.0, 0.0]), [0, 0, 0, -9.81], atol=1e-13)
    # huge entries: det overflows, LU solves; x'' = -x/2 ... from
    # L = 1e200 (x'^2 + x'y' + y'^2 - x^2 - y^2) / 2: M = 1e200 [[1, 1/2], [1/2, 1]]
    Lh = sp.Float(1e200) * (x.diff(t) ** 2 + x.diff(t) * y.diff(t) + y.diff(t) ** 2
                           - x ** 2 - y ** 2) / 2
    sh = mp.lagrangian(Lh, [x, y])
    assert _uses_closed(sh)
    a = np.linalg.solve([[1, 0.5], [0.5, 1]], [-0.3, -0.7])
    assert np.allclose(sh.rhs(0, [0.3, 0.7, 0.0, 0.0])[2:], a, rtol=1e-14)
    # singular everywhere: M = [[1, 1], [1, 1]]
    Ls = (x.diff(t) + y.diff(t)) ** 2 / 2 - x ** 2 / 2 - y ** 2 / 2
    ss = mp.lagrangian(Ls, [x, y])
    assert _uses_closed(ss)
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        ss.rhs(0, [0.1, 0.2, 0.0, 0.0])


@pytest.mark.parametrize("closed_max", [3, 0])
def test_non_finite_forcing_is_an_error_on_both_solve_paths(closed_max, monkeypatch, tmp_path):
    # d/dx sqrt(x) is NaN for x < 0 while the mass matrix stays the identity: the
    # closed form (whose determinant test sees A only) and LU both refuse the
    # state, never returning NaN accelerations with a success status
    from mechpy.symbolic import codegen
    monkeypatch.setattr(codegen, "CLOSED_MAX", closed_max)
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    x, y = mp.coordinates("x y")
    s = mp.lagrangian((x.diff() ** 2 + y.diff() ** 2) / 2 + sp.sqrt(x) + y, [x, y])
    assert _uses_closed(s) == (closed_max == 3)
    assert s.rhs(0.0, [4.0, 0.0, 0.0, 0.0]) == pytest.approx([0.0, 0.0, 0.25, 1.0], rel=1e-15)
    with pytest.raises(mp.NonFiniteError):
        s.rhs(0.0, [-1.0, 0.0, 0.0, 0.0])
    pytest.importorskip("numba")
    nb = mp.lagrangian((x.diff() ** 2 + y.diff() ** 2) / 2 + sp.sqrt(x) + y, [x, y],
                       backend="numba")
    with pytest.raises(mp.NonFiniteError):
        nb.rhs(0.0, [-1.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("theta", [1e-2, 1e-4, 1e-6])
def test_closed_form_keeps_its_precision_near_a_singular_configuration(theta):
    """The heavy top's mass matrix couples phi and psi in a block whose
    determinant is I1 I3 sin^2 theta; from the entries' values it is the
    difference (I1 s^2 + I3 c^2) I3 - (I3 c)^2, which cancels to a relative
    error of about eps / sin^2 theta (1e-4 at theta = 1e-6).  The closed form
    reduces the block symbolically, so the accelerations keep full precision
    near theta = 0: against SymPy's own equations solved in 50-digit
    arithmetic."""
    import mpmath
    from sympy.physics.mechanics import LagrangesMethod
    L, q, vals = _heavy_top()
    s = mp.lagrangian(L, q, params=vals)
    assert _uses_closed(s)
    lm = LagrangesMethod(L, q)
    lm.form_lagranges_equations()
    x = sp.symbols("x0:6")
    sub = {**{qi.diff(t): x[3 + i] for i, qi in enumerate(q)},
           **{qi: x[i] for i, qi in enumerate(q)}}
    sub2 = {sp.Symbol(k): v for k, v in vals.items()}
    M = sp.lambdify(x, lm.mass_matrix.subs(sub).subs(sub2), "mpmath")
    F = sp.lambdify(x, lm.forcing.subs(sub).subs(sub2), "mpmath")
    y = [0.3, theta, -0.2, 0.7, -0.4, 5.0]
    with mpmath.workdps(50):
        ym = [mpmath.mpf(v) for v in y]
        want = mpmath.lu_solve(mpmath.matrix(M(*ym)), mpmath.matrix(F(*ym)))
        want = np.array([float(w) for w in want])
    got = s.rhs(0.0, np.array(y))[3:]
    # measured: at most 2.1e-16 relative at every theta (from the entries: 2e-5
    # at theta = 1e-6)
    assert np.max(np.abs(got - want) / np.abs(want)) < 2e-15


@pytest.mark.parametrize("n, coupled", [
    (1, ()), (2, ()), (2, ((0, 1),)), (3, ()), (3, ((0, 1),)), (3, ((0, 2),)),
    (3, ((1, 2),)), (3, ((0, 1), (1, 2))), (3, ((0, 1), (0, 2), (1, 2)))])
@pytest.mark.parametrize("symbolic_ops", [None, pytest.param(0, marks=pytest.mark.slow)])
def test_closed_form_by_blocks_against_sympy(n, coupled, symbolic_ops, monkeypatch, tmp_path):
    """Mass matrices that split into every pattern of diagonal blocks up to
    3 x 3 (entries that depend on the coordinates and on a parameter, a
    potential that couples the blocks): the closed form, block by block,
    equals SymPy's Euler-Lagrange equations solved by NumPy at random states,
    with the cheaper of its two forms and (CLOSED_SYMBOLIC_OPS = 0) with the
    entries' form alone."""
    if symbolic_ops is not None:
        from mechpy.symbolic import codegen
        monkeypatch.setattr(codegen, "CLOSED_SYMBOLIC_OPS", symbolic_ops)
        monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    q = mp.coordinates(" ".join(f"q{i}" for i in range(n)))
    q = list(q) if n > 1 else [q[0]]
    m0 = sp.Symbol("m0")
    M = sp.zeros(n, n)
    for i in range(n):
        M[i, i] = (m0 if i == 0 else 1 + i / 2) * (1 + sp.Rational(3, 10)
                                                   * sp.sin(q[(i + 1) % n]) ** 2)
    for i, j in coupled:
        M[i, j] = M[j, i] = sp.Rational(1, 5) * sp.cos(q[i] - q[j])
    qd = sp.Matrix([qi.diff(t) for qi in q])
    V = sum((i + 1) * (1 - sp.cos(qi)) for i, qi in enumerate(q)) + q[0] * q[-1] / 10
    L = (qd.T * M * qd)[0, 0] / 2 - V
    vals = {"m0": 1.3}
    s = mp.lagrangian(L, q, params=vals)
    assert _uses_closed(s)
    ref = _sympy_rhs(L, q, vals)
    rng = np.random.default_rng(7 * n + len(coupled))
    worst = 0.0
    for _ in range(10):
        y = rng.uniform(-2, 2, 2 * n)
        want = ref(y)
        worst = max(worst, np.max(np.abs(s.rhs(0.0, y) - want)) / np.max(np.abs(want)))
    # measured: at most 8.3e-16
    assert worst < 4e-15


def test_a_mass_matrix_singular_up_to_rounding_is_refused():
    """M = 1000 [[49, 1], [1, a]] with a = fl(1/49) is singular but for
    rounding: its determinant comes out as 1e6 (49 a - 1) = -1.1e-10, not 0.
    The closed form must hand over to LU (which finds the pivot below its
    tolerance) and raise, never return the quotient by that rounding error
    (accelerations of order 1e13)."""
    x, y = mp.coordinates("x y")
    a = sp.Symbol("a")
    L = 500 * (49 * x.diff(t) ** 2 + 2 * x.diff(t) * y.diff(t) + a * y.diff(t) ** 2) \
        - (x ** 2 + y ** 2) / 2
    s = mp.lagrangian(L, [x, y], params={"a": 1 / 49})
    assert _uses_closed(s)
    assert 49 * (1 / 49) - 1 != 0
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        s.rhs(0.0, [0.3, 0.2, 0.0, 0.0])
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        mp.solve(s, (0, 1), [0.3, 0.2, 0.0, 0.0])
    # a regular neighbour (a = 2/49) is solved, by the same closed form
    r = s.replace(a=2 / 49)
    want = np.linalg.solve(1000 * np.array([[49, 1], [1, 2 / 49]]), [-0.3, -0.2])
    assert np.allclose(r.rhs(0.0, [0.3, 0.2, 0.0, 0.0])[2:], want, rtol=1e-13, atol=0)


def test_kane_block_split_is_taken_only_for_its_own_structure():
    # codegen solves a Kane model by blocks (M u' = F and C C^T mu = ...) only
    # when A has the blocks that split assumes: I and -C^T on the first rows,
    # M alone on u', C alone on q'; any other A goes through the whole LU
    from mechpy.symbolic.codegen import _kane_blocks
    c0, c1, m = sp.symbols("c0 c1 m")
    na, nc, ns = 4, 2, 3          # q' (2), u' (1), mu (1)

    def A(**change):
        rows = [[1, 0, 0, -c0], [0, 1, 0, -c1], [0, 0, m, 0], [c0, c1, 0, 0]]
        for key, v in change.items():
            i, j = int(key[1]), int(key[2])
            rows[i][j] = v
        return [e for r in rows for e in r]
    assert _kane_blocks(A(), na, nc, ns)
    assert not _kane_blocks(A(a03=c0), na, nc, ns)        # +C^T: mu would change sign
    assert not _kane_blocks(A(a13=0), na, nc, ns)         # not the transpose of C
    assert not _kane_blocks(A(a00=2), na, nc, ns)         # q' not alone
    assert not _kane_blocks(A(a20=c0), na, nc, ns)        # M's row reaches q'
    assert not _kane_blocks(A(a23=c1), na, nc, ns)        # ... or mu
    assert not _kane_blocks(A(a32=c1), na, nc, ns)        # C reaches u'


def test_each_parameter_vector_reaches_its_trajectory():
    """Expressions of the parameters alone (a b + a c, a + b, and a Piecewise
    whose condition compares two parameters) take each trajectory's values:
    the scene's, replace()'s, solve_many's rows (one by one and in SIMD
    lanes), against the exact solution expm(A t) y0."""
    from scipy.linalg import expm
    x, y = mp.coordinates("x y")
    a, b, c = sp.symbols("a b c")
    f = [sp.Piecewise((-a, a > b), (-b, True)) * x + (a * b + a * c) * y, -(a + b) * x - c * y]
    s = mp.equations(f, [x, y], params=dict(a=0.5, b=0.2, c=0.3))

    def exact(a_, b_, c_):
        A = np.array([[-a_ if a_ > b_ else -b_, a_ * b_ + a_ * c_], [-(a_ + b_), -c_]])
        return expm(2.0 * A) @ [1.0, 0.5]

    rows = np.array([[0.5, 0.2, 0.3], [0.2, 0.5, 0.3], [1.5, 0.7, 0.1]])
    opts = dict(rtol=1e-12, atol=1e-14)
    one = []
    for r in rows:
        sol = mp.solve(s.replace(a=r[0], b=r[1], c=r[2]), (0, 2), [1.0, 0.5], **opts)
        one.append(sol.y[:, -1])
        # measured: 2.2e-15, 5.1e-15, 9.3e-14 (the fastest row); another
        # row's values or the other branch is off by 1e-2 or more
        assert np.abs(sol.y[:, -1] - exact(*r)).max() < 5e-13
    for lanes in (False, True):
        ens = mp.solve_many(s, (0, 2), np.tile([1.0, 0.5], (3, 1)), lanes=lanes,
                            params={"a": rows[:, 0], "b": rows[:, 1], "c": rows[:, 2]}, **opts)
        for i, r in enumerate(rows):
            assert np.abs(ens.y[i, :, -1] - exact(*r)).max() < 5e-13
            if not lanes:
                assert np.array_equal(ens.y[i, :, -1], one[i])
    # a row of the wrong length is named with the scene's parameters
    with pytest.raises(ValueError, match=r"params must have 3 columns \(the scene's parameters"):
        mp.solve_many(s, (0, 1), np.tile([1.0, 0.5], (3, 1)), params=rows[:, :2])


# ---- non-smooth functions, numba's error model --------------------------------

def _coulomb_turning_points(x0, d):
    """The closed form of x'' = -w^2 x - F sign(x') from rest at x0, d = F/w^2:
    the positions at the turning points t = k pi/w (the amplitude about the
    shifted equilibrium +-d falls by 2d each half cycle), the last one where
    the mass sticks for good (|x| <= d: the spring no longer beats static
    friction)."""
    xs = [x0]
    while abs(xs[-1]) > d:
        xs.append(-np.sign(xs[-1]) * (abs(xs[-1]) - 2 * d))
    return np.array(xs)


def _coulomb(backend):
    x, v = sp.symbols("x v")
    w, F = sp.symbols("w F", positive=True)
    return mp.equations([v, -w ** 2 * x - F * sp.sign(v)], [x, v],
                        params={"w": 2.0, "F": 0.6}, backend=backend)


@pytest.mark.parametrize("backend", ["c", "numba"])
def test_dry_friction_compiles_and_follows_its_closed_form(backend):
    """sign(v) (Coulomb friction) compiles: its derivative is 0 almost
    everywhere.  What a solver can promise: an adaptive method resolves every
    turning point to its tolerance up to the moment the mass sticks (there
    x' = 0 with |x| <= F/k has no solution of the ODE beside it: sign(v) flips
    at every step and the step size collapses, measured: the step budget or
    the round-off limit ends dop853 and radau at that instant); a fixed step
    passes it, v chattering about 0 by O(F h) and x held in the resting band
    (rk4, h = 1e-3: x within 8.4e-4 of the closed form's resting point 5 s
    later)."""
    if backend == "numba":
        pytest.importorskip("numba")
    s = _coulomb(backend)
    w, d = 2.0, 0.6 / 4.0
    np.testing.assert_array_equal(s.jacobian(0.0, [0.3, 0.1]), [[0.0, 1.0], [-w * w, 0.0]])
    np.testing.assert_allclose(s.rhs(0.0, [0.3, 0.0]), [0.0, -1.2])    # sign(0) = 0
    xs = _coulomb_turning_points(1.0, d)
    np.testing.assert_allclose(xs, [1.0, -0.7, 0.4, -0.1])
    T = np.pi / w
    k = len(xs) - 1
    for method in ("dop853", "radau"):
        sol = mp.solve(s, (0, k * T), [1.0, 0.0], t_eval=T * np.arange(k + 1), method=method,
                       rtol=1e-10, atol=1e-12)
        assert sol.success, sol.message
        np.testing.assert_allclose(sol.y[0], xs, rtol=0, atol=1e-8)    # measured 3e-12
    te = np.r_[T * np.arange(k + 1), np.linspace(k * T, k * T + 5.0, 50)]
    sol = mp.solve(s, (0, k * T + 5.0), [1.0, 0.0], t_eval=np.unique(te), method="rk4",
                   h=1e-3)
    turning = np.searchsorted(sol.t, T * np.arange(k + 1))
    np.testing.assert_allclose(sol.y[0, turning], xs, rtol=0, atol=1e-6)   # measured 7e-8
    rest = sol.y[0, sol.t >= k * T]
    assert np.all(np.abs(rest) <= d)
    assert np.abs(rest - xs[-1]).max() < 5e-3
    assert np.abs(sol.y[1, sol.t >= k * T + 0.5]).max() < 1e-2     # v chatters about 0


def test_dry_friction_in_lanes():
    """Trajectories of the friction oscillator in the lanes of solve_many (C's
    lane rhs prints sign as selects): each sticks after its own number of half
    cycles, at the closed form's resting point (see above for rk4's chatter)."""
    s = _coulomb("c")
    w, d = 2.0, 0.15
    T = np.pi / w
    x0 = np.linspace(0.5, 1.2, 8)
    te = T * np.arange(7)
    ens = mp.solve_many(s, (0, te[-1]), np.c_[x0, np.zeros(8)], t_eval=te, method="rk4",
                        h=1e-3, lanes=True)
    assert ens.lanes
    for i, a in enumerate(x0):
        xs = _coulomb_turning_points(a, d)
        k = len(xs) - 1
        assert 1 <= k <= 4
        # the turning points while it moves (the last, where it sticks, is in
        # the resting band below: measured 1.6e-6 off after the chatter began)
        np.testing.assert_allclose(ens.y[i, 0, :k], xs[:-1], rtol=0, atol=1e-6)
        assert np.all(np.abs(ens.y[i, 0, k:]) <= d)
        assert np.abs(ens.y[i, 0, k:] - xs[-1]).max() < 5e-3


@pytest.mark.parametrize("backend", ["c", "numba", "numpy"])
def test_nonsmooth_functions_differentiate_almost_everywhere(backend):
    """Abs, sign, Max, Min, floor, ceiling in a right-hand side and in a
    Lagrangian: the Jacobian equals central differences of the rhs at points
    away from their kinks and jumps (where they are smooth)."""
    if backend == "numba":
        pytest.importorskip("numba")
    x, y = sp.symbols("x y")
    f = [sp.Abs(x - 0.3) * y + sp.Max(x, y ** 2, 0.2) + sp.floor(3 * x) * y,
         sp.Min(sp.sin(x), y) - sp.ceiling(y) * x ** 2 + sp.sign(x - y) * x * y]
    s = mp.equations(f, [x, y], backend=backend)
    fn = sp.lambdify([x, y], f, "numpy")
    for pt in ([0.1, 0.7], [0.9, 0.2], [0.45, -0.8], [-0.6, 0.95]):
        np.testing.assert_allclose(s.rhs(0.0, pt), fn(*pt), rtol=1e-14, atol=1e-15)
        h = 1e-6
        fd = np.array([(np.array(fn(*(np.array(pt) + h * e))) - fn(*(np.array(pt) - h * e)))
                       / (2 * h) for e in np.eye(2)]).T
        np.testing.assert_allclose(s.jacobian(0.0, pt), fd, rtol=1e-7, atol=1e-8)
    # a Lagrangian: V = k |q| (a V-shaped well) and quadratic drag by |q'| q'
    q, = mp.coordinates("q")
    L = q.diff(t) ** 2 / 2 - 2.0 * sp.Abs(q)
    lag = mp.lagrangian(L, [q], forces=[-0.5 * sp.Abs(q.diff(t)) * q.diff(t)],
                        backend=backend)
    for pt in ([0.4, 0.3], [-0.2, -0.6]):
        a = -2.0 * np.sign(pt[0]) - 0.5 * abs(pt[1]) * pt[1]
        np.testing.assert_allclose(lag.rhs(0.0, pt), [pt[1], a], rtol=1e-14)
        np.testing.assert_allclose(lag.jacobian(0.0, pt), [[0, 1], [0, -abs(pt[1])]],
                                   rtol=1e-14)


@pytest.mark.parametrize("backend", ["c", "numba"])
def test_division_by_zero_gives_inf_in_every_build(backend):
    """numba's Python error model raised ZeroDivisionError inside the cfunc,
    where nothing catches it: numba printed "Exception ignored" and rhs
    returned what the output held ([0.3, 0.0] for x'' = -1/x at x = 0).  Both
    builds now compute IEEE's inf: NonFiniteError, and an energy of inf."""
    if backend == "numba":
        pytest.importorskip("numba")
    x, v = sp.symbols("x v")
    s = mp.equations([v, -1 / x], [x, v], energy=v ** 2 / 2 - sp.log(x), backend=backend)
    with pytest.raises(mp.NonFiniteError, match="inf"):
        s.rhs(0.0, [0.0, 0.3])
    assert s.energy([0.0, 0.3]) == np.inf
    assert np.all(np.isfinite(s.rhs(0.0, [2.0, 0.3])))


# ---- the Jacobian printed by its nonzeros ---------------------------------------

def _mass_chain(n):
    """n masses in a line between two walls, springs between neighbours and a cubic
    drag: 2n states, a Jacobian with at most 3 nonzeros a row."""
    x, v = sp.symbols(f"x0:{n}"), sp.symbols(f"v0:{n}")
    k, c = sp.symbols("k c")
    acc = [k * ((x[i - 1] if i else 0) - 2 * x[i] + (x[i + 1] if i < n - 1 else 0))
           - c * v[i] ** 3 for i in range(n)]
    return list(v) + acc, list(x) + list(v)


def _jac_function(source):
    i = source.index("void gen_J(")
    return source[i:source.index("\n}\n", i)]


def test_jacobian_source_grows_with_its_nonzeros():
    """mp.equations printed the Jacobian densely: (2n)^2 lines for a chain of n
    masses, 9,803 of 10,832 lines `out[i] = 0.0;` at 100 states, and a build
    time that grew with their square (487 s at 400 states).  Now out[] is zeroed
    by one loop and the nonzeros alone are printed: the Jacobian's text per
    nonzero is the same at 20 and 160 states (measured 39 and 36 characters),
    and the Jacobian equals SymPy's dense one, evaluated independently."""
    per = []
    for n in (10, 80):
        f, y = _mass_chain(n)
        s = mp.equations(f, y, params={"k": 1.3, "c": 0.1})
        Jsym = sp.Matrix(f).jacobian(y)
        nnz = sum(1 for e in Jsym if e != 0)
        assert nnz == 2 * n + 3 * n - 2         # dx'/dv, the springs' band, the drag
        text = _jac_function(s.c_source)
        assert len(re.findall(r"\bout\[\d+\] = ", text)) == nnz
        assert "= 0.0;" not in text.replace("out[i] = 0.0;", "")
        per.append(len(text) / nnz)
        assert s._jac_band[:2] == (2, 2)      # radau's band LU takes the pattern
        fn = sp.lambdify([y, sp.symbols("k c")], Jsym, "numpy")
        rng = np.random.default_rng(n)
        for _ in range(3):
            yv = rng.normal(size=2 * n)
            np.testing.assert_allclose(s.jacobian(0.0, yv), fn(yv, [1.3, 0.1]), rtol=1e-15,
                                       atol=0)
    assert per[1] < 1.5 * per[0], per
    # the whole source is linear too: measured 172 characters a nonzero at 160
    # states (the rhs, its lane version, the fixed-step blocks beside the Jacobian)
    assert len(s.c_source) < 500 * nnz


# ---- clear errors (issue 51) ------------------------------------------------------

def test_a_singular_lagrangian_says_what_is_singular():
    """A Lagrangian with no kinetic term was reported as "singular
    configuration (gimbal lock, singular matrix)"; the error now says that L
    has no kinetic term, or which constraint Jacobian is rank-deficient."""
    th, = mp.coordinates("theta")
    pot = mp.lagrangian(-sp.cos(th), [th])
    for call in (lambda: pot.rhs(0.0, [0.1, 0.0]), lambda: mp.solve(pot, (0, 1), [0.1, 0.0])):
        with pytest.raises(mp.SingularityError, match=r"L has no kinetic term: its mass "
                           r"matrix d2L/dq'dq' is 0 at t = 0\.0, y = \[0\.1, 0\.0\]") as err:
            call()
        assert "gimbal" not in str(err.value)
    x, y = mp.coordinates("x y")
    ring = mp.lagrangian((x.diff(t) ** 2 + y.diff(t) ** 2) / 2, [x, y],
                         constraints=[x ** 2 + y ** 2 - 1])
    with pytest.raises(mp.SingularityError, match=r"the constraints' Jacobian dg/dq has rank "
                       r"0 of 1 at t = 0\.0"):
        ring.rhs(0.0, [0.0, 0.0, 0.0, 0.0])     # dg/dq = 2 (x, y) = 0 at the centre
    np.testing.assert_allclose(ring.rhs(0.0, [1.0, 0.0, 0.0, 0.5])[2:], [-0.25, 0.0],
                               atol=1e-15)    # centripetal: -v^2 / r on the circle


def test_compiler_command_errors_name_mechpy_cc(monkeypatch):
    """MECHPY_CC='gcc "' gave shlex's bare "No closing quotation", and a blank
    MECHPY_CC ran "-O2" as the compiler: the first names MECHPY_CC, the second
    counts as unset."""
    from mechpy.symbolic import build
    monkeypatch.setenv("MECHPY_CC", 'gcc "')
    with pytest.raises(mp.CompileError, match=r"MECHPY_CC = 'gcc \"' cannot be split into "
                       r"words \(No closing quotation\)"):
        build.compiler()
    for blank in ("", "   "):
        monkeypatch.setenv("MECHPY_CC", blank)
        assert build.compiler()[0] != "-O2" and build.compiler() == _default_cc(monkeypatch)
        x, v = sp.symbols("x v")
        osc = mp.equations([v, -2.5 * x], [x, v])
        np.testing.assert_array_equal(osc.rhs(0.0, [1.0, 0.0]), [0.0, -2.5])


def _default_cc(monkeypatch):
    """The compiler command with MECHPY_CC unset."""
    from mechpy.symbolic import build
    with monkeypatch.context() as m:
        m.delenv("MECHPY_CC", raising=False)
        return build.compiler()


def test_first_step_below_the_normal_range_is_refused():
    """first_step=5e-324 made radau report an overflow ("rescale the system");
    a first step below the smallest normal double is refused as a fixed h below
    the spacing of t is (radau overflowed at 1e-308 and ran at 2.2e-308)."""
    P = mp.scenes.Pendulum()
    for fs in (5e-324, 1e-308):
        with pytest.raises(ValueError, match=r"first_step = .* is below the smallest normal "
                           r"double"):
            mp.solve(P, (0, 1), [0.1, 0.0], method="radau", first_step=fs)
    s = mp.solve(P, (0, 1), [0.1, 0.0], method="radau", first_step=2.2250738585072014e-308)
    assert s.success


def test_a_truncated_numba_cache_file_is_rebuilt(tmp_path):
    """A truncated numba cache file (jit_<key>.*.nbc) made every later build
    of that system fail with numba's raw UnpicklingError, in every process;
    it is deleted and compiled again, as a damaged C library is."""
    pytest.importorskip("numba")
    code = textwrap.dedent("""
        import sympy as sp, mechpy as mp
        x, v = sp.symbols("x v")
        s = mp.equations([v, -3.0 * x], [x, v], backend="numba")
        print(s.rhs(0.0, [1.0, 0.5]).tolist())
    """)
    env = dict(os.environ, MECHPY_CACHE_DIR=str(tmp_path))

    def run():
        r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                           text=True, timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        return r.stdout.strip().splitlines()[-1]
    assert run() == "[0.5, -3.0]"
    data = [p for p in tmp_path.rglob("jit_*.nbc")]
    assert data
    for p in data:
        p.write_bytes(p.read_bytes()[:20])
    assert run() == "[0.5, -3.0]"
    assert all(p.stat().st_size > 20 for p in tmp_path.rglob("jit_*.nbc"))
    assert run() == "[0.5, -3.0]"      # and the rebuilt files load
