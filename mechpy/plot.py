"""Plots (matplotlib, an optional dependency: ``pip install "mechpy-classical[plot]"``).

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
a path in space as ``Solution.y`` gives it, (3, m).
"""
from __future__ import annotations

import warnings

import numpy as np

from . import _motion, _series
from ._validate import as_array, as_int, as_scalar
from .integrate import solve
from .scenes import Pendulum, Scene, VanDerPol

__all__ = ["phase_portrait", "work_precision", "modes", "trajectory3d", "animate_field", "animate"]


def _plt():
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise ImportError("mechpy.plot needs matplotlib: pip install \"mechpy-classical[plot]\" "
                          "(or pip install matplotlib)") from exc
    return plt


def _func_animation(fig, func, **kw):
    """A matplotlib FuncAnimation drawing each frame once when saved.

    ``FuncAnimation.save`` (and ``to_jshtml``, which saves) redraws the canvas
    after each frame and then again for the writer; the first redraw is
    skipped while saving (the frames written are the same, a third of the
    drawing less).  Shown live, it is the ordinary animation."""
    from matplotlib import animation

    class _Animation(animation.FuncAnimation):
        _saving = False

        def _post_draw(self, framedata, blit):
            if not self._saving:
                super()._post_draw(framedata, blit)

        def save(self, *args, **kwargs):
            self._saving = True
            try:
                return super().save(*args, **kwargs)
            finally:
                self._saving = False

    return _Animation(fig, func, **kw)


def _state_labels(system):
    """Axis labels, with units, of a two-state system's (q, q_dot): from the
    scene's type, its coordinate names (compiled scenes), or generic ones."""
    if isinstance(system, Pendulum):
        return r"$\theta$ (rad)", r"$\dot\theta$ (rad/s)"
    if isinstance(system, VanDerPol):
        return "$x$ (dimensionless)", r"$\dot x$ (dimensionless)"
    names = getattr(system, "coordinates", None) if isinstance(system, Scene) else None
    if isinstance(names, (list, tuple)) and len(names) == 1 and isinstance(names[0], str):
        return f"{names[0]} (model units)", f"d{names[0]}/dt (model units/s)"
    return "$y_0$ (state units)", r"$y_1$ (state units)"


def _colorbar(ax, mappable, label):
    """A colorbar beside ``ax`` for ``mappable``, labelled (with units)."""
    cb = ax.figure.colorbar(mappable, ax=ax, pad=0.02, fraction=0.05)
    cb.set_label(label)
    return cb


def _field(system, X, Y, t=0.0):
    """(U, V) of a 2-D system on the grid (X, Y)."""
    if isinstance(system, Scene):
        f = system.rhs(t, np.stack([X, Y]))
        return f[0], f[1]
    U = np.empty_like(X)
    V = np.empty_like(Y)
    for idx in np.ndindex(X.shape):
        u, v = system(t, np.array([X[idx], Y[idx]]))
        U[idx], V[idx] = u, v
    return U, V


def phase_portrait(system, xlim=(-2 * np.pi, 2 * np.pi), ylim=(-4.0, 4.0), *, t=0.0,
                   trajectories=(), t_max=20.0, grid=41, nullclines=True, ax=None,
                   labels=None, colorbar=True):
    r"""Streamlines of a 2-D system's vector field, nullclines and trajectories.

    The streamlines are coloured by the speed of the flow in the state plane,
    :math:`|\mathbf f(t, \mathbf y)|`, with a colorbar; the nullclines
    (dashed) and the trajectories (black, a dot at each start) are named in a
    legend below the axes.

    Parameters
    ----------
    system : Scene or callable f(t, y)
        A two-dimensional system.
    xlim, ylim : (float, float)
        The window in the state plane.
    t : float
        Time at which the field is drawn (driven systems).
    trajectories : sequence of initial states (2,)
        Each is integrated with :func:`mechpy.solve` over ``[0, t_max]`` and drawn.
    t_max : float
        Length of each trajectory (time units of the system).
    grid : int
        Grid points per axis for the streamlines.
    nullclines : bool
        Draw the curves where each component of the field vanishes.
    ax : matplotlib Axes, optional
        Where to draw; a new figure otherwise.
    labels : (str, str), optional
        Axis labels, with units.  Default: from the scene (``theta (rad)`` and
        ``theta_dot (rad/s)`` for a :class:`~mechpy.scenes.Pendulum`, the
        coordinate's name for a compiled scene), generic otherwise.
    colorbar : bool
        Add the colorbar of the speed beside the axes.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> ax = mp.plot.phase_portrait(mp.scenes.Pendulum(), (-np.pi, np.pi), (-7, 7),
    ...                             trajectories=[(1.0, 0.0)], t_max=3, grid=15)
    >>> ax.get_xlabel().endswith("(rad)"), ax.get_ylabel().endswith("(rad/s)")   # from the scene
    (True, True)
    >>> ax.get_xlim() == (-np.pi, np.pi)
    True
    >>> plt.close("all")
    """
    plt = _plt()
    from matplotlib.colors import PowerNorm
    from matplotlib.lines import Line2D
    grid = as_int(grid, "grid", minimum=3)
    xlim = as_array(xlim, "xlim", shape=(2,))
    ylim = as_array(ylim, "ylim", shape=(2,))
    if labels is None:
        labels = _state_labels(system)
    elif (not isinstance(labels, (list, tuple)) or len(labels) != 2
          or not all(isinstance(lb, str) for lb in labels)):
        raise ValueError(f"labels must be two strings (x label, y label), got {labels!r}")
    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 5), layout="constrained")
    x = np.linspace(*xlim, grid)
    y = np.linspace(*ylim, grid)
    X, Y = np.meshgrid(x, y)
    U, V = _field(system, X, Y, t)
    speed = np.hypot(U, V)
    finite = speed[np.isfinite(speed)]
    top = float(finite.max()) if finite.size and finite.max() > 0 else 1.0
    # a square-root scale: the slow flow near fixed points keeps its colours
    strm = ax.streamplot(X, Y, U, V, color=speed, cmap="viridis",
                         norm=PowerNorm(0.5, vmin=0.0, vmax=top), density=1.2,
                         linewidth=0.7, arrowsize=0.8)
    handles = []
    if nullclines:
        ax.contour(X, Y, U, levels=[0.0], colors="tab:red", linewidths=0.8, linestyles="--")
        ax.contour(X, Y, V, levels=[0.0], colors="tab:orange", linewidths=0.8, linestyles="--")
        names = [lb.rsplit(" (", 1)[0] for lb in labels]     # the symbols, without units
        handles += [Line2D([], [], color="tab:red", lw=0.8, ls="--",
                           label=f"nullcline d{names[0]}/dt = 0"),
                    Line2D([], [], color="tab:orange", lw=0.8, ls="--",
                           label=f"nullcline d{names[1]}/dt = 0")]
    for y0 in trajectories:
        s = solve(system, (0.0, t_max), as_array(y0, "trajectory start", shape=(2,)),
                  t_eval=np.linspace(0.0, t_max, 2000), rtol=1e-9)
        ax.plot(s.y[0], s.y[1], color="k", lw=1.2)
        ax.plot(*s.y[:, 0], "o", color="k", ms=3)
    if len(trajectories):
        handles.append(Line2D([], [], color="k", lw=1.2, marker="o", ms=3,
                              label="trajectories (dot: start)"))
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    if not ax.get_title():
        name = type(system).__name__ if isinstance(system, Scene) else "f(t, y)"
        ax.set_title(f"phase portrait of {name}")
    if colorbar:
        _colorbar(ax, strm.lines, "speed of the flow |dy/dt| (axis units/s)")
    if handles:
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.16),
                  ncol=min(len(handles), 2), frameon=False)
    return ax


