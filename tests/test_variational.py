"""mechpy.variational against closed forms, SciPy shooting and conservation laws."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, fsolve

import mechpy as mp

V = mp.variational
G = 9.81


def _order(errors):
    """Observed orders log2(e_n / e_2n) for n doubling."""
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


# ---- references (independent of the code under test) --------------------------

def _cycloid_ref(X, Y):
    """(theta_end, a, time) of the cycloid through (X, Y), y downward."""
    th = brentq(lambda t: (t - np.sin(t)) / (1 - np.cos(t)) - X / Y, 1e-3, 2 * np.pi - 1e-6,
                xtol=1e-15)
    a = Y / (1 - np.cos(th))
    return th, a, th * np.sqrt(a / G)


def _cycloid_y(x, a, th_end):
    out = []
    for xi in x:
        if xi == 0:
            out.append(0.0)
            continue
        t = brentq(lambda t: a * (t - np.sin(t)) - xi, 0, th_end + 1e-12, xtol=1e-15)
        out.append(a * (1 - np.cos(t)))
    return np.array(out)


def _catenary_ref(xa, ya, xb, yb, L):
    """y = A cosh((x - x0)/A) + c through both ends with arc length L (fsolve)."""
    def eqs(v):
        A, x0, c = v
        return [A * np.cosh((xa - x0) / A) + c - ya, A * np.cosh((xb - x0) / A) + c - yb,
                A * (np.sinh((xb - x0) / A) - np.sinh((xa - x0) / A)) - L]
    # A from sqrt(L^2 - v^2) = 2 A sinh(H / 2A), then fsolve on all three equations
    H, v = xb - xa, yb - ya
    A0 = brentq(lambda A: 2 * A * np.sinh(H / (2 * A)) - np.sqrt(L * L - v * v), H / 50, 1e3)
    x00 = 0.5 * (xa + xb) - A0 * np.arcsinh(v / (2 * A0 * np.sinh(H / (2 * A0))))
    c0 = ya - A0 * np.cosh((xa - x00) / A0)
    sol = fsolve(eqs, [A0, x00, c0], xtol=1e-12)
    assert np.max(np.abs(eqs(sol))) < 1e-11
    return sol


def _shoot(f, qa, qb, T, v_lo, v_hi, t_eval):
    """Shooting with solve_ivp (DOP853) + brentq on the initial velocity."""
    def miss(v):
        return solve_ivp(f, (0, T), [qa, v], method="DOP853", rtol=1e-12, atol=1e-12).y[0, -1] - qb
    v = brentq(miss, v_lo, v_hi, xtol=1e-13)
    s = solve_ivp(f, (0, T), [qa, v], method="DOP853", rtol=1e-12, atol=1e-12, t_eval=t_eval)
    return s.y[0]


def _action(L, t, q):
    """Midpoint discrete action sum h L(mid q, dq/h)."""
    h = np.diff(t)
    return np.sum(h * L(0.5 * (q[1:] + q[:-1]), np.diff(q) / h))


# ---- brachistochrone ------------------------------------------------------------------

def test_brachistochrone_published_values_and_order():
    r = V.brachistochrone(2.0, 1.0, n=50)
    # the cycloid's time theta_e sqrt(a / g), solved for theta_e here (0.80556383 s)
    th, a, t_ref = _cycloid_ref(2.0, 1.0)
    assert abs(r.time_exact - t_ref) < 1e-13 * t_ref
    assert abs(r.time_line - np.sqrt(2 * (2.0 ** 2 + 1.0 ** 2) / (G * 1.0))) < 1e-15
    assert abs(r.radius - a) < 1e-12 and abs(r.theta_end - th) < 1e-12
    errs, cerrs = [], []
    for n in (25, 50, 100, 200, 400):
        r = V.brachistochrone(2.0, 1.0, n=n)
        errs.append(abs(r.time - t_ref))
        cerrs.append(np.max(np.abs(r.y - _cycloid_y(r.x, a, th))))
    assert errs[-1] < 1e-7 and cerrs[-1] < 1e-6          # 5.3e-8 s, 2.5e-7 m measured
    assert np.all(np.abs(_order(errs) - 2) < 0.1), errs  # second order in 1/n
    assert np.all(_order(cerrs) > 1.8), cerrs
    assert r.time < r.time_line
    assert r.x[0] == 0 and r.y[0] == 0 and abs(r.x[-1] - 2) < 1e-15 and abs(r.y[-1] - 1) < 1e-14


@pytest.mark.parametrize("X, Y", [(10.0, 1.0), (0.3, 2.0), (1.0, 1.0)])
def test_brachistochrone_other_ends(X, Y):
    _, _, t_ref = _cycloid_ref(X, Y)
    errs = [abs(V.brachistochrone(X, Y, n=n).time - t_ref) for n in (100, 200, 400)]
    assert errs[-1] < 1e-5 * t_ref, errs       # 2.1e-6 relative for (10, 1), a deep dip
    assert np.all(np.abs(_order(errs) - 2) < 0.1), errs
    assert V.brachistochrone(X, Y, n=50).time < V.brachistochrone(X, Y, n=50).time_line


def test_brachistochrone_is_a_minimum_of_the_discrete_time():
    r = V.brachistochrone(2.0, 1.0, n=100)
    s = np.cbrt(r.x / 2.0)
    c = 1 / np.sqrt(2 * G)

    def J(u):   # the discrete functional in (s, u = sqrt y), written out here
        h = np.diff(s)
        sm, um, up = 0.5 * (s[1:] + s[:-1]), 0.5 * (u[1:] + u[:-1]), np.diff(u) / h
        return np.sum(h * c * np.sqrt((6 * sm * sm) ** 2 + 4 * um * um * up * up) / um)
    u = np.sqrt(r.y)
    assert abs(J(u) - r.time) < 1e-14
    rng = np.random.default_rng(1)
    for _ in range(20):
        eta = np.zeros_like(u)
        eta[1:-1] = rng.standard_normal(len(u) - 2) * np.sin(np.pi * s[1:-1])
        eps = 1e-5
        d2 = J(u + eps * eta) - J(u)
        assert d2 > 0
        # first variation vanishes: the symmetric difference is O(eps^3)
        assert abs(J(u + eps * eta) - J(u - eps * eta)) < 1e-3 * d2


# ---- catenary ----------------------------------------------------------------------------

@pytest.mark.parametrize("a, b, L", [(0.0, 2.0, 2.2), (0.0, 2.0, 3.0), (0.0, 2.0, 6.0),
                                     ((0.0, 0.0), (2.0, 1.0), 3.0), ((-1.0, 2.0), (1.5, 0.5), 4.0)])
def test_catenary_against_cosh(a, b, L):
    xa, ya = (a, 0.0) if np.ndim(a) == 0 else a
    xb, yb = (b, 0.0) if np.ndim(b) == 0 else b
    A, x0, c = _catenary_ref(xa, ya, xb, yb, L)
    errs = []
    for n in (50, 100, 200):
        r = V.catenary(a, b, L, n=n)
        y_ref = A * np.cosh((r.x - x0) / A) + c
        errs.append(np.max(np.abs(r.y - y_ref)))
        assert abs(r.length - L) < 1e-11
    assert np.all(np.abs(_order(errs) - 2) < 0.15), errs
    assert errs[-1] < 1e-4 * L
    assert abs(r.a - A) < 1e-10 * A and abs(r.c - c) < 1e-9 * (1 + abs(c))
    assert np.max(np.abs(r.y_exact - (A * np.cosh((r.x - x0) / A) + c))) < 1e-9
    # the multiplier is -c (tension per weight T/w = y + lambda = A cosh), to O(h^2)
    assert abs(r.multiplier - (-c)) < 2e-4 * (1 + abs(c))
    assert abs(r.horizontal_tension - A) < 2e-4 * A


def test_catenary_beyond_one_block_of_evaluations():
    """The integrands are evaluated by blocks of 2^18 intervals (Ctrl-C is asked
    between blocks): n = 270000 has a second block, whose length constraint must
    see its own nodes.  Against cosh, to round-off of the banded Newton solve
    (h^2 = 1.4e-11): y measured 2.7e-12, the length 3.7e-14, the multiplier 1.6e-12."""
    r = V.catenary((0.0, 0.0), (1.0, 0.0), 1.5, n=270000)
    assert np.max(np.abs(r.y - r.y_exact)) < 3e-11
    assert abs(r.length - 1.5) < 1e-12
    assert abs(r.multiplier - r.multiplier_exact) < 2e-11


def test_catenary_lower_energy_than_other_chains_of_same_length():
    r = V.catenary(0.0, 2.0, 3.0, n=100)
    rng = np.random.default_rng(2)
    x = r.x

    def length(y):
        return np.sum(np.hypot(np.diff(x), np.diff(y)))

    def energy(y):
        return np.sum(0.5 * (y[1:] + y[:-1]) * np.hypot(np.diff(x), np.diff(y)))
    for _ in range(10):
        eta = np.zeros_like(x)
        eta[1:-1] = rng.standard_normal(len(x) - 2) * 1e-2
        y = r.y + eta
        # stay on the constraint: y_s = s * y (ends are at 0), s fixed by the length
        s = brentq(lambda s: length(s * y) - 3.0, 0.2, 5.0)
        assert energy(s * y) > r.energy


# ---- least action -------------------------------------------------------------------------

def test_harmonic_oscillator_path_closed_form_and_order():
    def L(q, v):
        return 0.5 * v * v - 0.5 * q * q
    qa, qb, T = 0.3, 0.7, 2.0
    errs = []
    for n in (50, 100, 200):
        r = V.stationary_path(L, qa, qb, T, n)
        exact = (qa * np.sin(T - r.t) + qb * np.sin(r.t)) / np.sin(T)
        errs.append(np.max(np.abs(r.q - exact)))
    assert errs[-1] < 2e-5
    assert np.all(np.abs(_order(errs) - 2) < 0.05), errs
    # the scene route (Duffing with beta = 0 in C) gives the same discrete path
    d = V.stationary_path(mp.scenes.Duffing(alpha=1.0, beta=0.0), qa, qb, T, 200)
    assert np.max(np.abs(d.q - r.q)) < 1e-9
    # velocity and momentum from the discrete Legendre transform
    v_exact = (-qa * np.cos(T - r.t) + qb * np.cos(r.t)) / np.sin(T)
    assert np.max(np.abs(d.qdot - v_exact)) < 1e-4


def test_action_minimum_before_conjugate_point_saddle_after():
    def L(q, v):
        return 0.5 * v * v - 0.5 * q * q
    rng = np.random.default_rng(3)
    for T, is_min in ((2.0, True), (4.0, False)):   # conjugate point at T = pi
        r = V.stationary_path(L, 0.1, 0.2, T, 100)
        S0 = _action(L, r.t, r.q)
        assert abs(S0 - r.action) < 1e-12
        d2 = []
        for _ in range(20):
            eta = np.zeros_like(r.q)
            eta[1:-1] = rng.standard_normal(len(r.q) - 2)
            e = 1e-3
            plus, minus = _action(L, r.t, r.q + e * eta), _action(L, r.t, r.q - e * eta)
            assert abs(plus - minus) < 1e-9                 # first variation = 0
            d2.append(plus + minus - 2 * S0)
        mode = np.sin(np.pi * (r.t - r.t[0]) / T)            # the lowest mode
        dm = _action(L, r.t, r.q + 1e-3 * mode) - S0
        if is_min:
            assert min(d2) > 0 and dm > 0
        else:
            assert dm < 0


@pytest.mark.parametrize("damping", [0.0, 0.3])
def test_pendulum_path_against_solve_ivp_shooting(damping):
    p = mp.scenes.Pendulum(damping=damping)
    qa, qb, T = 0.2, -0.5, 1.0
    errs = []
    for n in (100, 200, 400):
        r = V.stationary_path(p, qa, qb, T, n)
        ref = _shoot(lambda t, y: [y[1], -G * np.sin(y[0]) - damping * y[1]], qa, qb, T,
                     -10, 5, r.t)
        errs.append(np.max(np.abs(r.q - ref)))
    assert errs[-1] < 2e-5, errs        # 1.3e-5 at n = 400
    assert np.all(np.abs(_order(errs) - 2) < 0.1), errs
    # mp.solve from the path's initial state lands on q_b
    s = mp.solve(p, (0, T), [qa, r.qdot[0]], rtol=1e-12, atol=1e-12)
    assert abs(s.y[0, -1] - qb) < 1e-4


# ---- variational integrator -----------------------------------------------------------------

def test_variational_integrator_energy_bounded_and_symplectic():
    p = mp.scenes.Pendulum()
    h = 0.05
    r = V.variational_integrate(p, (0, 2000), 2.0, 0.0, h)
    E = r.energy
    dE = np.abs(E - E[0])
    k = len(E) // 10
    assert dE.max() < 0.05 * abs(E[0])                         # O(h^2), no drift
    assert dE[-k:].max() < 1.5 * dE[:k].max() + 1e-12           # bounded over 40000 steps
    # classical RK4 with the same step drifts
    rk = mp.solve(p, (0, 2000), [2.0, 0.0], method="rk4", h=h)
    dErk = np.abs(p.energy(rk.y) - p.energy(rk.y[:, 0]))
    kk = len(dErk) // 10
    assert dErk[-kk:].max() > 5 * dErk[:kk].max()            # grows with time

    # symplectic: the (q, p) map over 200 steps has unit Jacobian determinant
    def flow(q0, p0):
        from mechpy import _core
        q, pp = _core.variational_integrate(("scene", "Pendulum", [G, 1.0, 0, 0, 0]), 0.0, h, 200,
                                            [[q0]], [[p0]], [[0.0]], 1e-12)
        return np.array([q[-1, 0], pp[-1, 0]])
    z = np.array([1.0, 0.5])
    d = 1e-6
    Jm = np.column_stack([(flow(*(z + d * e)) - flow(*(z - d * e))) / (2 * d)
                          for e in np.eye(2)])
    assert abs(np.linalg.det(Jm) - 1) < 1e-6


def test_variational_integrator_second_order_and_python_lagrangian():
    p = mp.scenes.Pendulum()
    ref = solve_ivp(lambda t, y: [y[1], -G * np.sin(y[0])], (0, 2), [1.0, 0.0], method="DOP853",
                    rtol=1e-12, atol=1e-12).y[:, -1]
    errs = [abs(V.variational_integrate(p, (0, 2), 1.0, 0.0, h).q[-1] - ref[0])
            for h in (0.02, 0.01, 0.005)]
    assert np.all(np.abs(_order(errs) - 2) < 0.1), errs
    a = V.variational_integrate(lambda q, v: 0.5 * v * v + G * np.cos(q), (0, 2), 1.0, 0.0, 0.01)
    b = V.variational_integrate(p, (0, 2), 1.0, 0.0, 0.01)
    assert np.max(np.abs(a.q - b.q)) < 1e-8
    assert np.max(np.abs(a.p - b.p)) < 1e-8


# ---- momenta, cyclic coordinates -------------------------------------------------------------

def test_central_force_cyclic_angle_and_conserved_momentum():
    cf = V.CentralForce(m=2.0, k=3.0)
    s = mp.solve(cf.rhs, (0, 20), [1.0, 0.0, 0.1, 1.1], rtol=1e-11, atol=1e-12,
                 t_eval=np.linspace(0, 20, 201))
    q, qd = s.y[:2], s.y[2:]
    assert V.cyclic_coordinates(cf, q, qd) == (1,)
    pm = V.generalized_momenta(cf, q, qd)
    assert np.max(np.abs(pm - cf.momenta(s.y))) < 1e-9
    assert np.ptp(pm[1]) < 1e-8                 # p_phi conserved
    assert np.ptp(pm[0]) > 0.1                  # p_r is not


def test_pendulum_momentum_and_hoop_has_no_cyclic_coordinate():
    p = mp.scenes.Pendulum(length=2.0)
    th, thd = np.array([0.1, 0.7]), np.array([1.0, -2.0])
    assert np.allclose(V.generalized_momenta(p, th, thd), 4.0 * thd, rtol=1e-10)
    assert V.cyclic_coordinates(p, th[None], thd[None]) == ()
    hoop = V.RotatingHoop(R=0.5, omega=6.0)
    s = mp.solve(hoop.rhs, (0, 10), [0.3, 0.0], rtol=1e-11, atol=1e-12,
                 t_eval=np.linspace(0, 10, 101))
    assert V.cyclic_coordinates(hoop, s.y[:1], s.y[1:]) == ()
    h = hoop.jacobi_integral(s.y)
    assert np.ptp(h) < 1e-8
    E = 0.5 * hoop.R ** 2 * (s.y[1] ** 2 + (hoop.omega * np.sin(s.y[0])) ** 2) \
        - G * hoop.R * np.cos(s.y[0])
    assert np.ptp(E) > 0.1                      # the energy itself is not conserved


# ---- constraint forces ------------------------------------------------------------------------

def test_pendulum_tension_matches_newton():
    p = mp.scenes.Pendulum(length=1.5)
    s = mp.solve(p, (0, 5), [2.5, 0.0], rtol=1e-10, atol=1e-12, t_eval=np.linspace(0, 5, 101))
    m = 0.7
    T = V.pendulum_tension(p, s.y, mass=m)
    newton = m * (G * np.cos(s.y[0]) + 1.5 * s.y[1] ** 2)
    assert np.max(np.abs(T - newton)) < 1e-12 * np.max(np.abs(newton))
    assert T.min() < 0 < T.max()     # the string goes slack near the top at 2.5 rad


def test_hoop_normal_force_matches_newton():
    hoop = V.RotatingHoop(R=0.5, omega=6.0, m=0.2)
    s = mp.solve(hoop.rhs, (0, 3), [0.3, 0.0], rtol=1e-12, atol=1e-13, dense_output=True)
    t = np.linspace(0.1, 2.9, 29)
    N = hoop.normal_force(t, s.sol(t))

    def pos(tt):
        th = s.sol(tt)[0]
        w = hoop.omega
        return hoop.R * np.stack([np.sin(th) * np.cos(w * tt), np.sin(th) * np.sin(w * tt),
                                  -np.cos(th)])
    d = 1e-3   # acceleration by a fourth-order central difference of the position
    acc = (-pos(t + 2 * d) + 16 * pos(t + d) - 30 * pos(t) + 16 * pos(t - d)
           - pos(t - 2 * d)) / (12 * d * d)
    Fn = hoop.m * acc - hoop.m * np.array([0, 0, -G])[:, None]   # Newton: N = m a - m g
    r = pos(t) / hoop.R
    ph = np.stack([-np.sin(6 * t), np.cos(6 * t), 0 * t])
    assert np.max(np.abs(N[0] - np.sum(Fn * r, 0))) < 1e-5
    assert np.max(np.abs(N[1] - np.sum(Fn * ph, 0))) < 1e-5
    assert np.max(np.abs(N[2])) < 1e-12
    assert np.max(np.abs(N[1])) > 0.1           # the hoop pushes the bead around


# ---- the general minimiser ----------------------------------------------------------------------

def test_minimal_surface_of_revolution_is_a_catenoid():
    r = V.minimize_functional(lambda x, y, yp: y * np.sqrt(1 + yp * yp), (-0.5, 0.5), (1.0, 1.0),
                              200)
    A = brentq(lambda A: A * np.cosh(0.5 / A) - 1, 0.6, 1.0)   # the stable (shallow) catenoid
    assert np.max(np.abs(r.y - A * np.cosh(r.x / A))) < 1e-5


def test_isoperimetric_arc_is_a_circle():
    L = 2.5    # maximise the area under a curve of fixed length over [-1, 1]
    r = V.minimize_functional(lambda x, y, yp: -y, (-1, 1), (0, 0), 200,
                              constraints=[(lambda x, y, yp: np.sqrt(1 + yp * yp), L)],
                              guess=0.5 * np.cos(np.pi * np.linspace(-1, 1, 201) / 2),
                              multipliers=[1.0])
    # circle through (+-1, 0) of arc length L: radius R with 2 R asin(1/R) = L
    R = brentq(lambda R: 2 * R * np.arcsin(1 / R) - L, 1.0 + 1e-12, 100)
    yc = np.sqrt(R * R - 1)
    assert np.max(np.abs(r.y - (np.sqrt(R * R - r.x ** 2) - yc))) < 1e-4
    assert abs(abs(r.multipliers[0]) - R) < 1e-3   # the multiplier is the radius


# ---- bad input -----------------------------------------------------------------------------------

def test_bad_input():
    with pytest.raises(ValueError, match="not longer"):
        V.catenary(0.0, 2.0, 1.5)
    with pytest.raises(ValueError, match="not longer"):
        V.catenary((0, 0), (3, 4), 5.0)
    with pytest.raises(ValueError, match="cannot be reached"):
        V.brachistochrone(2.0, -1.0)
    with pytest.raises(ValueError, match="cannot be reached"):
        V.brachistochrone(2.0, 0.0)
    with pytest.raises(ValueError, match="x_end"):
        V.brachistochrone(0.0, 1.0)
    for bad_n in (0, 2, 3):
        with pytest.raises(ValueError, match="too small"):
            V.brachistochrone(2.0, 1.0, n=bad_n)
        with pytest.raises(ValueError, match="too small"):
            V.catenary(0, 1, 2, n=bad_n)
    with pytest.raises(TypeError):
        V.brachistochrone(2.0, 1.0, n=10.5)
    with pytest.raises(ValueError):
        V.brachistochrone(np.nan, 1.0)
    with pytest.raises(ValueError):
        V.catenary(0, 2, np.inf)
    with pytest.raises(ValueError):
        V.stationary_path(mp.scenes.Pendulum(), 0, 1, -1.0, 50)
    with pytest.raises(TypeError):
        V.stationary_path(mp.scenes.VanDerPol(), 0, 1, 1.0, 50)
    with pytest.raises(TypeError):
        V.stationary_path("pendulum", 0, 1, 1.0, 50)
    with pytest.raises(mp.ConvergenceError):
        V.brachistochrone(2.0, 1.0, n=100, max_iter=1)
    with pytest.raises(ZeroDivisionError):
        V.stationary_path(lambda q, v: 1 / 0, 0, 1, 1.0, 20)
    with pytest.raises(ValueError):
        V.pendulum_tension(mp.scenes.Pendulum(), np.zeros((3, 4)))
    with pytest.raises(ValueError):
        V.constraint_forces(-1.0, [0, 0], [[1, 0]], [0])


def test_heavy_top_momenta_cyclic_and_conserved():
    """phi and psi are cyclic in the heavy top's Lagrangian: p_phi and p_psi
    (from dL/dqdot) are conserved along a trajectory and equal the closed forms."""
    top = mp.scenes.HeavyTop(I1=0.5, I3=0.2, mass=1.0, g=9.81, l=0.3)
    y0 = [0.0, 0.6, 0.0, 1.0, 0.0, 20.0]
    s = mp.solve(top, (0, 5), y0, rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 5, 201))
    q, qdot = s.y[:3], s.y[3:]
    assert mp.variational.cyclic_coordinates(top, q, qdot) == (0, 2)
    p = mp.variational.generalized_momenta(top, q, qdot)
    np.testing.assert_allclose(p[0], top.p_phi(s.y), rtol=1e-9)
    np.testing.assert_allclose(p[2], top.p_psi(s.y), rtol=1e-9)
    assert np.ptp(p[0]) < 1e-9 * abs(p[0][0]) and np.ptp(p[2]) < 1e-9 * abs(p[2][0])
    assert np.ptp(p[1]) > 1e-3  # p_theta is not conserved: the top nutates


# ---- d coordinates ------------------------------------------------------------------------------

# Two coupled oscillators, L = |v|^2 / 2 - q^T K q / 2: in the normal coordinates
# eta = U^T q (K = U diag(w^2) U^T) each mode is a harmonic oscillator, so the
# path between fixed ends is eta_j(t) = (eta_a sin(w (T - t)) + eta_b sin(w t)) / sin(w T).
KC = np.array([[2.0, -0.5], [-0.5, 1.5]])


def _coupled(q, v):
    return 0.5 * (v[0] ** 2 + v[1] ** 2) - 0.5 * (KC[0, 0] * q[0] ** 2 + 2 * KC[0, 1] * q[0] * q[1]
                                                 + KC[1, 1] * q[1] ** 2)


def _coupled_path(qa, qb, T, t):
    w2, U = np.linalg.eigh(KC)
    w = np.sqrt(w2)[:, None]
    ea, eb = (U.T @ qa)[:, None], (U.T @ qb)[:, None]
    s = np.sin(w * T)
    eta = (ea * np.sin(w * (T - t)) + eb * np.sin(w * t)) / s
    deta = (-ea * w * np.cos(w * (T - t)) + eb * w * np.cos(w * t)) / s
    return U @ eta, U @ deta


def _coupled_orbit(q0, v0, t):
    w2, U = np.linalg.eigh(KC)
    w = np.sqrt(w2)[:, None]
    e0, ev0 = (U.T @ q0)[:, None], (U.T @ v0)[:, None]
    return U @ (e0 * np.cos(w * t) + ev0 / w * np.sin(w * t))


QA2, QB2, T2 = np.array([0.3, -0.2]), np.array([0.1, 0.4]), 1.5


def test_coupled_oscillators_path_closed_form_and_order():
    errs, verrs = [], []
    for n in (50, 100, 200, 400):
        r = V.stationary_path(_coupled, QA2, QB2, T2, n)
        assert r.q.shape == r.p.shape == r.qdot.shape == (2, n + 1)
        q_ex, v_ex = _coupled_path(QA2, QB2, T2, r.t)
        errs.append(np.max(np.abs(r.q - q_ex)))
        verrs.append(np.max(np.abs(r.qdot - v_ex)))
        assert r.iterations <= 2           # a quadratic action: one Newton step, then the
                                           # residual at round-off ends it (2 measured)
    assert errs[-1] < 1e-5, errs           # 1.8e-6 at n = 400
    assert verrs[-1] < 4e-5, verrs         # 3.9e-6 at n = 400
    assert np.all(np.abs(_order(errs) - 2) < 0.05), errs
    assert np.all(np.abs(_order(verrs) - 2) < 0.05), verrs
    # for a quadratic L the momenta are the velocities of the midpoint
    # Legendre transform: p = qdot exactly
    assert np.max(np.abs(r.p - r.qdot)) < 1e-12
    # uncoupled (K diagonal): each coordinate is the 1-D path of its own oscillator
    r2 = V.stationary_path(lambda q, v: 0.5 * (v[0] ** 2 + v[1] ** 2)
                           - 0.5 * (q[0] ** 2 + 4 * q[1] ** 2), QA2, QB2, T2, 200)
    r1 = V.stationary_path(lambda q, v: 0.5 * v * v - 2 * q * q, QA2[1], QB2[1], T2, 200)
    assert np.max(np.abs(r2.q[1] - r1.q)) < 1e-12
    exact0 = (QA2[0] * np.sin(T2 - r2.t) + QB2[0] * np.sin(r2.t)) / np.sin(T2)
    assert np.max(np.abs(r2.q[0] - exact0)) < 1e-5


@pytest.mark.parametrize("d, bound", [(3, 3e-4), (6, 1.2e-4)])   # 3.2e-5, 1.2e-5 measured
def test_oscillator_chains_of_more_coordinates(d, bound):
    """A random positive definite K: the band of half-width 2d - 1 in Newton's
    matrix, against the normal-mode closed form."""
    rng = np.random.default_rng(d)
    A = rng.standard_normal((d, d))
    K = A @ A.T / d + np.eye(d)

    def L(q, v):
        return 0.5 * np.sum(v * v, axis=0) - 0.5 * np.einsum("im,ij,jm->m", q, K, q)
    qa, qb, T = rng.uniform(-1, 1, d), rng.uniform(-1, 1, d), 1.0
    w2, U = np.linalg.eigh(K)
    w = np.sqrt(w2)[:, None]
    errs = []
    for n in (50, 100, 200):
        r = V.stationary_path(L, qa, qb, T, n)
        ea, eb = (U.T @ qa)[:, None], (U.T @ qb)[:, None]
        exact = U @ ((ea * np.sin(w * (T - r.t)) + eb * np.sin(w * r.t)) / np.sin(w * T))
        errs.append(np.max(np.abs(r.q - exact)))
    assert errs[-1] < bound, errs
    assert np.all(np.abs(_order(errs) - 2) < 0.05), errs


def test_coupled_oscillators_integrator_order():
    v0 = np.array([0.0, 0.5])
    errs = []
    for h in (0.02, 0.01, 0.005):
        r = V.variational_integrate(_coupled, (0, 3), QA2, v0, h)
        assert r.q.shape == (2, len(r.t))
        errs.append(np.max(np.abs(r.q - _coupled_orbit(QA2, v0, r.t))))
        # the energy function of a quadratic L is kept to round-off by the
        # midpoint rule (6e-13 measured)
        assert np.ptp(r.energy) < 5e-12
    assert errs[-1] < 1e-4, errs           # 7.1e-6 at h = 0.005
    assert np.all(np.abs(_order(errs) - 2) < 0.05), errs


# The double pendulum (unit masses and lengths), q = (theta1, theta2) from the vertical
DP = dict(m1=1.0, m2=1.0, l1=1.0, l2=1.0)


def _dp_lagrangian(q, v):
    m1, m2, l1, l2 = DP.values()
    return (0.5 * (m1 + m2) * l1 ** 2 * v[0] ** 2 + 0.5 * m2 * l2 ** 2 * v[1] ** 2
            + m2 * l1 * l2 * v[0] * v[1] * np.cos(q[0] - q[1])
            + (m1 + m2) * G * l1 * np.cos(q[0]) + m2 * G * l2 * np.cos(q[1]))


def _dp_rhs(t, y):
    """Newton's equations of the double pendulum, M(q) qdd = f (solved here)."""
    m1, m2, l1, l2 = DP.values()
    q1, q2, v1, v2 = y
    c, s = np.cos(q1 - q2), np.sin(q1 - q2)
    M = np.array([[(m1 + m2) * l1 ** 2, m2 * l1 * l2 * c], [m2 * l1 * l2 * c, m2 * l2 ** 2]])
    f = np.array([-m2 * l1 * l2 * s * v2 ** 2 - (m1 + m2) * G * l1 * np.sin(q1),
                  m2 * l1 * l2 * s * v1 ** 2 - m2 * G * l2 * np.sin(q2)])
    return np.concatenate([[v1, v2], np.linalg.solve(M, f)])


