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

import math
import re
from dataclasses import dataclass

import sympy as sp
from sympy.printing.glsl import GLSLPrinter
from sympy.printing.codeprinter import PrintMethodNotImplementedError
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


#: The functions a page evaluates (GLSL on the GPU, JavaScript in the page), by SymPy's
#: name; sqrt and the other powers are Pow, printed apart.  The reciprocal ones (cot, sec,
#: csc, coth, sech, csch) are printed as 1/(tan, cos, ...).
SUPPORTED = ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh",
             "asinh", "acosh", "atanh", "cot", "sec", "csc", "coth", "sech", "csch", "exp",
             "log", "erf", "erfc", "Abs", "sign", "floor", "ceiling", "Max", "Min",
             "Heaviside", "Piecewise")

_RECIPROCAL = {sp.cot: sp.tan, sp.sec: sp.cos, sp.csc: sp.sin, sp.coth: sp.tanh,
               sp.sech: sp.cosh, sp.csch: sp.sinh}

#: Exponents up to this size print as a product in GLSL; larger integers through mp_powi
#: (repeated squaring); integers beyond int32 (all even) through mp_pow.
_INLINE_POWER = 8
_INT32 = 2**31 - 1


def _integer_exponent(x):
    """The exponent as a Python int when it is an integer or an integer-valued Float
    (x**2.0 is x**2: C's pow gives a negative base's sign for it), else None."""
    if x.is_Integer:
        return int(x)
    if x.is_Float and math.isfinite(float(x)) and float(x).is_integer():
        return int(float(x))
    return None


def _float_literal(v: float, glsl: bool) -> str:
    """A float constant as a literal of the language: GLSL has no inf or NaN literal."""
    if math.isnan(v):
        return "intBitsToFloat(0x7fc00000)" if glsl else "NaN"
    if math.isinf(v):
        if glsl:
            return "intBitsToFloat(0x7f800000)" if v > 0 else "intBitsToFloat(int(0xff800000u))"
        return "Infinity" if v > 0 else "(-Infinity)"
    r = repr(float(v))
    if glsl and "." not in r and "e" not in r:
        r += ".0"
    return f"({r})" if r.startswith("-") else r


class _Literals:
    """Every SymPy number (a Float, pi, E, EulerGamma, ..., inf, nan, zoo) as the
    language's float literal (``_glsl``: the shader's, which has no inf or NaN)."""
    _glsl = False

    def _print_Float(self, e):
        return _float_literal(float(e), self._glsl)

    def _print_NumberSymbol(self, e):
        return _float_literal(float(e), self._glsl)

    _print_Pi = _print_Exp1 = _print_NumberSymbol
    _print_Infinity = _print_NegativeInfinity = _print_NaN = _print_NumberSymbol

    def _print_ComplexInfinity(self, e):
        return _float_literal(float("nan"), self._glsl)


class _Glsl(_Literals, GLSLPrinter):
    """GLSL ES 3.00 with float arithmetic only: integers and rationals as
    float literals, integer powers as products or mp_powi (GLSL's pow is
    undefined for a negative base), half-integer powers through sqrt, any
    other power through mp_pow (C's pow: NaN for a negative base and a
    non-integral exponent, the sign by parity for an integral one); the
    elementary functions through the page's own float32 versions (mp_*:
    GLSL ES leaves the built-ins' precision open)."""

    _glsl = True

    _mp_math = {"sin": "mp_sin", "cos": "mp_cos", "tan": "mp_tan", "exp": "mp_exp",
                "log": "mp_log", "sinh": "mp_sinh", "cosh": "mp_cosh", "tanh": "mp_tanh",
                "asinh": "mp_asinh", "acosh": "mp_acosh", "atanh": "mp_atanh",
                "erf": "mp_erf", "erfc": "mp_erfc"}

    def __init__(self):
        super().__init__({"strict": True})

    def _print_Function(self, e):
        name = self._mp_math.get(type(e).__name__)
        if name is not None:
            return f"{name}({', '.join(self._print(a) for a in e.args)})"
        return super()._print_Function(e)

    def _print_Integer(self, e):
        return f"{int(e)}.0"

    def _print_Rational(self, e):
        return f"({int(e.p)}.0/{int(e.q)}.0)"


    def _print_Pow(self, e):
        b, x = e.as_base_exp()
        n = _integer_exponent(x)
        if n is not None and abs(n) <= _INLINE_POWER:
            prod = "*".join([f"({self._print(b)})"] * abs(n)) if n else "1.0"
            return f"(1.0/({prod}))" if n < 0 else f"({prod})"
        if n is not None and abs(n) <= _INT32:
            return f"mp_powi({self._print(b)}, {n})"
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


