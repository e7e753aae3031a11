"""Rotating frames: fictitious forces, frame changes, Foucault, Coriolis deflection."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

import mechpy as mp

OM = 7.2921159e-5


def test_fictitious_against_definitions():
    rng = np.random.default_rng(1)
    w, r, v, wd = rng.normal(size=(4, 5, 3))
    a = mp.frames.fictitious(w, r, v, omega_dot=wd)
    for i in range(5):
        W = np.array([[0, -w[i, 2], w[i, 1]], [w[i, 2], 0, -w[i, 0]], [-w[i, 1], w[i, 0], 0]])
        Wd = np.array([[0, -wd[i, 2], wd[i, 1]], [wd[i, 2], 0, -wd[i, 0]],
                       [-wd[i, 1], wd[i, 0], 0]])
        np.testing.assert_allclose(a["coriolis"][i], -2 * W @ v[i], atol=1e-14)
        np.testing.assert_allclose(a["centrifugal"][i], -W @ W @ r[i], atol=1e-14)
        np.testing.assert_allclose(a["euler"][i], -Wd @ r[i], atol=1e-14)
    # the centrifugal acceleration at the equator points outward with omega^2 R
    c = mp.frames.fictitious([0, 0, OM], [6.378e6, 0, 0], [0, 0, 0])["centrifugal"]
    np.testing.assert_allclose(c, [OM ** 2 * 6.378e6, 0, 0], rtol=1e-14)


def test_round_trip_is_identity_and_matches_scipy_rotation():
    rng = np.random.default_rng(2)
    r, v = rng.normal(size=(2, 7, 3))
    w = np.array([0.3, -0.2, 0.9])
    t = rng.uniform(0, 10, size=7)
    rr, vr = mp.frames.to_rotating(r, v, w, t)
    r2, v2 = mp.frames.from_rotating(rr, vr, w, t)
    np.testing.assert_allclose(r2, r, atol=1e-13)
    np.testing.assert_allclose(v2, v, atol=1e-13)
    R = Rotation.from_rotvec(w * t[:, None]).as_matrix()
    np.testing.assert_allclose(rr, np.einsum("kji,kj->ki", R, r), atol=1e-13)
    # a body at rest in inertial space moves as -omega x r in the rotating frame
    _, vr0 = mp.frames.to_rotating(r[0], [0, 0, 0], w, 0.0)
    np.testing.assert_allclose(vr0, -np.cross(w, r[0]), atol=1e-15)


def test_rotating_frame_motion_obeys_fictitious_forces():
    """A free particle seen from the rotating frame, integrated with the
    fictitious accelerations, matches the transformed straight line."""
    w = np.array([0.0, 0.0, 0.7])
    r0, v0 = np.array([1.0, 0.5, 0.2]), np.array([0.1, -0.3, 0.05])
    rr0, vr0 = mp.frames.to_rotating(r0, v0, w, 0.0)

    def f(t, y):
        return np.concatenate([y[3:], mp.frames.fictitious(w, y[:3], y[3:])["total"]])
    s = solve_ivp(f, (0, 5), np.concatenate([rr0, vr0]), rtol=1e-11, atol=1e-12)
    rr, vr = mp.frames.to_rotating(r0 + v0 * 5.0, v0, w, 5.0)
    np.testing.assert_allclose(s.y[:3, -1], rr, atol=1e-8)
    np.testing.assert_allclose(s.y[3:, -1], vr, atol=1e-8)


def test_foucault_period_paris():
    T = mp.frames.foucault_period(48.857)
    assert abs(T / 3600 - 31.78) < 0.005
    assert mp.frames.foucault_period(90.0) == pytest.approx(2 * np.pi / OM, rel=1e-15)
    assert mp.frames.foucault_period(-48.857) == T
    assert np.isinf(mp.frames.foucault_period(0.0))
    np.testing.assert_allclose(mp.frames.foucault_period([30.0, 90.0]),
                               [2 * np.pi / (OM * 0.5), 2 * np.pi / OM], rtol=1e-14)


def _swing_angle(x, y):
    """Orientation of the major axis of the points (x, y), in (-pi/2, pi/2]."""
    return 0.5 * np.arctan2(2 * np.mean(x * y), np.mean(x * x) - np.mean(y * y))


@pytest.mark.parametrize("lat", [48.857, -35.0])
def test_foucault_precession(lat):
    sc = mp.scenes.Foucault(lat, 67.0)
    T0 = 2 * np.pi * np.sqrt(67.0 / 9.81)
    t_end = 6 * 3600.0
    te = np.linspace(t_end - 2 * T0, t_end, 400)
    s = mp.solve(sc, (0, t_end), [1.0, 0, 0, 0], rtol=1e-11, atol=1e-12, t_eval=te)
    angle = _swing_angle(s.y[0], s.y[1])        # counter-clockwise positive
    expect = -OM * np.sin(np.radians(lat)) * (t_end - T0)  # clockwise in the north
    assert abs(angle - expect) < 1e-3 * abs(expect)
    assert (angle < 0) == (lat > 0)
    assert sc.precession_rate == pytest.approx(OM * np.sin(np.radians(lat)), rel=1e-15)
    E = sc.energy(s.y)
    assert np.ptp(E) < 1e-8 * E[0]


def test_foucault_against_solve_ivp():
    sc = mp.scenes.Foucault(48.857, 10.0, omega=1e-2)
    ref = solve_ivp(sc.rhs, (0, 200), [0.5, 0, 0, 0.01], method="DOP853", rtol=1e-12,
                    atol=1e-13)
    s = mp.solve(sc, (0, 200), [0.5, 0, 0, 0.01], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(s.y[:, -1], ref.y[:, -1], atol=1e-8)
    # the analytic Jacobian against finite differences
    y = np.array([0.3, -0.2, 0.1, 0.4])
    J = sc.jacobian(0.0, y)
    h = 1e-6
    Jfd = np.column_stack([(sc.rhs(0, y + h * e) - sc.rhs(0, y - h * e)) / (2 * h)
                           for e in np.eye(4)])
    np.testing.assert_allclose(J, Jfd, atol=1e-8)


def test_drop_eastward_deflection_100m():
    for lat in (0.0, 48.857, -60.0):
        land, t = mp.frames.drop(100.0, lat)
        d = mp.frames.eastward_deflection(100.0, lat)
        assert t == pytest.approx(np.sqrt(200 / 9.81), rel=1e-7)  # measured 1.8e-8
        assert land[0] == pytest.approx(d, rel=2e-7)  # measured 3.3e-8 (first order in Omega)
        assert land[0] > 0
    assert mp.frames.eastward_deflection(100.0, 0.0) == pytest.approx(
        OM / 3 * np.sqrt(8 * 100.0 ** 3 / 9.81), rel=1e-15)


def test_projectile_drift_closed_form():
    v0 = np.array([0.0, 50.0, 50.0])  # fired north
    land, T = mp.frames.projectile(v0, 45.0)
    vac = v0 * T + 0.5 * np.array([0, 0, -9.81]) * T ** 2
    drift = mp.frames.projectile_drift(v0, T, 45.0)
    np.testing.assert_allclose(land - vac, drift, atol=1e-3 * np.abs(drift).max())
    assert drift[0] > 0  # deflected to the right (east) in the north


@pytest.mark.parametrize("bad", [90.5, -91.0, np.nan])
def test_bad_latitude(bad):
    with pytest.raises(ValueError):
        mp.scenes.Foucault(bad, 10.0)
    with pytest.raises(ValueError):
        mp.frames.foucault_period(bad)
    with pytest.raises(ValueError):
        mp.frames.eastward_deflection(100.0, bad)


def test_bad_shapes():
    with pytest.raises(ValueError):
        mp.frames.fictitious([1, 2], [1, 2, 3], [1, 2, 3])
    with pytest.raises(ValueError):
        mp.scenes.Foucault(45.0, -1.0)
    with pytest.raises(TypeError):
        mp.frames.to_rotating("r", [0, 0, 0], [0, 0, 1], 0.0)


def test_drop_has_a_step_budget_and_answers_ctrl_c():
    # a drop from 1e300 m (about 1e150 s of flight) ran for hours; now a stated budget
    with pytest.raises(mp.StepBudgetError, match="max_steps = 20000"):
        mp.frames.drop(1e300, 45.0)
    with pytest.raises(mp.StepBudgetError, match="max_steps = 5 "):
        mp.frames.drop(1e6, 45.0, max_steps=5)
    with pytest.raises(ValueError, match="flight time overflows"):
        mp.frames.projectile([1.0, 0.0, 1e300], 45.0)
    from sigint import interrupt_delay
    dt = interrupt_delay("", "mp.frames.drop(1e300, 45.0, max_steps=10 ** 9)", delay=0.5)
    assert dt < 1.0, f"KeyboardInterrupt {dt} CPU s after SIGINT"   # measured < 0.01 s
