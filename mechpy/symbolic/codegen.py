"""Print an :class:`~mechpy.symbolic.derive.IR` as one C99 source file.

Each block of expressions becomes a static function that evaluates the block
after common subexpression elimination (SymPy's ``cse``), printed by SymPy's
C99 printer.  A small dense LU solver with partial pivoting (:data:`RUNTIME`),
sized by the compile-time dimension and working on stack arrays, solves the
mass-matrix system at each evaluation.  The exported functions and their
signatures are the ABI that ``mechpy._core`` binds (see :data:`ABI_VERSION`).
"""
from __future__ import annotations

import re

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.codeprinter import PrintMethodNotImplementedError

from . import _ctext  # csrc/gen/*.h's text, embedded at build time (csrc/meson.build)
from . import build
from .build import ABI_VERSION

#: Generated blocks (characters) from which a Lagrangian system's Jacobian
#: compiles as a translation unit of its own, beside the rest.
SPLIT = 60_000

#: The dense solver, written once (csrc/gen/lu.h): mp_lu_n and mp_lu_solve_n,
#: and mp_lu, mp_lu_solve for the NA x NA system.  NA is the size of the
#: linear system.
RUNTIME = "\n" + _ctext.LU


#: Mass-matrix systems of this size or smaller (NA = coordinates +
#: constraints) are solved in closed form by a Lagrangian system's mp_gen_rhs
#: (:func:`_closed_rhs`: A z = b by the blocks of A, each by its adjugate, A,
#: b and the solution printed as one block, so that they share their common
#: subexpressions and sin and cos of one angle become one sincos); larger ones
#: by mp_lu.  The Jacobian, the multipliers and the constraint forces keep
#: mp_lu's factors at every size.  The double pendulum's evaluation took 272
#: instructions for the solve and its call (valgrind) through mp_lu, against
#: the Fortran of the same equations' 134.
CLOSED_MAX = 3

#: A block of A whose entries and right-hand side hold more operations than
#: this is not solved symbolically (the expansions and SymPy's cancel grow
#: with their size): its adjugate is evaluated from the entries' values.  The
#: spherical pendulum's blocks hold 15, the heavy top's 39 and 20, the double
#: pendulum's 41 (its entries' form is the cheaper); the triple pendulum's 205,
#: whose symbolic form took 0.9 s of a first build to lose to the entries'.
CLOSED_SYMBOLIC_OPS = 100


#: The closed form's tests of a block's determinant, mp_closed_ok and
#: mp_closed_normal (csrc/gen/closed.h).
CLOSED = "\n" + _ctext.CLOSED + "\n"


def _components(A, na):
    """The diagonal blocks of the na x na SymPy matrix A: index lists of the
    connected components of its pattern of entries not identically zero."""
    root = list(range(na))

    def find(i):
        while root[i] != i:
            i = root[i]
        return i
    for i in range(na):
        for j in range(na):
            if not (A[i, j] == 0):
                root[find(i)] = find(j)
    out = {}
    for i in range(na):
        out.setdefault(find(i), []).append(i)
    return list(out.values())


def _ops(text: str) -> int:
    """The cost compared between two printings of the same C: its +, *, / and
    opening parentheses (calls, and the groupings that come with sums)."""
    return sum(text.count(c) for c in "+*/(")


def _closed_rhs(ir) -> str | None:
    """mp_gen_rhs for NA <= CLOSED_MAX as one block, or None (not printable).

    A z = b is solved by the diagonal blocks of A (:func:`_components`), each
    block by z = adj(A) b / det(A) in one of two forms, the one with fewer
    operations after common subexpressions: the adjugate and determinant
    expanded over the entries' values (the entries identically zero left out:
    0 * x is not folded by the compiler, which keeps NaN semantics), or the
    same solved symbolically, numerators and determinant expanded and each
    quotient reduced by SymPy's cancel (a factor common to the forcing and the
    determinant divides out: the spherical pendulum's theta'' needs no
    mass-matrix term, the heavy top's determinant is I1 I3 sin^2 theta instead
    of a difference that cancels).  Only the coordinates' rows of z are
    computed (the multipliers are not part of the state).  Each block's
    determinant is tested as mp_closed_solve tested the whole one: when it is
    not clearly away from 0 and from overflow (|det| <= k eps (sum |A_ij|)^k
    for a k x k block, or a NaN or inf in the block, which the sum carries),
    gen_rhs_lu solves by mp_lu, whose pivoting and statuses (MP_ENONFINITE,
    MP_ESINGULAR) decide, as for every larger system.  For a 1 x 1 block the
    test is mp_closed_normal (DBL_MIN < |a| <= DBL_MAX), the same test in
    fewer instructions."""
    B = ir.blocks
    na, nc = ir.nc + ir.k, ir.nc
    A = sp.Matrix(na, na, [sp.sympify(e) for e in B["A"]])
    b = [sp.sympify(e) for e in B["b"]]
    comps = _components(A, na)
    entry = {(i, j): sp.Symbol(f"mp_a{i * na + j}") for i in range(na) for j in range(na)
             if not (A[i, j] == 0)}
    bsym = [sp.Symbol(f"mp_b{i}") for i in range(na)]
    names = {ir.T: "t"}
    for i, p in enumerate(ir.P):
        names[p] = f"mp_p{i}"

    def form(symbolic):
        """[(name, expression)] for the entries, determinants and z of every
        block; None where the symbolic form is not tried."""
        outs = []
        for c, blk in enumerate(comps):
            sub = A.extract(blk, blk)
            if symbolic:
                if sum(sp.count_ops(e) for e in list(sub) + [b[i] for i in blk]) \
                        > CLOSED_SYMBOLIC_OPS:
                    return None
                M, rhs = sub, [b[i] for i in blk]
            else:
                M = sp.Matrix(len(blk), len(blk), lambda r, s: entry.get((blk[r], blk[s]),
                                                                         sp.S.Zero))
                rhs = [bsym[i] for i in blk]
            det = sp.expand(M.det(method="berkowitz")) if len(blk) > 1 else M[0, 0]
            adj = M.adjugate() if len(blk) > 1 else sp.Matrix([[1]])
            outs.append((f"mp_d{c}", det))
            for r, i in enumerate(blk):
                if i >= nc:
                    continue
                num = sp.expand(sum(adj[r, s] * rhs[s] for s in range(len(blk))))
                outs.append((f"mp_z{i}", sp.cancel(num / det) if symbolic else num / det))
        return outs

    best = None
    for symbolic in (False, True):
        outs = form(symbolic)
        if outs is None:
            continue
        # the entries first: the determinant tests read them (their sums)
        exprs = [(s.name, A[i, j]) for (i, j), s in entry.items()]
        if not symbolic:
            exprs += [(bsym[i].name, b[i]) for i in range(na)]
        exprs += outs
        em = _Emitter(names, ir.P)
        for _, e in exprs:
            em.scan(e)
        try:
            for n, e in exprs:   # each after the temporaries it needs
                em.lines.append(f"    const double {n} = {em.expr(e)};")
        except _Unprintable:
            if not symbolic:
                return None
            continue
        text = "\n".join(em.lines)
        if best is None or _ops(text) < _ops(best):
            best = text
    checks = []
    for c, blk in enumerate(comps):
        if len(blk) == 1:
            # mp_closed_ok(a, |a|, 1) is this test: |a| > eps |a| is implied by
            # |a| > DBL_MIN.  (A larger block whose determinant is a product,
            # such as the heavy top's I1 I3 sin^2 theta, keeps the test on the
            # entries' sum: a small determinant beside large entries is an
            # ill-conditioned block, whose numerators may cancel.)
            checks.append(f"mp_closed_normal(mp_d{c})")
            continue
        asum = " + ".join(f"fabs({entry[i, j].name})" for i in blk for j in blk
                          if (i, j) in entry) or "0.0"
        checks.append(f"mp_closed_ok(mp_d{c}, {asum}, {len(blk)})")
    used = set(re.findall(r"\bmp_[yp]\d+\b", best))
    loads = [f"    const double mp_y{i} = y[{i}];" for i in range(ir.n) if f"mp_y{i}" in used]
    loads += [f"    const double mp_p{i} = p[{i}];" for i in range(len(ir.P))
              if f"mp_p{i}" in used]
    stores = [f"    dydt[{i}] = " + (f"mp_y{nc + i};" if f"mp_y{nc + i}" in used
                                       else f"y[{nc + i}];") for i in range(nc)]
    stores += [f"    dydt[{nc + i}] = mp_z{i};" for i in range(nc)]
    return CLOSED + _RHS_BY_LU + r"""
/* dy/dt = (q', q'') at (t, y); params: the parameter vector.  A z = b in
 * closed form by the blocks of A (codegen._closed_rhs), by gen_rhs_lu where
 * a block's determinant test declines.  The closed form is stored before the
 * test, which gen_rhs_lu's values then overwrite: with the stores after it,
 * the heavy top's solve took 4% longer (measured side by side), the solution
 * waiting on a test it does not need. */
int mp_gen_rhs(double t, const double *y, double *dydt, void *params)
{
    const double *p = (const double *)params;
""" + "\n".join(loads + [best] + stores) + f"""
    if (!({' && '.join(checks)}))
        return gen_rhs_lu(t, y, dydt, p);""" + """
    (void)t;
    return MP_OK;
}
"""


