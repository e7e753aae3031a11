"""The array-layout rule (mechpy's package docstring, README "Conventions"),
checked on every public callable of every public module.

1. States follow SciPy: state axis first, batch/time axes after it; a function
   of states y (n, ...) returns (p, ...) or (...), t scalar or broadcast.
2. Everything else is a NumPy stack: batch axes first, component axes last; a
   series at times t is (len(t), n), a set of points (n_points, dim).

Every public callable is in TABLE with its clause and a case that calls it
on a scalar (batch ``()``) and on a batch (``(2, 3)``, two axes so that a
flattening or transposing mistake shows), and returns (label, result,
expected shape) triples.  A public name missing from TABLE fails the test:
a new function cannot be added without being classified here.
"""
from __future__ import annotations

import functools
import inspect
import types

import numpy as np
import pytest

import mechpy as mp

BATCHES = [(), (2, 3)]
RNG = np.random.default_rng(7)


def _r(*shape, lo=0.2, hi=0.9):
    return RNG.uniform(lo, hi, shape)


def _spd(b):
    """A stack of diagonal-dominant symmetric 3x3 matrices, shape b + (3, 3)."""
    a = _r(*b, 3, 3, lo=-0.2, hi=0.2)
    return a + np.swapaxes(a, -1, -2) + np.diag([1.0, 2.0, 3.5])


def _t(b):
    """A time, scalar or of shape b."""
    return 0.4 if b == () else _r(*b)


# ------------------------------------------------------------------ cases
# clause 1: functions of states (state axis first)

def _scene_case(scene, b, extra=()):
    n = scene.dim
    y = _r(n, *b)
    out = [("rhs", scene.rhs(0.3, y), (n,) + b),
           ("jacobian", scene.jacobian(0.3, y), (n, n) + b),
           ("energy", scene.energy(y), b)]
    for name, p in extra:
        out.append((name, getattr(scene, name)(y), (p,) + b if p else b))
    return out


_ROCKET = mp.scenes.Rocket(2500.0, 10.0, 1000.0, 200.0, g=9.81)


def _scene_members(b):
    """Scene methods and properties beyond the state functions."""
    if b != ():
        return [("ensemble_params", mp.scenes.Pendulum().ensemble_params(3, g=_r(3)), (3, 5))]
    S = mp.scenes
    c = S.SpringChain([1.0, 2.0, 1.5], [1.0, 2.0, 1.0, 3.0])
    K, M = c.matrices()
    u = S.SpringChain.uniform(4)
    return [("Pendulum.period", S.Pendulum().period(0.5), ()),
            ("Kepler.initial_state", S.Kepler().initial_state(0.5), (4,)),
            ("Foucault.precession_rate", S.Foucault(45.0, 10.0).precession_rate, ()),
            ("RigidBody.initial_state", S.RigidBody().initial_state([1.0, 2.0, 3.0]), (3,)),
            ("RigidBody.initial_state, orientation",
             S.RigidBody(orientation=True).initial_state([1.0, 2.0, 3.0]), (7,)),
            ("RigidBody.moments", S.RigidBody().moments, (3,)),
            ("SpringChain.initial_state", c.initial_state(_r(3)), (6,)),
            ("SpringChain.matrices K", K, (3, 3)), ("M", M, (3, 3)),
            ("SpringChain.modes", c.modes().vectors, (3, 3)),
            ("SpringChain.uniform", u.rhs(0.0, _r(8)), (8,)),
            ("SpringChain.ensemble_params", c.ensemble_params(2), (2, 11)),
            ("replace", S.Pendulum().replace(g=1.0).rhs(0.0, _r(2)), (2,)),
            ("Rocket.initial_state", _ROCKET.initial_state(), (3,)),
            ("Rocket.burnout_time", _ROCKET.burnout_time, ()),
            ("Rocket.fly", _ROCKET.fly((0.0, 30.0)).y[:, -1], (3,))]


def _scenes(b):
    S = mp.scenes
    return _scene_members(b) + (_scene_case(S.Pendulum(), b) + _scene_case(S.VanDerPol(), b)
            + _scene_case(S.Duffing(-1.0, 1.0, 0.2, 0.3, 1.2), b)
            + _scene_case(S.Kepler(), b) + _scene_case(S.RestrictedThreeBody(), b)
            + _scene_case(S.Foucault(45.0, 10.0), b)
            + _scene_case(S.RigidBody((1.0, 2.0, 3.0)), b, [("angular_momentum", 3)])
            + _scene_case(S.RigidBody((1.0, 2.0, 3.0), orientation=True), b,
                          [("angular_momentum", 3)])
            + _scene_case(S.HeavyTop(1.0, 2.0, 1.0), b, [("p_psi", 0), ("p_phi", 0)])
            + _scene_case(S.SpringChain([1.0, 2.0, 1.5], [1.0, 2.0, 1.0, 3.0]), b,
                          [("mode_energies", 3), ("momentum", 0)]))


@functools.lru_cache(maxsize=None)
def _compiled():
    """A bead on a vertical circle in Cartesian coordinates: 2 coordinates,
    one constraint (so momenta, constraint_forces and multipliers exist)."""
    import sympy as sp
    q = mp.coordinates("x z")
    t = sp.Symbol("t")
    x, z = q
    m, g = sp.symbols("m g")
    L = m / 2 * (x.diff(t) ** 2 + z.diff(t) ** 2) - m * g * z
    return mp.lagrangian(L, q, params={"m": 1.0, "g": 9.81}, constraints=[x ** 2 + z ** 2 - 1])


@functools.lru_cache(maxsize=None)
def _compiled_free():
    """A pendulum in its angle: 1 coordinate, no constraint."""
    import sympy as sp
    (th,) = mp.coordinates("th")
    t = sp.Symbol("t")
    g = sp.Symbol("g")
    return mp.lagrangian(th.diff(t) ** 2 / 2 + g * sp.cos(th), [th], params={"g": 9.81})


def _lagrangian_case(b):
    sc = _compiled()
    y = _r(4, *b)
    free = _compiled_free()
    extra = [] if b != () else [
        ("small_oscillations", free.small_oscillations([0.0]).vectors, (1, 1)),
        ("cyclic", np.array(free.cyclic, dtype=object), (0,)),
        ("replace", free.replace(g=1.0).rhs(0.0, _r(2)), (2,))]
    return extra + _scene_case(sc, b, [("momenta", 2)]) + [
        ("constraint_forces", sc.constraint_forces(0.3, y), (2,) + b),
        ("multipliers", sc.multipliers(0.3, y), (1,) + b)]


def _equations_case(b):
    import sympy as sp
    y = mp.coordinates("u w")
    mu = sp.Symbol("mu")
    sc = mp.equations([y[1], -y[0] + mu * y[1]], y, params={"mu": 0.1},
                      energy=(y[0] ** 2 + y[1] ** 2) / 2)
    return _scene_case(sc, b)


@functools.lru_cache(maxsize=None)
def _mechanics_disc():
    from mechpy.symbolic.models import rolling_disc
    return mp.mechanics(*rolling_disc())


