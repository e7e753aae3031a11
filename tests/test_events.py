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
    # past the accumulation time t_inf = t1 + 2 v1 e / (g (1 - e)) the solve ends
    # there, as at a terminal event, naming the event
    t_inf = want[0] + 2 * v1 * e / (G * (1 - e))
    assert sol.status == 1 and sol.success
    assert "events[0] accumulate (Zeno)" in sol.message
    assert abs(sol.t[-1] - t_inf) < 1e-9 * t_inf        # 8.8e-12 relative measured
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
