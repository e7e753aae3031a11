"""mechpy.inertia against closed forms, NumPy/SciPy references and exact arithmetic."""
import warnings

import numpy as np
import pytest
import scipy.linalg

import mechpy as mp
from mechpy import inertia as mi
from ref_inertia import (box_mesh, cone_mesh, point_masses_ref, polygon_cone_closed_form,
                         random_rotation, shift_exact)

CUBE_CORNER = np.array([[2 / 3, -1 / 4, -1 / 4], [-1 / 4, 2 / 3, -1 / 4], [-1 / 4, -1 / 4, 2 / 3]])


# ----------------------------------------------------------------------- point masses

def test_point_masses_match_einsum_batched(rng):
    m = rng.uniform(0.1, 2.0, size=(4, 5, 7))
    x = rng.normal(size=(4, 5, 7, 3))
    o = rng.normal(size=(5, 3))                     # broadcasts over the first axis
    got = mi.point_masses(m, x, o)
    ref = point_masses_ref(m, x, np.broadcast_to(o, (4, 5, 3)))
    assert got.shape == (4, 5, 3, 3)
    np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-13)


def test_section4_mass_along_x_axis():
    I = mi.point_masses([1.0, 2.0, 0.5], [[1, 0, 0], [-3, 0, 0], [2.5, 0, 0]])
    expected_yy = 1 * 1 + 2 * 9 + 0.5 * 6.25
    assert I[1, 1] == I[2, 2] == expected_yy > 0
    mask = np.ones((3, 3), bool)
    mask[1, 1] = mask[2, 2] = False
    assert np.all(I[mask] == 0)
    assert mi.classify(mi.point_masses([1.0, 2.0], [[1, 0, 0], [-0.5, 0, 0]])) == "rotor"


def test_cube_about_corner_closed_form():
    M, b = 2.5, 1.7
    I = mi.solid("cube", M, side=b).inertia_about([b / 2, b / 2, b / 2])
    np.testing.assert_allclose(I, M * b * b * CUBE_CORNER, rtol=1e-15, atol=1e-15)
    w, R = mi.principal_axes(I)
    np.testing.assert_allclose(w, M * b * b * np.array([1 / 6, 11 / 12, 11 / 12]), rtol=1e-14)
    # the small moment is about the body diagonal
    np.testing.assert_allclose(np.abs(R[:, 0]), np.full(3, 3 ** -0.5), rtol=1e-14)
    # same tensor from the mesh of the cube placed with a corner at the origin
    v, f = box_mesh(b, b, b, center=(b / 2, b / 2, b / 2))
    body = mi.mesh(v, f, mass=M)
    np.testing.assert_allclose(body.inertia_about([0, 0, 0]), M * b * b * CUBE_CORNER,
                               rtol=1e-13, atol=1e-14)


def test_cone_about_apex_and_com():
    M, R, h = 3.0, 0.8, 2.2
    cone = mi.solid("cone", M, radius=R, height=h)
    apex = mi.shift(cone.inertia, M, [0, 0, 0.75 * h])
    np.testing.assert_allclose(np.diag(apex), [0.6 * M * (R * R / 4 + h * h)] * 2
                               + [0.3 * M * R * R], rtol=1e-14)
    np.testing.assert_allclose(np.diag(cone.inertia),
                               [3 / 20 * M * R * R + 3 / 80 * M * h * h] * 2 + [0.3 * M * R * R],
                               rtol=1e-14)
    np.testing.assert_allclose(mi.shift(apex, M, [0, 0, 0.75 * h], to="com"), cone.inertia,
                               rtol=1e-14, atol=1e-15)


# Textbook closed forms (Marion & Thornton, Goldstein tables), written out here.
SOLIDS = [
    ("sphere", dict(radius=2.0), [0.4 * 4] * 3),
    ("shell", dict(radius=2.0), [2 / 3 * 4] * 3),
    ("box", dict(a=1.0, b=2.0, c=3.0), [(4 + 9) / 12, (1 + 9) / 12, (1 + 4) / 12]),
    ("cube", dict(side=3.0), [9 / 6] * 3),
    ("cylinder", dict(radius=1.0, height=2.0), [(3 + 4) / 12, (3 + 4) / 12, 0.5]),
    ("tube", dict(radius=2.0, inner_radius=1.0, height=3.0),
     [(15 + 9) / 12, (15 + 9) / 12, 2.5]),
    ("cone", dict(radius=1.0, height=4.0), [3 / 20 + 3 / 80 * 16] * 2 + [0.3]),
    ("hemisphere", dict(radius=2.0), [83 / 320 * 4] * 2 + [0.4 * 4]),
    ("rod", dict(length=3.0), [9 / 12, 9 / 12, 0.0]),
    ("disk", dict(radius=2.0), [1.0, 1.0, 2.0]),
    ("ring", dict(radius=2.0), [2.0, 2.0, 4.0]),
    ("ellipsoid", dict(a=1.0, b=2.0, c=3.0), [(4 + 9) / 5, (1 + 9) / 5, (1 + 4) / 5]),
]


