"""Every read of SymPy's private attributes, in one place.

SymPy's mechanics module keeps some of what :mod:`.multibody` and
:mod:`.derive` need only in private attributes (no public accessor as of
SymPy 1.14): whether Kane's equations were formed, the auxiliary and dependent
speeds, the constraint terms, a point's velocity and position trees, and the
time symbol of ``dynamicsymbols``.  They are read here and nowhere else, each
through :func:`_get`, which names the attribute and SymPy's version when one is
missing (a SymPy release that renamed it), instead of an AttributeError from
deep inside a model's derivation.  tests/test_mechanics.py checks every entry of
:data:`ATTRIBUTES` on the installed SymPy against :data:`CHECKED`.
"""
from __future__ import annotations

import sympy as sp

#: SymPy versions on which every attribute below was checked to exist and mean
#: what this module takes it to mean.
CHECKED = ("1.14.0",)

#: The private attributes read, by the class that has them.
ATTRIBUTES = {
    "KanesMethod": ("_fr", "_frstar", "_uaux", "_f_h", "_udep", "_k_nh", "_f_nh",
                    "_inertial"),
    "LagrangesMethod": ("_hol_coneqs",),
    "Point": ("_vel_dict", "_pos_dict"),
    "dynamicsymbols": ("_t",),
    "Symbol": ("_assumptions_orig",),
}


def _get(obj, name: str, owner: str):
    try:
        return getattr(obj, name)
    except AttributeError:
        raise RuntimeError(
            f"SymPy {sp.__version__}: {owner} has no attribute {name}, which mechpy reads "
            f"(mechpy/symbolic/_sympy_private.py, checked against SymPy "
            f"{', '.join(CHECKED)})") from None


def time():
    """The time symbol t of ``dynamicsymbols`` (``dynamicsymbols._t``)."""
    from sympy.physics.vector import dynamicsymbols
    return _get(dynamicsymbols, "_t", "dynamicsymbols")


def kane_formed(m) -> bool:
    """Whether a KanesMethod's equations were formed (``kanes_equations`` ran)."""
    return (_get(m, "_fr", "KanesMethod") is not None
            and _get(m, "_frstar", "KanesMethod") is not None)


def kane_inertial(m):
    """A KanesMethod's inertial frame (the frame it was made with; a
    LagrangesMethod has it public, as ``inertial``)."""
    return _get(m, "_inertial", "KanesMethod")


def kane_auxiliary_speeds(m):
    """A KanesMethod's auxiliary speeds (u_auxiliary)."""
    return _get(m, "_uaux", "KanesMethod")


def kane_holonomic(m) -> list:
    """A KanesMethod's holonomic constraints f_h(q) = 0, a list (empty: none)."""
    f_h = _get(m, "_f_h", "KanesMethod")
    return list(f_h) if f_h else []


def kane_dependent_speeds(m):
    """A KanesMethod's dependent speeds."""
    return _get(m, "_udep", "KanesMethod")


def kane_velocity_constraints(m, u) -> list:
    """A KanesMethod's velocity constraints B(q, t) u + c(q, t) at the speeds u,
    a list (``_k_nh u + _f_nh``)."""
    return list(_get(m, "_k_nh", "KanesMethod") * sp.Matrix(u)
                + _get(m, "_f_nh", "KanesMethod"))


def lagrange_holonomic(m) -> list:
    """A LagrangesMethod's holonomic constraints g_h(q, t) = 0, a list (empty: none)."""
    hol = _get(m, "_hol_coneqs", "LagrangesMethod")
    return list(hol) if hol else []


def point_velocity_set(P, frame):
    """P's velocity in ``frame`` if one was set (computed or given), else None."""
    return _get(P, "_vel_dict", "Point").get(frame)


def point_neighbours(P):
    """The points P's position was given from or to (its position tree's edges)."""
    return _get(P, "_pos_dict", "Point")


def assumptions_given(s) -> dict:
    """A symbol's assumptions as its author gave them (``_assumptions_orig``,
    for a message); the public ``assumptions0`` (the given ones with what they
    imply) where a SymPy release lacks it: a message only, so no error."""
    a = getattr(s, "_assumptions_orig", None)
    return dict(s.assumptions0 if a is None else a)
