"""GSL's steppers with state-changing events: after an action each row starts
afresh (csrc/ode/gsl.c's restart: GSL's evolve object and the multistep
rows' history reset), checked against the bouncing ball's closed form."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

G, H0, E = 9.81, 1.0, 0.5
V1 = np.sqrt(2 * G * H0)                       # the speed at the first landing
#: the accumulation time t_inf = t1 + 2 v1 e / (g (1 - e))
T_INF = np.sqrt(2 * H0 / G) + 2 * V1 * E / (G * (1 - E))

MULTISTEP = ["gsl:msbdf", "gsl:msadams", "BDF"]
ONE_STEP = ["gsl:rk2", "gsl:rk8pd", "gsl:rkf45"]
#: bounds on the bounce times and on the speeds before each bounce (s, m/s), the
#: first eight bounces at rtol = atol = 1e-10, about 10x what was measured:
#: the one-step rows are exact on a parabola (2.9e-15 s, 1.1e-14 m/s measured);
#: the multistep rows start again at order 1 after each bounce and hold the
#: height to atol, which grows relative to the flights as they shrink by e^2
#: (msbdf 5.0e-8 s and 1.9e-7 m/s, msadams 2.7e-8 s and 1.0e-7 m/s measured)
BOUND_T = {"gsl:rk2": 3e-14, "gsl:rk8pd": 3e-14, "gsl:rkf45": 3e-14,
           "gsl:msbdf": 5e-7, "BDF": 5e-7, "gsl:msadams": 3e-7}
BOUND_V = {"gsl:rk2": 1e-13, "gsl:rk8pd": 1e-13, "gsl:rkf45": 1e-13,
           "gsl:msbdf": 2e-6, "BDF": 2e-6, "gsl:msadams": 1e-6}


@pytest.fixture(scope="module")
def ball():
    """x'' = -g, compiled: state (x, v)."""
    x, v = mp.coordinates("x v")
    return mp.equations([v, -sp.Symbol("g")], [x, v], params={"g": G})


def _bounce_times(k):
    """t_1 = sqrt(2 h / g), then flights of 2 e^j v1 / g."""
    return np.sqrt(2 * H0 / G) + np.concatenate(
        [[0.0], np.cumsum(2 * E ** np.arange(1, k) * V1 / G)])


def _drop(ball, method, tf):
    return mp.solve(ball, (0, tf), [H0, 0.0], events=mp.events.impact("x", restitution=E),
                    method=method, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("method", MULTISTEP + ONE_STEP)
def test_gsl_rows_bounce_as_the_closed_form(ball, method):
    """Eight bounces (t_9 = 1.3511 lies past the span): the times, the speeds
    just before each (e^k v1), and no sample below the floor.  Before the
    restart hook the multistep rows refired at the first impact (their history
    carried the fall on) and the one-step rows took the first stage after each
    bounce from f before it (GSL reuses the last step's f), off by 3.6e-10 m."""
    sol = _drop(ball, method, 1.35)
    tb = sol.t_events[0]
    assert sol.status == 0 and len(tb) == 8
    assert np.max(np.abs(tb - _bounce_times(8))) < BOUND_T[method]
    vb = -sol.y_events[0][:, 1]
    assert np.max(np.abs(vb - V1 * E ** np.arange(8))) < BOUND_V[method]
    assert sol.y[0].min() > -2e-14                     # -1.8e-15 measured (rk2)


@pytest.mark.parametrize("method", ONE_STEP + MULTISTEP)
def test_gsl_rows_come_to_rest_at_the_accumulation_point(ball, method):
    """Through t_inf: the ball comes to rest on the floor there (its next bounce below
    the tolerance on x) and stays, status 0.  The one-step rows' t_inf to 3e-15
    relative measured; the multistep rows, restarting at order 1 after each bounce,
    lose flights as high as atol (their first step after a bounce, backward Euler,
    rounds the speed of such a flight to 0: they raised 'fires again at once' there)
    and rest that much early: 2.5e-5 relative measured at atol = 1e-10."""
    sol = _drop(ball, method, 2.0)
    assert sol.status == 0 and sol.t[-1] == 2.0
    assert sol.rests[0].shape == (1, 2) and sol.rests[0][0, 1] == np.inf
    bound = 1e-4 if method in MULTISTEP else 3e-14
    assert abs(sol.rests[0][0, 0] - T_INF) < bound * T_INF
    assert np.all(sol.y[:, sol.t > sol.rests[0][0, 0]] == 0.0)