# their volumes at the dimensions above (None: the thin ones)
VOLUMES = {"sphere": 4 / 3 * np.pi * 8, "shell": None, "box": 6.0, "cube": 27.0,
           "cylinder": 2 * np.pi, "tube": np.pi * (4 - 1) * 3, "cone": np.pi * 4 / 3,
           "hemisphere": 2 / 3 * np.pi * 8, "rod": None, "disk": None, "ring": None,
           "ellipsoid": 4 / 3 * np.pi * 6}


@pytest.mark.parametrize("shape,dims,diag", SOLIDS, ids=[s[0] for s in SOLIDS])
def test_every_solid_closed_form(shape, dims, diag):
    M = 1.0 * 1.5
    body = mi.solid(shape, M, **dims)
    np.testing.assert_allclose(body.inertia, M * np.diag(diag), rtol=1e-14, atol=1e-15)
    assert np.all(body.com == 0)
    assert body.mass == M
    if VOLUMES[shape] is None:
        assert body.volume is None
    else:
        assert body.volume == pytest.approx(VOLUMES[shape], rel=1e-15)   # measured: 0 or 1 ulp


def _uv_grid_fraction(inside, lo, hi, n, sub=4):
    """Volume fraction of each voxel (sub^3 sub-samples) of an indicator on [lo, hi]^3."""
    h = (hi - lo) / n
    c = lo + h * (np.arange(n) + 0.5)
    s = (np.arange(sub) + 0.5) / sub - 0.5
    frac = np.zeros((n, n, n))
    for dx in s:
        for dy in s:
            for dz in s:
                X, Y, Z = np.meshgrid(c + dx * h, c + dy * h, c + dz * h, indexing="ij")
                frac += inside(X, Y, Z)
    return frac / sub ** 3, h, np.full(3, lo + h / 2)


@pytest.mark.parametrize("shape,dims,inside", [
    ("hemisphere", dict(radius=1.0),
     lambda x, y, z: (x * x + y * y + (z + 3 / 8) ** 2 <= 1) & (z >= -3 / 8)),
    ("ellipsoid", dict(a=0.5, b=0.8, c=1.0),
     lambda x, y, z: (x / 0.5) ** 2 + (y / 0.8) ** 2 + z ** 2 <= 1),
    ("cylinder", dict(radius=0.7, height=1.8),
     lambda x, y, z: (x * x + y * y <= 0.49) & (np.abs(z) <= 0.9)),
    ("tube", dict(radius=0.9, inner_radius=0.5, height=1.2),
     lambda x, y, z: (x * x + y * y <= 0.81) & (x * x + y * y >= 0.25) & (np.abs(z) <= 0.6)),
])
def test_solids_placed_as_documented_against_grid(shape, dims, inside):
    """The com is at the origin and the tensor matches a sampled density."""
    frac, h, origin = _uv_grid_fraction(inside, -1.05, 1.05, 56)
    M = 2.0
    grid = mi.density_grid(frac, h, origin)
    grid = mi.Body(M, grid.com, grid.inertia * (M / grid.mass))
    ref = mi.solid(shape, M, **dims)
    scale = np.max(np.abs(ref.inertia))
    assert np.max(np.abs(grid.com)) < 2e-3
    assert np.max(np.abs(grid.inertia - ref.inertia)) < 5e-3 * scale


def test_thin_solids_against_point_masses():
    n = 4000
    t = (np.arange(n) + 0.5) / n
    M = 1.3
    rod = mi.point_masses(np.full(n, M / n), np.stack([0 * t, 0 * t, 2.0 * (t - 0.5)], -1))
    np.testing.assert_allclose(rod, mi.solid("rod", M, length=2.0).inertia, rtol=1e-6,
                               atol=1e-12)
    ph = 2 * np.pi * t
    ring = mi.point_masses(np.full(n, M / n), np.stack([np.cos(ph), np.sin(ph), 0 * t], -1))
    np.testing.assert_allclose(ring, mi.solid("ring", M, radius=1.0).inertia, rtol=1e-12,
                               atol=1e-12)
    # disk: rings of radius r weighted by r dr (midpoint rule in r)
    r = (np.arange(400) + 0.5) / 400
    rr, pp = np.meshgrid(r, 2 * np.pi * (np.arange(64) + 0.5) / 64, indexing="ij")
    w = (rr / rr.sum()).ravel() * M
    pts = np.stack([(rr * np.cos(pp)).ravel(), (rr * np.sin(pp)).ravel(), 0 * w], -1)
    np.testing.assert_allclose(mi.point_masses(w, pts), mi.solid("disk", M, radius=1.0).inertia,
                               rtol=1e-5, atol=1e-12)
    # thin shell: Fibonacci points on the unit sphere
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (1 + 5 ** 0.5) * k
    s = np.sqrt(1 - z * z)
    shell = mi.point_masses(np.full(n, M / n), np.stack([s * np.cos(phi), s * np.sin(phi), z], -1))
    np.testing.assert_allclose(shell, mi.solid("shell", M, radius=1.0).inertia, rtol=1e-3,
                               atol=1e-3)


# ----------------------------------------------------------------------- meshes

