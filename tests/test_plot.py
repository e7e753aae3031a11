"""mechpy.plot draws what it is given (Agg backend, no display)."""
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


def test_animate_field_advects_particles(tmp_path):
    anim = mp.plot.animate_field(mp.scenes.Pendulum(), particles=50, frames=3, trail=4,
                                 path=tmp_path / "field.html")
    html = (tmp_path / "field.html").read_text()
    assert "<script" in html and len(html) > 1000
    lc = anim._fig.axes[0].collections[0]
    assert len(lc.get_segments()) == 3 * 50  # (trail - 1) segments per particle
    plt.close("all")


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
def test_animate_field_bad_param(kw, exc, match):
    with pytest.raises(exc, match=match):
        mp.plot.animate_field(mp.scenes.VanDerPol(), **kw)
    with pytest.raises(TypeError, match="scene"):
        mp.plot.animate_field(lambda t, y: y, param="mu", values=[1.0])
    assert plt.get_fignums() == []
