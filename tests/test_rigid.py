"""Rigid bodies: Euler's equations against the exact elliptic solution, the
geometric split methods' invariants, the heavy top's nutation bounds and
conserved momenta, bad input."""
import ctypes

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


@pytest.mark.parametrize("wu", [0.9, 0.0])
@pytest.mark.parametrize("moments, axis", [((1.0, 2.5, 2.5), 0), ((2.5, 1.0, 2.5), 1),
                                           ((2.5, 2.5, 4.0), 2), ((4.0, 2.5, 2.5), 0)])
def test_free_rotation_symmetric_body_closed_form(moments, axis, wu):
    """A symmetric body, the equal pair the larger or the smaller moments: the
    component along the unique axis u stays constant and the other two turn at
    Omega = w_u (I_u - I) / I (Euler's equations of a symmetric top); with
    w_u = 0 the body spins steadily about an axis of the equal pair."""
    I_u = moments[axis]
    i, j = (axis + 1) % 3, (axis + 2) % 3
    I = moments[i]
    a = 0.35
    w0 = np.zeros(3)
    w0[axis], w0[j] = wu, a
    t = np.linspace(0, 25, 251)
    ex = mp.rigid.free_rotation(moments, w0, t)
    Omega = wu * (I_u - I) / I
    # w_i' = (I_j - I_u)/I w_j w_u = -Omega w_j, w_j' = Omega w_i (cyclic i, j, u)
    # measured: w_u exact, the pair within 3.3e-16
    assert np.all(ex[:, axis] == wu)
    assert np.abs(ex[:, i] + a * np.sin(Omega * t)).max() < 3e-15
    assert np.abs(ex[:, j] - a * np.cos(Omega * t)).max() < 3e-15
    with pytest.raises(ValueError):
        mp.rigid.flip_period(moments, w0)


@pytest.mark.parametrize("method", ["rigid:split", "rigid:split4"])
@pytest.mark.parametrize("orientation", [False, True])
def test_split_keeps_L_to_roundoff(method, orientation):
    # 10^6 steps: |L| (and |q|) to 1e-13 relative, the energy error bounded
    # (its O(h^p) oscillation at the end no larger than at the start)
    body = RigidBody((1.0, 2.0, 2.5), orientation=orientation)
    y0 = body.initial_state([0.3, 1.0, -0.4])
    n, h = 10**6, 0.01
    t_eval = np.linspace(0, n * h, 2001)
    s = mp.solve(body, (0, n * h), y0, method=method, h=h, t_eval=t_eval)
    L = np.linalg.norm(body.angular_momentum(s.y), axis=0)
    rel = np.abs(L / L[0] - 1).max()
    assert rel < 1e-13, rel
    if orientation:
        assert np.abs(np.linalg.norm(s.y[3:], axis=0) - 1).max() < 1e-13
    dE = np.abs(body.energy(s.y) / body.energy(y0) - 1)
    first, last = dE[:200].max(), dE[-200:].max()
    assert first < (1e-4 if method == "rigid:split" else 1e-8)
    assert last < 1.5 * first, (first, last)


def test_split_L_drift_below_unrotated_rounding():
    # the compensated increments: a fast spin (large rotation angle per step)
    # and a slow one both keep |L| within a few roundings
    for w0, h in (([5.0, 3.0, -2.0], 0.01), ([0.02, 1.0, 0.01], 0.05)):
        body = RigidBody((0.7, 1.3, 1.9))
        s = mp.solve(body, (0, 2e5 * h), w0, method="rigid:split4", h=h,
                     t_eval=np.linspace(0, 2e5 * h, 201))
        L = np.linalg.norm(body.angular_momentum(s.y), axis=0)
        assert np.abs(L / L[0] - 1).max() < 2e-14


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


