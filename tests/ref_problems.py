"""Outside test problems with their reference solutions (pure NumPy/SciPy).

Two sets:

* DETEST, the non-stiff problem classes A-E of Hull, Enright, Fellen and
  Sedgwick, "Comparing numerical methods for ordinary differential equations",
  SIAM J. Numer. Anal. 9 (1972) 603-637, in the form of Enright and Pryce's
  DETEST package, "Two FORTRAN packages for assessing initial value methods",
  ACM TOMS 13 (1987) 1-27: every problem runs on [0, 20].
* The stiff problems of the IVP test set: F. Mazzia and C. Magherini, "Test
  Set for Initial Value Problem Solvers", release 2.4, University of Bari
  (2008): HIRES, OREGO, ROBER, VDPOL (mu = 1000) and E5.

Reference values at the final time, and how each was obtained (``ref_how``):

* ``closed form``: A1-A4, B5 (Jacobi elliptic functions, m = 0.51), D1-D5
  (Kepler's equation, a = 1, so the mean anomaly is t), E1 (the Bessel
  function J_1/2(t + 1)), E4, E5 (elementary integrals); the linear systems
  B2, C1-C4 through ``scipy.linalg.expm``.
* ``DETEST``: A5, B1, B3, B4, C5, E2, E3 - the end values of the DETEST
  package's true solutions (as printed in the Enright-Pryce package and
  carried in its ports), cross-checked in tests/test_detest.py by
  ``solve_ivp(method="DOP853", rtol=1e-13)`` and by Radau.
* ``IVP test set``: the published end values of each problem (its Fortran
  ``solut`` routines: computed there with RADAU5 in extended precision, unit
  round-off 1.01e-19, at tolerances 1.1e-18).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq
from scipy.special import ellipj


@dataclass
class Problem:
    """One test problem: y' = f(t, y), y(t0) = y0, reference y(tf)."""
    name: str
    f: Callable
    y0: np.ndarray
    tf: float
    ref: np.ndarray
    ref_how: str
    jac: Callable | None = None
    t0: float = 0.0
    atol: float | np.ndarray = 1e-12   # the absolute tolerance the problem is run with
    scene: Callable | None = None      # a mechpy scene for the same system, if there is one
    extra: dict = field(default_factory=dict)

    @property
    def n(self):
        return self.y0.size


# ---- DETEST class A: single equations ------------------------------------------

def _a1(t, y):
    return -y


def _a2(t, y):
    return -0.5 * y ** 3


def _a3(t, y):
    return y * np.cos(t)


def _a4(t, y):
    return 0.25 * y * (1.0 - y / 20.0)


def _a5(t, y):
    return (y - t) / (y + t)


# ---- class B: small systems ------------------------------------------------------

def _b1(t, y):
    return np.array([2.0 * (y[0] - y[0] * y[1]), -(y[1] - y[0] * y[1])])


_B2 = np.array([[-1.0, 1.0, 0.0], [1.0, -2.0, 1.0], [0.0, 1.0, -1.0]])


def _b2(t, y):
    return _B2 @ y


def _b3(t, y):
    return np.array([-y[0], y[0] - y[1] ** 2, y[1] ** 2])


def _b4(t, y):
    r = np.hypot(y[0], y[1])
    return np.array([-y[1] - y[0] * y[2] / r, y[0] - y[1] * y[2] / r, y[0] / r])


def _b5(t, y):
    return np.array([y[1] * y[2], -y[0] * y[2], -0.51 * y[0] * y[1]])


# ---- class C: moderate systems ---------------------------------------------------

def _c1_matrix():
    A = np.diag(-np.ones(10)) + np.diag(np.ones(9), -1)
    A[9, 9] = 0.0                                    # y10' = y9
    return A


def _c2_matrix():
    i = np.arange(1, 11, dtype=float)
    A = np.diag(-i) + np.diag(i[:-1], -1)            # y_i' = (i-1) y_{i-1} - i y_i
    A[9, 9] = 0.0                                    # y10' = 9 y9
    return A


def _tridiag(n):
    return np.diag(-2.0 * np.ones(n)) + np.diag(np.ones(n - 1), 1) + np.diag(np.ones(n - 1), -1)


_C1, _C2, _C3, _C4 = _c1_matrix(), _c2_matrix(), _tridiag(10), _tridiag(51)


def _linear(A):
    def f(t, y):
        return A @ y
    f.matrix = A
    return f


# C5: the five outer planets about the Sun (heliocentric), DETEST's data
_C5_K2 = 2.95912208286
_C5_M0 = 1.00000597682
_C5_M = np.array([0.000954786104043, 0.000285583733151, 0.0000437273164546,
                  0.0000517759138449, 0.00000277777777778])
