"""Tour: collisions and the rocket (chapter 9)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import mechpy as mp
from mechpy._timing import median_time
from mechpy.tours import line

TITLE = "Particles: collisions, the centre-of-mass frame, the rocket"
ORDER = 75


def _rocket_rhs(t, y, u, b, md, g, k):
    burn = y[2] > md
    return [y[1], ((u * b if burn else 0.0) - k * y[1] * abs(y[1])) / y[2] - g,
            -b if burn else 0.0]


def run(out: Path) -> None:
    rng = np.random.default_rng(0)
    m1, m2 = rng.uniform(0.5, 2, 10_000), rng.uniform(0.5, 2, 10_000)
    v1, v2, e = rng.normal(size=10_000), rng.normal(size=10_000), rng.uniform(0, 1, 10_000)
    a, b = mp.particles.collide(m1, v1, m2, v2, e)
    lost = 0.5 * (m1 * v1**2 + m2 * v2**2 - m1 * a**2 - m2 * b**2)
    mu = m1 * m2 / (m1 + m2)
    line("10^4 collisions: energy lost vs (1-e^2) mu v^2/2", "closed form",
         err=float(np.max(np.abs(lost - 0.5 * (1 - e**2) * mu * (v1 - v2)**2))))
    u, rate, m0, md = 2500.0, 10.0, 1000.0, 200.0
    r = mp.scenes.Rocket(u, rate, m0, md)
    s = r.fly((0.0, 100.0), rtol=1e-13, atol=1e-12)
    v = u * np.log(m0 / md)
    line("rocket speed at burn-out (g = 0)", f"{s.y[1, -1]:.9f} m/s", ref=f"{v:.9f}",
         err=abs(s.y[1, -1] - v))
    g, k = 9.81, 0.05
    rd = mp.scenes.Rocket(u, rate, m0, md, g=g, drag=k)
    tb = rd.burnout_time

    def scipy_flight():
        s1 = solve_ivp(_rocket_rhs, (0, tb), [0, 0, m0], args=(u, rate, md, g, k),
                       method="DOP853", rtol=1e-10, atol=1e-8)
        yb = s1.y[:, -1].copy()
        yb[2] = md
        return solve_ivp(_rocket_rhs, (tb, 200.0), yb, args=(u, rate, md, g, k),
                         method="DOP853", rtol=1e-10, atol=1e-8).y[:, -1]
    ref = scipy_flight()
    ours = rd.fly((0.0, 200.0), rtol=1e-10, atol=1e-8).y[:, -1]
    t_mp = median_time(lambda: rd.fly((0.0, 200.0), rtol=1e-10, atol=1e-8), repeat=3)
    t_sp = median_time(scipy_flight, repeat=3)
    line("rocket with gravity and drag, height at 200 s", f"{ours[0]:.3f} m", ref=f"{ref[0]:.3f}",
         err=abs(ours[0] - ref[0]), t_mp=t_mp, t_ref=t_sp)
    # events that change the state: a ball bouncing with e = 0.9, and the
    # burn-out a plain solve crosses (a switch of the scene)
    x, vv = mp.coordinates("x v")
    ball = mp.equations([vv, -sp.Symbol("g")], [x, vv], params={"g": 9.81})
    bounce = mp.events.impact("x", restitution=0.9)
    sb = mp.solve(ball, (0.0, 20.0), [1.0, 0.0], events=bounce, rtol=1e-12, atol=1e-12)
    v1, t1 = np.sqrt(2 * 9.81), np.sqrt(2 / 9.81)
    t_inf = t1 + 2 * v1 * 0.9 / (9.81 * 0.1)
    t_rest = sb.rests[0][0, 0]      # the accumulation point: at rest on the floor from there
    line(f"bouncing ball, e = 0.9: {len(sb.t_events[0]) - 1} bounces, at rest from",
         f"{t_rest:.10f} s", ref=f"{t_inf:.10f}", err=abs(t_rest - t_inf),
         t_mp=median_time(lambda: mp.solve(ball, (0.0, 20.0), [1.0, 0.0], events=bounce,
                                           rtol=1e-12, atol=1e-12), repeat=3))
    plain = mp.solve(r, (0.0, 85.0), [0.0, 0.0, m0], rtol=1e-12, atol=1e-12)
    line("rocket, one plain solve across burn-out (a switch), speed at 85 s",
         f"{plain.y[1, -1]:.9f} m/s", ref=f"{v:.9f}", err=abs(plain.y[1, -1] - v))
