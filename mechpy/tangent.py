r"""The tangent flow: sensitivities, Lyapunov spectra, Floquet multipliers, fitting.

For :math:`\dot{\mathbf y} = \mathbf f(t, \mathbf y, \mathbf p)` the derivatives of the
solution with respect to parameters and initial state,
:math:`S = [\partial\mathbf y/\partial\mathbf p \,|\, \partial\mathbf y/\partial\mathbf y_0]`
(n x (p + n)), obey the variational equations

.. math:: \dot S = \frac{\partial\mathbf f}{\partial\mathbf y}\,S
          + \Big[\frac{\partial\mathbf f}{\partial\mathbf p}\,\Big|\,0\Big], \qquad
          S(t_0) = [\,0 \,|\, I\,].

They are generated symbolically from the system's right-hand side
(``system.symbolic()``: every built-in scene with a fixed set of expressions and the
unconstrained compiled systems of :func:`mechpy.equations` / :func:`mechpy.lagrangian`),
differentiated by SymPy, and the augmented system (y, S) of n (1 + p + n) states is compiled
to C by :func:`mechpy.equations` (cached on disk, and in memory per system and parameter
set): it runs in the one engine, in every method.

Error control.  The tolerances apply to every component of the augmented state alike: the
step's error estimate is the rms over y and S of ``e / (atol + rtol |z|)``.  S has the
units of y per unit parameter; where its entries are much larger than y's (long times,
chaotic flows) the relative term dominates and they are controlled relatively, where they
are much smaller ``atol`` sets their absolute accuracy.  Measured on y' = A y (3 states,
t = 10, atol = rtol / 100) against ``scipy.linalg.expm``: S's error relative to ``max |S|`` is
7.9e-7, 7.0e-9, 6.4e-11 at rtol = 1e-6, 1e-8, 1e-10, as y's own (9.3e-7, 9.5e-9, 8.3e-11;
the plain solve's 9.4e-7, 9.4e-9, 8.3e-11), for one or two more steps than the plain solve:
the sensitivities come out as accurate as the state, so no separate scaling is applied.

Non-smooth fields.  Abs, sign, Max and Min are differentiated as Piecewise functions
(Abs' = sign), with states and parameters taken as real.  Where a Piecewise condition
in the state switches the field's branch (the Rocket's burn-out, m > m_dry), the
solution is continuous but its sensitivities jump: each such surface g = 0 is an event
of the augmented solve, and S jumps there by the saltation matrix with A = I (below).
A derivative SymPy cannot take is a ValueError naming the user's row f[i].

Events.  With ``events`` carrying actions (:func:`mechpy.events.impact`, or a Python
action with its Jacobian ``action.jac``), the event functions and actions run on y with
the system's own indices and S jumps at each event by the saltation matrix
(:func:`sensitivity`'s ``events``); ``fit`` takes the same events.

``mechpy.phase.lyapunov_spectrum`` and ``mechpy.phase.floquet`` are built on the same
augmented system.  Ensembles of sensitivities (``y0`` of shape (K, n)) run as one
``mp.solve_many`` ensemble.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``): ``Solution.S``
(n, p + n, m) puts the state axis first, then the columns, then time.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from ._validate import as_array, as_int, as_scalar
from .errors import (ConvergenceError, EventError, NonFiniteError, StepBudgetError,
                     StepSizeError)
from .integrate import Solution, solve, solve_many
from .scenes import Scene, _row

__all__ = ["sensitivity", "fit", "FitResult"]

#: augmented systems compiled in this process: key -> (compiled, param names it takes)
_AUGMENTED: dict = {}


# ---- the augmented system ------------------------------------------------------------
def _no_symbolic(system) -> TypeError:
    return TypeError(
        f"system must be a scene or a compiled system (mp.equations, mp.lagrangian) with a "
        f"symbolic right-hand side, got {type(system).__name__}: the variational equations "
        "are generated from system.symbolic(); write a Python f(t, y) with mp.equations")


def _require(system) -> None:
    """A system the variational equations can be generated for, or TypeError."""
    if not isinstance(system, Scene) or not hasattr(system, "symbolic"):
        raise _no_symbolic(system)


def _values(system) -> dict:
    """The system's parameters by the names its symbolic form uses."""
    return system._columns()


def _system_key(system):
    """What identifies a system's symbolic field (not its parameter values)."""
    if getattr(system, "_model", None):
        return ("scene", system._model, system.dim,
                getattr(system, "_torque_fn", None) is not None)
    src = getattr(system, "c_source", None)
    if src is None:
        meta = getattr(system, "_meta", None)
        src = repr(meta.get("equations")) if isinstance(meta, dict) else None
    if src is None:
        return None
    return ("compiled", src)


def _augmented(system, pnames: tuple, with_y0: bool):
    """The compiled augmented system (y, S) for the columns ``pnames`` (+ y0),
    and the parameter names it takes (those in the field's expressions).

    S is stored row-major after y: S[i, j] is state n + i * ncol + j."""
    _require(system)
    skey = _system_key(system)
    key = (skey, tuple(pnames), bool(with_y0))
    if skey is not None and key in _AUGMENTED:
        return _AUGMENTED[key]
    disk = _disk_key(system, skey, key)
    out = _load(disk)
    if out is not None:
        _AUGMENTED[key] = out
        return out
    import sympy as sp

    from .symbolic import equations
    fld = system.symbolic()          # ValueError when the system has none (names it)
    f = [sp.sympify(e) for e in fld.f]
    y = list(fld.y)
    n = len(y)
    t = sp.Symbol("t")
    if fld.t != t:
        f = [e.xreplace({fld.t: t}) for e in f]
    by_name = {str(s): s for s in fld.params}
    P = [by_name.get(nm, sp.Symbol(nm)) for nm in pnames]
    ncol = len(P) + (n if with_y0 else 0)
    S = sp.Matrix(n, ncol, lambda i, j: sp.Symbol(f"mp_S{i}_{j}"))
    f, J, Fp = _derivatives(f, y, t, P, [str(s) for s in fld.y])
    dS = J * S
    for j in range(len(P)):
        for i in range(n):
            dS[i, j] += Fp[i, j]
    free = set().union(*(e.free_symbols for e in f)) if f else set()
    names = [str(s) for s in fld.params if s in free]
    values = {str(s): float(v) for s, v in fld.params.items()}
    try:
        aug = equations(f + list(dS), y + list(S), params={nm: values[nm] for nm in names})
    except ValueError as exc:
        raise ValueError(_user_rows(str(exc), n, ncol, list(pnames), [str(v) for v in y])) \
            from None
    out = (aug, tuple(names))
    if skey is not None:
        _AUGMENTED[key] = out
        _store(disk, aug)
    return out


def _piecewise(e):
    """``e`` with Abs, sign, Max and Min written as Piecewise of their arguments: the
    same values, and derivatives SymPy takes and mechpy compiles (Abs' = sign as a
    Piecewise of +-1, not the complex ``Derivative(re(v), v)``; the compiled augmented
    system is differentiated once more for its own Jacobian, where sign' = 0)."""
    import sympy as sp
    e = e.replace(sp.Abs, lambda a: sp.Piecewise((a, a >= 0), (-a, True)))
    e = e.replace(sp.sign, lambda a: sp.Piecewise((1, a > 0), (-1, a < 0), (0, True)))
    return e.rewrite(sp.Piecewise) if e.has(sp.Max, sp.Min) else e


