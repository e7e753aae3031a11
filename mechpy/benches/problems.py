"""Reference problems with published end values, each written once.

The benches (hard_cases, stiff_cvode) and the tests (tests/ref_problems.py,
tests/test_hard_cases.py, tests/test_stiff_set.py) read them from here, so a
bench and the test that checks it run the very same right-hand side against
the very same reference.

The stiff problems of the IVP test set: F. Mazzia and C. Magherini, "Test Set
for Initial Value Problem Solvers", release 2.4, University of Bari (2008),
after the CWI test set (Lioen and de Swart) and Hairer & Wanner, Solving
Ordinary Differential Equations II, IV.10.  The end values are the published
ones (the test set's Fortran ``solut`` routines: computed there with RADAU5 in
extended precision, unit round-off 1.01e-19, at tolerances 1.1e-18).

A problem's ``equations(y)`` is written once for both uses: y a sequence of
floats gives the right-hand side's values (``f``), y a sequence of SymPy
symbols its equations (``mp.equations``, as stiff_cvode compiles them).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class Problem:
    """y' = f(y) (autonomous), y(t0) = y0, and the published y(tf)."""
    name: str
    equations: Callable      # y (floats or SymPy symbols) -> the n right-hand sides, a list
    jacobian: Callable       # y (floats) -> the n x n df/dy, an ndarray
    y0: tuple
    t_span: tuple
    ref: tuple               # the published end values y(tf)
    atol: float | tuple | None  # the absolute tolerance it is run with (None: rtol's)
    source: str              # where ref comes from

    @property
    def n(self) -> int:
        return len(self.y0)

    def f(self, t, y):
        """dy/dt at (t, y) as an ndarray (SciPy's and mp.solve's signature)."""
        return np.array(self.equations(y))

    def jac(self, t, y):
        """df/dy at (t, y) as an ndarray (SciPy's and mp.solve's signature)."""
        return self.jacobian(y)


_IVP = "IVP test set (Mazzia, Magherini, release 2.4)"


# ---- ROBER: Robertson's chemical kinetics, to t = 1e11 -------------------------------------

def _rober(y):
    return [-0.04 * y[0] + 1e4 * y[1] * y[2],
            0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] ** 2,
            3e7 * y[1] ** 2]


def _rober_jac(y):
    return np.array([[-0.04, 1e4 * y[2], 1e4 * y[1]],
                     [0.04, -1e4 * y[2] - 6e7 * y[1], -1e4 * y[1]],
                     [0.0, 6e7 * y[1], 0.0]])


#: y2 ~ 1e-13 at the end: its absolute tolerance is 1e-20.
ROBER = Problem("ROBER", _rober, _rober_jac, (1.0, 0.0, 0.0), (0.0, 1e11),
                # IVP test set, rober.f's solut
                (0.2083340149701255e-7, 0.8333360770334713e-13, 0.9999999791665050),
                (1e-14, 1e-20, 1e-14), _IVP)


# ---- HIRES: plant physiology (8 states) -----------------------------------------------------

def _hires(y):
    return [-1.71 * y[0] + 0.43 * y[1] + 8.32 * y[2] + 0.0007,
            1.71 * y[0] - 8.75 * y[1],
            -10.03 * y[2] + 0.43 * y[3] + 0.035 * y[4],
            8.32 * y[1] + 1.71 * y[2] - 1.12 * y[3],
            -1.745 * y[4] + 0.43 * y[5] + 0.43 * y[6],
            -280.0 * y[5] * y[7] + 0.69 * y[3] + 1.71 * y[4] - 0.43 * y[5] + 0.69 * y[6],
            280.0 * y[5] * y[7] - 1.81 * y[6],
            -280.0 * y[5] * y[7] + 1.81 * y[6]]


def _hires_jac(y):
    J = np.zeros((8, 8))
    J[0, :3] = [-1.71, 0.43, 8.32]
    J[1, :2] = [1.71, -8.75]
    J[2, 2:5] = [-10.03, 0.43, 0.035]
    J[3, 1:4] = [8.32, 1.71, -1.12]
    J[4, 4:7] = [-1.745, 0.43, 0.43]
    J[5, 3:8] = [0.69, 1.71, -280.0 * y[7] - 0.43, 0.69, -280.0 * y[5]]
    J[6, 5:8] = [280.0 * y[7], -1.81, 280.0 * y[5]]
    J[7, 5:8] = [-280.0 * y[7], 1.81, -280.0 * y[5]]
    return J


HIRES = Problem("HIRES", _hires, _hires_jac, (1.0, 0, 0, 0, 0, 0, 0, 0.0057), (0.0, 321.8122),
                # IVP test set, hires.f's solut
                (0.7371312573325668e-3, 0.1442485726316185e-3, 0.5888729740967575e-4,
                 0.1175651343283149e-2, 0.2386356198831331e-2, 0.6238968252742796e-2,
                 0.2849998395185769e-2, 0.2850001604814231e-2), 1e-11, _IVP)


