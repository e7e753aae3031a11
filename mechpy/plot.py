"""Plots (matplotlib, an optional dependency: ``pip install mechpy[plot]``)."""
from __future__ import annotations

import numpy as np

from ._validate import as_array, as_int

__all__ = ["phase_portrait"]


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
