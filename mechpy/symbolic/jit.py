"""Compiled systems without a C compiler: the same blocks as numba ``cfunc``\\ s.

``mp.lagrangian(..., backend="numba")`` (and ``mp.equations``), or the default
``backend="c"`` where no C compiler is found (:func:`mechpy.symbolic.build.
have_compiler`; one warning per process), print the system's expression
blocks (the IR's A, b, D, energy, ... after SymPy's ``cse``) as Python and
compile them with numba (LLVM, no C compiler) into C-callable functions of the
generated library's signatures, ``int f(double t, const double *y, double
*out, void *params)``.  The engine binds them exactly as it binds a C build
(``_core``'s ``"compiled"`` system, its right-hand side called with the GIL
released); the dense solve is the C build's (``mp_lu``: LU with partial
pivoting, the same pivots, tolerance and order of operations), so both builds
give the same solution to round-off.  What the numba build lacks: the lane
right-hand side of ensembles (``solve_many`` runs trajectory by trajectory)
and the fixed-step blocks with the rhs inlined (fixed steps call the rhs).

Every function is compiled with numba's NumPy error model
(``error_model="numpy"``): a division by zero gives inf or NaN as IEEE 754
says and as the C build computes it, and the engine reports the non-finite
value (NonFiniteError).  Python's error model would raise inside the cfunc,
where nothing can catch it: numba prints "Exception ignored" and the caller
reads whatever the output held.

The generated module is written to the cache folder (``jit_<key>.py``) and
numba caches its machine code beside it (``cache=True``): a second process
loads the system without compiling.
"""
from __future__ import annotations

import os

__all__ = ["available", "module_source", "cfuncs"]

#: The functions made for a system (the scene's names; "lag" gives L and its
#: derivatives at one point, as mp_gen_lagrangian does per point).
NAMES = ("rhs", "jac", "energy", "momenta", "multipliers", "constraint_forces",
         "constraints", "lag")


def available() -> bool:
    """Whether numba imports."""
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def _printer_class():
    """SymPy's Python printer with sign printed as the C build prints it (1,
    -1, or the argument itself at 0 and NaN; SymPy's own gives +-1 for NaN)."""
    from sympy.printing.pycode import PythonCodePrinter

    class Printer(PythonCodePrinter):
        def _print_sign(self, e):
            a = self._print(e.args[0])
            return f"(1.0 if ({a}) > 0.0 else (-1.0 if ({a}) < 0.0 else ({a})))"
    return Printer


def _block(name: str, exprs, with_z: bool = False, sparse: bool = False) -> str:
    """A numba-compiled function ``name(t, y, p[, z], out)`` writing ``exprs``
    (in mp_t, mp_y*, mp_p*, mp_z*) to out[], after common subexpression
    elimination.  ``sparse``: out[] zeroed by one loop, then only the entries
    not identically zero written (the module grows with the nonzeros)."""
    import sympy as sp

    printer = _printer_class()
    exprs = [sp.sympify(e) for e in exprs]
    subs, red = sp.cse(exprs, symbols=sp.numbered_symbols("mp_c"))
    pr = printer({"fully_qualified_modules": True, "standard": "python3"})
    body = [f"    {s} = {pr.doprint(e)}" for s, e in subs]
    if sparse:
        body += [f"    for i in range({len(red)}):", "        out[i] = 0.0"]
    body += [f"    out[{i}] = {pr.doprint(e)}" for i, e in enumerate(red)
             if not (sparse and e == 0)]
    text = "\n".join(body)
    import re
    used = sorted(set(re.findall(r"\bmp_[ypz]\d+\b", text)), key=lambda s: (s[3], int(s[4:])))
    head = [f"    {u} = {u[3]}[{u[4:]}]" for u in used]     # mp_y3 = y[3], mp_p0 = p[0]
    if re.search(r"\bmp_t\b", text):
        head.append("    mp_t = t")
    args = "t, y, p, z, out" if with_z else "t, y, p, out"
    return (f"@numba.njit(cache=True, fastmath=False, error_model=\"numpy\")\n"
            f"def {name}({args}):\n"
            + "\n".join(head + body + ["    return 0"]) + "\n")


