"""``python -m mechpy bench``: time against error, mechpy beside SciPy.

Writes ``bench.csv``, ``bench.json``, ``bench.md`` (a Markdown table per
problem) and one work-precision plot per problem (log error against log
time, one line per implementation) into the output folder.
"""
from __future__ import annotations

import csv
import datetime
import json
import math
import platform
from pathlib import Path

from .benches import entries


def _machine() -> str:
    import os
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for ln in f:
                if ln.startswith("model name"):
                    cpu = ln.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def _fmt(v, kind):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if kind == "time":
        return f"{v * 1e3:.3g} ms" if v >= 1e-4 else f"{v * 1e6:.3g} us"
    if kind == "error":
        return f"{v:.2e}"
    return str(v)


def write_report(rows, out: Path, header: str) -> None:
    out.mkdir(parents=True, exist_ok=True)
    keys = ["problem", "impl", "rtol", "error", "time", "nfev", "ratio"]
    extra = sorted({k for r in rows for k in r} - set(keys))
    with open(out / "bench.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys + extra)
        w.writeheader()
        for r in rows:
            w.writerow(r)
    with open(out / "bench.json", "w") as f:
        json.dump({"header": header, "rows": rows}, f, indent=1, default=float)
    lines = [f"# mechpy benchmark\n\n{header}\n"]
    problems = list(dict.fromkeys(r["problem"] for r in rows))
    for p in problems:
        pr = [r for r in rows if r["problem"] == p]
        lines.append(f"\n## {p}\n\n| implementation | rtol | error | time | nfev | note |\n"
                     "| --- | --- | --- | --- | --- | --- |")
        for r in pr:
            lines.append(f"| {r['impl']} | {_fmt(r.get('rtol'), '')} | "
                         f"{_fmt(r.get('error'), 'error')} | {_fmt(r.get('time'), 'time')} | "
                         f"{_fmt(r.get('nfev'), '')} | {r.get('note', '')} |")
    (out / "bench.md").write_text("\n".join(lines) + "\n")
    _plots(rows, problems, out)


def _plots(rows, problems, out: Path) -> None:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plots written")
        return
    from .plot import work_precision
    for p in problems:
        pr = [r for r in rows if r["problem"] == p and isinstance(r.get("error"), float)
              and r["error"] > 0 and not math.isnan(r["error"])]
        impls = list(dict.fromkeys(r["impl"] for r in pr))
        if not pr or all(sum(r["impl"] == i for r in pr) < 2 for i in impls):
            continue  # a plot needs a curve: one implementation at two tolerances at least
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        work_precision(pr, p, ax=ax)
        fig.tight_layout()
        safe = "".join(c if c.isalnum() else "_" for c in p).strip("_").lower()
        fig.savefig(out / f"wp_{safe}.png", dpi=110)
        plt.close(fig)


def main(quick: bool = False, out: Path = Path("bench-output")) -> int:
    header = (f"{datetime.date.today().isoformat()}, {_machine()}"
              f"{', quick run' if quick else ''}")
    print(f"mechpy bench: {header}")
    rows = []
    for mod in entries():
        print(f"\n== {mod.TITLE}", flush=True)
        got = mod.run(quick)
        for r in got:
            print(f"  {r['problem'][:38]:<38s} {r['impl'][:34]:<34s} "
                  f"err {_fmt(r.get('error'), 'error'):>9s}  time {_fmt(r.get('time'), 'time'):>9s}",
                  flush=True)
        rows += got
    write_report(rows, out, header)
    print(f"\nwrote {out.resolve()}/bench.md, bench.csv, bench.json and wp_*.png")
    return 0
