"""Events that change the state: impacts, bounces, switches.

An event function given to :func:`mechpy.solve` or :func:`mechpy.solve_many`
may carry an ``action``, a callable ``action(t, y, *args) -> y_new``: at the
located crossing the state is replaced and the integration restarts from
there (the first step and the step-size control afresh; a fixed-step method
counts its steps from the event).  ``sol.t_events`` / ``sol.y_events`` hold
the states just before each action; without ``t_eval`` the solution has both
the state before and the state after at the event's time.

SciPy's ``terminal`` and ``direction`` keep their meaning: a terminal event
stops instead; an integer count on an action event (``max_events``) stops the
solve at that crossing (status 1, the message naming the event).  An event
that acted fires again only after g has been seen on the side its crossing
starts from, wherever the wall is.  Impacts that accumulate (Zeno: a ball
bouncing with restitution e < 1 after infinitely many bounces in a finite
time) put the body to rest on the wall at their accumulation point; it
follows the wall (which may move: a SymPy expression of t) until the contact
force would pull, then lifts off (``sol.rests``).  Other action events whose
crossings accumulate end the solve there (status 1, a message naming the
event); an action that leaves the state where its event fires again at once
raises :class:`mechpy.errors.EventError`.

:func:`impact` is the common case written in C: the velocity of one coordinate
reflected and scaled by a coefficient of restitution at a wall.  It runs
without the GIL (``solve_many`` on every thread) and takes its restitution
per trajectory from an array or from a parameter of the system.

Examples
--------
A ball dropped from 1 m bouncing with e = 0.9: the k-th flight lasts
e^k times the first, 2 v1 / g with v1 = sqrt(2 g h).

>>> import sympy as sp
>>> x, v = mp.coordinates("x v")
>>> g = sp.Symbol("g")
>>> ball = mp.equations([v, -g], [x, v], params={"g": 9.81})      # x'' = -g
>>> sol = mp.solve(ball, (0, 3), [1.0, 0.0], events=mp.events.impact("x", restitution=0.9),
...                rtol=1e-12, atol=1e-12)
>>> tb = sol.t_events[0]
>>> v1 = np.sqrt(2 * 9.81 * 1.0)
>>> round(float(tb[0]), 10), round(float(np.sqrt(2 / 9.81)), 10)  # the first landing
(0.451523641, 0.451523641)
>>> np.round(np.diff(tb[:4]) / (2 * v1 / 9.81), 10)              # e, e^2, e^3
array([0.9  , 0.81 , 0.729])
"""
from __future__ import annotations

import numbers

import numpy as np

from ._system import _is_scene
from ._validate import as_array, as_int, as_scalar

__all__ = ["impact", "Impact"]


