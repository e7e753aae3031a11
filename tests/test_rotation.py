"""mechpy.rotation against SciPy's Rotation, the textbook formulas of section 5
and finite differences."""
import re
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import mechpy as mp
from mechpy import rotation as rot

SEQS = rot.SEQUENCES
PROPER = [s for s in SEQS if s[0].lower() == s[2].lower()]


# ---------------------------------------------------------------- references
def textbook_lambda(phi, theta, psi):
    """lambda = lambda_psi lambda_theta lambda_phi, the matrices of the notes (section 5)."""
    c, s = np.cos, np.sin
    lphi = np.array([[c(phi), s(phi), 0], [-s(phi), c(phi), 0], [0, 0, 1]])
    lth = np.array([[1, 0, 0], [0, c(theta), s(theta)], [0, -s(theta), c(theta)]])
    lpsi = np.array([[c(psi), s(psi), 0], [-s(psi), c(psi), 0], [0, 0, 1]])
    return lpsi @ lth @ lphi


def textbook_omega_body(phi, theta, psi, dphi, dtheta, dpsi):
    """Body components of omega for ZXZ (the notes' omega_1, omega_2, omega_3)."""
    return np.array([dphi * np.sin(theta) * np.sin(psi) + dtheta * np.cos(psi),
                     dphi * np.sin(theta) * np.cos(psi) - dtheta * np.sin(psi),
                     dphi * np.cos(theta) + dpsi])


def random_angles(rng, n, seq):
    """Angles in each sequence's canonical ranges, away from gimbal lock."""
    a = rng.uniform(-np.pi, np.pi, (n, 3))
    if seq[0].lower() == seq[2].lower():
        a[:, 1] = rng.uniform(0.01, np.pi - 0.01, n)
    else:
        a[:, 1] = rng.uniform(-np.pi / 2 + 0.01, np.pi / 2 - 0.01, n)
    return a


def lock_angles(seq):
    """Middle angles at gimbal lock, exactly and 1e-9 away from it."""
    if seq[0].lower() == seq[2].lower():
        exact = [0.0, np.pi]
        near = [1e-9, np.pi - 1e-9]
    else:
        exact = [np.pi / 2, -np.pi / 2]
        near = [np.pi / 2 - 1e-9, -np.pi / 2 + 1e-9]
    return exact, near


def scipy_matrix(seq, a, passive):
    R = Rotation.from_euler(seq, a).as_matrix()
    return np.swapaxes(R, -1, -2) if passive else R


def angle_diff(a, b):
    """Difference of angles modulo 2 pi, in [-pi, pi]."""
    return np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b))))


def is_rotation(R, tol=1e-14):
    eye = np.eye(3)
    orth = np.max(np.abs(R @ np.swapaxes(R, -1, -2) - eye))
    det = np.linalg.det(R)
    return orth <= tol and np.all(np.abs(det - 1) <= tol)


# ---------------------------------------------------------------- conventions
def test_default_is_textbook_lambda_and_scipy_transpose(rng):
    for phi, theta, psi in rng.uniform(-3, 3, (20, 3)):
        L = rot.euler_matrix(phi, theta, psi)
        assert L.shape == (3, 3)
        np.testing.assert_allclose(L, textbook_lambda(phi, theta, psi), rtol=0, atol=1e-15)
        ref = Rotation.from_euler("ZXZ", [phi, theta, psi]).as_matrix().T
        np.testing.assert_allclose(L, ref, rtol=0, atol=1e-15)


def test_lambda_maps_space_to_body_components():
    # rotate by phi about z only: a fixed vector along x' has body components (cos, -sin, 0)
    phi = 0.7
    L = rot.euler_matrix(phi, 0.0, 0.0)
    np.testing.assert_allclose(L @ [1.0, 0, 0], [np.cos(phi), -np.sin(phi), 0], atol=1e-16)


@pytest.mark.parametrize("seq", SEQS)
@pytest.mark.parametrize("passive", [False, True])
def test_euler_matrix_against_scipy(seq, passive, rng):
    a = rng.uniform(-np.pi, np.pi, (200, 3))
    R = rot.euler_matrix(a, seq=seq, passive=passive)
    assert R.shape == (200, 3, 3)
    np.testing.assert_allclose(R, scipy_matrix(seq, a, passive), rtol=0, atol=2e-15)
    assert is_rotation(R, 2e-15)
    # the three-argument form is the same
    R3 = rot.euler_matrix(a[:, 0], a[:, 1], a[:, 2], seq, passive)
    np.testing.assert_array_equal(R3, R)


