"""Sweeps beyond one machine: ``mp.solve_many(..., client=client)`` on Dask.

With a ``dask.distributed.Client`` the ensemble (the initial states ``y0s``
and the per-trajectory ``params``) is cut into chunks of consecutive rows;
each chunk is one task that calls :func:`mechpy.solve_many` in C on a worker
(the GIL released), and the chunks' :class:`mechpy.EnsembleSolution` fields
are joined in the original order.  Each trajectory is the same computation
as in a local run, so the result equals ``mp.solve_many(...)`` on one machine
bit for bit.

Everything here is Dask's own machinery: ``client.map`` schedules the chunks,
the scheduler reruns the chunks of a worker that is lost mid-run on the
workers left (nothing lost, nothing duplicated: each chunk's result is kept
once, under its key), ``dask.distributed.progress`` draws the progress, and
``lazy=True`` gives ``dask.array`` fields built with ``da.from_delayed``.
Dask is imported only when a client is given (install it with
``pip install "mechpy-classical[cluster]"``; without it ``client=`` is a
``ModuleNotFoundError`` that says so).

What travels to the workers
---------------------------
- A scene pickles by value (its parameters); a compiled scene
  (:func:`mechpy.lagrangian`, :func:`mechpy.equations`) travels as its C
  source and parameters and is rebuilt on the worker, which needs a C
  compiler; the build cache is keyed by the source's hash, so each worker
  process compiles it at most once (not at all when it shares the cache
  folder).
- A Python right-hand side travels if ``cloudpickle`` can serialise it (a
  lambda, a closure, a function of an importable module); it then runs in
  Python on the worker, one thread per chunk, at the speed it has locally.
- A C callback (a ctypes function pointer, a ``scipy.LowLevelCallable``, a
  numba ``cfunc``, or a scene carrying one) is an address in this process's
  memory and cannot travel: ``TypeError`` before anything is submitted.
- The chunks' inputs travel inside their tasks (they are not scattered), so
  the scheduler can run a lost chunk again from its task alone.

Array shapes follow the layout rule in :mod:`mechpy` (``help(mechpy)``):
``y`` is (k, n, m) whether it is gathered or lazy.
"""
from __future__ import annotations

import inspect
import math
import operator

import numpy as np

from ._callbacks import c_address
from ._solution import _errors_mode, _raise_first
from ._system import SecondOrder, _ensemble_params
from ._validate import as_array, as_int

__all__: list = []

#: Chunks per worker thread when ``chunk_size`` is not given: a few per
#: thread balance the load and bound what a lost worker costs.
CHUNKS_PER_THREAD = 4


def _solve_chunk(local, system, t_span, y0s, params, options):
    """Run on a worker: one chunk of the ensemble through the local solve_many,
    with every failure reported as a status (``errors="status"``): the error
    rule is applied once, on the joined result, so that an exception names the
    trajectory's index in the whole ensemble, not in its chunk."""
    return local(system, t_span, y0s, params=params, **dict(options, errors="status"))


#: the extra of pyproject.toml that installs Dask
INSTALL_DASK = 'pip install "mechpy-classical[cluster]"'


def _require_dask() -> None:
    """Import dask.distributed, or ModuleNotFoundError naming the extra that
    installs it (Dask is optional: only ``client=`` needs it)."""
    try:
        import dask.distributed  # noqa: F401
    except ImportError as exc:
        raise ModuleNotFoundError(
            f"solve_many(client=...) runs on Dask, which is not installed ({exc}): "
            f"{INSTALL_DASK} (or pip install \"dask[distributed]\")",
            name=getattr(exc, "name", None) or "dask") from exc


def _client_threads(client) -> int:
    """The cluster's worker threads in total; ValueError for a closed client,
    TypeError for anything but a ``dask.distributed.Client``."""
    from dask.distributed import Client
    if not isinstance(client, Client):
        raise TypeError(f"client must be a dask.distributed.Client, got {type(client).__name__}")
    if client.status != "running":
        raise ValueError(f"client is {client.status}, not running: open a new "
                         "dask.distributed.Client")
    nthreads = sum(client.nthreads().values())
    if nthreads < 1:
        raise ValueError("client has no workers: start some (or wait for them with "
                         "client.wait_for_workers) before solve_many")
    return nthreads


def _check_travels(system):
    """TypeError unless ``system`` can be sent to another process."""
    obj = system.accel if isinstance(system, SecondOrder) else system
    for o in (obj, getattr(obj, "_torque_fn", None)):
        if o is not None and c_address(o) is not None:
            raise TypeError(
                "system holds a C callback (a ctypes function pointer, LowLevelCallable or "
                "numba cfunc): it is an address in this process and cannot travel to a Dask "
                "worker; use a scene, a compiled scene (mp.lagrangian / mp.equations) or a "
                "Python callable with client=, or solve_many without a client")
    import cloudpickle
    try:
        cloudpickle.dumps(system)
    except Exception as exc:
        raise TypeError(f"system cannot be pickled to travel to a Dask worker: {exc}") from exc


def _chunk_bounds(k: int, nthreads: int, chunk_size) -> list:
    """[(start, stop), ...] cutting k rows into chunks of chunk_size rows
    (default: CHUNKS_PER_THREAD chunks per worker thread)."""
    if chunk_size is None:
        size = max(1, math.ceil(k / (CHUNKS_PER_THREAD * nthreads)))
    else:
        size = as_int(chunk_size, "chunk_size", minimum=1)
    return [(a, min(a + size, k)) for a in range(0, k, size)]