class _Js(_Literals, JavascriptCodePrinter):
    """JavaScript in double precision (Math.*), Piecewise as conditionals,
    every number constant as its float literal, powers through Math.pow (C's
    pow for a negative base: never Math.cbrt, which takes a negative base's
    cube root where C gives NaN), erf and erfc through the page's own
    (``mp.erf``, ``mp.erfc`` in static/phase.js: JavaScript has none)."""

    def __init__(self):
        super().__init__({"strict": True})

    def _print_Function(self, e):
        name = type(e).__name__
        if name in ("erf", "erfc"):
            return f"mp.{name}({self._print(e.args[0])})"
        return super()._print_Function(e)


    def _print_Pow(self, e):
        b, x = e.as_base_exp()
        n = _integer_exponent(x)
        if n == -1:
            return f"(1/({self._print(b)}))"
        if x == sp.S.Half:
            return f"Math.sqrt({self._print(b)})"
        if b == sp.E:
            return f"Math.exp({self._print(x)})"
        return f"Math.pow({self._print(b)}, {self._print(x) if n is None else n})"

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
    """ValueError naming what in the field a page cannot evaluate (and what it can)."""
    from ..symbolic.multibody import _dag
    bad, has_i = set(), {}
    # each distinct sub-expression once, children first (a mechanics model's equations
    # share their subtrees: a tree walk meets the bicycle's millions of times)
    for a in _dag([sp.sympify(e) for e in fd.f]):
        has_i[a] = a is sp.I or any(has_i[x] for x in a.args)
        if isinstance(a, (sp.Derivative, sp.Integral, sp.Sum)) or has_i[a]:
            bad.add(type(a).__name__)
        elif isinstance(a, sp.core.function.AppliedUndef):
            bad.add(str(a))
        elif isinstance(a, sp.Function) and type(a).__name__ not in SUPPORTED:
            bad.add(type(a).__name__)
    if bad:
        raise ValueError(f"the field holds {', '.join(sorted(bad))}, which a live page cannot "
                         f"evaluate; it evaluates +, -, *, /, powers, {', '.join(SUPPORTED)} "
                         f"and the number constants (pi, E, EulerGamma, ...)")


def _prepare(fd: Field, glsl: bool) -> list:
    """The field's expressions in the printed names, reciprocal functions as 1/(...)."""
    from ..symbolic.multibody import _dag, _replace
    _check_printable(fd)
    sub = _names(fd, glsl)
    exprs = [sp.sympify(e) for e in fd.f]
    present = {type(a) for a in _dag(exprs)} & set(_RECIPROCAL)     # replace walks the tree
    out, memo = [], {}
    for e in exprs:
        for rf, f in _RECIPROCAL.items():
            if rf in present:
                e = e.replace(rf, lambda a, f=f: 1 / f(a, evaluate=False))
        out.append(_replace(e, sub, memo))      # xreplace, each shared subtree once
    return out


def _doprint(pr, e, lang: str) -> str:
    try:
        return pr.doprint(e)
    except PrintMethodNotImplementedError as err:     # a gap in the list above: say so plainly
        raise ValueError(f"the field's {lang} cannot be printed ({err.args[0].splitlines()[0]}); "
                         f"a live page evaluates {', '.join(SUPPORTED)}") from None


#: What may appear in the printed code besides numbers and operators: the names the
#: printers write.  :func:`check_code` refuses anything else, so a page never meets a
#: SyntaxError or an undefined name in its own field.
_JS_NAMES = frozenset(
    ["const", "return", "s", "t", "p", "NaN", "Infinity", "true", "false", "mp.erf", "mp.erfc"]
    + ["Math." + m for m in ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh",
                             "cosh", "tanh", "asinh", "acosh", "atanh", "exp", "log", "sqrt",
                             "pow", "abs", "sign", "floor", "ceil", "max", "min")])
_GLSL_NAMES = frozenset(
    ["float", "bool", "f", "s", "t", "p", "true", "false", "sqrt", "abs", "sign", "floor", "ceil",
     "asin", "acos", "atan", "min", "max", "int", "intBitsToFloat", "mp_pow", "mp_powi"]
    + [f"{v}.{c}" for v in "fs" for c in _XYZW]
    + list(_Glsl._mp_math.values()))