@pytest.mark.parametrize("seq", SEQS)
@pytest.mark.parametrize("passive", [False, True])
def test_euler_angles_against_scipy(seq, passive, rng):
    a = random_angles(rng, 200, seq)
    R = scipy_matrix(seq, a, passive)
    got = rot.euler_angles(R, seq, passive)
    ref = Rotation.from_matrix(R.swapaxes(-1, -2) if passive else R).as_euler(seq)
    np.testing.assert_allclose(angle_diff(got, ref), 0, atol=1e-13)
    np.testing.assert_allclose(angle_diff(got, a), 0, atol=1e-13)


@pytest.mark.parametrize("seq", SEQS)
def test_angle_ranges(seq, rng):
    R = Rotation.random(500, random_state=1).as_matrix()
    a = rot.euler_angles(R, seq, passive=False)
    assert np.all(np.abs(a[:, [0, 2]]) <= np.pi)
    if seq in PROPER:
        assert np.all((a[:, 1] >= 0) & (a[:, 1] <= np.pi))
    else:
        assert np.all(np.abs(a[:, 1]) <= np.pi / 2)
    # the quaternion path: the same ranges, and the angles give back the rotation
    q = np.random.default_rng(2).normal(size=(2000, 4))
    for passive in (False, True):
        a = rot.euler_from_quat(q, seq, passive)
        assert np.all(np.abs(a[:, [0, 2]]) <= np.pi)
        if seq in PROPER:
            assert np.all((a[:, 1] >= 0) & (a[:, 1] <= np.pi))
        else:
            assert np.all(np.abs(a[:, 1]) <= np.pi / 2)
        ref = Rotation.from_quat(q).as_matrix()
        assert np.abs(scipy_matrix(seq, a, passive) - ref).max() < 5e-15   # 1.4e-15


# ---------------------------------------------------------------- round trips and lock
def round_trip_error(seq, a, passive):
    R1 = rot.euler_matrix(a, seq=seq, passive=passive)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rot.GimbalLockWarning)
        b = rot.euler_angles(R1, seq, passive)
    assert np.all(np.isfinite(b))
    R2 = rot.euler_matrix(b, seq=seq, passive=passive)
    assert is_rotation(R2, 2e-15)
    return np.max(np.abs(R2 - R1))


@pytest.mark.parametrize("seq", SEQS)
@pytest.mark.parametrize("passive", [False, True])
def test_round_trip_random_and_at_lock(seq, passive, rng):
    a = rng.uniform(-np.pi, np.pi, (300, 3))
    exact, near = lock_angles(seq)
    lock = rng.uniform(-np.pi, np.pi, (40, 3))
    lock[:, 1] = np.repeat(exact + near, 10)
    a = np.concatenate([a, lock])
    # also random rotations, uniformly distributed
    R = Rotation.random(200, random_state=7).as_matrix()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", rot.GimbalLockWarning)
        b = rot.euler_angles(R, seq, passive)
    assert round_trip_error(seq, a, passive) <= 1e-14
    assert round_trip_error(seq, b, passive) <= 1e-14


def exact_lock_matrix(seq, a):
    """Active matrices of the angles a (..., 3) with the middle one at lock (0, pi or
    +-pi/2), with the entries that vanish at lock set to exactly 0: float64's pi and pi/2
    are 1e-16 from lock, and there the first and third angles are still determined."""
    R = rot.euler_matrix(a, seq=seq, passive=False)
    ax = ["xyz".index(ch) for ch in seq.lower()]
    if not seq.isupper():
        ax = ax[::-1]
    i, j, k = ax
    if i == k:
        l = 3 - i - j
        R[..., i, j] = R[..., i, l] = R[..., j, i] = R[..., l, i] = 0.0
        R[..., i, i] = np.sign(R[..., i, i])
    else:
        R[..., i, i] = R[..., i, j] = R[..., j, k] = R[..., k, k] = 0.0
        R[..., i, k] = np.sign(R[..., i, k])
    return R


