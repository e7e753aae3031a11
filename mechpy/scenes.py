"""Scenes: physical models whose right-hand side, Jacobian and energy run in C.

A scene models only what it needs: its state holds just its own coordinates,
and an optional term that is off (damping, drive) costs nothing: the C core
binds the cheapest right-hand side for the parameters given.

Every scene has ``dim``, ``params`` (a dict), ``rhs(t, y)``,
``jacobian(t, y)``, ``energy(y)`` (vectorised over trailing axes: ``y`` of
shape (dim, ...) as in ``Solution.y``), ``replace(**changes)``, and pickles.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
functions of states take y (dim, ...) and return (dim, ...), (dim, dim, ...) or (...).
"""
from __future__ import annotations

import ctypes
import functools
import inspect
import re
from typing import NamedTuple

import numpy as np

from . import _core
from ._callbacks import c_address
from ._solution import DenseOutput, Solution, _JoinedDense
from ._system import _method_names
from ._validate import as_array, as_int, as_scalar
from .integrate import solve
from .modes import chain, normal_modes

#: the public names; every scene class defined below is added at the end of the module
__all__ = ["Scene"]


class SymbolicField(NamedTuple):
    """A system's right-hand side in SymPy: dy/dt = f(t, y) with ``params``
    ({symbol: value}) substituted for its parameters (:meth:`Scene.symbolic`).

    Examples
    --------
    >>> import mechpy as mp
    >>> F = mp.scenes.VanDerPol(mu=2.0).symbolic()
    >>> F.f, F.y, F.params
    ([y1, mu*y1*(1 - y0**2) - y0], [y0, y1], {mu: 2.0})
    >>> [float(e.subs(F.params).subs({F.y[0]: 0.5, F.y[1]: 1.0})) for e in F.f]
    [1.0, 1.0]
    """

    f: list
    y: list
    t: object
    params: dict


@functools.lru_cache(maxsize=None)
def _row(model: str) -> dict:
    """The C row of a scene (``_core.scene_info``): dim, parameter names,
    defaults and bounds, separability, whether it has a Lagrangian."""
    return _core.scene_info(model)


def _domain(p: dict) -> str:
    """A parameter's domain from its row entry, as the docs print it."""
    lo, hi = p["lo"], p["hi"]
    if np.isinf(lo) and np.isinf(hi):
        return "finite"
    if lo == 0.0 and np.isinf(hi):
        return "> 0" if p["lo_open"] else ">= 0"
    return (f"{'(' if p['lo_open'] else '['}{lo:g}, {hi:g}{')' if p['hi_open'] else ']'}")


def _row_doc(model: str) -> str:
    """The paragraph on parameters, defaults and domains that a scene's
    docstring gets from its row."""
    row = _row(model)
    items = []
    for p in row["param_info"]:
        d = "required" if p["default"] is None else f"default {p['default']!r}"
        items.append(f"``{p['name']}`` ({d}, {_domain(p)})")
    sep = row["separable"]
    sep = ("never separable" if sep is None else "separable" if sep == "always"
           else f"separable when {sep}")
    states = ", ".join(f"``{nm}``" for nm in row["states"])
    return ("Parameters from the scene's C row: " + ", ".join(items) + f"; {sep} "
            f"(the symplectic methods need it).  Its states, by name (:attr:`Scene.states`): "
            f"{states}" + (" (``#``: 0 to N - 1)" if "#" in states else "") + ".")


def _expand(row: dict, what: str, dim: int) -> list:
    """A row's names (``what``: states, coordinates or speeds) for a state of
    ``dim`` components: the names themselves, or for a variable-size scene
    each pattern with "#" replaced by 0, 1, ... over its block (the row's
    states are the blocks: dim / their number each)."""
    per = dim // len(row["states"])
    return [p.replace("#", str(i)) for p in row[what]
            for i in (range(per) if "#" in p else (0,))]


def _state_vector(names: list, values, name_of=None) -> np.ndarray:
    """A state vector from ``values``: a dict keyed by the state ``names`` (or
    by objects that ``name_of`` turns into them), every state once; or a
    sequence of len(names) numbers.  ValueError naming what is missing,
    unknown or given twice."""
    if not isinstance(values, dict):
        return as_array(values, "y0", shape=(len(names),))
    out = {}
    for k, val in values.items():
        nm = k if isinstance(k, str) else name_of(k) if name_of else None
        if nm not in names:
            raise ValueError(f"y0: {k!r} is not a state of the system (its states: {names})")
        if nm in out:
            raise ValueError(f"y0 gives the state {nm!r} twice")
        out[nm] = as_scalar(val, f"y0[{nm!r}]")
    missing = [nm for nm in names if nm not in out]
    if missing:
        raise ValueError(f"y0 has no value for the state(s) {missing} (its states: {names})")
    return np.array([out[nm] for nm in names])


def _takes_named_states(fn):
    """A scene's own ``initial_state`` that also takes the state as one dict
    keyed by :attr:`Scene.states` (what ``mp.solve`` passes for a dict y0)."""
    @functools.wraps(fn)
    def initial_state(self, *args, **kwargs):
        if len(args) == 1 and not kwargs and isinstance(args[0], dict):
            return _state_vector(self.states, args[0])
        return fn(self, *args, **kwargs)
    return initial_state


def _add_row_doc(cls) -> None:
    """Put the row's paragraph into cls's docstring, before its first numpydoc
    section (or at its end)."""
    doc = inspect.cleandoc(cls.__doc__ or "")
    para = _row_doc(cls._model)
    m = re.search(r"^\w[\w ]*\n-{3,}$", doc, flags=re.M)
    cls.__doc__ = (doc[:m.start()] + para + "\n\n" + doc[m.start():] if m
                   else doc + "\n\n" + para + "\n")