_RUNTIME = '''
@numba.njit(cache=True, error_model="numpy")
def mp_lu(A, piv, dinv):
    """mp_lu of the C build (codegen.RUNTIME), operation for operation."""
    amax = 0.0
    for i in range(NA * NA):
        a = abs(A[i])
        if not math.isfinite(a):
            return MP_ENONFINITE
        if a > amax:
            amax = a
    tol = NA * 2.220446049250313e-16 * amax
    for k in range(NA):
        p = k
        best = abs(A[k * NA + k])
        for i in range(k + 1, NA):
            a = abs(A[i * NA + k])
            if a > best:
                best = a
                p = i
        if not (best > tol):
            return MP_ESINGULAR
        piv[k] = p
        if p != k:
            for j in range(NA):
                s = A[k * NA + j]
                A[k * NA + j] = A[p * NA + j]
                A[p * NA + j] = s
        inv = 1.0 / A[k * NA + k]
        dinv[k] = inv
        for i in range(k + 1, NA):
            m = A[i * NA + k] * inv
            A[i * NA + k] = m
            if m != 0.0:
                for j in range(k + 1, NA):
                    A[i * NA + j] -= m * A[k * NA + j]
    return MP_OK


@numba.njit(cache=True, error_model="numpy")
def mp_lu_solve(LU, piv, dinv, x):
    for k in range(NA):
        p = piv[k]
        if p != k:
            s = x[k]
            x[k] = x[p]
            x[p] = s
    for i in range(1, NA):
        s = x[i]
        for j in range(i):
            s -= LU[i * NA + j] * x[j]
        x[i] = s
    for i in range(NA - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, NA):
            s -= LU[i * NA + j] * x[j]
        x[i] = s * dinv[i]


@numba.njit(cache=True, error_model="numpy")
def gen_solve(t, y, p, A0, LU, piv, dinv, z):
    gen_A(t, y, p, A0)
    if NA == 1:
        piv[0] = 0
        LU[0] = A0[0]
        if not math.isfinite(LU[0]):
            return MP_ENONFINITE
        if LU[0] == 0.0:
            return MP_ESINGULAR
        dinv[0] = 1.0 / LU[0]
        gen_b(t, y, p, z)
        z[0] *= dinv[0]
        return MP_OK
    for i in range(NA * NA):
        LU[i] = A0[i]
    rc = mp_lu(LU, piv, dinv)
    if rc != MP_OK:
        return rc
    gen_b(t, y, p, z)
    mp_lu_solve(LU, piv, dinv, z)
    return MP_OK
'''

_LAGRANGIAN = '''
def rhs(t, y_, out_, p_):
    y = numba.carray(y_, (NS,))
    out = numba.carray(out_, (NS,))
    p = numba.carray(p_, (NP,))
    A0 = STACKF(NA * NA)
    LU = STACKF(NA * NA)
    dinv = STACKF(NA)
    z = STACKF(NA)
    piv = STACKI(NA)
    rc = gen_solve(t, y, p, A0, LU, piv, dinv, z)
    if rc != MP_OK:
        return rc
    for i in range(NC):
        out[i] = y[NC + i]
        out[NC + i] = z[i]
    return MP_OK


def jac(t, y_, out_, p_):
    y = numba.carray(y_, (NS,))
    J = numba.carray(out_, (NS * NS,))
    p = numba.carray(p_, (NP,))
    A0 = STACKF(NA * NA)
    LU = STACKF(NA * NA)
    dinv = STACKF(NA)
    z = STACKF(NA)
    piv = STACKI(NA)
    D = STACKF(NA * 2 * NC)
    col = STACKF(NA)
    rc = gen_solve(t, y, p, A0, LU, piv, dinv, z)
    if rc != MP_OK:
        return rc
    gen_D(t, y, p, z, D)
    for i in range(NS * NS):
        J[i] = 0.0
    for i in range(NC):
        J[i * NS + NC + i] = 1.0
    for c in range(2 * NC):
        for r in range(NA):
            col[r] = D[r * 2 * NC + c]
        mp_lu_solve(LU, piv, dinv, col)
        for i in range(NC):
            J[(NC + i) * NS + c] = col[i]
    return MP_OK


def energy(t, y_, out_, p_):
    gen_energy(t, numba.carray(y_, (NS,)), numba.carray(p_, (NP,)), numba.carray(out_, (1,)))
    return MP_OK


def momenta(t, y_, out_, p_):
    gen_momenta(t, numba.carray(y_, (NS,)), numba.carray(p_, (NP,)),
                numba.carray(out_, (NC,)))
    return MP_OK


def lag(t, y_, out_, p_):
    gen_lag(t, numba.carray(y_, (NS,)), numba.carray(p_, (NP,)),
            numba.carray(out_, (1 + 2 * NC + 3 * NC * NC,)))
    return MP_OK
'''

