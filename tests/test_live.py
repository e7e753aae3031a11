"""mechpy.live's phase portrait: the symbolic form against the C right-hand
side, and the page in headless Chromium (software WebGL2) against a float64
RK4 computed here, overlays against mechpy.phase's closed forms, the saved
page offline."""
import os
import sys

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

sys.path.insert(0, os.path.dirname(__file__))
from live_browser import driver, network_requests, open_page  # noqa: E402,F401
from ref_ode import rk4_fixed  # noqa: E402

SCENES = [
    mp.scenes.Pendulum(g=9.5, length=1.3, damping=0.2, drive_amplitude=0.7, drive_frequency=1.9),
    mp.scenes.VanDerPol(mu=2.5),
    mp.scenes.Duffing(alpha=-1.0, beta=1.2, delta=0.3, gamma=0.4, omega=1.4),
    mp.scenes.Kepler(mu=1.7),
    mp.scenes.RestrictedThreeBody(mu=0.012277471),
    mp.scenes.Foucault(latitude=48.85, length=67.0),
    mp.scenes.RigidBody(moments=(1.0, 2.0, 2.5), torque=(0.1, -0.2, 0.3)),
    mp.scenes.RigidBody(moments=(1.0, 2.0, 2.5), torque=(0.1, -0.2, 0.3), orientation=True),
    mp.scenes.HeavyTop(I1=1.0, I3=0.5, mass=1.0, g=9.81, l=0.3),
    mp.scenes.Rocket(exhaust_speed=2500, burn_rate=10, m0=1000, m_dry=200, g=9.81, drag=0.3),
]


@pytest.mark.parametrize("scene", SCENES, ids=lambda s: type(s).__name__ + str(s.dim))
def test_symbolic_form_is_the_c_rhs(scene, rng):
    """The row's symbolic form (what the page evaluates) equals the C rhs."""
    F = scene.symbolic()
    f = sp.lambdify([F.t, F.y], [e.subs(F.params) for e in F.f], "numpy")
    for k in range(20):
        y = rng.uniform(0.2, 1.4, scene.dim) * rng.choice([-1, 1], scene.dim)
        if isinstance(scene, mp.scenes.Rocket):
            y[2] = rng.choice([150.0, 900.0])         # both sides of burn-out
        t = rng.uniform(0, 10)
        ref = scene.rhs(t, y)
        got = np.array(f(t, y), dtype=float)
        np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-13 * np.abs(ref).max())


def test_no_symbolic_form_is_a_clear_error():
    with pytest.raises(ValueError, match="no symbolic form"):
        mp.scenes.SpringChain(masses=[1.0, 1.0], springs=[1.0, 1.0, 1.0]).symbolic()
    import ctypes
    dp = ctypes.POINTER(ctypes.c_double)
    TORQUE = ctypes.CFUNCTYPE(None, ctypes.c_double, dp, dp, ctypes.c_void_p)

    def tau(t, y, out, user):
        out[0] = out[1] = out[2] = 0.0
    fn = TORQUE(tau)
    with pytest.raises(ValueError, match="no symbolic form"):
        mp.scenes.RigidBody(torque=fn).symbolic()


def test_compiled_symbolic_form_is_its_rhs(rng):
    th1, th2 = mp.coordinates("th1 th2")
    m, g = sp.symbols("m g")
    w1, w2 = th1.diff(), th2.diff()
    L = m * (w1**2 + w2**2 / 2 + w1 * w2 * sp.cos(th1 - th2)) + g * (2 * sp.cos(th1) + sp.cos(th2))
    s = mp.lagrangian(L, [th1, th2], params={"m": 1.3, "g": 9.81})
    F = s.symbolic()
    f = sp.lambdify([F.t, F.y], [e.subs(F.params) for e in F.f], "numpy")
    for _ in range(10):
        y = rng.uniform(-2, 2, 4)
        np.testing.assert_allclose(np.array(f(0.0, y), dtype=float), s.rhs(0.0, y),
                                   rtol=1e-12, atol=1e-12)