def _mechanics_case(b):
    sc = _mechanics_disc()
    y = _r(10, *b)
    extra = [] if b != () else [("linearize A", sc.linearize(sc.project(_r(10)))[0], (8, 8))]
    return extra + _scene_case(sc, b) + [("constraint_residual", sc.constraint_residual(y),
                                          (2,) + b)]


def _solve_case(b):
    s = mp.solve(mp.scenes.Pendulum(), (0, 1), [0.3, 0.0], t_eval=np.linspace(0, 1, 5),
                 dense_output=True)
    tt = 0.5 if b == () else _r(*b)          # times of any shape: (n, *t.shape)
    return [("Solution.t", s.t, (5,)), ("Solution.y", s.y, (2, 5)),
            ("Solution.sol", s.sol(tt), (2,) + np.shape(tt))]


def _solve_many_case(b):
    e = mp.solve_many(mp.scenes.Pendulum(), (0, 1), _r(3, 2), t_eval=np.linspace(0, 1, 5),
                      threads=1)
    return [("t", e.t, (5,)), ("y", e.y, (3, 2, 5)), ("success", e.success, (3,)),
            ("status", e.status, (3,)), ("nfev", e.nfev, (3,))]


def _second_order_case(b):
    so = mp.SecondOrder(lambda t, q: -q)
    s = mp.solve(so, (0, 1), [1.0, 0.5, 0.0, 0.0], method="verlet", h=0.1)
    return [("y", s.y, (4, s.t.size))]


def _stationary_path_case(b):
    V = mp.variational
    p1 = V.stationary_path(mp.scenes.Pendulum(), 0.1, 0.2, 1.0, 10)
    p3 = V.stationary_path(mp.scenes.HeavyTop(1.0, 2.0, 1.0), [0, 1, 0], [0.1, 1, 0.2], 0.1, 10)
    return [("q 1-d", p1.q, (11,)), ("q", p3.q, (3, 11)), ("p", p3.p, (3, 11)),
            ("qdot", p3.qdot, (3, 11)), ("t", p3.t, (11,))]


def _stationary_paths_case(b):
    if b != ():        # two coordinates: q (d, n + 1), one row per coordinate
        paths = mp.variational.stationary_paths(
            lambda q, v: 0.5 * np.sum(v * v, 0) - 0.5 * np.sum(q * q, 0),
            [0.1, 0.2], [0.3, -0.1], 1.0, 40, velocities=[[0.0, 0.0], [0.5, 0.5]])
        return [(f"stationary_paths[{i}].q, d = 2", p.q, (2, 41)) for i, p in enumerate(paths)]
    paths = mp.variational.stationary_paths(mp.scenes.Pendulum(g=1.0), 0.0, 0.0, 4.5, 40)
    return [(f"stationary_paths[{i}].q", p.q, (41,)) for i, p in enumerate(paths)]


def _variational_integrate_case(b):
    V = mp.variational
    tr = V.variational_integrate(mp.scenes.HeavyTop(1.0, 2.0, 1.0), (0, 0.5), [0, 1, 0],
                                 [0, 0, 20.0], 0.1)
    m = tr.t.size
    return [("q", tr.q, (3, m)), ("p", tr.p, (3, m)), ("qdot", tr.qdot, (3, m)),
            ("energy", tr.energy, (m,))]


def _lagrangian_fn_case(b):
    V = mp.variational
    L1 = V.lagrangian(mp.scenes.Pendulum())
    L3 = V.lagrangian(mp.scenes.HeavyTop(1.0, 2.0, 1.0))
    return [("L 1-d", L1(_r(*b), _r(*b)), b),
            ("L 3-d", L3(_r(3, *b), _r(3, *b)), b),
            ("L compiled", V.lagrangian(_compiled())(_r(2, *b), _r(2, *b)), b)]


def _momenta_case(b):
    V = mp.variational
    return [("pendulum", V.generalized_momenta(mp.scenes.Pendulum(), _r(*b), _r(*b)), b),
            ("top", V.generalized_momenta(mp.scenes.HeavyTop(1.0, 2.0, 1.0),
                                          _r(3, *b), _r(3, *b)), (3,) + b),
            ("callable", V.generalized_momenta(V.CentralForce(), _r(2, *b), _r(2, *b)),
             (2,) + b)]


def _tension_case(b):
    return [("T", mp.variational.pendulum_tension(mp.scenes.Pendulum(), _r(2, *b)), b)]


def _central_force_case(b):
    c = mp.variational.CentralForce()
    return [("L", c(_r(2, *b), _r(2, *b)), b), ("rhs", c.rhs(0.0, _r(4, *b)), (4,) + b),
            ("momenta", c.momenta(_r(4, *b)), (2,) + b)]


def _hoop_case(b):
    h = mp.variational.RotatingHoop()
    y = _r(2, *b)
    return [("L", h(_r(*b), _r(*b)), b), ("rhs", h.rhs(0.0, y), (2,) + b),
            ("jacobi_integral", h.jacobi_integral(y), b),
            ("normal_force, scalar t", h.normal_force(0.3, y), (3,) + b),
            ("normal_force, t per state", h.normal_force(_t(b), y), (3,) + b)]


def _trajectory3d_case(b):
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    path = _r(3, 7)                          # a path (3, m), as sol.y[:3]
    ax = mp.plot.trajectory3d(path)
    drawn = np.array(ax.lines[0].get_data_3d())
    plt.close("all")
    assert np.array_equal(drawn, path)       # rows read as x, y, z: not transposed
    return [("drawn path", drawn, (3, 7))]


def _animate_case(b):
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t = np.linspace(0.0, 1.0, 7)
    y = _r(2, 7)                             # states (n, m), as Solution.y
    anim = mp.plot.animate(mp.scenes.Pendulum(length=1.0), y, t=t)
    ax = anim._fig.axes[0]
    drawn = []
    for i in range(7):
        anim._func(i)
        bob = [a for a in ax.lines if a.get_gid() == "bob"][0]
        drawn.append(np.ravel(bob.get_data()))
    plt.close("all")
    drawn = np.array(drawn).T
    assert np.allclose(drawn, [np.sin(y[0]), -np.cos(y[0])])   # rows read as states
    return [("bob positions", drawn, (2, 7))]


# clause 2: NumPy stacks (batch first, components last)

def _point_masses_case(b):
    I = mp.inertia
    m, r, v = _r(*b, 4), _r(*b, 4, 3), _r(*b, 4, 3)
    return [("point_masses", I.point_masses(m, r), b + (3, 3)),
            ("center_of_mass", I.center_of_mass(m, r), b + (3,)),
            ("total_momentum", I.total_momentum(m, v), b + (3,)),
            ("angular_momentum_about", I.angular_momentum_about(m, r, v), b + (3,))]


def _inertia_case(b):
    I = mp.inertia
    J, w = _spd(b), _r(*b, 3)
    moments, axes = I.principal_axes(J)
    return [("shift", I.shift(J, 2.0, _r(*b, 3)), b + (3, 3)),
            ("principal_axes moments", moments, b + (3,)), ("axes", axes, b + (3, 3)),
            ("angular_momentum", I.angular_momentum(J, w), b + (3,)),
            ("kinetic_energy", I.kinetic_energy(J, w), b)]


