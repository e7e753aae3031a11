"""Property-based fuzzing of every public function (hypothesis).

Each entry point gets random shapes, dtypes (int, float32, complex, object,
bool), non-contiguous and reversed strides, NaN/inf, huge and tiny
magnitudes, empty arrays and wrong types.  Every call must either return
finite float64 results of the right shape or raise a documented exception
(``TypeError``, ``ValueError``, ``numpy.linalg.LinAlgError`` or a
``mechpy.errors`` class).  The batches run in a child interpreter
(``python tests/test_fuzz.py <group>``), so a crash of the C core is a test
failure naming the entry point, not an abort of the suite.  The examples are
derandomized (reproducible) and counted per entry point.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

try:
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st
except ImportError:  # the parent test skips; the child needs hypothesis
    st = None

HERE = Path(__file__).resolve().parent
EXAMPLES = int(os.environ.get("MECHPY_FUZZ_EXAMPLES", "60"))

# --------------------------------------------------------------------------- #
# Strategies
# --------------------------------------------------------------------------- #

SPECIAL = [0.0, -0.0, 1.0, -1.0, 0.5, math.pi, math.nan, math.inf, -math.inf, 1e100, -1e100,
           1e-100, 5e-324, 1e300, -2.5]
JUNK = [None, "abc", b"x", [1, "a"], [[1.0, 2.0], [3.0]], {}, object(), 1j, True, 10 ** 400,
        (), [[]], np.datetime64("2020-01-01")]


def _floats():
    return st.one_of(st.floats(-10, 10), st.sampled_from(SPECIAL),
                     st.floats(allow_nan=True, allow_infinity=True))


def _scalar():
    """A number that is mostly valid, sometimes special, sometimes junk."""
    return st.one_of(st.floats(0.1, 5.0), st.floats(-5.0, 5.0), st.sampled_from(SPECIAL),
                     st.integers(-3, 5), st.sampled_from(JUNK),
                     st.builds(np.float32, st.floats(-5, 5, width=32)))


def _pos():
    """A mostly positive scalar."""
    return st.one_of(st.floats(0.1, 5.0), st.floats(0.1, 5.0), _scalar())


DTYPES = [np.float64, np.float64, np.float64, np.float32, np.int64, np.int8, np.bool_,
          np.complex128, object]


# without hypothesis the module still imports (its own tests run; test_fuzz skips)
@(st.composite if st is not None else (lambda f: f))
def _array(draw, shape, pos=False):
    """An array-like of roughly `shape`: random dtype, layout and values."""
    shape = tuple(shape)
    if draw(st.integers(0, 9)) == 0:  # wrong shape
        shape = draw(st.one_of(
            st.just(()), st.just((0,)), st.just(shape + (2,)), st.just(shape[1:]),
            st.lists(st.integers(0, 4), max_size=3).map(tuple)))
    if draw(st.integers(0, 24)) == 0:
        return draw(st.sampled_from(JUNK))
    n = int(np.prod(shape, dtype=np.int64))
    vals = draw(st.lists(st.floats(0.2, 3.0) if pos else st.floats(-3.0, 3.0),
                         min_size=n, max_size=n))
    a = np.array(vals, dtype=np.float64).reshape(shape)
    if n and draw(st.integers(0, 3)) == 0:  # a few special values
        for _ in range(draw(st.integers(1, 3))):
            a.flat[draw(st.integers(0, n - 1))] = draw(_floats())
    dtype = draw(st.sampled_from(DTYPES))
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if dtype is object:
            b = a.astype(object)
        elif np.issubdtype(dtype, np.integer):
            b = np.nan_to_num(a, posinf=0, neginf=0).clip(-100, 100).astype(dtype)
        else:
            b = a.astype(dtype)
    layout = draw(st.integers(0, 4))
    if layout == 1 and b.ndim:  # non-contiguous: every other element of a bigger array
        big = np.zeros(b.shape[:-1] + (2 * b.shape[-1],), dtype=b.dtype)
        big[..., ::2] = b
        b = big[..., ::2]
    elif layout == 2 and b.ndim:  # negative strides, same values
        b = b[..., ::-1].copy()[..., ::-1]
    elif layout == 4 and b.ndim > 1:
        b = np.asfortranarray(b)
    elif layout == 3:
        return b.tolist()
    return b


def A(*shape, pos=False):
    return _array(shape, pos)


def _seq():
    return st.sampled_from(["ZXZ", "zxz", "XYZ", "xyz", "ZYX", "zyx", "YXY", "xzx", "ZZZ", "abc",
                            "", "ZX", 3])


# --------------------------------------------------------------------------- #
# Result checks
# --------------------------------------------------------------------------- #

def _extreme(args, depth=0):
    """Whether an input has a magnitude beyond 1e100 or below 1e-100 (but not 0):
    then a result may overflow float64 for real, and inf (never NaN) is accepted."""
    if depth > 3:
        return False
    if isinstance(args, dict):
        args = list(args.values())
    if isinstance(args, (list, tuple)):
        return any(_extreme(a, depth + 1) for a in args)
    try:
        a = np.asarray(args, dtype=float)
    except (TypeError, ValueError, OverflowError):
        return isinstance(args, int) and not isinstance(args, bool)
    with np.errstate(all="ignore"):
        m = np.abs(a[np.isfinite(a)])
    return bool(np.any(m > 1e100) or np.any((m > 0) & (m < 1e-100)))


def _finite(obj, where="result", depth=0, inf_ok=False):
    """Every float in obj (arrays, numbers, containers, result objects) is finite
    (or, with inf_ok, at least not NaN)."""
    if depth > 4:
        return
    ok = (lambda v: ~np.isnan(v)) if inf_ok else np.isfinite
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fc":
            assert obj.dtype == np.float64 or obj.dtype.kind == "c", f"{where}: dtype {obj.dtype}"
            assert np.all(ok(obj)), f"{where}: non-finite values"
        return
    if isinstance(obj, (float, np.floating)):
        assert ok(obj), f"{where} = {obj}"
        return
    if isinstance(obj, (str, bytes, int, bool, np.integer, np.bool_)) or obj is None:
        return
    if isinstance(obj, dict):
        for k, v in obj.items():
            _finite(v, f"{where}[{k!r}]", depth + 1, inf_ok)
        return
    if isinstance(obj, (tuple, list)):
        for i, v in enumerate(obj[:50]):
            _finite(v, f"{where}[{i}]", depth + 1, inf_ok)
        return
    for name in ("mass", "com", "inertia", "omega", "vectors", "t", "y"):
        if hasattr(obj, name) and not callable(getattr(obj, name)):
            _finite(getattr(obj, name), f"{where}.{name}", depth + 1, inf_ok)


def _allowed():
    import mechpy
    return (TypeError, ValueError, np.linalg.LinAlgError, mechpy.errors.MechpyError)


COUNTS: dict[str, int] = {}


def _run(name, fn, *args, check=None, inf_ok=False, strict=False, **kw):
    """Call fn; a documented exception is fine, anything else fails.  With
    ``strict`` an overflow must be an error even for extreme inputs (never inf)."""
    COUNTS[name] = COUNTS.get(name, 0) + 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            out = fn(*args, **kw)
        except _allowed():
            return None
    _finite(out, name, inf_ok=inf_ok or (not strict and _extreme((args, kw))))
    if check is not None:
        check(out)
    return out


def _shape(*expect):
    def check(out):
        assert np.shape(out) == expect, f"shape {np.shape(out)}, expected {expect}"
    return check


def _settings(n=None):
    return settings(max_examples=n or EXAMPLES, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck), print_blob=True)


# --------------------------------------------------------------------------- #
# The fuzz batches (run in the child; `fuzz_<group>` runs every function of a group)
# --------------------------------------------------------------------------- #

def fuzz_integrate():
    import mechpy as mp

    scenes = [mp.scenes.Pendulum(), mp.scenes.VanDerPol(mu=2.0), mp.scenes.Duffing(1.0, 1.0),
              mp.scenes.Kepler(), mp.scenes.RigidBody((1.0, 2.0, 3.0)),
              mp.scenes.RigidBody((1.0, 2.0, 3.0), orientation=True),
              mp.scenes.HeavyTop(1.0, 0.5, 1.0), mp.scenes.Foucault(45.0, 10.0),
              mp.scenes.RestrictedThreeBody()]

    def bad_rhs(t, y):
        raise ZeroDivisionError("user error")

    def py_rhs(t, y):
        return -np.asarray(y)

    callbacks = [py_rhs, bad_rhs, lambda t, y: np.full(len(y), np.nan), lambda t, y: "x",
                 lambda t, y: np.zeros(len(y) + 1), lambda t, y: [1.0] * len(y),
                 mp.SecondOrder(lambda t, q: -np.asarray(q))]
    systems = st.sampled_from(scenes + callbacks + [None, 3, "pendulum"])
    names = [m["name"] for m in mp.methods()] + ["bdf", "nope", 7]
    user_errors = (ZeroDivisionError,)

    def y0_for(system):
        dim = getattr(system, "dim", 2)
        return A(dim)

    @_settings(3 * EXAMPLES)
    @given(st.data())
    def solve(data):
        system = data.draw(systems)
        method = data.draw(st.sampled_from(names))
        t0 = data.draw(st.one_of(st.just(0.0), _scalar()))
        tf = data.draw(st.one_of(st.floats(0.01, 3.0), _scalar()))
        kw = dict(rtol=data.draw(st.one_of(st.just(1e-6), st.sampled_from([1e-12, 1e-3, 0.0, -1.0,
                                                                        math.nan, 1.0]))),
                  atol=data.draw(st.one_of(st.just(1e-8), A(2, pos=True), _scalar())),
                  max_steps=data.draw(st.one_of(st.integers(1, 3000), st.sampled_from(
                      [0, -1, 1.5, "x", None]))))
        if data.draw(st.booleans()):
            kw["h"] = data.draw(st.one_of(st.floats(1e-3, 0.5), _scalar()))
        if data.draw(st.integers(0, 3)) == 0:
            kw["t_eval"] = data.draw(st.one_of(A(data.draw(st.integers(0, 5))),
                                               st.just(np.linspace(0, 1, 5))))
        if data.draw(st.integers(0, 4)) == 0:
            kw["dense_output"] = True
        if data.draw(st.integers(0, 4)) == 0:
            ev = data.draw(st.sampled_from([lambda t, y: y[0], lambda t, y: "x",
                                            lambda t, y: 1 / 0, lambda t, y: np.nan]))
            ev.terminal = data.draw(st.sampled_from([True, False, 2, -1, "x"]))
            kw["events"] = ev
        if data.draw(st.integers(0, 5)) == 0:
            kw["first_step"] = data.draw(_scalar())
            kw["max_step"] = data.draw(_scalar())
        y0 = data.draw(y0_for(system))
        try:
            sol = _run("mp.solve", mp.solve, system, (t0, tf), y0, method, **kw)
        except user_errors:
            return
        if sol is not None:
            n = np.asarray(y0).size
            assert sol.y.shape == (n, sol.t.size)
            assert sol.status in (-1, 0, 1)
            if sol.sol is not None and sol.t.size:
                _run("Solution.sol", sol.sol, data.draw(st.one_of(_scalar(), A(3))))

    last = {}

    def _many(*a, **kw):  # y of a failed trajectory is NaN by contract: only successes checked
        ens = last["ens"] = mp.solve_many(*a, **kw)
        return ens.t, ens.y[ens.success], ens.status

    @_settings(EXAMPLES)
    @given(st.data())
    def solve_many(data):
        system = data.draw(systems)
        k = data.draw(st.integers(0, 4))
        dim = getattr(system, "dim", 2)
        y0s = data.draw(A(k, dim))
        kw = dict(max_steps=data.draw(st.integers(1, 2000)),
                  threads=data.draw(st.one_of(st.integers(1, 3), st.sampled_from([0, -1, None,
                                                                                   "x"]))))
        if data.draw(st.booleans()):
            kw["params"] = data.draw(st.one_of(A(k, len(getattr(system, "params", (1,)))),
                                               st.just({"g": np.full(k, 3.0)}), _scalar()))
        if data.draw(st.booleans()):
            kw["t_eval"] = data.draw(A(3))
        method = data.draw(st.sampled_from(names))
        if data.draw(st.booleans()):
            kw["h"] = data.draw(st.one_of(st.floats(1e-2, 0.5), _scalar()))
        try:
            ens = _run("mp.solve_many", _many, system,
                       (0.0, data.draw(st.one_of(st.floats(0.01, 2.0), _scalar()))), y0s,
                       method=method, **kw)
        except user_errors:
            return
        if ens is not None:
            ens = last["ens"]  # failed trajectories are NaN (documented), the others finite
            assert ens.y.shape[:2] == np.shape(y0s)
            assert np.all(np.isfinite(ens.y[ens.success])), "successful trajectory not finite"
            assert ens.y.shape[2] == ens.t.size

    solve()
    solve_many()


def fuzz_scenes():
    import mechpy as mp
    ctors = {
        "Pendulum": (mp.scenes.Pendulum, ["g", "length", "damping", "drive_amplitude",
                                          "drive_frequency"]),
        "VanDerPol": (mp.scenes.VanDerPol, ["mu"]),
        "Duffing": (mp.scenes.Duffing, ["alpha", "beta", "delta", "gamma", "omega"]),
        "Kepler": (mp.scenes.Kepler, ["mu"]),
        "RestrictedThreeBody": (mp.scenes.RestrictedThreeBody, ["mu"]),
        "Foucault": (mp.scenes.Foucault, ["latitude", "length", "g", "omega"]),
        "HeavyTop": (mp.scenes.HeavyTop, ["I1", "I3", "mass", "g", "l"]),
    }

    @_settings(3 * EXAMPLES)
    @given(st.data())
    def scenes(data):
        name = data.draw(st.sampled_from(sorted(ctors) + ["RigidBody"]))
        if name == "RigidBody":
            kw = dict(moments=data.draw(st.one_of(st.just((1.0, 2.0, 3.0)), A(3, pos=True))))
            if data.draw(st.booleans()):
                kw["torque"] = data.draw(A(3))
            kw["orientation"] = data.draw(st.sampled_from([False, True, "x", 2]))
            ctor = mp.scenes.RigidBody
        else:
            ctor, pars = ctors[name]
            kw = {p: data.draw(_pos() if data.draw(st.integers(0, 4)) == 0 else
                               st.floats(0.1, 5.0))
                  for p in pars if data.draw(st.integers(0, 3)) == 0 or
                  p in ("alpha", "beta", "latitude", "length", "I1", "I3", "mass")}
        scene = _run(f"scenes.{name}()", ctor, **kw)
        if scene is None:
            return
        dim = scene.dim
        lead = data.draw(st.sampled_from([(), (3,), (2, 2), (0,)]))
        y = data.draw(A(dim, *lead))  # vectorised: y (dim, ...)
        t = data.draw(st.one_of(st.just(0.0), _scalar()))
        # the singular points (HeavyTop at theta = 0 or pi, Kepler at r = 0) are
        # drawn on purpose: there rhs/jacobian/energy raise (SingularityError,
        # NonFiniteError) rather than return garbage or NaN
        if isinstance(y, np.ndarray) and y.dtype.kind in "biuf" and y.shape[:1] == (dim,) \
                and data.draw(st.booleans()):
            y = y.astype(float)
            q = y.reshape(dim, -1)
            if name == "HeavyTop" and q.shape[1]:
                q[1, 0] = data.draw(st.sampled_from([0.0, np.pi]))
            if name == "Kepler" and q.shape[1]:
                q[:2, 0] = 0.0
        _run(f"{name}.rhs", scene.rhs, t, y, check=_shape(*np.shape(y)) if isinstance(
            y, np.ndarray) and y.shape[:1] == (dim,) and y.dtype.kind in "biuf" else None)
        _run(f"{name}.jacobian", scene.jacobian, t, y)
        _run(f"{name}.energy", scene.energy, y)
        _run(f"{name}.replace", scene.replace, **{data.draw(st.sampled_from(
            list(scene.params) + ["nope"])): data.draw(_scalar())})

    scenes()


def fuzz_inertia():
    import mechpy as mp
    I = mp.inertia

    @_settings()
    @given(st.data())
    def point_masses(data):
        n = data.draw(st.integers(0, 5))
        _run("inertia.point_masses", I.point_masses, data.draw(A(n, pos=True)),
             data.draw(A(n, 3)), data.draw(st.one_of(st.just((0, 0, 0)), A(3))), strict=True)

    shapes = {"sphere": ["radius"], "shell": ["radius"], "box": ["a", "b", "c"],
              "cube": ["side"], "cylinder": ["radius", "height"], "cone": ["radius", "height"],
              "hemisphere": ["radius"], "rod": ["length"], "disk": ["radius"],
              "ellipsoid": ["a", "b", "c"]}

    @_settings()
    @given(st.data())
    def solid(data):
        shape = data.draw(st.sampled_from(sorted(shapes) + ["blob", 3]))
        dims = {d: data.draw(_pos()) for d in shapes.get(shape, ["radius"])}
        if data.draw(st.integers(0, 5)) == 0:
            dims["bogus"] = 1.0
        body = _run("inertia.solid", I.solid, shape, data.draw(_pos()), **dims)
        if body is not None:
            _run("Body.principal", body.principal)
            _run("Body.inertia_about", body.inertia_about, data.draw(A(3)), check=_shape(3, 3))
            _run("Body.moved", body.moved, data.draw(A(3)))
            _run("Body.rotated", body.rotated, data.draw(A(3, 3)))
            _run("Body.__add__", lambda: body + body.moved((1.0, 0.0, 0.0)))

    @_settings()
    @given(st.data())
    def mesh(data):
        V, F = I.uv_sphere(1.0, 4, 6)
        kind = data.draw(st.integers(0, 3))
        if kind == 0:
            V = data.draw(A(*V.shape))
        elif kind == 1:
            F = data.draw(st.one_of(A(*F.shape), st.just(F[::-1] + 1), st.just(F[:, ::-1]),
                                    st.just(F[1:]), st.just(F * 0)))
        elif kind == 2:
            V = V * data.draw(st.sampled_from([1e-100, 1e100, 0.0, -1.0]))
        kw = {}
        if data.draw(st.booleans()):
            kw[data.draw(st.sampled_from(["density", "mass"]))] = data.draw(_pos())
        _run("inertia.mesh", I.mesh, V, F, **kw)

    @_settings()
    @given(st.data())
    def density_grid(data):
        shape = tuple(data.draw(st.lists(st.integers(0, 4), min_size=3, max_size=3)))
        _run("inertia.density_grid", I.density_grid, data.draw(A(*shape, pos=True)),
             data.draw(st.one_of(A(3, pos=True), _pos())),
             data.draw(st.one_of(st.just((0, 0, 0)), A(3))))

    @_settings(2 * EXAMPLES)
    @given(st.data())
    def tensors(data):
        lead = data.draw(st.sampled_from([(), (), (2,), (0,)]))
        J = data.draw(st.one_of(A(*lead, 3, 3), st.builds(
            lambda d: np.diag(d), st.lists(st.floats(0.0, 4.0), min_size=3, max_size=3))))
        _run("inertia.shift", I.shift, J, data.draw(_pos()), data.draw(A(3)),
             to=data.draw(st.sampled_from(["point", "com", "x"])))
        _run("inertia.principal_axes", I.principal_axes, J)
        _run("inertia.classify", I.classify, J)
        _run("inertia.angular_momentum", I.angular_momentum, J, data.draw(A(*lead, 3)))
        _run("inertia.kinetic_energy", I.kinetic_energy, J, data.draw(A(*lead, 3)))
        sig = J
        _run("stress.principal", mp.stress.principal, sig)
        _run("stress.pressure", mp.stress.pressure, sig)
        _run("stress.von_mises", mp.stress.von_mises, sig)
        _run("stress.max_shear", mp.stress.max_shear, sig)

    point_masses()
    solid()
    mesh()
    density_grid()
    tensors()


def fuzz_rotation():
    import mechpy as mp
    R = mp.rotation

    @_settings(2 * EXAMPLES)
    @given(st.data())
    def rotation(data):
        lead = data.draw(st.sampled_from([(), (3,), (2, 2), (0,)]))
        seq = data.draw(_seq())
        passive = data.draw(st.sampled_from([True, False, 1, "x"]))
        ang = data.draw(A(*lead, 3))
        out = _run("rotation.euler_matrix", R.euler_matrix, ang, seq=seq, passive=passive)
        if out is not None and isinstance(ang, np.ndarray) and ang.dtype.kind in "biuf":
            assert out.shape == ang.shape[:-1] + (3, 3)
        phi, th, psi = (data.draw(st.one_of(_scalar(), A(*lead))) for _ in range(3))
        _run("rotation.euler_matrix(phi, theta, psi)", R.euler_matrix, phi, th, psi, seq=seq)
        M = data.draw(st.one_of(A(*lead, 3, 3), st.just(np.eye(3)),
                                st.just(R.euler_matrix([0.3, 0.0, 0.2]))))
        _run("rotation.euler_angles", R.euler_angles, M, seq=seq, passive=passive)
        _run("rotation.quat_from_matrix", R.quat_from_matrix, M)
        q = data.draw(A(*lead, 4))
        _run("rotation.matrix_from_quat", R.matrix_from_quat, q)
        _run("rotation.quat_multiply", R.quat_multiply, q, data.draw(A(*lead, 4)))
        _run("rotation.quat_normalize", R.quat_normalize, q)
        _run("rotation.quat_from_euler", R.quat_from_euler, ang, seq=seq)
        _run("rotation.euler_from_quat", R.euler_from_quat, q, seq=seq)
        frame = data.draw(st.sampled_from(["body", "space", "x"]))
        _run("rotation.angular_velocity", R.angular_velocity, ang, data.draw(A(*lead, 3)),
             seq=seq, frame=frame)
        _run("rotation.euler_rates", R.euler_rates, ang, data.draw(A(*lead, 3)), seq=seq,
             frame=frame)

    rotation()


def fuzz_modes_rigid():
    import mechpy as mp

    @_settings(2 * EXAMPLES)
    @given(st.data())
    def modes(data):
        n = data.draw(st.integers(0, 5))
        kind = data.draw(st.integers(0, 2))
        if kind == 0:
            K, M = mp.modes.chain(max(n, 1))
            K = K * data.draw(st.sampled_from([1.0, -1.0, 1e-100, 1e100, 0.0]))
        else:
            K = data.draw(A(n, n))
            M = data.draw(st.one_of(st.none(), A(n, n), A(n, pos=True)))
        method = data.draw(st.sampled_from(["auto", "auto", "dense", "chain", "x"]))
        m = _run("modes.normal_modes", mp.modes.normal_modes, K, M, method=method)
        if m is not None:
            nn = m.omega.size
            assert m.vectors.shape == (nn, nn)
            t = data.draw(A(3))
            _run("Modes.evolve", m.evolve, data.draw(A(nn)), data.draw(A(nn)), t,
                 check=_shape(len(t), nn) if np.ndim(t) == 1 else None, strict=True)
            _run("Modes.coordinates", m.coordinates, data.draw(A(nn)))
        _run("modes.chain", mp.modes.chain, data.draw(st.one_of(st.integers(-1, 6), _scalar())),
             data.draw(_pos()), data.draw(_pos()),
             ends=data.draw(st.sampled_from(["fixed", "free", "periodic", "x"])), strict=True)
        _run("modes.dispersion_diatomic", mp.modes.dispersion_diatomic, data.draw(_pos()),
             data.draw(_pos()), data.draw(_pos()), data.draw(_pos()), data.draw(A(3)),
             strict=True)
        _run("modes.dispersion", mp.modes.dispersion, data.draw(_pos()), data.draw(_pos()),
             data.draw(_pos()), data.draw(A(4)))

    @_settings(2 * EXAMPLES)
    @given(st.data())
    def rigid(data):
        I3 = data.draw(A(3, pos=True))
        w = data.draw(A(3))
        t = data.draw(st.one_of(A(data.draw(st.integers(0, 5))), _scalar()))
        out = _run("rigid.free_rotation", mp.rigid.free_rotation, I3, w, t)
        if out is not None and np.ndim(t) == 1:
            assert out.shape == (np.size(t), 3)
        _run("rigid.flip_period", mp.rigid.flip_period, I3, w,
             inf_ok=True)  # documented: inf for a steady rotation or on the separatrix
        _run("rigid.nutation_bounds", mp.rigid.nutation_bounds,
             *[data.draw(_pos()) for _ in range(9)])

    modes()
    rigid()


def fuzz_phase_frames_variational():
    import mechpy as mp
    scenes = [mp.scenes.Pendulum(), mp.scenes.VanDerPol(), mp.scenes.Duffing(-1.0, 1.0),
              mp.scenes.Kepler(), lambda t, y: -np.asarray(y), None]

    @_settings(EXAMPLES)
    @given(st.data())
    def phase(data):
        sys_ = data.draw(st.sampled_from(scenes))
        n = data.draw(st.integers(0, 4))
        X = data.draw(A(n, n))
        _run("phase.vector_field", mp.phase.vector_field, sys_, X, data.draw(A(n, n)))
        _run("phase.fixed_points", mp.phase.fixed_points, sys_,
             data.draw(st.one_of(A(2, 2), A(4), _scalar())), seeds=data.draw(
                 st.one_of(st.integers(1, 3), _scalar())))
        y0 = data.draw(A(2))
        _run("phase.poincare", mp.phase.poincare, sys_, y0, data.draw(_pos()),
             data.draw(st.one_of(st.integers(-1, 4), _scalar())))
        _run("phase.lyapunov", mp.phase.lyapunov, sys_, y0,
             data.draw(st.one_of(st.floats(0.1, 3.0), _scalar())))

    @_settings(EXAMPLES)
    @given(st.data())
    def frames(data):
        lead = data.draw(st.sampled_from([(), (3,)]))
        _run("frames.fictitious", mp.frames.fictitious, data.draw(A(3)), data.draw(A(*lead, 3)),
             data.draw(A(*lead, 3)), data.draw(A(3)))
        for f in (mp.frames.to_rotating, mp.frames.from_rotating):
            _run(f"frames.{f.__name__}", f, data.draw(A(*lead, 3)), data.draw(A(*lead, 3)),
                 data.draw(A(3)), data.draw(st.one_of(_scalar(), A(*lead))))
        _run("frames.foucault_period", mp.frames.foucault_period, data.draw(_scalar()),
             inf_ok=True)  # documented: infinite at the equator

    @_settings(EXAMPLES)
    @given(st.data())
    def variational(data):
        n = data.draw(st.one_of(st.integers(3, 40), _scalar()))
        _run("variational.brachistochrone", mp.variational.brachistochrone, data.draw(_pos()),
             data.draw(_pos()), n=n, max_iter=data.draw(st.integers(1, 50)))
        _run("variational.catenary", mp.variational.catenary, data.draw(_scalar()),
             data.draw(_scalar()), data.draw(_pos()), n=n, max_iter=data.draw(
                 st.integers(1, 50)))
        scene = data.draw(st.sampled_from([mp.scenes.Pendulum(), mp.scenes.Kepler(),
                                           lambda q, qd, t=0.0: 0.5 * qd ** 2 - q ** 2,
                                           lambda q, qd, t=0.0: 1 / 0, None]))
        try:
            _run("variational.stationary_path", mp.variational.stationary_path, scene,
                 data.draw(_scalar()), data.draw(_scalar()), data.draw(_pos()), n=n,
                 max_iter=data.draw(st.integers(1, 30)))
            _run("variational.variational_integrate", mp.variational.variational_integrate,
                 scene, (0.0, data.draw(st.one_of(st.floats(0.1, 3.0), _scalar()))),
                 data.draw(_scalar()), data.draw(_scalar()),
                 data.draw(st.one_of(st.floats(0.01, 0.5), _scalar())))
        except ZeroDivisionError:  # the user's Lagrangian raised: propagated unchanged
            pass

    phase()
    frames()
    variational()


def fuzz_core():
    """The C entry points called directly with arbitrary arguments."""
    import mechpy
    core = mechpy._core
    fns = sorted(n for n in dir(core) if not n.startswith("_") and callable(getattr(core, n))
                 and not isinstance(getattr(core, n), type))
    arg = st.one_of(A(3), A(2, 3), A(1, 3, 3), A(0), A(4), A(2, 9), _scalar(),
                    st.sampled_from(["ZXZ", "pendulum", "rhs", "dop853", ("scene", "pendulum",
                                                                          np.ones(5))]))

    @_settings(6 * EXAMPLES)
    @given(st.sampled_from(fns), st.lists(arg, max_size=6))
    def core_args(name, args):
        COUNTS[f"_core.{name}"] = COUNTS.get(f"_core.{name}", 0) + 1
        try:
            getattr(core, name)(*args)
        except (TypeError, ValueError, OverflowError, np.linalg.LinAlgError,
                mechpy.errors.MechpyError):
            pass

    core_args()


def fuzz_properties():
    """Properties that catch whole classes of wrong answers (not only crashes)."""
    import mechpy as mp
    from mechpy import rotation as R

    @_settings(EXAMPLES)
    @given(st.data())
    def vector_field_pointwise(data):
        # a callable is evaluated point by point: A @ y on any grid is the linear field
        A_ = np.array(data.draw(st.lists(st.floats(-3, 3), min_size=4, max_size=4))).reshape(2, 2)
        shape = tuple(data.draw(st.lists(st.integers(1, 4), min_size=1, max_size=3)))
        X = np.array(data.draw(st.lists(st.floats(-5, 5), min_size=int(np.prod(shape)),
                                        max_size=int(np.prod(shape))))).reshape(shape)
        Y = X[::-1].copy() if X.ndim else X
        COUNTS["phase.vector_field(A @ y)"] = COUNTS.get("phase.vector_field(A @ y)", 0) + 1
        U, V = mp.phase.vector_field(lambda t, y: A_ @ y, X, Y)
        np.testing.assert_allclose(U, A_[0, 0] * X + A_[0, 1] * Y, rtol=1e-14, atol=1e-13)
        np.testing.assert_allclose(V, A_[1, 0] * X + A_[1, 1] * Y, rtol=1e-14, atol=1e-13)

    @_settings(2 * EXAMPLES)
    @given(st.data())
    def euler_near_lock(data):
        # every angle comes back while the distance from lock has a normal sine
        seq = data.draw(st.sampled_from(R.SEQUENCES))
        passive = data.draw(st.booleans())
        proper = seq[0].lower() == seq[2].lower()
        k = data.draw(st.integers(0, 307 if proper else 15))
        dist = data.draw(st.floats(1.0, 9.99)) * 10.0 ** -k
        phi, psi = data.draw(st.floats(-3.1, 3.1)), data.draw(st.floats(-3.1, 3.1))
        mid = dist if proper else data.draw(st.sampled_from([1.0, -1.0])) * (np.pi / 2 - dist)
        a = np.array([phi, mid, psi])
        COUNTS["rotation.euler_angles(near lock)"] = \
            COUNTS.get("rotation.euler_angles(near lock)", 0) + 1
        with warnings.catch_warnings():
            warnings.simplefilter("error", R.GimbalLockWarning)
            b = R.euler_angles(R.euler_matrix(a, seq=seq, passive=passive), seq, passive)
        d = np.angle(np.exp(1j * (b - a)))
        # phi and psi come from pairs of entries sharing the factor sin or cos of mid, so
        # its rounding cancels; mid is relative to round-off near 0, absolute near pi/2
        assert abs(d[1]) <= (4e-15 * abs(mid) if proper else 4e-16), (seq, a, b)
        assert abs(d[0]) <= 4e-15 and abs(d[2]) <= 4e-15, (seq, a, b)

    @_settings(EXAMPLES)
    @given(st.data())
    def shift_to_com_is_physical(data):
        # the way back from a point is a mass distribution's tensor, or a ValueError
        m = np.array(data.draw(st.lists(st.floats(0.1, 3.0), min_size=1, max_size=4)))
        x = np.array(data.draw(st.lists(st.floats(-3, 3), min_size=3 * m.size,
                                        max_size=3 * m.size))).reshape(-1, 3)
        p = np.array(data.draw(st.lists(st.floats(-5, 5), min_size=3, max_size=3)))
        claim = data.draw(st.floats(0.0, 3.0))     # 1: the true offset; else a wrong one
        com = m @ x / m.sum()
        Ip = mp.inertia.point_masses(m, x, p)
        COUNTS["inertia.shift(to=com)"] = COUNTS.get("inertia.shift(to=com)", 0) + 1
        try:
            out = mp.inertia.shift(Ip, m.sum(), claim * (p - com), to="com")
        except ValueError:
            assert claim > 1.0                     # only a too-large offset is impossible
            return
        w = np.linalg.eigvalsh(out)
        tol = 1e-12 * max(1.0, np.abs(Ip).max())
        assert w[0] >= -tol and w[0] + w[1] >= w[2] - tol

    @_settings(EXAMPLES)
    @given(st.data())
    def nutation_bounds_are_roots(data):
        I1, I3 = data.draw(st.floats(0.1, 2.0)), data.draw(st.floats(0.05, 2.0))
        M, g, l = 1.0, 9.81, data.draw(st.floats(0.01, 0.5))
        th = data.draw(st.floats(0.01, 3.13))
        thd = data.draw(st.sampled_from([0.0, 1e-9, 1e-4, 0.3]))
        w3 = data.draw(st.floats(1.0, 300.0))
        c = np.cos(th)
        disc = (I3 * w3) ** 2 - 4 * I1 * c * M * g * l
        ph = 2 * M * g * l / (I3 * w3 + np.sqrt(disc)) if disc >= 0 else 0.5
        ph *= 1.0 + data.draw(st.sampled_from([0.0, 1e-12, -1e-9, 1e-6, 0.1]))
        ps = w3 - ph * c
        COUNTS["rigid.nutation_bounds(property)"] = \
            COUNTS.get("rigid.nutation_bounds(property)", 0) + 1
        lo, hi = mp.rigid.nutation_bounds(I1, I3, M, g, l, th, thd, ph, ps)
        assert 0.0 <= lo <= th <= hi <= np.pi
        a = I3 * w3 / I1
        b = (I1 * ph * np.sin(th) ** 2 + I3 * w3 * c) / I1
        beta = 2 * M * g * l / I1
        alpha = thd ** 2 + ph ** 2 * np.sin(th) ** 2 + beta * c
        for u in (np.cos(lo), np.cos(hi)):
            f = (1 - u * u) * (alpha - beta * u) - (b - a * u) ** 2
            scale = max(alpha, beta, b * b, a * a, 1.0)
            assert abs(f) <= 1e-9 * scale, (u, f)

    vector_field_pointwise()
    euler_near_lock()
    shift_to_com_is_physical()
    nutation_bounds_are_roots()


GROUPS = {
    "integrate": fuzz_integrate,
    "scenes": fuzz_scenes,
    "inertia": fuzz_inertia,
    "rotation": fuzz_rotation,
    "modes_rigid": fuzz_modes_rigid,
    "phase_frames_variational": fuzz_phase_frames_variational,
    "properties": fuzz_properties,
    "core": fuzz_core,
}


def main(argv):
    import faulthandler
    faulthandler.enable()
    for group in argv:
        print(f"FUZZ-BEGIN {group}", flush=True)
        GROUPS[group]()
    print("FUZZ-COUNTS " + json.dumps(COUNTS), flush=True)
    return 0


# --------------------------------------------------------------------------- #
# The tests (parent side): each group in a child interpreter
# --------------------------------------------------------------------------- #

def _child_env():
    import mechpy
    env = dict(os.environ)
    root = str(Path(mechpy.__file__).resolve().parent.parent)  # the mechpy under test
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env["MPLBACKEND"] = "Agg"
    return env


@pytest.mark.parametrize("group", list(GROUPS))
def test_fuzz(group, tmp_path):
    pytest.importorskip("hypothesis")
    r = subprocess.run([sys.executable, str(HERE / "test_fuzz.py"), group], cwd=tmp_path,
                       env=_child_env(), capture_output=True, text=True, timeout=600)
    tail = (r.stdout[-4000:] + "\n" + r.stderr[-8000:]).strip()
    assert r.returncode == 0, f"fuzz group {group!r} failed (return code {r.returncode}):\n{tail}"
    line = [s for s in r.stdout.splitlines() if s.startswith("FUZZ-COUNTS ")]
    assert line, tail
    counts = json.loads(line[-1][len("FUZZ-COUNTS "):])
    assert counts and min(counts.values()) > 0
    print(f"\n{group}: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))


# --------------------------------------------------------------------------- #
# Regressions: the bugs the fuzzing found, each pinned by its failing example
# --------------------------------------------------------------------------- #

def test_huge_python_int_is_a_value_error():
    import mechpy as mp  # was OverflowError from float(10**400) in as_scalar
    with pytest.raises(ValueError, match="mass"):
        mp.inertia.solid("sphere", 10 ** 400, radius=1.0)
    with pytest.raises(ValueError, match="mass"):
        mp.modes.chain(3, mass=10 ** 400)


def test_solid_overflow_is_a_value_error():
    import mechpy as mp  # was OverflowError from M * side**2 in Python floats
    with pytest.raises(ValueError, match="overflows"):
        mp.inertia.solid("cube", 1e300, side=1e300)
    assert mp.inertia.solid("cube", 6.0, side=1.0).inertia[0, 0] == 1.0  # M s^2 / 6


def test_dispersion_at_q0_with_tiny_mass_is_zero():
    import mechpy as mp  # was sqrt(k/m) = inf times sin(0) = NaN
    w = mp.modes.dispersion(5e-324, 1.0, 1.0, [0.0, 0.5])
    assert w[0] == 0.0 and np.isfinite(w[1])
    assert w[1] == pytest.approx(2 * math.sin(0.25) / math.sqrt(5e-324), rel=1e-12)


def test_brachistochrone_exact_cycloid_for_a_shallow_drop():
    import mechpy as mp  # th rounds to 2 pi: a = Y / (1 - cos th) was inf, y_exact NaN
    r = mp.variational.brachistochrone(1.0, 1.8e-191, n=4, max_iter=1)
    assert np.all(np.isfinite(r.y_exact)) and np.isfinite(r.time_exact)
    # x_end = a (th - sin th) with th -> 2 pi: a -> x_end / (2 pi)
    assert r.radius == pytest.approx(1.0 / (2 * math.pi), rel=1e-12)
    assert r.time_exact == pytest.approx(2 * math.pi * math.sqrt(r.radius / 9.81), rel=1e-12)


def test_python_int_beyond_int64_names_the_argument():
    import mechpy as mp  # was OverflowError "Python int too large to convert to C long"
    P = mp.scenes.Pendulum()
    with pytest.raises(ValueError, match="skip"):
        mp.phase.poincare(P, [0.1, 0.0], 1.0, 3, skip=10 ** 25)
    with pytest.raises(ValueError, match="skip"):
        mp.phase.bifurcation(P, "damping", [0.1], [0.1, 0.0], 1.0, 3, 2 ** 64)
    with pytest.raises(ValueError, match="N"):
        mp.modes.chain(2 ** 63)
    with pytest.raises(ValueError, match="n_lon"):
        mp.inertia.uv_sphere(1.0, 4, 2 ** 70)


def test_overflow_is_an_error_not_inf_or_nan():
    import mechpy as mp
    from mechpy.errors import NonFiniteError
    # was [0, nan, 0, ...]: 1e300 * (1e200)^2
    with pytest.raises(NonFiniteError, match="point_masses.*overflow"):
        mp.inertia.point_masses([1e300], [[1e200, 0.0, 0.0]])
    with pytest.raises(NonFiniteError, match="overflow"):
        mp.inertia.point_masses([1.0], [[0.0, 1e200, 0.0]])
    # was K with inf on the diagonal (1e308 + 1e308)
    with pytest.raises(ValueError, match="spring"):
        mp.modes.chain(3, spring=1e308)
    with pytest.raises(ValueError, match="springs"):
        mp.modes.chain(2, springs=[1.0, 1.7e308, 1.7e308])
    assert np.isfinite(mp.modes.chain(3, spring=8e307)[0]).all()   # 1.6e308 still fits
    # was OverflowError (1/m1)**2 in Python floats, or inf frequencies
    with pytest.raises(NonFiniteError, match="dispersion_diatomic"):
        mp.modes.dispersion_diatomic(5e-324, 1.0, 1e300, 1.0, [0.5])   # sqrt(k/m) ~ 4e311
    # masses that only overflowed the intermediate 1/m^2 now give the closed form; with
    # r = m1/m2 = 1e-200 the O(r) terms vanish: optical sqrt(2k/m1), acoustic sqrt(2k/m2)|sin|
    ac, op = mp.modes.dispersion_diatomic(1e-200, 1.0, 1.0, 1.0, [0.5, np.pi])
    np.testing.assert_allclose(op, np.sqrt(2e200), rtol=1e-15)
    np.testing.assert_allclose(ac, np.sqrt(2.0) * np.abs(np.sin([0.25, np.pi / 2])),
                               rtol=1e-15)
    ac, op = mp.modes.dispersion_diatomic(1e-300, 1.0, 1e300, 1.0, [np.pi])  # was OverflowError
    np.testing.assert_allclose([ac[0], op[0]], [np.sqrt(2) * 1e150, np.sqrt(2) * 1e300],
                               rtol=1e-15)
    # was NaN: cos(omega t) at omega t = inf
    m = mp.modes.normal_modes(*mp.modes.chain(3))
    with pytest.raises(NonFiniteError, match="t"):
        m.evolve([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1e308)
    q = m.evolve([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], 1e300)      # omega t finite: exact
    assert np.isfinite(q).all()
    free = mp.modes.normal_modes(*mp.modes.chain(2, ends="free"))
    with pytest.raises(NonFiniteError):                       # zero mode drifting past 1e308
        free.evolve([0.0, 0.0], [1e10, 1e10], 1e300)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
