"""mp.live.animate(mechanics scene, ..., params=, y0=): a page that integrates an
mp.mechanics model itself (its linear system A z = b, printed as JavaScript and
solved by LU at each evaluation; its drawing's places and direction cosines
printed too), read back from headless Chromium against mp.solve (rtol 1e-10)
run through the scene's own compiled kinematics, before and after setParam; the
bicycle's wheels on the ground at every frame; what the page refuses."""
from __future__ import annotations

import os
import pickle

import numpy as np
import pytest

import mechpy as mp
from mechpy import _motion

pytest.importorskip("anywidget")
from live_browser import driver, network_requests, open_page  # noqa: E402,F401
from test_live_bodies import _every_frame  # noqa: E402
from test_live_motion import _page  # noqa: E402
from test_mechanics import _cartesian_pendulum  # noqa: E402


def _solved(system, span, y0, times, rtol, **changes):
    """mp.solve's places (frames, bodies, 3) and rotations (frames, solids, 3, 3) at
    ``times``, through the scene's compiled kinematics (DOP853 at ``rtol``, atol
    1e-2 rtol)."""
    s = system.replace(**changes) if changes else system
    sol = mp.solve(s, span, y0, dense_output=True, rtol=rtol, atol=1e-2 * rtol)
    return _motion.bodies_places(s, _motion.bodies_drawing(s), sol.sol(times))


def _agrees(driver, system, span, y0, truth, **changes):
    """Every frame of the page against mp.solve at ``changes``: the largest
    difference of the places (m) and of the rotations, at rtol 1e-10 under 1e-7
    (the contract), at rtol 1e-13 under ``truth`` (the page's own error)."""
    t, P, R = _every_frame(driver)
    rigid = [i for i, k in enumerate(_motion.bodies_drawing(system)["kinds"]) if k == "rigid"]
    for rtol, bound in ((1e-10, 1e-7), (1e-13, truth)):
        Pr, Rr = _solved(system, span, y0, t, rtol, **changes)
        err = np.abs(P - Pr).max(), np.abs(R[:, rigid] - Rr).max(initial=0.0)
        print(f"  {changes or 'as built'}: page - mp.solve (rtol {rtol:g}): places "
              f"{err[0]:.2g} m, rotations {err[1]:.2g}")
        assert err[0] < bound and err[1] < bound
    return t, P, R


def _set(driver, name, value):
    return driver.execute_script(f"return window.mechpyLive.setParam({name!r}, {value!r})")


def test_rolling_disc_page_simulates(driver, tmp_path):
    from mechpy.symbolic.models import rolling_disc
    kane, params = rolling_disc()
    disc = mp.mechanics(kane, params)
    span = (0.0, 3.0)
    y0 = disc.project([0.0, 0.2, 0.0, 0.0, 0.0, 0.3, 0.0, 4.0, 0.0, 0.0])
    w = mp.live.animate(disc, None, t=span, fps=10, params={"g": (1.0, 20.0)}, y0=y0,
                        shapes={"disc": dict(kind="cylinder", size=(0.5, 0.02))},
                        plots=["energy"])
    sim = w.spec["sim"]
    assert w.kind == "bodies" and sim["na"] == 10 and sim["nrot"] == 1 and w.spec["pos"] is None
    _page(driver, tmp_path, w, "disc_sim")
    assert driver.execute_script("return window.mechpyLive.simulation()")["status"] == "done"
    # measured at rtol 1e-10: 2.8e-10 m and 1.3e-10 (mp.solve's own error dominates); at
    # rtol 1e-13: 2.2e-12 m and 2.5e-12 (the page's), 3e-12 after setParam
    t, P, R = _agrees(driver, disc, span, y0, 3e-11)
    # on the ground at every frame: the rim's lowest point (radius r down the disc's plane,
    # whose normal is its y axis) at z = 0
    contact = np.abs(P[:, 0, 2] - 0.5 * np.sqrt(1.0 - R[:, 0, 2, 1] ** 2)).max()
    print(f"  disc: rim above the ground {contact:.2g} m")
    assert contact < 1e-15                     # measured 5.6e-17 m: the exact geometry
    assert _set(driver, "g", 4.0)["status"] == "done"
    t, _, _ = _agrees(driver, disc, span, y0, 3e-11, g=4.0)
    # the energy plotted beside it, recomputed by the page with the run: the scene's energy
    # (compiled) at mp.solve's states, g = 4
    got = driver.execute_script("return window.mechpyLive.plot('energy')")
    slow = disc.replace(g=4.0)
    ref = slow.energy(mp.solve(slow, span, y0, dense_output=True, rtol=1e-13,
                               atol=1e-15).sol(t))
    err = np.abs(np.array(got["y"]) - ref).max()
    print(f"  disc energy plot (g = 4) - the scene's energy: {err:.2g} J")
    assert np.array_equal(got["t"], t) and err < 1e-11           # measured 1.4e-12 J
    # r enters the rolling constraints: setParam refuses it, as params= does
    with pytest.raises(Exception, match="r enters the model's constraints"):
        _set(driver, "r", 0.6)


