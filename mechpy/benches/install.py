"""Bench: the install paths and the build of compiled systems without a C compiler.

* Building mechpy._core (``meson setup`` + ``ninja``, the source tree's
  meson.build, release, from an empty build folder): with the system's GSL and
  LAPACK (pkg-config), and with pkg-config pointed at an empty folder (GSL's
  subset compiled from subprojects/gsl.wrap, OpenBLAS from the
  scipy-openblas32 wheel).  The GSL tarball is taken from
  subprojects/packagecache when a build has downloaded it (the row says so):
  the figure is the compile, not the download.  Needs the source tree
  (``MECHPY_SOURCE_DIR`` or the package's parent folder) and meson, ninja and
  scipy-openblas32 in this interpreter; rows left out otherwise.
* The double pendulum from its Lagrangian (dop853, rtol 1e-10, t = 10), the
  C build against the numba build (``backend="numba"``, what a machine
  without a C compiler takes): the solve's time (goal: within 3x), the first
  build in an empty cache folder and the build from the cache, each in a new
  process.

Rows carry ``path`` ("build-system", "build-fallback", "solve-c",
"solve-numba", "first-c", "first-numba", "cached-c", "cached-numba").
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TITLE = "Install paths: build times, and compiled systems without a C compiler (numba)"
ORDER = 97


def _source() -> Path | None:
    d = os.environ.get("MECHPY_SOURCE_DIR")
    cands = [Path(d)] if d else []
    import mechpy
    cands.append(Path(mechpy.__file__).resolve().parent.parent)
    for c in cands:
        if (c / "meson.build").is_file() and (c / "subprojects" / "gsl.wrap").is_file():
            return c
    return None


def _build_rows(quick: bool) -> list:
    src = _source()
    meson = shutil.which("meson") or shutil.which("meson", path=os.path.dirname(sys.executable))
    ninja = shutil.which("ninja") or shutil.which("ninja", path=os.path.dirname(sys.executable))
    if src is None or meson is None or ninja is None:
        return []
    rows = []
    cached = (src / "subprojects" / "packagecache").is_dir()
    with tempfile.TemporaryDirectory(prefix="mechpy-bench-build-") as tmp:
        tmp = Path(tmp)
        # a copy of the tree's build inputs: the subproject unpacks inside it
        tree = tmp / "src"
        skip = shutil.ignore_patterns(".git", ".venv", "build", "docs", "notebooks", "tests",
                                      "__pycache__")

        def ignore(folder, names):   # and the GSL source a build here has unpacked
            out = set(skip(folder, names))
            return out | ({"gsl"} if Path(folder) == src / "subprojects" else set())
        shutil.copytree(src, tree, ignore=ignore)
        empty = tmp / "empty"
        empty.mkdir()
        for path, env_extra, label in (
                ("build-system", {}, "system GSL + LAPACK (pkg-config)"),
                ("build-fallback", {"PKG_CONFIG_LIBDIR": str(empty),
                                    "PKG_CONFIG_PATH": str(empty)},
                 "GSL from subprojects/gsl.wrap + scipy-openblas32"
                 + (" (tarball from the package cache)" if cached else " (download included)"))):
            env = dict(os.environ, **env_extra)
            b = tmp / path
            t0 = time.perf_counter()
            r = subprocess.run([meson, "setup", str(b), str(tree), "-Dbuildtype=release",
                                "-Doptimization=2",
                                f"--native-file={_native(tmp)}"],
                               env=env, capture_output=True, text=True)
            if r.returncode == 0:
                r = subprocess.run([ninja, "-C", str(b)], env=env, capture_output=True,
                                   text=True)
            dt = time.perf_counter() - t0
            if r.returncode != 0:
                continue   # e.g. no system GSL here: that path has no figure
            rows.append(dict(problem="building mechpy._core (meson setup + ninja, 2 jobs)"
                             if os.cpu_count() == 2 else "building mechpy._core "
                             "(meson setup + ninja)", impl=label, time=dt,
                             error=float("nan"), path=path))
            if quick:
                shutil.rmtree(b, ignore_errors=True)
    return rows


def _native(tmp: Path) -> Path:
    """A meson native file naming this interpreter (as meson-python writes one)."""
    f = tmp / "native.ini"
    f.write_text(f"[binaries]\npython = '{sys.executable}'\n")
    return f


_SOLVE = r"""
import json, sys, time
import numpy as np
import mechpy as mp
from mechpy.benches.own import double_pendulum_lagrangian, DP_PARAMS, DP_Y0, DP_T
t0 = time.perf_counter()
L, q = double_pendulum_lagrangian()
s = mp.lagrangian(L, q, DP_PARAMS, backend=sys.argv[1])
build = time.perf_counter() - t0
kw = dict(method="dop853", rtol=1e-10, atol=1e-12)
sol = mp.solve(s, (0, DP_T), DP_Y0, **kw)
times = []
for _ in range(int(sys.argv[2])):
    t1 = time.perf_counter()
    sol = mp.solve(s, (0, DP_T), DP_Y0, **kw)
    times.append(time.perf_counter() - t1)
