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
