"""mp.live.animate of any system from its own description (kind "bodies"): a
mechanics model's bodies and a Lagrangian system's points, read back from the
page in headless Chromium against SymPy's own kinematics (lambdified here,
independently of the printed C) and against the geometry of rolling; bad
input."""
from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import mechpy as mp

pytest.importorskip("anywidget")
from live_browser import driver, network_requests, open_page  # noqa: E402,F401
from test_live_motion import _page  # noqa: E402


def _every_frame(driver):
    """(times (n,), positions (n, bodies, 3), rotations (n, solids, 3, 3)) of
    every frame, shown one after another by the page."""
    got = driver.execute_script("""
        const L = window.mechpyLive, out = [];
        for (let i = 0; i < L.frames(); i++) {
          L.frame(i);
          out.push([L.time(), L.positions(), L.rotations()]);
        }
        return out;""")
    t = np.array([g[0] for g in got])
    P = np.array([g[1] for g in got]).reshape(len(got), -1, 3)
    R = np.array([g[2] for g in got]).reshape(len(got), -1, 3, 3)
    return t, P, R


def _inertial(kane):
    """The KanesMethod's inertial frame (SymPy keeps it as ``_inertial`` only)."""
    return kane._inertial


def test_whipple_bicycle_wheels_touch_the_ground(driver, tmp_path):
    from mechpy.symbolic import _sympy_private as private
    from mechpy.symbolic.models import whipple_bicycle, whipple_state
    kane, params = whipple_bicycle()
    bike = mp.mechanics(kane, params)
    y0 = bike.project(whipple_state(4.6, roll_rate=0.5))
    sol = mp.solve(bike, (0, 3), y0, dense_output=True, rtol=1e-11, atol=1e-12)
    rR, rF = params["rR"], params["rF"]
    w = mp.live.animate(bike, sol, fps=10, shapes={"R": dict(kind="torus", size=rR),
                                                   "F": dict(kind="torus", size=rF)})
    assert w.kind == "bodies" and w.bodies == ["B", "H", "R", "F"]
    _page(driver, tmp_path, w, "bicycle")
    t, P, R = _every_frame(driver)
    assert np.array_equal(t, w.times) and R.shape == (t.size, 4, 3, 3)
    ground = [ln for ln in driver.execute_script("return window.mechpyLive.lines()")
              if ln["label"] == "ground plane"]
    assert ground and np.abs(np.array(ground[0]["points"]).reshape(-1, 3)[:, 2]).max() == 0
    # a wheel's lowest point: its centre, down its plane (normal: the wheel's y axis, the
    # drawn solid's second column) by its radius; on the ground z = 0.  Measured 0 (rear,
    # exact geometry: 5.6e-17 m) and 1.1e-13 m (front: the configuration constraint, held by
    # the solve at rtol 1e-11)
    for j, r in ((2, rR), (3, rF)):
        ny = R[:, j, 2, 1]
        contact_z = P[:, j, 2] - r * np.sqrt(1.0 - ny ** 2)
        assert np.abs(contact_z).max() < 1e-9
    # the wheel centres against SymPy's kinematics, lambdified: measured 1.7e-16 m
    hubR, hubF = kane.bodies[2].masscenter, kane.bodies[3].masscenter
    cR = next(p for p in private.point_neighbours(hubR) if p.name == "cR")
    N = _inertial(kane)
    consts = sorted({s for e in (hubR.pos_from(cR), hubF.pos_from(cR))
                     for s in e.to_matrix(N).free_symbols}, key=str)
    consts = [s for s in consts if s.name in params]
    q = list(kane.q)
    f = sp.lambdify(q + consts, sp.Matrix([hubR.pos_from(cR).to_matrix(N).T,
                                           hubF.pos_from(cR).to_matrix(N).T]))
    err = 0.0
    for k, tk in enumerate(t):
        y = sol.sol(tk)
        ref = np.array(f(*y[:len(q)], *[params[s.name] for s in consts]), dtype=float)
        err = max(err, np.abs(P[k, 2:4] - ref).max())
    assert err < 1e-12


