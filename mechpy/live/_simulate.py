"""A page that simulates: what :func:`mechpy.live.animate` sends the page when
it is given ``params={"name": (min, max)}`` or ``y0=``.

The page integrates the system itself (``static/simulate.js``): the
Dormand-Prince 5(4) pair with Hairer's 4th-order dense output, in double
precision, at ``RTOL`` and ``ATOL``, from the right-hand side printed as
JavaScript by :mod:`._field` (the phase portrait's printer).  A Lagrangian of
two or more coordinates is printed as its mass matrix M(q) and its forces
F(q, q', t) (:meth:`mechpy.symbolic.scene.CompiledScene._mass_form`), and the
page solves M q'' = F by LU with partial pivoting at each evaluation (no
symbolic inverse).  An :func:`mechpy.mechanics` scene is printed as the
linear system A z = b that its C solves (the same expressions, kept in memory
by the scene: :class:`mechpy.symbolic.multibody.SymPyForm`), solved likewise,
dy/dt the first ``dim`` unknowns.  The places drawn are printed from the
drawing's own geometry (``mechpy._motion.DRAWINGS``' ``geometry``: the bobs of
a pendulum, the ``points=`` of a system; a mechanics model's places and its
solids' direction cosines), so the page computes every frame it shows.

In the printed code the state is ``s[i]``, the time ``t`` and parameter j is
``p[j]`` (the order of the field's parameters), as in the phase portrait.
"""
from __future__ import annotations

import numpy as np
import sympy as sp

from .. import _motion, _series
from .._validate import as_scalar
from ..integrate import solve
from . import _field

#: the page's tolerances (weighted RMS norm of the local error estimate, as Hairer's
#: dopri5): chosen so that the page agrees with mp.solve at rtol 1e-10 to 1e-7 after 10 s
#: (measured: see tests/test_live_simulate.py)
RTOL, ATOL = 1e-12, 1e-12

#: the step budget of one run: this many steps a frame (a runaway stops with a message)
STEPS_PER_FRAME = 1000


def _mechanics(system):
    """(Field, na) of an :func:`mechpy.mechanics` scene: the expressions are A
    (na x na, row-major) then b of the linear system A z = b its C solves at
    each evaluation (:class:`mechpy.symbolic.multibody.SymPyForm`, the same
    expressions), dy/dt = z[:dim].  ValueError when the scene has no SymPy
    form in memory or a specified input is a Python callable."""
    form = system._sympy
    if form is None:
        raise ValueError("this mechanics scene holds no SymPy form (an unpickled scene): "
                         "make it again with mp.mechanics(method, params) in this session")
    if system._functions:
        raise ValueError(f"the specified input(s) {sorted(system._functions)} are Python "
                         "callables, which the page cannot call: give them values (a "
                         "parameter)")
    exprs = form.A + form.b
    td = any(form.T in sp.sympify(e).free_symbols for e in exprs)
    fd = _field.Field(exprs, form.Y, form.T, form.P, list(form.param_names),
                      [float(v) for v in system._vector()], td)
    return fd, len(form.b)


def _locked(system, fd) -> dict:
    """{name: why} of the parameters that a slider or setParam may not change: a
    mechanics scene's parameters in its constraints (the initial state, placed
    on the constraints at the system's values, would leave them, and mp.solve
    refuses such a state)."""
    form = getattr(system, "_sympy", None)
    if form is None or not form.G:
        return {}
    used = set().union(*(sp.sympify(g).free_symbols for g in form.G))
    return {nm: (f"{nm} enters the model's constraints: the initial state, on the "
                 "constraints at its value, would leave them at another")
            for nm, s in zip(fd.names, fd.p) if s in used}


