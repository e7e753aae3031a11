"""Sensitivities and fits through events with actions (mp.sensitivity / mp.fit with
``events``): the saltation jump against the bouncing ball's closed form and against
central differences of mp.solve with the same events; a damped pendulum striking a wall;
a Python action (with its Jacobian) at a moving wall; the refusal of a Python action
without one; a fit of restitution and gravity to a 60 fps track against a Monte Carlo
spread."""
import numpy as np
import pytest
import sympy as sp

import mechpy as mp
from mechpy.errors import EventError
from mechpy.tangent import _saltation
from ref_ode import central_sensitivities

G = 9.81


@pytest.fixture(scope="module")
def ball():
    """x'' = -g, state (x, v); e (the impact's restitution, by name) is a parameter
    that no equation uses."""
    x, v = mp.coordinates("x v")
    g = sp.Symbol("g")
    return mp.equations([v, -g], [x, v], params={"g": G, "e": 0.8})


def _ball_closed(h0, v0, e, g, T):
    """(x, v) at T of a ball thrown from (h0, v0) above a floor at 0: each flight a
    parabola, landing at s = (v + sqrt(v^2 + 2 g x)) / g, leaving at -e times the landing
    velocity.  Written so that complex arguments give derivatives by the complex step."""
    t, x, v = 0.0, h0, v0
    for _ in range(100):
        s = (v + np.sqrt(v * v + 2 * g * x)) / g
        if (t + s).real > T:
            s = T - t
            return np.array([x + v * s - g * s * s / 2, v - g * s])
        t, x, v = t + s, 0.0 * x, -e * (v - g * s)
    raise AssertionError("more than 100 bounces")


def _ball_S(h0, v0, e, g, T):
    """d(x, v)(T) / d(g, e, h0, v0) of the closed form, exact to round-off (complex step
    of size 1e-30)."""
    base = [h0, v0, e, g, T]
    out = np.empty((2, 4))
    for col, i in enumerate((3, 2, 0, 1)):
        z = [complex(b) for b in base]
        z[i] += 1e-30j
        out[:, col] = _ball_closed(*z).imag / 1e-30
    return out


def test_one_bounce_in_closed_form(ball):
    """After the first landing at t1 = sqrt(2 h0 / g), speed V = sqrt(2 g h0), the flight
    x = e V s - g s^2 / 2 (s = T - t1) gives dx/dh0 = -e + (1 + e) g s / V and
    dv/dh0 = (1 + e) g / V: the jump of S at the impact, not the free fall's 1 and 0."""
    h0, e, T = 1.0, 0.8, 0.7
    V, t1 = np.sqrt(2 * G * h0), np.sqrt(2 * h0 / G)
    s = mp.sensitivity(ball, (0, T), [h0, 0.0], params=("g", "e"), t_eval=[T],
                       events=mp.events.impact("x", restitution="e"), rtol=1e-12,
                       atol=1e-12)
    S = s.S[:, :, -1]
    want = [-e + (1 + e) * G * (T - t1) / V, (1 + e) * G / V]
    # measured 1.5e-14 (both columns)
    np.testing.assert_allclose(S[:, 2], want, rtol=0, atol=1e-13)
    assert abs(S[0, 2] - 1.0) > 0.5                   # not the free fall's dx/dh0 = 1
    # dv(T)/de = -V (the direct term: v+ = -e v-), dx(T)/de = -V s
    np.testing.assert_allclose(S[:, 1], [V * (T - t1), V], rtol=0, atol=1e-13)


def test_ball_sensitivities_match_the_closed_form(ball):
    """All four columns (g, e, h0, v0) after up to four bounces, thrown upwards."""
    h0, v0, e = 1.0, 0.5, 0.8
    te = np.array([0.3, 0.9, 1.5, 2.0, 2.2, 2.6])
    s = mp.sensitivity(ball.replace(e=e), (0, 2.6), [h0, v0], params=("g", "e"),
                       t_eval=te, events=mp.events.impact("x", restitution="e"),
                       rtol=1e-12, atol=1e-12)
    assert len(s.t_events[0]) == 4 and s.y_events[0].shape == (4, 2)
    want = np.stack([_ball_S(h0, v0, e, G, T) for T in te], axis=-1)
    np.testing.assert_allclose(s.y, np.stack([_ball_closed(h0, v0, e, G, T) for T in te],
                                             axis=-1), rtol=0, atol=3e-12)   # 3.2e-13
    # measured 3.1e-14 of max |S| (= 49)
    assert np.abs(s.S - want).max() <= 3e-13 * np.abs(want).max()


