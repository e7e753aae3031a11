"""Events that change the state (mp.events, an event's action): bouncing balls,
a pendulum striking a wall, Newton's cradle, against their closed forms."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.special import ellipk

import mechpy as mp

G = 9.81


@pytest.fixture(scope="module")
def ball():
    """A ball in free fall, x'' = -g, compiled: state (x, v)."""
    x, v = mp.coordinates("x v")
    g = sp.Symbol("g")
    # e, the impact's restitution (swept through params), is a parameter of the
    # system that no equation uses
    return mp.equations([v, -g], [x, v], params={"g": G, "e": 0.9})


def _bounce_times(h0, e, k):
    """t_1 = sqrt(2 h0 / g), t_{j+1} = t_j + 2 e^j v1 / g."""
    v1 = np.sqrt(2 * G * h0)
    t = [np.sqrt(2 * h0 / G)]
    for j in range(1, k):
        t.append(t[-1] + 2 * e**j * v1 / G)
    return np.array(t), v1


def test_bouncing_ball_times_energy_and_rest(ball):
    e = 0.9
    sol = mp.solve(ball, (0, 20), [1.0, 0.0], events=mp.events.impact("x", restitution=e),
                   rtol=1e-12, atol=1e-12)
    tb, yb = sol.t_events[0], sol.y_events[0]
    want, v1 = _bounce_times(1.0, e, 20)
    # the first 20 bounce times to 1e-10 relative (4e-14 measured)
    assert np.max(np.abs(tb[:20] - want) / want) < 1e-10
    # the states before each action: at the floor, falling at e^j v1: the energy
    # after each bounce e^2 times the energy before (flights conserve it)
    assert np.max(np.abs(yb[:20, 0])) < 1e-12
    np.testing.assert_allclose(-yb[:20, 1], v1 * e ** np.arange(20), rtol=1e-10)
    Eb = 0.5 * yb[:, 1] ** 2
    np.testing.assert_allclose(Eb[1:20] / Eb[:19], e**2, rtol=1e-9)
    # at the accumulation time t_inf = t1 + 2 v1 e / (g (1 - e)) the ball comes to
    # rest on the floor (gravity pushes it there) and the solve goes on to the end
    t_inf = want[0] + 2 * v1 * e / (G * (1 - e))
    assert sol.status == 0 and sol.success
    assert sol.rests[0].shape == (1, 2) and sol.rests[0][0, 1] == np.inf
    assert abs(sol.rests[0][0, 0] - t_inf) < 1e-11 * t_inf   # 1.2e-13 relative measured
    assert abs(sol.t_events[0][-1] - t_inf) < 1e-11 * t_inf  # the accumulation recorded
    assert sol.t[-1] == 20.0 and np.all(sol.y[:, sol.t > t_inf] == 0.0)  # at rest
    assert sol.nfev < 20000                              # 242 bounces, ~3k evaluations
    # every sample between bounces is above the floor, each flight a parabola
    assert np.all(sol.y[0] > -1e-12)


def test_elastic_ball_keeps_its_energy_and_period(ball):
    sol = mp.solve(ball, (0, 10), [1.0, 0.0], events=mp.events.impact(0, restitution=1.0),
                   rtol=1e-12, atol=1e-12, dense_output=True)
    T = 2 * np.sqrt(2 * 1.0 / G)                          # a bounce's period
    tb = sol.t_events[0]
    np.testing.assert_allclose(np.diff(tb), T, rtol=1e-10)
    assert sol.status == 0 and len(tb) == int((10 - T / 2) // T) + 1
    h = sol.y[0] + sol.y[1] ** 2 / (2 * G)                # height the energy reaches
    assert np.max(np.abs(h - 1.0)) < 1e-10
    # the dense output is piecewise: each piece a parabola between bounces
    tq = tb[3] + np.linspace(0.01, T - 0.01, 7)
    xq = sol.sol(tq)[0]
    np.testing.assert_allclose(xq, np.sqrt(2 * G) * (tq - tb[3]) - G / 2 * (tq - tb[3]) ** 2,
                               rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("method", ["dop853", "dopri5", "radau", "rk4"])
def test_solve_many_restitutions_equal_each_solve(ball, method):
    """1000 restitutions through params (and as an array): on the scalar path each
    row equals its single solve, bit for bit; in SIMD lanes (each lane jumps on
    its own) to round-off, with the same statuses, counts and bounces."""
    k = 1000 if method == "dop853" else 40
    es = np.linspace(0.3, 0.95, k)
    kw = {"h": 1e-3} if method == "rk4" else {}
    te = np.linspace(0, 2, 5)
    imp = mp.events.impact("x", restitution="e")
    many = mp.solve_many(ball, (0, 2), np.tile([1.0, 0.0], (k, 1)), params={"e": es},
                         events=imp, t_eval=te, method=method, rtol=1e-10, atol=1e-12,
                         lanes=False, **kw)
    arr = mp.solve_many(ball, (0, 2), np.tile([1.0, 0.0], (k, 1)),
                        events=mp.events.impact("x", restitution=es), t_eval=te,
                        method=method, rtol=1e-10, atol=1e-12, lanes=False, **kw)
    assert np.array_equal(many.y, arr.y, equal_nan=True)
    if method != "radau":       # the lanes: a row with a lane kernel
        lan = mp.solve_many(ball, (0, 2), np.tile([1.0, 0.0], (k, 1)), params={"e": es},
                            events=imp, t_eval=te, method=method, rtol=1e-10, atol=1e-12,
                            **kw)
        assert lan.lanes and not many.lanes
        # a free fall is exact for every method: the lanes agree to round-off
        # (1.4e-13 measured), bounce for bounce
        np.testing.assert_allclose(lan.y, many.y, rtol=0, atol=1e-11, equal_nan=True)
        assert (lan.status == many.status).all()
        # near the accumulation point a step accepted on one path and rejected on the
        # other changes nfev (151 of 1000 rows, by 7.1% at most, measured), never the
        # bounces
        assert np.max(np.abs(lan.nfev / many.nfev - 1)) < 0.15
        for i in range(k):
            assert len(lan.t_events[i][0]) == len(many.t_events[i][0])
        for i in range(0, k, max(1, k // 50)):
            np.testing.assert_allclose(lan.t_events[i][0], many.t_events[i][0], rtol=1e-12)
    for i in (0, k // 2, k - 1):
        s = mp.solve(ball.replace(e=es[i]), (0, 2), [1.0, 0.0], events=imp, t_eval=te,
                     method=method, rtol=1e-10, atol=1e-12, **kw)
        m = s.y.shape[1]             # a ball at rest (Zeno) before t = 2: NaN after
        assert np.array_equal(s.y, many.y[i][:, :m]) and np.isnan(many.y[i][:, m:]).all()
        assert s.nfev == many.nfev[i] and s.status == many.status[i]
        assert s.message == many.message[i]
        assert np.array_equal(s.t_events[0], many.t_events[i][0])
    # against the closed form: the second bounce at t1 + 2 e v1 / g
    t1, v1 = np.sqrt(2 / G), np.sqrt(2 * G)
    second = np.array([te_[0][1] for te_ in many.t_events])
    tol = 1e-6 if method == "rk4" else 1e-8
    np.testing.assert_allclose(second, t1 + 2 * es * v1 / G, rtol=tol)


def test_pendulum_striking_a_wall():
    """From 1 rad onto a wall at theta = 0: the first impact after the exact
    quarter period K(sin^2(1/2)) sqrt(L/g); the rebound reaches the amplitude
    whose energy is e^2 times the first."""
    pend = mp.scenes.Pendulum()
    e = 0.6
    up = lambda t, y: y[1]            # noqa: E731  theta_dot = 0: the turning points
    up.direction = -1
    sol = mp.solve(pend, (0, 1.5), [1.0, 0.0], rtol=1e-12, atol=1e-12,
                   events=[mp.events.impact("theta", restitution=e), up])
    K = ellipk(np.sin(0.5) ** 2) / np.sqrt(G)
    assert abs(sol.t_events[0][0] - K) < 1e-10 * K
    after = sol.t_events[1] > sol.t_events[0][0]   # (the release at t = 0 is one too)
    amp = sol.y_events[1][after][0][0]             # the first turning point after the rebound
    # 1 - cos(amp) = e^2 (1 - cos 1)
    assert abs((1 - np.cos(amp)) - e**2 * (1 - np.cos(1.0))) < 1e-11
    # and it is reached a quarter period of that amplitude after the impact
    Ka = ellipk(np.sin(amp / 2) ** 2) / np.sqrt(G)
    assert abs(sol.t_events[1][after][0] - sol.t_events[0][0] - Ka) < 1e-9


@pytest.fixture(scope="module")
def cradle():
    """Three equal point masses on a line, free between collisions."""
    xs = mp.coordinates("x1 x2 x3 v1 v2 v3")
    return mp.equations([xs[3], xs[4], xs[5], 0, 0, 0], list(xs))


def _collision(i, e):
    """Balls i and i+1 (equal masses) meet: the gap x_{i+1} - x_i reaches 0."""
    def gap(t, y):
        return y[i + 1] - y[i]

    def action(t, y):
        y = np.array(y)
        a, b = y[3 + i], y[4 + i]
        y[3 + i] = 0.5 * ((1 - e) * a + (1 + e) * b)
        y[4 + i] = 0.5 * ((1 + e) * a + (1 - e) * b)
        y[i + 1] = y[i]                 # exactly in contact
        return y

    gap.direction, gap.action = -1, action
    return gap


@pytest.mark.parametrize("e", [1.0, 0.7])
def test_newtons_cradle(cradle, e):
    """Ball 1 at 1 m/s hits balls 2 and 3 at rest: momentum is conserved through
    every collision; each one keeps (1 + e^2)/2 of the pair's relative... the
    closed forms: e = 1 hands the velocity on (ball 3 leaves at 1 m/s, the
    others at rest); e < 1 loses (1 - e^2)/4 m v_rel^2 per collision."""
    y0 = [-1.0, 0.0, 0.5, 1.0, 0.0, 0.0]
    sol = mp.solve(cradle, (0, 5), y0, events=[_collision(0, e), _collision(1, e)],
                   rtol=1e-12, atol=1e-12)
    v = sol.y[3:]
    np.testing.assert_allclose(v.sum(axis=0), 1.0, rtol=0, atol=1e-14)     # momentum
    E = 0.5 * (v**2).sum(axis=0)
    # the energy lost at each collision: (1 - e^2)/4 v_rel^2 (equal unit masses)
    lost = 0.0
    for k, (tk, yk) in enumerate(zip(sol.t_events, sol.y_events)):
        for y in yk:
            lost += (1 - e**2) / 4 * (y[3 + k] - y[4 + k]) ** 2
    assert abs(E[-1] - (0.5 - lost)) < 1e-13
    assert np.all(np.diff(sol.y[:3], axis=0)[:, -1] >= -1e-12)   # never pass each other
    if e == 1.0:
        np.testing.assert_allclose(sol.t_events[0], [1.0], rtol=1e-12)
        np.testing.assert_allclose(sol.t_events[1], [1.5], rtol=1e-12)
        np.testing.assert_allclose(v[:, -1], [0.0, 0.0, 1.0], atol=1e-13)
    else:   # the first collision: the closed form of a target at rest
        assert abs(E[np.searchsorted(sol.t, 1.2)] - 0.5 * (1 + e**2) / 2) < 1e-13


@pytest.mark.parametrize("method", ["dop853", "dopri5", "rk4"])
def test_impact_oscillators_in_lanes_equal_the_scalar_path(method):
    """A pendulum striking a wall, 200 restitutions, in lanes and one by one: the
    same impacts (count and times to round-off), statuses, nfev and samples,
    backwards too; max_events ends each lane on its own."""
    pend = mp.scenes.Pendulum()
    k = 200
    es = np.linspace(0.5, 0.95, k)
    kw = {"h": 1e-3} if method == "rk4" else {}
    for span in ((0.0, 5.0), (0.0, -5.0)):
        te = np.linspace(*span, 11)
        imp = mp.events.impact("theta", restitution=es)
        a, b = (mp.solve_many(pend, span, np.tile([1.0, 0.0], (k, 1)), t_eval=te, events=imp,
                              method=method, rtol=1e-10, atol=1e-12, lanes=lanes, **kw)
                for lanes in (True, False))
        assert a.lanes and not b.lanes
        np.testing.assert_allclose(a.y, b.y, rtol=0, atol=1e-12)       # 4.5e-14 measured
        assert (a.status == b.status).all() and (a.nfev == b.nfev).all()
        for i in range(k):
            assert len(a.t_events[i][0]) == len(b.t_events[i][0]) == 5
            np.testing.assert_allclose(a.t_events[i][0], b.t_events[i][0], rtol=0, atol=1e-13)
            np.testing.assert_allclose(a.y_events[i][0], b.y_events[i][0], rtol=0, atol=1e-12)
    imp = mp.events.impact("theta", restitution=es)
    imp.max_events = 3
    a, b = (mp.solve_many(pend, (0, 5), np.tile([1.0, 0.0], (k, 1)), t_eval=[5.0], events=imp,
                          method=method, lanes=lanes, **kw) for lanes in (True, False))
    assert (a.status == 1).all() and (b.status == 1).all()
    assert all(len(x[0]) == 3 for x in a.t_events)
    assert a.message[0] == b.message[0] or "reached max_events=3" in a.message[0]


def test_max_events_and_terminal(ball):
    imp = mp.events.impact("x", restitution=0.9)
    imp.max_events = 5
    sol = mp.solve(ball, (0, 20), [1.0, 0.0], events=imp, rtol=1e-10)
    assert sol.status == 1 and len(sol.t_events[0]) == 5
    assert "events[0] reached max_events=5" in sol.message
    want, _ = _bounce_times(1.0, 0.9, 5)
    assert abs(sol.t[-1] - want[-1]) < 1e-8
    # a terminal event with an action stops instead (the action not applied)
    imp2 = mp.events.impact("x", restitution=0.9)
    imp2.terminal = True
    s2 = mp.solve(ball, (0, 20), [1.0, 0.0], events=imp2, rtol=1e-10)
    assert s2.status == 1 and s2.y[1, -1] < 0 and len(s2.t_events[0]) == 1
    with pytest.raises(ValueError, match="both terminal and max_events"):
        imp2.max_events = 3
        mp.solve(ball, (0, 20), [1.0, 0.0], events=imp2)


def test_bad_actions_name_the_event(ball):
    def g(t, y):
        return y[0]
    g.direction = -1

    g.action = lambda t, y: [0.0, 1.0, 2.0]
    with pytest.raises(ValueError, match=r"events\[0\]\.action returned shape \(3,\)"):
        mp.solve(ball, (0, 2), [1.0, 0.0], events=g)
    g.action = lambda t, y: [np.nan, 1.0]
    with pytest.raises(mp.NonFiniteError, match=r"events\[0\]\.action returned NaN"):
        mp.solve(ball, (0, 2), [1.0, 0.0], events=g)
    # an action that leaves the ball above the floor still falling: it fires again at once
    g.action = lambda t, y: [abs(y[0]), y[1]]
    with pytest.raises(mp.EventError, match=r"events\[0\] at t = 0\.45"):
        mp.solve(ball, (0, 2), [1.0, 0.0], events=g)
    g.action = 3.0
    with pytest.raises(TypeError, match=r"events\[0\]\.action must be callable"):
        mp.solve(ball, (0, 2), [1.0, 0.0], events=g)
    with pytest.raises(ValueError, match="not a coordinate"):
        mp.solve(ball, (0, 2), [1.0, 0.0], events=mp.events.impact("y"))
    with pytest.raises(ValueError, match="not a parameter"):
        mp.solve(ball, (0, 2), [1.0, 0.0], events=mp.events.impact("x", restitution="mu"))
    with pytest.raises(ValueError, match="restitution must be >= 0"):
        mp.events.impact("x", restitution=-0.5)
    with pytest.raises(ValueError, match="side"):
        mp.events.impact("x", side=2)
    with pytest.raises(ValueError, match="for solve_many"):
        mp.solve(ball, (0, 2), [1.0, 0.0], events=mp.events.impact("x", restitution=[0.5]))


@pytest.mark.parametrize("method", ["dop853", "dopri5", "radau"])
def test_fires_again_at_once_is_relative_to_t(method):
    """An action that leaves a falling ball d above the floor: it crosses again d / |v|
    later.  "At once" is within the root finder's resolution in t, 4 eps (|t| + |h|): the
    same drop at t0 = 1000, d = 1e-13 and 1e-12 (a new crossing 2e-14 and 2e-13 s later,
    below 2 ulps of t = 1000.45), is an EventError; at t0 = 0 the same d = 1e-12 gives a
    crossing 2e-13 s later, 4000 ulps of t = 0.45: two actions, an accumulation (Zeno)."""
    def f(t, y):
        return [y[1], -G]

    for t0, d, again in [(1000.0, 1e-13, True), (1000.0, 1e-12, True), (0.0, 1e-12, False)]:
        def g(t, y):
            return y[0]
        g.direction = -1
        g.action = lambda t, y: [abs(y[0]) + d, y[1]]
        t_hit = t0 + np.sqrt(2 / G)
        if again:
            with pytest.raises(mp.EventError, match=r"fires again at once"):
                mp.solve(f, (t0, t0 + 2), [1.0, 0.0], events=g, method=method, max_steps=3000)
        else:
            s = mp.solve(f, (t0, t0 + 2), [1.0, 0.0], events=g, method=method,
                         max_steps=3000)
            assert s.status == 1 and "accumulate (Zeno)" in s.message
            assert len(s.t_events[0]) == 2
            assert abs(s.t_events[0][0] - t_hit) < 1e-12
            assert 0 < s.t_events[0][1] - s.t_events[0][0] < 1e-12


def test_python_action_and_backward_solve():
    """A harmonic oscillator x'' = -x reflected at x = 0 (e = 1): |x| of the free
    oscillator; backwards in time the same reflection, the events mirrored."""
    def f(t, y):
        return [y[1], -y[0]]

    def wall(t, y):
        return y[0]
    wall.direction = -1
    wall.action = lambda t, y: np.array([0.0, -y[1]])
    sol = mp.solve(f, (0, 10), [1.0, 0.0], events=wall, rtol=1e-12, atol=1e-12,
                   t_eval=np.linspace(0, 10, 101))
    np.testing.assert_allclose(sol.y[0], np.abs(np.cos(sol.t)), atol=1e-9)
    np.testing.assert_allclose(sol.t_events[0], np.pi / 2 + np.pi * np.arange(3), rtol=1e-11)
    back = mp.solve(f, (0, -10), [1.0, 0.0], events=wall, rtol=1e-12, atol=1e-12,
                    t_eval=np.linspace(0, -10, 101))
    np.testing.assert_allclose(back.y[0], np.abs(np.cos(back.t)), atol=1e-9)
    np.testing.assert_allclose(back.t_events[0], -(np.pi / 2 + np.pi * np.arange(3)),
                               rtol=1e-11)


U, B, M0, MD = 2500.0, 10.0, 1000.0, 200.0


def test_any_solve_of_the_rocket_crosses_burn_out():
    """Burn-out is a switch the engine crosses: a plain solve past it (no t_span
    break) gives Tsiolkovsky's v = u ln(m0/m_dry) and then coasts."""
    r = mp.scenes.Rocket(exhaust_speed=U, burn_rate=B, m0=M0, m_dry=MD)
    for method in ("dop853", "dopri5", "radau"):
        s = mp.solve(r, (0, 85), [0, 0, M0], method=method, rtol=1e-10, atol=1e-10,
                     t_eval=[40.0, 85.0])
        assert s.success and s.status == 0
        np.testing.assert_allclose(s.y[1], U * np.log(M0 / np.array([M0 - B * 40, MD])),
                                   rtol=1e-8)
        assert s.y[2, -1] == MD                     # the mass exactly dry after the switch
    # in an ensemble too (the scalar path: a switch is an event)
    e = mp.solve_many(r, (0, 85), [[0, 0, M0], [0, 0, 600.0]], rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(e.y[:, 1, -1], U * np.log(np.array([M0, 600.0]) / MD),
                               rtol=1e-8)
    assert not e.lanes


def test_rocket_lands_sits_and_never_lifts_off():
    g = 9.81
    # lands: a terminal event at height 0 on the way down, after a ballistic coast
    r = mp.scenes.Rocket(exhaust_speed=U, burn_rate=B, m0=M0, m_dry=MD, g=g)
    s = r.fly((0, 2000))
    tb = 80.0
    vb = U * np.log(M0 / MD) - g * tb
    hb = U / B * (M0 - MD - MD * np.log(M0 / MD)) - 0.5 * g * tb**2
    t_land = tb + (vb + np.sqrt(vb**2 + 2 * g * hb)) / g
    assert s.status == 1 and "lands" in s.message
    assert abs(s.t[-1] - t_land) < 1e-6 * t_land and abs(s.y[0, -1]) < 1e-6
    assert np.all(s.y[0] > -1e-6)
    # thrust 2500*2 = 5000 N below the launch weight 9810 N: it sits on the pad
    # until m = u b / g, then lifts off (never below the ground)
    slow = mp.scenes.Rocket(exhaust_speed=U, burn_rate=2.0, m0=M0, m_dry=MD, g=g)
    t = np.linspace(0, 300, 31)
    s = slow.fly((0, 300), t_eval=t, rtol=1e-10, atol=1e-8)
    m_lift = U * 2.0 / g
    t_lift = (M0 - m_lift) / 2.0
    assert np.all(s.y[0] >= 0) and np.all(s.y[0][t <= t_lift] == 0)
    np.testing.assert_allclose(s.y[2], np.maximum(M0 - 2.0 * t, MD), rtol=1e-12)
    # after lift-off v' = u b / m - g with m = m_lift - b (t - t_lift):
    # v = u ln(m_lift / m) - g (t - t_lift)
    k = t > t_lift
    m = M0 - 2.0 * t[k]
    np.testing.assert_allclose(s.y[1][k], U * np.log(m_lift / m) - g * (t[k] - t_lift),
                               rtol=1e-8, atol=1e-8)
    # thrust never above the weight, not even dry: it rests, and says so
    heavy = mp.scenes.Rocket(exhaust_speed=U, burn_rate=0.5, m0=M0, m_dry=MD, g=g)
    s = heavy.fly((0, 100))
    assert s.success and np.all(s.y[:2] == 0) and "never lifts off" in s.message


def test_impact_as_a_python_event_and_its_checks():
    """The Impact's own event function and action (for a Python event list), its
    index rules, and the restitution checked when the solve reads it."""
    floor = mp.events.impact(0, wall=0.3, restitution=0.5)
    ceiling = mp.events.impact(0, wall=0.3, restitution=0.5, side=-1)
    assert floor(0.0, [1.0, -2.0]) == pytest.approx(0.7, abs=1e-15)
    assert ceiling(0.0, [1.0, -2.0]) == pytest.approx(-0.7, abs=1e-15)
    assert floor.action(0.0, [0.3 - 1e-9, -2.0]).tolist() == [0.3, 1.0]
    # the Python function gives the C impact's crossings: x'' = -x from 1, wall at 0.3
    def f(t, y):
        return [y[1], -y[0]]

    def g(t, y):
        return floor(t, y)
    g.direction, g.action = -1, floor.action
    py = mp.solve(f, (0, 4), [1.0, 0.0], events=g, rtol=1e-12, atol=1e-12)
    c = mp.solve(f, (0, 4), [1.0, 0.0], events=floor, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(py.t_events[0], c.t_events[0], rtol=1e-12)
    np.testing.assert_allclose(c.t_events[0][0], np.arccos(0.3), rtol=1e-12)
    # a velocity's index is not a coordinate: (q, v) with q = y[:n/2]
    with pytest.raises(ValueError, match="coordinate 1 needs a state"):
        mp.solve(f, (0, 1), [1.0, 0.0], events=mp.events.impact(1))
    # the restitution as the solve reads it: a negative one set after the fact is refused,
    # 0 (the velocity stops) is allowed
    late = mp.events.impact(0, restitution=0.5)
    late.restitution = -0.5
    with pytest.raises(ValueError, match="restitution must be >= 0"):
        mp.solve(f, (0, 4), [1.0, 0.0], events=late)
    stop = mp.events.impact(0, restitution=0.0)
    stop.terminal = True
    s = mp.solve(f, (0, 4), [1.0, 0.0], events=stop, rtol=1e-12, atol=1e-12)
    assert s.status == 1 and abs(s.t[-1] - np.pi / 2) < 1e-10


# ---- contact: floors anywhere, grazing, rest, sticking, lift-off -------------------------

def _table(A, w, **extra):
    """A ball x'' = -g over a table at A sin(w t) (A and w: parameters of the wall alone)."""
    x, v = mp.coordinates("x v")
    return mp.equations([v, -sp.Symbol("g")], [x, v], params={"g": G, "A": A, "w": w, **extra})


@pytest.mark.parametrize("wall", [0.0, 1e-3, 0.1, 1.0, 1000.3, -5.0, 1e6])
@pytest.mark.parametrize("e", [0.5, 0.9])
def test_ball_on_a_floor_anywhere_bounces_and_rests(ball, wall, e):
    """A ball dropped 1 m onto a floor at `wall`: never below it by more than a few ulps,
    the bounces at t_k = t1 + 2 e v1 (1 - e^k) / (g (1 - e)), at rest from t_inf =
    t1 + 2 e v1 / (g (1 - e)) on (the floor far from 0 once let it fall through)."""
    T = 3.0 if e == 0.5 else 12.0
    ev = mp.events.impact("x", wall=wall, restitution=e)
    sol = mp.solve(ball, (0, T), [wall + 1.0, 0.0], events=ev, rtol=1e-12, atol=1e-12,
                   dense_output=True)
    scale = max(1.0, abs(wall))
    t1, v1 = np.sqrt(2 / G), np.sqrt(2 * G)
    t_inf = t1 + 2 * e * v1 / (G * (1 - e))
    assert sol.status == 0 and sol.t[-1] == T
    ulps = 64 * np.spacing(scale)      # the located root's side: 8.3e-15 at most measured
    assert (sol.y[0] - wall).min() >= -ulps
    tq = np.linspace(0, T, 20001)
    assert (sol.sol(tq)[0] - wall).min() >= -ulps
    tb = sol.t_events[0][:-1]                    # the last: the accumulation point
    k = np.arange(len(tb))
    want = t1 + 2 * e * v1 / G * (1 - e ** k) / (1 - e)
    # bounce times and t_inf to the integration's accuracy at the wall's scale (rtol
    # 1e-12 of |x|): |t_inf error| / sqrt(scale) measured 7.7e-12 to 1.3e-11 (e = 0.5),
    # 5.7e-11 to 2.6e-10 (e = 0.9) for walls at 1, 1000.3 and 1e6; 1.3e-14 at 0
    bound = (1e-10 if e == 0.5 else 2e-9) * np.sqrt(scale)
    assert np.abs(tb - want).max() < bound
    assert sol.rests[0].shape == (1, 2) and sol.rests[0][0, 1] == np.inf
    assert abs(sol.rests[0][0, 0] - t_inf) < bound
    assert np.all(sol.y[:, sol.t > sol.rests[0][0, 0]] == [[wall], [0.0]])
    # the same in solve_many, in lanes and on the scalar path: the same answer
    tev = np.linspace(0, T, 301)
    for lanes in (True, False):
        ens = mp.solve_many(ball, (0, T), [[wall + 1.0, 0.0]] * 3, t_eval=tev, events=ev,
                            rtol=1e-12, atol=1e-12, lanes=lanes)
        assert ens.success.all()
        np.testing.assert_array_equal(ens.t_events[1][0], sol.t_events[0])
        np.testing.assert_array_equal(ens.rests[2][0], sol.rests[0])
        assert (ens.y[:, 0] - wall).min() >= -ulps


def test_grazing_impacts_are_not_missed():
    """A pendulum released at 0.5 rad against a wall at -0.3 rad (e = 0.5) for 200 s:
    every touch is an impact, the swing never passes the wall (it dipped 87 times, up
    to 2.1e-5 rad, where g dips below 0 and back between two sub-points)."""
    pend = mp.scenes.Pendulum()
    sol = mp.solve(pend, (0, 200), [0.5, 0.0],
                   events=mp.events.impact("theta", wall=-0.3, restitution=0.5),
                   rtol=1e-10, atol=1e-12, dense_output=True)
    assert sol.success
    th = sol.sol(np.linspace(0, 200, 100001))[0]
    assert th.min() >= -0.3 - 1e-12                     # 2.9e-11 above it measured
    assert len(sol.t_events[0]) > 30


def test_restitution_zero_rests_at_once_and_rides_the_table():
    """e = 0 under gravity rests at once on a fixed floor; on a table vibrating with
    A w^2 < g the ball rides it from its first touch, to 1e-10."""
    b = _table(0.01, 20.0)
    x = sp.Symbol("x")
    t, A, w = sp.symbols("t A w")
    sol = mp.solve(b, (0, 2), [0.5, 0.0], events=mp.events.impact("x", restitution=0.0),
                   rtol=1e-12, atol=1e-12)
    t1 = np.sqrt(2 * 0.5 / G)
    assert sol.status == 0 and len(sol.t_events[0]) == 1
    assert abs(sol.rests[0][0, 0] - t1) < 1e-12 and sol.rests[0][0, 1] == np.inf
    assert np.all(sol.y[:, sol.t > t1] == 0.0)
    del x
    sol = mp.solve(b, (0, 3), [0.01, 0.2], events=mp.events.impact("x", wall=A * sp.sin(w * t),
                                                                     restitution=0.0),
                   rtol=1e-12, atol=1e-12, dense_output=True)
    assert sol.status == 0 and sol.rests[0].shape == (1, 2)
    ts = np.linspace(sol.rests[0][0, 0], 3, 5001)
    y = sol.sol(ts)
    np.testing.assert_allclose(y[0], 0.01 * np.sin(20 * ts), rtol=0, atol=1e-10)
    np.testing.assert_allclose(y[1], 0.2 * np.cos(20 * ts), rtol=0, atol=1e-9)


def test_a_table_that_shakes_harder_than_g_throws_the_ball_off():
    """A w^2 > g: the ball resting on the table lifts off where the table's acceleration
    -A w^2 sin(w t) reaches -g (sin(w t) = g / (A w^2)), each period; and the period-1
    orbit (one bounce a period T = 2 pi / w) has its impact phase at
    cos(phi) = g T (1 - e) / (2 A w (1 + e))."""
    t, A, w = sp.symbols("t A w")
    b = _table(0.05, 20.0)
    sol = mp.solve(b, (0, 1.0), [0.0, 1.0], rtol=1e-12, atol=1e-12,
                   events=mp.events.impact("x", wall=A * sp.sin(w * t), restitution=0.0))
    assert sol.success
    lift = sol.rests[0][:, 1]
    phi = np.arcsin(G / (0.05 * 400))
    want = phi / 20 + 2 * np.pi / 20 * np.arange(len(lift))
    assert len(lift) >= 3
    np.testing.assert_allclose(lift, want, rtol=0, atol=1e-12)   # 4e-18 measured (first)
    e, Av, wv = 0.8, 0.02, 30.0
    b = _table(Av, wv)
    T = 2 * np.pi / wv
    ph = np.arccos(G * T * (1 - e) / (2 * Av * wv * (1 + e)))
    t0 = ph / wv
    sol = mp.solve(b, (t0, t0 + 5 * T + 1e-3), [Av * np.sin(ph), G * T / 2],
                   events=mp.events.impact("x", wall=A * sp.sin(w * t), restitution=e),
                   rtol=1e-12, atol=1e-12)
    te = sol.t_events[0]
    assert len(te) == 5
    np.testing.assert_allclose(te, t0 + T * np.arange(1, 6), rtol=0, atol=1e-12)  # 1.1e-13


def test_tiny_restitutions_and_late_starts_rest():
    """Restitutions of 1e-4 to 1e-8 rest after a few bounces (they raised EventError);
    the same drop at t0 = 5000 rests at t0 + t_inf (10^7 bounces of 3e-11 s before)."""
    x, v = mp.coordinates("x v")
    b = mp.equations([v, -sp.Symbol("g")], [x, v], params={"g": G})
    t1, v1 = np.sqrt(2 / G), np.sqrt(2 * G)
    for e in (1e-3, 1e-4, 1e-5, 1e-6, 1e-8):
        s = mp.solve(b, (0, 2), [1.0, 0.0], events=mp.events.impact("x", restitution=e),
                     rtol=1e-12, atol=1e-12)
        t_inf = t1 + 2 * e * v1 / (G * (1 - e))
        assert s.status == 0 and abs(s.rests[0][0, 0] - t_inf) < 1e-12
    for t0 in (0.0, 5000.0):
        s = mp.solve(b, (t0, t0 + 3), [1.0, 0.0], events=mp.events.impact("x", restitution=0.5),
                     rtol=1e-12, atol=1e-12, max_steps=100000)
        t_inf = t0 + t1 + 2 * 0.5 * v1 / (G * 0.5)
        assert s.status == 0 and abs(s.rests[0][0, 0] - t_inf) < 1e-9 * max(1, t0)


def test_a_kick_goes_on_through_the_surface_the_same_with_every_method():
    """An action that changes the speed only (a kick at x = 0, the motion going on
    through it): one answer whatever the method (it raised EventError with dop853)."""
    def f(t, y):
        return [y[1], 0.0]

    def g(t, y):
        return y[0]
    g.direction = -1
    g.action = lambda t, y: [y[0], 2.0 * y[1]]
    for method in ("dop853", "dopri5", "radau", "gsl:rkf45"):
        s = mp.solve(f, (0, 2), [1.0, -1.0], events=g, method=method, rtol=1e-10, atol=1e-12)
        assert s.success and len(s.t_events[0]) == 1
        assert abs(s.t_events[0][0] - 1.0) < 1e-9
        np.testing.assert_allclose(s.y[:, -1], [-2.0, -2.0], rtol=1e-8)


@pytest.mark.parametrize("method", ["gsl:rk2", "gsl:rk4", "gsl:rkf45", "gsl:rkck", "gsl:rk8pd",
                                    "gsl:rk2imp", "gsl:rk4imp", "gsl:msadams", "gsl:msbdf",
                                    "BDF", "RK45", "LSODA"])
def test_every_method_bounces_and_rests(ball, method):
    """The ball dropped 1 m with e = 0.5 (floor at 1: far from 0) with GSL's steppers and
    SciPy's names at rtol = atol = 1e-12: the first bounces at the closed form, at rest
    near t_inf, never below the floor.  (GSL's multistep rows kept their history across
    an action: 'fires again at once'; rk2 ended in a false accumulation after one
    bounce, rk8pd's accumulation was 4.6e-5 s early.)  The multistep rows restart at
    order 1 after each bounce: their short flights drift (t_inf 3.6e-6 early measured,
    the first 8 bounces 1.4e-9); the one-step rows' t_inf to 1.4e-10, bounces 3e-14."""
    e, wall = 0.5, 1.0
    s = mp.solve(ball, (0, 3), [wall + 1.0, 0.0], method=method, rtol=1e-12, atol=1e-12,
                 events=mp.events.impact("x", wall=wall, restitution=e))
    t1, v1 = np.sqrt(2 / G), np.sqrt(2 * G)
    k = np.arange(8)
    want = t1 + 2 * e * v1 / G * (1 - e ** k) / (1 - e)
    multistep = method in ("gsl:msadams", "gsl:msbdf", "BDF")
    assert s.status == 0
    np.testing.assert_allclose(s.t_events[0][:8], want, rtol=0,
                               atol=1e-8 if multistep else 3e-13)
    t_inf = t1 + 2 * e * v1 / (G * (1 - e))
    assert abs(s.rests[0][0, 0] - t_inf) < (2e-5 if multistep else 1e-9)
    assert s.y[0].min() >= wall - 1e-14


def test_chattering_on_a_shaking_table_in_lanes_and_alone():
    """A ball on a table shaking at 40 rad/s (A w^2 from 3 to 32 m/s^2 across the rows):
    bouncing, chattering (hundreds of impacts at relative speeds down to the tolerance,
    which raised 'fires again at once'), sticking and lifting off each period.  Never
    below the table (1.2e-13 measured); solve_many's lanes, its scalar path and lone
    solves at each row's parameters equal to the bit."""
    t, A, w = sp.symbols("t A w")
    b = _table(0.01, 40.0)
    wall = A * sp.sin(w * t)
    for e in (0.3, 0.6, 0.9):
        s = mp.solve(b, (0, 10), [0.05, 0.0], events=mp.events.impact("x", wall=wall,
                                                                        restitution=e),
                     rtol=1e-10, atol=1e-12, dense_output=True)
        assert s.status == 0
        ts = np.linspace(0, 10, 100001)
        assert (s.sol(ts)[0] - 0.01 * np.sin(40 * ts)).min() > -1e-12
        if e == 0.3:
            assert len(s.t_events[0]) > 300 and len(s.rests[0]) > 30   # chatters, sticks
    rows = np.array([[G, a, 40.0] for a in np.linspace(0.002, 0.02, 8)])
    tev = np.linspace(0, 5, 501)
    ev = mp.events.impact("x", wall=wall, restitution=0.5)
    ens = [mp.solve_many(b, (0, 5), [[0.05, 0.0]] * 8, params=rows, t_eval=tev, events=ev,
                         rtol=1e-10, atol=1e-12, lanes=lanes) for lanes in (True, False)]
    assert ens[0].lanes and not ens[1].lanes and ens[0].success.all()
    np.testing.assert_array_equal(ens[0].y, ens[1].y)
    assert sum(len(r[0]) for r in ens[0].rests) > 10            # some rows rested
    for i in (0, 2, 3, 7):
        s = mp.solve(b.replace(A=rows[i, 1]), (0, 5), [0.05, 0.0], t_eval=tev, events=ev,
                     rtol=1e-10, atol=1e-12)
        np.testing.assert_array_equal(s.y, ens[0].y[i])
        np.testing.assert_array_equal(s.t_events[0], ens[0].t_events[i][0])
        np.testing.assert_array_equal(s.rests[0], ens[1].rests[i][0])


@pytest.mark.parametrize("wall", [0.0, 0.1, 1.0, 1000.3, -5.0, 1e6])
def test_a_python_bounce_on_a_floor_anywhere_ends_at_its_accumulation(wall):
    """The same drop with a Python event and action (the driver knows neither g' nor
    the force): no fall-through whatever the wall; once the state leaves the floor and
    is back before g can show it (the field at the action points away from the floor:
    not a kick), the bounces have accumulated: status 1, the message naming the event,
    the end before t_inf by the flights left unresolved (measured 8.3e-13 s at a floor
    at 0, 1.4e-8 s at 1, 4.5e-7 s at 1000.3, 1.5e-5 s at 1e6: flights ~ sqrt(an ulp of
    the wall's position); an impact, whose g' and force are known, rests at t_inf)."""
    def f(t, y):
        return [y[1], -G]

    def g(t, y):
        return y[0] - wall
    g.direction = -1
    g.action = lambda t, y: [wall, -0.5 * y[1]]
    s = mp.solve(f, (0, 3), [wall + 1.0, 0.0], events=g, rtol=1e-12, atol=1e-12)
    t_inf = np.sqrt(2 / G) + 2 * 0.5 * np.sqrt(2 * G) / (G * 0.5)
    assert s.status == 1 and "events[0] accumulate (Zeno)" in s.message
    assert (s.y[0] - wall).min() >= -64 * np.spacing(max(1.0, abs(wall)))
    assert 0 <= t_inf - s.t[-1] < 2e-7 * np.sqrt(max(1.0, abs(wall)))


@pytest.mark.parametrize("c", [0.0, 1.0])
def test_a_lagrangian_rests_only_where_its_mass_matrix_does_not_couple(c):
    """A ball in a plane from mp.lagrangian, L = (x'^2 + y'^2 + c x' y') / 2 - g y,
    bouncing on y = 0 with e = 0.5.  c = 0: it comes to rest on the floor at t_inf and
    slides on, x = x0 + u t exactly.  c = 1 (the mass matrix couples y to x: a contact
    force on y's equation alone would be the wrong constraint): the solve ends at the
    accumulation (status 1, naming the event), as before contact was modelled."""
    x, y = mp.coordinates("x y")
    t, g = sp.symbols("t g")
    L = (x.diff(t) ** 2 + y.diff(t) ** 2 + c * x.diff(t) * y.diff(t)) / 2 - g * y
    plane = mp.lagrangian(L, [x, y], params={"g": G})
    s = mp.solve(plane, (0, 3), [0.0, 1.0, 1.0, 0.0], rtol=1e-12, atol=1e-12,
                 events=mp.events.impact("y", restitution=0.5))
    if c == 0.0:
        t_inf = np.sqrt(2 / G) + 2 * 0.5 * np.sqrt(2 * G) / (G * 0.5)
        assert s.status == 0 and abs(s.rests[0][0, 0] - t_inf) < 1e-11
        np.testing.assert_allclose(s.y[:, -1], [3.0, 0.0, 1.0, 0.0], rtol=0, atol=1e-12)
    else:
        assert s.status == 1 and "events[0] accumulate (Zeno)" in s.message
        assert s.rests[0].shape == (0, 2) and s.y[1].min() > -1e-12


@pytest.mark.parametrize("which", ["rocket", "duffing"])
def test_a_built_in_scene_of_explicit_equations_rests_on_a_wall(which):
    """A built-in scene rests on an impact's wall when its row is explicit equations
    of its coordinates: a state of two (Duffing's row, a Lagrangian of one coordinate)
    or, beyond two, a fixed-size row without a Lagrangian (the Rocket: h, v, m).  Both
    made a ball dropped from 1 under g (Duffing with alpha = beta = delta = omega = 0,
    gamma = -g: x'' = -g; a Rocket without fuel, m0 = m_dry: h'' = -g), e = 0.5: at
    rest on the floor from t_inf = sqrt(2/g) + 2 e sqrt(2 g) / (g (1 - e)), to tf."""
    if which == "rocket":
        scene = mp.scenes.Rocket(exhaust_speed=U, burn_rate=1.0, m0=100.0, m_dry=100.0, g=G)
        y0, rest = [1.0, 0.0, 100.0], [0.0, 0.0, 100.0]
    else:
        scene = mp.scenes.Duffing(alpha=0.0, beta=0.0, delta=0.0, gamma=-G, omega=0.0)
        y0, rest = [1.0, 0.0], [0.0, 0.0]
    s = mp.solve(scene, (0, 3), y0, rtol=1e-12, atol=1e-12,
                 events=mp.events.impact(0, restitution=0.5))
    t_inf = np.sqrt(2 / G) + 2 * 0.5 * np.sqrt(2 * G) / (G * 0.5)
    assert s.status == 0 and s.t[-1] == 3.0
    assert s.rests[0].shape == (1, 2) and s.rests[0][0, 1] == np.inf
    assert abs(s.rests[0][0, 0] - t_inf) < 1e-11
    np.testing.assert_allclose(s.y[:, -1], rest, rtol=0, atol=1e-12)