class Scene:
    """Base class of the C scenes (see the module docstring).

    A subclass names its C row (``class Oscillator(Scene, row="Oscillator")``,
    kept as ``_model``).  When the row's scalar
    parameters are the scene's own, the subclass needs nothing more: its
    signature, defaults and checks come from the row.  A scene whose
    parameters are packed into the row's vector (``RigidBody``,
    ``SpringChain``) writes ``__init__`` and calls :meth:`_set` with its
    public parameters and the packed vector.

    Examples
    --------
    Every scene carries its parameters, its right-hand side and Jacobian in C, and
    its energy:

    >>> pend = mp.scenes.Pendulum(length=2.0)
    >>> pend.dim, pend.params
    (2, {'g': 9.81, 'length': 2.0, 'damping': 0.0, 'drive_amplitude': 0.0, 'drive_frequency': 0.0})
    >>> pend.rhs(0.0, np.array([np.pi / 2, 0.0]))                # theta'' = -(g/L) sin(theta)
    array([ 0.   , -4.905])
    >>> print(pend.energy(np.array([0.0, 1.0])))               # L^2 theta_dot^2 / 2
    2.0
    >>> pend.replace(length=1.0).params["length"]
    1.0
    """

    _model: str = ""
    #: the protocol mechpy._system recognises a scene by (no import of this module)
    _is_mechpy_scene = True
    #: the rigid-body splitting methods (rows with "rigid") run on this scene
    _rigid_split = False

    def __init_subclass__(cls, row: str = "", **kwargs):
        super().__init_subclass__(**kwargs)
        if not row:
            return
        cls._model = row
        if "initial_state" in cls.__dict__:
            cls.initial_state = _takes_named_states(cls.__dict__["initial_state"])
        _add_row_doc(cls)
        if "__init__" in cls.__dict__:
            return
        row = _row(cls._model)
        params = [inspect.Parameter(p["name"], inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                    default=(inspect.Parameter.empty if p["default"] is None
                                             else p["default"]))
                  for p in row["param_info"]]
        sig = inspect.Signature(params)

        def __init__(self, *args, **kwargs):
            bound = sig.bind(*args, **kwargs)
            bound.apply_defaults()
            values = {k: as_scalar(v, k) for k, v in bound.arguments.items()}
            self._set(values, np.array(list(values.values()), dtype=np.float64))

        __init__.__signature__ = inspect.Signature(
            [inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)] + params)
        __init__.__doc__ = f"A {cls.__name__} (parameters as in the class docstring)."
        __init__.__qualname__ = f"{cls.__qualname__}.__init__"
        cls.__init__ = __init__

    def _set(self, params: dict, vector: np.ndarray) -> None:
        """Keep the public parameters and the row's vector, checked by the row
        (ValueError naming the parameter); the row gives the dimension."""
        self._vec = np.ascontiguousarray(vector, dtype=np.float64)
        self._dim = int(_core.scene_check(self._model, self._vec))
        self._params = params

    # -- the common interface ------------------------------------------------
    @property
    def dim(self) -> int:
        """Number of state components."""
        return self._dim

    @property
    def params(self) -> dict:
        """The parameters (a copy)."""
        return {k: v.copy() if isinstance(v, np.ndarray) else v for k, v in self._params.items()}

    # -- what the scene says about itself (its C row) ------------------------------
    def _names(self, what: str) -> list:
        return _expand(_row(self._model), what, self._dim)

    @property
    def states(self) -> list:
        """The names of the state components, in order (from the scene's C row)."""
        return self._names("states")

    @property
    def coordinates(self) -> list:
        """The names of the coordinates among :attr:`states`."""
        return self._names("coordinates")

    @property
    def speeds(self) -> list:
        """The names of the coordinates' velocities, in the coordinates' order;
        or the generalized speeds the state holds when they are no
        coordinate's velocity (a rigid body's omega: another count)."""
        return self._names("speeds")

    @property
    def drawing(self) -> str | None:
        """The name of the scene's drawing (``mechpy._motion``), or None."""
        return _row(self._model)["drawing"]

    def _velocity_index(self, iq: int) -> int | None:
        """Where coordinate ``iq``'s velocity sits in the state: from the row's
        speeds (paired with the coordinates when as many); None when the state
        holds none."""
        q, v = self.coordinates, self.speeds
        if len(q) != len(v) or not 0 <= iq < len(q):
            return None
        return self.states.index(v[iq])

    def initial_state(self, values) -> np.ndarray:
        """A state vector (dim,) from ``values``: a dict keyed by the names of
        :attr:`states`, every state once, or a sequence of dim numbers."""
        return _state_vector(self.states, values)

    def replace(self, **changes) -> "Scene":
        """A copy with some parameters changed."""
        p = self.params
        unknown = set(changes) - set(p)
        if unknown:
            raise TypeError(f"{type(self).__name__} got unknown parameter(s) {sorted(unknown)}; "
                            f"parameters are {list(p)}")
        p.update(changes)
        return type(self)(**p)

    def _vector(self) -> np.ndarray:
        return self._vec

    def _columns(self) -> dict:
        """The scalar parameters that rows of :meth:`ensemble_params` vary, by
        name, in the order of the vector: the row's own for a C scene."""
        if self._model:
            return dict(zip(_row(self._model)["params"], self._vec.tolist()))
        return dict(self._params)

    def ensemble_params(self, k: int, /, **columns) -> np.ndarray:
        """Rows of parameters for :func:`mechpy.solve_many`, one per trajectory.

        Each keyword names a parameter and gives one value per row (shape
        (k,)) or one for all; the others keep this scene's values (``k`` is
        positional-only: any name, ``k`` and ``self`` too, is a parameter's).  This is
        what ``solve_many(scene, ..., params={name: values})`` uses.  The
        names are the scene's C row's (``RigidBody``: I1, I2, I3, tau1,
        tau2, tau3); each row is checked as the scene's parameters are.
        """
        base = self._columns()
        unknown = set(columns) - set(base)
        if unknown:
            raise ValueError(f"unknown parameter(s) {sorted(unknown)}; the scene has "
                             f"{list(base)}")
        cols = []
        for name, v in base.items():
            col = as_array(columns.get(name, v), f"params[{name!r}]", min_ndim=0)
            cols.append(np.broadcast_to(col, (k,)) if col.ndim == 0 else col)
        for name, c in zip(base, cols):
            if c.shape != (k,):
                raise ValueError(f"params[{name!r}] must have shape ({k},), got {c.shape}")
        out = np.ascontiguousarray(np.stack(cols, axis=1))
        if self._model and k:
            _core.scene_check(self._model, out)
        return out

    def _state_rows(self, t, y):
        """Check (t, y) with y of shape (dim, ...); -> (t, rows (m, dim), y)."""
        y = self._states(y)
        return as_scalar(t, "t"), np.ascontiguousarray(y.reshape(self._dim, -1).T), y

    def _states(self, y) -> np.ndarray:
        """States y of shape (dim, ...), checked."""
        y = as_array(y, "y", min_ndim=1)
        if y.shape[0] != self._dim:
            raise ValueError(f"y must have {self._dim} components along its first axis, "
                             f"got shape {y.shape}")
        return y

    def _eval(self, what, t, y):
        t, flat, y = self._state_rows(t, y)
        out = _core.scene_eval(self._model, self._vector(), what, t, flat)
        rest = y.shape[1:]
        if what == "energy":
            return out.reshape(rest) if rest else float(out[0])
        if what == "rhs":
            return np.moveaxis(out, 0, -1).reshape(y.shape)
        return np.moveaxis(out, 0, -1).reshape((self._dim, self._dim) + rest)

    def rhs(self, t, y) -> np.ndarray:
        """dy/dt at (t, y); y of shape (dim, ...)."""
        return self._eval("rhs", t, y)

    def __call__(self, t, y):
        return self.rhs(t, y)

    def jacobian(self, t, y) -> np.ndarray:
        """df/dy, shape (dim, dim, ...)."""
        return self._eval("jac", t, y)

    def energy(self, y):
        """The scene's energy for states y of shape (dim, ...) -> shape (...)."""
        return self._eval("energy", 0.0, y)

    def symbolic(self) -> "SymbolicField":
        """The right-hand side as SymPy expressions, from the scene's C row.

        Returns
        -------
        SymbolicField
            ``f`` (dim expressions), ``y`` (the state symbols ``y0, y1, ...``),
            ``t`` (the time symbol) and ``params`` ({symbol: value}, the scene's
            parameters): dy/dt = f(t, y, params), the same right-hand side the C
            engine evaluates (a test checks them against each other).  The live
            views print it to GLSL and JavaScript.

        Raises
        ------
        ValueError
            When the scene has no symbolic form (a variable-size chain, a torque
            given as a callable).
        """
        row = _row(self._model) if self._model else None
        if not row or row["field"] is None or getattr(self, "_torque_fn", None) is not None:
            raise ValueError(f"{type(self).__name__} has no symbolic form (its right-hand "
                             "side is not a fixed set of expressions)")
        import sympy as sp
        y = sp.symbols(f"y0:{self._dim}")
        t = sp.Symbol("t")
        names = list(row["params"])
        syms = {nm: sp.Symbol(nm) for nm in names}
        local = dict(syms, t=t, **{str(s): s for s in y})
        f = [sp.sympify(e, locals=local) for e in row["field"]]
        values = dict(zip(names, self._vector().tolist()))
        return SymbolicField(f, list(y), t, {syms[nm]: values[nm] for nm in names})

    def _lagrangian_spec(self):
        """The C spec of the scene's Lagrangian for :mod:`mechpy.variational`
        (from its row), or None when the row has none."""
        if self._model and _row(self._model)["lagrangian"]:
            return ("scene", self._model, self._vector())
        return None

    def _identity(self) -> tuple:
        """What, besides the type and the vector, tells two scenes apart."""
        return ()

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self._params.items())
        return f"{type(self).__name__}({args})"

    def __eq__(self, other):
        return (type(self) is type(other) and self._model == other._model
                and np.array_equal(self._vector(), other._vector())
                and self._identity() == other._identity())

    def __hash__(self):
        return hash((type(self).__name__, self._model, tuple(self._vector().tolist()),
                     self._identity()))

    def __reduce__(self):
        return (_rebuild, (type(self), self.params))


