"""What a solve is handed: the system spec the C core takes, the method
table, event functions and the callbacks' exception watch.

A scene is recognised by the protocol every scene implements (``_spec(method)``
and ``dim``; ``_rigid_split`` for the scene the rigid-body splittings run on),
not by its class, so that this module, and ``mechpy.integrate`` above it,
import no scene module: the scenes import ``integrate`` at load time, one way.
"""
from __future__ import annotations

import contextlib
import ctypes
import sys
import threading

import numpy as np

from . import _core
from ._callbacks import c_address as _c_address
from ._validate import as_array, as_int, as_scalar

class SecondOrder:
    """A second-order system q'' = a(t, q) for the symplectic methods.

    ``accel`` is a Python callable ``a(t, q, *args)`` returning the
    acceleration (same length as q), or a C callback ``void a(double t,
    const double *q, double *acc, void *user_data)`` (ctypes, LowLevelCallable
    or numba cfunc).  The state is ``y = (q, v)``: give ``y0`` of even length
    2 len(q).  Every method accepts it; ``verlet``, ``yoshida4`` and
    ``yoshida6`` need it (or an undamped scene).

    Example: ``mp.solve(mp.SecondOrder(lambda t, q: -q), (0, 10), [1, 0],
    method="yoshida4", h=0.01)``.

    Examples
    --------
    q'' = -q with Yoshida's 4th-order symplectic method: q(t) = cos t, and the energy
    (q^2 + v^2)/2 stays at 1/2 without drift.

    >>> s = mp.solve(mp.SecondOrder(lambda t, q: -q), (0, 10), [1.0, 0.0],
    ...              method="yoshida4", h=0.01)
    >>> round(float(s.y[0, -1]), 8), round(float(np.cos(10.0)), 8)
    (-0.83907153, -0.83907153)
    >>> energy = 0.5 * (s.y[0] ** 2 + s.y[1] ** 2)
    >>> bool(np.abs(energy - 0.5).max() < 1e-9)
    True
    """

    def __init__(self, accel):
        if _c_address(accel) is None and not callable(accel):
            raise TypeError("accel must be callable or a C callback")
        self.accel = accel

    def __repr__(self):
        return f"SecondOrder({self.accel!r})"


def methods() -> list[dict]:
    """Every integration method: name, order, adaptive, implicit, symplectic,
    needs_jacobian, dense_output (the order of its interpolant), lanes
    (:func:`solve_many` runs it in SIMD lanes), rigid (a rigid-body
    splitting: the ``RigidBody`` scene only), compensated (its updates of
    the state are compensated sums, which keep the state's low-order part from
    step to step: ``yoshida4`` and ``yoshida6``; see the integrators guide)
    and scalar_rtol (it takes one rtol, not one per component: GSL's
    steppers, whose control scales the error by a single relative tolerance).

    GSL's steppers have no interpolant of their own: the one-step rows of
    order >= 4 use a quintic Hermite interpolant (the midpoint from a half
    step, built only on steps that need output; their steps are then kept to
    the length at which it meets the tolerance), the others the cubic Hermite
    interpolant.  SciPy's method names are accepted as aliases (see
    :data:`SCIPY_METHODS`).

    Known limitations: ``"gsl:bsimp"`` (GSL's Bader-Deuflhard stepper)
    underestimates its error on components that sit a few tens of atol above
    zero in a stiff system: on the test set's E5 it ends 150% off at rtol 1e-6
    with status 0 (6e-2 at 1e-8); it needs rtol <= 1e-10 there (1.1e-3, the
    atol-limited error of every method), or use ``"radau"``.  ``"gsl:msbdf"``
    (and ``"BDF"``) is the least accurate stiff row per rtol: 2-10x SciPy's
    BDF error at the same tolerances.

    Examples
    --------
    >>> rows = {m["name"]: m for m in mp.methods()}
    >>> rows["dop853"]["order"], rows["dop853"]["adaptive"], rows["verlet"]["symplectic"]
    (8, True, True)
    >>> rows["radau"]["implicit"], rows["radau"]["order"]         # Radau IIA, order 5
    (True, 5)
    >>> sorted(name for name, row in rows.items() if row["lanes"])  # the lane kernels
    ['dop853', 'dopri5', 'rk4']
    """
    return _core.ode_methods()


#: SciPy's ``solve_ivp`` method names and the mechpy method each one runs.
#: ``"RK23"`` (Bogacki-Shampine 3(2)) runs ``"dopri5"``, the explicit pair of
#: the next order: the same tolerances met in fewer steps; ``"BDF"`` runs
#: GSL's variable-order BDF, ``"LSODA"`` the stiffness-switching ``"auto"``
#: (dop853 and radau rather than Adams and BDF).
SCIPY_METHODS = {"RK45": "dopri5", "RK23": "dopri5", "DOP853": "dop853", "Radau": "radau",
                 "BDF": "gsl:msbdf", "LSODA": "auto"}


_METHOD_NAMES = None


def _method_names():
    global _METHOD_NAMES
    if _METHOD_NAMES is None:
        _METHOD_NAMES = {m["name"]: m for m in methods()}
    return _METHOD_NAMES


def _python_backed(obj) -> bool:
    """True for a ctypes callback made from a Python function (directly or
    inside a scipy.LowLevelCallable): ctypes swallows its exceptions."""
    if isinstance(obj, tuple) and type(obj).__name__ == "LowLevelCallable":
        obj = tuple.__getitem__(obj, 1)
    if not isinstance(obj, ctypes._CFuncPtr):
        return False
    objs = getattr(obj, "_objects", None)
    return isinstance(objs, dict) and any(type(v).__name__ == "CThunkObject"
                                          for v in objs.values())