@pytest.mark.parametrize("method", ["rigid:split", "rigid:split4"])
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_constant_torque_about_each_axis_split(axis, method):
    # a torque of 0.1 N m about one principal axis of a body spinning about it: the body
    # stays on that axis, w_i = w0 + tau t / I_i, and the orientation turns about the axis
    # by theta = w0 t + tau t^2 / (2 I_i), q = (sin(theta/2) e_i, cos(theta/2)); the split
    # kicks by tau h/2 about the exact rotation, so both hold to round-off
    tau, w0, T = 0.1, 0.5, 2.0
    torque = [0.0, 0.0, 0.0]
    torque[axis] = tau
    body = RigidBody(I123, torque=tuple(torque), orientation=True)
    w = [0.0, 0.0, 0.0]
    w[axis] = w0
    s = mp.solve(body, (0, T), body.initial_state(w, [0.0, 0.0, 0.0, 1.0]), method=method,
                 h=0.01)
    Ii = I123[axis]
    e = np.eye(3)[axis]
    theta = w0 * s.t + tau * s.t ** 2 / (2 * Ii)
    assert np.abs(s.y[:3] - np.outer(e, w0 + tau * s.t / Ii)).max() < 2e-15
    q = np.vstack([np.outer(e, np.sin(theta / 2)), np.cos(theta / 2)])
    assert np.abs(s.y[3:] - q).max() < 2e-15


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


def _steady_precession(I1, I3, M, g, l, th0, w3):
    """(phi_dot, psi_dot) of the slow steady precession at theta0 with spin w3: the root of
    I1 cos(theta0) phi_dot^2 - I3 w3 phi_dot + M g l = 0 (Goldstein 5.7), stably."""
    c, A = np.cos(th0), I3 * w3
    ph = 2.0 * M * g * l / (A + np.sqrt(A * A - 4.0 * I1 * c * M * g * l))
    return ph, w3 - ph * c


def _theta_extremes(top, y0, T):
    """min and max of theta over [0, T] from the turning points (theta_dot = 0 events)."""
    ev = lambda t, y: y[4]  # noqa: E731
    s = mp.solve(top, (0, T), y0, rtol=1e-13, atol=1e-15, events=ev)
    th = np.concatenate([s.y_events[0][:, 1], [y0[1]]])
    return th.min(), th.max()


TOP = (0.5, 0.2, 1.0, 9.81, 0.1)


@pytest.mark.parametrize("th0, w3", [(0.5, 40.0), (1.2, 8.0), (2.6, 400.0),
                                     (2.99826200791656, 40.0)])
def test_nutation_bounds_at_steady_precession(th0, w3):
    # on the steady-precession condition theta stays at theta0 (a double root of f(u))
    ph, ps = _steady_precession(*TOP, th0, w3)
    lo, hi = mp.rigid.nutation_bounds(*TOP, th0, 0.0, ph, ps)
    assert abs(lo - th0) <= 4e-16 and abs(hi - th0) <= 4e-16      # measured 0 .. 1.1e-16


@pytest.mark.parametrize("th0, w3", [(0.5, 40.0), (2.99826200791656, 40.0),
                                     (1.3142822200446478, 40.0)])
@pytest.mark.parametrize("thd, dphi", [(1e-4, 0.0), (1e-6, 0.0), (0.0, 1e-6), (0.0, -1e-4),
                                       (1e-9, 1e-9), (1e-3, 1e-5)])
def test_nutation_bounds_near_steady_precession_match_integration(th0, w3, thd, dphi):
    # a small nutation about steady precession: the two roots of f next to u0 nearly merge;
    # from the cubic's power-basis roots they were off by up to 7.5e-9 rad here, or the
    # call failed, or returned theta_min = 0 (3 rad off at theta0 = 2.998)
    ph, ps = _steady_precession(*TOP, th0, w3)
    ph *= 1.0 + dphi
    lo, hi = mp.rigid.nutation_bounds(*TOP, th0, thd, ph, ps)
    ref = _theta_extremes(HeavyTop(*TOP), [0.0, th0, 0.0, ph, thd, ps], 3.0)
    assert lo <= th0 <= hi
    assert abs(lo - ref[0]) < 5e-14 and abs(hi - ref[1]) < 5e-14   # measured <= 4e-16


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


# ---- torque as a C callback ------------------------------------------------

_DP = ctypes.POINTER(ctypes.c_double)
_TORQUE = ctypes.CFUNCTYPE(None, ctypes.c_double, _DP, _DP, ctypes.c_void_p)
TAU = (0.1, -0.2, 0.3)


