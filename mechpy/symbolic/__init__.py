"""A user's own system, compiled: ``mp.coordinates``, ``mp.lagrangian``, ``mp.equations``,
and ``mp.mechanics`` (SymPy's KanesMethod, LagrangesMethod or System, see :mod:`.multibody`).

The equations of motion are derived with SymPy (:mod:`.derive`), printed as
C99 (:mod:`.codegen`), compiled once by the C compiler Python was built with
and cached on disk (:mod:`.build`), and bound to the integrator engine as a
scene (:mod:`.scene`).  SymPy is imported only when these functions are
called, so ``import mechpy`` stays fast.
"""
from __future__ import annotations

import os

__all__ = ["coordinates", "lagrangian", "equations", "mechanics", "CompileError"]

_SOURCES = ("derive.py", "codegen.py", "__init__.py")   # __init__: the meta
_GEN_HASH = None


def _generator_hash() -> str:
    """A hash of the generator's own code: a cached derivation is valid only
    for the code that made it (and for the engine's fixed-step blocks its
    source embeds, ``_core.FIXED_STEPS_C``)."""
    import hashlib

    from .. import _core
    global _GEN_HASH
    if _GEN_HASH is None:
        h = hashlib.sha256()
        here = os.path.dirname(__file__)
        for name in _SOURCES:
            with open(os.path.join(here, name), "rb") as f:
                h.update(f.read())
        h.update(_core.FIXED_STEPS_C.encode())
        _GEN_HASH = h.hexdigest()
    return _GEN_HASH


def __getattr__(name):
    if name == "CompileError":
        from .build import CompileError
        return CompileError
    raise AttributeError(name)


def coordinates(names):
    """Generalized coordinates as SymPy functions of time.

    Parameters
    ----------
    names : str or sequence of str
        Names separated by spaces or commas, ``"theta1 theta2"``.

    Returns
    -------
    list of sympy.Function
        One function of ``t`` each (``sympy.physics.mechanics.dynamicsymbols``);
        ``q.diff()`` is its velocity.  A list even for a single name.

    Examples
    --------
    >>> import sympy
    >>> import mechpy as mp
    >>> th, = mp.coordinates("theta")
    >>> m, g, l = sympy.symbols("m g l", positive=True)
    >>> L = m * l**2 * th.diff()**2 / 2 + m * g * l * sympy.cos(th)
    >>> th.diff()
    Derivative(theta(t), t)
    """
    from .derive import coordinates as _coordinates
    return _coordinates(names)


def _check_params(params):
    if params is None:
        return {}
    if not isinstance(params, dict):
        raise TypeError(f"params must be a dict {{name: value}}, got {type(params).__name__}")
    out = {}
    for k, v in params.items():
        name = getattr(k, "name", k)
        if not isinstance(name, str):
            raise TypeError(f"params keys must be symbol names (str), got {k!r}")
        out[name] = v
    return out


def _key(kind, parts, param_names) -> str:
    import hashlib

    import sympy as sp
    h = hashlib.sha256()
    h.update(kind.encode())
    for p in parts:
        h.update(b"\0")
        h.update(sp.srepr(p, order="none").encode() if not isinstance(p, str) else p.encode())
    h.update(b"\0" + "\0".join(param_names).encode())
    h.update(b"\0" + _generator_hash().encode())
    return h.hexdigest()[:40]


