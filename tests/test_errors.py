"""Every exported exception is raised by a real failure, and the one status
table decides what solve and solve_many raise or report."""
import builtins
import re

import numpy as np
import pytest

import mechpy as mp
from mechpy import errors

VDP = mp.scenes.VanDerPol(mu=1000.0)      # stiff: an explicit method needs ~1e5 steps


def _solve_budget():        # the step budget of an explicit method on a stiff problem
    mp.solve(VDP, (0, 3000), [2.0, 0.0], max_steps=200, errors="raise")


def _solve_step():          # y' = y^2 blows up at t = 1: the step falls below round-off
    mp.solve(lambda t, y: y * y, (0, 2), [1.0], errors="raise")


def _nonfinite():
    mp.solve(lambda t, y: [np.nan if t > 0.5 else -y[0]], (0, 1), [1.0])


def _singular():            # the heavy top's Euler-angle equations at theta = 0
    mp.solve(mp.scenes.HeavyTop(1.0, 2.0, 1.0), (0, 1), [0, 0.0, 0, 1, 1, 1])


def _domain():
    mp.rotation.to_scipy(2 * np.eye(3))


def _mesh():                # a tetrahedron with a face missing: open
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    mp.inertia.mesh(v, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2]]))


def _unstable():
    mp.modes.normal_modes(np.array([[1.0, 2.0], [2.0, 1.0]]), np.eye(2), method="dense")


def _not_spd():
    mp.modes.normal_modes(np.eye(2), np.array([[1.0, 2.0], [2.0, 1.0]]))


def _convergence():         # gauss4's iteration at h = 0.1 on van der Pol with eps = 1e-6
    mp.solve(lambda t, y: [y[1], ((1 - y[0] ** 2) * y[1] - y[0]) / 1e-6], (0, 1), [2.0, 0.0],
             method="gauss4", h=0.1)


def _gsl():                 # kc^2 underflows: GSL's R_F(0, 0, 1) is a domain error
    mp._core.ellipk_complement(1e-200)


def _event():               # an action leaving the state where its event fires at once
    def floor(t, y):
        return y[0]
    floor.direction = -1
    floor.action = lambda t, y: [1e-17, y[1]]    # above it, still falling: again at once
    mp.solve(lambda t, y: [y[1], -9.81], (0, 1), [1.0, 0.0], events=floor)


PROVOKE = {
    "MechpyError": _singular, "DomainError": _domain, "NonFiniteError": _nonfinite,
    "SingularityError": _singular, "MeshError": _mesh, "UnstableSystemError": _unstable,
    "NotPositiveDefiniteError": _not_spd, "StepBudgetError": _solve_budget,
    "StepSizeError": _solve_step, "ConvergenceError": _convergence, "GSLError": _gsl,
    "EventError": _event,
}


def test_every_exported_class_has_a_provoking_case():
    assert sorted(PROVOKE) == sorted(errors.__all__)


@pytest.mark.parametrize("name", errors.__all__)
def test_each_class_is_raised_for_real(name):
    cls = getattr(errors, name)
    with pytest.raises(cls):
        PROVOKE[name]()


@pytest.mark.parametrize("name,builtin", [
    ("DomainError", ValueError), ("NonFiniteError", ValueError), ("SingularityError", ValueError),
    ("MeshError", ValueError), ("UnstableSystemError", ValueError),
    ("NotPositiveDefiniteError", np.linalg.LinAlgError), ("StepBudgetError", RuntimeError),
    ("StepSizeError", RuntimeError), ("ConvergenceError", RuntimeError),
    ("GSLError", RuntimeError), ("EventError", RuntimeError)])
def test_dual_inheritance(name, builtin):
    cls = getattr(errors, name)
    assert issubclass(cls, errors.MechpyError) and issubclass(cls, builtin)
    with pytest.raises(builtin):
        PROVOKE[name]()


def test_the_table_is_the_one_source_of_messages():
    rows = {r["name"]: r for r in mp._core.STATUS_TABLE}
    assert [r["code"] for r in mp._core.STATUS_TABLE] == list(range(len(rows)))
    assert {r["name"]: r["code"] for r in mp._core.STATUS_TABLE} == mp._core.STATUS
    # a class's docstring is its row's message; the module docstring lists every class
    for r in rows.values():
        cls = r["exception"]
        if cls is not None and issubclass(cls, errors.MechpyError):
            assert r["message"] in cls.__doc__
            assert cls.__name__ in errors.__doc__
    s = mp.solve(VDP, (0, 3000), [2.0, 0.0], max_steps=200)
    assert s.message.startswith(rows["MP_EMAXSTEPS"]["message"])
    assert mp.solve(VDP, (0, 1), [2.0, 0.0], method="radau").message == rows["MP_OK"]["message"]