_C5_Y0 = np.array([
    3.42947415189, 3.35386959711, 1.35494901715,
    6.64145542550, 5.97156957878, 2.18231499728,
    11.2630437207, 14.6952576794, 6.27960525067,
    -30.1552268759, 1.65699966404, 1.43785752721,
    -21.1238353380, 28.4465098142, 15.3882659679,
    -0.557160570446, 0.505696783289, 0.230578543901,
    -0.415570776342, 0.365682722812, 0.169143213293,
    -0.325325669158, 0.189706021964, 0.0877265322780,
    -0.0240476254170, -0.287659532608, -0.117219543175,
    -0.176860753121, -0.216393453025, -0.0148647893090])


def _c5(t, y):
    q = y[:15].reshape(5, 3)                         # body j: q[j] = (x, y, z)
    r3 = np.sum(q * q, axis=1) ** 1.5
    d = q[None, :, :] - q[:, None, :]                # d[j, k] = q_k - q_j
    d3 = np.sum(d * d, axis=2) ** 1.5
    np.fill_diagonal(d3, np.inf)
    acc = -(_C5_M0 + _C5_M)[:, None] * q / r3[:, None]
    pert = d / d3[:, :, None] - (q / r3[:, None])[None, :, :]
    pert[np.arange(5), np.arange(5)] = 0.0
    acc += np.einsum("k,jki->ji", _C5_M, pert)
    return np.concatenate([y[15:], _C5_K2 * acc.reshape(15)])


# ---- class D: orbit equations (Kepler, eccentricity e) ---------------------------

def _kepler(t, y):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])


def kepler_exact(e, t):
    """The orbit from perihelion (1 - e, 0) with a = 1, so the mean anomaly is t."""
    E = brentq(lambda E: E - e * np.sin(E) - t, t - 1.0, t + 1.0, xtol=1e-15)
    for _ in range(3):  # Newton polish to the last bit
        E -= (E - e * np.sin(E) - t) / (1.0 - e * np.cos(E))
    c, s = np.cos(E), np.sin(E)
    b = np.sqrt(1.0 - e * e)
    w = 1.0 - e * c
    return np.array([c - e, b * s, -s / w, b * c / w])


# ---- class E: higher-order equations ---------------------------------------------

def _e1(t, y):
    x = t + 1.0
    return np.array([y[1], -(y[1] / x + (1.0 - 0.25 / (x * x)) * y[0])])


def _bessel_half(x):
    """J_1/2(x) = sqrt(2/(pi x)) sin x and its derivative."""
    c = np.sqrt(2.0 / np.pi)
    return np.array([c * np.sin(x) / np.sqrt(x),
                     c * (np.cos(x) / np.sqrt(x) - 0.5 * np.sin(x) / x ** 1.5)])


def _e2(t, y):
    return np.array([y[1], (1.0 - y[0] ** 2) * y[1] - y[0]])


def _e3(t, y):
    return np.array([y[1], y[0] ** 3 / 6.0 - y[0] + 2.0 * np.sin(2.78535 * t)])


def _e4(t, y):
    return np.array([y[1], 0.032 - 0.4 * y[1] ** 2])


def _e4_exact(t):
    # y2' = a - b y2^2: y2 = sqrt(a/b) tanh(sqrt(ab) t), y1 = 30 + ln(cosh(sqrt(ab) t)) / b
    a, b = 0.032, 0.4
    w = np.sqrt(a * b)
    return np.array([30.0 + np.log(np.cosh(w * t)) / b, np.sqrt(a / b) * np.tanh(w * t)])


def _e5(t, y):
    return np.array([y[1], np.sqrt(1.0 + y[1] ** 2) / (25.0 - t)])


def _e5_exact(t):
    # asinh(y2) = ln(25 / s), s = 25 - t; y1 = integral of y2 = (25/s - s/25)/2
    s = 25.0 - t
    y2 = 0.5 * (25.0 / s - s / 25.0)
    y1 = 12.5 * np.log(25.0 / s) + (s * s - 625.0) / 100.0
    return np.array([y1, y2])


