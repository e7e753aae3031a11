"""mechpy.live's printed fields and overlays (issue 51): powers of a negative base,
number constants, the hyperbolic functions and erf, overlays with the axes swapped
and with a pole in the view.  The pages run in headless Chromium (software WebGL2);
particles are checked against a float64 RK4 of the C right-hand side, function
values against SciPy, overlays against the field at each drawn point."""
import os
import sys

import numpy as np
import pytest
import scipy.special as ss
import sympy as sp
from sympy.codegen.cfunctions import hypot, log1p

import mechpy as mp
from mechpy.live import _field

sys.path.insert(0, os.path.dirname(__file__))
from live_browser import driver, network_requests, open_page  # noqa: E402,F401
from ref_ode import rk4_path  # noqa: E402
from test_live import _close, _states  # noqa: E402

X, Y, U, W, A = sp.symbols("x y u w a")


def _save_open(driver, tmp_path, w, name):
    path = w.save(tmp_path / f"{name}.html")
    open_page(driver, path)
    return path


def _values(driver, tmp_path, g1, g2, xlim, ylim, params=None, n=4000):
    """g1 and g2 as the page evaluates them at its seeds (x, y) over the view: the
    field (0, 0, g1, g2) with u = w = 0 and one RK4 step of dt = 6, so that u and w
    become 6 g (the stages agree: x and y do not move).  Returns the seeds, the GPU's
    (float32) g1 and g2, and the page's JavaScript (float64) g1 and g2."""
    s = mp.equations([sp.S(0), sp.S(0), g1, g2], [X, Y, U, W], params=params or {})
    w = mp.live.phase_portrait(s, xlim, ylim, particles=n, play=False, overlays=False,
                               dt=6.0, hidden=[(0, 0)] * 4)
    _save_open(driver, tmp_path, w, "values")
    seeds = _states(driver, "seeds").reshape(-1, 4)
    driver.execute_script("window.mechpyLive.step(1)")
    got = np.array(driver.execute_script("return Array.from(window.mechpyLive.particles())"),
                   dtype=float).reshape(-1, 4)
    js = np.array(driver.execute_script(
        "const L = window.mechpyLive; return arguments[0].map((s) => L.field(s));",
        seeds.tolist()), dtype=float)
    return seeds, got[:, 2] / 6, got[:, 3] / 6, js[:, 2], js[:, 3]


def _rel(got, ref):
    return np.max(np.abs(got - ref) / np.abs(ref))


# ---- 1. powers ---------------------------------------------------------------------
def test_powers_print_without_exp_log():
    """x**9, x**2.0 and x**(-12) print as exact integer powers, never exp(9 log x)."""
    s = mp.equations([Y, -X**9 + X**sp.Float(2.0) - X**-12], [X, Y])
    g = _field.glsl(_field.field_of(s))
    assert "mp_pow(" not in g and "mp_powi(s.x, 9)" in g and "mp_powi(s.x, 12)" in g
    assert "((s.x)*(s.x))" in g
    js = _field.javascript(_field.field_of(s))
    assert "Math.pow(s[0], 2)" in js and "2.0" not in js


def test_negative_base_particles_are_rk4(driver, tmp_path):
    """A field with x**9, x**2.0 and x**a (a = 3 on a slider) over a view half at x < 0:
    every particle against a float64 RK4 of the C right-hand side (before: NaN at x < 0)."""
    s = mp.equations([Y, -X**9 / 4 - Y * X**sp.Float(2.0) / 2 - X**A / 8], [X, Y],
                     params={"a": 3.0})
    w = mp.live.phase_portrait(s, (-1.3, 1.3), (-1.5, 1.5), particles=2000, play=False,
                               overlays=False)
    _save_open(driver, tmp_path, w, "powers")
    seeds = _states(driver, "seeds").reshape(-1, 2)
    assert (seeds[:, 0] < 0).mean() > 0.4
    driver.execute_script("window.mechpyLive.step(100)")
    got = _states(driver, "particles").reshape(-1, 2)
    assert np.isfinite(got).all()
    _close(got, lambda t, z: s.rhs(t, z.T).T, 0.0, seeds, 0.01, 100, "negative base")


