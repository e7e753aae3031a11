"""mechpy: classical mechanics with a fast C core.

``import mechpy as mp``: ``mp.solve``, ``mp.solve_many``, ``mp.methods``,
``mp.scenes``, ``mp.inertia``, ``mp.stress``, ``mp.rotation``, ``mp.rigid``,
``mp.modes``, ``mp.phase``, ``mp.frames``, ``mp.variational``, ``mp.plot``; a user's own
system compiled to C: ``mp.coordinates``, ``mp.lagrangian``, ``mp.equations``.
"""
from . import _core
from .errors import *  # noqa: F401,F403
from . import integrate, plot, scenes  # noqa: F401
from . import inertia, modes, rotation, stress, variational  # noqa: F401
from . import frames, phase, rigid  # noqa: F401
from .integrate import (DenseOutput, EnsembleSolution, SecondOrder, Solution,  # noqa: F401
                        methods, solve, solve_many)
from .symbolic import coordinates, equations, lagrangian  # noqa: F401  (SymPy loads on call)
from .symbolic.build import CompileError  # noqa: F401

__version__ = "0.1.0"