def test_box_mesh_is_exact():
    v, f = box_mesh(1.0, 2.0, 3.0, center=(10.0, -5.0, 2.0))
    body = mi.mesh(v, f, density=2.0)
    assert body.mass == pytest.approx(12.0, rel=1e-14)
    assert body.volume == pytest.approx(6.0, rel=1e-14)
    np.testing.assert_allclose(body.com, [10, -5, 2], rtol=1e-14)
    np.testing.assert_allclose(body.inertia, 12.0 / 12 * np.diag([4 + 9, 1 + 9, 1 + 4.0]), rtol=1e-13, atol=1e-12)


def test_right_tetrahedron_mesh_closed_form():
    """The tetrahedron with legs a, b, c along the axes from one corner: com at
    (a, b, c) / 4, about it Ixx = 3 M (b^2 + c^2) / 80 (cyclic) and
    Ixy = M a b / 80 (products of inertia as -integral of x y dm), the closed
    form of integral x^2 dV = V a^2 / 10, integral x y dV = V a b / 20.  Unequal
    legs put the com off the bounding box's centre by a different amount on
    each axis (every centre-of-mass term of the mesh integrals is used)."""
    a, b, c, M = 1.0, 2.0, 3.5, 1.5
    d = np.array([0.3, -1.2, 2.0])
    v = np.array([[0, 0, 0], [a, 0, 0], [0, b, 0], [0, 0, c]]) + d
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    body = mi.mesh(v, f, mass=M)
    # measured: volume 2.2e-16, com exact, inertia 5.6e-16 (relative)
    assert body.volume == pytest.approx(a * b * c / 6, rel=2e-15)
    np.testing.assert_allclose(body.com, d + [a / 4, b / 4, c / 4], rtol=2e-15)
    expect = M / 80 * np.array([[3 * (b * b + c * c), a * b, a * c],
                                [a * b, 3 * (a * a + c * c), b * c],
                                [a * c, b * c, 3 * (a * a + b * b)]])
    np.testing.assert_allclose(body.inertia, expect, rtol=5e-15, atol=0)


def test_sphere_mesh_converges_second_order():
    errs = []
    for n in (16, 32, 64):
        v, f = mi.uv_sphere(1.0, n, 2 * n)
        body = mi.mesh(v, f, mass=1.0)
        errs.append(np.max(np.abs(body.inertia - 0.4 * np.eye(3))))
        assert np.max(np.abs(body.com)) < 1e-14
        assert body.volume < 4 / 3 * np.pi          # inscribed polyhedron
    assert errs[-1] < 4e-4
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 3.5) & (ratios < 4.5)), (errs, ratios)


def test_cone_mesh_exact_for_polygon_and_converges():
    M, R, h = 2.0, 1.2, 3.0
    errs = []
    for n in (12, 48, 192):
        v, f = cone_mesh(R, h, n)
        body = mi.mesh(v, f, mass=M)
        np.testing.assert_allclose(body.inertia, polygon_cone_closed_form(M, R, h, n),
                                   rtol=1e-13, atol=1e-14)
        np.testing.assert_allclose(body.com, 0, atol=1e-14)
        errs.append(np.max(np.abs(body.inertia - mi.solid("cone", M, radius=R, height=h).inertia)))
    assert errs[0] > 10 * errs[1] > 100 * errs[2]


def test_same_sphere_as_mesh_grid_and_solid():
    M, R = 5.0, 1.0
    solid = mi.solid("sphere", M, radius=R)
    v, f = mi.uv_sphere(R, 128, 256)
    msh = mi.mesh(v, f, mass=M)
    frac, h, origin = _uv_grid_fraction(lambda x, y, z: x * x + y * y + z * z <= 1, -1.0, 1.0, 48)
    grid = mi.density_grid(frac * M / (frac.sum() * h ** 3), h, origin)
    assert grid.mass == pytest.approx(M, rel=1e-12)
    scale = 0.4 * M
    assert np.max(np.abs(msh.inertia - solid.inertia)) < 3e-4 * scale   # O(1/n^2), 2.0e-4
    assert np.max(np.abs(grid.inertia - solid.inertia)) < 3e-3 * scale
    assert np.max(np.abs(grid.inertia - msh.inertia)) < 3e-3 * scale


def test_mesh_moved_and_rotated_equals_body_moved_and_rotated(rng):
    v, f = box_mesh(1.0, 2.0, 0.5)
    body = mi.mesh(v, f, density=3.0)
    R = random_rotation(rng)
    d = np.array([3.0, -1.0, 2.0])
    moved = mi.mesh(v @ R.T + d, f, density=3.0)
    expect = body.rotated(R).moved(d)
    np.testing.assert_allclose(moved.com, expect.com, rtol=1e-13)
    np.testing.assert_allclose(moved.inertia, expect.inertia, rtol=1e-12, atol=1e-13)


def test_mesh_large_translation_keeps_accuracy():
    v, f = mi.uv_sphere(1.0, 32, 64)
    near = mi.mesh(v, f)
    far = mi.mesh(v + 1e6, f)
    np.testing.assert_allclose(far.com, 1e6, rtol=1e-15)
    # only the rounding of the input coordinates (1e6 * 1.1e-16) enters
    np.testing.assert_allclose(far.inertia, near.inertia, atol=1e-9)


def _defect(v, f, word):
    with pytest.raises(mp.MeshError, match=word):
        mi.mesh(v, f)