@contextlib.contextmanager
def _catch_unraisable(caught: list):
    """Collect into ``caught`` the exceptions ctypes would print and drop
    (sys.unraisablehook) in this thread while the solve runs; the C core
    checks the list after every call of the system and raises the first one
    again."""
    me = threading.get_ident()
    prev = sys.unraisablehook

    def hook(u):
        if threading.get_ident() == me:
            if not caught:
                exc = u.exc_value if u.exc_value is not None else u.exc_type()
                if u.exc_traceback is not None and exc.__traceback__ is None:
                    exc = exc.with_traceback(u.exc_traceback)
                caught.append(exc)
        else:
            prev(u)

    sys.unraisablehook = hook
    try:
        yield caught
    finally:
        sys.unraisablehook = prev


def _watch_list(system):
    """An empty list to collect a ctypes callback's swallowed exceptions in,
    or None when the system has no callback written in Python."""
    if isinstance(system, SecondOrder):
        obj = system.accel
    else:  # a scene carries its torque callback (RigidBody) as _torque_fn
        obj = getattr(system, "_torque_fn", system)
    return [] if _python_backed(obj) else None


def _system_spec(system, args, method):
    if isinstance(system, SecondOrder):
        c = _c_address(system.accel)
        if c is not None:
            return ("cfunc2", c[0], c[1]), None
        return ("python2", system.accel, tuple(args)), None
    if _is_scene(system):
        if args:
            raise TypeError("args are not used with a scene: set its parameters instead")
        # a scene may carry a C callback bound into its model (RigidBody's torque)
        spec = getattr(system, "_spec", None)
        if spec is not None:
            return spec(method), system.dim
        return ("scene", system._model, system._vector()), system.dim
    c = _c_address(system)
    if c is not None:
        return ("cfunc", c[0], c[1]), None
    if callable(system):
        return ("python", system, tuple(args)), None
    raise TypeError(f"system must be a scene, a callable f(t, y, *args) or a C callback, "
                    f"got {type(system).__name__}")


def _events_spec(events, system=None, n=0, k=None):
    """The event list as the C core takes it: per event a callable g, a pair
    (g, action) or an impact's C entry (mechpy.events.Impact), and the
    terminal counts and directions.  ``system`` and ``n`` resolve an impact's
    coordinate; ``k`` (solve_many) allows a restitution per trajectory."""
    if events is None:
        return None, None, None
    if callable(events):
        events = [events]
    try:
        evs = list(events)
    except TypeError:
        raise TypeError(f"events must be a callable or a sequence of callables, got "
                        f"{type(events).__name__}") from None
    if not evs:   # SciPy's events=[]: no event, empty t_events and y_events
        return evs, None, None
    term, dirs, entries = [], [], []
    for i, e in enumerate(evs):
        if not callable(e):
            raise TypeError(f"events[{i}] must be callable")
        t = getattr(e, "terminal", False)
        if t is None:  # SciPy treats None as False
            t = False
        if isinstance(t, (bool, np.bool_)):
            count = 1 if t else 0
        else:
            count = as_int(t, f"events[{i}].terminal", minimum=0)
        action = getattr(e, "action", None)
        if action is not None and not callable(action):
            raise TypeError(f"events[{i}].action must be callable action(t, y) -> y_new, "
                            f"got {type(action).__name__}")
        most = getattr(e, "max_events", None)
        if most is not None:
            if action is None:
                raise ValueError(f"events[{i}].max_events is for an event with an action "
                                 "(a plain event counts with terminal)")
            if count:
                raise ValueError(f"events[{i}] has both terminal and max_events: a terminal "
                                 "event stops at its crossing, max_events after that many "
                                 "actions")
            count = as_int(most, f"events[{i}].max_events", minimum=1)
        term.append(count)
        d = getattr(e, "direction", 0)
        d = as_scalar(d, f"events[{i}].direction")
        dirs.append(int(np.sign(d)))
        if hasattr(e, "_c_entry"):      # an impact: event and action in C
            entries.append(e._c_entry(system, n, k))
        elif action is not None:
            entries.append((e, action))
        else:
            entries.append(e)
    return entries, np.array(term, dtype=np.intc), np.array(dirs, dtype=np.intc)


def _as_args(args) -> tuple:
    if isinstance(args, tuple):
        return args
    return tuple(args) if isinstance(args, list) else (args,)


def _rigid_split_check(method, system):
    """The rigid-body splitting methods run on RigidBody scenes only."""
    if _method_names()[method]["rigid"]:
        if not getattr(system, "_rigid_split", False):
            raise ValueError(f"method {method!r} integrates a RigidBody scene (torque-free or "
                             f"a constant torque), not {type(system).__name__}")


def _python_fun(system) -> bool:
    """A Python callable system (not a scene, SecondOrder or C callback)."""
    return (callable(system) and not isinstance(system, SecondOrder) and not _is_scene(system)
            and _c_address(system) is None)


def _is_scene(obj) -> bool:
    """A scene (mechpy.scenes.Scene and its subclasses, compiled ones too)."""
    return getattr(type(obj), "_is_mechpy_scene", False)


def _ensemble_params(system, params, k):
    if params is None:
        return None
    if isinstance(params, dict):
        if not _is_scene(system):
            raise TypeError("params as a dict of names needs a scene")
        return system.ensemble_params(k, **params)
    p = as_array(params, "params", ndim=2)
    if p.shape[0] != k:
        raise ValueError(f"params must have {k} rows (one per trajectory), got {p.shape}")
    return p
