"""mp.solve_many(..., client=...) on a Dask LocalCluster: the same result as a
local run bit for bit, field by field; compiled scenes and Python callables
travel, C callbacks do not; a worker killed mid-run costs nothing; lazy
dask arrays reduce to the local figures; bad inputs are clear errors.

Every wait has a timeout, so the file stops by itself on a loaded machine.
"""
import concurrent.futures
import ctypes
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

distributed = pytest.importorskip("dask.distributed")
da = pytest.importorskip("dask.array")

TIMEOUT = 120      # seconds for any one sweep, far above the ~1-8 s each takes


def _cluster():
    return distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                    dashboard_address=":0", silence_logs=40)


@pytest.fixture(scope="module")
def client():
    with _cluster() as cluster, distributed.Client(cluster, timeout=60) as c:
        c.wait_for_workers(2, timeout=60)
        yield c


def _run(fn, *a, **kw):
    """fn(*a, **kw) in a thread, failing the test after TIMEOUT seconds."""
    with concurrent.futures.ThreadPoolExecutor(1) as ex:
        return ex.submit(fn, *a, **kw).result(timeout=TIMEOUT)


def _assert_same(a, b):
    assert type(a) is type(b) and set(a) == set(b)
    for name in a:
        x, y = np.asarray(a[name]), np.asarray(b[name])
        # a failed trajectory's samples past its failure are NaN in both
        assert np.array_equal(x, y, equal_nan=x.dtype.kind == "f"), name
        assert np.asarray(a[name]).dtype == np.asarray(b[name]).dtype, name


def _pendulum_ensemble(k, seed=1):
    rng = np.random.default_rng(seed)
    y0s = np.column_stack([rng.uniform(-3, 3, k), rng.uniform(-1, 1, k)])
    amps = rng.uniform(0.0, 1.5, k)
    return y0s, {"drive_amplitude": amps}


SCENE = mp.scenes.Pendulum(damping=0.5, drive_frequency=2 / 3)
T_EVAL = np.linspace(0.0, 20.0, 11)


def test_importing_mechpy_does_not_import_dask():
    code = "import sys, mechpy; print(any(m.split('.')[0] in ('dask', 'distributed') " \
           "for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("chunk_size", [None, 7, 1000])
def test_scene_sweep_equals_local_run(client, chunk_size):
    y0s, params = _pendulum_ensemble(101)
    local = mp.solve_many(SCENE, (0, 20), y0s, params=params, t_eval=T_EVAL)
    remote = _run(mp.solve_many, SCENE, (0, 20), y0s, params=params, t_eval=T_EVAL,
                  client=client, chunk_size=chunk_size)
    _assert_same(remote, local)
    assert remote.y.shape == (101, 2, 11)


def test_failed_trajectories_keep_their_place(client):
    # a step budget that some trajectories exhaust: status and success travel per row
    y0s, params = _pendulum_ensemble(40, seed=3)
    kw = dict(params=params, t_eval=T_EVAL, max_steps=125)
    local = mp.solve_many(SCENE, (0, 20), y0s, **kw)
    assert 0 < np.count_nonzero(local.success) < 40
    _assert_same(_run(mp.solve_many, SCENE, (0, 20), y0s, client=client, chunk_size=6, **kw),
                 local)


