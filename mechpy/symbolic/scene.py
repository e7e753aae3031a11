"""The scene of a user's compiled system: :class:`CompiledScene`.

It binds a generated library (:mod:`.codegen`, :mod:`.build`) to the one
integrator engine as a system of kind ``"compiled"``, or, with
``backend="numpy"``, evaluates the same expression blocks in Python through
``sympy.lambdify`` (slower, no compiler needed).
"""
from __future__ import annotations

import ctypes

import numpy as np

from .. import _core
from .._validate import as_array, as_finite_result, as_scalar, band_of_pattern
from ..scenes import Scene, _state_vector

__all__ = ["CompiledScene"]

#: Outputs and their lengths: per function, (C symbol, length as a function of
#: (n, nc, k)).
_FUNCS = {
    "rhs": ("mp_gen_rhs", lambda n, nc, k: n),
    "jac": ("mp_gen_jac", lambda n, nc, k: n * n),
    "energy": ("mp_gen_energy", lambda n, nc, k: 1),
    "momenta": ("mp_gen_momenta", lambda n, nc, k: nc),
    "multipliers": ("mp_gen_multipliers", lambda n, nc, k: k),
    "constraint_forces": ("mp_gen_constraint_forces", lambda n, nc, k: nc),
    "constraints": ("mp_gen_constraints", lambda n, nc, k: 2 * k),
}


def _state_scale(Y) -> np.ndarray:
    """Per row of the states Y (k, n): max(1, max |y|), the size an initial
    state's constraint residuals are measured against (so that the check
    reads the same in any units).  ndarray methods, not np.max's wrapper: it
    runs before every solve."""
    scale = np.abs(Y).max(axis=1)
    np.maximum(scale, 1.0, out=scale)
    return scale


def _first_over(values, limit):
    """(row, column) of the first entry of ``values`` (k, m) whose size is
    not within its row's ``limit`` (k,) (NaN is not), or None: which
    constraint of which initial state an error names."""
    ok = np.abs(values) <= limit[:, None]
    if ok.all():
        return None
    i, c = np.argwhere(~ok)[0]
    return int(i), int(c)


def _guard(fn):
    """fn (made by sympy.lambdify), with a function that NumPy lacks (lambdify
    leaves its name undefined) reported as a ValueError naming it."""
    def call(*args):
        try:
            return fn(*args)
        except NameError as exc:
            name = getattr(exc, "name", None) or str(exc)
            raise ValueError(f"backend='numpy': the system uses {name}, which "
                             "sympy.lambdify cannot evaluate with NumPy; rewrite it") from None
    return call


class _NumpyFunctions:
    """The IR's blocks as NumPy functions of (t, y, p), one state at a time."""

    def __init__(self, kind, nc, k, T, Y, P, Z, blocks):
        import sympy as sp
        self.kind, self.nc, self.k = kind, nc, k
        self.na = nc + k
        self.f = {}
        for name, exprs in blocks.items():
            args = (T, Y, P, Z) if name == "D" else (T, Y, P)
            self.f[name] = _guard(sp.lambdify(args, list(exprs), "numpy"))

    def _solve(self, t, y, p):
        from ..errors import SingularityError
        A = np.array(self.f["A"](t, y, p), dtype=float).reshape(self.na, self.na)
        b = np.array(self.f["b"](t, y, p), dtype=float)
        if np.linalg.cond(A) > 1e15:
            raise SingularityError("the mass matrix d2L/dqd2 (with the constraint Jacobian) "
                                   f"is singular at t = {t!r}, y = {list(y)}")
        return A, np.linalg.solve(A, b)

    def __call__(self, what, t, y, p):
        nc, k = self.nc, self.k
        if self.kind == "equations":
            if what == "rhs":
                return np.array(self.f["f"](t, y, p), dtype=float)
            if what == "jac":
                return np.array(self.f["J"](t, y, p), dtype=float)
            return np.array(self.f[what](t, y, p), dtype=float)
        if what in ("energy", "momenta", "lag"):
            return np.array(self.f[what](t, y, p), dtype=float)
        if what == "constraints":
            return np.array(self.f["g"](t, y, p), dtype=float)
        A, z = self._solve(t, y, p)
        if what == "rhs":
            return np.concatenate([y[nc:], z[:nc]])
        if what == "jac":
            D = np.array(self.f["D"](t, y, p, z), dtype=float).reshape(self.na, 2 * nc)
            X = np.linalg.solve(A, D)[:nc]
            J = np.zeros((2 * nc, 2 * nc))
            J[:nc, nc:] = np.eye(nc)
            J[nc:] = X
            return J.reshape(-1)
        lam = -z[nc:]
        if what == "multipliers":
            return lam
        if what == "constraint_forces":
            return A[nc:, :nc].T @ lam
        raise KeyError(what)


