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
system at once are safe.  Each library's sha256 is recorded beside it when it
is built (``mp_<key>.json``) and checked before the file is loaded: a
truncated, damaged, foreign or unrecorded file is compiled again and replaced,
never loaded (loading a damaged shared object can kill the process).  A cache
folder that cannot be made or takes no file (a file of that name, a read-only
folder) is still read; new systems then go to a private temporary folder for
the process, with one RuntimeWarning that names the cache.
"""
from __future__ import annotations

import os
import threading

# ctypes, hashlib, json, shlex, subprocess, sysconfig, tempfile and warnings are imported
# where they are used: importing mechpy must stay fast.

#: Version of the generated libraries' interface (function set, signatures,
#: mp_gen_dims); part of every library's cache key.
ABI_VERSION = 2

__all__ = ["CompileError", "cache_dir", "compiler", "have_compiler", "build", "load_meta",
           "store_meta"]

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


def _configured() -> str:
    """The cache folder the environment names (see the module docstring)."""
    d = os.environ.get("MECHPY_CACHE_DIR")
    if not d:
        xdg = os.environ.get("XDG_CACHE_HOME")
        d = os.path.join(xdg, "mechpy") if xdg else os.path.join(
            os.path.expanduser("~"), ".cache", "mechpy")
    return d


#: This process's private temporary cache, once the configured one proved
#: unusable (see _private); removed at exit.
_PRIVATE: list = []
_PRIVATE_LOCK = threading.Lock()


def _private(folder: str, exc: BaseException) -> str:
    """A private temporary cache folder for this process, made (with a
    warning, once per process) when ``folder`` cannot be used."""
    import atexit
    import shutil
    import tempfile
    import warnings
    with _PRIVATE_LOCK:
        if not _PRIVATE:
            d = tempfile.mkdtemp(prefix="mechpy-cache-")
            atexit.register(shutil.rmtree, d, True)
            _PRIVATE.append(d)
            warnings.warn(f"mechpy's cache folder {folder!r} cannot be used ({exc}); compiled "
                          f"systems go to the temporary folder {d!r} for this process and "
                          "are compiled again in the next one: set MECHPY_CACHE_DIR to a "
                          "writable folder", RuntimeWarning, stacklevel=4)
        return _PRIVATE[0]


def cache_dir() -> str:
    """The folder of compiled systems (created on demand): ``MECHPY_CACHE_DIR``,
    else ``$XDG_CACHE_HOME/mechpy``, else ``~/.cache/mechpy``; when that
    cannot be made (a file of that name, no permission), a private temporary
    folder for this process, with a RuntimeWarning once."""
    d = _configured()
    try:
        os.makedirs(d, exist_ok=True)
    except OSError as exc:
        return _private(d, exc)
    return d


def _folders() -> list:
    """The folders to look for a cached file in: the cache, then the private
    one if this process has had to make it."""
    return [cache_dir()] + [d for d in _PRIVATE if d != cache_dir()]


class _Unwritable(Exception):
    """A temporary file could not be made in a cache folder."""

    def __init__(self, folder, exc):
        super().__init__(folder, exc)
        self.folder, self.exc = folder, exc


def _mkstemp(folder: str, suffix: str):
    """tempfile.mkstemp in ``folder``; _Unwritable if the folder takes no file."""
    import tempfile
    try:
        return tempfile.mkstemp(suffix=suffix, prefix=".mp_", dir=folder)
    except OSError as exc:
        raise _Unwritable(folder, exc) from None


def _env_cc() -> str:
    """``MECHPY_CC`` stripped; blank (empty or spaces) counts as unset (it was
    split into no words, and the first flag, -O2, ran as the compiler)."""
    return os.environ.get("MECHPY_CC", "").strip()


def compiler() -> list:
    """The compiler command: ``MECHPY_CC`` if set (and not blank), else
    sysconfig's ``CC``, else ``cc``, split as a shell splits words.  A command
    that does not split (an unclosed quote) is a CompileError naming where it
    comes from."""
    import shlex
    import sysconfig
    env = _env_cc()
    cc = env or sysconfig.get_config_var("CC") or "cc"
    try:
        words = shlex.split(cc)
    except ValueError as exc:
        where = "MECHPY_CC" if env else "sysconfig's CC"
        raise CompileError(f"the compiler command {where} = {cc!r} cannot be split into "
                           f"words ({exc}): fix its quoting") from None
    return words or ["cc"]


def have_compiler() -> bool:
    """Whether there is a C compiler to build with: ``MECHPY_CC`` when set (a
    compiler asked for by name counts as there: a missing one is the
    CompileError that names it), else whether sysconfig's ``CC`` (or ``cc``)
    names a program on PATH.  Where there is none, ``backend="c"`` takes the
    numba build (:mod:`.jit`) with one warning, if numba is installed."""
    import shutil
    if _env_cc():
        return True
    cmd = compiler()
    return bool(cmd) and shutil.which(cmd[0]) is not None


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
    flags = list(_flags(source))
    made = []
    procs = []
    try:
        fd, tmp_so = _mkstemp(folder, ".so")
        os.close(fd)
        made.append(tmp_so)
        parts = units(source)
        srcs = []
        for text in parts:
            fd, src = _mkstemp(folder, ".c")
            made.append(src)
            with os.fdopen(fd, "w") as f:
                f.write(text)
            srcs.append(src)
        # every compiler process stays in procs until it has been waited for:
        # an exception while waiting (a unit failed, KeyboardInterrupt) kills
        # the ones still running, the one being waited on included, so that no
        # compiler outlives the call
        if len(srcs) == 1:
            full = cmd + flags + ["-o", tmp_so, srcs[0]] + list(LIBS)
            procs.append((_run(full), full))
        else:
            compile_flags = [f for f in flags if f != "-shared"]
            objs = [src[:-2] + ".o" for src in srcs]
            made += objs
            for src, obj in zip(srcs, objs):
                full = cmd + compile_flags + ["-c", "-o", obj, src]
                procs.append((_run(full), full))
            while procs:
                proc, full = procs[0]
                _wait(proc, full)
                procs.pop(0)
            full = cmd + ["-shared", "-o", tmp_so] + objs + list(LIBS)
            procs.append((_run(full), full))
        proc, full = procs[0]
        _wait(proc, full)
        procs.pop(0)
        if os.path.getsize(tmp_so) == 0:
            raise CompileError(f"the C compiler {' '.join(full)!r} exited 0 but wrote no "
                               "library: set MECHPY_CC to a working C compiler or use "
                               "backend='numpy'")
        os.replace(tmp_so, target)
    finally:
        for proc, _ in procs:      # a unit failed or the wait was interrupted
            if proc.poll() is None:
                proc.kill()
            proc.communicate()     # reaped: no zombie, its pipes closed
        for f in made:
            try:
                os.unlink(f)
            except FileNotFoundError:
                pass


def _digest(path: str) -> str:
    """The sha256 of a file's bytes (hex)."""
    import hashlib
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _record_path(lib: str) -> str:
    """The file that records a library's sha256: ``mp_<key>.json`` beside it."""
    return lib[:-3] + ".json"


