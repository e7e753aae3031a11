"""Bench: generated systems against Hairer's Fortran DOP853 with the same
equations inlined.

Three systems from their Lagrangians, compiled by ``mp.lagrangian``: the
double pendulum (2 coordinates), the spherical pendulum (2) and the heavy
symmetric top in Euler angles (3).  Beside each, Hairer's ``dop853.f``
compiled with gfortran (-O2, as the generated C) and a driver whose FCN holds
the same equations of motion written out by hand (the accelerations in closed
form), at the same rtol and atol (scalars, ITOL = 0), no dense output.  Both
take the same number of evaluations (printed per system: the same algorithm,
step for step), and each side's final state is compared with the other's and
with a tight reference.  Time is CPU time per solve (the process's, over a
batch; the machine may be shared), the two sides measured in alternation
and the median taken; the mechpy side is a whole ``mp.solve`` call from
Python.  Goal: generated / Fortran <= 1.15x on each system.

``dop853.f`` is the copy in SciPy's source distribution (scipy 1.13.1's
sdist on PyPI, ``scipy/integrate/dop/dop853.f``), fetched once with
``pip download`` into the cache folder (``mechpy.symbolic.build.cache_dir()``
/ ``fortran``): pip unpacks the sdist, the file is copied and pip is stopped
(scipy itself is never built).  Without gfortran, or where the download fails,
the section says so and has no rows.
"""
from __future__ import annotations

import glob
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

TITLE = "Generated systems against Hairer's Fortran DOP853 with the same equations inlined"
ORDER = 91

SCIPY_SDIST = "scipy==1.13.1"
RTOL, ATOL = 1e-10, 1e-13
#: Goal of generated / Fortran CPU time per solve.
GOAL = 1.15

#: FCN bodies (Fortran), the equations of motion of each system solved for the
#: accelerations by hand; PAR holds the parameters in the order of PARAMS.
_FCN = {
    "double pendulum": """
      C = COS(Y(1) - Y(2))
      S = SIN(Y(1) - Y(2))
      A11 = (PAR(1) + PAR(2)) * PAR(3)**2
      A12 = PAR(2) * PAR(3) * PAR(4) * C
      A22 = PAR(2) * PAR(4)**2
      B1 = -PAR(2) * PAR(3) * PAR(4) * S * Y(4)**2
     &     - (PAR(1) + PAR(2)) * PAR(5) * PAR(3) * SIN(Y(1))
      B2 = PAR(2) * PAR(3) * PAR(4) * S * Y(3)**2 - PAR(2) * PAR(5) * PAR(4) * SIN(Y(2))
      DET = A11 * A22 - A12 * A12
      F(1) = Y(3)
      F(2) = Y(4)
      F(3) = (A22 * B1 - A12 * B2) / DET
      F(4) = (A11 * B2 - A12 * B1) / DET
""",
    "spherical pendulum": """
      ST = SIN(Y(1))
      CT = COS(Y(1))
      F(1) = Y(3)
      F(2) = Y(4)
      F(3) = ST * CT * Y(4)**2 - PAR(3) / PAR(2) * ST
      F(4) = -2.0D0 * CT * Y(3) * Y(4) / ST
""",
    "heavy top": """
      ST = SIN(Y(2))
      CT = COS(Y(2))
      W3 = Y(6) + Y(4) * CT
      F(1) = Y(4)
      F(2) = Y(5)
      F(3) = Y(6)
      F(4) = Y(5) * (PAR(2) * W3 - 2.0D0 * PAR(1) * CT * Y(4)) / (PAR(1) * ST)
      F(5) = (PAR(1) * Y(4)**2 * ST * CT - PAR(2) * W3 * Y(4) * ST + PAR(3) * ST) / PAR(1)
      F(6) = Y(4) * ST * Y(5) - F(4) * CT
""",
}

_DRIVER = """
      SUBROUTINE FCN(N, X, Y, F, RPAR, IPAR)
      IMPLICIT DOUBLE PRECISION (A-H, O-Z)
      DIMENSION Y(N), F(N), RPAR(*), IPAR(*)
      COMMON /MPPAR/ PAR(8)
{body}
      RETURN
      END

      SUBROUTINE SOLOUT
      RETURN
      END

      PROGRAM MPDRV
      IMPLICIT DOUBLE PRECISION (A-H, O-Z)
      EXTERNAL FCN, SOLOUT
      COMMON /MPPAR/ PAR(8)
      DIMENSION Y0(8), Y(8), RTOL(1), ATOL(1), WORK(200), IWORK(40), RPAR(1), IPAR(1)
      READ (*, *) N, NREP, NPAR
      READ (*, *) (PAR(I), I = 1, NPAR)
      READ (*, *) XEND, RTOL(1), ATOL(1)
      READ (*, *) (Y0(I), I = 1, N)
      CALL CPU_TIME(T0)
      DO K = 1, NREP
        DO I = 1, N
          Y(I) = Y0(I)
        END DO
        X = 0.0D0
        DO I = 1, 20
          WORK(I) = 0.0D0
          IWORK(I) = 0
        END DO
        CALL DOP853(N, FCN, X, Y, XEND, RTOL, ATOL, 0, SOLOUT, 0,
     &              WORK, 200, IWORK, 40, RPAR, IPAR, IDID)
      END DO
      CALL CPU_TIME(T1)
      WRITE (*, '(I4, 1X, I10, 1X, ES24.16)') IDID, IWORK(17), (T1 - T0) / NREP
      WRITE (*, '(8ES25.17)') (Y(I), I = 1, N)
      END
"""


