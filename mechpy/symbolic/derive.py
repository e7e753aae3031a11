"""Derive a user's equations of motion with SymPy, as blocks of expressions.

The result of :func:`lagrangian_ir` or :func:`equations_ir` is an :class:`IR`:
plain SymPy expressions in a fixed set of symbols (time ``mp_t``, the state
``mp_y0..``, the user's parameter symbols and, for the Jacobian, the unknowns
``mp_z0..`` of the linear system), which the C printer (:mod:`.codegen`) and
the NumPy backend (:mod:`.scene`) both consume.  Nothing here inverts a matrix:
the mass matrix is printed and solved numerically at each evaluation.

For a Lagrangian L(q, q', t) with n coordinates and k holonomic constraints
g(q, t) = 0 the blocks are

* ``A`` (n + k, n + k) = [[M, C^T], [C, 0]] with M = d2L/dq'dq' and
  C = dg/dq, and ``b`` (n + k) = [F + Q, -(dg'/dq q' + dg'/dt) - 2 alpha g'
  - beta^2 g] with F = dL/dq - (dp/dq) q' - dp/dt, p = dL/dq' and
  g' = C q' + dg/dt (Baumgarte's stabilisation), so that A [q'', -lambda] = b;
* ``D`` (n + k, 2n): [db/dq - (dA/dq) z, db/dq' - (dA/dq') z] evaluated at the
  solution z of A z = b; the Jacobian of q'' is the first n rows of A^-1 D;
* ``energy`` (1): the Jacobi integral h = sum q' dL/dq' - L;
* ``momenta`` (n): dL/dq';
* ``g`` (2k, with constraints): g and g' = C q' + dg/dt;
* ``lag`` (1 + 2n + 3n^2): L, dL/dq, dL/dq', d2L/dqdq, d2L/dqdq'
  ([a][b] = d2L/dq_a dq'_b), d2L/dq'dq' (row-major), in q = y[:n], q' = y[n:].
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import sympy as sp
from sympy.physics.mechanics import dynamicsymbols

from . import _sympy_private as _private

#: Default Baumgarte stabilisation (alpha, beta) in 1/s: the constraint error
#: obeys g'' + 2 alpha g' + beta^2 g = 0, critically damped.
BAUMGARTE = (5.0, 5.0)


@dataclass
class IR:
    """Blocks of SymPy expressions for one system (see the module docstring)."""

    kind: str                       # "lagrangian" or "equations"
    n: int                          # state dimension
    nc: int                         # coordinates (lagrangian) or n (equations)
    k: int                          # constraints
    nq: int                         # second-order split for symplectic methods (0: none)
    T: sp.Symbol
    Y: list
    P: list
    Z: list
    names: list                     # coordinate / state names
    param_names: list
    blocks: dict = field(default_factory=dict)
    cyclic: list = field(default_factory=list)
    equations: list = field(default_factory=list)
    #: the user's expressions in the plain symbols, by name ("L", "rhs[0]", ...)
    sources: dict = field(default_factory=dict)
    #: plain symbol -> the symbol shown in messages (theta, theta', t)
    display: dict = field(default_factory=dict)
    #: the Jacobian's nonzero entries [(i, j), ...] from its symbolic zeros
    #: (equations), or None: their band serves radau's band LU and grouped
    #: differences (integrate.solve's jac_sparsity)
    jac_nonzeros: list | None = None

    def show(self, e) -> str:
        """e as text in the user's names."""
        return str(sp.sympify(e).xreplace(self.display))


def coordinates(names):
    """Generalized coordinates as SymPy functions of time.

    Parameters
    ----------
    names : str or sequence of str
        Names separated by spaces or commas (``"theta1 theta2"``), as
        :func:`sympy.physics.mechanics.dynamicsymbols` takes them.

    Returns
    -------
    list of sympy.Function
        One function of ``t`` per name (a list even for one name); ``q.diff()``
        (or ``q.diff(t)``) is its velocity.  The time symbol is
        ``sympy.Symbol("t")``.
    """
    if not isinstance(names, str):
        try:
            names = " ".join(str(s) for s in names)
        except TypeError:
            raise TypeError("names must be a string of coordinate names or a sequence of "
                            "strings") from None
    if not names.strip():
        raise ValueError("names must name at least one coordinate")
    q = dynamicsymbols(names)
    return list(q) if isinstance(q, (list, tuple)) else [q]