#: Lane right-hand sides (mp_gen_lanes): the function attribute that compiles
#: one body for AVX2+FMA and portable x86-64 (a resolver picks at load time)
#: and libmvec's vector variants, as csrc/ode/lanes.h declares them for the C
#: scenes.  The library is compiled on the machine that loads it, so glibc's
#: version at compile time is the one at run time: the variants glibc 2.35
#: added are declared only from there.  Elsewhere (clang, another libc, not
#: x86-64) every name is the plain function and the loop is the scalar one.
LANE_RUNTIME = "\n" + _ctext.LANES   # csrc/gen/lanes.h

#: The solver of mp_lu and mp_lu_solve across the lanes of a lane rhs (A and b
#: laid out lane by lane): the same operations in the same order for every
#: lane, the pivot choice and row exchanges as selects (no branch on a lane's
#: values), so that the loops over the lanes vectorise.
LANE_SOLVER = "\n" + _ctext.LU_LANES   # csrc/gen/lu_lanes.h

#: Generated expression text (characters) of a lane right-hand side above
#: which none is emitted (the ensemble then runs the scalar rhs in lanes
#: through the engine's generic wrapper): the loop body is compiled twice
#: (AVX2 and portable) beside the scalar blocks.
LANE_MAX = 100_000


class _Unprintable(ValueError):
    """An expression the generator cannot print as C: ``culprit`` is the
    sub-expression, ``reason`` what is wrong with it."""

    def __init__(self, culprit, reason):
        super().__init__(f"{culprit}: {reason}")
        self.culprit = culprit
        self.reason = reason


def _constant(x) -> str:
    """A C literal for the real number x (a SymPy number or number symbol such
    as pi, E, EulerGamma): the double nearest to it, printed with ``repr``
    (17 significant digits at most, read back exactly).  The build's -std=c99
    declares no M_PI or M_E, and a literal is the same on every compiler.
    _Unprintable for a non-real or non-finite value, or one beyond the range of
    double precision."""
    if x.is_Integer and abs(int(x)) < 2 ** 53:
        return f"{int(x)}.0"
    if x.is_Rational and not x.is_Integer and abs(x.p) < 2 ** 53 and x.q < 2 ** 53:
        return f"({x.p}.0/{x.q}.0)"       # one correctly rounded division
    if x is sp.S.NaN or x.is_finite is False:
        raise _Unprintable(x, "not a finite number")
    if x.is_extended_real is False:
        raise _Unprintable(x, "a complex number: the compiled system is real; remove I "
                           "(the imaginary unit)")
    try:
        v = float(x)
    except (TypeError, ValueError, OverflowError):
        raise _Unprintable(x, "not a real number") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise _Unprintable(x, "beyond the range of double precision (about 1.8e308)")
    return repr(v)


class _Printer(C99CodePrinter):
    """C99 printer (for what the emitter does not print itself, e.g. Piecewise):
    numbers and constants as literals (no M_PI: see _constant), small integer
    powers as products (exact, fast), strict (anything it cannot print raises
    PrintMethodNotImplementedError)."""

    def __init__(self):
        super().__init__(dict(math_macros={}, strict=True))

    def _print_Pow(self, expr):
        b, e = expr.as_base_exp()
        if e.is_Integer and 2 <= int(e) <= 4:
            base = self._print(b)
            return "(" + "*".join([f"({base})"] * int(e)) + ")"
        if e == -1:
            return f"(1.0/({self._print(b)}))"
        return super()._print_Pow(expr)

    def _print_Number(self, expr):
        return _constant(expr)

    _print_Integer = _print_Rational = _print_Float = _print_NumberSymbol = _print_Number
    _print_Infinity = _print_NegativeInfinity = _print_NaN = _print_Number
    _print_ComplexInfinity = _print_ImaginaryUnit = _print_Number


#: C names of the one-argument functions printed directly.
_FUNCS1 = {"sin": "sin", "cos": "cos", "tan": "tan", "exp": "exp", "log": "log",
           "asin": "asin", "acos": "acos", "atan": "atan", "sinh": "sinh", "cosh": "cosh",
           "tanh": "tanh", "asinh": "asinh", "acosh": "acosh", "atanh": "atanh",
           "Abs": "fabs", "pow": "pow", "atan2": "atan2",
           # C99 <math.h> functions SymPy knows
           "erf": "erf", "erfc": "erfc", "gamma": "tgamma", "loggamma": "lgamma",
           "exp2": "exp2", "expm1": "expm1", "log2": "log2", "log10": "log10",
           "log1p": "log1p", "Cbrt": "cbrt", "floor": "floor", "ceiling": "ceil",
           "hypot": "hypot", "Max": "fmax", "Min": "fmin"}

