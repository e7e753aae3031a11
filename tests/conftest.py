import ctypes
import os
from pathlib import Path

import numpy as np
import pytest

import mechpy

SANITIZED = bool(os.environ.get("MECHPY_SANITIZED"))


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
