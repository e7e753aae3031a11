"""The kinematics a drawing needs, printed as C and compiled like a system.

:func:`mechpy.live.animate` draws a system from its own description: the
places of its points and mass centres and the direction cosines of its
bodies' frames, as functions of the state and the parameters.  This module
takes them

- from a SymPy mechanics model (:func:`model_drawing`, called by
  :func:`mechpy.mechanics` when it derives the system; the description is
  stored with the system's, in its cached ``meta``), or
- from the user's ``points={"name": (x, y, z)}`` for a system of
  :func:`mechpy.lagrangian` or :func:`mechpy.equations`
  (:func:`points_drawing`),

prints them as one C function of the state by mechpy's own printer
(:mod:`.codegen`, common subexpressions shared), and compiles it into a small
library cached on disk by its source's sha256 (:func:`.build.build`).
:func:`evaluate` computes every frame in one call (the GIL released, as
ctypes does for a foreign function).

The vector a state gives: the places (3 numbers a point, in the model's
inertial frame, measured from its point at rest) of every drawn point in
order, then the body-to-world rotation matrices (9 numbers, row-major) of the
turned solids in order.
"""
from __future__ import annotations

import ctypes
from types import SimpleNamespace

import numpy as np
import sympy as sp

from . import _sympy_private as _private

__all__ = ["model_drawing", "points_drawing", "evaluate", "numeric"]


def _source(exprs, P, n, what) -> str:
    """The C source of ``mp_kin(m, Y, p, out)``: the expressions (in mp_y<i>
    and the parameter symbols P) at each of m states (rows of Y, n each) into
    rows of out (len(exprs) each)."""
    from . import build, codegen
    # what codegen._block needs of an IR: the time and parameter symbols, the state size
    # and, for its messages, the sources
    ir = SimpleNamespace(T=sp.Symbol("mp_t"), P=list(P), n=n, Z=[], show=str,
                         sources={what: sp.Add(*exprs, evaluate=False)})
    block = codegen._block("gen_kin", exprs, ir, codegen._ARGS, what)
    return "\n".join([
        "/* mechpy: the kinematics of a drawing (mechpy/symbolic/kinematics.py). */",
        "#include <math.h>",
        f"const long mp_gen_dims[5] = {{0, 0, 0, 0, {build.ABI_VERSION}}};",
        block,
        f"/* out[k * {len(exprs)} ...] = {what} at the state Y[k * {n} ...], k < m. */",
        "int mp_kin(long m, const double *Y, const double *p, double *out)",
        "{",
        "    for (long k = 0; k < m; k++)",
        f"        gen_kin(0.0, Y + k * {n}, p, out + k * {len(exprs)});",
        "    return 0;",
        "}", ""])


def evaluate(drawing: dict, Y, p) -> np.ndarray:
    """The compiled kinematics of a drawing (its ``source``, ``nout``
    outputs) at every state: ``Y`` (n, frames), parameter vector ``p``;
    returns (frames, nout).  The library is compiled once and cached (on
    disk, by its source)."""
    from .build import build
    lib = build(drawing["source"])[0]
    f = lib.mp_kin
    dp = ctypes.POINTER(ctypes.c_double)
    f.argtypes = (ctypes.c_long, dp, dp, dp)
    f.restype = ctypes.c_int
    nout = int(drawing["nout"])
    Yc = np.ascontiguousarray(np.asarray(Y, dtype=float).T)          # (frames, n)
    pc = np.ascontiguousarray(p, dtype=float)
    out = np.empty((Yc.shape[0], nout))
    if Yc.shape[0]:
        f(Yc.shape[0], Yc.ctypes.data_as(dp), (pc if pc.size else np.zeros(1)).ctypes.data_as(dp),
          out.ctypes.data_as(dp))
    return out


def numeric(text: str, y, p) -> np.ndarray:
    """A stored expression (``srepr`` in mp_y / mp_p symbols) at one state."""
    e = sp.sympify(text)
    sub = {sp.Symbol(f"mp_y{i}"): float(v) for i, v in enumerate(y)}
    sub.update({sp.Symbol(f"mp_p{i}"): float(v) for i, v in enumerate(p)})
    e = e if isinstance(e, sp.MatrixBase) else sp.Matrix([e])
    return np.array(e.xreplace(sub).evalf(17), dtype=float)


def _plain_symbols(P):
    """The parameters' symbols -> mp_p0, mp_p1, ... (as the library's p[])."""
    return {s: sp.Symbol(f"mp_p{i}") for i, s in enumerate(P)}


