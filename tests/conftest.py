import ctypes
import os
import re
from pathlib import Path

import numpy as np
import pytest

import mechpy

SANITIZED = bool(os.environ.get("MECHPY_SANITIZED"))
ROOT = Path(__file__).resolve().parent.parent


def _test_extra():
    """Import names of mechpy's `test` extra (``pytest-timeout`` -> ``pytest_timeout``),
    from the installed distribution's metadata (the sdist run has no pyproject.toml)."""
    from importlib import metadata
    reqs = [r.split(";")[0] for r in metadata.requires("mechpy-classical") or []
            if re.search(r"""extra\s*==\s*["']test["']""", r)]
    if not reqs:
        raise RuntimeError("mechpy's installed metadata lists no `test` extra")
    return {re.split(r"[<>=!~\[; (]", r.strip())[0].lower().replace("-", "_") for r in reqs}


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """In CI (``CI`` set): a skip for a missing module of the `test` extra is a failure.

    pytest.importorskip skips with "could not import 'name'"; an incomplete test
    environment must not pass quietly where the extra is meant to be installed.
    """
    outcome = yield
    rep = outcome.get_result()
    if not rep.skipped or os.environ.get("CI", "").lower() not in ("1", "true", "yes"):
        return
    reason = str(rep.longrepr[-1]) if isinstance(rep.longrepr, tuple) else str(rep.longrepr)
    m = re.search(r"could not import '([\w.]+)'", reason)
    if m and m.group(1).split(".")[0].lower() in _test_extra():
        rep.outcome = "failed"
        rep.longrepr = (f"CI: skipped because {m.group(1)!r} (pyproject's `test` extra) is "
                        f"missing: {reason}")


@pytest.fixture
def rng():
    return np.random.default_rng(20241121)


def pytest_report_header(config):
    core = Path(mechpy._core.__file__)
    return f"mechpy._core: {core}" + (" (ASan+UBSan)" if SANITIZED else "")


def pytest_sessionstart(session):
    if SANITIZED:  # scripts/sanitize.sh: the sanitized copy must be the one imported
        core = Path(mechpy._core.__file__).resolve()
        if "asan" not in core.parts:
            raise pytest.UsageError(f"sanitizer run imported the normal build {core}")


def pytest_sessionfinish(session, exitstatus):
    """Under the sanitizers: a leak check inside the live interpreter.

    Everything Python still holds is reachable from its globals, so LSan reports
    only blocks that nothing points to any more (a C path that forgot to free).
    """
    if not SANITIZED or "leak_check_at_exit=0" not in os.environ.get("ASAN_OPTIONS", ""):
        return
    try:
        check = ctypes.CDLL(None).__lsan_do_recoverable_leak_check
    except AttributeError:
        return
    check.restype = ctypes.c_int
    import gc
    gc.collect()  # cyclic garbage not yet collected is unreachable, not leaked
    if check():
        session.exitstatus = 1
        print("\nLeakSanitizer: leaks found (report above)")


@pytest.fixture
def double_pendulum():
    """The double pendulum from its Lagrangian (m1 = m2 = 1, l1 = 1, l2 = 0.5, g = 9.81),
    compiled: the drawings of mp.plot.animate and mp.live.animate take it."""
    import sympy as sp
    th1, th2 = mechpy.coordinates("theta1 theta2")
    m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g")
    w1, w2 = th1.diff(), th2.diff()
    L = ((m1 + m2) * l1**2 * w1**2 / 2 + m2 * l2**2 * w2**2 / 2
         + m2 * l1 * l2 * w1 * w2 * sp.cos(th1 - th2)
         + (m1 + m2) * g * l1 * sp.cos(th1) + m2 * g * l2 * sp.cos(th2))
    return mechpy.lagrangian(L, [th1, th2], params=dict(m1=1.0, m2=1.0, l1=1.0, l2=0.5, g=9.81))