def _rebuild(cls, params):
    return cls(**params)


class Pendulum(Scene, row="Pendulum"):
    r"""The plane pendulum, optionally damped and driven.

    .. math:: \ddot\theta = -\frac{g}{L}\sin\theta - b\,\dot\theta + A\cos(\Omega t)

    State ``(theta, theta_dot)`` in rad and rad/s.  Parameters: ``g`` (m/s^2),
    ``length`` L (m), ``damping`` b (1/s), ``drive_amplitude`` A (rad/s^2),
    ``drive_frequency`` Omega (rad/s).  ``energy`` is per unit mass (J/kg):
    :math:`E = \tfrac12 L^2\dot\theta^2 + gL(1-\cos\theta)`.

    Examples
    --------
    The period of a small swing is 2 pi sqrt(L/g); at 90 degrees it is longer by
    the factor 2 K(1/2) / pi = 1.18034:

    >>> pend = mp.scenes.Pendulum(g=9.81, length=1.0)
    >>> round(float(pend.period(1e-4)), 6), round(2 * np.pi * (1.0 / 9.81) ** 0.5, 6)
    (2.006067, 2.006067)
    >>> round(float(pend.period(np.pi / 2) / pend.period(1e-8)), 5)
    1.18034
    >>> s = mp.solve(pend, (0, pend.period(2.0)), [2.0, 0.0], rtol=1e-11, atol=1e-12)
    >>> round(float(s.y[0, -1]), 8)                              # back at the start
    2.0
    """

    def period(self, amplitude) -> float:
        r"""Exact period of the free, undamped pendulum released from rest at
        ``amplitude`` (rad): :math:`T = 4\sqrt{L/g}\,K(\sin^2(\theta_0/2))` (s)."""
        a = as_scalar(amplitude, "amplitude")
        if not 0 < abs(a) < np.pi:
            raise ValueError("amplitude must be in (0, pi) in magnitude")
        p = self._params
        return 4.0 * np.sqrt(p["length"] / p["g"]) * _core.ellipk_complement(np.cos(0.5 * a))


class VanDerPol(Scene, row="VanDerPol"):
    r"""The Van der Pol oscillator :math:`\ddot x - \mu(1-x^2)\dot x + x = 0`.

    State ``(x, x_dot)`` (dimensionless); ``mu >= 0``.  ``energy`` is
    :math:`(x^2 + \dot x^2)/2`, the energy of its harmonic part.

    Examples
    --------
    For mu = 0 it is the harmonic oscillator (energy conserved); for mu > 0 every
    start is drawn to the limit cycle of amplitude 2.00862 (mu = 1):

    >>> s = mp.solve(mp.scenes.VanDerPol(0.0), (0, 2 * np.pi), [1.0, 0.0], rtol=1e-10, atol=1e-12)
    >>> np.round(s.y[:, -1], 8) + 0.0
    array([1., 0.])
    >>> T, A = mp.phase.limit_cycle(mp.scenes.VanDerPol(1.0), [0.5, 0.0])
    >>> round(T, 6), round(A, 5)
    (6.663287, 2.00862)
    """


class Duffing(Scene, row="Duffing"):
    r"""The Duffing oscillator
    :math:`\ddot x + \delta\dot x + \alpha x + \beta x^3 = \gamma\cos(\omega t)`.

    State ``(x, x_dot)``.  ``energy`` is
    :math:`\dot x^2/2 + \alpha x^2/2 + \beta x^4/4`.

    Examples
    --------
    beta = 0 is the harmonic oscillator x = cos(sqrt(alpha) t); a hardening spring
    (beta > 0) keeps its energy alpha x^2/2 + beta x^4/4 + v^2/2:

    >>> s = mp.solve(mp.scenes.Duffing(4.0, 0.0), (0, 1), [1.0, 0.0], rtol=1e-10, atol=1e-12)
    >>> round(float(s.y[0, -1]), 8), round(float(np.cos(2.0)), 8)
    (-0.41614684, -0.41614684)
    >>> duff = mp.scenes.Duffing(1.0, 1.0)
    >>> s = mp.solve(duff, (0, 20), [1.0, 0.0], rtol=1e-10, atol=1e-12)
    >>> round(float(duff.energy(s.y[:, -1])), 8), 1 / 2 + 1 / 4
    (0.75, 0.75)
    """


