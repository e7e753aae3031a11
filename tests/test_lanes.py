"""mp.solve_many in SIMD lanes (csrc/ode/lanes.c) against the scalar path.

Each lane repeats the scalar driver's decisions; fused multiply-adds and
libmvec's sin/cos round differently, so samples agree to round-off amplified
by the flow, and statuses, messages (but for the last digits of a time) and
evaluation counts agree.
"""
import re

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

S = mp.scenes
LANES = 8   # MP_LANES in csrc/ode/lanes.h: trajectories in one lane group

# one instance of every scene (the walk below checks none is missing), a start,
# and the relative spread of the ensemble's starts around it
CASES = {
    "Pendulum": (S.Pendulum(), [1.0, 0.0], 1e-2),
    "Pendulum driven": (S.Pendulum(damping=0.1, drive_amplitude=0.5, drive_frequency=1.2),
                        [1.0, 0.0], 1e-2),
    "VanDerPol": (S.VanDerPol(mu=1.0), [2.0, 0.0], 1e-2),
    "Duffing": (S.Duffing(alpha=-1.0, beta=1.0, delta=0.2, gamma=0.3, omega=1.2), [1.0, 0.0],
                1e-2),
    "Kepler": (S.Kepler(), [1.0, 0.0, 0.0, 1.1], 1e-2),
    # Arenstorf's orbit: a spread of 1e-2 sends starts into the primaries, where
    # round-off grows to the method's error on either path
    "RestrictedThreeBody": (S.RestrictedThreeBody(), [0.994, 0.0, 0.0, -2.00158510637908],
                            1e-6),
    "Foucault": (S.Foucault(latitude=45.0, length=10.0), [0.1, 0.0, 0.0, 0.0], 1e-2),
    "RigidBody": (S.RigidBody(), [1.0, 0.1, 0.2], 1e-2),
    "HeavyTop": (S.HeavyTop(I1=1.0, I3=0.5, mass=1.0), [0.0, 0.5, 0.0, 0.0, 0.0, 10.0], 1e-2),
    "SpringChain": (S.SpringChain(masses=[1.0, 1.0, 1.0]), [0.1, 0.0, -0.1, 0.0, 0.0, 0.0],
                    1e-2),
    "Rocket": (S.Rocket(exhaust_speed=2000.0, burn_rate=10.0, m0=1000.0, m_dry=200.0),
               [0.0, 0.0, 1000.0], 1e-2),
}
METHODS = {"dop853": {}, "dopri5": {}, "rk4": {"h": 1e-3}}


def _compiled_pendulum():
    x, v = mp.coordinates("x v")
    return mp.equations([v, -sp.sin(x)], [x, v])


def _both(system, t_span, y0s, **kw):
    a = mp.solve_many(system, t_span, y0s, lanes=True, **kw)
    b = mp.solve_many(system, t_span, y0s, lanes=False, **kw)
    assert a.lanes and not b.lanes
    return a, b


def _starts(y0, spread, k):
    return np.asarray(y0, float) * (1 + spread * np.linspace(-1, 1, k))[:, None]


def _rel_diff(a, b, rows=slice(None)):
    ya, yb = a.y[rows], b.y[rows]
    scale = np.maximum(np.max(np.abs(yb), axis=(0, 2)), 1e-300)
    return float(np.max(np.abs(ya - yb) / scale[None, :, None]))


def _strip_times(messages):
    return [re.sub(r"t = [-+0-9.e]+", "t = ?", m) for m in messages]


def test_cases_cover_every_scene():
    # the C scenes (a row of the scene table); compiled scenes are cased apart
    classes = {c.__name__ for c in S.Scene.__subclasses__() if getattr(c, "_model", None)}
    assert classes <= {type(s).__name__ for s, _, _ in CASES.values()}