def _derivatives(f, y, t, P, names):
    """(f, df/dy (n, n), df/dp (n, len(P))): the field as it is compiled and its
    derivatives, as SymPy expressions and matrices.

    States, time and parameters are differentiated as real symbols (a symbol of
    unknown kind makes SymPy leave ``Derivative(re(v), v)`` for ``Abs(v)``), with
    Abs, sign, Max and Min as Piecewise (:func:`_piecewise`); the results are written
    back in the field's own symbols.  A derivative SymPy still cannot take (an
    undefined function, a ``floor``) is a ValueError naming the user's row f[i] and
    the state component or parameter, not a row of the generated augmented system."""
    import sympy as sp
    free = set(y) | {t} | set(P)
    for e in f:
        free |= {s for s in e.free_symbols if isinstance(s, sp.Symbol)}
    real = {s: sp.Dummy(s.name, real=True) for s in free if not s.is_real}
    back = {v: k for k, v in real.items()}
    fr = [_piecewise(e.xreplace(real)) for e in f]
    yr = [real.get(s, s) for s in y]
    Pr = [real.get(s, s) for s in P]

    def d(i, x, what):
        out = sp.diff(fr[i], x).xreplace(back)
        left = sorted({str(a) for a in out.atoms(sp.Derivative, sp.Subs)})
        if left:
            raise ValueError(
                f"the variational equations need d f[{i}] / d {what} of the system's "
                f"right-hand side, f[{i}] = {f[i]}, which SymPy leaves unevaluated: {left}; "
                "write f[i] with functions SymPy can differentiate (the elementary "
                "functions, Abs, sign, Max, Min, Piecewise)")
        return out

    n = len(y)
    J = sp.Matrix(n, n, lambda i, j: d(i, yr[j], f"y[{j}] ({names[j]})"))
    Fp = sp.Matrix(n, len(P), lambda i, j: d(i, Pr[j], f"the parameter {P[j]}"))
    return [e.xreplace(back) for e in fr], J, Fp


def _user_rows(msg: str, n: int, ncol: int, pnames: list, ynames: list) -> str:
    """A message of the augmented system's compiler with its rows named as the user's:
    rhs[k] for k < n is the system's f[k]; rhs[n + i ncol + j] is the variational
    equation of S[i, j] = d y[i] / d (column j: a parameter, or y0[j - p])."""
    import re

    def name(m):
        k = int(m.group(1))
        if k < n:
            return f"f[{k}] (the system's rhs[{k}])"
        i, j = divmod(k - n, ncol)
        col = pnames[j] if j < len(pnames) else f"y0[{j - len(pnames)}]"
        return (f"the variational equation of S[{i}, {j}] = d {ynames[i]} / d {col} "
                f"(from the system's rhs[{i}])")
    return "the variational equations (mechpy.tangent): " + re.sub(r"\brhs\[(\d+)\]", name, msg)


def _disk_key(system, skey, key):
    """The on-disk key of an augmented system: the field's text (a scene's row, a compiled
    system's C source), the columns, and the code that generates it (this module and the
    symbolic generator), so a warm start needs no SymPy."""
    if skey is None:
        return None
    import hashlib
    import os

    from .symbolic import _generator_hash
    h = hashlib.sha256(b"tangent\0")
    if skey[0] == "scene":
        h.update(repr((skey, _row(system._model).get("field"))).encode())
    else:
        h.update(skey[1].encode())
    h.update(repr(key[1:]).encode())
    with open(os.path.abspath(__file__), "rb") as f:
        h.update(f.read())
    h.update(_generator_hash().encode())
    return h.hexdigest()[:40]


def _load(disk):
    """The augmented system stored under ``disk`` (its library loaded), or None."""
    if disk is None:
        return None
    try:
        from .symbolic import build
        from .symbolic.scene import CompiledScene
        meta = build.load_meta(disk)
        if not isinstance(meta, dict) or "param_names" not in meta:
            return None
        names = list(meta["param_names"])
        aug = CompiledScene(meta, {nm: 0.0 for nm in names}, "c")
        return aug, tuple(names)
    except Exception:  # a damaged or foreign entry: derive again
        return None


def _store(disk, aug) -> None:
    if disk is None:
        return
    try:
        from .symbolic import build
        build.store_meta(disk, aug._meta)
    except Exception:  # a read-only cache: the next process derives again
        pass


def _bind(aug, names, values: dict):
    """The augmented system at the parameter values ``values`` (by name)."""
    cur = aug.params
    change = {nm: float(values[nm]) for nm in names if cur[nm] != float(values[nm])}
    if not change:
        return aug
    # the same library with another parameter vector: a shallow copy (replace() would
    # load the library again, 1 ms a call, a third of a fit's time)
    new = copy.copy(aug)
    cur.update(change)
    new._params = cur
    new._vec = np.array(list(cur.values()), dtype=np.float64)
    return new


def _param_names(system, params) -> tuple:
    _require(system)
    if isinstance(params, str):
        params = (params,)
    try:
        names = tuple(params)
    except TypeError:
        raise TypeError(f"params must be a sequence of parameter names, got "
                        f"{type(params).__name__}") from None
    have = _values(system)
    for nm in names:
        if not isinstance(nm, str):
            raise TypeError(f"params must hold parameter names (str), got {nm!r}")
        if nm not in have:
            raise ValueError(f"params: {type(system).__name__} has no parameter {nm!r}; its "
                             f"parameters are {list(have)}")
    if len(set(names)) != len(names):
        raise ValueError(f"params names a parameter twice: {list(names)}")
    return names


def _check(s, what: str):
    if s.status < 0:
        s.raise_for_status()
        raise ConvergenceError(f"{what}: the integration failed: {s.message}")


# ---- events: the jump of the sensitivities --------------------------------------------
class _AugEvent:
    """One event of the augmented solve (y, S): the event function and its action read
    the original state y = z[:n] (an impact's coordinate by its original index); the
    action replaces y and jumps S by the saltation matrix (``_saltation``).

    ``terminal``, ``direction`` and ``max_events`` are the user's event's; ``action`` is
    None for an event without one (the sensitivities then pass it unchanged)."""

    def __init__(self, g, n, src, action=None):
        self._g = g
        self._n = n
        self.terminal = getattr(src, "terminal", False)
        self.direction = getattr(src, "direction", 0)
        most = getattr(src, "max_events", None)
        if most is not None:
            self.max_events = most
        self.action = action

    def __call__(self, t, z, *args):
        return self._g(t, np.asarray(z)[:self._n], *args)


def _saltation(t, S, A, a_t, gy, g_t, fm, fp, what, g_p=0.0):
    r"""S just after an event: :math:`S^+ = A S^- - (f^+ - A f^- - a_t)\,d\tau/dz` with
    :math:`d\tau/dz = -(g_y S^-)/(g_t + g_y f^-)`, A = D_y a, a_t = D_t a, the
    gradient (g_t, g_y) of the event function at the crossing and f^-, f^+ the field
    before and after the action.  (An event later by d tau meets the state
    y^- + f^- d tau, leaves a(y^-) + (A f^- + a_t) d tau, which at the event's own time
    is that minus f^+ d tau.)  ``g_p`` adds the event function's own dependence on the
    columns (a switch at a differentiated parameter's value): d tau/dz gains
    -g_p/(g_t + g_y f^-).  A crossing with g_t + g_y f^- = 0 (grazing) has no finite
    event-time derivative: EventError."""
    den = g_t + gy @ fm
    scale = abs(g_t) + np.abs(gy) @ np.abs(fm)
    if not np.isfinite(den) or abs(den) <= 1e-13 * scale or scale == 0.0:
        raise EventError(
            f"{what} at t = {t:.17g} grazes (dg/dt + grad g . f = {den:.3g}): the event "
            "time does not depend smoothly on the parameters there, so the sensitivities "
            "have no jump")
    dtau = -(gy @ S + g_p) / den
    return A @ S - np.outer(fp - A @ fm - a_t, dtau)


def _field(aug, t, y, n):
    """f(t, y) at the augmented system's bound parameter values (its first n rows)."""
    z = np.zeros(aug.dim)
    z[:n] = y
    return np.asarray(aug.rhs(t, z), dtype=np.float64)[:n]


