"""mechpy.plot draws what it is given (Agg backend, no display)."""
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import mechpy as mp  # noqa: E402


def test_phase_portrait_draws_trajectories():
    ax = mp.plot.phase_portrait(mp.scenes.VanDerPol(), (-3, 3), (-3, 3),
                                trajectories=[[0.1, 0.0]], t_max=40)
    x = ax.lines[0].get_xdata()
    assert abs(np.max(np.abs(x[len(x) // 2:])) - 2.0086) < 0.02  # reaches the limit cycle
    plt.close("all")


def test_work_precision_one_line_per_implementation():
    rows = [dict(problem="p", impl=i, time=t, error=e) for i, t, e in
            [("a", 1e-3, 1e-4), ("a", 2e-3, 1e-8), ("b", 1e-2, 1e-4), ("b", 3e-2, 1e-8),
             ("b", 4e-2, float("nan"))]]
    ax = mp.plot.work_precision(rows)
    assert [ln.get_label() for ln in ax.lines] == ["a", "b"]
    assert ax.lines[1].get_xdata().tolist() == [1e-2, 3e-2]  # the NaN row is left out
    with pytest.raises(ValueError):
        mp.plot.work_precision([dict(problem="p", impl="a", time=1.0)])
    plt.close("all")


def test_modes_plot_draws_the_mode_shapes():
    K, M = mp.modes.chain(5)
    m = mp.modes.normal_modes(K, M)
    ax = mp.plot.modes(m, [0, 4])
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), m.vectors[:, 0])
    assert len([ln for ln in ax.lines if ln.get_label().startswith("mode")]) == 2
    plt.close("all")


def test_trajectory3d_and_bad_input():
    y = np.vstack([np.cos(np.linspace(0, 6, 50)), np.sin(np.linspace(0, 6, 50)),
                   np.linspace(0, 1, 50)])
    ax = mp.plot.trajectory3d(y)
    xs, ys, zs = ax.lines[0].get_data_3d()
    np.testing.assert_array_equal(zs, y[2])
    with pytest.raises(ValueError, match="3 rows"):
        mp.plot.trajectory3d(y[:2])
    plt.close("all")


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_animate_field_advects_particles(tmp_path):
    anim = mp.plot.animate_field(mp.scenes.Pendulum(), particles=50, frames=3, trail=4,
                                 path=tmp_path / "field.html")
    html = (tmp_path / "field.html").read_text()
    assert "<script" in html and len(html) > 1000
    lc = anim._fig.axes[0].collections[0]
    assert len(lc.get_segments()) == 3 * 50  # (trail - 1) segments per particle
    plt.close("all")


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_animate_field_param_slider_renders_each_value():
    widgets = pytest.importorskip("ipywidgets")
    vdp = mp.scenes.VanDerPol()
    w = mp.plot.animate_field(vdp, (-3, 3), (-3, 3), particles=20, frames=2, trail=3,
                              param="mu", values=[0.5, 3.0])
    assert isinstance(w, widgets.VBox)
    slider, out = w.children
    assert slider.description == "mu"
    assert [label for label, _ in slider.options] == ["0.5", "3"]
    first = out.outputs[0]["data"]
    assert "<script" in first["text/html"] and "mu = 0.5" in first["text/plain"]
    slider.value = 1                        # choosing another value re-renders
    second = out.outputs[0]["data"]
    assert "mu = 3" in second["text/plain"] and second["text/html"] != first["text/html"]
    assert plt.get_fignums() == []          # the rendered figures are closed


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_animate_field_param_without_ipywidgets(monkeypatch):
    import builtins
    real_import = builtins.__import__

    def no_ipywidgets(name, *args, **kw):
        if name == "ipywidgets" or name.startswith("ipywidgets."):
            raise ImportError("No module named 'ipywidgets'")
        return real_import(name, *args, **kw)
    monkeypatch.setattr(builtins, "__import__", no_ipywidgets)
    with pytest.raises(ImportError, match="ipywidgets"):
        mp.plot.animate_field(mp.scenes.VanDerPol(), param="mu", values=[1.0, 2.0])
    # without param nothing needs ipywidgets
    anim = mp.plot.animate_field(mp.scenes.VanDerPol(), particles=5, frames=1, trail=2)
    assert len(anim._fig.axes[0].collections) == 1
    plt.close("all")


@pytest.mark.parametrize("kw, exc, match", [
    (dict(param="nu", values=[1.0]), ValueError, r"'nu' is not a parameter of VanDerPol.*mu"),
    (dict(param="mu"), ValueError, "needs values"),
    (dict(param="mu", values=[]), ValueError, "values must not be empty"),
    (dict(param="mu", values=[1.0, np.nan]), ValueError, "values"),
    (dict(param="mu", values=[-1.0]), ValueError, "mu"),
    (dict(values=[1.0, 2.0]), ValueError, "without param"),
    (dict(param=3, values=[1.0]), TypeError, "param"),
    (dict(param="mu", values=[1.0], path="x.html"), ValueError, "path"),
])
@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_animate_field_bad_param(kw, exc, match):
    with pytest.raises(exc, match=match):
        mp.plot.animate_field(mp.scenes.VanDerPol(), **kw)
    with pytest.raises(TypeError, match="scene"):
        mp.plot.animate_field(lambda t, y: y, param="mu", values=[1.0])
    assert plt.get_fignums() == []


# ------------------------------------------------------------------ mp.plot.animate

def _gid(ax, gid):
    found = [a for a in ax.get_children() if a.get_gid() == gid]
    assert len(found) == 1, gid
    return found[0]


def test_animate_pendulum_bob_and_rod_follow_the_solution():
    p = mp.scenes.Pendulum(length=1.7)
    sol = mp.solve(p, (0, 4), [2.0, 0.0], t_eval=np.linspace(0, 4, 81))
    anim = mp.plot.animate(p, sol, frames=41)
    ax = anim._fig.axes[0]
    np.testing.assert_array_equal(anim.samples, np.arange(0, 81, 2))
    for i in (0, 7, 40):
        anim._func(i)
        k = anim.samples[i]
        th = sol.y[0, k]
        bx, by = (np.asarray(v) for v in _gid(ax, "bob").get_data())
        # closed form of the bob's place; measured difference 0 to 2e-16
        np.testing.assert_allclose([bx[0], by[0]], [1.7 * np.sin(th), -1.7 * np.cos(th)],
                                   rtol=0, atol=1e-12)
        rx, ry = _gid(ax, "rod").get_data()
        assert rx[0] == ry[0] == 0.0 and rx[-1] == bx[0]
        assert _gid(ax, "time").get_text() == f"t = {sol.t[k]:.2f} s"
    plt.close("all")


def test_animate_double_pendulum_from_a_compiled_scene(double_pendulum):
    scene = double_pendulum
    sol = mp.solve(scene, (0, 3), [1.0, 0.5, 0.0, 0.0], t_eval=np.linspace(0, 3, 31))
    anim = mp.plot.animate(scene, sol, trail=np.inf)
    ax = anim._fig.axes[0]
    anim._func(30)
    a, b = sol.y[0], sol.y[1]
    x2, y2 = np.sin(a) + 0.5 * np.sin(b), -np.cos(a) - 0.5 * np.cos(b)
    bx, by = _gid(ax, "bob").get_data()
    np.testing.assert_allclose([bx[1], by[1]], [x2[-1], y2[-1]], rtol=0, atol=1e-12)
    np.testing.assert_allclose([bx[0], by[0]], [np.sin(a[-1]), -np.cos(a[-1])], rtol=0, atol=1e-12)
    segs = _gid(ax, "trail").get_segments()      # the lower bob's whole path
    pts = np.vstack([segs[0][:1]] + [s[1:] for s in segs])
    np.testing.assert_allclose(pts, np.column_stack([x2, y2]), rtol=0, atol=1e-12)
    plt.close("all")


def test_animate_foucault_rosette_is_the_state():
    f = mp.scenes.Foucault(48.857, 1.0, omega=0.25)
    sol = mp.solve(f, (0, 30), [1.0, 0.0, 0.0, 0.0], t_eval=np.linspace(0, 30, 301),
                   rtol=1e-10)
    anim = mp.plot.animate(f, sol, frames=11)
    ax = anim._fig.axes[0]
    anim._func(10)
    segs = np.array(_gid(ax, "trail").get_segments())
    np.testing.assert_array_equal(segs[:, 0], sol.y[:2, :-1].T)    # every sample, in order
    np.testing.assert_array_equal(segs[-1, 1], sol.y[:2, -1])
    bx, by = _gid(ax, "bob").get_data()
    assert (bx[0], by[0]) == (sol.y[0, -1], sol.y[1, -1])
    plt.close("all")


def test_animate_top_axis_is_the_unit_vector_of_phi_theta():
    top = mp.scenes.HeavyTop(0.5, 0.2, 1.0, 9.81, 0.1)
    y0 = [0.0, 0.8, 0.0, 0.0, 0.0, 15.0]
    sol = mp.solve(top, (0, 2), y0, t_eval=np.linspace(0, 2, 101), rtol=1e-10)
    anim = mp.plot.animate(top, sol, frames=5)
    ax = anim._fig.axes[0]
    for i in range(5):
        anim._func(i)
        k = anim.samples[i]
        ph, th = sol.y[0, k], sol.y[1, k]
        xs, ys, zs = _gid(ax, "axis").get_data_3d()
        e3 = [np.sin(th) * np.sin(ph), -np.sin(th) * np.cos(ph), np.cos(th)]
        np.testing.assert_allclose([xs[1], ys[1], zs[1]], e3, rtol=0, atol=1e-12)  # 1e-16
    lo, hi = mp.rigid.nutation_bounds(0.5, 0.2, 1.0, 9.81, 0.1, 0.8, 0.0, 0.0, 15.0)
    heights = sorted(ln.get_data_3d()[2][0] for ln in ax.lines if ln.get_gid() == "bound")
    np.testing.assert_allclose(heights, sorted([np.cos(lo), np.cos(hi)]), rtol=0, atol=1e-15)
    # the sampled tip stays between the circles (it reaches cos(theta_max) within 1.3e-5)
    assert np.cos(hi) - 1e-7 < np.cos(sol.y[1]).min() and np.cos(sol.y[1]).max() < np.cos(lo) + 1e-7
    plt.close("all")


def test_animate_rigid_body_axes_keep_angular_momentum_fixed():
    from scipy.spatial.transform import Rotation
    I = np.array([1.0, 2.0, 3.0])
    w0 = [0.02, 1.0, 0.01]
    T = mp.rigid.flip_period(I, w0)
    te = np.linspace(0, T, 61)
    body = mp.scenes.RigidBody(I)
    sol = mp.solve(body, (0, T), w0, t_eval=te, rtol=1e-11, atol=1e-12)
    anim = mp.plot.animate(body, sol, frames=61)         # omega only: orientation integrated
    ax = anim._fig.axes[0]
    oriented = mp.scenes.RigidBody(I, orientation=True)
    ref = mp.solve(oriented, (0, T), oriented.initial_state(w0), t_eval=te, rtol=1e-11,
                   atol=1e-12)
    L0 = None
    for i in (0, 20, 45, 60):
        anim._func(i)
        A = np.array([_gid(ax, f"axis{j}").get_data_3d() for j in (1, 2, 3)])[:, :, 1].T
        R = Rotation.from_quat(ref.y[3:, i]).as_matrix()             # SciPy, scalar last
        np.testing.assert_allclose(A, R, rtol=0, atol=1e-12)  # measured 4e-16 (same integration)
        L = A @ (I * sol.y[:, i])                                    # space frame: conserved
        L0 = L if L0 is None else L0
        np.testing.assert_allclose(L, L0, rtol=0, atol=5e-10)        # measured 7e-11
    plt.close("all")


def test_animate_chain_masses_and_modes():
    ch = mp.scenes.SpringChain(np.ones(6), 1.0)
    y0 = ch.initial_state(np.exp(-0.5 * (np.arange(6) - 1.0) ** 2))
    te = np.linspace(0, 12, 49)
    sol = mp.solve(ch, (0, 12), y0, t_eval=te, rtol=1e-12, atol=1e-13)
    anim = mp.plot.animate(ch, sol, frames=49)
    ax = anim._fig.axes[0]
    exact = ch.modes().evolve(y0[:6], y0[6:], te)
    for i in (0, 30, 48):
        anim._func(i)
        xs, ys = _gid(ax, "displacement").get_data()
        np.testing.assert_array_equal(ys, sol.y[:6, i])
        np.testing.assert_array_equal(xs, np.arange(1, 7))
        mx, my = _gid(ax, "modes").get_data()
        np.testing.assert_allclose(my, exact[i], rtol=0, atol=1e-15)
        np.testing.assert_allclose(my, sol.y[:6, i], rtol=0, atol=1e-11)  # measured 1.1e-12
        px, _ = _gid(ax, "masses").get_data()
        np.testing.assert_allclose(px, np.arange(1, 7) + 0.4 * sol.y[:6, i]
                                   / np.abs(sol.y[:6]).max(), rtol=0, atol=1e-14)
    plt.close("all")


def test_plot_animate_series_axes_and_cursor():
    import sympy as sp
    p = mp.scenes.Pendulum(length=1.3)
    sol = mp.solve(p, (0, 4), [2.0, 0.0], t_eval=np.linspace(0, 4, 81))
    th = sp.Symbol("theta")
    anim = mp.plot.animate(p, sol, frames=41, plots=["energy", "theta'", p.params["g"] * sp.cos(th)
                                                     * sp.Symbol("length")])
    axes = anim.series_axes
    assert len(axes) == 3 and all(a in anim._fig.axes for a in axes)
    th, om = sol.y
    # per unit mass: L^2 theta'^2 / 2 + g L (1 - cos theta)
    refs = [1.3 ** 2 * om ** 2 / 2 + 9.81 * 1.3 * (1 - np.cos(th)), om, 9.81 * 1.3 * np.cos(th)]
    for a, ref in zip(axes, refs):
        (curve,) = [ln for ln in a.get_lines() if ln.get_gid() == "series"]
        assert np.array_equal(curve.get_xdata(), sol.t)
        np.testing.assert_allclose(curve.get_ydata(), ref, rtol=1e-13, atol=1e-13)
    for i in (0, 13, 40):
        changed = anim._func(i)
        cursors = [ln for a in axes for ln in a.get_lines() if ln.get_gid() == "cursor"]
        assert len(cursors) == 3 and all(c in changed for c in cursors)
        assert all(list(c.get_xdata()) == [sol.t[anim.samples[i]]] * 2 for c in cursors)
    with pytest.raises(ValueError, match="give ax=None"):
        mp.plot.animate(p, sol, plots=["theta"], ax=plt.figure().add_subplot())
    plt.close("all")


def test_animate_saves_a_gif_that_pil_opens(tmp_path):
    from PIL import Image
    p = mp.scenes.Pendulum()
    sol = mp.solve(p, (0, 1), [1.0, 0.0], t_eval=np.linspace(0, 1, 3))
    mp.plot.animate(p, sol, path=tmp_path / "swing.gif", fps=5)
    with Image.open(tmp_path / "swing.gif") as im:
        assert im.format == "GIF" and im.n_frames == 3
    plt.close("all")


def test_animate_an_array_with_times():
    p = mp.scenes.Pendulum(length=2.0)
    t = np.linspace(0, 1, 5)
    y = np.vstack([0.3 * np.cos(t), -0.3 * np.sin(t)])
    anim = mp.plot.animate(p, y, t=t)
    anim._func(4)
    bx, by = _gid(anim._fig.axes[0], "bob").get_data()
    np.testing.assert_allclose([bx[0], by[0]], [2 * np.sin(y[0, 4]), -2 * np.cos(y[0, 4])],
                               rtol=0, atol=1e-12)
    plt.close("all")


def test_animate_bad_input():
    p = mp.scenes.Pendulum()
    sol = mp.solve(p, (0, 1), [1.0, 0.0], t_eval=np.linspace(0, 1, 5))
    cases = [
        (lambda: mp.plot.animate(lambda t, y: y, sol), TypeError, "system must be a mechpy scene"),
        (lambda: mp.plot.animate(mp.scenes.VanDerPol(), sol), TypeError, "give kind"),
        (lambda: mp.plot.animate(p, sol, kind="spinner"), ValueError, "kind must be one of"),
        (lambda: mp.plot.animate(p, sol, kind="top"), TypeError, "HeavyTop"),
        (lambda: mp.plot.animate(p, sol, kind="double_pendulum"), TypeError, "4 states"),
        (lambda: mp.plot.animate(p, np.zeros((2, 0)), t=[]), ValueError, "empty"),
        (lambda: mp.plot.animate(p, np.zeros((2, 3))), ValueError, "give its times t"),
        (lambda: mp.plot.animate(p, np.zeros((3, 3)), t=[0, 1, 2]), ValueError, "2 states"),
        (lambda: mp.plot.animate(p, np.zeros((2, 3)), t=[0, 2, 1]), ValueError, "monotonic"),
        (lambda: mp.plot.animate(p, np.zeros((2, 3)), t=[0, 1]), ValueError, "3 samples"),
        (lambda: mp.plot.animate(p, "sol"), TypeError, "sol must be a Solution"),
        (lambda: mp.plot.animate(p, sol, frames=0), ValueError, "frames"),
        (lambda: mp.plot.animate(p, sol, fps=-1), ValueError, "fps"),
        (lambda: mp.plot.animate(p, sol, trail=-1.0), ValueError, "trail"),
        (lambda: mp.plot.animate(p, np.full((2, 3), np.nan), t=[0, 1, 2]), ValueError, "finite"),
    ]
    for call, exc, match in cases:
        with pytest.raises(exc, match=match):
            call()
    fig = plt.figure()
    with pytest.raises(ValueError, match="3-D"):
        top = mp.scenes.HeavyTop(0.5, 0.2, 1.0)
        mp.plot.animate(top, np.tile([[0.0], [0.8], [0], [0], [0], [15]], 3), t=[0, 1, 2],
                        ax=fig.add_subplot())
    plt.close("all")


# ------------------------------------------------------------ readable figures

UNIT = re.compile(r"\(.+\)")      # every axis label ends in its unit: "t (s)", "x (unit vector)"


def _colorbars(fig):
    return [a for a in fig.axes if getattr(a, "_colorbar", None) is not None]


def _plot_axes(fig):
    return [a for a in fig.axes if getattr(a, "_colorbar", None) is None]


def _legend_off_the_data(ax):
    """No vertex of a drawn line lies under the legend (2-D axes)."""
    leg = ax.get_legend()
    if leg is None or ax.name == "3d":
        return True
    ax.figure.canvas.draw()
    box = leg.get_window_extent()
    for ln in ax.lines:
        xy = np.column_stack([np.asarray(v, float) for v in ln.get_data()])
        if ln.get_visible() and xy.size and box.count_contains(ln.get_transform().transform(xy)):
            return False
    return True


def assert_readable(fig, coloured=False):
    """Axes labelled with units, a title, legends off the data, and a labelled
    colorbar when colour carries a value."""
    for ax in _plot_axes(fig):
        labels = [ax.get_xlabel(), ax.get_ylabel()]
        if ax.name == "3d":
            labels.append(ax.get_zlabel())
        for lb in labels:
            assert UNIT.search(lb), f"axis label {lb!r} names no unit"
        assert ax.get_title(), "the axes have no title"
        assert _legend_off_the_data(ax), f"the legend of {ax.get_title()!r} covers data"
    cbs = _colorbars(fig)
    if coloured:
        assert cbs, "colour carries a value but there is no colorbar"
    for cax in cbs:
        assert UNIT.search(cax.get_ylabel()), f"colorbar label {cax.get_ylabel()!r} names no unit"


def test_phase_portrait_is_readable_and_its_colorbar_is_the_speed():
    pend = mp.scenes.Pendulum(g=1.0, length=1.0)
    ax = mp.plot.phase_portrait(pend, (-4, 4), (-3, 3), grid=31, trajectories=[[0.0, 1.0]],
                                t_max=5)
    fig = ax.figure
    assert_readable(fig, coloured=True)
    assert ax.get_xlabel() == r"$\theta$ (rad)" and ax.get_ylabel() == r"$\dot\theta$ (rad/s)"
    (cax,) = _colorbars(fig)
    # the field of the pendulum is (theta_dot, -sin theta): its largest speed on the grid
    X, Y = np.meshgrid(np.linspace(-4, 4, 31), np.linspace(-3, 3, 31))
    top = np.hypot(Y, np.sin(X)).max()
    norm = cax._colorbar.norm
    assert norm.vmin == 0.0 and abs(norm.vmax - top) < 1e-12 * top   # measured 0 (same sums)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == [r"nullcline d$\theta$/dt = 0", r"nullcline d$\dot\theta$/dt = 0",
                      "trajectories (dot: start)"]
    plt.close("all")
    ax = mp.plot.phase_portrait(lambda t, y: np.array([y[1], -y[0]]), (-1, 1), (-1, 1), grid=5,
                                colorbar=False, labels=("q (m)", "p (m/s)"))
    assert _colorbars(ax.figure) == [] and ax.get_title() == "phase portrait of f(t, y)"
    assert ax.get_xlabel() == "q (m)"
    with pytest.raises(ValueError, match="labels"):
        mp.plot.phase_portrait(pend, labels="theta")
    plt.close("all")


def test_phase_portrait_labels_a_compiled_scene_by_its_coordinate():
    (x,) = mp.coordinates("x")
    scene = mp.lagrangian(x.diff() ** 2 / 2 - x ** 2 / 2, [x])
    ax = mp.plot.phase_portrait(scene, (-1, 1), (-1, 1), grid=5)
    assert ax.get_xlabel() == "x (model units)" and ax.get_ylabel() == "dx/dt (model units/s)"
    plt.close("all")


def test_work_precision_modes_and_trajectory3d_are_readable():
    rows = [dict(problem="p", impl=i, time=t, error=e) for i, t, e in
            [("a", 1e-3, 1e-4), ("a", 2e-3, 1e-8), ("b", 1e-2, 1e-4), ("b", 3e-2, 1e-8)]]
    assert_readable(mp.plot.work_precision(rows).figure)
    K, M = mp.modes.chain(5)
    assert_readable(mp.plot.modes(mp.modes.normal_modes(K, M)).figure)
    ax = mp.plot.modes(mp.modes.normal_modes(K, M), positions=np.arange(5) * 0.1,
                       position_unit="cm")
    assert ax.get_xlabel() == "equilibrium position (cm)"
    y = np.vstack([np.cos(np.linspace(0, 6, 50)), np.sin(np.linspace(0, 6, 50)),
                   np.linspace(0, 1, 50)])
    assert_readable(mp.plot.trajectory3d(y).figure)
    plt.close("all")


def test_animate_field_is_readable():
    anim = mp.plot.animate_field(mp.scenes.VanDerPol(), particles=5, frames=1, trail=2)
    assert_readable(anim._fig)
    assert anim._fig.axes[0].get_xlabel() == "$x$ (dimensionless)"
    plt.close("all")


def _motions():
    import sympy as sp
    th1, th2 = mp.coordinates("theta1 theta2")
    w1, w2 = th1.diff(), th2.diff()
    l1, l2 = sp.symbols("l1 l2")
    L = (l1**2 * w1**2 + l2**2 * w2**2 / 2 + l1 * l2 * w1 * w2 * sp.cos(th1 - th2)
         + 9.81 * (2 * l1 * sp.cos(th1) + l2 * sp.cos(th2)))
    dp = mp.lagrangian(L, [th1, th2], params=dict(l1=1.0, l2=0.7))
    return [(mp.scenes.Pendulum(), [1.0, 0.0]), (dp, [1.0, 0.5, 0.0, 0.0]),
            (mp.scenes.Foucault(48.9, 1.0, omega=0.25), [1.0, 0.0, 0.0, 0.0]),
            (mp.scenes.HeavyTop(0.5, 0.2, 1.0, 9.81, 0.1), [0.0, 0.8, 0.0, 0.0, 0.0, 15.0]),
            (mp.scenes.RigidBody([1.0, 2.0, 3.0]), [0.02, 1.0, 0.01]),
            (mp.scenes.SpringChain(np.ones(4), 1.0), [0.1, 0.0, 0.0, 0.0, 0, 0, 0, 0])]


def test_every_animation_is_readable():
    for scene, y0 in _motions():
        sol = mp.solve(scene, (0, 1), y0, t_eval=np.linspace(0, 1, 6))
        anim = mp.plot.animate(scene, sol, frames=3)
        assert_readable(anim._fig)
        plt.close("all")


def test_to_jshtml_draws_each_frame_once(monkeypatch):
    from matplotlib.figure import Figure
    p = mp.scenes.Pendulum()
    sol = mp.solve(p, (0, 1), [1.0, 0.0], t_eval=np.linspace(0, 1, 9))
    anims = [mp.plot.animate(p, sol),
             mp.plot.animate_field(mp.scenes.VanDerPol(), particles=5, frames=9, trail=2)]
    draw = Figure.draw
    count = [0]

    def counted(self, renderer):
        count[0] += 1
        return draw(self, renderer)
    monkeypatch.setattr(Figure, "draw", counted)
    for anim in anims:
        count[0] = 0
        html = anim.to_jshtml()
        # 9 frames in the page; matplotlib's own save draws each three times (27)
        assert html.count("data:image/png;base64") == 9
        assert count[0] == 9, count[0]
    plt.close("all")


def test_animate_field_is_deprecated_for_the_live_view():
    with pytest.warns(DeprecationWarning, match="mp.live.phase_portrait"):
        mp.plot.animate_field(mp.scenes.VanDerPol(), particles=5, frames=1, trail=2)
    plt.close("all")


@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_animate_field_moves_particles_forward_along_the_field(tmp_path):
    # the harmonic field (Van der Pol at mu = 0: x' = y, y' = -x) turns every point
    # clockwise by dt per frame: each trail segment (a, b) is b = R(-dt) a to RK4's
    # error (dt^5 / 120 relative); a particle respawned in between jumps, and is left out
    dt = 0.03
    anim = mp.plot.animate_field(mp.scenes.VanDerPol(mu=0.0), (-3, 3), (-3, 3), particles=200,
                                 frames=4, trail=4, dt=dt, respawn=0.0,
                                 path=tmp_path / "field.html")
    segs = np.array(anim._fig.axes[0].collections[0].get_segments())
    a, b = segs[:, 0, :], segs[:, 1, :]
    c, s = np.cos(dt), np.sin(dt)
    turned = np.column_stack([c * a[:, 0] + s * a[:, 1], -s * a[:, 0] + c * a[:, 1]])
    # (a trail not yet grown has segments of length 0: left out too)
    kept = (np.abs(np.hypot(*b.T) - np.hypot(*a.T)) < 1e-8) & np.any(a != b, axis=1)
    assert kept.sum() > 0.8 * len(segs)   # measured 582 of 600
    err = np.max(np.abs(b[kept] - turned[kept]))
    assert err < 5e-9, err   # measured 6.0e-10
    plt.close("all")


def test_resample_is_the_cubic_hermite_interpolant():
    # the frames between samples (mechpy._motion.resample, which every animation uses):
    # exact for a cubic motion, whose derivatives the system gives (y = t^3 - 2 t,
    # y' = 3 t^2 - 2 as the state (y, v) of v' = 6 t), and 4th order on the harmonic
    # oscillator (the error falls 16x when the spacing halves)
    from mechpy import _motion

    class Cubic:
        dim = 2

        def rhs(self, t, y):
            return np.array([3 * t * t - 2.0, 6.0 * t])

    t = np.array([0.0, 0.7, 1.5, 2.0])
    y = np.array([t ** 3 - 2 * t, 3 * t ** 2 - 2])
    times = np.linspace(0.0, 2.0, 37)
    got = _motion.resample(Cubic(), t, y, times)
    assert np.max(np.abs(got[0] - (times ** 3 - 2 * times))) < 1e-14
    sc = mp.scenes.VanDerPol(mu=0.0)
    errs = []
    for m in (9, 17):
        ts = np.linspace(0.0, 4.0, m)
        ys = np.array([np.cos(ts), -np.sin(ts)])
        fine = np.linspace(0.0, 4.0, 401)
        errs.append(np.max(np.abs(_motion.resample(sc, ts, ys, fine)[0] - np.cos(fine))))
    assert 14 < errs[0] / errs[1] < 18, errs   # measured 16.0
    assert np.array_equal(_motion.resample(sc, ts, ys, ts), ys)   # exact at the samples


def test_work_precision_leaves_out_every_row_without_a_positive_finite_error():
    # as documented: NaN, inf, zero, negative errors and None, and a time that is not
    # positive, are left out of the log-log lines
    rows = [dict(problem="p", impl="a", time=t, error=e) for t, e in
            [(1e-3, 1e-4), (2e-3, float("inf")), (3e-3, 0.0), (4e-3, -1e-6), (5e-3, None),
             (0.0, 1e-6), (6e-3, float("nan")), (7e-3, 1e-8)]]
    ax = mp.plot.work_precision(rows)
    assert ax.lines[0].get_xdata().tolist() == [1e-3, 7e-3]
    assert ax.lines[0].get_ydata().tolist() == [1e-4, 1e-8]
    plt.close("all")


def test_foucault_bob_is_the_state_and_the_height_on_the_sphere():
    from mechpy import _motion
    sc = mp.scenes.Foucault(latitude=45.0, length=10.0)
    y = np.array([[0.3, -1.2, 0.0], [0.7, 0.5, -2.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    xyz = _motion.foucault_bob(sc, y)
    assert np.array_equal(xyz[:2], y[:2])
    # on the sphere of radius L about the pivot (0, 0, L)
    np.testing.assert_allclose(xyz[0] ** 2 + xyz[1] ** 2 + (10.0 - xyz[2]) ** 2, 100.0,
                               rtol=1e-15)
