"""The methods' constant tables, as the C sources hold them, against the theory
they come from: Butcher's order conditions over every rooted tree (Hairer,
Norsett & Wanner, Solving ODE I, section II.2), explicitness, the nodes as row
sums, the embedded pairs' lower orders, Yoshida's composition conditions and
the Radau IIA transformation.

A method is its tableau: a coefficient mistyped or a row shifted gives wrong
answers that a loose test tolerance can hide (a weight of a stage the step
never reads, a row the code replaces by another), so the tables are checked
here as numbers, independently of any solve.
"""
from __future__ import annotations

import itertools
import os
import re
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

# the checkout (dev.sh names it in MECHPY_SOURCE_DIR when the suite runs from a copy of tests/)
ROOT = Path(os.environ.get("MECHPY_SOURCE_DIR") or Path(__file__).resolve().parents[1])
ODE = ROOT / "csrc" / "ode"

pytestmark = pytest.mark.skipif(not ODE.is_dir(), reason="needs the source tree (csrc/ode)")


# ----------------------------------------------------------- reading the C tables

def _c_tables(path: Path) -> dict:
    """Every ``static const double NAME[..] = {...};`` of a C file, as nested
    lists of floats (rows written short, ``{0}`` or ``{0.2}``, padded with
    zeros to the declared width), with the file's ``#define`` constants
    substituted."""
    src = path.read_text()
    defines = dict(re.findall(r"^#define (\w+) (.+?)(?:\s*/\*.*)?$", src, re.M))
    env: dict = {}
    for name, expr in defines.items():         # in order: later ones use earlier ones
        try:
            env[name] = eval(expr, {}, dict(env))  # noqa: S307 (the project's own constants)
        except (SyntaxError, NameError, TypeError):
            pass
    out = {}
    for name, dims, body in re.findall(
            r"static const double (\w+)((?:\[\d+\])+)\s*=\s*(\{.*?\});", src, re.S):
        shape = [int(d) for d in re.findall(r"\[(\d+)\]", dims)]
        val = eval(body.replace("{", "[").replace("}", "]"), {}, dict(env))  # noqa: S307
        out[name] = _padded(val, shape)
    return out


def _padded(val, shape):
    if len(shape) == 1:
        return np.array(list(val) + [0.0] * (shape[0] - len(val)), dtype=float)
    rows = [_padded(r, shape[1:]) for r in val]
    rows += [np.zeros(shape[1:])] * (shape[0] - len(rows))
    return np.array(rows)


# ------------------------------------------------------ rooted trees (Butcher)

@lru_cache(maxsize=None)
def _trees(order: int) -> tuple:
    """The rooted trees with ``order`` vertices, each a sorted tuple of its
    root's subtrees (a multiset)."""
    if order == 1:
        return ((),)
    out = set()
    for parts in _partitions(order - 1):
        for kids in itertools.product(*(_trees(p) for p in parts)):
            out.add(tuple(sorted(kids)))
    return tuple(sorted(out))


def _partitions(n, largest=None):
    largest = n if largest is None else largest
    if n == 0:
        yield ()
        return
    for k in range(min(n, largest), 0, -1):
        for rest in _partitions(n - k, k):
            yield (k, *rest)


def _size(tree) -> int:
    return 1 + sum(_size(k) for k in tree)


def _gamma(tree) -> int:
    """The tree's density: its size times its subtrees' densities."""
    g = _size(tree)
    for k in tree:
        g *= _gamma(k)
    return g


def _phi(tree, A):
    """The elementary weight's stage vector: prod over subtrees of A Phi(subtree)."""
    v = np.ones(A.shape[0])
    for k in tree:
        v = v * (A @ _phi(k, A))
    return v


def order_defects(A, b, order):
    """max |b . Phi(tree) - 1/gamma(tree)| over the trees of each size up to ``order``."""
    return {p: max(abs(b @ _phi(t, A) - 1.0 / _gamma(t)) for t in _trees(p))
            for p in range(1, order + 1)}


def _tol(w) -> float:
    """The rounding a sum of terms of weights w can carry: a few ulps of sum |w_i|
    (the elementary weights Phi are at most 1 on nodes in [0, 1])."""
    return 4 * np.finfo(float).eps * float(np.abs(w).sum())


def test_the_trees_are_counted_as_published():
    # OEIS A000081: 1, 1, 2, 4, 9, 20, 48, 115 rooted trees with 1..8 vertices
    assert [len(_trees(p)) for p in range(1, 9)] == [1, 1, 2, 4, 9, 20, 48, 115]


# ------------------------------------------------------------------ the tables

