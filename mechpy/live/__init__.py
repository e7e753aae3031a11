"""Live views in the browser: phase portraits on the GPU and motion in 3D.

``mechpy.plot`` draws with matplotlib; ``mechpy.live`` runs in the browser, with
no kernel round trip for what the page can do itself.  Both take the same
systems.

* :func:`phase_portrait`: particles advected through a system's own field by
  the GPU (WebGL2, RK4 in float32, states in float textures), as fieldplay
  does; sliders change the field's parameters in the page at once; overlays of
  fixed points, nullclines and the limit cycle from :mod:`mechpy.phase`; a
  click drops a trajectory.
* :func:`animate`: the motion of a solution in 3D (three.js): pendulums, the
  Foucault bob, a top, a rigid body, a chain; orbit camera, play/pause, a time
  slider, trails.

Each returns an ``anywidget.AnyWidget`` (JupyterLab, Notebook 7, VS Code) whose
``save(path)`` writes one self-contained HTML file that runs offline.  Every
page exposes ``window.mechpyLive`` (``pause``, ``play``, ``step``,
``particles``, ``seeds``, ``setParam``, ``field``, ``frame``, ``positions``, ``overlays``,
``fps``) for tests and automation.

Needs anywidget (the ``live`` extra: ``pip install "mechpy-classical[live]"``).
"""
from __future__ import annotations

__all__ = ["phase_portrait", "animate", "PhasePortrait", "Motion"]

_LAZY = {"phase_portrait": "phase", "PhasePortrait": "phase", "animate": "motion",
         "Motion": "motion"}


def __getattr__(name):
    # anywidget (and IPython) load only when a live view is made
    if name in _LAZY:
        import importlib
        mod = importlib.import_module(f".{_LAZY[name]}", __name__)
        return getattr(mod, name)
    raise AttributeError(f"module 'mechpy.live' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_LAZY))