class Kepler(Scene, row="Kepler"):
    r"""The Kepler problem in a plane: :math:`\ddot{\mathbf r} = -\mu\,\mathbf r/|\mathbf r|^3`.

    State ``(x, y, vx, vy)``; ``mu`` = GM (length^3/time^2).  Separable: the
    symplectic methods apply.  ``energy`` is the specific orbital energy
    :math:`|\mathbf v|^2/2 - \mu/r`.

    Examples
    --------
    An orbit of eccentricity 0.5 returns to its pericentre after 2 pi sqrt(a^3/mu),
    and its energy is -mu / (2a):

    >>> kep = mp.scenes.Kepler(mu=1.0)
    >>> y0 = kep.initial_state(0.5, a=1.0)
    >>> y0
    array([0.5       , 0.        , 0.        , 1.73205081])
    >>> s = mp.solve(kep, (0, 2 * np.pi), y0, rtol=1e-11, atol=1e-12)
    >>> np.round(s.y[:, -1] - y0, 7) + 0.0
    array([0., 0., 0., 0.])
    >>> round(float(kep.energy(y0)), 12)
    -0.5
    """

    def initial_state(self, eccentricity, a=1.0):
        """State at pericentre of the orbit with semi-major axis ``a`` and the
        given eccentricity (0 <= e < 1); its period is 2 pi sqrt(a^3/mu)."""
        e = as_scalar(eccentricity, "eccentricity", nonnegative=True, hi=1.0 - 1e-15)
        a = as_scalar(a, "a", positive=True)
        mu = self._params["mu"]
        return np.array([a * (1 - e), 0.0, 0.0, np.sqrt(mu / a * (1 + e) / (1 - e))])


class RestrictedThreeBody(Scene, row="RestrictedThreeBody"):
    r"""The planar circular restricted three-body problem, rotating frame.

    .. math:: \ddot x = x + 2\dot y - \mu'\frac{x+\mu}{r_1^3} - \mu\frac{x-\mu'}{r_2^3},\quad
              \ddot y = y - 2\dot x - \mu'\frac{y}{r_1^3} - \mu\frac{y}{r_2^3}

    with :math:`\mu' = 1-\mu` (dimensionless units; the default mass ratio is
    the Earth-Moon value of Arenstorf's orbits).  State ``(x, y, vx, vy)``;
    ``energy`` is the Jacobi integral in energy form
    :math:`|\mathbf v|^2/2 - (x^2+y^2)/2 - \mu'/r_1 - \mu/r_2`.

    Examples
    --------
    The Jacobi integral is conserved along an orbit in the rotating frame (here a
    start between the Earth and the Moon):

    >>> r3 = mp.scenes.RestrictedThreeBody()
    >>> y0 = np.array([0.5, 0.0, 0.0, 0.3])
    >>> s = mp.solve(r3, (0, 2), y0, rtol=1e-12, atol=1e-12)
    >>> bool(abs(r3.energy(s.y[:, -1]) - r3.energy(y0)) < 1e-9)
    True
    """


class Foucault(Scene, row="Foucault"):
    r"""The Foucault pendulum at a latitude, small swings, in the local
    horizontal plane (Marion & Thornton, Example 10.5):

    .. math:: \ddot x = -\frac{g}{L}x + 2\Omega_z\dot y,\qquad
              \ddot y = -\frac{g}{L}y - 2\Omega_z\dot x,\qquad
              \Omega_z = \Omega\sin\lambda

    x east, y north.  State ``(x, y, vx, vy)`` in m and m/s.  Parameters:
    ``latitude`` (degrees, in [-90, 90]), ``length`` L (m), ``g`` (m/s^2),
    ``omega`` Omega (rad/s, the Earth's sidereal rate by default).  The plane
    of swing turns clockwise (seen from above) in the north at
    :math:`\Omega\sin\lambda`.  ``energy`` is per unit mass (J/kg),
    :math:`(v_x^2+v_y^2)/2 + (g/L)(x^2+y^2)/2`, conserved (Coriolis does no work).

    Examples
    --------
    The plane of swing turns at Omega sin(latitude); at the pole once a sidereal day:

    >>> f = mp.scenes.Foucault(90.0, 67.0)
    >>> round(2 * np.pi / f.precession_rate), round(2 * np.pi / 7.2921159e-05)
    (86164, 86164)
    >>> round(2 * np.pi / mp.scenes.Foucault(48.857, 67.0).precession_rate / 3600, 2)   # Paris
    31.78
    """

    @property
    def precession_rate(self) -> float:
        """Rate at which the plane of swing turns, Omega sin(latitude) [rad/s]
        (positive: clockwise seen from above)."""
        p = self._params
        return p["omega"] * float(np.sin(np.radians(p["latitude"])))

def _row_defaults(model: str, n: int) -> tuple:
    """The defaults of the first n parameters of a row."""
    return tuple(p["default"] for p in _row(model)["param_info"][:n])


