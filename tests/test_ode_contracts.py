"""The engine's inline contracts, compiled as C (-Wall -Wextra -Werror) and
called directly: control.h's decisions about impacts and actions at the
boundaries their contracts state, and lu.h's solves with LAPACK's factors
against NumPy's solve.

A solve reaches these only through a trajectory, where an exact boundary (a
bounce whose height is the tolerance, a gap equal to the time resolution) is
never hit on purpose: here each contract's inequality is put on its edge and
just past it, and the values are the closed forms of the contracts' text
(the flights' sum 2 rho / (|a| (1 - e)) of a constant acceleration).  The
solves run inside Newton iterations, which converge (more slowly) with a
wrong linear solve: here each is checked on its own.
"""
from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mechpy.symbolic import build

ROOT = Path(os.environ.get("MECHPY_SOURCE_DIR") or Path(__file__).resolve().parents[1])
CONTROL = ROOT / "csrc" / "ode" / "control.h"

pytestmark = pytest.mark.skipif(not CONTROL.is_file(), reason="needs the source tree (csrc/)")

EPS = float(np.finfo(float).eps)
ZENO = 1e-12            # MP_ODE_ZENO_FRAC, read back from the header below

_MAIN = r"""
#include <stdio.h>
#include "ode/control.h"

/* each line of stdin: a function's name and its arguments; each line out:
 * the result (and the output argument) printed exactly */
int main(void)
{
    char fn[32];
    double a[8];
    printf("zeno %.17g\n", MP_ODE_ZENO_FRAC);
    while (scanf("%31s", fn) == 1) {
        if (fn[0] == 'r') {                 /* rests t t_start rho a e x xtol */
            double t_left = -1.0;
            for (int i = 0; i < 7; i++) if (scanf("%lf", &a[i]) != 1) return 2;
            int r = mp_ode_impact_rests(a[0], a[1], a[2], a[3], a[4], a[5], a[6], &t_left);
            printf("%d %.17g\n", r, t_left);
        } else if (fn[0] == 'g') {          /* gap t t_prev n_prev t_start h */
            double gap = -1.0;
            for (int i = 0; i < 5; i++) if (scanf("%lf", &a[i]) != 1) return 2;
            int r = mp_ode_action_gap(a[0], a[1], (long)a[2], a[3], a[4], &gap);
            printf("%d %.17g\n", r, gap);
        } else if (fn[0] == 'e') {          /* resolution t t_start */
            for (int i = 0; i < 2; i++) if (scanf("%lf", &a[i]) != 1) return 2;
            printf("%.17g\n", mp_ode_time_resolution(a[0], a[1]));
        } else {
            return 3;
        }
    }
    return 0;
}
"""


def _harness(tmp_path_factory, name: str, source: str):
    """A program of ``source`` compiled against csrc/ (-Wall -Wextra -Werror):
    run(text) -> its standard output for ``text`` on its standard input."""
    if not build.have_compiler():
        pytest.skip("no C compiler")
    d = tmp_path_factory.mktemp(name)
    src, exe = d / f"{name}.c", d / name
    src.write_text(source)
    subprocess.run(build.compiler() + ["-std=c11", "-O1", "-fopenmp-simd", "-Wall", "-Wextra",
                                       "-Werror", f"-I{ROOT / 'csrc'}", str(src), "-o", str(exe),
                                       "-lm"], check=True, capture_output=True)
    return lambda text: subprocess.run([str(exe)], input=text, check=True, capture_output=True,
                                       text=True).stdout


@pytest.fixture(scope="module")
def control(tmp_path_factory):
    """call(lines) -> the harness's output lines for the given input lines."""
    run = _harness(tmp_path_factory, "control", _MAIN)

    def call(lines):
        out = run("\n".join(lines) + "\n").split("\n")
        assert float(out[0].split()[1]) == ZENO
        return [ln.split() for ln in out[1:] if ln]
    return call