def test_ball_sensitivities_match_central_differences_of_solve(ball):
    """Thrown down from 1.2 m, e = 0.7 (the system's parameter, which the impact reads
    by name), three bounces: the four columns against central differences of mp.solve
    with the impact."""
    h0, v0, e = 1.2, -0.3, 0.7
    te = np.array([0.4, 1.1, 1.9])
    kw = dict(params=("g", "e"), t_eval=te, events=mp.events.impact("x", restitution="e"),
              rtol=1e-12, atol=1e-12)
    s = mp.sensitivity(ball.replace(e=e), (0, 1.9), [h0, v0], **kw)
    assert len(s.t_events[0]) == 3

    def run(gg=G, ee=e, yy=(h0, v0)):
        return mp.solve(ball.replace(g=gg), (0, 1.9), list(yy), t_eval=te, rtol=1e-13,
                        atol=1e-13, events=mp.events.impact("x", restitution=ee)).y

    d = 1e-5
    fd = np.stack([(run(gg=G + d) - run(gg=G - d)) / (2 * d),
                   (run(ee=e + d) - run(ee=e - d)) / (2 * d),
                   (run(yy=(h0 + d, v0)) - run(yy=(h0 - d, v0))) / (2 * d),
                   (run(yy=(h0, v0 + d)) - run(yy=(h0, v0 - d))) / (2 * d)], axis=1)
    # measured 1.8e-10 of max |S|: the differences' own error (they differ from the
    # closed form by as much, the sensitivities from it by 1.2e-14)
    assert np.abs(s.S - fd).max() <= 2e-9 * np.abs(fd).max()
    # the restitution is the system's at the call: at its default e = 0.8 all differs
    other = mp.sensitivity(ball, (0, 1.9), [h0, v0], **kw)
    assert np.abs(other.S - fd).max() > 1e-2 * np.abs(fd).max()


def test_pendulum_against_a_wall_matches_central_differences():
    """A damped pendulum released at 1 rad strikes a wall at theta = -0.2 three times
    in 4 s (restitution 0.6): the seven columns against central differences."""
    sc = mp.scenes.Pendulum(damping=0.2, length=1.2)
    wall = mp.events.impact("theta", wall=-0.2, restitution=0.6)
    y0 = np.array([1.0, 0.0])
    te = np.linspace(0.5, 4.0, 8)
    names = ("g", "length", "damping")
    s = mp.sensitivity(sc, (0, 4), y0, params=names, t_eval=te, events=wall,
                       rtol=1e-12, atol=1e-13)
    assert len(s.t_events[0]) == 3

    def run(scene, yy):
        return mp.solve(scene, (0, 4), yy, t_eval=te, events=wall, rtol=1e-13,
                        atol=1e-14).y

    fd = central_sensitivities(run, sc, y0, names)
    # measured 7.6e-10 of max |S| (1.0e-9 against differences at rtol 1e-12: theirs)
    assert np.abs(s.S - fd).max() <= 5e-9 * np.abs(fd).max()


@pytest.fixture(scope="module")
def oscillator():
    x, v = mp.coordinates("x v")
    w = sp.Symbol("w")
    return mp.equations([v, -w**2 * x], [x, v], params={"w": 3.0})


def _moving_wall(with_grad):
    """A wall at x = -0.5 + 0.1 t moving up at u = 0.1: the event g = x + 0.5 - u t
    (dg/dt = -u), the action x -> wall(t), v -> u - 0.7 (v - u): D_y a = diag(0, -0.7),
    D_t a = (u, 0)."""
    u = 0.1

    def hit(t, y):
        return y[0] + 0.5 - u * t

    def bounce(t, y):
        return np.array([-0.5 + u * t, u - 0.7 * (y[1] - u)])

    bounce.jac = lambda t, y: (np.diag([0.0, -0.7]), np.array([u, 0.0]))
    hit.direction = -1
    hit.action = bounce
    if with_grad:
        hit.grad = lambda t, y: (np.array([1.0, 0.0]), -u)
    return hit


