"""Bench: a pendulum sweep on a 2-worker Dask LocalCluster beside 2 local threads.

10^6 pendulum trajectories (t in [0, 10], 11 samples, rtol 1e-8) through
``mp.solve_many(..., client=client)`` on ``LocalCluster(n_workers=2,
threads_per_worker=1)`` against ``mp.solve_many(..., threads=2)`` on this
machine: the cluster's overhead (chunk tasks, pickling, gathering the
176 MB result).  A few smaller sizes locate the crossover below which the
local run is faster.  The same sweep as a plain ``dask.array.map_blocks``
over SciPy's ``solve_ivp`` (DOP853, same rtol) on the same cluster runs on a
subset and is scaled.  The error column is the largest difference from the
local mechpy run (0: the cluster's result equals it bit for bit).  Skipped
when ``dask[distributed]`` is not installed.
"""
import time

import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Sweeps on a Dask cluster"
ORDER = 16

_TE = np.linspace(0.0, 10.0, 11)


def _ensemble(k):
    return np.column_stack([np.linspace(0.1, 3.0, k), np.zeros(k)])


def _scipy_block(y0s):
    """One map_blocks block: solve_ivp DOP853 per row -> (rows, 2, 11)."""
    from scipy.integrate import solve_ivp

    def f(t, y):
        return [y[1], -9.81 * np.sin(y[0])]

    return np.stack([solve_ivp(f, (0.0, 10.0), y0, method="DOP853", rtol=1e-8, atol=1e-10,
                               t_eval=_TE).y for y0 in y0s])


def run(quick: bool):
    try:
        from dask.distributed import Client, LocalCluster
        import dask.array as da
    except ImportError:
        print("  (dask[distributed] is not installed: pip install 'mechpy-classical[cluster]')")
        return []
    p = mp.scenes.Pendulum()
    rows = []
    big = 100_000 if quick else 1_000_000
    sizes = [1_000, 10_000, 100_000] if quick else [1_000, 10_000, 100_000, big]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0", silence_logs=40) as cluster, \
            Client(cluster) as client:
        client.wait_for_workers(2, timeout=120)
        crossover = None
        for k in sizes:
            y0s = _ensemble(k)
            # the big sizes run once: their results are the ones compared
            t0 = time.perf_counter()
            local = mp.solve_many(p, (0, 10), y0s, t_eval=_TE, threads=2)
            t_loc = time.perf_counter() - t0
            t0 = time.perf_counter()
            on = mp.solve_many(p, (0, 10), y0s, t_eval=_TE, client=client)
            t_cl = time.perf_counter() - t0
            err = float(np.max(np.abs(on.y - local.y)))
            if k < 100_000:
                t_loc = median_time(lambda: mp.solve_many(p, (0, 10), y0s, t_eval=_TE,
                                                          threads=2), repeat=3, warmup=0)
                t_cl = median_time(lambda: mp.solve_many(p, (0, 10), y0s, t_eval=_TE,
                                                         client=client), repeat=3, warmup=0)
            if crossover is None and t_cl <= t_loc:
                crossover = k
            name = f"{k} pendulum trajectories, t=10, rtol=1e-8 (11 samples each)"
            rows.append(dict(problem=name, impl="mechpy solve_many, 2 local threads",
                             path=f"cluster-local-{k}", time=t_loc, error=0.0))
            rows.append(dict(problem=name, impl="mechpy solve_many, 2-worker LocalCluster",
                             path=f"cluster-{k}", time=t_cl, error=err,
                             note=f"cluster/local = {t_cl / t_loc:.2f}"))
        # the same sweep as dask.array.map_blocks over solve_ivp, on a subset, scaled
        sub = 200 if quick else 1000
        y0s = _ensemble(big)[:: big // sub]
        arr = da.from_array(y0s, chunks=(sub // 8, 2))
        lazy = arr.map_blocks(_scipy_block, dtype=float, new_axis=2,
                              chunks=(arr.chunks[0], (2,), (11,)))
        t_sp = median_time(lambda: lazy.compute(), repeat=1, warmup=0) * (big / sub)
        ys = lazy.compute()
        ref = mp.solve_many(p, (0, 10), y0s, t_eval=_TE, threads=2).y
        rows.append(dict(problem=f"{big} pendulum trajectories, t=10, rtol=1e-8 "
                                 "(11 samples each)",
                         impl="dask map_blocks of scipy solve_ivp, 2-worker LocalCluster",
                         path="cluster-scipy", time=t_sp,
                         error=float(np.max(np.abs(ys - ref))),
                         note=f"{sub} trajectories timed, scaled to {big}; error = largest "
                              "difference from mechpy's samples"))
        rows[-1]["note"] += (f"; crossover: the cluster is faster from {crossover} "
                             "trajectories" if crossover else
                             "; the cluster was slower at every size measured")
    return rows