def test_mesh_defects_are_named():
    v, f = box_mesh(1.0, 1.0, 1.0)
    _defect(v, f[:, ::-1], "inside out")
    _defect(v, f[:-1], "open")
    _defect(v, np.concatenate([f, f[:2]]), "non-manifold")
    _defect(v, np.concatenate([f[:1, ::-1], f[1:]]), "inconsistently oriented")
    _defect(v, np.concatenate([f, [[0, 0, 1]]]), "repeats a vertex")
    _defect(v, np.concatenate([f, [[0, 1, 8]]]), "does not exist")
    _defect(v, np.concatenate([f, [[0, 1, -1]]]), "does not exist")
    _defect(v, f[:3], "open")
    # zero-area face in an otherwise valid closed mesh: vertex 4 is the midpoint of
    # edge 0-1 and the sliver (0, 1, 4) closes the split tetrahedron
    w = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0, 0]], float)
    split = np.array([[0, 2, 1], [0, 4, 3], [4, 1, 3], [0, 3, 2], [1, 2, 3], [0, 1, 4]])
    _defect(w, split, "face 5 has zero area")
    _defect(w, split[:5], "open")
    # a flat quad seen from both sides: every inner edge has four faces
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    _defect(flat, np.array([[0, 2, 1], [1, 2, 3], [0, 1, 2], [1, 3, 2]]), "non-manifold")
    v2 = v.copy()
    v2[1] = v2[0]
    _defect(v2, f, "zero area")
    # a flat, closed "tetrahedron" (all four vertices in one plane)
    plane = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0]], float)
    _defect(plane, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]), "volume is zero")


def test_mesh_bad_arguments():
    v, f = box_mesh(1.0, 1.0, 1.0)
    with pytest.raises(TypeError, match="faces"):
        mi.mesh(v, f.astype(float))
    with pytest.raises(ValueError, match="vertices"):
        mi.mesh(v[:, :2], f)
    with pytest.raises(ValueError, match="faces"):
        mi.mesh(v, f[:, :2])
    vn = v.copy()
    vn[3, 1] = np.nan
    with pytest.raises(ValueError, match="finite"):
        mi.mesh(vn, f)
    with pytest.raises(ValueError, match="not both"):
        mi.mesh(v, f, density=1.0, mass=1.0)
    with pytest.raises(ValueError, match="positive"):
        mi.mesh(v, f, mass=-1.0)


# ----------------------------------------------------------------------- grids

def test_density_grid_voxel_box_is_exact():
    rho = np.zeros((10, 12, 14))
    rho[2:6, 3:11, 1:13] = 2.5             # a 4 x 8 x 12 voxel box, h = 0.25
    body = mi.density_grid(rho, 0.25, origin=(1.0, 2.0, 3.0))
    a, b, c = 4 * 0.25, 8 * 0.25, 12 * 0.25
    M = 2.5 * a * b * c
    assert body.mass == pytest.approx(M, rel=1e-14)
    np.testing.assert_allclose(body.com, [1 + 0.25 * 3.5, 2 + 0.25 * 6.5, 3 + 0.25 * 6.5],
                               rtol=1e-14)
    np.testing.assert_allclose(body.inertia, M / 12 * np.diag([b * b + c * c, a * a + c * c,
                                                                a * a + b * b]), rtol=1e-13)


def test_density_grid_smooth_density_second_order():
    """A density (1 - r^2)^3 inside the unit ball (smooth, vanishing to 2nd order at r = 1)."""
    # closed forms: M = 4pi int_0^1 r^2 (1-r^2)^3 dr = 4pi * 16/315;
    # I = 2/3 * 4pi int_0^1 r^4 (1-r^2)^3 dr = 2/3 * 4pi * 16/1155
    M = 4 * np.pi * 16 / 315
    Iref = 2 / 3 * 4 * np.pi * 16 / 1155
    errs = []
    for n in (20, 40, 80):
        h = 2.0 / n
        c = -1 + h * (np.arange(n) + 0.5)
        X, Y, Z = np.meshgrid(c, c, c, indexing="ij")
        rho = np.clip(1 - (X * X + Y * Y + Z * Z), 0, None) ** 3
        body = mi.density_grid(rho, (h, h, h), (c[0], c[0], c[0]))
        errs.append(max(abs(body.mass - M) / M, np.max(np.abs(body.inertia - Iref * np.eye(3)))
                        / Iref))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert errs[-1] < 2e-3 and np.all(ratios > 3.0), (errs, ratios)