def _as_list(x, what):
    if x is None:
        return []
    if isinstance(x, sp.MatrixBase):
        return list(x)
    if isinstance(x, (list, tuple)):
        return [sp.sympify(e) for e in x]
    return [sp.sympify(x)]


def _coordinate_list(q, what="q"):
    qs = _as_list(q, what)
    t = _private.time()
    out = []
    for i, qi in enumerate(qs):
        if isinstance(qi, sp.Symbol) and qi != t:
            out.append(qi)          # plain symbols accepted for first-order states
            continue
        if not (isinstance(qi, sp.core.function.AppliedUndef) and qi.args == (t,)):
            raise TypeError(f"{what}[{i}] = {qi} is not a coordinate: make coordinates with "
                            "mp.coordinates('q1 q2 ...') (functions of t)")
        out.append(qi)
    if not out:
        raise ValueError(f"{what} must hold at least one coordinate")
    if len(set(out)) != len(out):
        raise ValueError(f"{what} holds a coordinate twice")
    return out


def _name(qi):
    return qi.func.__name__ if isinstance(qi, sp.core.function.AppliedUndef) else qi.name


def _params(params, exprs, t, allowed_extra=(), states=()):
    """Parameter symbols in the order of ``params``; checks every free symbol
    has a value and no two symbols share a name.

    A key that names no symbol of the expressions is a parameter all the same
    (an event may be its only reader: ``mp.events.impact(..., restitution="e")``),
    bound to a plain Symbol of that name that no expression holds.  A
    misspelt key is caught where it can be told apart: the symbol it was meant
    for is then left without a value, and the message names the keys no
    expression uses.  A key that names one of ``states`` (the states'
    names) or the time ``t`` is refused: those are not parameters."""
    if params is None:
        params = {}
    if not isinstance(params, dict):
        raise TypeError("params must be a dict {name: value}")
    free = set()
    for e in exprs:
        free |= {s for s in e.free_symbols if s != t}
    free -= set(allowed_extra)
    by_name = {}
    for s in sorted(free, key=lambda s: (s.name, _assumptions(s))):
        other = by_name.setdefault(s.name, s)
        if other is not s:
            raise ValueError(
                f"two different symbols are named {s.name!r} (assumptions "
                f"{_assumptions(other)} and {_assumptions(s)}): SymPy treats them as "
                "different symbols, a parameter is one value; make every "
                f"{s.name!r} the same symbol")
    missing = sorted(set(by_name) - set(params))
    unused = [k for k in params if k not in by_name]
    if missing:
        hint = (" (the time is sympy.Symbol('t') with no assumptions, as mp.coordinates "
                "uses it)" if "t" in missing else "")
        if unused:
            hint += (f"; params names {unused}, which no expression of the system uses: "
                     "misspelt?")
        raise ValueError(f"symbol(s) {missing} have no value: give them in params "
                         f"(params={{{', '.join(repr(m) + ': ...' for m in missing)}}})"
                         + hint)
    for k in unused:
        if k == "t" or k in states:
            raise ValueError(f"params {k!r} names {'the time' if k == 't' else 'a state'} of "
                             f"the system, not a parameter (its symbols: {sorted(by_name)})")
        if _RESERVED.match(k):
            raise ValueError(f"params {k!r} is a name mechpy reserves for its own variables: "
                             "rename it")
    return list(params), [by_name[k] if k in by_name else sp.Symbol(k) for k in params]


def _assumptions(s):
    """A symbol's assumptions as given (for a message)."""
    a = {k: v for k, v in _private.assumptions_given(s).items()
         if not (k == "commutative" and v)}
    return "{" + ", ".join(f"{k}={v}" for k, v in sorted(a.items())) + "}" if a else "none"


#: Reserved names of the plain symbols (time, states, unknowns, parameters).
_RESERVED = re.compile(r"mp_(t|[ypzc]\d+)$")


