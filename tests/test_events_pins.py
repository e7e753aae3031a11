"""Pins of what an event's location and an action leave behind, each against a
closed form or an independent computation; each was changed by a mutation
audit with no test failing:

- the located root is the point past the crossing (control.h's
  mp_ode_event_root returns b of its final bracket);
- the state after an action is a sample (driver.c's apply_action);
- the dense output at an action's time gives the state after it;
- a per-trajectory restitution array must be non-negative (events.py);
- a time shared by two joined pieces is the later piece's (_solution.py's
  _JoinedDense)."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechpy as mp
from mechpy._solution import _ConstantDense, _JoinedDense

G, E = 9.81, 0.5


@pytest.fixture(scope="module")
def ball():
    x, v = mp.coordinates("x v")
    return mp.equations([v, -sp.Symbol("g")], [x, v], params={"g": G})


def _level(t, y):
    return y[0] - 1.0 / 3.0


@pytest.mark.parametrize("direction", [1, -1])
def test_located_root_is_past_the_crossing(direction):
    """y' = direction: g = y - 1/3 crosses at t = 1/3, which no double is.  The
    event's time is the first double past the crossing (g already of the new
    sign, 1 ulp from 1/3), in both directions."""
    _level.direction = direction
    _level.terminal = True
    sol = mp.solve(lambda t, y: [float(direction)], (0, 1), [0.0 if direction > 0 else 2 / 3],
                   events=_level, rtol=1e-12, atol=1e-12)
    te, ye = sol.t_events[0][0], sol.y_events[0][0, 0]
    assert abs(te - 1 / 3) <= 4e-16                      # 1 ulp measured
    # past the crossing: g of the new sign (or zero), never of the old one
    assert te >= 1 / 3 and direction * _level(te, [ye]) >= 0.0


def test_state_after_each_action_is_a_sample(ball):
    """Without t_eval each bounce's time is in sol.t twice: the state before (as
    y_events holds it) and then the action's result, x = 0 and v = -e v."""
    sol = mp.solve(ball, (0, 1.3), [1.0, 0.0], events=mp.events.impact("x", restitution=E),
                   rtol=1e-12, atol=1e-12)
    tb, yb = sol.t_events[0], sol.y_events[0]
    i = np.nonzero(np.diff(sol.t) == 0)[0]
    assert len(tb) == 5 and len(i) == 5
    np.testing.assert_array_equal(sol.t[i], tb)
    np.testing.assert_array_equal(sol.y[:, i].T, yb)
    np.testing.assert_array_equal(sol.y[0, i + 1], 0.0)
    np.testing.assert_array_equal(sol.y[1, i + 1], -E * yb[:, 1])


def test_dense_output_at_an_action_is_the_state_after(ball):
    """sol.sol at each bounce's time: the ball on the floor rising at e^k v1,
    the closed form (v1 = sqrt(2 g h)); just before it, falling."""
    sol = mp.solve(ball, (0, 1.3), [1.0, 0.0], events=mp.events.impact("x", restitution=E),
                   rtol=1e-12, atol=1e-12, dense_output=True)
    tb = sol.t_events[0]
    v1 = np.sqrt(2 * G)
    Y = sol.sol(tb)
    assert np.max(np.abs(Y[0])) < 1e-13                  # 0 measured: the floor itself
    np.testing.assert_allclose(Y[1], v1 * E ** np.arange(1, len(tb) + 1), rtol=1e-11)
    before = sol.sol(tb - 1e-9)
    assert np.all(before[1] < 0)


def test_restitution_array_must_be_non_negative(ball):
    y0 = np.tile([1.0, 0.0], (2, 1))
    with pytest.raises(ValueError, match="restitution"):
        mp.solve_many(ball, (0, 1), y0, events=mp.events.impact("x", restitution=[0.5, -0.5]))
    ok = mp.solve_many(ball, (0, 1), y0, events=mp.events.impact("x", restitution=[0.5, 0.0]),
                       errors="status")
    assert ok.t_events[0][0][0] == pytest.approx(np.sqrt(2 / G), rel=1e-6)


def test_joined_pieces_share_a_time_with_the_later_piece():
    """Two pieces, 1 on [0, 1] and 2 on [1, 2] (a switch at t = 1): t = 1 is
    the piece's that starts there, the state after the switch."""
    J = _JoinedDense([_ConstantDense([1.0], 0.0, 1.0), _ConstantDense([2.0], 1.0, 2.0)])
    np.testing.assert_array_equal(J(np.array([0.0, 0.5, 1.0, 1.5, 2.0]))[0],
                                  [1.0, 1.0, 2.0, 2.0, 2.0])
    assert J(1.0)[0] == 2.0
    assert J(np.nextafter(1.0, 0.0))[0] == 1.0