def work_precision(rows, problem=None, *, ax=None):
    """Work-precision diagram: error against wall time, log-log, one line per
    implementation (the rows of ``python -m mechpy bench``: dicts with
    ``problem``, ``impl``, ``time`` (s) and ``error``).

    Rows without a positive finite error are left out; ``problem`` picks one
    problem when the rows hold several (default: the first).  Returns the Axes.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> rows = [dict(problem="pendulum", impl="mechpy", time=t, error=e)
    ...         for t, e in [(1e-3, 1e-6), (2e-3, 1e-9)]]
    >>> rows += [dict(problem="pendulum", impl="scipy", time=t, error=e)
    ...          for t, e in [(1e-2, 1e-6), (3e-2, 1e-9)]]
    >>> ax = mp.plot.work_precision(rows)
    >>> len(ax.get_lines()), ax.get_xscale(), ax.get_yscale()
    (2, 'log', 'log')
    >>> plt.close("all")
    """
    plt = _plt()
    rows = list(rows)
    if not rows:
        raise ValueError("rows must not be empty")
    for i, r in enumerate(rows):
        if not isinstance(r, dict) or not {"problem", "impl", "time", "error"} <= set(r):
            raise ValueError(f"rows[{i}] must be a dict with problem, impl, time and error")
    if problem is None:
        problem = rows[0]["problem"]
    pr = [r for r in rows if r["problem"] == problem and r["error"] is not None
          and np.isfinite(r["error"]) and r["error"] > 0 and r["time"] > 0]
    if not pr:
        raise ValueError(f"no rows with a positive error for problem {problem!r}")
    if ax is None:
        _, ax = plt.subplots(figsize=(9.5, 4.5), layout="constrained")
    impls = list(dict.fromkeys(r["impl"] for r in pr))
    colors = plt.get_cmap("tab20" if len(impls) > 10 else "tab10")
    for i, impl in enumerate(impls):
        # along the tolerance sweep (by rtol where given), so noise cannot zig-zag the line
        pts = sorted(((-(r.get("rtol") or 0.0), r["time"], r["error"]) for r in pr
                      if r["impl"] == impl), key=lambda p: (p[0], -p[2]))
        style = ("o-" if impl.startswith("mechpy") else
                 "s--" if impl.startswith("scipy") else "^:")
        ax.loglog([p[1] for p in pts], [p[2] for p in pts], style, label=impl, ms=3.5,
                  color=colors(i % colors.N), lw=1.6 if impl.startswith("mechpy") else 1.1)
    ax.set_xlabel("median wall time (s)")
    ax.set_ylabel("error at the final time (state units)")
    ax.set_title(f"work-precision: {problem}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5))
    return ax


def modes(m, which=None, *, positions=None, ax=None, position_unit="m"):
    """Mode shapes of a :class:`mechpy.modes.Modes`: the displacement of each
    coordinate in the chosen modes (default: up to the six lowest), each
    labelled with its angular frequency (rad/s).  ``positions`` places the
    coordinates along the horizontal axis (default 1..n, in units of
    ``position_unit``).  The shapes are M-normalised (:math:`a^T M a = 1`: in
    kg^-1/2 for masses in kg).  Returns the Axes.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> m = mp.modes.normal_modes(*mp.modes.chain(4))      # 4 unit masses, fixed ends
    >>> ax = mp.plot.modes(m)
    >>> len(ax.get_lines()) >= 4             # one shape per mode
    True
    >>> plt.close("all")
    """
    plt = _plt()
    V = np.asarray(m.vectors)
    n = V.shape[0]
    idx = range(min(6, V.shape[1])) if which is None else \
        [as_int(k, "which", minimum=0, maximum=V.shape[1] - 1) for k in np.atleast_1d(which)]
    x = np.arange(1, n + 1) if positions is None else as_array(positions, "positions", shape=(n,))
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 4), layout="constrained")
    for k in idx:
        ax.plot(x, V[:, k], "o-", ms=3, label=rf"mode {k + 1}: $\omega$ = {m.omega[k]:.4g} rad/s")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel("coordinate index i (count)" if positions is None
                  else f"equilibrium position ({position_unit})")
    ax.set_ylabel(r"mode shape $a_i$ (kg$^{-1/2}$, $a^T M a = 1$)")
    ax.set_title("normal modes: shapes and angular frequencies")
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5))
    return ax


