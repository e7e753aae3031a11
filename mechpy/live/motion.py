"""The motion of a solution in 3D, in the browser (three.js): :func:`animate`.

The frames are computed here, in NumPy, from the solution's dense output (or
from its samples); the page only places the bodies, draws the trails and
plays.  The kinds are the entries of ``mechpy._motion`` (each names its
painter here, a function ``(system, times, Y, **options) -> dict``); their
geometry is :mod:`mechpy._motion`'s, the same as :func:`mechpy.plot.animate`'s.
"""
from __future__ import annotations

import numpy as np

from .. import _motion, _series
from .._validate import as_array, as_scalar
from . import _simulate
from ._page import LiveWidget, pack

__all__ = ["animate", "Motion"]

#: the most frames a page holds (a minute at 60 frames per second)
MAX_FRAMES = 3600

_RED, _GREEN, _BLUE = "#d62728", "#2ca02c", "#1f77b4"
_ORANGE, _GREY, _DARK = "#ff7f0e", "#7f7f7f", "#333333"


class Motion(LiveWidget):
    """The 3D view made by :func:`animate` (an ``anywidget.AnyWidget``).

    Attributes
    ----------
    kind : str
        What is drawn (one of the kinds of :func:`animate`).
    times : ndarray, shape (frames,)
        The time of each frame (time units of the solution).
    bodies : list of str
        The bodies whose places ``window.mechpyLive.positions()`` gives, in
        that order.

    Examples
    --------
    >>> import mechpy as mp
    >>> pend = mp.scenes.Pendulum(length=1.0)
    >>> T = pend.period(1.0)                       # 4 sqrt(L/g) K(sin^2(1/2))
    >>> sol = mp.solve(pend, (0, T), [1.0, 0.0], dense_output=True)
    >>> w = mp.live.animate(pend, sol, fps=30, duration=2.0)
    >>> w.kind, w.times.size, round(float(w.times[-1] / T), 12)
    ('pendulum', 61, 1.0)
    """

    _view = "animate"
    _three = True

    def __init__(self, spec: dict, kind: str, times: np.ndarray, bodies: list):
        # a page that simulates (spec["sim"]) carries its integrator (static/simulate.js)
        super().__init__(spec, extra=("simulate.js",) if spec.get("sim") else ())
        self.kind = kind
        self.times = times
        self.bodies = bodies

    def __repr__(self):
        return (f"<mechpy.live.Motion {self.kind}: {self.times.size} frames, "
                f"t in [{self.times[0]:g}, {self.times[-1]:g}]>")


def _frame_times(t, fps, duration):
    """The frames' times: evenly spread over [t[0], t[-1]], ``duration * fps``
    intervals (duration: the span itself, at most 60 s, by default)."""
    span = abs(float(t[-1] - t[0]))
    if duration is None:
        duration = min(span, 60.0) if span > 0 else 1.0
    else:
        duration = as_scalar(duration, "duration", positive=True)
    n = int(round(duration * fps)) + 1
    if n > MAX_FRAMES:
        raise ValueError(f"duration * fps = {duration:g} s * {fps:g} /s gives {n} frames, more "
                         f"than {MAX_FRAMES}: give a shorter duration or a lower fps")
    return np.linspace(t[0], t[-1], max(n, 2)), duration


def _states(system, sol, t, times):
    """The states (n, frames) at ``times``: the solution's dense output when it
    has one, else the Hermite interpolant through its samples."""
    dense = getattr(sol, "sol", None)
    if dense is not None and t is None:
        return np.asarray(dense(times), dtype=float).reshape(system.dim, times.size)
    tt, y = _motion.samples(system, sol, t)
    return _motion.resample(system, tt, y, times)


def _body(name, color, radius, local=None, shape="sphere"):
    return {"name": name, "color": color, "radius": float(radius), "shape": shape,
            "local": None if local is None else [float(v) for v in local]}


def _polyline(pts, color, label=None, dashed=False):
    return {"pts": pack(np.asarray(pts, dtype=float).reshape(-1, 3)), "color": color,
            "label": label, "dashed": bool(dashed)}