def _rests(call, *cases):
    out = call(["r " + " ".join(repr(float(v)) for v in c) for c in cases])
    return [(int(r), float(tl)) for r, tl in out]


def test_impact_rests_on_the_edges_of_its_contract(control):
    # (t, t_start, rho, a, e, x, xtol): rho, a side-signed; a < 0 pushes back
    h = 1.0       # rho^2 / (-2 a) with rho = 1, a = -0.5: the next flight's height, exact
    cases = [
        (5.0, 0.0, 1.0, -0.5, 0.5, 0.0, h),                      # height == xtol: within
        (5.0, 0.0, 1.0, -0.5, 0.5, 0.0, np.nextafter(h, 0.0)),   # one ulp above it: flies
        (5.0, 0.0, 1.0, -0.5, 0.5, 2.0 ** 60, 0.0),              # within 16 ulps of x: 4096
        (5.0, 0.0, 0.0, -0.5, 0.5, 0.0, 0.0),                    # rho = 0: rests at once
        (5.0, 0.0, 1.0, 0.0, 0.5, 0.0, 10.0),                    # a = 0: never
        (5.0, 0.0, 1.0, 0.5, 0.5, 0.0, 10.0),                    # pulled away: never
        (5.0, 0.0, 1.0, -0.5, 1.0, 0.0, 10.0),                   # elastic: never
        (5.0, 0.0, -1.0, -0.5, 0.5, 0.0, 10.0),                  # arriving, not leaving: no
        (5.0, 0.0, 1.0, -0.5, float("nan"), 0.0, 10.0),          # e = nan: not < 1: no
    ]
    got = _rests(control, *cases)
    assert [r for r, _ in got] == [1, 0, 1, 1, 0, 0, 0, 0, 0]
    # 16 ulps of x = 2^60 are 2^60 * 16 * 2^-52 = 4096: a height of 4096 exactly is
    # within, one just above it is not
    rho = np.sqrt(2 * 0.5 * 4096.0)                      # 64: height 4096
    edge = _rests(control, (5.0, 0.0, rho, -0.5, 0.5, 2.0 ** 60, 0.0),
                  (5.0, 0.0, np.nextafter(rho, 100.0), -0.5, 0.5, 2.0 ** 60, 0.0))
    assert [r for r, _ in edge] == [1, 0]
    # the time to the accumulation: the sum of the flights left, 2 rho / (|a| (1 - e))
    assert got[0][1] == 2 * 1.0 / (0.5 * 0.5)
    assert got[3][1] == 0.0


def test_impact_rests_when_the_flights_left_are_below_the_time_resolution(control):
    # all the flights left, 2 rho / (|a| (1 - e)), within the time resolution of
    # t: ZENO (t - t_start), or 64 ulps of t
    t, ts = 2.0 ** 40, 0.0
    res = max(ZENO * (t - ts), 64 * EPS * t)
    a, e = -1.0, 0.0
    rho = res * -a * (1 - e) / 2                     # t_left == res exactly (powers of 2 ...)
    got = _rests(control, (t, ts, rho, a, e, 0.0, 0.0),
                 (t, ts, 2 * rho, a, e, 0.0, 0.0))
    assert got[0][1] == 2 * rho / (-a * (1 - e))
    assert got[0][1] <= res < got[1][1]
    assert [r for r, _ in got] == [1, 0]


