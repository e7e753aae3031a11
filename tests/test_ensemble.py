"""mp.solve_many: each trajectory equals mp.solve; parameters; threads; bad input."""
import ctypes
import pickle

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechpy as mp
from ref_ode import pendulum_rhs

P = mp.scenes.Pendulum()


def _starts(k):
    return np.column_stack([np.linspace(0.1, 3.0, k), np.linspace(-1, 1, k)])


def test_each_trajectory_equals_solve():
    y0s = _starts(50)
    te = np.linspace(0, 5, 21)
    # the scalar path (lanes=False) is bit for bit solve; lanes: tests/test_lanes.py
    e = mp.solve_many(P, (0, 5), y0s, t_eval=te, rtol=1e-9, lanes=False)
    assert e.y.shape == (50, 2, 21) and e.t.shape == (21,)
    assert e.success.all() and (e.status == 0).all() and e.nfev.shape == (50,)
    for i in (0, 17, 49):
        s = mp.solve(P, (0, 5), y0s[i], t_eval=te, rtol=1e-9)
        assert np.array_equal(s.y, e.y[i])
        assert s.nfev == e.nfev[i]


def test_default_keeps_final_state_and_matches_solve_ivp():
    y0s = _starts(8)
    e = mp.solve_many(P, (0, 3), y0s, rtol=1e-11, atol=1e-12)
    assert e.y.shape == (8, 2, 1) and e.t.tolist() == [3.0]
    for i in range(8):
        r = solve_ivp(pendulum_rhs, (0, 3), y0s[i], method="DOP853", rtol=1e-11, atol=1e-12)
        assert np.max(np.abs(r.y[:, -1] - e.y[i, :, 0])) < 1e-8


def test_threads_give_identical_results():
    y0s = _starts(200)
    a = mp.solve_many(P, (0, 4), y0s, t_eval=[1.0, 4.0], threads=1)
    b = mp.solve_many(P, (0, 4), y0s, t_eval=[1.0, 4.0], threads=2)
    c = mp.solve_many(P, (0, 4), y0s, t_eval=[1.0, 4.0], threads=8)
    assert np.array_equal(a.y, b.y) and np.array_equal(a.y, c.y)


def test_scene_params_per_trajectory():
    k = 6
    damping = np.linspace(0, 1, k)
    y0s = np.tile([1.0, 0.0], (k, 1))
    e = mp.solve_many(P, (0, 5), y0s, params={"damping": damping}, rtol=1e-10,
                      lanes=False)   # bit for bit solve; in lanes: tests/test_lanes.py
    full = np.column_stack([np.full(k, 9.81), np.ones(k), damping, np.zeros(k), np.zeros(k)])
    f = mp.solve_many(P, (0, 5), y0s, params=full, rtol=1e-10, lanes=False)
    assert np.array_equal(e.y, f.y)
    for i in range(k):
        s = mp.solve(P.replace(damping=damping[i]), (0, 5), y0s[i], rtol=1e-10)
        assert np.array_equal(s.y[:, -1], e.y[i, :, 0])


def test_every_parameter_name_can_be_swept():
    # ensemble_params(self, k, **columns) took params={"k": ...} (the usual spring
    # constant) or {"self": ...} as its own arguments: TypeError; now positional-only
    import sympy as sp
    x, = mp.coordinates("x")
    m, k, me = sp.symbols("m k self", positive=True)
    L = m * x.diff(sp.Symbol("t")) ** 2 / 2 - k * me * x ** 2 / 2
    osc = mp.lagrangian(L, [x], params={"m": 1.0, "k": 1.0, "self": 1.0})
    ks, selfs = np.array([1.0, 4.0, 9.0]), np.array([1.0, 1.0, 0.25])
    e = mp.solve_many(osc, (0, 2), np.tile([1.0, 0.0], (3, 1)),
                      params={"k": ks, "self": selfs}, rtol=1e-10, atol=1e-12)
    # x = cos(sqrt(k self / m) t); measured 1.9e-11
    np.testing.assert_allclose(e.y[:, 0, -1], np.cos(np.sqrt(ks * selfs) * 2.0), atol=2e-10)
    rows = osc.ensemble_params(3, k=ks, self=selfs)
    assert rows.shape == (3, 3) and np.array_equal(rows[:, list(osc.params).index("k")], ks)


