"""mp.mechanics: SymPy's KanesMethod, LagrangesMethod and System, compiled.

References nobody here wrote: the built-in pendulum scene, SymPy's own
equations (KanesMethod.rhs and mass_matrix_full / forcing_full, lambdified,
and its Linearizer), the published eigenvalues and self-stability speeds of
the benchmark bicycle (Meijaard, Papadopoulos, Ruina, Schwab 2007, Proc. R.
Soc. A 463, Table 2), SciPy's solve_ivp at tight tolerance, and the
conservation of energy.
"""
from __future__ import annotations

import os
import pickle

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from sympy.physics.mechanics import (KanesMethod, LagrangesMethod, Lagrangian, Particle,
                                     Point, ReferenceFrame, RigidBody, dynamicsymbols)

import mechpy as mp
from mechpy.symbolic.derive import BAUMGARTE
from mechpy.symbolic.models import n_link_cart, rolling_disc, whipple_bicycle, whipple_state


@pytest.fixture(scope="module", autouse=True)
def cache(tmp_path_factory):
    """A fresh cache folder for this module (the first build compiles)."""
    d = str(tmp_path_factory.mktemp("mechpy_cache"))
    old = os.environ.get("MECHPY_CACHE_DIR")
    os.environ["MECHPY_CACHE_DIR"] = d
    yield d
    if old is None:
        os.environ.pop("MECHPY_CACHE_DIR", None)
    else:
        os.environ["MECHPY_CACHE_DIR"] = old


G, L = 9.81, 1.3


def _pendulum_kane(formed=True):
    th, w = dynamicsymbols("theta omega")
    g, l, m = sp.symbols("g l m", positive=True)
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    A.set_ang_vel(N, w * N.z)
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    kane = KanesMethod(N, [th], [w], kd_eqs=[th.diff() - w])
    if formed:
        kane.kanes_equations([Particle("bob", P, m)], [(P, m * g * N.x)])
    return kane


def _pendulum_lagrange():
    th = dynamicsymbols("theta")
    g, l, m = sp.symbols("g l m", positive=True)
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    bob = Particle("bob", P, m)
    bob.potential_energy = -m * g * l * sp.cos(th)
    lm = LagrangesMethod(Lagrangian(N, bob), [th])
    lm.form_lagranges_equations()
    return lm


def _pendulum_system():
    from sympy.physics.mechanics import PinJoint, System
    g, l, m = sp.symbols("g l m", positive=True)
    th, w = dynamicsymbols("theta omega")
    ceiling = RigidBody("ceiling")
    bob = Particle("bob", mass=m)
    sys_ = System.from_newtonian(ceiling)
    N = ceiling.frame
    bob_frame = ReferenceFrame("bobframe")
    pin = PinJoint("pin", ceiling, bob, coordinates=th, speeds=w,
                   child_point=-l * bob_frame.x, child_interframe=bob_frame,
                   joint_axis=N.z)
    sys_.add_joints(pin)
    sys_.add_loads((bob.masscenter, m * g * N.x))
    sys_.form_eoms()
    return sys_


PARAMS = {"g": G, "l": L, "m": 2.0}


@pytest.mark.parametrize("make", [_pendulum_kane, _pendulum_lagrange, _pendulum_system],
                         ids=["kane", "lagrange", "system"])
def test_pendulum_equals_the_scene(make):
    pend = mp.mechanics(make(), PARAMS)
    ref_scene = mp.scenes.Pendulum(g=G, length=L)
    y0 = [1.2, -0.3]
    s = mp.solve(pend, (0, 5), y0, rtol=1e-11, atol=1e-12, t_eval=np.linspace(0, 5, 11))
    ref = mp.solve(ref_scene, (0, 5), y0, rtol=1e-11, atol=1e-12, t_eval=np.linspace(0, 5, 11))
    assert np.abs(s.y - ref.y).max() < 1e-12     # measured 1.0e-14
    Y = np.random.default_rng(0).uniform(-2, 2, (2, 7))
    assert np.allclose(pend.rhs(0.0, Y), ref_scene.rhs(0.0, Y), rtol=1e-13, atol=1e-13)
    assert np.allclose(pend.jacobian(0.0, Y), ref_scene.jacobian(0.0, Y), rtol=1e-12,
                       atol=1e-12)
    # energy: m (E of the scene per unit mass) up to a constant
    e = pend.energy(s.y) - PARAMS["m"] * ref_scene.energy(s.y)
    assert np.ptp(e) < 1e-13                     # measured 7e-15
    A, B = pend.linearize([0.0, 0.0])
    assert np.allclose(A, [[0, 1], [-G / L, 0]], rtol=1e-14, atol=1e-14)
    assert B.shape == (2, 0)


def test_pickle_replace_and_lanes():
    pend = mp.mechanics(_pendulum_kane(), PARAMS)
    back = pickle.loads(pickle.dumps(pend))
    y = np.array([0.4, 0.1])
    assert np.array_equal(back.rhs(0.0, y), pend.rhs(0.0, y))
    short = pend.replace(l=0.5)
    # a scene is a value: its copies are equal (and hash alike), another length or
    # another model is not
    assert back == pend and hash(back) == hash(pend) and pend.replace(l=L) == pend
    assert short != pend and short.replace(l=L) == pend
    assert mp.mechanics(_pendulum_lagrange(), PARAMS) != pend
    assert np.isclose(short.rhs(0.0, [np.pi / 2, 0.0])[1], -G / 0.5)
    lengths = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5])
    ens = mp.solve_many(pend, (0, 2), np.tile([0.3, 0.0], (9, 1)), params={"l": lengths},
                        rtol=1e-10, atol=1e-12)
    for i, li in enumerate(lengths):
        one = mp.solve(mp.scenes.Pendulum(g=G, length=li), (0, 2), [0.3, 0.0], rtol=1e-10,
                       atol=1e-12)
        assert np.abs(ens.y[i][:, -1] - one.y[:, -1]).max() < 1e-8