def test_time_resolution_and_action_gaps(control):
    out = control(["e 1000 0", "e 1 0.999999"])
    assert float(out[0][0]) == max(ZENO * 1000.0, 64 * EPS * 1000.0)
    assert float(out[1][0]) == 64 * EPS                  # the floor of 64 ulps of t = 1
    # (t, t_prev, n_prev, t_start, h): MP_OK, MP_EEVENT (within the root finder's
    # 8 ulps of |t| + |h| of the last action) or MP_TERMINATED (below the resolution)
    from mechpy import _core
    ok, again, zeno = _core.STATUS["MP_OK"], _core.STATUS["MP_EEVENT"], _core.STATUS["MP_TERMINATED"]
    t, h = 1.0, 0.5
    tol = 8 * EPS * (t + h)                              # 3 * 2^-50: the finder's
    res = 64 * EPS * t                # 2^-46: the time grid's (a solve started at t)
    assert tol < res
    lines = [f"g {t!r} {t - tol!r} 1 {t!r} {h!r}",         # gap == tol: fires again at once
             f"g {t!r} {t - res!r} 1 {t!r} {h!r}",         # gap == resolution: Zeno
             f"g {t!r} {t - 2 * res!r} 1 {t!r} {h!r}",     # beyond both: apply
             f"g {t!r} {t - tol!r} 0 {t!r} {h!r}"]         # no action before: apply
    out = control(lines)
    assert [int(r) for r, _ in out] == [again, zeno, ok, ok]
    assert [float(g) for _, g in out[:3]] == [tol, res, 2 * res]   # exact differences


# ------------------------------------------------------------------- lu.h

_LU_MAIN = r"""
#include <stdio.h>
#include <stdlib.h>
#include "ode/lu.h"

/* LAPACK's solves, called by mp_ode_getrs and mp_ode_zgetrs from
 * MP_ODE_LU_SMALL on: the sizes here are below it */
void dgetrs_(const char *t, const int *n, const int *r, const double *a, const int *la,
             const int *p, double *b, const int *lb, int *info)
{ (void)t; (void)n; (void)r; (void)a; (void)la; (void)p; (void)b; (void)lb; (void)info; abort(); }
void zgetrs_(const char *t, const int *n, const int *r, const double complex *a, const int *la,
             const int *p, double complex *b, const int *lb, int *info)
{ (void)t; (void)n; (void)r; (void)a; (void)la; (void)p; (void)b; (void)lb; (void)info; abort(); }

static int get(double *v, int m) { for (int i = 0; i < m; i++) if (scanf("%lf", v + i) != 1) return 0; return 1; }

/* stdin: kind (d dense, z dense complex, b band, c band complex), n, kl, ku,
 * the factors (column-major; complex as re, im), the 1-based pivots, b */
int main(void)
{
    char kind[4];
    int n, kl, ku;
    while (scanf("%3s %d %d %d", kind, &n, &kl, &ku) == 4) {
        int cplx = kind[0] == 'z' || kind[0] == 'c', band = kind[0] == 'b' || kind[0] == 'c';
        int ld = band ? 2 * kl + ku + 1 : n, w = cplx ? 2 : 1;
        double *F = malloc(sizeof(double) * (size_t)(ld * n * w)), *b = malloc(sizeof(double) * (size_t)(n * w));
        double *dinv = malloc(sizeof(double) * (size_t)(n * w));
        int *ipiv = malloc(sizeof(int) * (size_t)n);
        if (!F || !b || !dinv || !ipiv || !get(F, ld * n * w)) return 2;
        for (int i = 0; i < n; i++) if (scanf("%d", ipiv + i) != 1) return 2;
        if (!get(b, n * w)) return 2;
        if (kind[0] == 'd') mp_ode_getrs(n, F, ipiv, b);
        else if (kind[0] == 'z') mp_ode_zgetrs(n, (double complex *)F, ipiv, (double complex *)b);
        else if (kind[0] == 'b') {
            mp_ode_gbdinv(n, kl + ku, F, ld, dinv);
            mp_ode_gbtrs(n, kl, ku, F, ld, ipiv, dinv, b);
        } else {
            mp_ode_zgbdinv(n, kl + ku, (double complex *)F, ld, (double complex *)dinv);
            mp_ode_zgbtrs(n, kl, ku, (double complex *)F, ld, ipiv, (double complex *)dinv,
                          (double complex *)b);
        }
        for (int i = 0; i < n * w; i++) printf("%.17g ", b[i]);
        printf("\n");
        free(F); free(b); free(dinv); free(ipiv);
    }
    return 0;
}
"""