def _dp_energy(q, v):
    m1, m2, l1, l2 = DP.values()
    return (0.5 * (m1 + m2) * l1 ** 2 * v[0] ** 2 + 0.5 * m2 * l2 ** 2 * v[1] ** 2
            + m2 * l1 * l2 * v[0] * v[1] * np.cos(q[0] - q[1])
            - (m1 + m2) * G * l1 * np.cos(q[0]) - m2 * G * l2 * np.cos(q[1]))


def _dp_shoot(qa, qb, T, t_eval, v_guess):
    """The boundary-value problem by shooting: solve_ivp (DOP853) + fsolve on qdot(0)."""
    def end(v):
        return solve_ivp(_dp_rhs, (0, T), np.concatenate([qa, v]), method="DOP853",
                         rtol=1e-12, atol=1e-12).y[:2, -1] - qb
    v = fsolve(end, v_guess, xtol=1e-13)
    assert np.max(np.abs(end(v))) < 1e-10
    return solve_ivp(_dp_rhs, (0, T), np.concatenate([qa, v]), method="DOP853", rtol=1e-12,
                     atol=1e-12, t_eval=t_eval).y


def test_double_pendulum_path_against_solve_ivp_shooting():
    qa, qb, T = np.array([0.4, -0.3]), np.array([-0.2, 0.5]), 0.8
    errs, verrs = [], []
    for n in (100, 200, 400):
        r = V.stationary_path(_dp_lagrangian, qa, qb, T, n)
        ref = _dp_shoot(qa, qb, T, r.t, (qb - qa) / T)
        errs.append(np.max(np.abs(r.q - ref[:2])))
        verrs.append(np.max(np.abs(r.qdot - ref[2:])))
    assert errs[-1] < 2e-5, errs           # 2.1e-6 rad at n = 400
    assert verrs[-1] < 2e-4, verrs         # 1.9e-5 rad/s at n = 400
    assert np.all(np.abs(_order(errs) - 2) < 0.1), errs
    assert np.all(np.abs(_order(verrs) - 2) < 0.1), verrs