def test_errors_name_the_trajectory_in_the_whole_ensemble(client):
    """The error rule is applied once on the joined result: a singular HeavyTop state
    (theta = 0) in row 9 of chunks of 4 raises naming trajectory 9, as a local run does;
    with errors="status" its status and raise_for_status travel too."""
    top = mp.scenes.HeavyTop(1.0, 2.0, 1.0)
    y0s = np.tile([0.0, 0.5, 0.0, 1.0, 1.0, 1.0], (12, 1))
    y0s[9, 1] = 0.0                                   # theta = 0: singular Euler angles
    with pytest.raises(mp.SingularityError) as local:
        mp.solve_many(top, (0, 1), y0s)
    with pytest.raises(mp.SingularityError) as remote:
        _run(mp.solve_many, top, (0, 1), y0s, client=client, chunk_size=4)
    assert "trajectory 9" in str(local.value) and str(remote.value) == str(local.value)
    st_local = mp.solve_many(top, (0, 1), y0s, errors="status")
    st_remote = _run(mp.solve_many, top, (0, 1), y0s, errors="status", client=client,
                     chunk_size=4)
    _assert_same(st_remote, st_local)
    with pytest.raises(mp.SingularityError, match="trajectory 9"):
        st_remote.raise_for_status()


def test_failing_first_row_gives_statuses_as_locally(client):
    """errors="status" with row 0 failing (HeavyTop singular at y0, SingularityError
    under "auto"): the cluster's checks ran row 0 under "auto" and raised where the
    local run returns statuses; now the same result, field by field, and "auto"
    still raises naming trajectory 0, as locally."""
    top = mp.scenes.HeavyTop(1.0, 2.0, 1.0)
    y0s = np.tile([0.0, 0.5, 0.0, 1.0, 1.0, 1.0], (6, 1))
    y0s[0, 1] = 0.0                                   # theta = 0: singular Euler angles
    local = mp.solve_many(top, (0, 1), y0s, errors="status")
    assert local.status.tolist() == [-3, 0, 0, 0, 0, 0]
    _assert_same(_run(mp.solve_many, top, (0, 1), y0s, errors="status", client=client,
                      chunk_size=2), local)
    lazy = _run(mp.solve_many, top, (0, 1), y0s, errors="status", client=client,
                chunk_size=2, lazy=True)
    assert np.array_equal(lazy.status.compute(), local.status)
    with pytest.raises(mp.SingularityError, match="trajectory 0"):
        _run(mp.solve_many, top, (0, 1), y0s, client=client, chunk_size=2)
    with pytest.raises(ValueError, match="errors must be one of"):
        mp.solve_many(top, (0, 1), y0s, errors="quiet", client=client)


def test_compiled_scene_is_rebuilt_on_the_workers(client):
    th, = mp.coordinates("theta")
    m, l, g = sp.symbols("m length g")
    L = m * l ** 2 / 2 * th.diff(sp.Symbol("t")) ** 2 + m * g * l * sp.cos(th)
    sc = mp.lagrangian(L, [th], params=dict(m=1.0, length=1.0, g=9.81))
    y0s = np.column_stack([np.linspace(0.1, 3.0, 30), np.zeros(30)])
    params = {"length": np.linspace(0.5, 2.0, 30)}
    local = mp.solve_many(sc, (0, 5), y0s, params=params, t_eval=[2.5, 5.0])
    remote = _run(mp.solve_many, sc, (0, 5), y0s, params=params, t_eval=[2.5, 5.0],
                  client=client, chunk_size=8)
    _assert_same(remote, local)
    # the workers ran the C library, not a Python fallback: their processes loaded it
    libs = client.run(lambda: sorted(m for m in sys.modules if m.startswith("mechpy.symbolic")))
    assert all("mechpy.symbolic.scene" in v for v in libs.values())


def test_python_callable_travels_by_cloudpickle(client):
    w = 1.7                                     # a closure: cloudpickle sends it by value

    def rhs(t, y, a):
        return [y[1], -a * w * w * np.sin(y[0])]

    y0s = np.column_stack([np.linspace(0.1, 1.0, 12), np.zeros(12)])
    params = np.linspace(0.5, 1.5, 12)[:, None]
    local = mp.solve_many(rhs, (0, 3), y0s, params=params, t_eval=[1.0, 3.0])
    remote = _run(mp.solve_many, rhs, (0, 3), y0s, params=params, t_eval=[1.0, 3.0],
                  client=client, chunk_size=5)
    _assert_same(remote, local)


