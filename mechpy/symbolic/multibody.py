"""Models as SymPy's mechanics module writes them, compiled: ``mp.mechanics``.

(Named ``multibody``, not ``mechanics``: a submodule of that name would replace
the function ``mechpy.symbolic.mechanics`` once imported.)

A :class:`sympy.physics.mechanics.KanesMethod` (after ``kanes_equations``), a
:class:`~sympy.physics.mechanics.LagrangesMethod` (after
``form_lagranges_equations``) or a :class:`~sympy.physics.mechanics.System`
(after ``form_eoms``) gives its equations as a mass matrix and a forcing
vector, ``M(q, u, t) x' = F(q, u, t)``.  They become the blocks of an
:class:`~mechpy.symbolic.derive.IR` of kind ``"mechanics"`` with the plain
symbols of :mod:`.derive` (time ``mp_t``, state ``mp_y0..``, unknowns
``mp_z0..``); :mod:`.codegen` prints them as C, where a dense LU solves the
linear system at each evaluation (no symbolic inverse).

The linear system, of size NA, in the unknowns z:

* Kane, with n coordinates (the last kh dependent, holonomic constraints
  f_h(q) = 0 with C = df_h/dq) and o speeds (the last m dependent, velocity
  constraints g_v = B(q, t) u + c(q, t) = 0): z = (q', u', mu), NA = n + o + kh,

      q' - C^T mu = f_k(q, u)                    (the kinematical equations)
      M(q) u'     = F(q, u) (- 2 alpha g_v on the m rows d/dt g_v)
      C q'        = -beta f_h                    (the holonomic drift damped)

  so that g_v' = -2 alpha g_v and f_h' = -beta f_h (the kinematical
  equations projected onto the tangent of f_h = 0: a velocity that breaks
  the holonomic constraint's rate never reaches the coordinates).
* Lagrange, with n coordinates, k holonomic constraints g_h(q, t) = 0 and the
  velocity-level constraints c (their rates, then the nonholonomic ones):
  SymPy's ``mass_matrix_full`` and ``forcing_full``, z = (q', q'', lambda),
  the rows of c' = 0 with Baumgarte's terms, c' + 2 alpha c + beta^2 g_h = 0.

Besides: ``G`` (the constraint residuals f_h, g_v), ``GJ`` (dG/dy), ``D``
(db/dv - (dA/dv) z for v the states and the specified inputs: the Jacobian and
the input matrix after one solve) and ``energy`` when the loads are constant
forces (T + V, or the Jacobi integral of L plus V).
"""
from __future__ import annotations

import math

import numpy as np
import sympy as sp

from .. import _core
from . import _sympy_private as _private
from .derive import IR, _assumptions, _check_derived, _check_input, _Diff, baumgarte_rates
from .scene import CompiledScene, _first_over, _state_scale

__all__ = ["mechanics_parts", "MechanicsScene", "SymPyForm"]


def _dag(exprs):
    """The distinct sub-expressions of ``exprs``, children before parents
    (each shared subtree once: SymPy's own traversals walk the tree, which
    for Kane's equations of a bicycle is millions of nodes)."""
    seen = set()
    order = []
    for root in exprs:
        stack = [(root, False)]
        while stack:
            x, done = stack.pop()
            if done:
                order.append(x)
                continue
            if x in seen:
                continue
            seen.add(x)
            stack.append((x, True))
            stack.extend((a, False) for a in x.args if a not in seen)
    return order


def _replace(e, mapping, memo):
    """e.xreplace(mapping) with the results of shared subtrees memoised."""
    r = memo.get(e)
    if r is not None:
        return r
    for x in _dag([e]):
        if x in memo:
            continue
        if x in mapping:
            memo[x] = mapping[x]
        elif not x.args:
            memo[x] = x
        else:
            args = [memo[a] for a in x.args]
            memo[x] = x if all(a is b for a, b in zip(args, x.args)) else x.func(*args)
    return memo[e]


def _digest(exprs, h):
    """Feed the structure of ``exprs`` (a DAG walk, not srepr's tree walk) to
    the hash ``h``."""
    ids = {}
    for x in _dag(exprs):
        if x.args:
            text = type(x).__name__ + "(" + ",".join(str(ids[a]) for a in x.args) + ")"
        else:
            text = sp.srepr(x)
        ids[x] = len(ids)
        h.update(text.encode() + b";")
    for x in exprs:
        h.update(f"root {ids[x]};".encode())