# ---- the compiled-Lagrangian interface (mp_gen_lagrangian), with a hand-written library ---------

C_LAGRANGIANS = r"""
#include <math.h>
#include <stddef.h>
#include <string.h>

/* K = 1 + 2d + 3d^2 = 17 values per point (d = 2)
   two coupled oscillators, params k11, k12, k22, bound: L = |qd|^2/2 - q^T K q/2;
   MP_EDOM (1) when |q_a| > bound */
int mp_gen_lagrangian(size_t m, const double *t, const double *q, const double *qd,
                      double *out, void *params)
{
    const double *k = params;
    (void)t;
    for (size_t i = 0; i < m; i++) {
        const double *x = q + 2 * i, *v = qd + 2 * i;
        double *o = out + 17 * i;
        if (fabs(x[0]) > k[3] || fabs(x[1]) > k[3]) return 1;
        memset(o, 0, 17 * sizeof(double));
        o[0] = 0.5 * (v[0] * v[0] + v[1] * v[1])
               - 0.5 * (k[0] * x[0] * x[0] + 2 * k[1] * x[0] * x[1] + k[2] * x[1] * x[1]);
        o[1] = -(k[0] * x[0] + k[1] * x[1]);
        o[2] = -(k[1] * x[0] + k[2] * x[1]);
        o[3] = v[0];
        o[4] = v[1];
        o[5] = -k[0]; o[6] = -k[1]; o[7] = -k[1]; o[8] = -k[2];   /* d2L/dq dq */
        o[13] = 1.0; o[16] = 1.0;                                /* d2L/dqd dqd */
    }
    return 0;
}

/* the double pendulum, params m1, m2, l1, l2, g */
int double_pendulum(size_t m, const double *t, const double *q, const double *qd,
                    double *out, void *params)
{
    const double *k = params;
    double a = (k[0] + k[1]) * k[2] * k[2], b = k[1] * k[3] * k[3], c0 = k[1] * k[2] * k[3];
    double g1 = (k[0] + k[1]) * k[4] * k[2], g2 = k[1] * k[4] * k[3];
    (void)t;
    for (size_t i = 0; i < m; i++) {
        const double *x = q + 2 * i, *v = qd + 2 * i;
        double *o = out + 17 * i, C = cos(x[0] - x[1]), S = sin(x[0] - x[1]);
        o[0] = 0.5 * a * v[0] * v[0] + 0.5 * b * v[1] * v[1] + c0 * v[0] * v[1] * C
               + g1 * cos(x[0]) + g2 * cos(x[1]);
        o[1] = -c0 * v[0] * v[1] * S - g1 * sin(x[0]);
        o[2] = c0 * v[0] * v[1] * S - g2 * sin(x[1]);
        o[3] = a * v[0] + c0 * v[1] * C;
        o[4] = b * v[1] + c0 * v[0] * C;
        o[5] = -c0 * v[0] * v[1] * C - g1 * cos(x[0]);
        o[6] = o[7] = c0 * v[0] * v[1] * C;
        o[8] = -c0 * v[0] * v[1] * C - g2 * cos(x[1]);
        o[9] = -c0 * v[1] * S; o[10] = -c0 * v[0] * S;          /* d2L/dq1 dqd_b */
        o[11] = c0 * v[1] * S; o[12] = c0 * v[0] * S;           /* d2L/dq2 dqd_b */
        o[13] = a; o[14] = o[15] = c0 * C; o[16] = b;
    }
    return 0;
}
"""