def _dynamics(system):
    """(Field, nc, na): the field printed for the page; ``nc`` > 0 for a
    Lagrangian's mass-matrix form (the field's expressions are then M
    row-major, then F: M q'' = F), ``na`` > 0 for a mechanics scene's linear
    system (A row-major, then b: dy/dt = z[:dim] of A z = b), both 0 for y' =
    f.  ValueError naming why a system cannot be simulated by the page."""
    why = "the page cannot simulate this system: "
    mass = getattr(system, "_mass_form", None)
    na = 0
    try:
        if (getattr(system, "_meta", None) or {}).get("kind") == "mechanics":
            (fd, na), nc = _mechanics(system), 0
        elif mass is not None and system._meta["kind"] == "lagrangian" and system._nc >= 2:
            M, F, y, t, params = mass()
            exprs = list(M) + list(F)
            td = any(t in sp.sympify(e).free_symbols for e in exprs)
            fd = _field.Field(exprs, y, t, list(params), [str(s) for s in params],
                              [float(v) for v in params.values()], td)
            nc = system._nc
        else:
            fd, nc = _field.field_of(system), 0
        _field._check_printable(fd)
    except ValueError as e:
        raise ValueError(why + str(e)) from None
    return fd, nc, na


def _renamed(exprs, fd, what="drawing"):
    """The geometry's (or the series') expressions (state ``y<i>``, time ``t``,
    parameters by name) in the field's own symbols, so that they print as
    s[i], t and p[j]."""
    # the contract's y<i> and t (a mechanics field's own symbols are mp_y<i>, mp_t)
    byname = {f"y{i}": s for i, s in enumerate(fd.y)}
    byname["t"] = fd.t
    byname.update({str(s): s for s in fd.y})
    byname[str(fd.t)] = fd.t
    byname.update({nm: s for nm, s in zip(fd.names, fd.p)})
    out = []
    for e in exprs:
        e = sp.sympify(e)
        sub = {}
        for s in e.free_symbols:
            if s.name not in byname:
                raise ValueError(f"the page cannot simulate this {what}: it depends on {s}, "
                                 "which is neither a state nor a parameter")
            sub[s] = byname[s.name]
        out.append(e.xreplace(sub))
    return out


def _sliders(params, fd, locked) -> list:
    """[{name, index, min, max, value}] of ``params={"name": (min, max)}``
    (ValueError for a ``locked`` one, with its reason)."""
    if params is None:
        return []
    if not isinstance(params, dict):
        raise TypeError(f"params must be a dict {{name: (min, max)}}, got "
                        f"{type(params).__name__}")
    out = []
    for nm, rng in params.items():
        if nm not in fd.names:
            raise ValueError(f"params: {nm!r} is not a parameter of the system (its "
                             f"parameters: {fd.names})")
        if isinstance(rng, (str, bytes)) or not hasattr(rng, "__len__") or len(rng) != 2:
            raise ValueError(f"params[{nm!r}] must be (min, max), got {rng!r}")
        lo = as_scalar(rng[0], f"params[{nm!r}][0]")
        hi = as_scalar(rng[1], f"params[{nm!r}][1]")
        if nm in locked:
            raise ValueError(f"params[{nm!r}]: the page cannot re-run the motion at another "
                             f"value: {locked[nm]}")
        j = fd.names.index(nm)
        v = fd.values[j]
        if not lo < hi or not lo <= v <= hi:
            raise ValueError(f"params[{nm!r}] = ({lo:g}, {hi:g}) must be an interval min < "
                             f"max holding the system's value {v:g}")
        out.append({"name": nm, "index": j, "min": lo, "max": hi, "value": v})
    return out


def _series_field(system, plots, fd):
    """The Field of ``plots``' series (:func:`mechpy._series.expressions`) in
    the field's symbols, for the page to evaluate at each frame's state; None
    without plots.  ValueError for a series the page cannot compute (a
    built-in scene's energy, which is in C only)."""
    if not plots:
        return None
    exprs = _series.expressions(system, plots)
    missing = [label for label, e in exprs if e is None]
    if missing:
        raise ValueError(f"the page cannot recompute the series {missing}: a built-in "
                         "scene's energy is computed in C only; plot a SymPy expression of "
                         "the states instead, or animate without params= and y0=")
    return _field.Field(_renamed([e for _, e in exprs], fd, "series"), fd.y, fd.t, fd.p,
                        fd.names, fd.values, True)


