"""mechpy: classical mechanics with a fast C core.

``import mechpy as mp``: ``mp.solve``, ``mp.solve_many``, ``mp.methods``,
``mp.scenes``, ``mp.inertia``, ``mp.stress``, ``mp.rotation``, ``mp.rigid``,
``mp.modes``, ``mp.phase``, ``mp.frames``, ``mp.variational``, ``mp.plot``; a user's own
system compiled to C: ``mp.coordinates``, ``mp.lagrangian``, ``mp.equations``.
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
from . import integrate, plot, scenes  # noqa: F401
from . import inertia, modes, rotation, stress, variational  # noqa: F401
from . import frames, phase, rigid  # noqa: F401
from .integrate import (DenseOutput, EnsembleSolution, SecondOrder, Solution,  # noqa: F401
                        methods, solve, solve_many)
from .symbolic import coordinates, equations, lagrangian  # noqa: F401  (SymPy loads on call)
from .symbolic.build import CompileError  # noqa: F401

__version__ = "0.1.0"
