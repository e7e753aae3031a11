"""Compile generated C into a shared library, cached on disk, and load it.

The compiler is the one Python was built with (``sysconfig``'s ``CC``), with
:data:`FLAGS` and no ``-march`` (the library runs wherever Python does; the
lane right-hand side is compiled for AVX2+FMA too and picks at load time);
sources over :data:`LARGE` characters take ``-O1``, which compiles the 10-link
pendulum on a cart in about 17% less time at the same integration speed
(within 1%).  The cache folder is ``MECHPY_CACHE_DIR``, else
``$XDG_CACHE_HOME/mechpy``, else ``~/.cache/mechpy``; a library's file name is
the sha256 of its source, the compiler command, the flags and the ABI
version, so a second build of the same system loads the file without
compiling.  Libraries are compiled to a temporary name in that folder and
moved into place with ``os.replace`` (atomic): processes building the same
system at once are safe.
"""
from __future__ import annotations

import os
import threading

# ctypes, hashlib, json, shlex, subprocess, sysconfig and tempfile are imported
# where they are used: importing mechpy must stay fast.

#: Version of the generated libraries' interface (function set, signatures,
#: mp_gen_dims); part of every library's cache key.
ABI_VERSION = 2

__all__ = ["CompileError", "cache_dir", "compiler", "build", "load_meta", "store_meta"]

#: -fopenmp-simd: the lane right-hand side's ``#pragma omp simd`` loops (no
#: OpenMP runtime); -fno-math-errno: sqrt becomes one instruction (a vector one
#: in those loops) instead of a call that may set errno; -ffp-contract=fast:
#: fused multiply-adds where the target has them (only the AVX2+FMA clone of
#: the lane rhs: the rest is compiled for baseline x86-64); -fno-trapping-math:
#: no floating-point traps are enabled, so a select between two computed values
#: vectorises (the lane solver's elimination).  None of them changes a
#: comparison or an isfinite test (no -ffast-math).  -fno-semantic-interposition:
#: the exported mp_gen_rhs may be inlined into the fixed-step blocks beside it
#: (nothing interposes the library's own functions).
FLAGS = ("-O2", "-fPIC", "-shared", "-std=c99", "-fopenmp-simd", "-fno-math-errno",
         "-ffp-contract=fast", "-fno-trapping-math", "-fno-semantic-interposition")
#: Source size (characters) from which -O1 replaces -O2.
LARGE = 150_000
LIBS = ("-lm",)
#: A line that separates translation units in a generated source (see
#: :func:`units`): large systems compile as several units at once.
UNIT = "\n/* ---- mechpy: translation unit ---- */\n"

#: Libraries loaded in this process, by path (a library is loaded once).
_LOADED: dict = {}
_LOCK = threading.Lock()


def _error_base():
    from .. import _core
    return _core.MechpyError


class CompileError(_error_base(), RuntimeError):
    """The C compiler is missing or failed on a generated system.

    The message names the command and gives the first lines of the compiler's
    output.  ``backend="numpy"`` runs the same system without a compiler.
    """


def cache_dir() -> str:
    """The folder of compiled systems (created on demand)."""
    d = os.environ.get("MECHPY_CACHE_DIR")
    if not d:
        xdg = os.environ.get("XDG_CACHE_HOME")
        d = os.path.join(xdg, "mechpy") if xdg else os.path.join(
            os.path.expanduser("~"), ".cache", "mechpy")
    os.makedirs(d, exist_ok=True)
    return d


def compiler() -> list:
    """The compiler command: ``MECHPY_CC`` if set, else sysconfig's ``CC``, else ``cc``."""
    import shlex
    import sysconfig
    cc = os.environ.get("MECHPY_CC") or sysconfig.get_config_var("CC") or "cc"
    return shlex.split(cc)


def _flags(source: str) -> tuple:
    """The compiler flags for ``source`` (-O1 for sources over LARGE characters)."""
    if len(source) > LARGE:
        return ("-O1",) + FLAGS[1:]
    return FLAGS


def _key(source: str, cmd: list) -> str:
    import hashlib
    h = hashlib.sha256()
    for part in (source, " ".join(cmd), " ".join(_flags(source) + LIBS), f"abi{ABI_VERSION}"):
        h.update(part.encode())
        h.update(b"\0")
    return h.hexdigest()[:32]


