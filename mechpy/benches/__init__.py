"""Entries of ``python -m mechpy bench``.

Each module here defines ``TITLE``, ``ORDER`` and ``run(quick)`` returning a
list of row dicts with at least ``problem``, ``impl`` (e.g. "mechpy dop853 (C
scene)", "scipy DOP853"), ``time`` (median seconds) and ``error`` (against the
problem's reference, or NaN where it has none); optional ``rtol``, ``nfev``,
``n``.  Rows of one problem are measured side by side in one run.
``problems`` is no entry: the reference problems (published end values) that
the benches and the tests share.
"""
from __future__ import annotations

import importlib
import pkgutil

_NOT_ENTRIES = {"problems"}


def entries():
    mods = [importlib.import_module(f"{__name__}.{m.name}")
            for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_") and m.name not in _NOT_ENTRIES]
    return sorted(mods, key=lambda m: m.ORDER)
