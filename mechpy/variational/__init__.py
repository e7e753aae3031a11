r"""Lagrangian mechanics: the calculus of variations, least action, constraint forces.

The work runs in C (``csrc/variational.c``): a functional

.. math:: J[y] = \int_a^b F(x, y, y')\,dx, \qquad y(a) = y_a,\ y(b) = y_b,

with y in :math:`\mathbb R^d`, is discretised on nodes
:math:`x_0 < \dots < x_n` by the midpoint rule,
:math:`J_h = \sum_i h_i F(\bar x_i, (y_i + y_{i+1})/2, (y_{i+1} - y_i)/h_i)`
(second order), and the discrete Euler-Lagrange equations
:math:`\partial J_h/\partial y_j = 0` are solved by Newton's method.  Their
Hessian is block-tridiagonal with d x d blocks (banded LU or Cholesky,
O(n d^3) per iteration); a line search (on J when minimising, on the residual
otherwise) and an iteration budget make the solver safe, and a failure raises
:class:`mechpy.ConvergenceError`.  Integral constraints
:math:`\int G_k\,dx = c_k` enter through Lagrange multipliers (a bordered
system).

Modules (every public name is importable from ``mechpy.variational``)
---------------------------------------------------------------------
functionals
    :func:`minimize_functional`: any functional F(x, y, y') given as a
    vectorised Python callable.
classic
    :func:`brachistochrone`, :func:`catenary`: the two classic problems
    beside their closed forms (cycloid, cosh).
action
    :func:`stationary_path`, :func:`variational_integrate`: the path of
    stationary discrete action between two configurations, and the
    (symplectic) variational integrator of the same discrete action, for a
    scene (Pendulum, Duffing, HeavyTop, a compiled ``mp.lagrangian`` scene)
    or a Lagrangian ``L(q, qdot[, t])`` of any number of coordinates.
lagrangians
    :func:`lagrangian`, :func:`generalized_momenta`,
    :func:`cyclic_coordinates`, :class:`CentralForce`, :class:`RotatingHoop`.
constraints
    :func:`constraint_forces`, :func:`pendulum_tension`: forces of
    constraint from Lagrange multipliers.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
paths and trajectories state first, (d, m); functions of states y (n, ...) return (p, ...).
"""
from .action import (MAX_STEPS, StationaryPath, VariationalTrajectory, stationary_path,
                     variational_integrate)
from .classic import Brachistochrone, Catenary, brachistochrone, catenary
from .constraints import constraint_forces, pendulum_tension
from .functionals import Extremal, minimize_functional
from .lagrangians import (CentralForce, RotatingHoop, cyclic_coordinates, generalized_momenta,
                          lagrangian)

__all__ = ["minimize_functional", "Extremal", "brachistochrone", "Brachistochrone",
           "catenary", "Catenary", "stationary_path", "StationaryPath",
           "variational_integrate", "VariationalTrajectory", "MAX_STEPS", "lagrangian",
           "generalized_momenta", "cyclic_coordinates", "constraint_forces",
           "pendulum_tension", "CentralForce", "RotatingHoop"]