# ---- OREGO: the Oregonator (Belousov-Zhabotinskii) ------------------------------------------

_OR_S, _OR_W, _OR_Q = 77.27, 0.161, 8.375e-6


def _orego(y):
    s, w, q = _OR_S, _OR_W, _OR_Q
    return [s * (y[1] + y[0] * (1 - q * y[0] - y[1])),
            (y[2] - (1 + y[0]) * y[1]) / s,
            w * (y[0] - y[2])]


def _orego_jac(y):
    s, w, q = _OR_S, _OR_W, _OR_Q
    return np.array([[s * (1.0 - 2.0 * q * y[0] - y[1]), s * (1.0 - y[0]), 0.0],
                     [-y[1] / s, -(1.0 + y[0]) / s, 1.0 / s],
                     [w, 0.0, -w]])


OREGO = Problem("OREGO", _orego, _orego_jac, (1.0, 2.0, 3.0), (0.0, 360.0),
                # IVP test set, orego.f's solut
                (0.1000814870318523e1, 0.1228178521549917e4, 0.1320554942846706e3), 1e-8, _IVP)


# ---- VDPOL: Van der Pol, mu = 1000, in its two forms ----------------------------------------

#: The plain form x'' - mu (1 - x^2) x' + x = 0 (mp.scenes.VanDerPol's), on [0, 2000].
VDP_MU = 1000.0


def _vdpol(y):
    return [y[1], VDP_MU * (1 - y[0] ** 2) * y[1] - y[0]]


def _vdpol_jac(y):
    return np.array([[0.0, 1.0],
                     [-2.0 * VDP_MU * y[0] * y[1] - 1.0, VDP_MU * (1.0 - y[0] ** 2)]])


VDPOL = Problem("VDPOL", _vdpol, _vdpol_jac, (2.0, 0.0), (0.0, 2000.0),
                # IVP test set's end values, for the unscaled form
                (0.1706167732170469e1, -0.8928097010248125e-3), 1e-10, _IVP)

#: The scaled form y1' = y2, eps y2' = (1 - y1^2) y2 - y1 with eps = 1/mu^2 = 1e-6, on
#: [0, 2] (Hairer & Wanner II, IV.10; t and y2 of the plain form scaled by mu).
VDP_EPS = 1e-6


def _vdp_scaled(y):
    return [y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / VDP_EPS]


def _vdp_scaled_jac(y):
    return np.array([[0.0, 1.0],
                     [(-2 * y[0] * y[1] - 1) / VDP_EPS, (1 - y[0] ** 2) / VDP_EPS]])


VDP_SCALED = Problem("VDP eps=1e-6", _vdp_scaled, _vdp_scaled_jac, (2.0, 0.0), (0.0, 2.0),
                     # end values published with the IVP test set (Mazzia, Magherini;
                     # Hairer & Wanner), for the scaled form
                     (1.706167732170483, -0.8928097010247975), None,
                     "IVP test set (Mazzia, Magherini); Hairer & Wanner")


# ---- E5: a chemical pyrolysis, to t = 1e13 --------------------------------------------------

_E5_A, _E5_B, _E5_CM, _E5_C = 7.89e-10, 1.1e7, 1.13e9, 1.13e3


def _e5(y):
    p1 = _E5_A * y[0]
    p2 = _E5_B * y[0] * y[2]
    p3 = _E5_CM * y[1] * y[2]
    p4 = _E5_C * y[3]
    f1, f2, f4 = -p1 - p2, p1 - p3, p2 - p4
    return [f1, f2, f2 - f4, f4]


def _e5_jac(y):
    A, B, CM, C = _E5_A, _E5_B, _E5_CM, _E5_C
    return np.array([
        [-A - B * y[2], 0.0, -B * y[0], 0.0],
        [A, -CM * y[2], -CM * y[1], 0.0],
        [A - B * y[2], -CM * y[2], -B * y[0] - CM * y[1], C],
        [B * y[2], 0.0, B * y[0], -C]])


#: y2, y3 ~ 9e-23 at the end: absolute tolerance 1.7e-24.
E5 = Problem("E5", _e5, _e5_jac, (1.76e-3, 0.0, 0.0, 0.0), (0.0, 1e13),
             # IVP test set, e5.f's solut
             (0.1152903278711829e-290, 0.8867655517642120e-22, 0.8854814626268838e-22, 0.0),
             1.7e-24, _IVP)

#: The IVP test set's stiff problems that the tests and the CVODE bench run.
STIFF_SET = (HIRES, OREGO, ROBER, VDPOL, E5)