@pytest.mark.parametrize("seq", SEQS)
def test_exact_lock_third_angle_zero_and_one_warning(seq, rng):
    exact, near = lock_angles(seq)
    a = rng.uniform(-3, 3, (50, 3))
    a[:, 1] = np.repeat(exact, 25)
    R = exact_lock_matrix(seq, a)
    with pytest.warns(rot.GimbalLockWarning) as rec:
        b = rot.euler_angles(R, seq, passive=False)
    assert len([w for w in rec if issubclass(w.category, rot.GimbalLockWarning)]) == 1
    assert np.all(b[:, 2] == 0.0)
    np.testing.assert_allclose(angle_diff(b[:, 1], a[:, 1]), 0, atol=1e-15)
    np.testing.assert_allclose(rot.euler_matrix(b, seq=seq, passive=False), R, atol=1e-15)
    # SciPy gives the same triple at exact lock
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        ref = Rotation.from_matrix(R).as_euler(seq)
    np.testing.assert_allclose(angle_diff(b, ref), 0, atol=1e-13)


@pytest.mark.parametrize("seq", SEQS)
@pytest.mark.parametrize("passive", [False, True])
def test_near_lock_angles_are_exact_down_to_the_smallest_normal(seq, passive, rng):
    # theta = 1e-12 away from lock was reported as lock (third angle 0, the first and third
    # off by up to 1e-12 and a warning); every angle is determined while the sine of the
    # distance from lock is a normal number, and comes back to round-off
    a = rng.uniform(-3, 3, (8 * 6, 3))
    dist = np.repeat([1e-9, 1e-12, 1e-100, 1e-300, 1e-307, 2.3e-308], 8)
    proper = seq[0].lower() == seq[2].lower()
    if proper:
        a[:, 1] = dist                      # near 0 (pi - dist is not representable)
    else:
        a[:, 1] = np.where(np.arange(a.shape[0]) % 2, 1.0, -1.0) * (np.pi / 2 - 1e-9)
        a[: 8 * 2, 1] = np.pi / 2 - np.repeat([1e-9, 1e-12], 8)
    R = rot.euler_matrix(a, seq=seq, passive=passive)
    with warnings.catch_warnings():
        warnings.simplefilter("error", rot.GimbalLockWarning)
        b = rot.euler_angles(R, seq, passive)
        # the quaternion holds sin(theta / 2): normal down to theta = 4.5e-308
        q = rot.quat_from_euler(a[:-8], seq=seq, passive=passive)
        bq = rot.euler_from_quat(q, seq, passive)
    # theta to relative round-off; phi and psi individually (measured <= 9e-16)
    np.testing.assert_allclose(b[:, 1], a[:, 1], rtol=4e-15, atol=0)
    np.testing.assert_allclose(angle_diff(b[:, [0, 2]], a[:, [0, 2]]), 0, atol=4e-15)
    if proper:
        np.testing.assert_allclose(bq[:, 1], a[:-8, 1], rtol=4e-15, atol=0)
        np.testing.assert_allclose(angle_diff(bq[:, [0, 2]], a[:-8, [0, 2]]), 0, atol=4e-15)
    else:
        # near Tait-Bryan lock the angles sit in differences of O(1) quaternion components,
        # which quat_from_euler rounds: the quaternion, not the angles, comes back
        q2 = rot.quat_from_euler(bq, seq=seq, passive=passive)
        np.testing.assert_allclose(np.abs(np.sum(q2 * q, axis=-1)), 1.0, rtol=0,
                                   atol=2e-15)                        # measured 4.4e-16
    # SciPy calls all of these locked (its band is 1e-7) and returns psi = 0: its triple
    # reproduces the matrix too, but not the angles
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        ref = Rotation.from_matrix(R.swapaxes(-1, -2) if passive else R).as_euler(seq)
    np.testing.assert_allclose(rot.euler_matrix(ref, seq=seq, passive=passive), R, atol=1e-8)
    np.testing.assert_allclose(rot.euler_matrix(b, seq=seq, passive=passive), R, atol=2e-15)