def _method(method):
    """(kind, eom method) of a KanesMethod, LagrangesMethod or System; a clear
    TypeError / ValueError when the equations were never formed."""
    from sympy.physics.mechanics import KanesMethod, LagrangesMethod
    try:
        from sympy.physics.mechanics import System
    except ImportError:       # SymPy < 1.13
        System = ()
    if System and isinstance(method, System):
        em = method.eom_method
        if em is None:
            raise ValueError("method: the System's equations of motion were never formed: "
                             "call system.form_eoms() first")
        method = em
    if isinstance(method, KanesMethod):
        if not _private.kane_formed(method):
            raise ValueError("method: the KanesMethod's equations were never formed: call "
                             "kane.kanes_equations(bodies, loads) first")
        if _private.kane_auxiliary_speeds(method):
            raise ValueError("method: auxiliary speeds (u_auxiliary) give constraint "
                             "forces, not motion: form the equations without them")
        return "kane", method
    if isinstance(method, LagrangesMethod):
        if method.eom is None:
            raise ValueError("method: the LagrangesMethod's equations were never formed: "
                             "call lagrange.form_lagranges_equations() first")
        return "lagrange", method
    raise TypeError("method must be a sympy.physics.mechanics KanesMethod, LagrangesMethod "
                    f"or System, got {type(method).__name__}")


def _name(f):
    if isinstance(f, sp.Derivative) and isinstance(f.expr, sp.core.function.AppliedUndef):
        return _name(f.expr) + "'" * f.derivative_count
    return f.func.__name__ if isinstance(f, sp.core.function.AppliedUndef) else str(f)


def _constant_loads_V(method, frame):
    """V = -sum F . r for the loads when every one is a force constant in the
    inertial frame (gravity), r measured from a point at rest in the frame that
    the point's position is defined from; None (no energy) otherwise."""
    from sympy.physics.vector import Point, ReferenceFrame
    loads = method.loads or []
    t = _private.time()
    V = sp.S.Zero
    for load in loads:
        where, vec = load[0], load[1]
        if isinstance(where, ReferenceFrame):
            if vec != 0:
                return None
            continue
        if not isinstance(where, Point) or frame is None:
            return None
        if vec.dt(frame).simplify() != 0 or any(
                isinstance(a, sp.core.function.AppliedUndef) and a.has(t)
                for a in vec.to_matrix(frame).atoms(sp.Function)):
            return None
        origin = _rest_point(where, frame)
        if origin is None:
            return None
        V -= vec.dot(where.pos_from(origin))
    return V


def _rest_point(P, frame):
    """A point of P's position tree whose velocity in ``frame`` was set to
    zero, or None."""
    seen, todo = {P}, [P]
    while todo:
        x = todo.pop(0)
        v = _private.point_velocity_set(x, frame)
        if v is not None and v == 0:
            return x
        for o in _private.point_neighbours(x):
            if o not in seen:
                seen.add(o)
                todo.append(o)
    return None