def test_density_grid_bad_input():
    with pytest.raises(ValueError, match="rho"):
        mi.density_grid(-np.ones((2, 2, 2)), 1.0)
    with pytest.raises(ValueError, match="positive total"):
        mi.density_grid(np.zeros((2, 2, 2)), 1.0)
    with pytest.raises(ValueError, match="rho"):
        mi.density_grid(np.ones((2, 2)), 1.0)
    with pytest.raises(ValueError, match="spacing"):
        mi.density_grid(np.ones((2, 2, 2)), (1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="spacing"):
        mi.density_grid(np.ones((2, 2, 2)), (1.0, 1.0))


def _bipyramid(n):
    """Two cones of height 1 on a regular n-gon of circumradius 1: 2n faces, each apex of
    degree n (the case an edge lookup linear in the degree makes quadratic)."""
    ph = 2 * np.pi * np.arange(n) / n
    V = np.concatenate([np.stack([np.cos(ph), np.sin(ph), np.zeros(n)], -1),
                        [[0, 0, 1.0], [0, 0, -1.0]]])
    j = np.arange(n)
    top = np.stack([j, (j + 1) % n, np.full(n, n)], -1)
    bot = np.stack([(j + 1) % n, j, np.full(n, n + 1)], -1)
    return V, np.concatenate([top, bot]).astype(np.int64)


@pytest.mark.parametrize("n", [15, 16, 17])
def test_mesh_apex_degree_near_the_scan_limit(rng, n):
    """Apexes of degree 15-17 (about where an edge lookup stops scanning a
    vertex's list and searches it), the faces in random order: volume of the
    bipyramid 2/3 x the n-gon's area, and its defects still found."""
    V, F = _bipyramid(n)
    F = F[rng.permutation(len(F))]
    area = 0.5 * n * np.sin(2 * np.pi / n)
    b = mi.mesh(V, F)
    assert b.volume == pytest.approx(2 * area / 3, rel=2e-15)          # measured <= 2.2e-16
    np.testing.assert_allclose(b.com, 0.0, atol=1e-16)
    apex = np.nonzero(np.any(F == n, axis=1))[0]
    with pytest.raises(mp.MeshError, match="open"):
        mi.mesh(V, np.delete(F, apex[3], axis=0))
    G = F.copy()
    G[apex[5]] = G[apex[5]][::-1]
    with pytest.raises(mp.MeshError, match="oriented|open"):
        mi.mesh(V, G)
    with pytest.raises(mp.MeshError, match="non-manifold"):
        mi.mesh(V, np.concatenate([F, F[apex[:1]]]))


def test_mesh_high_degree_vertices_bipyramid():
    # 400k faces, two vertices of degree 200k: took minutes when each edge lookup scanned
    # the apex's whole list (80k faces: 7 s); now about 0.1 s
    n = 200_000
    V, F = _bipyramid(n)
    b = mi.mesh(V, F)
    area = 0.5 * n * np.sin(2 * np.pi / n)            # the n-gon
    assert b.volume == pytest.approx(2 * area / 3, rel=1e-14)      # measured 6e-16
    np.testing.assert_allclose(b.com, 0.0, atol=1e-16)
    # the apex's defects are still found: drop one face -> open, at the apex's edges
    with pytest.raises(mp.MeshError, match="open"):
        mi.mesh(V, F[1:])
    G = F.copy()
    G[n + 5] = G[n + 5][::-1]
    with pytest.raises(mp.MeshError, match="oriented|open"):
        mi.mesh(V, G)
    H = np.concatenate([F, F[:1]])
    with pytest.raises(mp.MeshError, match="non-manifold"):
        mi.mesh(V, H)


def test_mesh_ctrl_c_is_prompt():
    from sigint import interrupt_delay
    setup = ("n = 1_000_000\nph = 2 * np.pi * np.arange(n) / n\n"
              "V = np.concatenate([np.stack([np.cos(ph), np.sin(ph), np.zeros(n)], -1),"
              " [[0, 0, 1.0], [0, 0, -1.0]]])\nj = np.arange(n)\n"
              "F = np.concatenate([np.stack([j, (j + 1) % n, np.full(n, n)], -1),"
              " np.stack([(j + 1) % n, j, np.full(n, n + 1)], -1)]).astype(np.int64)\n")
    dt = interrupt_delay(setup, "[mp.inertia.mesh(V, F) for _ in range(20)]", delay=0.3)
    assert dt < 1.0, f"KeyboardInterrupt {dt} CPU s after SIGINT"   # measured ~0.01 s


def test_mesh_out_of_range_is_not_zero_area():
    V, F = mi.uv_sphere(1.0, 4, 6)
    # coordinates 1e200: squared edges overflow; said so, not "zero area"
    with pytest.raises(mp.MeshError, match="overflow"):
        mi.mesh(V * 1e200, F)
    with pytest.raises(mp.MeshError, match="underflow"):
        mi.mesh(V * 1e-200, F)
    # up to 1e60 the inertia (size^5) fits: exact scaling of the unit result
    b1, b = mi.mesh(V, F), mi.mesh(V * 2.0 ** 190, F)
    assert b.volume == b1.volume * 2.0 ** 570
    np.testing.assert_array_equal(b.inertia, b1.inertia * 2.0 ** 950)


# ----------------------------------------------------------------------- Steiner

def test_shift_large_offsets_exact_rounding(rng):
    for _ in range(20):
        A = rng.normal(size=(3, 3))
        S = A @ A.T                            # second moments of some distribution
        I = np.trace(S) * np.eye(3) - S        # its inertia tensor
        M = rng.uniform(0.5, 2.0)
        a = rng.normal(size=3) * 1e6
        out = mi.shift(I, M, a)
        ref = shift_exact(I, M, a, +1)
        np.testing.assert_allclose(out, ref, rtol=2.3e-16, atol=0)
        back = mi.shift(out, M, a, to="com")
        refb = shift_exact(out, M, a, -1)
        # the way back is computed from the rounded tensor: exact up to one rounding
        np.testing.assert_allclose(back, refb, rtol=0, atol=4e-16 * np.max(np.abs(refb)))
        # and it recovers I up to what the rounding of `out` (ulp ~ 1e-4) carries
        assert np.max(np.abs(back - I)) <= 2 * np.max(np.spacing(np.abs(out)))


def test_shift_batched_and_steiner_matches_point_masses(rng):
    m = rng.uniform(0.1, 1.0, size=(6, 9))
    x = rng.normal(size=(6, 9, 3))
    p = rng.normal(size=(6, 3))
    com = np.einsum("bn,bnk->bk", m, x) / m.sum(1)[:, None]
    Icom = point_masses_ref(m, x, com)
    got = mi.shift(Icom, m.sum(1), p - com)
    np.testing.assert_allclose(got, point_masses_ref(m, x, p), rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="to"):
        mi.shift(Icom[0], 1.0, p[0], to="corner")
    with pytest.raises(ValueError, match="mass"):
        mi.shift(Icom[0], -1.0, p[0])


def test_shift_to_com_refuses_an_impossible_tensor(rng):
    # a unit point mass at distance 1 has I = diag(0, 1, 1) about the origin; claiming its
    # centre of mass lies 2 away would give moments 1 - 4 < 0
    I = mi.point_masses([1.0], [[1.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="principal moments") as exc:
        mi.shift(I, 1.0, [2.0, 0.0, 0.0], to="com")
    assert "a" in str(exc.value) and "mass" in str(exc.value)
    # the true offset gives exactly zero (a point mass about itself)
    np.testing.assert_array_equal(mi.shift(I, 1.0, [1.0, 0.0, 0.0], to="com"), 0.0)
    # I about the centre of mass already, shifted once more: moments 2/5 - 1 < 0
    ball = mi.solid("sphere", 1.0, radius=1.0)
    with pytest.raises(ValueError, match="centre of mass"):
        mi.shift(ball.inertia, 1.0, [0.0, 0.0, 1.0], to="com")
    # PSD but I1 + I2 < I3 (no mass distribution): also refused
    with pytest.raises(ValueError, match="I1 \\+ I2 < I3"):
        mi.shift(np.diag([1.0, 1.0, 5.0]) + 0.0, 1.0, [0.0, 0.0, 1e-3], to="com")
    # a batch names its bad item; the good ones alone pass
    m = rng.uniform(0.5, 2.0, 5)
    x = rng.normal(size=(5, 4, 3))
    pts = rng.normal(size=(5, 3))
    com = np.einsum("bn,bnk->bk", m[:, None] * np.ones(4), x) / (4 * m[:, None])
    Ip = mi.point_masses(m[:, None] * np.ones(4), x, pts)
    back = mi.shift(Ip, 4 * m, pts - com, to="com")
    np.testing.assert_allclose(back, mi.point_masses(m[:, None] * np.ones(4), x, com),
                               rtol=1e-12, atol=1e-12)
    a = pts - com
    a[3] *= 10.0
    with pytest.raises(ValueError, match="item 3"):
        mi.shift(Ip, 4 * m, a, to="com")


# ----------------------------------------------------------------------- principal axes

def test_principal_axes_against_eigh(rng):
    A = rng.normal(size=(200, 3, 3))
    I = A @ np.swapaxes(A, 1, 2)
    w, R = mi.principal_axes(I)
    np.testing.assert_allclose(w, np.linalg.eigh(I)[0], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.swapaxes(R, 1, 2) @ R, np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-14)
    np.testing.assert_allclose(R @ (w[:, :, None] * np.swapaxes(R, 1, 2)), I, atol=1e-13)
    for k in range(5):
        ws, vs = scipy.linalg.eigh(I[k])
        np.testing.assert_allclose(w[k], ws, rtol=1e-13)
        # eigenvectors agree with SciPy's up to sign (distinct moments)
        np.testing.assert_allclose(np.abs(np.sum(vs * R[k], axis=0)), 1.0, rtol=1e-10)


def test_principal_axes_widely_spread_moments():
    Q = random_rotation(np.random.default_rng(3))
    w0 = np.array([1e-9, 1.0, 1e9])
    I = Q @ np.diag(w0) @ Q.T      # itself rounded at eps * 1e9 ~ 1e-7 absolute
    w, R = mi.principal_axes(I)
    np.testing.assert_allclose(w, np.linalg.eigvalsh(I), rtol=0, atol=4 * 2.2e-16 * 1e9)
    np.testing.assert_allclose(w, w0, rtol=0, atol=1e-6)
    np.testing.assert_allclose(R @ np.diag(w) @ R.T, I, rtol=0, atol=4 * 2.2e-16 * 1e9)
    np.testing.assert_allclose(np.abs(np.sum(R * Q, axis=0)), 1.0, rtol=1e-12)
    # an exactly diagonal tensor is returned exactly, however spread
    w, R = mi.principal_axes(np.diag([1e9, 1e-9, 1.0]))
    assert np.all(w == [1e-9, 1.0, 1e9])
    assert np.all(np.abs(R) == np.eye(3)[:, [1, 2, 0]])


def test_rotated_tensors_keep_eigenvalues(rng):
    body = mi.solid("box", 2.0, a=1.0, b=2.0, c=3.0).moved([1.0, 2.0, -1.0])
    R = random_rotation(rng, 10)
    for Rk in R:
        rb = body.rotated(Rk)
        np.testing.assert_allclose(rb.principal()[0], body.principal()[0], rtol=1e-13)
        np.testing.assert_allclose(rb.com, Rk @ body.com, rtol=1e-13)
    with pytest.raises(ValueError, match="rotation"):
        body.rotated(np.diag([1.0, 1.0, -1.0]))


def test_classify():
    assert mi.classify(mi.solid("sphere", 1.0, radius=1.0).inertia) == "spherical"
    assert mi.classify(mi.solid("cube", 1.0, side=1.0).inertia) == "spherical"
    assert mi.classify(mi.solid("cylinder", 1.0, radius=1.0, height=1.0).inertia) == "symmetric"
    assert mi.classify(mi.solid("box", 1.0, a=1.0, b=2.0, c=3.0).inertia) == "asymmetric"
    assert mi.classify(mi.solid("rod", 1.0, length=1.0).inertia) == "rotor"
    # the cylinder with h = sqrt(3) R is a spherical top
    assert mi.classify(mi.solid("cylinder", 1.0, radius=1.0, height=3 ** 0.5).inertia) == "spherical"
    near = np.diag([1.0, 1.0 + 1e-12, 2.0])
    assert mi.classify(near) == "symmetric"
    assert mi.classify(near, rtol=1e-14) == "asymmetric"
    Q = random_rotation(np.random.default_rng(1))
    assert mi.classify(Q @ np.diag([2.0, 3.0, 3.0]) @ Q.T) == "symmetric"
    with pytest.raises(ValueError):
        mi.classify(np.zeros((3, 3)))


def test_principal_axes_bad_input():
    with pytest.raises(ValueError, match="symmetric"):
        mi.principal_axes([[1, 2, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="semi-definite"):
        mi.principal_axes(np.diag([1.0, -1.0, 2.0]))
    with pytest.raises(ValueError):
        mi.principal_axes(np.eye(2))
    with pytest.raises(ValueError, match="finite"):
        mi.principal_axes(np.full((3, 3), np.nan))
    with pytest.raises(TypeError):
        mi.principal_axes("eye")


# ----------------------------------------------------------------------- dynamics

def test_angular_momentum_and_energy_of_rigid_rotation(rng):
    m = rng.uniform(0.5, 1.5, 12)
    x = rng.normal(size=(12, 3))
    w = rng.normal(size=3)
    v = np.cross(w, x)
    I = mi.point_masses(m, x)
    L = mi.angular_momentum_about(m, x, v)
    np.testing.assert_allclose(mi.angular_momentum(I, w), L, rtol=1e-12)
    T = 0.5 * np.sum(m * np.sum(v * v, axis=1))
    assert mi.kinetic_energy(I, w) == pytest.approx(T, rel=1e-12)
    # batched
    Ib = np.stack([I, 2 * I])
    np.testing.assert_allclose(mi.kinetic_energy(Ib, np.stack([w, w])), [T, 2 * T], rtol=1e-12)


def test_kinetic_energy_split_rigid_and_internal(rng):
    m = rng.uniform(0.5, 1.5, 10)
    x = rng.normal(size=(10, 3)) + 5.0
    Vc = np.array([1.0, -2.0, 0.5])
    w = np.array([0.3, -0.7, 1.1])
    c = mi.center_of_mass(m, x)
    v = Vc + np.cross(w, x - c)
    s = mi.kinetic_energy_split(m, x, v)
    M = m.sum()
    assert s.translational == pytest.approx(0.5 * M * Vc @ Vc, rel=1e-13)
    Icm = mi.point_masses(m, x, c)
    assert s.rotational == pytest.approx(0.5 * w @ Icm @ w, rel=1e-12)
    assert s.total == pytest.approx(s.translational + s.rotational, rel=1e-12)
    assert s.deformation < 1e-12 * s.total
    np.testing.assert_allclose(s.omega, w, rtol=1e-10)
    np.testing.assert_allclose(mi.total_momentum(m, v), M * Vc, rtol=1e-13)
    # L about a point = L about the com + R x P
    p = np.array([1.0, 2.0, 3.0])
    Lp = mi.angular_momentum_about(m, x, v, p)
    Lc = mi.angular_momentum_about(m, x, v, c)
    np.testing.assert_allclose(Lp, Lc + np.cross(c - p, M * Vc), rtol=1e-12)
    # a non-rigid motion has internal energy beyond rotation
    s2 = mi.kinetic_energy_split(m, x, v + rng.normal(size=v.shape))
    assert s2.total == pytest.approx(s2.translational + s2.internal, rel=1e-12)
    assert s2.deformation > 0


def test_kinetic_energy_split_of_a_rotor():
    """Collinear masses (one principal moment exactly 0): spin about z at w,
    a drift V and a stretch along the rod with no momentum.  T_rot = I w^2 / 2
    with I = sum m x^2 = 1.5, T_def the stretch's energy; no 1/0 on the way."""
    m = np.array([1.0, 2.0])
    x = np.array([[-1.0, 0.0, 0.0], [0.5, 0.0, 0.0]])          # com at the origin
    w, V = 0.8, np.array([0.3, -0.2, 0.1])
    stretch = np.array([[0.2, 0.0, 0.0], [-0.1, 0.0, 0.0]])
    v = np.cross([0.0, 0.0, w], x) + V + stretch
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = mi.kinetic_energy_split(m, x, v)
    # measured: within 1 ulp (deformation 9e-16)
    assert s.translational == pytest.approx(0.5 * 3.0 * V @ V, rel=1e-15)
    assert s.rotational == pytest.approx(0.5 * 1.5 * w * w, rel=1e-15)
    assert s.deformation == pytest.approx(0.5 * (0.2 ** 2 + 2 * 0.1 ** 2), rel=5e-15)
    np.testing.assert_allclose(s.omega, [0.0, 0.0, w], rtol=1e-15, atol=0)


def test_particle_helpers_bad_input():
    with pytest.raises(ValueError, match="masses"):
        mi.center_of_mass([1.0, 0.0], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match="positions"):
        mi.center_of_mass([1.0, 2.0], [[0, 0, 0]])
    with pytest.raises(ValueError, match="velocities"):
        mi.kinetic_energy_split([1.0], [[0, 0, 0]], [[0, 0]])


# ----------------------------------------------------------------------- Body

def test_two_cubes_make_a_box():
    a = mi.solid("cube", 1.0, side=1.0).moved([-0.5, 0, 0])
    b = mi.solid("cube", 1.0, side=1.0).moved([0.5, 0, 0])
    box = a + b
    ref = mi.solid("box", 2.0, a=2.0, b=1.0, c=1.0)
    assert box.mass == 2.0 and box.volume == pytest.approx(2.0)
    np.testing.assert_allclose(box.com, 0, atol=1e-16)
    np.testing.assert_allclose(box.inertia, ref.inertia, rtol=1e-15, atol=1e-16)
    assert sum([a, b]).mass == 2.0


def test_composite_equals_union_of_point_masses(rng):
    m = rng.uniform(0.5, 1.5, 8)
    x = rng.normal(size=(8, 3))
    whole = mi.Body.from_point_masses(m, x)
    parts = mi.Body.from_point_masses(m[:3], x[:3]) + mi.Body.from_point_masses(m[3:], x[3:])
    np.testing.assert_allclose(parts.inertia, whole.inertia, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(parts.com, whole.com, rtol=1e-13)
    p = rng.normal(size=3)
    np.testing.assert_allclose(whole.inertia_about(p), point_masses_ref(m, x, p), rtol=1e-12)


def test_bad_input():
    with pytest.raises(ValueError, match="masses"):
        mi.point_masses([1.0, -1.0], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match="masses"):
        mi.point_masses([1.0, 0.0], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match="positions"):
        mi.point_masses([1.0, 1.0], [[0, np.nan, 0], [1, 0, 0]])
    with pytest.raises(ValueError):
        mi.point_masses([1.0, 1.0], [[0, 0], [1, 0]])
    with pytest.raises(ValueError):
        mi.point_masses([1.0, 1.0, 1.0], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(TypeError):
        mi.point_masses(["a", "b"], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(ValueError, match="unknown shape"):
        mi.solid("torus", 1.0, radius=1.0)
    with pytest.raises(TypeError, match="height"):
        mi.solid("cone", 1.0, radius=1.0)
    with pytest.raises(TypeError, match="side"):
        mi.solid("sphere", 1.0, radius=1.0, side=2.0)
    with pytest.raises(ValueError, match="radius"):
        mi.solid("sphere", 1.0, radius=-1.0)
    with pytest.raises(ValueError, match="mass"):
        mi.solid("sphere", 0.0, radius=1.0)
    with pytest.raises(ValueError, match="I1 \\+ I2 >= I3"):
        mi.Body(1.0, [0, 0, 0], np.diag([1.0, 1.0, 3.0]))
    with pytest.raises(ValueError, match="symmetric"):
        mi.Body(1.0, [0, 0, 0], [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]])


def test_body_checks_its_tensor_alike_in_any_units():
    """Body's check of a mass distribution's tensor (principal moments >= 0 with
    I1 + I2 >= I3) does not depend on the units: at the scales 1e-6, 1 and 1e6 a flat
    body (I1 + I2 = I3) and a point mass (zero tensor) are accepted, a violation of
    the triangle inequality by 1e-6 relative, or a negative moment, refused."""
    for a in (1e-6, 1.0, 1e6):
        for ok in ([a, a, 2 * a], [a, 2 * a, 3 * a], [0.0, a, a], [0.0, 0.0, 0.0]):
            b = mi.Body(2.0, inertia=np.diag(ok))
            assert np.array_equal(b.inertia, np.diag(ok))
        for bad in ([a, a, 2 * a * (1 + 1e-6)], [a, 2 * a, 3 * a * (1 + 1e-6)],
                    [-1e-6 * a, a, a]):
            with pytest.raises(ValueError, match="I1 \\+ I2 >= I3"):
                mi.Body(2.0, inertia=np.diag(bad))