_TOKEN = re.compile(r"\s+|(?P<num>(0x[0-9a-fA-F]+u?|(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?))"
                    r"|(?P<name>[A-Za-z_$][\w$]*(\.[A-Za-z_$][\w$]*)?)"
                    r"|(?P<op>&&|\|\||[<>=!]=|[-+*/<>=!?:,;()\[\]])")


def check_code(src: str, lang: str) -> None:
    """ValueError unless ``src`` (a printed field, ``lang`` "javascript" or "glsl") holds
    only the names the printers write (common subexpressions ``c0, c1, ...``), numbers,
    operators and balanced brackets, as statements the page's function body expects.

    Not a parser: a check that what the printers emit stayed within what they are
    meant to emit (an unknown constant, a function printed by name, a declaration
    inside an expression), so that a page is never saved blank."""
    names = _JS_NAMES if lang == "javascript" else _GLSL_NAMES
    what = "JavaScript" if lang == "javascript" else "GLSL"
    locals_ = set()
    for ln, line in enumerate(src.splitlines(), 1):
        pos, depth, toks = 0, [], []
        while pos < len(line):
            m = _TOKEN.match(line, pos)
            if m is None or m.end() == pos:
                raise ValueError(f"the field's printed {what} is not valid (line {ln}: "
                                 f"{line[pos:pos + 30]!r}): a page would show nothing")
            pos = m.end()
            if m.group("name"):
                nm = m.group("name")
                if not (nm in names or nm in locals_ or re.fullmatch(r"c\d+", nm)):
                    raise ValueError(f"the field's printed {what} names {nm!r}, which a page "
                                     f"does not define (line {ln}: {line.strip()[:80]!r})")
                toks.append(nm)
            elif m.group("op"):
                op = m.group("op")
                if op in "([":
                    depth.append(op)
                elif op in ")]":
                    if not depth or depth.pop() != {")": "(", "]": "["}[op]:
                        raise ValueError(f"the field's printed {what} has unbalanced brackets "
                                         f"(line {ln})")
                toks.append(op)
            elif m.group("num"):
                toks.append("0")
        if depth or not toks or toks[-1] != ";" or ";" in toks[:-1]:
            raise ValueError(f"the field's printed {what} is not one statement per line "
                             f"(line {ln}: {line.strip()[:80]!r})")
        if lang == "javascript":
            ok = (toks[:1] == ["const"] and len(toks) > 3 and re.fullmatch(r"c\d+", toks[1])
                  and toks[2] == "=") or toks[:2] == ["return", "["]
        else:
            ok = ((toks[:1] in (["float"], ["bool"]) and len(toks) > 3
                   and re.fullmatch(r"c\d+", toks[1]) and toks[2] == "=")
                  or (len(toks) > 2 and re.fullmatch(r"f\.[xyzw]", toks[0]) and toks[1] == "="))
        if not ok:
            raise ValueError(f"the field's printed {what} is not one statement per line "
                             f"(line {ln}: {line.strip()[:80]!r})")
        if toks[0] in ("const", "float", "bool"):
            locals_.add(toks[1])


def glsl(fd: Field) -> str:
    """The body of ``vec4 mp_field(vec4 s, float t)``: common subexpressions as
    floats, the result in ``f`` (components past the dimension stay 0).

    Raises
    ------
    ValueError
        The field holds a function a page cannot evaluate (named, with the list
        of those it can).
    """
    reps, exprs = sp.cse(_prepare(fd, True), symbols=sp.numbered_symbols("c"))
    pr = _Glsl()
    lines = [f"{'bool' if isinstance(v, sp.logic.boolalg.Boolean) else 'float'} {s} = "
             f"{_doprint(pr, v, 'GLSL')};" for s, v in reps]
    lines += [f"f.{_XYZW[i]} = {_doprint(pr, e, 'GLSL')};" for i, e in enumerate(exprs)]
    out = "\n".join(lines)
    check_code(out, "glsl")
    return out


def javascript(fd: Field) -> str:
    """The body of ``function (s, t, p, mp)`` returning the array dy/dt (``mp``: the
    page's erf and erfc).

    Raises
    ------
    ValueError
        As :func:`glsl`.
    """
    reps, exprs = sp.cse(_prepare(fd, False), symbols=sp.numbered_symbols("c"))
    pr = _Js()
    lines = [f"const {s} = {_doprint(pr, v, 'JavaScript')};" for s, v in reps]
    lines.append("return [" + ", ".join(_doprint(pr, e, "JavaScript") for e in exprs) + "];")
    out = "\n".join(lines)
    check_code(out, "javascript")
    return out
