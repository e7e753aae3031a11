"""The scenes' C rows as the one description: signatures, defaults, checks,
separability and Lagrangians, each checked against what the scenes do."""
from __future__ import annotations

import inspect

import numpy as np
import pytest

import mechpy as mp
from mechpy import _core

S = mp.scenes
#: the scene classes, one per row (RigidBody: two), from the module's list
CLASSES = [getattr(S, n) for n in S.__all__
           if isinstance(getattr(S, n), type) and issubclass(getattr(S, n), S.Scene)
           and getattr(S, n)._model]
#: the scenes whose public parameters are their row's scalars (their __init__ made by
#: Scene from the row); the Rocket's check joins m_dry to m0 (tried in test_scene_values)
PLAIN = [c for c in CLASSES if "__init_subclass__" in c.__init__.__code__.co_qualname
         and c is not S.Rocket]
#: one valid instance of every scene (of every row: the test below checks it)
SCENES = [S.Pendulum(), S.Pendulum(damping=0.1), S.VanDerPol(), S.Duffing(1.0, 0.5),
          S.Duffing(1.0, 0.5, delta=0.2), S.Kepler(), S.RestrictedThreeBody(),
          S.Foucault(45.0, 10.0), S.HeavyTop(1.0, 0.5, 1.0, l=0.3), S.RigidBody(),
          S.RigidBody(orientation=True), S.SpringChain(np.ones(3)),
          S.Rocket(2500.0, 10.0, 1000.0, 200.0)]


def test_the_lists_cover_every_row():
    assert {s._model for s in SCENES} == set(_core.scene_rows())
    assert {c._model for c in CLASSES} | {"RigidBodyOriented"} == set(_core.scene_rows())


@pytest.mark.parametrize("cls", PLAIN, ids=lambda c: c.__name__)
def test_signature_and_docs_come_from_the_row(cls):
    row = _core.scene_info(cls._model)
    sig = inspect.signature(cls)
    assert list(sig.parameters) == list(row["params"])
    for p in row["param_info"]:
        want = inspect.Parameter.empty if p["default"] is None else p["default"]
        assert sig.parameters[p["name"]].default == want
    assert "Parameters from the scene's C row" in cls.__doc__
    # the defaults are what an instance gets
    required = {p["name"]: 0.5 for p in row["param_info"] if p["default"] is None}
    scene = cls(**required)
    for p in row["param_info"]:
        assert scene.params[p["name"]] == (0.5 if p["default"] is None else p["default"])


def test_heavy_top_default_l_from_the_row():
    """The Python table that had drifted left l out: now HeavyTop(I1, I3,
    mass) has the row's l = 1.0, and positional arguments follow the row."""
    assert S.HeavyTop(1.0, 0.5, 2.0).params == dict(I1=1.0, I3=0.5, mass=2.0, g=9.81, l=1.0)
    assert S.HeavyTop(1.0, 0.5, 2.0, 9.0, 0.3) == S.HeavyTop(1.0, 0.5, 2.0, g=9.0, l=0.3)
    with pytest.raises(TypeError):
        S.HeavyTop(1.0, 0.5)                       # mass is required
    with pytest.raises(TypeError):
        S.Pendulum(lenght=1.0)                     # a misspelt name


@pytest.mark.parametrize("cls", PLAIN, ids=lambda c: c.__name__)
def test_each_bound_of_the_row_is_checked_with_the_name(cls):
    """Every finite bound of every parameter: a value just outside it is a
    ValueError naming the scene and the parameter, one inside is accepted."""
    row = _core.scene_info(cls._model)
    base = {p["name"]: (0.5 if p["default"] is None else p["default"])
            for p in row["param_info"]}
    checked = 0
    for p in row["param_info"]:
        for edge, is_open, out in ((p["lo"], p["lo_open"], -1), (p["hi"], p["hi_open"], 1)):
            if np.isinf(edge):
                continue
            bad = edge if is_open else edge + out * 1e-3
            with pytest.raises(ValueError, match=f"{cls.__name__}: {p['name']} must be"):
                cls(**{**base, p["name"]: bad})
            cls(**{**base, p["name"]: edge - out * 1e-3})
            checked += 1
        with pytest.raises(ValueError, match=p["name"]):
            cls(**{**base, p["name"]: np.nan})
    assert checked >= (0 if cls in (S.Duffing,) else 1)