def mechanics_parts(method, params, specified=None, baumgarte=None):
    """The plain (not yet differentiated) blocks of a mechanics model.

    Returns (ir, key_parts): ``ir`` holds A, b, G, energy; :func:`finish`
    adds the derivatives.  Raises the errors :func:`mechpy.mechanics` lists.
    """
    kind, m = _method(method)
    t = _private.time()
    alpha, beta = baumgarte_rates(baumgarte)
    q = list(m.q)
    n = len(q)
    if kind == "kane":
        u = list(m.u)
        kdd = m.kindiffdict()
        qd_expr = [kdd[qi.diff(t)] for qi in q]
        fh = _private.kane_holonomic(m)
        kh = len(fh)
        mdep = len(_private.kane_dependent_speeds(m))
        o = len(u)
        Mdyn = m.mass_matrix
        Fdyn = list(m.forcing)
        gv = _private.kane_velocity_constraints(m, u) if mdep else []
        qdot_sub = dict(kdd)
        ind = list(range(n - kh)) + [n + i for i in range(o - mdep)]
    else:
        u = [qi.diff(t) for qi in q]
        o = n
        fh = _private.lagrange_holonomic(m)
        kh = len(fh)
        cv = list(m.coneqs) if m.coneqs else []
        mdep = len(cv)
        gv = cv
        qdot_sub = {}
        ind = list(range(n - kh)) + [n + i for i in range(n - mdep)]
    NS = n + o
    T = sp.Symbol("mp_t")
    Y = [sp.Symbol(f"mp_y{i}") for i in range(NS)]

    # specified inputs: the dynamicsymbols left in the equations besides q, u
    known = set(q) | set(u) | {qi.diff(t) for qi in q}
    spec = {} if specified is None else specified
    if not isinstance(spec, dict):
        raise TypeError("specified must be a dict {input name: value or f(t, y)}")
    if kind == "kane":
        probe = list(Mdyn) + Fdyn + qd_expr + gv + fh
    else:
        probe = list(m.mass_matrix_full) + list(m.forcing_full) + fh
    probe = [sp.sympify(e) for e in probe]
    funcs = {f for f in _dag(probe) if isinstance(f, sp.core.function.AppliedUndef)
             and f.args == (t,)}
    inputs = sorted((f for f in funcs if f not in known), key=_name)
    names_in = [_name(f) for f in inputs]
    missing = [nm for nm in names_in if nm not in spec]
    if missing:
        raise ValueError(f"specified input(s) {missing} have no value: give specified="
                         f"{{{', '.join(repr(x) + ': value or f(t, y)' for x in missing)}}}")
    unknown = [k for k in spec if k not in names_in]
    if unknown:
        raise ValueError(f"specified {unknown} name no input of the equations "
                         f"(its inputs: {names_in})")
    R = [sp.Symbol(f"mp_r{i}") for i in range(len(inputs))]

    sub = {}
    for i, qi in enumerate(q):
        sub[qi] = Y[i]
    for i, ui in enumerate(u):
        sub[ui] = Y[n + i]
    for f, r in zip(inputs, R):
        sub[f] = r
    memo1, memo2 = {}, {}
    sub[t] = T

    def plain(e, what):
        e = sp.sympify(e)
        if isinstance(e, sp.core.relational.Relational) or not isinstance(e, sp.Expr):
            _check_input(e, what)
        nodes = _dag([e])
        leaves = [a for a in nodes if not a.args and (a.is_Number or a.is_NumberSymbol
                                                       or a.is_Symbol or a is sp.I)]
        if leaves:
            _check_input(sp.Add(*leaves, evaluate=False), what)
        if qdot_sub:
            e = _replace(e, qdot_sub, memo1)
        e = _replace(e, sub, memo2)
        rest = {x for x in _dag([e]) if isinstance(x, (sp.Derivative,
                                                         sp.core.function.AppliedUndef))}
        if rest:
            raise ValueError(f"{what} depends on {sorted(map(str, rest))}, which are not "
                             "coordinates, speeds or specified inputs")
        return e

    ir = IR("mechanics", NS, n, 0, 0, T, Y, [], [], [_name(x) for x in q + u], [])
    if kind == "kane":
        NA = NS + kh
        A = sp.zeros(NA, NA)
        b = [sp.S.Zero] * NA
        fhx = [plain(g, f"configuration_constraints[{i}]") for i, g in enumerate(fh)]
        Cm = [[sp.diff(g, Y[j]) for j in range(n)] for g in fhx]
        for i in range(n):
            A[i, i] = sp.S.One
            b[i] = plain(qd_expr[i], f"the kinematical equation of {_name(q[i])}")
            for c in range(kh):
                A[i, NS + c] = -Cm[c][i]
        for i in range(o):
            for j in range(o):
                A[n + i, n + j] = plain(Mdyn[i, j], "the mass matrix")
            b[n + i] = plain(Fdyn[i], "the forcing vector")
        gvx = [plain(g, f"velocity_constraints[{i}]") for i, g in enumerate(gv)]
        for c in range(mdep):
            b[n + o - mdep + c] -= 2 * alpha * gvx[c]
        for c in range(kh):
            for j in range(n):
                A[NS + c, j] = Cm[c][j]
            b[NS + c] = -beta * fhx[c]
        res = fhx + gvx
        res_names = ([f"configuration constraint {i} ({fh[i]} = 0)" for i in range(kh)]
                     + [f"velocity constraint {i} ({gv[i]} = 0)" for i in range(mdep)])
    else:
        Mf = m.mass_matrix_full
        Ff = list(m.forcing_full)
        NA = Mf.shape[0]
        A = sp.Matrix(NA, NA, lambda i, j: plain(Mf[i, j], "the mass matrix"))
        b = [plain(f, "the forcing vector") for f in Ff]
        fhx = [plain(g, f"hol_coneqs[{i}]") for i, g in enumerate(fh)]
        gvx = [plain(g, f"coneqs[{i}]") for i, g in enumerate(gv)]
        for c in range(mdep):
            b[NS + c] -= 2 * alpha * gvx[c] + (beta ** 2 * fhx[c] if c < kh else 0)
        res = fhx + gvx
        res_names = ([f"holonomic constraint {i} ({fh[i]} = 0)" for i in range(kh)]
                     + [f"velocity-level constraint {i} ({gv[i]} = 0)" for i in range(mdep)])

    # the energy, when the loads are constant forces
    frame = _private.kane_inertial(m) if kind == "kane" else m.inertial
    V = _constant_loads_V(m, frame)
    energy = None
    if V is not None:
        if kind == "kane":
            from sympy.physics.mechanics import kinetic_energy, potential_energy
            bodies = list(m.bodies or [])
            if bodies and frame is not None:
                energy = kinetic_energy(frame, *bodies) + potential_energy(*bodies) + V
        else:
            L = m._L[0] if isinstance(m._L, sp.MatrixBase) else sp.sympify(m._L)
            qd = [qi.diff(t) for qi in q]
            energy = sum(v * sp.diff(L, v) for v in qd) - L + V
    ex = [] if energy is None else [plain(energy, "the energy")]

    # the constants: every free symbol other than t
    allx = list(A) + b + res + ex
    free = set()
    for e in allx:
        free |= e.free_symbols
    free -= set(Y) | set(R) | {T}
    by_name = {}
    for s in sorted(free, key=lambda s: (s.name, _assumptions(s))):
        other = by_name.setdefault(s.name, s)
        if other is not s:
            raise ValueError(f"two different symbols are named {s.name!r} (assumptions "
                             f"{_assumptions(other)} and {_assumptions(s)}): make them one")
    params = {} if params is None else params
    missing = sorted(set(by_name) - set(params))
    if missing:
        raise ValueError(f"constant(s) {missing} have no value: give them in params "
                         f"(params={{{', '.join(repr(x) + ': ...' for x in missing)}}})")
    extra = [k for k in params if k not in by_name]
    if extra:
        raise ValueError(f"params {extra} name no constant of the equations (its constants: "
                         f"{sorted(by_name)})")
    clash = [nm for nm in names_in if nm in by_name]
    if clash:
        raise ValueError(f"the specified input(s) {clash} share their name with a constant: "
                         "rename one")
    pnames = list(params)
    P = [by_name[k] for k in pnames] + R
    ir.P = P
    ir.param_names = pnames + names_in
    ir.k = 0
    ir.Z = [sp.Symbol(f"mp_z{i}") for i in range(NA)]
    ir.blocks = dict(A=list(A), b=b, G=res)
    if ex:
        ir.blocks["energy"] = ex
    ir.sources = {"the equations of motion": sp.Add(*b)}
    ir.display = {T: t, **{Yi: sp.Symbol(nm) for Yi, nm in zip(Y, ir.names)}}
    info = dict(method=kind, nq=n, nu=o, nres=len(res), res_names=res_names, ind=ind,
                inputs=names_in, na=NA)
    key_parts = [list(A), b, res, ex, [str(s) for s in P],
                 repr((kind, n, o, NA, ind, alpha, beta))]
    return ir, info, key_parts


