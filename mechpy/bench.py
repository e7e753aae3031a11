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


def _ratios(pairs):
    """(min, median, count) of t_other / t_mechpy over the pairs."""
    r = sorted(b / a for a, b in pairs if a > 0 and b > 0)
    return (r[0], r[len(r) // 2], len(r)) if r else None


def targets(rows) -> list[dict]:
    """The overhead budget of the report, computed from the rows.

    * C scene against ``solve_ivp`` (Python rhs) at equal final error: for each
      SciPy run, the fastest C-scene run of the same problem whose error is no
      larger (no interpolation, so the ratio is conservative); the same
      against ``odeint``, reported without a target;
    * Python rhs through ``mp.solve`` against ``solve_ivp`` with the same
      method and tolerance;
    * C callback against numbalsoda with the same numba ``cfunc``, at equal
      error as for the C scene;
    * ``solve_many``: in lanes against the Python loop, against the scalar
      path per core (1 thread each), against numbalsoda in a numba ``prange``
      loop, and 2 threads against 1;
    * fixed-step rk4, verlet and yoshida4 against plain C loops doing the same
      arithmetic (the time ratio, target <= 1.3), on the C scene and on the same
      pendulum compiled from its Lagrangian;
    * the benches' own targets (the call cost against numbalsoda, ...).
    """
    def ok(r):
        e = r.get("error")
        return isinstance(e, float) and e > 0 and not math.isnan(e)

    out = []
    problems = list(dict.fromkeys(r["problem"] for r in rows))

    def equal_error(mine, theirs, label, goal):
        for p in problems:
            ours = [r for r in rows if r["problem"] == p and r.get("path") == mine and ok(r)]
            refs = [r for r in rows if r["problem"] == p and r.get("path") == theirs and ok(r)]
            pairs = []
            for q in refs:
                fit = [r["time"] for r in ours if r["error"] <= q["error"]]
                if fit:
                    pairs.append((min(fit), q["time"]))
            got = _ratios(pairs)
            if got:
                out.append(dict(target=label, problem=p, goal=goal, worst=got[0],
                                median=got[1], n=got[2]))

    equal_error("c-scene", "scipy", "C scene vs solve_ivp at equal error", ">= 100x")
    equal_error("c-scene", "odeint", "C scene vs odeint (Fortran LSODA) at equal error",
                "(none)")
    equal_error("cfunc", "numbalsoda", "C callback vs numbalsoda at equal error", ">= 1x")
    for p in problems:
        py = [r for r in rows if r["problem"] == p and r.get("path") == "python"]
        sc = {(r.get("method"), r.get("rtol")): r for r in rows
              if r["problem"] == p and r.get("path") == "scipy"}
        pairs = [(r["time"], sc[(r.get("method"), r.get("rtol"))]["time"]) for r in py
                 if (r.get("method"), r.get("rtol")) in sc]
        got = _ratios(pairs)
        if got:
            out.append(dict(target="Python rhs vs solve_ivp, same method and rtol", problem=p,
                            goal=">= 5x", worst=got[0], median=got[1], n=got[2]))
    by = {r.get("path"): r for r in rows if r.get("path")}
    def best(tag):  # the faster of 1 and 2 threads
        got = [by[f"ensemble-{tag}-{th}"]["time"] for th in (1, 2)
               if f"ensemble-{tag}-{th}" in by]
        return min(got) if got else None
    lanes, scalar, nbs = best("lanes"), best("scalar"), best("numbalsoda")
    problem = by.get("ensemble-lanes-1", {}).get("problem")
    if lanes and "ensemble-loop" in by:
        v = by["ensemble-loop"]["time"] / lanes
        out.append(dict(target="solve_many vs a Python loop of solve_ivp", problem=problem,
                        goal=">= 1000x", worst=v, median=v, n=1))
    if "ensemble-lanes-1" in by and "ensemble-scalar-1" in by:
        v = by["ensemble-scalar-1"]["time"] / by["ensemble-lanes-1"]["time"]
        out.append(dict(target="solve_many in lanes vs one solve per trajectory, per core",
                        problem=problem, goal=">= 2x", worst=v, median=v, n=1))
    if lanes and nbs:
        v = nbs / lanes
        out.append(dict(target="solve_many vs numbalsoda in a numba prange loop",
                        problem=problem, goal=">= 1x", worst=v, median=v, n=1))
    if "ensemble-lanes-1" in by and "ensemble-lanes-2" in by:
        v = by["ensemble-lanes-1"]["time"] / by["ensemble-lanes-2"]["time"]
        out.append(dict(target="solve_many, 2 threads vs 1", problem=problem,
                        goal=">= 1.7x", worst=v, median=v, n=1))
    for meth in ("rk4", "verlet", "yoshida4"):  # each against its own plain loop
        for path, what in ((meth, "C scene"), (f"{meth}-compiled", "compiled Lagrangian")):
            if path in by and f"plain-c-{meth}" in by:
                v = by[path]["time"] / by[f"plain-c-{meth}"]["time"]
                out.append(dict(target=f"fixed-step {meth}, {what}: time / plain C loop",
                                problem=by[meth]["problem"], goal="<= 1.3x", worst=v,
                                median=v, n=1))
    for mod in entries():  # a section with its own targets computes them from its rows
        if hasattr(mod, "targets"):
            out += mod.targets(rows)
    return out


def _targets_md(tg) -> list[str]:
    lines = ["\n## Overhead budget (ratios from this run)\n",
             "| target | problem | goal | worst | median | pairs |",
             "| --- | --- | --- | --- | --- | --- |"]
    for t in tg:
        u = t.get("unit", "x")
        lines.append(f"| {t['target']} | {t['problem']} | {t['goal']} | {t['worst']:.3g}{u} | "
                     f"{t['median']:.3g}{u} | {t['n']} |")
    return lines


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
    tg = targets(rows)
    with open(out / "targets.json", "w") as f:
        json.dump({"header": header, "targets": tg}, f, indent=1)
    lines = [f"# mechpy benchmark\n\n{header}\n"] + _targets_md(tg)
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
        fig, ax = plt.subplots(figsize=(9.5, 4.5), layout="constrained")
        work_precision(pr, p, ax=ax)
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
    print("\n".join(_targets_md(targets(rows))))
    print(f"\nwrote {out.resolve()}/bench.md, bench.csv, bench.json and wp_*.png")
    return 0