@pytest.mark.parametrize("with_grad", [True, False])
def test_python_action_with_its_jacobian_at_a_moving_wall(oscillator, with_grad):
    """A Python event and action that depend on t (a_t and g_t in the saltation):
    against central differences of mp.solve with the same event; the event's gradient
    given (event.grad) or by differences of g."""
    ev = _moving_wall(with_grad)
    y0 = np.array([0.8, 0.0])
    te = np.linspace(0.3, 3.0, 10)
    s = mp.sensitivity(oscillator, (0, 3), y0, params=("w",), t_eval=te, events=ev,
                       rtol=1e-12, atol=1e-13)
    assert len(s.t_events[0]) == 2

    def run(sys, yy):
        return mp.solve(sys, (0, 3), yy, t_eval=te, events=ev, rtol=1e-13, atol=1e-14).y

    fd = np.empty_like(s.S)
    h = 1e-5
    fd[:, 0] = (run(oscillator.replace(w=3 + h), y0)
                - run(oscillator.replace(w=3 - h), y0)) / (2 * h)
    for j in range(2):
        d = np.zeros(2)
        d[j] = h
        fd[:, 1 + j] = (run(oscillator, y0 + d) - run(oscillator, y0 - d)) / (2 * h)
    # measured 1.8e-10 of max |S| either way (the differences' own error); without
    # D_t a the error is 5e-2, without dg/dt 7e-2
    assert np.abs(s.S - fd).max() <= 2e-9 * np.abs(fd).max()
    if not with_grad:
        # differences of g against its exact gradient: measured 2.1e-12 of max |S|
        ref = mp.sensitivity(oscillator, (0, 3), y0, params=("w",), t_eval=te,
                             events=_moving_wall(True), rtol=1e-12, atol=1e-13)
        assert np.abs(s.S - ref.S).max() <= 2e-11 * np.abs(ref.S).max()


def test_python_action_without_its_jacobian_is_refused(ball):
    """An action on y alone would leave S as the free flight's (dx/dh0 = 1 after the
    bounce, silently wrong): without action.jac the call refuses, naming it."""
    def hit(t, y):
        return y[0]

    def bounce(t, y):
        return np.array([0.0, -0.9 * y[1]])

    hit.direction = -1
    hit.action = bounce
    with pytest.raises(TypeError, match=r"events\[1\] has an action without its Jacobian.*"
                                        r"action\.jac"):
        mp.sensitivity(ball, (0, 1), [1.0, 0.0], params=("g",),
                       events=[lambda t, y: y[0] - 5.0, hit])
    t = np.linspace(0.1, 1.0, 10)
    with pytest.raises(TypeError, match="action.jac"):
        mp.fit(ball, t, np.zeros(10), {"g": 9.0}, y0=[1.0, 0.0], observe=0, events=hit)
    # given the Jacobian, the same action jumps S as the impact does (to round-off)
    bounce.jac = lambda t, y: np.diag([0.0, -0.9])
    kw = dict(params=("g",), t_eval=[0.3, 1.0], rtol=1e-12, atol=1e-12)
    a = mp.sensitivity(ball, (0, 1), [1.0, 0.0], events=hit, **kw)
    b = mp.sensitivity(ball, (0, 1), [1.0, 0.0],
                       events=mp.events.impact("x", restitution=0.9), **kw)
    np.testing.assert_allclose(a.S, b.S, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.S[:, :, -1], _ball_S(1.0, 0.0, 0.9, G, 1.0)[:, [0, 2, 3]],
                               rtol=0, atol=1e-11)


def test_grazing_crossing_raises():
    """g_t + g_y f = 0 at the crossing: the event time has no derivative."""
    S = np.eye(2)
    with pytest.raises(EventError, match="grazes"):
        _saltation(0.0, S, np.eye(2), 0.0, np.array([1.0, 0.0]), 0.0,
                   np.array([0.0, -9.81]), np.array([0.0, -9.81]), "events[0]")