def test_restricted_three_body_mass_ratio_is_checked_at_construction():
    """Before, mu = 2 made a scene that failed only in mp.solve, with a
    message naming no parameter."""
    with pytest.raises(ValueError, match=r"RestrictedThreeBody: mu must be in \(0, 1\)"):
        S.RestrictedThreeBody(mu=2.0)


def test_rigid_checks_come_from_the_row():
    with pytest.raises(ValueError, match="triangle inequality"):
        S.RigidBody((1.0, 1.0, 3.0))
    with pytest.raises(ValueError, match="I2 must be positive"):
        S.RigidBody((1.0, -2.0, 3.0))
    with pytest.raises(ValueError, match="moments: .*triangle"):
        mp.rigid.flip_period((1.0, 1.0, 3.0), [0.1, 1.0, 0.1])
    with pytest.raises(ValueError, match="masses must be positive"):
        S.SpringChain([1.0, -1.0])
    with pytest.raises(ValueError, match="springs must be non-negative"):
        S.SpringChain([1.0, 1.0], [1.0, -1.0, 1.0])


@pytest.mark.parametrize("scene", SCENES, ids=repr)
def test_separable_flag_is_what_the_symplectic_methods_find(scene):
    """verlet runs exactly on the scenes (and parameters) the row calls
    separable, and refuses the others with the row's reason."""
    sep = _core.scene_info(scene._model)["separable"]
    p = scene.params
    if sep is not None and sep != "always":
        name, value = (x.strip() for x in sep.split("="))
        ok = p[name] == float(value)
    else:
        ok = sep == "always"
    y0 = np.full(scene.dim, 0.1)
    if isinstance(scene, S.HeavyTop):
        y0[1] = 0.5
    if ok:
        sol = mp.solve(scene, (0, 0.1), y0, method="verlet", h=0.01)
        assert sol.success
    else:
        with pytest.raises(ValueError, match=f"{scene._model} is"):
            mp.solve(scene, (0, 0.1), y0, method="verlet", h=0.01)


def test_not_separable_message_lists_the_rows():
    """A Python system: the message lists the scenes whose rows are separable
    (SpringChain was missing from the list written by hand)."""
    with pytest.raises(ValueError, match="Kepler, SpringChain"):
        mp.solve(lambda t, y: -y, (0, 1), [1.0, 0.0], method="verlet", h=0.1)


def test_rigid_body_ensemble_params_by_row_names():
    """RigidBody's rows vary its row's parameters (I1 .. tau3): it failed
    before (its public parameters are not the row's)."""
    rb = S.RigidBody((1.0, 2.0, 3.0))
    P = rb.ensemble_params(2, I1=[1.0, 1.5])
    assert P.shape == (2, 6)
    w0 = np.array([0.1, 1.0, 0.1])
    ens = mp.solve_many(rb, (0, 5), np.tile(w0, (2, 1)), params={"I1": [1.0, 1.5]},
                        t_eval=[5.0], rtol=1e-10, atol=1e-12)
    for i, I1 in enumerate((1.0, 1.5)):
        exact = mp.rigid.free_rotation((I1, 2.0, 3.0), w0, [5.0])[0]
        assert np.max(np.abs(ens.y[i, :, -1] - exact)) < 3e-10  # 2.7e-11 measured
    with pytest.raises(ValueError, match=r"params\[1\]: .*triangle"):
        rb.ensemble_params(2, I1=[1.0, 9.0])
    with pytest.raises(ValueError, match=r"params\[0\]: g must be positive"):
        S.Pendulum().ensemble_params(2, g=[-1.0, 2.0])


# ---------------------------------------------------------------- Lagrangians

