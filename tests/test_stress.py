"""mechpy.stress against NumPy's eigh and closed-form stress states."""
import numpy as np
import pytest

from mechpy import stress
from ref_inertia import random_rotation, von_mises_ref


def _random_sym(rng, n):
    A = rng.normal(size=(n, 3, 3)) * 1e6
    return 0.5 * (A + np.swapaxes(A, 1, 2))


def test_principal_against_eigh(rng):
    S = _random_sym(rng, 100)
    w, D = stress.principal(S)
    wr, Dr = np.linalg.eigh(S)
    np.testing.assert_allclose(w, wr, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(np.linalg.det(D), 1.0, rtol=1e-14)
    np.testing.assert_allclose(D @ (w[..., None] * np.swapaxes(D, 1, 2)), S, atol=1e-8)
    np.testing.assert_allclose(np.abs(np.sum(D * Dr, axis=1)), 1.0, rtol=1e-9)


def test_uniaxial_pure_shear_and_hydrostatic():
    s0 = 250e6
    uni = np.diag([s0, 0.0, 0.0])
    assert stress.von_mises(uni) == pytest.approx(s0, rel=1e-15)
    assert stress.max_shear(uni) == pytest.approx(s0 / 2, rel=1e-15)
    assert stress.pressure(uni) == pytest.approx(-s0 / 3, rel=1e-15)
    tau = 80e6
    shear = np.array([[0, tau, 0], [tau, 0, 0], [0, 0, 0]])
    w, D = stress.principal(shear)
    np.testing.assert_allclose(w, [-tau, 0, tau], atol=1e-8)
    # tension along (x + y)/sqrt(2), compression along (x - y)/sqrt(2)
    np.testing.assert_allclose(np.abs(D[:, 2]), [2 ** -0.5, 2 ** -0.5, 0], atol=1e-15)
    assert D[0, 0] * D[1, 0] < 0
    assert stress.von_mises(shear) == pytest.approx(3 ** 0.5 * tau, rel=1e-15)
    assert stress.max_shear(shear) == pytest.approx(tau, rel=1e-15)
    p = 101.325e3
    hyd = -p * np.eye(3)
    assert stress.pressure(hyd) == pytest.approx(p, rel=1e-15)
    assert stress.von_mises(hyd) == 0.0
    assert stress.max_shear(hyd) == 0.0
    np.testing.assert_allclose(stress.deviator(hyd), 0, atol=1e-10)
    np.testing.assert_allclose(stress.traction(hyd, [0, 0, 2.0]), [0, 0, -p], rtol=1e-15)


def test_invariants_under_rotation_and_batch(rng):
    S = _random_sym(rng, 50)
    R = random_rotation(rng, 50)
    Sr = R @ S @ np.swapaxes(R, 1, 2)
    np.testing.assert_allclose(stress.von_mises(S), von_mises_ref(S), rtol=1e-13)
    np.testing.assert_allclose(stress.von_mises(Sr), stress.von_mises(S), rtol=1e-12)
    np.testing.assert_allclose(stress.pressure(Sr), stress.pressure(S), rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(stress.max_shear(Sr), stress.max_shear(S), rtol=1e-12)
    np.testing.assert_allclose(stress.principal(Sr)[0], stress.principal(S)[0], rtol=1e-11,
                               atol=1e-8)
    w = np.linalg.eigvalsh(S)
    np.testing.assert_allclose(stress.max_shear(S), 0.5 * (w[:, 2] - w[:, 0]), rtol=1e-12)


def test_bad_input():
    with pytest.raises(ValueError, match="symmetric"):
        stress.principal([[1, 2, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="symmetric"):
        stress.von_mises([[1, 2, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="finite"):
        stress.pressure(np.full((3, 3), np.nan))
    with pytest.raises(ValueError):
        stress.max_shear(np.eye(2))
    with pytest.raises(TypeError):
        stress.principal([["a"] * 3] * 3)
    with pytest.raises(ValueError, match="normal"):
        stress.traction(np.eye(3), [0, 0, 0])