def test_python_callable_params_are_leading_args():
    g = np.array([[9.81], [4.0], [1.0]])
    y0s = np.tile([1.0, 0.0], (3, 1))
    e = mp.solve_many(lambda t, y, gg: [y[1], -gg * np.sin(y[0])], (0, 2), y0s, params=g,
                      rtol=1e-11)
    for i in range(3):
        s = mp.solve(mp.scenes.Pendulum(g=g[i, 0]), (0, 2), y0s[i], rtol=1e-11)
        np.testing.assert_allclose(e.y[i, :, 0], s.y[:, -1], atol=1e-13)


def test_c_callback_user_data_is_the_params_row():
    CB = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.POINTER(ctypes.c_double),
                          ctypes.POINTER(ctypes.c_double), ctypes.c_void_p)

    @CB
    def f(t, y, dydt, ud):
        g = ctypes.cast(ud, ctypes.POINTER(ctypes.c_double))[0]
        dydt[0] = y[1]
        dydt[1] = -g * np.sin(y[0])
    g = np.array([[9.81], [2.0]])
    e = mp.solve_many(f, (0, 2), np.tile([1.0, 0.0], (2, 1)), params=g, rtol=1e-10, threads=1)
    for i in range(2):
        s = mp.solve(mp.scenes.Pendulum(g=g[i, 0]), (0, 2), [1.0, 0.0], rtol=1e-10)
        np.testing.assert_allclose(e.y[i, :, 0], s.y[:, -1], atol=1e-13)


def test_failures_are_per_trajectory_statuses():
    v = mp.scenes.VanDerPol(mu=1000.0)
    e = mp.solve_many(v, (0, 30), [[2.0, 0.0], [2.0, 0.0]], params=[[1.0], [1000.0]],
                      max_steps=2000)
    assert e.status.tolist() == [0, -1]
    assert e.success.tolist() == [True, False]


def test_callback_exception_propagates():
    def f(t, y):
        raise ZeroDivisionError("inside")
    with pytest.raises(ZeroDivisionError, match="inside"):
        mp.solve_many(f, (0, 1), [[1.0, 0.0]])


def test_inputs_pickle_for_distributed_sweeps():
    payload = pickle.loads(pickle.dumps((P.replace(damping=0.2), _starts(3))))
    e = mp.solve_many(payload[0], (0, 1), payload[1])
    assert e.success.all()


def _final_angles(scene, amplitudes):
    y0s = np.column_stack([amplitudes, np.zeros_like(amplitudes)])
    return mp.solve_many(scene, (0.0, 5.0), y0s, t_eval=[5.0], threads=1).y[:, 0, -1]


def test_sweep_spread_over_a_process_pool_matches_one_process():
    # the README's distributed sweep, with the standard library's pool: the
    # scene and the chunks travel by pickle and each worker runs its own ensemble
    import concurrent.futures as cf
    import multiprocessing as mpc
    scene = P.replace(damping=0.1)
    chunks = np.array_split(np.linspace(0.1, 3.0, 40), 4)
    with cf.ProcessPoolExecutor(2, mp_context=mpc.get_context("fork")) as pool:
        got = np.concatenate(list(pool.map(_final_angles, [scene] * 4, chunks)))
    want = _final_angles(scene, np.concatenate(chunks))
    np.testing.assert_array_equal(got, want)


def test_bad_input():
    with pytest.raises(ValueError, match="y0s"):
        mp.solve_many(P, (0, 1), [1.0, 0.0])
    with pytest.raises(ValueError, match="y0s"):
        mp.solve_many(P, (0, 1), [[1.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="y0s"):
        mp.solve_many(P, (0, 1), [[np.nan, 0.0]])
    with pytest.raises(ValueError, match="rows"):
        mp.solve_many(P, (0, 1), _starts(3), params=np.ones((2, 5)))
    with pytest.raises(ValueError, match="columns"):
        mp.solve_many(P, (0, 1), _starts(3), params=np.ones((3, 2)))
    with pytest.raises(ValueError, match="unknown parameter"):
        mp.solve_many(P, (0, 1), _starts(3), params={"mass": [1, 2, 3]})
    with pytest.raises(ValueError, match="params\\[1\\]"):
        mp.solve_many(P, (0, 1), _starts(2), params={"length": [1.0, -1.0]})
    with pytest.raises(ValueError, match="threads"):
        mp.solve_many(P, (0, 1), _starts(2), threads=0)
    e = mp.solve_many(P, (0, 1), np.zeros((0, 2)))
    assert e.y.shape == (0, 2, 1)