_CONSTRAINED = '''
def constraints(t, y_, out_, p_):
    gen_g(t, numba.carray(y_, (NS,)), numba.carray(p_, (NP,)), numba.carray(out_, (2 * NK,)))
    return MP_OK


@numba.njit(cache=True, error_model="numpy")
def _lambda(t, y, p, A0, z):
    LU = STACKF(NA * NA)
    dinv = STACKF(NA)
    piv = STACKI(NA)
    return gen_solve(t, y, p, A0, LU, piv, dinv, z)


def multipliers(t, y_, out_, p_):
    y = numba.carray(y_, (NS,))
    out = numba.carray(out_, (NK,))
    A0 = STACKF(NA * NA)
    z = STACKF(NA)
    rc = _lambda(t, y, numba.carray(p_, (NP,)), A0, z)
    if rc != MP_OK:
        return rc
    for c in range(NK):
        out[c] = -z[NC + c]
    return MP_OK


def constraint_forces(t, y_, out_, p_):
    y = numba.carray(y_, (NS,))
    out = numba.carray(out_, (NC,))
    A0 = STACKF(NA * NA)
    z = STACKF(NA)
    rc = _lambda(t, y, numba.carray(p_, (NP,)), A0, z)
    if rc != MP_OK:
        return rc
    for i in range(NC):
        s = 0.0
        for c in range(NK):
            s += A0[(NC + c) * NA + i] * -z[NC + c]
        out[i] = s
    return MP_OK
'''

_EQUATIONS = '''
def rhs(t, y_, out_, p_):
    gen_f(t, numba.carray(y_, (NS,)), numba.carray(p_, (NP,)), numba.carray(out_, (NS,)))
    return MP_OK


def jac(t, y_, out_, p_):
    gen_J(t, numba.carray(y_, (NS,)), numba.carray(p_, (NP,)), numba.carray(out_, (NS * NS,)))
    return MP_OK
'''

_ENERGY_EQ = '''
def energy(t, y_, out_, p_):
    gen_energy(t, numba.carray(y_, (NS,)), numba.carray(p_, (NP,)), numba.carray(out_, (1,)))
    return MP_OK
'''


def _stacks(text: str, dims: dict) -> str:
    """STACKF(expr) / STACKI(expr) in a template -> a stack array of that many
    doubles / C ints (expr in NS, NC, NK, NA: a literal in the module)."""
    import re

    def sub(m):
        n = int(eval(m.group(2), {"__builtins__": {}}, dims))
        fn = "stack_f64" if m.group(1) == "F" else "stack_intc"
        return f"numba.carray({fn}({n}), ({n},))"
    return re.sub(r"STACK([FI])\(([^()]+)\)", sub, text)


def module_source(meta: dict, status: dict) -> str:
    """The Python source of a system's numba module, from its stored
    description (``meta`` with ``blocks``, see symbolic._meta)."""
    import sympy as sp
    blocks = {k: sp.sympify(v) for k, v in meta["blocks"].items()}
    n, nc, k = int(meta["n"]), int(meta["nc"]), int(meta["k"])
    lagr = meta["kind"] == "lagrangian"
    head = [f"# Generated by mechpy.symbolic.jit: {meta['kind']} system, states "
            f"{meta['names']}, parameters {meta['param_names']}.",
            "import math", "", "import numba", "import numpy as np",
            "from numba import types", "",
            "from mechpy.symbolic._jit_rt import stack_f64, stack_intc", "",
            f"NS = {n}", f"NC = {nc}", f"NK = {k}", f"NA = {nc + k}",
            f"NP = {len(meta['param_names'])}"]
    head += [f"{s} = {int(status[s])}" for s in ("MP_OK", "MP_ESINGULAR", "MP_ENONFINITE")]
    head.append("SIG = types.intc(types.float64, types.CPointer(types.float64), "
                "types.CPointer(types.float64), types.CPointer(types.float64))\n\n")
    parts = ["\n".join(head)]
    if lagr:
        for name in ("A", "b", "energy", "momenta", "lag"):
            parts.append(_block(f"gen_{name}", blocks[name]))
        parts.append(_block("gen_D", blocks["D"], with_z=True))
        if k:
            parts.append(_block("gen_g", blocks["g"]))
        parts += [_RUNTIME, _LAGRANGIAN] + ([_CONSTRAINED] if k else [])
    else:
        parts += [_block("gen_f", blocks["f"]), _block("gen_J", blocks["J"], sparse=True)]
        if "energy" in blocks:
            parts += [_block("gen_energy", blocks["energy"]), _ENERGY_EQ]
        parts.append(_EQUATIONS)
    dims = dict(NS=n, NC=nc, NK=k, NA=nc + k)
    return _stacks("\n\n".join(parts), dims)