def _recorded(lib: str):
    """The sha256 recorded for the library ``lib`` when it was built, or None."""
    import json
    try:
        with open(_record_path(lib)) as f:
            rec = json.load(f)
    except (OSError, ValueError):
        return None
    h = rec.get("sha256") if isinstance(rec, dict) else None
    return h if isinstance(h, str) else None


def _load(path: str):
    """ctypes.CDLL(path) with its ABI version checked; CompileError naming the
    file if it does not load or is not a generated library of this version."""
    import ctypes
    try:
        lib = ctypes.CDLL(path)
        dims = (ctypes.c_long * 5).in_dll(lib, "mp_gen_dims")
    except (OSError, ValueError) as exc:
        raise CompileError(f"the compiled system {path} does not load ({exc}): delete it "
                           "(it is compiled again) or use backend='numpy'") from None
    if dims[4] != ABI_VERSION:
        raise CompileError(f"{path} has ABI version {dims[4]}, expected {ABI_VERSION}: "
                           "delete it")
    return lib


def _cached(path: str):
    """The library at ``path`` if it is there, unchanged since it was built
    (its sha256 is the one recorded then) and loads; else None (it is then
    built again: a truncated, damaged or foreign file is never loaded, as
    loading it may crash the process)."""
    want = _recorded(path)
    try:
        if want is None or _digest(path) != want:
            return None
    except OSError:
        return None
    try:
        return _load(path)
    except CompileError:
        return None


