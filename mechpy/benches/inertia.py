"""Bench: mesh mass properties (mechpy's validated C pass vs trimesh and a
NumPy tetrahedron sum), batched point masses vs a NumPy einsum, batched
principal axes vs numpy.linalg.eigh."""
from __future__ import annotations

import math

import numpy as np

from .._timing import median_time
from .. import inertia as mi

TITLE = "Inertia: meshes, point masses, principal axes"
ORDER = 40


def numpy_mesh(vertices, faces):
    """Volume, centre of mass and inertia about it of a closed mesh (unit
    density) by the signed tetrahedra (origin, face) in vectorised NumPy:
    the usual way to do it without a library (no mesh checks)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    d = np.einsum("ij,ij->i", a, np.cross(b, c))          # 6 x signed tet volume
    vol = d.sum() / 6
    com = np.einsum("i,ij->j", d, a + b + c) / (24 * vol)
    s = a + b + c
    # second moments of each tet: d/120 (sum_p p p^T + s s^T)
    S = (np.einsum("i,ij,ik->jk", d, a, a) + np.einsum("i,ij,ik->jk", d, b, b)
         + np.einsum("i,ij,ik->jk", d, c, c) + np.einsum("i,ij,ik->jk", d, s, s)) / 120
    S -= vol * np.outer(com, com)
    return vol, com, np.trace(S) * np.eye(3) - S


def _trimesh():
    try:
        import trimesh  # noqa: F401
        from trimesh.triangles import mass_properties
        return mass_properties
    except Exception:   # trimesh is an optional benchmark extra
        return None


def _rel(I, ref):
    return float(np.max(np.abs(I - ref)) / np.max(np.abs(ref)))


def mesh_rows(n_lat: int, budget: float = 3.0) -> list[dict]:
    v, f = mi.uv_sphere(1.0, n_lat, 2 * n_lat)
    nf = len(f)
    ref = 0.4 * np.eye(3) * (4 / 3 * math.pi)      # the unit ball, unit density
    prob = f"mesh mass properties, sphere, {nf:.2g} triangles"
    rows = []
    body = mi.mesh(v, f)
    t = median_time(lambda: mi.mesh(v, f), budget=budget)
    rows.append(dict(problem=prob, impl="mechpy inertia.mesh (C, validated)", time=t,
                     error=_rel(body.inertia, ref), n=nf,
                     note="includes the closed/manifold/orientation checks"))
    _, _, In = numpy_mesh(v, f)
    t = median_time(lambda: numpy_mesh(v, f), budget=budget)
    rows.append(dict(problem=prob, impl="numpy signed tetrahedra (no checks)", time=t,
                     error=_rel(In, ref), n=nf))
    mp_tri = _trimesh()
    if mp_tri is None:
        rows.append(dict(problem=prob, impl="trimesh mass_properties", time=float("nan"),
                         error=float("nan"), n=nf, note="skipped: trimesh not installed"))
    else:
        props = mp_tri(v[f])
        t = median_time(lambda: mp_tri(v[f]), budget=budget)
        rows.append(dict(problem=prob, impl="trimesh triangles.mass_properties (no checks)",
                         time=t, error=_rel(np.asarray(props["inertia"]), ref), n=nf))
    return rows


def point_mass_rows(nbody: int, n: int) -> list[dict]:
    rng = np.random.default_rng(0)
    m = rng.uniform(0.5, 1.5, (nbody, n))
    x = rng.normal(size=(nbody, n, 3))

    def einsum():
        r2 = np.einsum("bni,bni->bn", x, x)
        return (np.einsum("bn,bn->b", m, r2)[:, None, None] * np.eye(3)
                - np.einsum("bn,bni,bnj->bij", m, x, x))

    ref = einsum()
    got = mi.point_masses(m, x)
    prob = f"point_masses, {nbody} bodies x {n} masses"
    err = _rel(got, ref)
    return [dict(problem=prob, impl="mechpy inertia.point_masses (C)", n=nbody * n,
                 time=median_time(lambda: mi.point_masses(m, x)), error=err),
            dict(problem=prob, impl="numpy einsum", n=nbody * n, time=median_time(einsum),
                 error=0.0)]


def principal_rows(nbody: int) -> list[dict]:
    rng = np.random.default_rng(1)
    A = rng.normal(size=(nbody, 3, 3))
    I = A @ np.swapaxes(A, 1, 2)
    w, _ = mi.principal_axes(I)
    wr = np.linalg.eigvalsh(I)
    prob = f"principal axes of {nbody} tensors"
    return [dict(problem=prob, impl="mechpy inertia.principal_axes (C Jacobi)", n=nbody,
                 time=median_time(lambda: mi.principal_axes(I)), error=_rel(w, wr)),
            dict(problem=prob, impl="numpy.linalg.eigh (batched LAPACK)", n=nbody,
                 time=median_time(lambda: np.linalg.eigh(I)), error=0.0)]


def run(quick: bool) -> list[dict]:
    rows = mesh_rows(100 if quick else 500, budget=1.0 if quick else 4.0)
    rows += point_mass_rows(1000 if quick else 10000, 100)
    rows += principal_rows(10000 if quick else 100000)
    return rows
