"""What an animation of the motion draws, in NumPy: the samples of a solution
and the places of the bodies.

:func:`mechpy.plot.animate` draws these with matplotlib and
:func:`mechpy.live.animate` with three.js; both take their geometry from here,
and the kinds of drawing from one registry, ``DRAWINGS`` (below).
Frames: x to the right and y up for the planar pendulums (angles from the
downward vertical) and for a particle (one coordinate: its height, y up);
x east, y north, z up for the Foucault pendulum; the space frame of the top
(z up) and of the free body.

A solution with jumps (an event's action, :mod:`mechpy.events`) has the state
before and the state after each action at the same time: ``sol.t`` is
monotonic, not strictly, and a time it holds twice shows the state after the
action (:func:`after_jumps`, :func:`resample`; ``sol.sol`` gives it too).
"""
from __future__ import annotations

import importlib
from typing import Callable, NamedTuple

import numpy as np

from ._validate import as_array
from .integrate import solve
from .rigid import nutation_bounds
from .rotation import euler_matrix, matrix_from_quat
from .scenes import Scene

# ------------------------------------------------------- the registry of drawings
#
# What :func:`mechpy.plot.animate` (matplotlib) and
# :func:`mechpy.live.animate` (three.js) draw for a system, one entry a kind.
#
# An entry names its two painters (``"module:function"``, imported when first
# drawn), the scenes it is made for (their C rows), what it needs of any other
# system, its default trail and the options it takes.  A scene names its
# drawing in its C row (``drawing``, read as ``mechpy.scenes.Scene.drawing``);
# a compiled system names none of its own and gets the first generic entry that
# fits its description (fitting).  The geometry both painters draw is this
# module's (below).
#
# The painters' contracts:
#
# - ``plot(ax, system, t, y, trail, lengths) -> update``: draws the still parts
#   on the matplotlib Axes ``ax`` (3-D when the entry is ``three_d``) and
#   returns ``update(k)``, which shows sample k and returns the artists it
#   changed;
# - ``live(system, times, Y, **options) -> dict``: the frames' geometry for the
#   page (``mechpy/live/static/animate.js``): ``P`` (frames, bodies, 3) the
#   places of the bodies, ``R`` (frames, 3, 3) the rotation of a solid,
#   ``bodies``, ``rods``, ``lines``, ``trail`` (the bodies with a trail),
#   ``legend``, ``solid``, ``up``, ``center``, ``extent``, ``camera``,
#   ``title`` (see mechpy/live/motion.py).
#
# A new drawing is one entry in DRAWINGS and its two painters (CONTRIBUTING.md).


class Drawing(NamedTuple):
    """One kind of drawing (see the comment above)."""

    name: str
    #: the painters, "module:function"
    plot: str
    live: str
    #: the C rows of the scenes it is made for (their classes' drawing); empty:
    #: any system with ``states`` states that ``fits``
    rows: tuple = ()
    #: the number of states it needs, None: any
    states: int | None = None
    #: for a system that names no drawing of its own (a compiled one): whether
    #: this drawing fits its description; None: never chosen for one
    fits: Callable | None = None
    #: what it draws, for the messages
    what: str = ""
    #: the default trail, as a fraction of the time span
    trail: float = 0.2
    #: matplotlib: 3-D Axes, and the figure's size (inches)
    three_d: bool = False
    figsize: tuple = (4.5, 4.5)
    #: matplotlib: the figure's bottom margin (a fraction) for a legend under the axes
    bottom: float | None = None
    #: the keyword options of mp.live.animate it takes
    options: tuple = ()
    #: its geometry as SymPy expressions, "module:function" ``(system, **options) ->
    #: [(x, y, z), ...]`` in the state symbols ``y0, y1, ...`` and the parameters'
    #: symbols (by name), the places of the bodies it draws in their order: what a page
    #: that simulates (mp.live.animate's params=, y0=) prints; None: not simulated
    geometry: str | None = None

    def painter(self, which: str):
        """The painter ``which`` ("plot", "live" or "geometry"), imported."""
        module, _, name = getattr(self, which).partition(":")
        return getattr(importlib.import_module(module), name)


def _lengths_named(system, keys) -> bool:
    return set(keys) <= set(getattr(system, "params", {}) or {})


def _fits_pendulum(system) -> bool:
    return _lengths_named(system, ("length",)) or _lengths_named(system, ("l",))


def _fits_particle(system) -> bool:
    return bool(particle_coordinates(system))


