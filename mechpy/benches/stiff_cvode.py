"""Bench: the stiff set against CVODE, both on the same C right-hand side.

ROBER, HIRES, VDPOL (mu = 1000) and OREGO of the IVP test set, and a large
system (the 1-D Brusselator of Hairer & Wanner, N = 100 grid points, n = 200
states: SymPy takes minutes over the 500-state one's Jacobian),
each written once as SymPy equations and compiled by ``mp.equations``: mechpy's
``radau`` and ``auto`` run that compiled scene, and CVODE (SUNDIALS' C API,
BDF, Newton with its dense linear solver and the analytic Jacobian) runs the
very same generated C (``scene.c_source``: ``mp_gen_rhs``, ``mp_gen_jac``)
in a small driver compiled here with the system's C compiler and the flags
mechpy compiles its systems with.  Same rtol and atol; each row gives njev,
nlu (CVODE: its linear-solver setups, each a new LU), nfev (CVODE: rhs
evaluations of the integrator), the time of a solve (median, CVODE's measured
inside the driver) and the error at the end against the published value (the
Brusselator's: radau at rtol 1e-12).  The Brusselator's Jacobian is banded
(ml = mu = 2, the states (u_1, v_1, u_2, ...)), a band its compiled scene
knows from the symbolic Jacobian: radau factorises it in band form, and
runs again dense (``jac_sparsity`` all ones); CVODE runs dense and with its
band matrix and solver (the same band), each form against its like.
Without SUNDIALS (Debian's
libsundials-dev) or a compiler the mechpy rows are still given and a row says
why CVODE is missing.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile

import numpy as np

import mechpy as mp
from mechpy._timing import median_time
from mechpy._validate import band_pays
from mechpy.benches.problems import HIRES, OREGO, ROBER, VDPOL

TITLE = "Stiff set: radau and auto against CVODE (SUNDIALS, C API) on one C right-hand side"
ORDER = 21


def problems(n_bruss: int = 100):
    """(name, equations, y0, (t0, tf), atol, reference or None) of each problem; the
    equations are SymPy expressions in the symbols ``y`` (a list).  The test set's
    are mechpy.benches.problems' (published end values), the Brusselator this file's."""
    import sympy as sp
    out = []
    for P in (ROBER, HIRES, VDPOL, OREGO):
        y = sp.symbols(f"y0:{P.n}")
        atol = np.array(P.atol) if isinstance(P.atol, tuple) else P.atol
        out.append((P.name, P.equations(y), y, list(P.y0), P.t_span, atol, list(P.ref)))
    name, eqs, y, y0 = brusselator(n_bruss)
    out.append((name, eqs, y, y0, (0.0, 10.0), 1e-8, None))
    return out


def brusselator(N: int):
    """Hairer & Wanner's 1-D Brusselator (Solving ODEs I, II.10; II, IV.10):
    u' = 1 + u^2 v - 4u + a (N+1)^2 (u_{i-1} - 2u_i + u_{i+1}), v' = 3u - u^2 v +
    a (N+1)^2 (...), a = 1/50, u = 1, v = 3 at the ends, u(0) = 1 + sin(2 pi x), v(0) = 3;
    the state (u_1, v_1, u_2, v_2, ...).  (name, equations, symbols, y0)."""
    import sympy as sp
    y = sp.symbols(f"y0:{2 * N}")
    u, v = y[0::2], y[1::2]
    c = sp.Float((N + 1) ** 2 / 50.0)
    eqs = []
    for i in range(N):
        ul = u[i - 1] if i > 0 else sp.Integer(1)
        ur = u[i + 1] if i < N - 1 else sp.Integer(1)
        vl = v[i - 1] if i > 0 else sp.Integer(3)
        vr = v[i + 1] if i < N - 1 else sp.Integer(3)
        eqs.append(1 + u[i] ** 2 * v[i] - 4 * u[i] + c * (ul - 2 * u[i] + ur))
        eqs.append(3 * u[i] - u[i] ** 2 * v[i] + c * (vl - 2 * v[i] + vr))
    x = np.arange(1, N + 1) / (N + 1)
    y0 = np.empty(2 * N)
    y0[0::2] = 1 + np.sin(2 * np.pi * x)
    y0[1::2] = 3.0
    return f"Brusselator 1-D, N={N} (n={2 * N})", eqs, y, y0


_DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunlinsol/sunlinsol_band.h>

static int f(realtype t, N_Vector y, N_Vector ydot, void *ud)
{
    return mp_gen_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), ud) == MP_OK ? 0 : -1;
}

static int jac(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *ud, N_Vector t1,
               N_Vector t2, N_Vector t3)
{
    (void)fy; (void)t1; (void)t2; (void)t3;
    double *rm = ud; /* row-major scratch, NS x NS */
    if (mp_gen_jac(t, N_VGetArrayPointer(y), rm, NULL) != MP_OK) return -1;
#ifdef MP_BAND /* the band (ML, MU) of the generated Jacobian */
    for (sunindextype j = 0; j < NS; j++)
        for (sunindextype i = j > MU ? j - MU : 0; i < NS && i <= j + ML; i++)
            SM_ELEMENT_B(J, i, j) = rm[i * NS + j];
#else
    for (sunindextype j = 0; j < NS; j++) {
        double *col = SM_COLUMN_D(J, j);
        for (sunindextype i = 0; i < NS; i++) col[i] = rm[i * NS + j];
    }
#endif
    return 0;
}

/* argv: rtol t0 tf repeats, then NS values of y0 and NS of atol.  Prints
 * status nsteps nfev njev nlu seconds(median) and the NS end values. */
int main(int argc, char **argv)
{
    if (argc != 5 + 2 * NS) return 2;
    double rtol = atof(argv[1]), t0 = atof(argv[2]), tf = atof(argv[3]);
    int reps = atoi(argv[4]);
    SUNContext ctx;
    if (SUNContext_Create(NULL, &ctx)) return 3;
    N_Vector y = N_VNew_Serial(NS, ctx), at = N_VNew_Serial(NS, ctx);
    double *scratch = malloc(sizeof(double) * NS * NS);
    double *times = malloc(sizeof(double) * reps);
    long nst = 0, nfe = 0, nje = 0, nsetups = 0;
    int flag = 0;
    for (int r = 0; r < reps; r++) {
        for (int i = 0; i < NS; i++) {
            NV_Ith_S(y, i) = atof(argv[5 + i]);
            NV_Ith_S(at, i) = atof(argv[5 + NS + i]);
        }
        struct timespec a, b;
        clock_gettime(CLOCK_MONOTONIC, &a);
        void *mem = CVodeCreate(CV_BDF, ctx);
#ifdef MP_BAND
        SUNMatrix A = SUNBandMatrix(NS, MU, ML, ctx);
        SUNLinearSolver LS = SUNLinSol_Band(y, A, ctx);
#else
        SUNMatrix A = SUNDenseMatrix(NS, NS, ctx);
        SUNLinearSolver LS = SUNLinSol_Dense(y, A, ctx);
#endif
        CVodeInit(mem, f, t0, y);
        CVodeSVtolerances(mem, rtol, at);
        CVodeSetUserData(mem, scratch);
        CVodeSetLinearSolver(mem, LS, A);
        CVodeSetJacFn(mem, jac);
        CVodeSetMaxNumSteps(mem, 10000000);
        double t = t0;
        flag = CVode(mem, tf, y, &t, CV_NORMAL);
        clock_gettime(CLOCK_MONOTONIC, &b);
        times[r] = (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec);
        CVodeGetNumSteps(mem, &nst);
        CVodeGetNumRhsEvals(mem, &nfe);
        CVodeGetNumJacEvals(mem, &nje);
        CVodeGetNumLinSolvSetups(mem, &nsetups);
        CVodeFree(&mem);
        SUNLinSolFree(LS);
        SUNMatDestroy(A);
    }
    for (int i = 1; i < reps; i++) /* insertion sort for the median */
        for (int j = i; j > 0 && times[j] < times[j - 1]; j--) {
            double s = times[j]; times[j] = times[j - 1]; times[j - 1] = s;
        }
    printf("%d %ld %ld %ld %ld %.9g", flag, nst, nfe, nje, nsetups, times[reps / 2]);
    for (int i = 0; i < NS; i++) printf(" %.17g", NV_Ith_S(y, i));
    printf("\n");
    N_VDestroy(y);
    N_VDestroy(at);
    free(scratch);
    free(times);
    SUNContext_Free(&ctx);
    return 0;
}
"""