def trajectory3d(path, *, ax=None, unit="m", **line_kw):
    """A curve in space: ``path`` of shape (3, m) (e.g. ``sol.y[:3]``), or a
    :class:`mechpy.Solution` whose first three components are drawn.  Marks the
    start; the axes are labelled x, y, z in ``unit``.  Returns the 3-D Axes.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> t = np.linspace(0, 4 * np.pi, 200)
    >>> helix = np.array([np.cos(t), np.sin(t), t / (2 * np.pi)])
    >>> ax = mp.plot.trajectory3d(helix, unit="m")
    >>> ax.name, ax.get_zlabel()
    ('3d', 'z (m)')
    >>> plt.close("all")
    """
    plt = _plt()
    y = path.y if hasattr(path, "y") else path
    y = as_array(y, "path", ndim=2)
    if y.shape[0] < 3:
        raise ValueError(f"path must have at least 3 rows (x, y, z), got shape {y.shape}")
    if ax is None:
        fig = plt.figure(figsize=(6, 5))
        ax = fig.add_subplot(projection="3d")
    ax.plot(y[0], y[1], y[2], **({"lw": 1.0} | line_kw))
    ax.plot([y[0, 0]], [y[1, 0]], [y[2, 0]], "o", color="k", ms=4)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_zlabel(f"z ({unit})")
    if not ax.get_title():
        ax.set_title("path in space (dot: start)")
    return ax


def animate_field(system, xlim=(-2 * np.pi, 2 * np.pi), ylim=(-4.0, 4.0), *, particles=800,
                  frames=120, dt=0.03, trail=8, respawn=0.01, t=0.0, seed=0, path=None,
                  interval=40, param=None, values=None):
    r"""Particles advected through a 2-D field and fading, as fieldplay does (deprecated).

    Deprecated: use :func:`mechpy.live.phase_portrait`, whose particles move
    on the GPU in the browser (10^4 at 32-34 fps in software WebGL, against
    0.8 s a frame and 16 MB of pre-rendered frames for 30 frames here), whose
    sliders work in a saved page, and which draws fixed points, nullclines
    and the limit cycle.  This function stays for a printed figure or a GIF
    and warns (``DeprecationWarning``).

    Each frame moves every particle one RK4 step of ``dt`` through the field
    :math:`\dot{\mathbf y} = \mathbf f(t, \mathbf y)` (evaluated in C for
    scenes) and draws its last ``trail`` positions with fading opacity; a
    fraction ``respawn`` of the particles, and any that leave the window,
    restart at random places.

    Parameters
    ----------
    system : Scene or callable f(t, y)
        A two-dimensional system (state units on both axes).
    xlim, ylim : (float, float)
        The window in the state plane.
    particles, frames, trail : int
        Particles advected, frames drawn, positions kept per particle's trail.
    dt : float
        Time step per frame (time units of the system).
    respawn : float
        Fraction of the particles restarted at random at each frame.
    t : float
        Time at which the field is frozen (driven systems).
    seed : int
        Seed of the random particle positions (the animation is reproducible).
    path : str or Path, optional
        Also write the animation there: ``.html`` as a JavaScript animation,
        otherwise a GIF (Pillow).
    interval : int
        Milliseconds between frames.
    param : str, optional
        The name of a parameter of the scene ``system`` (e.g. ``"mu"`` for
        :class:`mechpy.scenes.VanDerPol`) to offer on a slider; needs
        ipywidgets (``pip install "mechpy-classical[plot]"``).
    values : array_like, shape (m,), optional
        The values the slider offers (required with ``param``).

    Returns
    -------
    matplotlib.animation.FuncAnimation or ipywidgets.VBox
        Without ``param``, the animation: in a notebook show it with
        ``IPython.display.HTML(anim.to_jshtml())``.  With ``param``, a widget
        (a slider over ``values`` above an output showing the JavaScript
        animation of ``system.replace(param=value)``; each value is rendered
        once, when first chosen).

    Raises
    ------
    ImportError
        ``param`` was given but ipywidgets is not installed.
    ValueError
        ``param`` is not a parameter of the scene, ``values`` is missing,
        empty or not finite, or ``path`` is combined with ``param``.
    TypeError
        ``param`` was given for a system that is not a scene.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> anim = mp.plot.animate_field(mp.scenes.VanDerPol(1.0), (-3, 3), (-4, 4),
    ...                              particles=50, frames=5, dt=0.1)
    >>> from matplotlib.animation import FuncAnimation
    >>> isinstance(anim, FuncAnimation)
    True
    >>> plt.close("all")
    """
    warnings.warn("mp.plot.animate_field is deprecated: mp.live.phase_portrait advects the "
                  "particles on the GPU in the browser, with sliders that work in a saved page",
                  DeprecationWarning, stacklevel=2)
    if param is None:
        if values is not None:
            raise ValueError("values is given without param: name the scene parameter "
                             "the slider should vary")
        return _animate_field(system, xlim, ylim, particles=particles, frames=frames, dt=dt,
                              trail=trail, respawn=respawn, t=t, seed=seed, path=path,
                              interval=interval)
    if not isinstance(param, str):
        raise TypeError(f"param must be a parameter name (str), got {type(param).__name__}")
    if not isinstance(system, Scene):
        raise TypeError("animate_field(param=...) needs a scene (its parameters are varied), "
                        f"got {type(system).__name__}")
    if param not in system.params:
        raise ValueError(f"{param!r} is not a parameter of {type(system).__name__}: "
                         f"{list(system.params)}")
    if values is None:
        raise ValueError(f"animate_field(param={param!r}) needs values: the values the "
                         "slider offers")
    vals = as_array(values, "values", ndim=1)
    if path is not None:
        raise ValueError("path cannot be combined with param: write one file per value "
                         "with animate_field(system.replace(...), path=...)")
    scenes = [system.replace(**{param: float(v)}) for v in vals]  # bad values fail here
    try:
        import ipywidgets as widgets
    except ImportError as exc:
        raise ImportError("animate_field(param=...) draws a slider and needs ipywidgets: "
                          "pip install \"mechpy-classical[plot]\" "
                          "(or pip install ipywidgets)") from exc
    plt = _plt()
    opts = dict(particles=particles, frames=frames, dt=dt, trail=trail, respawn=respawn, t=t,
                seed=seed, path=None, interval=interval)
    cache = {}

    def render(i):
        if i not in cache:
            anim = _animate_field(scenes[i], xlim, ylim, **opts)
            cache[i] = anim.to_jshtml()
            plt.close(anim._fig)
        return cache[i]

    slider = widgets.SelectionSlider(options=[(f"{v:g}", i) for i, v in enumerate(vals)],
                                     value=0, description=param, continuous_update=False)
    out = widgets.Output()

    def show(i):
        out.outputs = ({"output_type": "display_data", "metadata": {},
                        "data": {"text/html": render(i),
                                 "text/plain": f"<{type(system).__name__} field, "
                                               f"{param} = {vals[i]:g}>"}},)

    slider.observe(lambda change: show(change["new"]), names="value")
    show(0)
    return widgets.VBox([slider, out])