def _run(full: list):
    """Start the compiler command ``full``; CompileError if it cannot run."""
    import subprocess
    try:
        return subprocess.Popen(full, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
    except OSError as exc:
        raise CompileError(f"cannot run the C compiler {' '.join(full)!r}: {exc}. Install "
                           "a C compiler (Debian: apt-get install gcc), set MECHPY_CC, or "
                           "use backend='numpy'") from None


def _wait(proc, full: list) -> None:
    """Wait for ``proc`` (started by _run on ``full``); CompileError if it failed."""
    out, err = proc.communicate()
    if proc.returncode != 0:
        msg = "\n".join((err or out).strip().splitlines()[:12])
        raise CompileError(f"the C compiler failed (exit {proc.returncode}) on "
                           f"{' '.join(full)!r}:\n{msg}")


def units(source: str) -> list:
    """The translation units of ``source``: the whole source, or, when it holds
    :data:`UNIT` lines, the text before the first one (declarations shared by
    every unit) followed by each section after it."""
    parts = source.split(UNIT)
    if len(parts) == 1:
        return [source]
    return [parts[0] + part for part in parts[1:]]


def _compile(source: str, cmd: list, target: str, folder: str) -> None:
    """Compile ``source`` into the shared library ``target`` (moved into place
    atomically).  Several translation units (see :func:`units`) are compiled
    at once, each by its own compiler process, then linked.  Temporary files
    in ``folder`` are removed on every path; CompileError on failure."""
    import tempfile
    flags = list(_flags(source))
    made = []
    procs = []
    try:
        fd, tmp_so = tempfile.mkstemp(suffix=".so", prefix=".mp_", dir=folder)
        os.close(fd)
        made.append(tmp_so)
        parts = units(source)
        srcs = []
        for text in parts:
            fd, src = tempfile.mkstemp(suffix=".c", prefix=".mp_", dir=folder)
            made.append(src)
            with os.fdopen(fd, "w") as f:
                f.write(text)
            srcs.append(src)
        if len(srcs) == 1:
            full = cmd + flags + ["-o", tmp_so, srcs[0]] + list(LIBS)
            _wait(_run(full), full)
        else:
            compile_flags = [f for f in flags if f != "-shared"]
            objs = [src[:-2] + ".o" for src in srcs]
            made += objs
            for src, obj in zip(srcs, objs):
                full = cmd + compile_flags + ["-c", "-o", obj, src]
                procs.append((_run(full), full))
            while procs:
                proc, full = procs.pop(0)
                _wait(proc, full)
            full = cmd + ["-shared", "-o", tmp_so] + objs + list(LIBS)
            _wait(_run(full), full)
        os.replace(tmp_so, target)
    finally:
        for proc, _ in procs:      # a unit failed: stop the others
            proc.kill()
            proc.communicate()
        for f in made:
            try:
                os.unlink(f)
            except FileNotFoundError:
                pass


def build(source: str):
    """Compile ``source`` (or find it in the cache) and load it.

    Returns
    -------
    (library, path, compiled)
        The loaded ``ctypes.CDLL``, its file, and whether this call compiled it.
    """
    import ctypes
    cmd = compiler()
    folder = cache_dir()
    path = os.path.join(folder, f"mp_{_key(source, cmd)}.so")
    with _LOCK:
        lib = _LOADED.get(path)
        if lib is not None:
            return lib, path, False
        compiled = False
        if not os.path.exists(path):
            _compile(source, cmd, path, folder)
            compiled = True
        lib = ctypes.CDLL(path)
        dims = (ctypes.c_long * 5).in_dll(lib, "mp_gen_dims")
        if dims[4] != ABI_VERSION:
            raise CompileError(f"{path} has ABI version {dims[4]}, expected {ABI_VERSION}: "
                               "delete it")
        _LOADED[path] = lib
        return lib, path, compiled


def _meta_path(key: str) -> str:
    return os.path.join(cache_dir(), f"sys_{key}.json")


def load_meta(key: str):
    """The stored description of a derived system, or None."""
    import json
    try:
        with open(_meta_path(key)) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def store_meta(key: str, meta: dict) -> None:
    """Store a derived system's description (atomically)."""
    import json
    import tempfile
    folder = cache_dir()
    fd, tmp = tempfile.mkstemp(suffix=".json", prefix=".mp_", dir=folder)
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(meta, f)
        os.replace(tmp, _meta_path(key))
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