def _wall_of(ev, values, cols, i):
    """The impact's wall as a function of t: (w, w', w'').  A moving wall (a SymPy
    expression of t) at the system's parameter values; one that moves with a
    differentiated parameter is refused (its column would need dw/dp)."""
    if not ev._moving:
        w = float(ev.wall)
        return lambda t: (w, 0.0, 0.0)
    import sympy as sp
    expr = ev.wall
    used = sorted(str(x) for x in expr.free_symbols if str(x) in cols)
    if used:
        raise ValueError(f"events[{i}]: the wall moves with {used}, among the parameters "
                         "differentiated; mp.sensitivity takes walls that depend on t and "
                         "on parameters held fixed")
    t = sp.Symbol("t")
    e0 = expr.subs({x: t for x in expr.free_symbols if str(x) == "t"})
    e0 = e0.subs({sp.Symbol(k): v for k, v in values.items()})
    fns = [sp.lambdify(t, d, "math") for d in (e0, sp.diff(e0, t), sp.diff(e0, t, 2))]
    return lambda tt: tuple(float(f(tt)) for f in fns)


def _jump_of_impact(ev, system, n, cols, values, aug, i):
    """An impact's event and its action on (y, S): g = side (y[iq] - w(t)),
    y[iq] -> w, y[iv] -> w' - e (y[iv] - w'); D_y a = diag(1, ..., 0 at iq, -e at iv,
    ...), D_t a = (w' at iq, (1 + e) w'' at iv), g_t = -side w'; a restitution that is
    a differentiated parameter adds dy[iv]+/de = -(y[iv]- - w') in its column."""
    iq, iv = ev._indices(system, n)
    e = ev.restitution
    col = None
    if isinstance(e, str):
        if e not in values:
            raise ValueError(f"events[{i}]: impact restitution {e!r} is not a parameter of "
                             f"the system (its parameters: {list(values)})")
        col = cols.get(e)
        name = e
    elif np.ndim(e) != 0:
        raise ValueError(f"events[{i}]: a restitution per trajectory (an array) is for "
                         "mp.solve_many; mp.sensitivity takes a number or a parameter's name")
    else:
        name = None
        e = as_scalar(e, "restitution", nonnegative=True)
    side = float(ev.side)
    wall = _wall_of(ev, values, cols, i)
    gy = np.zeros(n)
    gy[iq] = side

    def g(t, y, *args):
        return side * (float(y[iq]) - wall(t)[0])

    def action(t, z, *args):
        z = np.array(z, dtype=np.float64)
        y, S = z[:n], z[n:].reshape(n, -1)
        ee = float(values[name]) if name is not None else e
        w0, w1, w2 = wall(t)
        yp = y.copy()
        yp[iv] = w1 - ee * (y[iv] - w1)          # relative to the wall
        yp[iq] = w0
        A = np.eye(n)
        A[iq, iq] = 0.0
        A[iv, iv] = -ee
        a_t = np.zeros(n)                        # the action's own rate: the wall moving
        a_t[iq], a_t[iv] = w1, (1.0 + ee) * w2
        Sp = _saltation(t, S, A, a_t, gy, -side * w1, _field(aug, t, y, n),
                        _field(aug, t, yp, n), f"events[{i}] (an impact)")
        if col is not None:
            Sp[iv, col] -= y[iv] - w1
        return np.concatenate([yp, Sp.ravel()])

    return _AugEvent(g, n, ev, action)


def _event_gradient(ev, t, y, args, n):
    """(g_t, g_y) of a Python event function: ``ev.grad(t, y, *args)`` (dg/dy, or the
    pair (dg/dy, dg/dt)) where given, else central differences of g (step
    1e-6 max(1, |y_j|) in y, 1e-6 max(1, |t|) in t: about 1e-10 relative for a smooth g)."""
    grad = getattr(ev, "grad", None)
    if grad is not None:
        out = grad(t, y, *args)
        if isinstance(out, tuple):
            gy, g_t = out
        else:
            gy, g_t = out, 0.0
        gy = np.asarray(gy, dtype=np.float64).reshape(-1)
        if gy.shape != (n,):
            raise ValueError(f"event.grad(t, y) must give dg/dy of shape ({n},), got "
                             f"{np.shape(gy)}")
        return float(g_t), gy
    gy = np.empty(n)
    for j in range(n):
        h = 1e-6 * max(1.0, abs(y[j]))
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        gy[j] = (float(ev(t, yp, *args)) - float(ev(t, ym, *args))) / (2 * h)
    h = 1e-6 * max(1.0, abs(t))
    g_t = (float(ev(t + h, y, *args)) - float(ev(t - h, y, *args))) / (2 * h)
    return g_t, gy


def _jump_of_action(ev, action, n, aug, i):
    """A Python event with an action: the action on y, its Jacobian from ``action.jac``
    (D_y a, or the pair (D_y a, D_t a)), the event's gradient from ``ev.grad`` or central
    differences."""
    jac = getattr(action, "jac", None)
    if jac is None or not callable(jac):
        raise TypeError(
            f"events[{i}] has an action without its Jacobian: the sensitivities jump at the "
            "event by the saltation matrix, which needs D_y a of the action a(t, y).  Give "
            "it as action.jac(t, y) -> (n, n) array (or the pair (D_y a, D_t a) when the "
            "action depends on t), e.g. act.jac = lambda t, y: np.diag([0.0, -0.9])")

    def action_aug(t, z, *args):
        z = np.array(z, dtype=np.float64)
        y, S = z[:n].copy(), z[n:].reshape(n, -1)
        yp = np.asarray(action(t, y.copy(), *args), dtype=np.float64).reshape(-1)
        if yp.shape != (n,):
            raise ValueError(f"events[{i}].action(t, y) must return {n} values, got "
                             f"shape {yp.shape}")
        out = jac(t, y.copy(), *args)
        A, a_t = out if isinstance(out, tuple) else (out, 0.0)
        A = np.asarray(A, dtype=np.float64)
        if A.shape != (n, n):
            raise ValueError(f"events[{i}].action.jac(t, y) must give D_y a of shape "
                             f"({n}, {n}), got {A.shape}")
        a_t = np.broadcast_to(np.asarray(a_t, dtype=np.float64), (n,))
        g_t, gy = _event_gradient(ev, t, y, args, n)
        Sp = _saltation(t, S, A, a_t, gy, g_t, _field(aug, t, y, n), _field(aug, t, yp, n),
                        f"events[{i}]")
        return np.concatenate([yp, Sp.ravel()])

    return _AugEvent(ev, n, ev, action_aug)


# ---- switches of the field: the jump of the sensitivities where f jumps ---------------
#: switching surfaces of each system's field: system key -> list of _Switch (or [])
_SWITCHES: dict = {}


class _Switch:
    """A surface g(t, y, p) = 0 across which the field changes branch (a condition of its
    Piecewise, after Abs, sign, Max, Min are written as Piecewise): g, its gradient and
    the field on either side (g > 0: ``f_pos``, g < 0: ``f_neg``), as Python functions of
    (t, y..., params...)."""

    def __init__(self, g, grad_t, grad_y, grad_p, f_pos, f_neg, text):
        self.g, self.grad_t, self.grad_y, self.grad_p = g, grad_t, grad_y, grad_p
        self.f_pos, self.f_neg, self.text = f_pos, f_neg, text


def _switches(system):
    """The switching surfaces of the system's field (cached per field; none, and no
    SymPy, for a field without Piecewise, Abs, sign, Max or Min)."""
    skey = _system_key(system)
    if skey is not None and skey in _SWITCHES:
        return _SWITCHES[skey]
    text = repr(_row(system._model).get("field")) if skey and skey[0] == "scene" else \
        (skey[1] if skey else None)
    if text is not None and not any(w in text for w in ("Piecewise", "Abs", "sign", "Max",
                                                          "Min", "fabs", "fmax", "fmin", "?")):
        out = []
    else:
        out = _derive_switches(system)
    if skey is not None:
        _SWITCHES[skey] = out
    return out


