"""One engine, two widths: what the method rows say (lanes, rigid) is what the
engine does; solve_many takes solve's options (events, jac) with each
trajectory equal to its own solve; the C core compares no method names."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import mechpy as mp

ROOT = Path(__file__).resolve().parents[1]
P = mp.scenes.Pendulum()
ROWS = {m["name"]: m for m in mp.methods()}


@pytest.mark.parametrize("name", sorted(ROWS))
def test_lanes_field_is_what_solve_many_runs(name):
    """A row with lanes runs in lanes (and gives the scalar path's answer to
    round-off); a row without refuses lanes=True and runs the scalar path."""
    row = ROWS[name]
    kw = {} if row["adaptive"] else {"h": 0.01}
    y0s = [[0.5, 0.0], [1.0, 0.2], [2.0, -0.1]]
    system = mp.scenes.RigidBody() if row["rigid"] else P
    if row["rigid"]:
        y0s = [[0.1, 1.0, 0.1]] * 3
    if row["lanes"]:
        e = mp.solve_many(system, (0, 1), y0s, method=name, lanes=True, rtol=1e-9, **kw)
        s = mp.solve_many(system, (0, 1), y0s, method=name, lanes=False, rtol=1e-9, **kw)
        assert e.lanes and not s.lanes
        # the lane rhs rounds differently (FMA, vector sin): 1e-12 measured
        np.testing.assert_allclose(e.y, s.y, rtol=0, atol=1e-11)
        assert list(e.status) == list(s.status)
    else:
        with pytest.raises(ValueError, match="lanes=True needs"):
            mp.solve_many(system, (0, 1), y0s, method=name, lanes=True, **kw)
        e = mp.solve_many(system, (0, 1), y0s, method=name, rtol=1e-9, **kw)
        assert not e.lanes and e.success.all()


def test_lane_rows_are_the_explicit_rk_methods_with_kernels():
    assert {n for n, r in ROWS.items() if r["lanes"]} <= {n for n, r in ROWS.items()
                                                          if not r["implicit"]}
    assert {n for n, r in ROWS.items() if r["rigid"]} == {"rigid:split", "rigid:split4"}


def test_rigid_rows_refuse_other_scenes_and_backward_spans():
    with pytest.raises(ValueError, match="RigidBody"):
        mp.solve(P, (0, 1), [0.5, 0.0], method="rigid:split", h=0.01)
    with pytest.raises(ValueError, match="forwards"):
        mp.solve(mp.scenes.RigidBody(), (1, 0), [0.1, 1.0, 0.1], method="rigid:split", h=0.01)


def _crossing(t, y):
    return y[0]


_crossing.direction = -1


@pytest.mark.parametrize("method", ["dop853", "radau", "rk4"])
def test_solve_many_events_equal_each_solve(method):
    """Per trajectory, the crossings of theta = 0 downwards equal solve's, bit for
    bit (the scalar path); the pendulum's half-period from rest at theta0 is the
    closed form 2 K(sin^2(theta0/2)) sqrt(L/g) apart."""
    from scipy.special import ellipk
    kw = {"h": 1e-3} if method == "rk4" else {}
    th0 = np.array([0.3, 1.0, 2.0])
    y0s = np.column_stack([th0, np.zeros(3)])
    e = mp.solve_many(P, (0, 6), y0s, events=_crossing, method=method, rtol=1e-10,
                      atol=1e-12, **kw)
    assert not e.lanes and len(e.t_events) == 3 and len(e.t_events[0]) == 1
    for i in range(3):
        s = mp.solve(P, (0, 6), y0s[i], events=_crossing, method=method, rtol=1e-10,
                     atol=1e-12, **kw)
        assert np.array_equal(s.t_events[0], e.t_events[i][0])
        assert np.array_equal(s.y_events[0], e.y_events[i][0])
        T = 4 * ellipk(np.sin(th0[i] / 2) ** 2) / np.sqrt(9.81)
        # crossings downwards at T/4, 5T/4, ...: spaced by a period
        d = np.diff(e.t_events[i][0])
        tol = 1e-6 if method == "rk4" else 1e-8
        assert np.allclose(d, T, rtol=tol) and abs(e.t_events[i][0][0] - T / 4) < tol * T


def test_solve_many_terminal_event_per_trajectory_and_params():
    """A terminal event ends each trajectory at its own time; with Python rows the
    event gets the row as the system does."""
    def rhs(t, y, k):
        return [y[1], -k * y[0]]

    def ev(t, y, k):
        return y[0] - 0.5

    ev.terminal = True
    ks = np.array([[1.0], [4.0], [9.0]])
    e = mp.solve_many(rhs, (0, 10), [[1.0, 0.0]] * 3, params=ks, events=ev, rtol=1e-11,
                      atol=1e-13, t_eval=np.linspace(0, 10, 5))
    w = np.sqrt(ks[:, 0])
    t_hit = np.arccos(0.5) / w             # x = cos(w t) reaches 0.5
    got = np.array([te[0][0] for te in e.t_events])
    np.testing.assert_allclose(got, t_hit, rtol=1e-9)
    assert (e.status == 1).all()


def test_solve_many_jac_callable_and_constant_equal_solve():
    """radau with the user's Jacobian: each trajectory equals its solve bit for bit,
    the Jacobian counted as solve counts it."""
    A = np.array([[-1.0, 1.0], [0.0, -1000.0]])

    def f(t, y):
        return A @ y

    y0s = np.array([[1.0, 1.0], [2.0, -1.0]])
    for jac in (A, lambda t, y: A):
        e = mp.solve_many(f, (0, 2), y0s, method="radau", jac=jac, rtol=1e-8,
                          t_eval=[0.5, 2.0])
        for i in range(2):
            s = mp.solve(f, (0, 2), y0s[i], method="radau", jac=jac, rtol=1e-8,
                         t_eval=[0.5, 2.0])
            assert np.array_equal(s.y, e.y[i]) and s.nfev == e.nfev[i]
        # the closed form: y2 = y2(0) e^{-1000 t}, y1 from the variation of constants
        t = 2.0
        y2 = y0s[:, 1] * np.exp(-1000 * t)
        y1 = y0s[:, 0] * np.exp(-t) + y0s[:, 1] * (np.exp(-t) - np.exp(-1000 * t)) / 999
        np.testing.assert_allclose(e.y[:, 0, -1], y1, rtol=1e-6)
        assert np.all(np.abs(e.y[:, 1, -1] - y2) < 1e-9)


def test_solve_many_bad_jac_and_events():
    with pytest.raises(ValueError, match=r"jac must have shape \(2, 2\)"):
        mp.solve_many(P, (0, 1), [[0.1, 0.0]], method="radau", jac=np.eye(3))
    with pytest.raises(TypeError, match="events"):
        mp.solve_many(P, (0, 1), [[0.1, 0.0]], events=3)
    with pytest.raises(ValueError, match="lanes=True"):
        mp.solve_many(P, (0, 1), [[0.1, 0.0]], events=_crossing, lanes=True)


def test_no_method_name_is_compared_outside_the_rows():
    """Whether and how a method runs (lanes, rigid bodies) is a row field: the C
    core finds a method by name in one place (methods.c) and compares no other."""
    hits = []
    for f in sorted((ROOT / "csrc").rglob("*.c")):
        text = f.read_text()
        for m in re.finditer(r'strcmp\([^;]*->name[^;]*\)|"(dopri5|dop853|rk4|rigid:[a-z0-9]+)"',
                             text):
            line = text.count("\n", 0, m.start()) + 1
            hits.append(f"{f.relative_to(ROOT)}:{line}: {m.group(0)}")
    allowed = ("csrc/ode/methods.c", "csrc/ode/rk.c", "csrc/ode/rigid_split.c",
               "csrc/models/models.c", "csrc/variational.c")
    assert [h for h in hits if not h.startswith(allowed)] == []
    py = (ROOT / "mechpy").rglob("*.py")
    assert not [str(p) for p in py if 'startswith("rigid:")' in p.read_text()]


def test_one_step_policy_for_both_widths():
    """driver.c and lanes.c take the controller, first step, error norm and stiffness
    test from control.h, and neither defines its own."""
    for name in ("driver.c", "lanes.c"):
        text = (ROOT / "csrc" / "ode" / name).read_text()
        assert '#include "ode/control.h"' in text
        for fn in ("mp_ode_control(", "mp_ode_hinit_trial(", "mp_ode_hinit_final(",
                   "mp_ode_stiffness_test(", "mp_ode_step_span(", "mp_ode_step_floor("):
            assert fn in text, (name, fn)
        assert "pow(0.01 / der12" not in text and "fac_min, fac11" not in text