def _fits_bodies(system) -> bool:
    """A mechanics model (mp.mechanics) that carries its drawing."""
    return bool((getattr(system, "_info", None) or {}).get("drawing"))


_ANGLES = "angles from the downward vertical and their rates"

#: The drawings, in the order a compiled system's is chosen among them.
DRAWINGS = {d.name: d for d in (
    Drawing("bodies", "mechpy.plot:_bodies", "mechpy.live.motion:_bodies", fits=_fits_bodies,
            what="a mechanics model's bodies, or points=", three_d=True,
            options=("points", "links", "shapes"), geometry="mechpy._motion:points_geometry"),
    Drawing("pendulum", "mechpy.plot:_planar_pendulum", "mechpy.live.motion:_pendulum",
            states=2, fits=_fits_pendulum, what=_ANGLES, options=("lengths",),
            geometry="mechpy._motion:pendulum_geometry"),
    Drawing("double_pendulum", "mechpy.plot:_planar_pendulum", "mechpy.live.motion:_pendulum",
            states=4, fits=lambda s: _lengths_named(s, ("l1", "l2")), what=_ANGLES,
            options=("lengths",), geometry="mechpy._motion:pendulum_geometry"),
    Drawing("foucault", "mechpy.plot:_foucault", "mechpy.live.motion:_foucault",
            rows=("Foucault",), trail=np.inf),
    Drawing("top", "mechpy.plot:_top", "mechpy.live.motion:_top", rows=("HeavyTop",),
            trail=np.inf, three_d=True),
    Drawing("rigid", "mechpy.plot:_rigid", "mechpy.live.motion:_rigid",
            rows=("RigidBody", "RigidBodyOriented"), trail=0.25, three_d=True),
    Drawing("chain", "mechpy.plot:_chain", "mechpy.live.motion:_chain", rows=("SpringChain",),
            trail=0.0, figsize=(7, 5), bottom=0.36, options=("spacing",)),
    Drawing("particle", "mechpy.plot:_particle", "mechpy.live.motion:_particle",
            fits=_fits_particle),
)}
KINDS = tuple(DRAWINGS)


def fitting(system) -> str | None:
    """The first drawing whose ``fits`` takes ``system`` (a system that names
    no drawing of its own), or None."""
    for d in DRAWINGS.values():
        if d.fits is not None and (d.states in (None, system.dim)) and d.fits(system):
            return d.name
    return None


def kind_of(system, kind) -> Drawing:
    """The drawing for ``system``: ``kind`` checked against it, or the one the
    system names (its ``drawing``: an entry's name, or a :class:`Drawing` of
    its own)."""
    if not isinstance(system, Scene):
        raise TypeError("system must be a mechpy scene (the one that made sol), "
                        f"got {type(system).__name__}")
    if kind is None:
        kind = system.drawing
        if kind is None:
            raise TypeError(f"animate cannot tell what to draw for a {type(system).__name__}: "
                            f"give kind, one of {KINDS}")
    if isinstance(kind, Drawing):          # an entry of the system's own (not registered)
        d = kind
    elif not isinstance(kind, str) or kind not in DRAWINGS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    else:
        d = DRAWINGS[kind]
    kind = d.name
    if d.rows and system._model not in d.rows:
        raise TypeError(f"kind={kind!r} draws a mp.scenes.{d.rows[0]}, "
                        f"got {type(system).__name__}")
    if d.name == "particle" and not _fits_particle(system):
        raise TypeError("kind='particle' draws a system whose state is (q, v) with one or two "
                        f"coordinates q (its coordinates: {getattr(system, 'coordinates', None)}, "
                        f"{system.dim} states)")
    if d.states is not None and system.dim != d.states:
        raise TypeError(f"kind={kind!r} needs a system of {d.states} states ({d.what}), "
                        f"got {system.dim}")
    return d