def _stress_case(b):
    S = mp.stress
    sig = _spd(b)
    vals, dirs = S.principal(sig)
    return [("principal", vals, b + (3,)), ("directions", dirs, b + (3, 3)),
            ("pressure", S.pressure(sig), b), ("von_mises", S.von_mises(sig), b),
            ("max_shear", S.max_shear(sig), b), ("deviator", S.deviator(sig), b + (3, 3)),
            ("traction", S.traction(sig, _r(*b, 3)), b + (3,))]


def _rotation_case(b):
    R = mp.rotation
    ang = _r(*b, 3)
    M = R.euler_matrix(ang)
    q = R.quat_from_matrix(M)
    return [("euler_matrix (..., 3)", M, b + (3, 3)),
            ("euler_matrix phi, theta, psi", R.euler_matrix(*np.moveaxis(ang, -1, 0)),
             b + (3, 3)),
            ("euler_angles", R.euler_angles(M), b + (3,)),
            ("angular_velocity", R.angular_velocity(ang, _r(*b, 3)), b + (3,)),
            ("euler_rates", R.euler_rates(ang, _r(*b, 3)), b + (3,)),
            ("quat_from_matrix", q, b + (4,)), ("matrix_from_quat", R.matrix_from_quat(q),
                                                  b + (3, 3)),
            ("quat_multiply", R.quat_multiply(q, q), b + (4,)),
            ("quat_normalize", R.quat_normalize(_r(*b, 4)), b + (4,)),
            ("quat_from_euler", R.quat_from_euler(ang), b + (4,)),
            ("euler_from_quat", R.euler_from_quat(q), b + (3,)),
            ("from_scipy(to_scipy)", R.from_scipy(R.to_scipy(M)), b + (3, 3))]


def _free_rotation_case(b):
    t = 0.4 if b == () else np.linspace(0, 1, 6)
    return [("omega(t)", mp.rigid.free_rotation((1.0, 2.0, 3.0), (0.1, 1.0, 0.1), t),
             np.shape(t) + (3,))]


def _modes_case(b):
    m = mp.modes.normal_modes(*mp.modes.chain(3))
    t = 0.4 if b == () else np.linspace(0, 1, 6)
    q = _r(*b, 3)
    qt, vt = m.evolve(_r(3), _r(3), t, velocities=True)
    return [("omega", m.omega, (3,)), ("vectors", m.vectors, (3, 3)),
            ("eigenvalues", m.eigenvalues, (3,)), ("frequencies", m.frequencies, (3,)),
            ("zero_modes", m.zero_modes, (3,)), ("n", np.zeros(m.n), (3,)),
            ("evolve", m.evolve(_r(3), _r(3), t), np.shape(t) + (3,)),
            ("evolve q, velocities", qt, np.shape(t) + (3,)),
            ("evolve v", vt, np.shape(t) + (3,)),
            ("coordinates", m.coordinates(q), b + (3,)),
            ("energy", m.energy(q, _r(*b, 3)), b + (3,))]


def _dispersion_case(b):
    q = _r(*b)
    o1, o2 = mp.modes.dispersion_diatomic(1.0, 2.0, 1.0, 1.0, q)
    return [("dispersion", mp.modes.dispersion(1.0, 1.0, 1.0, q), b),
            ("acoustic", o1, b), ("optical", o2, b)]


def _vector_field_case(b):
    X, Y = _r(*b), _r(*b)
    U, V = mp.phase.vector_field(mp.scenes.Pendulum(), X, Y)
    return [("U", U, b), ("V", V, b)]


def _poincare_case(b):
    d = mp.scenes.Duffing(-1.0, 1.0, 0.3, 0.5, 1.2)
    P = 2 * np.pi / 1.2
    return [("poincare", mp.phase.poincare(d, [1.0, 0.0], P, 7), (7, 2)),
            ("bifurcation", mp.phase.bifurcation(d, "gamma", [0.3, 0.5], [1.0, 0.0], P, 7, 2),
             (2, 7, 2))]


def _frames_case(b):
    F = mp.frames
    w, r, v = _r(*b, 3), _r(*b, 3), _r(*b, 3)
    out = [("fictitious " + k, a, b + (3,)) for k, a in F.fictitious(w, r, v).items()]
    out += [("earth_omega", F.earth_omega(_r(*b, lo=10, hi=80)), b + (3,)),
            ("foucault_period", F.foucault_period(_r(*b, lo=10, hi=80)), b),
            ("eastward_deflection", F.eastward_deflection(_r(*b, lo=10, hi=90), 45.0), b)]
    return out


def _to_rotating_case(b):
    F = mp.frames
    w, r, v = [0.0, 0.0, 1.0], _r(*b, 3), _r(*b, 3)
    out = []
    for name, fn in (("to_rotating", F.to_rotating), ("from_rotating", F.from_rotating)):
        rr, vv = fn(r, v, w, 0.3)                           # batch of vectors, scalar t
        out += [(name + " r", rr, b + (3,)), (name + " v", vv, b + (3,))]
        rr, vv = fn([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], w, _t(b))   # a series at times t
        out += [(name + " r(t)", rr, b + (3,)), (name + " v(t)", vv, b + (3,))]
    return out


def _drift_case(b):
    F = mp.frames
    return [("drift, batch of v0", F.projectile_drift(_r(*b, 3), 1.0, 45.0), b + (3,)),
            ("drift at times t", F.projectile_drift([10.0, 0.0, 10.0], _t(b), 45.0), b + (3,))]


def _logistic_case(b):
    r = _r(*b, lo=2.5, hi=4.0)
    return [("logistic", mp.phase.logistic(r, n=5), b + (5,)),
            ("logistic_bifurcation", mp.phase.logistic_bifurcation([3.2, 3.5, 3.9], n=4),
             (3, 4))]


def _collide_case(b):
    P = mp.particles
    m1, m2, e = _r(*b), _r(*b), _r(*b)
    out = []
    for k, v in enumerate(P.collide(m1, _r(*b), m2, _r(*b), e)):
        out.append((f"collide 1D v{k + 1}'", v, b))
    for k, v in enumerate(P.collide(m1, _r(*b, 3), m2, _r(*b, 3), e, normal=_r(*b, 3))):
        out.append((f"collide 3D v{k + 1}'", v, b + (3,)))
    return out


def _cm_case(b):
    P = mp.particles
    m, v = _r(*b, 4), _r(*b, 4, 3)
    V, u = P.to_cm(m, v)
    V1, u1 = P.to_cm(m, v[..., 0])
    return [("to_cm V", V, b + (3,)), ("to_cm u", u, b + (4, 3)),
            ("from_cm", P.from_cm(V, u), b + (4, 3)),
            ("to_cm 1D V", V1, b), ("to_cm 1D u", u1, b + (4,)),
            ("from_cm 1D", P.from_cm(V1, u1), b + (4,))]


def _constraint_forces_case(b):
    lam, f = mp.variational.constraint_forces(1.0, _r(*b, 3), _r(*b, 1, 3), _r(*b, 1))
    return [("lam", lam, b + (1,)), ("f", f, b + (3,))]


# single objects (not vectorised): one call, the documented shapes

def _single(fn):
    def case(b):
        return fn() if b == () else []
    return case