def _derive_switches(system):
    import sympy as sp
    fld = system.symbolic()
    y, t = list(fld.y), fld.t
    params = list(fld.params)
    f = [_piecewise(sp.sympify(e)) for e in fld.f]
    rels = set()
    for e in f:
        for pw in e.atoms(sp.Piecewise):
            for _, c in pw.args:
                rels |= {r for r in sp.sympify(c).atoms(sp.Rel)
                         if isinstance(r, (sp.StrictGreaterThan, sp.GreaterThan,
                                           sp.StrictLessThan, sp.LessThan))}
    groups = []          # [(g, [(relational, sign of its lhs - rhs against g)])]
    for r in sorted(rels, key=str):
        h = sp.expand(r.lhs - r.rhs)
        if not (h.free_symbols & set(y)):
            continue                     # a switch in t or the parameters alone: no jump of S
        for g, members in groups:
            if sp.expand(h - g) == 0:
                members.append((r, 1))
                break
            if sp.expand(h + g) == 0:
                members.append((r, -1))
                break
        else:
            groups.append((h, [(r, 1)]))
    args = [t, *y, *params]
    out = []
    for g, members in groups:
        def side(sigma):
            # each relational's truth value where sign(g) = sigma
            sub = {}
            for r, sg in members:
                up = isinstance(r, (sp.StrictGreaterThan, sp.GreaterThan))
                sub[r] = sp.true if (sg * sigma > 0) == up else sp.false
            return [e.xreplace(sub) for e in f]
        lam = lambda e: sp.lambdify(args, e, "math")   # noqa: E731
        gp = [sp.diff(g, p) for p in params]
        out.append(_Switch(lam(g), lam(sp.diff(g, t)), lam([sp.diff(g, v) for v in y]),
                           lam(gp), lam(side(1)), lam(side(-1)), f"{g} = 0"))
    return out


def _switch_events(system, n, cols, values):
    """The augmented solve's events at the field's switches: S jumps by the saltation
    matrix with A = I (the state does not jump), f^- and f^+ the field's branches on
    the sides the orbit leaves and enters."""
    sw = _switches(system)
    if not sw:
        return []
    fld_params = list(_values(system))
    pv = [float(values[nm]) for nm in fld_params]
    gp_cols = [(j, fld_params.index(nm)) for nm, j in cols.items() if nm in fld_params]
    out = []
    for k, w in enumerate(sw):
        def g(t, y, *args, w=w):
            return float(w.g(t, *y, *pv))

        def action(t, z, *args, w=w):
            z = np.array(z, dtype=np.float64)
            y, S = z[:n], z[n:].reshape(n, -1)
            a = (t, *y, *pv)
            gt, gy = float(w.grad_t(*a)), np.asarray(w.grad_y(*a), dtype=float).ravel()
            fpos = np.asarray(w.f_pos(*a), dtype=float).ravel()
            fneg = np.asarray(w.f_neg(*a), dtype=float).ravel()
            # the side left: the one whose flow moves g towards the other
            rate_pos, rate_neg = gt + gy @ fpos, gt + gy @ fneg
            if rate_pos < 0 and not rate_neg > 0:
                fm, fp = fpos, fneg
            elif rate_neg > 0 and not rate_pos < 0:
                fm, fp = fneg, fpos
            elif rate_pos < 0 and rate_neg > 0:
                raise EventError(
                    f"the field's switch {w.text} at t = {t:.17g}: the flow on both sides "
                    "points into the surface (a sliding motion), where the sensitivities have "
                    "no jump mechpy computes")
            else:
                return z                     # grazing or leaving on both sides: no crossing
            gpv = np.zeros(S.shape[1])
            if gp_cols:
                allp = np.asarray(w.grad_p(*a), dtype=float).ravel()
                for j, i in gp_cols:
                    gpv[j] = allp[i]
            Sp = _saltation(t, S, np.eye(n), np.zeros(n), gy, gt, fm, fp,
                            f"the field's switch {w.text}", g_p=gpv)
            return np.concatenate([y, Sp.ravel()])

        ev = _AugEvent(g, n, None, action)
        out.append(ev)
    return out


def _aug_events(events, system, n, cols, values, aug):
    """The events of the augmented solve (y, S), or None: each reads the original state,
    and each action jumps S by the saltation matrix (:func:`_saltation`).  ``cols`` maps
    the differentiated parameters to their columns of S, ``values`` the parameters' values
    (an impact's restitution by name), ``aug`` the bound augmented system (its field)."""
    switches = _switch_events(system, n, cols, values)
    if events is None:
        return switches or None
    from .events import Impact
    evs = [events] if callable(events) else events
    try:
        evs = list(evs)
    except TypeError:
        raise TypeError(f"events must be a callable or a sequence of callables, got "
                        f"{type(events).__name__}") from None
    out = []
    for i, ev in enumerate(evs):
        if not callable(ev):
            raise TypeError(f"events[{i}] must be callable")
        if isinstance(ev, Impact):
            out.append(_jump_of_impact(ev, system, n, cols, values, aug, i))
            continue
        action = getattr(ev, "action", None)
        if action is None:
            out.append(_AugEvent(ev, n, ev))
        elif not callable(action):
            raise TypeError(f"events[{i}].action must be callable action(t, y) -> y_new, "
                            f"got {type(action).__name__}")
        else:
            out.append(_jump_of_action(ev, action, n, aug, i))
    return out + switches


