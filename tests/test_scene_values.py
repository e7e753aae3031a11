"""Scenes checked by value: Jacobians, right-hand sides, initial states and the
closed forms of the variational module, against formulas written here."""
import os

import numpy as np
import pytest
from scipy.optimize import brentq

import mechpy as mp
from mechpy import variational as V


def _compiled_double_pendulum(tmp_path_factory):
    import sympy as sp
    old = os.environ.get("MECHPY_CACHE_DIR")
    os.environ["MECHPY_CACHE_DIR"] = str(tmp_path_factory.mktemp("mechpy_cache"))
    try:
        t = sp.Symbol("t")
        a, b = mp.coordinates("a b")
        m, g = sp.symbols("m g")
        ad, bd = a.diff(t), b.diff(t)
        # two unit rods, unit bobs: a coupled, nonlinear mass matrix
        T = m * ad ** 2 + m * ad * bd * sp.cos(a - b) + m * bd ** 2 / 2
        U = -2 * m * g * sp.cos(a) - m * g * sp.cos(b)
        return mp.lagrangian(T - U, [a, b], params={"m": 1.3, "g": 9.81})
    finally:
        if old is None:
            os.environ.pop("MECHPY_CACHE_DIR", None)
        else:
            os.environ["MECHPY_CACHE_DIR"] = old


def _scenes(rng, tmp_path_factory):
    u = rng.uniform
    return [
        mp.scenes.Pendulum(g=u(5, 15), length=u(0.5, 2), damping=u(0, 1),
                           drive_amplitude=u(0, 2), drive_frequency=u(0.5, 3)),
        mp.scenes.Duffing(u(-1, 1), u(0.1, 2), delta=u(0, 1), gamma=u(0, 1), omega=u(0.5, 2)),
        mp.scenes.VanDerPol(mu=u(0.5, 5)),
        mp.scenes.Kepler(mu=u(0.5, 2)),
        mp.scenes.RestrictedThreeBody(mu=u(0.01, 0.3)),
        mp.scenes.Foucault(u(-80, 80), u(1, 20)),
        mp.scenes.HeavyTop(u(1, 2), u(0.5, 3), u(0.5, 2), l=u(0.2, 1)),
        mp.scenes.RigidBody(moments=tuple(u(1, 3, 3))),
        mp.scenes.RigidBody(moments=tuple(u(1, 3, 3)), orientation=True),
        mp.scenes.SpringChain(u(0.5, 2, 4), springs=u(0.5, 2, 5), alpha=u(0, 0.3),
                              beta=u(0, 0.5)),
        mp.scenes.SpringChain(u(0.5, 2, 3), springs=u(0.5, 2, 3), ends="periodic",
                              beta=u(0, 0.5)),
        _compiled_double_pendulum(tmp_path_factory),
    ]


def test_every_scene_jacobian_matches_central_differences(rng, tmp_path_factory):
    # central differences, h = 1e-6 * max(1, |y_j|): truncation h^2 f''' ~ 1e-12 and
    # round-off eps |f| / h ~ 1e-10; measured max relative error 1.2e-9 over all scenes
    # and states (a sign error in one entry is an O(1) error)
    worst = 0.0
    for sc in _scenes(rng, tmp_path_factory):
        for _ in range(4):
            y = rng.uniform(-1.5, 1.5, sc.dim)
            if isinstance(sc, mp.scenes.Kepler):
                y[:2] += np.sign(y[:2]) * 0.5          # away from the singular origin
            t = rng.uniform(0, 5)
            J = np.asarray(sc.jacobian(t, y))
            assert J.shape == (sc.dim, sc.dim)
            fd = np.empty_like(J)
            for j in range(sc.dim):
                h = 1e-6 * max(1.0, abs(y[j]))
                e = np.zeros(sc.dim)
                e[j] = h
                fd[:, j] = (np.asarray(sc.rhs(t, y + e)) - np.asarray(sc.rhs(t, y - e))) / (2 * h)
            err = np.max(np.abs(J - fd)) / max(1.0, np.max(np.abs(fd)))
            worst = max(worst, err)
            assert err < 1e-7, (type(sc).__name__, y, J, fd)