def _pendulum(system, times, Y, lengths=None):
    two = Y.shape[0] == 4
    ls = _motion.pendulum_lengths(system, two, lengths)
    xs, ys = _motion.pendulum_bobs(Y, ls)
    P = np.stack([xs.T, ys.T, np.zeros_like(xs.T)], axis=-1)        # (frames, bobs, 3)
    r = float(ls.sum())
    names = ["bob 1", "bob 2"] if two else ["bob"]
    bodies = [_body(nm, _BLUE, 0.05 * r) for nm in names]
    rods = [[[0.0, 0.0, 0.0], 0, _DARK]] + ([[0, 1, _DARK]] if two else [])
    lines = [_polyline([[-0.15 * r, 0, 0], [0.15 * r, 0, 0]], _DARK, "pivot")]
    return dict(P=P, bodies=bodies, rods=rods, lines=lines, up=[0, 1, 0], trail=[len(names) - 1],
                center=[0.0, -0.3 * r, 0.0], extent=1.15 * r, camera=[0.0, 0.0, 1.0],
                title="double pendulum: rods, bobs and the lower bob's trail (x right, y up; m)"
                if two else "pendulum: rod, bob and its trail (x right, y up; m)")


def _foucault(system, times, Y):
    B = _motion.foucault_bob(system, Y)                            # (3, frames)
    L = float(system.params["length"])
    A = float(np.max(np.hypot(B[0], B[1]))) or 0.1 * L
    bodies = [_body("bob", _RED, 0.06 * A)]
    lines = [_polyline([[-A, 0, 0], [A, 0, 0]], _GREY, "x: east"),
             _polyline([[0, -A, 0], [0, A, 0]], _GREY, "y: north")]
    # the rod runs up out of the view to its suspension point (L >> A): the camera frames
    # the bob and its rosette, not the rod's top (frame_rods)
    return dict(P=B.T[:, None, :], bodies=bodies, rods=[[[0.0, 0.0, L], 0, _DARK]], lines=lines,
                up=[0, 0, 1], trail=[0], center=[0.0, 0.0, 0.0], extent=1.3 * A,
                camera=[0.35, -0.6, 1.0], frame_rods=False,
                title="Foucault pendulum: the bob and its rosette (x east, y north, z up; m)")


def _top(system, times, Y):
    R = _motion.top_rotation(Y)                                    # (frames, 3, 3)
    ell = float(system.params["l"])
    mark = np.array([0.3 * ell, 0.0, ell])           # on the body's side, beside the centre of mass
    P = np.stack([ell * R[:, :, 2], R @ mark], axis=1)
    bodies = [_body("centre of mass", _BLUE, 0.06 * ell, local=[0.0, 0.0, ell]),
              _body("mark on the side (spin)", _RED, 0.07 * ell, local=mark)]
    phi = np.linspace(0.0, 2 * np.pi, 121)
    lines = []
    for th, what in zip(_motion.top_bounds(system, Y[:, 0]), ("theta_min", "theta_max")):
        c = ell * np.stack([np.sin(th) * np.cos(phi), np.sin(th) * np.sin(phi),
                            np.full_like(phi, np.cos(th))], axis=-1)
        lines.append(_polyline(c, _GREY, f"nutation bound {what} = {th:.4f} rad", dashed=True))
    lines.append(_polyline([[0, 0, 0], [0, 0, 1.3 * ell]], _GREY, "vertical z"))
    return dict(P=P, R=R, bodies=bodies, rods=[[[0.0, 0.0, 0.0], 0, _DARK]], lines=lines,
                up=[0, 0, 1], trail=[0], center=[0.0, 0.0, 0.3 * ell], extent=1.5 * ell,
                camera=[1.0, -1.2, 0.6], solid={"shape": "top", "l": ell, "color": _ORANGE},
                title="heavy top: its body, the centre of mass's path and the nutation bounds "
                      "(z up; m)")