# ---- sensitivities --------------------------------------------------------------------
def sensitivity(system, t_span, y0, params=(), *, t_eval=None, method: str = "dop853",
                rtol: float = 1e-8, atol=1e-10, events=None, **solve_kw) -> Solution:
    r"""The solution and its derivatives with respect to parameters and initial state.

    .. math:: S_{ij}(t) = \frac{\partial y_i(t)}{\partial \theta_j}, \qquad
              \theta = (p_1, \dots, p_k, y_{0,1}, \dots, y_{0,n}),

    from the variational equations
    :math:`\dot S = (\partial f/\partial y) S + [\partial f/\partial p \,|\, 0]`,
    generated with SymPy from ``system.symbolic()`` and compiled with the system
    (:mod:`mechpy.tangent`).  The tolerances apply to all n (1 + k + n) components of
    the augmented state (see the module's notes on error control).

    Parameters
    ----------
    system : Scene or compiled system
        A scene with a symbolic form (``system.symbolic()``) or a system from
        :func:`mechpy.equations` / :func:`mechpy.lagrangian` (unconstrained).  A Python
        callable has no symbolic form: ``TypeError``.
    t_span : (t0, tf)
    y0 : array_like, shape (n,) or (K, n)
        The initial state, or K of them: an ensemble, run by :func:`mechpy.solve_many`
        (in SIMD lanes where it can; the system's parameter values for all).
    params : sequence of str
        The parameters to differentiate by, by name (``scene.params``' names; for a
        compiled system, its symbols').
    t_eval : array_like, optional
        Output times, as in :func:`mechpy.solve` (for an ensemble: default the final
        time only, as :func:`mechpy.solve_many`).
    events : callable or list of callables, optional
        As for :func:`mechpy.solve`: each event function sees the system's state y (n
        values), and at an event with an action the state jumps and S with it, by the
        saltation matrix

        .. math:: S^+ = A S^- - (f^+ - A f^- - a_t)\,\frac{d\tau}{d\theta}, \qquad
                  \frac{d\tau}{d\theta} = -\frac{g_y S^-}{g_t + g_y f^-},

        A = D_y a and a_t = D_t a the action's derivatives, (g_t, g_y) the event
        function's gradient, f^-, f^+ the field before and after.  For
        :func:`mechpy.events.impact` everything is exact (a restitution given as the
        name of a differentiated parameter adds its direct term dv+/de = -v-).  A Python
        action needs its Jacobian as ``action.jac(t, y, *args)``, returning D_y a (n, n)
        or the pair (D_y a, D_t a) (``TypeError`` without it); the event function's
        gradient is ``event.grad(t, y, *args)`` (dg/dy, or the pair (dg/dy, dg/dt))
        where given, else central differences of g (about 1e-10 relative for a smooth
        g).  An action cannot depend on the system's parameters except an impact's
        restitution.  A crossing that grazes (g_t + g_y f^- = 0): ``EventError``.
        ``t_events`` / ``y_events`` as :func:`mechpy.solve` (y before each action).
    method, rtol, atol, **solve_kw
        Passed to :func:`mechpy.solve` (:func:`mechpy.solve_many`) for the augmented
        system.  With ``dense_output``, ``sol`` gives the augmented state (y, then S
        row by row).

    Returns
    -------
    Solution
        As :func:`mechpy.solve` (``t``, ``y`` (n, m), ...) with ``S`` of shape
        (n, k + n, m): ``S[:, :k]`` dy/dparams (units of y per unit of each parameter),
        ``S[:, k:]`` dy/dy0 (the state transition matrix); ``params`` the names.  For an
        ensemble an :class:`mechpy.EnsembleSolution` with ``y`` (K, n, m) and ``S``
        (K, n, k + n, m).

    Examples
    --------
    >>> import numpy as np
    >>> import mechpy as mp
    >>> s = mp.sensitivity(mp.scenes.Pendulum(damping=0.1), (0, 1), [0.3, 0.0],
    ...                    params=("damping",), t_eval=[1.0])
    >>> s.S.shape
    (2, 3, 1)

    Through an impact: a ball dropped from h0 = 1 m lands at t1 = sqrt(2 h0 / g) with
    speed V = sqrt(2 g h0) and leaves at e V; at T = 0.7 s, dx/dh0 = -e + (1 + e) g
    (T - t1) / V and dv/dh0 = (1 + e) g / V (the free fall's would be 1 and 0).

    >>> import sympy as sp
    >>> x, v = mp.coordinates("x v")
    >>> ball = mp.equations([v, -sp.Symbol("g")], [x, v], params={"g": 9.81})
    >>> s = mp.sensitivity(ball, (0, 0.7), [1.0, 0.0], t_eval=[0.7], rtol=1e-12,
    ...                    atol=1e-12, events=mp.events.impact("x", restitution=0.8))
    >>> s.S[:, 0, -1].round(10).tolist()                   # d(x, v)/dh0
    [0.1905515584, 3.9865022263]
    >>> V, t1 = np.sqrt(2 * 9.81), np.sqrt(2 / 9.81)
    >>> [round(float(-0.8 + 1.8 * 9.81 * (0.7 - t1) / V), 10), round(float(1.8 * 9.81 / V), 10)]
    [0.1905515584, 3.9865022263]
    """
    names = _param_names(system, params)
    y0 = as_array(y0, "y0", min_ndim=1)
    if y0.ndim > 2 or y0.shape[-1] != system.dim:
        raise ValueError(f"y0 must have shape ({system.dim},) or (k, {system.dim}), got "
                         f"{y0.shape}")
    aug, pn = _augmented(system, names, True)
    values = _values(system)
    aug = _bind(aug, pn, values)
    n, k = system.dim, len(names)
    evs = _aug_events(events, system, n, {nm: j for j, nm in enumerate(names)}, values, aug)
    S0 = np.zeros((n, k + n))
    S0[:, k:] = np.eye(n)
    if y0.ndim == 2:
        z0 = np.hstack([y0, np.broadcast_to(S0.ravel(), (y0.shape[0], S0.size))])
        e = solve_many(aug, t_span, z0, t_eval=t_eval, method=method, rtol=rtol, atol=atol,
                       events=evs, **solve_kw)
        z = e.y
        e["y"] = np.ascontiguousarray(z[:, :n])
        e["S"] = np.ascontiguousarray(z[:, n:].reshape(z.shape[0], n, k + n, -1))
        e["params"] = list(names)
        if e.get("y_events") is not None:
            e["y_events"] = [[np.ascontiguousarray(np.asarray(v)[..., :n]) for v in row]
                             for row in e["y_events"]]
        return e
    s = solve(aug, t_span, np.concatenate([y0, S0.ravel()]), method, rtol=rtol, atol=atol,
              t_eval=t_eval, events=evs, **solve_kw)
    z = s.y
    out = Solution(s)
    out.__dict__.update(s.__dict__)
    out["y"] = np.ascontiguousarray(z[:n])
    out["S"] = np.ascontiguousarray(z[n:].reshape(n, k + n, -1))
    out["params"] = list(names)
    for key in ("y_events",):
        if out.get(key) is not None:
            out[key] = [np.ascontiguousarray(np.asarray(v)[..., :n]) for v in out[key]]
    return out


def _flow(aug, n, t0, t1, y, cols0, method, rtol, atol, what, events=None):
    """Integrate the augmented system from (y, S = cols0) over [t0, t1]; -> (y, S).
    ``events``: the field's switches (:func:`_switch_events`), where S jumps."""
    ncol = cols0.shape[1]
    s = solve(aug, (t0, t1), np.concatenate([y, cols0.ravel()]), method, rtol=rtol,
              atol=atol, t_eval=[t1], events=events or None)
    _check(s, what)
    z = s.y[:, -1]
    return z[:n].copy(), z[n:].reshape(n, ncol).copy()


def _initial_state(system, y0):
    """y0 as a fresh float array of the system's dimension, and that dimension."""
    y = as_array(y0, "y0", ndim=1).copy()
    n = system.dim if isinstance(system, Scene) else y.size
    if y.shape[0] != n:
        raise ValueError(f"y0 must have {n} components, got shape {y.shape}")
    return y, n


# ---- Lyapunov spectrum ----------------------------------------------------------------
def _lyapunov_spectrum(system, y0, t, *, dt: float = 1.0, transient: float = 0.0,
                       method: str = "dop853", rtol: float = 1e-10, atol: float = 1e-12,
                       return_history: bool = False):
    """What :func:`mechpy.phase.lyapunov_spectrum` does (its docstring)."""
    _require(system)
    y, n = _initial_state(system, y0)
    T = as_scalar(t, "t", positive=True)
    dt = as_scalar(dt, "dt", positive=True)
    transient = as_scalar(transient, "transient", nonnegative=True)
    aug, pn = _augmented(system, (), True)
    aug = _bind(aug, pn, _values(system))
    switches = _switch_events(system, n, {}, _values(system))
    t0 = 0.0
    if transient > 0:
        s = solve(system, (0.0, transient), y, method, rtol=rtol, atol=atol, t_eval=[transient])
        _check(s, "lyapunov_spectrum (transient)")
        y, t0 = s.y[:, -1].copy(), transient
    m = max(1, int(round(T / dt)))
    times = t0 + (T / m) * np.arange(1, m + 1)
    Q = np.eye(n)
    sums = np.zeros(n)
    running = np.empty((m, n))
    ta = t0
    for i in range(m):
        try:
            y1, Phi = _flow(aug, n, ta, times[i], y, Q, method, rtol, atol,
                            "lyapunov_spectrum", switches)
        except (NonFiniteError, StepSizeError, StepBudgetError, ConvergenceError) as exc:
            raise _tangent_failure(exc, system, y, ta, times[i], method, rtol, atol) from exc
        y = y1
        Q, R = np.linalg.qr(Phi)
        d = np.diag(R)
        if not np.all(np.isfinite(d)):
            raise ConvergenceError(
                f"lyapunov_spectrum: the tangent vectors overflowed between t = {ta:.6g} and "
                f"{times[i]:.6g} (R's diagonal {d.tolist()}): they grow by about "
                f"exp(lambda dt) over one dt = {T / m:.6g}; use a shorter dt, so that "
                "lambda_max dt stays well below 709 (float64's range)")
        # a zero of R's diagonal: the tangent map is singular, a direction of the state
        # collapsed in finite time (a switch of the field that pins a component, as the
        # rocket's burn-out pins its mass): its exponent is -inf, and the frame keeps Q's
        # column for it (any unit vector orthogonal to the others)
        with np.errstate(divide="ignore"):
            sums += np.log(np.abs(d))
        Q = Q * np.where(d < 0, -1.0, 1.0)
        running[i] = sums / (times[i] - t0)
        ta = times[i]
    spec = np.sort(running[-1])[::-1].copy()
    if return_history:
        return spec, times, running
    return spec