def _meta(ir, source, constraints=(), numpy_blocks=False):
    import sympy as sp
    meta = dict(kind=ir.kind, n=ir.n, nc=ir.nc, k=ir.k, nq=ir.nq, names=ir.names,
                param_names=ir.param_names, cyclic=ir.cyclic,
                has_energy="energy" in ir.blocks, source=source,
                equations=sp.srepr(ir.equations, order="none"),
                constraints=[str(g) for g in constraints])
    if "energy" in ir.blocks:
        # the energy in y<i>, t and the parameters' names (mechpy._series.expressions)
        sub = {ir.T: sp.Symbol("t"), **{Yi: sp.Symbol(f"y{i}") for i, Yi in enumerate(ir.Y)},
               **{p: sp.Symbol(nm) for p, nm in zip(ir.P, ir.param_names)}}
        meta["energy"] = sp.srepr(sp.sympify(ir.blocks["energy"][0]).xreplace(sub))
    if ir.jac_nonzeros is not None:
        meta["jac_nonzeros"] = [list(e) for e in ir.jac_nonzeros]
    if numpy_blocks:
        sub = {p: sp.Symbol(f"mp_p{i}") for i, p in enumerate(ir.P)}
        meta["blocks"] = {k: sp.srepr([sp.sympify(e).xreplace(sub) for e in v], order="none")
                          for k, v in ir.blocks.items()}
    return meta


def _make(kind, ir_fn, key_parts, params, backend, constraints=()):
    from .. import _core
    from . import build
    from .scene import CompiledScene
    if backend not in ("c", "numba", "numpy"):
        raise ValueError(f"backend must be 'c', 'numba' or 'numpy', got {backend!r}")
    if backend == "c" and not build.have_compiler():
        backend = _no_compiler()
    key = _key(kind, key_parts, list(params))
    if backend == "c":
        meta = build.load_meta(key)
        if meta is not None and meta.get("param_names") == list(params):
            return CompiledScene(meta, params, "c")
    from .. import _progress
    from . import codegen    # SymPy's C printer: loaded only to derive
    steps = ("deriving the equations", "printing C",
             "compiling" if backend != "numpy" else "binding")
    with _progress.Stages(f"mp.{kind}", steps) as bar:   # shown past a second
        bar.stage(steps[0])
        ir = ir_fn()
        bar.stage(steps[1])
        try:
            source = codegen.c_source(ir, _core.STATUS)
        except ValueError as exc:
            if backend == "c":
                raise
            source = f"/* not printable as C: {exc} */"    # NumPy evaluates it
        meta = _meta(ir, source, constraints, numpy_blocks=backend in ("numpy", "numba"))
        bar.stage(steps[2])
        scene = CompiledScene(meta, params, backend)
    if backend == "c":
        build.store_meta(key, meta)
    return scene


_WARNED = []


def _no_compiler() -> str:
    """backend="c" where no C compiler is found: "numba" (with one warning per
    process) if numba is installed, else CompileError."""
    from . import build, jit
    cmd = " ".join(build.compiler())
    if not jit.available():
        raise build.CompileError(
            f"no C compiler: {cmd!r} is not found (set MECHPY_CC or CC, or install one), and "
            "numba, which compiles the system without one, is not installed (pip install "
            "\"mechpy-classical[jit]\", or pip install numba); backend='numpy' needs neither")
    if not _WARNED:
        import warnings
        _WARNED.append(True)
        warnings.warn(f"no C compiler ({cmd!r} is not found): compiled systems are built "
                      "with numba instead (backend='numba'; about 0.7x the C build's "
                      "speed for a double pendulum, docs/install.md)", RuntimeWarning,
                      stacklevel=4)
    return "numba"