# ---------------------------------------------------------------- rolling disc

@pytest.fixture(scope="module")
def disc():
    kane, params = rolling_disc()
    return kane, params, mp.mechanics(kane, params)


def test_disc_rhs_equals_sympys(disc):
    kane, params, scene = disc
    rhs = kane.rhs()                     # SymPy's own first-order form
    byname = {s.name: s for s in rhs.free_symbols}
    x = list(kane.q) + list(kane.u)
    f = sp.lambdify([x, [byname[k] for k in params]], rhs, "numpy")
    rng = np.random.default_rng(3)
    for _ in range(10):
        y = scene.project(rng.uniform(-1.5, 1.5, 10))   # on the rolling constraints
        assert np.abs(scene.constraint_residual(y)).max() < 1e-14
        ref = np.asarray(f(y, list(params.values())), dtype=float).ravel()
        assert np.allclose(scene.rhs(0.0, y), ref, rtol=1e-13, atol=1e-13)  # measured 2e-15


def test_disc_conserves_energy_and_holds_constraints(disc):
    _, _, scene = disc
    y0 = scene.project(np.array([0.0, 0.2, 0.0, 0.0, 0.0, 0.3, 0.1, 5.0, 0.0, 0.0]))
    s = mp.solve(scene, (0, 10), y0)
    E = scene.energy(s.y)
    assert np.abs(E - E[0]).max() < 3e-8              # measured 3.3e-9
    assert np.abs(scene.constraint_residual(s.y)).max() < 1e-7   # measured 1.5e-8
    # over 100 s the stabilised residual stays bounded; without the
    # stabilisation the rolling constraints drift away linearly
    s = mp.solve(scene, (0, 100), y0)
    end = np.abs(scene.constraint_residual(s.y[:, -1])).max()
    assert end < 1e-8                                 # measured 7.8e-10
    loose = mp.mechanics(*rolling_disc(), baumgarte=(0.0, 0.0))
    s2 = mp.solve(loose, (0, 100), y0)
    assert np.abs(loose.constraint_residual(s2.y[:, -1])).max() > 3e-8   # measured 6.1e-8


def test_disc_linearize_equals_sympys_linearizer(disc):
    kane, params, scene = disc
    u = kane.u
    y0 = scene.project(np.array([0.3, 0.0, 0.2, 0.1, -0.2, 0.0, 0.0, 4.0, 0.0, 0.0]))
    q = kane.q
    op = {**{qi: v for qi, v in zip(q, y0[:5])}, **{ui: v for ui, v in zip(u, y0[5:])},
          **{ui.diff(): 0 for ui in u}}
    byname = {s.name: s for s in kane.forcing_full.free_symbols}
    A_sym, B_sym, _ = kane.linearize(A_and_B=True, op_point=op)
    A_ref = np.array(A_sym.xreplace({byname[k]: v for k, v in params.items() if k in byname}),
                     dtype=float)
    A, B = scene.linearize(y0)
    assert A.shape == A_ref.shape == (8, 8)
    assert np.allclose(A, A_ref, rtol=1e-11, atol=1e-11)


def test_disc_rolling_upright_closed_forms(disc):
    """The upright rolling disc against its closed forms (the references above are
    SymPy's equations of the same model, blind to a wrong inertia or coordinate):
    at yaw psi and spin w the contact point moves at r w (cos psi, sin psi) in the
    plane, and the lean obeys (I1 + m r^2) phi'' = (m g r - I3 (I3 + m r^2) w^2 / I1)
    phi (the yaw rate following I1 psi'' = I3 w phi'), I1 = m r^2 / 4 about a
    diameter, I3 = m r^2 / 2 about the axle: stable above w^2 = g / (3 r)."""
    _, params, scene = disc
    m, r, g = params["m"], params["r"], params["g"]
    for psi in (0.0, 0.7, np.pi / 2, 2.5, -1.2):
        w = 3.0
        y = scene.project(np.array([psi, 0.0, 0.4, 0.3, -0.2, 0.0, 0.0, w, 0.0, 0.0]))
        ref = r * w * np.array([np.cos(psi), np.sin(psi)])
        assert np.abs(y[8:] - ref).max() < 5e-15             # the dependent speeds
        assert np.abs(scene.rhs(0.0, y)[3:5] - ref).max() < 5e-15   # q4', q5' (7e-16)
    I1, I3 = m * r**2 / 4, m * r**2 / 2
    for w in (1.5, np.sqrt(g / (3 * r)) * 1.3, 8.0):
        y0 = scene.project(np.array([0.4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, w, 0.0, 0.0]))
        A, _ = scene.linearize(y0)
        lam2 = (m * g * r - I3 * (I3 + m * r**2) * w**2 / I1) / (I1 + m * r**2)
        ev = np.linalg.eigvals(A)
        big = ev[np.abs(ev) > 1e-6]
        ref = np.sqrt(complex(lam2)) * np.array([1, -1])
        assert len(big) == 2
        err = np.abs(np.sort_complex(big) - np.sort_complex(ref)).max()
        assert err < 5e-15 * np.sqrt(abs(lam2))                  # measured 6e-16


# ---------------------------------------------------------------- the bicycle

@pytest.fixture(scope="module")
def bike():
    return mp.mechanics(*whipple_bicycle())