def _build_into(source: str, cmd: list, path: str, folder: str):
    """Compile ``source`` into ``path`` (in ``folder``) and load it: the
    library is compiled to a temporary name, hashed and loaded from there,
    then its sha256 is recorded and it is moved into place (atomically; what
    this process loaded is what it hashed, whatever another process writes)."""
    import json
    fd, tmp = _mkstemp(folder, ".so")
    os.close(fd)
    fd_rec, tmp_rec = None, None
    try:
        _compile(source, cmd, tmp, folder)
        digest = _digest(tmp)
        try:
            lib = _load(tmp)
        except CompileError as exc:
            raise CompileError(f"the library {' '.join(cmd)!r} compiled for {path} does not "
                               f"load: {exc}") from None
        fd_rec, tmp_rec = _mkstemp(folder, ".json")
        with os.fdopen(fd_rec, "w") as f:
            json.dump({"sha256": digest, "abi": ABI_VERSION, "compiler": cmd}, f)
        os.replace(tmp_rec, _record_path(path))
        os.replace(tmp, path)
        return lib
    finally:
        for f in (tmp, tmp_rec):
            if f is not None:
                try:
                    os.unlink(f)
                except FileNotFoundError:
                    pass


def build(source: str):
    """Compile ``source`` (or find it in the cache) and load it.

    A cached library is loaded only if its sha256 is the one recorded when it
    was built (``mp_<key>.json`` beside it); a damaged or unrecorded one is
    compiled again and replaced.  A cache folder that takes no file (read-only,
    not a folder) is replaced by a private temporary one (see cache_dir).

    Returns
    -------
    (library, path, compiled)
        The loaded ``ctypes.CDLL``, its file, and whether this call compiled it.
    """
    cmd = compiler()
    name = f"mp_{_key(source, cmd)}.so"
    with _LOCK:
        for folder in _folders():
            path = os.path.join(folder, name)
            lib = _LOADED.get(path)
            if lib is None and os.path.exists(path):
                lib = _cached(path)
                if lib is not None:
                    _LOADED[path] = lib
            if lib is not None:
                return lib, path, False
        folder = cache_dir()
        try:
            path = os.path.join(folder, name)
            lib = _build_into(source, cmd, path, folder)
        except _Unwritable as exc:
            folder = _private(exc.folder, exc.exc)
            path = os.path.join(folder, name)
            lib = _build_into(source, cmd, path, folder)
        _LOADED[path] = lib
        return lib, path, True


#: The keys of a derived system's stored description (see symbolic._meta).
META_KEYS = ("kind", "n", "nc", "k", "nq", "names", "param_names", "cyclic", "has_energy",
             "source", "equations", "constraints")


def load_meta(key: str):
    """The stored description of a derived system, or None (none stored, or
    unreadable or not a description: it is then derived again)."""
    import json
    for folder in _folders():
        try:
            with open(os.path.join(folder, f"sys_{key}.json")) as f:
                meta = json.load(f)
        except (OSError, ValueError):
            continue
        if isinstance(meta, dict) and all(k in meta for k in META_KEYS) \
                and isinstance(meta["source"], str) and isinstance(meta["param_names"], list):
            return meta
    return None


def store_meta(key: str, meta: dict) -> None:
    """Store a derived system's description (atomically), in the cache or,
    when it takes no file, in the private temporary one."""
    import json
    folder = cache_dir()
    try:
        fd, tmp = _mkstemp(folder, ".json")
    except _Unwritable as exc:
        folder = _private(exc.folder, exc.exc)
        fd, tmp = _mkstemp(folder, ".json")
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(meta, f)
        os.replace(tmp, os.path.join(folder, f"sys_{key}.json"))
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