def _body():
    bd = mp.inertia.solid("box", 2.0, a=1.0, b=2.0, c=3.0)
    moments, axes = bd.principal()
    return [("com", bd.com, (3,)), ("inertia", bd.inertia, (3, 3)),
            ("inertia_about", bd.inertia_about([1.0, 0.0, 0.0]), (3, 3)),
            ("moments", moments, (3,)), ("axes", axes, (3, 3)),
            ("moved", bd.moved([1.0, 0, 0]).com, (3,)),
            ("rotated", bd.rotated(np.eye(3)).inertia, (3, 3)),
            ("density", bd.density, ()),
            ("classify", np.array(bd.classify()), ()),
            ("from_point_masses", mp.inertia.Body.from_point_masses(
                [1.0, 2.0], [[1.0, 0, 0], [0, 1.0, 0]]).inertia, (3, 3))]


def _mesh():
    v, f = mp.inertia.uv_sphere(1.0, 4, 8)
    bd = mp.inertia.mesh(v, f, density=1.0)
    return [("vertices", v, (26, 3)), ("faces", f, (48, 3)), ("inertia", bd.inertia, (3, 3))]


def _grid():
    return [("inertia", mp.inertia.density_grid(np.ones((3, 4, 5)), 0.1).inertia, (3, 3))]


def _classify():
    return [("classify", np.array(mp.inertia.classify(np.diag([1.0, 2.0, 3.0]))), ())]


def _split():
    s = mp.inertia.kinetic_energy_split(_r(4), _r(4, 3), _r(4, 3))
    return [("total", s.total, ()), ("omega", s.omega, (3,))]


def _flip():
    return [("flip_period", mp.rigid.flip_period((1.0, 2.0, 3.0), (0.1, 1.0, 0.1)), ())]


def _nutation():
    lo, hi = mp.rigid.nutation_bounds(1.0, 2.0, 1.0, 9.81, 1.0, 0.5, 0.0, 0.0, 20.0)
    return [("theta_min", lo, ()), ("theta_max", hi, ())]


def _top_rates():
    slow, fast = mp.rigid.steady_precession(1.0, 2.0, 1.0, 9.81, 0.5, 0.3, 200.0)
    body, space = mp.rigid.free_precession([1.0, 1.0, 2.0], [0.1, 0.0, 1.0])
    return [("slow", slow, ()), ("fast", fast, ()), ("body", body, ()), ("space", space, ()),
            ("sleeping", float(mp.rigid.sleeping_top(1.0, 2.0, 1.0, 9.81, 0.5, 200.0)), ())]


def _chain():
    K, M = mp.modes.chain(4)
    return [("K", K, (4, 4)), ("M", M, (4, 4))]


def _triatomic():
    tri = mp.modes.linear_triatomic()
    return [("modes.omega", tri.modes.omega, (tri.modes.n,)), ("omega", tri.omega, (4,)),
            ("wavenumbers", tri.wavenumbers, (4,))]


def _fixed_points():
    fps = mp.phase.fixed_points(mp.scenes.Pendulum(), [(-4.0, 4.0), (-1.0, 1.0)])
    return [("x", fp.x, (2,)) for fp in fps] + [("eigenvalues", fp.eigenvalues, (2,))
                                                for fp in fps]


def _limit_cycle():
    T, A = mp.phase.limit_cycle(mp.scenes.VanDerPol(), [2.0, 0.0])
    return [("period", T, ()), ("amplitude", A, ())]


def _lyapunov():
    return [("exponent", mp.phase.lyapunov(mp.scenes.Duffing(-1.0, 1.0, 0.3, 0.5, 1.2),
                                           [1.0, 0.0], 20.0), ())]


def _tangent_flow():
    sc = mp.scenes.Pendulum(damping=0.2)
    s = mp.sensitivity(sc, (0, 1), [0.3, 0.0], params=("damping",), t_eval=[0.0, 0.5, 1.0])
    t = np.linspace(0.0, 2.0, 9)
    data = mp.solve(sc, (0, 2), [0.3, 0.0], t_eval=t).y[:1]
    r = mp.fit(sc, t, data, {"damping": 0.1}, y0=[0.3, 0.0], observe=0)
    return [("sensitivity y", s.y, (2, 3)), ("sensitivity S", s.S, (2, 3, 3)),
            ("fit cov", r.cov, (1, 1)), ("fit residuals", r.residuals, (1, 9))]


def _phase_tangent():
    duff = mp.scenes.Duffing(-1.0, 1.0, 0.3, 0.5, 1.2)
    T, mu = mp.phase.floquet(mp.scenes.VanDerPol(), [2.0, 0.0])
    return [("lyapunov_spectrum", mp.phase.lyapunov_spectrum(duff, [1.0, 0.0], 5.0), (2,)),
            ("floquet period", T, ()), ("floquet multipliers", mu, (2,))]


def _impact():
    imp = mp.events.impact(0, restitution=0.5)
    sol = mp.solve(mp.scenes.Pendulum(), (0.0, 1.0), [1.0, 0.0], events=imp)
    return [("impact action", imp.action(0.0, [0.0, -1.0]), (2,)),
            ("impact y_events", sol.y_events[0], (1, 2))]


def _drop():
    r, t = mp.frames.drop(100.0, 45.0)
    r2, t2 = mp.frames.projectile([10.0, 0.0, 10.0], 45.0)
    return [("drop r", r, (3,)), ("drop t", t, ()), ("projectile r", r2, (3,)),
            ("projectile t", t2, ())]


def _minimize():
    e = mp.variational.minimize_functional(lambda x, y, yp: np.sqrt(1 + yp ** 2),
                                           (0.0, 1.0), (0.0, 1.0), 10)
    return [("x", e.x, (11,)), ("y", e.y, (11,))]


def _brach():
    c = mp.variational.brachistochrone(1.0, 1.0, n=20)
    k = mp.variational.catenary((0.0, 0.0), (1.0, 0.0), 1.5, n=20)
    return [("x", c.x, (21,)), ("y", c.y, (21,)), ("y_exact", c.y_exact, (21,)),
            ("catenary y", k.y, (21,)), ("catenary y_exact", k.y_exact, (21,))]


def _cyclic():
    c = mp.variational.cyclic_coordinates(mp.variational.CentralForce(), _r(2, 3), _r(2, 3))
    return [("cyclic", np.array(c), (1,))]


def _methods():
    return [("methods", np.array(len(mp.methods()) > 0), ())]


def _coordinates():
    return [("coordinates", np.array(mp.coordinates("a b c"), dtype=object), (3,))]


def _no_array():
    """Plots return matplotlib objects (exercised in test_plot.py); exception
    and warning classes return nothing."""
    return []


# ------------------------------------------------------------------ the table
STATE, STACK, SINGLE, NONE = "state", "stack", "single", "none"

