"""Conventions users expect from neighbouring libraries: SciPy's Rotation,
SciPy's elliptic integral, a tqdm progress bar on long ensembles."""
import sys
import types

import numpy as np
import pytest
from scipy.special import ellipk, ellipkm1
from scipy.spatial.transform import Rotation

import mechpy as mp
from mechpy import _core


# ---- rotation interop with scipy.spatial.transform.Rotation -----------------

def test_to_scipy_active_and_passive_against_scipy():
    rng = np.random.default_rng(7)
    ref = Rotation.random(50, random_state=rng)
    R = ref.as_matrix()
    rot = mp.rotation.to_scipy(R, passive=False)      # SciPy's active matrices
    # measured max difference 4.4e-16
    assert np.abs(rot.as_matrix() - R).max() < 5e-15
    assert len(rot) == 50
    # passive: R is the coordinate transformation lambda = R_active^T
    lam = mp.rotation.euler_matrix(0.3, 1.1, -0.7)
    r1 = mp.rotation.to_scipy(lam, passive=True)
    assert r1.single
    # measured 2.2e-16
    assert np.abs(r1.as_euler("ZXZ") - [0.3, 1.1, -0.7]).max() < 5e-15
    assert np.abs(r1.as_matrix() - lam.T).max() < 5e-15


def test_from_scipy_is_the_inverse_of_to_scipy():
    rng = np.random.default_rng(8)
    rot = Rotation.random(20, random_state=rng)
    R = mp.rotation.from_scipy(rot, passive=False)
    assert R.shape == (20, 3, 3) and R.dtype == np.float64 and R.flags.c_contiguous
    assert np.array_equal(R, rot.as_matrix())
    lam = mp.rotation.from_scipy(rot, passive=True)
    assert np.array_equal(lam, np.swapaxes(rot.as_matrix(), -1, -2))
    back = mp.rotation.to_scipy(lam, passive=True)
    # measured 6.7e-16 (quaternions agree up to sign)
    assert np.all(np.abs(back.approx_equal(rot, atol=1e-14)))
    # the textbook matrix through SciPy's Euler angles
    single = Rotation.from_euler("ZXZ", [0.2, 0.4, 0.6])
    assert np.abs(mp.rotation.from_scipy(single, passive=True)
                  - mp.rotation.euler_matrix(0.2, 0.4, 0.6)).max() < 5e-15


def test_interop_bad_input():
    with pytest.raises(TypeError, match="rot"):
        mp.rotation.from_scipy(np.eye(3))
    with pytest.raises(TypeError, match="passive"):
        mp.rotation.to_scipy(np.eye(3), passive="yes")
    with pytest.raises(mp.DomainError):
        mp.rotation.to_scipy(2 * np.eye(3))          # not orthogonal: no silent fix
    with pytest.raises(ValueError, match="R"):
        mp.rotation.to_scipy(np.zeros((3, 4)))
    stack = np.tile(np.eye(3), (2, 2, 1, 1))
    try:
        rot = mp.rotation.to_scipy(stack)     # SciPy >= 1.17: any batch shape
    except ValueError as exc:
        assert "R of shape (2, 2, 3, 3)" in str(exc)
    else:
        assert np.array_equal(mp.rotation.from_scipy(rot, passive=False), stack)


# ---- the pendulum's period through GSL's elliptic integral ------------------

def test_ellipk_complement_against_scipy():
    kc = np.array([1.0, 0.9, 0.5, 0.1, 1e-3, 1e-8])
    got = np.array([_core.ellipk_complement(x) for x in kc])
    # K(m) with 1 - m = kc^2: SciPy's ellipkm1 takes the complement directly
    want = ellipkm1(kc**2)
    # measured max relative difference 2.4e-16
    assert np.abs(got / want - 1).max() < 4e-15
    for bad in (0.0, -0.5, 1.5, np.nan):
        with pytest.raises(ValueError, match="kc"):
            _core.ellipk_complement(bad)


def test_pendulum_period_near_the_top_keeps_precision():
    # released 1e-6 rad below the top: 1 - sin^2(theta0/2) cancels in m,
    # so the reference takes the complement p = cos^2(theta0/2)
    P = mp.scenes.Pendulum(g=9.81, length=2.0)
    for theta0 in (0.05, 1.0, 3.0, np.pi - 1e-6):
        p = np.cos(theta0 / 2) ** 2
        T = 4 * np.sqrt(2.0 / 9.81) * ellipkm1(p)
        # measured 1.7e-16
        assert abs(P.period(theta0) / T - 1) < 4e-15
    # small amplitude: 2 pi sqrt(L/g) (1 + theta0^2/16), the first correction
    T0 = 2 * np.pi * np.sqrt(2.0 / 9.81)
    assert abs(P.period(1e-3) / (T0 * (1 + 1e-6 / 16)) - 1) < 1e-12
    assert abs(P.period(1.0) - 4 * np.sqrt(2.0 / 9.81) * ellipk(np.sin(0.5) ** 2)) < 1e-14


# ---- progress on ensembles --------------------------------------------------

class _FakeTqdm:
    made = []

    def __init__(self, total, **kw):
        self.total, self.n, self.closed, self.updates = total, 0, False, []
        _FakeTqdm.made.append(self)

    def update(self, d):
        self.updates.append(d)
        self.n += d

    def close(self):
        self.closed = True


def _ensemble(progress, k=200, threads=1):
    # one thread: the C side reports from the calling thread only, so a second
    # thread could finish every trajectory before the first report
    y0s = np.column_stack([np.linspace(0.1, 3.0, k), np.zeros(k)])
    return mp.solve_many(mp.scenes.Pendulum(), (0, 5), y0s, progress=progress, threads=threads)


def test_progress_feeds_tqdm_auto(monkeypatch):
    fake = types.ModuleType("tqdm.auto")
    fake.tqdm = _FakeTqdm
    monkeypatch.setitem(sys.modules, "tqdm", types.ModuleType("tqdm"))
    monkeypatch.setitem(sys.modules, "tqdm.auto", fake)
    _FakeTqdm.made.clear()
    ens = _ensemble(True)
    assert ens.success.all()
    (bar,) = _FakeTqdm.made
    assert bar.total == 200 and bar.n == 200 and bar.closed
    assert all(d >= 0 for d in bar.updates) and len(bar.updates) >= 2
    # the same numbers with and without progress, on one thread or two
    assert np.array_equal(ens.y, _ensemble(False).y)
    assert np.array_equal(ens.y, _ensemble(True, threads=2).y)


def test_progress_without_tqdm_writes_a_line(monkeypatch, capfd):
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)    # import fails
    ens = _ensemble(True, k=50)
    assert ens.success.all()
    assert "solve_many:" in capfd.readouterr().err


def test_progress_callback_errors_never_stop_a_solve(monkeypatch):
    class Broken(_FakeTqdm):
        def update(self, d):
            raise RuntimeError("display gone")

    fake = types.ModuleType("tqdm.auto")
    fake.tqdm = Broken
    monkeypatch.setitem(sys.modules, "tqdm.auto", fake)
    with pytest.warns(RuntimeWarning, match="display gone"):
        ens = _ensemble(True)
    assert ens.success.all() and ens.y.shape == (200, 2, 1)