def _check_input(e, what):
    """``e`` (a user's expression) is a real, finite SymPy expression:
    ValueError naming ``what`` and the culprit for an equation or condition,
    the imaginary unit, an infinite or out-of-range number, a reserved name."""
    # a Symbol is a Boolean to SymPy (it may stand for a truth value): a state or a
    # parameter given as a right-hand side (x' = v) is an expression here
    if isinstance(e, sp.core.relational.Relational) or (
            isinstance(e, sp.logic.boolalg.Boolean) and not isinstance(e, sp.Symbol)):
        raise ValueError(f"{what} = {e} is an equation or a condition, not an expression "
                         "(give the expression itself" + (": the right-hand side f of "
                                                          "y' = f)" if what.startswith("rhs")
                                                          else ")"))
    if not isinstance(e, sp.Expr) or isinstance(e, sp.MatrixBase):
        raise TypeError(f"{what} must be a scalar SymPy expression, got "
                        f"{type(e).__name__}")
    for a in e.atoms(sp.Number, sp.NumberSymbol, type(sp.I), sp.Symbol):
        if a.is_Symbol:
            if _RESERVED.match(a.name):
                raise ValueError(f"{what} uses the symbol {a.name}, a name mechpy reserves "
                                 "for its own variables: rename it")
            continue
        if a.is_extended_real is False:
            raise ValueError(f"{what} contains the imaginary unit I ({_where(e, a)}): a "
                             "compiled system is real")
        if a.is_finite is False or a is sp.S.NaN:
            raise ValueError(f"{what} contains {a}, not a finite number")
        try:
            v = float(a)
        except (TypeError, ValueError, OverflowError):
            v = float("inf")
        if not abs(v) < float("inf"):
            raise ValueError(f"{what} contains the number {sp.Float(a, 5)} ({_where(e, a)}), "
                             "beyond the range of double precision (about 1.8e308)")


def _where(e, a):
    """The smallest term of e that holds the atom a, with a shortened (for a
    message)."""
    best = e
    for node in sp.preorder_traversal(e):
        if node.has(a) and node.count_ops() < best.count_ops() and node != a:
            best = node
    return str(best.xreplace({a: sp.Symbol(str(sp.Float(a, 5)))}) if a.is_Number else best)


#: Functions whose derivatives cannot be printed (unevaluated, Heaviside,
#: DiracDelta): a culprit of these kinds is named through the user's function
#: that leads to it, not as one of the same kind in the input.
_NONSMOOTH = ("Abs", "sign", "Max", "Min", "floor", "ceiling", "frac", "Heaviside",
             "DiracDelta", "re", "im", "arg")


def explain(ir, what, culprit, reason, numpy_ok=True) -> str:
    """The message for an expression ``culprit`` of block ``what`` that cannot
    be evaluated: where the user wrote it (or a function of the same kind),
    or, when it comes from a derivative, which of the user's functions has no
    usable derivative."""
    shown = str(sp.Float(culprit, 5)) if culprit.is_Number else ir.show(culprit)
    fix = "; rewrite it" + (" or use backend='numpy'" if numpy_ok else "")
    for name, src in ir.sources.items():
        if src.has(culprit):
            return f"{name} contains {shown}: {reason}{fix}"
    for name, src in ir.sources.items():
        same = [x for x in sp.preorder_traversal(src) if x.func == culprit.func]
        if same and not culprit.is_Atom and type(culprit).__name__ not in _NONSMOOTH \
                and culprit.func not in (sp.Derivative, sp.Subs):
            return f"{name} contains {ir.show(same[0])}: {reason}{fix}"
    rough = {}      # the user's functions whose first or second derivative holds it
    kind = culprit.func
    for name, src in ir.sources.items():
        for f in sp.preorder_traversal(src):
            if not f.is_Function or isinstance(f, sp.core.function.AppliedUndef):
                continue
            for v in f.free_symbols:
                d1 = sp.diff(f, v)
                if any(x.func == kind for x in sp.preorder_traversal(d1)) or any(
                        x.func == kind for x in sp.preorder_traversal(sp.diff(d1, v))):
                    rough.setdefault(ir.show(f), name)
    if rough:
        where = ", ".join(f"{f} (in {name})" for f, name in sorted(rough.items()))
        return (f"{where}: its derivative, {shown} (needed by {what}), cannot be compiled. "
                "Functions without a derivative mechpy can print (gamma and loggamma, "
                "whose derivative is polygamma; functions SymPy leaves underived) are "
                "refused through the Jacobian (the equations of motion and their Jacobian "
                "differentiate the system): write the expression with other functions")
    return (f"{what} (derived from {', '.join(ir.sources)}) contains {shown}: "
            f"{reason}{fix}")