class CompiledScene(Scene):
    """A system derived from the user's SymPy expressions, compiled to C.

    Made by :func:`mechpy.lagrangian` or :func:`mechpy.equations`; see there
    for the meaning of the state and of each method.  It is a
    :class:`mechpy.scenes.Scene`: ``mp.solve`` and ``mp.solve_many`` run its
    generated right-hand side and Jacobian in C with the GIL released (the
    NumPy backend calls Python at each evaluation).
    """

    def __init__(self, meta: dict, params: dict, backend: str = "c", numpy_fns=None):
        self._meta = meta
        names = meta["param_names"]
        if set(params) != set(names):
            unknown = sorted(set(params) - set(names))
            missing = sorted(set(names) - set(params))
            raise TypeError(f"parameters {names}: unknown {unknown}, missing {missing}")
        self._params = {nm: as_scalar(params[nm], f"params[{nm!r}]") for nm in names}
        self._dim = int(meta["n"])
        self._nc = int(meta["nc"])
        self._k = int(meta["k"])
        self._backend = backend
        nz = meta.get("jac_nonzeros")   # equations only: their Jacobian's band, or None
        self._jac_band = (None if nz is None else
                          band_of_pattern([e[0] for e in nz], [e[1] for e in nz], self._dim))
        self._vec = np.array(list(self._params.values()), dtype=np.float64)
        self._eqs = None
        solve = ("the mass matrix d2L/dqd2" + (" with the constraint Jacobian" if self._k
                                               else "")
                 if meta["kind"] == "lagrangian" else meta["kind"])
        self._context = {w: f"{w} of the compiled system: {solve}" for w in _FUNCS}
        if backend == "c":
            from .build import build
            self._lib, self._path, self._compiled = build(meta["source"])
            self._addr = {w: ctypes.cast(getattr(self._lib, sym), ctypes.c_void_p).value
                          for w, (sym, _) in _FUNCS.items()
                          if w != "constraints" or self._k}
            self._addr_lag = ctypes.cast(self._lib.mp_gen_lagrangian, ctypes.c_void_p).value
            # the lane rhs of ensembles (absent for very large systems)
            lanes = getattr(self._lib, "mp_gen_lanes", None)
            self._addr_lanes = (None if lanes is None
                                else ctypes.cast(lanes, ctypes.c_void_p).value)
            # the fixed-step blocks with the rhs inlined (compose: separable only)
            self._addr_blocks = (
                ctypes.cast(self._lib.mp_gen_rk4, ctypes.c_void_p).value,
                ctypes.cast(self._lib.mp_gen_compose, ctypes.c_void_p).value
                if int(meta["nq"]) else None)
            self._np = None
        elif backend == "numba":
            from .jit import cfuncs
            self._jit = cfuncs(meta)     # kept: the addresses live as long as they do
            self._addr = _JitAddresses(self._jit)
            self._addr_lanes = None          # ensembles: one trajectory at a time
            self._addr_blocks = (None, None)  # fixed steps call the rhs
            self._np = None
            self._compiled = False
        elif backend == "numpy":
            if numpy_fns is None:
                numpy_fns = _numpy_from_meta(meta)
            self._np = numpy_fns
            self._compiled = False
        else:
            raise ValueError(f"backend must be 'c', 'numba' or 'numpy', got {backend!r}")

    # -- the scene interface --------------------------------------------------
    @property
    def params(self) -> dict:
        """The parameters (a copy), in the order of the parameter vector."""
        return dict(self._params)

    def _vector(self) -> np.ndarray:
        return self._vec.copy()

    def replace(self, **changes) -> "CompiledScene":
        """A copy with some parameters changed (same library, no recompilation)."""
        unknown = set(changes) - set(self._params)
        if unknown:
            raise TypeError(f"unknown parameter(s) {sorted(unknown)}; parameters are "
                            f"{list(self._params)}")
        p = self.params
        p.update(changes)
        return CompiledScene(self._meta, p, self._backend, self._np)

    def _spec(self, method: str) -> tuple:
        """The system spec for _core: the generated library's functions (the
        scalar rhs, the Jacobian, the second-order split, the lane rhs or None,
        the fixed-step blocks rk4 and compose or None)."""
        nq = int(self._meta["nq"])
        if self._backend in ("c", "numba"):
            return ("compiled", (self._addr["rhs"], self._addr["jac"], nq, self._addr_lanes,
                                 *self._addr_blocks), self._vector())
        if nq:
            return ("python2", self._py_accel, ())
        return ("python", self._py_rhs, ())

    def _py_rhs(self, t, y, *p):
        return self._np("rhs", t, y, np.asarray(p) if p else self._vec)

    def _py_accel(self, t, q, *p):
        y = np.concatenate([q, np.zeros_like(q)])
        return self._np("rhs", t, y, np.asarray(p) if p else self._vec)[self._nc:]

    def _eval(self, what, t, y, *, flat=False):
        """Function ``what`` at (t, y) for y of shape (dim, ...) -> (m, nout).
        t is a scalar, or times broadcast against y's trailing axes (as a
        solution's ``(sol.t, sol.y)``): one C call per distinct time."""
        if np.ndim(t) == 0:
            t, Y, y = self._state_rows(t, y)
            return self._raw(what, t, Y), y.shape[1:]
        y = self._states(y)
        ta = as_array(t, "t")
        try:
            shape = np.broadcast_shapes(ta.shape, y.shape[1:])
        except ValueError:
            raise ValueError(f"t must be a scalar or broadcast against y's trailing shape "
                             f"{y.shape[1:]}, got shape {ta.shape}") from None
        y = y.reshape(y.shape[:1] + (1,) * (len(shape) - y.ndim + 1) + y.shape[1:])
        Y = np.ascontiguousarray(np.broadcast_to(y, y.shape[:1] + shape)
                                 .reshape(self._dim, -1).T)
        times, which = np.unique(np.broadcast_to(ta, shape).reshape(-1), return_inverse=True)
        out = None
        for j, tj in enumerate(times):
            rows = which == j
            part = self._raw(what, float(tj), np.ascontiguousarray(Y[rows]))
            if out is None:
                out = np.empty((Y.shape[0], part.shape[1]))
            out[rows] = part
        if out is None:   # no states
            out = self._raw(what, 0.0, Y)
        return out, shape

    def _raw(self, what, t, Y, vec=None):
        """Function ``what`` at time t for the rows of Y (m, dim) -> (m, nout),
        with the parameter vector ``vec`` (default: the scene's)."""
        nout = _FUNCS[what][1](self._dim, self._nc, self._k)
        vec = self._vec if vec is None else vec
        if self._backend in ("c", "numba"):
            try:
                return _core.compiled_eval(self._addr[what], vec, t, Y, nout,
                                           self._context[what])
            except _core.SingularityError:
                msg = (self._singular_where(t, Y, vec) if self._meta["kind"] == "lagrangian"
                       else None)
                if msg is None:
                    raise
                raise _core.SingularityError(f"{what} of the compiled system: {msg}") from None
        return np.array([self._np(what, t, row, vec) for row in Y]).reshape(-1, nout)

    def _singular_where(self, t, Y, vec):
        """What is singular in a Lagrangian system's A = [[M, C^T], [C, 0]] at
        the first state of Y (m, dim) where it is: the mass matrix
        M = d2L/dq'dq' (no kinetic term at all, or none for some coordinate's
        velocity, or M rank-deficient), else the constraints' Jacobian C =
        dg/dq (read off the rates g' = C q' + dg/dt, linear in q'); None when
        neither is (the solve's own message stands)."""
        n, k, names = self._nc, self._k, self._meta["names"]
        for y in np.asarray(Y, dtype=float).reshape(-1, self._dim):
            at = f"at t = {float(t)!r}, y = {y.tolist()}"
            v = self._lagrangian_values(t, y[:n], y[n:]) if self._backend == "c" else \
                _core.compiled_eval(self._addr["lag"], vec, float(t), y[None, :],
                                    1 + 2 * n + 3 * n * n, "L")[0]
            M = v[1 + 2 * n + 2 * n * n:].reshape(n, n)
            if not np.all(np.isfinite(M)):
                continue        # the status would have been MP_ENONFINITE
            scale = max(np.abs(M).max(), np.finfo(float).tiny)
            if not np.any(M):
                return (f"L has no kinetic term: its mass matrix d2L/dq'dq' is 0 {at} (L "
                        "must hold the velocities, e.g. m q'**2/2)")
            zero = [names[i] for i in range(n) if not np.any(M[i])]
            if zero:
                return (f"L has no kinetic term in the velocity of {zero}: d2L/dq'dq' has a "
                        f"zero row {at}")
            rank = np.linalg.matrix_rank(M, tol=n * np.finfo(float).eps * scale)
            if rank < n:
                return f"the mass matrix d2L/dq'dq' is singular {at} (rank {rank} of {n})"
            if k:
                g0 = self._raw("constraints", t, np.r_[y[:n], np.zeros(n)][None, :], vec)[0]
                C = np.array([self._raw("constraints", t, np.r_[y[:n], e][None, :],
                                        vec)[0, k:] - g0[k:] for e in np.eye(n)]).T
                rank = np.linalg.matrix_rank(C)
                if rank < k:
                    return (f"the constraints' Jacobian dg/dq has rank {rank} of {k} {at}: the "
                            "constraints are dependent or stationary in q there")
        return None

    @staticmethod
    def _shape(out, rest, lead):
        """(m, prod(lead)) -> lead + rest."""
        return np.moveaxis(out, 0, -1).reshape(tuple(lead) + tuple(rest))

    def rhs(self, t, y) -> np.ndarray:
        """dy/dt at (t, y); y of shape (dim, ...).  NonFiniteError where the
        equations give a NaN or inf (as a solve reports it)."""
        out, rest = self._eval("rhs", t, y)
        as_finite_result(out, f"the right-hand side at t = {t}",
                         "the equations give NaN or inf at this state (outside their domain?)")
        return self._shape(out, rest, (self._dim,))

    def jacobian(self, t, y) -> np.ndarray:
        """df/dy, shape (dim, dim, ...): analytic, through the same linear solve
        as the right-hand side (d q''/dq = A^-1 (db/dq - (dA/dq) z))."""
        out, rest = self._eval("jac", t, y)
        return self._shape(out, rest, (self._dim, self._dim))

    def energy(self, y, t: float = 0.0):
        """The Jacobi integral h = sum q' dL/dq' - L for states (dim, ...) -> (...)
        (for :func:`mechpy.equations`, the ``energy`` expression given there)."""
        if not self._meta["has_energy"]:
            raise AttributeError("this system has no energy: give mp.equations(..., "
                                 "energy=expression)")
        out, rest = self._eval("energy", t, y)
        return out.reshape(rest) if rest else float(out[0, 0])

    def momenta(self, y, t: float = 0.0) -> np.ndarray:
        """Generalized momenta p = dL/dq', shape (n, ...) for y of shape (dim, ...)."""
        self._need_lagrangian("momenta")
        out, rest = self._eval("momenta", t, y)
        return self._shape(out, rest, (self._nc,))

    def multipliers(self, t, y) -> np.ndarray:
        """The Lagrange multipliers lambda, shape (k, ...): the equations of
        motion are d/dt dL/dq' - dL/dq = Q + sum_c lambda_c dg_c/dq.  t is a
        scalar or times broadcast against y's trailing axes:
        ``multipliers(sol.t, sol.y)``."""
        self._need_constraints("multipliers")
        out, rest = self._eval("multipliers", t, y)
        return self._shape(out, rest, (self._k,))

    def constraint_forces(self, t, y) -> np.ndarray:
        """The generalized constraint forces sum_c lambda_c dg_c/dq, shape (n, ...)
        (in Cartesian coordinates, the force the constraint exerts); t as for
        :meth:`multipliers`: ``constraint_forces(sol.t, sol.y)``."""
        self._need_constraints("constraint_forces")
        out, rest = self._eval("constraint_forces", t, y)
        return self._shape(out, rest, (self._nc,))

    def constraints(self, t, y) -> np.ndarray:
        """The constraint values g and their rates g', shape (2k, ...)."""
        self._need_constraints("constraints")
        out, rest = self._eval("constraints", t, y)
        return self._shape(out, rest, (2 * self._k,))

    def _need_lagrangian(self, what):
        if self._meta["kind"] != "lagrangian":
            raise AttributeError(f"{what} needs a system made by mp.lagrangian")

    def _need_constraints(self, what):
        if not self._k:
            raise AttributeError(f"{what}: the system has no constraints")

    # -- initial-state check (mechpy.solve calls it) ----------------------------
    def _check_initial(self, t0, y0, params=None, tol: float = 1e-8, singular: bool = True):
        """Raise if an initial state (validated float64, (n,) or rows (k, n),
        with ``params`` rows (k, p) if given) violates a constraint (|g| or
        |g'| above tol, scaled by the state's size) or, with ``singular``, the
        mass matrix is singular there (``singular=False``: the solve reports
        it, as a status under ``errors="status"``).  One C evaluation per
        function (per row with params)."""
        if not (singular or self._constrained()):
            return
        Y = np.ascontiguousarray(y0.reshape(-1, self._dim))
        if params is None:
            vecs = [(self._vec, slice(None))]
        else:
            if params.shape[1] != self._vec.size:
                raise ValueError(f"params must have {self._vec.size} columns (the scene's "
                                 f"parameters {list(self._params)}), got {params.shape[1]}")
            vecs = [(np.ascontiguousarray(params[i]), slice(i, i + 1))
                    for i in range(Y.shape[0])]
        for vec, rows in vecs:
            self._check_rows(t0, Y[rows], vec, rows.start or 0, y0.ndim > 1, tol, singular)

    def _constrained(self) -> bool:
        """Whether an initial state has constraints to meet (_check_rows)."""
        return bool(self._k)

    def _check_rows(self, t0, Y, vec, first, many, tol, singular=True):
        if self._k:
            gv = self._raw("constraints", t0, Y, vec)
            # squared: a constraint such as x^2 + y^2 - l^2 (and its rate) grows
            # as the square of the state's size
            limit = tol * _state_scale(Y) ** 2
            checks = (("constraint", "g", slice(0, self._k),
                       "place the initial state on the constraint"),
                      ("the rate of constraint", "g'", slice(self._k, None),
                       "the initial velocity must be tangent to the constraint"))
            for what, sym, cols, hint in checks:
                bad = _first_over(gv[:, cols], limit)
                if bad is not None:
                    i, c = bad
                    row = f" (row {first + i} of y0s)" if many else ""
                    raise ValueError(f"y0{row} violates {what} {c}: {sym} = "
                                     f"{gv[i, cols][c]!r} ({self._meta['constraints'][c]} = 0); "
                                     f"{hint}")
        if singular and self._meta["kind"] == "lagrangian":
            self._raw("rhs", t0, Y, vec)   # raises SingularityError naming the mass matrix

    # -- what a Lagrangian gives besides -----------------------------------------
    @property
    def coordinates(self) -> list:
        """The names of the coordinates (mp.lagrangian) or of the states
        (mp.equations)."""
        return list(self._meta["names"])

    @property
    def speeds(self) -> list:
        """The names of the coordinates' velocities, ``"q'"`` for a coordinate
        q (mp.lagrangian); none for a first-order system (mp.equations)."""
        if self._meta["kind"] == "lagrangian":
            return [nm + "'" for nm in self._meta["names"]]
        return []

    @property
    def states(self) -> list:
        """The names of the state components, in order: the coordinates then
        their velocities (mp.lagrangian), the states (mp.equations)."""
        if self._meta["kind"] == "equations":
            return list(self._meta["names"])
        return self.coordinates + self.speeds

    def _velocity_index(self, iq: int) -> int | None:
        """Where coordinate iq's velocity sits: paired by name (mp.lagrangian's
        q', mp.mechanics' speeds when as many as the coordinates); a
        first-order system (mp.equations) names none: its state is read as
        (q, v), v after q."""
        if self._meta["kind"] == "equations":
            from ..events import _velocity_after
            return _velocity_after(iq, self._dim)
        return super()._velocity_index(iq)

    @property
    def drawing(self) -> str | None:
        """The drawing of mechpy's animations for this system: a compiled
        system has none of its own, so the first drawing of the registry that
        fits its description (``mechpy._motion.fitting``), or None."""
        from .._motion import fitting
        return fitting(self)

    def initial_state(self, values) -> np.ndarray:
        """A state vector (dim,) from ``values``: a dict keyed by the names of
        :attr:`states` or by the SymPy objects they name (a coordinate
        ``q(t)``, its velocity ``q(t).diff()``, a dynamic symbol of
        ``mp.mechanics``' model, a plain symbol of ``mp.equations``), every
        state once; or a sequence of dim numbers, returned as an array.

        Raises
        ------
        ValueError
            A state without a value, a key that names no state, a state
            given twice (by its name and by its symbol), or a sequence of
            the wrong length.

        Examples
        --------
        >>> import sympy
        >>> x, v = sympy.symbols("x v")
        >>> osc = mp.equations([v, -x], [x, v])
        >>> osc.initial_state({"v": 0.5, x: 1.0}).tolist()
        [1.0, 0.5]
        """
        return _state_vector(self.states, values, _state_name)

    @property
    def cyclic(self) -> list:
        """Names of the ignorable coordinates (absent from L, the forces and
        the constraints): their momenta are conserved."""
        return list(self._meta["cyclic"])

    @property
    def c_source(self) -> str:
        """The generated C source."""
        return self._meta["source"]

    def symbolic(self):
        """The right-hand side as SymPy expressions: a
        :class:`mechpy.scenes.SymbolicField` (``f``, ``y``, ``t``, ``params``),
        from the equations of motion this system was built from (for a
        Lagrangian, M(q) q'' = F solved for q'' symbolically: meant for the few
        coordinates a live view shows).  A system with constraints has none
        (its accelerations carry the multipliers): ValueError."""
        import sympy as sp

        from ..scenes import SymbolicField
        n, nc = self._dim, self._nc
        if self._meta["kind"] == "lagrangian":
            M, b, y, t, params = self._mass_form()
            acc = list(M.LUsolve(b)) if nc > 1 else [b[0] / M[0, 0]]
            f = y[nc:] + [sp.simplify(e) if nc <= 2 else e for e in acc]
        else:
            y = list(sp.symbols(f"y0:{n}"))
            t = sp.Symbol("t")
            eqs = self.equations
            states = [e.lhs.args[0] for e in eqs]
            sub = dict(zip(states, y))
            f = [e.rhs.xreplace(sub) for e in eqs]
            params = self._param_symbols(f)
        return SymbolicField(f, y, t, params)

    def _mass_form(self):
        """A Lagrangian's equations as M(q) q'' = F(q, q', t) in the state
        symbols: ``(M (nc, nc), F (nc, 1), y, t, params)`` (SymPy matrices; y,
        t and params as :meth:`symbolic` names them), for an evaluator that
        solves the linear system numerically at each state (the live page's
        LU) rather than through a symbolic inverse.  ValueError for a system
        with constraints (its accelerations carry the multipliers) or of
        :func:`mechpy.equations` (first order: no mass matrix)."""
        import sympy as sp
        if self._meta["kind"] != "lagrangian":
            raise ValueError("a first-order system (mp.equations) has no mass matrix")
        if self._k:
            raise ValueError("a system with constraints has no symbolic field of its own "
                             "(its accelerations carry the Lagrange multipliers)")
        n, nc = self._dim, self._nc
        y = list(sp.symbols(f"y0:{n}"))
        t = sp.Symbol("t")
        q = [sp.Function(nm)(t) for nm in self._meta["names"]]
        a = sp.symbols(f"mp_a0:{nc}")
        sub = {qi.diff(t, 2): ai for qi, ai in zip(q, a)}
        sub2 = {qi.diff(t): y[nc + i] for i, qi in enumerate(q)}
        sub3 = {qi: y[i] for i, qi in enumerate(q)}
        rows = [(e.lhs - e.rhs).subs(sub).subs(sub2).subs(sub3) for e in self.equations]
        M, b = sp.linear_eq_to_matrix(rows, a)
        return M, b, y, t, self._param_symbols(list(M) + list(b))

    def _param_symbols(self, exprs) -> dict:
        """{symbol: value} of the parameters, each symbol as ``exprs`` hold it
        (with its assumptions), else a plain one of its name."""
        import sympy as sp
        byname = {str(s): s for e in exprs for s in sp.sympify(e).free_symbols}
        return {byname.get(nm, sp.Symbol(nm)): v for nm, v in self._params.items()}

    @property
    def equations(self) -> list:
        """The equations of motion as SymPy ``Eq``: M q'' = F + Q + C^T lambda
        (and g = 0) for a Lagrangian, y' = f for a first-order system."""
        if self._eqs is None:
            import sympy as sp
            from sympy.physics.mechanics import dynamicsymbols  # noqa: F401
            self._eqs = sp.sympify(self._meta["equations"])
        return list(self._eqs)

    @property
    def _lagrangian_c(self) -> tuple:
        """(address of mp_gen_lagrangian, parameter vector) for the variational
        solvers: ``int f(size_t m, const double *t, const double *q, const
        double *qd, double *out, void *params)``."""
        self._need_lagrangian("_lagrangian_c")
        if self._backend != "c":
            raise AttributeError("_lagrangian_c needs backend='c'")
        return self._addr_lag, self._vector()

    def _lagrangian_values(self, t, q, qd) -> np.ndarray:
        """L and its derivatives (K = 1 + 2d + 3d^2 values) at one point."""
        d = self._nc
        K = 1 + 2 * d + 3 * d * d
        q = np.ascontiguousarray(q, dtype=float)
        qd = np.ascontiguousarray(qd, dtype=float)
        if self._backend == "numpy":
            return np.array(self._np("lag", t, np.concatenate([q, qd]), self._vec))
        if self._backend == "numba":
            return _core.compiled_eval(self._addr["lag"], self._vec, float(t),
                                       np.concatenate([q, qd])[None, :], K, "L")[0]
        out = np.zeros(K)
        dp = ctypes.POINTER(ctypes.c_double)
        f = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_size_t, dp, dp, dp, dp,
                             ctypes.c_void_p)(self._addr_lag)
        tt = np.array([float(t)])
        f(1, tt.ctypes.data_as(dp), q.ctypes.data_as(dp), qd.ctypes.data_as(dp),
          out.ctypes.data_as(dp), self._vec.ctypes.data)
        return out

    def small_oscillations(self, q0, t: float = 0.0):
        """Normal modes about the equilibrium q0: K = -d2L/dqdq and
        M = d2L/dq'dq' at (q0, q' = 0) -> :class:`mechpy.modes.Modes`.

        Raises ValueError if q0 is not an equilibrium (dL/dq != 0 there).
        Generalized forces (damping, drive) are not part of the modes.
        """
        from ..modes import normal_modes
        self._need_lagrangian("small_oscillations")
        if self._k:
            raise ValueError("small_oscillations needs an unconstrained system: write L in "
                             "independent coordinates")
        d = self._nc
        q0 = as_array(q0, "q0", shape=(d,))
        v = self._lagrangian_values(t, q0, np.zeros(d))
        grad = v[1:1 + d]
        o = 1 + 2 * d
        K = -v[o:o + d * d].reshape(d, d)
        M = v[o + 2 * d * d:o + 3 * d * d].reshape(d, d)
        scale = max(1.0, float(np.max(np.abs(K))) * max(1.0, float(np.max(np.abs(q0)))))
        if not np.all(np.abs(grad) <= 1e-9 * scale):
            raise ValueError(f"q0 = {list(q0)} is not an equilibrium: dV/dq = {list(-grad)}")
        return normal_modes(K, M)

    # -- identity, pickling -------------------------------------------------------
    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self._params.items())
        return (f"CompiledScene({self._meta['kind']}, states={self._meta['names']}, {args}"
                f"{'' if self._backend == 'c' else ', backend=' + self._backend})")

    def __eq__(self, other):
        return (type(other) is CompiledScene and self._meta["source"] == other._meta["source"]
                and self._meta["equations"] == other._meta["equations"]
                and self._params == other._params and self._backend == other._backend)

    def __hash__(self):
        return hash((self._meta["source"], tuple(self._params.items())))

    def __reduce__(self):
        meta = self._meta
        if self._backend in ("numpy", "numba") and "blocks" not in meta:
            raise TypeError("a numpy-backend scene made in this process pickles only with "
                            "its blocks: rebuild it with mp.lagrangian on the other side")
        return (_rebuild_compiled, (meta, self._params, self._backend))