print(json.dumps(dict(build=build, time=float(np.median(times)), y=sol.y[:, -1].tolist(),
                      nfev=int(sol.nfev))))
"""


def _jit_rows(quick: bool) -> list:
    try:
        import numba  # noqa: F401
    except ImportError:
        return []
    from mechpy.symbolic import build
    if not build.have_compiler():
        return []
    rows, res = [], {}
    reps = 5 if quick else 21
    with tempfile.TemporaryDirectory(prefix="mechpy-bench-jit-") as cache:
        env = dict(os.environ, MECHPY_CACHE_DIR=cache)
        for be in ("c", "numba"):
            out = []
            for _ in range(2):   # first build (empty cache), then from the cache
                r = subprocess.run([sys.executable, "-c", _SOLVE, be, str(reps)], env=env,
                                   capture_output=True, text=True, timeout=1200)
                if r.returncode != 0:
                    return []
                out.append(json.loads(r.stdout.strip().splitlines()[-1]))
            res[be] = out
    import numpy as np
    ref = np.array(res["c"][1]["y"])
    for be, what in (("c", "C build (the system's compiler)"),
                     ("numba", "numba build (no C compiler)")):
        first, again = res[be]
        err = float(np.abs(np.array(again["y"]) - ref).max())
        rows.append(dict(problem="double pendulum from its Lagrangian, dop853 rtol 1e-10, "
                         "t = 10", impl=f"solve, {what}", time=again["time"],
                         error=err, nfev=again["nfev"], path=f"solve-{be}"))
        rows.append(dict(problem="double pendulum from its Lagrangian: building it",
                         impl=f"first build in a new process, {what}", time=first["build"],
                         error=float("nan"), path=f"first-{be}"))
        rows.append(dict(problem="double pendulum from its Lagrangian: building it",
                         impl=f"build from the cache in a new process, {what}",
                         time=again["build"], error=float("nan"), path=f"cached-{be}"))
    return rows


def run(quick: bool = False) -> list:
    return _build_rows(quick) + _jit_rows(quick)


def targets(rows) -> list[dict]:
    """The numba build's solve against the C build's (time ratio, goal <= 3x), and
    the fallback build's time against the system-library build's."""
    by = {r.get("path"): r for r in rows if r.get("path")}
    out = []
    if "solve-c" in by and "solve-numba" in by:
        v = by["solve-numba"]["time"] / by["solve-c"]["time"]
        out.append(dict(target="numba build / C build, double pendulum solve (time ratio)",
                        problem=by["solve-c"]["problem"], goal="<= 3x", worst=v, median=v,
                        n=1))
    if "build-system" in by and "build-fallback" in by:
        v = by["build-fallback"]["time"] / by["build-system"]["time"]
        out.append(dict(target="build without system libraries / with them (time ratio)",
                        problem=by["build-system"]["problem"], goal="(none)", worst=v,
                        median=v, n=1))
    return out