def _check_derived(ir):
    """No unevaluated derivative (Derivative, Subs) in the blocks: SymPy could
    not differentiate one of the user's functions (one that neither SymPy nor
    _Diff knows how to differentiate)."""
    seen = set()
    names = {"A": "the equations of motion (mass matrix)", "b": "the equations of motion",
             "D": "the Jacobian", "J": "the Jacobian", "f": "the equations", "g":
             "the constraints", "lag": "the derivatives of L", "momenta": "the momenta",
             "energy": "the energy"}
    for key, exprs in ir.blocks.items():
        stack = [sp.sympify(e) for e in exprs]
        while stack:
            x = stack.pop()
            if not x.args or x in seen:
                continue
            seen.add(x)
            if isinstance(x, (sp.Derivative, sp.Subs)):
                raise ValueError(explain(ir, names.get(key, key), x,
                                         "SymPy leaves this derivative unevaluated",
                                         numpy_ok=False))
            stack.extend(x.args)


def _check_functions(e, what):
    """No function of t other than the coordinates may remain."""
    rest = e.atoms(sp.core.function.AppliedUndef) | e.atoms(sp.Derivative)
    if rest:
        raise ValueError(f"{what} depends on {sorted(map(str, rest))}, which are not "
                         "coordinates or their first derivatives")


class _Diff:
    """Partial derivatives of expressions in plain symbols, memoised.

    SymPy's ``diff`` builds a ``Derivative`` object per call and per
    sub-expression and asks assumptions of every intermediate; here the
    elementary rules (sums, products, powers, the trigonometric, hyperbolic,
    exponential and logarithmic functions of one argument) are applied
    directly, each sub-expression's derivative and free symbols are computed
    once per variable, and anything else falls back to ``sympy.diff``.  The
    results are equal (``==`` after SymPy's automatic evaluation) to
    ``sympy.diff``'s up to the order of factors and terms.

    The non-smooth functions are differentiated almost everywhere, where
    SymPy leaves an unevaluated derivative or a distribution: Abs' = sign,
    sign' = floor' = ceiling' = 0, Max' and Min' the derivative of the
    argument that is the maximum (minimum), as a Piecewise; Piecewise piece by
    piece.  A Jacobian is then exact wherever the function is smooth and the
    one-sided value at its kinks and jumps (at a jump of sign(v), such as dry
    friction's -mu g sign(v), it has no term for the jump).
    """

    def __init__(self):
        self._memo = {}
        self._free = {}
        t = sp.functions
        d1 = {
            t.sin: lambda a: t.cos(a),
            t.cos: lambda a: -t.sin(a),
            t.tan: lambda a: 1 + t.tan(a) ** 2,
            t.exp: lambda a: t.exp(a),
            t.log: lambda a: 1 / a,
            t.sinh: lambda a: t.cosh(a),
            t.cosh: lambda a: t.sinh(a),
            t.tanh: lambda a: 1 - t.tanh(a) ** 2,
            t.asin: lambda a: 1 / sp.sqrt(1 - a ** 2),
            t.acos: lambda a: -1 / sp.sqrt(1 - a ** 2),
            t.atan: lambda a: 1 / (1 + a ** 2),
        }
        self._d1 = d1

    def _minmax(self, e, v):
        """d Max(a_1, ..., a_n)/dv (or Min's) as a Piecewise: a_i' where a_i is
        the largest (smallest) of the arguments, the first such i at a tie."""
        args = e.args
        better = (lambda a, b: a >= b) if isinstance(e, sp.Max) else (lambda a, b: a <= b)
        pieces = []
        for i, a in enumerate(args[:-1]):
            cond = sp.And(*[better(a, b) for j, b in enumerate(args) if j != i])
            pieces.append((self(a, v), cond))
        pieces.append((self(args[-1], v), True))
        return sp.Piecewise(*pieces)

    def free(self, e):
        """The free symbols of ``e`` (memoised)."""
        f = self._free.get(e)
        if f is None:
            if e.is_Symbol:
                f = frozenset((e,))
            elif not e.args:
                f = frozenset()
            elif e.is_Add or e.is_Mul or e.is_Pow or e.is_Function:
                f = frozenset().union(*(self.free(a) for a in e.args))
            else:
                f = frozenset(e.free_symbols)
            self._free[e] = f
        return f

    def __call__(self, e, v):
        """d e / d v for a plain symbol ``v``."""
        if v not in self.free(e):
            return sp.S.Zero
        if e is v:
            return sp.S.One
        key = (e, v)
        r = self._memo.get(key)
        if r is not None:
            return r
        if e.is_Add:
            r = sp.Add(*[self(a, v) for a in e.args])
        elif e.is_Mul:
            args = e.args
            terms = []
            for i, a in enumerate(args):
                if v in self.free(a):
                    da = self(a, v)
                    if da != 0:
                        terms.append(sp.Mul(*args[:i], da, *args[i + 1:]))
            r = sp.Add(*terms)
        elif e.is_Pow and v not in self.free(e.exp):
            b, x = e.args
            r = x * b ** (x - 1) * self(b, v)
        elif e.is_Function and len(e.args) == 1 and type(e) in self._d1:
            a = e.args[0]
            r = self._d1[type(e)](a) * self(a, v)
        elif isinstance(e, (sp.Abs, sp.sign, sp.floor, sp.ceiling)):
            # almost everywhere: |a|' = sign(a) a', and sign, floor and ceiling
            # are piecewise constant (their jumps, a set of measure zero, have
            # no derivative a solver could use: a DiracDelta is no number)
            a = e.args[0]
            r = sp.sign(a) * self(a, v) if isinstance(e, sp.Abs) else sp.S.Zero
        elif isinstance(e, (sp.Max, sp.Min)):
            # the derivative of the argument that is the maximum (minimum): at
            # a tie the first argument's, a choice on a set of measure zero
            r = self._minmax(e, v)
        elif e.is_Piecewise:
            # piece by piece, the conditions kept (SymPy's diff would call
            # itself on the pieces, and refuse the rules above)
            r = sp.Piecewise(*[(self(x, v), c) for x, c in e.args])
        else:
            r = sp.diff(e, v)
        self._memo[key] = r
        return r