def lagrangian(L, q, params=None, constraints=(), forces=None, *, baumgarte=None,
               backend: str = "c"):
    r"""A scene from a Lagrangian L(q, q', t), compiled to C.

    The Euler-Lagrange equations in mass-matrix form,

    .. math:: M(q, t)\,\ddot q = F(q, \dot q, t) + Q + C^T\lambda, \qquad
              M = \frac{\partial^2 L}{\partial\dot q\,\partial\dot q}, \quad
              F = \frac{\partial L}{\partial q}
                  - \frac{\partial^2 L}{\partial\dot q\,\partial q}\dot q
                  - \frac{\partial^2 L}{\partial\dot q\,\partial t},

    with holonomic constraints g(q, t) = 0 (C = dg/dq) enforced at the
    acceleration level with Baumgarte's stabilisation
    :math:`\ddot g + 2\alpha\dot g + \beta^2 g = 0`, are printed as C (M is
    never inverted symbolically: a dense LU with partial pivoting solves the
    (n + k) system at each evaluation), compiled and cached.

    Parameters
    ----------
    L : sympy.Expr
        The Lagrangian in the coordinates, their first derivatives, t
        (``sympy.Symbol("t")``) and parameter symbols.
    q : sequence of coordinates
        From :func:`coordinates`; the state is ``(q_1..q_n, q_dot_1..q_dot_n)``.
    params : dict
        A value for every free symbol other than t, keyed by the symbol's
        name; their order is the order of ``scene.params`` and of the rows of
        ``mp.solve_many(..., params=...)``.  A name that no expression uses
        is a parameter all the same, for an event to read (a restitution,
        ``mp.events.impact(..., restitution="e")``), as SciPy's ``args``
        carry what only an event function reads; a misspelt name is caught
        where the symbol it was meant for is then left without a value.
    constraints : sequence of sympy.Expr
        Holonomic constraints g(q, t) = 0.  ``mp.solve`` checks that y0
        satisfies them (g and g') before it integrates.
    forces : sequence of sympy.Expr, optional
        Generalized non-conservative forces Q(q, q', t), one per coordinate.
    baumgarte : (alpha, beta), optional
        Stabilisation rates (1/s), default (5, 5) (critically damped).
    backend : {"c", "numba", "numpy"}
        ``"numba"`` compiles the same equations with numba instead of a C
        compiler (:mod:`mechpy.symbolic.jit`; taken, with one RuntimeWarning,
        when ``"c"`` finds no compiler and numba is installed); ``"numpy"``
        evaluates them through ``sympy.lambdify`` (a Python right-hand side:
        much slower, nothing to compile).

    Returns
    -------
    CompiledScene
        A :class:`mechpy.scenes.Scene` with ``rhs``, ``jacobian`` (analytic,
        constrained systems included), ``energy`` (the Jacobi integral
        h = sum q' dL/dq' - L), ``momenta``, ``cyclic``, ``equations``,
        ``c_source``, ``small_oscillations``, and with constraints
        ``multipliers`` and ``constraint_forces``.  When M is constant, V
        depends on q alone and there are no forces or constraints, the scene is
        separable and the symplectic methods take it.

    Raises
    ------
    ValueError
        A free symbol without a value (named, with the names in ``params``
        that no expression uses: a misspelling), a name in ``params`` that is
        a coordinate's or t, a coordinate absent from L, a
        wrong number of forces, a velocity-dependent constraint, or an
        expression that cannot be compiled, named with where it is.  The
        expressions may hold numbers and SymPy's constants (printed as
        doubles), ``+``, ``*``, powers, ``Piecewise`` and the functions sin, cos, tan,
        cot, sec, csc, their inverses asin, acos, atan, atan2, the hyperbolic
        ones and their inverses, exp, log, erf, erfc,
        ``sympy.codegen.cfunctions``' expm1, log1p, exp2, log2, log10, Cbrt,
        hypot, and the non-smooth Abs, sign, Max, Min, floor, ceiling
        (differentiated almost everywhere: Abs' = sign, sign' = floor' =
        ceiling' = 0, Max' and Min' the larger or smaller argument's
        derivative; dry friction -F sign(v) compiles).  Refused: other
        functions (Sum, besselj), the imaginary unit, oo or numbers beyond the
        double range, an ``Eq`` where an expression is expected, two symbols
        of one name with different assumptions; and, through the Jacobian
        (their derivative, polygamma, cannot be printed), gamma, loggamma.
    CompileError
        No C compiler and no numba, or the compiler failed (the command and
        its first lines), or it wrote no library.

    Examples
    --------
    The plane pendulum from its Lagrangian per unit mass, compiled to C: its small
    oscillations are at sqrt(g/l), and it moves as the built-in scene:

    >>> import sympy
    >>> th, = mp.coordinates("theta")
    >>> g, l = sympy.symbols("g l", positive=True)
    >>> L = l**2 * th.diff()**2 / 2 + g * l * sympy.cos(th)
    >>> pend = mp.lagrangian(L, [th], params={"g": 9.81, "l": 1.0})
    >>> round(float(pend.small_oscillations([0.0]).omega[0]), 10), round(9.81 ** 0.5, 10)
    (3.1320919527, 3.1320919527)
    >>> s = mp.solve(pend, (0, 1), [1.0, 0.0], rtol=1e-10, atol=1e-12)
    >>> ref = mp.solve(mp.scenes.Pendulum(g=9.81, length=1.0), (0, 1), [1.0, 0.0], rtol=1e-10,
    ...                atol=1e-12)
    >>> bool(np.abs(s.y[:, -1] - ref.y[:, -1]).max() < 1e-8)
    True
    """
    from .derive import lagrangian_ir
    import sympy as sp
    params = _check_params(params)
    cons = [] if constraints is None else (list(constraints) if isinstance(
        constraints, (list, tuple)) else [constraints])
    parts = [sp.sympify(L), list(q) if isinstance(q, (list, tuple)) else q,
             [sp.sympify(g) for g in cons],
             "none" if forces is None else [sp.sympify(f) for f in (
                 forces if isinstance(forces, (list, tuple)) else [forces])],
             repr(None if baumgarte is None else tuple(float(x) for x in baumgarte))]
    return _make("lagrangian", lambda: lagrangian_ir(L, q, params, cons, forces, baumgarte),
                 parts, params, backend, cons)