class RigidBody(Scene, row="RigidBody"):
    r"""A rigid body about its centre of mass: Euler's equations in the
    principal body frame,

    .. math:: I_1\dot\omega_1 = (I_2 - I_3)\,\omega_2\omega_3 + \tau_1 \quad\text{(cyclic)},

    and, only when ``orientation=True``, the orientation as a unit quaternion
    ``q`` (scalar last, body to space) with :math:`\dot q = \tfrac12 q\otimes(\omega, 0)`.

    State ``omega`` (3,) in rad/s, or ``(omega, q)`` (7,).  Parameters:
    ``moments`` (I1, I2, I3) principal moments (kg m^2), positive and obeying
    the triangle inequality; ``torque`` the body-frame torque (N m): None, a
    constant (3,), or a C function
    ``void torque(double t, const double *y, double *tau, void *user_data)``
    of the scene state y (omega, and q with orientation) writing tau (3,),
    given as a ctypes function pointer, a ``scipy.LowLevelCallable`` or a
    numba ``cfunc``; it runs in C with the GIL released (:func:`mechpy.solve`,
    :func:`mechpy.solve_many`).  ``energy`` is the rotational kinetic energy
    :math:`T = \tfrac12\sum_i I_i\omega_i^2` (J).  The geometric methods
    ``"rigid:split"`` (order 2) and ``"rigid:split4"`` (order 4) of
    :func:`mechpy.solve` keep ``|L|`` and ``|q|`` to round-off; they take a constant
    torque, not a callback.

    Examples
    --------
    Torque-free, the kinetic energy is conserved and the motion is the exact
    one of :func:`mechpy.rigid.free_rotation`:

    >>> body = mp.scenes.RigidBody(moments=(1.0, 2.0, 3.0))
    >>> w0 = np.array([0.1, 0.2, 1.0])
    >>> s = mp.solve(body, (0, 5), w0, rtol=1e-11, atol=1e-12)
    >>> exact = mp.rigid.free_rotation((1.0, 2.0, 3.0), w0, [5.0])[0]
    >>> bool(np.abs(s.y[:, -1] - exact).max() < 1e-9)
    True
    >>> round(float(body.energy(s.y[:, -1])), 10), round(float(body.energy(w0)), 10)
    (1.545, 1.545)
    """

    _rigid_split = True

    def __init__(self, moments=_row_defaults("RigidBody", 3), torque=None, orientation=False):
        m = as_array(moments, "moments", shape=(3,))
        self._torque_fn = self._torque_c = None
        if torque is None:
            tau = np.zeros(3)
        elif (c := c_address(torque)) is not None:
            self._torque_fn, self._torque_c, tau = torque, c, np.zeros(3)
        elif callable(torque):
            raise TypeError("torque must be a constant body-frame vector (3,) or a C function "
                            "void torque(double t, const double *y, double *tau, void *user_data)"
                            " (ctypes, scipy.LowLevelCallable or numba cfunc); for a torque "
                            "written in Python, give mp.solve a Python right-hand side")
        else:
            tau = as_array(torque, "torque", shape=(3,))
        if not isinstance(orientation, (bool, np.bool_)):
            raise TypeError("orientation must be True or False")
        self._model = "RigidBodyOriented" if orientation else "RigidBody"
        if self._torque_fn is None and torque is not None:
            torque = tuple(tau.tolist())
        self._set(dict(moments=tuple(m.tolist()), torque=torque, orientation=bool(orientation)),
                  np.concatenate([m, tau]))

    def _spec(self, method: str) -> tuple:
        """The system spec for _core: the scene, with the torque callback if any."""
        spec = ("scene", self._model, self._vector())
        if self._torque_c is None:
            return spec
        if _method_names()[method]["rigid"]:
            raise ValueError(f"method {method!r} needs a torque-free body or a constant torque; "
                             "with a torque callback use a general method (dop853, rk4, "
                             "radau, ...)")
        return spec + (self._torque_c,)

    def _callback_torque(self, t, y):
        """The callback's torque at (t, y) for states y of shape (dim, m) -> (3, m)."""
        dp = ctypes.POINTER(ctypes.c_double)
        fn = ctypes.CFUNCTYPE(None, ctypes.c_double, dp, dp, ctypes.c_void_p)(self._torque_c[0])
        out = np.zeros((y.shape[1], 3))
        for k in range(y.shape[1]):
            yk = np.ascontiguousarray(y[:, k])
            fn(t, yk.ctypes.data_as(dp), out[k].ctypes.data_as(dp), self._torque_c[1])
        return out.T

    def rhs(self, t, y) -> np.ndarray:
        f = super().rhs(t, y)
        if self._torque_c is not None:
            y = as_array(y, "y", min_ndim=1)
            tau = self._callback_torque(as_scalar(t, "t"), y.reshape(self._dim, -1))
            f[:3] += (tau / self.moments[:, None]).reshape((3,) + y.shape[1:])
        return f

    def jacobian(self, t, y) -> np.ndarray:
        """df/dy, shape (dim, dim, ...); with a torque callback, the torque's
        part by central differences (about 1e-10 relative)."""
        J = super().jacobian(t, y)
        if self._torque_c is None:
            return J
        y = as_array(y, "y", min_ndim=1)
        flat = y.reshape(self._dim, -1)
        t = as_scalar(t, "t")
        dJ = np.empty((3, self._dim, flat.shape[1]))
        for j in range(self._dim):
            e = np.zeros((self._dim, 1))
            e[j] = 1e-6 * np.maximum(1.0, np.abs(flat[j]))
            d = self._callback_torque(t, flat + e) - self._callback_torque(t, flat - e)
            dJ[:, j] = d / (2 * e[j]) / self.moments[:, None]
        J[:3] += dJ.reshape((3, self._dim) + y.shape[1:])
        return J

    @property
    def moments(self) -> np.ndarray:
        """The principal moments (I1, I2, I3)."""
        return self._vec[:3].copy()

    @property
    def _orientation(self) -> bool:
        return self._params["orientation"]

    def initial_state(self, omega, quat=None, *, atol: float = 1e-12) -> np.ndarray:
        """The state for body angular velocity ``omega`` (and, with
        orientation, a unit quaternion ``quat``, scalar last; identity if None)."""
        w = as_array(omega, "omega", shape=(3,))
        if not self._orientation:
            if quat is not None:
                raise ValueError("quat is only used with orientation=True")
            return w.copy()
        q = np.array([0.0, 0.0, 0.0, 1.0]) if quat is None else as_array(quat, "quat", shape=(4,))
        if abs(np.linalg.norm(q) - 1.0) > atol:
            raise ValueError(f"quat must be a unit quaternion, |q| = {np.linalg.norm(q)!r}")
        return np.concatenate([w, q])

    def angular_momentum(self, y) -> np.ndarray:
        """Body-frame angular momentum L = I omega for states y of shape (dim, ...)."""
        y = as_array(y, "y", min_ndim=1)
        return self.moments.reshape((3,) + (1,) * (y.ndim - 1)) * y[:3]

    def _identity(self) -> tuple:
        p = self._params
        return (p["torque"] is None, None if self._torque_fn is None else id(self._torque_fn))

    def __reduce__(self):
        if self._torque_fn is not None:
            raise TypeError("a RigidBody with a C torque callback cannot be pickled")
        return super().__reduce__()


class HeavyTop(Scene, row="HeavyTop"):
    r"""The heavy symmetric top with one fixed point, in Euler angles (ZXZ).

    .. math:: L = \tfrac{I_1}{2}(\dot\theta^2 + \dot\phi^2\sin^2\theta)
              + \tfrac{I_3}{2}(\dot\psi + \dot\phi\cos\theta)^2 - M g l\cos\theta

    State ``(phi, theta, psi, phi_dot, theta_dot, psi_dot)`` (rad, rad/s);
    ``I1`` the moment about a transverse axis through the fixed point, ``I3``
    about the symmetry axis (kg m^2), ``mass`` (kg), ``g`` (m/s^2) and ``l``
    the distance of the centre of mass from the fixed point (m).  Conserved:
    ``energy`` :math:`E = \tfrac{I_1}{2}(\dot\theta^2 + \dot\phi^2\sin^2\theta)
    + \tfrac{I_3}{2}\omega_3^2 + Mgl\cos\theta` (J), ``p_phi`` and ``p_psi``.
    Singular at theta = 0 or pi (Euler angles).

    Examples
    --------
    Released at theta = 1 rad and spinning at 20 rad/s about its axis, the top
    nutates between the bounds of :func:`mechpy.rigid.nutation_bounds`; the energy,
    p_phi and p_psi = I3 omega3 are conserved:

    >>> top = mp.scenes.HeavyTop(1.0, 0.5, 1.0, g=9.81, l=0.3)
    >>> y0 = np.array([0.0, 1.0, 0.0, 0.0, 0.0, 20.0])     # released at theta = 1 rad, spinning
    >>> s = mp.solve(top, (0, 2), y0, rtol=1e-11, atol=1e-12)
    >>> round(float(top.p_psi(s.y[:, -1])), 10), round(float(top.p_psi(y0)), 10)   # I3 omega3
    (10.0, 10.0)
    >>> bool(abs(top.energy(s.y[:, -1]) - top.energy(y0)) < 1e-8)
    True
    >>> lo, hi = mp.rigid.nutation_bounds(1.0, 0.5, 1.0, 9.81, 0.3, 1.0, 0.0, 0.0, 20.0)
    >>> bool(lo - 1e-9 <= s.y[1].min() and s.y[1].max() <= hi + 1e-9)   # theta nutates between
    True
    """

    def p_psi(self, y):
        """p_psi = I3 (psi_dot + phi_dot cos theta) for states (6, ...)."""
        y = as_array(y, "y", min_ndim=1)
        return self._params["I3"] * (y[5] + y[3] * np.cos(y[1]))

    def p_phi(self, y):
        """p_phi = I1 phi_dot sin^2 theta + p_psi cos theta for states (6, ...)."""
        y = as_array(y, "y", min_ndim=1)
        s = np.sin(y[1])
        return self._params["I1"] * y[3] * s * s + self.p_psi(y) * np.cos(y[1])