def simulation(system, drawing, options: dict, params, y0, times, plots=None) -> dict:
    """The ``sim`` entry of the page's spec: the printed field and geometry,
    the series of ``plots`` (evaluated at each frame's state, time and the
    parameters of the run), the parameters and their sliders, the initial
    state, the tolerances and the step budget.  The frames' times are the
    page's ``t``.

    Raises
    ------
    ValueError
        The system or the drawing cannot be simulated (named), a bad
        ``params`` or ``y0``, a span that runs backward.
    TypeError
        ``params`` is not a dict.
    """
    if drawing.geometry is None:
        raise ValueError(f"the page cannot simulate kind={drawing.name!r}: it simulates the "
                         "kinds with a symbolic geometry ("
                         + ", ".join(repr(k) for k, e in _motion.DRAWINGS.items() if e.geometry)
                         + ")")
    fd, nc, na = _dynamics(system)
    nrot = 0
    if na:           # a mechanics model: its drawing's places, then its solids' rotations
        try:
            exprs = system._sympy.kinematics()
        except ValueError as e:
            raise ValueError(f"this mechanics model cannot be drawn: {e}") from None
        d = _motion.bodies_drawing(system)
        nrot = d["nrot"]
        if len(exprs) != 3 * len(d["names"]) + 9 * nrot:      # the stored drawing's layout
            raise ValueError("the page cannot simulate this mechanics model: its method's "
                             "bodies are not those of its stored drawing")
    else:
        exprs = _renamed([c for xyz in drawing.painter("geometry")(system, **options)
                          for c in xyz], fd)
    geom = _field.Field(exprs, fd.y, fd.t, fd.p, fd.names, fd.values, False)
    series = _series_field(system, plots, fd)
    locked = _locked(system, fd)
    sliders = _sliders(params, fd, locked)
    state = np.asarray(system.initial_state(y0), dtype=float).reshape(-1)
    if not np.all(np.isfinite(state)):
        raise ValueError("y0 must be finite")
    if times[-1] <= times[0]:
        raise ValueError("the page integrates forward in time: the span must run from an "
                         "earlier to a later time")
    check = getattr(system, "_check_initial", None)      # y0 that mp.solve refuses, named
    if check is not None:
        check(float(times[0]), state)
    try:
        field_js, geom_js = _field.javascript(fd), _field.javascript(geom)
        series_js = None if series is None else _field.javascript(series)
    except ValueError as e:
        raise ValueError("the page cannot simulate this system: " + str(e)) from None
    return {"dim": system.dim, "nc": nc, "na": na, "nrot": nrot, "field": field_js,
            "geometry": geom_js, "series": series_js, "names": fd.names, "values": fd.values,
            "sliders": sliders, "locked": locked,
            "y0": state.tolist(), "rtol": RTOL, "atol": ATOL,
            "max_steps": STEPS_PER_FRAME * len(times)}


def framing(system, t, y0):
    """The solution that frames a page given no ``sol`` (``sol=None``): mp.solve
    from ``y0`` over ``t = (t0, t1)`` with dense output (rtol 1e-10), which the
    drawing is laid out from (its extent, its centre); the page's frames are
    its own."""
    if y0 is None:
        raise ValueError("sol=None: the page simulates from y0, give it (and t=(t0, t1))")
    if t is None or isinstance(t, (str, bytes)) or np.ndim(t) != 1 or len(t) != 2:
        raise ValueError(f"sol=None: t must be the span (t0, t1), got {t!r}")
    t0, t1 = as_scalar(t[0], "t[0]"), as_scalar(t[1], "t[1]")
    if not t1 > t0:
        raise ValueError(f"sol=None: t = ({t0:g}, {t1:g}) must run forward (t0 < t1)")
    return solve(system, (t0, t1), system.initial_state(y0), dense_output=True, rtol=1e-10,
                 atol=1e-12)