def _rigid(system, times, Y):
    Y = _motion.rigid_oriented(system, times, Y)
    R = _motion.rigid_rotation(Y)                                  # (frames, 3, 3)
    P = np.transpose(R, (0, 2, 1))                                 # rows: the axes in space
    I = system.moments
    bodies = [_body(f"principal axis {j + 1} (I{j + 1} = {I[j]:.4g} kg m^2)", c, 0.04,
                    local=np.eye(3)[j], shape="cone")
              for j, c in enumerate((_RED, _GREEN, _BLUE))]
    rods = [[[0.0, 0.0, 0.0], j, c] for j, c in enumerate((_RED, _GREEN, _BLUE))]
    L = _motion.angular_momentum_space(system, R[:1], Y[:, :1])[0]
    nL = float(np.linalg.norm(L))
    lines = []
    if nL > 0:
        Lh = L / nL
        lines.append(_polyline([-1.3 * Lh, 1.3 * Lh], "#000000",
                               f"angular momentum L, fixed (|L| = {nL:.4g} kg m^2/s)",
                               dashed=True))
    sides = _motion.box_sides(I)                                   # a 1 kg box, m
    sides = np.maximum(sides, 0.02 * sides.max())                  # a flat body: a thin plate
    sides = 1.2 * sides / np.linalg.norm(sides)                    # its diagonal 1.2 (display)
    return dict(P=P, R=R, bodies=bodies, rods=rods, lines=lines, up=[0, 0, 1], trail=[0, 1, 2],
                center=[0.0, 0.0, 0.0], extent=1.4, camera=[1.0, -1.4, 0.8],
                solid={"shape": "box", "size": sides.tolist(), "color": "#c8b28a"},
                title="free rigid body: the box of its moments, its principal axes (unit "
                      "vectors) and L")


def _chain(system, times, Y, spacing=None):
    N = system.N
    X = Y[:N]
    sp = _motion.chain_spacing(X) if spacing is None else as_scalar(spacing, "spacing",
                                                                    positive=True)
    pos = _motion.chain_positions(X, sp)                            # (N, frames)
    P = np.stack([pos.T, np.zeros_like(pos.T), np.zeros_like(pos.T)], axis=-1)
    bodies = [_body(f"mass {i + 1}", _RED, 0.15 * sp, shape="cube") for i in range(N)]
    walls = _motion.chain_walls(system)
    rods = [[i, i + 1, _GREY] for i in range(N - 1)]
    lines = []
    if walls:
        w0, w1 = [0.0, 0.0, 0.0], [(N + 1) * sp, 0.0, 0.0]
        rods = [[w0, 0, _GREY]] + rods + [[N - 1, w1, _GREY]]
        for w in (w0, w1):
            lines.append(_polyline([[w[0], -0.4 * sp, 0], [w[0], 0.4 * sp, 0]], "#000000", "wall"))
    half = 0.5 * (N + 1) * sp
    return dict(P=P, bodies=bodies, rods=rods, lines=lines, up=[0, 1, 0], trail=[],
                legend=[[_RED, f"{N} masses"]],
                center=[half, 0.0, 0.0], extent=1.1 * half, camera=[0.0, 0.5, 1.0],
                title=f"spring chain of {N} masses along x (units of x; spacing {sp:.4g})")


def _particle(system, times, Y):
    P = _motion.particle_places(Y)                                 # (3, frames)
    names = _motion.particle_coordinates(system)
    one = Y.shape[0] == 2
    lo, hi = P.min(axis=1), P.max(axis=1)
    r = float(np.max(hi - lo)) or 1.0
    bodies = [_body("particle", _BLUE, 0.04 * r)]
    lines = ([_polyline([[-0.3 * r, 0, 0], [0.3 * r, 0, 0]], _DARK, f"{names[0]} = 0")]
             if one else [])
    return dict(P=P.T[:, None, :], bodies=bodies, rods=[], lines=lines, up=[0, 1, 0], trail=[0],
                center=(0.5 * (lo + hi)).tolist(), extent=0.7 * r, camera=[0.0, 0.0, 1.0],
                title=(f"particle: its height {names[0]} (y up)" if one else
                       f"particle: ({names[0]}, {names[1]}) in the plane"))


#: the shapes of shapes=, and what their size is (a number: the first; the rest follow it)
_SHAPES = {"sphere": "radius", "box": "sides (a, b, c) along the body's x, y, z",
           "cylinder": "(radius, length), its axis the body's y",
           "cone": "(radius, height), its axis the body's y",
           "torus": "(radius, tube radius), its axis the body's y"}
_PALETTE = ("#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
            "#17becf")