class _CompiledScene:
    """What a scene compiled by mp.lagrangian offers the variational tools."""

    def __init__(self, lib, name, params, d):
        import ctypes
        self._lib = lib                       # keeps the library loaded
        address = ctypes.cast(getattr(lib, name), ctypes.c_void_p).value
        self._lagrangian_c = (address, np.asarray(params, dtype=np.float64))
        self.dim = 2 * d


@pytest.fixture(scope="module")
def clib(tmp_path_factory):
    import ctypes
    import shutil
    import subprocess
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    d = tmp_path_factory.mktemp("clagrangian")
    (d / "lag.c").write_text(C_LAGRANGIANS)
    subprocess.run([cc, "-shared", "-fPIC", "-O2", "-Wall", "-Werror", "-o", str(d / "lag.so"),
                    str(d / "lag.c"), "-lm"], check=True)
    return ctypes.CDLL(str(d / "lag.so"))


def _dp_scene(clib):
    m1, m2, l1, l2 = DP.values()
    return _CompiledScene(clib, "double_pendulum", [m1, m2, l1, l2, G], 2)


def test_compiled_lagrangian_oscillators_path_and_orbit(clib):
    scene = _CompiledScene(clib, "mp_gen_lagrangian", [KC[0, 0], KC[0, 1], KC[1, 1], 10.0], 2)
    errs = []
    for n in (100, 200, 400):
        r = V.stationary_path(scene, QA2, QB2, T2, n)
        q_ex, v_ex = _coupled_path(QA2, QB2, T2, r.t)
        errs.append(np.max(np.abs(r.q - q_ex)))
    assert np.all(np.abs(_order(errs) - 2) < 0.05), errs
    # the same discrete equations as the Python path (its finite differences
    # are exact for a quadratic L up to round-off)
    py = V.stationary_path(_coupled, QA2, QB2, T2, 400)
    assert np.max(np.abs(r.q - py.q)) < 1e-13           # 1.2e-15 measured
    assert np.max(np.abs(r.qdot - py.qdot)) < 5e-13     # 4.4e-14 measured
    v0 = np.array([0.0, 0.5])
    o = V.variational_integrate(scene, (0, 3), QA2, v0, 0.005)
    assert np.max(np.abs(o.q - _coupled_orbit(QA2, v0, o.t))) < 1e-5   # 7.1e-6 measured
    assert np.ptp(o.energy) < 3e-13                                     # 3.4e-14 measured
    assert abs(o.energy[0] - _coupled(QA2, v0) - KC @ QA2 @ QA2) < 1e-14
    py = V.variational_integrate(_coupled, (0, 3), QA2, v0, 0.005)
    assert np.max(np.abs(o.q - py.q)) < 3e-12                           # 2.5e-13 measured
    # the C function reports a point outside its domain (|q| > bound): the
    # straight-line guess is outside, so the problem is refused
    out = _CompiledScene(clib, "mp_gen_lagrangian", [KC[0, 0], KC[0, 1], KC[1, 1], 0.35], 2)
    with pytest.raises(mp.errors.DomainError):
        V.stationary_path(out, QA2, np.array([0.1, 0.5]), T2, 50)
    with pytest.raises(ValueError, match="coordinate"):
        V.stationary_path(scene, 0.3, 0.1, T2, 50)