#: Meijaard et al. (2007), Table 2: eigenvalues of the lean and steer motion.
TABLE2 = {0.0: [-5.53094371765393, -3.13164324790656, 3.13164324790656, 5.53094371765393],
          4.0: [-12.15861426576447, -1.42944427361326, 0.41325331521125 - 3.07910818603206j,
                0.41325331521125 + 3.07910818603206j],
          5.0: [-14.07838969279822, -0.32286642900409, -0.77534188219585 - 4.46486771378823j,
                -0.77534188219585 + 4.46486771378823j],
          10.0: [-24.62459635017404, 0.16105338653172, -3.72016840437287 - 10.90681139476287j,
                 -3.72016840437287 + 10.90681139476287j]}
#: the same paper, Table 1: the wheels' radii, the masses and moments of inertia (kg m^2)
#: of the rear wheel R, rear frame B, front frame H and front wheel F, and g
TABLE1 = dict(rR=0.3, mR=2.0, IRxx=0.0603, IRyy=0.12, mB=85.0, IBxx=9.2, IByy=11.0, IBzz=2.8,
              IBxz=2.4, mH=4.0, IHxx=0.05892, IHyy=0.06, IHzz=0.00708, IHxz=-0.00756, rF=0.35,
              mF=3.0, IFxx=0.1405, IFyy=0.28, g=9.81)


def test_bicycle_constants_are_table1():
    """The bodies' masses and inertias are Table 1's as published (IHyy, the front
    frame's pitch moment, is one the linear eigenvalues of Table 2 do not involve); the
    products IBxz, IHxz enter with the opposite sign, the model's convention for them
    (the eigenvalues of Table 2 check that, and the geometry's conversion)."""
    _, params = whipple_bicycle()
    for k, v in TABLE1.items():
        assert params[k] == (-v if k.endswith("xz") else v), k

#: the same paper: weave and capsize speeds (m/s)
WEAVE, CAPSIZE = 4.29238253634111, 6.02426201538837
LEAN_STEER = [1, 2, 3, 5]          # q2 roll, q5 steer, u2 roll rate, u5 steer rate


def _eig(bike, v):
    A, _ = bike.linearize(whipple_state(v))
    return np.linalg.eigvals(A[np.ix_(LEAN_STEER, LEAN_STEER)])


@pytest.mark.slow
@pytest.mark.parametrize("v", sorted(TABLE2))
def test_bicycle_benchmark_eigenvalues(bike, v):
    got = np.sort_complex(_eig(bike, v))
    want = np.sort_complex(np.array(TABLE2[v], dtype=complex))
    assert np.abs(got - want).max() < 1e-12      # measured 2.3e-14 (v = 5)


@pytest.mark.slow
def test_bicycle_weave_and_capsize_speeds(bike):
    def abscissa(v):
        return float(np.max(_eig(bike, v).real))
    weave = brentq(abscissa, 4.0, 5.0, xtol=1e-12)
    capsize = brentq(abscissa, 5.5, 7.0, xtol=1e-12)
    assert abs(weave - WEAVE) < 1e-11 and abs(capsize - CAPSIZE) < 1e-11   # measured 1.3e-14
    # the remaining modes of the full linearisation (yaw, rear wheel) are neutral
    A, _ = bike.linearize(whipple_state(5.0))
    ev = np.sort(np.abs(np.linalg.eigvals(A)))
    assert ev[0] < 1e-12 and ev[1] < 1e-12


