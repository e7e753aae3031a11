"""The live phase portrait: particles advected through a system's field on the
GPU in the browser (static/phase.js), with overlays from :mod:`mechpy.phase`."""
from __future__ import annotations

import math
import re
import unicodedata
import warnings

import numpy as np

from .. import phase as _phase
from ..errors import MechpyError
from .._validate import as_int, as_scalar
from ..integrate import solve
from . import _field
from ._page import LiveWidget

#: Particle counts a page takes (a texture of at most 4096 x 4096 states)
PARTICLES_MAX = 4096 * 4096


def _range(v, what):
    try:
        lo, hi = (float(x) for x in v)
    except (TypeError, ValueError):
        raise TypeError(f"{what} must be a pair (min, max) of numbers, got {v!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"{what} must be finite, got ({lo}, {hi})")
    if not lo < hi:
        raise ValueError(f"{what} must have min < max, got ({lo}, {hi})")
    return lo, hi


def _label(name: str) -> str:
    """A state's name as the portrait's axes show it: a leading Greek letter's
    name as the letter ("theta'" -> "θ'", "omega1" -> "ω1")."""
    m = re.match(r"([A-Za-z]+)(.*)", name, flags=re.S)
    if m:
        case = "CAPITAL" if m[1][0].isupper() else "SMALL"
        try:
            return unicodedata.lookup(f"GREEK {case} LETTER {m[1].upper()}") + m[2]
        except KeyError:
            pass
    return name


def _state_names(system, dim: int) -> list:
    """The axes' names: the system's own (:attr:`states`), else y[i]."""
    names = list(getattr(system, "states", None) or ())
    return [_label(nm) for nm in names] if len(names) == dim else [f"y[{i}]" for i in range(dim)]


def _states(ax: int, ay: int, h, v) -> np.ndarray:
    """2-D states (2, m) with the horizontal values ``h`` as component ``ax`` and the
    vertical ``v`` as ``ay``."""
    S = np.empty((2, len(h)))
    S[ax], S[ay] = h, v
    return S


def _field_where_defined(sysv, S) -> np.ndarray:
    """The field at the states S (dim, m), NaN where it is undefined: a block of states
    whose right-hand side raises (NonFiniteError at a pole, DomainError, ...) is halved
    down to the single states that do."""
    out = np.full(S.shape, np.nan)
    todo = [(0, S.shape[1])]
    while todo:
        a, b = todo.pop()
        try:
            with np.errstate(all="ignore"):
                out[:, a:b] = sysv.rhs(0.0, S[:, a:b])
        except (MechpyError, ArithmeticError):
            if b - a > 1:
                m = (a + b) // 2
                todo += [(a, m), (m, b)]
    out[~np.isfinite(out)] = np.nan
    return out


def _refine_zeros(sysv, ax, ay, which, pts, xs, ys, Fw):
    """Each contour vertex of component ``which`` moved onto the zero of the grid edge
    it lies on (30 bisections, then the secant in the last bracket), and whether it is
    one: a zero's bracket ends shrink with the bracket (to 1e-9 of the edge's ends for
    a simple zero), a pole's grow; kept when they end below 1e-2 of the edge's ends."""
    x0, hx = xs[0], xs[1] - xs[0]
    y0, hy = ys[0], ys[1] - ys[0]
    n = len(xs)
    fi, fj = (pts[:, 0] - x0) / hx, (pts[:, 1] - y0) / hy
    vert = np.abs(fi - np.round(fi)) < 1e-7          # on a vertical grid line: a y-edge
    i = np.where(vert, np.round(fi), np.floor(fi)).astype(int).clip(0, n - 1)
    j = np.where(vert, np.floor(fj), np.round(fj)).astype(int).clip(0, n - 1)
    i2 = np.where(vert, i, i + 1).clip(0, n - 1)
    j2 = np.where(vert, j + 1, j).clip(0, n - 1)
    A = np.stack([xs[i], ys[j]], axis=1)
    B = np.stack([xs[i2], ys[j2]], axis=1)
    fa, fb = Fw[j, i], Fw[j2, i2]
    scale = np.fmax(np.abs(fa), np.abs(fb))
    lo, hi, flo, fhi = np.zeros(len(pts)), np.ones(len(pts)), fa.copy(), fb.copy()
    ok = np.isfinite(fa) & np.isfinite(fb) & (np.sign(fa) * np.sign(fb) <= 0)

    def f(u):
        P = A + u[:, None] * (B - A)
        return _field_where_defined(sysv, _states(ax, ay, P[:, 0], P[:, 1]))[which]

    for _ in range(30):
        mid = 0.5 * (lo + hi)
        fm = f(mid)
        ok &= np.isfinite(fm)
        left = np.sign(fm) * np.sign(flo) <= 0          # the zero is in [lo, mid]
        hi, fhi = np.where(left, mid, hi), np.where(left, fm, fhi)
        lo, flo = np.where(left, lo, mid), np.where(left, flo, fm)
    keep = ok & (np.fmax(np.abs(flo), np.abs(fhi)) <= 1e-2 * scale)
    with np.errstate(all="ignore"):
        u = np.where(flo != fhi, lo + (hi - lo) * flo / (flo - fhi), lo)
    u = np.where(np.isfinite(u), u.clip(lo, hi), lo)
    refined = A + u[:, None] * (B - A)
    return np.where(keep[:, None], refined, pts), keep


class PhasePortrait(LiveWidget):
    """A live phase portrait (see :func:`phase_portrait`): an anywidget whose
    ``spec`` holds the field printed to GLSL and JavaScript, the sliders and
    the overlays; ``save(path)`` writes it as one offline page.

    Examples
    --------
    >>> import mechpy as mp
    >>> w = mp.live.phase_portrait(mp.scenes.Pendulum(), (-7, 7), (-8, 8), particles=1000)
    >>> [(round(x, 6), kind) for x, y, kind, stable in w.spec["overlays"]["sets"][0]["fixed_points"]]
    [(-6.283185, 'centre'), (-3.141593, 'saddle'), (0.0, 'centre'), (3.141593, 'saddle'), (6.283185, 'centre')]
    """

    _view = "phase"

    def __init__(self, spec: dict, system, field, overlays: bool, grid: int):
        self._system = system
        self._fd = field
        self._want_overlays = overlays
        self._grid = grid
        super().__init__(spec)

    # -- overlays ---------------------------------------------------------------
    def _system_at(self, values: dict):
        changes = {k: v for k, v in values.items() if k in self._system.params}
        return self._system.replace(**changes) if changes else self._system

    def _overlays_at(self, values: dict) -> dict:
        """Fixed points by kind, nullclines (2-D), the limit cycle (2-D, where the
        flow leaves an unstable fixed point for one) at the parameters ``values``."""
        spec = self.spec
        sysv = self._system_at(values)
        ax, ay = spec["axes"]
        dim = spec["dim"]
        out = {"values": dict(values), "fixed_points": [], "nullclines": [], "limit_cycle": []}
        if not self._fd.autonomous_at(values):
            return out          # a driven field has no fixed points (t moves)
        (x0, x1), (y0, y1) = spec["xlim"], spec["ylim"]
        bounds = []
        for i in range(dim):
            lo, hi = spec["hidden"][i]
            if hi - lo <= 0:
                lo, hi = lo - 1.0, hi + 1.0
            bounds.append((lo, hi))
        mx, my = 1e-6 * (x1 - x0), 1e-6 * (y1 - y0)
        bounds[ax] = (x0 - mx, x1 + mx)
        bounds[ay] = (y0 - my, y1 + my)
        try:
            fps = _phase.fixed_points(sysv, bounds, seeds=15 if dim <= 2 else 7)
        except Exception:                       # noqa: BLE001 - an overlay, not the answer
            fps = []
        for p in fps:
            out["fixed_points"].append([float(p.x[ax]), float(p.x[ay]), p.kind, bool(p.stable)])
        if dim == 2:
            out["nullclines"] = self._nullclines(sysv)
            for p in fps:
                if not p.stable and p.kind in ("focus", "node"):
                    cyc = self._cycle(sysv, p.x, spec)
                    if cyc:
                        out["limit_cycle"] = cyc["points"]
                        out["period"], out["amplitude"] = cyc["period"], cyc["amplitude"]
                        break
        return out

    def _nullclines(self, sysv) -> list:
        """The curves where one component of the field vanishes, in the plane shown
        (the horizontal grid is component ``axes[0]``): contours of each component on
        a 201 x 201 grid, masked where the field is undefined, each vertex refined
        onto the zero of its grid edge by bisection; a vertex whose edge holds a pole
        (the field grows instead of vanishing as the bracket shrinks: x'' = -1/x
        changes sign at x = 0 without a zero) is dropped, its line split there."""
        import contourpy
        spec = self.spec
        ax, ay = spec["axes"]
        (x0, x1), (y0, y1) = spec["xlim"], spec["ylim"]
        n = 201
        xs, ys = np.linspace(x0, x1, n), np.linspace(y0, y1, n)
        X, Y = np.meshgrid(xs, ys)
        F = _field_where_defined(sysv, _states(ax, ay, X.ravel(), Y.ravel())).reshape(2, n, n)
        out = []
        for which in (0, 1):
            Z = np.ma.masked_invalid(F[which])
            if Z.mask.all() or Z.min() > 0 or Z.max() < 0:
                continue
            gen = contourpy.contour_generator(X, Y, Z)
            for line in gen.lines(0.0):
                if len(line) < 2:
                    continue
                pts, keep = _refine_zeros(sysv, ax, ay, which, np.asarray(line, dtype=float),
                                          xs, ys, F[which])
                # split where a vertex was dropped
                cuts = np.flatnonzero(~keep)
                for piece in np.split(np.arange(len(pts)), cuts):
                    piece = piece[keep[piece]]
                    if len(piece) >= 2:
                        out.append({"which": which, "points": np.round(pts[piece], 9).tolist()})
        return out

    @staticmethod
    def _cycle(sysv, x, spec):
        """The limit cycle around the fixed point ``x``, as points in the plane shown
        (``axes[0]`` horizontal), with its period and mechpy.phase's amplitude."""
        ax, ay = spec["axes"]
        (x0, x1), _ = spec["xlim"], spec["ylim"]
        start = np.array(x, dtype=float)
        start[ax] += 0.05 * (x1 - x0)          # off the fixed point, along the horizontal
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                period, amp = _phase.limit_cycle(sysv, start, tol=1e-8, t_max=2e3,
                                                 max_periods=400)
        except Exception:                       # noqa: BLE001 - no cycle: no overlay
            return None
        # onto the cycle (after the transient), then one period from its maximum
        sol = solve(sysv, (0.0, 60.0 * period), start, rtol=1e-10, atol=1e-12)
        s = solve(sysv, (0.0, period), sol.y[:, -1], rtol=1e-10, atol=1e-12,
                  t_eval=np.linspace(0.0, period, 721))
        return {"period": float(period), "amplitude": float(amp),
                "points": np.round(np.stack([s.y[ax], s.y[ay]], axis=1), 8).tolist()}

    def precompute(self, n: int | None = None) -> None:
        """The overlays over each slider's range (``n`` values each, the others at
        their current values), for a page without a kernel."""
        spec = dict(self.spec)
        ov = spec.get("overlays")
        if not ov or ov.get("complete"):
            return
        n = self._grid if n is None else as_int(n, "n", minimum=2)
        from .._progress import Stages
        base = {q["name"]: q["value"] for q in spec["params"]}
        sets = list(ov["sets"])
        todo = [(q["name"], float(v)) for q in spec["params"] if q["min"] is not None
                for v in np.linspace(q["min"], q["max"], n)]
        names = [f"overlays at {nm} = {v:.4g}" for nm, v in todo]
        with Stages("phase_portrait", names) as bar:          # shown past a second
            for (nm, v), label in zip(todo, names):
                bar.stage(label)
                sets.append(self._overlays_at(dict(base, **{nm: v})))
        spec["overlays"] = dict(ov, sets=sets, complete=True)
        self.spec = spec

    def html(self, title: str = "mechpy live phase portrait") -> str:
        """The page as one HTML string; ValueError, never a blank page, when the printed
        field is not code a page can run (:func:`mechpy.live._field.check_code`)."""
        _field.check_code(self.spec["js"], "javascript")
        _field.check_code(self.spec["glsl"], "glsl")
        self.precompute()
        return super().html(title)

    def save(self, path, *, title: str = "mechpy live phase portrait"):
        """Write the portrait as one HTML file that runs offline (see
        :meth:`mechpy.live._page.LiveWidget.save`); the overlays are first
        computed over every slider's range (``overlay_grid`` values each)."""
        return super().save(path, title=title)

    # -- the kernel's answers -----------------------------------------------------
    def _answer(self, content: dict):
        kind = content.get("type")
        values = {k: float(v) for k, v in (content.get("params") or {}).items()}
        if kind == "overlays":
            return {"type": "overlays", "data": self._overlays_at(values)}
        if kind == "trajectory":
            y0 = np.asarray(content["y0"], dtype=float)
            t0 = float(content.get("t0", 0.0))
            spec = self.spec
            T = spec["dt"] * spec["path_steps"]
            sol = solve(self._system_at(values), (t0, t0 + T), y0, rtol=1e-9, atol=1e-11,
                        t_eval=np.linspace(t0, t0 + T, 2001))
            ax, ay = spec["axes"]
            return {"type": "trajectory",
                    "points": np.stack([sol.y[ax], sol.y[ay]], axis=1).tolist()}
        return None


def phase_portrait(system, xlim, ylim, *, params=None, particles: int = 10_000,
                   dt: float = 0.01, axes=(0, 1), seed: int = 0, overlays: bool = True,
                   hidden=None, t0: float = 0.0, steps_per_frame: int = 1,
                   fade: float = 0.94, drop: float = 0.004, point_size: float = 1.5,
                   width: int = 720, height: int = 480, play: bool = True,
                   overlay_grid: int = 9, path_steps: int = 4000) -> PhasePortrait:
    r"""A live phase portrait: particles advected through the system's field on the GPU.

    Every particle carries the whole state and takes RK4 steps of ``dt`` in
    float32 in a fragment shader (states in float textures, as fieldplay
    does); the field is the system's own right-hand side, printed to GLSL from
    its symbolic form (:meth:`mechpy.scenes.Scene.symbolic`), so the page
    evaluates what the C engine does.  Trails fade, colour tells the speed in
    the plane shown; drag pans, the wheel zooms, a click drops a trajectory
    (integrated by :func:`mechpy.solve` when a kernel is connected, by the
    page's own RK4 in double precision in a saved page).

    Parameters
    ----------
    system : Scene or compiled system
        A built-in scene or a system from :func:`mechpy.lagrangian` /
        :func:`mechpy.equations` of dimension 2, 3 or 4.  A field that depends
        on t (a drive) advances t with the particles.
    xlim, ylim : (float, float)
        The view: the ranges of the two components shown (``axes``).
    params : dict, optional
        ``{name: (min, max)}``: sliders for the system's parameters; a slider
        changes the field in the page at once (a uniform), with no kernel.
    particles : int
        Number of particles (1 to 4096^2): 10^4 runs at 30 fps or more in
        software WebGL; a laptop GPU takes 10^6.
    dt : float
        The RK4 step (time units) of each particle per update.
    axes : (int, int)
        The state components shown.
    seed : int
        Seed of the particles' initial states (the same in every browser).
    overlays : bool
        Draw fixed points by kind, nullclines (2-D) and the limit cycle
        (2-D) from :mod:`mechpy.phase`, recomputed for a slider's value (by the
        kernel; precomputed over ``overlay_grid`` values of each slider for a
        saved page).  None for a field that depends on t.
    hidden : sequence of (float, float), optional
        For a 3- or 4-dimensional system, the range of each component the
        seeds draw from (the shown ones are the view); default 0 for the
        components not shown.
    t0 : float
        The field's initial time.
    steps_per_frame : int
        RK4 steps per drawn frame while playing.
    fade : float
        Trail persistence per frame, in (0, 1).
    drop : float
        Chance per step that a particle restarts at a random state while
        playing (keeps the view filled, as fieldplay's drop probability).
    point_size, width, height : float, int, int
        Pixels.
    play : bool
        Start playing (False: paused at the seeds; ``window.mechpyLive.step``).
    overlay_grid : int
        Slider values per parameter at which a saved page holds the overlays.
    path_steps : int
        Length of a dropped trajectory, in steps of ``dt``.

    Returns
    -------
    PhasePortrait
        An ``anywidget.AnyWidget``: display it in a notebook; ``.save(path)``
        writes a page that runs offline.

    Raises
    ------
    ValueError
        A system of dimension outside 2..4 or without a symbolic form, a
        parameter the system lacks, a range with min >= max, a particle count
        outside 1..4096^2, axes out of range.

    Examples
    --------
    >>> import mechpy as mp
    >>> w = mp.live.phase_portrait(mp.scenes.VanDerPol(mu=1.0), (-4, 4), (-6, 6),
    ...                            params={"mu": (0.0, 4.0)}, overlays=False)
    >>> w.spec["dim"], w.spec["particles"]
    (2, 10000)
    >>> w.save("vdp.html").suffix    # doctest: +SKIP
    '.html'
    """
    fd = _field.field_of(system)
    dim = fd.dim
    if not 2 <= dim <= 4:
        raise ValueError(f"phase_portrait takes systems of dimension 2, 3 or 4 (each particle "
                         f"holds the whole state in a vec4); this one has dimension {dim}")
    xlim = _range(xlim, "xlim")
    ylim = _range(ylim, "ylim")
    try:
        axes = tuple(int(a) for a in axes)
    except (TypeError, ValueError):
        raise TypeError(f"axes must be two state indices, got {axes!r}") from None
    if len(axes) != 2 or axes[0] == axes[1] or not all(0 <= a < dim for a in axes):
        raise ValueError(f"axes must be two different indices in 0..{dim - 1}, got {axes}")
    particles = as_int(particles, "particles", minimum=1)
    if particles > PARTICLES_MAX:
        raise ValueError(f"particles must be at most {PARTICLES_MAX} (a 4096 x 4096 state "
                         f"texture), got {particles}")
    dt = as_scalar(dt, "dt")
    if not (math.isfinite(dt) and dt != 0):
        raise ValueError(f"dt must be finite and non-zero, got {dt}")
    fade = as_scalar(fade, "fade")
    if not 0 < fade < 1:
        raise ValueError(f"fade must lie in (0, 1), got {fade}")
    drop = as_scalar(drop, "drop")
    if not 0 <= drop <= 1:
        raise ValueError(f"drop must lie in [0, 1], got {drop}")
    sliders = {}
    if params is not None and not isinstance(params, dict):
        raise TypeError("params must be a dict {name: (min, max)} of the system's parameters "
                        f"(sliders), got {type(params).__name__}")
    for name, rng in (params or {}).items():
        if name not in fd.names:
            raise ValueError(f"params: {type(system).__name__} has no parameter {name!r}; its "
                             f"parameters are {fd.names}")
        sliders[name] = _range(rng, f"params[{name!r}]")
    if hidden is None:
        hid = [(0.0, 0.0)] * dim
    else:
        try:
            hid = list(hidden)
        except TypeError:
            raise TypeError(f"hidden must be a sequence of {dim} pairs (min, max), got "
                            f"{hidden!r}") from None
        if len(hid) != dim:
            raise ValueError(f"hidden must give a (min, max) for each of the {dim} components")
        for i, h in enumerate(hid):
            try:
                a, b = (float(x) for x in h)
            except (TypeError, ValueError):
                raise TypeError(f"hidden[{i}] must be a pair (min, max) of numbers, got "
                                f"{h!r}") from None
            if not (math.isfinite(a) and math.isfinite(b) and a <= b):
                raise ValueError(f"hidden[{i}] must be finite with min <= max, got ({a}, {b})")
            hid[i] = (a, b)
    names = _state_names(system, dim)
    plist = []
    for nm, v in zip(fd.names, fd.values):
        lo, hi = sliders.get(nm, (None, None))
        if lo is not None and not lo <= v <= hi:
            v = min(max(v, lo), hi)
        plist.append({"name": nm, "value": v, "min": lo, "max": hi})
    spec = {
        "dim": dim, "axes": list(axes), "names": names, "xlim": list(xlim), "ylim": list(ylim),
        "particles": particles, "dt": dt, "seed": as_int(seed, "seed", minimum=0),
        "glsl": _field.glsl(fd), "js": _field.javascript(fd), "params": plist,
        "time_dependent": fd.time_dependent, "hidden": [list(h) for h in hid],
        "t0": as_scalar(t0, "t0"), "steps_per_frame": as_int(steps_per_frame, "steps_per_frame",
                                                             minimum=1),
        "fade": fade, "drop": drop, "point_size": as_scalar(point_size, "point_size",
                                                            positive=True),
        "width": as_int(width, "width", minimum=64), "height": as_int(height, "height", minimum=64),
        "play": bool(play), "path_steps": as_int(path_steps, "path_steps", minimum=1),
        "overlays": None,
    }
    # the overlays at the parameters given (the system's own values, clipped onto the sliders)
    start_values = {q["name"]: q["value"] for q in plist}
    w = PhasePortrait(spec, system, fd, bool(overlays),
                      as_int(overlay_grid, "overlay_grid", minimum=2))
    if overlays:
        first = w._overlays_at(start_values)
        w.spec = dict(spec, overlays={"sets": [first], "initial": 0, "complete": not sliders})
    return w
