"""Rigid bodies: Euler's equations against the exact elliptic solution, the
geometric split methods' invariants, the heavy top's nutation bounds and
conserved momenta, bad input."""
import numpy as np
import pytest

import mechpy as mp
from mechpy.scenes import HeavyTop, RigidBody

I123 = (1.0, 2.0, 3.0)


def _near_separatrix(eps, side):
    # L^2 - 2 E I2 = -w1^2 + 3 w3^2 for I = (1, 2, 3): a relative distance eps
    w3 = 0.01
    w1 = np.sqrt(3.0 * w3 * w3 * (1.0 - side * eps))
    return np.array([w1, 1.0, w3])


@pytest.mark.parametrize("moments", [I123, (3.0, 2.0, 1.0), (2.0, 3.0, 1.5), (2.0, 1.0, 2.5)])
@pytest.mark.parametrize("w0", [[0.3, 0.1, 1.0], [1.0, 0.1, 0.3], [-0.2, 0.5, -0.3],
                                [0.2, -1.0, 0.1]])
def test_free_rotation_matches_integration(moments, w0):
    t = np.linspace(0.0, 30.0, 201)
    s = mp.solve(RigidBody(moments), (0, 30), w0, rtol=1e-12, atol=1e-12, t_eval=t)
    ex = mp.rigid.free_rotation(moments, w0, t)
    assert ex.shape == (201, 3)
    assert np.abs(s.y.T - ex).max() < 1e-9


@pytest.mark.parametrize("side", [1, -1])
def test_separatrix_flip(side):
    w0 = _near_separatrix(1e-8, side)
    T = mp.rigid.flip_period(I123, w0)
    assert np.isfinite(T) and T > 0
    t = np.linspace(0.0, 1.25 * T, 2001)
    s = mp.solve(RigidBody(I123), (0, t[-1]), w0, method="dop853", rtol=1e-13, atol=1e-14,
                 t_eval=t)
    ex = mp.rigid.free_rotation(I123, w0, t)
    # a trajectory 1e-8 from the separatrix passes the saddle, which amplifies
    # a perturbation by ~1/k'^2 ~ 1e8: integrations at rtol 1e-13 differ from
    # each other by ~1e-3 here, and from the exact solution by ~3e-4
    err = np.abs(s.y.T - ex).max()
    assert err < 1e-3, err
    # the intermediate component reverses every T/2: zero crossings of omega_2
    d = mp.solve(RigidBody(I123), (0, t[-1]), w0, rtol=1e-13, atol=1e-14, dense_output=True)
    w2 = s.y[1]
    idx = np.nonzero(np.sign(w2[:-1]) != np.sign(w2[1:]))[0]
    assert len(idx) == 2
    from scipy.optimize import brentq
    z = [brentq(lambda x: d.sol(x)[1], t[i], t[i + 1], xtol=1e-12) for i in idx]
    # same saddle sensitivity: matched to ~5e-6 T at 1e-8 (see test_flip_period_moderate)
    assert abs((z[1] - z[0]) - T / 2) < 2e-5 * T
    # the flip itself: omega_2 goes from +1 to -1
    assert w2.min() < -0.99


@pytest.mark.parametrize("side", [1, -1])
def test_flip_period_moderate(side):
    w0 = _near_separatrix(1e-2, side)
    T = mp.rigid.flip_period(I123, w0)
    d = mp.solve(RigidBody(I123), (0, 2 * T), w0, rtol=1e-13, atol=1e-14, dense_output=True)
    from scipy.optimize import brentq
    t = np.linspace(0, 2 * T, 4001)
    w2 = d.sol(t)[1]
    idx = np.nonzero(np.sign(w2[:-1]) != np.sign(w2[1:]))[0]
    z = np.array([brentq(lambda x: d.sol(x)[1], t[i], t[i + 1], xtol=1e-13) for i in idx])
    assert len(z) == 4
    assert np.abs(np.diff(z) - T / 2).max() < 1e-9 * T
    ex = mp.rigid.free_rotation(I123, w0, t)
    assert np.abs(d.sol(t).T - ex).max() < 1e-8