# ---- bad input: clear errors at the call ---------------------------------------------
def test_bad_input():
    vdp = mp.scenes.VanDerPol()
    y = sp.symbols("y0:5")
    five = mp.equations([y[1], -y[0], y[3], -y[2], -y[4]], list(y))
    with pytest.raises(ValueError, match="dimension 2, 3 or 4"):
        mp.live.phase_portrait(five, (-1, 1), (-1, 1))
    with pytest.raises(ValueError, match="no parameter 'alpha'.*mu"):
        mp.live.phase_portrait(vdp, (-1, 1), (-1, 1), params={"alpha": (0, 1)})
    with pytest.raises(ValueError, match=r"params\['mu'\] must have min < max"):
        mp.live.phase_portrait(vdp, (-1, 1), (-1, 1), params={"mu": (3, 1)})
    with pytest.raises(ValueError, match="xlim must have min < max"):
        mp.live.phase_portrait(vdp, (1, -1), (-1, 1))
    for n in (0, 10**9):
        with pytest.raises(ValueError, match="particles"):
            mp.live.phase_portrait(vdp, (-1, 1), (-1, 1), particles=n)
    with pytest.raises(ValueError, match="symbolic form"):
        mp.live.phase_portrait(lambda t, y: -y, (-1, 1), (-1, 1))
    with pytest.raises(ValueError, match="no symbolic form"):
        mp.live.phase_portrait(mp.scenes.SpringChain(masses=[1.0], springs=[1.0, 1.0]),
                               (-1, 1), (-1, 1))
    with pytest.raises(ValueError, match="axes"):
        mp.live.phase_portrait(vdp, (-1, 1), (-1, 1), axes=(0, 2))


# ---- the page in Chromium ------------------------------------------------------------
def _states(driver, what):
    return np.array(driver.execute_script(f"return Array.from(window.mechpyLive.{what}())"))


def _page(driver, tmp_path, w, name):
    path = w.save(tmp_path / f"{name}.html")
    open_page(driver, path)
    return path


def _vdp(mu):
    return lambda t, y: np.stack([y[:, 1], mu * (1 - y[:, 0]**2) * y[:, 1] - y[:, 0]], axis=1)


def _close(got, f, t0, y0, h, n, what):
    """float32 states against the float64 RK4 from the same states: each particle's
    error, over the growth of its own errors (the norm of the RK4 map's derivative,
    by central differences), within 100 steps' round-off of float32 (2^-24 each;
    measured: 1e-7 after one step, its growth after 100)."""
    y0 = np.asarray(y0, dtype=float)
    ref = rk4_fixed(f, t0, y0, h, n)
    grow = np.zeros(len(y0))
    for i in range(y0.shape[1]):
        e = np.zeros(y0.shape[1])
        e[i] = 1e-6
        d = (rk4_fixed(f, t0, y0 + e, h, n) - rk4_fixed(f, t0, y0 - e, h, n)) / 2e-6
        grow = np.maximum(grow, np.linalg.norm(d, axis=1))
    err = np.abs(got - ref).max(axis=1) / (np.maximum(1.0, np.abs(ref).max(axis=1))
                                           * np.maximum(1.0, grow))
    assert err.max() < n * 2.0**-24, f"{what}: max scaled error {err.max():.3g}"
    return ref


def test_vanderpol_particles_are_rk4_and_follow_a_slider(driver, tmp_path):
    w = mp.live.phase_portrait(mp.scenes.VanDerPol(mu=1.0), (-4, 4), (-6, 6),
                               params={"mu": (0.0, 4.0)}, particles=4000, play=False,
                               overlays=False)
    _page(driver, tmp_path, w, "vdp")
    seeds = _states(driver, "seeds").reshape(-1, 2)
    assert seeds.shape == (4000, 2)
    assert np.all((seeds[:, 0] >= -4) & (seeds[:, 0] <= 4) & (seeds[:, 1] >= -6) & (seeds[:, 1] <= 6))
    driver.execute_script("window.mechpyLive.step(100)")
    got = _states(driver, "particles").reshape(-1, 2)
    _close(got, _vdp(1.0), 0.0, seeds, 0.01, 100, "mu = 1")
    # a slider's value: the next steps follow the new field, not the old
    driver.execute_script("window.mechpyLive.setParam('mu', 3)")
    driver.execute_script("window.mechpyLive.step(50)")
    after = _states(driver, "particles").reshape(-1, 2)
    _close(after, _vdp(3.0), 1.0, got, 0.01, 50, "mu = 3")
    old = rk4_fixed(_vdp(1.0), 1.0, got.astype(float), 0.01, 50)
    assert np.abs(after - old).max() > 0.1
    assert network_requests(driver) == []