def test_compiled_double_pendulum_matches_python_and_shooting(clib):
    dp = _dp_scene(clib)
    rng = np.random.default_rng(5)
    q, v = rng.uniform(-2, 2, (2, 7)), rng.uniform(-3, 3, (2, 7))
    # the hand-written derivatives against finite differences of the Python L
    from mechpy.variational.functionals import _fd_spec, _lagrangian_fn
    fd = _fd_spec(_lagrangian_fn(_dp_lagrangian, 2, False), 2)
    spec = ("c", mp._core._variational_capsule(dp._lagrangian_c[0]), dp._lagrangian_c[1], 2)
    c = mp._core.variational_eval(spec, np.zeros(7), q.T.copy(), v.T.copy())
    f = fd[1](np.zeros(7), q.T.copy(), v.T.copy())
    assert np.max(np.abs(c[:, :5] - f[:, :5])) < 5e-10     # L and gradient: 4.2e-11 measured
    assert np.max(np.abs(c - f)) < 1e-4                    # mixed second order: 1e-5
    # the Lagrangian helpers take the compiled scene too
    assert np.max(np.abs(V.lagrangian(dp)(q, v) - _dp_lagrangian(q, v))) < 1e-13
    p_exact = np.stack([2 * v[0] + v[1] * np.cos(q[0] - q[1]), v[1] + v[0] * np.cos(q[0] - q[1])])
    assert np.max(np.abs(V.generalized_momenta(dp, q, v) - p_exact)) < 2e-11   # 1.7e-12
    qa, qb, T = np.array([0.4, -0.3]), np.array([-0.2, 0.5]), 0.8
    r = V.stationary_path(dp, qa, qb, T, 400)
    ref = _dp_shoot(qa, qb, T, r.t, (qb - qa) / T)
    assert np.max(np.abs(r.q - ref[:2])) < 2e-5            # 2.1e-6 measured
    py = V.stationary_path(_dp_lagrangian, qa, qb, T, 400)
    assert np.max(np.abs(r.q - py.q)) < 1e-12              # 6e-14 measured


def test_double_pendulum_integrator_order_and_bounded_energy(clib):
    dp = _dp_scene(clib)
    q0, v0 = np.array([1.0, 0.5]), np.array([0.0, 0.0])
    ref = solve_ivp(_dp_rhs, (0, 2), np.concatenate([q0, v0]), method="DOP853", rtol=1e-13,
                    atol=1e-13).y[:, -1]
    errs = [np.max(np.abs(V.variational_integrate(dp, (0, 2), q0, v0, h).q[:, -1] - ref[:2]))
            for h in (0.004, 0.002, 0.001)]
    assert errs[-1] < 5e-5, errs                       # 6.3e-6 rad at h = 1e-3
    assert np.all(np.abs(_order(errs) - 2) < 0.1), errs
    # a long run (10^5 steps, 10 J above the lowest energy, chaotic): the energy
    # error oscillates at O(h^2) and does not grow (RK4 at the same step drifts:
    # 1.5e-5 J in the first tenth, 1.5e-4 J in the last)
    r = V.variational_integrate(dp, (0, 1000), q0, v0, 0.01)
    E = _dp_energy(r.q, r.qdot)
    assert np.max(np.abs(r.energy - E)) < 5e-15 * np.max(np.abs(E))   # h = v.p - L is E: 1e-14 J
    dE = np.abs(E - E[0])
    k = len(E) // 10
    assert dE.max() < 4e-4 * abs(E[0])             # 4.0e-5 relative measured
    assert dE[-k:].max() < 1.5 * dE[:k].max()      # 7.742e-4 J vs 7.737e-4 J


