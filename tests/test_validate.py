"""mechpy._validate: each helper's contract at its boundaries (inclusive bounds,
the int64 range, shapes, the pass-through of arrays the C core takes as they are),
as its docstring states it; the modules' own tests meet these only through their
arguments."""
import numpy as np
import pytest

from mechpy import _validate as V
from mechpy.errors import NonFiniteError


def test_as_array_passes_a_c_contiguous_float64_array_through_and_converts_the_rest():
    a = np.arange(6.0).reshape(2, 3)
    assert V.as_array(a, "a") is a
    for x in (a.T, a.astype(np.float32), a.astype(np.int64), a.tolist(), np.asfortranarray(a)):
        r = V.as_array(x, "a")
        assert r.dtype == np.float64 and r.flags.c_contiguous and r is not x
        assert np.array_equal(r, np.asarray(x, float))
    assert V.as_array(3, "a").shape == ()   # 0-d stays 0-d


@pytest.mark.parametrize("x, err, match", [
    ("abc", TypeError, "a must be a real numeric array, got str"),
    (None, TypeError, "got NoneType"),
    ([[1.0], [1.0, 2.0]], ValueError, "rectangular"),
    ([1 + 2j], TypeError, "dtype complex128"),
])
def test_as_array_refuses_what_is_not_real(x, err, match):
    with pytest.raises(err, match=match):
        V.as_array(x, "a")


def test_as_array_shapes():
    x = np.zeros((2, 3))
    assert V.as_array(x, "a", ndim=2) is x
    with pytest.raises(ValueError, match=r"a must have 1 dimension\(s\), got shape \(2, 3\)"):
        V.as_array(x, "a", ndim=1)
    assert V.as_array(x, "a", min_ndim=2) is x
    with pytest.raises(ValueError, match="at least 3"):
        V.as_array(x, "a", min_ndim=3)
    assert V.as_array(x, "a", shape=(2, None)) is x
    assert V.as_array(x, "a", shape=(None, 3)) is x
    for bad in [(3, None), (None, 2), (2,), (2, 3, 1), (None, None, None)]:
        with pytest.raises(ValueError, match=r"a must have shape \("):
            V.as_array(x, "a", shape=bad)
    with pytest.raises(ValueError, match=r"a must have shape \(n, 2\), got \(2, 3\)"):
        V.as_array(x, "a", shape=(None, 2))


@pytest.mark.parametrize("size", [1, 16, 17, 100])   # two ways of testing finiteness
def test_as_array_finite_positive_nonnegative_and_empty(size):
    x = np.ones(size)
    for bad in (np.nan, np.inf, -np.inf):
        y = x.copy()
        y[-1] = bad
        with pytest.raises(ValueError, match="a must be finite"):
            V.as_array(y, "a")
        assert V.as_array(y, "a", finite=False) is y
    z = x.copy()
    z[-1] = 0.0
    assert V.as_array(z, "a", nonnegative=True) is z
    with pytest.raises(ValueError, match="a must be positive"):
        V.as_array(z, "a", positive=True)
    z[-1] = -1e-300
    with pytest.raises(ValueError, match="a must be non-negative"):
        V.as_array(z, "a", nonnegative=True)
    assert V.as_array(x, "a", positive=True) is x
    with pytest.raises(ValueError, match="a must not be empty"):
        V.as_array(np.zeros(0), "a")
    assert V.as_array(np.zeros((0, 2)), "a", allow_empty=True).shape == (0, 2)


def test_as_scalar_bounds_are_inclusive():
    assert V.as_scalar(2, "s", lo=2, hi=2) == 2.0
    assert V.as_scalar(np.float32(0.5), "s") == 0.5
    assert V.as_scalar(np.array(1.5), "s") == 1.5
    with pytest.raises(ValueError, match="s must be >= 2, got 1.999"):
        V.as_scalar(1.999, "s", lo=2)
    with pytest.raises(ValueError, match="s must be <= 2, got 2.001"):
        V.as_scalar(2.001, "s", hi=2)
    assert V.as_scalar(0.0, "s", nonnegative=True) == 0.0
    assert V.as_scalar(-0.0, "s", nonnegative=True) == 0.0
    with pytest.raises(ValueError, match="s must be positive, got 0.0"):
        V.as_scalar(0.0, "s", positive=True)
    with pytest.raises(ValueError, match="s must be non-negative, got -1e-300"):
        V.as_scalar(-1e-300, "s", nonnegative=True)
    with pytest.raises(ValueError, match="s must be positive, got nan"):
        V.as_scalar(np.nan, "s", positive=True, finite=False)
    assert V.as_scalar(np.inf, "s", finite=False) == np.inf
    with pytest.raises(ValueError, match="s must be finite, got inf"):
        V.as_scalar(np.inf, "s")
    with pytest.raises(ValueError, match="too large for float64"):
        V.as_scalar(10 ** 400, "s")