class Impact:
    """An impact at a wall (see :func:`impact`): an event function with its
    action, both also run in C.

    Calling it gives the event function ``side * (y[i] - wall)`` (for a state
    whose coordinate index is known: an int ``coordinate``); ``action(t, y)``
    the state after the impact.  ``direction`` (-1: towards the wall),
    ``terminal`` (False) and ``max_events`` (None: no limit) may be set as on
    any event function.

    Examples
    --------
    >>> wall = mp.events.impact(0, wall=0.0, restitution=0.5)
    >>> wall(0.0, [0.2, -1.0]), wall.action(0.0, [0.0, -1.0]).tolist()
    (0.2, [0.0, 0.5])
    """

    def __init__(self, coordinate, wall, restitution, side):
        self.coordinate = coordinate
        self.wall = wall
        self.restitution = restitution
        self.side = side
        self.direction = -1
        self.terminal = False
        self.max_events = None
        self._walls = {}     # a moving wall compiled, per system's parameter names

    @property
    def _moving(self) -> bool:
        """Whether the wall moves (a SymPy expression of t)."""
        return not isinstance(self.wall, float)

    def __repr__(self):
        return (f"impact({self.coordinate!r}, wall={self.wall!r}, "
                f"restitution={self.restitution!r}, side={self.side:+d})")

    def _indices(self, system, n):
        """(coordinate index, its velocity's index) in a state of n values."""
        c = self.coordinate
        if isinstance(c, str):
            names = list(getattr(system, "coordinates", None) or ())
            if c not in names:
                raise ValueError(f"impact: {c!r} is not a coordinate of the system "
                                 f"(its coordinates: {names or 'unnamed: give an index'})")
            iq = names.index(c)
        else:
            iq = as_int(c, "coordinate", minimum=0)
        if _is_scene(system):       # where the system says the velocity is
            iv = system._velocity_index(iq)
            if iv is None:
                raise ValueError(f"impact: coordinate {iq} of {type(system).__name__} has no "
                                 "velocity in its state")
            return iq, iv
        return iq, _velocity_after(iq, n)

    def _standing(self, what):
        if self._moving:
            raise TypeError(f"impact.{what}: a moving wall runs compiled with its system; "
                            "pass the impact to mp.solve or mp.solve_many")

    def __call__(self, t, y, *args):
        self._standing("__call__")
        iq, _ = self._indices(None, np.shape(y)[0])
        return self.side * (float(np.asarray(y)[iq]) - self.wall)

    def action(self, t, y, *args):
        """The state after the impact: the coordinate at the wall, its velocity
        reflected and scaled by the restitution (a number)."""
        self._standing("action")
        y = np.array(y, dtype=float)
        iq, iv = self._indices(None, y.shape[0])
        if not isinstance(self.restitution, numbers.Real):
            raise TypeError("impact.action(t, y) takes a numeric restitution")
        y[iv] = -float(self.restitution) * y[iv]
        y[iq] = self.wall
        return y

    def _may_rest(self, system, n, iq) -> bool:
        """Whether coordinate iq may rest on the wall, a contact force acting on
        its own equation alone: a system written as explicit first-order
        equations (a Python function, mp.equations, a Cartesian scene), a model
        of one coordinate, or a Lagrangian without constraints whose mass matrix
        does not couple iq to the others (no q_j'' in q_iq's equation, no
        q_iq'' in theirs).  Any other model ends at the accumulation instead."""
        if not _is_scene(system):
            return True
        meta = getattr(system, "_meta", None)
        if meta is None:
            # a built-in scene, by its row: explicit equations of its coordinates without
            # a Lagrangian (no mass matrix to couple them), each velocity in the state, of
            # a fixed size (the variable-size chain ends at the accumulation, as it did
            # before its row named its states)
            from .scenes import _row
            row = _row(system._model)
            return n == 2 or (row["dim"] != 0 and not row["lagrangian"]
                              and system._velocity_index(iq) is not None)
        if meta["kind"] == "equations" or n == 2:
            return True
        if meta["kind"] != "lagrangian" or int(meta["k"]):
            return False
        import sympy as sp
        t = sp.Symbol("t")
        nc = int(meta["nc"])
        acc = [sp.Function(nm)(t).diff(t, 2) for nm in meta["names"][:nc]]
        for i, eq in enumerate(system.equations[:nc]):
            lhs = sp.expand(eq.lhs - eq.rhs)
            for j in range(nc):
                if i != j and iq in (i, j) and lhs.coeff(acc[j]) != 0:
                    return False
        return True

    def _wall_address(self, system) -> int:
        """The address of the moving wall compiled for system (0: it stands):
        mp_wall_fn (position, velocity and acceleration at t from the system's
        parameters), printed from the SymPy expression and its derivatives."""
        if not self._moving:
            return 0
        import ctypes

        import sympy as sp

        from .symbolic.build import ABI_VERSION, build
        from .symbolic.codegen import _Printer
        names = list(getattr(system, "params", {}) or {})
        key = tuple(names)
        if key not in self._walls:
            t = sp.Symbol("t")
            expr = self.wall
            free = {str(x) for x in expr.free_symbols} - {"t"}
            unknown = sorted(free - set(names))
            if unknown:
                raise ValueError(f"impact: the wall names {unknown}, which are not parameters "
                                 f"of the system (its parameters: {names}); the time is "
                                 "sympy.Symbol('t')")
            pr = _Printer()
            sub = {sp.Symbol(nm): sp.Symbol(f"mp_p{j}") for j, nm in enumerate(names)}
            tt = [x for x in expr.free_symbols if str(x) == "t"]
            e0 = expr.subs({x: t for x in tt})
            ws = [e0, sp.diff(e0, t), sp.diff(e0, t, 2)]
            lines = [f"    double mp_p{j} = p[{j} * ps];" for j in range(len(names))]
            body = "\n".join(lines + [f"    w[{i}] = {pr.doprint(w.subs(sub))};"
                                      for i, w in enumerate(ws)])
            # mp_gen_dims: what the cache checks of every generated library (its ABI)
            src = ("#include <math.h>\n#include <stddef.h>\n"
                   f"const long mp_gen_dims[5] = {{0, 0, 0, 0, {ABI_VERSION}}};\n"
                   "void mp_wall(double t, const double *p, size_t ps, double *w)\n{\n"
                   f"    (void)p; (void)ps; (void)t;\n{body}\n}}\n")
            lib = build(src)[0]
            self._walls[key] = (lib, ctypes.cast(lib.mp_wall, ctypes.c_void_p).value)
        return self._walls[key][1]

    def _c_entry(self, system, n, k=None):
        """The entry the C core takes: ("impact", iq, iv, wall, e, side, e_param):
        e a float, a (k,) array (per trajectory), or e_param the index of a
        system parameter (then e is unused)."""
        iq, iv = self._indices(system, n)
        e, e_param = self.restitution, -1
        if isinstance(e, str):
            names = list(getattr(system, "params", {}) or {})
            if e not in names:
                raise ValueError(f"impact: restitution {e!r} is not a parameter of the system "
                                 f"(its parameters: {names})")
            e_param, e = names.index(e), 0.0
        elif np.ndim(e) == 0:
            e = as_scalar(e, "restitution")
            if not 0.0 <= e:
                raise ValueError(f"impact: restitution must be >= 0, got {e}")
        else:
            if k is None:
                raise ValueError("impact: restitution as an array is for solve_many (one per "
                                 "trajectory); solve takes a number")
            e = as_array(e, "restitution", shape=(k,), nonnegative=True)
        wall = 0.0 if self._moving else float(self.wall)
        return ("impact", iq, iv, wall, e, float(self.side), e_param,
                self._wall_address(system), self._may_rest(system, n, iq))