@_TORQUE
def _const_torque(t, y, tau, ud):
    tau[0], tau[1], tau[2] = TAU


def _driven(t, w):
    # a time- and state-dependent torque: a rotating drive and a damping of w3
    return np.array([0.3 * np.cos(1.7 * t), 0.2 * np.sin(0.9 * t), -0.05 * w[2]])


@_TORQUE
def _driven_c(t, y, tau, ud):
    tau[0], tau[1], tau[2] = _driven(t, [y[0], y[1], y[2]])


@pytest.mark.parametrize("orientation", [False, True])
def test_callback_torque_jacobian_closed_form(orientation):
    # _driven's only state dependence is tau3 = -0.05 w3: the Jacobian is the
    # torque-free body's (exact) plus d(w3')/d(w3) = -0.05 / I3, taken by differences
    y = RigidBody(I123, orientation=orientation).initial_state([0.3, 1.0, -0.4])
    J = RigidBody(I123, torque=_driven_c, orientation=orientation).jacobian(0.7, y)
    expect = RigidBody(I123, orientation=orientation).jacobian(0.7, y)
    expect[2, 2] += -0.05 / I123[2]
    assert np.abs(J - expect).max() < 1e-12     # measured 9.9e-14 (central differences)


@pytest.mark.parametrize("orientation", [False, True])
@pytest.mark.parametrize("method", ["dop853", "rk4"])
def test_callback_torque_equals_constant(orientation, method):
    kw = dict(h=0.01) if method == "rk4" else {}
    a_body = RigidBody(I123, torque=TAU, orientation=orientation)
    b_body = RigidBody(I123, torque=_const_torque, orientation=orientation)
    y0 = a_body.initial_state([0.3, 1.0, -0.4])
    a = mp.solve(a_body, (0, 10), y0, method=method, **kw)
    b = mp.solve(b_body, (0, 10), y0, method=method, **kw)
    assert np.array_equal(a.y, b.y)  # the same arithmetic in the same order
    assert np.array_equal(a_body.rhs(0.5, y0), b_body.rhs(0.5, y0))
    # radau: the callback's Jacobian comes from differences, the constant's is exact
    a = mp.solve(a_body, (0, 10), y0, method="radau", rtol=1e-12, atol=1e-12)
    b = mp.solve(b_body, (0, 10), y0, method="radau", rtol=1e-12, atol=1e-12)
    assert np.abs(a.y[:, -1] - b.y[:, -1]).max() < 1e-10


def test_callback_torque_against_solve_ivp():
    from scipy.integrate import solve_ivp
    Iv = np.array(I123)

    def f(t, w):
        e = [(Iv[1] - Iv[2]) * w[1] * w[2], (Iv[2] - Iv[0]) * w[2] * w[0],
             (Iv[0] - Iv[1]) * w[0] * w[1]]
        return (np.array(e) + _driven(t, w)) / Iv

    w0 = [0.3, 1.0, -0.4]
    t = np.linspace(0, 20, 101)
    ref = solve_ivp(f, (0, 20), w0, method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t)
    s = mp.solve(RigidBody(I123, torque=_driven_c), (0, 20), w0, rtol=1e-12, atol=1e-12,
                 t_eval=t)
    assert np.abs(s.y - ref.y).max() < 1e-9
    # the ensemble runs the same C callback on threads with the GIL released
    e = mp.solve_many(RigidBody(I123, torque=_driven_c), (0, 20), [w0, [1.0, 0.0, 0.5]],
                      rtol=1e-12, atol=1e-12, t_eval=t, threads=2)
    assert np.array_equal(e.y[0], s.y)
    r2 = solve_ivp(f, (0, 20), [1.0, 0.0, 0.5], method="DOP853", rtol=1e-12, atol=1e-12,
                   t_eval=t)
    assert np.abs(e.y[1] - r2.y).max() < 1e-9