@pytest.mark.parametrize("x, match", [
    (True, "got bool"), (np.bool_(False), "got bool"), ("1", "got str"), ([1.0], "got list"),
    (np.array([1.0]), r"array of shape \(1,\)"), (np.array(1 + 1j), "array of shape"),
    (1 + 0j, "got complex"),
])
def test_as_scalar_refuses_what_is_not_a_real_number(x, match):
    with pytest.raises(TypeError, match=match):
        V.as_scalar(x, "s")


def test_as_int_takes_the_whole_int64_range_and_no_more():
    lo, hi = -2 ** 63, 2 ** 63 - 1
    assert V.as_int(lo, "k") == lo and V.as_int(hi, "k") == hi
    assert V.as_int(np.int64(hi), "k") == hi and V.as_int(np.uint8(7), "k") == 7
    with pytest.raises(ValueError, match=r"k is too large \(a 19-digit integer\)"):
        V.as_int(hi + 1, "k")
    with pytest.raises(ValueError, match=r"k is too large \(a negative 19-digit integer\)"):
        V.as_int(lo - 1, "k")
    with pytest.raises(ValueError, match="a 301-digit integer"):
        V.as_int(10 ** 300, "k")
    assert V.as_int(3, "k", minimum=3, maximum=3) == 3
    with pytest.raises(ValueError, match="k must be >= 3, got 2"):
        V.as_int(2, "k", minimum=3)
    with pytest.raises(ValueError, match="k must be <= 3, got 4"):
        V.as_int(np.int32(4), "k", maximum=3)
    for bad, name in [(True, "bool"), (np.bool_(True), "bool"), (2.0, "float"),
                      ("2", "str"), (None, "NoneType")]:
        with pytest.raises(TypeError, match=f"k must be an integer, got {name}"):
            V.as_int(bad, "k")


def test_as_vector3_and_as_square():
    assert V.as_vector3([1, 2, 3], "v").shape == (3,)
    assert V.as_vector3(np.zeros((4, 5, 3)), "v").shape == (4, 5, 3)
    with pytest.raises(ValueError, match=r"v must have a last axis of length 3, got shape \(3, 2\)"):
        V.as_vector3(np.zeros((3, 2)), "v")
    assert V.as_square(np.eye(3), "A", n=3).shape == (3, 3)
    with pytest.raises(ValueError, match=r"A must be a square matrix, got shape \(2, 3\)"):
        V.as_square(np.zeros((2, 3)), "A")
    with pytest.raises(ValueError, match=r"A must be a square matrix, got shape \(2, 3, 3\)"):
        V.as_square(np.zeros((2, 3, 3)), "A")
    assert V.as_square(np.zeros((2, 3, 3)), "A", batch=True).shape == (2, 3, 3)
    with pytest.raises(ValueError, match=r"A must be a square matrix stack, got shape \(2, 3, 2\)"):
        V.as_square(np.zeros((2, 3, 2)), "A", batch=True)
    with pytest.raises(ValueError, match=r"A must be 2x2, got shape \(3, 3\)"):
        V.as_square(np.eye(3), "A", n=2)


def test_as_symmetric_tolerance_and_exact_symmetry():
    A = np.array([[2.0, 1.0], [1.0 + 2e-10, 3.0]])   # |A - A^T| = 2e-10 = rtol * max|A|
    S = V.as_symmetric(A, "A", rtol=2e-10 / 3.0 * (1 + 1e-6))
    assert np.array_equal(S, S.T) and S[0, 1] == 0.5 * (1.0 + (1.0 + 2e-10))
    with pytest.raises(ValueError, match=r"A must be symmetric \(max \|A - A\^T\| = 2e-10\)"):
        V.as_symmetric(A, "A", rtol=2e-10 / 3.0 * (1 - 1e-6))
    assert np.array_equal(V.as_symmetric(A, "A", rtol=0.0, atol=2.1e-10), S)
    with pytest.raises(ValueError, match="symmetric"):
        V.as_symmetric(A, "A", rtol=0.0, atol=1.9e-10)


def test_as_finite_result():
    x = np.array([1.0, 2.0])
    assert V.as_finite_result(x, "the energy", "x is large") is x
    with pytest.raises(NonFiniteError, match="the energy overflowed float64 .*contains inf.*: "
                                             "x is large"):
        V.as_finite_result(np.array([1.0, np.inf]), "the energy", "x is large")
    with pytest.raises(NonFiniteError, match="contains NaN"):
        V.as_finite_result(np.array([np.inf, np.nan]), "the energy", "x is large")
    assert V.as_finite_result(np.array([1, 2]), "n", "") is not None   # integers are finite