@pytest.mark.parametrize("method", sorted(METHODS))
@pytest.mark.parametrize("name", sorted(CASES) + ["compiled"])
def test_lanes_agree_with_scalar_path(name, method):
    if name == "compiled":
        system, y0, spread = _compiled_pendulum(), [1.0, 0.0], 1e-2
    else:
        system, y0, spread = CASES[name]
    te = np.linspace(0, 2, 5)
    a, b = _both(system, (0, 2), _starts(y0, spread, 37), t_eval=te, method=method,
                 **METHODS[method])
    # measured: at most 2.5e-13 (Pendulum, dopri5); 0 for most rk4 cases
    assert _rel_diff(a, b) < 3e-12
    assert np.array_equal(a.status, b.status) and a.success.all()
    assert np.array_equal(a.nfev, b.nfev)
    assert np.array_equal(a.t, b.t)


def test_backward_and_params_in_lanes():
    p = S.Pendulum()
    k = 21
    y0s = _starts([1.0, 0.3], 0.2, k)
    params = {"length": np.linspace(0.5, 2.0, k), "drive_amplitude": np.linspace(0, 1, k),
              "drive_frequency": np.full(k, 1.3)}
    te = np.linspace(3, -3, 7)
    a, b = _both(p, (3, -3), y0s, t_eval=te, params=params)
    assert _rel_diff(a, b) < 3e-12   # measured 3e-14
    assert np.array_equal(a.nfev, b.nfev)
    for i in (0, 10, 20):   # each lane's own parameters
        row = {n: float(v[i]) for n, v in params.items()}
        s = mp.solve(p.replace(**row), (3, -3), y0s[i], t_eval=te)
        assert np.max(np.abs(s.y - a.y[i])) < 1e-10   # measured 1e-14


def test_thread_count_does_not_change_lanes():
    y0s = _starts([1.0, 0.0], 0.5, 53)
    te = np.linspace(0, 5, 6)
    a = mp.solve_many(S.Pendulum(), (0, 5), y0s, t_eval=te, threads=1, lanes=True)
    b = mp.solve_many(S.Pendulum(), (0, 5), y0s, t_eval=te, threads=2, lanes=True)
    assert np.array_equal(a.y, b.y) and np.array_equal(a.nfev, b.nfev)


# ---- statuses: failures in the middle of a lane group, refill --------------------

@pytest.mark.parametrize("k", [1, LANES - 1, LANES + 1, 37])
def test_step_budget_per_lane(k):
    """Starts of growing amplitude need more steps: a budget between them fails
    some lanes early, their slots take the next trajectories."""
    y0s = np.column_stack([np.linspace(0.1, 3.1, k)[::-1], np.zeros(k)])
    te = np.linspace(0, 20, 9)
    full = mp.solve_many(S.Pendulum(), (0, 20), y0s, t_eval=te, lanes=False)
    budget = int(np.median(full.nfev) / 12) if k > 1 else 5
    kw = dict(t_eval=te, max_steps=budget, errors="status")
    a, b = _both(S.Pendulum(), (0, 20), y0s, **kw)
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    if k >= LANES:
        assert 0 < np.sum(a.status == -1) < k   # some ran out, some finished
    assert _strip_times(a.message) == _strip_times(b.message)
    assert np.array_equal(np.isnan(a.y), np.isnan(b.y))   # samples past a failure are NaN
    ok = ~np.isnan(b.y)
    assert np.max(np.abs(a.y[ok] - b.y[ok]), initial=0.0) < 1e-10   # measured 2e-13


