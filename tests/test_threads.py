"""Thread safety: mixed calls from 8 threads equal the serial results bit for
bit, and long C calls release the GIL (another Python thread runs meanwhile).

Free-threaded CPython (no GIL) is not tested and not declared supported.
"""
from __future__ import annotations

import random
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import mechpy as mp
from mechpy import _core


def _tasks():
    rng = np.random.default_rng(7)
    angles = rng.uniform(-3, 3, (2000, 3))
    A = rng.standard_normal((40, 40))
    K = A @ A.T + 40 * np.eye(40)
    Mm = np.diag(rng.uniform(1, 2, 40))
    V, F = mp.inertia.uv_sphere(1.0, 8, 16)
    P = mp.scenes.Pendulum(damping=0.1)
    return {
        "solve dop853 scene": lambda: mp.solve(P, (0, 20), [2.5, 0.0], rtol=1e-10).y,
        "solve radau scene": lambda: mp.solve(mp.scenes.VanDerPol(mu=100.0), (0, 5), [2.0, 0.0],
                                              method="radau").y,
        "solve python rhs": lambda: mp.solve(lambda t, y: -y, (0, 2), [1.0, 2.0], rtol=1e-6).y,
        "solve_many": lambda: mp.solve_many(P, (0, 5), np.c_[np.linspace(0.1, 3, 64),
                                                              np.zeros(64)], threads=2).y,
        "rotations": lambda: mp.rotation.euler_angles(mp.rotation.euler_matrix(angles)),
        "quaternions": lambda: mp.rotation.euler_from_quat(mp.rotation.quat_from_euler(angles)),
        "modes": lambda: mp.modes.normal_modes(K, Mm).vectors,
        "inertia mesh": lambda: mp.inertia.mesh(V, F, density=2.0).inertia,
        "principal axes": lambda: mp.inertia.principal_axes(np.diag([1.0, 2.0, 3.0]) + 0.1)[1],
        "free rotation": lambda: mp.rigid.free_rotation([1.0, 2.0, 3.0], [0.1, 1.0, 0.1],
                                                        np.linspace(0, 50, 500)),
        "rigid body scene": lambda: mp.solve(mp.scenes.RigidBody((1.0, 2.0, 3.0)), (0, 20),
                                             [0.1, 1.0, 0.1], rtol=1e-10).y,
        "brachistochrone": lambda: mp.variational.brachistochrone(2.0, 1.0, n=100).y,
    }


def test_mixed_calls_from_8_threads_equal_serial():
    tasks = _tasks()
    serial = {name: f() for name, f in tasks.items()}
    jobs = [name for name in tasks for _ in range(4)]
    random.Random(3).shuffle(jobs)
    with ThreadPoolExecutor(max_workers=8) as ex:
        results = list(ex.map(lambda name: (name, tasks[name]()), jobs))
    assert len(results) == len(jobs)
    for name, out in results:
        assert np.array_equal(out, serial[name]), f"{name}: threaded result differs"


LONG = {
    # (each call at least ~0.1 s: 20 switch intervals are 0.02 s, which a release build
    # of a 4000-unit Kepler orbit, 0.020 s, and 400 lane trajectories reached)
    "ode_solve": lambda: mp.solve(mp.scenes.Kepler(), (0, 20000.0),
                                  mp.scenes.Kepler().initial_state(0.6), rtol=1e-12),
    "ode_solve_many": lambda: mp.solve_many(mp.scenes.Pendulum(), (0, 50.0),
                                            np.c_[np.linspace(0.1, 3, 2000), np.zeros(2000)],
                                            threads=1, rtol=1e-10),
    "rotation_euler_matrix": lambda: mp.rotation.euler_matrix(np.ones((1_000_000, 3))),
    "modes_dense": lambda: mp.modes.normal_modes(np.diag(np.arange(1.0, 401.0)) + 0.01,
                                                 np.eye(400), method="dense"),
}


SWITCH = 0.001        # the switch interval during the check (s)


def _python_ran_during(call):
    """Run ``call(record)`` in a worker thread while the main thread loops; ``call`` runs
    the C function between ``record("start")`` and ``record("end")``.  Return the call's
    length and whether the main thread ran throughout it.

    With the GIL held through the C call, the main thread can run only next to its ends
    (before the worker takes the GIL back to record them; on a loaded machine that can
    take several switch intervals), so one gap covers most of the call.  With the GIL
    released the main thread runs all along: no gap between its ticks (or the call's
    ends) spans half of the call."""
    window = {}

    def record(key):
        window[key] = time.perf_counter()

    worker = threading.Thread(target=call, args=(record,))
    ticks = []
    interval = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH)
    try:
        worker.start()
        while worker.is_alive():
            ticks.append(time.perf_counter())
        worker.join()
    finally:
        sys.setswitchinterval(interval)
    t0, t1 = window["start"], window["end"]
    points = np.array([t0] + [t for t in ticks if t0 < t < t1] + [t1])
    return t1 - t0, np.diff(points).max() < 0.5 * (t1 - t0)


@pytest.mark.parametrize("entry", list(LONG))
def test_long_c_call_releases_the_gil(entry, monkeypatch):
    """While the C call runs in one thread, the main thread keeps executing Python."""
    inner = getattr(_core, entry)
    box = {}

    def timed(*a, **kw):
        box["record"]("start")
        try:
            return inner(*a, **kw)
        finally:
            box["record"]("end")

    def call(record):
        box["record"] = record
        LONG[entry]()

    monkeypatch.setattr(_core, entry, timed)
    # The OS may deschedule either thread for longer than EDGE on a loaded machine, so
    # each check gets three tries: one clear observation decides.
    for _ in range(3):
        length, ran = _python_ran_during(call)
        assert length > 20 * SWITCH, f"{entry}: the call ({length:.3f} s) is too short to tell"
        if ran:
            break
    assert ran, f"{entry}: the main thread did not run during the C call"


def test_the_check_sees_a_call_that_holds_the_gil():
    """The check above can fail: a builtin that never releases the GIL (sum over a
    range, one C call) is reported as such."""
    def call(record):
        record("start")
        sum(range(20_000_000))
        record("end")

    for _ in range(3):
        length, ran = _python_ran_during(call)
        assert length > 20 * SWITCH
        if not ran:
            break
    assert not ran
