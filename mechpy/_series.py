"""The time series drawn beside an animation of the motion: ``plots=[...]``
of :func:`mechpy.live.animate` and :func:`mechpy.plot.animate`.

An entry of ``plots`` is

- a state's name (one of ``system.states``): that state component;
- ``"energy"``: the system's own ``energy`` (a built-in scene's, the Jacobi
  integral of :func:`mechpy.lagrangian`, the ``energy=`` of
  :func:`mechpy.equations`, T + V of an :func:`mechpy.mechanics` model whose
  loads are constant forces);
- a SymPy expression of the states (symbols, or functions of t, named as
  the states: ``sp.Symbol("theta1")``, ``sp.Symbol("theta1'")`` or, for a
  coordinate ``q(t)`` of :func:`mechpy.coordinates`, ``q`` and
  ``q.diff(t)``), the time ``t`` and the system's parameters by name (at the
  system's values).

Its label (the legend's text and the name ``window.mechpyLive.plot(name)``
takes) is the entry as given: the state's name, ``"energy"``, or
``str(expr)``.  Both painters take their series from :func:`series`; a page
that computes its own frames takes them from :func:`expressions`.
"""
from __future__ import annotations

import numpy as np

__all__ = ["series", "expressions", "labels"]


def _entries(system, plots) -> list:
    """[(label, kind, what)] of ``plots``, checked: kind "state" (what: its
    index), "energy" (what: None) or "expr" (what: the expression in the state
    symbols y0.., t and the parameters' symbols by name)."""
    if isinstance(plots, (str, bytes)) or not hasattr(plots, "__iter__"):
        raise TypeError("plots must be a list of state names, 'energy' or SymPy expressions, "
                        f"got {plots!r}")
    states = list(system.states)
    out = []
    for entry in plots:
        if isinstance(entry, str):
            if entry == "energy":
                out.append(("energy", "energy", None))
            elif entry in states:
                out.append((entry, "state", states.index(entry)))
            else:
                raise ValueError(f"plots: {entry!r} is neither a state of the system "
                                 f"({states}) nor 'energy'")
            continue
        out.append((str(entry), "expr", _in_states(system, entry, states)))
    labels = [e[0] for e in out]
    twice = sorted({x for x in labels if labels.count(x) > 1})
    if twice:
        raise ValueError(f"plots names {twice} more than once")
    return out


def _in_states(system, entry, states):
    """A SymPy expression of the states (by name), t and the parameters (by
    name) in the symbols y0.., t and the parameters' own names."""
    import sympy as sp
    if not isinstance(entry, sp.Basic):
        raise TypeError(f"plots: {entry!r} is not a state's name, 'energy' or a SymPy "
                        f"expression (a {type(entry).__name__})")
    if not isinstance(entry, sp.Expr):
        raise TypeError(f"plots: {entry} is a {type(entry).__name__}, not a SymPy expression "
                        "of one value")
    y = sp.symbols(f"y0:{len(states)}")
    t = sp.Symbol("t")
    params = list(getattr(system, "params", {}) or {})
    sub = {}
    # a state written as a function of t (mp.coordinates, dynamicsymbols) and its rate
    for d in entry.atoms(sp.Derivative):
        f = d.expr
        nm = f"{getattr(f, 'func', f).__name__}'" if d.derivative_count == 1 else None
        if nm not in states or not isinstance(f, sp.core.function.AppliedUndef):
            raise ValueError(f"plots[{str(entry)!r}] holds the derivative {d}, which is no "
                             f"state of the system (its states: {states})")
        sub[d] = y[states.index(nm)]
    e = entry.xreplace(sub)
    # the states by name (a symbol, or a function of t), t, the parameters by name
    named = {}
    for s in e.atoms(sp.Symbol, sp.core.function.AppliedUndef) - set(sub.values()):
        applied = isinstance(s, sp.core.function.AppliedUndef)
        nm = s.func.__name__ if applied else s.name
        if nm in states:
            named[s] = y[states.index(nm)]
        elif not applied and nm == "t":
            named[s] = t
        elif not applied and nm in params:
            named[s] = sp.Symbol(nm)
        else:
            raise ValueError(f"plots[{str(entry)!r}] depends on {s}, which is neither a "
                             f"state ({states}) nor a parameter ({params}) of the system")
    return e.xreplace(named)


def labels(system, plots) -> list:
    """The labels of ``plots`` (checked as :func:`series` checks them)."""
    return [e[0] for e in _entries(system, plots)]


