"""Installs anywhere: without system GSL or LAPACK, without a C compiler.

- The build's fallbacks (meson.build): GSL from subprojects/gsl.wrap, LAPACK
  from the scipy-openblas32 wheel, whose symbols meson.build renames.  The build
  where pkg-config finds nothing (it links no system libgsl and passes the core
  test files) is tests/test_release.py's: the sdist's offline build, one build
  shared with the wheel's checks.
- Compiled systems where no C compiler is found: the numba build (mechpy.
  symbolic.jit) gives the C build's solution to round-off, at its speed.
"""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechpy as mp

SANITIZED = bool(os.environ.get("MECHPY_SANITIZED"))
# numba's JIT-compiled code is not instrumented: the sanitizer pass checks the C core
jit = pytest.mark.skipif(SANITIZED, reason="numba's code is not instrumented")

ROOT = Path(__file__).resolve().parent.parent
# the source tree: under dev.sh's sdist pass the tests run from a copy, and dev.sh names
# the checkout in MECHPY_SOURCE_DIR
SOURCE = Path(os.environ.get("MECHPY_SOURCE_DIR") or ROOT)


def _meson_build():
    path = SOURCE / "meson.build"
    if not path.is_file():
        pytest.skip("needs the source tree's meson.build (MECHPY_SOURCE_DIR)")
    return path.read_text()


def test_scipy_openblas_renames_every_lapack_routine_csrc_calls():
    """meson.build renames the LAPACK routines to scipy-openblas32's prefixed symbols:
    a routine csrc/ declares and the list lacks would be an undefined symbol at import."""
    listed = re.search(r"lapack_routines = \[([^\]]*)\]", _meson_build())
    assert listed, "meson.build has no lapack_routines list"
    names = set(re.findall(r"'(\w+_)'", listed.group(1)))
    declared = set()
    for f in (SOURCE / "csrc").rglob("*.[ch]"):   # sources and headers (ode/lu.h)
        declared |= set(re.findall(r"extern\s+void\s+([a-z]\w*_)\s*\(", f.read_text()))
    assert declared, "no LAPACK declarations found in csrc/"
    assert names == declared


def test_gsl_wrap_names_its_source_and_checksum():
    wrap = (SOURCE / "subprojects" / "gsl.wrap")
    if not wrap.is_file():
        pytest.skip("needs the source tree")
    text = wrap.read_text()
    assert re.search(r"^source_url = http://deb\.debian\.org/debian/pool/main/g/gsl/"
                     r"gsl_2\.7\.1\+dfsg\.orig\.tar\.gz$", text, re.M)
    # the sha256 Debian's signed gsl_2.7.1+dfsg-5+deb12u1.dsc gives for that file
    assert re.search(r"^source_hash = e560d6b9c6e254e46769bbb03583c00ecafbdd51b062c55db2"
                     r"3b3b9612868567$", text, re.M)
    overlay = SOURCE / "subprojects" / "packagefiles" / "gsl"
    assert (overlay / "meson.build").is_file() and (overlay / "config.h").is_file()


# -- set-up without root -----------------------------------------------------------------