def test_rolling_disc_turns_by_its_direction_cosines(driver, tmp_path):
    from mechpy.symbolic.models import rolling_disc
    kane, params = rolling_disc()
    disc = mp.mechanics(kane, params)
    y0 = disc.project([0.0, 0.2, 0.0, 0.0, 0.0, 0.3, 0.0, 4.0, 0.0, 0.0])
    sol = mp.solve(disc, (0, 2), y0, dense_output=True, rtol=1e-10, atol=1e-12)
    w = mp.live.animate(disc, sol, fps=10, shapes={"disc": dict(kind="cylinder",
                                                                size=(0.5, 0.02))})
    _page(driver, tmp_path, w, "disc")
    t, P, R = _every_frame(driver)
    body = kane.bodies[0]
    N = _inertial(kane)
    q = list(kane.q)
    dcm = sp.lambdify(q + [sp.Symbol("r", positive=True)], N.dcm(body.frame))
    O = _origin(body.masscenter)[0]
    place = sp.lambdify(q + [sp.Symbol("r", positive=True)],
                        body.masscenter.pos_from(O).to_matrix(N))
    errR = errP = 0.0
    for k, tk in enumerate(t):
        y = sol.sol(tk)
        errR = max(errR, np.abs(R[k, 0] - np.array(dcm(*y[:5], 0.5), dtype=float)).max())
        errP = max(errP, np.abs(P[k, 0] - np.array(place(*y[:5], 0.5), dtype=float)
                                .reshape(-1)).max())
    assert errR < 1e-12      # measured 5.3e-16 (the page's quaternion, read back)
    assert errP < 1e-12      # measured 0 m
    # the ground plane: the disc's lowest point (its rim, radius r, in its plane: the
    # normal is its y axis) on z = 0, by the rolling constraint's geometry
    contact_z = P[:, 0, 2] - 0.5 * np.sqrt(1.0 - R[:, 0, 2, 1] ** 2)
    assert np.abs(contact_z).max() < 1e-12       # measured 5.6e-17 m


def _origin(point):
    """The points of ``point``'s position tree whose velocity is set to zero."""
    from mechpy.symbolic import _sympy_private as private
    seen, todo, found = {point}, [point], []
    while todo:
        p = todo.pop()
        for o in private.point_neighbours(p):
            if o not in seen:
                seen.add(o)
                todo.append(o)
                if o.name == "O":
                    found.append(o)
    return found


def _triple_pendulum():
    t = sp.Symbol("t")
    th = mp.coordinates("a b c")
    l, g = sp.symbols("l g")
    X = Y = T = V = 0
    points = {}
    for i, q in enumerate(th):
        X, Y = X + l * sp.sin(q), Y - l * sp.cos(q)
        points[f"bob{i + 1}"] = (X, Y, 0)
        T += (X.diff(t) ** 2 + Y.diff(t) ** 2) / 2
        V += g * Y
    return mp.lagrangian(T - V, list(th), params=dict(l=0.7, g=9.81)), points


def test_triple_pendulum_links_keep_their_length(driver, tmp_path):
    scene, points = _triple_pendulum()
    sol = mp.solve(scene, (0, 3), [1.2, 0.4, -0.3, 0.0, 0.0, 0.0], dense_output=True,
                   rtol=1e-10)
    links = [("O", "bob1"), ("bob1", "bob2"), ("bob2", "bob3")]
    w = mp.live.animate(scene, sol, fps=20, points=points, links=links,
                        shapes={"bob3": dict(kind="box", size=0.08)})
    assert w.kind == "bodies" and w.bodies == ["bob1", "bob2", "bob3"]
    _page(driver, tmp_path, w, "triple")
    t, P, R = _every_frame(driver)
    assert t.size == 61
    ends = np.concatenate([np.zeros((t.size, 1, 3)), P], axis=1)
    lengths = np.linalg.norm(np.diff(ends, axis=1), axis=2)
    assert np.abs(lengths - 0.7).max() < 1e-14                  # measured 2.2e-16 m
    # the points at the solution's coordinates (the sums of l (sin, -cos)): measured 0 m
    a = np.array([sol.sol(tk)[:3] for tk in t])
    ref = np.stack([np.cumsum(0.7 * np.sin(a), axis=1), np.cumsum(-0.7 * np.cos(a), axis=1),
                    np.zeros_like(a)], axis=-1)
    assert np.abs(P - ref).max() < 1e-14
    assert np.array_equal(R, np.broadcast_to(np.eye(3), R.shape))   # points are not turned