#: Reciprocal functions, printed as 1/(their reciprocal).
_RECIPROCAL = {"cot": "tan", "sec": "cos", "csc": "sin", "coth": "tanh", "sech": "cosh",
               "csch": "sinh"}

#: Functions of two arguments (Max and Min of more are nested).
_FUNCS2 = ("atan2", "hypot", "Max", "Min")

#: Functions with a vector variant in glibc's libmvec: the lane right-hand
#: side calls them as mp_lane_<name> (declared in LANE_RUNTIME), which a
#: ``#pragma omp simd`` loop calls four lanes at a time.
_LANE_VEC = ("sin", "cos", "exp", "log", "pow", "tan", "asin", "acos", "atan", "atan2",
             "sinh", "cosh", "tanh", "asinh", "acosh", "atanh")
_FUNCS_LANE = {k: f"mp_lane_{v}" if v in _LANE_VEC else v for k, v in _FUNCS1.items()}


class _Emitter:
    """Common subexpressions and C printing in one pass over an expression DAG.

    Every non-atomic sub-expression met more than once (SymPy expressions are
    hashable and compare structurally) becomes a ``const double`` temporary,
    emitted before its first use; sums, products, powers, numbers and the
    elementary functions are printed here without rebuilding or sorting any
    expression, anything else by SymPy's C99 printer (``_Printer``).  ``names``
    maps symbols to their C names.
    """

    def __init__(self, names, coef=(), funcs=None):
        self.names = names
        self.coef = frozenset(coef)
        self.funcs = _FUNCS1 if funcs is None else funcs
        self.count = {}
        self.temps = {}
        self.lines = []
        self.pr = None

    def scan(self, e):
        """Count the references to each sub-expression of e (iteratively)."""
        count = self.count
        stack = [e]
        while stack:
            x = stack.pop()
            if not x.args:
                continue
            c = count.get(x)
            count[x] = 1 if c is None else c + 1
            if c is None and (x.is_Add or x.is_Mul or x.is_Pow or x.is_Function):
                stack.extend(x.args)

    def _fallback(self, x):
        if self.pr is None:
            self.pr = _Printer()
        try:
            return self.pr.doprint(x.xreplace({s: sp.Symbol(c) for s, c in self.names.items()
                                               if s in x.free_symbols}))
        except PrintMethodNotImplementedError:
            # the first part that cannot be printed, for the message
            bad = _first_unprintable(x)
            raise _Unprintable(bad if bad is not None else x, _NOT_C) from None

    def expr(self, x):
        """C text of x; temporaries it needs are appended to ``lines``."""
        if x.is_Symbol:
            return self.names.get(x, x.name)
        if x.is_Atom:
            if x.is_number:
                return _constant(x)
            raise _Unprintable(x, _NOT_C)
        t = self.temps.get(x)
        if t is not None:
            return t
        text = self._render(x)
        if self.count.get(x, 0) > 1:
            t = f"mp_c{len(self.temps)}"
            self.temps[x] = t
            self.lines.append(f"    const double {t} = {text};")
            return t
        return text

    def _pow(self, b, e):
        """C text of b**e for a numeric e (None: not a simple case)."""
        if e.is_Integer:
            k = int(e)
            if 1 <= k <= 4:
                bt = self.expr(b)
                return "(" + "*".join([bt] * k) + ")"
            if -4 <= k <= -1:
                bt = self.expr(b)
                return "(1.0/(" + "*".join([bt] * -k) + "))"
            return None
        if e.is_Rational and e.q == 2 and abs(e.p) <= 7:
            # b**(k/2) = b**m sqrt(b): a square root and products, not pow()
            bt = self.expr(b)
            text = "*".join([bt] * ((abs(e.p) - 1) // 2) + [f"sqrt({bt})"])
            return f"({text})" if e.p > 0 else f"(1.0/({text}))"
        return None

    def _terms(self, args):
        """C texts of the terms of a sum, terms that differ only by a factor of
        numbers and parameters gathered: c1 X + c2 X -> (c1 + c2) X, the sum
        of coefficients a temporary shared by every sum that has it."""
        groups = {}
        for a in args:
            if a.is_Mul:
                co = [f for f in a.args if f.is_Number or f in self.coef]
                core = [f for f in a.args if not (f.is_Number or f in self.coef)]
                co, core = (_product(co), _product(core)) if co else (sp.S.One, a)
            elif a.is_Number or a in self.coef:
                co, core = a, sp.S.One
            else:
                co, core = sp.S.One, a
            groups.setdefault(core, []).append((co, a))
        out = []
        for core, terms in groups.items():
            if len(terms) == 1 or core is sp.S.One:
                out.extend(self.expr(a) for _, a in terms)
                continue
            c = sp.Add(*[co for co, _ in terms])
            ct = self.expr(c)
            if c not in self.temps:
                text, ct = ct, f"mp_c{len(self.temps)}"
                self.temps[c] = ct
                self.lines.append(f"    const double {ct} = {text};")
            out.append(f"{ct}*{self.expr(core)}")
        return out

    def _render(self, x):
        if x.is_Add:
            return "(" + " + ".join(self._terms(x.args)) + ")"
        if x.is_Mul:
            num, den = [], []
            for a in x.args:
                # a reciprocal met more than once is a temporary that
                # multiplies (one division for all its uses)
                if (a.is_Pow and a.exp.is_Rational and a.exp.is_negative
                        and a not in self.temps and self.count.get(a, 0) <= 1):
                    d = self._pow(a.base, -a.exp)
                    den.append(d if d is not None else self.expr(a.base ** -a.exp))
                elif a is sp.S.NegativeOne:
                    num.append("-1.0")
                else:
                    num.append(self.expr(a))
            top = "*".join(num) if num else "1.0"
            return f"({top})" if not den else f"(({top})/({'*'.join(den)}))"
        if x.is_Pow:
            b, e = x.args
            if e.is_Number:
                r = self._pow(b, e)
                if r is not None:
                    return r
                e_text = _constant(e)
                return f"{self.funcs['pow']}({self.expr(b)}, {e_text})"
            return f"{self.funcs['pow']}({self.expr(b)}, {self.expr(e)})"
        if x.is_Function:
            name = type(x).__name__
            f = self.funcs.get(name)
            if f is not None and len(x.args) == 1 and name not in _FUNCS2:
                return f"{f}({self.expr(x.args[0])})"
            if name in _FUNCS2 and len(x.args) >= 2:
                # Max(a, b, c) -> fmax(a, fmax(b, c))
                args = [self.expr(a) for a in x.args]
                text = args[-1]
                for a in reversed(args[:-1]):
                    text = f"{f}({a}, {text})"
                return text
            if name == "sign" and len(x.args) == 1:
                # SymPy's sign: 1, -1, or the argument itself at 0 (0.0 or
                # -0.0) and at NaN (kept NaN, as every other function keeps it)
                a = self.expr(x.args[0])
                return f"({a} > 0.0 ? 1.0 : ({a} < 0.0 ? -1.0 : {a}))"
            r = _RECIPROCAL.get(name)
            if r is not None and len(x.args) == 1:
                return f"(1.0/{self.funcs[r]}({self.expr(x.args[0])}))"
            if x.is_Piecewise:
                return self._fallback(x)
            raise _Unprintable(x, _NOT_C)
        raise _Unprintable(x, _NOT_C)


#: Why an expression cannot be printed.
_NOT_C = ("mechpy cannot print it as C (it prints numbers, +, *, powers, Piecewise and the "
          "functions " + ", ".join(sorted(set(_FUNCS1) - {"pow"} | set(_RECIPROCAL)
                                          | {"sign"})) + ")")


def _first_unprintable(x):
    """The first sub-expression of x (depth first) that the strict printer
    cannot print, or None."""
    pr = _Printer()
    for a in x.args:
        try:
            pr.doprint(a)
        except (PrintMethodNotImplementedError, _Unprintable, ValueError):
            return _first_unprintable(a) or a
    return None


def _product(factors):
    """The product of already canonical factors, without re-evaluating it."""
    if not factors:
        return sp.S.One
    return factors[0] if len(factors) == 1 else sp.Mul._from_args(factors)


def _block(name, exprs, ir, args, what, static=True, sparse=False):
    """A function ``name`` (static unless ``static`` is False) writing the
    expressions to out[].  ``sparse``: out[] is zeroed by one loop and only the
    entries not identically zero are printed, so that the text grows with the
    nonzeros, not with the block's length (a Jacobian: n^2 entries, a few per
    row nonzero in a chain)."""
    names = {ir.T: "t"}
    for i, p in enumerate(ir.P):
        names[p] = f"mp_p{i}"
    exprs = [sp.sympify(e) for e in exprs]
    em = _Emitter(names, ir.P)
    for e in exprs:
        em.scan(e)
    outs = [f"    for (int i = 0; i < {len(exprs)}; i++) out[i] = 0.0;"] if sparse else []
    try:
        for i, e in enumerate(exprs):
            if sparse and e == 0:
                continue
            outs.append(f"    out[{i}] = {em.expr(e)};")
    except _Unprintable as exc:
        from .derive import explain
        raise ValueError(explain(ir, what, exc.culprit, exc.reason)) from None
    body = "\n".join(em.lines + outs)
    lines = [f"/* out[0..{len(exprs) - 1}] = {what} at (t, y), parameters p"
             + (", unknowns z" if "const double *z" in args else "") + ". */",
             f"{'static ' if static else ''}void {name}({args})", "{"]
    # the inputs the body reads, as locals (no reload after each store to out)
    used = set(re.findall(r"\bmp_[ypz]\d+\b", body))
    for i in range(ir.n):
        if f"mp_y{i}" in used:
            lines.append(f"    const double mp_y{i} = y[{i}];")
    for i in range(len(ir.P)):
        if f"mp_p{i}" in used:
            lines.append(f"    const double mp_p{i} = p[{i}];")
    for i in range(len(ir.Z)):
        if f"mp_z{i}" in used:
            lines.append(f"    const double mp_z{i} = z[{i}];")
    lines.append(body)
    lines.append("    (void)t; (void)y; (void)p; (void)out;")
    lines.append("}")
    return "\n".join(lines)


def _lane_loop(ir, outputs, what):
    """The body of a ``MP_LANE_LOOP``: every expression of ``outputs`` (pairs of
    expressions and an output array name, element i of lane l written to
    name[i * MP_LANES + l]) at lane l's (t, y, p), after one shared common
    subexpression pass; None when the text is over :data:`LANE_MAX`."""
    names = {ir.T: "t"}
    for i, p in enumerate(ir.P):
        names[p] = f"mp_p{i}"
    em = _Emitter(names, ir.P, _FUNCS_LANE)
    flat = [(sp.sympify(e), out, i) for exprs, out in outputs for i, e in enumerate(exprs)]
    for e, _, _ in flat:
        em.scan(e)
    try:
        outs = [f"    {out}[{i} * MP_LANES + l] = {em.expr(e)};" for e, out, i in flat]
    except _Unprintable:
        return None    # the scalar blocks raise the error that names the culprit
    body = "\n".join(em.lines + outs)
    if len(body) > LANE_MAX:
        return None
    used = set(re.findall(r"\bmp_[yp]\d+\b", body))
    lines = ["    const double t = tl[l];"]
    lines += [f"    const double mp_y{i} = y[{i} * MP_LANES + l];" for i in range(ir.n)
              if f"mp_y{i}" in used]
    lines += [f"    const double mp_p{i} = p[{i} * MP_LANES + l];" for i in range(len(ir.P))
              if f"mp_p{i}" in used]
    lines += [body, "    (void)t;"]
    return f"    /* {what} */\n    MP_LANE_LOOP {{\n" + "\n".join(
        "    " + x if x else x for x in "\n".join(lines).split("\n")) + "\n    }"


#: The lane right-hand side's signature (lanes.h's mp_lane_rhs).
_LANE_ARGS = "const double *tl, const double *y, double *f, const double *p, int *status"

_LANE_DOC = """
/* mp_gen_rhs for MP_LANES states at once (the engine's mp_lane_rhs): tl
 * (MP_LANES,), y and f (NS * MP_LANES, component i of lane l at
 * [i * MP_LANES + l]), p (np * MP_LANES, each lane's parameter row, the same
 * layout); status[l] = what mp_gen_rhs returns for lane l's state. */
"""


def _lanes_equations(ir):
    """mp_gen_lanes of a first-order system, or '' (none: see _lane_loop)."""
    loop = _lane_loop(ir, [(ir.blocks["f"], "f")], "f at each lane's (t, y, p)")
    if loop is None:
        return ""
    return (_LANE_DOC + f"MP_LANE_FN void mp_gen_lanes({_LANE_ARGS})\n{{\n"
            f"    (void)p;\n{loop}\n"
            "    MP_LANE_LOOP status[l] = MP_OK;\n}\n")


def _lanes_lagrangian(ir):
    """mp_gen_lanes of a Lagrangian system, or '' (none: see _lane_loop): A and
    b vectorised across the lanes, then gen_solve's solve and statuses for
    every lane at once (LANE_SOLVER)."""
    B = ir.blocks
    loop = _lane_loop(ir, [(B["A"], "A"), (B["b"], "b")], "A and b at each lane's (t, y, p)")
    if loop is None:
        return ""
    return (LANE_SOLVER + _LANE_DOC + f"MP_LANE_FN void mp_gen_lanes({_LANE_ARGS})\n{{\n"
            "    double A[NA * NA * MP_LANES], b[NA * MP_LANES];\n    (void)p;\n" + loop
            + r"""
#if NA == 1
    MP_LANE_LOOP {
        const double a = A[l];
        status[l] = !isfinite(a) ? MP_ENONFINITE : a == 0.0 ? MP_ESINGULAR : MP_OK;
        f[MP_LANES + l] = b[l] * (1.0 / a);
    }
#else
    mp_lu_lanes(A, b, status);
    for (int i = 0; i < NC; i++)
        MP_LANE_LOOP f[(NC + i) * MP_LANES + l] = b[i * MP_LANES + l];
#endif
    for (int i = 0; i < NC; i++)
        MP_LANE_LOOP f[i * MP_LANES + l] = y[(NC + i) * MP_LANES + l];
}
""")


def _fixed_blocks(ir):
    """The engine's fixed-step blocks (csrc/ode/fixed.h, as the C core was
    built with it) instantiated with mp_gen_rhs: mp_gen_rk4 and mp_gen_compose
    (meaningful when ir.nq > 0), with the signatures of the engine's
    mp_ode_blocks, so that rk4 and the symplectic methods run a compiled system
    as the engine runs its own scenes (mp_gen_rhs inlined where the compiler
    finds it worth it: build.FLAGS has -fno-semantic-interposition)."""
    from .. import _core
    return ("\n/* ---- fixed-step blocks: mechpy._core.FIXED_STEPS_C ---- */\n"
            + _core.FIXED_STEPS_C
            + f"\nMP_ODE_BLOCK_FNS(, mp_gen, mp_gen_rhs, NS, {ir.nq})\n")


def _header(ir, status):
    from .. import _core
    n, nc, k = ir.n, ir.nc, ir.k
    na = nc + k
    defs = "\n".join(f"#define {name} {value}" for name, value in sorted(status.items()))
    return f"""/* Generated by mechpy.symbolic: {ir.kind} system, states {ir.names}, parameters
 * {ir.param_names}.  Exported: mp_gen_rhs, mp_gen_jac, mp_gen_energy, mp_gen_momenta,
 * mp_gen_multipliers, mp_gen_constraint_forces, mp_gen_lagrangian, mp_gen_dims,
 * mp_gen_lanes unless the system is too large (ABI version {ABI_VERSION}).  Every function
 * returns a mechpy status code (mp_gen_lanes: one per lane). */
#include <float.h>
#include <math.h>
#include <stddef.h>

{defs}

#define NS {n}   /* state dimension */
#define NC {nc}   /* coordinates */
#define NK {k}   /* constraints */
#define NA {na}   /* size of the linear system */
#define MP_LANES {_core.LANES}   /* lanes of the engine's ensembles (csrc/ode/lanes.h) */
{LANE_RUNTIME}"""


def _dims(ir):
    return (f"const long mp_gen_dims[5] = {{{ir.n}, {ir.nq}, {len(ir.P)}, {ir.k}, "
            f"{ABI_VERSION}}};\n")


_ARGS = "double t, const double *y, const double *p, double *out"
_ARGS_Z = "double t, const double *y, const double *p, const double *z, double *out"


#: dy/dt of a Lagrangian system by gen_solve's LU: its mp_gen_rhs where NA >
#: CLOSED_MAX (_RHS_LU), where the closed form declines otherwise (_closed_rhs).
_RHS_BY_LU = r"""
/* dy/dt = (q', q'') at (t, y) by gen_solve's LU, parameters p. */
static int gen_rhs_lu(double t, const double *y, double *dydt, const double *p)
{
    double A0[NA * NA], LU[NA * NA], dinv[NA], z[NA];
    int piv[NA];
    int rc = gen_solve(t, y, p, A0, LU, piv, dinv, z);
    if (rc != MP_OK) return rc;
    for (int i = 0; i < NC; i++) {
        dydt[i] = y[NC + i];
        dydt[NC + i] = z[i];
    }
    return MP_OK;
}
"""

#: A Lagrangian system's mp_gen_rhs by mp_lu (NA > CLOSED_MAX; else _closed_rhs).
_RHS_LU = _RHS_BY_LU + r"""
/* dy/dt = (q', q'') at (t, y); params: the parameter vector. */
int mp_gen_rhs(double t, const double *y, double *dydt, void *params)
{
    return gen_rhs_lu(t, y, dydt, (const double *)params);
}
"""


def _lagrangian_source(ir, status):
    B = ir.blocks
    n, k = ir.nc, ir.k
    blocks = [_block("gen_A", B["A"], ir, _ARGS, "the mass matrix"),
              _block("gen_b", B["b"], ir, _ARGS, "the equations of motion (right-hand side)"),
              _block("gen_energy", B["energy"], ir, _ARGS, "the energy"),
              _block("gen_momenta", B["momenta"], ir, _ARGS, "the momenta"),
              _block("gen_lag", B["lag"], ir, _ARGS, "L")]
    rhs = _closed_rhs(ir) if n + k <= CLOSED_MAX else None
    jac = _block("gen_D", B["D"], ir, _ARGS_Z, "the Jacobian", static=False)
    if len(jac) + sum(map(len, blocks)) > SPLIT:
        # the Jacobian's block compiles beside the rest (see build.units)
        parts = [_header(ir, status), "#if defined(__GNUC__)\n#define MP_HIDDEN "
                 "__attribute__((visibility(\"hidden\")))\n#else\n#define MP_HIDDEN\n#endif\n"
                 f"MP_HIDDEN void gen_D({_ARGS_Z});", build.UNIT, _dims(ir),
                 RUNTIME] + blocks
        # and so does the lane rhs
        lanes = _lanes_lagrangian(ir)
        tail = [build.UNIT, jac] + ([build.UNIT, lanes] if lanes else [])
    else:
        lanes = None
        parts = [_header(ir, status), _dims(ir), RUNTIME, jac.replace("\nvoid gen_D(",
                                                                        "\nstatic void gen_D(")]
        parts += blocks
        tail = []
    parts.append(r"""
/* Solve A z = b at (t, y): z = (q'', -lambda).  A0 receives A before the
 * factorisation, LU its factors.  Returns MP_ESINGULAR for a singular mass
 * (or constrained) matrix. */
static inline int gen_solve(double t, const double *y, const double *p, double *A0,
                            double *LU, int *piv, double *dinv, double *z)
{
    /* A is factorised before b is evaluated: the division overlaps b's work */
    gen_A(t, y, p, A0);
#if NA == 1
    piv[0] = 0;
    LU[0] = A0[0];
    if (!isfinite(LU[0])) return MP_ENONFINITE;
    if (LU[0] == 0.0) return MP_ESINGULAR;
    dinv[0] = 1.0 / LU[0];
    gen_b(t, y, p, z);
    z[0] *= dinv[0];
#else
    for (int i = 0; i < NA * NA; i++) LU[i] = A0[i];
    int rc = mp_lu(LU, piv, dinv);
    if (rc != MP_OK) return rc;
    gen_b(t, y, p, z);
    mp_lu_solve(LU, piv, dinv, z);
#endif
    return MP_OK;
}

""")
    parts.append(_RHS_LU if rhs is None else rhs)
    parts.append(r"""
/* Row-major NS x NS Jacobian of mp_gen_rhs: d q''/d(q, q') = first NC rows of
 * A^-1 D with D = [db/dq - (dA/dq) z, db/dq' - (dA/dq') z]. */
int mp_gen_jac(double t, const double *y, double *jac, void *params)
{
    const double *p = params;
    double A0[NA * NA], LU[NA * NA], dinv[NA], z[NA], D[NA * 2 * NC], col[NA];
    int piv[NA];
    int rc = gen_solve(t, y, p, A0, LU, piv, dinv, z);
    if (rc != MP_OK) return rc;
    gen_D(t, y, p, z, D);
    for (int i = 0; i < NS * NS; i++) jac[i] = 0.0;
    for (int i = 0; i < NC; i++) jac[i * NS + NC + i] = 1.0;
    for (int c = 0; c < 2 * NC; c++) {
        for (int r = 0; r < NA; r++) col[r] = D[r * 2 * NC + c];
        mp_lu_solve(LU, piv, dinv, col);
        for (int i = 0; i < NC; i++) jac[(NC + i) * NS + c] = col[i];
    }
    return MP_OK;
}

/* out[0] = the Jacobi integral h = sum q' dL/dq' - L. */
int mp_gen_energy(double t, const double *y, double *out, void *params)
{
    gen_energy(t, y, (const double *)params, out);
    return MP_OK;
}

/* out[i] = dL/dq'_i. */
int mp_gen_momenta(double t, const double *y, double *out, void *params)
{
    gen_momenta(t, y, (const double *)params, out);
    return MP_OK;
}

/* At m points (t[i], q[i*NC..], q'[i*NC..]): out[i*K..] with K = 1 + 2NC + 3NC^2:
 * L, dL/dq, dL/dq', d2L/dqdq, d2L/dqdq' ([a][b] = d2L/dq_a dq'_b), d2L/dq'dq'. */
int mp_gen_lagrangian(size_t m, const double *t, const double *q, const double *qd,
                      double *out, void *params)
{
    const size_t K = 1 + 2 * NC + 3 * NC * NC;
    double yy[2 * NC];
    for (size_t i = 0; i < m; i++) {
        for (int j = 0; j < NC; j++) {
            yy[j] = q[i * NC + j];
            yy[NC + j] = qd[i * NC + j];
        }
        gen_lag(t[i], yy, (const double *)params, out + i * K);
    }
    return MP_OK;
}
""")
    if lanes is None:
        parts.append(_lanes_lagrangian(ir))
    parts.append(_fixed_blocks(ir))
    if k:
        parts.append(_block("gen_g", B["g"], ir, _ARGS, "the constraints"))
        parts.append(r"""
/* out = (g (NK), g' (NK)): the constraints and their rates (not part of the
 * engine's interface: the initial-state check uses it). */
int mp_gen_constraints(double t, const double *y, double *out, void *params)
{
    gen_g(t, y, (const double *)params, out);
    return MP_OK;
}

/* out[c] = lambda_c, the Lagrange multipliers. */
int mp_gen_multipliers(double t, const double *y, double *out, void *params)
{
    double A0[NA * NA], LU[NA * NA], dinv[NA], z[NA];
    int piv[NA];
    int rc = gen_solve(t, y, (const double *)params, A0, LU, piv, dinv, z);
    if (rc != MP_OK) return rc;
    for (int c = 0; c < NK; c++) out[c] = -z[NC + c];
    return MP_OK;
}

/* out[j] = sum_c lambda_c dg_c/dq_j, the generalized constraint forces. */
int mp_gen_constraint_forces(double t, const double *y, double *out, void *params)
{
    double A0[NA * NA], LU[NA * NA], dinv[NA], z[NA];
    int piv[NA];
    int rc = gen_solve(t, y, (const double *)params, A0, LU, piv, dinv, z);
    if (rc != MP_OK) return rc;
    for (int j = 0; j < NC; j++) {
        double s = 0.0;
        for (int c = 0; c < NK; c++) s += A0[(NC + c) * NA + j] * -z[NC + c];
        out[j] = s;
    }
    return MP_OK;
}
""")
    else:
        parts.append(_absent("mp_gen_multipliers") + _absent("mp_gen_constraint_forces"))
    return "\n".join(parts + tail)


def _absent(name, sig="double t, const double *y, double *out, void *params"):
    return f"""
/* Not defined for this system: returns MP_EDOM. */
int {name}({sig})
{{
    (void)t; (void)y; (void)out; (void)params;
    return MP_EDOM;
}}
"""


def _first_order_tail(has_energy: bool, what: str) -> str:
    """The functions of a library whose state is not (q, q'): mp_gen_energy (the
    given energy, printed before as gen_energy, or absent), absent momenta,
    multipliers and constraint forces, and mp_gen_lagrangian refusing (what: the
    kind of system, for its comment)."""
    energy = r"""
/* out[0] = the given energy. */
int mp_gen_energy(double t, const double *y, double *out, void *params)
{
    gen_energy(t, y, (const double *)params, out);
    return MP_OK;
}
""" if has_energy else _absent("mp_gen_energy")
    return "\n".join([energy, _absent("mp_gen_momenta") + _absent("mp_gen_multipliers")
                      + _absent("mp_gen_constraint_forces"), f"""
/* Not defined for {what}: returns MP_EDOM. */
int mp_gen_lagrangian(size_t m, const double *t, const double *q, const double *qd,
                      double *out, void *params)
{{
    (void)m; (void)t; (void)q; (void)qd; (void)out; (void)params;
    return MP_EDOM;
}}
"""])


def _equations_source(ir, status):
    B = ir.blocks
    parts = [_header(ir, status), _dims(ir),
             _block("gen_f", B["f"], ir, _ARGS, "rhs"),
             _block("gen_J", B["J"], ir, _ARGS, "the Jacobian", sparse=True)]
    parts.append(r"""
/* dy/dt = f(t, y). */
int mp_gen_rhs(double t, const double *y, double *dydt, void *params)
{
    gen_f(t, y, (const double *)params, dydt);
    return MP_OK;
}

/* Row-major NS x NS df/dy. */
int mp_gen_jac(double t, const double *y, double *jac, void *params)
{
    gen_J(t, y, (const double *)params, jac);
    return MP_OK;
}
""")
    parts.append(_lanes_equations(ir))
    parts.append(_fixed_blocks(ir))
    if "energy" in B:
        parts.append(_block("gen_energy", B["energy"], ir, _ARGS, "the energy"))
    parts.append(_first_order_tail("energy" in B, "a first-order system"))
    return "\n".join(parts)


#: A mechanics model's lane right-hand side is emitted below this size (its
#: loop compiled twice, AVX2 and portable: the bicycle's, 71k characters,
#: cost 5 s of compilation for ensembles that the engine's generic lane
#: wrapper runs on the scalar rhs anyway).
LANE_MAX_MECHANICS = 40_000


def _lanes_mechanics(ir):
    """mp_gen_lanes of a mechanics model, or '' (none: see _lane_loop): A and b
    across the lanes, LANE_SOLVER's solve, dy/dt the first NS unknowns."""
    B = ir.blocks
    loop = _lane_loop(ir, [(B["A"], "A"), (B["b"], "b")], "A and b at each lane's (t, y, p)")
    if loop is None or len(loop) > LANE_MAX_MECHANICS:
        return ""
    return (LANE_SOLVER + _LANE_DOC + f"MP_LANE_FN void mp_gen_lanes({_LANE_ARGS})\n{{\n"
            "    double A[NA * NA * MP_LANES], b[NA * MP_LANES];\n    (void)p;\n" + loop
            + r"""
    mp_lu_lanes(A, b, status);
    for (int i = 0; i < NS; i++)
        MP_LANE_LOOP f[i * MP_LANES + l] = b[i * MP_LANES + l];
}
""")


#: A block whose text is over this many characters is printed as functions
#: of about CHUNK characters each, its common subexpressions kept in an array
#: (one function of thousands of temporaries costs the compiler's register
#: allocator tens of seconds: the bicycle's Jacobian took 32 s at -O1 as one
#: function, 7.4 s in chunks of 12k characters, 4.0-5.9 s in chunks of 4k).
CHUNKED = 60_000
CHUNK = 4_000


def _chunked(text):
    """The block function ``text`` (as :func:`_block` prints it) as a driver
    and static functions of about CHUNK characters, the temporaries mp_cK in
    the driver's array w[K]; ``text`` itself when it is short."""
    if len(text) <= CHUNKED:
        return text
    lines = text.split("\n")
    start = next(i for i, x in enumerate(lines) if x == "{")
    sig = lines[start - 1]
    comment = lines[:start - 1]
    body = [x for x in lines[start + 1:-1]
            if not re.match(r"    const double mp_[ypz]\d+ = [ypz]\[\d+\];$", x)
            and not x.startswith("    (void)t;")]
    temps = re.findall(r"const double (mp_c\d+) = ", "\n".join(body))
    index = {t: i for i, t in enumerate(temps)}
    sub = re.compile(r"\b(mp_c\d+)\b")

    def arr(m):
        return f"w[{index[m.group(1)]}]"

    body = [sub.sub(arr, x.replace("const double ", "", 1) if x.startswith(
        "    const double mp_c") else x) for x in body]
    name = re.search(r"void (\w+)\(", sig).group(1)
    args = sig[sig.index("(") + 1:sig.rindex(")")]
    argn = [a.split()[-1].lstrip("*") for a in args.split(",")]
    chunks, cur, size = [], [], 0
    for x in body:
        cur.append(x)
        size += len(x)
        if size > CHUNK:
            chunks.append(cur)
            cur, size = [], 0
    if cur:
        chunks.append(cur)
    out = []
    for k, ch in enumerate(chunks):
        txt = "\n".join(ch)
        used = sorted(set(re.findall(r"\bmp_[ypz]\d+\b", txt)),
                      key=lambda v: (v[3], int(v[4:])))
        decl = [f"    const double {v} = {v[3]}[{v[4:]}];" for v in used]
        out.append(f"static void {name}_{k}({args}, double *w)\n{{\n" + "\n".join(decl)
                   + "\n" + txt + "\n    " + " ".join(f"(void){a};" for a in argn)
                   + " (void)w;\n}")
    call_args = ", ".join(argn)
    driver = "\n".join(comment) + f"\n{sig}\n{{\n    double w[{max(1, len(temps))}];\n" + "".join(
        f"    {name}_{k}({call_args}, w);\n" for k in range(len(chunks))) + "}"
    return "\n".join(out) + "\n" + driver


def _kane_blocks(A, na, nc, ns):
    """Whether the NA x NA matrix A (row-major, its entries as SymPy
    expressions) has the blocks of a Kane model (multibody.py): the first nc
    rows the identity on q' beside -C^T on the multipliers, the next ns - nc
    rows the mass matrix M on u' alone, the last na - ns rows C on q' alone.
    Then A z = b splits: M u' = F, and (C C^T) mu = b_mu - C f_k with
    q' = f_k + C^T mu (f_k the first nc entries of b, b_mu the last)."""
    def a(i, j):
        return sp.sympify(A[i * na + j])

    for i in range(nc):
        for j in range(ns):
            if a(i, j) != (1 if i == j else 0):
                return False
        for c in range(ns, na):
            if sp.expand(a(i, c) + a(c, i)) != 0:
                return False
    for i in range(nc, ns):
        if any(a(i, j) != 0 for j in list(range(nc)) + list(range(ns, na))):
            return False
    for c in range(ns, na):
        if any(a(c, j) != 0 for j in range(nc, na)):
            return False
    return True


#: mp_gen_rhs of a Kane model from its blocks (see _kane_blocks): the LU of
#: the NU x NU mass matrix and of the NH x NH C C^T instead of the NA x NA
#: system (the n-link cart's 22 x 22 becomes 11 x 11, the bicycle's 11 x 11
#: a 6 x 6 and a 1 x 1); the Jacobian keeps the whole system's factors.
_RHS_KANE = r"""
/* dy/dt = (q', u') at (t, y) from the blocks of A z = b: M u' = F by mp_lu_n,
 * then with the NH holonomic constraints (C C^T) mu = b_mu - C f_k and
 * q' = f_k + C^T mu (C the last NH rows of A, f_k the first NC entries of b);
 * without them q' = f_k.  params: the parameter vector. */
int mp_gen_rhs(double t, const double *y, double *dydt, void *params)
{
    double Ab[NA * NA + NA], M[NU * NU], dinv[NU];
    int piv[NU], rc;
    gen_Ab(t, y, (const double *)params, Ab);
    const double *b = Ab + NA * NA;
    for (int i = 0; i < NU; i++) {
        for (int j = 0; j < NU; j++) M[i * NU + j] = Ab[(NC + i) * NA + NC + j];
        dydt[NC + i] = b[NC + i];
    }
    if ((rc = mp_lu_n(M, NU, piv, dinv)) != MP_OK) return rc;
    mp_lu_solve_n(M, NU, piv, dinv, dydt + NC);
    for (int i = 0; i < NC; i++) dydt[i] = b[i];
#if NH > 0
    double S[NH * NH], mu[NH], sinv[NH];
    int spiv[NH];
    const double *C = Ab + NS * NA;          /* row c: C[c * NA + j], j < NC */
    for (int c = 0; c < NH; c++) {
        double r = b[NS + c];
        for (int j = 0; j < NC; j++) r -= C[c * NA + j] * b[j];
        mu[c] = r;
        for (int d = 0; d < NH; d++) {
            double s = 0.0;
            for (int j = 0; j < NC; j++) s += C[c * NA + j] * C[d * NA + j];
            S[c * NH + d] = s;
        }
    }
    if ((rc = mp_lu_n(S, NH, spiv, sinv)) != MP_OK) return rc;
    mp_lu_solve_n(S, NH, spiv, sinv, mu);
    for (int i = 0; i < NC; i++)
        for (int c = 0; c < NH; c++) dydt[i] += C[c * NA + i] * mu[c];
#endif
    for (int i = 0; i < NS; i++)
        if (!isfinite(dydt[i])) return MP_ENONFINITE;
    return MP_OK;
}
"""


#: mp_gen_rhs of a mechanics model whose A has no blocks to split.
_RHS_FULL = r"""
/* dy/dt = z[:NS] at (t, y); params: the parameter vector. */
int mp_gen_rhs(double t, const double *y, double *dydt, void *params)
{
    double LU[NA * NA + NA], dinv[NA], z[NA];
    int piv[NA];
    int rc = gen_solve(t, y, (const double *)params, LU, piv, dinv, z);
    if (rc != MP_OK) return rc;
    for (int i = 0; i < NS; i++) dydt[i] = z[i];
    return MP_OK;
}
"""


def _mechanics_source(ir, status):
    """A model of SymPy's mechanics (see multibody.py): A z = b solved at each
    evaluation (by its blocks for a Kane model: _kane_blocks), dy/dt = z[:NS];
    the Jacobian and the input matrix from D after the whole system's
    factorisation."""
    B = ir.blocks
    nv = len(B["D"]) // len(B["b"])          # NS states + the specified inputs
    # A and b in one pass: the subexpressions they share (the bicycle: the
    # trigonometry and geometry, a tenth of the arithmetic) computed once
    blocks = [_block("gen_Ab", list(B["A"]) + list(B["b"]), ir, _ARGS,
                     "the mass matrix A (row-major), then the forcing vector b"),
              _block("gen_G", B["G"] or [0], ir, _ARGS, "the constraints"),
              _block("gen_GJ", B["GJ"] or [0], ir, _ARGS, "the constraints' Jacobian")]
    if "energy" in B:
        blocks.append(_block("gen_energy", B["energy"], ir, _ARGS, "the energy"))
    blocks = [_chunked(x) for x in blocks]
    # A and b, the arithmetic of every evaluation, compiled for AVX2+FMA too
    # (MP_LANE_FN's clones, picked at load time: the bicycle's rhs in 15%
    # fewer instructions, three-operand and fused arithmetic)
    blocks[0] = re.sub(r"^static void gen_Ab", "MP_LANE_FN static void gen_Ab", blocks[0],
                       flags=re.M)
    jac = _chunked(_block("gen_D", B["D"], ir, _ARGS_Z, "the Jacobian", static=False))
    na = len(B["b"])
    header = re.sub(r"\n#define NA \d+ ", f"\n#define NA {na} ", _header(ir, status))
    head = [header, f"#define NV {nv}   /* columns of D: states, inputs */"]
    if _kane_blocks(B["A"], na, ir.nc, ir.n):
        head.append(f"#define NU {ir.n - ir.nc}   /* speeds: M is NU x NU */\n"
                    f"#define NH {na - ir.n}   /* holonomic constraints: C is NH x NC */")
        rhs = _RHS_KANE
    else:
        rhs = _RHS_FULL
    if len(jac) + sum(map(len, blocks)) > SPLIT:
        parts = head + ["#if defined(__GNUC__)\n#define MP_HIDDEN "
                        "__attribute__((visibility(\"hidden\")))\n#else\n#define MP_HIDDEN"
                        f"\n#endif\nMP_HIDDEN void gen_D({_ARGS_Z});", build.UNIT,
                        _dims(ir), RUNTIME] + blocks
        lanes = _lanes_mechanics(ir)
        tail = [build.UNIT, jac] + ([build.UNIT, lanes] if lanes else [])
    else:
        lanes = None
        parts = head + [_dims(ir), RUNTIME,
                        jac.replace("\nvoid gen_D(", "\nstatic void gen_D(")] + blocks
        tail = []
    parts.append(r"""
/* Solve A z = b at (t, y); LU (NA * NA + NA: A's factors, then b) piv, dinv
 * receive the factors. */
static inline int gen_solve(double t, const double *y, const double *p, double *LU,
                            int *piv, double *dinv, double *z)
{
    gen_Ab(t, y, p, LU);
    int rc = mp_lu(LU, piv, dinv);
    if (rc != MP_OK) return rc;
    for (int i = 0; i < NA; i++) z[i] = LU[NA * NA + i];
    mp_lu_solve(LU, piv, dinv, z);
    for (int i = 0; i < NA; i++)
        if (!isfinite(z[i])) return MP_ENONFINITE;
    return MP_OK;
}

MP_GEN_RHS
/* out (NS x ncol, row-major) = the first NS rows of A^-1 D[:, :ncol]: the
 * Jacobian (ncol = NS) or, with the inputs' columns, (df/dy, df/dr). */
static int gen_lin(double t, const double *y, const double *p, double *out, int ncol)
{
    double LU[NA * NA + NA], dinv[NA], z[NA], D[NA * NV], col[NA];
    int piv[NA];
    int rc = gen_solve(t, y, p, LU, piv, dinv, z);
    if (rc != MP_OK) return rc;
    gen_D(t, y, p, z, D);
    for (int c = 0; c < ncol; c++) {
        for (int r = 0; r < NA; r++) col[r] = D[r * NV + c];
        mp_lu_solve(LU, piv, dinv, col);
        for (int i = 0; i < NS; i++) out[i * ncol + c] = col[i];
    }
    return MP_OK;
}

/* Row-major NS x NS Jacobian of mp_gen_rhs. */
int mp_gen_jac(double t, const double *y, double *jac, void *params)
{
    return gen_lin(t, y, (const double *)params, jac, NS);
}

/* out = (df/dy | df/dr), NS x NV row-major (the inputs r are the last
 * parameters). */
int mp_gen_linear(double t, const double *y, double *out, void *params)
{
    return gen_lin(t, y, (const double *)params, out, NV);
}

/* out = the constraint residuals (configuration, then velocity). */
int mp_gen_residual(double t, const double *y, double *out, void *params)
{
    gen_G(t, y, (const double *)params, out);
    return MP_OK;
}

/* out = their Jacobian d(residuals)/dy, row-major. */
int mp_gen_residual_jac(double t, const double *y, double *out, void *params)
{
    gen_GJ(t, y, (const double *)params, out);
    return MP_OK;
}

/* out (NA * NA + NA) = A (row-major), then b, unsolved: what a failed solve
 * is diagnosed from (which row is not finite, which block is singular). */
int mp_gen_Ab(double t, const double *y, double *out, void *params)
{
    gen_Ab(t, y, (const double *)params, out);
    return MP_OK;
}
""")
    parts[-1] = parts[-1].replace("MP_GEN_RHS\n", rhs)
    parts.append(_first_order_tail("energy" in B, "a mechanics model"))
    if lanes is None:
        parts.append(_lanes_mechanics(ir))
    parts.append(_fixed_blocks(ir))
    return "\n".join(parts + tail)


def c_source(ir, status: dict) -> str:
    """The C source of the system ``ir``; ``status`` maps the C core's status
    names (``MP_OK``, ...) to their values (``mechpy._core.STATUS``)."""
    if ir.kind == "lagrangian":
        return _lagrangian_source(ir, status)
    if ir.kind == "mechanics":
        return _mechanics_source(ir, status)
    return _equations_source(ir, status)