def test_dop853_is_explicit_of_order_8_with_its_embedded_orders_5_and_3():
    t = _c_tables(ODE / "dop853_tableau.h")
    A, c, b = t["mp_dop853_a"], t["mp_dop853_c"], t["mp_dop853_b"]
    # explicit: a stage reads only the stages before it (rk.c's stage_point
    # reads s columns; an entry on or above the diagonal is never read, so a
    # wrong one there is a table that is not the published one)
    assert np.all(np.triu(A) == 0.0)
    np.testing.assert_allclose(A.sum(axis=1), c, rtol=0, atol=4e-15)
    # stage 13 is f(t + h, y1): its row is the weights (rk.c uses mp_dop853_b for it)
    np.testing.assert_array_equal(A[12, :12], b)
    assert c[12] == 1.0
    A12 = A[:12, :12]
    d = order_defects(A12, b, 9)
    assert max(d[p] for p in range(1, 9)) < _tol(b), d
    assert d[9] > 1e-6                              # order 8, not more
    # the error estimators are b minus a weight of order 5 and of order 3
    A13 = A[:13, :13]
    b13 = np.append(b, 0.0)
    for e, p in ((t["mp_dop853_e5"], 5), (t["mp_dop853_e3"], 3)):
        d = order_defects(A13, b13 - e, p + 1)
        assert max(d[q] for q in range(1, p + 1)) < _tol(np.abs(b13) + np.abs(e)), (p, d)
        assert d[p + 1] > 1e-6, (p, d)
    # the 7th-order dense output's four correction rows vanish on a constant
    # (each is a combination of stage differences)
    D = t["mp_dop853_d"]
    assert np.all(np.abs(D.sum(axis=1)) < 1e-15 * np.abs(D).sum(axis=1).max() * 16)


def test_dopri5_is_explicit_of_order_5_with_an_embedded_order_4():
    t = _c_tables(ODE / "dopri5_tableau.h")
    A = np.zeros((7, 7))
    A[:, :6] = t["dp_a"]
    c, e = t["dp_c"], t["dp_e"]
    assert np.all(np.triu(A) == 0.0)
    np.testing.assert_allclose(A.sum(axis=1), c, rtol=0, atol=4e-16)
    b = A[6]                              # FSAL: stage 7 is f(t + h, y1)
    d = order_defects(A, b, 6)
    assert max(d[p] for p in range(1, 6)) < 1e-15, d
    assert d[6] > 1e-6
    d = order_defects(A, b - e, 5)
    assert max(d[p] for p in range(1, 5)) < 1e-15, d
    assert d[5] > 1e-6
    # Shampine's dense output (Hairer's contd5), of order 4 at every theta in
    # [0, 1]: its weights b_i(theta) meet the conditions of the trees to order 4
    # for the step theta h, b(theta) . Phi(tree) = theta^|tree| / gamma(tree)
    for th in (0.1, 0.5, 0.8):
        bt = _dopri5_dense_weights(b, t["dp_d"], th)
        for tree in itertools.chain.from_iterable(_trees(p) for p in range(1, 5)):
            got = bt @ _phi(tree, A)
            want = th ** _size(tree) / _gamma(tree)
            assert abs(got - want) < 1e-15, (th, tree, got, want)
        assert max(abs(bt @ _phi(tr, A) - th ** 5 / _gamma(tr)) for tr in _trees(5)) > 1e-6


def _dopri5_dense_weights(b, d, th):
    """The weights b_i(theta) of the dense output as the scalar step forms it
    (rk.c's dopri5 coefficients: rcont1..5 of Hairer's DOPRI5), per unit h:
    y(t0 + th h) = y0 + h * sum_i b_i(th) k_i."""
    e1 = np.zeros(7)
    e1[0] = 1.0
    e7 = np.zeros(7)
    e7[6] = 1.0
    # rcont2 = y1 - y0 = h b.k ; rcont3 = h k1 - rcont2 ; rcont4 = rcont2 - h k7 - rcont3 ;
    # rcont5 = h d.k ; y = y0 + th (rcont2 + (1-th)(rcont3 + th (rcont4 + (1-th) rcont5)))
    r2 = b
    r3 = e1 - r2
    r4 = r2 - e7 - r3
    r5 = d
    return th * (r2 + (1 - th) * (r3 + th * (r4 + (1 - th) * r5)))


def test_gauss_legendre_two_stages_is_of_order_4():
    t = _c_tables(ODE / "geometric.c")
    A, c = t["gl_a"], t["gl_c"]
    np.testing.assert_allclose(A.sum(axis=1), c, rtol=0, atol=1e-16)
    d = order_defects(A, np.array([0.5, 0.5]), 5)
    assert max(d[p] for p in range(1, 5)) < 1e-15, d
    assert d[5] > 1e-4