def samples(system, sol, t):
    """(t (m,), y (n, m)) from a Solution or an array (n, m) with times t."""
    if hasattr(sol, "t") and hasattr(sol, "y"):
        if t is not None:
            raise ValueError("t is given with a Solution: it carries its own times sol.t")
        tt, y = sol.t, sol.y
    elif isinstance(sol, (np.ndarray, list, tuple)):
        if t is None:
            raise ValueError("sol is an array (n, m): give its times t (m,)")
        tt, y = t, sol
    else:
        raise TypeError("sol must be a Solution of mp.solve or an array of states (n, m), "
                        f"got {type(sol).__name__}")
    y = as_array(y, "sol.y", ndim=2, allow_empty=True)
    tt = as_array(tt, "t", ndim=1, allow_empty=True)
    if y.shape[1] == 0 or tt.size == 0:
        raise ValueError("sol is empty: it has no samples to draw (integrate with t_eval)")
    if tt.size != y.shape[1]:
        raise ValueError(f"t has {tt.size} times but sol.y has {y.shape[1]} samples (n, m)")
    if y.shape[0] != system.dim:
        raise ValueError(f"sol.y has {y.shape[0]} rows but a {type(system).__name__} has "
                         f"{system.dim} states: the state axis comes first, (n, m)")
    # a time held twice is an action's (the states before and after it): t
    # is monotonic, strictly between the jumps
    dt = np.diff(tt)
    if not (np.any(dt != 0) or tt.size == 1) or not (np.all(dt >= 0) or np.all(dt <= 0)):
        raise ValueError("t must be monotonic (a time held twice: the states before and after "
                         "an action), and span an interval")
    return tt, y


def after_jumps(t, idx):
    """The sample indices ``idx`` moved to the last sample of their time, in
    the order of the solve: at an action's time, the state after it."""
    u = t if t[-1] >= t[0] else -t
    return np.searchsorted(u, u[np.asarray(idx)], side="right") - 1


