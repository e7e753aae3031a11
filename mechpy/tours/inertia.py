"""Tour section: a composite body and its principal axes; closed forms; a mesh."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from . import line
from .._timing import median_time
from .. import inertia as mi
from .. import stress

TITLE = "Inertia tensors, principal axes, stress"
ORDER = 40


def run(out: Path) -> None:
    # the cube about a corner (section 4): M b^2 [[2/3, -1/4, -1/4], ...]
    M, b = 1.0, 1.0
    I = mi.solid("cube", M, side=b).inertia_about([b / 2] * 3)
    ref = M * b * b * (np.full((3, 3), -0.25) + np.eye(3) * (2 / 3 + 0.25))
    w, _ = mi.principal_axes(I)
    line("cube about a corner, I_xx, I_xy", f"{I[0, 0]:.15f}, {I[0, 1]:.15f}",
         ref="2/3, -1/4", err=float(np.max(np.abs(I - ref))), ref_name="closed form")
    line("  principal moments", np.array2string(w, precision=12),
         ref="1/6, 11/12, 11/12", err=float(np.max(np.abs(w - [1 / 6, 11 / 12, 11 / 12]))))

    # a composite body: a cone standing on a cylinder, tilted and moved
    R, h = 0.3, 1.0
    body = (mi.solid("cylinder", 2.0, radius=R, height=h)
            + mi.solid("cone", 0.5, radius=R, height=0.6).moved([0, 0, h / 2 + 0.15]))
    c, s = math.cos(0.4), math.sin(0.4)
    tilt = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    body = body.rotated(tilt).moved([1.0, 2.0, 0.5])
    w, axes = body.principal()
    wr, vr = np.linalg.eigh(body.inertia)
    line("rocket (cylinder + cone), com", np.array2string(body.com, precision=6))
    line("  principal moments", np.array2string(w, precision=6),
         ref="numpy eigh", err=float(np.max(np.abs(w - wr))))
    line("  symmetry axis (smallest moment)", np.array2string(axes[:, 0], precision=6),
         ref="tilted z", err=float(1 - abs(axes[:, 0] @ tilt[:, 2])))
    line("  type of top", body.classify())

    # a 2e5-triangle sphere mesh against the ball and against NumPy
    v, f = mi.uv_sphere(1.0, 200, 400)
    m = mi.mesh(v, f, mass=1.0)
    t_mp = median_time(lambda: mi.mesh(v, f, mass=1.0))
    from ..benches.inertia import numpy_mesh
    t_np = median_time(lambda: numpy_mesh(v, f))
    line(f"sphere mesh ({len(f)} triangles), I_xx", f"{m.inertia[0, 0]:.9f}", ref="2/5",
         err=abs(m.inertia[0, 0] - 0.4), t_mp=t_mp, t_ref=t_np, ref_name="NumPy")

    # principal stresses of a pure shear
    tau = 80e6
    sw, _ = stress.principal([[0, tau, 0], [tau, 0, 0], [0, 0, 0]])
    vm = stress.von_mises([[0, tau, 0], [tau, 0, 0], [0, 0, 0]])
    line("pure shear 80 MPa: principal stresses", np.array2string(sw / 1e6, precision=6) + " MPa",
         ref="-80, 0, 80")
    line("  von Mises", f"{vm / 1e6:.9f} MPa", ref="sqrt(3) * 80",
         err=abs(vm - math.sqrt(3) * tau) / tau)