TABLE = {
    # integrate
    "mechpy.integrate.solve": (STATE, _solve_case),
    "mechpy.integrate.Solution": (STATE, _solve_case),
    "mechpy.integrate.DenseOutput": (STATE, _solve_case),
    "mechpy.integrate.solve_many": (STATE, _solve_many_case),
    "mechpy.integrate.EnsembleSolution": (STATE, _solve_many_case),
    "mechpy.integrate.SecondOrder": (STATE, _second_order_case),
    "mechpy.integrate.methods": (SINGLE, _single(_methods)),
    # scenes
    **{f"mechpy.scenes.{n}": (STATE, _scenes) for n in mp.scenes.__all__
       if n != "SymbolicField"},
    # compiled scenes
    "mechpy.symbolic.lagrangian": (STATE, _lagrangian_case),
    "mechpy.symbolic.equations": (STATE, _equations_case),
    "mechpy.symbolic.mechanics": (STATE, _mechanics_case),
    "mechpy.symbolic.coordinates": (SINGLE, _single(_coordinates)),
    "mechpy.symbolic.CompileError": (NONE, None),
    # inertia
    "mechpy.inertia.point_masses": (STACK, _point_masses_case),
    "mechpy.inertia.center_of_mass": (STACK, _point_masses_case),
    "mechpy.inertia.total_momentum": (STACK, _point_masses_case),
    "mechpy.inertia.angular_momentum_about": (STACK, _point_masses_case),
    "mechpy.inertia.shift": (STACK, _inertia_case),
    "mechpy.inertia.principal_axes": (STACK, _inertia_case),
    "mechpy.inertia.angular_momentum": (STACK, _inertia_case),
    "mechpy.inertia.kinetic_energy": (STACK, _inertia_case),
    "mechpy.inertia.Body": (SINGLE, _single(_body)),
    "mechpy.inertia.solid": (SINGLE, _single(_body)),
    "mechpy.inertia.mesh": (SINGLE, _single(_mesh)),
    "mechpy.inertia.uv_sphere": (SINGLE, _single(_mesh)),
    "mechpy.inertia.density_grid": (SINGLE, _single(_grid)),
    "mechpy.inertia.classify": (SINGLE, _single(_classify)),
    "mechpy.inertia.kinetic_energy_split": (SINGLE, _single(_split)),
    "mechpy.inertia.EnergySplit": (SINGLE, _single(_split)),
    # stress
    **{f"mechpy.stress.{n}": (STACK, _stress_case) for n in (
        "principal", "pressure", "von_mises", "max_shear", "deviator", "traction")},
    # rotation
    **{f"mechpy.rotation.{n}": (STACK, _rotation_case) for n in (
        "euler_matrix", "euler_angles", "angular_velocity", "euler_rates", "quat_from_matrix",
        "matrix_from_quat", "quat_multiply", "quat_normalize", "quat_from_euler",
        "euler_from_quat", "to_scipy", "from_scipy")},
    "mechpy.rotation.GimbalLockWarning": (NONE, None),
    # rigid
    "mechpy.rigid.free_rotation": (STACK, _free_rotation_case),
    "mechpy.rigid.flip_period": (SINGLE, _single(_flip)),
    "mechpy.rigid.nutation_bounds": (SINGLE, _single(_nutation)),
    "mechpy.rigid.steady_precession": (SINGLE, _single(_top_rates)),
    "mechpy.rigid.sleeping_top": (SINGLE, _single(_top_rates)),
    "mechpy.rigid.free_precession": (SINGLE, _single(_top_rates)),
    # modes
    "mechpy.modes.Modes": (STACK, _modes_case),
    "mechpy.modes.normal_modes": (STACK, _modes_case),
    "mechpy.modes.dispersion": (STACK, _dispersion_case),
    "mechpy.modes.dispersion_diatomic": (STACK, _dispersion_case),
    "mechpy.modes.chain": (SINGLE, _single(_chain)),
    "mechpy.modes.linear_triatomic": (SINGLE, _single(_triatomic)),
    "mechpy.modes.TriatomicModes": (SINGLE, _single(_triatomic)),
    # phase
    "mechpy.phase.vector_field": (STACK, _vector_field_case),
    "mechpy.phase.poincare": (STACK, _poincare_case),
    "mechpy.phase.bifurcation": (STACK, _poincare_case),
    "mechpy.phase.fixed_points": (SINGLE, _single(_fixed_points)),
    "mechpy.phase.FixedPoint": (SINGLE, _single(_fixed_points)),
    "mechpy.phase.limit_cycle": (SINGLE, _single(_limit_cycle)),
    "mechpy.phase.lyapunov": (SINGLE, _single(_lyapunov)),
    "mechpy.phase.LyapunovFloorWarning": (NONE, None),
    "mechpy.phase.logistic": (STACK, _logistic_case),
    "mechpy.phase.logistic_bifurcation": (STACK, _logistic_case),
    "mechpy.phase.lyapunov_spectrum": (SINGLE, _single(_phase_tangent)),
    "mechpy.phase.floquet": (SINGLE, _single(_phase_tangent)),
    # tangent
    **{f"mechpy.tangent.{n}": (SINGLE, _single(_tangent_flow)) for n in (
        "sensitivity", "fit", "FitResult")},
    # events
    "mechpy.events.impact": (SINGLE, _single(_impact)),
    "mechpy.events.Impact": (SINGLE, _single(_impact)),
    # particles
    "mechpy.particles.collide": (STACK, _collide_case),
    "mechpy.particles.to_cm": (STACK, _cm_case),
    "mechpy.particles.from_cm": (STACK, _cm_case),
    # frames
    "mechpy.frames.fictitious": (STACK, _frames_case),
    "mechpy.frames.earth_omega": (STACK, _frames_case),
    "mechpy.frames.foucault_period": (STACK, _frames_case),
    "mechpy.frames.eastward_deflection": (STACK, _frames_case),
    "mechpy.frames.to_rotating": (STACK, _to_rotating_case),
    "mechpy.frames.from_rotating": (STACK, _to_rotating_case),
    "mechpy.frames.projectile_drift": (STACK, _drift_case),
    "mechpy.frames.drop": (SINGLE, _single(_drop)),
    "mechpy.frames.projectile": (SINGLE, _single(_drop)),
    # variational
    "mechpy.variational.stationary_path": (STATE, _stationary_path_case),
    "mechpy.variational.StationaryPath": (STATE, _stationary_path_case),
    "mechpy.variational.stationary_paths": (STATE, _stationary_paths_case),
    "mechpy.variational.variational_integrate": (STATE, _variational_integrate_case),
    "mechpy.variational.VariationalTrajectory": (STATE, _variational_integrate_case),
    "mechpy.variational.lagrangian": (STATE, _lagrangian_fn_case),
    "mechpy.variational.generalized_momenta": (STATE, _momenta_case),
    "mechpy.variational.pendulum_tension": (STATE, _tension_case),
    "mechpy.variational.CentralForce": (STATE, _central_force_case),
    "mechpy.variational.RotatingHoop": (STATE, _hoop_case),
    "mechpy.variational.constraint_forces": (STACK, _constraint_forces_case),
    "mechpy.variational.cyclic_coordinates": (SINGLE, _single(_cyclic)),
    "mechpy.variational.minimize_functional": (SINGLE, _single(_minimize)),
    "mechpy.variational.Extremal": (SINGLE, _single(_minimize)),
    "mechpy.variational.brachistochrone": (SINGLE, _single(_brach)),
    "mechpy.variational.Brachistochrone": (SINGLE, _single(_brach)),
    "mechpy.variational.catenary": (SINGLE, _single(_brach)),
    "mechpy.variational.Catenary": (SINGLE, _single(_brach)),
    # plot: matplotlib objects; a path is (3, m) as sol.y[:3] gives it
    "mechpy.plot.trajectory3d": (STATE, _trajectory3d_case),
    "mechpy.plot.animate": (STATE, _animate_case),
    **{f"mechpy.plot.{n}": (NONE, None) for n in (
        "phase_portrait", "work_precision", "modes", "animate_field")},
    # live views: widgets (their pages are exercised in test_live_*.py)
    **{f"mechpy.live.{n}": (NONE, None) for n in ("animate", "Motion", "phase_portrait",
                                                  "PhasePortrait")},
    "mechpy.scenes.SymbolicField": (NONE, None),
    # exceptions
    **{f"mechpy.errors.{n}": (NONE, None) for n in mp.errors.__all__},
}