def test_duffing_rhs_is_the_written_equation():
    # x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t): the drive enters with +
    a, b, d, g, w = -0.7, 1.3, 0.25, 0.8, 1.7
    sc = mp.scenes.Duffing(a, b, delta=d, gamma=g, omega=w)
    for t, x, v in [(0.0, 0.3, -0.2), (0.9, -1.1, 0.7), (2.4, 0.5, 1.5)]:
        ref = [v, -d * v - a * x - b * x ** 3 + g * np.cos(w * t)]
        np.testing.assert_allclose(sc.rhs(t, [x, v]), ref, rtol=1e-15, atol=1e-15)
    # at t = 0, x = v = 0 only the drive acts: acceleration +gamma
    assert sc.rhs(0.0, [0.0, 0.0])[1] == pytest.approx(g, rel=1e-15)


@pytest.mark.parametrize("e, a, mu", [(0.0, 1.0, 1.0), (0.5, 3.0, 2.0), (0.9, 0.7, 0.3)])
def test_kepler_initial_state_is_pericentre_with_vis_viva(e, a, mu):
    y = mp.scenes.Kepler(mu=mu).initial_state(e, a=a)
    rp = a * (1 - e)                                    # pericentre distance
    vp = np.sqrt(mu * (2 / rp - 1 / a))                 # vis-viva
    np.testing.assert_allclose(y, [rp, 0.0, 0.0, vp], rtol=1e-15, atol=1e-15)
    # the specific energy is -mu / (2 a)
    assert mp.scenes.Kepler(mu=mu).energy(y) == pytest.approx(-mu / (2 * a), rel=1e-14)


@pytest.mark.parametrize("e", [1.0, 1.5, -0.1, np.nan])
def test_kepler_initial_state_refuses_unbound_eccentricity(e):
    # a pericentre state of a closed orbit needs 0 <= e < 1 (e = 1: infinite speed)
    with pytest.raises(ValueError, match="eccentricity"):
        mp.scenes.Kepler().initial_state(e)


def test_earth_omega_is_the_sidereal_rate():
    # one sidereal day is 86164.0905 s (IERS Conventions 2010, ch. 1; the IERS value
    # of Omega is 7.292115e-5 rad/s); mechpy's 7.2921159e-5 agrees to 7 digits
    sidereal = 2 * np.pi / 86164.0905
    assert mp.frames.OMEGA_EARTH == pytest.approx(sidereal, rel=1e-7)
    for lat in (0.0, 45.0, -30.0, 90.0):
        w = mp.frames.earth_omega(lat)
        lam = np.radians(lat)
        np.testing.assert_allclose(w, mp.frames.OMEGA_EARTH * np.array([0, np.cos(lam),
                                                                        np.sin(lam)]),
                                   rtol=0, atol=1e-20)


def _cycloid(x_end, y_end, g, x):
    """The cycloid through (0, 0) and (x_end, y_end), found here by root finding."""
    ratio = x_end / y_end
    th_e = brentq(lambda th: (th - np.sin(th)) - ratio * (1 - np.cos(th)), 1e-3, 2 * np.pi)
    a = y_end / (1 - np.cos(th_e))
    th = np.array([brentq(lambda s: a * (s - np.sin(s)) - xi, 0, th_e) if xi > 0 else 0.0
                   for xi in x])
    return a * (1 - np.cos(th)), a, th_e * np.sqrt(a / g)


@pytest.mark.parametrize("x_end, y_end", [(2.0, 1.0), (1.0, 2.0), (3.0, 0.5), (0.5, 1.5)])
def test_brachistochrone_exact_fields_are_the_cycloid(x_end, y_end):
    # x_end > y_end: the cycloid dips below the end point (theta_e > pi);
    # x_end < y_end: it reaches it on the way down (theta_e < pi)
    r = V.brachistochrone(x_end, y_end, g=9.81, n=60)
    y_ref, a, T = _cycloid(x_end, y_end, 9.81, r.x)
    assert r.radius == pytest.approx(a, rel=1e-12)       # measured ~1e-15
    assert r.time_exact == pytest.approx(T, rel=1e-12)
    np.testing.assert_allclose(r.y_exact, y_ref, rtol=1e-10, atol=1e-12)