def _shape_of(name, given, default):
    """(kind, size list) of shapes[name]: a kind's name or dict(kind=..., size=...);
    ``default`` the size a number or None stands for."""
    if isinstance(given, str):
        kind, size = given, None
    elif isinstance(given, dict):
        extra = sorted(set(given) - {"kind", "size", "color"})
        if extra or "kind" not in given:
            raise ValueError(f"shapes[{name!r}] is dict(kind=..., size=..., color=...), got "
                             f"keys {sorted(given)}")
        kind, size = given["kind"], given.get("size")
    else:
        raise TypeError(f"shapes[{name!r}] must be a shape's name or dict(kind=..., "
                        f"size=...), got {type(given).__name__}")
    if kind not in _SHAPES:
        raise ValueError(f"shapes[{name!r}]: unknown shape kind {kind!r}; one of "
                         f"{tuple(_SHAPES)}")
    if size is None:
        return kind, default(kind)
    size = np.atleast_1d(as_array(size, f"shapes[{name!r}]['size']", positive=True))
    if size.ndim != 1 or size.size > 3:
        raise ValueError(f"shapes[{name!r}]['size'] is a number or up to 3 numbers: "
                         f"{_SHAPES[kind]}")
    r = float(size[0])
    full = {"sphere": [r], "box": [r, r, r], "cylinder": [r, 2 * r], "cone": [r, 2 * r],
            "torus": [r, 0.08 * r]}[kind]
    full[:size.size] = size.tolist()
    return kind, full[:3 if kind == "box" else 1 if kind == "sphere" else 2]


def _user_links(links, points, names) -> list:
    """The rods of ``links=[("O", "p1"), ...]`` between the named points ("O":
    the origin), as [end, end, colour] (an end: a point's index or a place)."""
    if links is None:
        return []
    if points is None:
        raise ValueError("links join points=: a mechanics model draws its own links")
    if isinstance(links, (str, bytes)) or not hasattr(links, "__iter__"):
        raise TypeError(f"links must be a list of pairs of point names, got {links!r}")
    rods = []
    for pair in links:
        if isinstance(pair, (str, bytes)) or len(pair) != 2:
            raise TypeError(f"links: each link is a pair of point names, got {pair!r}")
        ends = []
        for e in pair:
            if e == "O":
                ends.append([0.0, 0.0, 0.0])
            elif e in names:
                ends.append(names.index(e))
            else:
                raise ValueError(f"links: {e!r} is no point (the points: {names}, and "
                                 "'O' the origin)")
        rods.append([ends[0], ends[1], _DARK])
    return rods