class SymPyForm:
    """What a :class:`MechanicsScene` keeps in memory of the model it was built
    from, for a page that simulates (:mod:`mechpy.live._simulate`): the linear
    system A z = b exactly as :mod:`.codegen` prints it as C (A row-major, NA x
    NA; dy/dt = z[:NS]; the dependent speeds' rows and the holonomic
    constraints' rows with their Baumgarte terms), the constraint residuals G,
    in the plain symbols (state ``Y``, time ``T``, parameters ``P`` in the
    order of ``param_names``), and the method, whose drawing's kinematics
    (:func:`.kinematics.model_kinematics`) are derived when a page asks.

    Made by every :func:`mechpy.mechanics` call, also when the compiled code
    comes from the cache (the expressions are derived before the cache is
    looked up); never stored on disk nor pickled (an unpickled scene has
    none)."""

    def __init__(self, method, ir):
        self.method = method
        self.A, self.b = list(ir.blocks["A"]), list(ir.blocks["b"])
        self.G = list(ir.blocks["G"])
        self.T, self.Y, self.P = ir.T, list(ir.Y), list(ir.P)
        self.param_names = list(ir.param_names)
        self._n = ir.n
        self._kin = None

    def kinematics(self) -> list:
        """The drawing's places then direction cosines (see
        :func:`.kinematics.model_kinematics`) in ``Y`` and ``P``; derived once."""
        if self._kin is None:
            from types import SimpleNamespace

            from .kinematics import model_kinematics
            ir = SimpleNamespace(n=self._n, Y=self.Y, T=self.T, P=self.P)
            back = {sp.Symbol(f"mp_p{j}"): s for j, s in enumerate(self.P)}
            self._kin = [sp.sympify(e).xreplace(back) for e in model_kinematics(self.method, ir)]
        return self._kin