def test_callback_torque_with_params_and_lowlevelcallable():
    from scipy import LowLevelCallable
    # user_data points to a drive amplitude read by the callback
    amp = (ctypes.c_double * 1)(0.4)

    @_TORQUE
    def drive(t, y, tau, ud):
        a = ctypes.cast(ud, _DP)[0]
        tau[0], tau[1], tau[2] = 0.0, 0.0, a

    llc = LowLevelCallable(drive, ctypes.cast(amp, ctypes.c_void_p))
    body = RigidBody(I123, torque=llc)
    s = mp.solve(body, (0, 2), [0, 0, 0.5], rtol=1e-12, atol=1e-12)
    assert abs(s.y[2, -1] - (0.5 + 0.4 * 2 / 3)) < 1e-12  # spin-up about axis 3
    # per-trajectory moments through params (the torque is read from the callback)
    P = [[1.0, 2.0, 3.0, 0, 0, 0], [1.0, 2.0, 2.0, 0, 0, 0]]
    e = mp.solve_many(body, (0, 2), [[0, 0, 0.5], [0, 0, 0.5]], params=P, rtol=1e-12,
                      atol=1e-12)
    assert np.abs(e.y[:, 2, -1] - (0.5 + 0.4 * 2 / np.array([3.0, 2.0]))).max() < 1e-12


def test_callback_torque_numba():
    pytest.importorskip("numba")
    from mechpy.benches.rigid import _numba_torque
    driven = _numba_torque()  # the torque of _driven_c, as a numba cfunc

    w0 = [0.3, 1.0, -0.4]
    a = mp.solve(RigidBody(I123, torque=driven), (0, 20), w0, rtol=1e-12, atol=1e-12)
    b = mp.solve(RigidBody(I123, torque=_driven_c), (0, 20), w0, rtol=1e-12, atol=1e-12)
    assert np.abs(a.y[:, -1] - b.y[:, -1]).max() < 1e-13


def test_callback_gravity_torque_is_the_heavy_top():
    # a symmetric top about its fixed point, gravity as a body-frame torque
    # tau = l e3 x R^T (0, 0, -M g) of the quaternion: the HeavyTop scene's theta(t)
    I1, I3, M, g, l = 0.5, 0.2, 1.0, 9.81, 0.1

    @_TORQUE
    def gravity(t, y, tau, ud):
        x, yy, z, w = y[3], y[4], y[5], y[6]
        # third row of R (body to space): the space z axis in body coordinates
        zb = (2 * (x * z - w * yy), 2 * (yy * z + w * x), 1 - 2 * (x * x + yy * yy))
        tau[0] = -l * zb[1] * (-M * g)
        tau[1] = l * zb[0] * (-M * g)
        tau[2] = 0.0

    th0, phd0, psd0 = 0.5, 0.8, 40.0
    # ZXZ angles (phi, theta, psi) = (0, th0, 0), theta_dot = 0: body omega
    # (phi' sin th sin psi, phi' sin th cos psi, psi' + phi' cos th)
    w0 = [0.0, phd0 * np.sin(th0), psd0 + phd0 * np.cos(th0)]
    q0 = [np.sin(th0 / 2), 0.0, 0.0, np.cos(th0 / 2)]
    body = RigidBody((I1, I1, I3), torque=gravity, orientation=True)
    t = np.linspace(0, 2, 201)
    s = mp.solve(body, (0, 2), body.initial_state(w0, q0), rtol=1e-12, atol=1e-12, t_eval=t)
    x, y_ = s.y[3], s.y[4]
    cos_th = 1 - 2 * (x * x + y_ * y_)
    top = mp.solve(HeavyTop(I1, I3, M, g, l), (0, 2), [0, th0, 0, phd0, 0.0, psd0],
                   rtol=1e-12, atol=1e-12, t_eval=t)
    assert np.abs(cos_th - np.cos(top.y[1])).max() < 1e-8


def test_callback_torque_bad_input():
    with pytest.raises(ValueError, match="torque callback"):
        mp.solve(RigidBody(I123, torque=_const_torque), (0, 1), [1, 0, 0], method="rigid:split",
                 h=0.1)
    with pytest.raises(ValueError, match="torque callback"):
        mp.solve_many(RigidBody(I123, torque=_const_torque), (0, 1), [[1, 0, 0]],
                      method="rigid:split4", h=0.1)
    with pytest.raises(TypeError, match="C function"):
        RigidBody(I123, torque=lambda t, y: [0, 0, 0])
    with pytest.raises(TypeError, match="signature"):
        RigidBody(I123, torque=ctypes.CFUNCTYPE(None, ctypes.c_double)(lambda t: None))
    with pytest.raises(TypeError):
        import pickle
        pickle.dumps(RigidBody(I123, torque=_const_torque))