def _tangent_failure(exc, system, y, ta, tb, method, rtol, atol):
    """The error of a failed tangent-flow interval of lyapunov_spectrum, in the user's
    terms (the failing solve's message speaks of the hidden augmented system): the
    orbit itself fails there (the plain system's own failure), or only the tangent
    vectors do, which a shorter dt cures."""
    plain = solve(system, (ta, tb), y, method, rtol=rtol, atol=atol, t_eval=[tb],
                  errors="status")
    if plain.status < 0:
        msg = (f"lyapunov_spectrum: the orbit from y = {y.tolist()} at t = {ta:.6g} fails "
               f"before t = {tb:.6g}: {plain.message}")
    else:
        msg = (f"lyapunov_spectrum: the tangent vectors outgrow float64 between t = "
               f"{ta:.6g} and {tb:.6g}, though the orbit does not (they grow by about "
               f"exp(lambda dt) over one dt = {tb - ta:.6g}); use a shorter dt, so that "
               "lambda_max dt stays well below 709")
    return type(exc)(msg)


# ---- Floquet multipliers --------------------------------------------------------------
def _first_return(system, y0, f0, t_max, method, rtol, atol):
    """The time of the first return of the orbit from y0 to the plane through y0
    normal to f0, crossed in the direction of f0."""
    def g(t, y):
        return float(f0 @ (np.asarray(y) - y0))
    # g is zero at t = 0 and leaves zero upwards: as in solve_ivp that start is an
    # event too, so the solve stops at the second (the return)
    g.terminal, g.direction = 2, 1.0
    s = solve(system, (0.0, t_max), y0, method, rtol=rtol, atol=atol, events=g,
              t_eval=[])
    _check(s, "floquet (first return)")
    te = s.t_events[0]
    te = te[te > 0.0]
    if te.size == 0:
        raise ConvergenceError(
            f"floquet: the orbit from y0 did not return to the plane through y0 across its "
            f"velocity within t = {t_max:g}; give the period (period=...) or start on the "
            "orbit")
    return float(te[0])


def _check_forcing_period(system, T, y):
    """ValueError unless f(t + T, y) = f(t, y) at a few (t, y) near the orbit's start:
    a T that is not a period of the forcing has no periodic orbit to shoot for (Newton
    still finds a fixed point of phi_T, the state after T, which is no orbit of f)."""
    rng = np.random.default_rng(0)
    scale = 1.0 + np.abs(y)
    for t in (0.0, *(T * rng.random(4))):
        yy = y + 0.1 * scale * rng.standard_normal(y.size)
        a = np.asarray(system.rhs(t, yy), dtype=np.float64)
        b = np.asarray(system.rhs(t + T, yy), dtype=np.float64)
        gap = np.abs(b - a).max()
        if gap > 1e-9 * max(1.0, np.abs(a).max(), np.abs(b).max()) * max(1.0, abs(t + T)):
            raise ValueError(
                f"floquet: period = {T:.17g} is not a period of the forcing: f(t + T, y) - "
                f"f(t, y) reaches {gap:.3g} (t = {t:.6g}, y = {yy.tolist()}); give the "
                "forcing's period (2 pi / omega for a drive at omega) or a multiple of it")


def _floquet(system, y0, *, period=None, tol: float = 1e-10, max_iter: int = 50,
             method: str = "dop853", rtol: float = 1e-11, atol: float = 1e-12,
             t_max: float = 1e4, return_orbit: bool = False):
    """What :func:`mechpy.phase.floquet` does (its docstring)."""
    _require(system)
    import sympy as sp
    y, n = _initial_state(system, y0)
    tol = as_scalar(tol, "tol", positive=True)
    max_iter = as_int(max_iter, "max_iter", minimum=1)
    aug, pn = _augmented(system, (), True)
    aug = _bind(aug, pn, _values(system))
    switches = _switch_events(system, n, {}, _values(system))
    # forced: f depends on t at these parameter values (a drive of amplitude 0 is none)
    fld = system.symbolic()
    forced = any(fld.t in sp.sympify(e).xreplace(fld.params).free_symbols for e in fld.f)
    if period is None and forced:
        raise ValueError("floquet: the system is forced (its right-hand side depends on t): "
                         "give its period (period=...)")
    guess = None if period is None else as_scalar(period, "period", positive=True)

    def shoot(y, T):
        """Newton's shooting from (y, T) -> (y, T, M)."""
        eye = np.eye(n)
        for it in range(max_iter + 1):
            yT, M = _flow(aug, n, 0.0, T, y, eye, method, rtol, atol, "floquet", switches)
            r = yT - y
            scale = 1.0 + np.linalg.norm(y)
            if np.linalg.norm(r) <= tol * scale:
                return y, T, M
            if it == max_iter:
                raise ConvergenceError(
                    f"floquet: Newton's shooting did not converge in {max_iter} iterations "
                    f"(|phi_T(y) - y| = {np.linalg.norm(r):.3g}); start nearer the orbit")
            if forced:
                dy = np.linalg.solve(M - eye, -r)
                dT = 0.0
            else:
                fy = system.rhs(0.0, y)
                A = np.zeros((n + 1, n + 1))
                A[:n, :n] = M - eye
                A[:n, n] = system.rhs(T, yT)
                A[n, :n] = fy
                sol = np.linalg.lstsq(A, -np.concatenate([r, [0.0]]), rcond=None)[0]
                dy, dT = sol[:n], sol[n]
            y = y + dy
            T = T + dT
            if not T > 0:
                raise ConvergenceError("floquet: the period went non-positive in Newton's "
                                       "shooting; start nearer the orbit")

    if forced:
        # the period is the forcing's, fixed: refuse one that is not
        _check_forcing_period(system, guess, y)
        y, T, M = shoot(y, guess)
    else:
        f0 = system.rhs(0.0, y)
        if not np.any(f0):
            raise ValueError("floquet: y0 is a fixed point (f(y0) = 0), not on a periodic orbit")
        # the first guess of T is the first return to the section through y0 (a given
        # period only bounds the search, to a few periods); Newton then refines it
        horizon = t_max if guess is None else min(t_max, 4.0 * guess)
        try:
            T = _first_return(system, y, f0, horizon, method, rtol, atol)
        except ConvergenceError:
            if guess is None:
                raise
            T = guess
        y, T, M = shoot(y, T)
        if not np.linalg.norm(system.rhs(0.0, y)) > 1e-8 * (1.0 + np.linalg.norm(y)) / T:
            raise ConvergenceError(
                f"floquet: Newton's shooting converged to a fixed point (y = {y.tolist()}, "
                "f(y) = 0), not a periodic orbit: there is none near y0")
        # the minimal period: the converged orbit's first return to its own section; a T
        # that is k of them (Newton from a guess near k periods) is replaced by it
        t1 = _first_return(system, y, system.rhs(0.0, y), 1.5 * T, method, rtol, atol)
        k = int(round(T / t1))
        if k > 1 and abs(T - k * t1) <= 1e-6 * T:
            y, T, M = shoot(y, t1)
        elif abs(T - t1) > 1e-6 * T:
            raise ConvergenceError(
                f"floquet: Newton's shooting closed the orbit after T = {T:.10g}, but it first "
                f"returns to its section after {t1:.10g}, which does not divide T: no "
                "periodic orbit with a well-defined period was found; start nearer the orbit")
    mult = np.linalg.eigvals(M).astype(complex)
    mult = mult[np.argsort(-np.abs(mult), kind="stable")]
    if return_orbit:
        return float(T), mult, y
    return float(T), mult