_CHAIN_ENDS = {"fixed": 0, "free": 1, "periodic": 2}
_CHAIN_NSPRINGS = {"fixed": 1, "free": -1, "periodic": 0}   # springs = N + this


def _chain_springs(springs, N: int, ends: str) -> np.ndarray:
    """One spring constant for all, or N + 1, N - 1 or N of them (fixed,
    free, periodic); their domain is the row's check."""
    ns = N + _CHAIN_NSPRINGS[ends]
    if np.ndim(springs) == 0 and not isinstance(springs, (str, bytes)) and springs is not None:
        return np.full(ns, as_scalar(springs, "springs"))
    k = as_array(springs, "springs", allow_empty=(ns == 0))
    if k.shape != (ns,):
        raise ValueError(f"springs must be a scalar or have {ns} values for a {ends} chain "
                         f"of {N} masses (N + 1 fixed, N - 1 free, N periodic), got shape "
                         f"{k.shape}")
    return k


class SpringChain(Scene, row="SpringChain"):
    r"""A one-dimensional chain of masses and springs, integrated in time,
    optionally with the Fermi-Pasta-Ulam-Tsingou (FPUT) nonlinearity.

    Mass ``i`` is displaced by ``x_i`` from equilibrium; spring ``j`` of
    constant :math:`k_j`, stretched by :math:`r_j = x_{right} - x_{left}`,
    stores

    .. math:: V_j(r) = k_j\left(\frac{r^2}{2} + \frac{\alpha r^3}{3}
              + \frac{\beta r^4}{4}\right),\qquad
              m_i\ddot x_i = V'_{right(i)}(r) - V'_{left(i)}(r).

    The ends follow :func:`mechpy.modes.chain`: ``"fixed"`` (walls at both
    ends, N + 1 springs, spring 0 joins the left wall to mass 0),
    ``"free"`` (N - 1 springs, spring j joins masses j and j+1) and
    ``"periodic"`` (a ring, N springs, spring N-1 joins mass N-1 to mass 0).
    With ``alpha = beta = 0`` (the default) the motion is ``M x'' = -K x``
    with ``K, M = mp.modes.chain(N, ends=ends, masses=masses,
    springs=springs)``, solved exactly by :meth:`modes`; the FPUT terms cost
    nothing when off.

    State ``(x (N), v (N))``, ``dim = 2 N``; separable, so the symplectic
    methods (``"verlet"``, ``"yoshida"``, ``"gauss4"``) apply.

    Parameters
    ----------
    masses : array_like (N,)
        Masses (kg), positive; N >= 1.
    springs : float or array_like
        Spring constants (N/m), non-negative: one value for all, or N + 1,
        N - 1 or N of them (fixed, free, periodic).
    ends : {"fixed", "free", "periodic"}
    alpha : float
        Quadratic FPUT coefficient (1/m): the tension is
        :math:`k(r + \alpha r^2 + \beta r^3)`.
    beta : float
        Cubic FPUT coefficient (1/m^2).

    Notes
    -----
    ``energy`` is :math:`\sum_i m_i v_i^2/2 + \sum_j V_j(r_j)` (J), conserved.
    For free and periodic ends the momentum :math:`\sum_i m_i v_i` (kg m/s)
    is conserved too.  For :func:`mechpy.solve_many` with per-trajectory
    parameters, build the rows with :meth:`ensemble_params`.

    Examples
    --------
    >>> import numpy as np, mechpy as mp
    >>> ch = mp.scenes.SpringChain(np.ones(8), 1.0)            # fixed ends
    >>> md = ch.modes()
    >>> y0 = ch.initial_state(md.vectors[:, 0])                # the lowest mode
    >>> sol = mp.solve(ch, (0, 10), y0, method="dop853", rtol=1e-12, atol=1e-12)
    >>> bool(np.allclose(sol.y[:8, -1], md.evolve(y0[:8], y0[8:], 10.0)))
    True
    """

    def __init__(self, masses, springs=1.0, ends: str = "fixed",
                 alpha: float = _row_defaults("SpringChain", 4)[2],
                 beta: float = _row_defaults("SpringChain", 4)[3]):
        if not isinstance(ends, str) or ends not in _CHAIN_ENDS:
            raise ValueError(f"ends must be one of {tuple(_CHAIN_ENDS)}, got {ends!r}")
        m = as_array(masses, "masses", allow_empty=True)
        if m.ndim != 1:
            raise ValueError(f"masses must be a 1-D array (one mass per site), got shape {m.shape}")
        if m.size < 1:
            raise ValueError("a SpringChain needs at least one mass (N >= 1)")
        N = m.size
        k = _chain_springs(springs, N, ends)
        a, b = as_scalar(alpha, "alpha"), as_scalar(beta, "beta")
        self._set(dict(masses=m, springs=k, ends=ends, alpha=a, beta=b),
                  np.concatenate([[N, _CHAIN_ENDS[ends], a, b], m, k]))
        self._modes = None

    @classmethod
    def uniform(cls, N: int, mass: float = 1.0, spring: float = 1.0, ends: str = "fixed",
                alpha: float = 0.0, beta: float = 0.0) -> "SpringChain":
        """A chain of N equal masses (kg) and equal springs (N/m)."""
        N = as_int(N, "N", minimum=1)
        return cls(np.full(N, as_scalar(mass, "mass")), spring, ends, alpha, beta)

    # -- parameters ----------------------------------------------------------
    @property
    def N(self) -> int:
        """Number of masses."""
        return self._dim // 2

    @property
    def nonlinear(self) -> bool:
        """Whether the FPUT terms are on (alpha or beta non-zero)."""
        return self._params["alpha"] != 0.0 or self._params["beta"] != 0.0

    def ensemble_params(self, k: int | None = None, /, **columns) -> np.ndarray:
        """Rows of parameters for :func:`mechpy.solve_many`, one per trajectory.

        Each keyword (``masses``, ``springs``, ``alpha``, ``beta``) gives
        either one value for all rows or one per row (a leading axis of
        length k: ``alpha`` of shape (k,), ``masses`` of shape (k, N), ...);
        the others are this chain's.  N and ``ends`` are shared by all rows.

        Returns
        -------
        ndarray (k, 4 + N + n_springs)
            Pass as ``params=`` with this chain as the system.
        """
        allowed = ("masses", "springs", "alpha", "beta")
        unknown = set(columns) - set(allowed)
        if unknown:
            raise ValueError(f"ensemble_params takes {allowed} (N and ends are shared), "
                             f"got {sorted(unknown)}")
        base = self._params
        N, ns = self.N, base["springs"].size
        width = {"masses": N, "springs": ns}
        blocks = {}
        for name in allowed:
            v = as_array(columns.get(name, base[name]), name, allow_empty=True)
            rows = None
            if name in width:
                w = width[name]
                if v.ndim == 0 and name == "springs":
                    v = np.full((1, w), float(v))
                elif v.shape == (w,):
                    v = v[None, :]
                elif v.ndim == 2 and v.shape[1] == w:
                    rows = v.shape[0]
                else:
                    raise ValueError(f"{name} must have shape ({w},) or (k, {w}), got {v.shape}")
            elif v.ndim <= 1:
                rows = v.shape[0] if v.ndim == 1 else None
                v = v.reshape(-1, 1)
            else:
                raise ValueError(f"{name} must be a scalar or of shape (k,), got {v.shape}")
            if rows is not None:
                if k is not None and rows != k:
                    raise ValueError(f"{name} has {rows} rows, expected {k} (one per trajectory)")
                k = rows
            blocks[name] = v
        k = 1 if k is None else as_int(k, "k", minimum=1)
        out = np.empty((k, 4 + N + ns))
        out[:, 0] = N
        out[:, 1] = _CHAIN_ENDS[base["ends"]]
        out[:, 2:3] = blocks["alpha"]
        out[:, 3:4] = blocks["beta"]
        out[:, 4:4 + N] = blocks["masses"]
        out[:, 4 + N:] = blocks["springs"]
        _core.scene_check(self._model, out)
        return out

    # -- states and the linear theory ------------------------------------------
    def initial_state(self, x, v=None) -> np.ndarray:
        """The state ``(x, v)`` from displacements x (N,) (m) and velocities
        v (N,) (m/s, zero if None)."""
        x = as_array(x, "x", shape=(self.N,))
        v = np.zeros(self.N) if v is None else as_array(v, "v", shape=(self.N,))
        return np.concatenate([x, v])

    def matrices(self):
        """The linearisation ``(K, M)``, as :func:`mechpy.modes.chain` gives it."""
        p = self._params
        return chain(self.N, ends=p["ends"], masses=p["masses"], springs=p["springs"])

    def modes(self):
        """Normal modes of the linearised chain,
        ``mp.modes.normal_modes(*self.matrices())`` (exact motion by
        ``Modes.evolve``; the FPUT terms are left out)."""
        if self._modes is None:
            self._modes = normal_modes(*self.matrices())
        return self._modes

    def mode_energies(self, y) -> np.ndarray:
        r"""Harmonic energy in each normal mode,
        :math:`E_k = (\dot\eta_k^2 + \omega_k^2\eta_k^2)/2`, for states y of
        shape (2N, ...) -> (N, ...) (J).  Constant for a linear chain; the
        FPUT terms share energy among them."""
        y = self._states(y)
        q = np.moveaxis(y[:self.N], 0, -1)
        v = np.moveaxis(y[self.N:], 0, -1)
        return np.moveaxis(self.modes().energy(q, v), -1, 0)

    def momentum(self, y):
        """Total momentum :math:`\\sum_i m_i v_i` (kg m/s) of states (2N, ...)."""
        y = self._states(y)
        m = self._params["masses"].reshape((self.N,) + (1,) * (y.ndim - 1))
        return np.sum(m * y[self.N:], axis=0)

    # -- identity ------------------------------------------------------------
    def __repr__(self):
        p = self._params
        extra = f", alpha={p['alpha']!r}, beta={p['beta']!r}" if self.nonlinear else ""
        return f"SpringChain(N={self.N}, ends={p['ends']!r}{extra})"