def equations(rhs, y, params=None, *, energy=None, backend: str = "c"):
    """A scene from a first-order system y' = rhs(t, y), compiled to C.

    Parameters
    ----------
    rhs : sequence of sympy.Expr
        One expression per state, in the states, t and parameter symbols.
    y : sequence of states
        From :func:`coordinates` (functions of t) or plain SymPy symbols.
    params : dict
        A value for every free symbol other than t, keyed by name; a name no
        expression uses is a parameter all the same, for an event to read
        (see :func:`lagrangian`).
    energy : sympy.Expr, optional
        A conserved quantity to expose as ``scene.energy(y)``.
    backend : {"c", "numba", "numpy"}
        ``"numba"``: numba instead of a C compiler (taken when ``"c"`` finds
        none, see :func:`lagrangian`); ``"numpy"``: ``sympy.lambdify``
        instead of C (slower).

    Returns
    -------
    CompiledScene
        ``rhs``, ``jacobian`` (analytic), ``energy`` (when given),
        ``equations``, ``c_source``.

    Raises
    ------
    ValueError
        A free symbol without a value (named, with the names in ``params``
        that no expression uses), a name in ``params`` that is a state's or t,
        a wrong number of expressions, or an
        expression that cannot be compiled, named: the expressions may hold
        what :func:`lagrangian` lists (numbers and constants, ``+``, ``*``, powers,
        Piecewise, the elementary functions, erf, erfc, ...); an ``Eq`` in
        place of a right-hand side, the imaginary unit, numbers beyond the
        double range and other functions are refused, and gamma, loggamma
        through the Jacobian (Abs, sign, Max, Min, floor, ceiling compile:
        see :func:`lagrangian`).
    CompileError
        No C compiler and no numba, or the compiler failed, or it wrote no
        library.

    Examples
    --------
    The harmonic oscillator as a first-order system, with its energy:

    >>> import sympy
    >>> x, v = sympy.symbols("x v")
    >>> w = sympy.Symbol("w", positive=True)
    >>> osc = mp.equations([v, -w**2 * x], [x, v], params={"w": 2.0},
    ...                    energy=(v**2 + w**2 * x**2) / 2)
    >>> s = mp.solve(osc, (0, 1), [1.0, 0.0], rtol=1e-10, atol=1e-12)
    >>> round(float(s.y[0, -1]), 8), round(float(np.cos(2.0)), 8)          # x = cos(w t)
    (-0.41614684, -0.41614684)
    >>> round(float(osc.energy(s.y[:, -1])), 8)                            # w^2 x0^2 / 2
    2.0
    """
    from .derive import equations_ir
    import sympy as sp
    params = _check_params(params)
    rl = list(rhs) if isinstance(rhs, (list, tuple)) else [rhs]
    parts = [[sp.sympify(e) for e in rl], list(y) if isinstance(y, (list, tuple)) else y,
             "none" if energy is None else sp.sympify(energy)]
    return _make("equations", lambda: equations_ir(rl, y, params, energy), parts, params,
                 backend)