@pytest.mark.parametrize("seq", SEQS)
def test_lock_warning_names_the_lock_angle(seq):
    # proper Euler sequences lock at theta = 0 or pi, Tait-Bryan ones at +-pi/2
    exact, _ = lock_angles(seq)
    R = exact_lock_matrix(seq, np.array([[0.7, exact[0], 0.4]]))
    which = "0 or pi" if seq in PROPER else "+-pi/2"
    with pytest.warns(rot.GimbalLockWarning, match=re.escape(f"{seq!r} at {which})")):
        rot.euler_angles(R, seq, passive=False)


@pytest.mark.parametrize("seq", PROPER)
def test_lock_below_the_smallest_normal_still_warns(seq):
    # sin(theta) subnormal: the first and third angles have lost their precision
    a = np.array([[0.7, 1e-310, 0.4], [0.7, 0.0, 0.4]])
    R = rot.euler_matrix(a, seq=seq, passive=False)
    with pytest.warns(rot.GimbalLockWarning, match="2 of 2"):
        b = rot.euler_angles(R, seq, passive=False)
    np.testing.assert_array_equal(b[:, 2], 0.0)
    np.testing.assert_allclose(rot.euler_matrix(b, seq=seq, passive=False), R, atol=4e-16)


def test_lock_warning_is_silenceable_and_a_userwarning():
    assert issubclass(rot.GimbalLockWarning, UserWarning)
    R = rot.euler_matrix(0.4, 0.0, 0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", rot.GimbalLockWarning)
        a = rot.euler_angles(R)
    np.testing.assert_allclose(a, [0.7, 0.0, 0.0], atol=1e-15)
    # 1e-9 from lock: no warning, the angles themselves come back
    R = rot.euler_matrix(0.4, 1e-9, 0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = rot.euler_angles(R)
    np.testing.assert_allclose(a[1], 1e-9, rtol=1e-6)
    np.testing.assert_allclose(a[0] + a[2], 0.7, atol=1e-15)


def test_lock_tolerance_is_adjustable():
    R = rot.euler_matrix(0.4, 1e-9, 0.3)
    with pytest.warns(rot.GimbalLockWarning):
        a = rot.euler_angles(R, lock_tol=1e-7)        # SciPy's band
    assert a[2] == 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        ref = Rotation.from_matrix(R.T).as_euler("ZXZ")
    np.testing.assert_allclose(angle_diff(a, ref), 0, atol=1e-12)


# ---------------------------------------------------------------- quaternions
@pytest.mark.parametrize("seq", SEQS)
@pytest.mark.parametrize("passive", [False, True])
def test_quat_from_euler_against_scipy(seq, passive, rng):
    a = rng.uniform(-np.pi, np.pi, (200, 3))
    q = rot.quat_from_euler(a, seq=seq, passive=passive)
    ref = Rotation.from_euler(seq, a)
    ref = ref.inv() if passive else ref
    np.testing.assert_allclose(q, ref.as_quat(), rtol=0, atol=1e-15)
    np.testing.assert_allclose(rot.matrix_from_quat(q), rot.euler_matrix(a, seq=seq,
                                                                        passive=passive),
                               atol=2e-15)


@pytest.mark.parametrize("seq", SEQS)
@pytest.mark.parametrize("passive", [False, True])
def test_euler_from_quat_against_scipy(seq, passive, rng):
    a = random_angles(rng, 200, seq)
    q = Rotation.from_euler(seq, a).as_quat()
    q = q * rng.uniform(0.1, 10, (200, 1))          # need not be unit
    if passive:
        q[:, :3] *= -1
    got = rot.euler_from_quat(q, seq, passive)
    np.testing.assert_allclose(angle_diff(got, a), 0, atol=1e-13)



@pytest.mark.parametrize("seq", SEQS)
def test_euler_from_quat_of_the_identity_and_the_half_turns(seq):
    """The quaternions with one nonzero component (the identity and the half turns
    about x, y, z), unit and scaled by 1e-140 or 1e140: their angles give back SciPy's
    matrix (at lock the angles are another choice of the same rotation)."""
    for k in range(4):
        for scale in (1.0, 1e-140, 1e140):
            q = np.zeros(4)
            q[k] = scale
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)    # gimbal lock at some
                a = rot.euler_from_quat(q, seq)
            R = Rotation.from_quat(np.eye(4)[k]).as_matrix()
            assert np.abs(scipy_matrix(seq, a, False) - R).max() < 1e-15, (k, scale)

def test_quat_from_matrix_against_scipy_every_branch():
    # identity-like, near-180-degree rotations about each axis (each Shepperd branch), random
    R = np.concatenate([
        Rotation.random(300, random_state=3).as_matrix(),
        Rotation.from_rotvec(np.diag([np.pi - 1e-9] * 3)).as_matrix(),
        Rotation.from_rotvec(np.pi * np.eye(3)).as_matrix(),
        Rotation.from_rotvec([[1e-12, 0, 0], [0, 0, 0]]).as_matrix(),
    ])
    q = rot.quat_from_matrix(R)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1, atol=1e-15)
    ref = Rotation.from_matrix(R).as_quat()
    np.testing.assert_allclose(q, ref, rtol=0, atol=1e-15)     # same sign as SciPy
    np.testing.assert_allclose(rot.matrix_from_quat(q), R, atol=2e-15)