def test_ensemble_equals_each_sensitivity(ball):
    y0s = np.array([[1.0, 0.0], [1.5, 0.2], [0.7, -1.0]])
    kw = dict(params=("g", "e"), t_eval=[0.5, 1.5], rtol=1e-11, atol=1e-12,
              events=mp.events.impact("x", restitution="e"))
    many = mp.sensitivity(ball, (0, 1.5), y0s, **kw)
    assert many.S.shape == (3, 2, 4, 2)
    for i, y0 in enumerate(y0s):
        one = mp.sensitivity(ball, (0, 1.5), y0, **kw)
        np.testing.assert_allclose(many.S[i], one.S, rtol=0, atol=1e-12)
        np.testing.assert_allclose(many.y_events[i][0], one.y_events[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(many.S[i][..., -1], _ball_S(*y0, 0.8, G, 1.5),
                                   rtol=0, atol=1e-10)


def test_fit_restitution_and_gravity_to_a_60fps_track(ball):
    """A ball dropped from 1 m, e = 0.8, tracked at 60 fps for 2 s (4 bounces) with
    5 mm noise: the fit of (g, e) from (9, 0.7) recovers them, and over 40 tracks the
    spread of the estimates matches the reported standard errors."""
    t = np.arange(1, 121) / 60.0
    imp = mp.events.impact("x", restitution="e")
    track = mp.solve(ball, (0, 2), [1.0, 0.0], t_eval=t, events=imp, rtol=1e-12,
                     atol=1e-12).y[:1]
    sigma = 0.005
    rng = np.random.default_rng(47)
    est, err = [], []
    for _ in range(40):
        data = track + sigma * rng.normal(size=track.shape)
        r = mp.fit(ball, t, data, {"g": 9.0, "e": 0.7}, y0=[1.0, 0.0], t0=0.0,
                   observe=0, sigma=sigma, events=imp, bounds=([1.0, 0.0], [20.0, 1.0]))
        assert r.success and r.names == ["g", "e"]
        est.append([r.params["g"], r.params["e"]])
        err.append([r.stderr["g"], r.stderr["e"]])
    est, err = np.array(est), np.array(err)
    # the estimates scatter about the truth by their standard errors (mean stderr
    # 0.0076 in g, 3.2e-4 in e; the mean's offset measured 0.16 and 0.07 of its own)
    mean_err = err.mean(axis=0)
    assert np.all(np.abs(est.mean(axis=0) - [G, 0.8]) < 4 * mean_err / np.sqrt(40))
    # the Monte Carlo spread over the reported standard error: measured 0.99 (g) and
    # 1.02 (e) here, 0.98 and 0.97 over 400 fits; with 40 fits the ratio's own
    # spread is about 0.11
    ratio = est.std(axis=0, ddof=1) / mean_err
    assert np.all((ratio > 0.7) & (ratio < 1.4)), ratio


def test_impact_at_a_shaking_table_matches_central_differences():
    """mp.events.impact at a moving wall A sin(w t) (a SymPy expression, compiled in the
    solve; its rate enters the saltation as g_t = -w' and the action's rate as
    (w', (1 + e) w'')): dy/d(g, e, y0) through four impacts against central differences
    of mp.solve with the same C impact; a wall that moves with a differentiated
    parameter is refused."""
    x, v = mp.coordinates("x v")
    g, e, A, w, t = sp.symbols("g e A w t")
    table = mp.equations([v, -g], [x, v], params={"g": G, "e": 0.7, "A": 0.02, "w": 12.0})
    ev = mp.events.impact("x", wall=A * sp.sin(w * t), restitution="e")
    y0 = np.array([0.3, 0.0])
    te = np.linspace(0.2, 0.95, 6)
    s = mp.sensitivity(table, (0, 0.95), y0, params=("g", "e"), t_eval=te, events=ev,
                       rtol=1e-12, atol=1e-13)
    assert len(s.t_events[0]) == 4

    def run(sc, yy):
        return mp.solve(sc, (0, 0.95), yy, t_eval=te, events=ev, rtol=1e-13, atol=1e-14).y

    fd = central_sensitivities(run, table, y0, ("g", "e"))
    # measured 2.5e-9 of max |S| (the differences' own error); without the wall's rate
    # in the action 0.2, without g_t 0.13
    err = np.abs(s.S - fd).max() / np.abs(fd).max()
    assert err <= 2e-8, err
    with pytest.raises(ValueError, match=r"the wall moves with \['A'\]"):
        mp.sensitivity(table, (0, 1.2), y0, params=("A",), events=ev)