def finish(ir, info):
    """The derivatives: D (NA x (NS + nr)) and GJ (nres x NS)."""
    d = _Diff()
    NA = info["na"]
    A = ir.blocks["A"]
    b = ir.blocks["b"]
    Z = ir.Z
    R = ir.P[len(ir.P) - len(info["inputs"]):] if info["inputs"] else []
    V = list(ir.Y) + list(R)
    AZ = [sp.Add(*[A[i * NA + j] * Z[j] for j in range(NA) if A[i * NA + j] != 0])
          for i in range(NA)]
    D = []
    for i in range(NA):
        for v in V:
            D.append(d(b[i], v) - d(AZ[i], v))
    ir.blocks["D"] = D
    ir.blocks["GJ"] = [d(g, y) for g in ir.blocks["G"] for y in ir.Y]
    _check_derived(ir)
    return ir


class MechanicsScene(CompiledScene):
    """The compiled scene of a SymPy mechanics model (see :func:`mechpy.mechanics`).

    State ``(q..., u...)`` in the method's order (independent, then dependent).
    """

    _EXTRA = {"residual": "mp_gen_residual", "residual_jac": "mp_gen_residual_jac",
              "linear": "mp_gen_linear"}

    #: the model's SymPy form (:class:`SymPyForm`), set by :func:`mechpy.mechanics`
    #: and kept by :meth:`replace`; None for an unpickled scene
    _sympy = None

    def __init__(self, meta, params, backend="c", numpy_fns=None, functions=None):
        super().__init__(meta, params, "c")
        info = meta["mechanics"]
        self._info = info
        # what the solve of each evaluation solves: A x' = b, its rows the
        # kinematical equations, the dynamic ones and the constraints' (when
        # the model has constraints); _diagnose says which part failed
        rows = "the kinematical equations, the mass matrix" + (
            ", the constraints' rows" if info["na"] > info["nq"] + info["nu"]
            or info["nres"] else "")
        what = (f"the linear system of {'Kane' if info['method'] == 'kane' else 'Lagrange'}'s "
                f"equations ({rows})")
        for w in list(self._context):
            self._context[w] = f"{w} of the compiled mechanics model: {what}"
        import ctypes
        for w, sym in self._EXTRA.items():
            self._addr[w] = ctypes.cast(getattr(self._lib, sym), ctypes.c_void_p).value
            self._context[w] = f"{w} of the compiled mechanics model: {what}"
        ab = getattr(self._lib, "mp_gen_Ab", None)
        self._addr_ab = None if ab is None else ctypes.cast(ab, ctypes.c_void_p).value
        inputs = info["inputs"]
        self._functions = dict(functions or {})
        bad = [k for k in self._functions if k not in inputs]
        if bad:
            raise ValueError(f"specified {bad} name no input (inputs: {inputs})")
        self._rslot = {nm: len(self._vec) - len(inputs) + i for i, nm in enumerate(inputs)}

    # -- outputs beyond the compiled scene's ----------------------------------
    def _raw(self, what, t, Y, vec=None):
        try:
            return self._raw_eval(what, t, Y, vec)
        except (_core.SingularityError, _core.NonFiniteError) as exc:
            if what not in ("rhs", "jac", "linear") or self._addr_ab is None:
                raise
            msg = self._diagnose(t, Y, self._vec if vec is None else vec)
            if msg is None:
                raise
            raise type(exc)(f"{what} of the compiled mechanics model: {msg}") from None

    def _diagnose(self, t, Y, vec):
        """What makes A x' = b fail at the first state of Y (rows (m, NS))
        where it fails, in the model's terms, or None when A and b look sound
        there (a solution that overflows): a row of A or b that is NaN or inf,
        named by its equation (the kinematical equation of a coordinate, the
        dynamic equation of a speed, a constraint's row), else the singular
        block (the mass matrix of the speeds, or the constraints' rows)."""
        info, names = self._info, self._meta["names"]
        na, n, ns = info["na"], info["nq"], self._dim
        kane = info["method"] == "kane"

        def row(i):
            if i < n:
                return f"the kinematical equation of {names[i]}"
            if i < ns:
                return (f"the dynamic equation of {names[i]}" if kane else
                        f"Lagrange's equation of {names[i - n]}")
            return f"the constraint row {i - ns}"
        for y in np.asarray(Y, dtype=float).reshape(-1, ns):
            v = np.asarray(self._with_inputs(t, y, vec) if self._functions else vec, float)
            ab = _core.compiled_eval(self._addr_ab, np.ascontiguousarray(v), float(t),
                                     np.ascontiguousarray(y)[None, :], na * na + na, "A, b")[0]
            A, b = ab[:na * na].reshape(na, na), ab[na * na:]
            at = f"at t = {float(t)!r}, y = {y.tolist()}"
            bad = np.argwhere(~np.isfinite(A))
            if bad.size:
                i, j = bad[0]
                return (f"{row(i)} has a coefficient {float(A[i, j])!r} (column {j}, the "
                        f"derivative of {names[j] if j < ns else 'a multiplier'}) {at}: a "
                        "0/0 or a singular expression of the model")
            bad = np.flatnonzero(~np.isfinite(b))
            if bad.size:
                i = bad[0]
                return (f"{row(i)} evaluates to {float(b[i])!r} {at} (its right-hand side: a "
                        "0/0 or a singular expression of the model, e.g. sin(q)/tan(q) at "
                        "q = 0)")
            tol = na * np.finfo(float).eps * max(np.abs(A).max(), np.finfo(float).tiny)
            if np.linalg.matrix_rank(A, tol=tol) == na:
                continue
            M = A[n:ns, n:ns]
            rank = np.linalg.matrix_rank(M, tol=tol)
            if rank < ns - n:
                zero = [names[n + j] for j in range(ns - n) if not np.any(M[:, j])]
                what = (f"; no equation holds the rate of {zero}" if zero else "")
                return (f"the mass matrix of the {'speeds' if kane else 'coordinates'} is "
                        f"singular {at} (rank {rank} of {ns - n}{what})")
            return (f"the constraints' rows are singular {at}: the constraints are dependent "
                    "or stationary there (their Jacobian is rank-deficient)")
        return None

    def _raw_eval(self, what, t, Y, vec=None):
        if what not in self._EXTRA and not (what in ("rhs", "jac") and self._functions):
            return super()._raw(what, t, Y, vec)
        NS = self._dim
        nr = len(self._info["inputs"])
        nout = {"residual": self._info["nres"], "residual_jac": self._info["nres"] * NS,
                "linear": NS * (NS + nr), "rhs": NS, "jac": NS * NS}[what]
        vec = self._vec if vec is None else vec
        if self._functions and what in ("rhs", "jac", "linear"):
            out = np.empty((Y.shape[0], nout))
            for i, row in enumerate(Y):
                v = self._with_inputs(t, row, vec)
                out[i] = _core.compiled_eval(self._addr[what], v, t, row[None, :], nout,
                                             self._context[what])[0]
            return out
        return _core.compiled_eval(self._addr[what], vec, t, Y, nout, self._context[what])

    def _with_inputs(self, t, y, vec):
        """The parameter vector ``vec`` with the callable inputs' values at
        (t, y) in their slots.  A value that is not a number is a TypeError, a
        NaN or inf a NonFiniteError naming the input (the model would report
        it as its own non-finite result)."""
        v = np.array(vec, dtype=float)
        for nm, f in self._functions.items():
            val = f(t, y)
            try:
                x = float(val)
            except (TypeError, ValueError):
                raise TypeError(f"specified[{nm!r}](t, y) must return a number, got "
                                f"{type(val).__name__}") from None
            if not math.isfinite(x):
                raise _core.NonFiniteError(
                    f"the specified input {nm!r} is {x!r} at t = {t!r}, y = "
                    f"{np.asarray(y).tolist()}: specified[{nm!r}](t, y) must return a finite "
                    "number")
            v[self._rslot[nm]] = x
        return v

    def _spec(self, method):
        if not self._functions:
            return super()._spec(method)
        addr, ctx, NS = self._addr["rhs"], self._context["rhs"], self._dim
        vec = self._vec

        # *p: a parameter row of solve_many(params=...) (the inputs' slots are
        # then overwritten by the callables' values), else the scene's vector
        def rhs(t, y, *p):
            v = self._with_inputs(t, y, np.asarray(p, dtype=float) if p else vec)
            return _core.compiled_eval(addr, v, t, np.ascontiguousarray(y)[None, :], NS,
                                       ctx)[0]
        return ("python", rhs, ())

    def symbolic(self):
        """Not available: the right-hand side solves M x' = F numerically at
        each evaluation (a symbolic solve is what this path avoids); the
        method object has the equations (``mass_matrix_full``,
        ``forcing_full``).  ValueError."""
        raise ValueError("a mechanics model has no symbolic field: its right-hand side "
                         "solves the mass-matrix system numerically; the equations are the "
                         "method's mass_matrix_full and forcing_full")

    def constraint_residual(self, y, t: float = 0.0) -> np.ndarray:
        """The constraint residuals at states y (dim, ...) -> (k, ...): the
        configuration constraints f_h(q) first, then the velocity constraints
        (Kane: B u + c; Lagrange: the holonomic constraints' rates and the
        nonholonomic constraints), in the units the model writes them;
        ``constraint_names`` says which is which."""
        out, rest = self._eval("residual", t, y)
        return self._shape(out, rest, (self._info["nres"],))

    @property
    def constraint_names(self) -> list:
        """What each row of :meth:`constraint_residual` is."""
        return list(self._info["res_names"])

    @property
    def coordinates(self) -> list:
        """The names of the generalized coordinates q, in the state's order
        (independent, then dependent), as PyDy's ``System.coordinates``."""
        return list(self._meta["names"][:self._info["nq"]])

    @property
    def speeds(self) -> list:
        """The names of the generalized speeds u (Kane) or of the coordinates'
        rates ``q'`` (Lagrange), in the state's order, as PyDy's
        ``System.speeds``."""
        return list(self._meta["names"][self._info["nq"]:])

    @property
    def states(self) -> list:
        """The names of the state components: :attr:`coordinates` then
        :attr:`speeds` (PyDy's ``System.states``).  :meth:`initial_state`
        takes a dict keyed by these names or by the model's dynamic symbols."""
        return list(self._meta["names"])

    @property
    def inputs(self) -> list:
        """The names of the specified inputs (their values are parameters)."""
        return list(self._info["inputs"])

    def energy(self, y, t: float = 0.0):
        """T + V (Kane, from the bodies and the constant loads) or the Jacobi
        integral of L plus V of the constant loads (Lagrange), for states
        (dim, ...) -> (...)."""
        if not self._meta["has_energy"]:
            raise AttributeError("this model has no energy: its loads are not all constant "
                                 "forces (gravity) and torque-free, or it has no bodies")
        return super().energy(y, t)

    def linearize(self, y0, t: float = 0.0, *, independent=None):
        """(A, B) of the motion linearised about the state y0, in the
        independent states: dx/dt = A x + B r for x the independent
        coordinates then speeds, r the specified inputs (B has no columns
        without inputs).  The dependent states follow from the constraints'
        Jacobian at y0 (as SymPy's Linearizer eliminates them); y0 should
        satisfy the constraints.  ``independent``: indices (or names) of the
        independent states, default the method's own (for Lagrange with
        constraints, the first coordinates and speeds).
        """
        NS = self._dim
        nr = len(self._info["inputs"])
        y0 = np.asarray(y0, dtype=float)
        if y0.shape != (NS,):
            raise ValueError(f"y0 must have shape ({NS},), got {y0.shape}")
        ind = self._info["ind"] if independent is None else [
            self._meta["names"].index(i) if isinstance(i, str) else int(i)
            for i in independent]
        dep = [i for i in range(NS) if i not in ind]
        L = self._raw("linear", float(t), y0[None, :]).reshape(NS, NS + nr)
        J, B = L[:, :NS], L[:, NS:]
        Tm = np.zeros((NS, len(ind)))
        Tm[ind, np.arange(len(ind))] = 1.0
        if dep:
            G = self._raw("residual_jac", float(t), y0[None, :]).reshape(-1, NS)
            if G.shape[0] != len(dep):
                raise ValueError(f"{G.shape[0]} constraints for {len(dep)} dependent states: "
                                 "give independent= with as many dependent states as "
                                 "constraints")
            Gd, Gi = G[:, dep], G[:, ind]
            try:
                Tm[dep] = -np.linalg.solve(Gd, Gi)
            except np.linalg.LinAlgError:
                names = [self._meta["names"][i] for i in dep]
                raise ValueError(f"linearize: the dependent states {names} cannot be solved "
                                 "from the constraints at y0 (their Jacobian there is "
                                 "singular): choose others with independent=[...]") from None
        return J[ind] @ Tm, B[ind]

    def project(self, y, t: float = 0.0, *, independent=None, tol: float = 1e-13,
                maxiter: int = 50) -> np.ndarray:
        """The state nearest y on the constraints with y's independent states:
        the dependent coordinates and speeds solved from the configuration and
        velocity constraints (Newton's method on the residuals, their Jacobian
        in C), for one state (dim,).  ValueError if it does not converge."""
        NS = self._dim
        y = np.array(y, dtype=float)
        if y.shape != (NS,):
            raise ValueError(f"y must have shape ({NS},), got {y.shape}")
        ind = self._info["ind"] if independent is None else [
            self._meta["names"].index(i) if isinstance(i, str) else int(i)
            for i in independent]
        dep = [i for i in range(NS) if i not in ind]
        if not dep:
            return y
        scale = max(1.0, float(np.max(np.abs(y))))
        for _ in range(maxiter):
            g = self._raw("residual", float(t), y[None, :])[0]
            if np.all(np.abs(g) <= tol * scale):
                return y
            G = self._raw("residual_jac", float(t), y[None, :]).reshape(-1, NS)
            y[dep] -= np.linalg.lstsq(G[:, dep], g, rcond=None)[0]
        raise ValueError(f"project: the constraints did not converge from y = {list(y)} "
                         f"(residuals {list(g)})")

    def _constrained(self) -> bool:
        return bool(self._info["nres"])

    def _check_rows(self, t0, Y, vec, first, many, tol, singular=True):
        nres = self._info["nres"]
        if nres:
            g = _core.compiled_eval(self._addr["residual"], vec, t0, Y, nres,
                                    self._context["residual"])
            bad = _first_over(g, tol * _state_scale(Y))
            if bad is not None:
                i, c = bad
                row = f" (row {first + i} of y0s)" if many else ""
                raise ValueError(f"y0{row} violates the {self._info['res_names'][c]} by "
                                 f"{g[i, c]:.3g}: place the initial state on the constraints "
                                 "(dependent coordinates from the configuration constraints, "
                                 "dependent speeds from the velocity constraints)")
        if singular:    # through _raw: its error says what is singular, where
            if self._functions:
                for row in Y:
                    self._raw("rhs", t0, row[None, :], vec)
            else:
                self._raw("rhs", t0, Y, vec)

    def replace(self, **changes):
        """A copy with some parameters (or specified inputs' values) changed
        (same library, no recompilation)."""
        unknown = set(changes) - set(self._params)
        if unknown:
            raise TypeError(f"unknown parameter(s) {sorted(unknown)}; parameters are "
                            f"{list(self._params)}")
        p = self.params
        fns = dict(self._functions)
        for k, v in changes.items():
            if callable(v):
                fns[k] = v
                p[k] = 0.0
            else:
                fns.pop(k, None)
                p[k] = v
        out = MechanicsScene(self._meta, p, functions=fns)
        out._sympy = self._sympy
        return out

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self._params.items()
                         if k not in self._functions)
        return f"MechanicsScene({self._info['method']}, states={self._meta['names']}, {args})"

    def __eq__(self, other):
        return (type(other) is MechanicsScene and self._meta["source"] == other._meta["source"]
                and self._params == other._params and self._functions == other._functions)

    def __hash__(self):
        return hash((self._meta["source"], tuple(self._params.items())))

    def __reduce__(self):
        return (_rebuild_mechanics, (self._meta, self._params, self._functions))


def _rebuild_mechanics(meta, params, functions):
    return MechanicsScene(meta, params, functions=functions)