@pytest.fixture(scope="module")
def lu_solve(tmp_path_factory):
    """solve(kind, factors, ipiv 0-based, b, kl, ku) -> x from lu.h."""
    run = _harness(tmp_path_factory, "lu", _LU_MAIN)

    def solve(kind, F, ipiv, b, kl=0, ku=0):
        cplx = np.iscomplexobj(F)
        flat = lambda a: (np.column_stack([a.real, a.imag]).ravel() if cplx  # noqa: E731
                          else np.asarray(a, float))
        text = " ".join([kind, str(len(b)), str(kl), str(ku),
                         *map(repr, map(float, flat(np.asarray(F).T.ravel()))),
                         *(str(int(p) + 1) for p in ipiv), *map(repr, map(float, flat(b)))])
        x = np.array(run(text + "\n").split(), float)
        return x[0::2] + 1j * x[1::2] if cplx else x
    return solve


def _banded(rng, n, kl, ku, cplx):
    A = np.zeros((n, n), complex if cplx else float)
    for i in range(n):
        for j in range(max(0, i - kl), min(n, i + ku + 1)):
            A[i, j] = rng.standard_normal() + (1j * rng.standard_normal() if cplx else 0)
    ab = np.zeros((2 * kl + ku + 1, n), A.dtype)               # LAPACK's band storage
    for j in range(n):
        for i in range(max(0, j - ku), min(n, j + kl + 1)):
            ab[kl + ku + i - j, j] = A[i, j]
    return A, ab


@pytest.mark.parametrize("cplx", [False, True])
@pytest.mark.parametrize("n, kl, ku", [(1, 0, 0), (7, 2, 1), (12, 1, 3), (20, 3, 2), (9, 0, 2)])
def test_band_solves_with_lapacks_factors_equal_numpys_solve(lu_solve, n, kl, ku, cplx):
    from scipy.linalg import lapack
    rng = np.random.default_rng(52 + n)
    A, ab = _banded(rng, n, kl, ku, cplx)
    lu, piv, info = (lapack.zgbtrf if cplx else lapack.dgbtrf)(ab, kl, ku)
    assert info == 0
    b = rng.standard_normal(n) + (1j * rng.standard_normal(n) if cplx else 0)
    x = lu_solve("c" if cplx else "b", lu, piv, b, kl, ku)
    want = np.linalg.solve(A, b)
    # relative to cond(A) |x|: below 3.5e-17 measured over these cases (a
    # backward-stable solve's few ulps)
    assert np.abs(x - want).max() / (np.linalg.cond(A) * np.abs(want).max()) <= 3e-16


@pytest.mark.parametrize("cplx", [False, True])
@pytest.mark.parametrize("n", [1, 3, 8, 15])
def test_dense_solves_with_lapacks_factors_equal_numpys_solve(lu_solve, n, cplx):
    from scipy.linalg import lapack
    rng = np.random.default_rng(36 + n)
    A = rng.standard_normal((n, n)) + (1j * rng.standard_normal((n, n)) if cplx else 0)
    lu, piv, info = (lapack.zgetrf if cplx else lapack.dgetrf)(A)
    assert info == 0
    b = rng.standard_normal(n) + (1j * rng.standard_normal(n) if cplx else 0)
    if n > 1:
        b[n // 2] = 0.0                               # a zero entry: the skipped column
    x = lu_solve("z" if cplx else "d", lu, piv, b)
    want = np.linalg.solve(A, b)
    # relative to cond(A) |x|: below 3.5e-17 measured over these cases (a
    # backward-stable solve's few ulps)
    assert np.abs(x - want).max() / (np.linalg.cond(A) * np.abs(want).max()) <= 3e-16