def _top_lagrangian(I1, I3, Mgl):
    """The heavy top's L(q, qdot), q = (phi, theta, psi) of shape (3, ...)
    (Goldstein eq. 5.61), in NumPy."""
    def L(q, qdot, t=0.0):
        th = np.asarray(q, dtype=float)[1]
        phd, thd, psd = np.asarray(qdot, dtype=float)[:3]
        return (0.5 * I1 * (thd ** 2 + (phd * np.sin(th)) ** 2)
                + 0.5 * I3 * (psd + phd * np.cos(th)) ** 2 - Mgl * np.cos(th))
    return L


def test_heavy_top_integrator_conserves_cyclic_momenta():
    """phi and psi are cyclic: the variational integrator keeps p_phi and p_psi
    exactly (discrete Noether), up to round-off, and follows mp.solve."""
    top = mp.scenes.HeavyTop(I1=0.5, I3=0.2, mass=1.0, g=9.81, l=0.3)
    y0 = np.array([0.0, 0.6, 0.0, 1.0, 0.0, 20.0])
    r = V.variational_integrate(top, (0, 20), y0[:3], y0[3:], 1e-3)
    assert r.q.shape == (3, 20001)
    y = np.concatenate([r.q, r.qdot])
    assert np.ptp(r.p[0]) < 2e-9 * abs(r.p[0, 0])      # 1.4e-10 relative measured
    assert np.ptp(r.p[2]) < 2e-9 * abs(r.p[2, 0])      # 1.5e-10
    np.testing.assert_allclose(r.p[0], top.p_phi(y), rtol=1e-14)   # 4e-16 measured
    np.testing.assert_allclose(r.p[2], top.p_psi(y), rtol=1e-14)
    assert np.ptp(r.energy) < 3e-9 * abs(r.energy[0])  # O(h^2): 3.2e-10 relative measured
    s = mp.solve(top, (0, 20), y0, rtol=1e-12, atol=1e-12, t_eval=r.t[::1000])
    assert np.max(np.abs(r.q[:, ::1000] - s.y[:3])) < 2e-4   # 2.1e-5 rad measured
    # the row's Lagrangian and its derivatives against the closed form and its
    # finite differences
    from mechpy.variational.functionals import _fd_spec, _lagrangian_fn
    fd = _fd_spec(_lagrangian_fn(_top_lagrangian(0.5, 0.2, 9.81 * 0.3), 3, False), 3)
    Q, Vq = y[:3, ::4000].T.copy(), y[3:, ::4000].T.copy()
    c = mp._core.variational_eval(("scene", "HeavyTop", [0.5, 0.2, 1.0, 9.81, 0.3]),
                                  r.t[::4000], Q, Vq)
    np.testing.assert_allclose(V.lagrangian(top)(Q.T, Vq.T), c[:, 0], rtol=1e-15)
    f = fd[1](r.t[::4000], Q, Vq)
    assert np.max(np.abs(c[:, :7] - f[:, :7])) < 2e-12 * np.max(np.abs(c[:, :7]))  # 1.3e-13
    assert np.max(np.abs(c - f)) < 2e-7 * np.max(np.abs(c))    # mixed, 2nd order: 1.6e-8


# ---- regressions ----------------------------------------------------------------------------

def test_step_budget_refused_before_allocating():
    with pytest.raises(ValueError, match="max_steps"):    # was a 15 GiB allocation
        V.variational_integrate(mp.scenes.Pendulum(), (0, 10), 1.0, 0.0, 1e-9)
    with pytest.raises(ValueError, match="max_steps"):
        V.variational_integrate(mp.scenes.Pendulum(), (0, 10), 1.0, 0.0, 0.01, max_steps=999)
    r = V.variational_integrate(mp.scenes.Pendulum(), (0, 10), 1.0, 0.0, 0.01, max_steps=1000)
    assert len(r.t) == 1001


@pytest.mark.parametrize("L, q0, v0", [
    (lambda q, v: q * v - 0.5 * q * q, 0.1, 0.2),                        # linear in qdot
    (lambda q, v: 0.5 * (v[0] + v[1]) ** 2 - 0.5 * (q[0] ** 2 + q[1] ** 2),
     [0.1, 0.0], [0.2, 0.0]),                                           # rank-one mass matrix
])
def test_lagrangian_singular_in_qdot_raises(L, q0, v0):
    # the velocities and energies were NaN
    with pytest.raises(mp.errors.SingularityError, match="singular"):
        V.variational_integrate(L, (0, 1), q0, v0, 0.1)
    with pytest.raises(mp.errors.SingularityError):
        V.stationary_path(L, q0, v0, 1.0, 20)


def test_lagrangian_of_a_non_scene_is_a_type_error():
    with pytest.raises(TypeError, match="scene"):          # was AttributeError
        V.lagrangian(3.0)
    with pytest.raises(TypeError, match="Lagrangian"):
        V.lagrangian(mp.scenes.VanDerPol())


def test_brachistochrone_tiny_x_end_is_refused():
    with pytest.raises(ValueError, match="too small"):     # was inf / NaN
        V.brachistochrone(5e-324, 1.0)
    r = V.brachistochrone(1e-150, 1.0, n=20)               # still representable
    assert np.isfinite(r.radius) and np.all(np.isfinite(r.y_exact))
    assert r.time_exact == pytest.approx(np.sqrt(2 / G), rel=1e-12)   # free fall


def test_one_coordinate_as_a_vector_and_bad_shapes():
    def L(q, v):
        return 0.5 * v[0] ** 2 - 0.5 * q[0] ** 2
    r = V.stationary_path(L, [0.3], [0.7], 2.0, 100)
    s = V.stationary_path(lambda q, v: 0.5 * v * v - 0.5 * q * q, 0.3, 0.7, 2.0, 100)
    assert r.q.shape == (1, 101) and s.q.shape == (101,)
    assert np.max(np.abs(r.q[0] - s.q)) < 1e-12
    with pytest.raises(ValueError, match="coordinate"):
        V.stationary_path(mp.scenes.HeavyTop(1.0, 1.0, 1.0), [0, 1, 0], [0, 1], 1.0, 20)
    with pytest.raises(ValueError, match="shape"):
        V.stationary_path(_coupled, QA2, QB2, 1.0, 20, guess=np.zeros(21))
    with pytest.raises(ValueError):
        V.variational_integrate(_coupled, (0, 1), QA2, [[0.0, 1.0]], 0.1)
    with pytest.raises(ValueError, match="one value per sample"):   # L not summed over q
        V.stationary_path(lambda q, v: 0.5 * v ** 2, QA2, QB2, 1.0, 20)


def test_time_dependent_python_lagrangian_matches_the_scene():
    """A callable taking a third argument receives the times: the damped, driven
    Duffing oscillator's Caldirola-Kanai Lagrangian in Python gives the C
    built-in's path and orbit."""
    al, be, de, ga, om = 1.0, 0.5, 0.3, 0.4, 1.2
    duff = mp.scenes.Duffing(alpha=al, beta=be, delta=de, gamma=ga, omega=om)

    def L(q, v, t):
        return np.exp(de * t) * (0.5 * v * v - 0.5 * al * q * q - 0.25 * be * q ** 4
                                 + ga * np.cos(om * t) * q)
    a = V.stationary_path(L, 0.2, -0.4, 2.0, 200, t0=0.5)
    b = V.stationary_path(duff, 0.2, -0.4, 2.0, 200, t0=0.5)
    assert np.max(np.abs(a.q - b.q)) < 5e-14          # 5.6e-15 measured
    a = V.variational_integrate(L, (0, 5), 0.2, 0.1, 0.01)
    b = V.variational_integrate(duff, (0, 5), 0.2, 0.1, 0.01)
    assert np.max(np.abs(a.q - b.q)) < 5e-13          # 6.7e-14 measured
    # and the orbit is the scene's equation of motion (mp.solve), to O(h^2)
    s = mp.solve(duff, (0, 5), [0.2, 0.1], rtol=1e-12, atol=1e-12, t_eval=b.t)
    assert np.max(np.abs(b.q - s.y[0])) < 1e-4         # 1.1e-5 measured