def test_whipple_bicycle_page_simulates(driver, tmp_path):
    """The Whipple bicycle at 4.6 m/s for 10 s at 30 fps: the page's size, the
    printed model's size and the page's integration time are measured."""
    from mechpy.symbolic.models import whipple_bicycle, whipple_state
    kane, params = whipple_bicycle()
    bike = mp.mechanics(kane, params)
    span = (0.0, 10.0)
    y0 = bike.project(whipple_state(4.6, roll_rate=0.5))
    rR, rF = params["rR"], params["rF"]
    w = mp.live.animate(bike, None, t=span, params={"g": (1.0, 20.0)}, y0=y0,
                        shapes={"R": dict(kind="torus", size=rR),
                                "F": dict(kind="torus", size=rF)})
    sim = w.spec["sim"]
    path = _page(driver, tmp_path, w, "bicycle_sim")
    size = os.path.getsize(path)
    rep = driver.execute_script("return window.mechpyLive.simulation()")
    print(f"\n  bicycle page: {size / 1e6:.2f} MB, printed model {len(sim['field']) / 1e3:.1f} kB "
          f"(A and b) + {len(sim['geometry']) / 1e3:.1f} kB (kinematics); 10 s in the page: "
          f"{rep['ms']:.0f} ms, {rep['steps']} steps ({rep['rejected']} rejected)")
    assert size < 2e6 and rep["status"] == "done" and w.times.size == 301
    # measured at rtol 1e-10: 6e-12 m and 1.2e-11; at rtol 1e-13: 1.4e-12 m and 2e-12
    t, P, R = _agrees(driver, bike, span, y0, 2e-11)
    # both wheels on the ground at every frame: centre, down the wheel's plane (normal: its
    # y axis) by its radius, at z = 0 (measured 5.6e-17 m rear: the exact geometry; 4.2e-15
    # m front: the holonomic constraint as the page's integration holds it)
    for j, r in ((2, rR), (3, rF)):
        contact = np.abs(P[:, j, 2] - r * np.sqrt(1.0 - R[:, j, 2, 1] ** 2)).max()
        print(f"  bicycle: wheel {j} above the ground {contact:.2g} m")
        assert contact < 5e-14
    assert _set(driver, "g", 6.0)["status"] == "done"
    _agrees(driver, bike, span, y0, 2e-11, g=6.0)


def test_lagrange_method_with_a_multiplier_page_simulates(driver, tmp_path):
    """The pendulum in Cartesian coordinates (x down, y across) on the circle
    x^2 + y^2 = l^2 by LagrangesMethod with a multiplier: the page solves
    mass_matrix_full z = forcing_full (with the constraint row's Baumgarte
    terms), 5 x 5; its bob keeps to the circle and follows mp.solve."""
    prm = {"g": 9.81, "l": 1.3, "m": 2.0}
    # the same equations without the bob and frame named: no drawing; the cache keeps the
    # two apart (its key holds the drawing's frame and bodies)
    assert "error" in mp.mechanics(_cartesian_pendulum()[0], prm)._info["drawing"]
    lm = _cartesian_pendulum(drawn=True)[0]
    scene = mp.mechanics(lm, prm)
    span, th, w0 = (0.0, 5.0), 1.0, 0.4
    y0 = [1.3 * np.cos(th), 1.3 * np.sin(th), -1.3 * w0 * np.sin(th), 1.3 * w0 * np.cos(th)]
    w = mp.live.animate(scene, None, t=span, fps=10, params={"g": (1.0, 20.0)}, y0=y0)
    sim = w.spec["sim"]
    assert sim["na"] == 5 and sim["nrot"] == 0 and list(sim["locked"]) == ["l"]
    _page(driver, tmp_path, w, "lagrange_sim")
    # measured at rtol 1e-10: 9.8e-11 m; at rtol 1e-13: 1.8e-12 m
    t, Pg, _ = _agrees(driver, scene, span, y0, 1e-11)
    radius = np.abs(np.linalg.norm(Pg[:, 0], axis=1) - 1.3).max()
    print(f"  Cartesian pendulum: off the circle by {radius:.2g} m")
    assert radius < 5e-12                      # measured 4.6e-13 m (Baumgarte holds it)
    assert _set(driver, "g", 3.0)["status"] == "done"
    _agrees(driver, scene, span, y0, 1e-11, g=3.0)


def test_what_the_page_cannot_simulate_of_a_model():
    from mechpy.symbolic.models import n_link_cart, rolling_disc
    kane, params = rolling_disc()
    disc = mp.mechanics(kane, params)
    y0 = disc.project([0.0, 0.2, 0.0, 0.0, 0.0, 0.3, 0.0, 4.0, 0.0, 0.0])
    a = mp.live.animate
    with pytest.raises(ValueError, match=r"params\['r'\]: the page cannot re-run the motion "
                                         r"at another value: r enters the model's constraints"):
        a(disc, None, t=(0, 1), params={"r": (0.2, 1.0)}, y0=y0)
    bad = y0.copy()
    bad[8] += 0.1                                        # a dependent speed off its constraint
    with pytest.raises(ValueError, match="y0 violates the velocity constraint"):
        a(disc, None, t=(0, 1), y0=bad)
    with pytest.raises(ValueError, match="holds no SymPy form"):
        a(pickle.loads(pickle.dumps(disc)), None, t=(0, 1), y0=y0)
    # the SymPy form survives replace()
    assert disc.replace(g=3.0)._sympy is disc._sympy
    kane, params = n_link_cart(1)
    cart = mp.mechanics(kane, params, specified={"F": lambda t, y: 0.0})
    with pytest.raises(ValueError, match=r"the specified input\(s\) \['F'\] are Python "
                                         "callables"):
        a(cart, None, t=(0, 1), y0=np.zeros(cart.dim))