def test_pow_of_a_negative_base_is_c_pow(driver, tmp_path):
    """x**(1/3) and x**a with a = 2.5 are NaN at x < 0 in the shader and in the page's
    JavaScript, as in C (which raises NonFiniteError there); x**a with a = -3 (a slider's
    integral value) keeps the sign (float32 relative error 2e-7 measured)."""
    seeds, g1, g2, j1, j2 = _values(driver, tmp_path, X**sp.Rational(1, 3), X**A,
                                    (-1.5, 1.5), (-1, 1), params={"a": 2.5})
    neg = seeds[:, 0] < 0
    s = mp.equations([Y, X**sp.Rational(1, 3)], [X, Y])
    with pytest.raises(mp.errors.NonFiniteError):
        s.rhs(0.0, np.array([-1.0, 0.0]))
    assert np.isnan(g1[neg]).all() and np.isnan(j1[neg]).all()
    assert np.isnan(g2[neg]).all() and np.isnan(j2[neg]).all()
    pos = ~neg & (seeds[:, 0] > 1e-3)
    assert _rel(g1[pos], np.cbrt(seeds[pos, 0])) < 2e-6
    assert _rel(g2[pos], seeds[pos, 0]**2.5) < 5e-6        # exp(2.5 log x): 1.0e-6
    assert _rel(j1[pos], np.cbrt(seeds[pos, 0])) < 1e-15
    seeds, g1, g2, j1, j2 = _values(driver, tmp_path, X**A, X**50, (-1.5, 1.5), (-1, 1),
                                    params={"a": -3.0})
    ok = np.abs(seeds[:, 0]) > 1e-2
    assert _rel(g1[ok], seeds[ok, 0]**-3.0) < 2e-6
    big = np.abs(seeds[:, 0]) > 0.3                       # x**50 a normal float32
    assert _rel(g2[big], seeds[big, 0]**50) < 1e-5        # (measured 2.2e-6)
    assert _rel(j1[ok], seeds[ok, 0]**-3.0) < 1e-15


# ---- 2. overlays with the axes swapped -------------------------------------------------
def test_overlays_follow_the_axes(driver, tmp_path):
    """Van der Pol shown as (v, x): every drawn nullcline point zeroes its component
    of the field (measured 7e-9: the points are rounded to 1e-9), the limit cycle's
    horizontal extent is v's and its vertical x's (the amplitude 2.0086)."""
    vdp = mp.scenes.VanDerPol(mu=1.0)
    w = mp.live.phase_portrait(vdp, (-6, 6), (-4, 4), axes=(1, 0), particles=200, play=False)
    _save_open(driver, tmp_path, w, "swapped")
    ov = driver.execute_script("return window.mechpyLive.overlays()")
    assert {c["which"] for c in ov["nullclines"]} == {0, 1}
    for c in ov["nullclines"]:
        P = np.array(c["points"])
        F = vdp.rhs(0.0, np.stack([P[:, 1], P[:, 0]]))[c["which"]]   # state (x, v) = (vert, horiz)
        assert np.abs(F).max() < 1e-7, (c["which"], np.abs(F).max())
    period, amp = mp.phase.limit_cycle(vdp, [2.0, 0.0])
    on = mp.solve(vdp, (0, 40 * period), [2.0, 0.0], rtol=1e-11, atol=1e-12).y[:, -1]
    cyc = mp.solve(vdp, (0, period), on, rtol=1e-11, atol=1e-12,
                   t_eval=np.linspace(0, period, 2001)).y
    got = np.array(ov["limit_cycle"])
    assert got[:, 1].max() == pytest.approx(amp, abs=1e-4)              # vertical: x
    assert got[:, 0].max() == pytest.approx(cyc[1].max(), abs=1e-4)     # horizontal: v
    assert len(ov["fixed_points"]) == 1 and np.abs(ov["fixed_points"][0][:2]).max() < 1e-9