def detest() -> list[Problem]:
    """The 25 DETEST problems A1 ... E5 with their end values at t = 20."""
    P = []
    one = np.array([1.0])
    P.append(Problem("A1", _a1, one.copy(), 20.0, np.exp([-20.0]), "closed form"))
    P.append(Problem("A2", _a2, one.copy(), 20.0, np.array([1.0 / np.sqrt(21.0)]),
                     "closed form"))
    P.append(Problem("A3", _a3, one.copy(), 20.0, np.exp([np.sin(20.0)]), "closed form"))
    P.append(Problem("A4", _a4, one.copy(), 20.0,
                     np.array([20.0 / (1.0 + 19.0 * np.exp(-5.0))]), "closed form"))
    P.append(Problem("A5", _a5, np.array([4.0]), 20.0, np.array([-0.7887826688964196]),
                     "DETEST"))
    P.append(Problem("B1", _b1, np.array([1.0, 3.0]), 20.0,
                     np.array([0.6761876008576667, 0.1860816099640036]), "DETEST"))
    y0 = np.array([2.0, 0.0, 1.0])
    P.append(Problem("B2", _b2, y0, 20.0, expm(20.0 * _B2) @ y0, "closed form"))
    P.append(Problem("B3", _b3, np.array([1.0, 0.0, 0.0]), 20.0,
                     np.array([2.061153488557776e-9, 5.257228022048349e-2, 0.9474277177183630]),
                     "DETEST"))
    P.append(Problem("B4", _b4, np.array([3.0, 0.0, 0.0]), 20.0,
                     np.array([0.9826950928005993, 2.198447081694832, 0.9129452507276399]),
                     "DETEST"))
    sn, cn, dn, _ = ellipj(20.0, 0.51)
    P.append(Problem("B5", _b5, np.array([0.0, 1.0, 1.0]), 20.0, np.array([sn, cn, dn]),
                     "closed form"))
    for name, A in [("C1", _C1), ("C2", _C2), ("C3", _C3), ("C4", _C4)]:
        y0 = np.zeros(A.shape[0])
        y0[0] = 1.0
        P.append(Problem(name, _linear(A), y0, 20.0, expm(20.0 * A) @ y0, "closed form",
                         jac=(lambda A: lambda t, y: A)(A)))
    P.append(Problem("C5", _c5, _C5_Y0.copy(), 20.0, np.array([
        -4.792730224323733, -2.420550725448973, -0.9212509306014886,
        -4.217310404035213, 7.356202947498970, 3.223785985421212,
        4.035559443262270, 17.19865528670555, 7.478910794233703,
        -29.98759326324844, -4.107310937550929, -0.9277008321754407,
        -24.42125302518482, 23.81459045746554, 14.92096306951359,
        0.3499208963063806, -0.5748487687912825, -0.2551694020879149,
        -0.5237040978903326, -0.2493000463579661, -0.08045341642044464,
        -0.3875289237334110, 0.05648603288767891, 0.03023606472143342,
        0.04133856546712445, -0.2862393029841379, -0.1183032405136207,
        -0.1511986457359206, -0.2460068894318766, -0.03189687411323877]), "DETEST"))
    for k, e in enumerate([0.1, 0.3, 0.5, 0.7, 0.9], start=1):
        y0 = np.array([1.0 - e, 0.0, 0.0, np.sqrt((1.0 + e) / (1.0 - e))])
        P.append(Problem(f"D{k}", _kepler, y0, 20.0, kepler_exact(e, 20.0), "closed form",
                         extra=dict(e=e)))
    P.append(Problem("E1", _e1, _bessel_half(1.0), 20.0, _bessel_half(21.0), "closed form"))
    P.append(Problem("E2", _e2, np.array([2.0, 0.0]), 20.0,
                     np.array([2.008149762174948, -0.04250887527320057]), "DETEST"))
    P.append(Problem("E3", _e3, np.array([0.0, 0.0]), 20.0,
                     np.array([-0.1004178858647128, 0.2411400132095954]), "DETEST"))
    P.append(Problem("E4", _e4, np.array([30.0, 0.0]), 20.0, _e4_exact(20.0), "closed form"))
    P.append(Problem("E5", _e5, np.array([0.0, 0.0]), 20.0, _e5_exact(20.0), "closed form"))
    return P


# ---- the IVP test set's stiff problems: mechpy.benches.problems (the benches run them too)

def stiff_set() -> list[Problem]:
    """HIRES, OREGO, ROBER, VDPOL (mu = 1000, plain form) and E5 with the IVP
    test set's published end values (mechpy/benches/problems.py, one home for
    the tests and the benches); each runs with an absolute tolerance below the
    size of the components that matter (ROBER's y2 ~ 1e-13 gets 1e-20, E5's
    y2, y3 ~ 9e-23 get 1.7e-24)."""
    import mechpy as mp
    from mechpy.benches.problems import STIFF_SET, VDP_MU, VDPOL
    scenes = {VDPOL.name: lambda: mp.scenes.VanDerPol(mu=VDP_MU)}
    return [Problem(P.name, P.f, np.array(P.y0, dtype=float), P.t_span[1], np.array(P.ref),
                    "IVP test set", jac=P.jac, t0=P.t_span[0],
                    atol=np.array(P.atol) if isinstance(P.atol, tuple) else P.atol,
                    scene=scenes.get(P.name))
            for P in STIFF_SET]


def error_norm(y, ref, rtol, atol):
    """SciPy's test measure: RMS of (y - ref) / (atol + rtol |ref|)."""
    e = (np.asarray(y) - ref) / (atol + rtol * np.abs(ref))
    return float(np.sqrt(np.mean(e * e)))


def max_abs_error(y, ref):
    return float(np.max(np.abs(np.asarray(y) - ref)))


def relative_error(y, ref, atol):
    """max_i |y_i - ref_i| / max(|ref_i|, 10 atol_i): relative where a component is
    well above its absolute tolerance, in units of 10 atol where it is not (E5's
    y1 ~ 1e-290 and y4 = 0)."""
    atol = np.broadcast_to(atol, np.shape(ref))
    return float(np.max(np.abs(np.asarray(y) - ref) / np.maximum(np.abs(ref), 10 * atol)))