def test_scene_evaluation_at_a_singular_state_raises_instead_of_returning_garbage():
    # the top's Euler-angle equations are singular at theta = 0; its rhs reports
    # it, and the evaluation must say so rather than hand back unwritten memory
    top = mp.scenes.HeavyTop(1.0, 2.0, 1.0)
    y = np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0])
    with pytest.raises(mp.errors.SingularityError, match="HeavyTop rhs"):
        top.rhs(0.0, y)
    with pytest.raises(mp.errors.SingularityError, match="HeavyTop jacobian"):
        top.jacobian(0.0, y)
    good = y.copy()
    good[1] = 0.4
    assert np.isfinite(top.rhs(0.0, np.stack([good, good], axis=1))).all()
    with pytest.raises(mp.errors.NonFiniteError, match="Kepler rhs at state 1"):
        mp.scenes.Kepler().rhs(0.0, np.array([[1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]))


@pytest.mark.parametrize("th0, thd, phd, psd", [
    (2.2, 0.5, 1.0, 30.0), (2.8, -0.3, 0.2, 30.0), (1.9, 0.0, 3.0, 30.0), (0.4, 0.7, -0.5, 30.0),
    # a wide nutation from below the horizontal: theta_min (1.54) above u = 1 + 2 cos theta0
    (2.5, 6.6, 2.1, 22.9), (1.93, -1.86, 9.94, 48.1),
    # a slow top falling from near the vertical past the horizontal: cos theta_max
    # below cos theta0 - 1, the far end of the lower root's bracket
    (0.3, 0.0, 0.0, 3.0), (0.5, 1.0, 0.0, 5.0)])
def test_nutation_bounds_below_the_horizontal_match_integration(th0, thd, phd, psd):
    # theta0 beyond pi/2 (cos theta0 < 0) as well as above: both turning points against
    # the extremes of a tight integration
    y0 = [0.0, th0, 0.0, phd, thd, psd]
    lo, hi = mp.rigid.nutation_bounds(*TOP, th0, thd, phd, psd)
    ref = _theta_extremes(HeavyTop(*TOP), y0, 3.0)
    assert lo <= th0 <= hi
    assert abs(lo - ref[0]) < 1e-13 and abs(hi - ref[1]) < 1e-13   # measured <= 2e-14


def test_free_precession_closed_form_and_integration():
    # a symmetric body (I1 = I2): omega's component across the axis turns in the body
    # at Omega = omega3 (I3 - I1) / I1, and the axis about L in space at |L| / I1
    I1, I3, w0 = 1.0, 1.5, np.array([0.3, 0.0, 2.0])
    body, space = mp.rigid.free_precession([I1, I1, I3], w0)
    assert body == pytest.approx(2.0 * (I3 - I1) / I1, rel=1e-15)
    assert space == pytest.approx(np.sqrt(0.3 ** 2 + (I3 * 2.0) ** 2) / I1, rel=1e-15)
    T = 2 * np.pi / abs(body)
    s = mp.solve(RigidBody((I1, I1, I3)), (0, T), w0, rtol=1e-12, atol=1e-12,
                 t_eval=[T / 2, T])
    np.testing.assert_allclose(s.y[:, 0], [-0.3, 0.0, 2.0], atol=1e-9)
    np.testing.assert_allclose(s.y[:, 1], w0, atol=1e-9)
    # I1 = I2 up to 1e-12 relative is symmetric; beyond it is refused, named
    assert mp.rigid.free_precession([1.0, 1.0 + 5e-13, 1.5], w0)[0] == pytest.approx(body)
    with pytest.raises(ValueError, match="symmetric body, I1 = I2"):
        mp.rigid.free_precession([1.0, 1.1, 1.5], w0)