# Public methods and properties of the public classes (and of the compiled
# scene that mp.lagrangian returns): the TABLE entry whose case checks each, or
# None for members that hold no array (names, flags, SymPy objects, source).
_SCENE, _CHAIN, _RB = "mechpy.scenes.Pendulum", "mechpy.scenes.SpringChain", "mechpy.scenes.RigidBody"
_LAG, _BODY, _MODES = "mechpy.symbolic.lagrangian", "mechpy.inertia.Body", "mechpy.modes.Modes"
METHODS = {
    **{f"Scene.{n}": _SCENE for n in ("replace", "ensemble_params", "rhs", "jacobian", "energy")},
    "Scene.dim": None, "Scene.params": None, "Scene.symbolic": None,
    **{f"Scene.{n}": None for n in ("states", "coordinates", "speeds", "drawing")},
    "Scene.initial_state": _SCENE,
    "CompiledScene.symbolic": None, "CompiledScene.drawing": None,
    **{f"PhasePortrait.{n}": None for n in ("html", "precompute", "save")},
    "Solution.raise_for_status": None, "EnsembleSolution.raise_for_status": None,
    "Impact.action": "mechpy.events.impact",
    "Pendulum.period": _SCENE, "Kepler.initial_state": _SCENE,
    "Foucault.precession_rate": _SCENE,
    **{f"Rocket.{n}": _SCENE for n in ("burnout_time", "fly", "initial_state")},
    **{f"RigidBody.{n}": _RB for n in ("rhs", "jacobian", "moments", "initial_state",
                                      "angular_momentum")},
    "HeavyTop.p_psi": "mechpy.scenes.HeavyTop", "HeavyTop.p_phi": "mechpy.scenes.HeavyTop",
    **{f"SpringChain.{n}": _CHAIN for n in ("uniform", "ensemble_params",
                                           "initial_state", "matrices", "modes",
                                           "mode_energies", "momentum")},
    "SpringChain.N": None, "SpringChain.nonlinear": None,
    **{f"Body.{n}": _BODY for n in ("from_point_masses", "density", "inertia_about", "moved",
                                    "rotated", "principal", "classify")},
    **{f"Modes.{n}": _MODES for n in ("n", "eigenvalues", "frequencies", "zero_modes",
                                      "coordinates", "energy", "evolve")},
    "TriatomicModes.omega": "mechpy.modes.TriatomicModes",
    "TriatomicModes.wavenumbers": "mechpy.modes.TriatomicModes",
    "CentralForce.rhs": "mechpy.variational.CentralForce",
    "CentralForce.momenta": "mechpy.variational.CentralForce",
    **{f"RotatingHoop.{n}": "mechpy.variational.RotatingHoop"
       for n in ("rhs", "jacobi_integral", "normal_force")},
    **{f"CompiledScene.{n}": _LAG for n in ("replace", "rhs", "jacobian", "energy", "momenta",
                                           "multipliers", "constraint_forces", "cyclic",
                                           "small_oscillations")},
    **{f"CompiledScene.{n}": None for n in ("params", "constraints", "coordinates",
                                           "c_source", "equations", "speeds", "states")},
    "CompiledScene.initial_state": _LAG,
}


def _public_members(cls) -> list:
    """Public methods and properties defined on cls itself."""
    return [n for n, v in vars(cls).items() if not n.startswith("_") and (
        inspect.isfunction(v) or isinstance(v, (property, classmethod, staticmethod,
                                                functools.cached_property)))]


def test_every_public_method_is_classified():
    from mechpy.symbolic.scene import CompiledScene
    classes = [o for o in _public_callables().values()
               if inspect.isclass(o) and not issubclass(o, (BaseException, Warning))]
    members = {f"{c.__name__}.{n}" for c in classes + [CompiledScene] for n in _public_members(c)}
    missing = sorted(members - set(METHODS))
    assert not missing, f"public methods not in tests/test_layout.py's METHODS: {missing}"
    stale = sorted(set(METHODS) - members)
    assert not stale, f"METHODS names that are not public (any more): {stale}"
    for name, entry in METHODS.items():
        assert entry is None or TABLE[entry][1] is not None, name


def _public_callables() -> dict:
    """Every public callable: each public module's ``__all__`` (mechpy's own
    ``__all__`` lists the modules and the re-exported names), first listing wins."""
    found, seen = {}, set()
    modules = [getattr(mp, n) for n in mp.__all__ if isinstance(getattr(mp, n), types.ModuleType)]
    for mod in modules + [mp]:
        for name in mod.__all__:
            obj = getattr(mod, name)
            if isinstance(obj, types.ModuleType) or not callable(obj) or id(obj) in seen:
                continue
            seen.add(id(obj))
            found[f"{mod.__name__}.{name}"] = obj
    return found


def test_every_public_callable_is_classified():
    public = _public_callables()
    missing = sorted(set(public) - set(TABLE))
    assert not missing, f"public callables not in tests/test_layout.py's TABLE: {missing}"
    stale = sorted(set(TABLE) - set(public))
    assert not stale, f"TABLE names that are not public (any more): {stale}"
    assert len(public) > 90


def test_module_all_lists_are_complete():
    """No public function escapes the walk by being left out of its __all__."""
    for n in mp.__all__:
        mod = getattr(mp, n)
        if not isinstance(mod, types.ModuleType):
            continue
        for name, obj in vars(mod).items():
            if (name.startswith("_") or not (inspect.isfunction(obj) or inspect.isclass(obj))
                    or getattr(obj, "__module__", "").split(".")[:2] != mod.__name__.split(".")[:2]):
                continue
            assert name in mod.__all__, f"{mod.__name__}.{name} is public but not in __all__"


_CASES = {}
for _name, (_kind, _case) in TABLE.items():
    if _case is not None:
        _CASES.setdefault(_case, []).append(_name)


@pytest.mark.parametrize("batch", BATCHES, ids=["scalar", "batch"])
@pytest.mark.parametrize("case", list(_CASES), ids=[", ".join(v) for v in _CASES.values()])
def test_layout(case, batch):
    results = case(batch)
    if batch == () or TABLE[_CASES[case][0]][0] != SINGLE:
        assert results, "a case must check at least one output"
    for label, out, expected in results:
        assert np.shape(out) == expected, (
            f"{label}: shape {np.shape(out)}, the layout rule says {expected}")
        if expected != ():
            assert isinstance(out, np.ndarray), f"{label}: a {type(out).__name__}, not an array"
        if np.ndim(out) == 0 and expected == () and np.asarray(out).dtype.kind == "f":
            assert np.isfinite(out)


