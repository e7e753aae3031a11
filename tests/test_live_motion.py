"""mp.live.animate: the bodies the page places, read back from the page in
headless Chromium, against the solution (its dense output, evaluated here),
closed forms and SciPy's Rotation; the saved page offline; bad input."""
from __future__ import annotations

import os

import numpy as np
import pytest

import mechpy as mp

pytest.importorskip("anywidget")
from live_browser import driver, network_requests, open_page  # noqa: E402,F401

#: the saved page's size: three.js inlined (~0.76 MB) and the frames; measured 0.83 MB
MAX_PAGE_BYTES = 2_000_000


def _page(driver, tmp_path, w, name):
    """Save ``w``, open it offline and check it asked the network for nothing."""
    path = w.save(tmp_path / f"{name}.html")
    assert os.path.getsize(path) < MAX_PAGE_BYTES
    network_requests(driver)                        # what came before this page
    open_page(driver, path)
    assert network_requests(driver) == []
    assert driver.execute_script("return window.mechpyLive.frames()") == w.times.size
    return path


def _at(driver, i):
    """(t, positions (bodies, 3)) of frame i, shown by the page."""
    driver.execute_script(f"window.mechpyLive.frame({i})")
    t = driver.execute_script("return window.mechpyLive.time()")
    pos = driver.execute_script("return window.mechpyLive.positions()")
    return t, np.array(pos).reshape(-1, 3)