def _energy_values(system, times, Y):
    """The system's own energy at the states Y (n, frames) at ``times``."""
    fn = getattr(system, "energy", None)
    if fn is None:
        raise ValueError(f"plots: 'energy' asked of {system!r}, which has no energy")
    try:
        if hasattr(system, "_meta"):        # a compiled system: its energy may hold t
            return np.asarray(fn(Y, times), dtype=float)
        return np.asarray(fn(Y), dtype=float)
    except (AttributeError, NotImplementedError) as exc:
        raise ValueError(f"plots: 'energy' asked of {system!r}, which has none ({exc})") from None


def series(system, plots, times, Y) -> list:
    """The series of ``plots`` at the frames: ``[(label, values (frames,))]``.

    ``times`` (frames,) the frames' times, ``Y`` (n, frames) their states.
    Each value is computed from the frame's state alone: a state component,
    ``system.energy`` (at the frame's time for a compiled system), or the
    expression evaluated in NumPy (``sympy.lambdify``) with the parameters
    at the system's values.

    Raises
    ------
    TypeError
        ``plots`` is not a list, or an entry is neither a string nor a SymPy
        expression.
    ValueError
        An unknown state name, an expression with a symbol that is neither a
        state nor a parameter (nor t), ``"energy"`` for a system without
        one, a label given twice, or a series that is not finite (named).
    """
    times = np.asarray(times, dtype=float)
    Y = np.asarray(Y, dtype=float)
    out = []
    params = dict(getattr(system, "params", {}) or {})
    for label, kind, what in _entries(system, plots):
        if kind == "state":
            v = Y[what].copy()
        elif kind == "energy":
            v = _energy_values(system, times, Y)
        else:
            import sympy as sp
            y = sp.symbols(f"y0:{Y.shape[0]}")
            ps = sorted((s for s in what.free_symbols if s.name in params), key=str)
            f = sp.lambdify([sp.Symbol("t"), *y, *ps], what, "numpy")
            with np.errstate(all="ignore"):
                v = f(times, *Y, *[params[s.name] for s in ps])
            v = np.asarray(v)
            if np.iscomplexobj(v):
                raise ValueError(f"plots: the series {label!r} is complex at some frame")
            v = np.broadcast_to(v.astype(float), times.shape).copy()
        bad = ~np.isfinite(v)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"plots: the series {label!r} is not finite at t = {times[k]:g} "
                             f"(frame {k}: {v[k]})")
        out.append((label, v))
    return out


def expressions(system, plots) -> list:
    """Each series of ``plots`` as a SymPy expression: ``[(label, expr or None)]``.

    The contract (for a page that recomputes the series from states it
    integrates itself): ``expr`` is in the symbols ``y0, ..., y{n-1}``
    (``sympy.Symbol("y<i>")``, the state components in the order of
    ``system.states``), ``t`` (``sympy.Symbol("t")``) and the parameters,
    each ``sympy.Symbol(name)`` with ``name`` a key of ``system.params``
    (its value there); evaluated at a state it equals :func:`series`'s value.
    A state's series is ``y<i>``; a given expression, rewritten in these
    symbols; ``"energy"``, the energy a compiled system was derived with (the
    Jacobi integral h = sum q' dL/dq' - L of :func:`mechpy.lagrangian`, the
    ``energy=`` of :func:`mechpy.equations`, T + V of :func:`mechpy.mechanics`)
    or None where the system has no symbolic energy (a built-in scene's is in
    C only).  Raises as :func:`series` does for bad entries.
    """
    import sympy as sp
    out = []
    for label, kind, what in _entries(system, plots):
        if kind == "state":
            out.append((label, sp.Symbol(f"y{what}")))
        elif kind == "expr":
            out.append((label, what))
        else:
            out.append((label, _symbolic_energy(system)))
    return out


def _symbolic_energy(system):
    """A compiled system's energy in y<i>, t and the parameters' names (its
    stored ``meta['energy']``), None when it has none."""
    meta = getattr(system, "_meta", None)
    if not meta or not meta.get("has_energy"):
        if meta is not None:
            raise ValueError(f"plots: 'energy' asked of {system!r}, which has "
                             "none (mp.equations: give energy=; mp.mechanics: its loads must "
                             "be constant forces)")
        return None
    if not meta.get("energy"):
        return None
    import sympy as sp
    return sp.sympify(meta["energy"])
