"""The stiff problems of the IVP test set (Mazzia and Magherini, release 2.4):
HIRES, OREGO, ROBER, VDPOL (mu = 1000, the plain form on [0, 2000]) and E5,
against the test set's published end values, with absolute tolerances below the
components that matter and the analytic Jacobians.

* radau beside SciPy's Radau (the same Radau IIA, radau with RADAU5's economy):
  Jacobians and LU factorisations fall by a measured factor, the end values
  within the asked tolerance, at rtol 1e-6, 1e-8 and 1e-10;
* every stiff row (radau, auto, gsl:msbdf, gsl:bsimp and SciPy's names) solves
  each problem to a bound set from what it measures;
* `auto` beside LSODA over rtol 1e-4 ... 1e-10: error and nfev, and auto
  against its own stiff method.

Errors are ``relative_error``: relative where a component is well above its
absolute tolerance, in units of 10 atol where it is not.  Run as a script
(`python tests/test_stiff_set.py`) to print the tables.
"""
import functools
import os

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechpy as mp
from ref_problems import relative_error, stiff_set

PROBLEMS = {p.name: p for p in stiff_set()}
NAMES = list(PROBLEMS)
SWEEP = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]
# SciPy's LSODA (f2py ODEPACK) leaves references behind that LeakSanitizer
# reports with no mechpy code involved: skipped under the sanitizers
SCIPY_LSODA_LEAKS = pytest.mark.skipif(bool(os.environ.get("MECHPY_SANITIZED")),
                                       reason="SciPy's LSODA leaks references under LSan")


@functools.lru_cache(maxsize=None)
def run(name, impl, method, rtol, scene=False):
    """(error, nfev, njev, success) of one solve; impl is 'mp' or 'sp'."""
    P = PROBLEMS[name]
    system = P.scene() if scene else P.f
    if impl == "mp":
        s = mp.solve(system, (P.t0, P.tf), P.y0, method=method, rtol=rtol, atol=P.atol,
                     jac=None if scene else P.jac)
    else:
        s = solve_ivp(P.f, (P.t0, P.tf), P.y0, method=method, rtol=rtol, atol=P.atol,
                      jac=P.jac)
    err = relative_error(s.y[:, -1], P.ref, P.atol) if s.success else np.inf
    return err, int(s.nfev), int(s.njev), bool(s.success)


# ---- radau beside SciPy's Radau: RADAU5's economy -------------------------------------

@functools.lru_cache(maxsize=None)
def work(name, impl, method, rtol):
    """(error, nfev, njev, nlu, success) of one solve with the analytic Jacobian."""
    P = PROBLEMS[name]
    solver = mp.solve if impl == "mp" else solve_ivp
    s = solver(P.f, (P.t0, P.tf), P.y0, method=method, rtol=rtol, atol=P.atol, jac=P.jac)
    err = relative_error(s.y[:, -1], P.ref, P.atol) if s.success else np.inf
    return err, int(s.nfev), int(s.njev), int(s.nlu), bool(s.success)


# radau is SciPy's Radau IIA (5) with RADAU5's economy (csrc/ode/radau.c): the
# Jacobian kept while Newton contracts by theta <= 0.1, RADAU5's Newton loop
# (one pass may do) and its tolerance transformation at most 3 rtol.  SciPy's
# Radau refreshes J after every step whose Newton needed more than two passes
# at a rate above 1e-3 (radau did the same before: njev within 1%).
# Measured SciPy's / radau's njev at rtol 1e-8 (1e-10): HIRES 3.6 (7.5), OREGO
# 4.3 (4.5), ROBER 16 (39), VDPOL 6.9 (8.5); nlu: HIRES 3.4 (5.6), OREGO 4.3
# (4.0), ROBER 4.4 (9.1), VDPOL 5.4 (5.8); nfev 1.00 ... 1.55x SciPy's (the
# Newton iterations with a kept Jacobian); the end errors against the published
# values 0.007 ... 0.13 rtol (0.07 ... 1.6 rtol).
ECONOMY = {  # (njev factor, nlu factor) asked at both rtols: about half the least measured
    "HIRES": (1.8, 1.7), "OREGO": (2.1, 2.0), "ROBER": (8.0, 2.2), "VDPOL": (3.4, 2.7)}