def _animate_field(system, xlim, ylim, *, particles, frames, dt, trail, respawn, t, seed, path,
                   interval):
    plt = _plt()
    from matplotlib.collections import LineCollection
    particles = as_int(particles, "particles", minimum=1)
    frames = as_int(frames, "frames", minimum=1)
    trail = as_int(trail, "trail", minimum=2)
    dt = float(as_array(dt, "dt", positive=True))
    xlim = as_array(xlim, "xlim", shape=(2,))
    ylim = as_array(ylim, "ylim", shape=(2,))
    rng = np.random.default_rng(seed)

    def spawn(k):
        return np.stack([rng.uniform(*xlim, k), rng.uniform(*ylim, k)])

    def f(p):
        U, V = _field(system, p[0], p[1], t)
        return np.stack([U, V])

    pos = spawn(particles)
    hist = np.repeat(pos[None], trail, axis=0)  # (trail, 2, particles)
    fig, ax = plt.subplots(figsize=(6, 4.5))
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_facecolor("black")
    xl, yl = _state_labels(system)
    ax.set_xlabel(xl)
    ax.set_ylabel(yl)
    ax.set_title(f"particles carried by the field, {dt:g} time units per frame")
    lc = LineCollection([], linewidths=1.0)
    ax.add_collection(lc)
    alphas = np.linspace(0.05, 1.0, trail - 1)

    def step(_):
        nonlocal pos, hist
        k1 = f(pos)
        k2 = f(pos + 0.5 * dt * k1)
        k3 = f(pos + 0.5 * dt * k2)
        k4 = f(pos + dt * k3)
        pos = pos + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out = ((pos[0] < xlim[0]) | (pos[0] > xlim[1]) | (pos[1] < ylim[0]) | (pos[1] > ylim[1])
               | (rng.random(particles) < respawn) | ~np.all(np.isfinite(pos), axis=0))
        hist = np.roll(hist, -1, axis=0)
        if out.any():
            pos[:, out] = spawn(int(out.sum()))
            hist[:, :, out] = pos[None, :, out]
        hist[-1] = pos
        segs = np.stack([hist[:-1], hist[1:]], axis=1)        # (trail-1, 2pts, 2, P)
        segs = segs.transpose(0, 3, 1, 2).reshape(-1, 2, 2)  # ((trail-1)*P, 2pts, xy)
        colors = np.zeros((segs.shape[0], 4))
        colors[:, :3] = (0.55, 0.85, 1.0)
        colors[:, 3] = np.repeat(alphas, particles)
        lc.set_segments(segs)
        lc.set_color(colors)
        return (lc,)

    anim = _func_animation(fig, step, frames=frames, interval=interval, blit=True)
    if path is not None:
        _save(anim, path, max(1, 1000 // interval))
    return anim


# ---------------------------------------------------------------- the motion itself

def _square_view(ax, r, xlabel, ylabel):
    """A plane view of [-r, r]^2 at equal aspect, labelled, with the origin (the pivot)
    marked."""
    ax.set_xlim(-r, r)
    ax.set_ylim(-r, r)
    ax.set_aspect("equal")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.plot([0.0], [0.0], "k+", ms=8)


def _trail(ax, color):
    """An empty fading trail (a line collection, 3-D on 3-D axes)."""
    if ax.name == "3d":
        from mpl_toolkits.mplot3d.art3d import Line3DCollection
        lc = Line3DCollection([np.zeros((2, 3))], linewidths=1.2)
        ax.add_collection3d(lc, autolim=False)
    else:
        from matplotlib.collections import LineCollection
        lc = LineCollection([], linewidths=1.2)
        ax.add_collection(lc)
    lc.set_gid("trail")
    lc._mp_color = color
    return lc


def _fade(lc, pts):
    """Draw the points ``pts`` (k, d), oldest first, as segments fading in."""
    from matplotlib.colors import to_rgba
    if len(pts) < 2:
        lc.set_segments([])
        return
    segs = np.stack([pts[:-1], pts[1:]], axis=1)
    rgba = np.tile(to_rgba(lc._mp_color), (len(segs), 1))
    rgba[:, 3] = np.linspace(0.08, 1.0, len(segs))
    lc.set_segments(segs)
    lc.set_color(rgba)


def _window(t, trail):
    """first(k): the first sample within ``trail`` time units before sample k."""
    s = np.abs(t - t[0])
    return lambda k: int(np.searchsorted(s, s[k] - trail, side="left"))


def _planar_pendulum(ax, system, t, y, trail, lengths):
    """Rods from the pivot through the bobs; a fading trail of the last bob."""
    two = y.shape[0] == 4
    ls = _motion.pendulum_lengths(system, two, lengths)
    xs, ys = _motion.pendulum_bobs(y, ls)
    _square_view(ax, ls.sum() * 1.12, "x (m)", "y, up (m)")
    ax.set_title("double pendulum: rods, bobs, lower bob's trail" if two
                 else "pendulum: rod, bob and its trail")
    tr = _trail(ax, "tab:orange")
    (rod,) = ax.plot([], [], "-", color="0.3", lw=2, gid="rod")
    (bob,) = ax.plot([], [], "o", color="tab:blue", ms=10, gid="bob", zorder=3)
    first = _window(t, trail)

    def update(k):
        rod.set_data(np.r_[0.0, xs[:, k]], np.r_[0.0, ys[:, k]])
        bob.set_data(xs[:, k], ys[:, k])
        _fade(tr, np.column_stack([xs[-1, first(k):k + 1], ys[-1, first(k):k + 1]]))
        return rod, bob, tr
    return update


def _foucault(ax, system, t, y, trail, lengths):
    """The bob seen from above, tracing its rosette in the floor plane."""
    _square_view(ax, np.max(np.hypot(y[0], y[1])) * 1.15 or 1.0, "x, east (m)",
                 "y, north (m)")
    ax.set_title("Foucault pendulum seen from above")
    return _dot_and_trail(ax, t, y, trail, "tab:red", "tab:blue", 8, "bob")


def _dot_and_trail(ax, t, P, trail, color, trail_color, size, gid):
    """The update of a dot at (P[0, k], P[1, k]) with its fading trail of the
    last `trail` seconds."""
    tr = _trail(ax, trail_color)
    (dot,) = ax.plot([], [], "o", color=color, ms=size, gid=gid, zorder=3)
    first = _window(t, trail)

    def update(k):
        dot.set_data(P[0, k:k + 1], P[1, k:k + 1])
        _fade(tr, P[:2, first(k):k + 1].T)
        return dot, tr
    return update


def _sphere_axes(ax, label):
    """The unit cube around the unit sphere, at equal aspect, its axes labelled
    (the components of unit vectors, dimensionless)."""
    ax.set_xlim(-1, 1)
    ax.set_ylim(-1, 1)
    ax.set_zlim(-1, 1)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x (unit vector)")
    ax.set_ylabel("y (unit vector)")
    ax.set_zlabel(f"{label} (unit vector)")


def _top(ax, system, t, y, trail, lengths):
    """The symmetry axis e3 of a heavy top on the unit sphere, its tip's path,
    and the nutation bounds as two circles of latitude."""
    e3 = _motion.top_rotation(y)[:, :, 2]                # column 3 of R is e3
    _sphere_axes(ax, "z, up")
    ax.set_title("heavy top: symmetry axis and its tip")
    phi = np.linspace(0.0, 2 * np.pi, 121)
    bounds = _motion.top_bounds(system, y[:, 0])
    for th, ls in zip(bounds, ("--", ":")):
        ax.plot(np.sin(th) * np.cos(phi), np.sin(th) * np.sin(phi), np.full_like(phi, np.cos(th)),
                ls, color="0.4", lw=1, gid="bound",
                label=rf"$\theta$ = {th:.3f} rad")
    if bounds:
        ax.legend(loc="upper left", bbox_to_anchor=(0.0, 1.0),
                  title="nutation bounds")
    tr = _trail(ax, "tab:orange")
    (axis,) = ax.plot([], [], [], "-", color="tab:blue", lw=2.5, gid="axis")
    (tip,) = ax.plot([], [], [], "o", color="tab:blue", ms=5, gid="tip")
    first = _window(t, trail)

    def update(k):
        axis.set_data_3d([0.0, e3[k, 0]], [0.0, e3[k, 1]], [0.0, e3[k, 2]])
        tip.set_data_3d(e3[k:k + 1, 0], e3[k:k + 1, 1], e3[k:k + 1, 2])
        _fade(tr, e3[first(k):k + 1])
        return axis, tip, tr
    return update


def _rigid(ax, system, t, y, trail, lengths):
    """The body axes of a free rigid body in space (columns of R(q)), the tips'
    fading paths and the fixed angular momentum direction."""
    y = _motion.rigid_oriented(system, t, y)   # without orientation: integrated alongside
    R = _motion.rigid_rotation(y)                           # (m, 3, 3), body to space
    L = _motion.angular_momentum_space(system, R, y)
    Lhat = L[0] / (np.linalg.norm(L[0]) or 1.0)
    _sphere_axes(ax, "z")
    ax.set_title("free rigid body: body axes in space")
    ax.plot([0, Lhat[0]], [0, Lhat[1]], [0, Lhat[2]], "k--", lw=1, gid="L",
            label="angular momentum L (fixed)")
    arts, trails = [], []
    for j, c in enumerate(("tab:red", "tab:green", "tab:blue")):
        (ln,) = ax.plot([], [], [], "-", color=c, lw=2.5, gid=f"axis{j + 1}",
                        label=f"body axis {j + 1} ($I_{j + 1}$ = {system.moments[j]:.3g})")
        arts.append(ln)
        trails.append(_trail(ax, c))
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, 1.0))
    first = _window(t, trail)

    def update(k):
        for j in range(3):
            a = R[k, :, j]
            arts[j].set_data_3d([0.0, a[0]], [0.0, a[1]], [0.0, a[2]])
            _fade(trails[j], R[first(k):k + 1, :, j])
        return (*arts, *trails)
    return update


