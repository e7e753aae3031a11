"""Sections of ``python -m mechpy tour``.

Each module here defines ``TITLE``, ``ORDER`` (its place in the tour) and
``run(out)``, which computes something real, prints what it computed, its
error against a reference and its time beside SciPy's, and may write figures
into the folder ``out``.
"""
from __future__ import annotations

import importlib
import pkgutil
import time
from pathlib import Path


def sections():
    mods = [importlib.import_module(f"{__name__}.{m.name}")
            for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")]
    return sorted(mods, key=lambda m: m.ORDER)


def line(label: str, value, *, ref=None, err=None, t_mp=None, t_ref=None, ref_name="SciPy"):
    """Print one aligned result line of the tour."""
    parts = [f"  {label:<44s} {value}"]
    if ref is not None:
        parts.append(f"ref {ref}")
    if err is not None:
        parts.append(f"err {err:.2e}")
    if t_mp is not None:
        from .._timing import fmt_time
        s = f"time {fmt_time(t_mp)}"
        if t_ref is not None:
            s += f" vs {ref_name} {fmt_time(t_ref)} ({t_ref / t_mp:.0f}x)"
        parts.append(s)
    print(" | ".join(parts), flush=True)


def run_all(out: Path) -> int:
    out.mkdir(parents=True, exist_ok=True)
    print(f"mechpy tour: figures go to {out.resolve()}")
    failures = 0
    for mod in sections():
        print(f"\n== {mod.TITLE}")
        t0 = time.perf_counter()
        try:
            mod.run(out)
        except Exception as exc:  # a broken section must not hide the others
            failures += 1
            print(f"  FAILED: {type(exc).__name__}: {exc}")
        print(f"  ({time.perf_counter() - t0:.1f} s)")
    return failures