@pytest.mark.slow
@pytest.mark.parametrize("rtol", [1e-8, 1e-10])
@pytest.mark.parametrize("name", [n for n in NAMES if n != "E5"])
def test_radau_jacobian_economy(name, rtol):
    e_m, n_m, j_m, lu_m, ok_m = work(name, "mp", "radau", rtol)
    e_s, n_s, j_s, lu_s, ok_s = work(name, "sp", "Radau", rtol)
    assert ok_m and ok_s
    fj, flu = ECONOMY[name]
    assert j_m * fj <= j_s, (j_m, j_s)
    assert lu_m * flu <= lu_s, (lu_m, lu_s)
    assert n_m <= 2 * n_s, (n_m, n_s)
    # the end values against the published ones: at 1e-8 within the asked
    # tolerance (measured up to 0.13 rtol); at 1e-10, where the test set's atol
    # (1e-11 on HIRES' components of 1e-3) limits, measured up to 1.6 rtol
    assert e_m <= (1 if rtol == 1e-8 else 10) * rtol, e_m


def test_radau_beside_scipy_radau_loose():
    # at rtol 1e-6 both meet the tolerance on the five problems (E5 at its
    # atol-limited 1e-3; radau's errors measured 0.004 ... 0.14 rtol), radau with
    # 2.3 ... 6.0x fewer Jacobians
    for name in NAMES:
        e_m, n_m, j_m, lu_m, ok_m = work(name, "mp", "radau", 1e-6)
        e_s, n_s, j_s, lu_s, ok_s = work(name, "sp", "Radau", 1e-6)
        assert ok_m and ok_s
        assert 2 * j_m <= j_s, (name, j_m, j_s)
        assert n_m <= 1.5 * n_s, (name, n_m, n_s)
        if name != "E5":
            assert e_m <= 1e-6, (name, e_m)


# ---- a large system: the 1-D Brusselator, n = 200 ----------------------------------------

BRUSS_N = 100  # grid points: n = 200 states (u_1, v_1, u_2, v_2, ...)


def _bruss(t, y):
    """Hairer & Wanner's 1-D Brusselator (Solving ODEs II, IV.10): a = 1/50, u = 1
    and v = 3 at both ends."""
    u, v = y[0::2], y[1::2]
    c = (BRUSS_N + 1) ** 2 / 50.0
    up = np.concatenate(([1.0], u, [1.0]))
    vp = np.concatenate(([3.0], v, [3.0]))
    f = np.empty_like(y)
    f[0::2] = 1 + u * u * v - 4 * u + c * (up[:-2] - 2 * u + up[2:])
    f[1::2] = 3 * u - u * u * v + c * (vp[:-2] - 2 * v + vp[2:])
    return f


def _bruss_jac(t, y):
    u, v = y[0::2], y[1::2]
    c = (BRUSS_N + 1) ** 2 / 50.0
    n = y.size
    J = np.zeros((n, n))
    iu, iv = np.arange(0, n, 2), np.arange(1, n, 2)
    J[iu, iu] = 2 * u * v - 4 - 2 * c
    J[iu, iv] = u * u
    J[iv, iu] = 3 - 2 * u * v
    J[iv, iv] = -u * u - 2 * c
    for i in (iu, iv):  # the diffusion couples a component to its neighbours
        J[i[1:], i[:-1]] = c
        J[i[:-1], i[1:]] = c
    return J


def _bruss_y0():
    x = np.arange(1, BRUSS_N + 1) / (BRUSS_N + 1)
    y0 = np.empty(2 * BRUSS_N)
    y0[0::2] = 1 + np.sin(2 * np.pi * x)
    y0[1::2] = 3.0
    return y0


@pytest.mark.slow
def test_radau_large_system_economy():
    # n = 200 on [0, 10]: where the LU pair (a real and a complex 200 x 200) is
    # the cost.  Against SciPy's Radau at rtol 1e-10 (the reference) and at the
    # same rtol 1e-6: measured radau njev 2, nlu 35 against Radau's 20 and 88
    # (BDF's 2 and 41), the error 1.9e-8 against Radau's 8.7e-9 (BDF's 4.9e-6)
    y0 = _bruss_y0()
    assert np.allclose(_bruss_jac(0, y0 + 0.1) @ np.ones(200) * 1e-7,
                       _bruss(0, y0 + 0.1 + 1e-7) - _bruss(0, y0 + 0.1), rtol=1e-5, atol=1e-9)
    ref = solve_ivp(_bruss, (0, 10), y0, method="Radau", rtol=1e-10, atol=1e-12,
                    jac=_bruss_jac).y[:, -1]
    m = mp.solve(_bruss, (0, 10), y0, method="radau", rtol=1e-6, atol=1e-8, jac=_bruss_jac)
    s = solve_ivp(_bruss, (0, 10), y0, method="Radau", rtol=1e-6, atol=1e-8, jac=_bruss_jac)
    assert m.success and s.success
    err = np.max(np.abs(m.y[:, -1] - ref) / np.maximum(np.abs(ref), 1e-7))
    assert err < 2e-7, err
    assert 3 * m.njev <= s.njev, (m.njev, s.njev)
    assert 2 * m.nlu <= s.nlu, (m.nlu, s.nlu)