class CFuncs(dict):
    """The system's numba cfuncs by name (:data:`NAMES`, the ones the system
    has), each compiled when first asked for (rhs and jac at once)."""

    def __init__(self, mod):
        super().__init__()
        self._mod = mod
        self.names = [nm for nm in NAMES if hasattr(mod, nm)]

    def __missing__(self, name):
        import numba
        if name not in self.names:
            raise KeyError(name)

        def make():
            return numba.cfunc(self._mod.SIG, cache=True, error_model="numpy")(
                getattr(self._mod, name))
        try:
            f = make()
        except Exception:
            # numba's cache files of this module (jit_<key>.*.nbi, .nbc) may be
            # truncated or damaged (an interrupted write, a full disk): numba
            # then raises from its unpickling in every later process.  They are
            # deleted and the function compiled again, once; an error that is
            # not the cache's comes back from the second attempt.
            if not _purge_cache(self._mod):
                raise
            f = make()
        self[name] = f
        return f


def _purge_cache(mod) -> bool:
    """Delete numba's cache files of the generated module ``mod`` (index and
    data, ``<module file>.*.nbi`` / ``.nbc``, in the folder numba's locator
    chose); whether there were any."""
    import glob
    import numba
    stem = os.path.splitext(os.path.basename(mod.__file__))[0]
    folders = set()
    for obj in vars(mod).values():
        cache = getattr(obj, "_cache", None)
        path = getattr(cache, "cache_path", None)
        if isinstance(obj, numba.core.dispatcher.Dispatcher) and isinstance(path, str):
            folders.add(path)
    gone = False
    for folder in folders:
        for f in glob.glob(os.path.join(glob.escape(folder), glob.escape(stem) + ".*.nb[ci]")):
            try:
                os.unlink(f)
                gone = True
            except FileNotFoundError:
                pass
    return gone


#: The systems built in this process, by their description's hash (a scene's
#: ``replace`` and a second ``mp.lagrangian`` of the same system reuse them).
_MADE: dict = {}


def cfuncs(meta: dict) -> CFuncs:
    """The system's numba cfuncs (:class:`CFuncs`), from the module written to
    (or found in) the cache folder."""
    import hashlib
    import importlib.util
    import json
    import sys

    from .. import _core
    from . import build
    mkey = hashlib.sha256(json.dumps([meta[k] for k in ("kind", "n", "nc", "k", "names",
                                                       "param_names", "blocks")],
                                     sort_keys=True).encode()).hexdigest()
    if mkey in _MADE:
        return _MADE[mkey]
    source = module_source(meta, _core.STATUS)
    import numba
    key = hashlib.sha256((source + "\0" + numba.__version__).encode()).hexdigest()[:32]
    name = f"jit_{key}"
    folder = build.cache_dir()
    path = os.path.join(folder, name + ".py")
    try:
        current = None
        if os.path.exists(path):
            with open(path) as f:
                current = f.read()
        if current != source:
            fd, tmp = build._mkstemp(folder, ".py")
            with os.fdopen(fd, "w") as f:
                f.write(source)
            os.replace(tmp, path)
    except (OSError, build._Unwritable) as exc:
        folder = build._private(folder, exc)
        path = os.path.join(folder, name + ".py")
        with open(path, "w") as f:
            f.write(source)
    modname = "mechpy_jit_" + key
    mod = sys.modules.get(modname)
    if mod is None:
        spec = importlib.util.spec_from_file_location(modname, path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        sys.modules[modname] = mod
    out = CFuncs(mod)
    out["rhs"], out["jac"]    # noqa: B018 (compiled now: the engine takes their addresses)
    _MADE[mkey] = out
    return out