def lagrangian_ir(L, q, params=None, constraints=(), forces=None, baumgarte=None) -> IR:
    """The blocks of a Lagrangian system (see the module docstring)."""
    t = _private.time()
    qs = _coordinate_list(q)
    if any(isinstance(qi, sp.Symbol) for qi in qs):
        raise TypeError("coordinates of a Lagrangian must be functions of t: make them with "
                        "mp.coordinates('q1 q2 ...')")
    n = len(qs)
    L = sp.sympify(L)
    _check_input(L, "L")
    cons = _as_list(constraints, "constraints")
    if forces is None:
        Qf = [sp.S.Zero] * n
    else:
        Qf = _as_list(forces, "forces")
        if len(Qf) != n:
            raise ValueError(f"forces must have one entry per coordinate: got {len(Qf)} for "
                             f"{n} coordinate(s) {[_name(x) for x in qs]}")
    k = len(cons)
    alpha, beta = baumgarte_rates(baumgarte)

    T = sp.Symbol("mp_t")
    Q = [sp.Symbol(f"mp_y{i}") for i in range(n)]
    U = [sp.Symbol(f"mp_y{n + i}") for i in range(n)]
    d2s = {qi.diff(t): Ui for qi, Ui in zip(qs, U)}
    f2s = {qi: Qi for qi, Qi in zip(qs, Q)}

    def plain(e, what):
        _check_input(e, what)
        second = [d for d in e.atoms(sp.Derivative) if d.derivative_count > 1]
        if second:
            raise ValueError(f"{what} contains second derivatives {sorted(map(str, second))}")
        e = e.xreplace(d2s).xreplace(f2s)
        _check_functions(e, what)
        return e.xreplace({t: T})

    Lx = plain(L, "L")
    cx = [plain(g, f"constraints[{i}]") for i, g in enumerate(cons)]
    Fx = [plain(f, f"forces[{i}]") for i, f in enumerate(Qf)]
    for i, qi in enumerate(qs):
        if Q[i] not in Lx.free_symbols and U[i] not in Lx.free_symbols:
            raise ValueError(f"coordinate {_name(qi)} does not appear in L")
    for i, g in enumerate(cx):
        if set(U) & g.free_symbols:
            raise ValueError(f"constraints[{i}] depends on velocities: only holonomic "
                             "constraints g(q, t) = 0 are supported")
        if not (set(Q) & g.free_symbols):
            raise ValueError(f"constraints[{i}] does not depend on the coordinates")
    names, P = _params(params, [Lx] + cx + Fx, T, allowed_extra=Q + U,
                       states=[_name(qi) for qi in qs])

    # Derivatives are taken of the smallest pieces (SymPy's cost grows faster
    # than linearly with an expression's size): F and its Jacobian are
    # assembled from dL/dq, dp/dq, dp/dt and their own derivatives.
    V = Q + U
    d = _Diff()
    p = [d(Lx, Ui) for Ui in U]
    dLdq = [d(Lx, Qi) for Qi in Q]
    M = sp.Matrix(n, n, lambda i, j: d(p[i], U[j]))
    Pq = [[d(p[i], Q[j]) for j in range(n)] for i in range(n)]
    Pt = [d(p[i], T) for i in range(n)]
    rest = [sp.Add(*[Pq[i][j] * U[j] for j in range(n)], Pt[i], -Fx[i]) for i in range(n)]
    F = [dLdq[i] - rest[i] for i in range(n)]
    # d2L/dq_i dq_c (symmetric: the upper triangle is taken) and
    # d2L/dq_i dq'_c = dp_c/dq_i (already in Pq)
    Lqq = [[None] * n for _ in range(n)]
    for i in range(n):
        for c in range(i, n):
            Lqq[i][c] = Lqq[c][i] = d(dLdq[i], Q[c])
    Lqv = [Lqq[i] + [Pq[c][i] for c in range(n)] for i in range(n)]
    NA = n + k
    A = sp.zeros(NA, NA)
    A[:n, :n] = M
    b = list(F)
    gdots = []
    for c, g in enumerate(cx):
        Crow = [d(g, Qj) for Qj in Q]
        for j in range(n):
            A[n + c, j] = Crow[j]
            A[j, n + c] = Crow[j]
        gd = sum(Crow[j] * U[j] for j in range(n)) + d(g, T)
        gdots.append(gd)
        gdd = sum(d(gd, Q[j]) * U[j] for j in range(n)) + d(gd, T)
        b.append(-gdd - 2 * alpha * gd - beta ** 2 * g)
    Z = [sp.Symbol(f"mp_z{i}") for i in range(NA)]
    D = sp.zeros(NA, 2 * n)
    AZ = [sp.Add(*[A[i, j] * Z[j] for j in range(NA)]) for i in range(NA)]   # (A z)_i
    for i in range(NA):
        for c, v in enumerate(V):
            if i < n:   # d/dv of dL/dq_i - (sum_j Pq_ij U_j + Pt_i - Q_i)
                db = Lqv[i][c] - d(rest[i], v)
            else:
                db = d(b[i], v)
            D[i, c] = db - d(AZ[i], v)
    lag = ([Lx] + dLdq + p + [Lqv[a][c] for a in range(n) for c in range(n)]
           + [Lqv[a][n + c] for a in range(n) for c in range(n)] + list(M))
    energy = sum(U[i] * p[i] for i in range(n)) - Lx

    ir = IR("lagrangian", 2 * n, n, k, 0, T, Q + U, P, Z, [_name(x) for x in qs], names)
    ir.blocks = dict(A=list(A), b=b, D=list(D), energy=[energy], momenta=p, lag=lag)
    if k:
        ir.blocks["g"] = cx + gdots
    ir.sources = {"L": Lx, **{f"constraints[{i}]": g for i, g in enumerate(cx)},
                  **{f"forces[{i}]": f for i, f in enumerate(Fx) if forces is not None}}
    ir.display = {T: t, **{Qi: sp.Symbol(nm) for Qi, nm in zip(Q, ir.names)},
                  **{Ui: sp.Symbol(nm + "'") for Ui, nm in zip(U, ir.names)},
                  **{Zi: sp.Symbol(f"z{i}") for i, Zi in enumerate(Z)}}
    _check_derived(ir)
    others = set().union(*(e.free_symbols for e in cx + Fx)) if (cx or Fx) else set()
    ir.cyclic = [ir.names[i] for i in range(n)
                 if Q[i] not in Lx.free_symbols and Q[i] not in others]
    # separable: constant mass matrix, dL/dq of q alone, no forces or constraints
    velo = set(U) | {T}
    if (k == 0 and all(f == 0 for f in Fx) and all(not (e.free_symbols & (set(Q) | {T}))
                                                    for e in p)
            and all(not (e.free_symbols & velo) for e in dLdq)):
        ir.nq = n
    # the equations of motion as SymPy sees them, in the user's coordinates
    back = {**{Qi: qi for Qi, qi in zip(Q, qs)}, **{Ui: qi.diff(t) for Ui, qi in zip(U, qs)},
            T: t}
    acc = [qi.diff(t, 2) for qi in qs]
    lam = [sp.Symbol(f"lambda{c + 1}") for c in range(k)]
    eqs = []
    for i in range(n):
        lhs = sum(M[i, j].xreplace(back) * acc[j] for j in range(n))
        rhs = F[i].xreplace(back) + sum(lam[c] * A[n + c, i].xreplace(back) for c in range(k))
        eqs.append(sp.Eq(lhs, rhs, evaluate=False))
    eqs += [sp.Eq(g.xreplace(back), 0, evaluate=False) for g in cx]
    ir.equations = eqs
    return ir


