"""mp.particles: collisions against momentum conservation, the closed-form
energy loss and the textbook's special cases; the centre-of-mass frame."""
import numpy as np
import pytest

import mechpy as mp

P = mp.particles
RNG = np.random.default_rng(3)


def test_momentum_conserved_and_energy_loss_closed_form_1d():
    m1, m2 = RNG.uniform(0.1, 5, 50), RNG.uniform(0.1, 5, 50)
    v1, v2 = RNG.normal(size=50), RNG.normal(size=50)
    e = RNG.uniform(0, 1, 50)
    a, b = P.collide(m1, v1, m2, v2, e)
    np.testing.assert_allclose(m1 * a + m2 * b, m1 * v1 + m2 * v2, rtol=0, atol=1e-14)
    loss = 0.5 * (m1 * v1**2 + m2 * v2**2) - 0.5 * (m1 * a**2 + m2 * b**2)
    mu = m1 * m2 / (m1 + m2)
    # Marion & Thornton eq. 9.77: (1 - e^2) mu/2 (v1 - v2)^2; measured 4e-15
    np.testing.assert_allclose(loss, 0.5 * (1 - e**2) * mu * (v1 - v2)**2, rtol=0, atol=5e-14)
    np.testing.assert_allclose(b - a, -e * (v2 - v1), atol=1e-14)     # restitution


def test_elastic_equal_masses_exchange_and_e0_sticks():
    a, b = P.collide(2.0, 3.0, 2.0, -1.0)
    assert (float(a), float(b)) == (-1.0, 3.0)
    a, b = P.collide(1.0, 3.0, 2.0, 0.0, e=0.0)
    assert float(a) == pytest.approx(1.0, abs=1e-15) and float(b) == pytest.approx(1.0, abs=1e-15)


def test_billiards_90_degrees_equal_masses():
    """Equal masses, elastic, target at rest, glancing (off-centre) impact: the
    two leave at right angles (Marion & Thornton section 9.7)."""
    for angle in (0.2, 0.7, 1.1):
        n = np.array([np.cos(angle), np.sin(angle)])
        a, b = P.collide(1.0, [1.0, 0.0], 1.0, [0.0, 0.0], normal=n)
        assert abs(a @ b) < 1e-15                                       # perpendicular
        np.testing.assert_allclose(a + b, [1.0, 0.0], atol=1e-15)
        assert abs(b[0] * n[1] - b[1] * n[0]) < 1e-15                   # struck ball along n


def test_3d_tangential_kept_and_batch():
    m1, m2 = RNG.uniform(0.5, 2, (4, 5)), RNG.uniform(0.5, 2, (4, 5))
    v1, v2, n = RNG.normal(size=(4, 5, 3)), RNG.normal(size=(4, 5, 3)), RNG.normal(size=(4, 5, 3))
    e = 0.6
    a, b = P.collide(m1, v1, m2, v2, e, normal=n)
    nh = n / np.linalg.norm(n, axis=-1, keepdims=True)
    tang = lambda v: v - np.sum(v * nh, -1, keepdims=True) * nh     # noqa: E731
    np.testing.assert_allclose(tang(a), tang(v1), atol=1e-14)
    np.testing.assert_allclose(tang(b), tang(v2), atol=1e-14)
    np.testing.assert_allclose(m1[..., None] * a + m2[..., None] * b,
                               m1[..., None] * v1 + m2[..., None] * v2, atol=1e-14)
    for i in range(4):                       # one collision at a time gives the same
        a1, _ = P.collide(m1[i, 2], v1[i, 2], m2[i, 2], v2[i, 2], e, normal=n[i, 2])
        np.testing.assert_allclose(a1, a[i, 2], atol=1e-15)


@pytest.mark.parametrize("kw, match", [
    (dict(m1=-1.0), "m1"), (dict(m2=0.0), "m2"), (dict(e=1.5), "restitution"),
    (dict(e=-0.1), "restitution"), (dict(normal=[0.0, 0.0]), "zero"),
    (dict(normal=[1.0, 0.0, 0.0]), "last axis"), (dict(normal=[1.0]), "2D or 3D"),
    (dict(m1=[1.0, 2.0, 3.0], v1=[[1.0, 0.0]] * 2), "shape mismatch"),
])
def test_bad_input(kw, match):
    args = dict(m1=1.0, v1=[1.0, 0.0], m2=1.0, v2=[0.0, 0.0], e=1.0, normal=[1.0, 0.0])
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        P.collide(**args)


def test_cm_frame_round_trip_and_zero_momentum():
    m = RNG.uniform(0.5, 2, (3, 6))
    v = RNG.normal(size=(3, 6, 3))
    V, u = P.to_cm(m, v)
    np.testing.assert_allclose(np.sum(m[..., None] * u, axis=-2), 0.0, atol=1e-14)
    np.testing.assert_allclose(P.from_cm(V, u), v, atol=1e-15)
    V1, u1 = P.to_cm(m, v[..., 0])
    np.testing.assert_allclose(V1, V[..., 0], atol=1e-15)
    np.testing.assert_allclose(P.from_cm(V1, u1), v[..., 0], atol=1e-15)
    # a collision seen from the CM frame: elastic reverses both velocities
    a, b = P.collide(1.0, 3.0, 3.0, -1.0)
    Vc, uc = P.to_cm([1.0, 3.0], [3.0, -1.0])
    np.testing.assert_allclose(P.from_cm(Vc, -uc), [float(a), float(b)], atol=1e-15)
    with pytest.raises(ValueError, match="masses"):
        P.to_cm([1.0, -1.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="velocities"):
        P.to_cm([1.0, 1.0], [0.0, 1.0, 2.0])
    # vectors, but one per particle of another count: 3 particles, 4 velocities
    with pytest.raises(ValueError, match=r"velocities must have the masses' shape \(3,\)"):
        P.to_cm([1.0, 2.0, 3.0], np.zeros((4, 2)))


def test_restitution_law_along_the_normal_both_moving():
    """Both bodies moving, oblique normal, 2D and 3D: the normal relative velocity
    reverses scaled by e (Newton's law of restitution), and the kinetic energy lost
    is mu (1 - e^2) u^2 / 2 with mu the reduced mass and u the normal closing speed."""
    for d in (2, 3):
        m1, m2 = RNG.uniform(0.5, 2, 6), RNG.uniform(0.5, 2, 6)
        v1, v2 = RNG.normal(size=(6, d)), RNG.normal(size=(6, d))
        n = RNG.normal(size=(6, d))
        e = RNG.uniform(0, 1, 6)
        a, b = P.collide(m1, v1, m2, v2, e, normal=n)
        nh = n / np.linalg.norm(n, axis=-1, keepdims=True)
        u = np.sum((v1 - v2) * nh, -1)
        np.testing.assert_allclose(np.sum((a - b) * nh, -1), -e * u, rtol=0, atol=1e-14)
        ke = lambda x, y: (m1 * np.sum(x * x, -1) + m2 * np.sum(y * y, -1)) / 2   # noqa: E731
        mu = m1 * m2 / (m1 + m2)
        np.testing.assert_allclose(ke(v1, v2) - ke(a, b), mu * (1 - e ** 2) * u ** 2 / 2,
                                   rtol=0, atol=1e-14)
