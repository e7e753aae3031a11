"""Bench: a long run at round-off, mechpy beside REBOUND's IAS15.

Kepler e = 0.6 (a = 1, mu = 1) from pericentre over 1000 orbits (100 quick):
the relative energy error |E - E0| / |E0| at each orbit's end, the largest of
them (``error``), and the wall time, for mechpy's compensated compositions
(``yoshida6``, ``yoshida4``, whose updates of the state are compensated sums)
and dop853 at tight tolerances, beside REBOUND's IAS15 (15th order, adaptive,
compensated summation; ``pip install rebound``, in the ``bench`` extra) on the
same orbit (a test particle about a unit mass, G = 1), in one run.

The error is taken at the orbits' ends: a symplectic method's energy error
oscillates along an orbit with its truncation error (yoshida6 at h = T/400:
4e-9 near pericentre) and comes back at the same phase, so that what is left
there is what accumulates, round-off (the same steps in 80-bit arithmetic:
3e-16).  The note gives the error at the last orbit's end as well."""
import numpy as np

import mechpy as mp
from mechpy._timing import median_time

TITLE = "Long runs: Kepler e=0.6 at round-off, beside REBOUND's IAS15"
ORDER = 21

E = 0.6


def _problem(orbits):
    return f"Kepler e={E}, {orbits} orbits: relative energy error at the orbits' ends (max)"


def _rebound_ias15(orbits):
    """A function running REBOUND's IAS15 over the orbits and returning the
    relative energy errors at their ends, or None without rebound."""
    try:
        import rebound
    except ImportError:
        return None

    def run():
        sim = rebound.Simulation()
        sim.G = 1.0
        sim.add(m=1.0)
        sim.add(m=0.0, x=1.0 - E, y=0.0, vx=0.0, vy=np.sqrt((1 + E) / (1 - E)))
        sim.integrator = "ias15"
        sim.exact_finish_time = 0     # its own steps: the energy is read where one ends
        star, p = sim.particles[0], sim.particles[1]

        def energy():
            dx, dy, dz = p.x - star.x, p.y - star.y, p.z - star.z
            vx, vy, vz = p.vx - star.vx, p.vy - star.vy, p.vz - star.vz
            return 0.5 * (vx * vx + vy * vy + vz * vz) - 1.0 / np.sqrt(dx * dx + dy * dy
                                                                       + dz * dz)
        e0, out = energy(), []
        for k in range(1, orbits + 1):
            sim.integrate(2 * np.pi * k)
            out.append(abs(energy() - e0) / abs(e0))
        return np.array(out), int(sim.steps_done)
    return run


def run(quick: bool):
    orbits = 100 if quick else 1000
    k = mp.scenes.Kepler()
    y0 = k.initial_state(E)
    e0 = float(k.energy(y0))
    T = 2 * np.pi
    te = T * np.arange(1, orbits + 1)
    p = _problem(orbits)
    rows = []

    def row(impl, fn, rtol=None, path=None):
        s = fn()
        err = np.abs(k.energy(s.y) - e0) / abs(e0)
        rows.append(dict(problem=p, impl=impl, rtol=rtol, path=path, error=float(err.max()),
                         time=median_time(fn, repeat=3, budget=3.0), nfev=int(s.nfev),
                         note=f"at the last orbit's end {err[-1]:.1e}"))

    for meth, n in (("yoshida6", 400), ("yoshida4", 2000)):
        row(f"mechpy {meth} h=T/{n}, compensated (C scene)",
            lambda meth=meth, n=n: mp.solve(k, (0, te[-1]), y0, method=meth, h=T / n,
                                            t_eval=te), path=f"longrun-{meth}")
    for rtol in (1e-14, 1e-15, 1e-16):
        row(f"mechpy dop853 rtol={rtol:g} (C scene)",
            lambda rtol=rtol: mp.solve(k, (0, te[-1]), y0, rtol=rtol, atol=rtol, t_eval=te),
            rtol=rtol, path=f"longrun-dop853-{rtol:g}")
    ias = _rebound_ias15(orbits)
    if ias is None:
        rows.append(dict(problem=p, impl="REBOUND IAS15", path="longrun-ias15",
                         error=float("nan"), time=float("nan"),
                         note="skipped: rebound not installed (pip install rebound, or "
                              "the bench extra)"))
    else:
        err, steps = ias()
        rows.append(dict(problem=p, impl="REBOUND IAS15 (adaptive, compensated)",
                         path="longrun-ias15", error=float(err.max()),
                         time=median_time(ias, repeat=1, warmup=0),
                         note=f"at the last orbit's end {err[-1]:.1e}; {steps} steps"))
    return rows


def targets(rows):
    """mechpy's fastest run at or below 1e-14 against the 200 ms goal, and its
    time beside IAS15's."""
    mine = [r for r in rows if (r.get("path") or "").startswith("longrun-")
            and r["path"] != "longrun-ias15" and r["error"] <= 1e-14]
    ias = [r for r in rows if r.get("path") == "longrun-ias15" and np.isfinite(r["time"])]
    if not mine:
        return []
    best = min(mine, key=lambda r: r["time"])
    out = [dict(target=f"energy error <= 1e-14 over the run: {best['impl']}",
                problem=best["problem"], goal="<= 200 ms", worst=best["time"] * 1e3,
                median=best["time"] * 1e3, n=1, unit=" ms")]
    if ias:
        v = ias[0]["time"] / best["time"]
        out.append(dict(target="the same against REBOUND IAS15: its time / mechpy's",
                        problem=best["problem"], goal=">= 1x", worst=v, median=v, n=1))
    return out
