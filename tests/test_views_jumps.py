"""Both views play solutions with jumps (events with an action): the bouncing
ball (mp.equations, mp.events.impact with its restitution a parameter) and a
pendulum striking a wall, drawn by mp.plot.animate (its frames' artists) and
by mp.live.animate (the page's window.mechpyLive in headless Chromium),
against the solution itself, its piecewise dense output and a re-solve of
each flight."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

plt = pytest.importorskip("matplotlib.pyplot")
pytest.importorskip("anywidget")
from live_browser import driver, open_page  # noqa: E402,F401

G, E = 9.81, 0.8


@pytest.fixture(scope="module")
def ball():
    """x'' = -g, state (x, v); e, the restitution, a parameter no equation uses."""
    x, v = mp.coordinates("x v")
    return mp.equations([v, -sp.Symbol("g")], [x, v], params={"g": G, "e": E})


def _bounce(ball, **kw):
    return mp.solve(ball, (0, 3), [1.0, 0.0], events=mp.events.impact("x", restitution="e"),
                    rtol=1e-10, atol=1e-12, **kw)


def _flight(tq, tb, v1):
    """The closed form at times tq: a fall from 1 m, then flights from the floor
    at e^j v1 after each bounce tb[j-1] (x, v)."""
    j = np.searchsorted(tb, tq, side="right")           # bounces at or before tq
    t0 = np.where(j == 0, 0.0, tb[np.maximum(j - 1, 0)])
    x0 = np.where(j == 0, 1.0, 0.0)
    u0 = np.where(j == 0, 0.0, v1 * E ** j)
    s = tq - t0
    return x0 + u0 * s - G / 2 * s * s, u0 - G * s


def test_samples_of_a_solution_with_jumps_are_accepted(ball):
    sol = _bounce(ball)
    assert np.sum(np.diff(sol.t) == 0) == len(sol.t_events[0]) == 6
    tt, y = mp._motion.samples(ball, sol, None)
    assert tt is sol.t
    with pytest.raises(ValueError, match="must be monotonic"):
        mp._motion.samples(ball, sol.y[:, [0, 2, 1]], sol.t[[0, 2, 1]])


def test_plot_animate_bouncing_ball_frames_are_the_states_after(ball):
    sol = _bounce(ball)
    tb = sol.t_events[0]
    anim = mp.plot.animate(ball, sol)
    assert anim._fig.axes[0] is not None
    k = anim.samples
    # every sample shown once; at a bounce's time, the one after it
    at = np.isin(sol.t[k], tb)
    assert at.sum() == len(tb)
    np.testing.assert_array_equal(sol.y[1, k[at]], -E * sol.y_events[0][:, 1])
    assert np.all(sol.y[1, k[at]] > 0)
    ax = anim._fig.axes[0]
    dot = [a for a in ax.get_children() if a.get_gid() == "particle"][0]
    v1 = np.sqrt(2 * G)
    for i in range(len(k)):
        anim._func(i)
        px, py = (np.asarray(a) for a in dot.get_data())
        assert px[0] == 0.0 and py[0] == sol.y[0, k[i]]
        assert py[0] > -1e-12                              # never below the floor
        # the closed form: 1.9e-14 m measured (the bounce times to round-off)
        assert abs(py[0] - _flight(sol.t[k[i]], tb, v1)[0]) < 2e-13
    plt.close("all")


def test_resample_takes_each_piece_and_the_state_after(ball):
    sol = _bounce(ball)
    tb = sol.t_events[0]
    times = np.concatenate([np.linspace(0, 3, 301), tb])
    Y = mp._motion.resample(ball, sol.t, sol.y, times)
    # each flight a parabola: the cubic Hermite through its samples is exact
    # (2.4e-14 m and 5.0e-14 m/s measured, the samples' own error), the state
    # after each bounce at its time
    x, v = _flight(times, tb, np.sqrt(2 * G))
    assert np.max(np.abs(Y[0] - x)) < 3e-13 and np.max(np.abs(Y[1] - v)) < 5e-13
    assert np.all(Y[1, -len(tb):] > 0) and Y[0].min() > -1e-12


def test_resample_backwards_takes_the_state_after_in_the_solve_order():
    """A solve backwards in time with a jump: at the jump's time the state the
    backward solve continues from."""
    x, v = mp.coordinates("x v")
    free = mp.equations([v, sp.S.Zero], [x, v])                         # x'' = 0
    wall = mp.events.impact("x", wall=0.0, restitution=1.0, side=-1)   # x <= 0
    sol = mp.solve(free, (2.0, 0.0), [-1.0, -1.0], events=wall, rtol=1e-12, atol=1e-12)
    # backwards: x(t) = 1 - t reaches the wall at t = 1, then v -> 1: x = t - 1
    te = sol.t_events[0]
    assert len(te) == 1 and te[0] == pytest.approx(1.0, abs=1e-12)
    Y = mp._motion.resample(free, sol.t, sol.y, np.array([1.5, te[0], 0.5]))
    np.testing.assert_allclose(Y[0], [-0.5, 0.0, -0.5], atol=1e-12)
    np.testing.assert_allclose(Y[1], [-1.0, 1.0, 1.0], atol=1e-12)


@pytest.mark.parametrize("dense", [True, False])
def test_live_bouncing_ball_frames_are_the_solution(driver, tmp_path, ball, dense):
    """The page's frames (window.mechpyLive): the ball at (0, x, 0) with x the
    solution at each frame time (sol.sol, or the Hermite interpolant through
    the samples, each flight on its own), never below the floor; a frame at a
    bounce's time shows the state after it (the ball on the floor, rising)."""
    first = _bounce(ball).t_events[0][0]
    # a span of twice the first landing: frame 30 of 61 lies on it exactly
    sol = mp.solve(ball, (0, 2 * first), [1.0, 0.0], events=mp.events.impact(
        "x", restitution="e"), rtol=1e-10, atol=1e-12, dense_output=dense)
    assert sol.t_events[0].tolist() == [first]
    w = mp.live.animate(ball, sol, fps=30, duration=2.0)
    assert w.kind == "particle" and w.bodies == ["particle"] and w.times[30] == first
    path = w.save(tmp_path / f"ball_{dense}.html")
    open_page(driver, path)
    assert driver.execute_script("return window.mechpyLive.frames()") == 61
    xs = []
    for i in range(61):
        driver.execute_script(f"window.mechpyLive.frame({i})")
        assert driver.execute_script("return window.mechpyLive.time()") == w.times[i]
        xs.append(driver.execute_script("return window.mechpyLive.positions()"))
    P = np.array(xs)
    assert np.all(P[:, [0, 2]] == 0.0)
    x, v = _flight(w.times, sol.t_events[0], np.sqrt(2 * G))
    # the closed form, flight by flight: 9.9e-15 m measured (both paths)
    assert np.max(np.abs(P[:, 1] - x)) < 1e-13
    assert P[:, 1].min() >= 0.0 and P[30, 1] == 0.0
    # the state after the bounce there, rising at e v1
    Y = (sol.sol(w.times) if dense else
         mp._motion.resample(ball, sol.t, sol.y, w.times))
    assert Y[1, 30] == pytest.approx(E * np.sqrt(2 * G), rel=1e-10)
    np.testing.assert_array_equal(P[:, 1], Y[0])


def test_live_pendulum_striking_a_wall_is_the_re_solved_motion():
    """mp.live.animate of a pendulum with impacts from its dense output: the
    frames' states are the solution re-solved at the frame times (t_eval),
    and the bob never passes the wall (theta >= 0)."""
    p = mp.scenes.Pendulum()
    kw = dict(events=mp.events.impact("theta", restitution=0.5), rtol=1e-10, atol=1e-12)
    sol = mp.solve(p, (0, 2), [1.0, 0.0], dense_output=True, **kw)
    assert len(sol.t_events[0]) >= 2
    w = mp.live.animate(p, sol, fps=30)
    Y = mp.live.motion._states(p, sol, None, w.times)
    ref = mp.solve(p, (0, 2), [1.0, 0.0], t_eval=w.times, **kw)
    # the re-solve interpolates the same steps: equal to the bit, measured
    np.testing.assert_allclose(Y, ref.y, rtol=0, atol=1e-14)
    assert Y[0].min() > -1e-12