def mechanics(method, params=None, *, specified=None, baumgarte=None):
    r"""A compiled scene from SymPy's mechanics: Kane's or Lagrange's method, or a System.

    The model's mass matrix and forcing vector, :math:`M(q, u, t)\,x' = F(q, u, t)`
    (SymPy's ``mass_matrix_full`` and ``forcing_full``, or the kinematical and
    dynamic parts), are printed as C and solved by a dense LU at each
    evaluation (never inverted symbolically), compiled and cached.  The
    state is ``(q..., u...)`` in the method's order, independent then
    dependent (for Lagrange, ``(q..., q'...)``).  Constraint drift is held
    down in the equations themselves: for Kane, the velocity constraints
    :math:`g_v = B u + c` obey :math:`\dot g_v = -2\alpha g_v` (their rows of
    the mass matrix) and the configuration constraints :math:`f_h(q)`,
    :math:`\dot f_h = -\beta f_h` (the kinematical equations projected onto
    their tangent, :math:`\dot q = f_k + C^T\mu`, :math:`C\dot q = -\beta
    f_h`, :math:`C = \partial f_h/\partial q`); for Lagrange, Baumgarte's
    :math:`\ddot g + 2\alpha\dot g + \beta^2 g = 0` on the constraint rows.

    Parameters
    ----------
    method : KanesMethod, LagrangesMethod or System
        After ``kanes_equations``, ``form_lagranges_equations`` or
        ``form_eoms``; with configuration constraints and dependent
        coordinates, velocity (nonholonomic) constraints and dependent speeds.
    params : dict
        A value for every constant (free symbol other than t), keyed by name.
    specified : dict, optional
        ``{name: value or f(t, y)}`` for each specified input (a dynamic
        symbol of the equations that is neither a coordinate nor a speed,
        such as a torque ``T(t)``), keyed by its name.  A value becomes a
        parameter of the scene (``replace``, ``solve_many(params=...)``); a
        callable is called at each evaluation (a Python right-hand side:
        slower).
    baumgarte : (alpha, beta), optional
        Stabilisation rates (1/s), default (5, 5).

    Returns
    -------
    MechanicsScene
        A :class:`mechpy.scenes.Scene` of the one engine (``mp.solve`` with
        every method, ``mp.solve_many`` in lanes, events, pickling, the cache)
        with ``rhs``, ``jacobian`` (analytic, through the same solve),
        ``constraint_residual(y)`` (the configuration then the velocity
        constraints, ``constraint_names``), ``linearize(y0)`` -> (A, B) in the
        independent states (the dependent ones eliminated through the
        constraints' Jacobian, as SymPy's Linearizer does), ``energy(y)`` when
        every load is a constant force (T + V; for Lagrange the Jacobi
        integral of L plus V), ``inputs`` and ``c_source``.  ``mp.solve``
        checks that y0 satisfies the constraints (naming the one it violates
        and by how much) and that the mass matrix is regular there.

    Raises
    ------
    TypeError
        ``method`` is not one of the three.
    ValueError
        The equations were never formed, a constant has no value (named), a
        specified input has no value (named), a parameter or input names
        nothing in the equations, or an expression cannot be compiled.
    CompileError
        No C compiler, or it failed.

    Examples
    --------
    A pendulum by Kane's method equals the built-in scene:

    >>> import sympy
    >>> from sympy.physics.mechanics import (KanesMethod, Particle, Point, ReferenceFrame,
    ...                                      dynamicsymbols)
    >>> th, w = dynamicsymbols("theta omega")
    >>> g, l, m = sympy.symbols("g l m", positive=True)
    >>> N = ReferenceFrame("N"); A = N.orientnew("A", "Axis", (th, N.z))
    >>> A.set_ang_vel(N, w * N.z)
    >>> O = Point("O"); O.set_vel(N, 0)
    >>> P = O.locatenew("P", l * A.x); P.v2pt_theory(O, N, A)
    l*omega(t)*A.y
    >>> kane = KanesMethod(N, [th], [w], kd_eqs=[th.diff() - w])
    >>> _ = kane.kanes_equations([Particle("bob", P, m)], [(P, m * g * N.x)])
    >>> pend = mp.mechanics(kane, {"g": 9.81, "l": 1.0, "m": 1.0})
    >>> s = mp.solve(pend, (0, 2), [1.0, 0.0], rtol=1e-10, atol=1e-12)
    >>> ref = mp.solve(mp.scenes.Pendulum(g=9.81, length=1.0), (0, 2), [1.0, 0.0],
    ...                rtol=1e-10, atol=1e-12)
    >>> bool(np.abs(s.y[:, -1] - ref.y[:, -1]).max() < 1e-8)
    True
    >>> A, B = pend.linearize([0.0, 0.0])
    >>> np.round(A, 6).tolist()                  # [[0, 1], [-g/l, 0]]
    [[0.0, 1.0], [-9.81, 0.0]]
    """
    params = _check_params(params)
    if specified is not None and not isinstance(specified, dict):
        raise TypeError("specified must be a dict {input name: value or f(t, y)}, got "
                        f"{type(specified).__name__}")
    spec = {getattr(k, "name", None) or (k.func.__name__ if hasattr(k, "func") and
                                         not isinstance(k, str) else k): v
            for k, v in (specified or {}).items()}
    from .. import _progress
    steps = ("reading the model", "deriving the equations", "printing C", "compiling")
    with _progress.Stages("mp.mechanics", steps) as bar:       # shown past a second
        bar.stage(steps[0])
        return _mechanics_build(method, params, spec, baumgarte, bar, steps)