# ---- fitting --------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class FitResult:
    """The result of :func:`fit`.

    Attributes
    ----------
    params : dict
        Best-fit values by name (initial-state components as ``"y0[i]"``).
    stderr : dict
        Standard errors, sqrt of cov's diagonal.
    cov : ndarray (p, p)
        Covariance of the estimates, in the order of ``params``.
    residuals : ndarray (k, m)
        data - model at the optimum.
    chi2 : float
        Sum of squared residuals, each divided by its sigma (1 when sigma is None).
    dof : int
        Degrees of freedom, k m - p.
    nfev, njev : int
        Evaluations of the residuals and of their Jacobian (each one solve).
    success : bool
    message : str
        :func:`scipy.optimize.least_squares`' verdict.
    names : list of str
        The fitted quantities, in the order of ``cov``'s rows.

    Examples
    --------
    A damped oscillator x'' = -w^2 x - c x' measured without noise: the fit
    recovers (w, c) = (2, 0.3) and its residuals vanish.

    >>> import numpy as np, sympy as sp
    >>> import mechpy as mp
    >>> x, v, w, c = sp.symbols("x v w c")
    >>> osc = mp.equations([v, -w**2 * x - c * v], [x, v], params={"w": 2.0, "c": 0.3})
    >>> t = np.linspace(0, 6, 61)
    >>> data = mp.solve(osc, (0, 6), [1.0, 0.0], t_eval=t, rtol=1e-12, atol=1e-12).y[:1]
    >>> r = mp.fit(osc, t, data, {"w": 1.7, "c": 0.1}, y0=[1.0, 0.0], observe=0)
    >>> r.success, round(r.params["w"], 8), round(r.params["c"], 8), r.dof
    (True, 2.0, 0.3, 59)
    >>> bool(np.abs(r.residuals).max() < 1e-8)
    True
    """
    params: dict
    stderr: dict
    cov: np.ndarray
    residuals: np.ndarray
    chi2: float
    dof: int
    nfev: int
    njev: int
    success: bool
    message: str
    names: list = field(default_factory=list)

    def __repr__(self):
        rows = [f"{k} = {v:.10g} +- {self.stderr[k]:.3g}" for k, v in self.params.items()]
        return (f"FitResult(success={self.success}, chi2={self.chi2:.6g}, dof={self.dof}, "
                f"nfev={self.nfev}:\n  " + "\n  ".join(rows) + ")")


def _observer(observe, n):
    """-> (h(Y) (k, m), dh(Y) (k, n, m), k) for states Y (n, m)."""
    if observe is None:
        idx = list(range(n))
    elif callable(observe):
        def h(Y):
            out = np.asarray(observe(Y), dtype=np.float64)
            if out.ndim == 1:
                out = out[None, :]
            if out.ndim != 2 or out.shape[1] != Y.shape[1]:
                raise ValueError(f"observe(y) must return shape (k, m) for y of shape "
                                 f"{Y.shape}, got {out.shape}")
            return out

        def dh(Y):
            k = h(Y).shape[0]
            D = np.empty((k, n, Y.shape[1]))
            for j in range(n):
                e = 1e-6 * np.maximum(1.0, np.abs(Y[j]))
                Yp, Ym = Y.copy(), Y.copy()
                Yp[j] += e
                Ym[j] -= e
                D[:, j] = (h(Yp) - h(Ym)) / (2 * e)
            return D
        return h, dh, None
    else:
        items = [observe] if isinstance(observe, (int, np.integer)) else list(observe)
        idx = []
        for v in items:
            idx.append(as_int(v, "observe", minimum=-n, maximum=n - 1) % n)
    sel = np.zeros((len(idx), n))
    sel[np.arange(len(idx)), idx] = 1.0
    return (lambda Y: Y[idx]), (lambda Y: np.broadcast_to(sel[:, :, None],
                                                         sel.shape + (Y.shape[1],))), len(idx)