def test_bad_input_is_named():
    scene, points = _triple_pendulum()
    sol = mp.solve(scene, (0, 0.5), [0.1, 0.0, 0.0, 0.0, 0.0, 0.0])
    links = [("O", "bob1")]
    with pytest.raises(ValueError, match="unknown shape kind 'pyramid'"):
        mp.live.animate(scene, sol, points=points, shapes={"bob1": "pyramid"})
    with pytest.raises(ValueError, match=r"points\['p'\] depends on k, which is neither"):
        mp.live.animate(scene, sol, points={"p": (sp.Symbol("k"), 0, 0)})
    with pytest.raises(ValueError, match="links: 'bob9' is no point"):
        mp.live.animate(scene, sol, points=points, links=[("bob1", "bob9")])
    with pytest.raises(ValueError, match="shapes names 'wheel'"):
        mp.live.animate(scene, sol, points=points, links=links, shapes={"wheel": "torus"})
    with pytest.raises(TypeError, match=r"points\['bob1'\] must be \(x, y, z\)"):
        mp.live.animate(scene, sol, points={"bob1": (1, 2)})
    with pytest.raises(TypeError, match="drawn from points="):
        mp.live.animate(scene, sol, kind="bodies")
    pend = mp.scenes.Pendulum()
    with pytest.raises(ValueError, match="points is for kind='bodies', not kind='pendulum'"):
        mp.live.animate(pend, mp.solve(pend, (0, 1), [0.1, 0.0]), kind="pendulum",
                        points=points)


def test_system_joints_are_links_through_their_points():
    """A System of two links on pin joints: its ground is not drawn, each
    joint's point is placed where SymPy puts it and links the bodies it
    joins (no page: the places are the drawing's compiled kinematics)."""
    me = pytest.importorskip("sympy.physics.mechanics")
    from mechpy import _motion
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    l, m, g = sp.symbols("l m g")
    ground = me.RigidBody("ground")
    b1, b2 = me.RigidBody("link1"), me.RigidBody("link2")
    b1.mass = b2.mass = m
    j1 = me.PinJoint("j1", ground, b1, coordinates=q1, speeds=u1,
                     child_point=-l * b1.frame.y, joint_axis=ground.frame.z)
    j2 = me.PinJoint("j2", b1, b2, coordinates=q2, speeds=u2, parent_point=l * b1.frame.y,
                     child_point=-l * b2.frame.y, joint_axis=b1.frame.z)
    system = me.System.from_newtonian(ground)
    system.add_bodies(b1, b2)
    system.add_joints(j1, j2)
    system.apply_uniform_gravity(-g * ground.frame.y)
    system.form_eoms()
    scene = mp.mechanics(system, dict(l=0.5, m=1.0, g=9.81, link1_izz=0.1, link2_izz=0.1))
    d = _motion.bodies_drawing(scene)
    assert d["names"] == ["link1", "link2", "j1 (joint)", "j2 (joint)"]
    assert sorted(map(tuple, d["links"])) == [(0, 2), (0, 3), (1, 3)]
    Y = np.array([[0.3, -1.1, 2.0], [0.7, 0.2, -0.4], [0, 0, 0], [0, 0, 0]])
    P, R = _motion.bodies_places(scene, d, Y)
    O, N = ground.masscenter, ground.frame
    where = [b1.masscenter, b2.masscenter, j1.child_point, j2.child_point]
    f = sp.lambdify([q1, q2, l], sp.Matrix([p.pos_from(O).to_matrix(N).T for p in where]))
    for k in range(Y.shape[1]):
        ref = np.array(f(Y[0, k], Y[1, k], 0.5), dtype=float)
        assert np.abs(P[k] - ref).max() < 1e-14                  # measured 0 m
    assert R.shape == (3, 2, 3, 3)