@pytest.mark.parametrize("k", [1, LANES - 1, LANES + 1, 37])
def test_singular_heavy_top_in_a_lane_group(k):
    """theta = 0 is singular for the top's Euler angles: those lanes fail at
    once (SingularityError's status) while their neighbours run to the end."""
    top = S.HeavyTop(I1=1.0, I3=0.5, mass=1.0)
    y0s = _starts([0.0, 0.5, 0.0, 0.0, 0.0, 10.0], 0.1, k)
    y0s[k // 2, 1] = 0.0
    if k > 3:
        y0s[3, 1] = 0.0
    te = np.linspace(0, 1, 3)
    a, b = _both(top, (0, 1), y0s, t_eval=te, errors="status")
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    bad = y0s[:, 1] == 0.0
    assert (a.status[bad] == -3).all() and (a.status[~bad] == 0).all()
    assert _strip_times(a.message) == _strip_times(b.message)
    assert np.isnan(a.y[bad]).all()
    if (~bad).any():
        assert _rel_diff(a, b, ~bad) < 3e-12   # measured 4e-14
    first = min(k // 2, 3) if k > 3 else k // 2
    with pytest.raises(mp.SingularityError, match=rf"trajectory {first}:"):
        mp.solve_many(top, (0, 1), y0s, t_eval=te, lanes=True)


def test_blow_up_of_compiled_equations():
    """y' = y^2 from y0 > 0 leaves every float at t = 1/y0: the lanes that
    start above 2/3 fail within (0, 1.5) as the scalar path fails them."""
    (y,) = mp.coordinates("y")
    s = mp.equations([y ** 2], [y])
    y0s = np.linspace(-1.0, 1.0, 36)[:, None]
    te = np.linspace(0, 1.5, 4)
    a, b = _both(s, (0, 1.5), y0s, t_eval=te, errors="status")
    assert np.array_equal(a.status, b.status) and np.array_equal(a.nfev, b.nfev)
    blows = y0s[:, 0] > 1 / 1.5
    assert (a.status[blows] < 0).all() and (a.status[~blows] == 0).all()
    assert _strip_times(a.message) == _strip_times(b.message)
    assert np.array_equal(np.isnan(a.y), np.isnan(b.y))
    with np.errstate(divide="ignore"):
        exact = (y0s / (1 - y0s * te[None, :]))[:, None, :]
    ok = ~np.isnan(b.y) & np.isfinite(exact)
    rel = np.abs(a.y[ok] - exact[ok]) / np.maximum(np.abs(exact[ok]), 1.0)
    assert np.max(rel) < 1e-6   # measured 8e-8 (the samples nearest the pole)


def test_t_eval_samples_at_the_same_times():
    te = np.array([0.0, 0.013, 0.5, 1.25, 3.0 - 1e-12, 3.0])
    y0s = _starts([1.0, 0.0], 0.5, 11)
    a, b = _both(S.Duffing(alpha=1.0, beta=0.5), (0, 3), y0s, t_eval=te)
    assert np.array_equal(a.t, te)
    assert np.array_equal(a.y[:, :, 0], y0s)   # the start is copied, not computed
    assert _rel_diff(a, b) < 3e-12   # measured 2e-15


# ---- the forced scalar path and the choice ------------------------------------------

def test_forced_scalar_path_is_bit_identical_to_solve(monkeypatch):
    y0s = _starts([1.0, 0.2], 0.5, 10)
    te = np.linspace(0, 4, 9)
    off = mp.solve_many(S.Pendulum(), (0, 4), y0s, t_eval=te, lanes=False)
    monkeypatch.setenv("MECHPY_LANES", "0")
    env = mp.solve_many(S.Pendulum(), (0, 4), y0s, t_eval=te)
    assert not off.lanes and not env.lanes
    for i in (0, 5, 9):
        s = mp.solve(S.Pendulum(), (0, 4), y0s[i], t_eval=te)
        assert np.array_equal(off.y[i], s.y) and np.array_equal(env.y[i], s.y)
        assert off.nfev[i] == s.nfev
    monkeypatch.delenv("MECHPY_LANES")
    assert mp.solve_many(S.Pendulum(), (0, 4), y0s, t_eval=te).lanes


def test_what_lanes_cannot_do_takes_the_scalar_path():
    y0s = _starts([1.0, 0.0], 0.1, 5)
    assert not mp.solve_many(S.Pendulum(), (0, 1), y0s, method="radau").lanes
    assert not mp.solve_many(lambda t, y: [y[1], -y[0]], (0, 1), y0s).lanes
    with pytest.raises(ValueError, match="lanes=True needs"):
        mp.solve_many(S.Pendulum(), (0, 1), y0s, method="radau", lanes=True)
    with pytest.raises(ValueError, match="lanes=True needs"):
        mp.solve_many(lambda t, y: [y[1], -y[0]], (0, 1), y0s, lanes=True)
    with pytest.raises(TypeError, match="lanes must be"):
        mp.solve_many(S.Pendulum(), (0, 1), y0s, lanes="yes")


def test_empty_ensemble_in_lanes():
    e = mp.solve_many(S.Pendulum(), (0, 1), np.zeros((0, 2)), lanes=True)
    assert e.y.shape == (0, 2, 1)