@pytest.mark.parametrize("path, name, order", [
    ("geometric.c", "yoshida4_c", 4), ("geometric.c", "yoshida6_c", 6),
    ("rigid_split.c", "split4_c", 4)])
def test_yoshida_compositions_meet_their_conditions(path, name, order):
    """A symmetric composition of a second-order symmetric step with weights
    w is of order 4 when sum w = 1 and sum w^3 = 0 (Yoshida 1990); of order 6
    also when sum w^5 = 0 (and a condition of the bracket terms), which the
    published 15-digit weights of solution A meet to their own precision."""
    w = _c_tables(ODE / path)[name]
    assert np.array_equal(w, w[::-1])                       # symmetric
    assert abs(w.sum() - 1.0) < _tol(w)
    # solution A is published to 15 digits: its sums of powers vanish to
    # about 5e-14 (measured 8e-15 and 4.6e-14), the order-4 weights (closed
    # form) to rounding
    bound = 1e-13 if order == 6 else _tol(np.abs(w) ** 3)
    assert abs((w ** 3).sum()) < bound
    if order == 6:
        assert abs((w ** 5).sum()) < bound


def test_radau_iia_transformation_inverts_and_diagonalises():
    t = _c_tables(ODE / "radau.c")
    T, TI, c = t["rc_T"], t["rc_TI"], t["rc_c"]
    np.testing.assert_allclose(T @ TI, np.eye(3), rtol=0, atol=2e-15)
    # Radau IIA(3): the nodes are the roots of P3 - P2 shifted to [0, 1] ... with c3 = 1
    s6 = np.sqrt(6.0)
    np.testing.assert_allclose(c, [(4 - s6) / 10, (4 + s6) / 10, 1.0], rtol=0, atol=1e-16)
    # the collocation matrix A (a_ij = int_0^{c_i} l_j), its inverse turned by T
    # into one real eigenvalue and one complex pair (Hairer & Wanner IV.8)
    V = np.vander(c, 4, increasing=True)[:, 1:]      # c^1, c^2, c^3
    A = np.array([[sum(coef * ci ** (k + 1) / (k + 1) for k, coef in enumerate(lj))
                   for lj in _lagrange_coeffs(c)] for ci in c])
    assert V.shape == (3, 3)
    M = TI @ np.linalg.inv(A) @ T
    gamma = M[0, 0]
    alpha, beta = M[1, 1], M[1, 2]
    ev = np.linalg.eigvals(np.linalg.inv(A))
    real = ev[np.argmin(np.abs(ev.imag))].real
    np.testing.assert_allclose(gamma, real, rtol=1e-14)
    np.testing.assert_allclose(M[2, 2], alpha, rtol=1e-14)
    np.testing.assert_allclose(M[2, 1], -beta, rtol=1e-14)
    off = M.copy()
    off[0, 0] = off[1, 1] = off[1, 2] = off[2, 1] = off[2, 2] = 0.0
    assert np.abs(off).max() < 1e-13


def _lagrange_coeffs(c):
    """Coefficients (increasing powers) of the Lagrange basis on the nodes c."""
    out = []
    for j in range(len(c)):
        p = np.array([1.0])
        for m in range(len(c)):
            if m != j:
                p = np.convolve(p, np.array([-c[m], 1.0]) / (c[j] - c[m]))
        out.append(p)
    return out


def test_the_pages_dormand_prince_is_the_engines():
    """The page that simulates (mechpy/live/static/simulate.js) carries its own
    copy of the dopri5 tables, as JavaScript: it must be the C header's, entry
    for entry (to rounding: the page writes the fractions, the header some as
    decimals)."""
    js = (ROOT / "mechpy" / "live" / "static" / "simulate.js").read_text()
    body = re.search(r"const MP_DOPRI = \{(.*?)\n\};", js, re.S).group(1)
    body = re.sub(r"//[^\n]*", "", body)
    page = eval("{" + re.sub(r"(\b[a-z])\s*:", r'"\1":', body) + "}", {}, {})  # noqa: S307
    t = _c_tables(ODE / "dopri5_tableau.h")
    np.testing.assert_allclose(page["c"], t["dp_c"], rtol=1e-15, atol=0)
    A = np.zeros((7, 6))
    for i, row in enumerate(page["a"]):
        A[i, :len(row)] = row
    np.testing.assert_allclose(A, t["dp_a"], rtol=1e-15, atol=0)
    np.testing.assert_allclose(page["e"], t["dp_e"], rtol=1e-15, atol=0)
    np.testing.assert_allclose(page["d"], t["dp_d"], rtol=1e-15, atol=0)