def test_rule_is_written_where_users_read_it():
    doc = mp.__doc__
    assert "States follow SciPy" in doc and "NumPy stack" in doc
    for n in mp.__all__:
        mod = getattr(mp, n)
        if isinstance(mod, types.ModuleType) and n in (
                "integrate", "scenes", "inertia", "stress", "rotation", "rigid", "modes",
                "phase", "frames", "variational", "plot"):
            assert "layout rule in :mod:`mechpy`" in mod.__doc__, n
    from pathlib import Path
    readme = Path(__file__).resolve().parent.parent / "README.md"
    if readme.exists():
        text = readme.read_text()
        assert "## Conventions: array layout" in text and "States follow SciPy" in text


# ------------------------------------------------------------------ regressions

def test_hoop_normal_force_scalar_t_with_a_batch_of_states():
    """normal_force(t, y) with a scalar t and states (2, ...) failed to
    broadcast; it must equal the closed forms of its docstring (radial
    -mR(thd^2 + w^2 sin^2 th) - mg cos th, azimuthal 2 m R w thd cos th,
    tangential 0) at every state."""
    h = mp.variational.RotatingHoop(R=0.5, omega=6.0, m=0.2)
    th = np.linspace(-2.5, 2.5, 12).reshape(3, 4)
    thd = np.linspace(-3.0, 2.0, 12).reshape(3, 4)
    N = h.normal_force(0.7, np.stack([th, thd]))
    m, R, w, g = h.m, h.R, h.omega, h.g
    radial = -m * R * (thd ** 2 + (w * np.sin(th)) ** 2) - m * g * np.cos(th)
    azimuthal = 2 * m * R * w * thd * np.cos(th)
    assert N.shape == (3, 3, 4)
    scale = np.max(np.abs(radial))
    # measured relative to the largest radial force: 4.4e-16, 1.1e-16, 1.1e-16, 2.7e-16
    assert np.max(np.abs(N[0] - radial)) < 5e-15 * scale
    assert np.max(np.abs(N[1] - azimuthal)) < 5e-15 * scale
    assert np.max(np.abs(N[2])) < 5e-15 * scale
    # a time per state gives the same forces: the hoop's spin only turns the frame
    Nt = h.normal_force(np.linspace(0.0, 3.0, 4), np.stack([th, thd]))
    assert np.max(np.abs(Nt - N)) < 5e-15 * scale


def test_dense_output_keeps_the_shape_of_t():
    """sol(t) for times of shape (2, 3) gave (n, 6); it is (n, 2, 3), each
    column the value at its own time, and a scalar or 1-D t is as SciPy's."""
    s = mp.solve(mp.scenes.Pendulum(), (0, 2), [0.3, 0.0], dense_output=True)
    t = np.linspace(0.1, 1.9, 6).reshape(2, 3)
    y = s.sol(t)
    assert y.shape == (2, 2, 3)
    flat = s.sol(t.ravel())
    assert flat.shape == (2, 6)
    assert np.array_equal(y.reshape(2, 6), flat)
    assert np.array_equal(y[:, 1, 2], s.sol(t[1, 2]))


def test_hoop_normal_force_rejects_bad_states():
    h = mp.variational.RotatingHoop()
    with pytest.raises(ValueError, match="y must have 2 components"):
        h.normal_force(0.0, np.ones((3, 4)))
    with pytest.raises(ValueError, match="t of shape"):
        h.normal_force(np.ones(5), np.ones((2, 4)))


