"""Reference solutions for the integrator tests (pure NumPy/SciPy)."""
import numpy as np
from scipy.special import ellipj, ellipk

VDP_PERIOD_MU1 = 6.6632868593231301  # Van der Pol limit cycle, mu = 1


def pendulum_exact(theta0, t, g=9.81, length=1.0):
    """Free pendulum released from rest at theta0: sin(theta/2) = k sn(K - w0 t, k).

    Returns (theta, theta_dot) of shape (2, len(t))."""
    k = np.sin(0.5 * theta0)
    m = k * k
    w0 = np.sqrt(g / length)
    u = ellipk(m) - w0 * np.asarray(t, dtype=float)
    sn, cn, dn, _ = ellipj(u, m)
    theta = 2.0 * np.arcsin(k * sn)
    theta_dot = -2.0 * k * w0 * cn
    return np.array([theta, theta_dot])


def pendulum_period(theta0, g=9.81, length=1.0):
    return 4.0 * np.sqrt(length / g) * ellipk(np.sin(0.5 * theta0) ** 2)


def pendulum_rhs(t, y, g=9.81, length=1.0, b=0.0, A=0.0, w=0.0):
    return np.array([y[1], -(g / length) * np.sin(y[0]) - b * y[1] + A * np.cos(w * t)])


def vdp_rhs(t, y, mu=1.0):
    return np.array([y[1], mu * (1 - y[0] ** 2) * y[1] - y[0]])


def rk4_path(f, t0, y0, h, n):
    """n classical RK4 steps of h in float64 from (t0, y0) (y0 of any shape, e.g.
    (m, dim): m states at once; f(t, y) -> y's shape): the n + 1 states, (n + 1, *shape)."""
    y = np.array(y0, dtype=float)
    t = float(t0)
    out = [y]
    for _ in range(n):
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
        out.append(y)
    return np.array(out)


def rk4_fixed(f, t0, y0, h, n):
    """n classical RK4 steps of h in float64 from (t0, y0), y0 of shape (m, dim)
    (m states at once; f(t, y) -> (m, dim)); the state after them."""
    return rk4_path(f, t0, y0, h, n)[-1]


def central_sensitivities(run, scene, y0, names, cols=None, h=1e-5):
    """dy/d(params, y0) at the sample times by central differences of
    run(scene, y0) -> y (n, m): one column per parameter name (a step of h
    max(1, |p|), through scene.replace) then one per component of y0 (step h);
    (n, len(names) + n, m)."""
    y0 = np.asarray(y0, dtype=float)
    base = run(scene, y0)
    n = y0.size
    fd = np.empty((base.shape[0], len(names) + n, base.shape[1]))
    for j, nm in enumerate(names):
        v = scene.params[nm]
        d = h * max(1.0, abs(v))
        fd[:, j] = (run(scene.replace(**{nm: v + d}), y0)
                    - run(scene.replace(**{nm: v - d}), y0)) / (2 * d)
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fd[:, len(names) + j] = (run(scene, y0 + e) - run(scene, y0 - e)) / (2 * h)
    return fd