def test_budget_and_step_size_are_statuses_and_raise_on_request():
    s = mp.solve(VDP, (0, 3000), [2.0, 0.0], max_steps=200)
    assert s.status == -1 and not s.success and "max_steps=200" in s.message
    with pytest.raises(errors.StepBudgetError, match="max_steps=200"):
        s.raise_for_status()
    s = mp.solve(lambda t, y: y * y, (0, 2), [1.0])
    assert s.status == -1 and "round-off" in s.message
    # the blow-up is at t = 1: the step collapses there (measured t_fail 1 + 1.2e-9)
    assert abs(s.t[-1] - 1.0) < 1e-6
    with pytest.raises(errors.StepSizeError, match="round-off"):
        s.raise_for_status()
    assert mp.solve(VDP, (0, 1), [2.0, 0.0], method="radau").raise_for_status() is None


def test_errors_status_reports_what_auto_raises():
    top, y = mp.scenes.HeavyTop(1.0, 2.0, 1.0), [0, 0.0, 0, 1, 1, 1]
    s = mp.solve(top, (0, 1), y, errors="status")
    assert s.status == -3 and not s.success and "singular" in s.message
    with pytest.raises(errors.SingularityError):
        s.raise_for_status()
    s = mp.solve(lambda t, y: [np.nan if t > 0.5 else -y[0]], (0, 1), [1.0], errors="status")
    assert s.status == -2 and "dydt[0]" in s.message
    # up to the failure the samples are the solution: exp(-t)
    assert s.t[-1] <= 0.5 + 1e-12 and abs(s.y[0, -1] - np.exp(-s.t[-1])) < 1e-8
    with pytest.raises(ValueError, match="errors"):
        mp.solve(top, (0, 1), y, errors="ignore")


def test_heavy_top_at_theta_zero_is_the_same_in_solve_and_solve_many():
    top = mp.scenes.HeavyTop(1.0, 2.0, 1.0)
    good, bad = [0, 0.5, 0, 1, 1, 1], [0, 0.0, 0, 1, 1, 1]
    with pytest.raises(errors.SingularityError):
        mp.solve(top, (0, 1), bad)
    with pytest.raises(errors.SingularityError, match="trajectory 1"):
        mp.solve_many(top, (0, 1), [good, bad, bad], threads=1)
    e = mp.solve_many(top, (0, 1), [good, bad], errors="status", threads=1)
    s = mp.solve(top, (0, 1), bad, errors="status")
    assert e.status.tolist() == [0, s.status] and e.success.tolist() == [True, False]
    assert e.message[1] == s.message
    assert e.message[0] == mp.solve(top, (0, 1), good).message
    with pytest.raises(errors.SingularityError, match="trajectory 1"):
        e.raise_for_status()


def test_solve_many_budget_is_a_status_and_errors_raise_names_the_trajectory():
    y0s = [[2.0, 0.0], [2.0, 0.0]]
    p = [[1.0], [1000.0]]
    s = mp.solve(VDP.replace(mu=1000.0), (0, 30), [2.0, 0.0], max_steps=2000)
    e = mp.solve_many(VDP, (0, 30), y0s, params=p, max_steps=2000, lanes=False)
    assert e.status.tolist() == [0, s.status] == [0, -1]
    assert e.message[1] == s.message and "max_steps=2000" in e.message[1]
    # in SIMD lanes the same message but for the last digits of the time reached
    e = mp.solve_many(VDP, (0, 30), y0s, params=p, max_steps=2000, lanes=True)
    assert e.status.tolist() == [0, -1]
    num = r"[-+0-9.e]+"
    assert re.sub(num, "#", e.message[1]) == re.sub(num, "#", s.message)
    with pytest.raises(errors.StepBudgetError, match="trajectory 1"):
        e.raise_for_status()
    with pytest.raises(errors.StepBudgetError, match="trajectory 1"):
        mp.solve_many(VDP, (0, 30), y0s, params=p, max_steps=2000, errors="raise")
    ok = mp.solve_many(VDP, (0, 1), y0s, params=[[1.0], [1.0]])
    assert ok.raise_for_status() is None and ok.success.all()


def test_the_docstring_table_says_what_each_class_is():
    # each row of mechpy.errors' table against the classes themselves: the builtin
    # base of a mechpy class ("also an instance of"), nothing for a builtin class
    # (MemoryError, RuntimeError, KeyboardInterrupt are not mechpy's), the status
    # only where errors="status" can report one
    doc = errors.__doc__
    rule = next(ln for ln in doc.splitlines() if ln.startswith("====="))
    cols = [len(c) for c in rule.split("  ")]
    rows = []
    for ln in doc.splitlines():
        if ln.startswith("MP_"):
            cells, at = [], 0
            for w in cols:
                cells.append(ln[at:at + w].strip())
                at += w + 2
            rows.append(cells)
    assert len(rows) == sum(r["exception"] is not None for r in errors._TABLE)
    for cname, clsname, base, status, auto, message in rows:
        cls = next(r["exception"] for r in errors._TABLE if r["name"] == cname)
        assert cls.__name__ == clsname
        if issubclass(cls, errors.MechpyError):
            assert base and isinstance(cls("x"), getattr(builtins, base, Exception))
            assert base in [b.__name__ for b in cls.__mro__]
        else:
            assert base == "" and auto == "always raises"
        assert (status == "") == (auto == "always raises")