@pytest.mark.skipif(sys.platform != "linux", reason="dev.sh: Debian")
def test_setup_without_root_skips_apt_and_says_what_it_uses(tmp_path):
    """scripts/dev.sh as a user without root or sudo, where pkg-config finds nothing: no
    apt-get, and it names the fallbacks it builds with."""
    script = SOURCE / "scripts" / "dev.sh"
    if not script.is_file():
        pytest.skip("needs the source tree's scripts/dev.sh")
    shims = tmp_path / "shims"
    shims.mkdir()
    calls = tmp_path / "calls"
    for name, body in (("id", 'if [ "$1" = -u ]; then echo 1000; else exec /usr/bin/id "$@"; fi'),
                       ("sudo", f'echo sudo "$@" >> {calls}; exit 1'),
                       ("apt-get", f'echo apt-get "$@" >> {calls}; exit 1')):
        (shims / name).write_text(f"#!/bin/sh\n{body}\n")
        (shims / name).chmod(0o755)
    empty = tmp_path / "empty"
    empty.mkdir()
    env = dict(os.environ, PATH=f"{shims}{os.pathsep}{os.environ['PATH']}",
               PKG_CONFIG_LIBDIR=str(empty), PKG_CONFIG_PATH=str(empty),
               MECHPY_SETUP_SYSTEM_ONLY="1")
    r = subprocess.run(["bash", str(script), "test"], env=env, capture_output=True, text=True,
                       timeout=120, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stdout + r.stderr
    called = calls.read_text() if calls.exists() else ""
    assert "apt-get" not in called, called     # (sudo -n true: the probe for sudo)
    assert "no root and no sudo: using GSL 2.7.1 built from subprojects/gsl.wrap" in r.stdout
    assert "OpenBLAS from the scipy-openblas32 wheel (PyPI)" in r.stdout


# -- no C compiler -----------------------------------------------------------------------

_DOUBLE_PENDULUM = r"""
import json, sys, warnings
import sympy as sp
import mechpy as mp

th1, th2 = mp.coordinates("theta1 theta2")
m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g", positive=True)
t = sp.Symbol("t")
x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
T = (m1 * (x1.diff(t)**2 + y1.diff(t)**2) + m2 * (x2.diff(t)**2 + y2.diff(t)**2)) / 2
L = T - (m1 * g * y1 + m2 * g * y2)
with warnings.catch_warnings(record=True) as w:
    warnings.simplefilter("always")
    s = mp.lagrangian(L, [th1, th2], dict(m1=1.0, m2=2.0, l1=1.0, l2=0.5, g=9.81),
                      backend=sys.argv[1])
    mp.lagrangian(L, [th1, th2], dict(m1=1.0, m2=2.0, l1=1.0, l2=0.5, g=9.81))
y0 = [1.0, -0.5, 0.0, 0.5]
kw = dict(rtol=1e-10, atol=1e-12)
sol = mp.solve(s, (0, 5), y0, method="DOP853", **kw)
rad = mp.solve(s, (0, 1), y0, method="Radau", **kw)   # the Jacobian
print(json.dumps(dict(y=sol.y[:, -1].tolist(), nfev=int(sol.nfev),
                      radau=rad.y[:, -1].tolist(), backend=s._backend,
                      energy=[float(s.energy(y0)), float(s.energy(sol.y[:, -1]))],
                      warnings=[str(x.message) for x in w])))
"""


def _run_double_pendulum(tmp_path, backend, env_extra=None):
    script = tmp_path / "dp.py"
    script.write_text(_DOUBLE_PENDULUM)
    env = dict(os.environ, MECHPY_CACHE_DIR=str(tmp_path / "cache"), **(env_extra or {}))
    if env_extra:
        env.pop("MECHPY_CC", None)   # the compiler command comes from CC and PATH alone
    r = subprocess.run([sys.executable, str(script), backend], env=env, cwd=tmp_path,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


_COMPILER = re.compile(r"^(cc|c89|c99|gcc|clang|tcc|icc|icx|cl)(-[\d.]+)?$|-(gcc|cc|clang)(-[\d.]+)?$")


def _path_without_compilers(folder):
    """A PATH of one folder: links to every program on PATH but the C compilers (the
    tools the editable install's rebuild check runs stay)."""
    folder.mkdir()
    for d in os.environ.get("PATH", "").split(os.pathsep):
        d = os.path.abspath(d or ".")
        try:
            names = os.listdir(d)
        except OSError:
            continue
        for name in names:
            src = os.path.join(d, name)
            if (_COMPILER.search(name) or os.path.lexists(folder / name)
                    or not (os.path.isfile(src) and os.access(src, os.X_OK))):
                continue
            (folder / name).symlink_to(src)
    return str(folder)


@jit
def test_double_pendulum_without_a_compiler_matches_the_c_build(tmp_path):
    """PATH without a compiler and CC pointing nowhere: backend="c" takes numba, with one
    warning; the solution is the C build's to 1e-10.  Its time against the C build's
    (goal <= 3x) is the bench's install section's target, not a test's: a bound on
    time failed this test on a loaded machine (3.0x)."""
    pytest.importorskip("numba")
    from mechpy.symbolic import build
    if not build.have_compiler():
        pytest.skip("no C compiler here to compare with")
    c = _run_double_pendulum(tmp_path, "c")
    assert c["backend"] == "c" and not c["warnings"]
    env = {"PATH": _path_without_compilers(tmp_path / "bin"),
           "CC": str(tmp_path / "nowhere" / "cc")}
    nb = _run_double_pendulum(tmp_path, "c", env)
    assert nb["backend"] == "numba"
    assert len(nb["warnings"]) == 1 and "no C compiler" in nb["warnings"][0], nb["warnings"]
    assert nb["nfev"] == c["nfev"]
    np.testing.assert_allclose(nb["y"], c["y"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(nb["radau"], c["radau"], rtol=0, atol=1e-10)
    # the energy is conserved by both to the tolerance's order
    assert abs(nb["energy"][1] - nb["energy"][0]) < 1e-7 * abs(nb["energy"][0])


@jit
def test_numba_backend_in_process_gives_the_scene_functions(tmp_path, monkeypatch):
    """Every function of a constrained Lagrangian's scene from the numba build equals the
    C build's: a pendulum as a particle on a circle (x^2 + y^2 = l^2)."""
    pytest.importorskip("numba")
    import sympy as sp
    from mechpy.symbolic import build
    if not build.have_compiler():
        pytest.skip("no C compiler here to compare with")
    monkeypatch.setenv("MECHPY_CACHE_DIR", str(tmp_path / "cache"))
    x, y = mp.coordinates("x y")
    g, l = sp.symbols("g l", positive=True)
    L = (x.diff()**2 + y.diff()**2) / 2 - g * y
    P = dict(g=9.81, l=1.5)
    s = {be: mp.lagrangian(L, [x, y], P, constraints=[x**2 + y**2 - l**2], backend=be)
         for be in ("c", "numba")}
    y0 = [1.5 * np.sin(0.7), -1.5 * np.cos(0.7), 0.0, 0.0]
    sol = mp.solve(s["c"], (0, 2), y0, rtol=1e-10, atol=1e-12)
    Y = sol.y[:, ::7]
    T = sol.t[::7]
    for name, args in (("rhs", (T, Y)), ("jacobian", (T, Y)), ("multipliers", (T, Y)),
                       ("constraint_forces", (T, Y)), ("constraints", (T, Y)),
                       ("energy", (Y,)), ("momenta", (Y,))):
        a = getattr(s["c"], name)(*args)
        b = getattr(s["numba"], name)(*args)
        np.testing.assert_allclose(b, a, rtol=1e-13, atol=1e-13, err_msg=name)
    nb = mp.solve(s["numba"], (0, 2), y0, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(nb.y[:, -1], sol.y[:, -1], rtol=0, atol=1e-10)
    assert "backend=numba" in repr(s["numba"])
    # small oscillations through L's derivatives: an unconstrained pendulum, sqrt(g/l)
    th, = mp.coordinates("theta")
    pend = mp.lagrangian(l**2 * th.diff()**2 / 2 + g * l * sp.cos(th), [th], P,
                         backend="numba")
    assert abs(pend.small_oscillations([0.0]).omega[0] - np.sqrt(9.81 / 1.5)) < 1e-12


def test_backend_is_checked():
    import sympy as sp
    x, = mp.coordinates("x")
    with pytest.raises(ValueError, match="backend must be 'c', 'numba' or 'numpy'"):
        mp.lagrangian(x.diff()**2 / 2 - x**2 / 2, [x], {}, backend="fortran")
    del sp


def test_no_compiler_and_no_numba_says_what_to_install(tmp_path):
    """Neither a C compiler nor numba: a CompileError naming both ways out."""
    code = ("import sys; sys.modules['numba'] = None\n"
            "import mechpy as mp\n"
            "x, = mp.coordinates('x')\n"
            "try:\n"
            "    mp.lagrangian(x.diff()**2 / 2 - x**2 / 2, [x], {})\n"
            "except mp.symbolic.CompileError as e:\n"
            "    print('CompileError:', e)\n")
    env = dict(os.environ, PATH=_path_without_compilers(tmp_path / "bin"),
               CC=str(tmp_path / "nowhere" / "cc"), MECHPY_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("MECHPY_CC", None)
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "CompileError: no C compiler" in r.stdout, r.stdout
    assert "pip install numba" in r.stdout and "backend='numpy'" in r.stdout


def test_numba_module_source_is_the_same_in_every_process():
    """The generated numba source (its cache key) does not depend on the process's
    string hashing: a second process finds the first one's module and machine code
    (the module's promise) only if its text is the same, here with states,
    parameters and z values of the same indices in one block."""
    code = ("import sympy as sp\nfrom mechpy.symbolic import jit\n"
            "y, p, z = (sp.symbols(f'mp_{c}0:3') for c in 'ypz')\n"
            "print(jit._block('f', [y[i] * p[2 - i] + z[i] + sp.Symbol('mp_t') "
            "for i in range(3)], with_z=True))\n")
    outs = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           check=True, env={**os.environ, "PYTHONHASHSEED": str(seed)}).stdout
            for seed in range(6)}
    assert len(outs) == 1, outs