# --------------------------------------------------------------------------- systems

def spherical_pendulum_lagrangian():
    """L = m l^2 (theta'^2 + sin^2 theta phi'^2) / 2 + m g l cos theta (theta from
    the downward vertical); returns (L, q)."""
    import sympy as sp

    import mechpy as mp
    th, ph = mp.coordinates("theta phi")
    m, l, g = sp.symbols("m l g")
    return (m * l ** 2 / 2 * (th.diff() ** 2 + sp.sin(th) ** 2 * ph.diff() ** 2)
            + m * g * l * sp.cos(th)), [th, ph]


def heavy_top_lagrangian():
    """The heavy symmetric top in ZXZ Euler angles (phi, theta, psi), fixed point
    on the symmetry axis, centre of mass at distance l above it:
    L = I1 (theta'^2 + phi'^2 sin^2 theta) / 2 + I3 (psi' + phi' cos theta)^2 / 2
    - M g l cos theta; returns (L, q)."""
    import sympy as sp

    import mechpy as mp
    ph, th, ps = mp.coordinates("phi theta psi")
    I1, I3, mgl = sp.symbols("I1 I3 mgl")
    w3 = ps.diff() + ph.diff() * sp.cos(th)
    return (I1 / 2 * (th.diff() ** 2 + ph.diff() ** 2 * sp.sin(th) ** 2) + I3 / 2 * w3 ** 2
            - mgl * sp.cos(th)), [ph, th, ps]


def _systems():
    """(name, (L, q), params in the FCN's PAR order, y0, t_end): spans of
    thousands of evaluations (the heavy top's is longer: at t = 10 it takes
    800, and a solve's fixed cost, mp.solve's call from Python, would weigh
    more than its evaluations)."""
    from .own import DP_PARAMS, DP_Y0, double_pendulum_lagrangian
    return [
        ("double pendulum", double_pendulum_lagrangian(), dict(DP_PARAMS), DP_Y0, 10.0),
        ("spherical pendulum", spherical_pendulum_lagrangian(),
         {"m": 1.0, "l": 1.0, "g": 9.81}, np.array([1.0, 0.0, 0.0, 2.0]), 10.0),
        ("heavy top", heavy_top_lagrangian(), {"I1": 1.0, "I3": 0.5, "mgl": 1.0},
         np.array([0.0, 1.0, 0.0, 0.5, 0.0, 5.0]), 100.0),
    ]


# --------------------------------------------------------------------------- the Fortran side

def _fetch_dop853(folder: str):
    """The path of dop853.f in ``folder``, fetched when absent (see the module
    docstring); (path, how) or (None, why not)."""
    path = os.path.join(folder, "dop853.f")
    if os.path.exists(path):
        return path, f"cached {path}"
    os.makedirs(folder, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="mechpy-dop853-") as tmp:
        env = dict(os.environ, TMPDIR=tmp)
        cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", "scipy",
               "--no-build-isolation", "--no-clean", "--progress-bar", "off", SCIPY_SDIST,
               "-d", os.path.join(tmp, "dl")]
        proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        found = None
        t0 = time.monotonic()
        try:
            while time.monotonic() - t0 < 900:
                hits = glob.glob(os.path.join(tmp, "**", "scipy", "integrate", "dop",
                                              "dop853.f"), recursive=True)
                if hits:
                    time.sleep(1.0)     # the unpacking of that file is finished
                    found = hits[0]
                    break
                if proc.poll() is not None:
                    break
                time.sleep(0.5)
            if found:
                with open(found, "rb") as f:
                    text = f.read()
                if b"SUBROUTINE DOP853" not in text:
                    return None, f"{found} is not Hairer's DOP853"
                with open(path + ".part", "wb") as f:
                    f.write(text)
                os.replace(path + ".part", path)
        finally:
            if proc.poll() is None:
                proc.kill()      # the sdist is unpacked: scipy is not to be built
            proc.wait()
    if not found:
        return None, f"pip download {SCIPY_SDIST} gave no scipy/integrate/dop/dop853.f"
    return path, f"fetched from the {SCIPY_SDIST} sdist on PyPI with pip download"


def _build_driver(folder: str, dop: str, name: str) -> str:
    """The executable of Hairer's DOP853 with ``name``'s FCN (compiled once)."""
    src = _DRIVER.format(body=_FCN[name])
    key = hashlib.sha256((src + open(dop).read()).encode()).hexdigest()[:16]
    exe = os.path.join(folder, f"drv_{key}")
    if not os.path.exists(exe):
        with tempfile.TemporaryDirectory(prefix="mechpy-fortran-") as tmp:
            drv = os.path.join(tmp, "drv.f")
            with open(drv, "w") as f:
                f.write(src)
            subprocess.run(["gfortran", "-O2", "-w", "-ffixed-line-length-none", "-o",
                            exe + ".part", drv, dop], check=True, capture_output=True)
            os.replace(exe + ".part", exe)
    return exe