# ------------------------------------------------------------ a mechanics model

def _frame_of(body, N):
    """The frame a body is drawn turned by: its own when its orientation in N
    is known, else the one its inertia is written in (a wheel whose angle is
    ignorable has an angular velocity only; its inertia, symmetric about its
    axle, is written in the frame that carries the axle)."""
    try:
        N.dcm(body.frame)
        return body.frame
    except ValueError:
        pass
    for _, v1, _ in body.central_inertia.args:
        F = v1.args[0][1]
        try:
            N.dcm(F)
            return F
        except ValueError:
            continue
    raise ValueError(f"body {body.name}: its frame {body.frame} has no orientation in the "
                     f"inertial frame {N}, and neither has the frame of its inertia")


def model_drawing(method, ir) -> dict:
    """The drawing of a SymPy mechanics model (a KanesMethod, LagrangesMethod
    or System, formed), in the plain symbols of its derived system ``ir``: a
    JSON-able description, with the C source of its kinematics.

    Each body is drawn at its mass centre, measured from the model's point at
    rest in the inertial frame N (in N's components); a rigid body turned by
    its frame's direction cosines ``N.dcm(frame)`` (body to world), with its
    central inertia and mass (for the solid of its moments); a particle as a
    sphere; a System's fixed body (the ground) is not drawn.  A ``System``'s joints are links between their bodies' mass
    centres through the joint's point on the child.  The ground plane: the
    plane through the point at rest normal to the constant loads (gravity),
    for a model that rolls (velocity constraints).  A part that cannot be
    drawn gives ``{"error": message}`` (raised when it is drawn).
    """
    from .multibody import _method, _rest_point
    try:
        from sympy.physics.mechanics import System
    except ImportError:       # SymPy < 1.13
        System = ()
    joints = list(method.joints) if System and isinstance(method, System) else []
    kind, m = _method(method)
    try:
        return _model_drawing(kind, m, ir, joints, _rest_point)
    except ValueError as exc:
        return {"error": str(exc)}


def _known(plain, e, what):
    """``e`` in the plain symbols (srepr), or None when it holds constants the
    equations do not (a planar model's unused moments): its solid is then a
    sphere, still turned by its frame."""
    try:
        return sp.srepr(plain(e, what))
    except ValueError:
        return None


def _model_drawing(kind, m, ir, joints, rest_point):
    from sympy.physics.vector import Point
    N = _private.kane_inertial(m) if kind == "kane" else m.inertial
    bodies = list(m.bodies or [])
    if N is None or not bodies:
        raise ValueError("the model names no bodies or no inertial frame to draw")
    origin = None
    for b in bodies:
        origin = rest_point(b.masscenter, N)
        if origin is not None:
            break
    if origin is None:
        raise ValueError("no point of the model is at rest in the inertial frame (set_vel(N, "
                         "0)): the drawing measures the places from one")
    # the ground of a System (its fixed body: the inertial frame, at rest) is not drawn
    bodies = [b for b in bodies if not (getattr(b, "frame", None) == N
                                        and rest_point(b.masscenter, N) is b.masscenter)]
    t = _private.time()
    sub = {qi: ir.Y[i] for i, qi in enumerate(m.q)}
    sub[t] = ir.T
    coef = _plain_symbols(ir.P)

    def plain(e, what):
        e = sp.sympify(e).xreplace(sub)
        rest = sorted({str(f) for f in e.atoms(sp.Function, sp.Derivative)
                       if isinstance(f, (sp.Derivative, sp.core.function.AppliedUndef))})
        free = sorted(str(s) for s in e.free_symbols - set(ir.Y) - set(coef) - {ir.T})
        if rest or free:
            raise ValueError(f"{what} depends on {rest + free}, which are not coordinates or "
                             "parameters of the equations")
        return e.xreplace(coef)

    names, kinds, pos, rots, inertia, mass, frames = [], [], [], [], [], [], []
    for b in bodies:
        names.append(b.name)
        pos += list(plain(b.masscenter.pos_from(origin).to_matrix(N), f"the place of {b.name}"))
        mass.append(_known(plain, b.mass, f"the mass of {b.name}"))
        if hasattr(b, "frame") and hasattr(b, "central_inertia"):
            F = _frame_of(b, N)
            kinds.append("rigid")
            frames.append(str(F))
            rots.append(plain(N.dcm(F), f"the direction cosines of {b.name}'s frame {F}"))
            inertia.append(_known(plain, b.central_inertia.to_matrix(F),
                                  f"the inertia of {b.name}"))
        else:
            kinds.append("particle")
            frames.append(None)
            inertia.append(None)
    links = []
    index = {b.name: i for i, b in enumerate(bodies)}
    for j in joints:
        pname = f"{j.name} (joint)"
        where = j.child_point
        if not isinstance(where, Point):
            continue
        pos += list(plain(where.pos_from(origin).to_matrix(N), f"the place of joint {j.name}"))
        names.append(pname)
        kinds.append("joint")
        frames.append(None)
        inertia.append(None)
        mass.append(None)
        k = len(names) - 1
        for other in (j.parent, j.child):
            if other.name in index:
                links.append([index[other.name], k])
    ground = None
    rolls = (bool(_private.kane_dependent_speeds(m)) if kind == "kane"
             else bool(m.coneqs))
    if rolls:
        for load in m.loads or []:
            if isinstance(load[0], Point):
                g = load[1].to_matrix(N)
                if not (g.free_symbols & set(m.q)) and not g.atoms(sp.Function):
                    ground = sp.srepr(plain(-g, "the direction of the loads"))
                    break
    exprs = pos + [e for R in rots for e in R]
    P = [coef[s] for s in ir.P]
    return dict(names=names, kinds=kinds, frames=frames, inertia=inertia, mass=mass,
                links=links, ground=ground, n=ir.n, nrot=len(rots), nout=len(exprs),
                source=_source(exprs, P, ir.n, "the places of the bodies and their "
                                                 "frames' direction cosines"))