def test_lazy_arrays_reduce_to_the_local_figures(client):
    y0s, params = _pendulum_ensemble(90, seed=5)
    local = mp.solve_many(SCENE, (0, 20), y0s, params=params, t_eval=T_EVAL)
    lazy = mp.solve_many(SCENE, (0, 20), y0s, params=params, t_eval=T_EVAL, client=client,
                         lazy=True, chunk_size=20)
    assert isinstance(lazy.y, da.Array) and lazy.y.shape == (90, 2, 11)
    assert lazy.y.chunks[0] == (20, 20, 20, 20, 10)
    assert np.array_equal(lazy.t, local.t)
    peak, nfev, y = _run(lambda: da.compute(abs(lazy.y).max(axis=0), lazy.nfev.sum(), lazy.y))
    assert np.array_equal(peak, np.abs(local.y).max(axis=0))        # max is exact
    assert nfev == local.nfev.sum()
    assert np.array_equal(y, local.y)
    mean = _run(lazy.y.mean(axis=0).compute)
    # a tree of partial sums against NumPy's pairwise sum: measured 4e-16 relative
    np.testing.assert_allclose(mean, local.y.mean(axis=0), rtol=1e-14, atol=1e-14)


def test_a_worker_killed_mid_run_costs_only_its_chunks():
    # ~6 s of C work over 24 chunks; one worker process is killed with SIGKILL once
    # a few chunks are done, the nanny starts another, the scheduler runs the lost
    # chunks (running and finished-but-not-gathered ones) again
    k = 1200
    y0s, params = _pendulum_ensemble(k, seed=7)
    kw = dict(params=params, t_eval=np.linspace(0.0, 600.0, 7), rtol=1e-10, atol=1e-12)
    local = mp.solve_many(SCENE, (0, 600), y0s, threads=2, **kw)
    with _cluster() as cluster, distributed.Client(cluster, timeout=60) as c:
        c.wait_for_workers(2, timeout=60)
        seen = {}

        def killer():
            deadline = time.monotonic() + TIMEOUT
            while time.monotonic() < deadline:
                states = c.run_on_scheduler(lambda dask_scheduler: [
                    ts.state for key, ts in dask_scheduler.tasks.items()
                    if str(key).startswith("mechpy-solve_many")], )
                if sum(s == "memory" for s in states) >= 3:
                    pids = c.run(os.getpid)
                    addr, pid = sorted(pids.items())[0]
                    seen.update(states=states, addr=addr)
                    os.kill(pid, signal.SIGKILL)
                    return
                time.sleep(0.05)

        th = threading.Thread(target=killer, daemon=True)
        th.start()
        remote = _run(mp.solve_many, SCENE, (0, 600), y0s, client=c, chunk_size=50, **kw)
        th.join(timeout=TIMEOUT)
        assert seen, "the worker was never killed"
        assert len(seen["states"]) == 24 and "memory" in seen["states"]
        assert sum(s == "memory" for s in seen["states"]) < 24, "killed after the run"
        assert seen["addr"] not in c.scheduler_info()["workers"]
    _assert_same(remote, local)


def test_c_callback_cannot_travel(client):
    CB = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.POINTER(ctypes.c_double),
                          ctypes.POINTER(ctypes.c_double), ctypes.c_void_p)

    @CB
    def f(t, y, dydt, ud):
        dydt[0] = y[1]
        dydt[1] = -y[0]

    before = set(client.futures)
    with pytest.raises(TypeError, match="C callback.*cannot travel"):
        mp.solve_many(f, (0, 1), [[1.0, 0.0]], client=client)
    with pytest.raises(TypeError, match="C callback.*cannot travel"):
        mp.solve_many(mp.SecondOrder(f), (0, 1), [[1.0, 0.0]], client=client)
    assert set(client.futures) == before           # nothing was submitted