def test_flip_period_far_from_separatrix():
    # small oscillation about the largest axis: T -> 2 pi / sqrt((I3-I1)(I3-I2)/(I1 I2)) w3
    w0 = [1e-6, 1e-6, 1.0]
    T = mp.rigid.flip_period(I123, w0)
    T_lin = 2 * np.pi / np.sqrt((3 - 1) * (3 - 2) / (1 * 2))
    assert abs(T - T_lin) < 1e-9


def test_symmetric_precession_rate():
    I1, I3, w3 = 2.0, 3.0, 1.7
    w0 = [0.4, 0.0, w3]
    Omega = w3 * (I3 - I1) / I1
    t = np.linspace(0, 20, 101)
    s = mp.solve(RigidBody((I1, I1, I3)), (0, 20), w0, rtol=1e-12, atol=1e-12, t_eval=t)
    assert np.abs(s.y[0] - 0.4 * np.cos(Omega * t)).max() < 1e-9
    assert np.abs(s.y[1] - 0.4 * np.sin(Omega * t)).max() < 1e-9
    assert np.abs(mp.rigid.free_rotation((I1, I1, I3), w0, t) - s.y.T).max() < 1e-9


def test_split_keeps_L_to_roundoff():
    body = RigidBody((1.0, 2.0, 2.5))
    w0 = np.array([0.3, 1.0, -0.4])
    n = 10**6
    h = 0.01
    t_eval = np.linspace(0, n * h, 101)
    s = mp.solve(body, (0, n * h), w0, method="rigid:split", h=h, t_eval=t_eval)
    L = np.linalg.norm(body.angular_momentum(s.y), axis=0)
    rel = np.abs(L / L[0] - 1).max()
    assert rel < 1e-13, rel
    E = body.energy(s.y)
    assert np.abs(E / E[0] - 1).max() < 1e-3  # bounded oscillation, O(h^2)


@pytest.mark.parametrize("method,order", [("rigid:split", 2), ("rigid:split4", 4)])
def test_split_order_and_orientation(method, order):
    body = RigidBody(I123, orientation=True)
    y0 = body.initial_state([0.3, 1.0, -0.4])
    ref = mp.solve(body, (0, 5), y0, rtol=1e-13, atol=1e-14)
    errs = []
    for h in (0.02, 0.01):
        s = mp.solve(body, (0, 5), y0, method=method, h=h)
        errs.append(np.abs(s.y[:, -1] - ref.y[:, -1]).max())
        assert np.abs(np.linalg.norm(s.y[3:], axis=0) - 1).max() < 1e-13
    rate = np.log2(errs[0] / errs[1])
    assert abs(rate - order) < 0.3, rate
    # omega matches the exact solution too
    assert np.abs(s.y[:3, -1] - mp.rigid.free_rotation(I123, y0[:3], [5.0])[0]).max() < errs[1] * 2


def test_orientation_space_L_conserved():
    body = RigidBody(I123, orientation=True)
    y0 = body.initial_state([0.3, 1.0, -0.4], [0.1, 0.2, 0.3, np.sqrt(1 - 0.14)])
    s = mp.solve(body, (0, 10), y0, rtol=1e-12, atol=1e-12)
    R = mp.rotation.matrix_from_quat(s.y[3:].T)
    Ls = np.einsum("nij,jn->ni", R, body.angular_momentum(s.y))
    assert np.abs(Ls - Ls[0]).max() < 1e-9


def test_constant_torque():
    body = RigidBody(I123, torque=(0.0, 0.0, 0.6))
    # spin-up about a principal axis: w3 = w3_0 + tau t / I3
    s = mp.solve(body, (0, 2), [0, 0, 0.5], rtol=1e-12, atol=1e-12)
    assert abs(s.y[2, -1] - (0.5 + 0.6 * 2 / 3)) < 1e-12
    s2 = mp.solve(body, (0, 2), [0, 0, 0.5], method="rigid:split", h=0.01)
    assert abs(s2.y[2, -1] - (0.5 + 0.6 * 2 / 3)) < 1e-12