_LIBS = ["-lsundials_cvode", "-lsundials_nvecserial", "-lsundials_sunmatrixdense",
         "-lsundials_sunlinsoldense", "-lsundials_sunmatrixband", "-lsundials_sunlinsolband",
         "-lm"]


def cvode_missing() -> str | None:
    """Why CVODE cannot run here, or None."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if not cc:
        return "no C compiler"
    if not os.path.exists("/usr/include/cvode/cvode.h"):
        return "SUNDIALS is not installed (Debian: apt-get install libsundials-dev)"
    return None


def cvode_driver(scene, d: str, band=None) -> str:
    """Compile the CVODE driver around ``scene.c_source`` in directory d (with
    band = (ml, mu): CVODE's band matrix and linear solver); the executable's
    path."""
    from mechpy.symbolic.build import FLAGS
    cc = shutil.which("cc") or shutil.which("gcc")
    tag = "" if band is None else "_band"
    src, exe = os.path.join(d, f"cvode_driver{tag}.c"), os.path.join(d, f"cvode_driver{tag}")
    with open(src, "w") as fh:
        if band is not None:
            fh.write(f"#define MP_BAND 1\n#define ML {band[0]}\n#define MU {band[1]}\n")
        fh.write(scene.c_source + "\n" + _DRIVER)
    flags = [f for f in FLAGS if f not in ("-shared", "-fPIC", "-std=c99")]
    subprocess.run([cc, *flags, "-std=gnu99", src, "-o", exe, *_LIBS], check=True,
                   capture_output=True)
    return exe


def cvode_solve(exe: str, n: int, y0, atol, t_span, rtol: float, repeats: int = 3):
    """(status, nsteps, nfev, njev, nlu, seconds, y_end) of CVODE's solve."""
    atol = np.broadcast_to(np.asarray(atol, float), (n,))
    args = [exe, repr(rtol), repr(float(t_span[0])), repr(float(t_span[1])), str(repeats)]
    args += [repr(float(v)) for v in y0] + [repr(float(v)) for v in atol]
    out = subprocess.run(args, capture_output=True, text=True, check=True).stdout.split()
    st, nst, nfe, nje, nlu = (int(v) for v in out[:5])
    return st, nst, nfe, nje, nlu, float(out[5]), np.array([float(v) for v in out[6:]])


def _error(yend, ref, atol):
    ref = np.asarray(ref, float)
    atol = np.broadcast_to(atol, ref.shape)
    return float(np.max(np.abs(yend - ref) / np.maximum(np.abs(ref), 10 * atol)))


def run(quick: bool):
    rtols = [1e-4, 1e-6, 1e-8] if quick else [1e-4, 1e-6, 1e-8, 1e-10]
    why = cvode_missing()
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for name, eqs, y, y0, span, atol, ref in problems():
            scene = mp.equations(eqs, list(y))
            n = len(y0)
            if ref is None:  # the Brusselator: radau far below the tolerances asked
                ref = mp.solve(scene, span, y0, method="radau", rtol=1e-12,
                               atol=1e-14).y[:, -1]
            band = scene._jac_band    # from the symbolic Jacobian
            if band is not None and (len(band) > 2 or not band_pays(n, band[0], band[1])):
                band = None           # radau dense, or in an order CVODE's band has not
            exe = exe_band = None
            if why is None:
                try:
                    exe = cvode_driver(scene, d)
                    if band is not None:
                        exe_band = cvode_driver(scene, d, band)
                except subprocess.CalledProcessError as e:
                    why = f"the CVODE driver did not compile: {e.stderr.decode()[:200]}"
            # a banded system also runs radau dense (jac_sparsity all ones), for
            # what the band form gains
            runs = [("radau", None, "stiff-mechpy"), ("auto", None, "stiff-mechpy")]
            if band is not None:
                runs.append(("radau", np.ones((n, n)), "stiff-mechpy-dense"))
            for rtol in rtols:
                for m, sparsity, path in runs:
                    def fn(m=m, sparsity=sparsity):
                        return mp.solve(scene, span, y0, method=m, rtol=rtol, atol=atol,
                                        t_eval=[span[1]], jac_sparsity=sparsity)
                    s = fn()
                    form = ("" if band is None else
                            f", band LU {band[0]} + {band[1]}" if sparsity is None else
                            ", dense LU")
                    rows.append(dict(
                        problem=name, impl=f"mechpy {m} (compiled C rhs + jac{form})",
                        path=path, method=m, rtol=rtol, n=n,
                        error=_error(s.y[:, -1], ref, atol) if s.success else float("inf"),
                        time=median_time(fn, repeat=3, budget=3.0), nfev=int(s.nfev),
                        njev=int(s.njev), nlu=int(s.nlu)))
                for x, path, what in ((exe, "stiff-cvode", "dense"),
                                      (exe_band, "stiff-cvode-band",
                                       "band" if band is None else
                                       f"band {band[0]} + {band[1]}")):
                    if x is None:
                        continue
                    st, nst, nfe, nje, nlu, sec, yend = cvode_solve(x, n, y0, atol, span, rtol)
                    rows.append(dict(
                        problem=name, impl=f"CVODE BDF, {what}, analytic jac (same C rhs)",
                        path=path, method="cvode", rtol=rtol, n=n,
                        error=_error(yend, ref, atol) if st >= 0 else float("inf"),
                        time=sec, nfev=nfe, njev=nje, nlu=nlu))
            if exe is None:
                rows.append(dict(problem=name, impl=f"CVODE: not run ({why})",
                                 path="stiff-cvode-missing", time=float("nan"),
                                 error=float("nan")))
    return rows


def targets(rows) -> list[dict]:
    """radau against CVODE at each problem and rtol: njev ratio (goal <= 3x) and
    time ratio CVODE / radau (goal >= 1x); on a banded system also against
    CVODE with its band solver (each side in band form)."""
    out = []
    cv = {(r["problem"], r["rtol"]): r for r in rows if r.get("path") == "stiff-cvode"}
    cvb = {(r["problem"], r["rtol"]): r for r in rows if r.get("path") == "stiff-cvode-band"}
    for p in dict.fromkeys(k[0] for k in cvb):
        mine = [r for r in rows if r.get("path") == "stiff-mechpy" and r["method"] == "radau"
                and r["problem"] == p and (p, r["rtol"]) in cvb]
        tr = [cvb[(p, r["rtol"])]["time"] / r["time"] for r in mine]
        if tr:
            out.append(dict(target="radau (band LU): CVODE band's time / radau's, same rtol "
                            "(every rtol)", problem=p, goal=">= 1x", worst=min(tr),
                            median=float(np.median(tr)), n=len(tr)))
    # speed against error: each CVODE row against radau's quickest row that is at
    # least as accurate (radau's errors at a given rtol are far smaller)
    for path, what in (("stiff-cvode", "CVODE"), ("stiff-cvode-band", "CVODE band")):
        for p in dict.fromkeys(r["problem"] for r in rows if r.get("path") == path):
            mine = [r for r in rows if r.get("path") == "stiff-mechpy" and r["method"] == "radau"
                    and r["problem"] == p]
            tr = []
            for c in (r for r in rows if r.get("path") == path and r["problem"] == p):
                ok = [r["time"] for r in mine if r["error"] <= c["error"]]
                if ok:
                    tr.append(c["time"] / min(ok))
            if tr:
                out.append(dict(target=f"radau: {what}'s time / radau's quickest run at no "
                                "larger error (every CVODE rtol)", problem=p, goal=">= 1x",
                                worst=min(tr), median=float(np.median(tr)), n=len(tr)))
    for m in ("radau", "auto"):
        for p in dict.fromkeys(r["problem"] for r in rows if r.get("path") == "stiff-mechpy"):
            mine = [r for r in rows if r.get("path") == "stiff-mechpy" and r["method"] == m
                    and r["problem"] == p and (p, r["rtol"]) in cv]
            if not mine:
                continue
            jr = [r["njev"] / max(cv[(p, r["rtol"])]["njev"], 1) for r in mine]
            tr = [cv[(p, r["rtol"])]["time"] / r["time"] for r in mine]
            out.append(dict(target=f"{m}: njev / CVODE's, same rtol (every rtol)", problem=p,
                            goal="<= 3x", worst=max(jr), median=float(np.median(jr)),
                            n=len(jr)))
            out.append(dict(target=f"{m}: CVODE's time / {m}'s, same rtol (every rtol)",
                            problem=p, goal=">= 1x", worst=min(tr),
                            median=float(np.median(tr)), n=len(tr)))
    return out