def _join(parts: list, sizes: list):
    """One EnsembleSolution from the chunks' results, field by field: ``t``
    (shared) from the first; arrays whose first axis is the chunk's rows and
    lists are concatenated in order; any other field must be equal in every
    chunk."""
    first = parts[0]
    out = {}
    for name in first:
        vals = [p[name] for p in parts]
        v0 = vals[0]
        if name != "t" and isinstance(v0, np.ndarray) and v0.ndim >= 1 and all(
                v.shape[:1] == (s,) for v, s in zip(vals, sizes)):
            out[name] = np.concatenate(vals, axis=0)
        elif isinstance(v0, list):
            out[name] = [x for v in vals for x in v]
        elif all(_same(v, v0) for v in vals[1:]):
            out[name] = v0
        else:
            raise TypeError(f"solve_many(client=...): field {name!r} differs between chunks "
                            "and is not per trajectory; cannot join it")
    joined = type(first)(**out)
    # the raw C status of each trajectory (raise_for_status reads it)
    object.__setattr__(joined, "_code", np.concatenate(
        [np.asarray(p.__dict__.get("_code", np.zeros(s, int))) for p, s in zip(parts, sizes)]))
    return joined


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b)
    return a == b


def _lazy(template, tasks: list, sizes: list):
    """An EnsembleSolution whose per-trajectory array fields are dask arrays
    concatenated from the delayed chunk solves (shapes and dtypes from the
    one-row ``template``); other fields stay delayed."""
    import dask
    import dask.array as da
    out = {}
    for name, v in template.items():
        if name == "t":
            out[name] = v
        elif isinstance(v, np.ndarray) and v.ndim >= 1 and v.shape[0] == 1:
            out[name] = da.concatenate(
                [da.from_delayed(dask.delayed(operator.getitem)(d, name),
                                 shape=(s,) + v.shape[1:], dtype=v.dtype)
                 for d, s in zip(tasks, sizes)], axis=0)
        else:
            out[name] = dask.delayed(_join_field)([dask.delayed(operator.getitem)(d, name)
                                                   for d in tasks])
    return type(template)(**out)


def _join_field(vals: list):
    """A non-array field of the chunks, joined (lists concatenated; otherwise
    the first, all being equal)."""
    if isinstance(vals[0], list):
        return [x for v in vals for x in v]
    return vals[0]


def _solve_many(*, local, client, chunk_size, lazy, system, t_span, y0s, params=None,
                threads=None, progress=False, **options):
    """mp.solve_many(..., client=client): validate here, solve on the cluster.

    Every argument is checked before anything is submitted (one local solve
    of the first row with a one-step budget runs the same checks as a local
    call and gives the result's fields); then the chunks run on the cluster,
    each a local solve_many on ``threads`` threads (default 1: the worker's
    threads run chunks side by side).  ``local`` is that function
    (mechpy.integrate.solve_many, handed over so that this module imports
    nothing that solves: integrate imports it, one way).
    """
    if client is None:
        raise ValueError("chunk_size and lazy need a client (a dask.distributed.Client)")
    if options.get("events") is not None:
        raise ValueError("events are not taken with a client: the chunks' event lists are "
                         "not joined; solve the ensemble locally (client=None)")
    _require_dask()
    nthreads = _client_threads(client)
    if not isinstance(lazy, (bool, np.bool_)):
        raise TypeError("lazy must be a bool")
    if not isinstance(progress, (bool, np.bool_)):
        raise TypeError("progress must be a bool")
    if lazy and progress:
        raise ValueError("progress=True needs the sweep to run now; with lazy=True, "
                         "dask.distributed.progress the persisted arrays instead")
    Y0 = as_array(y0s, "y0s", ndim=2, allow_empty=True)
    k = Y0.shape[0]
    bounds = _chunk_bounds(k, nthreads, chunk_size)
    per_chunk = 1 if threads is None else as_int(threads, "threads", minimum=1)
    par = _ensemble_params(system, params, k)
    errors = _errors_mode(options.get("errors", _default(local, "errors")))
    # the local checks and the result's fields: one row, one step, its failures
    # statuses (the error rule applies once, to the joined result, as locally)
    probe = dict(options, max_steps=1, errors="status")
    template = local(system, t_span, Y0[:1], params=None if par is None else par[:1],
                     threads=1, progress=False, **probe)
    if k == 0:
        return template
    _check_travels(system)
    opts = dict(options, threads=per_chunk, progress=False)
    chunks = [(Y0[a:b], None if par is None else par[a:b]) for a, b in bounds]
    sizes = [b - a for a, b in bounds]
    if lazy:
        import dask
        solve = dask.delayed(_solve_chunk, pure=True)
        tasks = [solve(local, system, t_span, y, p, opts) for y, p in chunks]
        return _lazy(template, tasks, sizes)
    from dask.base import tokenize
    token = tokenize(system, t_span, opts, Y0, par)
    futures = client.map(_solve_chunk, [local] * len(chunks), [system] * len(chunks),
                         [t_span] * len(chunks),
                         [y for y, _ in chunks], [p for _, p in chunks],
                         [opts] * len(chunks),
                         key=[f"mechpy-solve_many-{token}-{i}" for i in range(len(chunks))])
    if progress:
        from dask.distributed import progress as dask_progress
        dask_progress(futures)
    out = _join(client.gather(futures), sizes)
    _raise_first(out._code, out["message"], errors)
    return out


def _default(local, name: str):
    """The default of one of solve_many's keyword arguments."""
    return inspect.signature(local).parameters[name].default