def _velocity_after(iq: int, n: int) -> int:
    """Coordinate iq's velocity in a state (q, v) of n values, v after q (a
    system that names no velocities: a Python function, mp.equations)."""
    if n % 2 or iq >= n // 2:
        raise ValueError(f"impact: coordinate {iq} needs a state (q, v) with q of at least "
                         f"{iq + 1} values and v after it (got {n} values)")
    return iq + n // 2


def _wall(wall):
    """A wall as given: a number (it stands there), or a SymPy expression of
    the time sympy.Symbol('t') and the system's parameters (it moves)."""
    if isinstance(wall, numbers.Real) or np.ndim(wall) == 0 and not hasattr(wall, "free_symbols"):
        return as_scalar(wall, "wall")
    import sympy as sp
    if isinstance(wall, sp.Expr):
        if not wall.free_symbols:
            return as_scalar(float(wall), "wall")
        return wall
    raise TypeError(f"wall must be a number or a SymPy expression of t, got {type(wall).__name__}")


def impact(coordinate, wall=0.0, restitution=1.0, side=+1) -> Impact:
    r"""An impact at a wall: the event ``side * (q - wall) = 0`` reached
    towards the wall, and its action ``q -> wall``, :math:`\dot q \to -e\,\dot q`.

    Parameters
    ----------
    coordinate : int or str
        The coordinate q: its index in the state (its velocity is the
        matching component of the second half, as in every (q, v) state), or
        its name (a compiled system's ``coordinates``; ``"theta"`` of a
        Pendulum, ``"height"`` of a Rocket, ...).
    wall : float or SymPy expression
        Where the wall is (in q's units): a number, or for a compiled system a
        SymPy expression of ``sympy.Symbol('t')`` and the system's parameters
        (a moving wall, compiled with its derivatives).
    restitution : float, (k,) array or str
        Coefficient of restitution e >= 0 (1: elastic, 0: the velocity
        relative to the wall stops; against a force into the wall the body
        then rests on it): a number; in :func:`mechpy.solve_many` one value per
        trajectory; or the name of a parameter of the system (then swept
        through ``params``).
    side : {+1, -1}
        The side the motion is on: +1 for q >= wall (a floor), -1 for
        q <= wall (a ceiling).

    Returns
    -------
    Impact
        An event function with ``direction = -1`` and its ``action``; pass it
        in ``events`` (with others).  It runs in C for every system: scenes,
        compiled systems, Python callables.

    Examples
    --------
    A pendulum released at 1 rad strikes a wall at theta = 0 after a quarter
    period 4 K(sin^2(theta0/2)) sqrt(L/g) / 4, and rebounds with e^2 of its
    energy.

    >>> from scipy.special import ellipk
    >>> pend = mp.scenes.Pendulum()
    >>> sol = mp.solve(pend, (0, 1.0), [1.0, 0.0], rtol=1e-12, atol=1e-12,
    ...                events=mp.events.impact("theta", restitution=0.5))
    >>> K = ellipk(np.sin(0.5) ** 2) / np.sqrt(9.81)
    >>> round(float(sol.t_events[0][0]), 9), round(float(K), 9)
    (0.5347844, 0.5347844)
    >>> E = pend.energy(sol.y) - pend.energy(np.zeros(2))   # above the lowest point
    >>> round(float(E[-1] / E[0]), 9)                            # e^2
    0.25
    """
    if side not in (1, -1):
        raise ValueError(f"side must be +1 or -1, got {side!r}")
    w = _wall(wall)
    if not isinstance(restitution, str) and np.ndim(restitution) == 0:
        e = as_scalar(restitution, "restitution")
        if e < 0:
            raise ValueError(f"restitution must be >= 0, got {e}")
    if not isinstance(coordinate, str):
        as_int(coordinate, "coordinate", minimum=0)
    return Impact(coordinate, w, restitution, int(side))