def _ground(system, ground, y, centre, size):
    """(up, lines) of a rolling model's ground plane: ``ground`` the direction
    of the constant loads reversed (a stored expression) at the state y; the
    plane through the origin under the drawing's centre, a 7 x 7 grid."""
    from ..symbolic.kinematics import numeric
    g = numeric(ground, y, system._vector()).reshape(-1)
    g = g / np.linalg.norm(g)
    a = np.cross(g, [1.0, 0.0, 0.0] if abs(g[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b2 = np.cross(g, a)
    c0 = centre - np.dot(centre, g) * g                  # the plane through the origin
    h = 0.75 * size + 0.5
    lines = []
    for s_ in np.linspace(-h, h, 7):
        lines.append(_polyline([c0 + s_ * a - h * b2, c0 + s_ * a + h * b2], _GREY,
                               "ground plane"))
        lines.append(_polyline([c0 - h * a + s_ * b2, c0 + h * a + s_ * b2], _GREY,
                               "ground plane"))
    return g.tolist(), lines


def _bodies(system, times, Y, points=None, links=None, shapes=None):
    d = _motion.bodies_drawing(system, points)
    P, R = _motion.bodies_places(system, d, Y)
    n, nb = P.shape[:2]
    names = list(d["names"])
    lo, hi = P.reshape(-1, 3).min(axis=0), P.reshape(-1, 3).max(axis=0)
    size = float(np.max(hi - lo))
    if size == 0:
        size = 1.0
    # the solids of the bodies: a rigid body's box of its principal moments (its
    # mass's uniform box), turned to its principal axes in its frame
    solid, slot, k = {}, [None] * nb, 0
    for i, kind in enumerate(d["kinds"]):
        if kind != "rigid":
            continue
        slot[i] = k
        k += 1
        if d["inertia"][i] is not None and d["mass"][i] is not None:
            w, E, mass = _motion.principal(d, i, system, Y[:, 0])
            sides = _motion.box_sides(w, mass)
            sides = np.maximum(sides, 0.02 * (sides.max() or size))     # a flat body: a plate
            solid[i] = ("box", sides.tolist(), E)
    if shapes is not None and not isinstance(shapes, dict):
        raise TypeError(f"shapes must be a dict {{body or point name: shape}}, got "
                        f"{type(shapes).__name__}")
    for nm, given in (shapes or {}).items():
        if nm not in names:
            raise ValueError(f"shapes names {nm!r}, which is no body or point of the drawing "
                             f"(its names: {names})")
        i = names.index(nm)
        ref = solid[i][1] if i in solid else [0.04 * size] * 3
        kind, sz = _shape_of(nm, given, lambda kind: {
            "sphere": [max(ref) / 2], "box": list(ref), "cylinder": [max(ref) / 2, min(ref)],
            "cone": [max(ref) / 2, max(ref)], "torus": [max(ref) / 2, 0.08 * max(ref)]}[kind])
        solid[i] = (kind, sz, None, given.get("color") if isinstance(given, dict) else None)
    bodies = []
    for i, nm in enumerate(names):
        c = _PALETTE[i % len(_PALETTE)]
        kind, sz, E, *col = solid.get(i, ("sphere", [(0.02 if d["kinds"][i] == "joint" else
                                                      0.04) * size], None))
        b = _body(nm, (col[0] if col and col[0] else c), max(sz), shape=kind)
        b.update(size=[float(v) for v in sz], rot=slot[i],
                 axes=None if E is None else E.reshape(-1).tolist())
        bodies.append(b)
    rods = [[int(a), int(b), _GREY] for a, b in d["links"]] + _user_links(links, points, names)
    lines = []
    up = [0.0, 1.0, 0.0] if points is not None else [0.0, 0.0, 1.0]
    if d.get("ground"):
        up, lines = _ground(system, d["ground"], Y[:, 0], 0.5 * (lo + hi), size)
    trail = [i for i, kd in enumerate(d["kinds"]) if kd in ("point", "particle")]
    what = ("points of the system" if points is not None else
            f"the bodies of the model ({', '.join(names)})")
    out = dict(P=P, bodies=bodies, rods=rods, lines=lines, up=up, trail=trail,
               center=(0.5 * (lo + hi)).tolist(),
               extent=0.6 * size + 0.6 * max(max(b["size"]) for b in bodies),   # solids in view
               camera=[0.0, 0.0, 1.0] if points is not None else [1.0, -1.4, 0.8],
               title=f"{what}: places from the system's own kinematics")
    if R.shape[1]:
        out["Rs"] = R
    return out


def animate(system, sol, *, kind=None, t=None, fps=30, duration=None, speed=1.0, trail=None,
            lengths=None, spacing=None, points=None, links=None, shapes=None,
            plots=None, params=None, y0=None) -> Motion:
    r"""The motion of a solution in 3D, in the browser (three.js).

    What is drawn depends on ``kind`` (by default the drawing the system
    names, ``system.drawing``), as in :func:`mechpy.plot.animate`:

    ``"pendulum"``, ``"double_pendulum"``
        rods and bobs at :math:`(l\sin\theta, -l\cos\theta, 0)` (x right, y
        up; the second bob adds :math:`l_2(\sin\theta_2, -\cos\theta_2)`), the
        last bob's trail.
    ``"foucault"``
        :class:`~mechpy.scenes.Foucault`: the bob at (x east, y north, z up)
        with z its height :math:`L - \sqrt{L^2 - x^2 - y^2}` above the lowest
        point, hung from (0, 0, L); its trail is the rosette.
    ``"top"``
        :class:`~mechpy.scenes.HeavyTop`: the top's body turned by its ZXZ
        Euler angles (phi, theta, psi), its centre of mass
        :math:`l e_3` and its path, the nutation bounds of
        :func:`mechpy.rigid.nutation_bounds` as two circles of latitude;
        the bodies placed are the centre of mass :math:`l e_3` and a mark on
        the body's side, :math:`0.3\,l\,e_1 + l e_3`, which shows the spin.
    ``"rigid"``
        :class:`~mechpy.scenes.RigidBody`: a box with the body's principal
        moments in proportion (the uniform box of 1 kg has sides
        :math:`a^2 = 6(I_2 + I_3 - I_1)` m^2, cyclic; shown at a fixed size),
        turned by the orientation quaternion; its principal axes (unit
        vectors, the columns of :math:`R(q)`) with trails, and the fixed
        direction of the angular momentum.  A state without orientation is
        integrated again with it, ``system.replace(orientation=True)`` from
        the identity at the frames' times (rtol 1e-11).
    ``"chain"``
        :class:`~mechpy.scenes.SpringChain`: mass i (from 1) at
        :math:`i\,s + x_i` along x, with springs and, for fixed ends, walls.
    ``"particle"``
        a compiled system whose state is (q, v) with one or two coordinates:
        the point at (0, q, 0), its height up (a bouncing ball), or at
        (q1, q2, 0), with its trail.

    ``"bodies"``
        any other system, from its own description
        (:mod:`mechpy.symbolic.kinematics`): an :func:`mechpy.mechanics`
        scene's rigid bodies as the uniform box of their principal moments
        at their mass centres, turned by their frames' direction cosines
        (``N.dcm(frame)``, body to world), particles as spheres, a
        ``System``'s joints as links, and the ground plane of a rolling
        model (normal to the constant loads, through the point at rest);
        a system of :func:`mechpy.lagrangian` or :func:`mechpy.equations`
        from ``points``, ``links`` and ``shapes``.  The places and
        direction cosines are printed as C and evaluated for every frame in
        one call.

    The frames are the states at ``duration * fps + 1`` times evenly spread
    over the solution's span: from ``sol.sol`` (dense output) when the
    solution has it, else the cubic Hermite interpolant through the samples
    and the system's derivatives there.  A solution with jumps (events with
    an action, :mod:`mechpy.events`) is played piece by piece: its samples
    hold the states before and after each action at the same time, its
    dense output is one piece per interval between actions, and a frame at
    an action's time shows the state after it.  The page plays them with an orbit
    camera, play/pause, a time slider and a speed slider, and exposes
    ``window.mechpyLive``: ``play()``, ``pause()``, ``frame(i)``, ``frames()``,
    ``time()``, ``positions()`` (the places of :attr:`Motion.bodies` at the
    frame shown, x, y, z each, in the system's units), ``rotations()`` (each
    drawn solid's rotation matrix, body to world, row-major, 9 numbers a
    solid in the order of ``positions()``; the top's and the rigid body's
    one solid), ``lines()`` (the fixed lines: nutation bounds, L, walls,
    the ground plane), ``plot(name)`` (a series of ``plots``), ``fps()``.
    The camera looks from the drawing's direction and frames everything
    drawn over all frames (bodies, solids, rods, fixed lines, trails; the
    Foucault pendulum's rod runs up out of the view) for the canvas's
    aspect.

    Parameters
    ----------
    system : Scene
        The scene that made ``sol``.
    sol : Solution or array_like, shape (n, m), or None
        A result of :func:`mechpy.solve` (with ``dense_output=True`` the
        frames come from its interpolant), or states (n, m) with ``t``; None
        for a page that simulates (``y0`` given) over ``t = (t0, t1)``.
    kind : str, optional
        One of ``"bodies"``, ``"pendulum"``, ``"double_pendulum"``,
        ``"foucault"``, ``"top"``, ``"rigid"``, ``"chain"``, ``"particle"``
        (``"bodies"`` when ``points`` is given).
    t : array_like, shape (m,), optional
        The times of an array ``sol``; monotonic (a time held twice: the
        states before and after an action).  With ``sol=None``: the span
        (t0, t1), t0 < t1.
    fps : float
        Frames per second of the playback at speed 1 (at most 120).
    duration : float, optional
        Seconds the playback lasts at speed 1; default the solution's time
        span (real time), at most 60 s.  At most 3600 frames in all.
    speed : float
        The initial playback speed (the page's slider: 0.1 to 10).
    trail : float, optional
        Length of the trails in time units of the solution: ``0`` for none,
        ``np.inf`` for the whole path.  Default: the whole path for the
        Foucault pendulum and the top, a fifth (a quarter for a rigid body)
        of the span otherwise.
    lengths : array_like, shape (1,) or (2,), optional
        Rod lengths (m) of the pendulum kinds, when the scene's parameters
        do not name them.
    spacing : float, optional
        The chain's spacing at rest, in the units of x; default the largest
        displacement over 0.4.
    points : dict, optional
        ``{"name": (x, y, z)}``: SymPy expressions of the coordinates and
        parameters (by name) of an :func:`mechpy.lagrangian` or
        :func:`mechpy.equations` system, each drawn as a sphere with a
        trail; ``positions()`` lists them in this order.
    links : list of (str, str), optional
        Rods between points of ``points`` (``"O"``: the origin).
    shapes : dict, optional
        ``{"body or point name": kind or dict(kind=..., size=..., color=...)}``
        with kind ``"sphere"`` (size: radius), ``"box"`` (sides), ``"cylinder"``
        (radius, length), ``"cone"`` (radius, height) or ``"torus"`` (radius,
        tube radius); a cylinder's, cone's or torus's axis is the body's y.
    plots : list, optional
        Time series drawn under the 3D view, one panel an entry, with a
        cursor at the shown frame's time (it follows play, the slider and
        ``frame(i)``; a click on a panel shows that time): a state's name
        (``system.states``), ``"energy"`` (the system's own ``energy``: a
        built-in scene's, the Jacobi integral of :func:`mechpy.lagrangian`,
        the ``energy=`` of :func:`mechpy.equations`, T + V of an
        :func:`mechpy.mechanics` model with constant loads) or a SymPy
        expression of the states (symbols named as the states; a coordinate
        of :func:`mechpy.coordinates` and its ``diff(t)``), ``t`` and the
        parameters (by name, at the system's values), each evaluated at every
        frame's state (:mod:`mechpy._series`; on a page that simulates, the
        page evaluates their printed expressions at its own frames, with the
        parameters of each run).  ``window.mechpyLive.plot(name)``
        returns a series as drawn, ``{t: [...], y: [...]}``, ``name`` the
        entry as given (a state's name, ``"energy"`` or ``str(expr)``).
    params : dict, optional
        ``{"name": (min, max)}``: the page simulates (below) and puts each
        parameter on a slider over its range, starting at the system's value;
        moving it re-runs the motion in the page, with no kernel.
    y0 : array_like, shape (n,), or dict, optional
        The initial state of a page that simulates (an array or a dict of
        state names, as :meth:`~mechpy.scenes.Scene.initial_state` takes);
        default the solution's first state.  ``params`` or ``y0`` make the
        page simulate: it integrates the system itself over the solution's
        span (Dormand-Prince 5(4) in double precision with its 4th-order
        dense output at the frames' times, rtol = atol = 1e-12), from the
        right-hand side printed as JavaScript (:mod:`mechpy.live._field`, as
        the phase portrait's; a Lagrangian of two or more coordinates as
        M(q) and F(q, q', t), solved by LU with partial pivoting at each
        evaluation; an :func:`mechpy.mechanics` scene as the linear system A z
        = b its C solves, the same expressions, solved likewise), and places
        the bodies by the drawing's printed SymPy geometry (``points``; the
        pendulum kinds' bobs; a mechanics model's places and direction
        cosines).  A parameter that enters a mechanics model's constraints has
        no slider (``y0``, on the constraints, would leave them).  A run takes at most
        1000 steps a frame, then stops and says so.  ``window.mechpyLive``
        adds ``setParam(name, value)``, ``params()`` and ``simulation()``
        (the last run's steps, evaluations, milliseconds and status).

    Returns
    -------
    Motion
        The widget; ``save(path)`` writes one HTML file that runs offline.

    Raises
    ------
    TypeError
        ``system`` is not a scene, its kind cannot be told, ``kind`` names a
        scene of another type, ``sol`` is neither a Solution nor an array (nor
        None for a page that simulates), or ``params`` is not a dict.
    ValueError
        ``kind`` is unknown; ``sol`` is empty, not finite or does not hold
        the scene's states (n, m); ``t`` is missing, of another length or not
        monotonic; bad ``fps``, ``duration``, ``speed``, ``trail``,
        ``lengths`` or ``spacing``; more than 3600 frames; a point that
        depends on a symbol that is neither a coordinate nor a parameter, a
        link to an unknown point, an unknown shape kind or a shape for no
        body or point; in ``plots``, an unknown state name, an expression
        with a symbol that is neither a state nor a parameter, ``"energy"``
        for a system without one, a name given twice or a series that is not
        finite (each named), or, on a page that simulates, a built-in
        scene's ``"energy"`` (computed in C only).  ``plots`` that is not a list,
        or an entry that is neither a string nor a SymPy expression, is a
        TypeError.  With ``params`` or ``y0``: what the page cannot
        simulate, named before any page is made (no printed form: a
        Lagrangian with constraints, whose accelerations carry multipliers;
        a function the page does not evaluate; an :func:`mechpy.mechanics`
        scene with a callable specified input, or unpickled (its SymPy form
        is kept in memory only); a kind other than
        ``"pendulum"``, ``"double_pendulum"`` or ``"bodies"`` (``points`` or
        a mechanics model)), a name that is not a parameter, a range (min, max)
        that does not hold the system's value or a parameter of a mechanics
        model's constraints, a bad ``y0`` (one off the constraints, as
        :func:`mechpy.solve` refuses it), a span that runs backward, a
        solution with actions of events; ``sol=None``
        without ``y0`` or without ``t = (t0, t1)``.

    Examples
    --------
    >>> import numpy as np, mechpy as mp
    >>> p = mp.scenes.Pendulum(length=1.5)
    >>> sol = mp.solve(p, (0, 4), [2.0, 0.0], dense_output=True)
    >>> w = mp.live.animate(p, sol, fps=25)
    >>> w.times.size, w.bodies
    (101, ['bob'])
    """
    if kind is None and points is not None:
        kind = "bodies"
    drawing = _motion.kind_of(system, kind)
    kind = drawing.name
    simulate = params is not None or y0 is not None
    if sol is None and simulate:                     # the span t = (t0, t1), framed by a solve
        sol, t = _simulate.framing(system, t, y0), None
    tt, y = _motion.samples(system, sol, t)                        # checks sol's shape
    fps = as_scalar(fps, "fps", positive=True, hi=120.0)
    speed = as_scalar(speed, "speed", lo=0.1, hi=10.0)
    times, duration = _frame_times(tt, fps, duration)
    span = abs(float(tt[-1] - tt[0]))
    trail = (drawing.trail * span if trail is None
             else as_scalar(trail, "trail", nonnegative=True, finite=False))
    if np.isnan(trail):
        raise ValueError("trail must be a non-negative time or np.inf, got nan")
    options = {k: v for k, v in (("lengths", lengths), ("spacing", spacing), ("points", points),
                                 ("links", links), ("shapes", shapes)) if v is not None}
    for k in options:
        if k not in drawing.options:
            takers = " or ".join(repr(d.name) for d in _motion.DRAWINGS.values()
                                 if k in d.options)
            raise ValueError(f"{k} is for kind={takers}, not kind={kind!r}")
    Y = _states(system, sol, t, times)
    if not np.all(np.isfinite(Y)):
        raise ValueError("the solution is not finite over its span (sol.sol or sol.y)")
    d = drawing.painter("live")(system, times, Y, **options)
    sim = None
    if simulate:
        if tt.size > 1 and np.any(np.diff(tt) == 0):
            raise ValueError("the page simulates without events: sol has actions (a time held "
                             "twice); animate it without params= and y0=")
        sim = _simulate.simulation(system, drawing, options, params,
                                   y[:, 0] if y0 is None else y0, times, plots)
    # a page that simulates computes its series with its frames (sim's printed series)
    drawn = ([] if plots is None else _series.series(system, plots, times, Y) if sim is None
             else [(nm, None) for nm in _series.labels(system, plots)])
    n, nb = d["P"].shape[:2]
    dt = span / (n - 1)
    window = n if not np.isfinite(trail) else int(np.ceil(trail / dt - 1e-9)) if dt > 0 else 0
    spec = {
        "kind": kind, "title": d["title"], "n": n, "nb": nb, "fps": fps, "speed": speed,
        "duration": duration, "t": pack(times), "pos": pack(d["P"].reshape(n, nb * 3)),
        "rot": pack(d["R"].reshape(n, 9)) if "R" in d else None,
        "rots": pack(d["Rs"].reshape(n, -1)) if "Rs" in d else None,
        "bodies": d["bodies"], "rods": d["rods"], "lines": d["lines"],
        "legend": d.get("legend", [[b["color"], b["name"]] for b in d["bodies"]]),
        "trails": [{"body": b, "color": d["bodies"][b]["color"], "window": window}
                   for b in d["trail"]] if window > 0 else [],
        "solid": d.get("solid"), "up": d["up"], "center": d["center"],
        "extent": float(d["extent"]), "camera": d["camera"],
        "frame_rods": bool(d.get("frame_rods", True)),
        "plots": [{"name": nm, "y": None if v is None else pack(v),
                   "color": _PALETTE[i % len(_PALETTE)]}
                  for i, (nm, v) in enumerate(drawn)],
    }
    if sim is not None:                         # the page computes the frames itself
        spec.update(pos=None, rots=None, sim=sim)
    return Motion(spec, kind, times, [b["name"] for b in d["bodies"]])
