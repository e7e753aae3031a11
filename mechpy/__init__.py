"""mechpy: classical mechanics with a fast C core.

``import mechpy as mp``: ``mp.solve``, ``mp.solve_many``, ``mp.methods``,
``mp.scenes``, ``mp.inertia``, ``mp.stress``, ``mp.rotation``, ``mp.rigid``,
``mp.modes``, ``mp.phase``, ``mp.frames``, ``mp.particles``, ``mp.variational``,
``mp.plot``; a user's own system compiled to C: ``mp.coordinates``, ``mp.lagrangian``,
``mp.equations``; the tangent flow: ``mp.sensitivity``, ``mp.fit`` (:mod:`mechpy.tangent`).

Array layout
------------
Every public function follows one rule with two clauses (``tests/test_layout.py``
walks them all and checks it):

1. **States follow SciPy.**  An array of a system's states puts the state axis first
   and the batch or time axes after it, as ``Solution.y`` (n, m) does
   (``EnsembleSolution.y`` (k, n, m), ``StationaryPath.q`` (d, m)).  A function of
   states takes ``y`` of shape (n, ...) and returns its components first too: (n, ...)
   for ``rhs``, (n, n, ...) for ``jacobian``, (p, ...) for p quantities per state
   (``momenta``, ``constraint_forces``, ``multipliers``, ``normal_force``), (...) for
   one number per state (``energy``).  A time ``t`` is a scalar applied to every state;
   where times per state are taken they broadcast against the axes (...)
   (``RotatingHoop.normal_force``), and ``Solution.sol(t)`` is (n, ...) for t of shape (...).
2. **Everything else is a NumPy stack**: batch axes first, then the component axes
   last: a vector (..., 3), a matrix (..., 3, 3), a quaternion (..., 4) (rotation,
   inertia, stress, frames).  A series a function samples at times ``t`` is
   (len(t), n) (``rigid.free_rotation``, ``Modes.evolve``, ``frames.to_rotating``), a
   set of points is (n_points, dim) (``phase.poincare``).

A scalar input gives the output without its batch axes; results are NumPy
arrays of float64.
"""
try:
    from . import _core
except ImportError as _exc:  # no built C core next to these sources
    import os as _os
    _here = _os.path.dirname(_os.path.abspath(__file__))
    if _os.path.exists(_os.path.join(_here, _os.pardir, "meson.build")):
        raise ImportError(
            "you are importing mechpy from its source tree, where its C core "
            "(mechpy._core) is not built. Build and install it (from the source "
            "tree: 'bash scripts/dev.sh test', or 'pip install .' with GSL and LAPACK "
            "where pkg-config finds them), then run Python from outside the source "
            "tree or in the environment that holds the editable install."
        ) from None
    raise ImportError(f"mechpy's C core mechpy._core could not be loaded: {_exc}") from _exc
from .errors import *  # noqa: F401,F403
from .errors import __all__ as _errors_all
from . import integrate, plot, scenes  # noqa: F401
from . import inertia, modes, rotation, stress, variational  # noqa: F401
from . import events, frames, live, particles, phase, rigid  # noqa: F401
from .integrate import (DenseOutput, EnsembleSolution, SecondOrder, Solution,  # noqa: F401
                        methods, solve, solve_many)
from .symbolic import coordinates, equations, lagrangian, mechanics  # noqa: F401  (SymPy loads on call)
from .symbolic.build import CompileError  # noqa: F401
from . import tangent  # noqa: F401
from .tangent import FitResult, fit, sensitivity  # noqa: F401

__version__ = "0.1.0"

__all__ = ["integrate", "scenes", "inertia", "stress", "rotation", "rigid", "modes", "phase",
           "frames", "particles", "variational", "plot", "live", "errors", "symbolic",
           "solve", "solve_many", "methods", "Solution", "EnsembleSolution", "DenseOutput",
           "SecondOrder", "coordinates", "lagrangian", "equations", "mechanics", "CompileError",
           "tangent", "sensitivity", "fit", "FitResult", "events",
           *_errors_all]