def test_driven_pendulum_advances_time(driver, tmp_path):
    sc = mp.scenes.Pendulum(damping=0.5, drive_amplitude=1.2, drive_frequency=2.0 / 3.0)
    w = mp.live.phase_portrait(sc, (-np.pi, np.pi), (-3, 3), particles=2000, dt=0.02,
                               t0=0.5, play=False, overlays=False)
    _page(driver, tmp_path, w, "driven")
    seeds = _states(driver, "seeds").reshape(-1, 2)
    t = driver.execute_script("return window.mechpyLive.step(100)")
    assert t == pytest.approx(0.5 + 100 * 0.02, rel=1e-12)

    def f(t, y):
        return np.stack([y[:, 1], -9.81 * np.sin(y[:, 0]) - 0.5 * y[:, 1]
                         + 1.2 * np.cos(2.0 / 3.0 * t)], axis=1)
    _close(_states(driver, "particles").reshape(-1, 2), f, 0.5, seeds, 0.02, 100,
           "driven pendulum")
    # the frozen-time field would differ: t really advances
    frozen = rk4_fixed(lambda t, y: f(0.5, y), 0.5, seeds, 0.02, 100)
    assert np.abs(_states(driver, "particles").reshape(-1, 2) - frozen).max() > 1e-2


def test_compiled_double_pendulum_4d(driver, tmp_path):
    th1, th2 = mp.coordinates("th1 th2")
    w1, w2 = th1.diff(), th2.diff()
    L = w1**2 + w2**2 / 2 + w1 * w2 * sp.cos(th1 - th2) + 2 * sp.cos(th1) + sp.cos(th2)
    s = mp.lagrangian(L, [th1, th2])
    w = mp.live.phase_portrait(s, (-2, 2), (-2, 2), particles=1000, play=False,
                               hidden=[(0, 0), (0, 0), (-1, 1), (-1, 1)], overlays=False)
    _page(driver, tmp_path, w, "double")
    seeds = _states(driver, "seeds").reshape(-1, 4)
    assert np.ptp(seeds[:, 2]) > 1.0 and np.all(np.abs(seeds[:, 2:]) <= 1)
    driver.execute_script("window.mechpyLive.step(100)")
    got = _states(driver, "particles").reshape(-1, 4)
    _close(got, lambda t, y: s.rhs(t, y.T).T, 0.0, seeds, 0.01, 100, "double pendulum")


def test_overlays_pendulum_fixed_points(driver, tmp_path):
    w = mp.live.phase_portrait(mp.scenes.Pendulum(), (-7, 7), (-8, 8), particles=500, play=False)
    _page(driver, tmp_path, w, "pend")
    fps = driver.execute_script("return window.mechpyLive.overlays().fixed_points")
    xs = sorted(p[0] for p in fps)
    np.testing.assert_allclose(xs, np.pi * np.arange(-2, 3), atol=1e-9)
    for x, y, kind, stable in fps:
        assert abs(y) < 1e-9
        k = round(x / np.pi)
        assert kind == ("centre" if k % 2 == 0 else "saddle"), (x, kind)


def test_overlays_vanderpol_limit_cycle_and_saved_grid(driver, tmp_path):
    vdp = mp.scenes.VanDerPol(mu=1.0)
    w = mp.live.phase_portrait(vdp, (-4, 4), (-6, 6), params={"mu": (0.5, 2.0)}, particles=500,
                               play=False, overlay_grid=4)
    path = _page(driver, tmp_path, w, "vdpcycle")
    ov = driver.execute_script("return window.mechpyLive.overlays()")
    cyc = np.array(ov["limit_cycle"])
    period, amp = mp.phase.limit_cycle(vdp, [2.0, 0.0])
    assert amp == pytest.approx(2.0086198609, abs=1e-8)
    assert cyc[:, 0].max() == pytest.approx(amp, abs=1e-4)
    assert np.linalg.norm(cyc[0] - cyc[-1]) < 1e-6           # closed after one period
    assert [p[2] for p in ov["fixed_points"]] == ["focus"]
    # nullclines of x' = v (v = 0) and of v' (v = x / (mu (1 - x^2)))
    v0 = [c for c in ov["nullclines"] if c["which"] == 0]
    assert v0 and all(abs(y) < 1e-9 for c in v0 for _, y in c["points"])
    # a saved page holds the overlays over the slider: mu = 2 shows its own cycle
    driver.execute_script("window.mechpyLive.setParam('mu', 2.0)")
    ov2 = driver.execute_script("return window.mechpyLive.overlays()")
    _, amp2 = mp.phase.limit_cycle(vdp.replace(mu=2.0), [2.0, 0.0])
    assert ov2["values"]["mu"] == 2.0
    assert np.array(ov2["limit_cycle"])[:, 0].max() == pytest.approx(amp2, abs=1e-4)
    assert os.path.getsize(path) < 5e6