# ---- 3. number constants ----------------------------------------------------------------
def test_number_constants_give_a_page(driver, tmp_path):
    """EulerGamma, GoldenRatio, Catalan, TribonacciConstant (and pi, E) print as float
    literals: the page loads and its particles and its JavaScript are the C field's."""
    consts = [sp.EulerGamma, sp.GoldenRatio, sp.Catalan, sp.TribonacciConstant, sp.pi, sp.E]
    s = mp.equations([Y * consts[0] / 2 + consts[1] / 10,
                      -X * consts[2] - Y * consts[3] / 5 + consts[4] / 10 - consts[5] / 10],
                     [X, Y])
    w = mp.live.phase_portrait(s, (-2, 2), (-2, 2), particles=1000, play=False, overlays=False)
    for c in ("EulerGamma", "GoldenRatio", "Catalan", "Tribonacci", "Math.PI", "Math.E"):
        assert c not in w.spec["js"] and c not in w.spec["glsl"]
    _save_open(driver, tmp_path, w, "constants")
    seeds = _states(driver, "seeds").reshape(-1, 2)
    js = np.array(driver.execute_script(
        "const L = window.mechpyLive; return arguments[0].map((s) => L.field(s));",
        seeds[:50].tolist()))
    np.testing.assert_allclose(js, s.rhs(0.0, seeds[:50].T).T, rtol=1e-15, atol=1e-15)
    driver.execute_script("window.mechpyLive.step(100)")
    _close(_states(driver, "particles").reshape(-1, 2), lambda t, z: s.rhs(t, z.T).T, 0.0,
           seeds, 0.01, 100, "constants")


def test_save_refuses_invalid_printed_code(tmp_path):
    """A page whose printed field could not run is never written: save raises."""
    w = mp.live.phase_portrait(mp.scenes.VanDerPol(), (-1, 1), (-1, 1), overlays=False)
    # what the printer of SymPy's own JavaScript wrote for EulerGamma
    w.spec = dict(w.spec, js="return [s[1], var EulerGamma = 0.57721566490153286;\n"
                             "EulerGamma*s[0]];")
    with pytest.raises(ValueError, match="JavaScript"):
        w.save(tmp_path / "bad.html")
    assert not (tmp_path / "bad.html").exists()
    for bad in ("return [s[1], EulerGamma*s[0]];", "return [s[1], (s[0]];",
                "return [s[1], s[0]]; alert(1);"):
        with pytest.raises(ValueError, match="JavaScript"):
            _field.check_code(bad, "javascript")
    with pytest.raises(ValueError, match="GLSL.*tanh"):
        _field.check_code("f.x = tanh(s.y);", "glsl")


# ---- 4. hyperbolic functions, erf, erfc -----------------------------------------------------
def test_smooth_friction_particles_and_path(driver, tmp_path):
    """x'' = -x - tanh(x'/0.3) + the other seven functions: particles against the
    float64 RK4 of the C field, a dropped trajectory (the page's double-precision RK4)
    against mp.solve."""
    s = mp.equations([Y, -X - sp.tanh(Y / sp.Float(0.3)) + sp.sinh(X) / 4 - sp.cosh(Y) / 8
                      + sp.asinh(X) / 5 + sp.acosh(2 + X**2) / 6 + sp.atanh(Y / 3) / 3
                      + sp.erf(X) / 2 - sp.erfc(Y) / 4], [X, Y])
    w = mp.live.phase_portrait(s, (-2, 2), (-2, 2), particles=2000, play=False,
                               overlays=False, path_steps=400)
    _save_open(driver, tmp_path, w, "friction")
    seeds = _states(driver, "seeds").reshape(-1, 2)
    driver.execute_script("window.mechpyLive.step(100)")
    _close(_states(driver, "particles").reshape(-1, 2), lambda t, z: s.rhs(t, z.T).T, 0.0,
           seeds, 0.01, 100, "smooth friction")
    driver.execute_script("return window.mechpyLive.dropPath(1.0, 0.5)")
    path = np.array(driver.execute_script("return window.mechpyLive.paths()[0]"))
    ref = mp.solve(s, (0, 4.0), [1.0, 0.5], rtol=1e-12, atol=1e-12, t_eval=[2.0, 4.0]).y.T
    np.testing.assert_allclose(path[[200, 400]], ref, atol=1e-8)
    assert network_requests(driver) == []