def test_stationary_paths_of_the_oscillator_start_at_zero():
    """T = 2 < pi: one path of stationary action for L = (v^2 - q^2)/2, the
    closed form (q_a sin(T - t) + q_b sin t) / sin T on t in [0, T] (t0 = 0 by
    default)."""
    L = lambda q, v: 0.5 * v * v - 0.5 * q * q
    qa, qb, T = 0.3, -0.5, 2.0
    paths = V.stationary_paths(L, qa, qb, T, 200)
    assert len(paths) == 1
    p = paths[0]
    assert p.t[0] == 0.0 and p.t[-1] == T
    exact = (qa * np.sin(T - p.t) + qb * np.sin(p.t)) / np.sin(T)
    assert np.abs(p.q - exact).max() < 2e-5                       # measured 2.6e-6 (n = 200)


def test_brachistochrone_grid_and_cycloid_samples():
    """n intervals give n + 1 points from (0, 0) to the end; the plotted
    cycloid x = a (theta - sin theta) against 40-digit arithmetic (theta from
    y = 2 a sin^2(theta / 2)), small theta included, where t - sin t cancels."""
    mpmath = pytest.importorskip("mpmath")   # a dependency of sympy (runtime)
    b = V.brachistochrone(1.0, 0.65, n=100)
    assert b.x.shape == b.y.shape == b.y_exact.shape == (101,)
    assert b.x[0] == 0.0 and b.x[-1] == 1.0
    a = b.radius
    theta = 2 * np.arcsin(np.sqrt(b.y_cycloid / (2 * a)))
    with mpmath.workdps(40):
        ref = np.array([float(a * (mpmath.mpf(t) - mpmath.sin(mpmath.mpf(t))))
                        for t in theta.tolist()])
    nz = theta > 0
    assert np.any(nz & (theta < 0.1))
    rel = np.abs(b.x_cycloid[nz] / ref[nz] - 1)
    assert rel.max() < 2e-13                                       # measured 2.2e-14


def test_variational_integrate_from_a_later_start():
    """t_span (1, 3) at h = 0.01: 200 steps from t = 1, the oscillator's
    q = q0 cos(t - 1) + v0 sin(t - 1) to second order."""
    L = lambda q, v: 0.5 * v * v - 0.5 * q * q
    r = V.variational_integrate(L, (1.0, 3.0), 0.3, 0.2, 0.01)
    assert len(r.t) == 201 and r.t[0] == 1.0
    assert r.t[-1] == pytest.approx(3.0, abs=1e-12)
    exact = 0.3 * np.cos(r.t - 1.0) + 0.2 * np.sin(r.t - 1.0)
    assert np.abs(r.q - exact).max() < 6e-5                        # measured 5.9e-6


def test_minimize_functional_refuses_an_empty_interval():
    with pytest.raises(ValueError, match="x_span"):
        V.minimize_functional(lambda x, y, yp: yp * yp, (1.0, 1.0), (0.0, 1.0))


@pytest.mark.parametrize("qa, qb", [(0.3, 5.0), (1e3, -2e3)])
def test_free_particle_path_is_the_straight_line_at_once(qa, qb):
    """L = v^2 / 2: the straight line (the first guess) is the path; its
    residual is at round-off on the first assembly, which ends the iteration
    there (no Newton step is needed)."""
    r = V.stationary_path(lambda q, v: 0.5 * v * v, qa, qb, 2.0, 200)
    assert r.iterations == 1
    line = qa + (qb - qa) * r.t / 2.0
    assert np.abs(r.q - line).max() < 7e-14 * max(abs(qa), abs(qb))   # measured 6.8e-15 rel.


# ---- the second variation: a minimum, never a saddle or a maximum ----------------------

@pytest.mark.parametrize("kL, ends, err", [
    (0.5 * np.pi, (0.0, 1.0), 1e-4),     # measured 1.3e-5
    (0.9 * np.pi, (0.0, 1.0), 1e-2),     # measured 1.4e-3 (of 8.7)
    (0.99 * np.pi, (0.0, 1.0), 1.0),     # measured 0.20 (of 99: 1/(pi - kL) amplifies h^2)
    (0.99 * np.pi, (0.0, 0.0), 0.0),
])
def test_minimum_before_the_conjugate_point(kL, ends, err):
    """Jacobi: F = y'^2 - k^2 y^2 on [0, 1] has a minimum iff k < pi (the
    conjugate point of 0 is pi / k); it is y = y_b sin(kx) / sin(k) with
    J = y_b^2 k cot(k)."""
    k = kL
    r = V.minimize_functional(lambda x, y, yp: yp * yp - k * k * y * y, (0.0, 1.0), ends, 200)
    yb = ends[1]
    assert abs(r.value - yb * yb * k / np.tan(k)) <= err
    assert np.max(np.abs(r.y - yb * np.sin(k * r.x) / np.sin(k))) <= max(err, 1e-12)


@pytest.mark.parametrize("kL, negative", [(1.01 * np.pi, 1), (1.1 * np.pi, 1),
                                          (np.sqrt(10) * np.pi, 3), (2.5 * np.pi, 2)])
def test_no_minimum_past_the_conjugate_point_is_refused(kL, negative):
    """Past the conjugate point (k L > pi) y = 0 is still stationary but a
    saddle: the second variation has floor(kL / pi) negative directions (the
    modes sin(j pi x / L), j < kL / pi).  It came back as the minimum, 0.0,
    after one iteration (issue #28: y'^2 - 10 y^2 on [0, pi])."""
    L = np.pi if kL == np.sqrt(10) * np.pi else 1.0
    k = kL / L
    with pytest.raises(mp.NotPositiveDefiniteError,
                       match=rf" {negative} negative eigenvalue.*not a minimum"):
        V.minimize_functional(lambda x, y, yp: yp * yp - k * k * y * y, (0.0, L), (0.0, 0.0), 200)
    # the stationary path itself is still there on request
    r = V.minimize_functional(lambda x, y, yp: yp * yp - k * k * y * y, (0.0, L), (0.0, 0.0), 200,
                              stationary=True)
    assert np.all(r.y == 0.0)


def test_a_maximum_is_not_reported_as_a_minimum():
    """F = -y'^2: the straight line is the maximum, J = -1 (issue #28: it came
    back as the minimum); every direction of the second variation is negative."""
    with pytest.raises(mp.NotPositiveDefiniteError, match="199 negative eigenvalue.*not a minimum"):
        V.minimize_functional(lambda x, y, yp: -yp * yp, (0.0, 1.0), (0.0, 1.0), 200)
    # the minimum of its negative is the same line
    r = V.minimize_functional(lambda x, y, yp: yp * yp, (0.0, 1.0), (0.0, 1.0), 200)
    assert abs(r.value - 1.0) < 1e-12 and np.max(np.abs(r.y - r.x)) < 1e-12


def test_a_newton_step_without_decrease_is_not_taken():
    """The line search takes a step only where J decreases (Armijo's sufficient
    decrease).  Arc length on [0, 4] (n = 4, h = 1) from the zigzag guess
    y = (0, c, 0, -c, 0): the symmetries y -> -y and x -> 4 - x keep Newton on
    this family, where J = 4 sqrt(1 + c^2) and Newton's step is c -> -c^3.  From
    c = 1 it lands on c = -1 with the same J: that step is refused, the halved one
    lands on c = 0, the straight line, and the next iteration ends there.  Taking
    the step without decrease swings between c = 1 and -1 (25 iterations)."""
    F = lambda x, y, yp: np.sqrt(1 + yp * yp)
    r = V.minimize_functional(F, (0.0, 4.0), (0.0, 0.0), 4, guess=[0.0, 1.0, 0.0, -1.0, 0.0],
                              max_iter=6)
    assert r.iterations <= 3   # the refused step, the exact halved one, the check there
    assert np.abs(r.y).max() < 1e-12 and abs(r.value - 4.0) < 1e-12


# ---- budgets and Ctrl-C ---------------------------------------------------------------------

def test_absurd_n_is_refused_before_allocating():
    """n = 10^8 intervals (16 GB of workspace) ran for minutes deaf to Ctrl-C
    (issue #28); beyond the budget it is a ValueError naming n."""
    for call in (lambda: V.brachistochrone(2.0, 1.0, n=10 ** 8),
                 lambda: V.minimize_functional(lambda x, y, yp: yp * yp, (0, 1), (0, 1), 10 ** 8),
                 lambda: V.catenary(-1.0, 1.0, 3.0, n=10 ** 8)):
        with pytest.raises(ValueError, match=r"n = 100000000 intervals is beyond the budget"):
            call()