def test_click_drops_a_trajectory_offline(driver, tmp_path):
    vdp = mp.scenes.VanDerPol(mu=1.0)
    w = mp.live.phase_portrait(vdp, (-4, 4), (-6, 6), particles=200, play=False,
                               overlays=False, path_steps=500)
    _page(driver, tmp_path, w, "click")
    driver.execute_script("return window.mechpyLive.dropPath(1.0, 0.5)")
    path = np.array(driver.execute_script("return window.mechpyLive.paths()[0]"))
    assert path.shape == (501, 2)
    ref = mp.solve(vdp, (0, 5.0), [1.0, 0.5], rtol=1e-12, atol=1e-12, t_eval=[2.5, 5.0]).y.T
    np.testing.assert_allclose(path[[250, 500]], ref, atol=1e-8)     # the page's RK4, h = 0.01


def test_saved_page_is_self_contained(driver, tmp_path):
    w = mp.live.phase_portrait(mp.scenes.Duffing(alpha=-1, beta=1), (-2, 2), (-2, 2),
                               params={"delta": (0, 0.5)}, overlays=False)
    path = _page(driver, tmp_path, w, "duffing")
    html = path.read_text()
    assert "<script src" not in html and "http://" not in html.split("mechpy-esm")[0]
    assert network_requests(driver) == []
    assert path.stat().st_size < 1e6


def test_kernel_answers_the_page():
    """What the kernel sends a page: the overlays at a slider's value (the limit
    cycle of mu = 2 through mechpy.phase's amplitude), a clicked trajectory
    (mp.solve's), and an error message, never an exception, for a bad request."""
    vdp = mp.scenes.VanDerPol(mu=1.0)
    w = mp.live.phase_portrait(vdp, (-4, 4), (-6, 6), params={"mu": (0.5, 3.0)}, play=False,
                               path_steps=200)
    ov = w._answer({"type": "overlays", "params": {"mu": 2.0}})["data"]
    period, amp = mp.phase.limit_cycle(vdp.replace(mu=2.0), [2.0, 0.0])
    assert ov["amplitude"] == pytest.approx(amp, rel=1e-7)
    assert ov["period"] == pytest.approx(period, rel=1e-7)
    tr = w._answer({"type": "trajectory", "y0": [1.0, 0.5], "t0": 1.0, "params": {"mu": 2.0}})
    pts = np.array(tr["points"])
    ref = mp.solve(vdp.replace(mu=2.0), (1.0, 3.0), [1.0, 0.5], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(pts[-1], ref.y[:, -1], atol=1e-7)
    sent = []
    w.send = sent.append
    w._on_page_message(w, {"type": "trajectory", "id": 7, "y0": "nonsense"}, [])
    assert sent and sent[0]["type"] == "error" and sent[0]["id"] == 7


def test_elementary_functions_in_the_shader(driver, tmp_path):
    """exp, log, tan, a fractional power and sqrt as the page evaluates them
    (its own float32 sin/cos/exp/log), against the compiled system's C rhs."""
    x, y = sp.symbols("x y")
    s = mp.equations([sp.log(1 + y**2) - x / 2 + sp.sqrt(1 + x**2) / 4,
                      sp.exp(-x**2 / 4) * sp.cos(y) - y**3 / 10 + sp.tan(x / 4)
                      + (2 + sp.sin(x))**sp.Rational(3, 2) / 8], [x, y])
    w = mp.live.phase_portrait(s, (-2, 2), (-2, 2), particles=1000, play=False, overlays=False)
    _page(driver, tmp_path, w, "elementary")
    seeds = _states(driver, "seeds").reshape(-1, 2)
    driver.execute_script("window.mechpyLive.step(100)")
    _close(_states(driver, "particles").reshape(-1, 2), lambda t, z: s.rhs(t, z.T).T, 0.0,
           seeds, 0.01, 100, "elementary functions")