def test_constraint_forces_pendulum_tension_closed_form():
    # bob on a rod: T = m (g cos(theta) + l theta_dot^2)
    m, g, ell = 0.7, 9.81, 1.6
    sc = mp.scenes.Pendulum(g=g, length=ell)
    th = np.array([0.0, 0.4, 1.2, 2.9, -2.0])
    w = np.array([0.0, 1.1, -0.5, 2.0, 0.3])
    T = V.pendulum_tension(sc, np.stack([th, w]), mass=m)
    np.testing.assert_allclose(T, m * (g * np.cos(th) + ell * w ** 2), rtol=1e-13, atol=1e-13)
    # constraint_forces directly: bead of mass m on a hoop of radius R at rest at angle
    # phi from the bottom under gravity; the hoop cancels the outward radial part of
    # gravity: f = -m g cos(phi) r/R (g = |x|^2 - R^2 = 0 has J = 2 x; here J = x, b = |v|^2 = 0)
    R, phi = 2.0, 0.6
    pos = R * np.array([np.sin(phi), -np.cos(phi)])
    lam, f = V.constraint_forces(m, [0.0, -m * g], pos[None, :], [0.0])
    np.testing.assert_allclose(f, -m * g * np.cos(phi) * pos / R, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(lam, [-m * g * np.cos(phi) / R], rtol=1e-14)


def test_variational_lagrangian_values():
    p = mp.scenes.Pendulum(g=9.81, length=1.5)
    L = V.lagrangian(p)
    th, w = 0.7, -1.2
    assert L(th, w) == pytest.approx(0.5 * 1.5 ** 2 * w ** 2 + 9.81 * 1.5 * np.cos(th),
                                     rel=1e-14)
    d = mp.scenes.Duffing(0.5, 2.0)
    Ld = V.lagrangian(d)
    x, v = 0.8, 0.3
    assert Ld(x, v) == pytest.approx(v ** 2 / 2 - 0.5 * x ** 2 / 2 - 2.0 * x ** 4 / 4, rel=1e-14)


def test_rocket_fly_closed_form_with_gravity():
    """Marion & Thornton 9.11 with constant g, no drag: while burning
    v = u ln(m0/m) - g t and h = (u/b)(m0 - m - m ln(m0/m)) - g t^2/2, m = m0 - b t;
    after burn-out at t_b = (m0 - m_dry)/b a free flight.  fly() stops at t_b
    (once, the mass there exactly m_dry) and goes on from it."""
    u, b, m0, md, g = 2500.0, 10.0, 1000.0, 200.0, 9.81
    r = mp.scenes.Rocket(exhaust_speed=u, burn_rate=b, m0=m0, m_dry=md, g=g)
    tb, tf = (m0 - md) / b, 100.0
    sol = r.fly((0.0, tf), rtol=1e-12, atol=1e-12)
    assert sol.success
    k = np.nonzero(sol.t == tb)[0]
    assert len(k) == 1 and sol.y[2, k[0]] == md
    vb = u * np.log(m0 / md) - g * tb
    hb = u / b * (m0 - md - md * np.log(m0 / md)) - 0.5 * g * tb ** 2
    # measured: 2.9e-13 (height), 4.3e-13 (speed), relative, at burn-out and at tf
    np.testing.assert_allclose(sol.y[:2, k[0]], [hb, vb], rtol=4e-12)
    dt = tf - tb
    np.testing.assert_allclose(sol.y[:, -1], [hb + vb * dt - 0.5 * g * dt ** 2, vb - g * dt, md],
                               rtol=4e-12)



@pytest.mark.parametrize("method", [m["name"] for m in mp.methods()
                                    if m["adaptive"] and not m["rigid"]])
def test_rocket_at_loose_tolerances_burns_out_on_every_method(method):
    """A long step's trial stage can reach a mass <= 0 (the mass falls linearly and
    nothing in the error estimate holds the step back): the step must be
    rejected and shrunk, not end the solve.  Before, 74 of 300 random rockets at
    rtol 1e-3 ended in DomainError.  Closed form while burning (M&T 9.11):
    v = u ln(m0/m) - g t at burn-out t_b = (m0 - m_dry)/b."""
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(12):
        u, b = rng.uniform(500.0, 4000.0), rng.uniform(20.0, 100.0)
        m0 = rng.uniform(100.0, 600.0)
        md = m0 * rng.uniform(0.05, 0.5)
        g = 9.81
        r = mp.scenes.Rocket(exhaust_speed=u, burn_rate=b, m0=m0, m_dry=md, g=g)
        tb = (m0 - md) / b
        sol = mp.solve(r, (0.0, 3.0 * tb), [0.0, 0.0, m0], rtol=1e-3, atol=1e-6,
                       method=method)
        assert sol.status == 0, sol.message
        assert sol.y[2, -1] == md           # set at the switch, constant after it
        v_end = u * np.log(m0 / md) - g * 3.0 * tb
        worst = max(worst, abs(sol.y[1, -1] - v_end) / abs(v_end))
    # the final speed: a guard against a wrong branch (thrust left on, or none, is
    # an O(1) error here), not an accuracy test (global errors at rtol 1e-3
    # measured 2.1e-5 (gsl:rk2) to 4.1e-2 (gsl:bsimp))
    assert worst < 0.1

# ---- every conservative scene: energy and invariants along a tight solve -------------
#
# Each energy is checked twice: against the formula of its docstring written here
# (a wrong coefficient in the C row's energy is an O(1) error at these states), and
# constant along a solve at rtol 1e-12 (a wrong energy is not constant along the
# true motion: Duffing's beta x^4/2 in place of /4 moves by beta x^4/4 over a swing).

def _spring_stretches(x, ends):
    """r_j of each spring for displacements x (N, ...): walls at both ends, none, a ring."""
    z = np.zeros_like(x[:1])
    if ends == "fixed":
        return np.diff(np.concatenate([z, x, z]), axis=0)
    if ends == "free":
        return np.diff(x, axis=0)
    return np.diff(np.concatenate([x, x[:1]]), axis=0)


CONSERVATIVE = {
    # name: (scene, y0, span, energy formula E(y), further invariants {name: f(y)})
    "Pendulum": (mp.scenes.Pendulum(g=9.81, length=1.3), [2.5, 0.4], 10.0,
                 lambda y: 0.5 * 1.3 ** 2 * y[1] ** 2 + 9.81 * 1.3 * (1 - np.cos(y[0])), {}),
    "Duffing hardening": (mp.scenes.Duffing(1.0, 2.0), [1.5, -0.3], 20.0,
                          lambda y: y[1] ** 2 / 2 + y[0] ** 2 / 2 + 2.0 * y[0] ** 4 / 4, {}),
    "Duffing double well": (mp.scenes.Duffing(-1.0, 1.0), [0.3, 1.0], 20.0,
                            lambda y: y[1] ** 2 / 2 - y[0] ** 2 / 2 + y[0] ** 4 / 4, {}),
    "VanDerPol mu=0": (mp.scenes.VanDerPol(mu=0.0), [1.7, -0.6], 20.0,
                       lambda y: (y[0] ** 2 + y[1] ** 2) / 2, {}),
    "Kepler": (mp.scenes.Kepler(mu=1.7), [1.0, 0.2, -0.3, 1.1], 20.0,
               lambda y: (y[2] ** 2 + y[3] ** 2) / 2 - 1.7 / np.hypot(y[0], y[1]),
               {"angular momentum": lambda y: y[0] * y[3] - y[1] * y[2],
                # the Laplace-Runge-Lenz vector (its two components)
                "LRL x": lambda y: (y[0] * y[3] - y[1] * y[2]) * y[3]
                - 1.7 * y[0] / np.hypot(y[0], y[1]),
                "LRL y": lambda y: -(y[0] * y[3] - y[1] * y[2]) * y[2]
                - 1.7 * y[1] / np.hypot(y[0], y[1])}),
    "RestrictedThreeBody": (mp.scenes.RestrictedThreeBody(mu=0.1), [0.5, 0.0, 0.0, 0.9], 5.0,
                            lambda y: (y[2] ** 2 + y[3] ** 2) / 2 - (y[0] ** 2 + y[1] ** 2) / 2
                            - 0.9 / np.hypot(y[0] + 0.1, y[1])
                            - 0.1 / np.hypot(y[0] - 0.9, y[1]), {}),
    "Foucault": (mp.scenes.Foucault(latitude=40.0, length=10.0, omega=0.05),
                 [0.3, -0.1, 0.02, 0.05], 60.0,
                 lambda y: (y[2] ** 2 + y[3] ** 2) / 2 + 9.81 / 10.0 * (y[0] ** 2 + y[1] ** 2) / 2,
                 {}),
    "RigidBody": (mp.scenes.RigidBody((1.0, 2.0, 2.5)), [0.3, 1.0, -0.4], 20.0,
                  lambda y: (1.0 * y[0] ** 2 + 2.0 * y[1] ** 2 + 2.5 * y[2] ** 2) / 2,
                  {"|L|^2": lambda y: (1.0 * y[0]) ** 2 + (2.0 * y[1]) ** 2
                   + (2.5 * y[2]) ** 2}),
    "HeavyTop": (mp.scenes.HeavyTop(1.0, 0.5, 1.0, g=9.81, l=0.3),
                 [0.0, 1.0, 0.0, 0.3, -0.2, 20.0], 5.0,
                 lambda y: 0.5 * (y[4] ** 2 + y[3] ** 2 * np.sin(y[1]) ** 2)
                 + 0.25 * (y[5] + y[3] * np.cos(y[1])) ** 2 + 9.81 * 0.3 * np.cos(y[1]),
                 {"p_psi": lambda y: 0.5 * (y[5] + y[3] * np.cos(y[1])),
                  "p_phi": lambda y: y[3] * np.sin(y[1]) ** 2
                  + 0.5 * (y[5] + y[3] * np.cos(y[1])) * np.cos(y[1])}),
}

_FPUT = dict(masses=[1.0, 2.0, 0.5, 1.5], springs=[1.0, 3.0, 0.7, 2.0, 1.2], alpha=0.4,
             beta=0.8)


def _fput_energy(ends, springs):
    m = np.array(_FPUT["masses"])[:, None]
    k = np.asarray(springs)[:, None]

    def E(y):
        x, v = y[:4], y[4:]
        r = _spring_stretches(x, ends)
        return np.sum(m * v ** 2, axis=0) / 2 + np.sum(k * (r ** 2 / 2 + 0.4 * r ** 3 / 3
                                                            + 0.8 * r ** 4 / 4), axis=0)
    return E


for _ends, _k in [("fixed", _FPUT["springs"]), ("free", _FPUT["springs"][:3]),
                  ("periodic", _FPUT["springs"][:4])]:
    _ch = mp.scenes.SpringChain(_FPUT["masses"], _k, ends=_ends, alpha=0.4, beta=0.8)
    _inv = {} if _ends == "fixed" else {
        "momentum": lambda y: np.sum(np.array(_FPUT["masses"])[:, None] * y[4:], axis=0)}
    CONSERVATIVE[f"SpringChain FPUT {_ends}"] = (
        _ch, [0.3, -0.2, 0.1, 0.25, 0.1, -0.3, 0.2, 0.05], 20.0, _fput_energy(_ends, _k), _inv)


def test_every_conservative_scene_is_listed():
    # every scene class has a conservative case here (Rocket's energy changes by design:
    # the burn and the drag; its closed form is test_rocket_fly_closed_form_with_gravity)
    classes = {c.__name__ for c in mp.scenes.Scene.__subclasses__() if getattr(c, "_model", None)}
    listed = {type(s).__name__ for s, *_ in CONSERVATIVE.values()}
    assert classes - listed == {"Rocket"}


@pytest.mark.parametrize("name", sorted(CONSERVATIVE))
def test_energy_is_the_formula_and_constant_along_a_tight_solve(name):
    scene, y0, span, E, invariants = CONSERVATIVE[name]
    y0 = np.asarray(y0, float)
    sol = mp.solve(scene, (0.0, span), y0, method="dop853", rtol=1e-12, atol=1e-12,
                   t_eval=np.linspace(0.0, span, 201))
    assert sol.success
    Ys = sol.y
    # the scene's energy is the written formula at every sampled state
    e_scene, e_ref = scene.energy(Ys), E(Ys)
    scale = max(np.max(np.abs(e_ref)), 1.0)
    assert np.max(np.abs(e_scene - e_ref)) < 4e-15 * scale, name   # measured 4.4e-16
    # and constant along the motion (which moves: the state swings by O(1))
    assert np.ptp(Ys[0]) > 0.1
    drift = np.max(np.abs(e_scene - e_scene[0])) / scale
    assert drift < 5e-10, (name, drift)   # measured at most 5.6e-11 (FPUT, free ends)
    for inv, f in invariants.items():
        v = f(Ys)
        # measured at most 1.0e-10 (Kepler's Laplace-Runge-Lenz vector)
        assert np.max(np.abs(v - v[0])) < 1e-9 * max(1.0, abs(v[0])), (name, inv)
    if isinstance(scene, mp.scenes.HeavyTop):
        assert np.allclose(scene.p_psi(Ys), invariants["p_psi"](Ys), rtol=1e-15, atol=1e-15)
        assert np.allclose(scene.p_phi(Ys), invariants["p_phi"](Ys), rtol=1e-14, atol=1e-14)
    if isinstance(scene, mp.scenes.RigidBody):
        L = scene.angular_momentum(Ys)
        assert np.allclose(np.sum(L ** 2, axis=0), invariants["|L|^2"](Ys), rtol=1e-14)
    if isinstance(scene, mp.scenes.SpringChain) and "momentum" in invariants:
        assert np.allclose(scene.momentum(Ys), invariants["momentum"](Ys), rtol=1e-14,
                           atol=1e-15)


def test_rocket_burnout_time_is_fuel_over_burn_rate():
    # t_b = (m0 - m_dry) / burn_rate, and the mass reaches m_dry exactly then
    r = mp.scenes.Rocket(exhaust_speed=2000.0, burn_rate=12.5, m0=1000.0, m_dry=200.0)
    assert r.burnout_time == 64.0
    s = mp.solve(r, (0.0, 64.0), r.initial_state(), rtol=1e-12, atol=1e-9)
    assert s.y[2, -1] == pytest.approx(200.0, rel=1e-11)   # measured 1.2e-12
    assert mp.scenes.Rocket(exhaust_speed=2000.0, burn_rate=0.0, m0=500.0,
                            m_dry=500.0).burnout_time == 0.0


S = mp.scenes
#: every scene row with a lane kernel, once per kernel the row chooses (the pendulum:
#: free, damped, driven; Duffing: free, driven), with a start
LANE_KERNELS = {
    "Pendulum": (S.Pendulum(g=9.0, length=1.2), [1.0, 0.2]),
    "Pendulum damped": (S.Pendulum(g=9.0, length=1.2, damping=0.3), [1.0, 0.2]),
    "Pendulum driven": (S.Pendulum(g=9.0, length=1.2, damping=0.1, drive_amplitude=0.5,
                                   drive_frequency=1.2), [1.0, 0.2]),
    "Duffing": (S.Duffing(-1.0, 1.0, delta=0.2), [1.0, 0.0]),
    "Duffing driven": (S.Duffing(-1.0, 1.0, delta=0.2, gamma=0.3, omega=1.2), [1.0, 0.0]),
    "VanDerPol": (S.VanDerPol(mu=1.5), [2.0, 0.0]),
    "Kepler": (S.Kepler(mu=1.2), [1.0, 0.0, 0.0, 1.1]),
    "RestrictedThreeBody": (S.RestrictedThreeBody(mu=0.1), [3.0, 0.0, 0.0, -2.5]),
    "Foucault": (S.Foucault(latitude=45.0, length=10.0, omega=0.3), [0.1, 0.0, 0.0, 0.0]),
    "HeavyTop": (S.HeavyTop(I1=1.0, I3=0.5, mass=1.0, l=0.7), [0.0, 0.5, 0.0, 0.0, 0.0, 10.0]),
}


@pytest.mark.parametrize("name", sorted(LANE_KERNELS))
def test_each_lane_takes_its_own_parameters(name):
    """solve_many in lanes with every nonzero parameter different in each trajectory
    (and each parameter spread differently): each trajectory is the scalar solve of
    the scene with its own parameters (the lane kernels read the parameters of their
    lane, not another lane's or another parameter's)."""
    scene, y0 = LANE_KERNELS[name]
    k = 11   # two lane groups
    names = [n for n, v in scene.params.items() if v != 0]
    params = {n: scene.params[n] * (1 + 0.2 * np.linspace(-1, 1, k) ** (j % 2 + 1)
                                    * (-1) ** j / (j + 1)) for j, n in enumerate(names)}
    te = np.linspace(0, 2, 5)
    kw = dict(t_eval=te, rtol=1e-10, atol=1e-12)
    e = mp.solve_many(scene, (0, 2), np.tile(y0, (k, 1)), params=params, lanes=True, **kw)
    assert e.lanes and e.success.all()
    worst = 0.0
    for i in range(k):
        s = mp.solve(scene.replace(**{n: float(v[i]) for n, v in params.items()}), (0, 2),
                     y0, **kw)
        worst = max(worst, np.abs(e.y[i] - s.y).max() / np.abs(s.y).max())
    assert worst < 2e-13, worst      # measured at most 1.6e-14 (Pendulum)


def test_rocket_burnout_switch_sets_the_dry_mass_and_cuts_the_thrust():
    """The burn-out switch of csrc/models/rocket.c, through a plain mp.solve (no break
    at the burn-out time: the engine locates the switch as an event).  After burn-out
    the mass is exactly m_dry (==): the switch's action sets it.  The located root
    alone mostly lands on g = m - m_dry = 0 exactly (the mass is linear in t), but
    not always: in the cases below (found by a scan of 400 random rockets, DOP853)
    the root is 1-4 ulps past the crossing, m_dry - m = 1.7e-18 ... 1.8e-15 without
    the action.  And a state with m = m_dry exactly is on the coasting branch:
    scene.rhs there is (v, -g - k v|v|/m, 0), no thrust, the closed form (one ulp
    above m_dry the thrust u b / m is on).  Pins the action's y[2] = m_dry and the
    branch at m = m_dry.  Measured: the mass == m_dry in all cases; rhs equal to the
    closed forms to 1 ulp (rtol 1e-14 allowed)."""
    g, k = 9.81, 0.02
    cases = [  # (m_dry, burn_rate, m0, rtol)
        (0.011450701520293923, 0.7935531956259836, 0.041209251605594556, 1e-6),
        (0.08963644533168423, 38.13786549466965, 0.15119132240034164, 1e-6),
        (13.747460997518361, 60.968065099494304, 17.697616350345697, 1e-6),
        (9.015084081721588, 93.77053132748121, 42.49743973488968, 1e-12),
        (180.0, 7.3, 950.0, 1e-10),
    ]
    for md, b, m0, tol in cases:
        r = mp.scenes.Rocket(exhaust_speed=2000.0, burn_rate=b, m0=m0, m_dry=md, g=g,
                             drag=k)
        tf = 2 * r.burnout_time
        s = mp.solve(r, (0.0, tf), r.initial_state(), rtol=tol, atol=tol * 1e-3)
        assert s.success and s.t[-1] == tf
        assert s.y[2, -1] == md, (md, s.y[2, -1] - md)
    u, b, md = 2100.0, 7.3, 180.0
    r = mp.scenes.Rocket(exhaust_speed=u, burn_rate=b, m0=950.0, m_dry=md, g=g, drag=k)
    for v in (350.0, -40.0, 0.0):
        f = r.rhs(0.0, np.array([1200.0, v, md]))
        np.testing.assert_allclose(f, [v, -g - k * v * abs(v) / md, 0.0], rtol=1e-14,
                                   atol=1e-14)
        above = np.array([1200.0, v, np.nextafter(md, np.inf)])
        np.testing.assert_allclose(r.rhs(0.0, above),
                                   [v, (u * b - k * v * abs(v)) / above[2] - g, -b],
                                   rtol=1e-14, atol=1e-14)


def test_rocket_symbolic_field_coasts_at_the_dry_mass():
    """The Rocket's symbolic field (Scene.symbolic(): the sensitivities' and the live
    pages' field) has the C rhs's burn-out branch: at m = m_dry exactly no thrust and no
    burn, (v, -g - k v|v|/m, 0); one ulp above, the thrust u b / m and m' = -b (closed
    forms, to 1e-14)."""
    import sympy as sp
    u, b, md, g, k = 2100.0, 7.3, 180.0, 9.81, 0.02
    r = mp.scenes.Rocket(exhaust_speed=u, burn_rate=b, m0=950.0, m_dry=md, g=g, drag=k)
    fld = r.symbolic()
    f = sp.lambdify([fld.y], [e.subs(fld.params) for e in fld.f], "math")
    for v in (350.0, -40.0, 0.0):
        np.testing.assert_allclose(f([1200.0, v, md]), [v, -g - k * v * abs(v) / md, 0.0],
                                   rtol=1e-14, atol=1e-14)
        m = np.nextafter(md, np.inf)
        np.testing.assert_allclose(f([1200.0, v, m]), [v, (u * b - k * v * abs(v)) / m - g, -b],
                                   rtol=1e-14, atol=1e-14)