def test_bad_inputs(client):
    y0s = [[0.1, 0.0], [0.2, 0.0]]
    for bad in (0, -3):
        with pytest.raises(ValueError, match="chunk_size"):
            mp.solve_many(SCENE, (0, 1), y0s, client=client, chunk_size=bad)
    with pytest.raises(TypeError, match="chunk_size"):
        mp.solve_many(SCENE, (0, 1), y0s, client=client, chunk_size=2.5)
    with pytest.raises(TypeError, match="client must be a dask.distributed.Client"):
        mp.solve_many(SCENE, (0, 1), y0s, client="tcp://127.0.0.1:8786")
    with pytest.raises(ValueError, match="need a client"):
        mp.solve_many(SCENE, (0, 1), y0s, lazy=True)
    with pytest.raises(ValueError, match="need a client"):
        mp.solve_many(SCENE, (0, 1), y0s, chunk_size=4)
    with pytest.raises(ValueError, match="lazy=True"):
        mp.solve_many(SCENE, (0, 1), y0s, client=client, lazy=True, progress=True)
    # the local checks run before anything is submitted
    with pytest.raises(ValueError, match="y0s must have 2 columns"):
        mp.solve_many(SCENE, (0, 1), [[0.1, 0.0, 0.0]], client=client)
    with pytest.raises(ValueError, match="rtol"):
        mp.solve_many(SCENE, (0, 1), y0s, client=client, rtol=-1.0)
    empty = mp.solve_many(SCENE, (0, 1), np.empty((0, 2)), client=client)
    _assert_same(empty, mp.solve_many(SCENE, (0, 1), np.empty((0, 2))))


def test_progress_with_a_client(client, capsys):
    y0s, params = _pendulum_ensemble(20)
    local = mp.solve_many(SCENE, (0, 20), y0s, params=params)
    _assert_same(_run(mp.solve_many, SCENE, (0, 20), y0s, params=params, client=client,
                      progress=True), local)


def test_closed_client():
    with _cluster() as cluster:
        c = distributed.Client(cluster, timeout=60)
        c.close()
        with pytest.raises(ValueError, match="client is closed"):
            mp.solve_many(SCENE, (0, 1), [[0.1, 0.0]], client=c)


def test_a_client_with_one_thread():
    # one worker with one thread is a cluster (the smallest one), not "no workers"
    y0s, params = _pendulum_ensemble(40, seed=3)
    kw = dict(params=params, t_eval=np.linspace(0.0, 5.0, 3))
    local = mp.solve_many(SCENE, (0, 5), y0s, threads=1, **kw)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=":0", silence_logs=40) as cluster, \
            distributed.Client(cluster, timeout=60) as c:
        c.wait_for_workers(1, timeout=60)
        assert sum(c.nthreads().values()) == 1
        _assert_same(_run(mp.solve_many, SCENE, (0, 5), y0s, client=c, **kw), local)


def test_chunks_are_a_few_per_worker_thread(client):
    # the documented default: about four chunks per worker thread (2 threads here), and
    # chunk_size rows each when given; a lazy result's fields keep the chunks' rows
    assert sum(client.nthreads().values()) == 2
    k = 40
    y0s, params = _pendulum_ensemble(k, seed=5)
    for chunk_size, rows in [(None, (5,) * 8), (7, (7,) * 5 + (5,)), (100, (40,))]:
        lazy = _run(mp.solve_many, SCENE, (0, 1), y0s, params=params, client=client,
                    chunk_size=chunk_size, lazy=True)
        assert lazy.y.chunks[0] == rows and lazy.status.chunks[0] == rows