class Rocket(Scene, row="Rocket"):
    r"""A rocket flying straight up (Marion & Thornton, section 9.11).

    .. math:: \dot h = v,\qquad \dot v = \frac{T - k\,v|v|}{m} - g,\qquad
              \dot m = -b,\quad T = u\,b\qquad (m > m_{dry}),

    and :math:`T = 0`, :math:`\dot m = 0` after burn-out, at
    :math:`t_b = (m_0 - m_{dry})/b`.  Without gravity and drag the speed
    follows Tsiolkovsky's :math:`v = u\ln(m_0/m)`; with constant g,
    :math:`v = u\ln(m_0/m) - g t` while burning.

    State ``(height, speed, mass)`` in m, m/s, kg.  Parameters:
    ``exhaust_speed`` u (m/s, relative to the rocket), ``burn_rate`` b
    (kg/s), ``m0`` the launch mass and ``m_dry`` the mass without propellant
    (kg, 0 < m_dry <= m0), ``g`` (m/s^2), ``drag`` k (kg/m: the drag force is
    :math:`-k\,v|v|`).  ``energy`` is the vehicle's mechanical energy
    :math:`m v^2/2 + m g h` (J), not conserved.

    Burn-out is a switch on the mass in the right-hand side, a kink in time:
    :meth:`fly` breaks the integration at the burn-out time (a ``t_span``
    break, so that no step straddles the kink) and joins the two pieces; a
    plain :func:`mechpy.solve` across :attr:`burnout_time` is correct only to
    the accuracy the step control reaches at a kink.

    Examples
    --------
    >>> import numpy as np, mechpy as mp
    >>> r = mp.scenes.Rocket(exhaust_speed=2500.0, burn_rate=10.0, m0=1000.0, m_dry=200.0)
    >>> sol = r.fly((0.0, 100.0), rtol=1e-12, atol=1e-12)
    >>> bool(np.isclose(sol.y[1, -1], 2500.0 * np.log(1000.0 / 200.0)))
    True
    """

    @property
    def burnout_time(self) -> float:
        """Time (s) from launch at which the propellant runs out,
        (m0 - m_dry)/burn_rate (inf when burn_rate is 0)."""
        p = self._params
        fuel = p["m0"] - p["m_dry"]
        return fuel / p["burn_rate"] if p["burn_rate"] > 0 else (0.0 if fuel == 0 else np.inf)

    def initial_state(self, height=0.0, speed=0.0) -> np.ndarray:
        """The launch state ``(height, speed, m0)``."""
        return np.array([as_scalar(height, "height"), as_scalar(speed, "speed"),
                         self._params["m0"]])

    def fly(self, t_span, y0=None, **options):
        """A flight from the launch pad to the ground: :func:`mechpy.solve`
        with the pad and the landing.

        A rocket on the pad (height 0, not rising) whose thrust ``u b`` does
        not exceed its weight ``m g`` stays there, burning, until the mass has
        fallen to ``u b / g`` (the pad holds it: it does not sink); it never
        lifts off when that mass is below ``m_dry`` (the message says so).
        In flight, burn-out is the scene's switch (any solve crosses it; here
        the interval is also broken at the burn-out time, so that it appears
        once, with the mass exactly ``m_dry``), and the flight ends when the
        rocket comes back to the ground (a terminal event: ``status`` 1, the
        message giving the landing time and speed).

        Parameters
        ----------
        t_span : (t0, tf)
            Forward interval (s).
        y0 : array_like (3,), optional
            State at t0 (the launch state at rest by default).
        **options
            Passed to :func:`mechpy.solve` (``method``, ``rtol``, ``atol``,
            ``t_eval``, ``dense_output``, ...; not ``events``).

        Returns
        -------
        Solution
            The pieces joined: ``t`` (m,), ``y`` (3, m), the counters summed,
            ``sol`` the joined dense output if asked for.
        """
        if "events" in options:
            raise TypeError("Rocket.fly does not take events (call mechpy.solve on the scene)")
        if np.shape(t_span) != (2,):
            raise ValueError(f"t_span must be a pair (t0, tf), got shape {np.shape(t_span)}")
        t0, tf = (as_scalar(v, "t_span") for v in t_span)
        if not tf > t0:
            raise ValueError(f"t_span must be increasing, got ({t0}, {tf})")
        y = self.initial_state() if y0 is None else as_array(y0, "y0", shape=(3,)).copy()
        p = self._params
        u, b, md, g = p["exhaust_speed"], p["burn_rate"], p["m_dry"], p["g"]
        t_eval = options.pop("t_eval", None)
        te = None if t_eval is None else as_array(t_eval, "t_eval", ndim=1)
        pieces, note = [], None
        if y[0] <= 0.0 and y[1] <= 0.0 and u * b <= y[2] * g and y[2] > 0:   # on the pad
            m_lift = u * b / g if g > 0 else np.inf
            lifts = b > 0 and m_lift > md
            t_lift = t0 + (y[2] - m_lift) / b if lifts else np.inf
            t_end = min(t_lift, tf)
            pieces.append(self._on_pad(t0, t_end, y[2], te, options.get("dense_output")))
            if not lifts:
                note = (f"the rocket never lifts off: its thrust u b = {u * b:.6g} N stays "
                        f"below its weight, {md * g:.6g} N even at burn-out (m_dry g); it "
                        "rests on the pad")
            if t_end >= tf:
                out = pieces[0]
                if note:
                    out["message"] = f"{out['message']} ({note})"
                return out
            t0, y = t_lift, np.array([0.0, 0.0, m_lift])
            te = None if te is None else te[te > t0]

        def ground(t, yy):
            return yy[0]

        ground.terminal, ground.direction = True, -1
        tb = t0 + (y[2] - md) / b if (y[2] > md and b > 0) else t0
        spans = [(t0, tb), (tb, tf)] if t0 < tb < tf else [(t0, tf)]
        for i, (a_, b_) in enumerate(spans):
            sel, extra = None, False
            if te is not None:   # the piece's samples, and its end (the next start)
                sel = te[(te >= a_) & (te <= b_)] if i == 0 else te[(te > a_) & (te <= b_)]
                extra = sel.size == 0 or sel[-1] != b_
                sel = np.append(sel, b_) if extra else sel
            piece = solve(self, (a_, b_), y, t_eval=sel, events=ground, **options)
            y = piece.y[:, -1].copy()
            if extra and piece.t.size and piece.t[-1] == b_:
                piece.t, piece.y = piece.t[:-1], piece.y[:, :-1]
            pieces.append(piece)
            if piece.status != 0:
                break
            if i == 0 and len(spans) == 2:
                y[2] = md                      # exactly empty: the coast branch from here
        out = _join_pieces(pieces, te is None)
        last = pieces[-1]
        if last.status == 1:                   # the ground
            tl, vl = last.t_events[0][0], last.y_events[0][0][1]
            out["message"] = (f"The rocket lands at t = {tl:.10g} s at {abs(vl):.6g} m/s "
                              "(a terminal event: height 0 reached descending).")
        elif note:
            out["message"] = f"{out['message']} ({note})"
        return out

    def _on_pad(self, t0, t1, m0, te, dense):
        """The rocket resting on the pad from t0 to t1, burning from mass m0."""
        b, md = self._params["burn_rate"], self._params["m_dry"]
        t = np.array([t0, t1]) if te is None else te[(te >= t0) & (te <= t1)]
        m = np.maximum(m0 - b * (t - t0), md)
        y = np.vstack([np.zeros_like(t), np.zeros_like(t), m])
        sol = _PadDense(t0, t1, m0, b, md) if dense else None
        return Solution(t=t, y=y, sol=sol, t_events=None, y_events=None, nfev=0, njev=0,
                        nlu=0, nsteps=0, nreject=0, status=0, success=True,
                        message="The solver successfully reached the end of the integration "
                                "interval.")