def _run_fortran(exe, params, y0, nrep, t_end):
    inp = (f"{len(y0)} {nrep} {len(params)}\n" + " ".join(repr(float(v)) for v in params)
           + f"\n{t_end!r} {RTOL!r} {ATOL!r}\n" + " ".join(repr(float(v)) for v in y0) + "\n")
    out = subprocess.run([exe], input=inp, capture_output=True, text=True, check=True)
    words = out.stdout.split()
    idid, nfev, sec = int(words[0]), int(words[1]), float(words[2])
    if idid != 1:
        raise RuntimeError(f"DOP853 returned IDID = {idid}")
    return nfev, sec, np.array([float(w.replace("D", "E")) for w in words[3:3 + len(y0)]])


# --------------------------------------------------------------------------- the section

def run(quick: bool) -> list[dict]:
    import mechpy as mp
    from mechpy.symbolic import build
    if shutil.which("gfortran") is None:
        print("  gfortran is not installed: no Fortran rows (apt-get install gfortran; "
              "scripts/dev.sh bench installs it)")
        return []
    folder = os.path.join(build.cache_dir(), "fortran")
    dop, how = _fetch_dop853(folder)
    if dop is None:
        print(f"  Hairer's dop853.f is not available ({how}): no Fortran rows")
        return []
    print(f"  dop853.f: {how} (sha256 {hashlib.sha256(open(dop, 'rb').read()).hexdigest()[:16]})")
    rounds = 3 if quick else 7
    rows = []
    for name, (L, q), params, y0, t_end in _systems():
        scene = mp.lagrangian(L, q, params=params)
        exe = _build_driver(folder, dop, name)
        ref = mp.solve(scene, (0, t_end), y0, rtol=1e-14, atol=1e-16).y[:, -1]
        sol = mp.solve(scene, (0, t_end), y0, rtol=RTOL, atol=ATOL)
        one = time.process_time()
        mp.solve(scene, (0, t_end), y0, rtol=RTOL, atol=ATOL)
        one = max(time.process_time() - one, 1e-5)
        nrep = max(5, int((0.05 if quick else 0.2) / one))
        tf, tm = [], []
        for _ in range(rounds):
            nfev_f, sec, yf = _run_fortran(exe, list(params.values()), y0, nrep, t_end)
            tf.append(sec)
            t0 = time.process_time()
            for _ in range(nrep):
                mp.solve(scene, (0, t_end), y0, rtol=RTOL, atol=ATOL)
            tm.append((time.process_time() - t0) / nrep)
        t_f, t_m = float(np.median(tf)), float(np.median(tm))
        problem = (f"{name} ({len(q)} coordinates), t={t_end:g}, dop853 rtol={RTOL:g} "
                   f"atol={ATOL:g}: generated vs Fortran")
        agree = float(np.max(np.abs(sol.y[:, -1] - yf)))
        note = (f"CPU time per solve, median of {rounds} alternating batches of {nrep}; "
                f"nfev mechpy {int(sol.nfev)}, Fortran {nfev_f}; final states differ by "
                f"{agree:.1e}; ratio {t_m / t_f:.2f}x")
        print(f"  {name}: generated {t_m * 1e6:.0f} us (nfev {int(sol.nfev)}), Fortran "
              f"{t_f * 1e6:.0f} us (nfev {nfev_f}), ratio {t_m / t_f:.2f}x "
              f"(goal <= {GOAL}x)", flush=True)
        rows.append(dict(problem=problem, impl="mechpy dop853 (compiled Lagrangian)",
                         path="generated-vs-fortran", method="dop853", rtol=RTOL,
                         error=float(np.max(np.abs(sol.y[:, -1] - ref))), nfev=int(sol.nfev),
                         time=t_m, note=note))
        rows.append(dict(problem=problem, impl="Hairer's dop853.f, same equations inlined "
                         "(gfortran -O2)", path="fortran", method="dop853", rtol=RTOL,
                         error=float(np.max(np.abs(yf - ref))), nfev=nfev_f, time=t_f,
                         note=note))
    return rows


def targets(rows) -> list[dict]:
    """Generated / Fortran CPU time per solve, per system (goal <= 1.15x)."""
    out = []
    for p in dict.fromkeys(r["problem"] for r in rows):
        by = {r.get("path"): r for r in rows if r["problem"] == p}
        if "generated-vs-fortran" in by and "fortran" in by:
            v = by["generated-vs-fortran"]["time"] / by["fortran"]["time"]
            out.append(dict(target="generated system / Fortran DOP853 with the equations "
                            "inlined (CPU time per solve)", problem=p, goal=f"<= {GOAL}x",
                            worst=v, median=v, n=1))
    return out