@pytest.mark.parametrize("g1, g2, xlim, ylim, r1, r2", [
    (sp.tanh(X), sp.sinh(Y), (-10, 10), (-1.2, 1.2), np.tanh, np.sinh),
    (sp.cosh(X), sp.asinh(Y), (-20, 20), (-1, 1), np.cosh, np.arcsinh),
    (sp.acosh(X), sp.atanh(Y), (1, 3), (-1, 1), np.arccosh, np.arctanh),
    (sp.asinh(X), sp.acosh(Y), (-1e-3, 1e-3), (1, 6000), np.arcsinh, np.arccosh),
    (sp.erf(X), sp.erfc(Y), (-4, 4), (-2, 9), ss.erf, ss.erfc),
    (sp.erf(X), sp.erfc(Y), (-0.5, 0.5), (0.3, 2.5), ss.erf, ss.erfc),
], ids=["tanh-sinh", "cosh-asinh", "acosh-atanh", "small-large", "erf-erfc", "erf-erfc-mid"])
def test_function_values(driver, tmp_path, g1, g2, xlim, ylim, r1, r2):
    """The page's float32 functions (its own, from mp_exp and mp_log: GLSL leaves the
    built-ins' precision open) within 7e-7 relative of SciPy at float64 (measured
    1.6e-7 to 5.2e-7, three roundings of the RK4 sum included), its JavaScript's within
    4e-15 (Math.*, and the page's erf) and erfc within 1e-12 (1 - erf below 2: 1.3e-13
    measured at 2)."""
    seeds, a, b, ja, jb = _values(driver, tmp_path, g1, g2, xlim, ylim)
    ra, rb = r1(seeds[:, 0]), r2(seeds[:, 1])
    assert _rel(a, ra) < 7e-7 and _rel(b, rb) < 7e-7
    assert _rel(ja, ra) < 4e-15
    assert _rel(jb, rb) < (1e-12 if g2.func == sp.erfc else 4e-15)


def test_unprintable_function_is_a_clear_error():
    """log1p and hypot compile in C but a page has neither: a ValueError names them and
    what a page evaluates (before: SymPy's PrintMethodNotImplementedError)."""
    s = mp.equations([log1p(X**2), hypot(X, Y)], [X, Y])
    with pytest.raises(ValueError, match=r"hypot.*log1p.*live page.*tanh.*erf"):
        mp.live.phase_portrait(s, (-1, 1), (-1, 1))


# ---- 5. a pole in the view --------------------------------------------------------------------
@pytest.mark.parametrize("rhs, xlim", [(-1 / X**2, (-2, 2)), (-1 / X, (-2, 2.1))],
                         ids=["on-grid", "off-grid"])
def test_overlays_skip_a_pole(driver, tmp_path, rhs, xlim):
    """x'' = -1/x**2 (the pole on the nullcline grid) and x'' = -1/x (between its
    points, where the field changes sign with no zero): the portrait is drawn (before:
    NonFiniteError), x''s nullcline v = 0 is there, and no drawn point is a pole."""
    s = mp.equations([Y, rhs], [X, Y])
    w = mp.live.phase_portrait(s, xlim, (-2, 2), particles=200, play=False)
    _save_open(driver, tmp_path, w, "pole")
    ov = driver.execute_script("return window.mechpyLive.overlays()")
    assert ov["fixed_points"] == [] and ov["limit_cycle"] == []
    assert [c["which"] for c in ov["nullclines"]] and all(c["which"] == 0
                                                         for c in ov["nullclines"])
    P = np.concatenate([np.array(c["points"]) for c in ov["nullclines"]])
    assert np.abs(P[:, 1]).max() == 0.0 and np.abs(P[:, 0]).min() > 0
    assert P[:, 0].min() == xlim[0] and P[:, 0].max() == xlim[1]