class _PadDense(DenseOutput):
    """The dense output of a rocket resting on the pad: h = v = 0, the mass
    falling at the burn rate to the dry mass."""

    def __init__(self, t0, t1, m0, b, md):
        self.t_min, self.t_max, self.n_segments = t0, t1, 1
        self._m0, self._b, self._md = m0, b, md

    def __call__(self, t):
        t = np.asarray(t, dtype=np.float64)
        m = np.maximum(self._m0 - self._b * (t - self.t_min), self._md)
        return np.stack([np.zeros_like(m), np.zeros_like(m), m])


def _join_pieces(pieces, every_step):
    """One Solution from consecutive pieces of a flight: samples in order (a
    piece's first sample, its start, dropped when it repeats the previous end),
    counters summed, dense outputs joined; the last piece's status."""
    out = Solution(pieces[-1])
    ts, ys = [pieces[0].t], [pieces[0].y]
    for q in pieces[1:]:
        keep = slice(1, None) if every_step and q.t.size and ts[-1].size and \
            q.t[0] == ts[-1][-1] else slice(None)
        if every_step and q.t.size and ts[-1].size and q.t[0] == ts[-1][-1]:
            ys[-1] = ys[-1].copy()
            ys[-1][:, -1] = q.y[:, 0]          # the state after a switch (the mass exact)
        ts.append(q.t[keep])
        ys.append(q.y[:, keep])
    out.t = np.concatenate(ts)
    out.y = np.concatenate(ys, axis=1)
    for k in ("nfev", "njev", "nlu", "nsteps", "nreject"):
        out[k] = sum(q[k] for q in pieces)
    if all(q.sol is not None for q in pieces):
        out.sol = _JoinedDense([q.sol for q in pieces])
    failed = [q for q in pieces if q.status < 0]
    return failed[0] if failed else out


# every scene class defined here (a new scene is its class line), then the field's type
__all__ += [c.__name__ for c in Scene.__subclasses__() if c.__module__ == __name__] + [
    "SymbolicField"]