def test_client_without_dask_names_the_extra_that_installs_it(monkeypatch):
    # issue 51, item 20: without Dask, client= names the install command, with the
    # extra of pyproject.toml that holds dask[distributed] (not a bare import error)
    import pathlib
    import tomllib
    meta = tomllib.loads((pathlib.Path(__file__).parents[1] / "pyproject.toml").read_text())
    project = meta["project"]
    extra = next(name for name, reqs in project["optional-dependencies"].items()
                 if name not in ("test", "docs") and any(r.startswith("dask[distributed]")
                                                         for r in reqs))
    want = f'pip install "{project["name"]}[{extra}]"'
    for mod in ("dask.distributed", "distributed"):
        monkeypatch.setitem(sys.modules, mod, None)   # an import of it now fails
    with pytest.raises(ModuleNotFoundError) as exc:
        mp.solve_many(SCENE, (0, 1), [[0.1, 0.0]], client=object())
    assert want in str(exc.value) and "client" in str(exc.value)


def test_events_are_refused_with_a_client_before_anything_is_submitted(client):
    """events with a client: a ValueError naming events (the chunks' event lists are not
    joined), raised before any task is submitted; without a client the same call runs.
    Pins cluster._solve_many's refusal, which no other test reaches."""
    y0s, params = _pendulum_ensemble(6, seed=4)

    def cross(t, y):
        return y[0]

    local = mp.solve_many(SCENE, (0, 5), y0s, params=params, events=cross)
    assert local.success.all()
    before = set(client.futures)
    with pytest.raises(ValueError, match="events are not taken with a client"):
        _run(mp.solve_many, SCENE, (0, 5), y0s, params=params, events=cross, client=client)
    assert set(client.futures) == before            # nothing was submitted


def test_the_one_step_probe_runs_under_statuses(client):
    """errors="raise" with a client on an ensemble that solves: the one-step probe (the
    local checks on row 0, max_steps=1) exhausts its budget by design, so it must run
    under errors="status" whatever the caller's errors; under the caller's "raise" it
    would raise StepBudgetError for a sweep that succeeds.  The sweep equals the local
    run field by field, and a real failure still raises its own class, naming the
    trajectory in the whole ensemble (HeavyTop singular at row 0: SingularityError).
    Pins the probe's errors="status" in cluster._solve_many."""
    y0s, params = _pendulum_ensemble(12, seed=6)
    kw = dict(params=params, t_eval=np.linspace(0.0, 5.0, 6), errors="raise")
    local = mp.solve_many(SCENE, (0, 5), y0s, **kw)
    assert local.success.all()
    _assert_same(_run(mp.solve_many, SCENE, (0, 5), y0s, client=client, chunk_size=5, **kw),
                 local)
    top = mp.scenes.HeavyTop(1.0, 2.0, 1.0)
    bad = np.tile([0.0, 0.5, 0.0, 1.0, 1.0, 1.0], (4, 1))
    bad[0, 1] = 0.0                                  # theta = 0: singular Euler angles
    with pytest.raises(mp.SingularityError, match="trajectory 0"):
        _run(mp.solve_many, top, (0, 1), bad, client=client, chunk_size=2, errors="raise")


def test_client_without_dask_names_the_missing_module(monkeypatch):
    """The ModuleNotFoundError of client= without Dask carries the name of the module
    whose import failed (as Python's own does, for tools that read ``exc.name``), and
    "dask" when the import error names none."""
    import importlib
    import mechpy.cluster as cluster
    for mod in ("dask.distributed", "distributed"):
        monkeypatch.setitem(sys.modules, mod, None)   # an import of it now fails
    with pytest.raises(ImportError) as ref:
        importlib.import_module("dask.distributed")
    assert ref.value.name                             # Python names the module
    with pytest.raises(ModuleNotFoundError) as exc:
        mp.solve_many(SCENE, (0, 1), [[0.1, 0.0]], client=object())
    assert exc.value.name == ref.value.name

    def unnamed(*a, **k):
        raise ImportError("no dask here")
    with monkeypatch.context() as m, pytest.raises(ModuleNotFoundError) as exc:
        m.setattr("builtins.__import__", unnamed)
        cluster._require_dask()
    assert exc.value.name == "dask"
