"""A system's field printed for the page: GLSL for the GPU, JavaScript for the
page's own integrator.

Both come from one symbolic form (:meth:`mechpy.scenes.Scene.symbolic`, the
row's right-hand side; or a compiled system's equations), so the page
evaluates exactly the right-hand side the C engine does.  In the printed code
the state is ``s`` (GLSL ``vec4 s``: ``s.x .. s.w``; JavaScript ``s[0] ..``),
the time ``t`` and parameter j is ``p[j]`` (a uniform array in GLSL): a slider
changes a uniform, never the program.
"""
from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from sympy.printing.glsl import GLSLPrinter
from sympy.printing.jscode import JavascriptCodePrinter

#: GLSL's names of a vec4's components
_XYZW = "xyzw"


@dataclass
class Field:
    """dy/dt = f(t, y; p) with ``params`` by name, ready to print."""

    f: list                 # SymPy expressions in y, t, p
    y: list                 # state symbols
    t: sp.Symbol
    p: list                 # parameter symbols, in the order of ``values``
    names: list             # parameter names
    values: list            # parameter values (floats)
    time_dependent: bool

    @property
    def dim(self) -> int:
        return len(self.f)

    def autonomous_at(self, values: dict) -> bool:
        """Whether the field is free of t with the parameters at ``values`` (by
        name; the others at their own values): a drive switched off."""
        if not self.time_dependent:
            return True
        sub = {s: values.get(nm, v) for s, nm, v in zip(self.p, self.names, self.values)}
        return not any(self.t in sp.sympify(e).xreplace(sub).free_symbols for e in self.f)


def field_of(system) -> Field:
    """The :class:`Field` of a scene or compiled system (ValueError when it has
    no symbolic form: a Python callable, a variable-size chain)."""
    sym = getattr(system, "symbolic", None)
    if sym is None:
        raise ValueError(f"system must be a mechpy scene or compiled system with a symbolic "
                         f"form (mp.lagrangian, mp.equations), got {type(system).__name__}")
    sf = sym()
    p = list(sf.params)
    f = [sp.sympify(e) for e in sf.f]
    # a parameter the field does not use stays (it may still be on a slider: it
    # then changes nothing, honestly)
    td = any(sf.t in e.free_symbols for e in f)
    return Field(f, list(sf.y), sf.t, p, [str(s) for s in p],
                 [float(v) for v in sf.params.values()], td)


class _Glsl(GLSLPrinter):
    """GLSL ES 3.00 with float arithmetic only: integers and rationals as
    float literals, integer powers as products (GLSL's pow is undefined for a
    negative base), half-integer powers through sqrt."""

    _mp_math = {"sin": "mp_sin", "cos": "mp_cos", "tan": "mp_tan", "exp": "mp_exp",
                "log": "mp_log"}

    def _print_Function(self, e):
        name = self._mp_math.get(type(e).__name__)
        if name is not None:
            return f"{name}({', '.join(self._print(a) for a in e.args)})"
        return super()._print_Function(e)

    def _print_Integer(self, e):
        return f"{int(e)}.0"

    def _print_Rational(self, e):
        return f"({int(e.p)}.0/{int(e.q)}.0)"

    def _print_Float(self, e):
        return repr(float(e)) if "." in repr(float(e)) or "e" in repr(float(e)) \
            else repr(float(e)) + ".0"

    def _print_NumberSymbol(self, e):
        return repr(float(e))

    _print_Pi = _print_Exp1 = _print_NumberSymbol

    def _print_Pow(self, e):
        b, x = e.as_base_exp()
        if x.is_Integer and abs(int(x)) <= 8:
            n = abs(int(x))
            prod = "*".join([f"({self._print(b)})"] * n) if n else "1.0"
            return f"(1.0/({prod}))" if x < 0 else f"({prod})"
        if x == sp.S.Half:
            return f"sqrt({self._print(b)})"
        if x == -sp.S.Half:
            return f"(1.0/sqrt({self._print(b)}))"
        if x.is_Rational and x.q == 2:
            return f"(sqrt({self._print(b)})*({self._print(b ** ((x.p - 1) // 2))}))"
        if b == sp.E:
            return f"mp_exp({self._print(x)})"
        return f"mp_pow({self._print(b)}, {self._print(x)})"

    def _print_Abs(self, e):
        return f"abs({self._print(e.args[0])})"

    def _print_Piecewise(self, e):
        out = self._print(e.args[-1][0]) if e.args[-1][1] == sp.true else "0.0"
        for val, cond in reversed(e.args[:-1] if e.args[-1][1] == sp.true else e.args):
            out = f"(({self._print(cond)}) ? ({self._print(val)}) : ({out}))"
        return out

    def _print_Relational(self, e):
        return f"{self._print(e.lhs)} {e.rel_op} {self._print(e.rhs)}"


class _Js(JavascriptCodePrinter):
    """JavaScript in double precision (Math.*), Piecewise as conditionals."""

    def _print_Piecewise(self, e):
        out = self._print(e.args[-1][0]) if e.args[-1][1] == sp.true else "NaN"
        for val, cond in reversed(e.args[:-1] if e.args[-1][1] == sp.true else e.args):
            out = f"(({self._print(cond)}) ? ({self._print(val)}) : ({out}))"
        return out


def _names(fd: Field, glsl: bool) -> dict:
    sub = {}
    for i, s in enumerate(fd.y):
        sub[s] = sp.Symbol(f"s.{_XYZW[i]}" if glsl else f"s[{i}]")
    for j, s in enumerate(fd.p):
        sub[s] = sp.Symbol(f"p[{j}]")
    sub[fd.t] = sp.Symbol("t")
    return sub


def _check_printable(fd: Field) -> None:
    bad = set()
    for e in fd.f:
        for a in sp.preorder_traversal(e):
            if isinstance(a, (sp.Derivative, sp.Integral, sp.Sum)) or a.has(sp.I):
                bad.add(type(a).__name__)
            elif isinstance(a, sp.core.function.AppliedUndef):
                bad.add(str(a))
    if bad:
        raise ValueError(f"the field holds {sorted(bad)}, which a page cannot evaluate")


def glsl(fd: Field) -> str:
    """The body of ``vec4 mp_field(vec4 s, float t)``: common subexpressions as
    floats, the result in ``f`` (components past the dimension stay 0)."""
    _check_printable(fd)
    sub = _names(fd, True)
    reps, exprs = sp.cse([e.xreplace(sub) for e in fd.f], symbols=sp.numbered_symbols("c"))
    pr = _Glsl()
    lines = [f"{'bool' if isinstance(v, sp.logic.boolalg.Boolean) else 'float'} {s} = "
             f"{pr.doprint(v)};" for s, v in reps]
    lines += [f"f.{_XYZW[i]} = {pr.doprint(e)};" for i, e in enumerate(exprs)]
    return "\n".join(lines)


def javascript(fd: Field) -> str:
    """The body of ``function (s, t, p)`` returning the array dy/dt."""
    _check_printable(fd)
    sub = _names(fd, False)
    reps, exprs = sp.cse([e.xreplace(sub) for e in fd.f], symbols=sp.numbered_symbols("c"))
    pr = _Js()
    lines = [f"const {s} = {pr.doprint(v)};" for s, v in reps]
    lines.append("return [" + ", ".join(pr.doprint(e) for e in exprs) + "];")
    return "\n".join(lines)