def test_portrait_arguments_are_named_when_malformed():
    """params as a list (not {name: (min, max)}) raised AttributeError; a hidden entry
    that is not a pair raised 'too many values to unpack'."""
    vdp = mp.scenes.VanDerPol(1.0)
    with pytest.raises(TypeError, match=r"params must be a dict \{name: \(min, max\)\}"):
        mp.live.phase_portrait(vdp, (-3, 3), (-3, 3), params=["mu"], overlays=False)
    kep = mp.scenes.Kepler()
    with pytest.raises(TypeError, match=r"hidden\[1\] must be a pair \(min, max\)"):
        mp.live.phase_portrait(kep, (-2, 2), (-2, 2), hidden=[(0, 1), (0, 1, 2), (0, 0), (0, 0)],
                               overlays=False)


# ---- 6. issue 52: behaviours a mutation audit of phase.js found unpinned ----------------------
def test_shader_sin_cos_of_large_arguments(driver, tmp_path):
    """The shader's own float32 sin and cos (mp_sincos: Cody-Waite reduction by pi/4 in
    three terms, 0.78515625 + 2.4187564849853515625e-4 + 3.77489497744594108e-8) at
    |x| up to 10^4, read from the GPU's particles (float32, one RK4 step of dt = 6 of
    the field (0, 0, sin x, cos y)) against NumPy's float64 sin and cos of the same
    float32 seeds.  Measured: 1.3e-7 absolute at most (the RK4 sum's roundings included;
    the page's JavaScript, Math.sin and Math.cos in float64, exact).  Dropping the
    reduction's third term (y 3.8e-8, y up to 1.27e4) measured 4.8e-4, the second 2.0.
    """
    seeds, s, c, js, jc = _values(driver, tmp_path, sp.sin(X), sp.cos(Y), (-1e4, 1e4),
                                  (-1e4, 1e4))
    assert np.abs(seeds).max() > 9.9e3
    rs, rc = np.sin(seeds[:, 0]), np.cos(seeds[:, 1])
    assert np.abs(s - rs).max() < 1.3e-6 and np.abs(c - rc).max() < 1.3e-6
    assert np.abs(js - rs).max() < 1e-15 and np.abs(jc - rc).max() < 1e-15   # Math.sin, cos




def test_clicked_trajectory_starts_at_the_page_time(driver, tmp_path):
    """A click on a saved page whose field depends on t (a driven, damped pendulum,
    theta'' = -(g/L) sin theta - b theta' + A cos(Omega t)) opened at t0 = 1.3 and
    stepped 37 times (page time 1.67): the dropped trajectory (the page's float64 RK4)
    starts at the page's time, not at 0 nor at t0.  Its first 100 steps against a
    float64 NumPy RK4 of the pendulum from the clicked state at the page's time:
    measured equal to the last bit (bound 1e-14); started at t = 0 the path is off by
    4.2 rad/s, started at t0 by 1.6 (measured).  (A page with a kernel asks
    mp.solve with t0 = the page's time instead: not exercised by a saved page.)"""
    g, L, b, A, Om = 9.81, 1.0, 0.3, 6.0, 2.5
    pend = mp.scenes.Pendulum(g=g, length=L, damping=b, drive_amplitude=A, drive_frequency=Om)
    w = mp.live.phase_portrait(pend, (-3, 3), (-4, 4), particles=100, play=False,
                               t0=1.3, dt=0.01, path_steps=100)
    _save_open(driver, tmp_path, w, "driven")
    t_page = driver.execute_script("return window.mechpyLive.step(37)")
    assert t_page == pytest.approx(1.67, abs=1e-12)
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    over = driver.find_elements(By.CSS_SELECTOR, ".mechpy-phase canvas")[1]
    ActionChains(driver).move_to_element_with_offset(over, 90, -60).click().perform()
    driver.execute_script("return 0")          # the click's (async) dropPath has run
    paths = driver.execute_script("return window.mechpyLive.paths()")
    assert len(paths) == 1
    path = np.array(paths[0])
    x0 = np.array(path[0])
    assert x0 == pytest.approx([90 / 720 * 6, 60 / 480 * 8], abs=0.02)   # the pixel clicked
    assert len(path) == 101 and driver.execute_script("return window.mechpyLive.time()") == t_page

    def f(t, y):
        return np.array([y[1], -g / L * np.sin(y[0]) - b * y[1] + A * np.cos(Om * t)])
    ref = rk4_path(f, t_page, x0, 0.01, 100)
    np.testing.assert_allclose(path, ref, rtol=0, atol=1e-14)