def fit(system, t, data, params, *, y0, observe=None, sigma=None, fit_y0=False,
        t0=None, method: str = "dop853", rtol: float = 1e-10, atol: float = 1e-12,
        bounds=None, loss: str = "linear", max_nfev=None, events=None) -> FitResult:
    r"""Fit parameters (and initial state) of a system to sampled data by least squares.

    .. math:: \min_\theta\ \sum_{i,j}\left(\frac{h_i(\mathbf y(t_j; \theta)) - d_{ij}}
              {\sigma_{ij}}\right)^2

    with :func:`scipy.optimize.least_squares` (trust region reflective, ``x_scale="jac"``)
    and the exact Jacobian :math:`\partial h/\partial y \cdot S` from the sensitivities
    (:func:`sensitivity`: one solve of the augmented system gives the residuals and
    the Jacobian).  Bounds default to the scene's parameter domains (its C row), so a
    poor start cannot wander into, say, a negative length.

    Parameters
    ----------
    system : Scene or compiled system
        With a symbolic form (``system.symbolic()``); the parameters not fitted keep
        the system's values.
    t : array_like (m,)
        Sample times, strictly increasing.
    data : array_like (k, m)
        The k observed quantities at the m times ((m,) for k = 1); finite.
    params : dict
        ``{name: initial guess}`` of the parameters to fit.
    y0 : array_like (n,)
        The initial state at ``t0`` (the first guess of it with ``fit_y0``).
    observe : int, sequence of int or callable, optional
        What ``data`` measures: state components by index, or ``h(y)`` taking states
        (n, m) to (k, m) (its derivative by central differences, step ``1e-6 max(1, |y|)``).
        Default: all n components.
    sigma : float, (k,) or (k, m), optional
        Standard deviations of the data.  Given: the residuals are weighted by 1/sigma
        and ``cov`` = (J^T J)^-1 (absolute sigma).  None: unit weights and ``cov`` =
        (J^T J)^-1 chi2 / (k m - p), scaled by the reduced chi-square (as
        ``scipy.optimize.curve_fit`` with ``absolute_sigma=False``).
    fit_y0 : bool or sequence of int
        Fit the initial state too (all components, or those indexed); they appear in
        the result as ``"y0[i]"``.
    t0 : float, optional
        The time of ``y0`` (default ``t[0]``).
    method, rtol, atol
        For :func:`mechpy.solve` of the augmented system.
    bounds : (lo, hi), optional
        Override the domains: arrays over the fitted quantities (params, then y0).
    loss : str
        :func:`scipy.optimize.least_squares`' loss (``"soft_l1"`` for outliers; the
        standard errors then are those of the linearised problem).
    max_nfev : int, optional
        Budget of residual evaluations.
    events : callable or list of callables, optional
        Events with actions (:func:`mechpy.events.impact`, Python actions with their
        ``action.jac``), as for :func:`sensitivity`: the Jacobian jumps with the state,
        so a restitution that is a parameter of the system (``impact(...,
        restitution="e")``) can be fitted.

    Returns
    -------
    FitResult
        ``params``, ``stderr``, ``cov``, ``residuals`` (data - model, (k, m)), ``chi2``,
        ``dof``, ``nfev``, ``njev``, ``success``, ``message``.

    Raises
    ------
    TypeError
        A system without a symbolic form (a Python callable), params not a dict.
    ValueError
        A parameter the system lacks (named), data of the wrong shape or non-finite
        (the first bad entry named), a guess outside the parameter's domain.
    ConvergenceError
        An integration failed at some trial parameters.

    Examples
    --------
    >>> import numpy as np
    >>> import mechpy as mp
    >>> sc = mp.scenes.Pendulum(damping=0.3)
    >>> t = np.linspace(0, 5, 51)
    >>> data = mp.solve(sc, (0, 5), [1.0, 0.0], t_eval=t).y[:1]
    >>> r = mp.fit(sc, t, data, {"damping": 0.1}, y0=[1.0, 0.0], observe=0)
    >>> round(r.params["damping"], 6)
    0.3
    """
    from scipy.optimize import least_squares
    _require(system)
    if not isinstance(params, dict) or not params:
        raise TypeError(f"params must be a non-empty dict {{name: initial guess}}, got "
                        f"{params!r}")
    names = _param_names(system, tuple(params))
    guess = np.array([as_scalar(params[nm], f"params[{nm!r}]") for nm in names])
    n = system.dim
    y0 = as_array(y0, "y0", ndim=1)
    if y0.shape[0] != n:
        raise ValueError(f"y0 must have {n} components, got shape {y0.shape}")
    t = as_array(t, "t", ndim=1)
    if t.size < 1 or np.any(np.diff(t) <= 0):
        raise ValueError("t must be strictly increasing sample times")
    m = t.size
    t0 = float(t[0]) if t0 is None else as_scalar(t0, "t0")
    if t0 > t[0]:
        raise ValueError(f"t0 ({t0}) must not lie after the first sample time t[0] = {t[0]}")
    data = as_array(data, "data", finite=False)
    if data.ndim == 1:
        data = data[None, :]
    h, dh, k = _observer(observe, n)
    if k is None:
        k = h(np.repeat(y0[:, None], m, axis=1)).shape[0]
    if data.shape != (k, m):
        raise ValueError(f"data must have shape (k, m) = ({k}, {m}) (k observed components "
                         f"at the {m} times t), got {data.shape}")
    bad = ~np.isfinite(data)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(f"data must be finite: data[{i}, {j}] = {data[i, j]} (and "
                         f"{int(bad.sum()) - 1} more)")
    if sigma is None:
        w = np.ones((k, m))
    else:
        sg = as_array(sigma, "sigma", min_ndim=0, positive=True)
        try:
            w = np.broadcast_to(sg if sg.ndim != 1 else sg[:, None], (k, m)).copy()
        except ValueError:
            raise ValueError(f"sigma must be a scalar, (k,) = ({k},) or (k, m) = ({k}, {m}), "
                             f"got shape {sg.shape}") from None
    if fit_y0 is True:
        y0_idx = list(range(n))
    elif fit_y0 is False or fit_y0 is None:
        y0_idx = []
    else:
        y0_idx = sorted({as_int(i, "fit_y0", minimum=0, maximum=n - 1) for i in fit_y0})
    np_ = len(names)
    x0 = np.concatenate([guess, y0[y0_idx]])
    labels = list(names) + [f"y0[{i}]" for i in y0_idx]
    if bounds is None:
        lo, hi = _scene_bounds(system, names)
        lo = np.concatenate([lo, np.full(len(y0_idx), -np.inf)])
        hi = np.concatenate([hi, np.full(len(y0_idx), np.inf)])
    else:
        lo, hi = (np.broadcast_to(as_array(b, "bounds", min_ndim=0, finite=False),
                                  x0.shape).copy() for b in bounds)
    for i, nm in enumerate(labels):
        if not lo[i] <= x0[i] <= hi[i]:
            raise ValueError(f"the initial guess {nm} = {x0[i]} lies outside its domain "
                             f"[{lo[i]}, {hi[i]}]")
    # least_squares wants x0 strictly inside: nudge a guess sitting on a bound
    span = np.where(np.isfinite(hi - lo), hi - lo, np.maximum(1.0, np.abs(x0)))
    x0 = np.clip(x0, lo + 1e-10 * span, hi - 1e-10 * span)
    with_y0 = bool(y0_idx)
    aug, pn = _augmented(system, names, with_y0)
    base = _values(system)
    ncol = np_ + (n if with_y0 else 0)
    cols = {nm: j for j, nm in enumerate(names)}
    # the events checked once, before the optimiser runs (a Python action without its
    # Jacobian, a restitution naming no parameter)
    _aug_events(events, system, n, cols, base, _bind(aug, pn, base))
    cache = {}

    def model(x):
        key = x.tobytes()
        if key in cache:
            return cache[key]
        vals = dict(base)
        vals.update(zip(names, x[:np_]))
        yy = y0.copy()
        yy[y0_idx] = x[np_:]
        S0 = np.zeros((n, ncol))
        if with_y0:
            S0[:, np_:] = np.eye(n)
        bound = _bind(aug, pn, vals)
        evs = _aug_events(events, system, n, cols, vals, bound)
        s = solve(bound, (t0, float(t[-1])), np.concatenate([yy, S0.ravel()]), method,
                  rtol=rtol, atol=atol, t_eval=t, events=evs)
        if s.status < 0 or s.y.shape[1] != m:
            raise ConvergenceError(
                f"fit: the integration failed at {dict(zip(labels, x.tolist()))}: "
                f"{s.message}")
        Y = s.y[:n]
        S = s.y[n:].reshape(n, ncol, m)
        if with_y0:
            S = np.concatenate([S[:, :np_], S[:, np_:][:, y0_idx]], axis=1)
        pred = h(Y)
        jac = np.einsum("knm,npm->kmp", dh(Y), S)
        cache.clear()
        cache[key] = (pred, jac)
        return pred, jac

    def fun(x):
        pred, _ = model(x)
        return ((pred - data) / w).ravel()

    def jac(x):
        _, J = model(x)
        return (J / w[:, :, None]).reshape(k * m, -1)

    res = least_squares(fun, x0, jac=jac, bounds=(lo, hi), x_scale="jac", loss=loss,
                        method="trf", max_nfev=max_nfev)
    pred, J = model(res.x)
    Jw = (J / w[:, :, None]).reshape(k * m, -1)
    r = (data - pred)
    chi2 = float(np.sum((r / w) ** 2))
    dof = k * m - x0.size
    _, sv, Vt = np.linalg.svd(Jw, full_matrices=False)
    keep = sv > sv[0] * 1e-12 if sv.size and sv[0] > 0 else np.zeros(sv.shape, bool)
    cov = (Vt[keep].T / sv[keep] ** 2) @ Vt[keep]
    if keep.sum() < x0.size:
        cov[:] = np.inf
    if sigma is None:
        cov = cov * (chi2 / dof if dof > 0 else np.inf)
    err = np.sqrt(np.diag(cov))
    return FitResult(params=dict(zip(labels, res.x.tolist())),
                     stderr=dict(zip(labels, err.tolist())), cov=cov, residuals=r,
                     chi2=chi2, dof=int(dof), nfev=int(res.nfev), njev=int(res.njev or 0),
                     success=bool(res.success), message=str(res.message), names=labels)


def _scene_bounds(system, names):
    """Bounds of the named parameters from the scene's C row (its domains: an open
    end is nudged inwards by 1e-12 of the scale); (-inf, inf) without a row."""
    lo, hi = np.full(len(names), -np.inf), np.full(len(names), np.inf)
    model = getattr(system, "_model", None)
    if not model:
        return lo, hi
    info = {p["name"]: p for p in _row(model)["param_info"]}
    for i, nm in enumerate(names):
        p = info.get(nm)
        if p is None:
            continue
        a, b = float(p["lo"]), float(p["hi"])
        if p.get("lo_open") and np.isfinite(a):
            a += 1e-12 * max(1.0, abs(a))
        if p.get("hi_open") and np.isfinite(b):
            b -= 1e-12 * max(1.0, abs(b))
        lo[i], hi[i] = a, b
    return lo, hi