def test_scene_jacobians_match_differences():
    rng = np.random.default_rng(1)
    for sc, dim in [(RigidBody(I123, torque=(0.1, 0.2, 0.3)), 3),
                    (RigidBody(I123, orientation=True), 7),
                    (HeavyTop(1.2, 0.7, 2.0, 9.81, 0.3), 6)]:
        y = rng.normal(size=dim)
        if dim == 6:
            y[1] = 0.8
        J = sc.jacobian(0.0, y)
        Jn = np.empty((dim, dim))
        for j in range(dim):
            e = np.zeros(dim)
            e[j] = 1e-6
            Jn[:, j] = (sc.rhs(0.0, y + e) - sc.rhs(0.0, y - e)) / 2e-6
        assert np.abs(J - Jn).max() < 1e-7


def test_heavy_top_nutation():
    I1, I3, M, g, l = 0.5, 0.2, 1.0, 9.81, 0.1
    top = HeavyTop(I1, I3, M, g, l)
    th0, thd0, phd0, psd0 = 0.5, 0.3, 0.8, 40.0
    lo, hi = mp.rigid.nutation_bounds(I1, I3, M, g, l, th0, thd0, phd0, psd0)
    assert lo < th0 < hi
    y0 = [0.0, th0, 0.0, phd0, thd0, psd0]
    t = np.linspace(0, 6, 6001)
    s = mp.solve(top, (0, 6), y0, rtol=1e-12, atol=1e-12, t_eval=t)
    th = s.y[1]
    assert th.min() >= lo - 1e-9 and th.max() <= hi + 1e-9
    assert abs(th.min() - lo) < 1e-5 and abs(th.max() - hi) < 1e-5
    for q in (top.energy(s.y), top.p_phi(s.y), top.p_psi(s.y)):
        assert np.abs(q - q[0]).max() < 1e-9 * max(1.0, abs(q[0]))


def test_heavy_top_release_from_rest_bound():
    # released with theta_dot = phi_dot = 0: theta0 is the upper turning point... one bound
    I1, I3, M, g, l = 0.5, 0.2, 1.0, 9.81, 0.1
    lo, hi = mp.rigid.nutation_bounds(I1, I3, M, g, l, 0.6, 0.0, 0.0, 30.0)
    assert lo == pytest.approx(0.6, abs=1e-12) and hi > 0.6
    s = mp.solve(HeavyTop(I1, I3, M, g, l), (0, 3), [0, 0.6, 0, 0, 0, 30.0], rtol=1e-12,
                 atol=1e-12, t_eval=np.linspace(0, 3, 3001))
    assert abs(s.y[1].max() - hi) < 1e-5


def test_bad_input():
    with pytest.raises(ValueError):
        RigidBody((1.0, -2.0, 3.0))
    with pytest.raises(ValueError):
        RigidBody((1.0, 0.0, 3.0))
    with pytest.raises(ValueError, match="triangle"):
        RigidBody((1.0, 1.0, 3.0))
    with pytest.raises(ValueError):
        mp.rigid.free_rotation((1.0, 1.0, 3.0), [1, 1, 1], [0.0])
    with pytest.raises(ValueError):
        mp.rigid.free_rotation((1.0, 2.0, np.nan), [1, 1, 1], [0.0])
    with pytest.raises(ValueError):
        mp.rigid.flip_period((1.0, 2.0, 3.0), [1, np.inf, 1])
    body = RigidBody(I123, orientation=True)
    with pytest.raises(ValueError, match="unit"):
        body.initial_state([1, 0, 0], [0, 0, 0, 2.0])
    with pytest.raises(ValueError):
        mp.solve(body, (0, 1), [1, 0, 0, 0, 0, 0, 2.0], method="rigid:split", h=0.1)
    with pytest.raises(ValueError):  # the split methods are for RigidBody only
        mp.solve(mp.scenes.Kepler(), (0, 1), [1, 0, 0, 1], method="rigid:split", h=0.1)
    with pytest.raises(ValueError):
        HeavyTop(-1.0, 1.0, 1.0)
    with pytest.raises(ValueError):
        mp.rigid.nutation_bounds(1, 1, 1, 9.81, 1, 0.0, 0, 0, 1)


def test_scene_pickles_and_replaces():
    import pickle
    b = RigidBody(I123, torque=(0, 0, 1.0), orientation=True)
    assert pickle.loads(pickle.dumps(b)) == b
    assert b.replace(orientation=False).dim == 3
    assert b.dim == 7
    assert RigidBody(I123).energy([1.0, 1.0, 1.0]) == pytest.approx(3.0)