def _central_jacobian(scene, y, h=1e-6):
    n = y.size
    J = np.empty((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h * max(1.0, abs(y[j]))
        J[:, j] = (scene.rhs(0.0, y + e) - scene.rhs(0.0, y - e)) / (2 * e[j])
    return J


@pytest.mark.slow
def test_bicycle_rhs_by_blocks_agrees_with_the_whole_system(bike):
    # the rhs solves Kane's blocks (M u' = F, then C C^T mu for q'); the
    # Jacobian's D comes from the whole A z = b, differentiated symbolically
    # and solved with the whole system's factors: central differences of the
    # one are the other; and the q' the blocks give holds the holonomic
    # constraint's Baumgarte law f_h' = -beta f_h off the constraint
    rng = np.random.default_rng(11)
    for v in (3.0, 5.5):
        y = bike.project(np.array(whipple_state(v, roll=0.15, steer=-0.1, roll_rate=0.4)))
        y = y + rng.normal(0, 1e-3, y.size)          # a little off the constraints
        J = bike.jacobian(0.0, y)
        Jfd = _central_jacobian(bike, y)
        # measured 1.3e-9 relative to the largest entry (central differences' own error)
        assert np.abs(J - Jfd).max() < 1e-8 * np.abs(J).max()
        f = bike.rhs(0.0, y)
        G = bike.constraint_residual(y)
        GJ = np.array([(bike.constraint_residual(y + e) - bike.constraint_residual(y - e))
                       / 2e-7 for e in np.eye(y.size) * 1e-7]).T
        assert abs(G[0]) > 1e-6                   # off the constraint, so the law shows
        beta = BAUMGARTE[1]
        # measured 2.6e-7 relative (GJ by central differences)
        assert abs((GJ[0] @ f) / G[0] + beta) < 3e-6 * beta


@pytest.mark.slow
def test_bicycle_nonlinear_run_stays_on_its_constraints(bike):
    y0 = bike.project(np.array(whipple_state(4.6, roll=0.2, steer=0.1, roll_rate=0.5)))
    s = mp.solve(bike, (0, 10), y0)
    assert s.status == 0
    res = np.abs(bike.constraint_residual(s.y)).max()
    assert res < 1e-8                        # measured 7.9e-10 (default rtol, baumgarte)
    E = bike.energy(s.y)
    assert np.ptp(E) < 3e-11 * abs(E[0])     # measured 2.4e-12 relative
    # self-stable at 4.6 m/s: the lean decays
    assert abs(s.y[1, -1]) < 0.05 * abs(y0[1]) + 0.01


# ---------------------------------------------------------------- n-link cart

def _reference(kane, params, y0, force, t_end):
    """SymPy's mass_matrix_full and forcing_full lambdified, solved by NumPy,
    integrated by solve_ivp at tight tolerance."""
    x = list(kane.q) + list(kane.u)
    F = dynamicsymbols("F")
    syms = {s.name: s for s in kane.forcing_full.free_symbols | kane.mass_matrix_full.free_symbols}
    consts = [syms[k] for k in params if k in syms]
    vals = [params[k] for k in params if k in syms]
    Mf = sp.lambdify([x, consts, [F]], kane.mass_matrix_full, "numpy")
    Ff = sp.lambdify([x, consts, [F]], kane.forcing_full, "numpy")

    def f(t, y):
        r = [force(t, y)]
        return np.linalg.solve(np.asarray(Mf(y, vals, r), float),
                               np.asarray(Ff(y, vals, r), float).ravel())
    return solve_ivp(f, (0, t_end), y0, method="DOP853", rtol=1e-12, atol=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("n", [5, 10])
def test_n_link_cart_against_solve_ivp(n):
    kane, params = n_link_cart(n)
    drive = lambda t, y: 0.5 * np.sin(2 * t)  # noqa: E731
    y0 = np.zeros(2 * (n + 1))
    y0[1:n + 1] = np.linspace(0.1, 0.3, n)
    ref = _reference(kane, params, y0, drive, 2.0)
    cart = mp.mechanics(kane, params, specified={"F": drive})
    s = mp.solve(cart, (0, 2), y0, rtol=1e-12, atol=1e-12)
    assert np.abs(s.y[:, -1] - ref.y[:, -1]).max() < 3e-11  # measured 1.5e-13, 2.4e-12 (10)
    # a constant force as a value equals the same force as a callable
    c1 = mp.mechanics(kane, params, specified={"F": 0.7})
    c2 = mp.mechanics(kane, params, specified={"F": lambda t, y: 0.7})
    Y = np.random.default_rng(1).uniform(-1, 1, (2 * (n + 1), 3))
    assert np.allclose(c1.rhs(0.0, Y), c2.rhs(0.0, Y), rtol=1e-14, atol=1e-14)
    # a driven model has no energy of its own
    with pytest.raises(AttributeError, match="no energy"):
        c1.energy(Y)
    # B of the linearisation: the force's column, against a difference of rhs
    A, B = c1.linearize(np.zeros(2 * (n + 1)))
    d = (c1.replace(F=1.0).rhs(0.0, np.zeros(2 * (n + 1)))
         - c1.replace(F=0.0).rhs(0.0, np.zeros(2 * (n + 1))))
    assert np.allclose(B[:, 0], d, rtol=1e-12, atol=1e-12)


# ---------------------------------------------------------------- bad input

def test_equations_never_formed():
    with pytest.raises(ValueError, match="kanes_equations"):
        mp.mechanics(_pendulum_kane(formed=False), PARAMS)
    with pytest.raises(TypeError, match="KanesMethod, LagrangesMethod"):
        mp.mechanics("pendulum", PARAMS)


def test_missing_constant_is_named():
    with pytest.raises(ValueError, match=r"\['l'\] have no value"):
        mp.mechanics(_pendulum_kane(), {"g": G, "m": 1.0})
    with pytest.raises(ValueError, match=r"params \['k'\] name no constant"):
        mp.mechanics(_pendulum_kane(), {**PARAMS, "k": 1.0})


def test_specified_input_without_value():
    kane, params = n_link_cart(1)
    with pytest.raises(ValueError, match=r"specified input\(s\) \['F'\] have no value"):
        mp.mechanics(kane, params)
    with pytest.raises(ValueError, match="name no input"):
        mp.mechanics(kane, params, specified={"F": 0.0, "Q": 1.0})


def test_initial_state_off_the_constraints(disc):
    _, _, scene = disc
    # rolling at u3 = 5 rad/s but the contact at rest: the first constraint is off by -r u3
    y0 = np.array([0.0, 0.2, 0.0, 0.0, 0.0, 0.3, 0.1, 5.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"velocity constraint 0 .* by -2\.5"):
        mp.solve(scene, (0, 1), y0)
    # among rows, the first row off its constraints is named; a row on them passes
    on = scene.project(y0)
    with pytest.raises(ValueError, match=r"y0 \(row 2 of y0s\) violates the velocity "
                                         r"constraint 0 .* by -2\.5"):
        mp.solve_many(scene, (0, 0.1), np.array([on, on, y0, y0]))
    # the test is relative to the state's size, max(1, max |y|): 1e-8 of it.
    # u3 moved by d puts the first velocity constraint off by -r d (r = 0.5)
    fast = on.copy()
    fast[7:] *= 100.0           # the speeds x 100 keep the velocity constraints
    size = np.abs(fast).max()
    assert size > 100.0
    for factor, fails in ((0.5, False), (2.0, True)):
        y = fast.copy()
        y[7] += factor * 1e-8 * size / 0.5
        if fails:
            with pytest.raises(ValueError, match="velocity constraint 0"):
                mp.solve(scene, (0, 1e-3), y)
        else:
            assert mp.solve(scene, (0, 1e-3), y).success


def test_singular_mass_matrix_at_y0():
    kane = _pendulum_kane()
    pend = mp.mechanics(kane, {**PARAMS, "m": 0.0})
    with pytest.raises(mp.SingularityError, match="mass matrix"):
        mp.solve(pend, (0, 1), [0.1, 0.0])



def _cartesian_pendulum(drawn=False):
    """The pendulum in Cartesian coordinates (x down, y across) on the circle
    x^2 + y^2 = l^2, by SymPy's LagrangesMethod with a multiplier: (method, x, y);
    ``drawn``: with its bob and inertial frame named (mp.live.animate draws it)."""
    x, y = dynamicsymbols("x y")
    g, l, m = sp.symbols("g l m", positive=True)
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, x.diff() * N.x + y.diff() * N.y)
    bob = Particle("bob", P, m)
    bob.potential_energy = -m * g * x
    lm = LagrangesMethod(Lagrangian(N, bob), [x, y], hol_coneqs=[x**2 + y**2 - l**2],
                         **(dict(bodies=[bob], frame=N) if drawn else {}))
    lm.form_lagranges_equations()
    return lm, x, y


def test_lagrange_with_a_holonomic_constraint():
    """The pendulum in Cartesian coordinates (x down, y across) on the circle
    x^2 + y^2 = l^2, by LagrangesMethod with a multiplier: its angle moves as
    the scene's, the constraint and its rate are held, and the energy is kept."""
    lm, x, y = _cartesian_pendulum()
    scene = mp.mechanics(lm, PARAMS)
    th0, w0 = 1.0, 0.4
    y0 = [L * np.cos(th0), L * np.sin(th0), -L * w0 * np.sin(th0), L * w0 * np.cos(th0)]
    s = mp.solve(scene, (0, 5), y0, rtol=1e-11, atol=1e-12, t_eval=[5.0])
    ref = mp.solve(mp.scenes.Pendulum(g=G, length=L), (0, 5), [th0, w0], rtol=1e-11,
                   atol=1e-12, t_eval=[5.0])
    xs, ys, us, vs = s.y[:, -1]
    assert abs(np.arctan2(ys, xs) - ref.y[0, -1]) < 1e-8                 # measured 1e-10
    assert abs((xs * vs - ys * us) / L**2 - ref.y[1, -1]) < 1e-8
    full = mp.solve(scene, (0, 5), y0)
    assert scene.coordinates == ["x", "y"] and scene.speeds == ["x'", "y'"]
    assert scene.states == ["x", "y", "x'", "y'"]
    assert np.abs(scene.constraint_residual(full.y)).max() < 1e-7        # measured 1.0e-8
    E = scene.energy(full.y)
    assert np.ptp(E) < 1e-7                                              # measured 2e-9
    # linearised about the bottom, x dependent: the pendulum's [[0, 1], [-g/l, 0]]
    with pytest.raises(ValueError, match=r"dependent states \['y', \"y'\"\] cannot be solved"):
        scene.linearize([L, 0.0, 0.0, 0.0])          # x independent: dg/dy = 0 at the bottom
    A, _ = scene.linearize([L, 0.0, 0.0, 0.0], independent=["y", "y'"])
    assert np.allclose(A, [[0, 1], [-G / L, 0]], rtol=1e-12, atol=1e-12)


def test_disc_implicit_method_ensemble_and_events(disc):
    """Every path of the engine: Radau with the analytic Jacobian (checked by
    central differences), solve_many in lanes, an event."""
    _, _, scene = disc
    y0 = scene.project(np.array([0.0, 0.3, 0.0, 0.0, 0.0, 0.5, 0.2, 4.0, 0.0, 0.0]))
    J = scene.jacobian(0.0, y0)
    h = 1e-6
    Jfd = np.column_stack([(scene.rhs(0.0, y0 + h * e) - scene.rhs(0.0, y0 - h * e)) / (2 * h)
                           for e in np.eye(10)])
    assert np.allclose(J, Jfd, rtol=1e-6, atol=1e-7)          # measured 3e-9
    ref = mp.solve(scene, (0, 3), y0, rtol=1e-12, atol=1e-12)
    rad = mp.solve(scene, (0, 3), y0, method="radau", rtol=1e-10, atol=1e-10)
    assert np.abs(rad.y[:, -1] - ref.y[:, -1]).max() < 1e-6   # measured 4e-9
    y0s = np.array([scene.project(y0 * f) for f in (0.8, 1.0, 1.2)])
    ens = mp.solve_many(scene, (0, 3), y0s, rtol=1e-10, atol=1e-12)
    for i in range(3):
        one = mp.solve(scene, (0, 3), y0s[i], rtol=1e-10, atol=1e-12)
        assert np.abs(ens.y[i][:, -1] - one.y[:, -1]).max() < 1e-8

    def spin_turn(t, y):          # the spin angle passes 2 pi
        return y[2] - 2 * np.pi
    spin_turn.terminal = True
    s = mp.solve(scene, (0, 10), y0, events=spin_turn, rtol=1e-10, atol=1e-12)
    assert s.status == 1 and abs(s.y_events[0][0][2] - 2 * np.pi) < 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("n", [5, 10])
def test_pydy_n_link_cart_against_pydys_integration(n):
    """PyDy's own model (pydy.models) integrated by PyDy's System.integrate
    (its generated rhs and odeint at tight tolerance) against mp.mechanics
    of the same KanesMethod; skipped without PyDy (pip install pydy)."""
    pytest.importorskip("pydy")
    from pydy.models import n_link_pendulum_on_cart
    sys_ = n_link_pendulum_on_cart(n, cart_force=True, joint_torques=False)
    consts = {s: (9.81 if s.name == "g" else 1.0 + 0.1 * i)
              for i, s in enumerate(sorted(sys_.constants_symbols, key=lambda s: s.name))}
    F = next(iter(sys_.specifieds_symbols))
    sys_.constants = consts
    sys_.specifieds = {F: lambda x, t: 0.5 * np.sin(2 * t)}
    y0 = np.zeros(2 * (n + 1))
    y0[1:n + 1] = np.linspace(0.1, 0.3, n)
    sys_.initial_conditions = dict(zip(sys_.coordinates + sys_.speeds, y0))
    sys_.times = np.linspace(0, 2, 3)
    sys_.integrator = "odeint"
    theirs = sys_.integrate(rtol=1e-12, atol=1e-12, mxstep=10**6)[-1]
    scene = mp.mechanics(sys_.eom_method, {s.name: v for s, v in consts.items()},
                         specified={"F": lambda t, y: 0.5 * np.sin(2 * t)})
    ours = mp.solve(scene, (0, 2), y0, rtol=1e-12, atol=1e-12).y[:, -1]
    assert np.abs(ours - theirs).max() < 5e-10       # measured 2.1e-11 (n = 5), 5.2e-11 (10)


def test_building_leaves_the_function_in_place():
    """The implementation's module is imported when a model is built; it must
    not replace the public function mechpy.symbolic.mechanics (a submodule of
    that name would)."""
    mp.mechanics(_pendulum_kane(), PARAMS)
    assert callable(mp.symbolic.mechanics) and mp.symbolic.mechanics is mp.mechanics


# ---------------------------------------------------------------- issue 51: clear errors

def _torque_pendulum():
    th, w = dynamicsymbols("theta omega")
    T = dynamicsymbols("T")
    g, l, m = sp.symbols("g l m", positive=True)
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    A.set_ang_vel(N, w * N.z)
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    kane = KanesMethod(N, [th], [w], kd_eqs=[th.diff() - w])
    kane.kanes_equations([Particle("bob", P, m)], [(P, m * g * N.x), (A, T * N.z)])
    return kane, th, w


def test_a_specified_input_that_returns_nan_is_named():
    """A callable input returning NaN was blamed on "the mass matrix of Kane's
    equations"; the error names the input, its value and the state."""
    kane, _, _ = _torque_pendulum()
    pend = mp.mechanics(kane, PARAMS, specified={"T": lambda t, y: float("nan")})
    with pytest.raises(mp.NonFiniteError, match=r"the specified input 'T' is nan at t = 0\.0"):
        pend.rhs(0.0, [0.1, 0.0])
    with pytest.raises(mp.NonFiniteError, match=r"specified input 'T' is nan"):
        mp.solve(pend, (0, 1), [0.1, 0.0])


def test_solve_many_params_with_a_callable_input():
    """solve_many(params=...) on a model with a callable input failed with the
    internal "rhs() takes 2 positional arguments but 6 were given"; each row's
    parameters now reach its trajectory (against mp.solve of the scene with
    that row's values), the input's slot taken by the callable."""
    kane, _, _ = _torque_pendulum()
    drive = lambda t, y: 0.3 * np.sin(t)  # noqa: E731
    pend = mp.mechanics(kane, PARAMS, specified={"T": drive})
    names = list(pend.params)
    rows = np.array([[PARAMS[k] if k in PARAMS else 0.0 for k in names] for _ in range(3)])
    rows[:, names.index("g")] = [9.81, 3.7, 1.6]
    y0s = np.array([[0.5, 0.0], [0.3, 0.1], [1.0, -0.2]])
    ens = mp.solve_many(pend, (0, 2), y0s, params=rows, rtol=1e-10, atol=1e-12)
    for i in range(3):
        one = mp.solve(pend.replace(g=rows[i, names.index("g")], T=drive), (0, 2), y0s[i],
                       rtol=1e-10, atol=1e-12, t_eval=[2.0])
        np.testing.assert_allclose(ens.y[i, :, -1], one.y[:, -1], rtol=0, atol=1e-12)
    # the g = 1.6 row is not the g = 9.81 one: the rows were used
    assert abs(ens.y[2, 0, -1] - mp.solve(pend, (0, 2), y0s[2], rtol=1e-10,
                                          atol=1e-12).y[0, -1]) > 1e-2


def test_states_speeds_coordinates_as_pydy_names_them():
    """.coordinates returned the speeds too; PyDy's names now: coordinates (q),
    speeds (u), states (both), and an initial state keyed by names or by the
    model's dynamic symbols."""
    kane, th, w = _torque_pendulum()
    pend = mp.mechanics(kane, PARAMS, specified={"T": 0.0})
    assert pend.coordinates == ["theta"] and pend.speeds == ["omega"]
    assert pend.states == ["theta", "omega"]
    np.testing.assert_array_equal(pend.initial_state({th: 0.4, w: -0.1}), [0.4, -0.1])
    np.testing.assert_array_equal(pend.initial_state({"omega": 2.0, "theta": 1.0}), [1.0, 2.0])
    s = mp.solve(pend, (0, 1), pend.initial_state({th: 0.4, "omega": 0.0}), t_eval=[1.0])
    assert s.success
    with pytest.raises(ValueError, match=r"no value for the state\(s\) \['omega'\]"):
        pend.initial_state({th: 0.4})
    with pytest.raises(ValueError, match=r"'phi' is not a state"):
        pend.initial_state({"theta": 0.4, "omega": 0.0, "phi": 1.0})
    with pytest.raises(ValueError, match=r"gives the state 'theta' twice"):
        pend.initial_state({"theta": 0.4, th: 0.4, "omega": 0.0})
    lm = mp.mechanics(_pendulum_lagrange(), PARAMS)
    q = _pendulum_lagrange().q[0]
    assert lm.coordinates == ["theta"] and lm.speeds == ["theta'"]
    np.testing.assert_array_equal(lm.initial_state({q: 0.2, q.diff(): 0.5}), [0.2, 0.5])
    # mp.lagrangian and mp.equations say the same of themselves
    x, = mp.coordinates("x")
    osc = mp.lagrangian(x.diff() ** 2 / 2 - x ** 2 / 2, [x])
    assert (osc.coordinates, osc.speeds, osc.states) == (["x"], ["x'"], ["x", "x'"])
    np.testing.assert_array_equal(osc.initial_state({x: 1.0, x.diff(): 0.0}), [1.0, 0.0])


def test_a_failed_solve_says_what_is_singular_where():
    """A 0/0 in the kinematical equations of a model with a constant mass
    matrix and no constraints was reported as "the mass matrix ... with the
    rows of the constraints"; a massless bob as the same.  The error now names
    the row that is NaN (the kinematical equation of theta) or the singular
    block (the mass matrix of the speeds), and the state."""
    th, w = dynamicsymbols("theta omega")
    g, l, m = sp.symbols("g l m", positive=True)
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    A.set_ang_vel(N, w * N.z)
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    # sin/tan = cos, which SymPy leaves unsimplified: 0/0 at theta = 0
    kane = KanesMethod(N, [th], [w], kd_eqs=[th.diff() - w * sp.sin(th) / sp.tan(th)])
    kane.kanes_equations([Particle("bob", P, m)], [(P, m * g * N.x)])
    pend = mp.mechanics(kane, PARAMS)
    np.testing.assert_allclose(pend.rhs(0.0, [0.3, 0.2]),
                               [0.2 * np.cos(0.3), -G / L * np.sin(0.3)], rtol=1e-14)
    with pytest.raises(mp.NonFiniteError, match=r"the kinematical equation of theta "
                       r"evaluates to nan at t = 0\.0, y = \[0\.0, 0\.2\]") as err:
        pend.rhs(0.0, [0.0, 0.2])
    assert "constraint" not in str(err.value)
    massless = mp.mechanics(_pendulum_kane(), {**PARAMS, "m": 0.0})
    with pytest.raises(mp.SingularityError, match=r"the mass matrix of the speeds is "
                       r"singular at t = 0\.0, y = \[0\.1, 0\.0\] \(rank 0 of 1"):
        mp.solve(massless, (0, 1), [0.1, 0.0])


def test_solve_takes_an_initial_state_keyed_by_names_or_symbols():
    """PyDy's habit: y0 as a dict keyed by the states' names or SymPy's objects, in
    mp.solve and in each row of mp.solve_many; the same trajectory as the vector."""
    import sympy as sp
    x, v = sp.symbols("x v")
    osc = mp.equations([v, -4 * x], [x, v])
    want = mp.solve(osc, (0, 1), [1.0, 0.5], t_eval=[1.0], rtol=1e-10).y
    got = mp.solve(osc, (0, 1), {"v": 0.5, x: 1.0}, t_eval=[1.0], rtol=1e-10).y
    np.testing.assert_array_equal(got, want)
    ens = mp.solve_many(osc, (0, 1), [{"x": 1.0, "v": 0.5}, [2.0, 0.0]], t_eval=[1.0],
                        rtol=1e-10)
    np.testing.assert_array_equal(ens.y[0], want)
    np.testing.assert_allclose(ens.y[1, 0, -1], 2.0 * np.cos(2.0), rtol=1e-9)
    with pytest.raises(TypeError, match="y0 as a dict needs a system with named states"):
        mp.solve(lambda t, y: -y, (0, 1), {"x": 1.0})
    with pytest.raises(ValueError):
        mp.solve(osc, (0, 1), {"x": 1.0})          # v without a value


def test_lagrange_holonomic_drift_decays_at_baumgartes_designed_rate():
    """The Cartesian pendulum (LagrangesMethod, x^2 + y^2 = l^2) started 1% off the
    circle with a velocity tangent to it: with Baumgarte's (alpha, beta) the residual
    g = x^2 + y^2 - l^2 obeys g'' + 2 alpha g' + beta^2 g = 0 exactly (the row c' = 0 of
    the constraint's rate is replaced by c' + 2 alpha c + beta^2 g = 0), so g(t) is that
    linear ODE's closed form, g0 e^(-alpha t) (cos wd t + alpha/wd sin wd t),
    wd = sqrt(beta^2 - alpha^2).  Pins the position term beta^2 (multibody.py's Lagrange
    branch): beta in its place fails here.  Measured: |g - closed form| <= 3.4e-12 with
    g0 = 0.034 (SciPy's DOP853 at rtol 1e-12 on the scene's rhs)."""
    lm, x, y = _cartesian_pendulum()
    alpha, beta = 1.0, 3.0
    scene = mp.mechanics(lm, PARAMS, baumgarte=(alpha, beta))
    th0, w0, r0 = 1.0, 0.4, 1.01 * L
    y0 = [r0 * np.cos(th0), r0 * np.sin(th0), -r0 * w0 * np.sin(th0), r0 * w0 * np.cos(th0)]
    ts = np.array([0.0, 0.3, 0.7, 1.2, 2.0])
    # (mp.solve refuses a start off the constraint: SciPy integrates the scene's field)
    s = solve_ivp(scene.rhs, (0, 2), y0, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=ts)
    gs = s.y[0] ** 2 + s.y[1] ** 2 - L**2
    g0 = r0**2 - L**2                              # and g'(0) = 2 (x u + y v) = 0
    wd = np.sqrt(beta**2 - alpha**2)
    closed = g0 * np.exp(-alpha * ts) * (np.cos(wd * ts) + alpha / wd * np.sin(wd * ts))
    assert abs(g0 - 0.034) < 1e-3 and np.abs(closed).max() > 0.3 * g0
    assert np.abs(gs - closed).max() < 3e-11, np.abs(gs - closed)      # measured 3.4e-12


# ---- SymPy's private attributes: one adapter (mechpy/symbolic/_sympy_private.py) ----------

def test_sympy_private_attributes_on_this_sympy():
    """Every private attribute the adapter reads exists on the installed SymPy
    (the adapter was checked against the versions in CHECKED) and means what
    the adapter takes it to mean, against public SymPy calls."""
    from mechpy.symbolic import _sympy_private as priv
    kane, lag = _pendulum_kane(), _cartesian_pendulum()[0]
    P = Point("P")
    objects = {"KanesMethod": kane, "LagrangesMethod": lag, "Point": P,
               "dynamicsymbols": dynamicsymbols, "Symbol": sp.Symbol("a", positive=True)}
    assert set(objects) == set(priv.ATTRIBUTES)
    missing = [f"{cls}.{a}" for cls, names in priv.ATTRIBUTES.items() for a in names
               if not hasattr(objects[cls], a)]
    assert not missing, (f"SymPy {sp.__version__} has no {', '.join(missing)}: "
                         "mechpy/symbolic/_sympy_private.py was checked against SymPy "
                         f"{', '.join(priv.CHECKED)} only; adapt it to this version")
    # their meaning, against what the public API says
    assert dynamicsymbols("q").args == (priv.time(),)
    assert priv.kane_formed(kane) and not priv.kane_formed(_pendulum_kane(formed=False))
    assert not priv.kane_auxiliary_speeds(kane) and priv.kane_holonomic(kane) == []
    assert len(priv.kane_dependent_speeds(kane)) == 0
    assert priv.kane_inertial(kane).name == "N"        # KanesMethod(N, ...) in _pendulum_kane
    # as given, not with what they imply (assumptions0 adds real, nonzero, ...)
    assert priv.assumptions_given(sp.Symbol("a", positive=True)) == {"positive": True}
    x, y = _cartesian_pendulum()[1:]
    l = sp.Symbol("l", positive=True)
    assert priv.lagrange_holonomic(lag) == [x**2 + y**2 - l**2]
    assert priv.lagrange_holonomic(_pendulum_lagrange()) == []
    N = ReferenceFrame("N")
    O = Point("O")
    assert priv.point_velocity_set(O, N) is None
    O.set_vel(N, 0)
    assert priv.point_velocity_set(O, N) == 0
    Q = O.locatenew("Q", 2 * N.x)
    assert O in priv.point_neighbours(Q) and Q in priv.point_neighbours(O)


def test_sympy_private_attribute_missing_is_named():
    from mechpy.symbolic import _sympy_private as priv
    with pytest.raises(RuntimeError, match=rf"SymPy {sp.__version__}: KanesMethod has no "
                       r"attribute _fr, .*checked against SymPy"):
        priv.kane_formed(object())


def _particle_on_a_line():
    """A particle in space held on the line x = y = z by two configuration constraints
    (y - x = 0, z - x = 0: Kane's method with two dependent coordinates and speeds),
    under gravity -m g N.z."""
    x, y, z, ux, uy, uz = dynamicsymbols("x y z u_x u_y u_z")
    g, m = sp.symbols("g m", positive=True)
    N = ReferenceFrame("N")
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y + z * N.z)
    P.set_vel(N, ux * N.x + uy * N.y + uz * N.z)
    kane = KanesMethod(N, [x], [ux], kd_eqs=[x.diff() - ux, y.diff() - uy, z.diff() - uz],
                       q_dependent=[y, z], configuration_constraints=[y - x, z - x],
                       u_dependent=[uy, uz], velocity_constraints=[uy - ux, uz - ux])
    kane.kanes_equations([Particle("p", P, m)], [(P, -m * g * N.z)])
    return kane


def test_kane_with_two_configuration_constraints():
    """The particle on the line x = y = z under gravity: the component g/sqrt(3) along
    the line gives each coordinate the acceleration -g/3, so from (s0, s0, s0) at speed
    v0 on each axis every coordinate is s0 + v0 t - g t^2 / 6 and every speed v0 - g t / 3
    (closed form); both constraints held.  Each configuration constraint has its own
    row of the system (two rows: one constraint overwriting a dynamic row goes wrong)."""
    scene = mp.mechanics(_particle_on_a_line(), {"g": G, "m": 2.0})
    s0, v0 = 0.5, 1.5
    ts = np.array([0.0, 0.4, 1.0, 2.0])
    s = mp.solve(scene, (0, 2), [s0] * 3 + [v0] * 3, t_eval=ts, rtol=1e-12, atol=1e-12)
    assert s.success
    pos, vel = s0 + v0 * ts - G * ts**2 / 6, v0 - G * ts / 3
    np.testing.assert_allclose(s.y[:3], np.tile(pos, (3, 1)), rtol=0, atol=1e-10)
    np.testing.assert_allclose(s.y[3:], np.tile(vel, (3, 1)), rtol=0, atol=1e-10)
    assert np.abs(scene.constraint_residual(s.y)).max() < 1e-10


@pytest.mark.parametrize("n", [1, 3])
def test_n_link_cart_kinematics_and_the_free_cart_pendulum(n):
    """n_link_cart's coordinates move at its speeds (q_i' = u_i, the cart's position and
    each link's angle), and with one link and no force the pendulum on a free cart swings
    at w^2 = g (m0 + m1) / (m0 l) about the hanging state (closed form; A's eigenvalues
    are +-i w and 0, 0 for the cart's free drift)."""
    kane, params = n_link_cart(n)
    cart = mp.mechanics(kane, params, specified={"F": 0.0})
    Y = np.random.default_rng(3).uniform(-1, 1, (2 * (n + 1), 4))
    np.testing.assert_allclose(cart.rhs(0.0, Y)[:n + 1], Y[n + 1:], rtol=1e-14, atol=1e-14)
    if n == 1:
        hang = np.array([0.0, -np.pi / 2, 0.0, 0.0])     # angle from I.x; gravity -I.y
        A, _ = cart.linearize(hang)
        ev = np.sort_complex(np.linalg.eigvals(A))
        w = np.sqrt(params["g"] * (params["m0"] + params["m1"]) / (params["m0"] * params["l0"]))
        np.testing.assert_allclose(ev, [-1j * w, 0, 0, 1j * w], rtol=0, atol=1e-12)
