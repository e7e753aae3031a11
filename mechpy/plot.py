"""Plots (matplotlib, an optional dependency: ``pip install mechpy[plot]``).

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
a path in space as ``Solution.y`` gives it, (3, m).
"""
from __future__ import annotations

import numpy as np

from ._validate import as_array, as_int

__all__ = ["phase_portrait", "work_precision", "modes", "trajectory3d", "animate_field"]


def _plt():
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise ImportError("mechpy.plot needs matplotlib: pip install matplotlib") from exc
    return plt


def _field(system, X, Y, t=0.0):
    """(U, V) of a 2-D system on the grid (X, Y)."""
    from .scenes import Scene
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
                   labels=("x", "x_dot")):
    """Streamlines of a 2-D system's vector field, nullclines and trajectories.

    Parameters
    ----------
    system : Scene or callable f(t, y)
        A two-dimensional system.
    xlim, ylim : (float, float)
        The window in the state plane.
    trajectories : sequence of initial states (2,)
        Each is integrated with :func:`mechpy.solve` over ``[0, t_max]`` and drawn.
    grid : int
        Grid points per axis for the streamlines.

    Returns
    -------
    matplotlib.axes.Axes
    """
    plt = _plt()
    grid = as_int(grid, "grid", minimum=3)
    xlim = as_array(xlim, "xlim", shape=(2,))
    ylim = as_array(ylim, "ylim", shape=(2,))
    if ax is None:
        _, ax = plt.subplots(figsize=(6, 4.5))
    x = np.linspace(*xlim, grid)
    y = np.linspace(*ylim, grid)
    X, Y = np.meshgrid(x, y)
    U, V = _field(system, X, Y, t)
    speed = np.hypot(U, V)
    ax.streamplot(X, Y, U, V, color=np.log1p(speed), cmap="viridis", density=1.2,
                  linewidth=0.7, arrowsize=0.8)
    if nullclines:
        ax.contour(X, Y, U, levels=[0.0], colors="tab:red", linewidths=0.8, linestyles="--")
        ax.contour(X, Y, V, levels=[0.0], colors="tab:orange", linewidths=0.8, linestyles="--")
    from .integrate import solve
    for y0 in trajectories:
        s = solve(system, (0.0, t_max), as_array(y0, "trajectory start", shape=(2,)),
                  t_eval=np.linspace(0.0, t_max, 2000), rtol=1e-9)
        ax.plot(s.y[0], s.y[1], color="k", lw=1.2)
        ax.plot(*s.y[:, 0], "o", color="k", ms=3)
    ax.set_xlim(*xlim)
    ax.set_ylim(*ylim)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    return ax


def work_precision(rows, problem=None, *, ax=None):
    """Work-precision diagram: error against wall time, log-log, one line per
    implementation (the rows of ``python -m mechpy bench``: dicts with
    ``problem``, ``impl``, ``time`` (s) and ``error``).

    Rows without a positive finite error are left out; ``problem`` picks one
    problem when the rows hold several (default: the first).  Returns the Axes.
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
    ax.set_xlabel("median wall time [s]")
    ax.set_ylabel("error at final time")
    ax.set_title(problem)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.01, 0.5))
    return ax


def modes(m, which=None, *, positions=None, ax=None):
    """Mode shapes of a :class:`mechpy.modes.Modes`: the displacement of each
    coordinate in the chosen modes (default: up to the six lowest), each
    labelled with its angular frequency (rad/s).  ``positions`` places the
    coordinates along the horizontal axis (default 1..n).  Returns the Axes."""
    plt = _plt()
    V = np.asarray(m.vectors)
    n = V.shape[0]
    idx = range(min(6, V.shape[1])) if which is None else \
        [as_int(k, "which", minimum=0, maximum=V.shape[1] - 1) for k in np.atleast_1d(which)]
    x = np.arange(1, n + 1) if positions is None else as_array(positions, "positions", shape=(n,))
    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 4))
    for k in idx:
        ax.plot(x, V[:, k], "o-", ms=3, label=f"mode {k + 1}: omega = {m.omega[k]:.4g} rad/s")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel("coordinate")
    ax.set_ylabel("mode shape (M-normalised)")
    ax.legend(fontsize=7)
    return ax


def trajectory3d(path, *, ax=None, **line_kw):
    """A curve in space: ``path`` of shape (3, m) (e.g. ``sol.y[:3]``), or a
    :class:`mechpy.Solution` whose first three components are drawn.  Marks the
    start.  Returns the 3-D Axes."""
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
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    return ax


def animate_field(system, xlim=(-2 * np.pi, 2 * np.pi), ylim=(-4.0, 4.0), *, particles=800,
                  frames=120, dt=0.03, trail=8, respawn=0.01, t=0.0, seed=0, path=None,
                  interval=40, param=None, values=None):
    r"""Particles advected through a 2-D field and fading, as fieldplay does.

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
        ipywidgets (``pip install mechpy[plot]``).
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
    """
    if param is None:
        if values is not None:
            raise ValueError("values is given without param: name the scene parameter "
                             "the slider should vary")
        return _animate_field(system, xlim, ylim, particles=particles, frames=frames, dt=dt,
                              trail=trail, respawn=respawn, t=t, seed=seed, path=path,
                              interval=interval)
    from .scenes import Scene
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
                          "pip install ipywidgets (or mechpy[plot])") from exc
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
    from matplotlib import animation
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

    anim = animation.FuncAnimation(fig, step, frames=frames, interval=interval, blit=True)
    if path is not None:
        path = str(path)
        if path.endswith(".html"):
            with open(path, "w") as fh:
                fh.write(anim.to_jshtml())
        else:
            anim.save(path, writer=animation.PillowWriter(fps=max(1, 1000 // interval)))
    return anim