def _closed_form(scene, t, q, v):
    """L of the scene written out (per unit mass for the pendulum)."""
    p = scene.params
    if isinstance(scene, S.Pendulum):
        L, g, b, A, W = p["length"], p["g"], p["damping"], p["drive_amplitude"], \
            p["drive_frequency"]
        return np.exp(b * t) * (0.5 * L * L * v * v + g * L * np.cos(q)
                                + L * L * A * np.cos(W * t) * q)
    a, bb, d, gam, w = p["alpha"], p["beta"], p["delta"], p["gamma"], p["omega"]
    return np.exp(d * t) * (0.5 * v * v - 0.5 * a * q * q - 0.25 * bb * q ** 4
                            + gam * np.cos(w * t) * q)


LAGRANGIAN_SCENES = [S.Pendulum(length=1.3, damping=0.2, drive_amplitude=0.7,
                                drive_frequency=1.1),
                     S.Duffing(-1.0, 1.0, delta=0.3, gamma=0.5, omega=1.2),
                     S.HeavyTop(0.5, 0.2, 1.0, g=9.81, l=0.3)]


@pytest.mark.parametrize("scene", LAGRANGIAN_SCENES[:2], ids=repr)
def test_row_lagrangian_is_the_closed_form(scene):
    rng = np.random.default_rng(3)
    t, q, v = rng.uniform(-1, 1, (3, 50))
    c = _core.variational_eval(scene._lagrangian_spec(), t, q, v)
    np.testing.assert_allclose(c[:, 0], _closed_form(scene, t, q, v), rtol=2e-15, atol=1e-15)  # 1.6e-16


@pytest.mark.parametrize("scene", LAGRANGIAN_SCENES, ids=repr)
def test_row_lagrangian_gives_the_row_rhs(scene):
    """Euler-Lagrange with the row's derivatives of L, with d/dt L_v's
    explicit time part by central differences, gives the acceleration of the
    scene's own right-hand side: L_vv a = L_q - L_vq v - dL_v/dt."""
    d = scene.dim // 2
    rng = np.random.default_rng(5)
    m = 20
    q = rng.uniform(0.3, 1.2, (m, d))
    v = rng.uniform(-1, 1, (m, d))
    t = rng.uniform(0, 2, m)
    spec = scene._lagrangian_spec()
    c = _core.variational_eval(spec, t, q, v)
    h = 1e-5
    cp = _core.variational_eval(spec, t + h, q, v)
    cm = _core.variational_eval(spec, t - h, q, v)
    Lq = c[:, 1:1 + d]
    Lqv = c[:, 1 + 2 * d + d * d:1 + 2 * d + 2 * d * d].reshape(m, d, d)  # [a][b] = d2L/dq_a dv_b
    Lvv = c[:, 1 + 2 * d + 2 * d * d:].reshape(m, d, d)
    Lv_t = (cp[:, 1 + d:1 + 2 * d] - cm[:, 1 + d:1 + 2 * d]) / (2 * h)
    rhs_el = Lq - np.einsum("mab,ma->mb", Lqv, v) - Lv_t
    a = np.linalg.solve(Lvv, rhs_el[..., None])[..., 0]
    f = np.stack([scene.rhs(ti, np.concatenate([qi, vi])) for ti, qi, vi in zip(t, q, v)])
    err = np.max(np.abs(a - f[:, d:])) / np.max(np.abs(f[:, d:]))
    assert err < 1e-10       # 1.1e-11 relative measured (the central difference in t)


def test_variational_tools_take_any_scene_with_a_row_lagrangian():
    """stationary_path takes the Lagrangian from the row: the pendulum's
    small-swing path between two angles matches the linear closed form."""
    sc = S.Pendulum(g=9.81, length=1.0)
    T, a, b = 0.5, 1e-4, 2e-4
    r = mp.variational.stationary_path(sc, a, b, T, 400)
    w = np.sqrt(9.81)
    exact = (a * np.sin(w * (T - r.t)) + b * np.sin(w * r.t)) / np.sin(w * T)
    assert np.max(np.abs(r.q - exact)) < 1e-5 * b   # 1.1e-6 relative measured (O(h^2))
    with pytest.raises(TypeError, match="no Lagrangian"):
        mp.variational.stationary_path(S.VanDerPol(), 0, 1, 1.0, 50)


