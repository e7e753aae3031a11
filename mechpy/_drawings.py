"""The registry of drawings: what :func:`mechpy.plot.animate` (matplotlib) and
:func:`mechpy.live.animate` (three.js) draw for a system, one entry a kind.

An entry names its two painters (``"module:function"``, imported when first
drawn), the scenes it is made for (their C rows), what it needs of any other
system, its default trail and the options it takes.  A scene names its
drawing in its C row (``drawing``, read as :attr:`mechpy.scenes.Scene.drawing`);
a compiled system names none of its own and gets the first generic entry that
fits its description (:func:`fitting`).  The geometry both painters draw is
:mod:`mechpy._motion`'s.

The painters' contracts:

- ``plot(ax, system, t, y, trail, lengths) -> update``: draws the still parts
  on the matplotlib Axes ``ax`` (3-D when the entry is ``three_d``) and
  returns ``update(k)``, which shows sample k and returns the artists it
  changed;
- ``live(system, times, Y, **options) -> dict``: the frames' geometry for the
  page (``mechpy/live/static/animate.js``): ``P`` (frames, bodies, 3) the
  places of the bodies, ``R`` (frames, 3, 3) the rotation of a solid,
  ``bodies``, ``rods``, ``lines``, ``trail`` (the bodies with a trail),
  ``legend``, ``solid``, ``up``, ``center``, ``extent``, ``camera``,
  ``title`` (see mechpy/live/motion.py).

A new drawing is one entry in :data:`DRAWINGS` and its two painters.
"""
from __future__ import annotations

import importlib
from typing import Callable, NamedTuple

import numpy as np


class Drawing(NamedTuple):
    """One kind of drawing (see the module docstring)."""

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
    #: the keyword options of mp.live.animate it takes
    options: tuple = ()

    def painter(self, which: str):
        """The painter ``which`` ("plot" or "live"), imported."""
        module, _, name = getattr(self, which).partition(":")
        return getattr(importlib.import_module(module), name)


def _lengths_named(system, keys) -> bool:
    return set(keys) <= set(getattr(system, "params", {}) or {})


def _fits_pendulum(system) -> bool:
    return _lengths_named(system, ("length",)) or _lengths_named(system, ("l",))


def _fits_particle(system) -> bool:
    from ._motion import particle_coordinates
    return bool(particle_coordinates(system))


_ANGLES = "angles from the downward vertical and their rates"

#: The drawings, in the order a compiled system's is chosen among them.
DRAWINGS = {d.name: d for d in (
    Drawing("pendulum", "mechpy.plot:_planar_pendulum", "mechpy.live.motion:_pendulum",
            states=2, fits=_fits_pendulum, what=_ANGLES, options=("lengths",)),
    Drawing("double_pendulum", "mechpy.plot:_planar_pendulum", "mechpy.live.motion:_pendulum",
            states=4, fits=lambda s: _lengths_named(s, ("l1", "l2")), what=_ANGLES,
            options=("lengths",)),
    Drawing("foucault", "mechpy.plot:_foucault", "mechpy.live.motion:_foucault",
            rows=("Foucault",), trail=np.inf),
    Drawing("top", "mechpy.plot:_top", "mechpy.live.motion:_top", rows=("HeavyTop",),
            trail=np.inf, three_d=True),
    Drawing("rigid", "mechpy.plot:_rigid", "mechpy.live.motion:_rigid",
            rows=("RigidBody", "RigidBodyOriented"), trail=0.25, three_d=True),
    Drawing("chain", "mechpy.plot:_chain", "mechpy.live.motion:_chain", rows=("SpringChain",),
            trail=0.0, figsize=(7, 4), options=("spacing",)),
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
    from .scenes import Scene
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