def test_drop_takes_its_closed_interval():
    """drop, the fraction of particles re-seeded per update, lies in [0, 1]: both ends
    accepted (0: none re-seeded; 1: all), a value beyond either refused, naming it."""
    s = mp.equations([Y, -X], [X, Y])
    for drop in (0.0, 1.0):
        w = mp.live.phase_portrait(s, (-1, 1), (-1, 1), particles=16, drop=drop,
                                   overlays=False, play=False)
        assert w.spec["drop"] == drop
    for drop in (-1e-12, 1.0 + 1e-12):
        with pytest.raises(ValueError, match=r"drop must lie in \[0, 1\]"):
            mp.live.phase_portrait(s, (-1, 1), (-1, 1), particles=16, drop=drop,
                                   overlays=False, play=False)


def test_piecewise_otherwise_branch_in_the_page(driver, tmp_path):
    """A Piecewise's last branch (condition True) is its value, in the page's
    JavaScript and its shader: g1 = x for x > 0 else -2 x, g2 = y^2 for y < 0.5 else
    3 - y, against numpy's where (float64 to 4e-15, float32 to 7e-7 as
    test_function_values)."""
    g1 = sp.Piecewise((X, X > 0), (-2 * X, True))
    g2 = sp.Piecewise((Y**2, Y < 0.5), (3 - Y, True))
    seeds, a, b, ja, jb = _values(driver, tmp_path, g1, g2, (-1, 1), (-1, 2))
    x, y = seeds[:, 0], seeds[:, 1]
    ra, rb = np.where(x > 0, x, -2 * x), np.where(y < 0.5, y**2, 3 - y)
    assert (x < 0).sum() > 100 and (y >= 0.5).sum() > 100      # both branches seen
    keep_a, keep_b = ra != 0, rb != 0
    assert _rel(a[keep_a], ra[keep_a]) < 7e-7 and _rel(b[keep_b], rb[keep_b]) < 7e-7
    assert _rel(ja[keep_a], ra[keep_a]) < 4e-15 and _rel(jb[keep_b], rb[keep_b]) < 4e-15


def test_the_largest_int32_power_keeps_a_negative_base_sign(driver, tmp_path):
    """An integer exponent up to 2^31 - 1 (int32's largest, odd) is a power by repeated
    squaring in the shader, which keeps a negative base's sign: a^(2^31 - 1) = -1 and
    a^(2^31 - 2) = 1 at a = -1 (exact; float32 would round the exponent 2^31 - 1 to the
    even 2^31), in the shader and the page's JavaScript."""
    n = 2**31 - 1
    seeds, a, b, ja, jb = _values(driver, tmp_path, A**n, A**(n - 1), (-1, 1), (-1, 1),
                                  params={"a": -1.0}, n=16)
    assert np.all(a == -1.0) and np.all(b == 1.0)
    assert np.all(ja == -1.0) and np.all(jb == 1.0)