def test_matrix_from_quat_and_normalize(rng):
    q = rng.normal(size=(100, 4)) * rng.uniform(1e-3, 1e3, (100, 1))
    np.testing.assert_allclose(rot.matrix_from_quat(q), Rotation.from_quat(q).as_matrix(),
                               atol=2e-15)
    u = rot.quat_normalize(q)
    np.testing.assert_allclose(u, q / np.linalg.norm(q, axis=-1, keepdims=True), atol=1e-15)
    np.testing.assert_allclose(rot.quat_normalize([0, 0, 1e200, 1e200]),
                               [0, 0, 2 ** -0.5, 2 ** -0.5], atol=1e-16)
    np.testing.assert_allclose(rot.quat_normalize([3e-300, 0, 0, 4e-300]), [0.6, 0, 0, 0.8])


def test_quat_multiply_is_composition(rng):
    p = Rotation.random(100, random_state=5)
    q = Rotation.random(100, random_state=6)
    r = rot.quat_multiply(p.as_quat(), q.as_quat())
    # SciPy may flip the sign of the product; compare up to sign and through matrices
    ref = (p * q).as_quat()
    sign = np.sign(np.sum(r * ref, axis=-1, keepdims=True))
    np.testing.assert_allclose(r, sign * ref, atol=1e-15)
    np.testing.assert_allclose(rot.matrix_from_quat(r), p.as_matrix() @ q.as_matrix(),
                               atol=2e-15)
    # Hamilton's rules i j = k, j i = -k, i^2 = -1; broadcasting of one factor
    i, j, k = np.eye(4)[:3]
    np.testing.assert_array_equal(rot.quat_multiply(i, j), k)
    np.testing.assert_array_equal(rot.quat_multiply(j, i), -k)
    np.testing.assert_array_equal(rot.quat_multiply(i, i), [0, 0, 0, -1])
    assert rot.quat_multiply(i, rng.normal(size=(2, 7, 4))).shape == (2, 7, 4)


# ---------------------------------------------------------------- angular velocity
def test_textbook_omega_zxz(rng):
    for _ in range(20):
        a, r = rng.uniform(-3, 3, 3), rng.normal(size=3)
        np.testing.assert_allclose(rot.angular_velocity(a, r), textbook_omega_body(*a, *r),
                                   atol=1e-15)


def vee(W):
    return np.stack([W[..., 2, 1] - W[..., 1, 2], W[..., 0, 2] - W[..., 2, 0],
                     W[..., 1, 0] - W[..., 0, 1]], axis=-1) / 2


@pytest.mark.parametrize("seq", SEQS)
def test_angular_velocity_against_finite_difference(seq, rng):
    a = rng.uniform(-3, 3, (50, 3))
    r = rng.normal(size=(50, 3))
    h = 1e-5
    L = rot.euler_matrix(a, seq=seq)
    Ldot = (rot.euler_matrix(a + h * r, seq=seq) - rot.euler_matrix(a - h * r, seq=seq)) / (2 * h)
    body = vee(-Ldot @ L.swapaxes(-1, -2))               # Omega_body = -lambda_dot lambda^T
    space = vee(-L.swapaxes(-1, -2) @ Ldot)              # Omega_space = R_dot R^T, R = L^T
    np.testing.assert_allclose(rot.angular_velocity(a, r, seq), body, atol=1e-9)
    np.testing.assert_allclose(rot.angular_velocity(a, r, seq, frame="space"), space,
                               atol=1e-9)
    # space = R body
    np.testing.assert_allclose(rot.angular_velocity(a, r, seq, "space"),
                               np.einsum("nji,nj->ni", L, rot.angular_velocity(a, r, seq)),
                               atol=1e-14)


