"""Compile generated C into a shared library, cached on disk, and load it.

The compiler is the one Python was built with (``sysconfig``'s ``CC``), with
``-O2 -fPIC -shared`` and no ``-march`` (the library runs wherever Python
does); sources over :data:`LARGE` characters take ``-O1``, which compiles the
10-link pendulum on a cart in about 17% less time at the same integration
speed (within 1%).  The cache folder is ``MECHPY_CACHE_DIR``, else
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
ABI_VERSION = 1

__all__ = ["CompileError", "cache_dir", "compiler", "build", "load_meta", "store_meta"]

FLAGS = ("-O2", "-fPIC", "-shared", "-std=c99")
#: Source size (characters) from which -O1 replaces -O2.
LARGE = 150_000
LIBS = ("-lm",)

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


def _compile(source: str, cmd: list, target: str, folder: str) -> None:
    import subprocess
    import tempfile
    fd, src = tempfile.mkstemp(suffix=".c", prefix=".mp_", dir=folder)
    tmp_so = src[:-2] + ".so"
    try:
        with os.fdopen(fd, "w") as f:
            f.write(source)
        full = cmd + list(_flags(source)) + ["-o", tmp_so, src] + list(LIBS)
        try:
            r = subprocess.run(full, capture_output=True, text=True)
        except OSError as exc:
            raise CompileError(f"cannot run the C compiler {' '.join(full)!r}: {exc}. Install "
                               "a C compiler (Debian: apt-get install gcc), set MECHPY_CC, or "
                               "use backend='numpy'") from None
        if r.returncode != 0:
            msg = "\n".join((r.stderr or r.stdout).strip().splitlines()[:12])
            raise CompileError(f"the C compiler failed (exit {r.returncode}) on "
                               f"{' '.join(full)!r}:\n{msg}")
        os.replace(tmp_so, target)
    finally:
        for f in (src, tmp_so):
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