def test_cycloid_inversion_converges_pointwise():
    """The exact cycloid's theta(x) at 10^5 nodes, checked against
    x = a (theta - sin theta): each point now stops when it has converged
    (the whole array ran all 200 iterations because a few points sat at the
    round-off floor: 22 s of brachistochrone(2, 1, n=10**6), now 1 s)."""
    from mechpy.variational.classic import _cycloid_theta_of_x
    a, th = 1.0, 4.0
    x = a * (th - np.sin(th)) * np.linspace(0.0, 1.0, 10 ** 5 + 1) ** 3
    theta = _cycloid_theta_of_x(x, a, th)
    assert np.max(np.abs(a * (theta - np.sin(theta)) - x)) < 1e-14   # measured 8.9e-16


def test_ctrl_c_is_prompt_in_a_long_minimisation():
    """KeyboardInterrupt within 1 s of SIGINT during a solve of 2 10^6 intervals
    (the C loop asks between blocks of the assembly, line-search trials and
    Hessian shifts; before, once per Newton iteration)."""
    from sigint import interrupt_delay
    dt = interrupt_delay("", "mp.variational.brachistochrone(2.0, 1.0, n=2 * 10 ** 6)", delay=1.0)
    assert dt < 1.0, f"KeyboardInterrupt {dt} CPU s after SIGINT"         # measured 0.02-0.3 s


class _Addressed:
    """An object offering the variational tools a compiled Lagrangian's address."""

    def __init__(self, address, dim):
        self._lagrangian_c = (address, np.array([1.0]))
        self.dim = dim


def test_compiled_lagrangian_address_and_dim_are_checked():
    """A null or negative function address is refused before anything calls it (a
    NULL call would crash the interpreter), as is a state dimension that is not an
    even int >= 2."""
    for address in (0, -8, True):
        with pytest.raises(TypeError, match="address"):
            V.stationary_path(_Addressed(address, 2), 0.0, 1.0, 1.0, 50)
    for dim in (0, 3, 2.0):
        with pytest.raises(TypeError, match="dim"):
            V.stationary_path(_Addressed(4096, dim), 0.0, 1.0, 1.0, 50)


def test_one_coordinate_compiled_lagrangian_stationary_path(tmp_path, monkeypatch):
    """A compiled Lagrangian of one coordinate (state dimension 2), the oscillator
    L = q'^2/2 - w^2 q^2/2: its stationary path between q(0) = qa and q(T) = qb is
    (qa sin w(T - t) + qb sin w t) / sin w T, to the midpoint rule's O(h^2)."""
    import sympy as sp
    from mechpy.symbolic import build
    if not build.have_compiler():
        pytest.skip("no C compiler")
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path))
    q, = mp.coordinates("q")
    w = sp.Symbol("w", positive=True)
    scene = mp.lagrangian(q.diff()**2 / 2 - w**2 * q**2 / 2, [q], {"w": 1.3})
    assert scene.dim == 2
    qa, qb, T = 0.4, -0.3, 1.7
    errs = []
    for n in (100, 200):
        r = V.stationary_path(scene, qa, qb, T, n)
        exact = (qa * np.sin(1.3 * (T - r.t)) + qb * np.sin(1.3 * r.t)) / np.sin(1.3 * T)
        errs.append(np.abs(r.q - exact).max())
    assert errs[1] < 1e-5 and 3.8 < errs[0] / errs[1] < 4.2      # 2.8e-6 measured


def test_minimize_functional_guess_ends_are_replaced():
    """A guess whose ends are not the end values: its ends are replaced by them (as the
    docstring says), so the extremal of the arc length is the straight line between
    the given ends, from any guess."""
    x = np.linspace(0.0, 2.0, 41)
    for guess in (np.full(41, 5.0), np.sin(3 * x) - 2.0):
        ext = V.minimize_functional(lambda x, y, yp: np.sqrt(1 + yp**2), (0.0, 2.0),
                                    (1.0, -0.5), n=40, guess=guess)
        assert ext.y[0] == 1.0 and ext.y[-1] == -0.5
        assert np.abs(ext.y - (1.0 - 0.75 * ext.x)).max() < 3e-13     # 3.7e-14 measured
        assert abs(ext.value - np.hypot(2.0, 1.5)) < 5e-15              # 4.4e-16


def test_minimize_functional_integrand_finite_at_the_edge_of_its_domain():
    """F = sqrt(y) y'^2 from (0, 0) to (1, 1): finite at the end y = 0, where its domain
    y >= 0 begins, so not refused as singular there (the check probes F along the
    chord, inside the domain).  Its extremal (first integral sqrt(y) y'^2 = C) is
    y = x^(4/5), with J = 0.64; the midpoint rule converges to them at first order (the
    path's derivative is singular at x = 0).  The same in u = y - x: sqrt(y - x) (y' - 1)^2
    from (0, 0) to (1, 2), whose domain y >= x leaves the line y = 0 at once, extremal
    y = x + x^(4/5)."""
    for F, yb, shift in ((lambda x, y, yp: np.sqrt(y) * yp**2, 1.0, 0.0),
                         (lambda x, y, yp: np.sqrt(y - x) * (yp - 1)**2, 2.0, 1.0)):
        errs = []
        for n in (100, 200):
            ext = V.minimize_functional(F, (0.0, 1.0), (0.0, yb), n=n)
            exact = shift * ext.x + ext.x ** 0.8
            assert np.abs(ext.y - exact).max() < 4e-3           # 1.8e-3, 1.0e-3 measured
            errs.append(ext.value - 0.64)
        assert 0 < errs[1] < 1e-3 and 1.8 < errs[0] / errs[1] < 2.2   # 6.7e-4, 3.4e-4


def test_variational_integrate_with_a_pivoting_mass_matrix():
    """L = q'^T M q' / 2 - q^T K q / 2 with M = [[1, 1.5], [1.5, 3]] (positive definite,
    its first column's largest entry off the diagonal: the velocity solve pivots) against
    the exact motion from SciPy's eigh(K, M), at second order."""
    import scipy.linalg as sl
    Mm = np.array([[1.0, 1.5], [1.5, 3.0]])
    Kk = np.array([[2.0, -0.5], [-0.5, 1.0]])

    def L(q, v):
        return (0.5 * np.einsum("i...,ij,j...->...", v, Mm, v)
                - 0.5 * np.einsum("i...,ij,j...->...", q, Kk, q))
    q0, v0 = np.array([0.3, -0.2]), np.array([0.1, 0.4])
    w2, U = sl.eigh(Kk, Mm)                    # U^T M U = I
    w = np.sqrt(w2)
    a0, b0 = U.T @ Mm @ q0, U.T @ Mm @ v0
    errs = []
    for h in (0.02, 0.01):
        o = V.variational_integrate(L, (0, 3), q0, v0, h)
        eta = (a0[:, None] * np.cos(w[:, None] * o.t)
               + (b0 / w)[:, None] * np.sin(w[:, None] * o.t))
        errs.append(np.abs(o.q - U @ eta).max())
    assert errs[1] < 5e-4 and 3.8 < errs[0] / errs[1] < 4.2      # 2.3e-4, ratio 4.0


def test_variational_integrate_time_dependent_beyond_one_chunk():
    """The Caldirola-Kanai Lagrangian e^(gamma t) (q'^2 - w0^2 q^2) / 2 (Duffing's row
    with beta = 0): the damped oscillator's exact motion, positions and the velocities
    recovered from the momenta at each node's own time, over 5001 nodes (more than one
    block of the C core's 4096 points), at second order."""
    g, w0 = 0.2, 1.0
    scene = mp.scenes.Duffing(w0**2, 0.0, delta=g)
    wd = np.sqrt(w0**2 - g**2 / 4)
    errs = []
    for h in (0.004, 0.002):
        o = V.variational_integrate(scene, (0, 10), 1.0, 0.0, h)
        e = np.exp(-g / 2 * o.t)
        A, B = 1.0, g / 2 / wd
        q = e * (A * np.cos(wd * o.t) + B * np.sin(wd * o.t))
        v = -g / 2 * q + e * wd * (B * np.cos(wd * o.t) - A * np.sin(wd * o.t))
        errs.append(max(np.abs(o.q - q).max(), np.abs(o.qdot - v).max()))
    assert len(o.t) == 5001
    assert errs[1] < 3e-6 and 3.8 < errs[0] / errs[1] < 4.2      # 1.2e-6, ratio 4.0