# ---------------------------------------------------------- what a scene says about itself

@pytest.mark.parametrize("scene", SCENES, ids=repr)
def test_states_coordinates_and_speeds_agree_with_the_rhs(scene):
    """The row's names: one per state component, unique; the coordinates and
    speeds among them; and where a speed is a coordinate's velocity, the
    right-hand side says so: d(coordinate)/dt is that component, exactly, at
    random states and times."""
    states, q, v = scene.states, scene.coordinates, scene.speeds
    assert len(states) == scene.dim == len(set(states))
    assert set(q) <= set(states) and set(v) <= set(states) and not set(q) & set(v)
    rng = np.random.default_rng(3)
    y = rng.uniform(0.2, 1.0, (scene.dim, 5))
    if scene._model == "RigidBodyOriented":
        y[3:] /= np.linalg.norm(y[3:], axis=0)
    if scene._model == "Rocket":
        y[2] = 500.0                                   # burning: above the dry mass
    f = scene.rhs(0.7, y)
    if len(q) == len(v):
        for i, name in enumerate(q):
            iv = scene._velocity_index(i)
            assert states[iv] == v[i]
            np.testing.assert_array_equal(f[states.index(name)], y[iv])
    else:                                              # a rigid body: omega is no q's rate
        assert scene._model.startswith("RigidBody")
        assert all(scene._velocity_index(i) is None for i in range(len(q)))


@pytest.mark.parametrize("scene", SCENES, ids=repr)
def test_a_state_by_name(scene):
    """mp.solve takes y0 as a dict keyed by the scene's state names: the same
    solution as the array; a missing, unknown or doubled name is refused."""
    y0 = np.linspace(0.3, 0.6, scene.dim)
    if scene._model == "RigidBodyOriented":
        y0[3:] /= np.linalg.norm(y0[3:])
    if scene._model == "Rocket":
        y0 = np.array([0.0, 0.0, 1000.0])
    named = dict(zip(scene.states, y0))
    np.testing.assert_array_equal(scene.initial_state(named), y0)
    a = mp.solve(scene, (0, 0.1), y0, rtol=1e-8)
    b = mp.solve(scene, (0, 0.1), named, rtol=1e-8)
    np.testing.assert_array_equal(a.y, b.y)
    with pytest.raises(ValueError, match="no value for the state"):
        scene.initial_state(dict(list(named.items())[1:]))
    with pytest.raises(ValueError, match="is not a state"):
        scene.initial_state({**named, "nope": 1.0})


def test_scene_drawings_are_registry_entries():
    """A row names its drawing (or none); the entry made for particular rows
    lists that row (the painters: tests/test_recipes.py)."""
    from mechpy import _motion
    for row in _core.scene_rows():
        name = _core.scene_info(row)["drawing"]
        if name is not None:
            d = _motion.DRAWINGS[name]
            assert not d.rows or row in d.rows


def _signature(cls) -> str:
    return ", ".join(n if p.default is inspect.Parameter.empty else f"{n}={p.default!r}"
                     for n, p in inspect.signature(cls).parameters.items())


def test_the_docs_table_of_scenes_is_the_rows():
    """docs/guide/scenes.md's table: one line per C row, in the rows' order,
    its states by name as the row gives them and the class's signature."""
    import pathlib
    import re
    page = pathlib.Path(__file__).parents[1] / "docs" / "guide" / "scenes.md"
    if not page.exists():
        pytest.skip("the docs are not beside these tests (a run against an installed copy)")
    lines = [ln for ln in page.read_text().splitlines() if ln.startswith("| `")]
    by_row = {c._model: c for c in CLASSES}
    rows = []
    for ln in lines:
        scene, states, params = [c.strip() for c in ln.strip("|").split("|")]
        row = re.match(r"`(\w+)`", scene)[1]
        rows.append(row)
        info = _core.scene_info(row)
        assert re.findall(r"`([^`]+)`", states) == list(info["states"]), row
        cls = by_row.get(row)
        if cls is not None:
            assert params == f"`{_signature(cls)}`", row
    assert rows == list(_core.scene_rows())