def _state_name(k) -> str | None:
    """The state name a SymPy key stands for: ``q`` for q(t), ``q'`` for
    q(t).diff(t), a symbol's name; None for anything else."""
    import sympy as sp
    if isinstance(k, sp.Derivative) and isinstance(k.expr, sp.core.function.AppliedUndef):
        return k.expr.func.__name__ + "'" * k.derivative_count
    if isinstance(k, sp.core.function.AppliedUndef):
        return k.func.__name__
    if isinstance(k, sp.Symbol):
        return k.name
    return None


class _JitAddresses(dict):
    """A numba build's function addresses by name, each compiled when first
    asked for (see jit.CFuncs)."""

    def __init__(self, fns):
        super().__init__()
        self._fns = fns

    def __missing__(self, what):
        addr = self[what] = self._fns[what].address
        return addr


def _rebuild_compiled(meta, params, backend):
    return CompiledScene(meta, params, backend)


def _numpy_from_meta(meta):
    import sympy as sp
    blocks = {k: sp.sympify(v) for k, v in meta["blocks"].items()}
    n, nc, k = meta["n"], meta["nc"], meta["k"]
    T = sp.Symbol("mp_t")
    Y = [sp.Symbol(f"mp_y{i}") for i in range(n)]
    Z = [sp.Symbol(f"mp_z{i}") for i in range(nc + k)]
    P = [sp.Symbol(f"mp_p{i}") for i in range(len(meta["param_names"]))]
    return _NumpyFunctions(meta["kind"], nc, k, T, Y, P, Z, blocks)