@pytest.mark.parametrize("seq", SEQS)
@pytest.mark.parametrize("frame", ["body", "space"])
def test_euler_rates_inverts_angular_velocity(seq, frame, rng):
    a = random_angles(rng, 100, seq)
    r = rng.normal(size=(100, 3))
    w = rot.angular_velocity(a, r, seq, frame)
    np.testing.assert_allclose(rot.euler_rates(a, w, seq, frame), r, atol=1e-12)


@pytest.mark.parametrize("seq", SEQS)
def test_euler_rates_singular_at_lock(seq):
    exact, _ = lock_angles(seq)
    for theta in exact:
        with pytest.raises(mp.SingularityError, match="gimbal lock"):
            rot.euler_rates([[0.1, 0.2, 0.3], [0.3, theta, 0.2]], [1.0, 2.0, 3.0], seq)


def test_euler_rates_textbook_zxz():
    phi, theta, psi = 0.3, 0.8, -1.1
    w = np.array([0.4, -0.7, 1.3])
    dphi = (w[0] * np.sin(psi) + w[1] * np.cos(psi)) / np.sin(theta)
    dtheta = w[0] * np.cos(psi) - w[1] * np.sin(psi)
    dpsi = w[2] - dphi * np.cos(theta)
    np.testing.assert_allclose(rot.euler_rates([phi, theta, psi], w), [dphi, dtheta, dpsi],
                               atol=1e-15)


# ---------------------------------------------------------------- shapes and bad input
def test_batch_shapes(rng):
    a = rng.uniform(-3, 3, (2, 5, 3))
    R = rot.euler_matrix(a)
    assert R.shape == (2, 5, 3, 3)
    assert rot.euler_angles(R).shape == (2, 5, 3)
    assert rot.quat_from_matrix(R).shape == (2, 5, 4)
    assert rot.matrix_from_quat(rot.quat_from_euler(a)).shape == (2, 5, 3, 3)
    assert rot.angular_velocity(a, [1, 2, 3]).shape == (2, 5, 3)
    assert rot.euler_matrix(np.zeros((0, 3))).shape == (0, 3, 3)
    assert rot.euler_matrix(0.1, [0.2, 0.3], 0.4).shape == (2, 3, 3)
    assert rot.euler_matrix([1, 2, 3], "zyx").shape == (3, 3)
    assert rot.quat_from_euler(0.1, 0.2, 0.3).shape == (4,)


@pytest.mark.parametrize("seq", ["ZZX", "XYz", "abc", "XY", "XYZX", "", "ZXZ ", "xyy"])
def test_unknown_sequences(seq):
    with pytest.raises(ValueError, match="seq"):
        rot.euler_matrix(0.1, 0.2, 0.3, seq=seq)
    with pytest.raises(ValueError, match="seq"):
        rot.euler_angles(np.eye(3), seq=seq)
    with pytest.raises(ValueError, match="seq"):
        rot.angular_velocity([0, 1, 0], [1, 1, 1], seq=seq)