# ---- the CVODE bench's problems and driver ------------------------------------------------

def test_cvode_bench_problems_are_the_test_set():
    # mechpy/benches/stiff_cvode.py writes each problem once as SymPy equations,
    # compiled for radau and, as the same C, for CVODE: they are the test set's
    # right-hand sides and Jacobians (and the Brusselator this file's)
    from mechpy.benches import stiff_cvode
    pytest.importorskip("sympy")
    rng = np.random.default_rng(5)
    for name, eqs, y, y0, span, atol, ref in stiff_cvode.problems(n_bruss=BRUSS_N):
        try:
            scene = mp.equations(eqs, list(y))
        except mp.symbolic.CompileError:
            pytest.skip("no C compiler")
        if name in PROBLEMS:
            P, f, jac = PROBLEMS[name], PROBLEMS[name].f, PROBLEMS[name].jac
            assert np.array_equal(y0, P.y0) and span == (P.t0, P.tf)
            np.testing.assert_array_equal(ref, P.ref)
        else:
            f, jac = _bruss, _bruss_jac
            np.testing.assert_array_equal(y0, _bruss_y0())
        for _ in range(3):
            yy = np.asarray(y0) * (1 + 0.1 * rng.standard_normal(len(y0))) + 1e-3
            np.testing.assert_allclose(scene.rhs(0.0, yy), f(0.0, yy), rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(scene.jacobian(0.0, yy), jac(0.0, yy), rtol=1e-12,
                                       atol=1e-12)


def test_cvode_bench_driver_meets_the_published_values():
    # the driver compiled around the generated C: CVODE on ROBER at rtol 1e-8 ends
    # within its usual error of the published values (measured 6.6e-7 relative)
    from mechpy.benches import stiff_cvode
    why = stiff_cvode.cvode_missing()
    if why:
        pytest.skip(why)
    name, eqs, y, y0, span, atol, ref = stiff_cvode.problems(n_bruss=2)[0]
    assert name == "ROBER"
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        exe = stiff_cvode.cvode_driver(mp.equations(eqs, list(y)), d)
        st, nst, nfe, nje, nlu, sec, yend = stiff_cvode.cvode_solve(exe, 3, y0, atol, span,
                                                                    1e-8, repeats=1)
    assert st == 0 and 0 < nje <= nlu <= nst and nfe > nst and sec > 0
    assert relative_error(yend, PROBLEMS["ROBER"].ref, PROBLEMS["ROBER"].atol) < 1e-5


# ---- every stiff row against the published values --------------------------------------

# bounds at rtol 1e-6 on the relative error, about 10x the worst measured over
# the five problems (E5 apart: its y2, y3 ~ 50 atol, so every method stops at
# about 1e-3 relative there whatever rtol)
BOUNDS = {"radau": 1e-6, "auto": 1e-6, "gsl:msbdf": 5e-4, "gsl:bsimp": 1e-4,
          "Radau": 1e-6, "BDF": 5e-4, "LSODA": 2e-4}
# (gsl:bsimp: y2, y3 off by up to 150% at rtol 1e-6 with status 0, 6e-2 at 1e-4
# and 1e-8, 1e-3 only at 1e-10; GSL's own driver with its bsimp stepper and the
# same scaled control, in plain C, ends 30% off too: the stepper's, not the glue's;
# its bound is what a correct answer needs: that row is run at the documented rtol 1e-10)
E5_BOUNDS = {"radau": 1e-2, "auto": 1e-2, "gsl:msbdf": 1e-1, "gsl:bsimp": 1e-1,
             "Radau": 1e-2, "BDF": 1e-1, "LSODA": 1e-1}


@pytest.mark.parametrize("method", list(BOUNDS))
@pytest.mark.parametrize("name", NAMES)
def test_stiff_row_solves_test_set(name, method):
    if name == "E5" and method == "gsl:bsimp":
        # GSL's bsimp misjudges its error on E5's components of ~50 atol: 150%
        # off at rtol 1e-6 with status 0 (GSL's own driver in plain C: 30%),
        # 6e-2 at 1e-8.  mp.methods() documents it and the remedy, rtol 1e-10
        # (measured 1.1e-3, the atol-limited error every method ends at)
        assert "E5" in mp.methods.__doc__ and "gsl:bsimp" in mp.methods.__doc__
        err, nfev, njev, ok = run(name, "mp", method, 1e-10)
        assert ok
        assert err < E5_BOUNDS[method], err
        return
    err, nfev, njev, ok = run(name, "mp", method, 1e-6)
    assert ok
    bound = E5_BOUNDS[method] if name == "E5" else BOUNDS[method]
    assert err < bound, err


@pytest.mark.parametrize("method", ["radau", "auto"])
def test_vdpol_scene_matches_python_rhs(method):
    # mp.scenes.VanDerPol(mu=1000) is the test set's VDPOL: the C right-hand
    # side and analytic Jacobian give the Python path's answer and work
    e_c, n_c, _, ok_c = run("VDPOL", "mp", method, 1e-8, scene=True)
    e_p, n_p, _, ok_p = run("VDPOL", "mp", method, 1e-8)
    assert ok_c and ok_p
    assert e_c < 1e-8, e_c  # measured 2.5e-11 (radau), 6.8e-10 (auto)
    assert abs(n_c - n_p) <= 0.05 * n_p


# ---- auto beside LSODA ------------------------------------------------------------------

@SCIPY_LSODA_LEAKS
@pytest.mark.parametrize("name", NAMES)
def test_auto_at_least_as_accurate_as_lsoda(name):
    for rtol in SWEEP:
        e_a, n_a, _, ok_a = run(name, "mp", "auto", rtol)
        e_l, n_l, _, ok_l = run(name, "sp", "LSODA", rtol)
        assert ok_a and ok_l, rtol
        # auto's radau steps are order 5 with an error estimate of order 3:
        # measured 0.003 ... 0.5x LSODA's error at the same rtol
        assert e_a <= 3 * e_l, (rtol, e_a, e_l)


@pytest.mark.parametrize("name", NAMES)
def test_auto_costs_no_more_than_its_stiff_method(name):
    # LSODA's promise: switching never costs much more than the better method
    # alone.  auto's stiffness test (dop853's h|lambda| > 6.1 on 15 of the recent
    # steps) fires late when the step-size controller holds h just inside the
    # stability boundary: ROBER at rtol 1e-10 then spends 3,600 dop853 steps on
    # t in [0.01, 8] before switching, 67,235 evaluations against radau's 31,627
    for rtol in SWEEP:
        _, n_a, _, ok_a = run(name, "mp", "auto", rtol)
        _, n_r, _, ok_r = run(name, "mp", "radau", rtol)
        assert ok_a and ok_r
        # 25% and the 15 explicit steps (12 evaluations each) that detect stiffness
        assert n_a <= 1.25 * n_r + 15 * 12, (rtol, n_a, n_r)


# ---- the tables ---------------------------------------------------------------------------

def table_same_rtol(rtols=(1e-6, 1e-10)):
    cols = [("mp", "auto"), ("sp", "LSODA"), ("mp", "radau"), ("sp", "Radau"), ("sp", "BDF"),
            ("mp", "gsl:msbdf")]
    head = " | ".join(m for _, m in cols)
    lines = [f"| problem | rtol | {head} |", "| --- | --- |" + " --- |" * len(cols)]
    for name in NAMES:
        for rtol in rtols:
            cells = []
            for impl, m in cols:
                e, n, _, ok = run(name, impl, m, rtol)
                cells.append(f"{e:.1e} / {n}" if ok else "failed")
            lines.append(f"| {name} | {rtol:.0e} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def table_equal_error():
    """For each LSODA run, the cheapest auto (and radau) run of the sweep that is
    at least as accurate: nfev ratio at equal error."""
    lines = ["| problem | LSODA rtol | LSODA error / nfev | auto: rtol, error / nfev | ratio |",
             "| --- | --- | --- | --- | --- |"]
    for name in NAMES:
        if name == "E5":
            continue  # every method ends at the same atol-limited 1e-3
        for rtol in (1e-4, 1e-6, 1e-8, 1e-10):
            e_l, n_l, _, _ = run(name, "sp", "LSODA", rtol)
            best = None
            for r in [1e-2, 1e-3] + SWEEP:
                e, n, _, ok = run(name, "mp", "auto", r)
                if ok and e <= e_l and (best is None or n < best[2]):
                    best = (r, e, n)
            cell = f"{best[0]:.0e}, {best[1]:.1e} / {best[2]}" if best else "-"
            ratio = f"{best[2] / n_l:.2f}" if best else "-"
            lines.append(f"| {name} | {rtol:.0e} | {e_l:.1e} / {n_l} | {cell} | {ratio} |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(table_same_rtol())
    print()
    print(table_equal_error())


# ---- banded Jacobians (jac_sparsity): grouped differences, radau's band LU ----------

def _chain(M=30, k=1e4, c=0.5):
    """A damped chain of M unit masses between fixed ends, springs k, dampers c
    to ground, the state (x_1, v_1, x_2, v_2, ...): y' = A y, A banded (3 below,
    1 above).  (A, y0)."""
    n = 2 * M
    A = np.zeros((n, n))
    for i in range(M):
        A[2 * i, 2 * i + 1] = 1.0
        A[2 * i + 1, 2 * i] = -2 * k
        A[2 * i + 1, 2 * i + 1] = -c
        if i > 0:
            A[2 * i + 1, 2 * i - 2] = k
        if i < M - 1:
            A[2 * i + 1, 2 * i + 2] = k
    x = np.arange(1, M + 1) / (M + 1)
    y0 = np.zeros(n)
    y0[0::2] = np.sin(np.pi * x) + 0.3 * np.sin(7 * np.pi * x)
    return A, y0


@pytest.mark.parametrize("rtol", [1e-6, 1e-8])
def test_band_lu_radau_against_the_exact_linear_flow(rtol):
    # y(T) = expm(A T) y0 exactly.  At these steps the Newton matrix's columns
    # have their largest entry off the diagonal (2k = 2e4 against gamma/h ~ 2e3):
    # the band factors pivot.  Measured: band and dense LU both 2.7e-7 (rtol 1e-6)
    # and 7.6e-10 (1e-8) from the exact flow, with the same Jacobians and within
    # 2% of each other's steps; SciPy's Radau 8.2e-8 and 2.4e-10 with 1.9x the nfev
    import scipy.linalg
    A, y0 = _chain()
    T = 2.0
    exact = scipy.linalg.expm(A * T) @ y0

    def f(t, y):
        return A @ y

    band = mp.solve(f, (0, T), y0, method="radau", rtol=rtol, atol=1e-10, jac=A,
                    jac_sparsity=A != 0)
    dense = mp.solve(f, (0, T), y0, method="radau", rtol=rtol, atol=1e-10, jac=A)
    assert band.success and dense.success
    scale = np.max(np.abs(exact))
    e_band = np.max(np.abs(band.y[:, -1] - exact)) / scale
    e_dense = np.max(np.abs(dense.y[:, -1] - exact)) / scale
    bound = {1e-6: 3e-6, 1e-8: 8e-9}[rtol]
    assert e_band < bound and e_dense < bound, (e_band, e_dense)
    assert e_band < 1.2 * e_dense, (e_band, e_dense)
    assert abs(band.nsteps - dense.nsteps) <= 0.05 * dense.nsteps, (band.nsteps, dense.nsteps)


@pytest.mark.slow
def test_band_lu_radau_on_the_brusselator_against_scipy():
    # the nonlinear large system in band form (n = 200, ml = mu = 2) against SciPy's
    # Radau at rtol 1e-10; measured error 1.9e-8 at rtol 1e-6, as dense (the bound of
    # the dense test above), and the same Jacobians and LU factorisations within 3
    y0 = _bruss_y0()
    ref = solve_ivp(_bruss, (0, 10), y0, method="Radau", rtol=1e-10, atol=1e-12,
                    jac=_bruss_jac, jac_sparsity=_bruss_jac(0, y0) != 0).y[:, -1]
    pattern = _bruss_jac(0.0, y0 + 0.1) != 0
    m = mp.solve(_bruss, (0, 10), y0, method="radau", rtol=1e-6, atol=1e-8, jac=_bruss_jac,
                 jac_sparsity=pattern)
    d = mp.solve(_bruss, (0, 10), y0, method="radau", rtol=1e-6, atol=1e-8, jac=_bruss_jac)
    assert m.success and d.success
    err = np.max(np.abs(m.y[:, -1] - ref) / np.maximum(np.abs(ref), 1e-7))
    assert err < 2e-7, err
    assert m.njev == d.njev and abs(m.nlu - d.nlu) <= 3, (m.njev, d.njev, m.nlu, d.nlu)


def test_grouped_differences_are_the_dense_differences():
    # a banded f: each f_i reads y_{i-2} .. y_{i+2} only, so perturbing columns
    # five apart together changes each f_i exactly as perturbing its own column
    # alone: the Jacobian is the dense one to the bit, the solve identical, and
    # each Jacobian costs ml + mu + 1 = 5 evaluations instead of n = 12 (n below 16:
    # the LU stays dense, so only the differences differ)
    global BRUSS_N
    saved, BRUSS_N = BRUSS_N, 6
    try:
        x = np.arange(1, 7) / 7
        y0 = np.empty(12)
        y0[0::2], y0[1::2] = 1 + np.sin(2 * np.pi * x), 3.0
        pattern = _bruss_jac(0.0, y0 + 0.1) != 0
        for method in ("radau", "gsl:msbdf"):
            band = mp.solve(_bruss, (0, 10), y0, method=method, rtol=1e-6, atol=1e-8,
                            jac_sparsity=pattern)
            dense = mp.solve(_bruss, (0, 10), y0, method=method, rtol=1e-6, atol=1e-8)
            assert band.success and dense.success and band.njev > 0
            np.testing.assert_array_equal(band.y, dense.y)
            assert band.njev == dense.njev
            assert dense.nfev - band.nfev == (12 - 5) * band.njev, (method, band.nfev,
                                                                    dense.nfev, band.njev)
    finally:
        BRUSS_N = saved


def test_jac_sparsity_forms_and_refusals():
    import scipy.sparse
    A, y0 = _chain(M=10)
    n = A.shape[0]

    def f(t, y):
        return A @ y

    kw = dict(method="radau", rtol=1e-8, atol=1e-10)
    base = mp.solve(f, (0, 0.5), y0, **kw)
    # a pattern covering the matrix is the dense solve, to the bit; a scipy.sparse
    # pattern is its dense twin's band
    full = mp.solve(f, (0, 0.5), y0, jac_sparsity=np.ones((n, n)), **kw)
    np.testing.assert_array_equal(full.y, base.y)
    a = mp.solve(f, (0, 0.5), y0, jac_sparsity=A != 0, **kw)
    b = mp.solve(f, (0, 0.5), y0, jac_sparsity=scipy.sparse.csr_matrix(A), **kw)
    np.testing.assert_array_equal(a.y, b.y)
    assert a.nfev < base.nfev     # 5 evaluations a Jacobian, not 20
    np.testing.assert_allclose(a.y[:, -1], base.y[:, -1], rtol=0, atol=1e-7)
    with pytest.raises(ValueError, match=r"jac_sparsity must have shape \(20, 20\)"):
        mp.solve(f, (0, 0.5), y0, jac_sparsity=np.ones((n, n - 1)), **kw)
    with pytest.raises(ValueError, match=r"jac_sparsity must have shape \(20, 20\)"):
        mp.solve(f, (0, 0.5), y0, jac_sparsity=scipy.sparse.eye(n + 1), **kw)
    with pytest.raises(ValueError, match="jac_sparsity"):
        mp.solve(f, (0, 0.5), y0, jac_sparsity=np.full((n, n), np.nan), **kw)
    with pytest.raises(TypeError, match="jac_sparsity"):
        mp.solve(f, (0, 0.5), y0, jac_sparsity="band", **kw)
    # solve_many: each trajectory as solve runs it alone, with its band; a C rhs
    # (a compiled system) runs there with the GIL released, so the band is the core's
    Ys = np.array([y0, 0.5 * y0])
    e = mp.solve_many(f, (0, 0.5), Ys, jac_sparsity=A != 0, **kw)
    np.testing.assert_array_equal(e.y[0, :, -1], a.y[:, -1])
    assert e.nfev[0] == a.nfev
    with pytest.raises(ValueError, match="jac_sparsity"):
        mp.solve_many(f, (0, 0.5), Ys, jac_sparsity=np.ones((n, 2)), **kw)
    # the core refuses a band it cannot use (a system's own _jac_band reaches it
    # unchecked by Python): a value error, never a read out of bounds
    class Own:
        def __call__(self, t, y):
            return A @ y
    own = Own()
    for bad, what in [((n, 0), "< n"), ((0, 2**62), "< n"), ((-1, 1), ">= 0"),
                      ((1, 1, list(range(n - 1)) + [0]), "permutation"),
                      ((1, 1, [n] + list(range(1, n))), "permutation")]:
        own._jac_band = bad
        with pytest.raises(ValueError, match=what):
            mp.solve(own, (0, 0.5), y0, **kw)
    own._jac_band = (3, 1, list(range(n)))   # the chain's band in the identity order
    np.testing.assert_array_equal(mp.solve(own, (0, 0.5), y0, **kw).y, a.y)
    # a complex state: the real system's pattern, the band then spans it (dense)
    c = mp.solve(lambda t, y: -1j * y, (0, 1.0), [1.0 + 0j, 0.5j], method="radau",
                 rtol=1e-10, atol=1e-12, jac_sparsity=np.eye(2))
    np.testing.assert_allclose(c.y[:, -1], np.exp(-1j) * np.array([1.0, 0.5j]), atol=1e-9)


def test_compiled_equations_know_their_band():
    # the band comes from the symbolic Jacobian's zeros (SymPy's own jacobian here);
    # mp.solve then factorises in band form by itself: the same solution as the
    # forced dense form, to the Newton tolerance
    sp = pytest.importorskip("sympy")
    from mechpy.benches import stiff_cvode
    name, eqs, y, y0, span, atol, ref = stiff_cvode.problems(n_bruss=20)[-1]
    try:
        scene = mp.equations(eqs, list(y))
    except mp.symbolic.CompileError:
        pytest.skip("no C compiler")
    J = sp.Matrix(eqs).jacobian(list(y))
    i, j = np.nonzero(np.array([[J[r, c] != 0 for c in range(J.cols)] for r in range(J.rows)]))
    assert scene._jac_band == (int(max(i - j)), int(max(j - i))) == (2, 2)
    kw = dict(method="radau", rtol=1e-8, atol=atol, t_eval=[span[1]])
    band = mp.solve(scene, span, y0, **kw)
    dense = mp.solve(scene, span, y0, jac_sparsity=np.ones((40, 40)), **kw)
    assert band.success and dense.success
    np.testing.assert_allclose(band.y, dense.y, rtol=1e-8)
    many = mp.solve_many(scene, span, np.array([y0, y0]), method="radau", rtol=1e-8, atol=atol)
    np.testing.assert_array_equal(many.y[1, :, -1], band.y[:, -1])
    assert many.nfev[1] == band.nfev
    # a coupled system has no narrow band: dense, as before
    q = sp.symbols("q0:3")
    full = mp.equations([q[1] * q[2], -q[0] * q[2], q[0] * q[1]], list(q))
    assert full._jac_band is None


def test_band_in_a_bandwidth_reducing_order():
    # a chain written y = (q, v): its Jacobian [[0, I], [K, -c I]] has band n/2 in
    # that order, 2 + 2 in reverse Cuthill-McKee's (interleaving q and v), which
    # radau then factorises in, permuting each right-hand side.  Against the exact
    # flow: measured 4.8e-11 (band) and 3.7e-11 (dense) at rtol 1e-8; the grouped
    # differences cost 5 evaluations a Jacobian instead of 200, the Jacobian the
    # same to the bit (the whole solve then identical to the dense differences')
    import scipy.linalg
    from mechpy._validate import band_of_pattern
    M = 100
    n = 2 * M
    K = -2e4 * np.eye(M) + 1e4 * (np.eye(M, k=1) + np.eye(M, k=-1))
    A = np.block([[np.zeros((M, M)), np.eye(M)], [K, -30.0 * np.eye(M)]])
    x = np.arange(1, M + 1) / (M + 1)
    y0 = np.r_[np.sin(np.pi * x) + 0.3 * np.sin(7 * np.pi * x), np.zeros(M)]
    exact = scipy.linalg.expm(A) @ y0
    ml, mu, perm = band_of_pattern(*np.nonzero(A), n)
    assert (ml, mu) == (2, 2) and sorted(perm) == list(range(n))
    P = A[np.ix_(perm, perm)]
    i, j = np.nonzero(P)
    assert max(i - j) == 2 and max(j - i) == 2

    def f(t, y):
        return A @ y
    kw = dict(method="radau", rtol=1e-8, atol=1e-10)
    band = mp.solve(f, (0, 1.0), y0, jac=A, jac_sparsity=A != 0, **kw)
    assert band.success
    err = np.max(np.abs(band.y[:, -1] - exact)) / np.max(np.abs(exact))
    assert err < 5e-10, err
    fd_band = mp.solve(f, (0, 1.0), y0, jac_sparsity=A != 0, method="gsl:msbdf", rtol=1e-6,
                       atol=1e-8)
    fd_dense = mp.solve(f, (0, 1.0), y0, method="gsl:msbdf", rtol=1e-6, atol=1e-8)
    np.testing.assert_array_equal(fd_band.y, fd_dense.y)
    assert fd_dense.nfev - fd_band.nfev == (n - 5) * fd_band.njev > 0


def test_band_without_scipy_keeps_the_states_order(monkeypatch):
    # no SciPy to reorder: the own order's band, or dense when it is too wide
    import sys
    from mechpy._validate import band_of_pattern
    monkeypatch.setitem(sys.modules, "scipy.sparse.csgraph", None)
    M = 20
    A = np.eye(2 * M) + np.eye(2 * M, k=10) + np.eye(2 * M, k=-10)   # RCM: band 1 + 1
    assert band_of_pattern(*np.nonzero(A), 2 * M) == (10, 10)
    qv = np.block([[np.zeros((M, M)), np.eye(M)], [np.eye(M), np.eye(M)]])
    assert band_of_pattern(*np.nonzero(qv), 2 * M) is None        # band 2M - 1: dense
    full = np.ones((2 * M, 2 * M))
    assert band_of_pattern(*np.nonzero(full), 2 * M) is None
    tri = np.eye(2 * M) + np.eye(2 * M, k=1)
    assert band_of_pattern(*np.nonzero(tri), 2 * M) == (0, 1)
    # a band that spans the matrix (ml + mu + 1 = n) is dense
    assert band_of_pattern(*np.nonzero(np.tril(full)), 2 * M) is None


def test_band_reordering_is_tried_where_the_own_band_is_too_wide():
    # at n = 29 the own band 4 + 5 (width 10, 3 x 10 > 29) is too wide for radau's band
    # form: reverse Cuthill-McKee's order, the path 4 - 0 - 5, has band 1 + 1
    from mechpy._validate import band_of_pattern
    P = np.eye(29)
    P[0, 5] = P[4, 0] = 1.0
    b = band_of_pattern(*np.nonzero(P), 29)
    assert len(b) == 3 and b[0] + b[1] <= 2, b
    # a scipy.sparse pattern's stored entries count, explicit zeros too (as SciPy's)
    import scipy.sparse
    S = scipy.sparse.coo_matrix((np.r_[np.ones(29), 0.0], (np.r_[np.arange(29), 28],
                                                           np.r_[np.arange(29), 0])))
    from mechpy.integrate import _jac_band
    b = _jac_band(S, None, 29)     # the stored zero at (28, 0): reordered to band 1 + 0
    assert len(b) == 3 and b[0] + b[1] == 1, b


def test_band_lu_reads_only_the_band():
    # the band form reads the analytic Jacobian within the band alone (the documented
    # contract): entries added outside it change nothing, to the bit; dense, they
    # change the Newton matrix and so the iterates
    A, y0 = _chain()
    far = np.zeros_like(A)
    far[0, -1] = far[-1, 0] = 1e3

    def f(t, y):
        return A @ y
    kw = dict(method="radau", rtol=1e-8, atol=1e-10, jac_sparsity=A != 0)
    good = mp.solve(f, (0, 0.5), y0, jac=A, **kw)
    noisy = mp.solve(f, (0, 0.5), y0, jac=A + far, **kw)
    np.testing.assert_array_equal(noisy.y, good.y)
    dense = mp.solve(f, (0, 0.5), y0, jac=A + far, method="radau", rtol=1e-8, atol=1e-10)
    assert not np.array_equal(dense.y, good.y)