def equations_ir(rhs, y, params=None, energy=None) -> IR:
    """The blocks of a first-order system y' = rhs(t, y): ``f`` (n), ``J``
    (n x n, df/dy row-major) and, when given, ``energy`` (1)."""
    t = _private.time()
    ys = _coordinate_list(y, "y")
    n = len(ys)
    fs = _as_list(rhs, "rhs")
    if len(fs) != n:
        raise ValueError(f"rhs must have one expression per state: got {len(fs)} for {n} "
                         f"state(s) {[_name(x) for x in ys]}")
    T = sp.Symbol("mp_t")
    Y = [sp.Symbol(f"mp_y{i}") for i in range(n)]
    sub = {yi: Yi for yi, Yi in zip(ys, Y)}

    def plain(e, what):
        _check_input(e, what)
        ders = [d for d in e.atoms(sp.Derivative)]
        if ders:
            raise ValueError(f"{what} contains derivatives {sorted(map(str, ders))}: a "
                             "first-order system's right-hand side depends on y and t only")
        e = e.xreplace(sub)
        _check_functions(e, what)
        return e.xreplace({t: T})

    fx = [plain(f, f"rhs[{i}]") for i, f in enumerate(fs)]
    ex = [] if energy is None else [plain(sp.sympify(energy), "energy")]
    names, P = _params(params, fx + ex, T, allowed_extra=Y, states=[_name(x) for x in ys])
    d = _Diff()
    J = [d(fx[i], Y[j]) for i in range(n) for j in range(n)]
    ir = IR("equations", n, n, 0, 0, T, Y, P, [], [_name(x) for x in ys], names)
    ir.blocks = dict(f=fx, J=J)
    ir.jac_nonzeros = [(i, j) for i in range(n) for j in range(n) if J[i * n + j] != 0]
    if ex:
        ir.blocks["energy"] = ex
    ir.sources = {**{f"rhs[{i}]": f for i, f in enumerate(fx)},
                  **({"energy": ex[0]} if ex else {})}
    ir.display = {T: t, **{Yi: sp.Symbol(nm) for Yi, nm in zip(Y, ir.names)}}
    _check_derived(ir)
    ir.equations = [sp.Eq(yi.diff(t) if not isinstance(yi, sp.Symbol) else
                          sp.Derivative(yi, t), f) for yi, f in zip(ys, fs)]
    return ir


def baumgarte_rates(baumgarte) -> tuple:
    """Baumgarte's (alpha, beta) (1/s): the default BAUMGARTE for None, else a
    checked pair of non-negative numbers (TypeError, ValueError)."""
    if baumgarte is None:
        baumgarte = BAUMGARTE
    try:
        alpha, beta = (float(x) for x in baumgarte)
    except (TypeError, ValueError):
        raise TypeError("baumgarte must be a pair (alpha, beta) of numbers (1/s)") from None
    if not (alpha >= 0 and beta >= 0):
        raise ValueError(f"baumgarte (alpha, beta) must be non-negative, got {baumgarte}")
    return alpha, beta