def _mechanics_build(method, params, spec, baumgarte, bar, steps):
    """mechanics' work, its stages told to ``bar``."""
    import hashlib

    from .. import _core
    from . import build
    from .multibody import MechanicsScene, SymPyForm, _digest, finish, mechanics_parts
    ir, info, parts = mechanics_parts(method, params, spec, baumgarte)
    for module in ("multibody.py", "kinematics.py"):       # what derives the stored meta
        with open(os.path.join(os.path.dirname(__file__), module), "rb") as f:
            parts.append(hashlib.sha256(f.read()).hexdigest())
    from .kinematics import drawing_key
    parts.append(drawing_key(method))                      # and the drawing's bodies
    values = dict(params)
    functions = {}
    for nm in info["inputs"]:
        v = spec[nm]
        if callable(v):
            functions[nm] = v
            values[nm] = 0.0
        else:
            values[nm] = v
    h = hashlib.sha256()
    _digest([e for part in parts[:4] for e in part], h)
    key = _key("mechanics", [h.hexdigest()] + parts[4:], ir.param_names)
    meta = build.load_meta(key)
    if meta is None or meta.get("param_names") != ir.param_names or "mechanics" not in meta:
        from . import codegen
        bar.stage(steps[1])
        finish(ir, info)
        bar.stage(steps[2])
        source = codegen.c_source(ir, _core.STATUS)
        meta = _meta(ir, source)
        meta["mechanics"] = info
        # the drawing of its bodies (mp.live.animate): their kinematics, printed as C
        from .kinematics import model_drawing
        info["drawing"] = model_drawing(method, ir)
        build.store_meta(key, meta)
    bar.stage(steps[3])
    scene = MechanicsScene(meta, values, functions=functions)
    scene._sympy = SymPyForm(method, ir)          # in memory: what a page that simulates prints
    return scene