def test_pendulum_bob_is_the_dense_solution(driver, tmp_path):
    p = mp.scenes.Pendulum(length=1.5)
    sol = mp.solve(p, (0, 4), [2.0, 0.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(p, sol, fps=25)
    # frames: duration (the span, 4 s) * fps intervals, evenly spread over [0, 4]
    np.testing.assert_array_equal(w.times, np.linspace(0, 4, 101))
    assert w.bodies == ["bob"]
    _page(driver, tmp_path, w, "pendulum")
    for i in (0, 37, 100):
        t, pos = _at(driver, i)
        assert t == w.times[i]
        th = sol.sol(t)[0]
        # (L sin theta, -L cos theta, 0): measured difference 0 m
        np.testing.assert_allclose(pos, [[1.5 * np.sin(th), -1.5 * np.cos(th), 0.0]],
                                   rtol=0, atol=1e-12)
    assert driver.execute_script("return window.mechpyLive.fps()") >= 0.0


def test_pendulum_from_samples_is_the_hermite_interpolant(driver, tmp_path):
    """Without dense output the frames between samples come from the cubic
    Hermite interpolant through the samples and the field there: 4th order,
    against SciPy's DOP853 at rtol 1e-12."""
    from scipy.integrate import solve_ivp
    p = mp.scenes.Pendulum(length=1.0, g=9.81)
    te = np.linspace(0, 2, 41)                              # h = 0.05 s
    sol = mp.solve(p, (0, 2), [1.0, 0.0], t_eval=te, rtol=1e-12, atol=1e-12)
    w = mp.live.animate(p, sol, fps=30, duration=1.0)       # 31 frames, t = k/15 s
    ref = solve_ivp(lambda t, y: [y[1], -9.81 * np.sin(y[0])], (0, 2), [1.0, 0.0],
                    method="DOP853", rtol=1e-12, atol=1e-12, dense_output=True)
    _page(driver, tmp_path, w, "samples")
    err = 0.0
    for i in (0, 7, 13, 22, 30):
        t, pos = _at(driver, i)
        th = ref.sol(t)[0]
        err = max(err, np.abs(pos[0, :2] - [np.sin(th), -np.cos(th)]).max())
    # measured 8.2e-7 m over every frame; h^4 max|y''''|/384 = 1.6e-6 m with h = 0.05 s
    assert err < 5e-6


def test_double_pendulum_bobs_from_a_lagrangian(driver, tmp_path, double_pendulum):
    scene = double_pendulum
    sol = mp.solve(scene, (0, 3), [2.0, 1.0, 0.0, 0.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(scene, sol, fps=20)
    assert w.kind == "double_pendulum" and w.bodies == ["bob 1", "bob 2"]
    _page(driver, tmp_path, w, "double")
    for i in (0, 25, 60):
        t, pos = _at(driver, i)
        a, b = sol.sol(t)[:2]
        x1, y1 = np.sin(a), -np.cos(a)
        ref = [[x1, y1, 0.0], [x1 + 0.5 * np.sin(b), y1 - 0.5 * np.cos(b), 0.0]]
        np.testing.assert_allclose(pos, ref, rtol=0, atol=1e-12)    # measured 0 m


def test_top_axis_and_spin_from_euler_angles(driver, tmp_path):
    from scipy.spatial.transform import Rotation
    top = mp.scenes.HeavyTop(0.5, 0.2, 1.0, 9.81, 0.1)
    sol = mp.solve(top, (0, 2), [0.3, 0.8, 0.1, 0.0, 0.0, 15.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(top, sol)
    _page(driver, tmp_path, w, "top")
    for i in (0, 17, 60):
        t, pos = _at(driver, i)
        R = Rotation.from_euler("ZXZ", sol.sol(t)[:3])          # intrinsic z-x'-z''
        # the centre of mass l e3 and the side mark 0.3 l e1 + l e3 (m): measured 4e-17
        np.testing.assert_allclose(pos[0], 0.1 * R.apply([0, 0, 1]), rtol=0, atol=1e-12)
        np.testing.assert_allclose(pos[1], R.apply([0.03, 0, 0.1]), rtol=0, atol=1e-12)
    # the nutation bounds: circles of radius l sin(theta) at height l cos(theta), theta the
    # extremes the solution itself reaches (a fine sampling of sol.sol); measured 1.9e-12 m
    th = sol.sol(np.linspace(0, 2, 20001))[1]
    lines = driver.execute_script("return window.mechpyLive.lines()")
    circles = [np.array(ln["points"]).reshape(-1, 3) for ln in lines
               if ln["label"].startswith("nutation bound")]
    assert len(circles) == 2
    for c, th_ref in zip(circles, (th.min(), th.max())):
        np.testing.assert_allclose(c[:, 2], 0.1 * np.cos(th_ref), rtol=0, atol=2e-11)
        np.testing.assert_allclose(np.hypot(c[:, 0], c[:, 1]), 0.1 * np.sin(th_ref), rtol=0,
                                   atol=2e-11)
        # whole circles: closed, the azimuth going once round in steps below 2 pi / 100
        np.testing.assert_allclose(c[0], c[-1], rtol=0, atol=1e-15)
        az = np.unwrap(np.arctan2(c[:, 1], c[:, 0]))
        assert abs(abs(az[-1] - az[0]) - 2 * np.pi) < 1e-12
        assert np.abs(np.diff(az)).max() < 2 * np.pi / 100


def test_rigid_body_axes_from_the_quaternion(driver, tmp_path):
    from scipy.spatial.transform import Rotation
    I = np.array([1.0, 2.0, 3.0])
    w0 = [0.02, 1.0, 0.01]
    T = mp.rigid.flip_period(I, w0)
    body = mp.scenes.RigidBody(I, orientation=True)
    sol = mp.solve(body, (0, T), body.initial_state(w0), dense_output=True, rtol=1e-11,
                   atol=1e-12)
    w = mp.live.animate(body, sol, duration=6)
    _page(driver, tmp_path, w, "rigid")
    for i in (0, 90, 180):
        t, pos = _at(driver, i)
        A = Rotation.from_quat(sol.sol(t)[3:]).as_matrix()      # SciPy, scalar last
        # rows of positions(): the principal axes in space, the columns of R; measured 2.5e-16
        np.testing.assert_allclose(pos, A.T, rtol=0, atol=1e-12)
        # the box's rotation, read back from the drawn solid: R itself; measured 2.2e-16
        rot = driver.execute_script("return window.mechpyLive.rotations()")
        np.testing.assert_allclose(np.reshape(rot, (3, 3)), A, rtol=0, atol=1e-12)
    # the dashed line of L: along L = R(q0) I omega0 with q0 the identity
    (L,) = [np.array(ln["points"]).reshape(-1, 3) for ln in
            driver.execute_script("return window.mechpyLive.lines()")
            if ln["label"].startswith("angular momentum")]
    d = (L[1] - L[0]) / np.linalg.norm(L[1] - L[0])
    np.testing.assert_allclose(d, I * w0 / np.linalg.norm(I * w0), rtol=0, atol=1e-15)  # 1e-16


def test_rigid_body_without_orientation_keeps_L_fixed(driver, tmp_path):
    """omega only: the orientation is integrated alongside; the page's axes
    turn the body-frame L = I omega into one fixed vector in space."""
    I = np.array([1.0, 2.0, 3.0])
    w0 = [0.02, 1.0, 0.01]
    T = mp.rigid.flip_period(I, w0)
    body = mp.scenes.RigidBody(I)
    sol = mp.solve(body, (0, T), w0, dense_output=True, rtol=1e-11, atol=1e-12)
    w = mp.live.animate(body, sol, duration=4)
    _page(driver, tmp_path, w, "rigid3")
    L0 = I * np.asarray(w0)                                      # the identity at t = 0
    for i in (0, 50, 120):
        t, A = _at(driver, i)
        np.testing.assert_allclose(A.T @ (I * sol.sol(t)), L0, rtol=0, atol=3e-10)  # 2.7e-11
        np.testing.assert_allclose(A @ A.T, np.eye(3), rtol=0, atol=1e-12)


def test_foucault_and_chain_places(driver, tmp_path):
    f = mp.scenes.Foucault(48.857, 10.0, omega=0.25)
    sol = mp.solve(f, (0, 20), [0.5, 0.0, 0.0, 0.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(f, sol, duration=5)
    _page(driver, tmp_path, w, "foucault")
    t, pos = _at(driver, 111)
    x, y = sol.sol(t)[:2]
    # east, north, and the height above the lowest point L - sqrt(L^2 - r^2)
    np.testing.assert_allclose(pos, [[x, y, 10.0 - np.sqrt(100.0 - x * x - y * y)]],
                               rtol=0, atol=1e-12)
    ch = mp.scenes.SpringChain(np.ones(5), 1.0)
    y0 = ch.initial_state(0.1 * np.arange(1, 6))
    sol = mp.solve(ch, (0, 5), y0, dense_output=True, rtol=1e-10)
    w = mp.live.animate(ch, sol, spacing=2.0, duration=2)
    _page(driver, tmp_path, w, "chain")
    t, pos = _at(driver, 33)
    xs = sol.sol(t)[:5]
    np.testing.assert_allclose(pos, np.column_stack([2.0 * np.arange(1, 6) + xs, np.zeros(5),
                                                     np.zeros(5)]), rtol=0, atol=1e-12)
    # fixed ends: a wall where mass 0 and mass N + 1 would rest (x = 0 and 6 s), each a
    # segment across the chain's line, centred on it, in the plane of the drawing
    walls = [np.array(ln["points"]).reshape(-1, 3) for ln in
             driver.execute_script("return window.mechpyLive.lines()") if ln["label"] == "wall"]
    assert len(walls) == 2
    for wall, x in zip(walls, (0.0, 12.0)):
        assert np.all(wall[:, 0] == x) and np.all(wall[:, 2] == 0.0)
        assert wall[0, 1] == -wall[-1, 1] and wall[-1, 1] > 0


def test_frames_and_defaults():
    p = mp.scenes.Pendulum()
    sol = mp.solve(p, (0, 100), [1.0, 0.0], dense_output=True)
    w = mp.live.animate(p, sol)                # a 100 s span plays in 60 s: 1801 frames
    assert w.times.size == 1801 and w.times[-1] == 100.0
    assert w.spec["trails"][0]["window"] == 360              # a fifth of the span: 20 s / (1/18 s)
    w = mp.live.animate(p, sol, duration=2, fps=10, trail=0)
    assert w.times.size == 21 and w.spec["trails"] == []
    assert repr(w).startswith("<mechpy.live.Motion pendulum: 21 frames")
    # at most 3600 frames in all (the docstring): 3600 are made, 3601 refused
    w = mp.live.animate(p, sol, fps=60, duration=3599 / 60)
    assert w.times.size == 3600 and w.times[0] == 0.0 and w.times[-1] == 100.0
    with pytest.raises(ValueError, match="3601 frames, more than 3600"):
        mp.live.animate(p, sol, fps=60, duration=60)


def test_bad_input():
    p = mp.scenes.Pendulum()
    sol = mp.solve(p, (0, 1), [1.0, 0.0], t_eval=np.linspace(0, 1, 5))
    a = mp.live.animate
    cases = [
        (lambda: a(lambda t, y: y, sol), TypeError, "system must be a mechpy scene"),
        (lambda: a(mp.scenes.VanDerPol(), sol), TypeError, "give kind, one of .*'rigid'"),
        (lambda: a(p, sol, kind="spinner"), ValueError, "kind must be one of"),
        (lambda: a(p, sol, kind="rigid"), TypeError, "RigidBody"),
        (lambda: a(p, sol, kind="double_pendulum"), TypeError, "4 states"),
        (lambda: a(p, np.zeros((3, 3)), t=[0, 1, 2]), ValueError, "2 states"),
        (lambda: a(p, np.zeros((2, 3))), ValueError, "give its times t"),
        (lambda: a(p, np.zeros((2, 3)), t=[0, 1]), ValueError, "3 samples"),
        (lambda: a(p, np.zeros((2, 3)), t=[0, 2, 1]), ValueError, "monotonic"),
        (lambda: a(p, np.zeros((2, 0)), t=[]), ValueError, "empty"),
        (lambda: a(p, np.full((2, 3), np.nan), t=[0, 1, 2]), ValueError, "finite"),
        (lambda: a(p, "sol"), TypeError, "sol must be a Solution"),
        (lambda: a(mp.scenes.HeavyTop(0.5, 0.2, 1.0), sol), ValueError, "6 states"),
        (lambda: a(p, sol, fps=0), ValueError, "fps"),
        (lambda: a(p, sol, fps=500), ValueError, "fps"),
        (lambda: a(p, sol, duration=-1), ValueError, "duration"),
        (lambda: a(p, sol, duration=1000), ValueError, "3600"),
        (lambda: a(p, sol, speed=0), ValueError, "speed"),
        (lambda: a(p, sol, trail=-1.0), ValueError, "trail"),
        (lambda: a(p, sol, lengths=[1.0, 2.0]), ValueError, "lengths"),
        (lambda: a(mp.scenes.RigidBody(), np.ones((3, 2)), t=[0, 1], lengths=[1.0]),
         ValueError, "lengths is for kind='pendulum' or 'double_pendulum', not kind='rigid'"),
        (lambda: a(p, sol, spacing=1.0), ValueError, "spacing is for kind='chain'"),
    ]
    for call, exc, match in cases:
        with pytest.raises(exc, match=match):
            call()


def _positions(w):
    """The frames' body positions as the page receives them: (frames, bodies, 3)."""
    import base64
    pos = np.frombuffer(base64.b64decode(w.spec["pos"]), dtype="<f8")
    return pos.reshape(w.spec["n"], w.spec["nb"], 3)


def _rod_lengths(w):
    """Per rod of the view, its length at every frame: a rod joins a fixed
    point [x, y, z] or a body (its index) to a body."""
    P = _positions(w)
    out = []
    for a, b, _ in w.spec["rods"]:
        A = np.asarray(a, dtype=float) if isinstance(a, list) else P[:, a]
        B = np.asarray(b, dtype=float) if isinstance(b, list) else P[:, b]
        out.append(np.linalg.norm(B - A, axis=-1))
    return out


def test_rods_are_as_long_as_the_links_they_draw(double_pendulum):
    """A rod from the pivot (or suspension) to a bob, or between two bobs,
    keeps the length of the link at every frame: the pendulum's L, the double
    pendulum's l1 and l2, the Foucault pendulum's 10 m wire, the top's pivot to
    its centre of mass, l.  (Measured: 1.5e-16 relative at most.)"""
    p = mp.scenes.Pendulum(length=1.5)
    w = mp.live.animate(p, mp.solve(p, (0, 4), [2.0, 0.0], dense_output=True), duration=2)
    (rod,) = _rod_lengths(w)
    np.testing.assert_allclose(rod, 1.5, rtol=2e-15)
    sol = mp.solve(double_pendulum, (0, 3), [2.0, 1.0, 0.0, 0.0], dense_output=True)
    w = mp.live.animate(double_pendulum, sol, duration=2)
    upper, lower = _rod_lengths(w)
    np.testing.assert_allclose(upper, 1.0, rtol=2e-15)
    np.testing.assert_allclose(lower, 0.5, rtol=2e-15)
    f = mp.scenes.Foucault(48.857, 10.0, omega=0.25)
    sol = mp.solve(f, (0, 20), [0.5, 0.0, 0.0, 0.0], dense_output=True)
    (wire,) = _rod_lengths(mp.live.animate(f, sol, duration=2))
    np.testing.assert_allclose(wire, 10.0, rtol=2e-15)
    top = mp.scenes.HeavyTop(0.5, 0.2, 1.0, 9.81, 0.1)
    sol = mp.solve(top, (0, 2), [0.3, 0.8, 0.1, 0.0, 0.0, 15.0], dense_output=True)
    (axis,) = _rod_lengths(mp.live.animate(top, sol, duration=2))
    np.testing.assert_allclose(axis, 0.1, rtol=2e-15)


def _every_frame(driver, tmp_path, w, name):
    """positions() of every frame the page shows: (frames, bodies, 3)."""
    _page(driver, tmp_path, w, name)
    return np.array(driver.execute_script(
        "const L = window.mechpyLive, out = [];"
        "for (let i = 0; i < L.frames(); i++) { L.frame(i); out.push(L.positions()); }"
        "return out;")).reshape(w.times.size, -1, 3)


def test_every_frame_of_the_six_kinds(driver, tmp_path, double_pendulum):
    """Every frame of each built-in kind, read back from the page, against the
    geometry computed here from the states sol.sol(times): the planar kinds
    and the chain to the bit (the page places what NumPy computed, and these
    are the same operations on the same states), the top and the rigid body
    (turned in the page by the rotation its solid is drawn with) to round-off."""
    from scipy.spatial.transform import Rotation
    p = mp.scenes.Pendulum(length=1.5)
    sol = mp.solve(p, (0, 4), [2.0, 0.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(p, sol)
    th = sol.sol(w.times)[0]
    ref = np.stack([1.5 * np.sin(th), -1.5 * np.cos(th), 0 * th], axis=-1)[:, None]
    np.testing.assert_array_equal(_every_frame(driver, tmp_path, w, "p"), ref)

    sol = mp.solve(double_pendulum, (0, 3), [2.0, 1.0, 0.0, 0.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(double_pendulum, sol)
    a, b = sol.sol(w.times)[:2]
    x1, y1 = 1.0 * np.sin(a), -1.0 * np.cos(a)
    ref = np.stack([np.stack([x1, y1, 0 * a], -1),
                    np.stack([x1 + 0.5 * np.sin(b), y1 + -0.5 * np.cos(b), 0 * a], -1)], 1)
    np.testing.assert_array_equal(_every_frame(driver, tmp_path, w, "dp"), ref)

    f = mp.scenes.Foucault(48.857, 10.0, omega=0.25)
    sol = mp.solve(f, (0, 20), [0.5, 0.0, 0.0, 0.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(f, sol, duration=5)
    x, y = sol.sol(w.times)[:2]
    ref = np.stack([x, y, 10.0 - np.sqrt(10.0 * 10.0 - np.minimum(x**2 + y**2, 100.0))], -1)
    np.testing.assert_array_equal(_every_frame(driver, tmp_path, w, "f"), ref[:, None])

    ch = mp.scenes.SpringChain(np.ones(5), 1.0)
    sol = mp.solve(ch, (0, 5), ch.initial_state(0.1 * np.arange(1, 6)), dense_output=True,
                   rtol=1e-10)
    w = mp.live.animate(ch, sol, spacing=2.0, duration=2)
    xs = sol.sol(w.times)[:5].T
    ref = np.stack([np.arange(1, 6) * 2.0 + xs, 0 * xs, 0 * xs], -1)
    np.testing.assert_array_equal(_every_frame(driver, tmp_path, w, "ch"), ref)

    top = mp.scenes.HeavyTop(0.5, 0.2, 1.0, 9.81, 0.1)
    sol = mp.solve(top, (0, 2), [0.3, 0.8, 0.1, 0.0, 0.0, 15.0], dense_output=True, rtol=1e-10)
    w = mp.live.animate(top, sol)
    R = Rotation.from_euler("ZXZ", sol.sol(w.times)[:3].T)
    ref = np.stack([R.apply([0, 0, 0.1]), R.apply([0.03, 0, 0.1])], 1)
    np.testing.assert_allclose(_every_frame(driver, tmp_path, w, "top"), ref, rtol=0,
                               atol=1e-15)           # measured 2.8e-17 m

    I = np.array([1.0, 2.0, 3.0])
    body = mp.scenes.RigidBody(I, orientation=True)
    T = mp.rigid.flip_period(I, [0.02, 1.0, 0.01])
    sol = mp.solve(body, (0, T), body.initial_state([0.02, 1.0, 0.01]), dense_output=True,
                   rtol=1e-11, atol=1e-12)
    w = mp.live.animate(body, sol, duration=4)
    A = Rotation.from_quat(sol.sol(w.times)[3:].T).as_matrix()
    np.testing.assert_allclose(_every_frame(driver, tmp_path, w, "rigid"),
                               np.transpose(A, (0, 2, 1)), rtol=0, atol=1e-14)  # 1.6e-15