def particle_coordinates(system) -> list:
    """The coordinates' names of a particle to draw, else []: a compiled
    system's state (q, v) with one or two coordinates q (``mp.lagrangian``'s
    ``coordinates``; ``mp.equations`` names every state, the first half are
    the coordinates, as :func:`mechpy.events.impact` reads them)."""
    names = list(getattr(system, "coordinates", None) or ())
    if len(names) == system.dim and system.dim % 2 == 0:
        names = names[:system.dim // 2]
    return names if 1 <= len(names) <= 2 and system.dim == 2 * len(names) else []


def particle_places(y):
    """The particle's places (3, m): one coordinate q at (0, q, 0), its height
    (y up); two at (q1, q2, 0)."""
    nq = y.shape[0] // 2
    z = np.zeros(y.shape[1])
    return np.stack([z, y[0], z]) if nq == 1 else np.stack([y[0], y[1], z])


def resample(system, t, y, times):
    """States at ``times`` (within [t[0], t[-1]]) from samples ``(t, y)``: the
    cubic Hermite interpolant through the states and the system's own
    derivatives ``system.rhs`` at the samples (4th order in the spacing);
    exact at the samples themselves.  One sample: that state.  With jumps (a
    time held twice) each interval is one piece's, and an action's time
    gives the state after it (in the order of the solve)."""
    if t.size == 1:
        return np.repeat(y, len(times), axis=1)
    sign = 1.0 if t[-1] >= t[0] else -1.0
    u, w = sign * t, sign * np.asarray(times, dtype=float)  # increasing, ties in solve order
    w = np.clip(w, u[0], u[-1])
    k = np.searchsorted(u, w, side="right") - 1             # the last sample at or before
    # the end itself: the interval before it (a jump there: its last sample)
    k = np.where(k >= t.size - 1, np.searchsorted(u, u[-1], side="left") - 1, k)
    k = np.clip(k, 0, t.size - 2)
    f = np.zeros_like(y)
    for j in np.unique(np.concatenate([k, k + 1])):      # only where an interval is used
        f[:, j] = system.rhs(float(t[j]), y[:, j])
    h = t[k + 1] - t[k]
    times = sign * w
    s = np.divide(times - t[k], h, out=np.ones_like(h), where=h != 0)
    h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
    h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
    return (h00 * y[:, k] + h10 * h * f[:, k] + h01 * y[:, k + 1] + h11 * h * f[:, k + 1])


# ---------------------------------------------------------------- the bodies

def pendulum_lengths(system, two: bool, lengths):
    """Rod lengths (1,) or (2,) (m): ``lengths``, else the scene's ``l1, l2``,
    ``length`` or ``l``."""
    p = system.params
    if lengths is None:
        keys = ("l1", "l2") if two else ("length",) if "length" in p else ("l",)
        if not set(keys) <= set(p):
            raise ValueError(f"lengths is needed: the system has no length parameters {keys}")
        lengths = [p[k] for k in keys]
    return as_array(lengths, "lengths", shape=(2 if two else 1,), positive=True)


def pendulum_bobs(y, ls):
    r"""The bobs of a planar (double) pendulum, x right and y up, pivot at the
    origin: :math:`x_k = \sum_{j\le k} l_j\sin\theta_j`,
    :math:`y_k = -\sum_{j\le k} l_j\cos\theta_j`; two arrays (bobs, m) (m)."""
    xs = np.cumsum(ls[:, None] * np.sin(y[:ls.size]), axis=0)
    ys = np.cumsum(-ls[:, None] * np.cos(y[:ls.size]), axis=0)
    return xs, ys


def pendulum_geometry(system, lengths=None) -> list:
    r"""The bobs of :func:`pendulum_bobs` as SymPy expressions (x right, y up):
    :math:`\sum_{j\le k} l_j(\sin y_j, -\cos y_j, 0)`, each length the scene's
    parameter by name (``l1``, ``l2``, ``length`` or ``l``) or the number of
    ``lengths``."""
    import sympy as sp
    two = system.dim == 4
    if lengths is not None:
        ls = list(pendulum_lengths(system, two, lengths))
    else:
        pendulum_lengths(system, two, None)                 # the same message when none
        p = system.params
        ls = [sp.Symbol(k) for k in (("l1", "l2") if two else
                                     ("length",) if "length" in p else ("l",))]
    out, x, y = [], sp.S.Zero, sp.S.Zero
    for j, lj in enumerate(ls):
        x, y = x + lj * sp.sin(sp.Symbol(f"y{j}")), y - lj * sp.cos(sp.Symbol(f"y{j}"))
        out.append((x, y, sp.S.Zero))
    return out


def foucault_bob(system, y):
    r"""The Foucault bob (3, m): x east, y north (the state) and its height
    above the lowest point, :math:`z = L - \sqrt{L^2 - x^2 - y^2}` (m); the
    pivot is at (0, 0, L)."""
    L = system.params["length"]
    r2 = np.minimum(y[0] ** 2 + y[1] ** 2, L * L)
    return np.stack([y[0], y[1], L - np.sqrt(L * L - r2)])


def top_rotation(y):
    """Body-to-space rotation matrices (m, 3, 3) of a heavy top from its ZXZ
    Euler angles (the active matrix: column 3 is the symmetry axis e3)."""
    return euler_matrix(y[0], y[1], y[2], passive=False)


def top_bounds(system, y0) -> tuple:
    """The nutation bounds (theta_min, theta_max) of the top started at
    ``y0`` (:func:`mechpy.rigid.nutation_bounds`); () for an upright or
    inverted start, where Euler angles are singular."""
    p = system.params
    try:
        return tuple(nutation_bounds(p["I1"], p["I3"], p["mass"], p["g"], p["l"], y0[1],
                                     y0[4], y0[3], y0[5]))
    except ValueError:
        return ()


def rigid_oriented(system, t, y):
    """States (7, m) with the orientation: ``y`` itself when it has one, else
    omega integrated again with the quaternion alongside,
    ``system.replace(orientation=True)`` from the identity at ``t[0]``, at the
    times ``t`` (rtol 1e-11)."""
    if y.shape[0] == 7:
        return y
    oriented = system.replace(orientation=True)
    y0 = oriented.initial_state(y[:, 0])
    if t[0] == t[-1]:                                  # one sample, or one instant
        return np.repeat(y0[:, None], t.size, axis=1)
    return solve(oriented, (t[0], t[-1]), y0, t_eval=t, rtol=1e-11, atol=1e-12).y


def rigid_rotation(y7):
    """Body-to-space rotation matrices (m, 3, 3) of oriented rigid-body states
    (7, m): columns are the principal axes in space."""
    return matrix_from_quat(y7[3:7].T)


def angular_momentum_space(system, R, y):
    """The angular momentum in space L = R (I omega), (m, 3) (kg m^2/s)."""
    return np.einsum("mij,jm->mi", R, system.moments[:, None] * y[:3])


def box_sides(moments, mass: float = 1.0):
    r"""Sides (a, b, c) (m) of the uniform box of ``mass`` (kg) whose principal
    moments are ``moments`` (kg m^2): :math:`I_1 = M(b^2 + c^2)/12` (cyclic),
    so :math:`a^2 = 6(I_2 + I_3 - I_1)/M`; 0 for a side of a flat body."""
    I = np.asarray(moments, dtype=float)
    sq = 6.0 * (I.sum() - 2 * I) / mass
    return np.sqrt(np.maximum(sq, 0.0))


def chain_spacing(x) -> float:
    """The spacing of the masses that makes the largest displacement 0.4 of it
    (1 when nothing moves)."""
    A = float(np.max(np.abs(x))) if x.size else 0.0
    return A / 0.4 if A > 0 else 1.0


def chain_positions(x, spacing):
    """Places of the masses along the chain (N, m): mass i (from 1) at
    ``i * spacing + x_i`` (units of x)."""
    return np.arange(1, x.shape[0] + 1)[:, None] * spacing + x


def chain_walls(system) -> list:
    """The walls' mass indices: 0 and N + 1 for fixed ends, none otherwise."""
    return [0, system.N + 1] if system.params["ends"] == "fixed" else []


# ------------------------------------------- bodies from a system's description

def bodies_drawing(system, points=None) -> dict:
    """The drawing of a system from its own description
    (:mod:`mechpy.symbolic.kinematics`): a mechanics model's (stored with it
    by :func:`mechpy.mechanics`), or ``points={"name": (x, y, z)}`` of a
    :func:`mechpy.lagrangian` or :func:`mechpy.equations` system.  Keys:
    ``names``, ``kinds`` ("rigid", "particle", "joint", "point"), ``links``
    (index pairs), ``nrot`` (the turned solids: the rigid bodies, in order),
    ``source`` (the C of the kinematics), ``inertia``, ``mass``, ``ground``."""
    from .symbolic import kinematics
    model = (getattr(system, "_info", None) or {}).get("drawing")
    if model is not None:
        if points is not None:
            raise ValueError("points is for a system of mp.lagrangian or mp.equations: an "
                             "mp.mechanics scene draws its own bodies (shapes= changes them)")
        if "error" in model:
            raise ValueError(f"this mechanics model cannot be drawn: {model['error']}")
        return model
    if not hasattr(system, "_meta"):
        raise TypeError("points= draws a system of mp.lagrangian or mp.equations, got a "
                        f"{type(system).__name__}")
    if points is None:
        raise TypeError(f"a {type(system).__name__} of mp.lagrangian or mp.equations is drawn "
                        "from points={'name': (x, y, z)} (SymPy expressions of its "
                        "coordinates and parameters)")
    d = kinematics.points_drawing(system, points)
    return dict(d, kinds=["point"] * len(d["names"]), links=[], nrot=0, ground=None)


def points_geometry(system, points=None, links=None, shapes=None) -> list:
    """The places of ``points=`` (kind "bodies") as SymPy expressions in the
    state symbols ``y0, y1, ...`` and the parameters' symbols (by name):
    ``kinematics.points_drawing``'s own, renamed.  ValueError for a mechanics
    model (its kinematics are stored as compiled C only)."""
    import sympy as sp
    if (getattr(system, "_info", None) or {}).get("drawing") is not None:
        raise ValueError("a mechanics model's bodies are not simulated by the page")
    d = bodies_drawing(system, points)
    names = list(system._meta["param_names"])
    sub = {sp.Symbol(f"mp_y{i}"): sp.Symbol(f"y{i}") for i in range(system.dim)}
    sub.update({sp.Symbol(f"mp_p{i}"): sp.Symbol(nm) for i, nm in enumerate(names)})
    e = [sp.sympify(v).xreplace(sub) for v in d["exprs"]]
    return [tuple(e[3 * i:3 * i + 3]) for i in range(len(e) // 3)]


def bodies_places(system, drawing, Y):
    """The places P (frames, bodies, 3) of a drawing's points and mass centres
    and the rotations R (frames, solids, 3, 3), body to world, at the states
    Y (n, frames): its compiled kinematics, every frame in one call."""
    from .symbolic import kinematics
    out = kinematics.evaluate(drawing, Y, system._vector())
    nb = len(drawing["names"])
    P = out[:, :3 * nb].reshape(out.shape[0], nb, 3)
    R = out[:, 3 * nb:].reshape(out.shape[0], drawing["nrot"], 3, 3)
    return P, R


def principal(drawing, i, system, y):
    """(moments (3,), axes (3, 3): columns, a right-handed frame, in the
    body's frame; mass) of rigid body i of a mechanics drawing, at state y
    (the central inertia in the frame it is drawn turned by)."""
    from .symbolic.kinematics import numeric
    p = system._vector()
    I = numeric(drawing["inertia"][i], y, p)
    w, E = np.linalg.eigh(0.5 * (I + I.T))
    if np.linalg.det(E) < 0:
        E[:, 2] = -E[:, 2]
    return w, E, float(numeric(drawing["mass"][i], y, p).reshape(-1)[0])