def _chain(ax, system, t, y, trail, lengths):
    """A spring chain: the displacements against the mass index (markers, the
    solution; dashed, the exact normal-mode superposition of Modes.evolve for
    linear springs), and below them the masses moving along the chain."""
    N = system.N
    x = y[:N]
    idx = np.arange(1, N + 1)
    A = np.max(np.abs(x)) or 1.0
    row = -1.6 * A
    spacing = _motion.chain_spacing(x)    # the largest displacement: 0.4 of the spacing
    walls = _motion.chain_walls(system)
    lo, hi = (0.5 if not walls else -0.3), (N + 0.5 if not walls else N + 1.3)
    ax.set_xlim(lo, hi)
    ax.set_ylim(row - 0.6 * A, 1.25 * A)
    ax.set_xlabel("mass index (equilibrium position, spacings)")
    ax.set_ylabel("displacement $x_i$ (m)")
    ax.set_title("spring chain: displacements and masses")
    ax.axhline(0.0, color="0.7", lw=0.6)
    for w in walls:
        ax.plot([w, w], [row - 0.3 * A, row + 0.3 * A], "k-", lw=3)
    exact = None
    if not system.nonlinear:
        exact = system.modes().evolve(x[:, 0], y[N:, 0], t - t[0])       # (m, N)
        (mline,) = ax.plot([], [], "--", color="0.3", lw=1, gid="modes",
                           label="normal modes (Modes.evolve)")
    (dots,) = ax.plot([], [], "o", color="tab:blue", ms=5, gid="displacement",
                      label="solution x_i(t)")
    (spring,) = ax.plot([], [], "-", color="0.5", lw=1, gid="springs")
    (masses,) = ax.plot([], [], "s", color="tab:red", ms=7, gid="masses",
                        label="masses along the chain (displacement x 0.4/max|x|)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=1)

    def update(k):
        dots.set_data(idx, x[:, k])
        pos = _motion.chain_positions(x[:, k:k + 1], spacing)[:, 0] / spacing
        masses.set_data(pos, np.full(N, row))
        spring.set_data(np.r_[walls[:1], pos, walls[1:]], np.full(N + len(walls), row))
        out = [dots, masses, spring]
        if exact is not None:
            mline.set_data(idx, exact[k])
            out.append(mline)
        return tuple(out)
    return update


def _particle(ax, system, t, y, trail, lengths):
    """The particle at its place (one coordinate: its height, drawn up), with a
    fading trail."""
    P = _motion.particle_places(y)
    one = y.shape[0] == 2
    names = _motion.particle_coordinates(system)
    if one:
        lo, hi = float(P[1].min()), float(P[1].max())
        pad = 0.08 * (hi - lo or 1.0)
        ax.set_xlim(-0.5 * (hi - lo or 1.0), 0.5 * (hi - lo or 1.0))
        ax.set_ylim(lo - pad, hi + pad)
        ax.set_xticks([])
        ax.set_ylabel(f"{names[0]} (up)")
    else:
        r = float(np.max(np.abs(P[:2]))) * 1.15 or 1.0
        _square_view(ax, r, names[0], names[1])
    ax.set_title(f"particle: ({', '.join(names)}) and its trail")
    return _dot_and_trail(ax, t, P, trail, "tab:blue", "tab:orange", 10, "particle")


def _bodies(ax, system, t, y, trail, lengths):
    """A mechanics model's mass centres (and joints) from its own compiled
    kinematics, the links between them, in the model's inertial frame (z up);
    the solids, the ground and points= are the live view's
    (:func:`mechpy.live.animate`)."""
    d = _motion.bodies_drawing(system)
    P, _ = _motion.bodies_places(system, d, y)                 # (m, bodies, 3)
    lo, hi = P.reshape(-1, 3).min(axis=0), P.reshape(-1, 3).max(axis=0)
    c, h = 0.5 * (lo + hi), 0.55 * (float(np.max(hi - lo)) or 1.0)
    ax.set_xlim(c[0] - h, c[0] + h)
    ax.set_ylim(c[1] - h, c[1] + h)
    ax.set_zlim(c[2] - h, c[2] + h)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.set_title("the bodies' mass centres (the system's own kinematics)")
    dots = [ax.plot([], [], [], "o", ms=7, gid=f"body{i}", label=nm)[0]
            for i, nm in enumerate(d["names"])]
    rods = [ax.plot([], [], [], "-", color="0.4", lw=1.5, gid="link")[0] for _ in d["links"]]
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, 1.0), fontsize=8)

    def update(k):
        for i, dot in enumerate(dots):
            dot.set_data_3d([P[k, i, 0]], [P[k, i, 1]], [P[k, i, 2]])
        for (a, b), rod in zip(d["links"], rods):
            rod.set_data_3d(*P[k, [a, b]].T)
        return (*dots, *rods)
    return update