def test_wrong_types_and_shapes():
    with pytest.raises(TypeError, match="seq"):
        rot.euler_matrix(0.1, 0.2, 0.3, seq=3)
    with pytest.raises(TypeError):
        rot.euler_matrix("a", "b", "c")
    with pytest.raises(ValueError, match="R"):
        rot.euler_angles(np.eye(4))
    with pytest.raises(ValueError, match="R"):
        rot.quat_from_matrix(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="angles"):
        rot.euler_matrix(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="quat"):
        rot.matrix_from_quat([1, 0, 0])
    with pytest.raises(ValueError, match="rates"):
        rot.angular_velocity([0, 1, 0], [1, 1])
    with pytest.raises(ValueError, match="broadcast"):
        rot.euler_matrix([0.1, 0.2], [0.1, 0.2, 0.3], 0.0)
    with pytest.raises(ValueError, match="frame"):
        rot.angular_velocity([0, 1, 0], [1, 1, 1], frame="lab")
    with pytest.raises(ValueError, match="finite"):
        rot.euler_matrix(np.nan, 0.0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        rot.euler_angles(np.full((3, 3), np.nan))
    with pytest.raises(TypeError, match="passive"):
        rot.euler_matrix(0.1, 0.2, 0.3, passive="yes")


def test_non_orthogonal_matrices_rejected_beyond_tolerance(rng):
    R = rot.euler_matrix(0.3, 0.4, 0.5)
    for bad in (2 * R, R + 1e-3 * rng.normal(size=(3, 3)), np.diag([1.0, 1.0, -1.0]),
                -np.eye(3), np.zeros((3, 3))):
        with pytest.raises(mp.DomainError, match="rotation matrix"):
            rot.euler_angles(bad)
        with pytest.raises(ValueError):
            rot.quat_from_matrix(bad)
    # the batch index of the offender is named
    stack = np.stack([R, R, 1.01 * R])
    with pytest.raises(mp.DomainError, match="item 2"):
        rot.euler_angles(stack)
    # within the stated tolerance (ORTH_TOL = 1e-6) a matrix is accepted ...
    slightly = R + 1e-8 * rng.normal(size=(3, 3))
    a = rot.euler_angles(slightly)
    np.testing.assert_allclose(rot.euler_matrix(a), R, atol=1e-7)
    # ... and the tolerance can be tightened or widened
    with pytest.raises(mp.DomainError):
        rot.euler_angles(slightly, orth_tol=1e-12)
    rot.quat_from_matrix(1.001 * R, orth_tol=1e-2)


def test_zero_quaternion_rejected():
    for f in (rot.matrix_from_quat, rot.quat_normalize, rot.euler_from_quat):
        with pytest.raises(mp.DomainError, match="non-zero"):
            f([[0, 0, 0, 1], [0, 0, 0, 0]])


def test_degrees_like_scipy(rng):
    a = rng.uniform(-170, 170, (20, 3))
    a[:, 1] = rng.uniform(5, 175, 20)
    np.testing.assert_allclose(rot.euler_matrix(a, seq="zxz", passive=False, degrees=True),
                               Rotation.from_euler("zxz", a, degrees=True).as_matrix(),
                               atol=2e-15)
    np.testing.assert_allclose(rot.quat_from_euler(a, seq="XYX", passive=False, degrees=True),
                               Rotation.from_euler("XYX", a, degrees=True).as_quat(), atol=1e-15)
    L = rot.euler_matrix(a, degrees=True)
    np.testing.assert_allclose(rot.euler_angles(L, degrees=True), a, atol=1e-11)
    np.testing.assert_allclose(rot.euler_from_quat(rot.quat_from_euler(a, degrees=True),
                                                   degrees=True), a, atol=1e-11)


# ---- the interchange with SciPy keeps the module's passive default (issue 51, item 18) ----

def test_to_scipy_and_from_scipy_round_trip_the_angles_with_the_defaults(rng):
    # euler_matrix is passive by default; so are to_scipy and from_scipy: the angles come
    # back through SciPy's Rotation with every default, for single and batched angles
    a = np.array([0.3, 0.2, 0.1])
    got = rot.to_scipy(rot.euler_matrix(*a)).as_euler("ZXZ")
    assert np.abs(got - a).max() < 5e-15                 # measured 5.6e-17
    A = np.column_stack([rng.uniform(-np.pi, np.pi, 30), rng.uniform(0.1, 3.0, 30),
                         rng.uniform(-np.pi, np.pi, 30)])
    assert np.abs(rot.to_scipy(rot.euler_matrix(A)).as_euler("ZXZ") - A).max() < 5e-14
    ref = Rotation.from_euler("ZXZ", A)
    assert np.abs(rot.from_scipy(ref) - rot.euler_matrix(A)).max() < 5e-15
    lam = rot.euler_matrix(A)
    assert np.abs(rot.from_scipy(rot.to_scipy(lam)) - lam).max() < 5e-15
    # the active matrices, as SciPy's as_matrix gives them, with passive=False
    R = ref.as_matrix()
    assert np.abs(rot.to_scipy(R, passive=False).as_matrix() - R).max() < 5e-15
    assert np.array_equal(rot.from_scipy(ref, passive=False), R)