# ------------------------------------------------------ points of any system

def points_drawing(system, points) -> dict:
    """The drawing of ``points={"name": (x, y, z)}`` for a system of
    :func:`mechpy.lagrangian` or :func:`mechpy.equations`: each a SymPy
    expression of the system's coordinates (by name: its functions of t or
    plain symbols) and parameters (by name).  ValueError naming a point and a
    symbol that is neither; TypeError for a point that is not 3 expressions."""
    if not isinstance(points, dict) or not points:
        raise TypeError("points must be a dict {name: (x, y, z)} of SymPy expressions, got "
                        f"{type(points).__name__}")
    names = list(system._meta["names"])
    pnames = list(system._meta["param_names"])
    n = system.dim
    Y = [sp.Symbol(f"mp_y{i}") for i in range(n)]
    Pp = [sp.Symbol(f"mp_p{i}") for i in range(len(pnames))]
    exprs = []
    for name, xyz in points.items():
        if not isinstance(name, str) or name == "O":
            raise ValueError(f"points: a point's name must be a string other than 'O' (the "
                             f"origin), got {name!r}")
        if isinstance(xyz, (str, bytes)) or not hasattr(xyz, "__len__") or len(xyz) != 3:
            raise TypeError(f"points[{name!r}] must be (x, y, z), three SymPy expressions, "
                            f"got {xyz!r}")
        for c in xyz:
            try:
                e = sp.sympify(c)
            except (sp.SympifyError, TypeError):
                raise TypeError(f"points[{name!r}]: {c!r} is not a SymPy expression") from None
            sub = {}
            for f in e.atoms(sp.core.function.AppliedUndef):
                nm = f.func.__name__
                if nm not in names:
                    raise ValueError(f"points[{name!r}] depends on {f}, which is not a "
                                     f"coordinate of the system (its coordinates: {names})")
                sub[f] = Y[names.index(nm)]
            if e.atoms(sp.Derivative):
                raise ValueError(f"points[{name!r}] depends on a velocity "
                                 f"{sorted(map(str, e.atoms(sp.Derivative)))}: a place is "
                                 "a function of the coordinates and parameters")
            e = e.xreplace(sub)
            for s in e.free_symbols - set(Y):
                if s.name in names:
                    sub2 = {s: Y[names.index(s.name)]}
                elif s.name in pnames:
                    sub2 = {s: Pp[pnames.index(s.name)]}
                else:
                    raise ValueError(f"points[{name!r}] depends on {s}, which is neither a "
                                     f"coordinate ({names}) nor a parameter ({pnames}) of "
                                     "the system")
                e = e.xreplace(sub2)
            exprs.append(e)
    return dict(names=list(points), n=n, nout=len(exprs), exprs=exprs,
                source=_source(exprs, Pp, n, "the places of the points"))