def _series_axes(fig, grid, drawn, t) -> list:
    """The Axes of the series under the motion (the rows of ``grid``), one a
    series: its curve over the samples' times ``t``, its label as legend."""
    axes = []
    for j, (label, v) in enumerate(drawn):
        a = fig.add_subplot(grid[j], sharex=axes[0] if axes else None)
        a.plot(t, v, color=f"C{j}", lw=1.3, label=label, gid="series")
        a.legend(loc="upper right", fontsize=8, frameon=False)
        a.tick_params(labelsize=8)
        a.ticklabel_format(axis="y", useOffset=True, style="sci", scilimits=(-3, 4))
        a.grid(alpha=0.3)
        if j < len(drawn) - 1:
            a.tick_params(labelbottom=False)
        axes.append(a)
    axes[-1].set_xlabel("t", fontsize=9)
    return axes


def _save(anim, path, fps):
    """Write ``anim`` to ``path``: .html (JavaScript), .mp4 (ffmpeg), else GIF (Pillow)."""
    from matplotlib import animation
    path = str(path)
    if path.endswith(".html"):
        with open(path, "w") as fh:
            fh.write(anim.to_jshtml())
    elif path.endswith(".mp4"):
        if not animation.writers.is_available("ffmpeg"):
            raise RuntimeError("saving an .mp4 needs ffmpeg on the PATH; save a .gif instead")
        anim.save(path, writer=animation.FFMpegWriter(fps=fps))
    else:
        anim.save(path, writer=animation.PillowWriter(fps=fps))