def test_no_merge_conflict_markers_in_the_tree():
    """No file the project tracks holds a merge's conflict markers."""
    import subprocess
    from pathlib import Path
    root = Path(__file__).resolve().parents[1]
    try:
        files = subprocess.run(["git", "ls-files"], cwd=root, capture_output=True, text=True,
                               check=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout (an sdist)")
    bad = []
    for name in files:
        p = root / name
        if p.suffix not in (".py", ".md", ".c", ".h", ".toml", ".build", ".sh", ".rst",
                            ".ipynb", ".wrap", ".txt", ".cfg"):
            continue
        for i, line in enumerate(p.read_text(errors="replace").splitlines(), 1):
            if line.startswith(("<<<<<<< ", ">>>>>>> ")) or line == "=======":
                bad.append(f"{name}:{i}")
    assert bad == []


# ------------------------------------------------------------------ the binding
# csrc/py is a binding that only translates: short functions, system kinds
# as one table, and CONTRIBUTING's "new method" recipe true to the tree.

# the checkout (dev.sh names it in MECHPY_SOURCE_DIR when the suite runs from a copy of
# tests/ beside an installed mechpy): these tests read its sources
_ROOT = __import__("pathlib").Path(__import__("os").environ.get("MECHPY_SOURCE_DIR")
                                   or __import__("pathlib").Path(__file__).resolve().parents[1])
_FN_START = __import__("re").compile(r"^(?!typedef|static const|const|PyMethodDef|struct)"
                                     r"[A-Za-z_][\w \*]*?\b(\w+)\s*\(")


def _c_functions(text: str) -> list[tuple[str, int, int]]:
    """(name, first line, lines from the signature to the closing brace) of
    each function defined in a C file written in the project's style (the
    signature at column 0, the braces of the body alone on their lines)."""
    lines = text.split("\n")
    out, i = [], 0
    while i < len(lines):
        m = _FN_START.match(lines[i])
        j = i
        while m and j < len(lines) and lines[j] != "{" and not lines[j].rstrip().endswith(
                (";", "}")):
            j += 1
        if m and j < len(lines) and lines[j] == "{":
            k = lines.index("}", j)
            out.append((m.group(1), i + 1, k - i + 1))
            i = k
        i += 1
    return out


def _binding_sources():
    files = sorted((_ROOT / "csrc" / "py").glob("*.c"))
    if not files:
        pytest.skip("no C sources beside the package (an installed copy)")
    return files


def test_no_binding_function_is_over_80_lines():
    """Each function in csrc/py, counted from its signature line to its
    closing brace, is at most 80 lines: the binding parses and translates,
    the work is the engine's."""
    found, long = {}, []
    for f in _binding_sources():
        for name, line, n in _c_functions(f.read_text()):
            found[name] = n
            if n > 80:
                long.append(f"{f.name}:{line}: {name} has {n} lines")
    # the walk finds the functions it must (so that it cannot pass by finding none)
    assert {"py_ode_solve", "py_ode_solve_many", "py_system_parse", "ode_opts_parse",
            "event_list_parse"} <= set(found)
    assert found["py_ode_solve"] > 20
    assert long == []


def test_c_function_walk_counts_what_it_should():
    text = ("static int f(int a,\n             int b)\n{\n    return a;\n}\n\n"
            "void g(void) { h(); }\n\nint k(void)\n{\n    if (1) {\n    }\n    return 0;\n}\n")
    assert _c_functions(text) == [("f", 1, 5), ("k", 9, 6)]


def test_system_kinds_are_one_table():
    """The kinds of system integrate.py describes (_system.py's specs) are
    rows of one table in the binding; no string comparison of a kind."""
    import re
    kinds = set()
    for path in ("_system.py", "symbolic/scene.py"):   # where the specs are written
        kinds |= set(re.findall(r'return \("(\w+)", ', (_ROOT / "mechpy" / path).read_text()))
    assert {"scene", "python", "python2", "cfunc", "cfunc2", "compiled"} <= kinds
    # the code, comments left out (they may quote a spec)
    sources = {f.name: re.sub(r"/\*.*?\*/", "", f.read_text(), flags=re.S)
               for f in _binding_sources()}
    ode = {name: text for name, text in sources.items() if '#include "py_ode.h"' in text}
    assert set(ode) == {"py_ode.c", "py_system.c", "py_events.c"}
    table = re.search(r"py_system_kinds\[\] = \{(.*?)\n\};", ode["py_system.c"], re.S)
    assert table, "py_system.c's table py_system_kinds"
    assert set(re.findall(r'\{"(\w+)", \w+', table.group(1))) == kinds
    for name, text in ode.items():
        assert "strcmp" not in text, name
        for kind in kinds:   # each kind's name is written once: its row
            n = text.count(f'"{kind}"')
            assert n == (1 if name == "py_system.c" else 0), (name, kind, n)
    # nor elsewhere in the binding (the variational integrands' tags are a table too)
    tags = "|".join(sorted(kinds | {"c"}))
    for name, text in sources.items():
        assert not re.search(r'strcmp\([^;]*"(%s)"' % tags, text), name


def _recipe() -> str:
    path = _ROOT / "CONTRIBUTING.md"
    if not path.exists():
        pytest.skip("no CONTRIBUTING.md beside the package (an installed copy)")
    text = path.read_text()
    start = text.index("## Adding an integration method")
    return text[start:text.index("\n## ", start + 3)]


def test_new_method_recipe_names_what_exists():
    """Every file and name CONTRIBUTING's "new method" recipe puts in
    backticks exists: a path (bare names under csrc/ode/), a field of
    mp_ode_method, a key of mp.methods(), an mp function, or a name defined
    in the files the recipe names."""
    import re
    recipe = _recipe()
    ticks = re.findall(r"`([^`]+)`", recipe)
    ode_h = (_ROOT / "csrc" / "ode" / "ode.h").read_text()
    row = re.search(r"typedef struct mp_ode_method \{(.*?)\} mp_ode_method;", ode_h, re.S)
    fields = set(re.findall(r"[\s\*\(](\w+)(?:\)\(.*?\))?(?:, \w+)*;", row.group(1)))
    fields |= {w for line in row.group(1).split(";") for w in re.findall(r"\b(\w+)\s*(?:,|$)",
                                                                        line.strip())}
    keys = set(mp.methods()[0])
    named, texts = [], []
    for t in ticks:
        if re.fullmatch(r"[\w/.<>]+\.(c|h|py|md|build)", t):
            p = _ROOT / t if "/" in t else _ROOT / "csrc" / "ode" / t
            named.append(t)
            if "<" not in t:
                assert p.exists(), t
                texts.append(p.read_text())
    assert {"csrc/ode/methods.c", "csrc/meson.build", "tests/test_integrate.py",
            "docs/guide/integrators.md", "csrc/mp_status.c"} <= set(named)
    corpus = "\n".join(texts)
    for t in ticks:
        if t in named or not re.fullmatch(r"[\w.*\[\]()]+", t):
            continue   # a path, or code in prose: (t, y, f), the extern line
        name = t.rstrip("()[]").replace("_*", "_")
        if name.startswith("mp."):
            assert callable(getattr(mp, name[3:])), t
        elif name in fields or name in keys:
            continue
        else:
            assert name in corpus, f"{t}: named by the recipe, found in none of its files"
    for flag in ("adaptive", "implicit", "symplectic", "needs_jacobian", "scalar_rtol", "ncoef", "dense_order", "nscratch", "expo", "beta",
                 "fac_min", "fac_max", "safety", "step", "finish", "alloc", "free", "restart",
                 "block", "lanes", "rigid"):
        assert f"`{flag}`" in recipe and re.search(rf"\b{flag}\b", row.group(1)), flag
    for key in ("lanes", "rigid", "scalar_rtol"):
        assert f"`{key}`" in recipe and key in keys, key


def test_new_method_recipe_steps_hold_for_every_row():
    """The recipe's steps, checked on every row there is: each row is in
    mp_ode_methods[] with its extern, each csrc/ode source is in c_sources,
    each method has its bound in tests/test_integrate.py's CROSS_CHECK and is
    named in docs/guide/integrators.md, and nothing in mechpy compares a
    method's name."""
    import re
    _recipe()
    methods_c = (_ROOT / "csrc" / "ode" / "methods.c").read_text()
    array = re.search(r"mp_ode_methods\[\] = \{(.*?)\};", methods_c, re.S).group(1)
    rows = re.findall(r"&(mp_ode_\w+)", array)
    assert len(rows) == len(mp.methods())
    externs = " ".join(re.findall(r"extern const mp_ode_method ([^;]*);", methods_c))
    assert all(re.search(rf"\b{r}\b", externs) for r in rows)
    meson = (_ROOT / "csrc" / "meson.build").read_text()
    for src in (_ROOT / "csrc" / "ode").glob("*.c"):
        assert f"'ode/{src.name}'" in meson, src.name
    cross = (_ROOT / "tests" / "test_integrate.py").read_text()
    block = re.search(r"CROSS_CHECK = \{(.*?)\}", cross, re.S).group(1)
    doc = (_ROOT / "docs" / "guide" / "integrators.md").read_text()
    names = [m["name"] for m in mp.methods()]
    for name in names:
        assert f'"{name}":' in block, name
        assert f"`{name}`" in doc, name
    alt = "|".join(map(re.escape, names))
    compare = re.compile(r'(method|name)\w*\]?\s*(==|!=|in)\s*[(\[{]?\s*"(%s)"|'
                         r'"(%s)"\s*(==|!=)\s*\w*(method|name)|startswith\("(gsl|rigid):'
                         % (alt, alt))
    hits = [f"{p.relative_to(_ROOT)}:{text.count(chr(10), 0, m.start()) + 1}"
            for p in (_ROOT / "mechpy").rglob("*.py") if "benches" not in p.parts
            for text in [p.read_text()] for m in compare.finditer(text)]
    assert hits == []


def test_solve_messages_live_in_the_status_table():
    """The binding formats a solve's message from the status table's rows
    (mp_status_details): no detail text of its own."""
    import re
    status = (_ROOT / "csrc" / "mp_status.c").read_text()
    assert "mp_status_details[MP_NDETAIL]" in status
    for f in _binding_sources():
        text = f.read_text()
        literals = " ".join(re.findall(r'"((?:[^"\\]|\\.)*)"', text))
        for phrase in ("NaN or inf", "at t = ", "max_steps=", "appears stiff", "Zeno"):
            assert phrase not in literals, (f.name, phrase)