def animate(system, sol, *, kind=None, t=None, frames=None, fps=20, trail=None, ax=None,
            lengths=None, path=None, plots=None):
    r"""An animation of the motion itself, drawn from a solution.

    What is drawn depends on ``kind``: by default the drawing the system names
    (``system.drawing``: a scene's C row names it; a compiled system gets the
    first of the registry, ``mechpy._motion``, that fits it: a pendulum of
    two states with a parameter ``length`` or ``l``, a double pendulum of four
    with ``l1`` and ``l2``, a particle):

    ``"pendulum"``
        :class:`~mechpy.scenes.Pendulum` (or any two-state scene with a
        ``length`` or ``l`` parameter): rod and bob at
        :math:`(l\sin\theta, -l\cos\theta)`, y up, with a fading trail.
    ``"double_pendulum"``
        a four-state scene ``(theta1, theta2, theta1_dot, theta2_dot)``, angles
        from the downward vertical, e.g. compiled by :func:`mechpy.lagrangian`
        with parameters ``l1``, ``l2`` (or give ``lengths``): both rods and bobs,
        :math:`x_2 = l_1\sin\theta_1 + l_2\sin\theta_2`, and the lower bob's trail.
    ``"foucault"``
        :class:`~mechpy.scenes.Foucault`: the bob seen from above in the floor
        plane (x east, y north), tracing its rosette (the whole path by default).
    ``"top"``
        :class:`~mechpy.scenes.HeavyTop` (3-D): the symmetry axis
        :math:`e_3 = (\sin\theta\sin\phi, -\sin\theta\cos\phi, \cos\theta)` on the
        unit sphere, its tip's path, and the nutation bounds of
        :func:`mechpy.rigid.nutation_bounds` as two circles of latitude.
    ``"rigid"``
        :class:`~mechpy.scenes.RigidBody` (3-D): the three body axes in space,
        the columns of :math:`R(q)`, with their tips' trails and the fixed
        direction of the angular momentum (the tennis-racket flip shows as
        axis 2 turning over).  A state without orientation (``omega`` only) is
        integrated again with the orientation alongside,
        ``system.replace(orientation=True)`` from the identity quaternion at the
        solution's times (rtol 1e-11).
    ``"chain"``
        :class:`~mechpy.scenes.SpringChain`: the displacements :math:`x_i`
        against the mass index (markers), for linear springs the exact
        normal-mode superposition of :meth:`mechpy.modes.Modes.evolve` from the
        first sample (dashed), and the masses moving along the chain beneath.
    ``"particle"``
        a compiled system (:func:`mechpy.equations`, :func:`mechpy.lagrangian`)
        whose state is (q, v) with one or two coordinates: the point at
        (0, q), its height drawn up (a bouncing ball), or at (q1, q2), with
        a fading trail.
    ``"bodies"``
        an :func:`mechpy.mechanics` scene: its bodies' mass centres (and a
        ``System``'s joints) from the model's own compiled kinematics, with
        the links between them, in its inertial frame; the solids, the
        ground plane and ``points=`` are :func:`mechpy.live.animate`'s.

    A solution with jumps (events with an action, :mod:`mechpy.events`) is
    drawn as it is: its samples hold the states before and after each
    action at the same time, and a frame at that time shows the state after
    it.

    Parameters
    ----------
    system : Scene
        The scene that made ``sol``.
    sol : Solution or array_like, shape (n, m)
        A result of :func:`mechpy.solve` (``sol.t``, ``sol.y``), or states
        (n, m) as ``Solution.y`` holds them, with ``t``.  Sample at the times
        to be shown (``t_eval``): frames show samples, not interpolants.
    kind : str, optional
        One of ``"bodies"``, ``"pendulum"``, ``"double_pendulum"``, ``"foucault"``,
        ``"top"``, ``"rigid"``, ``"chain"``, ``"particle"``.
    t : array_like, shape (m,), optional
        The times of an array ``sol`` (s); monotonic (a time held twice: the
        states before and after an action).
    frames : int, optional
        Frames drawn: frame i shows sample ``anim.samples[i]``, the samples
        evenly spread over ``sol`` (default ``min(m, 200)``; at an action's
        time the sample after it).
    fps : float
        Frames per second when played or saved.
    trail : float, optional
        Length of the fading trail in time units of ``sol.t`` (s): ``0`` for
        none, ``np.inf`` for the whole path.  Default: the whole path for the
        Foucault pendulum and the top, a fifth (a quarter for a rigid body) of
        the time span otherwise.
    ax : matplotlib Axes, optional
        Where to draw (3-D Axes for ``"top"`` and ``"rigid"``); a new figure
        otherwise.
    lengths : array_like, shape (1,) or (2,), optional
        Rod lengths (m) of the pendulum kinds, when the scene's parameters do
        not name them.
    path : str or Path, optional
        Also write the animation there: ``.gif`` (Pillow), ``.mp4`` (needs
        ffmpeg) or ``.html`` (JavaScript).
    plots : list, optional
        Time series drawn in axes under the motion, one an entry, with a
        vertical cursor line at the frame's time: a state's name
        (``system.states``), ``"energy"`` (the system's own ``energy``) or a
        SymPy expression of the states (symbols named as the states; a
        coordinate of :func:`mechpy.coordinates` and its ``diff(t)``), ``t``
        and the parameters (by name, at the system's values); each evaluated
        at every sample (:mod:`mechpy._series`, as :func:`mechpy.live.animate`
        does at its frames).  Needs a new figure (not ``ax``).

    Returns
    -------
    matplotlib.animation.FuncAnimation
        Its attribute ``samples`` (frames,) holds the sample index each frame
        shows; with ``plots``, ``series_axes`` holds the series' Axes (the
        curve's label: the entry's, a state's name, ``"energy"`` or
        ``str(expr)``; the cursor: the line with gid ``"cursor"``).  In a
        notebook: ``IPython.display.HTML(anim.to_jshtml())``;
        ``anim.save("motion.gif", writer="pillow")`` writes a file.

    Raises
    ------
    TypeError
        ``system`` is not a scene, its kind cannot be told, ``kind`` names a
        scene of another type, or ``sol`` is neither a Solution nor an array.
    ValueError
        ``kind`` is unknown; ``sol`` is empty, not finite or does not hold the
        scene's states (n, m); ``t`` is missing, of another length or not
        monotonic; ``ax`` is not 3-D for a 3-D kind; bad ``frames``, ``fps``,
        ``trail`` or ``lengths``; ``plots`` with ``ax``, an unknown state
        name in ``plots``, an expression with a symbol that is neither a
        state nor a parameter, ``"energy"`` for a system without one, or a
        series that is not finite (each named).

    Examples
    --------
    >>> import numpy as np, mechpy as mp
    >>> p = mp.scenes.Pendulum()
    >>> sol = mp.solve(p, (0, 4), [2.0, 0.0], t_eval=np.linspace(0, 4, 81))
    >>> anim = mp.plot.animate(p, sol, frames=40)
    >>> anim.samples[:4].tolist()
    [0, 2, 4, 6]
    """
    plt = _plt()
    drawing = _motion.kind_of(system, kind)
    kind = drawing.name
    tt, y = _motion.samples(system, sol, t)
    m = tt.size
    frames = min(m, 200) if frames is None else as_int(frames, "frames", minimum=1)
    fps = as_scalar(fps, "fps", positive=True)
    span = abs(tt[-1] - tt[0])
    trail = (drawing.trail * span if trail is None
             else as_scalar(trail, "trail", nonnegative=True, finite=False))
    if np.isnan(trail):
        raise ValueError("trail must be a non-negative time or np.inf, got nan")
    three_d = drawing.three_d
    drawn = [] if plots is None else _series.series(system, plots, tt, y)
    if drawn and ax is not None:
        raise ValueError("plots= draws the series in a figure of its own: give ax=None")
    series_axes = []
    if ax is None:
        # small and at 80 dpi: every frame is a PNG in to_jshtml
        w, h = drawing.figsize
        fig = plt.figure(figsize=(w, h + 1.25 * len(drawn)), dpi=80)
        if drawn:
            # the motion above, the series below (their own spacing: a row's height)
            grid = fig.add_gridspec(2, 1, height_ratios=[h, 1.25 * len(drawn)], hspace=0.18,
                                    left=0.17, right=0.95, top=0.95,
                                    bottom=0.45 / (h + 1.25 * len(drawn)))
            ax = fig.add_subplot(grid[0], projection="3d" if three_d else None)
            series_axes = _series_axes(fig, grid[1].subgridspec(len(drawn), 1, hspace=0.3),
                                       drawn, tt)
        else:
            ax = fig.add_subplot(projection="3d" if three_d else None)
        if drawing.bottom is not None and not drawn:
            fig.subplots_adjust(bottom=drawing.bottom)   # a legend under the axes
    else:
        if three_d != (getattr(ax, "name", "") == "3d"):
            raise ValueError(f"ax must be {'a 3-D' if three_d else 'a 2-D'} Axes for "
                             f"kind={kind!r}")
        fig = ax.figure
    # a frame at an action's time (a time held twice) shows the state after it
    samples = np.unique(_motion.after_jumps(tt, np.linspace(0, m - 1, frames).round()
                                            .astype(np.intp)))
    update = drawing.painter("plot")(ax, system, tt, y, trail, lengths)
    clock = (ax.text2D if three_d else ax.text)(0.98, 0.98, "", transform=ax.transAxes,
                                                ha="right", va="top", gid="time")

    cursors = [a.axvline(tt[0], color="tab:red", lw=1.2, gid="cursor") for a in series_axes]

    def frame(i):
        k = samples[i]
        clock.set_text(f"t = {tt[k]:.2f} s")
        for c in cursors:
            c.set_xdata([tt[k], tt[k]])
        return (*update(k), clock, *cursors)

    frame(0)
    if fig.get_layout_engine() is None and not series_axes:
        fig.tight_layout()
        # tight_layout leaves a placeholder engine behind, which makes every savefig
        # (every frame of to_jshtml) draw the figure twice
        fig.set_layout_engine(None)
    anim = _func_animation(fig, frame, frames=samples.size, interval=1000.0 / fps, blit=False)
    anim.samples = samples
    anim.series_axes = series_axes
    if path is not None:
        _save(anim, path, fps)
    return anim
